"""The mechanisms the toolkit derives and generates code for, by name.

Adding a mechanism means adding one entry here: a function returning a
:class:`~derivations.mechanism.Mechanism` (see ``notebooks/adding_a_mechanism.ipynb``).
"""
from __future__ import annotations

from collections.abc import Callable

from .mechanism import Mechanism, body_rate_mechanism, paper_platform

MECHANISMS: dict[str, Callable[[], Mechanism]] = {
    "platform": paper_platform,
    "attitude": lambda: body_rate_mechanism(
        "attitude", (1, 0, 0), (0, 1, 0),
        "rigid body steered by two body-fixed angular rates about e1 and e2"),
}


def get(name: str) -> Mechanism:
    """The mechanism called ``name`` (``KeyError`` lists the known names)."""
    try:
        return MECHANISMS[name]()
    except KeyError:
        raise KeyError(f"unknown mechanism {name!r}; known: {', '.join(MECHANISMS)}") from None
