"""The coordinate factor of a state space: :class:`Euclidean`, ``Rᵏ`` with named coordinates,
some of them angles (the conventions of a factor: :mod:`nonholo.spaces.axes`).
"""
from __future__ import annotations

import numpy as np

from ..numerics.checks import real_array
from .axes import Axis, kind_of, wrap


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
