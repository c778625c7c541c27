"""What the least-energy stage lowers and measures.

The energy ``∫_0^T |u|² dt`` of piecewise-constant controls is ``λᵀMλ`` (``λ`` the interval
values, ``M = diag(h_j)``; :func:`energy`). Where the motion comes close to a limit — the
singular set ``Δ = 0``, the legs' stroke, the coordinates' bounds — the optimiser
(:mod:`nonholo.planning.energy_optimiser`) lowers ``F``, the energy plus a small log barrier
on the clearances (:class:`Objective`, :func:`barrier_terms`): an optimum that rides a limit
is approached from inside instead of stalling against it. The energy of any controls, a
plan's among them, is taken by Gauss–Legendre quadrature (:func:`controls_energy`,
:func:`plan_energy_of`).
"""
from __future__ import annotations

import numpy as np

from ..io.result import PlanResult
from ..model.limits import BARRIER_CLEARANCE
from .endpoint_map import Evaluation, EndpointMap, node_sensitivities, spatial_gradient_delta

# -- the barrier on the clearance from Δ = 0 (:func:`barrier_terms`, :class:`Objective`)
#: The barrier on the clearance from ``Δ = 0`` acts where ``sgnΔ`` is below this (or below
#: twice ``delta_min``, where that is more: :func:`barrier_reach`).
BARRIER_DELTA = 0.1
#: Its derivatives are taken with ``r`` at least this (a node on the limit's edge would
#: make its curvature swamp the model in rounding).
MIN_BARRIER_R = 1e-4

# -- the quadrature of any controls' energy (:func:`controls_energy`)
#: Panels of :func:`controls_energy`'s quadrature on ``[0, T]`` at least.
ENERGY_PANELS = 64
#: The 8-point Gauss–Legendre nodes and weights on [-1, 1] of :func:`controls_energy`.
ENERGY_NODES = np.polynomial.legendre.leggauss(8)


def energy(ev: Evaluation, metric: np.ndarray) -> float:
    """``∫|u|² dt = Σ metric_k λ_k²`` of grid controls.

    Parameters
    ----------
    ev : Evaluation
        An evaluation of grid controls.
    metric : numpy.ndarray
        The interval lengths ``h_j``, one per parameter.

    Returns
    -------
    float
        The energy.
    """
    return float(np.dot(metric, ev.params ** 2))


def barrier_reach(delta_min: float) -> float:
    """Where the barrier on the clearance from ``Δ = 0`` acts: ``sgnΔ`` below
    :data:`BARRIER_DELTA`, or below ``2 delta_min`` where that is more (it must lie above
    ``delta_min``).

    Parameters
    ----------
    delta_min : float
        The least ``sgnΔ`` allowed.

    Returns
    -------
    float
        ``d₀``.
    """
    return max(BARRIER_DELTA, 2.0 * delta_min)


def barrier_terms(endpoint: EndpointMap, ev: Evaluation,
                  rows: bool = True) -> tuple[float, np.ndarray, np.ndarray, np.ndarray | None]:
    """The barrier ``Φ = Σ_{n ≥ 1} h ψ(r_n)`` of ``ev``'s nodes on the clearance from
    ``Δ = 0`` (``r = (sgnΔ − delta_min)/(d₀ − delta_min)``, ``d₀`` = :func:`barrier_reach`)
    and on the clearances of the endpoint's limits — the legs' stroke, the coordinates'
    bounds (``r = c/c₀``, ``c₀`` =
    :data:`~nonholo.model.limits.BARRIER_CLEARANCE`), ``ψ(r) = r − 1 − log r`` below 1 and 0
    above (zero with its slope at ``r = 1``).

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint.
    ev : Evaluation
        The evaluation.
    rows : bool, default True
        Compute the terms' gradient rows (the value alone needs none).

    Returns
    -------
    phi : float
        The barrier ``Φ``.
    nodes : numpy.ndarray
        The nodes of the terms within reach.
    r : numpy.ndarray
        Their ``r``.
    rows : numpy.ndarray or None
        Their ``dr/ds`` at the node, rows of ``d`` (``None`` unless asked for).
    """
    mech = endpoint.mechanism
    nodes, rs, grads = [], [], []
    # Δ ≡ +∞ without a singular set: no node near it
    d = endpoint.sign * endpoint.singular.values(ev.R, ev.q)
    span = barrier_reach(endpoint.delta_min) - endpoint.delta_min
    r = (d - endpoint.delta_min) / span
    near = np.nonzero(r < 1.0)[0]
    near = near[near > 0]
    if near.size:
        nodes.append(near), rs.append(r[near])
        if rows:
            grads.append((endpoint.sign / span) * spatial_gradient_delta(mech, ev.R[near], q=ev.q[near]))
    if endpoint.limits is not None:
        terms = endpoint.limits.clearance_terms(mech, ev.R, BARRIER_CLEARANCE, q=ev.q)
        if terms is not None:
            at, c, g = terms
            keep = at > 0
            nodes.append(at[keep]), rs.append(c[keep] / BARRIER_CLEARANCE), grads.append(g[keep] / BARRIER_CLEARANCE)
    if not nodes:
        empty = np.zeros(0)
        return 0.0, empty.astype(int), empty, np.zeros((0, mech.n_rates)) if rows else None
    nodes, r = np.concatenate(nodes), np.maximum(np.concatenate(rs), 1e-300)
    return (float(endpoint.h * np.sum(r - 1.0 - np.log(r))), nodes, r,
            np.concatenate(grads) if rows else None)


class Objective:
    """What a run lowers: ``F = E + τΦ``, the energy plus ``τ`` times the barrier
    (:func:`barrier_terms`), ``τ = ε E/T`` with ``ε`` =
    :data:`~nonholo.planning.energy_optimiser.BARRIER_WEIGHT` and ``E`` the run's energy when
    the iteration set it (the barrier costs at most about ``εE`` of energy). Its gradient
    and the Gauss–Newton Hessian of the barrier, ``τ h Σ ψ''(r_n) g_n g_nᵀ`` (``g_n =
    ∂r_n/∂λ``, from the nodes' sensitivities), make the steps of the quadratic model see the
    limits the motion comes close to.

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint map.
    metric : numpy.ndarray
        The interval lengths ``h_j``, one per parameter.
    """

    def __init__(self, endpoint: EndpointMap, metric: np.ndarray):
        self.endpoint, self.metric = endpoint, metric
        # the barrier can act where Δ is finite (not without a singular set) or limits are kept
        self.constrained = bool(np.isfinite(endpoint.singular.value(*endpoint.start))) or endpoint.limits is not None
        self.tau = 0.0
        self.last = None            # (evaluation, tau, derivatives): an iteration asks twice

    def near(self, ev: Evaluation) -> bool:
        """Whether the barrier may act on the next evaluations.

        They then keep what its derivatives need.

        Parameters
        ----------
        ev : Evaluation
            The current evaluation.

        Returns
        -------
        bool
            Whether its motion comes within twice a barrier's reach of a limit.
        """
        if not self.constrained:
            return False
        endpoint = self.endpoint
        near_delta = (ev.min_delta is not None
                      and ev.min_delta < 2.0 * barrier_reach(endpoint.delta_min))
        near_legs = ev.min_clearance is not None and ev.min_clearance < 2.0 * BARRIER_CLEARANCE
        return near_delta or near_legs

    def value(self, ev: Evaluation) -> float:
        """``F = E + τΦ`` at an evaluation.

        Parameters
        ----------
        ev : Evaluation
            The evaluation.

        Returns
        -------
        float
            The objective's value.
        """
        E = energy(ev, self.metric)
        if not self.constrained or self.tau == 0.0:
            return E
        return E + self.tau * barrier_terms(self.endpoint, ev, rows=False)[0]

    def derivatives(self, ev: Evaluation) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """The objective's derivatives at an evaluation.

        Parameters
        ----------
        ev : Evaluation
            The evaluation (a full one where :meth:`near`).

        Returns
        -------
        grad_energy : numpy.ndarray
            ``∇E``.
        grad_barrier : numpy.ndarray
            ``τ∇Φ``.
        hess_barrier : numpy.ndarray or None
            ``τ∇²Φ`` (Gauss–Newton), ``None`` where no term is within reach.
        """
        if self.last is not None and self.last[0] is ev and self.last[1] == self.tau:
            return self.last[2]
        gE = 2.0 * self.metric * ev.params
        zero = np.zeros_like(gE)
        if not self.constrained or ev.Z is None:
            found = gE, zero, None
        else:
            _, nodes, r, rows = barrier_terms(self.endpoint, ev)
            if not nodes.size:
                found = gE, zero, None
            else:
                at, where = np.unique(nodes, return_inverse=True)
                s = node_sensitivities(self.endpoint, ev, at)
                G = np.einsum("kd,kdp->kp", rows, s[where])           # ∂r_n/∂λ
                h = self.endpoint.h * self.tau
                r = np.maximum(r, MIN_BARRIER_R)
                found = gE, h * (1.0 - 1.0 / r) @ G, (G.T * (h / r ** 2)) @ G
        self.last = ev, self.tau, found
        return found


def plan_energy_of(result: PlanResult) -> float:
    """``∫|u|² dt`` of a plan's physical controls (:func:`controls_energy`).

    Parameters
    ----------
    result : PlanResult
        The plan.

    Returns
    -------
    float
        The energy.
    """
    return controls_energy(result.controls, result.breakpoints, result.T)


def controls_energy(controls, breakpoints, T: float) -> float:
    """``∫_0^T |u|² dt`` of controls by 8-point Gauss–Legendre on panels.

    The panels split ``[0, T]`` at the controls' breakpoints and at least
    :data:`ENERGY_PANELS` equal steps: exact for piecewise-polynomial controls of degree up to
    7, and within rounding for Fourier series of a few dozen harmonics and for frame
    controls played along their motion.

    Parameters
    ----------
    controls : callable
        ``controls(t)``: the physical inputs at the times ``t``, one row per time.
    breakpoints : array_like or None
        Where the controls may jump.
    T : float
        The horizon.

    Returns
    -------
    float
        The energy.
    """
    x, w = ENERGY_NODES
    bps = [] if breakpoints is None else np.asarray(breakpoints, dtype=float)
    b = np.unique(np.concatenate([np.linspace(0.0, T, ENERGY_PANELS + 1), bps]))
    b = b[(b >= 0.0) & (b <= T)]
    a, c = b[:-1], b[1:]
    t = (0.5 * (a + c))[:, None] + (0.5 * (c - a))[:, None] * x[None, :]
    u = np.asarray(controls(t.ravel())).reshape(len(a), len(x), -1)
    return float(np.sum(0.5 * (c - a)[:, None] * w[None, :] * np.sum(u ** 2, axis=2)))
