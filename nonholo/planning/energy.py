"""``objective="energy"``: a plan's goal kept, its energy ``∫_0^T |u|² dt`` brought to the least.

The least-energy motion of a driftless system ``ẋ = G(x) u`` between two states is a
sub-Riemannian geodesic. It is sought among piecewise-constant physical inputs on
:data:`ENERGY_GRID` equal intervals (parameters ``λ``, the interval values) by Gauss–Newton
sequential quadratic programming (:func:`descend`):

    ``λ⁺ = M⁻¹Jᵀ (J M⁻¹ Jᵀ)⁻¹ (Jλ − l_T)``,

the least-energy point of the linearised endpoint condition ``l_T + J(λ⁺ − λ) = 0``
(``∫|u|² = λᵀMλ``, ``M = diag(h_j)``; ``l_T`` the stacked terminal error and ``J =
∂s_T/∂λ`` from the variational system, as in the planner). A fixed point satisfies ``Mλ =
Jᵀν`` and ``l_T = 0``: the first-order conditions of the least energy with the endpoint
fixed (the discrete Pontryagin condition ``u = Gᵀp``). The step ``λ⁺ − λ`` is damped by a
backtracking line search on the merit ``E + μ|l_T|`` (``μ`` above the multiplier ``|ν|``)
and shortened until the trajectory is admissible — ``|Δ| ≥ delta_min``, the legs inside
their stroke — so every iterate is; the iteration need not start at the goal.

Such an iteration finds *a* critical point near its start; the least one is looked for
from several starts (:func:`starts`): the certified plan's inputs, then the drift toward
the goal plus loops of a few sizes in either sense (the motions that reach the bracket
directions at the least cost), then seeded random Fourier inputs. Each start is iterated
for :data:`PROBE_ITERATIONS`; the cheapest :data:`FINALISTS` of those near the goal are
iterated to convergence, and the least-energy one that is certified
(:mod:`nonholo.planning.certification`) is the result. Everything is budgeted in effort
(:mod:`nonholo.numerics.effort`, :data:`ENERGY_EFFORT`), not in wall time, so the same call
gives the same plan on any machine under any load.

The result's controls are those grid controls (method ``"nonparametric"``) of the
physical inputs; if no start ends at a certified control at least as cheap as the plan's,
the plan is returned as it was, its reason saying why.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from scipy.linalg import cho_factor, cho_solve

from ..controls.parametrisations import Controls, Fourier, PiecewiseConstant
from ..io.result import PlanResult
from ..numerics import effort
from .certification import certified
from ..model.limits import BARRIER_CLEARANCE
from .core import (
    Evaluation,
    Evaluator,
    Options,
    Outcome,
    build_result,
    node_gradient,
    record,
    spatial_gradient_delta,
)

#: Intervals of the piecewise-constant controls the energy is lowered over (the plan's
#: integrator steps are rounded up to a multiple of it).
ENERGY_GRID = 100
#: SQP iterations of one start at most (probe and final iterations together).
MAX_ITERATIONS = 80
#: SQP iterations of every start before the finalists are chosen.
PROBE_ITERATIONS = 12
#: Starts iterated to convergence: the cheapest near the goal after their probe.
FINALISTS = 3
#: A probe is near the goal when its terminal error is below this (in the error's units).
NEAR_GOAL = 1e-3
#: Seconds of effort (:mod:`nonholo.numerics.effort`) the stage may take.
ENERGY_EFFORT = 1.0
#: The iteration has converged when an accepted step lowers the energy by less than this
#: fraction (and the endpoint is within ``tol``).
ENERGY_RTOL = 1e-9
#: ... or when the energy's gradient is this close to the row space of ``J`` (relative, in
#: the metric ``M⁻¹``: the first-order conditions).
KKT_RTOL = 1e-8
#: A quasi-Newton step longer than this many Gauss–Newton steps (metric M), or one the
#: line search halved more than :data:`RESET_HALVINGS` times, resets the Hessian to ``2M``.
STEP_GROWTH = 4.0
RESET_HALVINGS = 3
#: Step halvings of the line search at most.
MAX_HALVINGS = 12
#: The barrier on the clearance from ``Δ = 0`` acts where ``sgnΔ`` is below this.
BARRIER_DELTA = 0.1
#: The barrier's weight ``ε`` relative to the energy (:class:`Objective`).
BARRIER_WEIGHT = 1e-3
#: Loop sizes of the starts, relative to the loop that encloses the goal's offset.
LOOP_SCALES = (1.0, 0.5, 2.0)
#: Frequencies (in ``2π/T``) of the first two inputs of the loops of the starts.
LOOP_FREQUENCIES = ((1, 1), (1, 2), (2, 1))
#: Seeded random Fourier starts after the deterministic ones.
RANDOM_STARTS = 4
RANDOM_SEED = 20240226


def energy(ev: Evaluation, metric: np.ndarray) -> float:
    """``∫|u|² dt = Σ metric_k λ_k²`` of grid controls."""
    return float(np.dot(metric, ev.params ** 2))


def barrier_terms(problem: Evaluator, ev: Evaluation) -> tuple[float, np.ndarray | None]:
    """The barrier ``Φ = Σ_{n ≥ 1} h ψ(r_n)`` of ``ev``'s nodes on the clearance from
    ``Δ = 0`` (``r = (sgnΔ − delta_min)/(d₀ − delta_min)``, ``d₀`` = :data:`BARRIER_DELTA`)
    and on the legs' clearances from their stroke (``r = c/c₀``, ``c₀`` =
    :data:`~nonholo.model.limits.BARRIER_CLEARANCE`), ``ψ(r) = r − 1 − log r`` below 1 and 0
    above (zero with its slope at ``r = 1``); and ``a`` (``(N+1, d)``), the derivative of
    ``Φ`` by the nodes' state variations (``None`` where no node is within reach)."""
    mech, h = problem.mechanism, problem.h
    a, total = None, 0.0
    if problem.singular.exists:
        d = problem.sign * mech.delta_samples(ev.R, ev.q)
        span = BARRIER_DELTA - problem.delta_min
        r = (d - problem.delta_min) / span
        near = r < 1.0
        near[0] = False
        if near.any():
            rn = np.maximum(r[near], 1e-300)
            total += float(h * np.sum(rn - 1.0 - np.log(rn)))
            grad = spatial_gradient_delta(mech, ev.R[near], q=ev.q[near])
            a = np.zeros((len(ev.R), mech.n_rates))
            a[near] = (h * problem.sign * (1.0 - 1.0 / rn) / span)[:, None] * grad
    if problem.leg_limits is not None:
        terms = problem.leg_limits.clearance_terms(mech, ev.R, BARRIER_CLEARANCE)
        if terms is not None:
            nodes, c, rows = terms
            keep = nodes > 0
            rn = np.maximum(c[keep] / BARRIER_CLEARANCE, 1e-300)
            total += float(h * np.sum(rn - 1.0 - np.log(rn)))
            a = np.zeros((len(ev.R), mech.n_rates)) if a is None else a
            np.add.at(a, nodes[keep], (h * (1.0 - 1.0 / rn) / BARRIER_CLEARANCE)[:, None] * rows[keep])
    return total, a


class Objective:
    """What a run lowers: the energy plus ``τ`` times the barrier (:func:`barrier_terms`),
    ``τ = ε E/T`` with ``ε`` = :data:`BARRIER_WEIGHT` and ``E`` the run's energy when the
    iteration set it (the barrier costs at most about ``εE`` of energy)."""

    def __init__(self, problem: Evaluator, metric: np.ndarray):
        self.problem, self.metric = problem, metric
        self.constrained = problem.singular.exists or problem.leg_limits is not None
        self.tau = 0.0

    def near(self, ev: Evaluation) -> bool:
        """Whether the barrier may act on the next evaluations (they then keep what its
        gradient needs)."""
        if not self.constrained:
            return False
        problem = self.problem
        near_delta = (problem.singular.exists and ev.min_delta is not None
                      and ev.min_delta < 2.0 * BARRIER_DELTA)
        near_legs = ev.min_clearance is not None and ev.min_clearance < 2.0 * BARRIER_CLEARANCE
        return near_delta or near_legs

    def value(self, ev: Evaluation) -> float:
        E = energy(ev, self.metric)
        if not self.constrained or self.tau == 0.0:
            return E
        return E + self.tau * barrier_terms(self.problem, ev)[0]

    def gradients(self, ev: Evaluation) -> tuple[np.ndarray, np.ndarray]:
        """``(∇E, ∇Φ)`` at ``ev`` (a full evaluation where :meth:`near`)."""
        gE = 2.0 * self.metric * ev.params
        if not self.constrained:
            return gE, np.zeros_like(gE)
        _, a = barrier_terms(self.problem, ev)
        if a is None or ev.Z is None:
            return gE, np.zeros_like(gE)
        return gE, node_gradient(self.problem, ev, a)


@dataclass(eq=False)
class Run:
    """One start's SQP iteration: its label, last evaluation, energy, whether it
    converged (or can make no further step), its history, the merit's weight ``mu``, the
    quasi-Newton Hessian ``B`` of the Lagrangian and the barrier's weight ``tau`` (carried
    from round to round), and the first-order residual ``kkt`` of its last iterate."""

    label: str
    evaluation: Evaluation
    energy: float
    converged: bool = False
    stuck: bool = False
    history: list = field(default_factory=list)
    mu: float = 0.0
    B: np.ndarray | None = None
    tau: float | None = None
    kkt: float = float("inf")


def qp_step(B: np.ndarray, g: np.ndarray, J: np.ndarray, l: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The step ``d`` of the quadratic model ``min gᵀd + ½dᵀBd`` subject to ``l + Jd = 0``
    and its multiplier ``ν`` (``Bd + g = Jᵀν``); ``B`` positive definite, a matrix or the
    vector of a diagonal one."""
    if B.ndim == 1:
        Hg, HJ = g / B, J.T / B[:, None]
    else:
        factor = cho_factor(B)
        Hg, HJ = cho_solve(factor, g), cho_solve(factor, J.T)
    nu = np.linalg.lstsq(J @ HJ, J @ Hg - l, rcond=None)[0]
    return HJ @ nu - Hg, nu


def line_search(problem: Evaluator, ev: Evaluation, d: np.ndarray, objective: Objective, mu: float,
                slope: float) -> tuple[Evaluation | None, float, int]:
    """The step along ``d`` from ``ev`` the merit ``F + μ|l_T|`` accepts (Armijo; ``F`` the
    :class:`Objective`), halved until the trajectory is admissible and the merit drops; a
    full step the merit rejects is first retried with a second-order correction (the
    least-energy ``c`` with ``J c = −l_T`` at the trial point: the merit's non-smooth term
    would otherwise reject the full steps of the fast local convergence). Returns
    ``(evaluation, α, rejected)``, the evaluation ``None`` when :data:`MAX_HALVINGS`
    halvings do not do."""
    merit0 = objective.value(ev) + mu * ev.error
    full = objective.near(ev)
    alpha, rejected = 1.0, 0
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


def descend(problem: Evaluator, run: Run, options: Options, iterations: int, deadline: float) -> Run:
    """At most ``iterations`` more SQP iterations of ``run`` (see the module), stopping at
    convergence, at a step the line search cannot accept, or past ``deadline`` (an
    :func:`nonholo.numerics.effort.seconds` reading)."""
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
        if objective.near(ev) and ev.Z is None:
            ev = problem.evaluate(ev.params, full=True)
        if run.tau is None:
            run.tau = BARRIER_WEIGHT * max(energy(ev, metric), 1e-12) / problem.T
        objective.tau = run.tau
        gE, gB = objective.gradients(ev)
        g = gE + run.tau * gB
        d, nu = qp_step(run.B, g, ev.J, ev.l)
        if run.B.ndim == 2:
            gn = qp_step(gn_hessian, g, ev.J, ev.l)
            if np.dot(metric * d, d) > STEP_GROWTH ** 2 * np.dot(metric * gn[0], gn[0]):
                run.B = gn_hessian
                d, nu = gn
        run.mu = max(run.mu, 2.0 * float(np.linalg.norm(nu)))
        E0 = energy(ev, metric)
        slope = float(np.dot(g, d)) - run.mu * ev.error
        accepted, alpha, rejected = line_search(problem, ev, d, objective, run.mu, slope)
        if accepted is None:
            run.stuck = True
            break
        if objective.near(accepted) and accepted.Z is None:
            accepted = problem.evaluate(accepted.params, full=True)
        gE1, gB1 = objective.gradients(accepted)
        g1 = gE1 + run.tau * gB1
        if rejected > RESET_HALVINGS:
            run.B = gn_hessian
        else:
            # damped BFGS update of the Lagrangian's Hessian (Powell): s, y of ∇(F − νᵀs_T)
            step = accepted.params - ev.params
            y = (g1 - accepted.J.T @ nu) - (g - ev.J.T @ nu)
            B = np.diag(run.B) if run.B.ndim == 1 else run.B
            Bs = B @ step
            sBs, sy = float(step @ Bs), float(step @ y)
            if sBs > 0.0:
                if sy < 0.2 * sBs:
                    theta = 0.8 * sBs / (sBs - sy)
                    y = theta * y + (1.0 - theta) * Bs
                    sy = float(step @ y)
                run.B = B + np.outer(y, y) / sy - np.outer(Bs, Bs) / sBs
        E1 = energy(accepted, metric)
        ev = accepted
        # first-order conditions: the gradient in the row space of J (in the metric M⁻¹)
        JW = ev.J / metric
        lam = np.linalg.lstsq(JW @ ev.J.T, JW @ g1, rcond=None)[0]
        resid = g1 - ev.J.T @ lam
        run.kkt = float(np.sqrt(np.dot(resid / metric, resid) / max(np.dot(g1 / metric, g1), 1e-300)))
        run.history.append(record(it, ev, alpha, "energy", rejected, energy=E1, start=run.label))
        if ev.error <= options.tol and (run.kkt <= KKT_RTOL or abs(E0 - E1) <= ENERGY_RTOL * E0):
            run.converged = True
    run.evaluation, run.energy = ev, energy(ev, metric)
    return run


def begin(problem: Evaluator, label: str, controls: Controls) -> Run | None:
    """A run from the physical ``controls`` projected on the grid, or ``None`` where that
    projection's motion is not admissible."""
    grid = PiecewiseConstant.fit(controls, problem.T, ENERGY_GRID, problem.mechanism.n_inputs)
    ev = problem.evaluate(grid)
    if not problem.admissible(ev):
        return None
    E = energy(ev, grid.metric())
    return Run(label, ev, E, history=[record(0, ev, 0.0, "energy", 0, energy=E, start=label)])


def correction(ev: Evaluation, metric: np.ndarray) -> np.ndarray:
    """The least-energy change ``c`` of the parameters with ``J c = −l_T`` (a Newton step
    toward the goal)."""
    JW = ev.J / metric
    return -JW.T @ np.linalg.lstsq(JW @ ev.J.T, ev.l, rcond=None)[0]


def estimate(run: Run) -> float:
    """The energy ``run`` is heading for: its parameters' after a Newton step to the goal
    (its energy itself when at the goal)."""
    ev = run.evaluation
    metric = ev.parametrisation.metric()
    return float(np.dot(metric, (ev.params + correction(ev, metric)) ** 2))


def polish(problem: Evaluator, run: Run, options: Options, steps: int = 4) -> Run:
    """Newton steps of least energy toward the goal (:func:`correction`) while they lower
    ``|l_T|`` and it is above ``tol``: an iteration stopped by its budget close to the goal
    ends on it."""
    ev = run.evaluation
    metric = ev.parametrisation.metric()
    for _ in range(steps):
        if ev.error <= options.tol:
            break
        trial = problem.evaluate(ev.params + correction(ev, metric))
        if not (problem.admissible(trial) and trial.error < ev.error):
            break
        ev = trial
        run.history.append(record(run.history[-1]["iteration"] + 1, ev, 1.0, "energy", 0,
                                  energy=energy(ev, metric), start=run.label))
    run.evaluation, run.energy = ev, energy(ev, metric)
    return run


def loop_starts(problem: Evaluator):
    """Labelled physical initial controls of the search: the drift ``ū = G(x₀)^# δ/T``
    toward the goal (``δ`` the offset of the goal from the start, a least-squares fit of
    the field at the start) plus loops ``u_i = A sin(k_i ωt ± iπ/2)`` (``ω = 2π/T``) of
    the frequencies :data:`LOOP_FREQUENCIES` (equal ones reach the first brackets, a 1:2
    pair the second), in either sense, of the sizes :data:`LOOP_SCALES` times the one whose
    enclosed area matches ``|δ|``; then :data:`RANDOM_STARTS` seeded random Fourier inputs
    of that size around the drift."""
    mech, T = problem.mechanism, problem.T
    m = mech.n_inputs
    offset = mech.space.offset(problem.R0, problem.q0, problem.Rd, problem.qd)
    drift = np.linalg.lstsq(mech.G(problem.R0, problem.q0), offset, rcond=None)[0] / T
    omega = 2.0 * np.pi / T
    size = omega * np.sqrt(max(float(np.linalg.norm(offset)), 1e-2) / np.pi)
    for scale in LOOP_SCALES:
        for pair in LOOP_FREQUENCIES:
            k = np.resize(np.asarray(pair, dtype=float), m)
            for sense in (1.0, -1.0):
                shift = 0.5 * np.pi * sense * np.arange(m)

                def loop(t, A=scale * size, k=k, shift=shift):
                    t = np.asarray(t, dtype=float)
                    return drift + A * np.sin(omega * k * t[..., None] + shift)

                yield f"loop {scale:g} {pair[0]}:{pair[1]}{'+' if sense > 0 else '-'}", loop
    rng = np.random.default_rng(RANDOM_SEED)
    for j in range(RANDOM_STARTS):
        K = 1 + j % 3
        c = rng.standard_normal((m, 2 * K + 1))
        c *= size / np.sqrt(np.sum(c[:, 0] ** 2) + 0.5 * np.sum(c[:, 1:] ** 2))
        c[:, 0] += drift
        yield f"random {j + 1}", Fourier(T, c)


def starts(problem: Evaluator, plan: Controls | None):
    """The starts of the search: the certified plan's physical inputs (when given), then
    :func:`loop_starts`."""
    if plan is not None:
        yield "plan", plan
    yield from loop_starts(problem)


def search(problem: Evaluator, initial, options: Options, budget: float) -> tuple[Outcome | None, str]:
    """The least-energy certified control of ``problem`` from the labelled physical
    controls ``initial`` (see the module) within ``budget`` seconds of effort:
    ``(outcome, "")``, or ``(None, why)``.

    Every start is iterated :data:`PROBE_ITERATIONS` times; then, in rounds of as many, the
    unfinished run heading for the least energy (:func:`estimate`), while it heads below
    every finished run at the goal and the budget lasts. The runs at the goal (after
    :func:`polish`), cheapest first, are certified until one is."""
    deadline = effort.seconds() + budget
    runs, skipped = [], 0
    for label, controls in initial:
        if effort.seconds() > deadline:
            break
        run = begin(problem, label, controls)
        if run is None:
            skipped += 1
            continue
        runs.append(descend(problem, run, options, PROBE_ITERATIONS, deadline))
    while effort.seconds() <= deadline:
        open_runs = [r for r in runs if not (r.converged or r.stuck) and len(r.history) <= MAX_ITERATIONS]
        if not open_runs:
            break
        heading = [estimate(r) for r in open_runs]
        k = int(np.argmin(heading))
        finished = [r.energy for r in runs if r.evaluation.error <= options.tol and r not in open_runs]
        if finished and heading[k] >= min(finished):
            break
        descend(problem, open_runs[k], options, PROBE_ITERATIONS, deadline)
    near = sorted((r for r in runs if r.evaluation.error <= NEAR_GOAL), key=lambda r: r.energy)
    why = ""
    tried = f"{len(runs)} starts" + (f", {skipped} not admissible" if skipped else "")
    for run in near[:FINALISTS]:
        polish(problem, run, options)
        if run.evaluation.error > options.tol:
            why = why or f"the iteration from '{run.label}' ended {run.evaluation.error:.2g} from the goal"
            continue
        how = "converged" if run.converged else f"stopped after {run.history[-1]['iteration']} iterations"
        first = run.history[0]["energy"]
        outcome = Outcome(evaluation=run.evaluation, success=True,
                          reason=(f"least energy {run.energy:.6g} on {ENERGY_GRID} intervals, from the "
                                  f"start '{run.label}' (energy {first:.6g}; {how}; {tried})"),
                          history=run.history, iterations=len(run.history) - 1)
        outcome = certified(outcome, problem, options)
        if outcome.success:
            return outcome, ""
        why = outcome.reason
    if not why:
        best = min((r.evaluation.error for r in runs), default=float("nan"))
        why = (f"no start's iteration ended within tol = {options.tol:g} of the goal on "
               f"{ENERGY_GRID} intervals ({tried}, the closest {best:.2g} from it)")
    return None, why


def improve(request, result: PlanResult, budget: float | None = None) -> PlanResult:
    """``result`` (a certified plan of ``request``) with its energy brought to the least
    :func:`search` finds, or as it was with a reason saying why not; ``options`` records
    the objective."""
    options = {**result.options, "objective": "energy"}
    if not result.success:
        return replace(result, options=options)
    grid = ENERGY_GRID
    steps = -(-result.steps // grid) * grid
    problem = request.evaluator(method="nonparametric", steps=steps)
    budget = ENERGY_EFFORT if budget is None else budget
    outcome, why = search(problem, starts(problem, result.parametrisation), request.options, budget)
    if outcome is None:
        return replace(result, reason=f"{result.reason}; energy not lowered: {why}", options=options)
    plan_energy = plan_energy_of(result)
    final = energy(outcome.evaluation, outcome.evaluation.parametrisation.metric())
    if final > plan_energy:
        return replace(result, reason=f"{result.reason}; energy not lowered: the least found on "
                                      f"{grid} intervals, {final:.6g}, is above the plan's {plan_energy:.6g}",
                       options=options)
    outcome = replace(outcome, history=result.history + outcome.history,
                      iterations=result.iterations + outcome.iterations,
                      reason=f"{result.reason}; {outcome.reason}")
    lowered = build_result(replace(request, method="nonparametric", grid=grid, steps=steps), outcome, True,
                           outcome.reason, problem)
    return replace(lowered, options={**lowered.options, "objective": "energy"}, route=result.route,
                   stitched=result.hops)


def plan_energy_of(result: PlanResult, samples: int = 4001) -> float:
    """``∫|u|² dt`` of a plan's physical controls (Simpson's rule between breakpoints)."""
    from scipy.integrate import simpson

    T = result.T
    bps = result.breakpoints if result.breakpoints is not None else np.array([0.0, T])
    total = 0.0
    for a, b in zip(bps[:-1], bps[1:]):
        n = max(5, int(samples * (b - a) / T) | 1)
        t = np.linspace(a, b, n)
        eps = 1e-12 * T
        t[0], t[-1] = a + eps, b - eps
        total += simpson(np.sum(result.controls(t) ** 2, axis=1), x=t)
    return float(total)
