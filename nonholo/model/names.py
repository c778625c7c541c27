"""Names and units of the quantities the toolkit shows: one table for every figure's labels,
the CSV's columns and the documentation.

**Angles.** An orientation is given by its RPY angles, the paper's convention
``R = RPY(φ, ϑ, ψ) = R(Z, φ) R(Y, ϑ) R(X, ψ)`` (:func:`nonholo.spaces.so3.from_rpy`: SciPy's
intrinsic ``"ZYX"`` Euler angles), in radians:

======  ======  ===========  ======================  =========
symbol  name    turns about  in figures              in ASCII
======  ======  ===========  ======================  =========
φ       yaw     z            ``φ (yaw, about z)``    ``phi``
ϑ       pitch   y            ``ϑ (pitch, about y)``  ``theta``
ψ       roll    x            ``ψ (roll, about x)``   ``psi``
======  ======  ===========  ======================  =========

**Units.** A figure gives a quantity's unit in brackets after its name, ``leg length
[radius]`` (:func:`label`); several units of one axes, ``[wheelbase, rad]``; a rate, the unit
per second, ``[radius/s]``. The units:

=============  =================================================================================
unit           what it is
=============  =================================================================================
``rad``        radian: angles, the terminal error ``‖l_T‖`` of an orientation
``s``          second: time
``ms``         millisecond: wall time of a computation
``1/s``        per second: a rate of a number, as a platform's scaled leg rates
               ``u_i = d(l_i²)/dt / (4 |A_i| |B_i|)``
``radius``     the length unit of a geometry whose sphere has radius 1: a platform's (its
               sphere; :class:`derivations.mechanisms.PlatformGeometry` checks ``|contact| =
               |tip_i| = 1``: leg lengths, joint positions) and the rolling ball's (its radius)
``wheelbase``  the car's length unit: its wheelbase ``ℓ = 1``
``m``          metre (coordinates a mechanism gives in metres, the unicycle's)
``N``          newton: contact forces of a physics model
``-``          a number without unit: ``Δ``, iterations, components of unit vectors and
               quaternions, the normal form's coordinates
=============  =================================================================================

A mechanism of one's own names its coordinates' units itself (``units=`` of
:meth:`nonholo.model.mechanism.Mechanism.from_equations`): its figures show those, and them
per second for its inputs and speeds. The slip at a physics model's rolling contacts is a speed, in the
mechanism's length unit per second (:func:`length_unit`: ``radius/s`` for a platform and the
ball, ``wheelbase/s`` for the car).

**The CSV** of a plan (:mod:`nonholo.io.csv_export`) names its columns as :data:`CSV_COLUMNS`
gives them, each with its unit (:func:`csv_units`).
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from ..spaces.rotation_factors import RPY


@dataclass(frozen=True)
class Angle:
    """One RPY angle of ``R = R(Z, φ) R(Y, ϑ) R(X, ψ)``.

    Parameters
    ----------
    symbol : str
        Its symbol (``"φ"``).
    name : str
        Its name (``"yaw"``).
    axis : str
        The axis it turns about (``"z"``).
    ascii : str
        Its name in ASCII (``"phi"``).
    """

    symbol: str
    name: str
    axis: str
    ascii: str

    @property
    def text(self) -> str:
        """The angle as figures name it: ``"φ (yaw, about z)"``."""
        return f"{self.symbol} ({self.name}, about {self.axis})"


#: The RPY angles, in the order of ``RPY(φ, ϑ, ψ)`` (:func:`nonholo.spaces.so3.as_rpy`).
ANGLES = tuple(Angle(symbol, name, axis, ascii) for symbol, name, axis, ascii, _ in RPY)

#: Radian.
RAD = "rad"
#: Second.
SECOND = "s"
#: Millisecond.
MILLISECOND = "ms"
#: Per second.
PER_SECOND = "1/s"
#: The length unit of a geometry whose sphere has radius 1 (a platform's, the ball's).
RADIUS = "radius"
#: The car's length unit, its wheelbase.
WHEELBASE = "wheelbase"
#: Metre.
METRE = "m"
#: Newton.
NEWTON = "N"
#: A number without unit.
NONE = "-"

#: Every unit of the table, with what it is (the module's table).
UNITS = {
    RAD: "radian: angles, the terminal error of an orientation",
    SECOND: "second: time",
    MILLISECOND: "millisecond: wall time of a computation",
    PER_SECOND: "per second: a rate of a number, as a platform's scaled leg rates",
    RADIUS: "the length unit of a geometry whose sphere has radius 1 (a platform's, the rolling ball's)",
    WHEELBASE: "the car's length unit: its wheelbase",
    METRE: "metre",
    NEWTON: "newton: contact forces",
    NONE: "a number without unit",
}

#: The columns of a plan's CSV, in order, as ``(name, unit, what)``; ``{i}`` stands for a
#: leg's or an input's number from 1, ``{coordinate}`` for a coordinate's name, and a unit
#: ``None`` for the input's (:func:`input_units`) or the coordinate's own.
CSV_COLUMNS = (
    ("t", SECOND, "time"),
    ("l{i}", RADIUS, "leg i's length |R tip_i − base_i|"),
    ("dl{i}_dt", f"{RADIUS}/{SECOND}", "leg i's speed"),
    ("u{i}", None, "input i (a platform's scaled leg rate, 1/s)"),
    ("{coordinate}", None, "a coordinate, as the mechanism names it"),
    ("qx", NONE, "the orientation's unit quaternion, x"),
    ("qy", NONE, "... y"),
    ("qz", NONE, "... z"),
    ("qw", NONE, "... w (scalar last)"),
    ("delta", NONE, "Δ"),
)

#: The generic state the field is evaluated at to see which coordinates an input moves:
#: an orientation off the axes and coordinates ``0.1, 0.17, 0.24, …`` (no zero, no
#: angle near ``π/2``).
PROBE_RPY = (0.31, -0.23, 0.17)


def angle_label(k: int, unit: bool = True) -> str:
    """The ``k``-th RPY angle as figures name it.

    Parameters
    ----------
    k : int
        0, 1 or 2: ``φ``, ``ϑ``, ``ψ``.
    unit : bool
        With its unit.

    Returns
    -------
    str
        ``"φ (yaw, about z) [rad]"`` (``"φ (yaw, about z)"`` without the unit).
    """
    text = ANGLES[k].text
    return label(text, RAD) if unit else text


def label(name: str, unit: str) -> str:
    """A quantity's name with its unit, as figures label it.

    Parameters
    ----------
    name : str
        The quantity.
    unit : str
        Its unit (``""``: none); several units written ``"(a, b)"`` (as
        :meth:`nonholo.spaces.product.Product.part_unit` gives them) are listed in the
        brackets.

    Returns
    -------
    str
        ``"name [unit]"`` (``"name [a, b]"``), or ``name`` alone without a unit.
    """
    if unit.startswith("(") and unit.endswith(")"):
        unit = unit[1:-1]
    return f"{name} [{unit}]" if unit else name


def per_second(unit: str) -> str:
    """The unit of a rate of a quantity of ``unit``.

    Parameters
    ----------
    unit : str
        The quantity's unit (``""`` or ``"-"``: a number).

    Returns
    -------
    str
        ``"radius/s"``, ``"1/s"`` for a number.
    """
    return PER_SECOND if unit in ("", NONE) else f"{unit}/{SECOND}"


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


def input_units(mechanism) -> tuple[str, ...]:
    """The unit of each input of a mechanism: the unit of the first coordinate the input
    moves (its row of the field ``G(R, q)`` at a generic state, :data:`PROBE_RPY`), per
    second — a speed in ``wheelbase/s``, a steering rate in ``rad/s``; an input that only
    turns the orientation is a rate in ``1/s`` (the platform's scaled leg rates); ``""``
    when the coordinate has no unit.

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
        return (PER_SECOND,) * m
    q = 0.1 + 0.07 * np.arange(k)
    R, _ = mechanism.space.from_cli(mechanism.space.numbers(rotation=PROBE_RPY, coordinates=q))
    with np.errstate(all="ignore"):
        G = np.asarray(mechanism.G(R, q), dtype=float)
    rows = G[G.shape[0] - k:]                      # the coordinates' rates
    units = []
    for j in range(m):
        moved = np.flatnonzero(np.isfinite(rows[:, j]) & (np.abs(rows[:, j]) > 1e-12))
        if not len(moved):
            units.append(PER_SECOND)
            continue
        unit = coordinate_units(mechanism)[moved[0]]
        units.append(f"{unit}/{SECOND}" if unit else "")
    return tuple(units)


def length_unit(mechanism) -> str:
    """The unit of the mechanism's lengths: those of its geometry, or of its position.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.

    Returns
    -------
    str
        :data:`RADIUS` for a platform (its sphere's radius is 1); else the unit of the first
        coordinate that is not an angle (``"radius"`` for the ball, ``"wheelbase"`` for the
        car); ``""`` when there is none.
    """
    if getattr(mechanism, "geometry", None) is not None:
        return RADIUS
    angles = tuple(mechanism.angles) or (False,) * mechanism.n_coordinates
    for unit, angle in zip(coordinate_units(mechanism), angles):
        if not angle and unit:
            return unit
    return ""


def csv_units(mechanism, header) -> list[str]:
    """The unit of each column of a plan's CSV (:data:`CSV_COLUMNS`).

    Parameters
    ----------
    mechanism : Mechanism
        The plan's mechanism.
    header : sequence of str
        The columns' names.

    Returns
    -------
    list of str
        One unit per column (``""`` for a coordinate without one).

    Raises
    ------
    ValueError
        Naming a column that is not one of :data:`CSV_COLUMNS` for ``mechanism``.
    """
    coordinates = dict(zip(mechanism.coordinates, coordinate_units(mechanism)))
    inputs = input_units(mechanism)
    geometry = getattr(mechanism, "geometry", None)
    count = {"l{i}": 0 if geometry is None else len(geometry.bases), "u{i}": len(inputs)}
    count["dl{i}_dt"] = count["l{i}"]
    written = (*mechanism.space.column_names(), *mechanism.singular.column_names)
    has = {column: column in written for column in ("qx", "qy", "qz", "qw", "delta")}
    out = []
    for name in header:
        unit = coordinates.get(name)
        for pattern, given, _ in CSV_COLUMNS:
            if unit is not None:
                break
            match = re.fullmatch(re.escape(pattern).replace(r"\{i\}", "([1-9][0-9]*)"), name)
            if pattern == "{coordinate}" or match is None or not has.get(pattern, True):
                continue
            if pattern in count and int(match.group(1)) > count[pattern]:
                break                                     # no such leg or input
            unit = given if given is not None else inputs[int(match.group(1)) - 1]
        if unit is None:
            raise ValueError(f"column {name!r} is not a column of a plan of mechanism "
                             f"{getattr(mechanism, 'name', mechanism)!r} (nonholo.model.names.CSV_COLUMNS)")
        out.append(unit)
    return out
