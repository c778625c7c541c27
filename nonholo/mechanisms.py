"""Numeric mechanisms: the generated ``delta``, ``L`` and ``Q`` of each mechanism, by name.

A mechanism is data: its generated module (``nonholo/generated/<name>.py``) provides
``L(R)``, ``Q(R, u)`` and, when it has a singular set, ``delta(R)``. Nothing downstream
depends on which mechanism it is.
"""
from __future__ import annotations

import importlib
import importlib.util
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from types import ModuleType

from .generated import MECHANISMS as NAMES


@dataclass(frozen=True)
class NumericMechanism:
    """Numeric kinematics of one mechanism, backed by its generated module."""

    name: str
    module: ModuleType

    @property
    def description(self) -> str:
        return self.module.DESCRIPTION

    @property
    def inputs(self) -> tuple[str, ...]:
        return self.module.INPUTS

    @property
    def n_inputs(self) -> int:
        return self.module.N_INPUTS

    @property
    def has_singular_set(self) -> bool:
        return self.module.HAS_SINGULAR_SET

    @property
    def geometry(self) -> dict | None:
        """Joint points, disk contact and axle of a platform (for drawings), else ``None``."""
        return getattr(self.module, "GEOMETRY", None)

    @property
    def delta(self):
        """``delta(R) -> float``, or ``None`` for mechanisms without a singular set."""
        return getattr(self.module, "delta", None)

    @property
    def L(self):
        """``L(R) -> (3, m)``: spatial angular velocity per unit input."""
        return self.module.L

    @property
    def Q(self):
        """``Q(R, u) -> (3, 3)`` with ``(∂L/∂θ) u = Q s``."""
        return self.module.Q

    def __repr__(self) -> str:
        return f"NumericMechanism({self.name!r}: {self.description})"


#: Mechanisms registered at run time from generated modules outside the package.
_REGISTERED: dict[str, ModuleType] = {}


def names() -> tuple[str, ...]:
    """Names of every known mechanism: the package's, then those registered at run time."""
    return tuple(NAMES) + tuple(n for n in _REGISTERED if n not in NAMES)


@cache
def get(name: str = "platform") -> NumericMechanism:
    """The numeric mechanism called ``name`` (``ValueError`` lists the known names)."""
    if isinstance(name, NumericMechanism):
        return name
    if name in _REGISTERED:
        return NumericMechanism(name, _REGISTERED[name])
    if name not in NAMES:
        raise ValueError(f"unknown mechanism {name!r}; known: {', '.join(names())}")
    return NumericMechanism(name, importlib.import_module(f"nonholo.generated.{name}"))


def register(path) -> NumericMechanism:
    """Make a generated module written outside the package usable by its ``NAME``.

    ``path`` is a file written by :func:`derivations.codegen.write_mechanism`; afterwards
    ``plan(..., mechanism=NAME)`` and every other function taking a mechanism name work
    with it, in this process. (To add a mechanism for good, register it in
    ``derivations/catalog.py`` and run ``nonholo derive``.)
    """
    path = Path(path)
    spec = importlib.util.spec_from_file_location(f"nonholo_registered_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    name = module.NAME
    if name in NAMES:
        raise ValueError(f"mechanism {name!r} already exists in the package")
    _REGISTERED[name] = module
    get.cache_clear()
    return get(name)
