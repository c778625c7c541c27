"""The factors of a state space: :class:`SO3`, :class:`FixedRotation` (its trivial stand-in
for a mechanism without an orientation) and :class:`Euclidean`.

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

from ..numerics import kernels
from ..numerics.checks import real_array
from . import so3
from .state import IDENTITY

#: The RPY angles of ``R = R(Z, φ) R(Y, ϑ) R(X, ψ)``, a rotation's command-line numbers: the
#: symbol, the angle's name, the axis it turns about, its ASCII name and its range (rad).
RPY = (("φ", "yaw", "z", "phi", (-np.pi, np.pi)), ("ϑ", "pitch", "y", "theta", (-np.pi / 2, np.pi / 2)),
       ("ψ", "roll", "x", "psi", (-np.pi, np.pi)))


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


class SO3:
    """The rotation group: states ``R`` (3×3), errors ``log(R R_dᵀ)`` (rad)."""

    dim = 3
    #: the state's part it owns
    part = "rotation"
    cli_names = ("φ", "ϑ", "ψ")
    name = "SO(3)"
    #: the unit of each row of a variation ``s_R`` (and of the RPY angles)
    units = ("rad", "rad", "rad")

    def describe(self) -> str:
        """What a state of this factor is, for messages.

        Returns
        -------
        str
            ``"a rotation matrix (3×3)"``.
        """
        return "a rotation matrix (3×3)"

    def parse(self, value, name: str) -> np.ndarray:
        """``value`` as a rotation matrix.

        Parameters
        ----------
        value : array_like
            The caller's rotation matrix.
        name : str
            The argument's name, for messages.

        Returns
        -------
        numpy.ndarray
            The 3×3 rotation.

        Raises
        ------
        ValueError
            Naming ``name``, if ``value`` is not a rotation matrix (a pair, say).
        """
        if isinstance(value, tuple):
            raise ValueError(f"{name} must be {self.describe()}, got a pair")
        return so3.check_rotation(value, name)

    def identity(self) -> np.ndarray:
        """The identity rotation.

        Returns
        -------
        numpy.ndarray
            ``I`` (3×3), a copy.
        """
        return IDENTITY.copy()

    def difference(self, R, Rd) -> np.ndarray:
        """``l`` with ``[l] = log(R R_dᵀ)`` (rad).

        Parameters
        ----------
        R, Rd : array_like
            Rotation matrices.

        Returns
        -------
        numpy.ndarray
            The 3-vector ``l``.
        """
        return kernels.log_error(np.ascontiguousarray(R, dtype=float), np.ascontiguousarray(Rd, dtype=float))[0]

    def error(self, R, Rd) -> tuple[np.ndarray, float]:
        """``(l, |l|)`` of :meth:`difference`.

        Parameters
        ----------
        R, Rd : array_like
            Rotation matrices.

        Returns
        -------
        tuple of (numpy.ndarray, float)
            ``l`` and its norm (rad).
        """
        l, err = kernels.log_error(np.ascontiguousarray(R, dtype=float), np.ascontiguousarray(Rd, dtype=float))
        return l, float(err)

    def distance(self, R1, R2) -> float:
        """The geodesic distance ``|log(R1 R2ᵀ)|``.

        Parameters
        ----------
        R1, R2 : array_like
            Rotation matrices.

        Returns
        -------
        float
            The distance (rad).
        """
        return self.error(R1, R2)[1]

    def interpolate(self, Ra, Rb, s) -> np.ndarray:
        """The geodesic ``exp(s·log(R_b R_aᵀ)) R_a`` at the fractions ``s``.

        Parameters
        ----------
        Ra, Rb : array_like
            The ends, rotation matrices.
        s : array_like
            Fractions of the way, shape ``(n,)``.

        Returns
        -------
        numpy.ndarray
            The rotations, shape ``(n, 3, 3)``.
        """
        return so3.geodesic(Ra, Rb, s)

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` rotations, uniform (Haar).

        Parameters
        ----------
        rng : numpy.random.Generator
            The random numbers.
        n : int
            How many.

        Returns
        -------
        numpy.ndarray
            The rotations, shape ``(n, 3, 3)``.
        """
        from scipy.spatial.transform import Rotation  # loaded when first needed

        return Rotation.random(n, random_state=rng).as_matrix().reshape(n, 3, 3)

    def retract(self, R, s) -> np.ndarray:
        """``exp([s]) R``: ``R`` moved by the variation ``s`` (rad), in the spatial frame.

        Parameters
        ----------
        R : array_like
            A rotation matrix.
        s : array_like
            The variation, shape ``(3,)``.

        Returns
        -------
        numpy.ndarray
            The moved rotation.
        """
        return so3.exp(np.asarray(s, dtype=float)) @ np.asarray(R, dtype=float)

    def to_json(self, R) -> list:
        """A rotation as JSON.

        Parameters
        ----------
        R : array_like
            A rotation matrix.

        Returns
        -------
        list
            Its rows, nested lists of floats.
        """
        return np.asarray(R, dtype=float).tolist()

    def from_json(self, value, name: str) -> np.ndarray:
        """The rotation of :meth:`to_json`'s form.

        Parameters
        ----------
        value : list
            Nested lists, 3×3.
        name : str
            The field's name, for messages.

        Returns
        -------
        numpy.ndarray
            The 3×3 rotation.
        """
        return self.parse(value if not isinstance(value, tuple) else list(value), name)

    def from_cli(self, numbers) -> np.ndarray:
        """RPY angles ``(φ, ϑ, ψ)`` (rad) as a rotation.

        Parameters
        ----------
        numbers : array_like
            The three angles.

        Returns
        -------
        numpy.ndarray
            The 3×3 rotation.
        """
        return so3.from_rpy(*np.asarray(numbers, dtype=float))

    def to_cli(self, R) -> np.ndarray:
        """A rotation's RPY angles ``(φ, ϑ, ψ)`` (rad), inverse of :meth:`from_cli`.

        Parameters
        ----------
        R : array_like
            A rotation matrix.

        Returns
        -------
        numpy.ndarray
            The three angles.
        """
        return so3.as_rpy(R)

    def axes(self) -> tuple[Axis, ...]:
        """The RPY angles as axes (:data:`RPY`).

        Returns
        -------
        tuple of Axis
            ``φ``, ``ϑ``, ``ψ``: angles in rad over their RPY ranges.
        """
        return tuple(Axis(symbol, (ascii,), bounds, True, "rad", f"{symbol} ({name}, about {axis})")
                     for symbol, name, axis, ascii, bounds in RPY)

    def from_cli_many(self, numbers) -> np.ndarray:
        """Rotations of RPY angles, vectorised (SciPy's ``"ZYX"`` Euler angles).

        Parameters
        ----------
        numbers : array_like
            ``(φ, ϑ, ψ)`` rows (rad), shape ``(n, 3)``.

        Returns
        -------
        numpy.ndarray
            The rotations, shape ``(n, 3, 3)``.
        """
        from scipy.spatial.transform import Rotation  # loaded when first needed

        return Rotation.from_euler("ZYX", np.asarray(numbers, dtype=float)).as_matrix().reshape(-1, 3, 3)

    def describe_numbers(self, numbers) -> str:
        """RPY angles in words, for messages.

        Parameters
        ----------
        numbers : array_like
            ``(φ, ϑ, ψ)`` (rad).

        Returns
        -------
        str
            ``"RPY(0.5, 1.2, -0.5)"`` (rounded to 3 decimals).
        """
        return f"RPY{tuple(round(float(a), 3) for a in numbers)}"

    #: the columns of a table of rotations (:meth:`columns`)
    column_names = ("qx", "qy", "qz", "qw")

    def columns(self, R) -> dict:
        """Rotations as table columns: their unit quaternions ``(x, y, z, w)``, signs kept
        continuous (:func:`~nonholo.spaces.so3.continuous_quaternions`).

        Parameters
        ----------
        R : numpy.ndarray
            Rotations, shape ``(n, 3, 3)``.

        Returns
        -------
        dict
            ``{"qx": …, "qy": …, "qz": …, "qw": …}``, arrays ``(n,)``.
        """
        quaternion = so3.continuous_quaternions(R)
        return {name: quaternion[:, i] for i, name in enumerate(self.column_names)}

    def difference_text(self, a: str, b: str) -> str:
        """:meth:`difference` of rotations named ``a`` and ``b``, for messages.

        Parameters
        ----------
        a, b : str
            The rotations' names.

        Returns
        -------
        str
            ``"log(a bᵀ)"``.
        """
        return f"log({a} {b}ᵀ)"

    def __repr__(self) -> str:
        return "SO3()"

    def __eq__(self, other) -> bool:
        return isinstance(other, SO3)

    def __hash__(self) -> int:
        return hash("SO3")


class FixedRotation:
    """The rotation factor of a mechanism without an orientation: the identity alone
    (``dim = 0``; no variation, no error, left out of the caller's forms). Its methods take
    and give what :class:`SO3`'s do."""

    dim = 0
    #: the state's part it owns
    part = "rotation"
    cli_names = ()
    name = ""
    units = ()

    def describe(self) -> str:
        """What a state of this factor is, for messages.

        Returns
        -------
        str
            ``""``: the caller never gives this part.
        """
        return ""

    def identity(self) -> np.ndarray:
        """The one state.

        Returns
        -------
        numpy.ndarray
            ``I`` (3×3), a copy.
        """
        return IDENTITY.copy()

    def parse(self, value, name: str) -> np.ndarray:
        """The one state, whatever the caller's form holds (it has no rotation).

        Parameters
        ----------
        value : object
            Unused.
        name : str
            Unused.

        Returns
        -------
        numpy.ndarray
            ``I`` (3×3).
        """
        return IDENTITY.copy()

    def difference(self, R, Rd) -> np.ndarray:
        """The empty variation.

        Parameters
        ----------
        R, Rd : array_like
            Unused.

        Returns
        -------
        numpy.ndarray
            Shape ``(0,)``.
        """
        return np.zeros(0)

    def error(self, R, Rd) -> tuple[np.ndarray, float]:
        """No error.

        Parameters
        ----------
        R, Rd : array_like
            Unused.

        Returns
        -------
        tuple of (numpy.ndarray, float)
            ``(∅, 0)``.
        """
        return np.zeros(0), 0.0

    def distance(self, R1, R2) -> float:
        """No distance.

        Parameters
        ----------
        R1, R2 : array_like
            Unused.

        Returns
        -------
        float
            ``0``.
        """
        return 0.0

    def interpolate(self, Ra, Rb, s) -> np.ndarray:
        """The one state at each fraction.

        Parameters
        ----------
        Ra, Rb : array_like
            Unused.
        s : array_like
            Fractions of the way, shape ``(n,)``.

        Returns
        -------
        numpy.ndarray
            ``I``, shape ``(n, 3, 3)``.
        """
        return np.broadcast_to(IDENTITY, (np.size(s), 3, 3))

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` copies of the one state (no random numbers drawn).

        Parameters
        ----------
        rng : numpy.random.Generator
            Unused.
        n : int
            How many.

        Returns
        -------
        numpy.ndarray
            ``I``, shape ``(n, 3, 3)``.
        """
        return np.broadcast_to(IDENTITY, (n, 3, 3))

    def retract(self, R, s) -> np.ndarray:
        """``R`` unmoved (the variation is empty).

        Parameters
        ----------
        R : array_like
            The state (the identity), or a stack of them.
        s : array_like
            The empty variation.

        Returns
        -------
        numpy.ndarray
            ``R``.
        """
        return np.asarray(R, dtype=float)

    def to_json(self, R) -> list:
        """No JSON: the part is left out.

        Parameters
        ----------
        R : array_like
            Unused.

        Returns
        -------
        list
            ``[]``.
        """
        return []

    def from_json(self, value, name: str) -> np.ndarray:
        """The one state.

        Parameters
        ----------
        value : object
            Unused.
        name : str
            Unused.

        Returns
        -------
        numpy.ndarray
            ``I`` (3×3).
        """
        return IDENTITY.copy()

    def from_cli(self, numbers) -> np.ndarray:
        """The one state (it takes no numbers).

        Parameters
        ----------
        numbers : array_like
            Empty.

        Returns
        -------
        numpy.ndarray
            ``I`` (3×3).
        """
        return IDENTITY.copy()

    def to_cli(self, R) -> np.ndarray:
        """No numbers.

        Parameters
        ----------
        R : array_like
            Unused.

        Returns
        -------
        numpy.ndarray
            Shape ``(0,)``.
        """
        return np.zeros(0)

    def axes(self) -> tuple:
        """No axes.

        Returns
        -------
        tuple
            ``()``.
        """
        return ()

    def from_cli_many(self, numbers) -> np.ndarray:
        """The identity for each row of ``numbers``.

        Parameters
        ----------
        numbers : array_like
            Shape ``(n, 0)``.

        Returns
        -------
        numpy.ndarray
            ``I`` ``n`` times, shape ``(n, 3, 3)`` (read-only).
        """
        return np.broadcast_to(IDENTITY, (np.shape(numbers)[0], 3, 3))

    def describe_numbers(self, numbers) -> str:
        """No numbers to describe.

        Parameters
        ----------
        numbers : array_like
            Unused.

        Returns
        -------
        str
            ``""``.
        """
        return ""

    column_names = ()

    def columns(self, R) -> dict:
        """No columns.

        Parameters
        ----------
        R : numpy.ndarray
            Unused.

        Returns
        -------
        dict
            ``{}``.
        """
        return {}

    def difference_text(self, a: str, b: str) -> str:
        """No difference.

        Parameters
        ----------
        a, b : str
            Unused.

        Returns
        -------
        str
            ``""``.
        """
        return ""

    def __repr__(self) -> str:
        return "FixedRotation()"

    def __eq__(self, other) -> bool:
        return isinstance(other, FixedRotation)

    def __hash__(self) -> int:
        return hash("FixedRotation")


class Euclidean:
    """``Rᵏ`` with named coordinates; the coordinates flagged in ``angles`` are taken
    modulo ``2π`` by differences (wrapped into ``(−π, π]``) and interpolation.

    Parameters
    ----------
    k : int
        The number of coordinates, ``≥ 0``.
    names : sequence of str, optional
        The coordinates' names (default ``q1 … qk``).
    units : sequence of str, optional
        Their units (default ``""`` each: not given).
    angles : sequence of bool, optional
        Which coordinates are angles (default: none).
    box : float
        Half-width of the box :meth:`sample` draws non-angle coordinates from.

    Raises
    ------
    ValueError
        If ``k`` is not a whole number ``≥ 0``, or ``names``, ``units`` or ``angles`` has
        not ``k`` entries.
    """

    def __init__(self, k: int, *, names=None, units=None, angles=None, box: float = np.pi):
        if int(k) != k or k < 0:
            raise ValueError(f"k must be a whole number ≥ 0, got {k!r}")
        self.dim = int(k)
        #: the state's part it owns
        self.part = "coordinates"
        self.names = tuple(names) if names is not None else tuple(f"q{i + 1}" for i in range(self.dim))
        self.units = tuple(units) if units is not None else ("",) * self.dim
        self.angles = tuple(bool(a) for a in angles) if angles is not None else (False,) * self.dim
        for field, value in (("names", self.names), ("units", self.units), ("angles", self.angles)):
            if len(value) != self.dim:
                raise ValueError(f"{field} must have {self.dim} entries, got {len(value)}")
        #: half-width of the box :meth:`sample` draws non-angle coordinates from
        self.box = float(box)
        self._wrapped = np.asarray(self.angles, dtype=bool)

    @property
    def name(self) -> str:
        """``"R^k"``."""
        return f"R^{self.dim}"

    @property
    def cli_names(self) -> tuple[str, ...]:
        """The coordinates' names, the numbers of a state on the command line."""
        return self.names

    def describe(self) -> str:
        """What a state of this factor is, for messages.

        Returns
        -------
        str
            ``"a vector of its k coordinates (names)"``.
        """
        return f"a vector of its {self.dim} coordinates ({', '.join(self.names)})"

    def parse(self, value, name: str, want: str | None = None) -> np.ndarray:
        """``value`` as ``k`` finite numbers.

        Parameters
        ----------
        value : array_like
            The caller's coordinates.
        name : str
            The argument's name, for messages.
        want : str, optional
            What the whole state should be, for messages (default: this factor's
            :meth:`describe`).

        Returns
        -------
        numpy.ndarray
            The coordinates, shape ``(k,)``.

        Raises
        ------
        ValueError
            Naming ``name``, if ``value`` is not ``k`` finite real numbers.
        """
        want = want or f"{name} must be {self.describe()}"
        try:
            q = real_array(value, name)
        except ValueError as exc:
            raise ValueError(f"{want}, got {kind_of(value)} ({exc})") from None
        if q.shape != (self.dim,):
            raise ValueError(f"{want}: {name} has shape {q.shape}, expected ({self.dim},)")
        if not np.all(np.isfinite(q)):
            raise ValueError(f"{name} must be finite, got {q}")
        return q

    def identity(self) -> np.ndarray:
        """The origin.

        Returns
        -------
        numpy.ndarray
            Zeros, shape ``(k,)``.
        """
        return np.zeros(self.dim)

    def difference(self, q, qd) -> np.ndarray:
        """``q − q_d`` with the angle coordinates wrapped.

        Parameters
        ----------
        q, qd : array_like
            Coordinates, shape ``(k,)`` or stacks ``(n, k)``.

        Returns
        -------
        numpy.ndarray
            The difference, of their shape.
        """
        d = np.asarray(q, dtype=float) - np.asarray(qd, dtype=float)
        if self._wrapped.any():
            d[..., self._wrapped] = wrap(d[..., self._wrapped])
        return d

    def error(self, q, qd) -> tuple[np.ndarray, float]:
        """``(δq, |δq|)`` of :meth:`difference`.

        Parameters
        ----------
        q, qd : array_like
            Coordinates, shape ``(k,)``.

        Returns
        -------
        tuple of (numpy.ndarray, float)
            The difference and its norm (in the coordinates' units).
        """
        d = self.difference(q, qd)
        return d, float(np.linalg.norm(d))

    def distance(self, q1, q2) -> float:
        """``|q1 ⊖ q2|``.

        Parameters
        ----------
        q1, q2 : array_like
            Coordinates, shape ``(k,)``.

        Returns
        -------
        float
            The norm of :meth:`difference`.
        """
        return self.error(q1, q2)[1]

    def interpolate(self, qa, qb, s) -> np.ndarray:
        """``q_a + s·(q_b ⊖ q_a)`` at the fractions ``s``.

        Parameters
        ----------
        qa, qb : array_like
            The ends, shape ``(k,)``.
        s : array_like
            Fractions of the way, shape ``(n,)``.

        Returns
        -------
        numpy.ndarray
            The points, shape ``(n, k)``.
        """
        s = np.atleast_1d(np.asarray(s, dtype=float))
        step = self.difference(qb, qa)
        return np.asarray(qa, dtype=float)[None] + s[:, None] * step[None]

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` points, uniform in ``[−box, box]`` (angles in ``(−π, π]``).

        Parameters
        ----------
        rng : numpy.random.Generator
            The random numbers.
        n : int
            How many.

        Returns
        -------
        numpy.ndarray
            The points, shape ``(n, k)``.
        """
        half = np.where(self._wrapped, np.pi, self.box)
        return rng.uniform(-1.0, 1.0, size=(n, self.dim)) * half

    def retract(self, q, s) -> np.ndarray:
        """``q + s``: the coordinates moved by the variation ``s``.

        Parameters
        ----------
        q, s : array_like
            Coordinates and a variation, shape ``(k,)``.

        Returns
        -------
        numpy.ndarray
            The moved coordinates.
        """
        return np.asarray(q, dtype=float) + np.asarray(s, dtype=float)

    def to_json(self, q) -> list:
        """Coordinates as JSON.

        Parameters
        ----------
        q : array_like
            Coordinates, shape ``(k,)``.

        Returns
        -------
        list
            The numbers as floats.
        """
        return np.asarray(q, dtype=float).tolist()

    def from_json(self, value, name: str) -> np.ndarray:
        """The coordinates of :meth:`to_json`'s form.

        Parameters
        ----------
        value : list
            ``k`` numbers.
        name : str
            The field's name, for messages.

        Returns
        -------
        numpy.ndarray
            The coordinates, shape ``(k,)``.
        """
        return self.parse(value, name)

    def from_cli(self, numbers) -> np.ndarray:
        """The coordinates of their command-line numbers.

        Parameters
        ----------
        numbers : array_like
            ``k`` numbers.

        Returns
        -------
        numpy.ndarray
            The coordinates (a copy).
        """
        return np.asarray(numbers, dtype=float).copy()

    def to_cli(self, q) -> np.ndarray:
        """The command-line numbers of coordinates.

        Parameters
        ----------
        q : array_like
            Coordinates, shape ``(k,)``.

        Returns
        -------
        numpy.ndarray
            The numbers (a copy).
        """
        return np.asarray(q, dtype=float).copy()

    def axes(self) -> tuple[Axis, ...]:
        """The coordinates as axes.

        Returns
        -------
        tuple of Axis
            One per coordinate: an angle over ``(−π, π)``, another over ``(−box, box)``.
        """
        return tuple(Axis(name, (), (-np.pi, np.pi) if angle else (-self.box, self.box), angle, unit, name)
                     for name, unit, angle in zip(self.names, self.units, self.angles))

    def from_cli_many(self, numbers) -> np.ndarray:
        """Coordinates of their command-line numbers, vectorised.

        Parameters
        ----------
        numbers : array_like
            Shape ``(n, k)``.

        Returns
        -------
        numpy.ndarray
            The coordinates, shape ``(n, k)``.
        """
        return np.asarray(numbers, dtype=float)

    def describe_numbers(self, numbers) -> str:
        """Coordinates in words, for messages.

        Parameters
        ----------
        numbers : array_like
            The ``k`` coordinates.

        Returns
        -------
        str
            ``"(x, y) = (0.0, 1.0)"`` (rounded to 3 decimals); ``""`` for ``k = 0``.
        """
        if not self.dim:
            return ""
        return f"({', '.join(self.names)}) = {tuple(round(float(a), 3) for a in numbers)}"

    @property
    def column_names(self) -> tuple[str, ...]:
        """The columns of a table of coordinates: their names."""
        return self.names

    def columns(self, q) -> dict:
        """Coordinates as table columns.

        Parameters
        ----------
        q : numpy.ndarray
            Coordinates, shape ``(n, k)``.

        Returns
        -------
        dict
            ``{name: q[:, i]}``.
        """
        return {name: q[:, i] for i, name in enumerate(self.names)}

    def difference_text(self, a: str, b: str) -> str:
        """:meth:`difference` of coordinates named ``a`` and ``b``, for messages.

        Parameters
        ----------
        a, b : str
            The coordinates' names.

        Returns
        -------
        str
            ``"a ⊖ b"``.
        """
        return f"{a} ⊖ {b}"

    def __repr__(self) -> str:
        return f"Euclidean({self.dim}, names={self.names!r}, angles={self.angles!r})"

    def __eq__(self, other) -> bool:
        return (isinstance(other, Euclidean) and (self.dim, self.names, self.angles)
                == (other.dim, other.names, other.angles))

    def __hash__(self) -> int:
        return hash((self.dim, self.names, self.angles))


