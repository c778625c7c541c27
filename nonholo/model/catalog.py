"""Mechanisms by name: the package's generated ones, and those added in this process.

``get("platform")`` is the paper's orienting platform; every function that takes a
``mechanism`` accepts a :class:`~nonholo.model.mechanism.Mechanism` or one of :func:`names`.
"""
from __future__ import annotations

import dataclasses
import importlib
from functools import cache

from ..generated import MECHANISMS as GENERATED
from . import drawing
from .mechanism import Mechanism

#: Mechanisms added at run time (:func:`add`), by name.
_ADDED: dict[str, Mechanism] = {}


def names() -> tuple[str, ...]:
    """Names of every mechanism that can be planned.

    Returns
    -------
    tuple of str
        The package's, then those added in this process (:func:`add`).
    """
    return tuple(GENERATED) + tuple(n for n in _ADDED if n not in GENERATED)


#: Bounds of the catalog's mechanisms, as :attr:`Mechanism.bounds` holds them, by name.
CATALOG_BOUNDS: dict[str, dict] = {}


@cache
def _generated(name: str) -> Mechanism:
    mechanism = Mechanism.from_module(importlib.import_module(f"nonholo.generated.{name}"))
    return dataclasses.replace(mechanism, drawing=drawing.catalog_drawing(name), bounds=CATALOG_BOUNDS.get(name))


def get(mechanism="platform") -> Mechanism:
    """A mechanism by name (``nonholo.mechanism_named``).

    Parameters
    ----------
    mechanism : str or Mechanism
        A name of :func:`names`, or a :class:`~nonholo.model.mechanism.Mechanism` (returned
        as it is).

    Returns
    -------
    Mechanism
        The mechanism; a generated one is loaded once per process.

    Raises
    ------
    ValueError
        For an unknown name, listing the known ones.
    """
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
    replaces it.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism to add.

    Returns
    -------
    Mechanism
        ``mechanism``.

    Raises
    ------
    ValueError
        If ``mechanism`` is not a :class:`~nonholo.model.mechanism.Mechanism` or takes a
        name of the package's own mechanisms.
    """
    if not isinstance(mechanism, Mechanism):
        raise ValueError(f"mechanism must be a nonholo.Mechanism, got {type(mechanism).__name__}")
    if mechanism.name in GENERATED:
        raise ValueError(f"mechanism {mechanism.name!r} already exists in the package")
    _ADDED[mechanism.name] = mechanism
    return mechanism
