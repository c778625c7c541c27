"""Bounds on a mechanism's inputs and coordinates, as constraint objects.

- :class:`InputBounds` ``(low, high)``: a box on the physical inputs ``u``. The mechanisms
  are driftless, so a planned path meets it by a time change (:mod:`nonholo.motion.speed_limits`):
  the inputs scale by ``dτ/dt > 0``, which neither turns their sign nor lifts them off zero,
  so every bound must hold zero inside, ``low < 0 < high``.
- :class:`StateBounds` ``(low, high)``: a box on the coordinates ``q`` of a state beyond
  SO(3), kept at every node of the motion like a platform's leg stroke
  (:mod:`nonholo.model.limits`): its *clearances* ``q_j − low_j`` and ``high_j − q_j`` (the
  finite ones) are non-negative, with gradients for the robust strategy's barrier.

``low`` and ``high`` are numbers (the same for every input or coordinate) or one per input
or coordinate, ``±inf`` where free; :meth:`InputBounds.check` and :meth:`StateBounds.check`
fit them to a mechanism. :func:`of_mechanism` turns a mechanism's bounds as data
(:attr:`~nonholo.model.mechanism.Mechanism.bounds`, ``{"inputs": {name: (low, high)},
"coordinates": {name: (low, high)}}``) into these objects and :func:`as_data` back;
:meth:`Box.record` and :meth:`Box.from_record` are a plan file's form (``null`` for ``±inf``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..numerics.checks import is_number
from . import catalog

#: A value beyond a bound by more than this, relative to ``max(1, |bound|)``, breaks it
#: (the certificate, a plan file's checks).
BOUND_RTOL = 1e-9


def input_names(mechanism) -> tuple[str, ...]:
    """The inputs' short names (``"v"`` of ``"v = rear-axle speed"``).

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.

    Returns
    -------
    tuple of str
        One name per input.
    """
    return tuple(s.split("=", 1)[0].strip() for s in mechanism.inputs)


def _side(value, cls: str, name: str):
    """One side of a box as given: a float, or a tuple of floats; ``ValueError`` naming it."""
    if is_number(value):
        if math.isnan(value):
            raise ValueError(f"{cls}: {name} must be a number or one per entry (±inf where free), got nan")
        return float(value)
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__iter__"):
        raise ValueError(f"{cls}: {name} must be a number or a sequence of numbers (±inf where free), "
                         f"got {type(value).__name__}")
    items = tuple(value)
    if not items:
        raise ValueError(f"{cls}: {name} is empty")
    for i, x in enumerate(items):
        if not is_number(x) or math.isnan(x):
            raise ValueError(f"{cls}: {name}[{i}] must be a number (±inf where free), got {x!r}")
    return tuple(float(x) for x in items)


def _sized(value, n: int) -> tuple:
    return (value,) * n if isinstance(value, float) else value


class Box:
    """What :class:`InputBounds` and :class:`StateBounds` share: two sides, checked (see the
    module)."""

    what = "entries"

    def __post_init__(self):
        cls = type(self).__name__
        low, high = _side(self.low, cls, "low"), _side(self.high, cls, "high")
        if isinstance(low, tuple) and isinstance(high, tuple) and len(low) != len(high):
            raise ValueError(f"{cls}: low has {len(low)} entries, high {len(high)}")
        n = len(low) if isinstance(low, tuple) else len(high) if isinstance(high, tuple) else 1
        for i, (a, b) in enumerate(zip(_sized(low, n), _sized(high, n))):
            if not a < b:
                at = "" if n == 1 and not isinstance(low, tuple) else f"[{i}]"
                raise ValueError(f"{cls}: low{at} = {a:g} must be below high{at} = {b:g}")
        object.__setattr__(self, "low", low)
        object.__setattr__(self, "high", high)

    def _fit(self, n: int, names, mechanism) -> tuple[tuple, tuple]:
        """Both sides with ``n`` entries (``ValueError`` naming the side of another length)."""
        cls = type(self).__name__
        for name in ("low", "high"):
            side = getattr(self, name)
            if isinstance(side, tuple) and len(side) != n:
                raise ValueError(f"{cls}: {name} has {len(side)} entries, mechanism {mechanism.name!r} has "
                                 f"{n} {self.what} ({', '.join(names)})")
        return _sized(self.low, n), _sized(self.high, n)

    @property
    def lows(self) -> np.ndarray:
        """``low`` as an array (after :meth:`InputBounds.check` or :meth:`StateBounds.check`: one entry per
        input or coordinate)."""
        return np.atleast_1d(np.asarray(self.low, dtype=float))

    @property
    def highs(self) -> np.ndarray:
        """``high`` as an array (after :meth:`InputBounds.check` or :meth:`StateBounds.check`: one entry per
        input or coordinate)."""
        return np.atleast_1d(np.asarray(self.high, dtype=float))

    @property
    def free(self) -> bool:
        """Whether every side is infinite: no bound at all."""
        return bool(np.all(np.isinf(self.lows)) and np.all(np.isinf(self.highs)))

    def record(self) -> list:
        """The bounds as a plan file records them: ``[[low, high], ...]``, ``None`` for ``±inf``.

        Returns
        -------
        list
            One pair per entry (call on checked bounds).
        """
        return [[None if math.isinf(a) else a, None if math.isinf(b) else b]
                for a, b in zip(self.lows.tolist(), self.highs.tolist())]

    @classmethod
    def from_record(cls, value, mechanism=None, name: str = "bounds"):
        """Bounds from :meth:`record`'s form, checked against ``mechanism``.

        Parameters
        ----------
        value : list
            ``[[low, high], ...]`` with ``None`` for ``±inf``.
        mechanism : Mechanism, optional
            The mechanism (``None``: the bounds are only checked on their own).
        name : str
            Where the value comes from, for messages.

        Returns
        -------
        InputBounds or StateBounds
            The bounds, checked.

        Raises
        ------
        ValueError
            Naming ``name``, for anything else.
        """
        if not isinstance(value, list) or not all(isinstance(p, list) and len(p) == 2 for p in value):
            raise ValueError(f"{name} must be a list of pairs [low, high] (null where free), got {value!r}")
        low = [-math.inf if a is None else a for a, _ in value]
        high = [math.inf if b is None else b for _, b in value]
        try:
            bounds = cls(low, high)
            return bounds if mechanism is None else bounds.check(mechanism)
        except ValueError as exc:
            raise ValueError(f"{name}: {exc}") from None

    def _sides_text(self, names, units=None) -> str:
        parts = []
        for j, (a, b) in enumerate(zip(self.lows, self.highs)):
            if math.isinf(a) and math.isinf(b):
                continue
            unit = f" {units[j]}" if units and units[j] else ""
            if a == -b:
                parts.append(f"|{names[j]}| ≤ {b:g}{unit}")
            elif math.isinf(a):
                parts.append(f"{names[j]} ≤ {b:g}{unit}")
            elif math.isinf(b):
                parts.append(f"{names[j]} ≥ {a:g}{unit}")
            else:
                parts.append(f"{a:g} ≤ {names[j]} ≤ {b:g}{unit}")
        return ", ".join(parts) or "none"


@dataclass(frozen=True)
class InputBounds(Box):
    """``low_i ≤ u_i(t) ≤ high_i`` for every physical input ``u_i`` along the motion, kept by
    re-timing the planned path (:mod:`nonholo.planning.retime`).

    Parameters
    ----------
    low, high : float or sequence of float
        The box: one number for every input, or one per input; ``-inf``/``inf`` where
        free. A bound that does not hold zero inside (``low < 0 < high``: a vehicle that only
        drives forward, ``0 < v_min ≤ v``) is kept by the least time alone
        (``objective="time"``, without drift), which scales the whole motion's time by one
        factor: a re-timing along the path slows the motion down to rest where it turns.

    Raises
    ------
    ValueError
        Naming ``low`` or ``high``: not numbers (NaN), ``low`` not below ``high``, sides of
        different lengths.
    """

    low: float | tuple = -math.inf
    high: float | tuple = math.inf
    what = "inputs"

    def check(self, mechanism) -> "InputBounds":
        """The bounds fitted to ``mechanism``'s inputs.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism planned.

        Returns
        -------
        InputBounds
            One entry per input.

        Raises
        ------
        ValueError
            Naming ``low``/``high`` and the mechanism's inputs, for another number of
            entries; naming the input, for a bound that does not hold zero inside (a time
            change cannot meet it).
        """
        names = input_names(mechanism)
        low, high = self._fit(mechanism.n_inputs, names, mechanism)
        return InputBounds(low, high)

    @property
    def holds_zero(self) -> bool:
        """Whether every bound holds zero inside (``low < 0 < high``)."""
        return bool(np.all(np.asarray(self.lows) < 0.0) and np.all(np.asarray(self.highs) > 0.0))

    def off_zero(self, mechanism) -> str | None:
        """The first bound that does not hold zero inside, in words (``None`` where all do).

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism, for the inputs' names.

        Returns
        -------
        str or None
            E.g. ``"0.25 ≤ v ≤ 0.5"``.
        """
        for name, a, b in zip(input_names(mechanism), self.lows, self.highs):
            if not a < 0.0 < b:
                return f"{a:g} ≤ {name} ≤ {b:g}"
        return None

    def refusal(self, mechanism, start, goal) -> str | None:
        """Never a reason: any path can be re-timed to keep the bounds.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism planned.
        start, goal : tuple
            States ``(R, q)``.

        Returns
        -------
        None
            They may be joined.
        """
        return None

    def usage(self, u) -> np.ndarray:
        """How much of its bound the most loaded input uses, at each sample:
        ``max_i max(u_i/high_i, u_i/low_i)`` over the sides away from zero (``high_i > 0``,
        ``low_i < 0``; 0 where free; above 1: such a bound is broken). A side off zero (``0 <
        low_i``) is met by :meth:`slack` instead.

        Parameters
        ----------
        u : array_like
            Inputs, ``(..., m)`` (checked bounds: ``m`` entries).

        Returns
        -------
        numpy.ndarray
            Shape ``(...)``.
        """
        u = np.asarray(u, dtype=float)
        highs, lows = np.asarray(self.highs, dtype=float), np.asarray(self.lows, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.maximum(np.where(highs > 0.0, u / highs, -np.inf), np.where(lows < 0.0, u / lows, -np.inf))
        ratio = np.where(np.isnan(u), np.inf, np.maximum(ratio, 0.0))
        return np.max(ratio, axis=-1)

    def slack(self, u) -> np.ndarray:
        """The largest factor the inputs may be divided by (a motion slowed down that much) and
        still meet the sides off zero (``0 < low_i`` or ``high_i < 0``), at each sample:
        ``min_i u_i/low_i`` over those sides (``inf`` without any; below 1: such a bound is
        broken).

        Parameters
        ----------
        u : array_like
            Inputs, ``(..., m)`` (checked bounds: ``m`` entries).

        Returns
        -------
        numpy.ndarray
            Shape ``(...)``.
        """
        u = np.asarray(u, dtype=float)
        highs, lows = np.asarray(self.highs, dtype=float), np.asarray(self.lows, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.minimum(np.where(lows > 0.0, u / lows, np.inf), np.where(highs < 0.0, u / highs, np.inf))
        return np.min(np.where(np.isnan(ratio), -np.inf, ratio), axis=-1)

    def excess(self, u, times=None, names=None) -> str | None:
        """Where inputs break the bounds by more than :data:`BOUND_RTOL` (relative).

        Parameters
        ----------
        u : array_like
            Inputs, ``(n, m)``.
        times : array_like, optional
            Their times (s), to say when.
        names : sequence of str, optional
            The inputs' names.

        Returns
        -------
        str or None
            The input that is out the most, its value and bound; ``None`` within.
        """
        u = np.asarray(u, dtype=float).reshape(-1, len(self.lows))
        lows, highs = self.lows, self.highs
        with np.errstate(invalid="ignore"):
            above = np.where(np.isfinite(highs), (u - highs) / np.maximum(1.0, np.abs(highs)), -np.inf)
            below = np.where(np.isfinite(lows), (lows - u) / np.maximum(1.0, np.abs(lows)), -np.inf)
        over = np.where(np.isnan(u), np.inf, np.maximum(above, below))
        k, i = np.unravel_index(int(np.argmax(over)), over.shape)
        if not over[k, i] > BOUND_RTOL:
            return None
        name = names[i] if names is not None else f"u[{i}]"
        bound = self.highs[i] if u[k, i] > 0 else self.lows[i]
        when = f" at t ≈ {times[k]:.4g} s" if times is not None else ""
        return f"input {name} reaches {u[k, i]:.6g}{when}, beyond its bound {bound:g} ({self.text(names)})"

    def text(self, names=None) -> str:
        """The bounds in words, e.g. ``"|v| ≤ 1, |u2| ≤ 1"``.

        Parameters
        ----------
        names : sequence of str, optional
            The inputs' names (default ``u[i]``).

        Returns
        -------
        str
            The finite bounds.
        """
        names = names or [f"u[{i}]" for i in range(len(self.lows))]
        return self._sides_text(names)


@dataclass(frozen=True)
class StateBounds(Box):
    """``low_j ≤ q_j ≤ high_j`` for every coordinate ``q_j`` at every node of the motion.

    Parameters
    ----------
    low, high : float or sequence of float
        The box: one number for every coordinate, or one per coordinate; ``-inf``/``inf``
        where free.

    Raises
    ------
    ValueError
        Naming ``low`` or ``high``: not numbers (NaN), ``low`` not below ``high``, sides of
        different lengths.
    """

    low: float | tuple = -math.inf
    high: float | tuple = math.inf
    what = "coordinates"
    #: what a motion that passes these bounds leaves, for messages
    kept_text = "the coordinates' bounds (StateBounds)"

    def check(self, mechanism) -> "StateBounds":
        """The bounds fitted to ``mechanism``'s coordinates.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism planned, one with coordinates.

        Returns
        -------
        StateBounds
            One entry per coordinate.

        Raises
        ------
        ValueError
            For a mechanism without coordinates, or another number of entries (naming
            ``low``/``high`` and the coordinates).
        """
        if not mechanism.n_coordinates:
            raise ValueError(f"StateBounds: mechanism {mechanism.name!r} has no coordinates (its state is "
                             "an orientation): nothing to bound")
        low, high = self._fit(mechanism.n_coordinates, mechanism.coordinates, mechanism)
        return StateBounds(low, high)

    @property
    def slack(self) -> float:
        """How far a replayed node may pass a bound and still keep it: :data:`BOUND_RTOL`
        times ``max(1, largest finite |bound|)``."""
        finite = np.abs(np.concatenate([self.lows, self.highs]))
        finite = finite[np.isfinite(finite)]
        return BOUND_RTOL * max(1.0, float(finite.max()) if finite.size else 1.0)

    def _columns(self):
        """The finite sides: ``(coordinate, side)`` per clearance column (side 0: low)."""
        cols = [(j, 0) for j in range(len(self.lows)) if np.isfinite(self.lows[j])]
        cols += [(j, 1) for j in range(len(self.highs)) if np.isfinite(self.highs[j])]
        return cols

    def around_zero(self) -> np.ndarray:
        """``|bound|`` of every finite side (in :meth:`clearances`' order) of a coordinate whose
        bounds hold zero inside (``low_j < 0 < high_j``), 0 for the others.

        Returns
        -------
        numpy.ndarray
            One entry per finite side.
        """
        return np.array([abs(self.lows[j] if side == 0 else self.highs[j]) if self.lows[j] < 0.0 < self.highs[j] else 0.0
                         for j, side in self._columns()])

    def clearances(self, mechanism, R, q=None) -> np.ndarray:
        """``q_j − low_j`` and ``high_j − q_j`` for every finite side.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism.
        R : array_like
            Orientations ``(n, 3, 3)`` (unused: the bounds are on ``q``).
        q : array_like
            Coordinates ``(n, k)``.

        Returns
        -------
        numpy.ndarray
            Shape ``(n, c)``, one column per finite side.
        """
        q = np.asarray(q, dtype=float).reshape(-1, len(self.lows))
        cols = self._columns()
        out = np.empty((q.shape[0], len(cols)))
        for c, (j, side) in enumerate(cols):
            out[:, c] = q[:, j] - self.lows[j] if side == 0 else self.highs[j] - q[:, j]
        return out

    def least_clearance(self, mechanism, R, q=None) -> float:
        """The least clearance over the nodes (``inf`` without a finite side).

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism.
        R, q : array_like
            The nodes' orientations and coordinates.

        Returns
        -------
        float
            Negative where a coordinate left its bounds.
        """
        c = self.clearances(mechanism, R, q)
        return float(c.min()) if c.size else math.inf

    def _worst(self, mechanism, R, q):
        c = self.clearances(mechanism, R, q)
        n, k = np.unravel_index(int(np.argmin(c)), c.shape)
        j, side = self._columns()[k]
        return int(n), j, side, float(c[n, k])

    def violation(self, mechanism, state, what: str) -> str | None:
        """Why a state is outside the bounds.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism.
        state : tuple
            ``(R, q)``.
        what : str
            What the state is, e.g. ``"the start"``.

        Returns
        -------
        str or None
            Naming the coordinate out the most and by how much; ``None`` inside.
        """
        if not self._columns():
            return None
        q = np.asarray(state[1], dtype=float)
        _, j, side, c = self._worst(mechanism, None, q)
        if c >= 0.0:
            return None
        end, limit = (("lower", self.lows[j]), ("upper", self.highs[j]))[side]
        return (f"{what} is outside the coordinates' bounds: {mechanism.coordinates[j]} = {q[j]:.6g} "
                f"passes its {end} bound {limit:g} by {-c:.3g}")

    def refusal(self, mechanism, start, goal) -> str | None:
        """Why ``start`` or ``goal`` is outside the bounds, naming the coordinate.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism planned.
        start, goal : tuple
            States ``(R, q)``.

        Returns
        -------
        str or None
            The reason, or ``None``: they may be joined.
        """
        return self.violation(mechanism, start, "the start") or self.violation(mechanism, goal, "the goal")

    def describe(self, mechanism, R, times=None, q=None) -> str:
        """Where nodes leave the bounds the most (for a failure's reason).

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism.
        R : array_like
            The nodes' orientations.
        times : array_like, optional
            Their times (s), to say when.
        q : array_like
            The nodes' coordinates.

        Returns
        -------
        str
            The coordinate, the bound it passes and by how much.
        """
        n, j, side, c = self._worst(mechanism, R, q)
        when = f" at t ≈ {times[n]:.4g} s" if times is not None else ""
        end, limit = (("lower", self.lows[j]), ("upper", self.highs[j]))[side]
        return (f"{mechanism.coordinates[j]} passes its {end} bound {limit:g} by {-c:.3g}{when} "
                f"({self._sides_text(mechanism.coordinates)})")

    def clearance_terms(self, mechanism, R, threshold: float, q=None):
        """The active terms of a log barrier on the clearances of nodes.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism.
        R : array_like
            The nodes' orientations.
        threshold : float
            Only clearances below it are active (the coordinates' units).
        q : array_like
            The nodes' coordinates.

        Returns
        -------
        tuple of numpy.ndarray or None
            ``(nodes, c, ∇c)`` for every clearance ``c < threshold`` (``∇c``: rows of
            ``n_rates`` along the stacked variation ``s = (s_R, δq)``), or ``None``.
        """
        c = self.clearances(mechanism, R, q)
        nodes, cols = np.nonzero(c < threshold)
        if nodes.size == 0:
            return None
        r = mechanism.space.rows("coordinates").start
        rows = np.zeros((nodes.size, mechanism.n_rates))
        spec = self._columns()
        for a, k in enumerate(cols):
            j, side = spec[k]
            rows[a, r + j] = 1.0 if side == 0 else -1.0
        return nodes, c[nodes, cols], rows

    def text(self, mechanism) -> str:
        """The bounds in words, e.g. ``"|phi| ≤ 0.6 rad"``.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism (its coordinates' names and units).

        Returns
        -------
        str
            The finite bounds.
        """
        return self._sides_text(mechanism.coordinates, mechanism.units)


def of_mechanism(mechanism) -> list:
    """A mechanism's own bounds (:attr:`~nonholo.model.mechanism.Mechanism.bounds`) as
    constraint objects.

    Parameters
    ----------
    mechanism : str or Mechanism
        The mechanism, or its name in the catalog (:func:`nonholo.model.catalog.names`).

    Returns
    -------
    list
        Its :class:`InputBounds` and :class:`StateBounds`, each checked, where it has them
        (empty without bounds): ``nonholo.plan(..., constraints=of_mechanism("car"))``.

    Raises
    ------
    ValueError
        For bounds data that name an unknown input or coordinate, or are not pairs.
    """
    mechanism = catalog.get(mechanism)
    data = mechanism.bounds
    if not data:
        return []
    if not isinstance(data, dict) or set(data) - {"inputs", "coordinates"}:
        raise ValueError(f"bounds of mechanism {mechanism.name!r} must be a mapping with 'inputs' and "
                         f"'coordinates', got {data!r}")
    out = []
    for key, cls, names, full in (("inputs", InputBounds, input_names(mechanism), mechanism.inputs),
                                  ("coordinates", StateBounds, mechanism.coordinates, mechanism.coordinates)):
        given = data.get(key) or {}
        if not given:
            continue
        low, high = [-math.inf] * len(names), [math.inf] * len(names)
        for name, pair in given.items():
            where = names.index(name) if name in names else full.index(name) if name in full else None
            if where is None:
                raise ValueError(f"bounds of mechanism {mechanism.name!r}: unknown {key[:-1]} {name!r}; "
                                 f"known: {', '.join(names)}")
            try:
                low[where], high[where] = (float(x) for x in pair)
            except (TypeError, ValueError):
                raise ValueError(f"bounds of mechanism {mechanism.name!r}: {key}.{name} must be a pair "
                                 f"(low, high), got {pair!r}") from None
        out.append(cls(low, high).check(mechanism))
    return out


def describe(mechanism) -> str:
    """A mechanism's own bounds in words (``"|v| ≤ 1, |u2| ≤ 1; |phi| ≤ 0.6 rad"``).

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.

    Returns
    -------
    str
        The inputs' bounds, then the coordinates'; empty without bounds.
    """
    parts = []
    for b in of_mechanism(mechanism):
        parts.append(b.text(input_names(mechanism)) if isinstance(b, InputBounds) else b.text(mechanism))
    return "; ".join(p for p in parts if p != "none")


def as_data(constraints, mechanism) -> dict | None:
    """The bounds among ``constraints`` as :attr:`~nonholo.model.mechanism.Mechanism.bounds`
    holds them (the inverse of :func:`of_mechanism`).

    Parameters
    ----------
    constraints : sequence
        Constraint objects; those that are not bounds are left out.
    mechanism : Mechanism
        The mechanism they are checked against.

    Returns
    -------
    dict or None
        ``{"inputs": {name: (low, high)}, "coordinates": {name: (low, high)}}`` (only the
        bounded entries), ``None`` without bounds.
    """
    out = {}
    for c in constraints:
        if isinstance(c, (InputBounds, StateBounds)):
            c = c.check(mechanism)
            key, names = (("inputs", input_names(mechanism)) if isinstance(c, InputBounds)
                          else ("coordinates", mechanism.coordinates))
            out[key] = {n: (float(a), float(b)) for n, a, b in zip(names, c.lows, c.highs)
                        if not (math.isinf(a) and math.isinf(b))}
    return out or None
