"""State spaces as objects: :class:`SO3`, :class:`Euclidean` and their :class:`Product`.

Conventions
-----------
- A *factor* (:class:`SO3`, :class:`Euclidean`) owns one part of a state: a rotation
  matrix ``R`` (3×3) or ``k`` coordinates ``q``. It parses and describes the caller's form
  of its part, takes differences (``log(R R_dᵀ)``, rad; ``q − q_d`` with angle coordinates
  wrapped into ``(−π, π]``), distances, interpolates (the geodesic; the straight line,
  angles the short way round), samples (Haar; a box) and writes JSON and command-line
  numbers (RPY angles in rad; the coordinates).
- A mechanism's space is a :class:`Product` of at most one :class:`SO3` and one
  :class:`Euclidean` factor; its states are pairs ``(R, q)`` throughout the package: ``R``
  is the identity, untouched, without an orientation, and ``q`` has shape ``(0,)`` without
  coordinates (an SO(3) mechanism is the product with ``k = 0``). The terminal error is
  the stacked vector ``e = (l, δq)`` of a variation ``s = (s_R, s_q)``; its parts are
  reported by name (``"rotation"`` in rad, ``"coordinates"`` in the mechanism's units).
- Units: each coordinate has one (``Euclidean.units``, ``""`` if not given), the
  rotation's rows are in rad; an error's norm is written with :meth:`Product.amount` (its
  unit, or the units it mixes: ``"3e-11 (wheelbase, rad)"``).
- The caller's form of a state: a rotation matrix for SO(3), the ``k`` numbers for
  ``Rᵏ``, the pair ``(R, q)`` for ``SO(3) × Rᵏ``; in JSON the same with nested lists
  (``[R, q]`` for the pair).
"""
from __future__ import annotations

import numpy as np

from ..numerics import kernels
from ..numerics.checks import real_array
from . import so3

IDENTITY = np.eye(3)
NO_COORDINATES = np.zeros(0)


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


def _kind(value) -> str:
    try:
        shape = np.shape(value)
    except ValueError:
        return type(value).__name__
    return f"an array of shape {shape}" if shape else type(value).__name__


class SO3:
    """The rotation group: states ``R`` (3×3), errors ``log(R R_dᵀ)`` (rad)."""

    dim = 3
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

    def __repr__(self) -> str:
        return "SO3()"

    def __eq__(self, other) -> bool:
        return isinstance(other, SO3)

    def __hash__(self) -> int:
        return hash("SO3")


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
            raise ValueError(f"{want}, got {_kind(value)} ({exc})") from None
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

    def __repr__(self) -> str:
        return f"Euclidean({self.dim}, names={self.names!r}, angles={self.angles!r})"

    def __eq__(self, other) -> bool:
        return (isinstance(other, Euclidean) and (self.dim, self.names, self.angles)
                == (other.dim, other.names, other.angles))

    def __hash__(self) -> int:
        return hash((self.dim, self.names, self.angles))


class Product:
    """``SO(3) × Rᵏ``, ``SO(3)`` (``k = 0``) or ``Rᵏ``: the state space of a mechanism,
    states ``(R, q)`` (see the module docstring).

    Parameters
    ----------
    rotation : SO3, optional
        The rotation factor (``None``: no orientation).
    coordinates : Euclidean, optional
        The coordinate factor (``None``: no coordinates).

    Raises
    ------
    ValueError
        If neither factor is given.
    """

    def __init__(self, rotation: SO3 | None = None, coordinates: Euclidean | None = None):
        if rotation is None and coordinates is None:
            raise ValueError("a product needs a rotation factor, a coordinate factor or both")
        self.rotation = rotation
        self.coordinates = coordinates if coordinates is not None else Euclidean(0)
        self.factors = tuple(f for f in (rotation, coordinates) if f is not None and f.dim)
        #: ``d``: rows of the stacked field ``G``; size of a variation ``s = (s_R, s_q)``
        self.dim = (3 if rotation is not None else 0) + self.coordinates.dim
        if rotation is None:
            self.error = self._coordinates_error
        elif not self.coordinates.dim:
            self.error = self._rotation_error

    @classmethod
    def of(cls, orientation: bool, names=(), units=None, angles=None) -> "Product":
        """The space of a mechanism with or without an orientation and the coordinates
        ``names``.

        Parameters
        ----------
        orientation : bool
            Whether the state has a rotation ``R``.
        names : sequence of str
            The coordinates' names (none: no coordinates).
        units, angles : sequence, optional
            The coordinates' units and which are angles, as :class:`Euclidean` takes them.

        Returns
        -------
        Product
            The space.
        """
        coords = Euclidean(len(names), names=names, units=units, angles=angles) if len(names) else None
        return cls(SO3() if orientation else None, coords)

    @property
    def has_orientation(self) -> bool:
        """Whether the states have a rotation ``R``."""
        return self.rotation is not None

    @property
    def k(self) -> int:
        """The number of coordinates ``q``."""
        return self.coordinates.dim

    @property
    def name(self) -> str:
        """``"SO(3)"``, ``"R^k"`` or ``"SO(3)xR^k"``."""
        return "x".join(f.name for f in self.factors)

    @property
    def cli_names(self) -> tuple[str, ...]:
        """The numbers of a state on the command line, in order."""
        return tuple(n for f in self.factors for n in f.cli_names)

    @property
    def units(self) -> tuple[str, ...]:
        """The unit of each row of a variation ``s = (s_R, s_q)`` (rad for the rotation's)."""
        return (self.rotation.units if self.rotation is not None else ()) + self.coordinates.units

    @property
    def error_unit(self) -> str:
        """The unit of the stacked error's norm ``|e|`` (:func:`unit_of` :attr:`units`)."""
        return unit_of(self.units)

    def part_unit(self, part: str) -> str:
        """The unit of one part of :meth:`error`.

        Parameters
        ----------
        part : {"rotation", "coordinates"}
            The part.

        Returns
        -------
        str
            ``"rad"`` for the rotation; :func:`unit_of` the coordinates' units.

        Raises
        ------
        ValueError
            If ``part`` is neither.
        """
        if part == "rotation":
            return unit_of(SO3.units)
        if part == "coordinates":
            return unit_of(self.coordinates.units)
        raise ValueError(f"part must be 'rotation' or 'coordinates', got {part!r}")

    def amount(self, value, spec: str = ".2g", part: str | None = None) -> str:
        """A norm of errors of this space's states, with its unit.

        Parameters
        ----------
        value : float or None
            The norm (``None``: ``"n/a"``).
        spec : str
            Its format spec.
        part : {"rotation", "coordinates"}, optional
            The part of the error it is a norm of (default: the stacked error).

        Returns
        -------
        str
            ``"3e-11 rad"``, ``"2e-12 wheelbase"``, ``"4e-15 (wheelbase, rad)"``.
        """
        unit = self.error_unit if part is None else self.part_unit(part)
        text = "n/a" if value is None else format(value, spec)
        return f"{text} {unit}" if unit else text

    def describe(self) -> str:
        """What a state is in the caller's form, for messages.

        Returns
        -------
        str
            The one factor's description, or that of the pair ``(R, q)``.
        """
        if len(self.factors) == 1:
            return self.factors[0].describe()
        return (f"a pair (R, q): a rotation matrix R (3×3) and the {self.k} coordinates "
                f"q = ({', '.join(self.coordinates.names)})")

    # -- the caller's form ------------------------------------------------------------

    def parse(self, value, name: str, owner: str = "") -> tuple[np.ndarray, np.ndarray]:
        """The caller's state as ``(R, q)``.

        Parameters
        ----------
        value : array_like or tuple
            The state in the caller's form (module docstring).
        name : str
            The argument's name, for messages.
        owner : str
            Appended to what the space expects, e.g. ``" for mechanism 'x'"``.

        Returns
        -------
        tuple of numpy.ndarray
            ``(R, q)``: ``R`` the identity without an orientation, ``q`` of shape ``(0,)``
            without coordinates.

        Raises
        ------
        ValueError
            Saying what the space expects, if ``value`` is not a state of it.
        """
        want = f"{name} must be {self.describe()}{owner}"
        if self.rotation is None:
            if isinstance(value, tuple) and len(value) == 2 and np.ndim(value[0]) == 2:
                raise ValueError(f"{want}, got a pair (R, q): this mechanism has no orientation")
            return IDENTITY.copy(), self.coordinates.parse(value, name, want)
        if not self.k:
            if isinstance(value, tuple):
                raise ValueError(f"{want}, got a pair")
            return self.rotation.parse(value, name), NO_COORDINATES
        if not (isinstance(value, (tuple, list)) and len(value) == 2):
            raise ValueError(f"{want}, got {_kind(value)}")
        R = self.rotation.parse(value[0], f"{name}[0] (the orientation)")
        return R, self.coordinates.parse(value[1], f"{name}[1] (the coordinates)", want)

    def public(self, R, q):
        """The state ``(R, q)`` in the caller's form.

        Parameters
        ----------
        R, q : numpy.ndarray
            The state's rotation and coordinates.

        Returns
        -------
        numpy.ndarray or tuple
            ``R``, ``q`` or ``(R, q)``.
        """
        if self.rotation is None:
            return q
        return (R, q) if self.k else R

    # -- differences, distances, paths ----------------------------------------------

    def error(self, R, q, Rd, qd) -> tuple[np.ndarray, dict]:
        """The stacked terminal error ``e = (l, δq)`` of ``(R, q)`` from ``(R_d, q_d)``.

        The factors' case is chosen once, in ``__init__``: this runs at every planner
        iteration.

        Parameters
        ----------
        R, q : numpy.ndarray
            The state.
        Rd, qd : numpy.ndarray
            The goal.

        Returns
        -------
        tuple of (numpy.ndarray, dict)
            ``(e, parts)``: ``e`` and the norms of its parts by name (``"rotation"`` in rad,
            ``"coordinates"`` in the mechanism's units; the parts the state has).
        """
        l, rot = self.rotation.error(R, Rd)
        dq, coord = self.coordinates.error(q, qd)
        return np.concatenate((l, dq)), {"rotation": rot, "coordinates": coord}

    def _rotation_error(self, R, q, Rd, qd) -> tuple[np.ndarray, dict]:
        l, rot = self.rotation.error(R, Rd)
        return l, {"rotation": rot}

    def _coordinates_error(self, R, q, Rd, qd) -> tuple[np.ndarray, dict]:
        dq, coord = self.coordinates.error(q, qd)
        return dq, {"coordinates": coord}

    def norm(self, parts: dict) -> float:
        """``|e|`` from the norms of its parts.

        Parameters
        ----------
        parts : dict
            The parts' norms by name, as :meth:`error` gives them.

        Returns
        -------
        float
            ``|e|``.
        """
        if len(parts) == 1:
            (value,) = parts.values()
            return float(value)
        return float(np.hypot(parts["rotation"], parts["coordinates"]))

    def distance(self, R, q, Rd, qd) -> float:
        """``|e|`` of :meth:`error`.

        Parameters
        ----------
        R, q : numpy.ndarray
            The state.
        Rd, qd : numpy.ndarray
            The goal.

        Returns
        -------
        float
            ``|e|``.
        """
        return self.norm(self.error(R, q, Rd, qd)[1])

    def offset(self, R0, q0, Rd, qd) -> np.ndarray:
        """The stacked displacement ``(log(R_d R0ᵀ), q_d ⊖ q0)`` from start to goal.

        Parameters
        ----------
        R0, q0 : numpy.ndarray
            The start.
        Rd, qd : numpy.ndarray
            The goal.

        Returns
        -------
        numpy.ndarray
            The displacement, shape ``(d,)``.
        """
        return self.error(Rd, qd, R0, q0)[0]

    def interpolate(self, a, b, s) -> list[tuple[np.ndarray, np.ndarray]]:
        """The states of the straight path ``a → b`` (geodesic × straight line).

        Parameters
        ----------
        a, b : tuple of numpy.ndarray
            The ends, ``(R, q)``.
        s : array_like
            Fractions of the way, shape ``(n,)``.

        Returns
        -------
        list of tuple
            The ``n`` states ``(R, q)``.
        """
        (Ra, qa), (Rb, qb) = a, b
        s = np.atleast_1d(np.asarray(s, dtype=float))
        R = (self.rotation.interpolate(Ra, Rb, s) if self.rotation is not None
             else np.broadcast_to(IDENTITY, (s.size, 3, 3)))
        q = self.coordinates.interpolate(qa, qb, s)
        return [(np.array(R[i]), q[i]) for i in range(s.size)]

    def sample(self, rng: np.random.Generator, n: int) -> list[tuple[np.ndarray, np.ndarray]]:
        """``n`` states, uniform: Haar on SO(3) × the coordinates' box.

        Parameters
        ----------
        rng : numpy.random.Generator
            The random numbers.
        n : int
            How many.

        Returns
        -------
        list of tuple
            The ``n`` states ``(R, q)``.
        """
        R = self.rotation.sample(rng, n) if self.rotation is not None else np.broadcast_to(IDENTITY, (n, 3, 3))
        q = self.coordinates.sample(rng, n)
        return [(np.array(R[i]), q[i]) for i in range(n)]

    # -- JSON and the command line --------------------------------------------------

    def to_json(self, R, q):
        """The state as JSON.

        Parameters
        ----------
        R, q : numpy.ndarray
            The state.

        Returns
        -------
        list
            A rotation as nested lists, coordinates as a list, the pair as ``[R, q]``.
        """
        if self.rotation is None:
            return self.coordinates.to_json(q)
        if not self.k:
            return self.rotation.to_json(R)
        return [self.rotation.to_json(R), self.coordinates.to_json(q)]

    def from_json(self, value, name: str) -> tuple[np.ndarray, np.ndarray]:
        """The state of :meth:`to_json`'s form.

        Parameters
        ----------
        value : list
            The JSON value.
        name : str
            The field's name, for messages.

        Returns
        -------
        tuple of numpy.ndarray
            ``(R, q)``.
        """
        if self.rotation is not None and self.k and isinstance(value, list) and len(value) == 2:
            value = (value[0], value[1])
        return self.parse(value, name)

    def from_cli(self, numbers) -> tuple[np.ndarray, np.ndarray]:
        """The state of its command-line numbers.

        Parameters
        ----------
        numbers : array_like
            :attr:`cli_names`: RPY angles in rad, then the coordinates.

        Returns
        -------
        tuple of numpy.ndarray
            ``(R, q)``.

        Raises
        ------
        ValueError
            If there are not as many numbers as :attr:`cli_names`.
        """
        numbers = np.asarray(numbers, dtype=float)
        if numbers.shape != (len(self.cli_names),):
            raise ValueError(f"a state takes {len(self.cli_names)} numbers "
                             f"({' '.join(self.cli_names)}), got {numbers.size}")
        r = 3 if self.rotation is not None else 0
        R = self.rotation.from_cli(numbers[:3]) if r else IDENTITY.copy()
        return R, self.coordinates.from_cli(numbers[r:])

    def to_cli(self, R, q) -> np.ndarray:
        """The command-line numbers of a state, inverse of :meth:`from_cli`.

        Parameters
        ----------
        R, q : numpy.ndarray
            The state.

        Returns
        -------
        numpy.ndarray
            RPY angles in rad (with an orientation), then the coordinates.
        """
        parts = ([self.rotation.to_cli(R)] if self.rotation is not None else []) + [self.coordinates.to_cli(q)]
        return np.concatenate(parts)

    def __repr__(self) -> str:
        return f"Product({', '.join(map(repr, self.factors))})"

    def __eq__(self, other) -> bool:
        return isinstance(other, Product) and (self.rotation, self.coordinates) == (other.rotation, other.coordinates)

    def __hash__(self) -> int:
        return hash((self.rotation, self.coordinates))
