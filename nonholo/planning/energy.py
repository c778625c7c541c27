"""The least-energy stage: a plan's goal kept, its energy ``∫_0^T |u|² dt`` brought to the least.

The least-energy motion of a driftless system ``ẋ = G(x) u`` between two states is a
sub-Riemannian geodesic. It is sought among piecewise-constant physical inputs on
:data:`ENERGY_GRID` equal intervals (parameters ``λ``, the interval values; ``∫|u|² =
λᵀMλ``, ``M = diag(h_j)``) by sequential quadratic programming (:func:`descend`): each
step is the least of the quadratic model ``gᵀd + ½dᵀBd`` on the linearised endpoint
condition ``l_T + J d = 0`` (``l_T`` the stacked terminal error, ``J = ∂s_T/∂λ`` from the
variational system, as in the planner; :func:`qp_step`). ``B`` starts as the energy's
Hessian ``2M`` — the Gauss–Newton step ``λ⁺ = M⁻¹Jᵀ(JM⁻¹Jᵀ)⁻¹(Jλ − l_T)``, the
least-energy point of the linearised condition — and learns the curvature of the
endpoint map by damped BFGS updates of the Lagrangian's Hessian (reset to ``2M`` when
its step runs away). A fixed point satisfies ``Mλ = Jᵀν``, ``l_T = 0``: the first-order
conditions of the least energy with the endpoint fixed (the discrete Pontryagin
condition ``u = Gᵀp``). Steps are damped by a backtracking line search on the merit
``F + μ|l_T|`` (``μ`` above the multiplier ``|ν|``), with a second-order correction of a
rejected full step, and shortened until the trajectory is admissible — ``|Δ| ≥
delta_min``, the legs inside their stroke — so every iterate is; the iteration need not
start at the goal. Once a run comes within :data:`POLISH_BELOW` of the goal, Newton steps
of least energy bring it onto it (:func:`newton_steps`), and from there on it stays at the
goal: each trial step is brought back by such steps and accepted where the objective
falls (:func:`restoring_search`), so a run at the goal never trades it for energy. Where
the motion comes close to those limits, ``F`` is the energy plus a small log barrier on
the clearances (:class:`Objective`): an optimum that rides a limit is approached from
inside instead of stalling against it.

Such an iteration finds *a* critical point near its start; the least one is looked for
from several starts (:func:`starts`): the certified plan's inputs, then the drift toward
the goal plus loops of a few sizes and frequency ratios in either sense (the motions
that reach the bracket directions at the least cost), then seeded random Fourier inputs.
Each start is iterated :data:`PROBE_ITERATIONS` times, or fewer where it heads for far more
energy than a run finished at the goal (:func:`probe`), then the run heading for the least
energy is continued, round by round, while it heads for not much more than the best
finished one (:data:`CONTINUE_WITHIN`; while none has finished, one round after each
start) and has not joined a run finished above it (:data:`JOIN_DISTANCE`); no further
start is taken once :data:`CONFIRMATIONS` finished runs agree on the least energy
(:func:`confirmed`; :func:`search`). The search integrates with a fraction of the plan's
steps (:data:`SEARCH_COARSENING`); the least-energy run at the goal, brought onto it on the
plan's own steps, that is certified (:mod:`nonholo.planning.certification`) is the result
(where none is, the search is run again on the plan's own steps: a motion riding a limit
may reach the goal only there). Everything is budgeted in effort
(:mod:`nonholo.numerics.effort`, :data:`ENERGY_EFFORT`), not in wall time, so the same call
gives the same plan on any machine under any load.

The result's controls are those grid controls (method ``"nonparametric"``) of the
physical inputs; if no start ends at a certified control at least as cheap as the plan's,
the plan is returned as it was, its reason saying why. :func:`improve` runs the stage
for ``objective="energy"`` and, quickly, for ``objective="auto"``, which keeps the plan
unless it needs far more energy than a motion the quick search finds; that motion is then
made smooth (a Fourier fit brought onto the goal and lowered in its coefficients,
:func:`smoothed`): grid controls jump at every interval, which a physical mechanism cannot
follow. Where the fit cannot be brought onto the goal, the plan's own fit is lowered
instead; where neither does, the plan is kept. The quick search and the fits keep most of
the plan's clearance from ``Δ = 0`` (:func:`smooth_clearance`).
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.linalg import cho_factor, cho_solve
from scipy.linalg.blas import dger

from ..controls.parametrisations import Controls, Fourier, PiecewiseConstant
from ..io.result import PlanResult
from ..model.limits import BARRIER_CLEARANCE
from ..motion.frame_controls import FrameControls
from ..numerics import effort
from .certification import certified
from .core import (
    Evaluation,
    Evaluator,
    Options,
    Outcome,
    build_result,
    node_sensitivities,
    record,
    spatial_gradient_delta,
)

#: Intervals of the piecewise-constant controls the energy is lowered over (the plan's
#: integrator steps are rounded up to a multiple of it).
ENERGY_GRID = 100
#: The full search integrates with this many times fewer steps than the plan (at least one
#: per interval); its finalists are brought onto the goal and certified on the plan's steps.
SEARCH_COARSENING = 2
#: SQP iterations of one start at most.
MAX_ITERATIONS = 80
#: SQP iterations of every start before any is continued, and of each round after.
PROBE_ITERATIONS = 12
#: ... in stages of this many (:func:`probe`), ...
PROBE_STAGE = 4
#: ... the probe ending once the run heads for more than this many times the least energy
#: of a run finished at the goal.
GIVE_UP_ABOVE = 2.0
#: A run whose controls come this close (relative, :func:`distance`) to those of a run
#: finished at the goal above the least energy is given up: it is heading for the same
#: critical point.
JOIN_DISTANCE = 0.05
#: Runs are continued while the one heading for the least energy heads below this many
#: times the least energy of a run finished at the goal (a run's heading after its probe
#: is a rough guess: one heading somewhat above the best may end below it).
CONTINUE_WITHIN = 1.15
#: The search starts no further run once this many runs finished at the goal agree on the
#: least energy of any (:func:`confirmed`) ...
CONFIRMATIONS = 2
#: ... within this relative difference.
AGREE_RTOL = 1e-5
#: Runs at the goal polished and certified at most, the cheapest first.
FINALISTS = 3
#: A probe is near the goal when its terminal error is below this (in the error's units).
NEAR_GOAL = 1e-3
#: A start whose projection on the grid ends closer to the goal than this, or a run's
#: iterate, is brought onto it by Newton steps.
POLISH_BELOW = 0.05
#: Seconds of effort (:mod:`nonholo.numerics.effort`) a search may take (the stage takes a
#: second search, on the plan's own steps, where the first certifies nothing).
ENERGY_EFFORT = 1.0
#: Seconds of effort an iteration's linear algebra counts, besides its simulations (about
#: its time on the reference machine).
ITERATION_EFFORT = 1e-3
#: The iteration has converged when an accepted step lowers the energy by less than this
#: fraction (and the endpoint is within ``tol``).
ENERGY_RTOL = 1e-9
#: ... or when the energy's gradient is this close to the row space of ``J`` (relative, in
#: the metric ``M⁻¹``: the first-order conditions).
KKT_RTOL = 1e-8
#: A quasi-Newton step longer than this many Gauss–Newton steps (metric M) resets the
#: Hessian to ``2M`` ...
STEP_GROWTH = 4.0
#: ... or this many, once the run is at the goal: there the Gauss–Newton step is the
#: slowly contracting fixed-point step, which the quasi-Newton step outgrows as it learns
#: the curvature, and the restoring search guards every step.
STEP_GROWTH_AT_GOAL = 8.0
#: ... and so does one the line search halved more than this many times.
RESET_HALVINGS = 3
#: The merit's weight on ``|l_T|``: this many times the multiplier ``|ν|`` (at least).
MERIT_FACTOR = 2.0
#: Step halvings of the line search at most.
MAX_HALVINGS = 12
#: Newton steps that bring a trial step of a run at the goal back onto it, at most (a long
#: quasi-Newton step may end 0.1 from the goal; quadratic convergence needs four or five
#: steps from there, and a trial refused for want of them costs a halving and a new trial).
RESTORE_STEPS = 6
#: ``objective="auto"``: the starts of the quick search (the plan's, then the loops of the
#: first size).
QUICK_STARTS = 5
#: ``objective="auto"``: the quick search's budget (seconds of effort).
QUICK_EFFORT = 0.3
#: ``objective="auto"``: the fraction of the plan's energy a motion the quick search finds
#: must need less than to replace it (a plan kept needs at most 1/0.6 ≈ 1.7 times what it
#: found).
REPLACE_BELOW = 0.6
#: ``objective="auto"``: the fraction of the plan's clearance from ``Δ = 0`` above
#: ``delta_min`` the motion that replaces it keeps (:func:`smooth_clearance`).
KEEP_CLEARANCE = 0.9
#: ``objective="auto"``: harmonics of the smooth motion that replaces a plan (:func:`smoothed`).
SMOOTH_HARMONICS = 16
#: ``objective="auto"``: SQP iterations of the smooth motion's energy at most.
SMOOTH_ITERATIONS = 12
#: ``objective="auto"``: ... and of the smooth motion from the plan's fit, where the least
#: energy's fit does not reach the goal ...
SMOOTH_PLAN_ITERATIONS = 40
#: ... which replaces the plan where it needs less than this fraction of its energy.
REFIT_BELOW = 0.9
#: The barrier on the clearance from ``Δ = 0`` acts where ``sgnΔ`` is below this (or below
#: twice ``delta_min``, where that is more: :func:`barrier_reach`).
BARRIER_DELTA = 0.1
#: The barrier's weight ``ε`` relative to the energy (:class:`Objective`).
BARRIER_WEIGHT = 1e-3
#: Its derivatives are taken with ``r`` at least this (a node on the limit's edge would
#: make its curvature swamp the model in rounding).
MIN_BARRIER_R = 1e-4
#: Loop sizes of the starts, relative to the loop that encloses the goal's offset.
LOOP_SCALES = (1.0, 0.5, 2.0)
#: Frequencies (in ``2π/T``) of the first two inputs of the loops of the starts.
LOOP_FREQUENCIES = ((1, 1), (1, 2), (2, 1))
#: Seeded random Fourier starts after the deterministic ones.
RANDOM_STARTS = 4
RANDOM_SEED = 20240226


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


def barrier_terms(problem: Evaluator, ev: Evaluation,
                  rows: bool = True) -> tuple[float, np.ndarray, np.ndarray, np.ndarray | None]:
    """The barrier ``Φ = Σ_{n ≥ 1} h ψ(r_n)`` of ``ev``'s nodes on the clearance from
    ``Δ = 0`` (``r = (sgnΔ − delta_min)/(d₀ − delta_min)``, ``d₀`` = :func:`barrier_reach`)
    and on the clearances of the problem's limits — the legs' stroke, the coordinates'
    bounds (``r = c/c₀``, ``c₀`` =
    :data:`~nonholo.model.limits.BARRIER_CLEARANCE`), ``ψ(r) = r − 1 − log r`` below 1 and 0
    above (zero with its slope at ``r = 1``).

    Parameters
    ----------
    problem : Evaluator
        The problem.
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
    mech = problem.mechanism
    nodes, rs, grads = [], [], []
    if problem.singular.exists:
        d = problem.sign * mech.delta_samples(ev.R, ev.q)
        span = barrier_reach(problem.delta_min) - problem.delta_min
        r = (d - problem.delta_min) / span
        near = np.nonzero(r < 1.0)[0]
        near = near[near > 0]
        if near.size:
            nodes.append(near), rs.append(r[near])
            if rows:
                grads.append((problem.sign / span) * spatial_gradient_delta(mech, ev.R[near], q=ev.q[near]))
    if problem.limits is not None:
        terms = problem.limits.clearance_terms(mech, ev.R, BARRIER_CLEARANCE, q=ev.q)
        if terms is not None:
            at, c, g = terms
            keep = at > 0
            nodes.append(at[keep]), rs.append(c[keep] / BARRIER_CLEARANCE), grads.append(g[keep] / BARRIER_CLEARANCE)
    if not nodes:
        empty = np.zeros(0)
        return 0.0, empty.astype(int), empty, np.zeros((0, mech.n_rates)) if rows else None
    nodes, r = np.concatenate(nodes), np.maximum(np.concatenate(rs), 1e-300)
    return (float(problem.h * np.sum(r - 1.0 - np.log(r))), nodes, r,
            np.concatenate(grads) if rows else None)


class Objective:
    """What a run lowers: ``F = E + τΦ``, the energy plus ``τ`` times the barrier
    (:func:`barrier_terms`), ``τ = ε E/T`` with ``ε`` = :data:`BARRIER_WEIGHT` and ``E`` the
    run's energy when the iteration set it (the barrier costs at most about ``εE`` of
    energy). Its gradient and the Gauss–Newton Hessian of the barrier, ``τ h Σ ψ''(r_n)
    g_n g_nᵀ`` (``g_n = ∂r_n/∂λ``, from the nodes' sensitivities), make the steps of the
    quadratic model see the limits the motion comes close to.

    Parameters
    ----------
    problem : Evaluator
        The problem.
    metric : numpy.ndarray
        The interval lengths ``h_j``, one per parameter.
    """

    def __init__(self, problem: Evaluator, metric: np.ndarray):
        self.problem, self.metric = problem, metric
        self.constrained = problem.singular.exists or problem.limits is not None
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
        problem = self.problem
        near_delta = (problem.singular.exists and ev.min_delta is not None
                      and ev.min_delta < 2.0 * barrier_reach(problem.delta_min))
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
        return E + self.tau * barrier_terms(self.problem, ev, rows=False)[0]

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
            _, nodes, r, rows = barrier_terms(self.problem, ev)
            if not nodes.size:
                found = gE, zero, None
            else:
                at, where = np.unique(nodes, return_inverse=True)
                s = node_sensitivities(self.problem, ev, at)
                G = np.einsum("kd,kdp->kp", rows, s[where])           # ∂r_n/∂λ
                h = self.problem.h * self.tau
                r = np.maximum(r, MIN_BARRIER_R)
                found = gE, h * (1.0 - 1.0 / r) @ G, (G.T * (h / r ** 2)) @ G
        self.last = ev, self.tau, found
        return found


@dataclass(eq=False)
class Run:
    """One start's SQP iteration: its label, last evaluation, energy, whether it
    converged (or can make no further step), its history, the merit's weight ``mu``, the
    quasi-Newton Hessian ``B`` of the Lagrangian, the barrier's weight ``tau`` and the first
    step of the next line search ``alpha`` (carried from round to round), and the
    first-order residual ``kkt`` of its last iterate.

    Parameters
    ----------
    label : str
        The start's label.
    evaluation : Evaluation
        The last evaluation.
    energy : float
        Its energy.
    converged : bool, default False
        Whether the iteration converged.
    stuck : bool, default False
        Whether it can make no further step.
    history : list
        Its history entries.
    mu : float, default 0.0
        The merit's weight on ``|l_T|``.
    B : numpy.ndarray or None
        The quasi-Newton Hessian of the Lagrangian (a vector: diagonal).
    H : numpy.ndarray or None
        Its inverse, once ``B`` is a matrix.
    tau : float or None
        The barrier's weight, once set.
    kkt : float, default inf
        The first-order residual of the last iterate.
    alpha : float, default 1.0
        The first step of the next line search.
    joined : str, default ""
        The label of the run finished above the least energy it came close to, once it did
        (:func:`continue_near_best`): it is not continued.
    """

    label: str
    evaluation: Evaluation
    energy: float
    converged: bool = False
    stuck: bool = False
    history: list = field(default_factory=list)
    mu: float = 0.0
    B: np.ndarray | None = None
    H: np.ndarray | None = None
    tau: float | None = None
    kkt: float = float("inf")
    alpha: float = 1.0
    joined: str = ""


def rank_one(A: np.ndarray, alpha: float, x: np.ndarray, y: np.ndarray) -> None:
    """``A += α x yᵀ`` in place (BLAS ``dger``; ``A`` square and C-ordered).

    Parameters
    ----------
    A : numpy.ndarray
        The matrix, updated.
    alpha : float
        ``α``.
    x, y : numpy.ndarray
        The vectors.
    """
    dger(alpha, y, x, a=A.T, overwrite_a=True)


def small_solve(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``A⁻¹b`` for the small square systems of the endpoint's dimension (least squares
    where ``A`` is singular).

    Parameters
    ----------
    A : numpy.ndarray
        The matrix.
    b : numpy.ndarray
        The right-hand side.

    Returns
    -------
    numpy.ndarray
        The solution.
    """
    try:
        x = np.linalg.solve(A, b)
        if np.all(np.isfinite(x)):
            return x
    except np.linalg.LinAlgError:
        pass
    return np.linalg.lstsq(A, b, rcond=None)[0]


def qp_step(B: np.ndarray, g: np.ndarray, J: np.ndarray, l: np.ndarray,
            H: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The step of the quadratic model ``min gᵀd + ½dᵀBd`` subject to ``l + Jd = 0``.

    Parameters
    ----------
    B : numpy.ndarray
        Positive definite: a matrix, or the vector of a diagonal one.
    g : numpy.ndarray
        The gradient.
    J : numpy.ndarray
        The Jacobian of the endpoint.
    l : numpy.ndarray
        The terminal error ``l_T``.
    H : numpy.ndarray, optional
        ``B⁻¹``, where it is known (a matrix ``B`` is otherwise factorised).

    Returns
    -------
    d : numpy.ndarray
        The step.
    nu : numpy.ndarray
        Its multiplier ``ν`` (``Bd + g = Jᵀν``).
    """
    if B.ndim == 1:
        Hg, HJ = g / B, J.T / B[:, None]
    elif H is not None:
        Hg, HJ = H @ g, H @ J.T
    else:
        factor = cho_factor(B)
        Hg, HJ = cho_solve(factor, g), cho_solve(factor, J.T)
    nu = small_solve(J @ HJ, J @ Hg - l)
    return HJ @ nu - Hg, nu


def line_search(problem: Evaluator, ev: Evaluation, d: np.ndarray, objective: Objective, mu: float,
                slope: float, alpha: float = 1.0) -> tuple[Evaluation | None, float, int]:
    """The step along ``d`` from ``ev`` the merit ``F + μ|l_T|`` accepts (Armijo; ``F`` the
    :class:`Objective`), halved until the trajectory is admissible and the merit drops; a
    full step the merit rejects is first retried with a second-order correction (the
    least-energy ``c`` with ``J c = −l_T`` at the trial point: the merit's non-smooth term
    would otherwise reject the full steps of the fast local convergence).

    Parameters
    ----------
    problem : Evaluator
        The problem.
    ev : Evaluation
        The current evaluation.
    d : numpy.ndarray
        The step.
    objective : Objective
        ``F``.
    mu : float
        The merit's weight ``μ``.
    slope : float
        The merit's directional derivative along ``d``.
    alpha : float, default 1.0
        The first step tried (the run's last accepted one, doubled: a run whose model
        overshoots does not pay the same halvings at every iteration).

    Returns
    -------
    evaluation : Evaluation or None
        The accepted evaluation, ``None`` when :data:`MAX_HALVINGS` halvings do not do.
    alpha : float
        The step ``α``.
    rejected : int
        Halvings.
    """
    merit0 = objective.value(ev) + mu * ev.error
    full = objective.near(ev)
    rejected = 0
    for _ in range(MAX_HALVINGS):
        trial = problem.evaluate(ev.params + alpha * d, full=full)
        if problem.admissible(trial):
            bound = merit0 + 1e-4 * alpha * min(slope, 0.0)
            if objective.value(trial) + mu * trial.error <= bound:
                return trial, alpha, rejected
            if alpha == 1.0:
                second = problem.evaluate(trial.params + correction(ev, objective.metric), full=full)
                if problem.admissible(second) and objective.value(second) + mu * second.error <= bound:
                    return second, alpha, rejected
        alpha *= 0.5
        rejected += 1
    return None, alpha, rejected


def restoring_search(problem: Evaluator, ev: Evaluation, d: np.ndarray, objective: Objective, slope: float,
                     alpha: float, options: Options) -> tuple[Evaluation | None, float, int]:
    """The step along ``d`` from ``ev`` at the goal, brought back onto it: each trial
    ``λ + αd`` is followed by Newton steps of least energy (:func:`correction`) until it
    ends within ``tol``; it is accepted where it is admissible and ``F`` drops (Armijo),
    else ``α`` is halved. The iterates of a run at the goal stay at it, and ``F`` falls
    at every one of them: a step cannot trade the goal for energy.

    Parameters
    ----------
    problem : Evaluator
        The problem.
    ev : Evaluation
        The current evaluation, within ``tol`` of the goal.
    d : numpy.ndarray
        The step.
    objective : Objective
        ``F``.
    slope : float
        ``F``'s directional derivative along ``d``.
    alpha : float
        The first step tried.
    options : Options
        The run's settings (``tol``).

    Returns
    -------
    evaluation : Evaluation or None
        The accepted evaluation, ``None`` when :data:`MAX_HALVINGS` halvings do not do.
    alpha : float
        The step ``α``.
    rejected : int
        Halvings.
    """
    F0 = objective.value(ev)
    full = objective.near(ev)
    metric = objective.metric
    rejected = 0
    for _ in range(MAX_HALVINGS):
        trial = problem.evaluate(ev.params + alpha * d, full=full)
        if problem.admissible(trial):
            trial = newton_steps(problem, trial, metric, options.tol, RESTORE_STEPS, full=full)
        if (problem.admissible(trial) and trial.error <= options.tol
                and objective.value(trial) <= F0 + 1e-4 * alpha * min(slope, 0.0)):
            return trial, alpha, rejected
        alpha *= 0.5
        rejected += 1
    return None, alpha, rejected


def descend(problem: Evaluator, run: Run, options: Options, iterations: int, deadline: float) -> Run:
    """More SQP iterations of a run (see the module).

    It stops at convergence, at a step the line search cannot accept, or past ``deadline``.

    Parameters
    ----------
    problem : Evaluator
        The problem.
    run : Run
        The run, updated.
    options : Options
        The run's settings.
    iterations : int
        Iterations at most.
    deadline : float
        An :func:`nonholo.numerics.effort.seconds` reading.

    Returns
    -------
    Run
        ``run``.
    """
    ev = run.evaluation
    metric = ev.parametrisation.metric()
    objective = Objective(problem, metric)
    gn_hessian = 2.0 * metric            # the Gauss–Newton Hessian 2M, diagonal
    if run.B is None:
        run.B = gn_hessian
    it0 = run.history[-1]["iteration"] if run.history else 0
    for it in range(it0 + 1, it0 + iterations + 1):
        if run.converged or run.stuck or effort.seconds() > deadline:
            break
        # the iteration's own work (the model, its factorisations, the limits' terms) counts
        # beside the kernels' steps
        effort.add(ITERATION_EFFORT * effort.STEPS_PER_SECOND)
        if objective.near(ev) and ev.Z is None:
            ev = problem.evaluate(ev.params, full=True)
        if run.tau is None:
            run.tau = BARRIER_WEIGHT * max(energy(ev, metric), 1e-12) / problem.T
        objective.tau = run.tau
        gE, gB, HB = objective.derivatives(ev)
        g = gE + gB
        model = run.B if HB is None else (np.diag(run.B) if run.B.ndim == 1 else run.B) + HB
        try:
            d, nu = qp_step(model, g, ev.J, ev.l, run.H if HB is None else None)
        except np.linalg.LinAlgError:       # the updates lost definiteness to rounding
            run.B, run.H = gn_hessian, None
            d, nu = qp_step(gn_hessian, g, ev.J, ev.l)
        if run.B.ndim == 2:
            gn = qp_step(gn_hessian if HB is None else np.diag(gn_hessian) + HB, g, ev.J, ev.l)
            growth = STEP_GROWTH if ev.error > options.tol else STEP_GROWTH_AT_GOAL
            if not np.dot(metric * d, d) <= growth ** 2 * np.dot(metric * gn[0], gn[0]):
                run.B, run.H = gn_hessian, None
                d, nu = gn
        run.mu = max(run.mu, MERIT_FACTOR * float(np.linalg.norm(nu)))
        E0 = energy(ev, metric)
        if ev.error <= options.tol:
            accepted, alpha, rejected = restoring_search(problem, ev, d, objective, float(np.dot(g, d)),
                                                         run.alpha, options)
        else:
            slope = float(np.dot(g, d)) - run.mu * ev.error
            accepted, alpha, rejected = line_search(problem, ev, d, objective, run.mu, slope, run.alpha)
        if accepted is None:
            run.stuck = True
            break
        run.alpha = min(1.0, 2.0 * alpha)
        if objective.near(accepted) and accepted.Z is None:
            accepted = problem.evaluate(accepted.params, full=True)
        gE1, gB1, _ = objective.derivatives(accepted)
        g1 = gE1 + gB1
        if rejected > RESET_HALVINGS:
            run.B, run.H = gn_hessian, None
        else:
            # damped BFGS update of the Hessian of the energy's Lagrangian E − νᵀs_T (Powell);
            # the barrier's is taken as it is
            step = accepted.params - ev.params
            y = (gE1 - accepted.J.T @ nu) - (gE - ev.J.T @ nu)
            B = np.diag(run.B) if run.B.ndim == 1 else run.B
            Bs = B @ step
            sBs, sy = float(step @ Bs), float(step @ y)
            if sBs > 0.0:
                if sy < 0.2 * sBs:
                    theta = 0.8 * sBs / (sBs - sy)
                    y = theta * y + (1.0 - theta) * Bs
                    sy = float(step @ y)
                # and of its inverse H, B⁺⁻¹ = H + ((sᵀy + yᵀHy)/(sᵀy)²) ssᵀ − (Hy sᵀ + s yᵀH)/sᵀy,
                # in place (the run's own matrices once B is one: B and H become matrices together)
                H = np.diag(1.0 / run.B) if run.B.ndim == 1 else run.H
                Hy = H @ y
                rank_one(B, 1.0 / sy, y, y)
                rank_one(B, -1.0 / sBs, Bs, Bs)
                rank_one(H, (sy + float(y @ Hy)) / sy ** 2, step, step)
                rank_one(H, -1.0 / sy, Hy, step)
                rank_one(H, -1.0 / sy, step, Hy)
                run.B, run.H = B, H
        E1 = energy(accepted, metric)
        ev = accepted
        # first-order conditions: the gradient in the row space of J (in the metric M⁻¹)
        JW = ev.J / metric
        lam = small_solve(JW @ ev.J.T, JW @ g1)
        resid = g1 - ev.J.T @ lam
        run.kkt = float(np.sqrt(np.dot(resid / metric, resid) / max(np.dot(g1 / metric, g1), 1e-300)))
        run.history.append(record(it, ev, alpha, "energy", rejected, energy=E1, start=run.label))
        settled = run.kkt <= KKT_RTOL or abs(E0 - E1) <= ENERGY_RTOL * E0
        if options.tol < ev.error <= POLISH_BELOW:
            # the goal is near: Newton steps end on it, and the run goes on at it
            # (restoring_search)
            run.evaluation = ev
            ev = polish(problem, run, options).evaluation
        if settled and ev.error <= options.tol:
            run.converged = True
    run.evaluation, run.energy = ev, energy(ev, metric)
    return run


def begin(problem: Evaluator, label: str, controls: Controls, options: Options) -> Run | None:
    """A run from physical controls projected on the grid.

    A projection that ends near the goal (a plan's) is first brought onto it
    (:func:`polish`): the iteration then lowers the energy of motions that reach the goal
    instead of trading the goal for energy.

    Parameters
    ----------
    problem : Evaluator
        The problem (grid controls).
    label : str
        The start's label.
    controls : Controls
        The physical controls.
    options : Options
        The run's settings.

    Returns
    -------
    Run or None
        The run, or ``None`` where the projection's motion is not admissible.
    """
    grid = PiecewiseConstant.fit(controls, problem.T, ENERGY_GRID, problem.mechanism.n_inputs)
    ev = problem.evaluate(grid)
    if not problem.admissible(ev):
        return None
    E = energy(ev, grid.metric())
    run = Run(label, ev, E, history=[record(0, ev, 0.0, "energy", 0, energy=E, start=label)])
    if ev.error <= POLISH_BELOW:
        polish(problem, run, options)
    return run


def correction(ev: Evaluation, metric: np.ndarray) -> np.ndarray:
    """The least-energy parameter change ``c`` with ``J c = −l_T`` (a Newton step to the goal).

    Parameters
    ----------
    ev : Evaluation
        A complete evaluation.
    metric : numpy.ndarray
        The interval lengths ``h_j``.

    Returns
    -------
    numpy.ndarray
        ``c``.
    """
    JW = ev.J / metric
    return -JW.T @ small_solve(JW @ ev.J.T, ev.l)


def estimate(run: Run) -> float:
    """The energy a run is heading for.

    Parameters
    ----------
    run : Run
        The run.

    Returns
    -------
    float
        Its parameters' energy after a Newton step to the goal (its energy itself when at
        the goal).
    """
    ev = run.evaluation
    metric = ev.parametrisation.metric()
    return float(np.dot(metric, (ev.params + correction(ev, metric)) ** 2))


def polish(problem: Evaluator, run: Run, options: Options, steps: int = 4) -> Run:
    """Newton steps of least energy toward the goal (:func:`correction`).

    While they lower ``|l_T|`` and it is above ``tol``: an iteration stopped by its budget
    close to the goal ends on it.

    Parameters
    ----------
    problem : Evaluator
        The problem.
    run : Run
        The run, updated.
    options : Options
        The run's settings.
    steps : int, default 4
        Steps at most.

    Returns
    -------
    Run
        ``run``.
    """
    metric = run.evaluation.parametrisation.metric()

    def note(ev):
        run.history.append(record(run.history[-1]["iteration"] + 1, ev, 1.0, "energy", 0,
                                  energy=energy(ev, metric), start=run.label))

    ev = newton_steps(problem, run.evaluation, metric, options.tol, steps, note=note)
    run.evaluation, run.energy = ev, energy(ev, metric)
    return run


def newton_steps(problem: Evaluator, ev: Evaluation, metric: np.ndarray, tol: float, steps: int,
                 full: bool = False, note=None) -> Evaluation:
    """Newton steps of least energy toward the goal (:func:`correction`) from ``ev``, while
    ``|l_T|`` is above ``tol`` and each step is admissible and lowers it.

    Parameters
    ----------
    problem : Evaluator
        The problem.
    ev : Evaluation
        The evaluation to start from.
    metric : numpy.ndarray
        The interval lengths ``h_j``.
    tol : float
        The goal's tolerance.
    steps : int
        Steps at most.
    full : bool, default False
        Keep the nodes' sensitivities (:meth:`~nonholo.planning.core.Evaluator.evaluate`).
    note : callable, optional
        ``note(evaluation)``, called after each step taken.

    Returns
    -------
    Evaluation
        The last evaluation taken.
    """
    for _ in range(steps):
        if not ev.complete or ev.error <= tol:      # a motion that ran into Δ = 0 has no l_T
            break
        trial = problem.evaluate(ev.params + correction(ev, metric), full=full)
        if not (problem.admissible(trial) and trial.error < ev.error):
            break
        ev = trial
        if note is not None:
            note(ev)
    return ev


def onto(problem: Evaluator, ev: Evaluation, tol: float) -> Evaluation:
    """``ev``'s controls on ``problem``'s integrator steps, brought onto the goal there by
    Newton steps of least energy (at most :data:`RESTORE_STEPS`).

    Parameters
    ----------
    problem : Evaluator
        The problem on the other steps.
    ev : Evaluation
        An evaluation of grid controls.
    tol : float
        The goal's tolerance.

    Returns
    -------
    Evaluation
        The last evaluation taken.
    """
    return newton_steps(problem, problem.evaluate(ev.controls), ev.parametrisation.metric(), tol, RESTORE_STEPS)


def loop_starts(problem: Evaluator):
    """Labelled physical initial controls of the search: the drift ``ū = G(x₀)^# δ/T``
    toward the goal (``δ`` the offset of the goal from the start, a least-squares fit of
    the field at the start) plus loops ``u_i = A sin(k_i ωt ± iπ/2)`` (``ω = 2π/T``) of
    the frequencies :data:`LOOP_FREQUENCIES` (equal ones reach the first brackets, a 1:2
    pair the second), in either sense, of the sizes :data:`LOOP_SCALES` times the one whose
    enclosed area matches ``|δ|``; then :data:`RANDOM_STARTS` seeded random Fourier inputs
    of that size around the drift. For a mechanism on SO(3) with a desingularised frame
    these are the frame coordinates ``w`` (``G = N``), played as the physical inputs
    ``u = W(R) w`` along their motion (:class:`~nonholo.motion.frame_controls.FrameControls`):
    loops of ``u`` itself would run into ``Δ = 0``, where ``L`` blows up.

    Parameters
    ----------
    problem : Evaluator
        The problem.

    Yields
    ------
    label : str
        The start's label.
    controls : Controls
        Its physical controls.
    """
    mech, T = problem.mechanism, problem.T
    m = mech.n_inputs
    in_frame = mech.has_frame and not mech.space.k
    offset = mech.space.offset(problem.R0, problem.q0, problem.Rd, problem.qd)
    field = mech.frame.N(problem.R0) if in_frame else mech.G(problem.R0, problem.q0)
    drift = np.linalg.lstsq(field, offset, rcond=None)[0] / T
    omega = 2.0 * np.pi / T
    size = omega * np.sqrt(max(float(np.linalg.norm(offset)), 1e-2) / np.pi)

    def physical(w: Fourier) -> Controls:
        return FrameControls(w, problem.R0, mech, problem.steps) if in_frame else w

    for scale in LOOP_SCALES:
        for pair in LOOP_FREQUENCIES:
            k = np.resize(np.asarray(pair, dtype=float), m)
            for sense in (1.0, -1.0):
                shift = 0.5 * np.pi * sense * np.arange(m)

                def loop(t, A=scale * size, k=k, shift=shift):
                    t = np.asarray(t, dtype=float)
                    return drift + A * np.sin(omega * k * t[..., None] + shift)

                label = f"loop {scale:g} {pair[0]}:{pair[1]}{'+' if sense > 0 else '-'}"
                yield label, physical(Fourier.fit(loop, T, int(max(pair)), m))
    rng = np.random.default_rng(RANDOM_SEED)
    for j in range(RANDOM_STARTS):
        K = 1 + j % 3
        c = rng.standard_normal((m, 2 * K + 1))
        c *= size / np.sqrt(np.sum(c[:, 0] ** 2) + 0.5 * np.sum(c[:, 1:] ** 2))
        c[:, 0] += drift
        yield f"random {j + 1}", physical(Fourier(T, c))


def starts(problem: Evaluator, plan: Controls | None):
    """The starts of the search: the certified plan's physical inputs, then :func:`loop_starts`.

    Parameters
    ----------
    problem : Evaluator
        The problem.
    plan : Controls or None
        The plan's physical controls, if any.

    Yields
    ------
    label : str
        The start's label.
    controls : Controls
        Its physical controls.
    """
    if plan is not None:
        yield "plan", plan
    yield from loop_starts(problem)


def finished_at_goal(run: Run, options: Options) -> bool:
    """Whether a run has finished (converged, or can make no further step) at the goal.

    Parameters
    ----------
    run : Run
        The run.
    options : Options
        The run's settings (``tol``).

    Returns
    -------
    bool
        Whether it has.
    """
    return (run.converged or run.stuck) and run.evaluation.error <= options.tol


def confirmed(runs: list[Run], options: Options) -> bool:
    """Whether :data:`CONFIRMATIONS` runs finished at the goal (converged, or no further
    step) agree (within :data:`AGREE_RTOL`) on the least energy of any: starts from
    different motions that end at the same critical point, the least found, make a lower
    one unlikely.

    Parameters
    ----------
    runs : list of Run
        The runs.
    options : Options
        The run's settings (``tol``).

    Returns
    -------
    bool
        Whether the search may stop starting runs.
    """
    found = sorted(r.energy for r in runs if finished_at_goal(r, options))
    return bool(found) and sum(e <= found[0] * (1.0 + AGREE_RTOL) for e in found) >= CONFIRMATIONS


def distance(run: Run, other: Run) -> float:
    """The distance of two runs' controls relative to the second's, ``|λ − λ'|_M / |λ'|_M``.

    Parameters
    ----------
    run, other : Run
        The runs (on the same grid).

    Returns
    -------
    float
        The distance.
    """
    metric = other.evaluation.parametrisation.metric()
    gap = float(np.dot(metric, (run.evaluation.params - other.evaluation.params) ** 2))
    return math.sqrt(gap / max(other.energy, 1e-300))


def probe(problem: Evaluator, run: Run, runs: list[Run], options: Options, deadline: float) -> Run:
    """A new run's first :data:`PROBE_ITERATIONS` iterations, in stages of
    :data:`PROBE_STAGE`, ended once it heads (:func:`estimate`) above
    :data:`GIVE_UP_ABOVE` times the least energy of a run finished at the goal.

    Parameters
    ----------
    problem : Evaluator
        The problem (grid controls).
    run : Run
        The new run, updated.
    runs : list of Run
        The runs before it.
    options : Options
        The run's settings.
    deadline : float
        An :func:`nonholo.numerics.effort.seconds` reading.

    Returns
    -------
    Run
        ``run``.
    """
    best = min((r.energy for r in runs if finished_at_goal(r, options)), default=math.inf)
    done = 0
    while done < PROBE_ITERATIONS and not (run.converged or run.stuck) and effort.seconds() <= deadline:
        descend(problem, run, options, min(PROBE_STAGE, PROBE_ITERATIONS - done), deadline)
        done += PROBE_STAGE
        if estimate(run) > GIVE_UP_ABOVE * best:
            break
    return run


def continue_near_best(problem: Evaluator, runs: list[Run], options: Options, deadline: float,
                       unfinished: float = 0) -> None:
    """Continue, in rounds of :data:`PROBE_ITERATIONS`, the open run heading for the least
    energy (:func:`estimate`) while it heads below :data:`CONTINUE_WITHIN` times every run
    finished at the goal (while none is, for ``unfinished`` rounds) and the budget lasts.
    A run that comes within :data:`JOIN_DISTANCE` of one finished above the least energy
    (:func:`distance`) is not continued: it is heading for the same critical point.

    Parameters
    ----------
    problem : Evaluator
        The problem (grid controls).
    runs : list of Run
        The runs, updated.
    options : Options
        The run's settings.
    deadline : float
        An :func:`nonholo.numerics.effort.seconds` reading.
    unfinished : float, default 0
        Rounds to continue while no run has finished at the goal (``math.inf``: until one
        has, or none is open).
    """
    while effort.seconds() <= deadline:
        open_runs = [r for r in runs if not (r.converged or r.stuck or r.joined)
                     and len(r.history) <= MAX_ITERATIONS]
        if not open_runs:
            return
        heading = [estimate(r) for r in open_runs]
        k = int(np.argmin(heading))
        finished = [r for r in runs if r.evaluation.error <= options.tol and r not in open_runs]
        if finished:
            least = min(r.energy for r in finished)
            join = next((r for r in finished if r.energy > least * (1.0 + AGREE_RTOL)
                         and distance(open_runs[k], r) <= JOIN_DISTANCE), None)
            if join is not None:
                open_runs[k].joined = join.label
                continue
        if (not finished and unfinished <= 0) or (finished and heading[k] >= CONTINUE_WITHIN * least):
            return
        if not finished:
            unfinished -= 1
        descend(problem, open_runs[k], options, PROBE_ITERATIONS, deadline)


def search(problem: Evaluator, initial, options: Options, budget: float,
           ceiling: float = math.inf, final: Evaluator | None = None) -> tuple[Outcome | None, str]:
    """The least-energy certified control of ``problem`` from the labelled physical
    controls ``initial`` (see the module) within ``budget`` seconds of effort, if its
    energy is below ``ceiling``: ``(outcome, "")``, or ``(None, why)``.

    The starts are taken in turn: each is probed (:func:`probe`), then the runs heading
    near the best finished one are continued (:func:`continue_near_best`; while none has
    finished, the one heading lowest for a round), until the runs agree on the least
    energy (:func:`confirmed`) or the starts run out; then the open runs are continued so
    once more, whether or not one has finished. The
    runs at the goal (after :func:`polish`), cheapest first, are certified until one is.

    Parameters
    ----------
    problem : Evaluator
        The problem (grid controls).
    initial : iterable of tuple
        Labelled physical controls ``(label, controls)``.
    options : Options
        The run's settings.
    budget : float
        Seconds of effort.
    ceiling : float, default inf
        The energy to beat.
    final : Evaluator, optional
        The problem on the steps to certify on, if not ``problem``'s: each finalist is
        brought onto the goal there by Newton steps first.

    Returns
    -------
    outcome : Outcome or None
        The certified least-energy outcome, or ``None``.
    why : str
        Why there is none (empty if there is).
    """
    deadline = effort.seconds() + budget
    runs, skipped = [], 0
    for label, controls in initial:
        if effort.seconds() > deadline:
            break
        run = begin(problem, label, controls, options)
        if run is None:
            skipped += 1
            continue
        runs.append(probe(problem, run, runs, options, deadline))
        continue_near_best(problem, runs, options, deadline, unfinished=1)
        if confirmed(runs, options):
            break
    continue_near_best(problem, runs, options, deadline, unfinished=math.inf)
    near = sorted((r for r in runs if r.evaluation.error <= NEAR_GOAL), key=lambda r: r.energy)
    why = ""
    tried = f"{len(runs)} starts" + (f", {skipped} not admissible" if skipped else "")
    for run in near[:FINALISTS]:
        if run.energy >= ceiling:
            why = why or f"the least energy found, {run.energy:.6g}, is not below {ceiling:.6g}"
            break
        polish(problem, run, options)
        on = problem
        if final is not None and run.evaluation.error <= options.tol:
            ev = onto(final, run.evaluation, options.tol)
            if not final.admissible(ev):
                why = why or f"the iteration from '{run.label}' is not admissible on {final.steps} steps"
                continue
            run.evaluation, run.energy, on = ev, energy(ev, ev.parametrisation.metric()), final
        if run.evaluation.error > options.tol:
            why = why or f"the iteration from '{run.label}' ended {run.evaluation.error:.2g} from the goal"
            continue
        how = "converged" if run.converged else f"stopped after {run.history[-1]['iteration']} iterations"
        first = run.history[0]["energy"]
        outcome = Outcome(evaluation=run.evaluation, success=True,
                          reason=(f"least energy {run.energy:.6g} on {ENERGY_GRID} intervals, from the "
                                  f"start '{run.label}' (energy {first:.6g}; {how}; {tried})"),
                          history=run.history, iterations=len(run.history) - 1,
                          problem=on if on is not problem else None)
        outcome = certified_or_finer(outcome, on, options, ceiling)
        if outcome.success:
            return outcome, ""
        why = outcome.reason
    if not why:
        best = min((r.evaluation.error for r in runs), default=float("nan"))
        why = (f"no start's iteration ended within tol = {options.tol:g} of the goal on "
               f"{ENERGY_GRID} intervals ({tried}, the closest {best:.2g} from it)")
    return None, why


def improve(request, result: PlanResult, quick: bool = False, budget: float | None = None) -> PlanResult:
    """``result`` (a certified plan of ``request``) with its energy brought to the least
    :func:`search` finds (``objective="energy"``), or as it was with a reason saying why not;
    ``options`` records the objective.

    ``quick`` (``objective="auto"``): the search from the first :data:`QUICK_STARTS` starts
    within :data:`QUICK_EFFORT`, and the plan replaced only by a motion needing less than
    :data:`REPLACE_BELOW` of its energy, made smooth (:func:`smoothed`); otherwise it is
    returned unchanged but for ``options`` (and, where the smooth fit does not end at the
    goal below that energy, its reason saying so: grid controls, which jump at every
    interval, are no motion to execute).

    Parameters
    ----------
    request : Problem
        The run's problem.
    result : PlanResult
        Its certified plan.
    quick : bool, default False
        The quick search of ``objective="auto"``.
    budget : float, optional
        Seconds of effort (default :data:`ENERGY_EFFORT`, quick: :data:`QUICK_EFFORT`).

    Returns
    -------
    PlanResult
        The plan of least energy found, or ``result``.
    """
    objective = "auto" if quick else "energy"
    options = {**result.options, "objective": objective}
    if not result.success:
        return result if quick else replace(result, options=options)
    grid = ENERGY_GRID
    steps = -(-request.steps // grid) * grid
    problem = request.evaluator(method="nonparametric", steps=steps,
                                delta_min=smooth_clearance(result) if quick else None)
    plan_energy = plan_energy_of(result)
    initial = starts(problem, result.parametrisation)
    if quick:
        initial = itertools.islice(initial, QUICK_STARTS)
        budget = QUICK_EFFORT if budget is None else budget
        ceiling = REPLACE_BELOW * plan_energy
    else:
        budget = ENERGY_EFFORT if budget is None else budget
        ceiling = plan_energy
    final = None
    if not quick and SEARCH_COARSENING > 1:
        coarse = max(grid, -(-steps // (SEARCH_COARSENING * grid)) * grid)
        if coarse < steps:
            final, problem = problem, problem.refined(coarse)
    outcome, why = search(problem, initial, request.options, budget, ceiling, final)
    if outcome is None and final is not None:
        # nothing certified from the search on fewer steps (a motion riding a limit may
        # reach the goal only on the plan's own): the search on those
        problem = final
        outcome, why = search(problem, starts(problem, result.parametrisation), request.options, budget, ceiling)
    lowered = replace(request, method="nonparametric", grid=grid, steps=steps)
    if outcome is not None and quick:
        found = energy(outcome.evaluation, outcome.evaluation.parametrisation.metric())
        lowered, problem, outcome, why = smoothed(request, outcome, ceiling, result)
        if outcome is None:
            return replace(result, options=options,
                           reason=f"{result.reason}; kept: a motion of energy {found:.6g} was found, but {why}")
    if outcome is None:
        if quick:
            return replace(result, options=options)
        return replace(result, reason=f"{result.reason}; energy not lowered: {why}", options=options)
    if outcome.problem is not None and not quick:
        # certified on a finer grid than the search's
        problem = outcome.problem
        lowered = replace(lowered, steps=problem.steps)
    outcome = replace(outcome, history=result.history + outcome.history,
                      iterations=result.iterations + outcome.iterations,
                      reason=f"{result.reason}; then the plan's energy {plan_energy:.6g} lowered: {outcome.reason}")
    lowered = build_result(lowered, outcome, True, outcome.reason, problem)
    return replace(lowered, options={**lowered.options, "objective": objective}, route=result.route,
                   stitched=result.hops)


def smooth_clearance(result: PlanResult | None) -> float | None:
    """The clearance from ``Δ = 0`` the motions that may replace ``result`` keep
    (``objective="auto"``): :data:`KEEP_CLEARANCE` of the plan's own above ``delta_min``. A
    motion closer to ``Δ = 0`` may need less energy, but it is more sensitive to whatever
    a mechanism does not follow exactly (``|ω| ~ 1/|Δ|``), and the default returns motions
    to execute.

    Parameters
    ----------
    result : PlanResult or None
        The certified plan.

    Returns
    -------
    float or None
        The clearance (``None`` without a plan or for a mechanism without a singular set).
    """
    if result is None or result.min_delta is None:
        return None
    delta_min = result.options["delta_min"]
    return delta_min + KEEP_CLEARANCE * max(result.min_delta - delta_min, 0.0)


def smoothed(request, outcome: Outcome, ceiling: float, plan: PlanResult | None = None):
    """The least-energy grid motion of ``outcome`` made smooth: its Fourier fit of
    :data:`SMOOTH_HARMONICS` harmonics, Newton steps of least energy toward the goal, at
    most :data:`SMOOTH_ITERATIONS` SQP iterations in its coefficients (they bring it onto
    the goal where the Newton steps could not, and lower its energy), Newton steps again,
    certified (:func:`smooth_run`). Grid controls jump at every interval, which a physical
    mechanism cannot follow; the fit of a smooth extremal needs hardly more energy. Where
    the fit of a motion that rides a limit cannot be brought onto the goal (or not below
    ``ceiling``), the same iteration runs from the fit of the certified ``plan``, which
    reaches it, for up to :data:`SMOOTH_PLAN_ITERATIONS` iterations: it descends to a smooth
    critical point near the plan, which replaces the plan where it needs less than
    :data:`REFIT_BELOW` of its energy.

    Parameters
    ----------
    request : Problem
        The run's problem.
    outcome : Outcome
        The certified grid motion.
    ceiling : float
        The energy the smooth fit of ``outcome`` must stay below (that from the plan: the
        plan's).
    plan : PlanResult, optional
        The certified plan: the smooth motion keeps its clearance from ``Δ = 0``
        (:func:`smooth_clearance`) and is integrated on at least its steps.

    Returns
    -------
    request : Problem
        The smooth motion's problem (method ``"parametric"``).
    problem : Evaluator
        Its evaluator.
    outcome : Outcome or None
        The certified smooth motion, or ``None`` if it does not end at the goal below
        ``ceiling`` or fails its certificate.
    why : str
        Why there is none (empty if there is).
    """
    K = SMOOTH_HARMONICS
    steps = max(request.steps, 4 * K, 0 if plan is None else plan.steps)
    smooth = replace(request, method="parametric", harmonics=K, steps=steps)
    problem = smooth.evaluator(method="parametric", steps=steps, delta_min=smooth_clearance(plan))
    found, why = smooth_run(problem, "the motion's fit", outcome.evaluation.controls, SMOOTH_ITERATIONS, ceiling,
                            request.options)
    if found is None and plan is not None:
        found, why_plan = smooth_run(problem, "the plan's fit", plan.parametrisation, SMOOTH_PLAN_ITERATIONS,
                                     REFIT_BELOW * plan_energy_of(plan), request.options)
        why = "" if found is not None else f"{why}; {why_plan}"
    if found is None:
        return smooth, problem, None, why
    problem = found.problem
    found = replace(found, reason=f"{outcome.reason}; made smooth: {found.reason}",
                    history=outcome.history + found.history, iterations=outcome.iterations + found.iterations)
    return replace(smooth, steps=problem.steps), problem, found, ""


def smooth_run(problem: Evaluator, label: str, controls: Controls, iterations: int, ceiling: float,
               options: Options) -> tuple[Outcome | None, str]:
    """The Fourier fit of ``controls`` in ``problem``'s harmonics, Newton steps of least
    energy toward the goal, at most ``iterations`` SQP iterations, Newton steps again,
    certified — on twice the integrator steps where the certificate finds the planner's
    grid too coarse for the motion.

    Parameters
    ----------
    problem : Evaluator
        The smooth problem (method ``"parametric"``).
    label : str
        What is fitted (for the reasons).
    controls : Controls
        The physical controls fitted.
    iterations : int
        SQP iterations at most.
    ceiling : float
        The energy the motion must stay below.
    options : Options
        The run's settings.

    Returns
    -------
    outcome : Outcome or None
        The certified smooth motion (its ``problem`` the evaluator it was certified on),
        or ``None``.
    why : str
        Why there is none (empty if there is).
    """
    K = SMOOTH_HARMONICS
    fit = Fourier.fit(controls, problem.T, K, problem.mechanism.n_inputs)
    ev = problem.evaluate(fit)
    if not problem.admissible(ev):
        return None, f"{label} of {K} harmonics is not admissible"
    metric = fit.metric()
    ev = newton_steps(problem, ev, metric, options.tol, RESTORE_STEPS + 2)
    E = energy(ev, metric)
    run = Run(label, ev, E, history=[record(0, ev, 0.0, "energy", 0, energy=E, start=label)])
    descend(problem, run, options, iterations, math.inf)
    polish(problem, run, options)
    if run.evaluation.error > options.tol:
        return None, (f"{label} of {K} harmonics ended {run.evaluation.error:.2g} from the goal "
                      f"after {len(run.history) - 1} iterations")
    if run.energy >= ceiling:
        return None, f"{label} of {K} harmonics needs {run.energy:.6g}, not below {ceiling:.6g}"
    found = Outcome(evaluation=run.evaluation, success=True,
                    reason=f"{label} of {K} harmonics, energy {run.energy:.6g}",
                    history=run.history, iterations=len(run.history) - 1, problem=problem)
    certificate = certified_or_finer(found, problem, options, ceiling)
    return (certificate, "") if certificate.success else (None, certificate.reason)


def certified_or_finer(found: Outcome, problem: Evaluator, options: Options, ceiling: float) -> Outcome:
    """``found`` certified (:func:`~nonholo.planning.certification.certified`) — or, where
    its certificate fails, its controls on twice the integrator steps, brought back onto
    the goal there by Newton steps of least energy and certified there (its ``problem``
    then the finer evaluator): the motion may be faster than the planner's grid resolves,
    or so sensitive that the replay's corrections cannot close the gap between the grids.

    Parameters
    ----------
    found : Outcome
        A success at the goal on ``problem``'s grid.
    problem : Evaluator
        Its problem.
    options : Options
        The run's settings.
    ceiling : float
        The energy the motion on the finer grid must stay below.

    Returns
    -------
    Outcome
        The certified motion, or the first certificate's failure.
    """
    certificate = certified(found, problem, options)
    if certificate.success:
        return certificate
    finer = problem.refined(2 * problem.steps)
    ev = onto(finer, found.evaluation, options.tol)
    if finer.admissible(ev) and ev.error <= options.tol and energy(ev, ev.parametrisation.metric()) < ceiling:
        again = certified(replace(found, evaluation=ev, problem=finer), finer, options)
        if again.success:
            return again
    return certificate


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


#: Panels of :func:`controls_energy`'s quadrature on ``[0, T]`` at least.
ENERGY_PANELS = 64


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
    x, w = np.polynomial.legendre.leggauss(8)
    bps = [] if breakpoints is None else np.asarray(breakpoints, dtype=float)
    b = np.unique(np.concatenate([np.linspace(0.0, T, ENERGY_PANELS + 1), bps]))
    b = b[(b >= 0.0) & (b <= T)]
    a, c = b[:-1], b[1:]
    t = (0.5 * (a + c))[:, None] + (0.5 * (c - a))[:, None] * x[None, :]
    u = np.asarray(controls(t.ravel())).reshape(len(a), len(x), -1)
    return float(np.sum(0.5 * (c - a)[:, None] * w[None, :] * np.sum(u ** 2, axis=2)))
