"""Mechanisms by name: the package's generated ones, and those added in this process.

``get("platform")`` is the paper's orienting platform; every function that takes a
``mechanism`` accepts a :class:`~nonholo.model.mechanism.Mechanism` or one of :func:`names`.
"""
from __future__ import annotations

import importlib
from functools import cache

from ..generated import MECHANISMS as GENERATED
from .mechanism import Mechanism

#: Mechanisms added at run time (:func:`add`), by name.
_ADDED: dict[str, Mechanism] = {}


def names() -> tuple[str, ...]:
    """Names of every mechanism that can be planned: the package's, then those added."""
    return tuple(GENERATED) + tuple(n for n in _ADDED if n not in GENERATED)


@cache
def _generated(name: str) -> Mechanism:
    return Mechanism.from_module(importlib.import_module(f"nonholo.generated.{name}"))


def get(mechanism="platform") -> Mechanism:
    """The :class:`~nonholo.model.mechanism.Mechanism` ``mechanism`` (returned as it is) or the
    one of that name (``ValueError`` lists the known names)."""
    if isinstance(mechanism, Mechanism):
        return mechanism
    if isinstance(mechanism, str):
        if mechanism in _ADDED:
            return _ADDED[mechanism]
        if mechanism in GENERATED:
            return _generated(mechanism)
    raise ValueError(f"unknown mechanism {mechanism!r}; known: {', '.join(names())} "
                     "(or pass a nonholo.Mechanism)")


def add(mechanism: Mechanism) -> Mechanism:
    """Make ``mechanism`` available by its name in this process (e.g. one built by
    :meth:`~nonholo.model.mechanism.Mechanism.from_symbolic`); adding again under the same name
    replaces it. The package's own names cannot be taken."""
    if not isinstance(mechanism, Mechanism):
        raise ValueError(f"mechanism must be a nonholo.Mechanism, got {type(mechanism).__name__}")
    if mechanism.name in GENERATED:
        raise ValueError(f"mechanism {mechanism.name!r} already exists in the package")
    _ADDED[mechanism.name] = mechanism
    return mechanism
