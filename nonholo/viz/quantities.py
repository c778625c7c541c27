"""Names and units of a mechanism's quantities for the figures, read from its data and the
table of names and units (:mod:`nonholo.model.names`, where :func:`label`,
:func:`coordinate_units` and :func:`input_units` are defined):

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

from ..model.names import coordinate_units, input_units, label

__all__ = ["coordinate_units", "input_units", "label", "plane_position", "unit_groups"]


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
