"""Controls re-timed so that no leg moves faster than a bound, or no input leaves its bounds:
the fastest re-timing of a path.

The mechanisms are driftless (``dR/dt = [L(R) u] R``): for a planned control ``u(τ)`` on
``[0, T]`` and an increasing map ``τ(t)`` from ``[0, T̃]`` onto ``[0, T]``, the control

    ``ũ(t) = u(τ(t)) · dτ/dt``

moves along the same orientations, ``R̃(t) = R(τ(t))``, only faster or slower. Each leg's
speed is scaled the same way: ``dl_i/dt = s_i(τ) dτ/dt`` with ``s_i(τ) = dl_i/dτ`` of the
planned motion. Under a bound ``|dl_i/dt| ≤ v`` the fastest re-timing has

    ``dτ/dt = 1/ρ(τ)``,  ``ρ(τ) = max_i |s_i(τ)| / v``,  ``T̃ = ∫_0^T ρ(τ) dτ``:

at every instant the fastest leg moves at ``v``, and no re-timing of the path takes less
than ``T̃`` (``TimeMap.minimum_time``). A longer ``T`` is met by ``dτ/dt = 1/(cρ)``,
``c = T/T̃ ≥ 1``: the fastest leg then moves at ``v/c`` throughout.

Except where the path nearly stops. Where its inputs pass near zero (a sharp turn of the
path, a near-cusp), ``ρ`` nearly vanishes and the exact least-time map rushes through:
``dτ/dt = 1/ρ`` is huge, and the inputs ``u/ρ``, whose size stays that of the bound, turn
round within microseconds, continuously but faster than any actuator follows. So ``ρ``
is floored at :data:`FLOOR` times its peak, ``ρ = max(max_i |s_i|, FLOOR · max_τ max_i
|s_i|) / v``: there the path is played no faster than ``1/FLOOR`` times its fastest
part's pace, every leg below ``v``, and the inputs turn at a bounded rate. A path whose
fastest leg never falls below :data:`FLOOR` of its peak is re-timed in the exact least
time.

How :class:`TimeMap` builds ``τ(t)``:

- the planned control is replayed from ``R0`` on ``nodes`` CF4 steps (a multiple of its
  grid, so jumps fall on nodes) and ``s_i`` evaluated at every node, from each side where
  the control jumps;
- each ``s_i`` is interpolated by a quintic spline ``S_i`` between consecutive jumps
  (:data:`DEGREE`), and ``ρ = max_i |S_i| / v`` *exactly*: its kinks, where the fastest leg
  changes or meets the floor, are the roots of ``S_a ∓ S_b`` and ``S_a ∓ floor``, found as
  polynomial roots, so between knots and kinks ``ρ`` is one quintic or the floor;
- ``t(τ) = c ∫ ρ`` is integrated piece by piece by 3-point Gauss–Legendre (exact for
  quintics) and inverted by Newton's method inside a piece (``dt/dτ = cρ > 0``), to
  round-off.

So the ``dτ/dt = 1/(cρ(τ(t)))`` that scales ``u`` is the derivative of the very map at which
``u`` is read: the re-timed control moves along the planned path to round-off, whatever
the spline's own error, which only moves the fastest leg's speed off ``v`` between nodes
(by the spline's interpolation error, ``O(h⁶)`` in the node spacing ``h``).

**Bounds on the inputs** (:class:`InputTimeMap`, :class:`InputRetimed`). The inputs scale
the same way, ``ũ_i(t) = u_i(τ) dτ/dt``, so a box ``low_i ≤ ũ_i ≤ high_i`` with
``low_i < 0 < high_i`` (:class:`~nonholo.model.bounds.InputBounds`) is met by the same
construction with the level ``ρ(τ) = max_i max(u_i(τ)/high_i, u_i(τ)/low_i)`` (the share of
its bound the most loaded input uses; ``u_i/±inf = 0`` where free): at every instant one
input is at its bound, the least time along the planned path. No replay is needed (the
splines go through the inputs themselves), the kinks are the roots of the differences of
the channels ``S_i/high_i``, ``S_j/low_j`` and of each channel and the floor, and
:data:`FLOOR` acts as above. A bound that does not hold zero inside is no box a time change
can meet (it neither turns an input's sign nor lifts it off zero).
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..controls import stages
from ..model.bounds import InputBounds
from ..numerics.checks import check_count, check_times, is_number
from ..spaces import so3
from . import playback
from .time_scaling import MIN_TIME, TimeChange, check_horizon

if TYPE_CHECKING:                       # SciPy's splines load when first needed
    from scipy.interpolate import PPoly

#: Nodes of the replay that samples the legs' speeds, at least (rounded up to a multiple of
#: the controls' grid): the spline's error in ``ρ`` is ``O((T/nodes)⁶)``.
RETIME_NODES = 1200
#: Newton steps that invert ``t(τ)`` inside a piece, at most (quadratic convergence from
#: the linear interpolant: round-off after 3–5; they stop there).
NEWTON_STEPS = 8
#: A motion whose fastest leg is slower than this fraction of its peak somewhere stands
#: (almost) still there: ``dτ/dt = 1/ρ`` would be unbounded.
STANDSTILL = 1e-9
#: ``ρ`` is at least this fraction of its peak (see the module): the most the re-timing
#: speeds up the slowest part of a path relative to its fastest is ``1/FLOOR``.
FLOOR = 0.05
#: Two inputs differing by more than this (relative to the largest input) at a node: the
#: control jumps there (the splines of ``s_i`` are broken at it).
JUMP_RTOL = 1e-12
#: Degree of the splines of the legs' speeds: C⁴ between jumps, so that an accurate
#: integrator of the re-timed controls (DOP853, order 8) is not slowed or misled at their
#: knots; the 3-point Gauss rule integrates ``ρ`` exactly on each piece.
DEGREE = 5

_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(3)


def check_leg_speed(value, mechanism) -> float | None:
    """``leg_speed`` as :func:`nonholo.plan` takes it.

    Parameters
    ----------
    value : float or None
        ``None`` (no bound) or a positive finite speed (the geometry's length units per
        second).
    mechanism : Mechanism
        The mechanism planned, one with legs.

    Returns
    -------
    float or None
        The speed, ``None`` for no bound.

    Raises
    ------
    ValueError
        Naming ``leg_speed``, if ``value`` is not such a speed or the mechanism has no legs.
    """
    if value is None:
        return None
    if not mechanism.has_legs:
        raise ValueError(f"leg_speed: mechanism {mechanism.name!r} has no legs (only platforms do)")
    if not is_number(value) or not math.isfinite(value) or value <= 0:
        raise ValueError(f"leg_speed must be a positive finite speed (length units per second), got {value!r}")
    return float(value)


def node_count(controls, nodes: int) -> int:
    """``nodes`` rounded up to a multiple of the controls' grid (1 for smooth controls).

    Parameters
    ----------
    controls : Controls
        The controls (a ``grid`` attribute, if any).
    nodes : int
        The least number of nodes.

    Returns
    -------
    int
        The number of nodes.
    """
    g = getattr(controls, "grid", None) or 1
    return -(-nodes // g) * g


class TimeMap:
    """``t(τ)`` and its inverse for controls played with every leg at most ``leg_speed``
    fast (see the module).

    Parameters
    ----------
    base : Controls or FrameControls
        The planned physical controls, on ``[0, T_base]``.
    R0 : array_like
        The start, a rotation matrix.
    mechanism : Mechanism
        The platform.
    leg_speed : float
        ``v``, the legs' top speed (geometry units per second).
    T : float, optional
        The re-timed duration; ``None`` for the least (``minimum_time``).
    nodes : int
        CF4 nodes of the replay that samples the legs' speeds, at least.

    Raises
    ------
    ValueError
        If ``leg_speed`` is not a positive finite speed or the mechanism has no legs, the
        motion never moves a leg or stands still somewhere, or runs into a non-finite
        angular velocity, or ``T`` is below the time needed (saying it).
    """

    def __init__(self, base, R0, mechanism, leg_speed: float, T: float | None = None,
                 nodes: int = RETIME_NODES):
        mech = mechanism
        self.leg_speed = check_leg_speed(leg_speed, mech)
        if self.leg_speed is None:
            raise ValueError("leg_speed must be a positive finite speed, got None")
        self._unit = self.leg_speed
        self.nodes = node_count(base, check_count(nodes, "nodes", minimum=2))
        self.T_base = base.T
        self._spline, jumps = _speed_spline(base, R0, mech, self.nodes)
        self._build(jumps, T)

    #: what the bound keeps, for messages
    bound_text = "every leg at most {v:g} fast"
    #: what does not move when nothing is bounded moves, for messages
    moving = "leg"

    def _level(self, values) -> np.ndarray:
        """``max_i |s_i|``: the fastest leg's speed at spline values ``(..., k)``."""
        return np.max(np.abs(values), axis=-1)

    def _kinks(self, floor: float) -> np.ndarray:
        return _kinks(self._spline, floor)

    def _describe_bound(self) -> str:
        return self.bound_text.format(v=self._unit)

    def _bound_name(self) -> str:
        return f"leg_speed = {self._unit:g}"

    def _build(self, jumps, T) -> None:
        """The map from the spline of the bounded quantities and its jumps (see the module)."""
        x = self._spline.x
        peak = float(np.max(self._level(self._spline.c[-1])))     # the level at the nodes
        if not peak > 0.0:
            raise ValueError(f"the planned motion never moves a {self.moving}: nothing to re-time")
        #: the floor of the level ``max_i |S_i|`` in ``ρ`` (see the module)
        self.floor = FLOOR * peak
        kinks = self._kinks(self.floor)
        self.edges = np.unique(np.concatenate([x, kinks]))
        self.kinks = np.setdiff1d(kinks, x)
        self.jumps = jumps
        a, b = self.edges[:-1], self.edges[1:]
        mid, half = 0.5 * (a + b), 0.5 * (b - a)
        rho_q = self.ratio(mid[:, None] + half[:, None] * _GAUSS_X[None, :])
        least = float(np.min(self._level(self._spline(self.edges[:-1])))) / self._unit
        if not least > STANDSTILL * peak / self._unit or not np.min(rho_q) > 0.0:
            raise ValueError(f"the planned motion stands still somewhere (every {self.moving} at rest): "
                             "its re-timing under a speed bound is not defined there")
        pieces = half * (rho_q @ _GAUSS_W)
        self._cumulative = np.concatenate([[0.0], np.cumsum(pieces)])
        self.minimum_time = float(self._cumulative[-1])
        if T is None:
            self.scale = 1.0
        else:
            T = check_horizon(T)
            if T < self.minimum_time * (1.0 - 1e-12):
                raise ValueError(f"T = {T:.6g} s is too short: the path needs at least "
                                 f"{self.minimum_time:.6g} s with {self._describe_bound()}")
            self.scale = max(T / self.minimum_time, 1.0)
        self.T = self.minimum_time * self.scale if T is None else T
        if not self.T >= MIN_TIME:
            raise ValueError(f"{self._bound_name()} re-times the motion in T = {self.T:.3g} s, less "
                             f"than {MIN_TIME:g} s: its inputs would not be finite (a mistake of units)")
        self._t_edges = self._cumulative * self.scale
        self._t_edges[-1] = self.T

    # -- ρ -----------------------------------------------------------------------------------
    def ratio(self, tau) -> np.ndarray:
        """``ρ(τ) = max(max_i |S_i(τ)|, floor) / v``: the planned motion's fastest leg speed
        over the bound, floored (see the module).

        Parameters
        ----------
        tau : array_like
            Planned times ``τ``.

        Returns
        -------
        numpy.ndarray
            ``ρ(τ)``, of the shape of ``tau``.
        """
        tau = np.asarray(tau, dtype=float)
        return np.maximum(self._level(self._spline(tau)), self.floor) / self._unit

    @property
    def peak_ratio(self) -> float:
        """``max ρ`` over the nodes and kinks: above 1, the planned motion breaks the bound."""
        return float(np.max(self.ratio(self.edges)))

    # -- the map -----------------------------------------------------------------------------
    def time(self, tau) -> np.ndarray:
        """``t(τ) = c ∫_0^τ ρ``.

        Parameters
        ----------
        tau : array_like
            Planned times ``τ`` (clipped to ``[0, T_base]``).

        Returns
        -------
        numpy.ndarray
            The re-timed times ``t``.
        """
        tau = np.clip(np.asarray(tau, dtype=float), 0.0, self.T_base)
        p = self._piece(tau, self.edges)
        return self._t_edges[p] + self.scale * self._integral(self.edges[p], tau)

    def tau(self, t) -> tuple[np.ndarray, np.ndarray]:
        """The planned time and its rate at times of the re-timed motion.

        Parameters
        ----------
        t : array_like
            Re-timed times (clipped to ``[0, T]``).

        Returns
        -------
        tuple of numpy.ndarray
            ``(τ(t), dτ/dt)``.
        """
        t = np.clip(check_times(t), 0.0, self.T)
        p = self._piece(t, self._t_edges)
        a, b = self.edges[p], self.edges[p + 1]
        ta, tb = self._t_edges[p], self._t_edges[p + 1]
        tau = a + (b - a) * np.where(tb > ta, (t - ta) / np.where(tb > ta, tb - ta, 1.0), 0.0)
        done = 4.0 * np.finfo(float).eps * self.T_base
        for _ in range(NEWTON_STEPS):
            f = ta + self.scale * self._integral(a, tau) - t
            new = np.clip(tau - f / (self.scale * self.ratio(tau)), a, b)
            moved = np.max(np.abs(new - tau), initial=0.0)
            tau = new
            if moved <= done:
                break
        if self.jumps.size:
            # at a jump the controls take their value after it (as grid controls do at a grid
            # point): τ rounded to either side of one is put on it, so that u and ρ agree
            j = np.clip(np.searchsorted(self.jumps, tau), 1, self.jumps.size) - 1
            for near in (self.jumps[j], self.jumps[np.minimum(j + 1, self.jumps.size - 1)]):
                tau = np.where(np.abs(tau - near) <= 16.0 * done, near, tau)
        return tau, 1.0 / (self.scale * self.ratio(tau))

    def _piece(self, x, edges) -> np.ndarray:
        return np.clip(np.searchsorted(edges, x, side="right") - 1, 0, len(self.edges) - 2)

    def _integral(self, a, tau) -> np.ndarray:
        """``∫_a^τ ρ`` for ``a ≤ τ`` inside one piece (exact: ``ρ`` is a quintic there)."""
        half = 0.5 * (tau - a)
        pts = (a + half)[..., None] + half[..., None] * _GAUSS_X
        return half * (self.ratio(pts) @ _GAUSS_W)


class InputTimeMap(TimeMap):
    """``t(τ)`` and its inverse for controls played with every input within its bounds (see
    the module): :class:`TimeMap` with the level ``max_i max(S_i/high_i, S_i/low_i)`` of the
    inputs' splines ``S_i``.

    Parameters
    ----------
    base : Controls or FrameControls
        The planned physical controls, on ``[0, T_base]``.
    bounds : InputBounds
        The bounds, checked (:meth:`~nonholo.model.bounds.InputBounds.check`: one per input,
        ``low < 0 < high``).
    T : float, optional
        The re-timed duration; ``None`` for the least (``minimum_time``).
    nodes : int
        Nodes the inputs are splined through, at least.

    Raises
    ------
    ValueError
        If ``bounds`` are not such bounds (or free everywhere), no bounded input ever moves
        or all stand still somewhere, or ``T`` is below the time needed (saying it).
    """

    bound_text = "every input within its bounds ({bounds})"
    moving = "bounded input"

    def __init__(self, base, bounds: InputBounds, T: float | None = None, nodes: int = RETIME_NODES):
        if not isinstance(bounds, InputBounds):
            raise ValueError(f"bounds must be InputBounds, got {type(bounds).__name__}")
        lows, highs = bounds.lows, bounds.highs
        if len(lows) != base.n_inputs or len(highs) != base.n_inputs:
            raise ValueError(f"bounds have {len(lows)} entries, the controls {base.n_inputs} inputs")
        if not (np.all(lows < 0.0) and np.all(highs > 0.0)):
            raise ValueError(f"bounds must hold 0 inside (low < 0 < high) for a time change to meet them, "
                             f"got {bounds.text()}")
        if bounds.free:
            raise ValueError("bounds are free everywhere: nothing to re-time under")
        self.bounds = bounds
        self.leg_speed = None
        self._unit = 1.0
        self.nodes = node_count(base, check_count(nodes, "nodes", minimum=2))
        self.T_base = base.T
        self._spline, jumps = _input_spline(base, self.nodes)
        self._build(jumps, T)

    def _level(self, values) -> np.ndarray:
        """``max_i max(S_i/high_i, S_i/low_i)`` at spline values ``(..., m)``."""
        return self.bounds.usage(values)

    def _kinks(self, floor: float) -> np.ndarray:
        return _channel_kinks(self._spline, self.bounds, floor)

    def _describe_bound(self) -> str:
        return self.bound_text.format(bounds=self.bounds.text())

    def _bound_name(self) -> str:
        return f"InputBounds {self.bounds.text()}"


def _speed_spline(base, R0, mech, nodes: int) -> tuple[PPoly, np.ndarray]:
    """The legs' speeds ``s_i(τ)`` of ``base`` played from ``R0``: splines of degree
    :data:`DEGREE` through their values at ``nodes`` CF4 nodes, broken where the control
    jumps (one PPoly with values of shape ``(k,)``), and the jumps' times."""
    T = base.T
    U = np.ascontiguousarray(stages.stage_table(base, nodes))
    start = mech.space.state(R0)
    sign = mech.singular.sign(*start)
    Rs, done, _, _ = playback.replay(start, base, T, mech, nodes, sign, U)
    if done < nodes:
        raise ValueError("the planned motion runs into a non-finite angular velocity: not re-timed")
    right = mech.leg_speeds(Rs[:-1], U[:, 0])          # s_i at the start of each step
    left = mech.leg_speeds(Rs[1:], U[:, 2])            # … and at its end
    return _broken_spline(U, right, left, T, nodes)


def _input_spline(base, nodes: int) -> tuple[PPoly, np.ndarray]:
    """The inputs ``u_i(τ)`` of ``base``: splines of degree :data:`DEGREE` through their
    values at ``nodes`` steps, broken where the control jumps, and the jumps' times."""
    U = np.ascontiguousarray(stages.stage_table(base, nodes))
    return _broken_spline(U, U[:, 0], U[:, 2], base.T, nodes)


def _broken_spline(U, right, left, T: float, nodes: int) -> tuple[PPoly, np.ndarray]:
    """Splines through values at the nodes (``right``: at the start of each step, ``left``:
    at its end), broken where the stage table ``U`` jumps, and the jumps' times."""
    from scipy.interpolate import PPoly, make_interp_spline  # loaded when first needed

    tau = np.arange(nodes + 1) * (T / nodes)
    tau[-1] = T
    scale = max(float(np.max(np.abs(U))), 1e-300)
    jump = np.flatnonzero(np.max(np.abs(U[1:, 0] - U[:-1, 2]), axis=1) > JUMP_RTOL * scale) + 1
    bounds = np.concatenate([[0], jump, [nodes]])
    coeffs, knots = [], []
    for j0, j1 in zip(bounds[:-1], bounds[1:]):
        x = tau[j0:j1 + 1]
        y = np.concatenate([right[j0:j1], left[j1 - 1:j1]])
        k = min(DEGREE, len(x) - 1)
        legs = [PPoly.from_spline(make_interp_spline(x, y[:, i], k=k)) for i in range(y.shape[1])]
        real = np.diff(legs[0].x) > 0                   # the B-spline's end knots repeat
        c = np.zeros((DEGREE + 1, int(real.sum()), y.shape[1]))
        for i, leg in enumerate(legs):
            c[DEGREE - k:, :, i] = leg.c[:, real]
        coeffs.append(c)
        knots.append(legs[0].x[:-1][real])
    knots.append([T])
    return PPoly(np.concatenate(coeffs, axis=1), np.concatenate(knots)), tau[jump]


def _kinks(spline: PPoly, floor: float = 0.0) -> np.ndarray:
    """Where two legs are equally fast, ``|S_a| = |S_b|`` (the roots of ``S_a ∓ S_b``), and
    where the fastest leg's speed meets ``floor`` (roots of ``S_a ∓ floor`` at which no leg
    is faster)."""
    from scipy.interpolate import PPoly  # loaded when first needed

    k = spline.c.shape[-1]
    roots = []
    for a in range(k):
        for b in range(a + 1, k):
            for sign in (-1.0, 1.0):
                diff = PPoly(spline.c[..., a] + sign * spline.c[..., b], spline.x)
                r = diff.roots(discontinuity=False, extrapolate=False)
                roots.append(r[np.isfinite(r)])
    if floor > 0.0:
        for a in range(k):
            for sign in (-1.0, 1.0):
                c = spline.c[..., a].copy()
                c[-1] += sign * floor
                r = PPoly(c, spline.x).roots(discontinuity=False, extrapolate=False)
                r = r[np.isfinite(r)]
                if r.size:
                    roots.append(r[np.max(np.abs(spline(r)), axis=-1) <= floor * (1.0 + 1e-9)])
    return np.unique(np.concatenate(roots)) if roots else np.empty(0)


def _channel_kinks(spline: PPoly, bounds: InputBounds, floor: float = 0.0) -> np.ndarray:
    """Where two inputs use equal shares of their bounds (roots of ``S_i/b_i − S_j/b_j``
    for every finite side ``b_i`` of input ``i`` and ``b_j`` of another input ``j``), and
    where a share meets ``floor`` (roots of ``S_i/b_i − floor`` at which no share is larger)."""
    from scipy.interpolate import PPoly  # loaded when first needed

    channels = [(i, b) for i, (lo, hi) in enumerate(zip(bounds.lows, bounds.highs))
                for b in (hi, lo) if math.isfinite(b)]
    roots = []
    for a, (i, bi) in enumerate(channels):
        for j, bj in channels[a + 1:]:
            if i == j:
                continue        # one input's two shares meet at 0, below the floor
            r = PPoly(spline.c[..., i] / bi - spline.c[..., j] / bj, spline.x).roots(
                discontinuity=False, extrapolate=False)
            roots.append(r[np.isfinite(r)])
    if floor > 0.0:
        for i, b in channels:
            c = spline.c[..., i] / b
            c[-1] -= floor
            r = PPoly(c, spline.x).roots(discontinuity=False, extrapolate=False)
            r = r[np.isfinite(r)]
            if r.size:
                roots.append(r[bounds.usage(spline(r)) <= floor * (1.0 + 1e-9)])
    return np.unique(np.concatenate(roots)) if roots else np.empty(0)


class MappedTimeChange(TimeChange):
    """A time change by a :class:`TimeMap` (the attribute ``map``) of base controls: what
    :class:`Retimed` and :class:`InputRetimed` share."""

    map: TimeMap

    def tau(self, t) -> tuple[np.ndarray, np.ndarray]:
        """The planned time at re-timed times (:meth:`TimeMap.tau`).

        Parameters
        ----------
        t : array_like
            Re-timed times.

        Returns
        -------
        tuple of numpy.ndarray
            ``(τ(t), dτ/dt)``.
        """
        return self.map.tau(t)

    def time(self, tau) -> np.ndarray:
        """The re-timed time of planned times (:meth:`TimeMap.time`).

        Parameters
        ----------
        tau : array_like
            Planned times ``τ``.

        Returns
        -------
        numpy.ndarray
            The re-timed times ``t``.
        """
        return self.map.time(tau)

    @property
    def breakpoints(self) -> np.ndarray:
        """The re-timed images of the base controls' breakpoints and of the instants where
        the fastest leg (the most loaded input) changes or meets the floor (``ũ`` has a kink
        there)."""
        b = getattr(self.base, "breakpoints", None)
        inner = [self.map.kinks, self.map.jumps, [0.0, self.base.T]]
        if b is not None:
            inner.append(np.asarray(b, dtype=float))
        out = self.time(np.unique(np.concatenate(inner)))
        out[0], out[-1] = 0.0, self.T
        return np.unique(out)


class Retimed(MappedTimeChange):
    """Physical controls re-timed so that every leg moves at most ``leg_speed`` fast:
    ``ũ(t) = u(τ(t)) dτ/dt`` on ``[0, T]`` (:class:`TimeMap`).

    Evaluates like a control (``u = self(t)``, vectorised); :meth:`~MappedTimeChange.tau` maps
    its times to the planned ones, :meth:`~MappedTimeChange.time` back.

    Parameters
    ----------
    base : Controls or FrameControls
        The planned physical controls, on ``[0, T_base]`` (not re-timed already).
    R0 : array_like
        The start, a rotation matrix.
    mechanism : Mechanism
        The platform.
    leg_speed : float
        ``v``, the legs' top speed (geometry units per second).
    T : float, optional
        The re-timed duration; ``None`` for the least time.
    nodes : int
        CF4 nodes of the replay that samples the legs' speeds, at least.

    Raises
    ------
    ValueError
        If ``base`` is re-timed already, ``R0`` is not a rotation, or :class:`TimeMap`
        refuses the rest.
    """

    kind = "retimed"

    def __init__(self, base, R0, mechanism, leg_speed: float, T: float | None = None,
                 nodes: int = RETIME_NODES):
        if isinstance(base, MappedTimeChange):
            raise ValueError("base is re-timed already: re-time its own base instead")
        self.mechanism = mechanism
        R = np.array(so3.check_rotation(R0, "R0"), dtype=float)
        R.setflags(write=False)
        self.R0 = R
        self.base = base
        self.map = TimeMap(base, R, self.mechanism, leg_speed, T, nodes)
        self.T = self.map.T

    @property
    def leg_speed(self) -> float:
        """``v``, the legs' top speed."""
        return self.map.leg_speed

    def to_dict(self) -> dict:
        """A JSON-able description for :func:`from_dict`.

        Returns
        -------
        dict
            ``{"kind": "retimed", "T", "leg_speed", "nodes", "mechanism", "R0", "base"}``.
        """
        return {"kind": self.kind, "T": self.T, "leg_speed": self.leg_speed, "nodes": self.map.nodes,
                "mechanism": self.mechanism.name, "R0": self.R0.tolist(), "base": self.base.to_dict()}

    def __repr__(self) -> str:
        return (f"Retimed({self.base!r} on [0, {self.T:.6g}], every leg at most "
                f"{self.leg_speed:g} fast)")


def from_dict(d: dict, base_from_dict, mechanism) -> Retimed:
    """Inverse of :meth:`Retimed.to_dict`; the time map is rebuilt by the same computation.

    Parameters
    ----------
    d : dict
        The description.
    base_from_dict : callable
        Reads the base controls.
    mechanism : Mechanism
        The mechanism, of the name ``d`` gives.

    Returns
    -------
    Retimed
        The controls.
    """
    return Retimed(base_from_dict(d["base"]), d["R0"], mechanism, d["leg_speed"], T=d["T"], nodes=d["nodes"])


class InputRetimed(MappedTimeChange):
    """Physical controls re-timed so that every input keeps its bounds:
    ``ũ(t) = u(τ(t)) dτ/dt`` on ``[0, T]`` (:class:`InputTimeMap`), the least time along the
    path for ``T=None``.

    Evaluates like a control (``u = self(t)``, vectorised); :meth:`~MappedTimeChange.tau` maps
    its times to the planned ones, :meth:`~MappedTimeChange.time` back.

    Parameters
    ----------
    base : Controls or FrameControls
        The planned physical controls, on ``[0, T_base]`` (not re-timed already).
    bounds : InputBounds
        The inputs' bounds, checked (one per input, ``low < 0 < high``).
    T : float, optional
        The re-timed duration; ``None`` for the least time.
    nodes : int
        Nodes the inputs are splined through, at least.

    Raises
    ------
    ValueError
        If ``base`` is re-timed already, or :class:`InputTimeMap` refuses the rest.
    """

    kind = "retimed_inputs"

    def __init__(self, base, bounds: InputBounds, T: float | None = None, nodes: int = RETIME_NODES):
        if isinstance(base, MappedTimeChange):
            raise ValueError("base is re-timed already: re-time its own base instead")
        self.base = base
        self.map = InputTimeMap(base, bounds, T, nodes)
        self.bounds = self.map.bounds
        self.T = self.map.T

    def to_dict(self) -> dict:
        """A JSON-able description for :func:`input_from_dict`.

        Returns
        -------
        dict
            ``{"kind": "retimed_inputs", "T", "bounds", "nodes", "base"}``; ``bounds``: one
            pair ``[low, high]`` per input, ``null`` where free.
        """
        return {"kind": self.kind, "T": self.T, "bounds": self.bounds.record(), "nodes": self.map.nodes,
                "base": self.base.to_dict()}

    def __repr__(self) -> str:
        return f"InputRetimed({self.base!r} on [0, {self.T:.6g}], inputs within {self.bounds.text()})"


def input_from_dict(d: dict, base_from_dict) -> InputRetimed:
    """Inverse of :meth:`InputRetimed.to_dict`; the time map is rebuilt by the same computation.

    Parameters
    ----------
    d : dict
        The description.
    base_from_dict : callable
        Reads the base controls.

    Returns
    -------
    InputRetimed
        The controls.
    """
    bounds = InputBounds.from_record(d["bounds"], name="bounds")
    return InputRetimed(base_from_dict(d["base"]), bounds, T=d["T"], nodes=d["nodes"])
