"""A mechanism's state space: :class:`Product`, the product of its factors.

Conventions
-----------
- A product has a rotation factor (:class:`~nonholo.spaces.rotation_factors.SO3`, or the
  trivial :class:`~nonholo.spaces.rotation_factors.FixedRotation` for a mechanism without an
  orientation) and a coordinate factor (:class:`~nonholo.spaces.euclidean.Euclidean`,
  ``k ≥ 0``), like OMPL's compound state space or manif's bundle. Its states are
  :class:`~nonholo.spaces.state.State` values ``(R, q)``; every method loops over the factors,
  so no caller asks which kind of space it has.
- The terminal error is the stacked vector ``e = (l, δq)`` of a variation ``s = (s_R, s_q)``
  (the factors' variations, in order); its parts are reported by name (``"rotation"`` in rad,
  ``"coordinates"`` in the mechanism's units), the parts the space has.
- The caller's form of a state: that of the one non-trivial factor (a rotation matrix for
  SO(3), the ``k`` numbers for ``Rᵏ``), or the pair ``(R, q)`` for ``SO(3) × Rᵏ``; in JSON the
  same with nested lists (``[R, q]`` for the pair). Units: an error's norm is written with
  :meth:`Product.amount` (its unit, or the units it mixes: ``"3e-11 (wheelbase, rad)"``).
"""
from __future__ import annotations

import numpy as np

from .axes import kind_of, unit_of
from .euclidean import Euclidean
from .rotation_factors import SO3, FixedRotation
from .state import State


class Product:
    """``SO(3) × Rᵏ``, ``SO(3)`` or ``Rᵏ``: the product of ``factors`` (see the module).

    Parameters
    ----------
    *factors : SO3 or Euclidean
        At most one rotation factor and one coordinate factor, the rotation first; a part not
        given is trivial (:class:`~nonholo.spaces.rotation_factors.FixedRotation`, ``Euclidean(0)``).

    Raises
    ------
    ValueError
        If no factor has a variation, or the factors are not one of each part in order.
    """

    def __init__(self, *factors):
        by_part = {}
        for f in factors:
            part = getattr(f, "part", None)
            if part not in ("rotation", "coordinates") or part in by_part or (part == "rotation" and by_part):
                raise ValueError(f"a product takes a rotation factor then a coordinate factor, got {factors!r}")
            by_part[part] = f
        self.rotation = by_part.get("rotation", FixedRotation())
        self.coordinates = by_part.get("coordinates", Euclidean(0))
        #: the factors, in the order of a state's parts ``(R, q)``
        self.factors = (self.rotation, self.coordinates)
        #: the factors the caller's form holds: those with a variation
        self.visible = tuple(f for f in self.factors if f.dim)
        if not self.visible:
            raise ValueError("a product needs a rotation factor, a coordinate factor or both")
        #: ``d``: rows of the stacked field ``G``; size of a variation ``s = (s_R, s_q)``
        self.dim = sum(f.dim for f in self.factors)

    @classmethod
    def of(cls, orientation: bool, names=(), units=None, angles=None) -> "Product":
        """The space of a mechanism with or without an orientation and the coordinates ``names``.

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
        factors = (SO3(),) if orientation else ()
        if len(names):
            factors += (Euclidean(len(names), names=names, units=units, angles=angles),)
        return cls(*factors)

    @property
    def has_orientation(self) -> bool:
        """Whether the states have a rotation ``R`` that varies."""
        return bool(self.rotation.dim)

    @property
    def k(self) -> int:
        """The number of coordinates ``q``."""
        return self.coordinates.dim

    @property
    def name(self) -> str:
        """``"SO(3)"``, ``"R^k"`` or ``"SO(3)xR^k"``."""
        return "x".join(f.name for f in self.visible)

    @property
    def cli_names(self) -> tuple[str, ...]:
        """The numbers of a state on the command line, in order."""
        return tuple(n for f in self.factors for n in f.cli_names)

    @property
    def units(self) -> tuple[str, ...]:
        """The unit of each row of a variation ``s = (s_R, s_q)`` (rad for the rotation's)."""
        return tuple(u for f in self.factors for u in f.units)

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
        if len(self.visible) == 1:
            return self.visible[0].describe()
        return (f"a pair (R, q): a rotation matrix R (3×3) and the {self.k} coordinates "
                f"q = ({', '.join(self.coordinates.names)})")

    def identity(self) -> State:
        """The state ``(I, 0)``.

        Returns
        -------
        State
            The identity rotation and zero coordinates.
        """
        return State(self.rotation.identity(), self.coordinates.identity())

    def state(self, R=None, q=None) -> State:
        """A state of the parts given, the others at the identity.

        Parameters
        ----------
        R : array_like, optional
            The orientation (default: the identity).
        q : array_like, optional
            The coordinates (default: zeros).

        Returns
        -------
        State
            ``(R, q)``.
        """
        return State(self.rotation.identity() if R is None else R, self.coordinates.identity() if q is None else q)

    def rows(self, part: str) -> slice:
        """The rows of one part of the state in a variation ``s = (s_R, s_q)``, ``G`` and ``e``.

        Parameters
        ----------
        part : {"rotation", "coordinates"}
            The part.

        Returns
        -------
        slice
            Its rows (empty where the states do not have the part).
        """
        factor = self._factor(part)
        start = self.rotation.dim if factor is self.coordinates else 0
        return slice(start, start + factor.dim)

    def recorded(self, part: str, value, otherwise=None):
        """What a record of this space's states keeps of one of their parts: ``value`` where the
        states have the part, ``otherwise`` where they do not (a plan on SO(3) records no ``q``).

        Parameters
        ----------
        part : {"rotation", "coordinates"}
            The part.
        value
            What the record holds of it.
        otherwise
            What it holds in its place.

        Returns
        -------
        object
            ``value`` or ``otherwise``.
        """
        return value if self._factor(part).dim else otherwise

    def _factor(self, part: str):
        """The factor that owns ``part`` (``ValueError`` naming it for another)."""
        for f in self.factors:
            if f.part == part:
                return f
        raise ValueError(f"part must be 'rotation' or 'coordinates', got {part!r}")

    # -- the caller's form ------------------------------------------------------------

    def parse(self, value, name: str, owner: str = "") -> State:
        """The caller's state as a :class:`~nonholo.spaces.state.State`.

        Parameters
        ----------
        value : array_like, tuple or State
            The state in the caller's form (module docstring), or a state.
        name : str
            The argument's name, for messages.
        owner : str
            Appended to what the space expects, e.g. ``" for mechanism 'x'"``.

        Returns
        -------
        State
            The state, checked.

        Raises
        ------
        ValueError
            Saying what the space expects, if ``value`` is not a state of it.
        """
        if isinstance(value, State):
            value = self.public(value)
        want = f"{name} must be {self.describe()}{owner}"
        if not self.rotation.dim:
            if isinstance(value, tuple) and len(value) == 2 and np.ndim(value[0]) == 2:
                raise ValueError(f"{want}, got a pair (R, q): this mechanism has no orientation")
            return State(self.rotation.identity(), self.coordinates.parse(value, name, want))
        if not self.k:
            if isinstance(value, tuple):
                raise ValueError(f"{want}, got a pair")
            return State(self.rotation.parse(value, name), self.coordinates.identity())
        if not (isinstance(value, (tuple, list)) and len(value) == 2):
            raise ValueError(f"{want}, got {kind_of(value)}")
        R = self.rotation.parse(value[0], f"{name}[0] (the orientation)")
        return State(R, self.coordinates.parse(value[1], f"{name}[1] (the coordinates)", want))

    def public(self, x):
        """The state ``x`` in the caller's form.

        Parameters
        ----------
        x : State or tuple
            The state ``(R, q)``.

        Returns
        -------
        numpy.ndarray or tuple
            ``R``, ``q`` or ``(R, q)``.
        """
        parts = tuple(p for f, p in zip(self.factors, x) if f.dim)
        return parts[0] if len(parts) == 1 else parts

    # -- differences, distances, paths ----------------------------------------------

    def error(self, x, goal) -> tuple[np.ndarray, dict]:
        """The stacked terminal error ``e = (l, δq)`` of the state ``x`` from ``goal``.

        Parameters
        ----------
        x, goal : State or tuple
            The state and the goal, ``(R, q)``.

        Returns
        -------
        tuple of (numpy.ndarray, dict)
            ``(e, parts)``: ``e`` and the norms of its parts by name (``"rotation"`` in rad,
            ``"coordinates"`` in the mechanism's units; the parts the space has).
        """
        rows, parts = [], {}
        for f, a, b in zip(self.factors, x, goal):
            if f.dim:
                d, n = f.error(a, b)
                rows.append(d)
                parts[f.part] = n
        return (rows[0] if len(rows) == 1 else np.concatenate(rows)), parts

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

    def distance(self, x, y) -> float:
        """``|e|`` of :meth:`error`.

        Parameters
        ----------
        x, y : State or tuple
            Two states.

        Returns
        -------
        float
            ``|e|``.
        """
        return self.norm(self.error(x, y)[1])

    def distance_text(self, x, goal) -> str:
        """:meth:`distance` of two states named by their parts, for messages.

        Parameters
        ----------
        x, goal : tuple of str
            The names of the parts ``(R, q)`` of each state, e.g. ``("R[-1]", "q[-1]")``.

        Returns
        -------
        str
            ``"|log(R[-1] Rdᵀ)|"`` on SO(3), ``"|q[-1] ⊖ qd|"`` on ``Rᵏ``, both on ``SO(3) × Rᵏ``.
        """
        parts = [f.difference_text(a, b) for f, a, b in zip(self.factors, x, goal) if f.dim]
        return f"|{parts[0]}|" if len(parts) == 1 else f"|({', '.join(parts)})|"

    def offset(self, start, goal) -> np.ndarray:
        """The stacked displacement ``(log(R_d R0ᵀ), q_d ⊖ q0)`` from ``start`` to ``goal``.

        Parameters
        ----------
        start, goal : State or tuple
            The two states.

        Returns
        -------
        numpy.ndarray
            The displacement, shape ``(d,)``.
        """
        return self.error(goal, start)[0]

    def retract(self, x, s) -> State:
        """``x ⊕ s = (exp([s_R]) R, q + s_q)``: the state ``x`` moved by the variation ``s``.

        Parameters
        ----------
        x : State or tuple
            The state.
        s : array_like
            The variation, shape ``(d,)``.

        Returns
        -------
        State
            The moved state.
        """
        s = np.asarray(s, dtype=float)
        r = self.rotation.dim
        return State(self.rotation.retract(x[0], s[:r]), self.coordinates.retract(x[1], s[r:]))

    def retract_stack(self, R, q, s) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`retract` of a stack of states by one variation: ``(exp([s_R]) R_n, q_n + s_q)``.

        Parameters
        ----------
        R, q : numpy.ndarray
            The states' rotations ``(n, 3, 3)`` and coordinates ``(n, k)``.
        s : array_like
            The variation, shape ``(d,)``.

        Returns
        -------
        tuple of numpy.ndarray
            The moved rotations and coordinates.
        """
        s = np.asarray(s, dtype=float)
        r = self.rotation.dim
        R = R if not r else self.rotation.retract(R, s[:r])
        return R, self.coordinates.retract(q, s[r:])

    def perturb(self, x, i: int, eps: float) -> State:
        """``x`` moved by ``eps`` along the ``i``-th row of a variation (a finite difference).

        Parameters
        ----------
        x : State or tuple
            The state.
        i : int
            The row, ``0 ≤ i < d``.
        eps : float
            The step (rad or the coordinate's unit).

        Returns
        -------
        State
            The moved state.
        """
        s = np.zeros(self.dim)
        s[i] = eps
        return self.retract(x, s)

    def interpolate(self, a, b, s) -> list[State]:
        """The states of the straight path ``a → b`` (geodesic × straight line).

        Parameters
        ----------
        a, b : State or tuple
            The ends, ``(R, q)``.
        s : array_like
            Fractions of the way, shape ``(n,)``.

        Returns
        -------
        list of State
            The ``n`` states.
        """
        s = np.atleast_1d(np.asarray(s, dtype=float))
        R = self.rotation.interpolate(a[0], b[0], s)
        q = self.coordinates.interpolate(a[1], b[1], s)
        return [State(R[i], q[i]) for i in range(s.size)]

    def sample(self, rng: np.random.Generator, n: int) -> list[State]:
        """``n`` states, uniform: Haar on SO(3) × the coordinates' box.

        Parameters
        ----------
        rng : numpy.random.Generator
            The random numbers.
        n : int
            How many.

        Returns
        -------
        list of State
            The ``n`` states.
        """
        R = self.rotation.sample(rng, n)
        q = self.coordinates.sample(rng, n)
        return [State(R[i], q[i]) for i in range(n)]

    # -- JSON and the command line --------------------------------------------------

    def to_json(self, x):
        """The state as JSON.

        Parameters
        ----------
        x : State or tuple
            The state.

        Returns
        -------
        list
            A rotation as nested lists, coordinates as a list, the pair as ``[R, q]``.
        """
        parts = [f.to_json(p) for f, p in zip(self.factors, x) if f.dim]
        return parts[0] if len(parts) == 1 else parts

    def from_json(self, value, name: str) -> State:
        """The state of :meth:`to_json`'s form.

        Parameters
        ----------
        value : list
            The JSON value.
        name : str
            The field's name, for messages.

        Returns
        -------
        State
            The state.
        """
        if len(self.visible) == 2 and isinstance(value, list) and len(value) == 2:
            value = (value[0], value[1])
        return self.parse(value, name)

    def from_cli(self, numbers) -> State:
        """The state of its command-line numbers.

        Parameters
        ----------
        numbers : array_like
            :attr:`cli_names`: RPY angles in rad, then the coordinates.

        Returns
        -------
        State
            The state.

        Raises
        ------
        ValueError
            If there are not as many numbers as :attr:`cli_names`.
        """
        numbers = np.asarray(numbers, dtype=float)
        if numbers.shape != (len(self.cli_names),):
            raise ValueError(f"a state takes {len(self.cli_names)} numbers "
                             f"({' '.join(self.cli_names)}), got {numbers.size}")
        r = len(self.rotation.cli_names)
        return State(self.rotation.from_cli(numbers[:r]), self.coordinates.from_cli(numbers[r:]))

    def to_cli(self, x) -> np.ndarray:
        """The command-line numbers of a state, inverse of :meth:`from_cli`.

        Parameters
        ----------
        x : State or tuple
            The state.

        Returns
        -------
        numpy.ndarray
            RPY angles in rad (with an orientation), then the coordinates.
        """
        return np.concatenate([f.to_cli(p) for f, p in zip(self.factors, x)])

    def axes(self, part: str | None = None) -> tuple:
        """The state's command-line numbers as axes of maps and plots, in order.

        Parameters
        ----------
        part : {"rotation", "coordinates"}, optional
            Only those of one part (default: all).

        Returns
        -------
        tuple of Axis
            The RPY angles of a rotation, then the coordinates (:class:`~nonholo.spaces.axes.Axis`:
            name, aliases, default range, angle or not, unit, text).
        """
        factors = self.factors if part is None else (self._factor(part),)
        return tuple(a for f in factors for a in f.axes())

    def axis(self, name: str):
        """One of :meth:`axes` by its name or an alias.

        Parameters
        ----------
        name : str
            A name of :attr:`cli_names` (or an alias, ``phi`` for ``φ``).

        Returns
        -------
        Axis
            The axis.

        Raises
        ------
        ValueError
            If no number of the state has that name.
        """
        axes = self.axes()
        for a in axes:
            if a.name == name:
                return a
        for a in axes:
            if name in a.aliases:
                return a
        raise ValueError(f"{name!r} is not one of the state's numbers ({' '.join(self.cli_names)})")

    def numbers(self, rotation=None, coordinates=None) -> np.ndarray:
        """A state's command-line numbers from those of its parts.

        Parameters
        ----------
        rotation : array_like, optional
            RPY angles (rad) of the rotation (default 0; left out without an orientation).
        coordinates : array_like, optional
            The coordinates (default 0; left out without coordinates).

        Returns
        -------
        numpy.ndarray
            The numbers, :attr:`cli_names` in order.
        """
        given = {"rotation": rotation, "coordinates": coordinates}
        parts = [np.zeros(len(f.cli_names)) if given[f.part] is None or not f.dim
                 else np.asarray(given[f.part], dtype=float).reshape(len(f.cli_names))
                 for f in self.factors]
        return np.concatenate(parts)

    def from_cli_many(self, numbers) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`from_cli` of each row of command-line numbers, vectorised (to rounding).

        Parameters
        ----------
        numbers : array_like
            Shape ``(n, len(cli_names))``.

        Returns
        -------
        tuple of numpy.ndarray
            ``(R, q)``: shapes ``(n, 3, 3)`` and ``(n, k)``.
        """
        numbers = np.asarray(numbers, dtype=float).reshape(-1, len(self.cli_names))
        r = len(self.rotation.cli_names)
        return self.rotation.from_cli_many(numbers[:, :r]), self.coordinates.from_cli_many(numbers[:, r:])

    def describe_numbers(self, numbers) -> str:
        """A state's command-line numbers in words, for messages.

        Parameters
        ----------
        numbers : array_like
            :attr:`cli_names` in order.

        Returns
        -------
        str
            ``"RPY(0.5, 1.2, -0.5)"``, ``"(x, y) = (0.0, 1.0)"`` or both, comma-separated.
        """
        r = len(self.rotation.cli_names)
        parts = (self.rotation.describe_numbers(numbers[:r]), self.coordinates.describe_numbers(numbers[r:]))
        return ", ".join(p for p in parts if p)

    def column_names(self) -> tuple[str, ...]:
        """The columns of a table of states (:meth:`columns`), in order.

        Returns
        -------
        tuple of str
            The coordinates' names, then ``qx, qy, qz, qw`` with an orientation.
        """
        return (*self.coordinates.column_names, *self.rotation.column_names)

    def columns(self, R, q) -> dict:
        """Stacks of states as the columns of a table (a plan's CSV).

        Parameters
        ----------
        R, q : numpy.ndarray
            Rotations ``(n, 3, 3)`` and coordinates ``(n, k)``.

        Returns
        -------
        dict
            The coordinates by name, then the rotations' unit quaternions ``qx, qy, qz, qw``
            (signs kept continuous), arrays ``(n,)``.
        """
        return {**self.coordinates.columns(q), **self.rotation.columns(R)}

    def __repr__(self) -> str:
        return f"Product({', '.join(map(repr, self.visible))})"

    def __eq__(self, other) -> bool:
        return isinstance(other, Product) and self.factors == other.factors

    def __hash__(self) -> int:
        return hash(self.factors)
