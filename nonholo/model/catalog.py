"""Mechanisms by name: the package's generated ones, and those added in this process.

``get("platform")`` is the paper's orienting platform; every function that takes a
``mechanism`` accepts a :class:`~nonholo.model.mechanism.Mechanism` or one of :func:`names`;
:func:`resolve` also takes a mechanism file (``.toml``) or a definition as data.
"""
from __future__ import annotations

import dataclasses
import hashlib
import importlib
import os
from collections.abc import Mapping
from functools import cache
from pathlib import Path

from ..generated import MECHANISMS as GENERATED
from . import definition_forms, drawing, mechanism_file
from .mechanism import Mechanism

#: Mechanisms added at run time (:func:`add`), by name.
_ADDED: dict[str, Mechanism] = {}
#: Mechanisms built by :func:`resolve` from files and definitions, by the digest of what
#: they were built from (at most :data:`BUILT_KEPT`, the oldest dropped first).
_BUILT: dict[str, Mechanism] = {}
#: How many mechanisms of files and definitions one process keeps built.
BUILT_KEPT = 32


def names() -> tuple[str, ...]:
    """Names of every mechanism that can be planned.

    Returns
    -------
    tuple of str
        The package's, then those added in this process (:func:`add`).
    """
    return tuple(GENERATED) + tuple(n for n in _ADDED if n not in GENERATED)


#: Bounds of the catalog's mechanisms, as :attr:`Mechanism.bounds` holds them, by name
#: (:mod:`nonholo.model.bounds`; what ``plan(..., T=None)`` keeps by default):
#:
#: - ``car`` (wheelbase 1; lengths in wheelbases): rear-axle speed ``|v| ≤ 1`` wheelbase/s,
#:   steering rate ``|φ̇| ≤ 1`` rad/s, steering angle ``|φ| ≤ 0.6`` rad (34°);
#: - ``unicycle``: ``|v| ≤ 0.5`` m/s, ``|ω| ≤ 0.5`` rad/s, as Dynobench's ``unicycle1_v0``;
#: - ``car_with_trailer``: Dynobench's ``car1_v0``: ``v ∈ [−0.1, 0.5]`` m/s, steering ``|φ| ≤ π/3``,
#:   its rate ``|φ̇| ≤ 10`` rad/s (the model's ``max_angular_vel``: Dynobench's steering is an
#:   input, free to jump);
#: - ``unicycle2``: ``|a| ≤ 0.25`` m/s², ``|α| ≤ 0.25`` rad/s², speed ``|v| ≤ 0.5`` m/s and
#:   turning rate ``|ω| ≤ 0.5`` rad/s, as Dynobench's ``unicycle2_v0``.
#:
#: ``rolling_ball`` has none: its inputs are the velocity of the ball's centre, for which no
#: reference gives a bound, and a box on ``(v1, v2)`` would not be a bound on its speed.
CATALOG_BOUNDS: dict[str, dict] = {
    "car": {"inputs": {"v": (-1.0, 1.0), "u2": (-1.0, 1.0)}, "coordinates": {"phi": (-0.6, 0.6)}},
    "unicycle": {"inputs": {"v": (-0.5, 0.5), "omega": (-0.5, 0.5)}},
    "car_with_trailer": {"inputs": {"v": (-0.1, 0.5), "u2": (-10.0, 10.0)},
                    "coordinates": {"phi": (-1.047198, 1.047198)}},
    "unicycle2": {"inputs": {"a": (-0.25, 0.25), "alpha": (-0.25, 0.25)},
                  "coordinates": {"speed": (-0.5, 0.5), "omega": (-0.5, 0.5)}},
}


@cache
def _generated(name: str) -> Mechanism:
    mechanism = Mechanism.from_module(importlib.import_module(f"nonholo.generated.{name}"))
    return dataclasses.replace(mechanism, drawing=drawing.catalog_drawing(name), bounds=CATALOG_BOUNDS.get(name))


def get(mechanism="platform") -> Mechanism:
    """A mechanism by name (``nonholo.mechanism_named``), or of a mechanism file.

    Parameters
    ----------
    mechanism : str, os.PathLike or Mechanism
        A name of :func:`names`, a mechanism file (a path ending in ``.toml``, read by
        :func:`resolve`), or a :class:`~nonholo.model.mechanism.Mechanism` (returned as it
        is).

    Returns
    -------
    Mechanism
        The mechanism; a generated one is loaded once per process, a file's built once per
        process.

    Raises
    ------
    ValueError
        For an unknown name, listing the known ones; naming the file, the line and the field
        of a mechanism file refused.
    """
    if isinstance(mechanism, Mechanism):
        return mechanism
    if isinstance(mechanism, (str, os.PathLike)) and str(mechanism).lower().endswith(".toml"):
        return resolve(mechanism)
    if isinstance(mechanism, str):
        if mechanism in _ADDED:
            return _ADDED[mechanism]
        if mechanism in GENERATED:
            return _generated(mechanism)
    raise ValueError(f"unknown mechanism {mechanism!r}; known: {', '.join(names())} "
                     "(or a mechanism file, NAME.toml, or a nonholo.Mechanism)")


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


def resolve(value, base=None, *, where=None) -> Mechanism:
    """The mechanism a user names: a :class:`~nonholo.model.mechanism.Mechanism` as it is, a
    name of :func:`names` (:func:`get`), a mechanism file (a path ending in ``.toml``,
    :meth:`~nonholo.model.mechanism.Mechanism.from_file`) or a definition as data (a mapping,
    :meth:`~nonholo.model.mechanism.Mechanism.from_definition`).

    A file or definition is built once per process: later calls with the same bytes (or
    data) return the same object (its kernels compiled once).

    Parameters
    ----------
    value : Mechanism, str, os.PathLike or mapping
        The mechanism.
    base : str or os.PathLike, optional
        The directory a relative file path is relative to (default: the working directory).
    where : callable or str, optional
        For a definition: ``where(field)``, the place of a field in messages, or a label
        (default ``"definition"``).

    Returns
    -------
    Mechanism
        The mechanism.

    Raises
    ------
    ValueError
        For an unknown name (listing the known ones); naming the file, the line and the
        field of a mechanism file refused; naming the field of a definition refused.
    """
    if isinstance(value, Mechanism):
        return value
    if isinstance(value, Mapping):
        return _built("definition:" + definition_forms.digest(value),
                      lambda: Mechanism.from_definition(value, where=where))
    if isinstance(value, (str, os.PathLike)) and str(value).lower().endswith(".toml"):
        path = Path(value)
        if base is not None and not path.is_absolute():
            path = Path(base) / path
        raw = mechanism_file.read_bytes(path)

        def build() -> Mechanism:
            definition, where = mechanism_file.parse_bytes(raw, str(path))
            return Mechanism.from_definition(definition, where=where)

        return _built("file:" + hashlib.sha256(raw).hexdigest(), build)
    return get(value)


def _built(key: str, build) -> Mechanism:
    """The mechanism kept under ``key``, else ``build()``'s — or the one kept of the same
    definition, so that one definition is one object (its kernels compiled once)."""
    if key not in _BUILT:
        mechanism = build()
        same = "definition:" + definition_forms.digest(mechanism.definition)
        mechanism = _BUILT.get(same, mechanism)
        for k in (same, key):
            _BUILT.pop(k, None)
            while len(_BUILT) >= BUILT_KEPT:
                _BUILT.pop(next(iter(_BUILT)))
            _BUILT[k] = mechanism
    return _BUILT[key]
