"""Names and units of a mechanism's quantities for the figures, read from its data.

- the coordinates: the units the derivation gives them (:attr:`Mechanism.units`);
- the inputs: the unit of the first coordinate an input moves (its row of the field
  ``G(R, q)`` at a generic state), per second — a speed in ``wheelbase/s``, a steering rate
  in ``rad/s``; an input that only turns the orientation is a rate in ``1/s`` (the
  platform's scaled leg rates); ``""`` when the coordinate has no unit;
- the plane position of a vehicle: the first two coordinates that are not angles and
  share a unit (the car's ``x, y``, the ball's ``p1, p2``), drawn to scale.

Nothing here depends on a mechanism's name: a mechanism defined in a script gets the same
labels from its own data.
"""
from __future__ import annotations

import numpy as np

from ..spaces import so3

#: The generic state the field is evaluated at to see which coordinates an input moves:
#: an orientation off the axes and coordinates ``0.1, 0.17, 0.24, …`` (no zero, no
#: angle near ``π/2``).
_PROBE_RPY = (0.31, -0.23, 0.17)


def label(name: str, unit: str) -> str:
    """An axis label with its unit.

    Parameters
    ----------
    name : str
        The quantity.
    unit : str
        Its unit (``""``: none).

    Returns
    -------
    str
        ``"name [unit]"``, or ``name`` alone without a unit.
    """
    return f"{name} [{unit}]" if unit else name


def coordinate_units(mechanism) -> tuple[str, ...]:
    """The unit of each coordinate.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.

    Returns
    -------
    tuple of str
        One unit per coordinate (``""`` for each when the mechanism gives none).
    """
    return tuple(mechanism.units) or ("",) * mechanism.n_coordinates


def _probe_state(mechanism):
    R = so3.from_rpy(*_PROBE_RPY) if mechanism.space.has_orientation else np.eye(3)
    q = 0.1 + 0.07 * np.arange(mechanism.n_coordinates)
    return R, q


def input_units(mechanism) -> tuple[str, ...]:
    """The unit of each input of a mechanism (see the module).

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.

    Returns
    -------
    tuple of str
        ``("wheelbase/s", "rad/s")`` for the car, ``("1/s", "1/s")`` for the platform.
    """
    m, k = mechanism.n_inputs, mechanism.n_coordinates
    if not k or mechanism.G is None:
        return ("1/s",) * m
    R, q = _probe_state(mechanism)
    with np.errstate(all="ignore"):
        G = np.asarray(mechanism.G(R, q), dtype=float)
    rows = G[G.shape[0] - k:]                      # the coordinates' rates
    units = []
    for j in range(m):
        moved = np.flatnonzero(np.isfinite(rows[:, j]) & (np.abs(rows[:, j]) > 1e-12))
        if not len(moved):
            units.append("1/s")
            continue
        unit = coordinate_units(mechanism)[moved[0]]
        units.append(f"{unit}/s" if unit else "")
    return tuple(units)


def plane_position(mechanism) -> tuple[int, int] | None:
    """The coordinates of a vehicle's position on the plane (see the module).

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.

    Returns
    -------
    tuple of int or None
        Their indices, or ``None`` when no two coordinates qualify.
    """
    k = mechanism.n_coordinates
    angles = tuple(mechanism.angles) or (False,) * k
    units = coordinate_units(mechanism)
    lengths = [i for i in range(k) if not angles[i]]
    for a, i in enumerate(lengths):
        for j in lengths[a + 1:]:
            if units[i] == units[j]:
                return i, j
    return None


def unit_groups(mechanism) -> list[tuple[str, list[int]]]:
    """The coordinates grouped by unit (one axes each, so that every axes has one unit).

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.

    Returns
    -------
    list of tuple
        ``[(unit, indices)]``, in order of first appearance.
    """
    groups: dict[str, list[int]] = {}
    units = coordinate_units(mechanism)
    for i in range(mechanism.n_coordinates):
        groups.setdefault(units[i], []).append(i)
    return list(groups.items())
