"""``plan()``: Jacobian motion planning of a mechanism from ``R0`` to ``R_d`` in time ``T``.

:func:`plan` is a thin wrapper: it builds a :class:`~nonholo.planning.problem.Problem`
(mechanism, start, goal, horizon, parametrisation, constraints, objective, settings) and
hands it to :func:`solve`, which runs the strategy and, if asked, the global route.

The method is the appendix's (Tchoń & Jakubiak, eqs. (4)–(11)); the planning core it
runs on — options, the step loop of the θ-flow — is :mod:`nonholo.planning.core`, on the
endpoint map of :mod:`nonholo.planning.endpoint_map`; the result is assembled by
:mod:`nonholo.planning.result_builder`. A *strategy* decides the coordinates, the initial
guesses and the step direction; :data:`STRATEGIES` maps the names :func:`plan` accepts to
them:

- ``"paper"`` (:mod:`nonholo.planning.strategy_paper`): the appendix's algorithm in the physical
  inputs ``u``;
- ``"robust"`` (:mod:`nonholo.planning.strategy_robust`, the default): the same flow in the
  desingularised frame coordinates ``w`` of ``ω = N(R) w``, with a drift initial guess,
  restarts and a null-space barrier on ``Δ``; the result's controls are the physical
  inputs ``u = W(R) w`` (:class:`~nonholo.motion.frame_controls.FrameControls`).

A new strategy subclasses :class:`~nonholo.planning.core.Strategy` and is passed to
:func:`plan` as ``strategy=`` (the class itself); nothing registers it. Success rates and
timings of the strategies: ``benchmarks/results/`` (``bench_robust.md``,
``bench_plan.md``).
"""
from __future__ import annotations

import dataclasses

import time
from typing import Callable

import numpy as np

from ..io.result import PlanResult
from ..numerics import effort
from ..numerics.blas import one_thread
from . import energy, least_time
from . import route as global_route
from . import route_paths, route_smoothing
from .correction import certified
from .constraint_objects import first_refusal
from .problem import OBJECTIVES, PLANNING_TIME, ROUTES, Problem
from .result_builder import build_result, build_route_result
from .settings import (
    METHODS,
    STRATEGIES,
    Settings,
    default_steps,
    initial_controls,
    strategy_class,
)
from .retime import limit_inputs, limit_speed

__all__ = ["plan", "solve", "Problem", "Settings", "STRATEGIES", "METHODS", "ROUTES", "OBJECTIVES", "PLANNING_TIME",
           "strategy_class", "initial_controls", "default_steps"]


def plan(start, goal, *, mechanism="platform", T: float | None = 1.0, objective: str | None = "auto",
         constraints=(), strategy="robust", route: str = "auto", settings=None, u0=None,
         callback: Callable[[dict], object] | None = None, allow_imports: bool = False) -> PlanResult:
    """Plan a motion of ``mechanism`` from ``start`` to ``goal`` in ``T`` seconds.

    The arguments build a :class:`~nonholo.planning.problem.Problem`, which :func:`solve`
    plans. A success is certified (:mod:`nonholo.certify.certificate`): its controls,
    replayed with an error bound, end within ``settings.tol`` of the goal and keep every
    constraint. The guide (``docs/guide/planning.md``) details each argument.

    Parameters
    ----------
    start, goal
        States as the mechanism's space takes them (:mod:`nonholo.spaces.product`), or
        :class:`~nonholo.spaces.state.State` values.
    mechanism : str, path or Mechanism
        A catalog name, a mechanism file (``.toml``) or a mechanism.
    T : float or None
        The horizon (s); ``None``: the least time under a
        :class:`~nonholo.planning.constraint_objects.LegSpeed` or input bounds.
    objective : {"auto", None, "energy", "time"}
        What is lowered once the goal is reached: the energy (:mod:`nonholo.planning.energy`)
        or, under input bounds, the time (:mod:`nonholo.planning.least_time`; ``T`` is then
        the horizon the path is planned in first).
    constraints : sequence
        Constraint objects (:mod:`nonholo.constraints`); a ``Clearance(1e-2)`` unless given.
    strategy, route : str
        ``"robust"`` or ``"paper"`` (or a Strategy subclass); ``"auto"``, ``"local"`` or ``"global"``.
    settings : Settings, dict or None
        The parametrisation and the solver's numbers (:class:`~nonholo.planning.settings.Settings`).
    u0, callback, allow_imports
        The initial control; ``callback(record)`` after each iteration (true: stop); let
        ``strategy`` be an import path ``"package.module:Class"``.

    Returns
    -------
    PlanResult
        The plan, successful or not (``success``, ``reason``).

    Raises
    ------
    ValueError, TypeError
        For bad input, naming the argument.
    """
    if callback is not None and not callable(callback):
        raise TypeError(f"callback must be callable (it is given each iteration's record), got {callback!r}")
    started = time.perf_counter()
    problem = Problem.build(start, goal, mechanism=mechanism, T=T, objective=objective, constraints=constraints,
                            strategy=strategy, route=route, settings=settings, u0=u0,
                            allow_imports=allow_imports)
    return solve(problem, callback, started=started)


def solve(problem: Problem, callback: Callable[[dict], object] | None = None, *,
          started: float | None = None) -> PlanResult:
    """The plan of ``problem``: its path (:func:`solve_path`), re-timed under its legs'
    speed or its inputs' bounds if it has them (:func:`nonholo.planning.retime.limit_speed`,
    :func:`~nonholo.planning.retime.limit_inputs`) — at a given ``T``, a path that cannot be
    re-timed into the bounds replaced by the path of least use of them
    (:func:`nonholo.planning.least_time.within_bounds`) — with BLAS on one thread
    (:func:`nonholo.numerics.blas.one_thread`).

    Parameters
    ----------
    problem : Problem
        The planning problem, checked when it was built
        (:meth:`~nonholo.planning.problem.Problem.build`).
    callback : callable, optional
        ``callback(record)`` after each accepted iteration of the local plan; a true value
        returned stops the run.
    started : float, optional
        The ``time.perf_counter()`` reading the call began at (:func:`plan`'s, before it
        built the problem), from which ``PlanResult.seconds`` counts (default: now).

    Returns
    -------
    PlanResult
        The certified plan, or a failed one with its reason.
    """
    started = time.perf_counter() if started is None else started
    started_effort = effort.seconds()
    with one_thread():
        result = solve_path(problem, callback, started_effort)
        T = None if problem.least_time else problem.T
        result = limit_speed(result, problem.leg_speed, T)
        limited = limit_inputs(result, problem.input_bounds, T)
        if T is not None and result.success and not limited.success:
            # the bounds shape the motion in T rather than refuse the goal
            limited = least_time.within_bounds(problem, result, limited)
        result = limited
        result = keep_clear(result, problem.obstacles)
    result.seconds = time.perf_counter() - started
    return result


def keep_clear(result: PlanResult, obstacles) -> PlanResult:
    """``result``, failed where its certified motion brings a body within the obstacles'
    margin (the planner keeps obstacles inside the least-time path only).

    Parameters
    ----------
    result : PlanResult
        The plan.
    obstacles : Obstacles or None
        The obstacles (``None``: ``result`` itself).

    Returns
    -------
    PlanResult
        The plan; ``options`` records the obstacles.
    """
    if obstacles is None:
        return result
    options = {**result.options, "obstacles": obstacles.record()}
    where = obstacles.violation(result.kinematics, result.q) if result.success else None
    if where is None:
        return dataclasses.replace(result, options=options)
    return dataclasses.replace(result, success=False, options=options,
                               reason=f"{result.reason}; but its motion meets an obstacle: {where}")


def field_refusal(problem) -> str | None:
    """Why no motion can start or end where the problem asks: the field ``G`` not finite
    (or not computable) at the start or the goal, off the singular set (which has its own
    refusals).

    Parameters
    ----------
    problem : Problem
        The planning problem.

    Returns
    -------
    str or None
        The reason, ``None`` where ``G`` is finite at both ends.
    """
    mech = problem.mechanism
    for where, (R, q) in (("start", problem.start), ("goal", problem.goal)):
        with np.errstate(all="ignore"):
            try:
                if mech.singular.value(R, q) == 0.0:
                    continue
                field = np.asarray(mech.G(R, q), dtype=float)
            except (ArithmeticError, ValueError, TypeError) as exc:
                return f"the field G of {mech.name!r} cannot be evaluated at the {where} ({exc}): unreachable"
        if not np.isfinite(field).all():
            at = f"coordinates {np.round(q, 6).tolist()}" if len(q) else "its orientation"
            return f"the field G of {mech.name!r} is not finite at the {where} ({at}): no motion can start or end there"
    return None


def solve_path(problem: Problem, callback: Callable[[dict], object] | None = None,
               started_effort: float | None = None) -> PlanResult:
    """The path of ``problem`` in its time ``T``: refused at once where a constraint rules
    the goal out, else the strategy's local plan, then (route ``"auto"`` after a failure, or
    ``"global"``) the global route, then the objective.

    Parameters
    ----------
    problem : Problem
        The planning problem (its ``leg_speed`` is not applied here).
    callback : callable, optional
        As for :func:`solve`.
    started_effort : float, optional
        The effort clock (:func:`nonholo.numerics.effort.seconds`) when solving started,
        from which the global route's budget counts (default: now).

    Returns
    -------
    PlanResult
        The plan of the path, not re-timed.
    """
    if started_effort is None:
        started_effort = effort.seconds()
    mech, options, cls = problem.mechanism, problem.options, problem.strategy_class
    # goals that cannot be reached: decided before anything is simulated (or compiled)
    refusal = first_refusal(problem.constraints, mech, problem.start, problem.goal) or field_refusal(problem)
    if refusal is not None:
        return build_result(problem, None, False, refusal)

    solver = cls(options)
    evaluator = problem.evaluator(frame=solver.frame(mech))
    start = solver.initial(evaluator, problem.controls, problem.u0_given)
    if problem.route == "global":
        outcome, local_reason = None, "not tried (route 'global')"
    else:
        outcome = solver.solve(evaluator, start, callback)
        if outcome.success and outcome.certificate is None:
            outcome = certified(outcome, evaluator, options)
        if outcome.success or problem.route == "local" or outcome.stopped:
            result = build_result(problem, outcome, outcome.success, outcome.reason, evaluator)
            return objective(problem, result)
        local_reason = outcome.reason

    def hop(a, b, T_hop, hop_delta_min):
        strategy = global_route.hop_strategy(cls, route_paths.max_hop_sensitivity(mech))
        return solve_path(problem.part(a, b, T_hop, hop_delta_min, strategy))

    def leg(a, b, T_leg, leg_delta_min, quick):
        strategy = global_route.quick_strategy(cls) if quick else cls
        return solve_path(problem.part(a, b, T_leg, leg_delta_min, strategy))

    route_started, budget = route_paths.time_budget(mech, started_effort)

    def smooth(stitched, reserve):
        return route_smoothing.smooth(problem, stitched, cls, deadline=route_started + budget,
                                      reserve=reserve)

    steered = global_route.steer(mech, problem.start, problem.goal, problem.T, hop, tol=options.tol,
                                 delta_min=options.delta_min, sign=evaluator.sign, started=route_started,
                                 budget=budget, leg_limits=problem.leg_limits, rescue=smooth, leg=leg,
                                 limits=problem.limits)
    if steered.controls is None and steered.smoothed is None:
        return build_result(problem, outcome, False,
                            f"{local_reason}; the global route failed too: {steered.reason}", evaluator)
    smoothed = steered.smoothed or smooth(steered.controls, steered.certify_seconds)
    result = build_route_result(problem, steered, local_reason, smoothed)
    return objective(problem, result)


def objective(problem: Problem, result: PlanResult) -> PlanResult:
    """``result`` after the problem's objective (:func:`nonholo.planning.energy.improve`).

    Parameters
    ----------
    problem : Problem
        The problem planned.
    result : PlanResult
        Its plan.

    Returns
    -------
    PlanResult
        The plan as it is for the objective ``None``; for ``"time"`` the path of least time
        under the input bounds (:func:`nonholo.planning.least_time.least_time_path`, from the
        least-energy path, re-timed by :func:`solve`); else after the least-energy stage.
    """
    if problem.objective is None:
        return result
    if problem.objective == "time":
        # from the least-energy path: a short path, in the homotopy class a time-optimal one
        # mostly shares (the plan as found may loop)
        shortest = energy.improve(problem, result)
        return least_time.least_time_path(problem, shortest if shortest.success else result)
    return energy.improve(problem, result, quick=problem.objective == "auto")
