"""``plan()``: Jacobian motion planning of a mechanism from ``R0`` to ``R_d`` in time ``T``.

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

import importlib
import time

import numpy as np

from ..controls import stages
from ..controls.parametrisations import (
    Controls,
    Fourier,
    PiecewiseConstant,
    paper_initial,
)
from ..io.result import PlanResult
from ..model import catalog
from ..model.limits import LegLimits
from ..motion.retimed import check_leg_speed
from ..motion.simulation import DEFAULT_STEPS
from ..numerics import effort
from ..numerics.checks import MAX_STEPS, check_count, check_time
from . import energy
from . import route as global_route
from .certification import certified
from .core import Options, Problem, Request, Strategy, build_result
from .retime import limit_speed
from .strategy_paper import PaperStrategy
from .strategy_robust import RobustStrategy

METHODS = ("parametric", "nonparametric")
#: The routes :func:`plan` takes to a goal.
ROUTES = ("auto", "local", "global")

#: What :func:`plan` optimises once the goal is reached: nothing, or the energy ∫|u|² dt.
OBJECTIVES = (None, "energy")

#: The strategies :func:`plan` knows by name.
STRATEGIES: dict[str, type[Strategy]] = {"paper": PaperStrategy, "robust": RobustStrategy}


def strategy_class(strategy) -> type[Strategy]:
    """The :class:`~nonholo.planning.core.Strategy` subclass ``strategy``, the one of that
    name in :data:`STRATEGIES`, or one given by its import path ``"package.module:Class"``
    (so that a problem table, JSON, can name any strategy); ``ValueError`` lists them."""
    if isinstance(strategy, type) and issubclass(strategy, Strategy):
        return strategy
    if isinstance(strategy, str) and strategy in STRATEGIES:
        return STRATEGIES[strategy]
    if isinstance(strategy, str) and ":" in strategy:
        module, _, qualname = strategy.partition(":")
        try:
            found = importlib.import_module(module)
            for part in qualname.split("."):
                found = getattr(found, part)
        except (ImportError, AttributeError, ValueError) as exc:
            raise ValueError(f"strategy {strategy!r} cannot be imported: {exc}") from None
        if isinstance(found, type) and issubclass(found, Strategy):
            return found
        raise ValueError(f"strategy {strategy!r} is not a Strategy subclass")
    raise ValueError(f"unknown strategy {strategy!r}; known: {', '.join(STRATEGIES)} "
                     "(or pass a Strategy subclass)")


def initial_controls(method: str, T: float, n_inputs: int, harmonics: int, grid: int, u0=None) -> Controls:
    """The initial control in the parametrisation of ``method``.

    ``u0``: ``None`` (the examples' ``u_1 = 0.3 sin 2πt/T``, ``u_2 = 0.3 cos 2πt/T``), a
    :class:`~nonholo.controls.parametrisations.Controls` of the right kind and size, or a vectorised
    function ``u(t)`` (projected: least squares on the Fourier basis, interval means on
    the grid).
    """
    kind, size = (Fourier, harmonics) if method == "parametric" else (PiecewiseConstant, grid)
    if isinstance(u0, Controls):
        if not isinstance(u0, kind):
            raise ValueError(f"u0 is a {type(u0).__name__}, method {method!r} needs a {kind.__name__}")
        if u0.T != T or u0.n_inputs != n_inputs:
            raise ValueError(f"u0 is defined for T = {u0.T:g}, m = {u0.n_inputs}; the problem has "
                             f"T = {T:g}, m = {n_inputs}")
        got = u0.harmonics if kind is Fourier else u0.grid
        if got != size:
            what = "harmonics" if kind is Fourier else "grid"
            raise ValueError(f"u0 has {what} = {got}, the planner was asked for {what} = {size}")
        return u0
    func = paper_initial(T, n_inputs) if u0 is None else u0
    if not callable(func):
        raise ValueError("u0 must be None, a nonholo.controls.parametrisations.Controls or a function u(t)")
    return kind.fit(func, T, size, n_inputs)


def default_steps(method: str, grid: int) -> int:
    """:data:`~nonholo.motion.simulation.DEFAULT_STEPS`, rounded up to a multiple of ``grid`` for grid controls."""
    if method == "nonparametric":
        return -(-DEFAULT_STEPS // grid) * grid
    return DEFAULT_STEPS


#: The planning horizon (s) of a plan asked for in the least time (``T=None``): the path is
#: planned in this time, then re-timed (:mod:`nonholo.planning.retime`).
PLANNING_TIME = 1.0


def plan(R0, Rd, *, T: float | None = 1.0, method: str = "parametric", harmonics: int = 2,
         grid: int = 100, u0=None, gamma: float | None = None, step: float = 1.0, tol: float = 1e-10,
         max_iter: int = 200, strategy="robust", mechanism="platform",
         delta_min: float = 1e-2, steps: int | None = None, newton_below: float = 1e-3,
         min_step: float = 1e-6, callback: Callable[[dict], object] | None = None,
         route: str = "auto", leg_length=None, leg_speed=None, objective: str | None = None) -> PlanResult:
    """Plan a control steering ``R0`` to ``Rd`` in time ``T`` (seconds).

    - ``R0``, ``Rd``: start and goal — rotation matrices for a mechanism on SO(3); for one
      whose state goes beyond SO(3) (:attr:`~nonholo.model.mechanism.Mechanism.state_space`)
      vectors of its coordinates (``"R^k"``) or pairs ``(R, q)`` (``"SO(3)xR^k"``), see
      :mod:`nonholo.spaces.state`. There the error is the stacked ``(l, q_T − q_d)`` and the
      result reports it by part (``errors``); strategies ``"paper"`` and ``"robust"`` plan
      in the physical inputs, and the global route, ``leg_length``, ``leg_speed`` and
      ``objective`` are for SO(3) mechanisms only (``ValueError`` otherwise).
    - ``mechanism``: a :class:`~nonholo.model.mechanism.Mechanism` or its name
      (:func:`nonholo.model.catalog.names`).
    - ``strategy``: ``"robust"`` (default, :mod:`nonholo.planning.strategy_robust`) or ``"paper"``
      (the appendix's algorithm, :mod:`nonholo.planning.strategy_paper`), or a
      :class:`~nonholo.planning.core.Strategy` subclass, itself or by its import path
      ``"package.module:Class"`` (:func:`strategy_class`).
    - ``method``: ``"parametric"`` (Fourier series with ``harmonics`` = K) or
      ``"nonparametric"`` (piecewise constant on ``grid`` equal intervals) — of the
      physical inputs ``u`` (``"paper"``) or of the frame coordinates ``w`` (``"robust"``;
      the result's :meth:`~nonholo.io.result.PlanResult.controls` are physical either way).
    - ``u0``: initial control in physical units (see :func:`initial_controls`; default:
      the examples'). ``"robust"`` converts it to frame coordinates
      (:func:`nonholo.planning.strategy_robust.to_frame`) and tries it first.
    - ``gamma`` (γ), ``step`` (initial θ-step h): each flow step asks the error to shrink
      by ``γh`` (default γ: the strategy's ``default_gamma``, 0.5 for ``"paper"`` as in
      the paper's examples, 1 for ``"robust"``); ``newton_below``: below this ``|l_T|``
      take full Newton steps (``γh = 1``);
      ``min_step``: give up when a step halved below this ``γh``; ``tol``: stop when
      ``|l_T| ≤ tol`` (rad); ``max_iter``: accepted steps at most.
    - ``delta_min``: every trajectory accepted keeps ``|Δ| ≥ delta_min`` (ignored for
      mechanisms without a singular set).
    - ``leg_length``: ``(lo, hi)``, the legs' stroke (a platform's, in its geometry's
      units, :meth:`~nonholo.model.mechanism.Mechanism.leg_lengths`): every leg keeps ``lo ≤
      l_i(R(t)) ≤ hi`` along the certified motion (:mod:`nonholo.model.limits`); a start or goal
      outside fails at once, naming the leg. ``None`` (default): no limits.
    - ``leg_speed``: ``v``, the legs' top speed (a platform's, geometry units per second):
      every leg keeps ``|dl_i/dt| ≤ v``. The path is planned as without it (in
      :data:`PLANNING_TIME` when ``T=None``), then re-timed (:mod:`nonholo.planning.retime`): with
      ``T=None`` in the least time — the fastest leg at ``v`` throughout; with a given
      ``T`` only if the plan breaks the bound, and it fails saying the time needed if its
      path cannot keep it within ``T``. ``None`` (default): no bound.
    - ``objective``: ``None`` (default): the plan as found; ``"energy"``: then the energy
      ``∫|u|² dt`` of its physical inputs lowered with the goal, ``delta_min`` and the
      stroke kept (:mod:`nonholo.planning.energy`: piecewise-constant inputs on
      :data:`~nonholo.planning.energy.ENERGY_GRID` intervals, method ``"nonparametric"``
      in the result).
    - ``steps``: CF4 steps on ``[0, T]`` (default :func:`default_steps`).
    - ``callback(record)``: called after each accepted iteration of the local plan with the
      history record; returning a true value stops the run (and no global route is taken).
    - ``route``: ``"auto"`` (default) plans from ``R0`` to ``Rd`` and, if that fails, takes
      the global route (:mod:`nonholo.planning.route`): hops along a path of orientations
      through the start's component, clear of ``Δ = 0`` (beyond SO(3): along the straight
      path of states, :mod:`nonholo.planning.state_path`), each planned like a local plan,
      stitched into one control, then re-planned where it can as one smooth control from
      the stitched one (the result's ``stitched`` keeps the hops); ``"local"`` plans from
      ``R0`` to ``Rd`` only (the strategy alone); ``"global"`` takes only the global route.

    Success is certified (:mod:`nonholo.certify.certificate`): the returned physical controls, replayed
    with an error bound, end within ``tol`` of ``Rd`` and keep ``|Δ| ≥ delta_min``; a
    plan converged on the planner's grid that cannot be certified is corrected or fails
    with the reason. The result's ``error_bound`` and ``replay_steps`` record it.

    Raises ``ValueError`` for bad input (``R0``/``Rd`` not rotations, ``Δ(R0) = 0``,
    ``T ≤ 0``, ``harmonics``/``grid``/``steps`` < 1, unknown method/strategy/mechanism, bad
    numerical options). A goal on or across the singular surface ``Δ = 0`` (or within
    ``delta_min`` of it) returns at once a failed :class:`~nonholo.io.result.PlanResult`
    with the reason.
    """
    mech = catalog.get(mechanism)
    speed = check_leg_speed(leg_speed, mech)
    if T is None and speed is None:
        raise ValueError("T=None asks for the least time, which needs a leg_speed to bound")
    if objective not in OBJECTIVES:
        raise ValueError(f"unknown objective {objective!r}; known: None, 'energy'")
    result = plan_path(R0, Rd, T=PLANNING_TIME if T is None else T, method=method, harmonics=harmonics,
                       grid=grid, u0=u0, gamma=gamma, step=step, tol=tol, max_iter=max_iter,
                       strategy=strategy, mechanism=mech, delta_min=delta_min, steps=steps,
                       newton_below=newton_below, min_step=min_step, callback=callback, route=route,
                       leg_length=leg_length, objective=objective)
    return limit_speed(result, speed, T)


def plan_path(R0, Rd, *, T: float = 1.0, method: str = "parametric", harmonics: int = 2,
              grid: int = 100, u0=None, gamma: float | None = None, step: float = 1.0, tol: float = 1e-10,
              max_iter: int = 200, strategy="robust", mechanism="platform",
              delta_min: float = 1e-2, steps: int | None = None, newton_below: float = 1e-3,
              min_step: float = 1e-6, callback: Callable[[dict], object] | None = None,
              route: str = "auto", leg_length=None, objective: str | None = None) -> PlanResult:
    """:func:`plan` without a bound on the legs' speed: the path, in the time ``T``."""
    started = time.perf_counter()
    started_effort = effort.seconds()
    if route not in ROUTES:
        raise ValueError(f"unknown route {route!r}; known: {', '.join(ROUTES)}")
    mech = catalog.get(mechanism)
    leg_limits = LegLimits.from_argument(leg_length, mech)
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; known: {', '.join(METHODS)}")
    cls = strategy_class(strategy)
    T = check_time(T)
    harmonics = check_count(harmonics, "harmonics")
    grid = check_count(grid, "grid")
    R0, q0 = mech.parse_state(R0, "R0")
    Rd, qd = mech.parse_state(Rd, "Rd")
    if objective is not None and not energy.supports(mech):
        raise ValueError(f"objective {objective!r} is for mechanisms on SO(3); {mech.name!r} has "
                         f"the state space {mech.space.name}")
    delta_at = mech.singular.value

    if gamma is None:
        gamma = cls.default_gamma
    options = Options(gamma=gamma, step=step, tol=tol, max_iter=max_iter,
                      newton_below=newton_below, min_step=min_step, delta_min=delta_min)
    if delta_at(R0, q0) == 0.0:
        raise ValueError(mech.singular.refusal)
    steps = check_count(default_steps(method, grid) if steps is None else steps, "steps", maximum=MAX_STEPS)
    if method == "parametric" and 2 * harmonics > steps:
        raise ValueError(f"harmonics = {harmonics} is more than the integrator's steps = {steps} "
                         "can resolve (at most steps/2; raise steps or lower harmonics)")
    controls = initial_controls(method, T, mech.n_inputs, harmonics, grid, u0)
    stages.check_steps(controls, steps)
    request = Request(mechanism=mech, method=method, strategy=cls.name, T=T, R0=R0, Rd=Rd, steps=steps,
                      options=options, harmonics=harmonics, grid=grid, controls=controls, started=started,
                      leg_limits=leg_limits, q0=q0, qd=qd)

    # goals that cannot be reached: decided before anything is simulated (or compiled)
    if mech.singular.exists:
        d0, dd = delta_at(R0, q0), delta_at(Rd, qd)
        where, at0, atd = mech.singular.where, mech.singular.at_start, mech.singular.at_goal
        refusal = None
        if dd == 0.0:
            refusal = (f"the goal lies on the singular {where} Δ = 0 ({atd} = 0): unreachable with "
                       "bounded inputs")
        elif np.sign(dd) != np.sign(d0):
            refusal = (f"the goal lies across the singular {where} Δ = 0 ({at0} = {d0:.4g}, "
                       f"{atd} = {dd:.4g}): no motion can cross it, unreachable")
        elif abs(dd) < options.delta_min:
            refusal = (f"the goal lies within delta_min = {options.delta_min:g} of the singular "
                       f"{where} (|{atd}| = {abs(dd):.3g})")
        elif abs(d0) < options.delta_min:
            refusal = (f"the start lies within delta_min = {options.delta_min:g} of the singular "
                       f"{where} (|{at0}| = {abs(d0):.3g})")
        if refusal is not None:
            return build_result(request, None, False, refusal)
    if leg_limits is not None:
        refusal = leg_limits.violation(mech, R0, "the start") or leg_limits.violation(mech, Rd, "the goal")
        if refusal is not None:
            return build_result(request, None, False, refusal)

    solver = cls(options)
    problem = Problem(R0, Rd, T, mech, method, steps, options.delta_min, frame=solver.frame(mech),
                      leg_limits=leg_limits, q0=q0, qd=qd)
    start = solver.initial(problem, controls, u0 is not None)
    if route == "global":
        outcome, local_reason = None, "not tried (route 'global')"
    else:
        outcome = solver.solve(problem, start, callback)
        if outcome.success and outcome.certificate is None:
            outcome = certified(outcome, problem, options)
        if outcome.success or route == "local" or outcome.stopped:
            result = build_result(request, outcome, outcome.success, outcome.reason, problem)
            return energy.improve(request, result) if objective == "energy" else result
        local_reason = outcome.reason

    def part(a, b, T_part, part_delta_min, part_strategy):
        """One part of the global route, ``a → b`` (states ``(R, q)``), planned locally."""
        return plan_path(mech.space.public(*a), mech.space.public(*b), T=T_part, method=method,
                         harmonics=harmonics, grid=grid, gamma=gamma, step=step, tol=tol, max_iter=max_iter,
                         strategy=part_strategy, mechanism=mech, delta_min=part_delta_min, steps=steps,
                         newton_below=newton_below, min_step=min_step, route="local", leg_length=leg_length)

    def hop(a, b, T_hop, hop_delta_min):
        return part(a, b, T_hop, hop_delta_min,
                    global_route.hop_strategy(cls, global_route.max_hop_sensitivity(mech)))

    def leg(a, b, T_leg, leg_delta_min, quick):
        return part(a, b, T_leg, leg_delta_min, global_route.quick_strategy(cls) if quick else cls)

    route_started, budget = global_route.time_budget(mech, started_effort)

    def smooth(stitched, reserve):
        return global_route.smooth(request, stitched, cls, deadline=route_started + budget, reserve=reserve)

    steered = global_route.steer(mech, R0, Rd, T, hop, tol=tol, delta_min=delta_min, sign=problem.sign,
                                 started=route_started, budget=budget, leg_limits=leg_limits, rescue=smooth,
                                 leg=leg, q0=q0, qd=qd)
    if steered.controls is None and steered.smoothed is None:
        return build_result(request, outcome, False,
                            f"{local_reason}; the global route failed too: {steered.reason}", problem)
    smoothed = steered.smoothed or smooth(steered.controls, steered.certify_seconds)
    result = global_route.build_result(request, steered, local_reason, smoothed)
    return energy.improve(request, result) if objective == "energy" else result
