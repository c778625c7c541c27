"""``plan()``: Jacobian motion planning of a mechanism from ``R0`` to ``R_d`` in time ``T``.

:func:`plan` is a thin wrapper: it builds a :class:`~nonholo.planning.problem.Problem`
(mechanism, start, goal, horizon, parametrisation, constraints, objective, settings) and
hands it to :func:`solve`, which runs the strategy and, if asked, the global route.

The method is the appendix's (Tchoń & Jakubiak, eqs. (4)–(11)); the planning core it
runs on — problem, evaluation, options, the step loop of the θ-flow, the result — is
:mod:`nonholo.planning.core`. A *strategy* decides the coordinates, the initial guesses
and the step direction; :data:`STRATEGIES` maps the names :func:`plan` accepts to them:

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

from typing import Callable

import numpy as np

from ..io.result import PlanResult
from ..numerics.blas import one_thread
from . import energy
from . import route as global_route
from .certification import certified
from .constraint_objects import first_refusal
from .core import build_result
from .problem import (
    METHODS,
    OBJECTIVES,
    PLANNING_TIME,
    ROUTES,
    STRATEGIES,
    Problem,
    default_steps,
    initial_controls,
    strategy_class,
)
from .retime import limit_inputs, limit_speed

__all__ = ["plan", "solve", "Problem", "STRATEGIES", "METHODS", "ROUTES", "OBJECTIVES", "PLANNING_TIME",
           "strategy_class", "initial_controls", "default_steps"]


def plan(R0, Rd, *, T: float | None = 1.0, method: str = "parametric", harmonics: int = 2,
         grid: int = 100, u0=None, gamma: float | None = None, step: float = 1.0, tol: float = 1e-10,
         max_iter: int = 200, strategy="robust", mechanism="platform",
         delta_min: float = 1e-2, steps: int | None = None, newton_below: float = 1e-3,
         min_step: float = 1e-6, callback: Callable[[dict], object] | None = None,
         route: str = "auto", leg_length=None, leg_speed=None, objective: str | None = "auto",
         constraints=(), allow_imports: bool = False) -> PlanResult:
    """Plan a control steering ``R0`` to ``Rd`` in time ``T`` (seconds).

    The keywords build a :class:`~nonholo.planning.problem.Problem` (:meth:`Problem.build
    <nonholo.planning.problem.Problem.build>`), which :func:`solve` plans. Success is
    certified (:mod:`nonholo.certify.certificate`): the returned physical controls, replayed
    with an error bound, end within ``tol`` of ``Rd`` and keep ``|Δ| ≥ delta_min``; a plan
    converged on the planner's grid that cannot be certified is corrected or fails with
    the reason. The result's ``error_bound`` and ``replay_steps`` record it.

    Parameters
    ----------
    R0, Rd
        Start and goal: rotation matrices for a mechanism on SO(3); for one whose state
        goes beyond SO(3) (:attr:`~nonholo.model.mechanism.Mechanism.state_space`) vectors
        of its coordinates (``"R^k"``) or pairs ``(R, q)`` (``"SO(3)xR^k"``), see
        :mod:`nonholo.spaces.groups`. There the error is the stacked ``(l, q_T − q_d)`` and
        the result reports it by part (``errors``); strategies ``"paper"`` and ``"robust"``
        plan in the physical inputs, and ``leg_length`` and ``leg_speed`` are for SO(3)
        mechanisms only.
    T : float or None
        The horizon in seconds, at least :data:`~nonholo.motion.time_change.MIN_TIME`;
        ``None``: the least time along the planned path under ``leg_speed`` or under
        :class:`~nonholo.model.bounds.InputBounds` (given in ``constraints``, else the
        mechanism's own: the catalog's car and unicycle have them, and their
        :class:`~nonholo.model.bounds.StateBounds` join).
    method : {"parametric", "nonparametric"}
        Fourier series with ``harmonics`` = K, or piecewise constant on ``grid`` equal
        intervals — of the physical inputs ``u`` (``"paper"``) or of the frame coordinates
        ``w`` (``"robust"``; the result's :meth:`~nonholo.io.result.PlanResult.controls` are
        physical either way).
    harmonics : int
        Harmonics K of the parametric form.
    grid : int
        Intervals of the nonparametric form (at most
        :data:`~nonholo.planning.problem.MAX_PLAN_STEPS`).
    u0 : optional
        Initial control in physical units (see :func:`~nonholo.planning.problem.initial_controls`; default: the
        examples'). ``"robust"`` converts it to frame coordinates
        (:func:`nonholo.planning.strategy_robust.to_frame`) and tries it first.
    gamma : float, optional
        γ: each flow step asks the error to shrink by ``γh`` (default: the strategy's
        ``default_gamma``, 0.5 for ``"paper"`` as in the paper's examples, 1 for
        ``"robust"``).
    step : float
        The initial θ-step h.
    tol : float
        Stop when ``|l_T| ≤ tol`` (rad).
    max_iter : int
        Accepted steps at most.
    strategy : str or type
        ``"robust"`` (default, :mod:`nonholo.planning.strategy_robust`) or ``"paper"`` (the
        appendix's algorithm, :mod:`nonholo.planning.strategy_paper`), or a
        :class:`~nonholo.planning.core.Strategy` subclass, itself or, with
        ``allow_imports=True``, by its import path ``"package.module:Class"``
        (:func:`~nonholo.planning.problem.strategy_class`).
    mechanism : str or Mechanism
        A :class:`~nonholo.model.mechanism.Mechanism` or its name
        (:func:`nonholo.model.catalog.names`).
    delta_min : float
        Every trajectory accepted keeps ``|Δ| ≥ delta_min`` (ignored for mechanisms without
        a singular set).
    steps : int, optional
        CF4 steps on ``[0, T]`` (default :func:`~nonholo.planning.problem.default_steps`; at
        most :data:`~nonholo.planning.problem.MAX_PLAN_STEPS`, the most a certificate replays).
    newton_below : float
        Below this ``|l_T|`` take full Newton steps (``γh = 1``).
    min_step : float
        Give up when a step halved below this ``γh``.
    callback : callable, optional
        ``callback(record)``, called after each accepted iteration of the local plan with
        the history record; returning a true value stops the run (and no global route is
        taken).
    route : {"auto", "local", "global"}
        ``"auto"`` (default) plans from ``R0`` to ``Rd`` and, if that fails, takes the
        global route (:mod:`nonholo.planning.route`): hops along a path of orientations
        through the start's component, clear of ``Δ = 0`` (beyond SO(3): along the
        straight path of states, :mod:`nonholo.planning.state_path`), each planned like a
        local plan, stitched into one control, then re-planned where it can as one smooth
        control from the stitched one (the result's ``stitched`` keeps the hops);
        ``"local"`` plans from ``R0`` to ``Rd`` only (the strategy alone); ``"global"``
        takes only the global route.
    leg_length : tuple of float, optional
        ``(lo, hi)``, the legs' stroke (a platform's, in its geometry's units,
        :meth:`~nonholo.model.mechanism.Mechanism.leg_lengths`): every leg keeps ``lo ≤
        l_i(R(t)) ≤ hi`` along the certified motion (:mod:`nonholo.model.limits`); a start
        or goal outside fails at once, naming the leg. ``None`` (default): no limits.
    leg_speed : float, optional
        ``v``, the legs' top speed (a platform's, geometry units per second): every leg
        keeps ``|dl_i/dt| ≤ v``. The path is planned as without it (in
        :data:`~nonholo.planning.problem.PLANNING_TIME` when ``T=None``), then re-timed
        (:mod:`nonholo.planning.retime`): with ``T=None`` in the least time — the fastest
        leg at ``v`` throughout but where the path nearly stops
        (:data:`~nonholo.motion.retimed.FLOOR`); with a given ``T`` only if the plan breaks the bound, and
        it fails saying the time needed if its path cannot keep it within ``T``. ``None``
        (default): no bound.
    objective : {None, "energy", "auto"}
        ``"auto"`` (default): the plan as found, unless a quick search (within
        :data:`~nonholo.planning.energy.QUICK_EFFORT`) finds a motion needing less than
        :data:`~nonholo.planning.energy.REPLACE_BELOW` of its energy — then that motion made
        smooth (a Fourier series, method ``"parametric"``). ``None``: the plan as found.
        ``"energy"``: the plan, then the least energy
        ``∫|u|² dt`` of its physical inputs that a search from several starts finds, with
        the goal, ``delta_min`` and the stroke kept, within a budget of effort (the same call
        gives the same plan on any machine) (:mod:`nonholo.planning.energy`:
        piecewise-constant inputs on :data:`~nonholo.planning.energy.ENERGY_GRID` intervals,
        method ``"nonparametric"`` in the result). ``options["objective"]`` records it.
    constraints : sequence or None
        Further constraint objects (``nonholo.constraints``:
        :data:`~nonholo.planning.constraint_objects.KINDS`); ``None`` as ``()``: none.
        :class:`~nonholo.model.bounds.StateBounds` are kept at every node like the legs'
        stroke; :class:`~nonholo.model.bounds.InputBounds` by re-timing the planned path
        (:func:`~nonholo.planning.retime.limit_inputs`): with ``T=None`` in the least time
        along it, with a given ``T`` as planned if its inputs keep them, re-timed in ``T``
        if its path needs no longer, else a failure saying the time it needs. A mechanism's
        own bounds (:func:`~nonholo.model.bounds.of_mechanism`) apply with ``T=None`` only,
        each kind unless given here (``InputBounds()``, free, drops them).
    allow_imports : bool
        Let ``strategy`` be an import path, which imports its module and runs its code. Off
        by default: a strategy's name read from a file (a plan file's label re-planned, a
        problem table) is data, and an import path there is refused, naming ``strategy``.

    Returns
    -------
    PlanResult
        The plan, successful or not (``success``, ``reason``). A goal on or across the
        singular surface ``Δ = 0`` (or within ``delta_min`` of it) returns at once a failed
        result with the reason.

    Raises
    ------
    ValueError
        For bad input, naming the argument: ``R0``/``Rd`` not states of the mechanism,
        ``Δ(R0) = 0``, ``T`` below :data:`~nonholo.motion.time_change.MIN_TIME`,
        ``harmonics``/``grid``/``steps`` < 1 or too large, an unknown method, strategy or
        mechanism, a strategy's import path without ``allow_imports``, bad numerical
        options, a Fourier basis too large for memory;
        ``leg_length`` or ``leg_speed`` for a mechanism beyond SO(3); ``T=None`` with nothing
        to bound the time; ``R0``/``Rd`` outside the state bounds (naming the coordinate);
        bounds that do not fit the mechanism (naming ``low``/``high``).
    TypeError
        For a ``callback`` that is not callable, ``constraints`` that are not constraint
        objects (naming ``constraints``), an ``allow_imports`` that is not a bool.

    See Also
    --------
    solve : plans a :class:`~nonholo.planning.problem.Problem` built beforehand.
    nonholo.retime : a stored plan re-timed under a leg-speed bound.
    """
    if callback is not None and not callable(callback):
        raise TypeError(f"callback must be callable (it is given each iteration's record), got {callback!r}")
    problem = Problem.build(R0, Rd, T=T, method=method, harmonics=harmonics, grid=grid, u0=u0,
                            gamma=gamma, step=step, tol=tol, max_iter=max_iter, strategy=strategy,
                            mechanism=mechanism, delta_min=delta_min, steps=steps,
                            newton_below=newton_below, min_step=min_step, route=route,
                            leg_length=leg_length, leg_speed=leg_speed, objective=objective,
                            constraints=constraints, allow_imports=allow_imports)
    return solve(problem, callback)


def solve(problem: Problem, callback: Callable[[dict], object] | None = None) -> PlanResult:
    """The plan of ``problem``: its path (:func:`solve_path`), re-timed under its legs'
    speed or its inputs' bounds if it has them (:func:`nonholo.planning.retime.limit_speed`,
    :func:`~nonholo.planning.retime.limit_inputs`), with BLAS on one thread
    (:func:`nonholo.numerics.blas.one_thread`).

    Parameters
    ----------
    problem : Problem
        The planning problem, checked when it was built
        (:meth:`~nonholo.planning.problem.Problem.build`).
    callback : callable, optional
        ``callback(record)`` after each accepted iteration of the local plan; a true value
        returned stops the run.

    Returns
    -------
    PlanResult
        The certified plan, or a failed one with its reason.
    """
    with one_thread():
        result = solve_path(problem, callback)
        T = None if problem.least_time else problem.T
        return limit_inputs(limit_speed(result, problem.leg_speed, T), problem.input_bounds, T)


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
    for where, R, q in (("start", problem.R0, problem.q0), ("goal", problem.Rd, problem.qd)):
        q = np.zeros(mech.n_coordinates) if q is None else np.asarray(q, dtype=float)
        with np.errstate(all="ignore"):
            try:
                if mech.singular.value(R, q if len(q) else None) == 0.0:
                    continue
                field = np.asarray(mech.G(np.asarray(R, dtype=float), q), dtype=float)
            except (ArithmeticError, ValueError, TypeError) as exc:
                return f"the field G of {mech.name!r} cannot be evaluated at the {where} ({exc}): unreachable"
        if not np.isfinite(field).all():
            at = f"coordinates {np.round(q, 6).tolist()}" if len(q) else "its orientation"
            return f"the field G of {mech.name!r} is not finite at the {where} ({at}): no motion can start or end there"
    return None


def solve_path(problem: Problem, callback: Callable[[dict], object] | None = None) -> PlanResult:
    """The path of ``problem`` in its time ``T``: refused at once where a constraint rules
    the goal out, else the strategy's local plan, then (route ``"auto"`` after a failure, or
    ``"global"``) the global route, then the objective.

    Parameters
    ----------
    problem : Problem
        The planning problem (its ``leg_speed`` is not applied here).
    callback : callable, optional
        As for :func:`solve`.

    Returns
    -------
    PlanResult
        The plan of the path, not re-timed.
    """
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
        strategy = global_route.hop_strategy(cls, global_route.max_hop_sensitivity(mech))
        return solve_path(problem.part(a, b, T_hop, hop_delta_min, strategy))

    def leg(a, b, T_leg, leg_delta_min, quick):
        strategy = global_route.quick_strategy(cls) if quick else cls
        return solve_path(problem.part(a, b, T_leg, leg_delta_min, strategy))

    route_started, budget = global_route.time_budget(mech, problem.started_effort)

    def smooth(stitched, reserve):
        return global_route.smooth(problem, stitched, cls, deadline=route_started + budget, reserve=reserve)

    steered = global_route.steer(mech, problem.R0, problem.Rd, problem.T, hop, tol=options.tol,
                                 delta_min=options.delta_min, sign=evaluator.sign, started=route_started,
                                 budget=budget, leg_limits=problem.leg_limits, rescue=smooth, leg=leg,
                                 q0=problem.q0, qd=problem.qd, limits=problem.limits)
    if steered.controls is None and steered.smoothed is None:
        return build_result(problem, outcome, False,
                            f"{local_reason}; the global route failed too: {steered.reason}", evaluator)
    smoothed = steered.smoothed or smooth(steered.controls, steered.certify_seconds)
    result = global_route.build_result(problem, steered, local_reason, smoothed)
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
        The plan as it is for the objective ``None``; else after the least-energy stage.
    """
    if problem.objective is None:
        return result
    return energy.improve(problem, result, quick=problem.objective == "auto")
