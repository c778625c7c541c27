"""``objective="energy"``: a plan's goal kept, its energy ``∫_0^T |u|² dt`` lowered.

After a certified plan (local or global), its physical inputs ``u`` are projected on
piecewise-constant controls on :data:`ENERGY_GRID` equal intervals (interval means) and
moved toward the least energy among the controls that end at the goal, by Gauss–Newton
sequential quadratic programming in the parameters ``λ`` (the interval values):

    ``λ⁺ = M⁻¹Jᵀ (J M⁻¹ Jᵀ)⁻¹ (Jλ − l_T)``,

the least-energy point of the linearised endpoint condition ``l_T + J(λ⁺ − λ) = 0``
(``∫|u|² = λᵀMλ``, ``M = diag(h_j)``; ``J = ∂s_T/∂λ`` from the variational system, as in
the planner). A fixed point satisfies ``Mλ = Jᵀν`` and ``l_T = 0``: the first-order
conditions of the least energy with the endpoint fixed. The step ``λ⁺ − λ`` is damped by
a backtracking line search on the merit ``E + μ|l_T|`` (``μ`` above the multiplier
``|ν|``) and shortened until the trajectory is admissible — ``|Δ| ≥ delta_min``, the legs
inside their stroke — so every iterate is. The iteration stops when the energy no
longer drops by :data:`ENERGY_RTOL` and ``|l_T|`` is below the planner's ``tol`` (then the
result is certified like any plan: :mod:`nonholo.planning.certification`), or after
:data:`MAX_ITERATIONS` / :data:`ENERGY_TIME`.

The result's controls are those grid controls (method ``"nonparametric"``) of the
physical inputs; if the stage cannot end at a certified control at least as cheap as
the plan's, the plan is returned as it was, its reason saying why.
"""
from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from ..controls.parametrisations import PiecewiseConstant
from ..io.result import PlanResult
from .certification import certified
from .core import Evaluation, Options, Outcome, Evaluator, build_result, record

#: Intervals of the piecewise-constant controls the energy is lowered over (the plan's
#: integrator steps are rounded up to a multiple of it).
ENERGY_GRID = 100
#: SQP iterations at most.
MAX_ITERATIONS = 60
#: Wall time of the stage at most (s).
ENERGY_TIME = 0.5
#: The iteration has converged when an accepted step lowers the energy by less than this
#: fraction (and the endpoint is within ``tol``).
ENERGY_RTOL = 1e-9
#: Step halvings of the line search at most.
MAX_HALVINGS = 12


def supports(mechanism) -> bool:
    """Whether the least-energy stage handles ``mechanism``: a state on SO(3) alone."""
    return not mechanism.space.k


def energy(ev: Evaluation, metric: np.ndarray) -> float:
    """``∫|u|² dt = Σ metric_k λ_k²`` of grid controls."""
    return float(np.dot(metric, ev.params ** 2))


def sqp_target(ev: Evaluation, inverse_metric: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The least-energy ``λ⁺`` on the linearised endpoint condition, and the multiplier
    ``ν`` (``Mλ⁺ = Jᵀν``)."""
    J = ev.J
    JW = J * inverse_metric
    rhs = J @ ev.params - ev.l
    nu = np.linalg.solve(JW @ J.T, rhs)
    return JW.T @ nu, nu


def lower(problem: Evaluator, physical, options: Options, grid: int | None = None,
          deadline: float | None = None) -> tuple[Outcome | None, str]:
    """Lower the energy of the physical controls ``physical`` (any control of ``problem``'s
    mechanism that reaches its goal) on ``grid`` intervals (see the module).

    Returns ``(outcome, note)``: a certified success with the cheaper grid controls, or
    ``None`` with the reason the stage gave up.
    """
    started = time.perf_counter()
    deadline = started + ENERGY_TIME if deadline is None else deadline
    grid = ENERGY_GRID if grid is None else grid
    controls = PiecewiseConstant.fit(physical, problem.T, grid, problem.mechanism.n_inputs)
    metric = controls.metric()
    inverse = 1.0 / metric
    ev = problem.evaluate(controls)
    if not problem.admissible(ev):
        return None, f"its projection on {grid} intervals is not admissible: {problem.why_not(ev)}"
    start_energy = energy(ev, metric)
    history = [record(0, ev, 0.0, "energy", 0, energy=start_energy)]
    mu = 0.0
    converged = False
    for it in range(1, MAX_ITERATIONS + 1):
        if time.perf_counter() > deadline:
            break
        target, nu = sqp_target(ev, inverse)
        mu = max(mu, 2.0 * float(np.linalg.norm(nu)))
        E0 = energy(ev, metric)
        merit0 = E0 + mu * ev.error
        d = target - ev.params
        # the merit's derivative along d: the energy's, and −|l_T| (d zeroes the linearised l_T)
        slope = 2.0 * float(np.dot(metric * ev.params, d)) - mu * ev.error
        alpha, rejected, accepted = 1.0, 0, None
        for _ in range(MAX_HALVINGS):
            trial = problem.evaluate(ev.params + alpha * d)
            if problem.admissible(trial):
                merit = energy(trial, metric) + mu * trial.error
                if merit <= merit0 + 1e-4 * alpha * min(slope, 0.0):
                    accepted = trial
                    break
            alpha *= 0.5
            rejected += 1
        if accepted is None:
            break
        E1 = energy(accepted, metric)
        ev = accepted
        history.append(record(it, ev, alpha, "energy", rejected, energy=E1))
        if ev.error <= options.tol and abs(E0 - E1) <= ENERGY_RTOL * E0:
            converged = True
            break
    if ev.error > options.tol:
        return None, (f"the controls projected on {grid} intervals end {history[0]['error']:.2g} rad from "
                      f"the goal, and the iteration stopped {ev.error:.2g} rad from it (tol = {options.tol:g})")
    final_energy = energy(ev, metric)
    if final_energy > start_energy:
        return None, "the energy iteration did not lower the energy"
    how = "converged" if converged else f"stopped after {len(history) - 1} iterations"
    outcome = Outcome(evaluation=ev, success=True,
                      reason=f"energy lowered on {grid} intervals from {start_energy:.6g} to "
                             f"{final_energy:.6g} ({how})",
                      history=history, iterations=len(history) - 1)
    outcome = certified(outcome, problem, options)
    if not outcome.success:
        return None, outcome.reason
    return outcome, ""


def improve(request, result: PlanResult) -> PlanResult:
    """``result`` (a certified plan of ``request``) with its energy lowered by :func:`lower`,
    or as it was with a reason saying why not; ``options`` records the objective."""
    options = {**result.options, "objective": "energy"}
    if not result.success:
        return replace(result, options=options)
    mech = request.mechanism
    grid = ENERGY_GRID
    steps = -(-result.steps // grid) * grid
    problem = Evaluator(request.R0, request.Rd, request.T, mech, "nonparametric", steps,
                      request.options.delta_min, frame=False, leg_limits=request.leg_limits)
    outcome, why = lower(problem, result.parametrisation, request.options, grid)
    if outcome is None:
        return replace(result, reason=f"{result.reason}; energy not lowered: {why}", options=options)
    outcome = replace(outcome, history=result.history + outcome.history,
                      iterations=result.iterations + outcome.iterations,
                      reason=f"{result.reason}; {outcome.reason}")
    lowered = build_result(replace(request, method="nonparametric", grid=grid, steps=steps), outcome, True,
                           outcome.reason, problem)
    return replace(lowered, options={**lowered.options, "objective": "energy"}, route=result.route,
                   stitched=result.hops)
