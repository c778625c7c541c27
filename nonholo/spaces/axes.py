"""What the factors of a state space (:mod:`nonholo.spaces.rotation_factors`,
:mod:`nonholo.spaces.euclidean`) share: :class:`Axis`, one of a state's command-line numbers
as the axis of a map or a plot, and the helpers of their numbers and messages
(:func:`~nonholo.spaces.axes.wrap`, :func:`unit_of`, :func:`kind_of`).

Conventions
-----------
- A factor owns one part of a state (:class:`~nonholo.spaces.state.State`): the rotation
  ``R`` (3×3) or the ``k`` coordinates ``q``. It parses and describes the caller's form of
  its part, takes differences (``log(R R_dᵀ)``, rad; ``q − q_d`` with angle coordinates
  wrapped into ``(−π, π]``), distances, interpolates (the geodesic; the straight line,
  angles the short way round), samples (Haar; a box), retracts a variation and writes JSON
  and command-line numbers (RPY angles in rad; the coordinates).
- ``dim`` is the size of the factor's variation; a factor of ``dim = 0`` is trivial: it has
  one state, and the product leaves it out of every form a caller sees.
- Units: each coordinate has one (``Euclidean.units``, ``""`` if not given), the
  rotation's rows are in rad.
- A factor lists its command-line numbers as :class:`Axis` values (name, default range,
  unit) and writes stacks of its part as a table's columns (a rotation's quaternion).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Axis:
    """One of a state's command-line numbers as the axis of a map or a plot.

    Parameters
    ----------
    name : str
        Its name, one of :attr:`~nonholo.spaces.product.Product.cli_names`.
    aliases : tuple of str
        Other names it is known by (ASCII: ``phi`` for ``φ``).
    bounds : tuple of float
        Its default range ``(lo, hi)``.
    angle : bool
        Whether it is an angle (rad, taken modulo ``2π``).
    unit : str
        Its unit (``""``: none given).
    text : str
        How figures name it: ``"φ (yaw, about z)"``, a coordinate's name.
    """

    name: str
    aliases: tuple
    bounds: tuple
    angle: bool
    unit: str
    text: str


def wrap(angle):
    """``angle`` wrapped into ``(−π, π]``.

    Parameters
    ----------
    angle : float or numpy.ndarray
        Angles (rad).

    Returns
    -------
    float or numpy.ndarray
        The same angles in ``(−π, π]``.
    """
    return np.pi - np.mod(np.pi - angle, 2.0 * np.pi)


def unit_of(units) -> str:
    """The unit of a norm over quantities in ``units``.

    Parameters
    ----------
    units : iterable of str
        The quantities' units (``""``: none given).

    Returns
    -------
    str
        Their one unit, the distinct ones in parentheses when they mix
        (``"(wheelbase, rad)"``), ``""`` when none is given.
    """
    found = list(dict.fromkeys(u for u in units if u))
    if len(found) <= 1:
        return found[0] if found else ""
    return f"({', '.join(found)})"


def kind_of(value) -> str:
    """What ``value`` is, for messages.

    Parameters
    ----------
    value : object
        The caller's value.

    Returns
    -------
    str
        ``"an array of shape (2, 3)"``, or its type's name.
    """
    try:
        shape = np.shape(value)
    except ValueError:
        return type(value).__name__
    return f"an array of shape {shape}" if shape else type(value).__name__
