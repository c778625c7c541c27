"""The least-energy stage: a plan's goal kept, its energy ``∫_0^T |u|² dt`` brought to the least.

A motion of least energy is, away from a limit, a normal extremal: the stage first shoots
on the extremals' initial costate from the projections of the plan and of the search's
starts (:mod:`nonholo.planning.extremals`, budget :data:`EXTREMAL_EFFORT`), and takes the
least one two starts agree on, landed on :data:`~nonholo.planning.energy_search.ENERGY_GRID`
equal intervals and certified. Where none is confirmed — a motion that rides a limit (the
singular set ``Δ = 0``, the legs' stroke, the coordinates' bounds) is no extremal — it
searches among piecewise-constant physical inputs on those intervals with the optimiser of
:mod:`nonholo.planning.energy_optimiser` (SQP with damped BFGS updates, the endpoint fixed,
the objective of :mod:`nonholo.planning.energy_objective`) run from several starts by the
search of :mod:`nonholo.planning.energy_search`. The search integrates with a fraction of
the plan's steps (:data:`SEARCH_COARSENING`); the least-energy run at the goal, brought
onto it on the plan's own steps, that is certified (:mod:`nonholo.planning.correction`) is
the result (where none is, the search is run again on the plan's own steps: a motion
riding a limit may reach the goal only there). Everything is budgeted in effort
(:mod:`nonholo.numerics.effort`, :data:`ENERGY_EFFORT`), not in wall time, so the same call
gives the same plan on any machine under any load.

The result's controls are those grid controls (method ``"nonparametric"``) of the physical
inputs; if no start ends at a certified control at least as cheap as the plan's, the plan
is returned as it was, its reason saying why. :func:`improve` runs the stage for
``objective="energy"`` and, quickly, for ``objective="auto"``, which keeps the plan unless
the extremal through it needs far less energy (or, for a wasteful plan, a motion the quick
search finds does). That extremal is returned as the Legendre series of its inputs
(:func:`~nonholo.planning.extremals.smooth_extremal`: the extremal itself, smooth); grid
controls, which jump at every interval and which a physical mechanism cannot follow, are
made smooth (:mod:`nonholo.planning.energy_smoothing`). Where the fit cannot be brought
onto the goal, the plan's own fit is lowered instead; where neither does, the plan is kept.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import replace

from ..controls.parametrisations import Fourier, Legendre, PiecewiseConstant
from ..io.result import PlanResult
from .result_builder import build_result
from .energy_objective import energy, plan_energy_of
from . import extremals
from .energy_search import ENERGY_GRID, loop_starts, search, starts
from .energy_smoothing import smooth_clearance, smoothed
from .strategy_robust import frame_coordinates

# -- the search of ``objective="energy"``
#: The full search integrates with this many times fewer steps than the plan (at least one
#: per interval); its finalists are brought onto the goal and certified on the plan's steps.
SEARCH_COARSENING = 2
#: Seconds of effort (:mod:`nonholo.numerics.effort`) a search may take (the stage takes a
#: second search, on the plan's own steps, where the first certifies nothing).
ENERGY_EFFORT = 1.0

#: Seconds of effort the extremals (:mod:`nonholo.planning.extremals`) may take before the
#: search.
EXTREMAL_EFFORT = 0.1
#: A confirmed least extremal within this relative margin above the plan's energy is the
#: plan itself, laid on the grid: the search is not run. (One needing more is not: the
#: least motion then rides a limit, where no extremal is.)
AT_THE_PLAN = 1e-3

# -- ``objective="auto"``
#: ``objective="auto"``: the budget of the extremal through the plan (seconds of effort).
QUICK_EXTREMAL_EFFORT = 0.05
#: ``objective="auto"``: a plan whose nearest extremal (or itself, where none reaches the
#: goal) needs more than this many times the least energy of the first loops
#: (:func:`~nonholo.planning.energy_search.loop_starts`, their size matched to the offset of
#: the goal) is wasteful: the quick search runs.
WASTEFUL = 3.0
#: ``objective="auto"``: the starts of the quick search (the plan's, then the loops of the
#: first size).
QUICK_STARTS = 5
#: ``objective="auto"``: the quick search's budget (seconds of effort).
QUICK_EFFORT = 0.1
#: ``objective="auto"``: the fraction of the plan's energy a motion the quick search finds
#: must need less than to replace it (a plan kept needs at most 1/0.6 ≈ 1.7 times what it
#: found).
REPLACE_BELOW = 0.6


def loop_energy(endpoint, count: int) -> float:
    """The least energy of the first ``count`` loops of the search
    (:func:`~nonholo.planning.energy_search.loop_starts`): the scale of a motion that
    reaches the goal's offset. Loops in frame coordinates (a mechanism on SO(3) with a
    desingularised frame) give ``inf``: their physical energy would cost a motion each.

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint.
    count : int
        The loops.

    Returns
    -------
    float
        Their least energy (``inf`` without loops of physical inputs).
    """
    if frame_coordinates(endpoint.mechanism):
        return math.inf
    least = math.inf
    for _, loop in itertools.islice(loop_starts(endpoint), count):
        if not isinstance(loop, Fourier):
            return math.inf
        least = min(least, float(loop.metric() @ loop.params ** 2))
    return least


def improve(problem, result: PlanResult, quick: bool = False, budget: float | None = None) -> PlanResult:
    """``result`` (a certified plan of ``problem``) with its energy brought to the least
    the extremals (:func:`~nonholo.planning.extremals.least_energy`) or, where they confirm
    none, :func:`~nonholo.planning.energy_search.search` find (``objective="energy"``), or
    as it was with a reason saying why not; ``options`` records the objective.

    ``quick`` (``objective="auto"``): the extremal through the plan within
    :data:`QUICK_EXTREMAL_EFFORT` — and, where the plan is wasteful (:data:`WASTEFUL`), the
    search from the first :data:`QUICK_STARTS` starts within :data:`QUICK_EFFORT` — and the
    plan replaced only by a motion needing less than :data:`REPLACE_BELOW` of its energy: the
    extremal as a Legendre series, a grid motion made smooth
    (:func:`~nonholo.planning.energy_smoothing.smoothed`); otherwise it is returned unchanged
    but for ``options`` (and, where the smooth fit does not end at the goal below that
    energy, its reason saying so: grid controls, which jump at every interval, are no motion
    to execute).

    Parameters
    ----------
    problem : Problem
        The run's endpoint.
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
    steps = -(-problem.steps // grid) * grid
    endpoint = problem.evaluator(method="nonparametric", steps=steps,
                                delta_min=smooth_clearance(result) if quick else None)
    # the plan's grid means and its energy from one sampling of its inputs (a global route's
    # controls may jump off the grid: for the energy to lower, its energy by quadrature
    # between its breakpoints)
    means, plan_energy = PiecewiseConstant.fit_with_energy(result.controls, problem.T, grid,
                                                           problem.mechanism.n_inputs)
    if not quick and result.hops is not None:
        plan_energy = plan_energy_of(result)
    if quick:
        budget = QUICK_EFFORT if budget is None else budget
        ceiling = REPLACE_BELOW * plan_energy
        found = extremals.least_energy(endpoint, [("plan", means)], problem.options, grid,
                                       QUICK_EXTREMAL_EFFORT, confirmations=1, ceiling=ceiling, continued=0,
                                       smooth=True, abandon=ceiling)
        outcome, why = found.outcome, found.why
        if outcome is None and min(found.least, plan_energy) > WASTEFUL * loop_energy(endpoint, QUICK_STARTS - 1):
            # the plan is not near a motion of the loops' energy: the quick search from its
            # own controls and the first loops
            initial = itertools.islice(starts(endpoint, result.parametrisation), QUICK_STARTS)
            outcome, why = search(endpoint, initial, problem.options, budget, ceiling)
    else:
        budget = ENERGY_EFFORT if budget is None else budget
        ceiling = plan_energy
        outcome, why = None, ""
        if EXTREMAL_EFFORT > 0:
            # where the plan's own extremal does not reach the goal the search is left to find
            # the motion (one riding a limit is no extremal); where the loops are in frame
            # coordinates (a mechanism on SO(3) planned in its desingularised frame, whose
            # plans start from a small control) the plan's extremal is taken unconfirmed
            framed = math.isinf(loop_energy(endpoint, 1))
            # (with drift, a plan's own extremal says less: its loops are no loops, and the
            # others' are tried as well)
            drift = problem.mechanism.has_drift
            initial = itertools.chain([("plan", means)], loop_starts(endpoint))
            found = extremals.least_energy(endpoint, initial, problem.options,
                                           grid, EXTREMAL_EFFORT, ceiling=ceiling * (1.0 + 1e-9),
                                           first_below=math.inf if framed else 0.0, first_or_none=not drift,
                                           smooth=drift)
            outcome, why = found.outcome, found.why
            if outcome is None and found.confirmed and ceiling <= found.least <= ceiling * (1.0 + AT_THE_PLAN):
                # the plan is the least extremal (to the grid's resolution): nothing to search for
                return replace(result, reason=f"{result.reason}; energy not lowered: {why}", options=options)
    final = None
    if outcome is None and not quick:
        # no extremal confirmed at the goal (one that rides a limit is none): the search
        initial = starts(endpoint, result.parametrisation)
        if SEARCH_COARSENING > 1:
            coarse = max(grid, -(-steps // (SEARCH_COARSENING * grid)) * grid)
            if coarse < steps:
                final, endpoint = endpoint, endpoint.refined(coarse)
        outcome, why = search(endpoint, initial, problem.options, budget, ceiling, final)
        if outcome is None and final is not None:
            # nothing certified from the search on fewer steps (a motion riding a limit may
            # reach the goal only on the plan's own): the search on those
            endpoint = final
            outcome, why = search(endpoint, starts(endpoint, result.parametrisation), problem.options, budget,
                                  ceiling)
    series = outcome is not None and isinstance(outcome.evaluation.parametrisation, Legendre)
    lowered = problem.with_settings(method="parametric" if series else "nonparametric", grid=grid, steps=steps)
    if outcome is not None and quick and not series:
        # grid controls, which jump at every interval, made smooth (an extremal as a Legendre
        # series is smooth already)
        found = energy(outcome.evaluation, outcome.evaluation.parametrisation.metric())
        lowered, endpoint, outcome, why = smoothed(problem, outcome, ceiling, result)
        if outcome is None:
            return replace(result, options=options,
                           reason=f"{result.reason}; kept: a motion of energy {found:.6g} was found, but {why}")
    if outcome is None:
        if quick:
            return replace(result, options=options)
        return replace(result, reason=f"{result.reason}; energy not lowered: {why}", options=options)
    if outcome.endpoint is not None and not quick:
        # certified on a finer grid than the search's
        endpoint = outcome.endpoint
        lowered = lowered.with_settings(steps=endpoint.steps)
    outcome = replace(outcome, history=result.history + outcome.history,
                      iterations=result.iterations + outcome.iterations,
                      reason=f"{result.reason}; then the plan's energy {plan_energy:.6g} lowered: {outcome.reason}")
    lowered = build_result(lowered, outcome, True, outcome.reason, endpoint)
    return replace(lowered, options={**lowered.options, "objective": objective}, route=result.route,
                   stitched=result.hops)
