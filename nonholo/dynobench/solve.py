"""A Dynobench instance planned in the least time under its model's bounds, on a whole number
of the model's steps, exported and checked.

:func:`solve` plans it.

The instance's mechanism is planned from its start to its goal with ``objective="time"``
under the model's input bounds and state bounds (the workspace bounds the position); the
least time found is rounded up to a whole number ``K`` of steps ``dt`` and the motion played
in ``K dt`` — re-timed along its path without drift, re-planned at that horizon with drift —
then exported (:func:`~nonholo.dynobench.trajectory.to_dynobench`) and checked by the
project's own checker (:func:`~nonholo.dynobench.checker.check`). The trajectory is then
brought to as few Euler steps of the model as keep its bounds and goal within the share
:data:`SHARE` of the checker's thresholds and its bodies clear of the obstacles by
:data:`STEP_MARGIN` at its states: a short one by SLSQP over its actions
(:mod:`nonholo.dynobench.euler_steps`), a longer one without drift as one sparse program
(:mod:`nonholo.dynobench.sparse_steps`).

The obstacles are kept at the nodes of the least-time path
(:class:`~nonholo.model.obstacles.Obstacles`). For the unicycle (:data:`ROUTED`) that path
starts from a route among the obstacles — the quickest on a lattice of poses
(:mod:`nonholo.planning.lattice_route`), or for a unicycle that only drives forward the
quickest chain of its own arcs (:mod:`nonholo.planning.arc_route`), else OMPL's RRT-Connect
(:mod:`nonholo.planning.plane_route`) — which leads it through a corridor, out of a trap and
round a wall (:func:`routed`); the second-order unicycle (:data:`ROUTED_WITH_DRIFT`) from
that unicycle's least-time path (:func:`routed_with_drift`). The car with a trailer
(:data:`BY_ARCS`), whose steering angle is Dynobench's action, is planned by the Euler steps
alone: the chain of its own arcs, each the model's Euler steps, brought onto the goal and to
its fewest steps whole, as one sparse program (:func:`by_arcs`,
:mod:`nonholo.dynobench.sparse_steps`). Others start from the least-energy
path without obstacles: a local method, which brings a motion out of an obstacle it crosses
near its edge but finds no route round a wall.
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import numpy as np

from ..model import catalog
from ..model.bounds import InputBounds, StateBounds
from ..model.obstacles import Body, Obstacles
from . import euler_steps, sparse_steps
from .checker import Report, check
from .trajectory import to_dynobench

#: The first horizon tried: this many times the straight distance at the model's top speed.
HORIZON_FACTOR = 2.0
#: The clearance kept from the obstacles at the nodes of the least-time path (the motion
#: between them may come closer: it must not overlap one).
MARGIN = 5e-3
#: The clearance the trajectory of Euler steps keeps from the obstacles at its states (which is
#: all Dynobench checks): a body never overlaps one (Dynobench's own collision check was seen
#: to hang on one that does).
STEP_MARGIN = 1e-3
#: The fraction of Dynobench's thresholds on the bounds and the goal that the trajectory of
#: Euler steps may use (:mod:`nonholo.dynobench.euler_steps`, :mod:`nonholo.dynobench.sparse_steps`):
#: the rest, a tenth of each, is left to another machine's round-off, which is far less.
SHARE = 0.9


@dataclass
class Solution:
    """What :func:`solve` found.

    Parameters
    ----------
    solved : bool
        Whether the trajectory passes every check.
    reason : str
        Why not, or how it was found.
    result : PlanResult or None
        The continuous plan the trajectory came from (``None`` for one of the Euler steps
        alone, :func:`by_arcs`).
    trajectory : dict or None
        Its ``states`` and ``actions``.
    report : Report or None
        Its check.
    seconds : float
        Wall time of the whole solve.
    """

    solved: bool
    reason: str
    result: object = None
    trajectory: dict | None = None
    report: Report | None = None
    seconds: float = 0.0


def obstacles(instance, margin: float = 0.0):
    """The instance's obstacles and the robot's bodies as a constraint object.

    Parameters
    ----------
    instance : Instance
        The instance.
    margin : float, default 0
        The clearance kept at the nodes.

    Returns
    -------
    Obstacles
        The boxes, with the vehicle's body (a car's trailer behind its hitch).
    """
    bodies = [Body(*instance.bodies[0])]
    if instance.dynamics == "car_with_trailers":
        bodies.append(Body(*instance.bodies[1], heading="theta1", behind=instance.hitch))
    return Obstacles.boxes([o.center for o in instance.obstacles], [o.size for o in instance.obstacles],
                           tuple(bodies), margin)


def constraints(instance) -> list:
    """The model's bounds as constraint objects of its mechanism.

    Parameters
    ----------
    instance : Instance
        The instance.

    Returns
    -------
    list
        ``InputBounds`` of the actions and ``StateBounds`` of the state (the workspace's on
        the position).
    """
    mech = catalog.get(instance.mechanism)
    low, high = np.full(mech.n_coordinates, -np.inf), np.full(mech.n_coordinates, np.inf)
    low[:2], high[:2] = instance.low, instance.high
    if instance.dynamics == "car_with_trailers":
        # Dynobench's steering angle, an action there, is the catalog car's state φ; its rate
        # is bounded as the catalog's car_with_trailer bounds it
        steer = float(instance.input_high[1])
        low[3], high[3] = -steer, steer
        own = mech.bounds["inputs"]["u2"]
        return [InputBounds((instance.input_low[0], own[0]), (instance.input_high[0], own[1])),
                StateBounds(tuple(low), tuple(high))]
    low[2:], high[2:] = instance.state_low[2:], instance.state_high[2:]
    return [InputBounds(tuple(instance.input_low), tuple(instance.input_high)),
            StateBounds(tuple(low), tuple(high))]


def mechanism_state(instance, x) -> np.ndarray:
    """A Dynobench state as the catalog mechanism's: a car's steering angle (an action in
    Dynobench) inserted, straight.

    Parameters
    ----------
    instance : Instance
        The instance.
    x : numpy.ndarray
        Dynobench's state.

    Returns
    -------
    numpy.ndarray
        The mechanism's.
    """
    x = np.asarray(x, dtype=float)
    if instance.dynamics == "car_with_trailers":
        return np.array([x[0], x[1], x[2], 0.0, x[3]])
    return x


def first_horizon(instance) -> float:
    """The horizon the least-time search starts from: :data:`HORIZON_FACTOR` times the
    straight distance at the top speed, at least one step.

    Parameters
    ----------
    instance : Instance
        The instance.

    Returns
    -------
    float
        The horizon (s).
    """
    top = float(max(abs(instance.input_high[0]), abs(instance.input_low[0])))
    if instance.dynamics == "unicycle2":
        top = float(max(abs(instance.state_high[3]), abs(instance.state_low[3])))
    straight = float(np.hypot(*(instance.goal[:2] - instance.start[:2])))
    return max(HORIZON_FACTOR * straight / top, instance.dt)


#: The mechanisms planned from a route among the obstacles (:mod:`nonholo.planning.lattice_route`
#: or, forward only, :mod:`nonholo.planning.arc_route`; else :mod:`nonholo.planning.plane_route`).
ROUTED = ("unicycle",)
#: The mechanisms with drift planned from the least-time path of a first-order one along such
#: a route (:func:`routed_with_drift`): theirs, whose speed and turning rate are coordinates.
ROUTED_WITH_DRIFT = {"unicycle2": "unicycle"}
#: The first horizon of a mechanism with drift, as a multiple of its first-order guide's least
#: time (it must speed up and slow down).
DRIFT_HORIZON = 1.3


def routed(mechanism: str, start, goal, given, low, high):
    """The least-time path from a route among the obstacles (the lattice's quickest or, for a
    vehicle that only drives forward, the quickest chain of its arcs; else OMPL's): the
    route's speed and turning rate as the first guess of the path of least use
    of the bounds in the route's time (:func:`nonholo.planning.least_time.least_use`, the
    obstacles kept at its nodes), certified, played in the least time along it.

    Parameters
    ----------
    mechanism : str
        The catalog mechanism (driven by its speed and turning rate).
    start, goal : numpy.ndarray
        The mechanism's coordinates at the ends.
    given : list
        The constraints: input bounds, state bounds, obstacles.
    low, high : numpy.ndarray
        The workspace's corners.

    Returns
    -------
    PlanResult
        The path in its least time, or a failed result saying why.
    """
    from ..planning import arc_route, lattice_route, plane_route

    mech = catalog.get(mechanism)
    bounds = given[0]
    turn = float(min(-bounds.lows[1], bounds.highs[1]))
    if bounds.lows[0] > 0:
        # a vehicle that only drives forward: the quickest chain of its own arcs, else Dubins
        # curves at its least speed's tightest turn (the local method widens a turn the other
        # way where that one is less tight)
        way = arc_route.route(given[-1], mech, start, goal, low, high, bounds.lows, bounds.highs)
        how = "the search over arcs"
        if isinstance(way, str):
            speed, slowest = float(bounds.highs[0]), float(bounds.lows[0])
            tightest = float(max(-bounds.lows[1], bounds.highs[1]))
            way = plane_route.route(given[-1], mech, start, goal, low, high, speed, tightest, slowest=slowest)
            how = "OMPL's RRT-Connect, Dubins curves"
    else:
        speed = float(min(-bounds.lows[0], bounds.highs[0]))
        way = lattice_route.route(given[-1], mech, start, goal, low, high, speed, turn)
        how = "the lattice's quickest"
        if isinstance(way, str):
            # a passage narrower than the lattice resolves: a sampling planner's route
            way = plane_route.route(given[-1], mech, start, goal, low, high, speed, turn)
            how = "OMPL's RRT-Connect, Reeds–Shepp curves"
    return from_route(mechanism, start, goal, given, way, how)


def from_route(mechanism: str, start, goal, given, way, how: str):
    """The least-time path from a route (or why there is none): the route's inputs as the
    first guess of the path of least use of the bounds in its time
    (:func:`nonholo.planning.least_time.least_use`, the obstacles kept at its nodes),
    certified, played in the least time along it.

    Parameters
    ----------
    mechanism : str
        The catalog mechanism.
    start, goal : numpy.ndarray
        Its coordinates at the ends.
    given : list
        The constraints: input bounds, state bounds, obstacles.
    way : Route or str
        The route (its ``rates`` the mechanism's inputs), or why there is none.
    how : str
        Where the route came from.

    Returns
    -------
    PlanResult
        The path in its least time, or a failed result saying why.
    """
    from ..planning import least_time
    from ..planning.problem import Problem
    from ..planning.result_builder import build_result
    from ..planning.retime import retime

    bounds = given[0]
    problem = Problem.build(start, goal, mechanism=mechanism, T=1.0 if isinstance(way, str) else way.T,
                            objective="time", constraints=given)
    if isinstance(way, str):
        return build_result(problem, None, False, way)
    seed = build_result(problem, None, False, (f"a route among the obstacles of length {way.length:.4g} in "
                                               f"{way.T:.4g} s ({how})"))
    used = least_time.least_use(problem, way)
    if isinstance(used, str):
        return dataclasses.replace(seed, reason=f"{seed.reason}; no path of least use from it: {used}")
    if not bounds.holds_zero:
        return least_time.least_time_off_zero(problem, seed, used)
    reason = (f"{seed.reason}; the path of least use of the bounds from it: {used.use:.6g} of them in "
              f"{problem.T:.6g} s (SLSQP, {used.iterations} iterations: {used.message})")
    result = least_time.finished(problem, seed, used, reason, fallback=seed)
    return retime(result, input_bounds=bounds) if result.success else result


def routed_with_drift(instance, start, goal, given):
    """The least-time path of a mechanism with drift whose speed and turning rate are
    coordinates (:data:`ROUTED_WITH_DRIFT`): its first-order guide planned by :func:`routed`
    with those coordinates' bounds as its input bounds; the accelerations that make the
    speed and turning rate follow the guide's, stretched to :data:`DRIFT_HORIZON` times its
    least time, at the nodes of the least-time grid, as the first guess of the least time
    with drift (:func:`nonholo.planning.least_time.least_time_with_drift`).

    Parameters
    ----------
    instance : Instance
        The instance.
    start, goal : numpy.ndarray
        The mechanism's coordinates at the ends.
    given : list
        The constraints: input bounds, state bounds, obstacles.

    Returns
    -------
    PlanResult
        The least-time path, or a failed result saying why.
    """
    from ..controls.parametrisations import PiecewiseConstant
    from ..planning import least_time
    from ..planning.problem import Problem
    from ..planning.result_builder import build_result

    guide_name = ROUTED_WITH_DRIFT[instance.mechanism]
    guide_mech = catalog.get(guide_name)
    k = guide_mech.n_coordinates
    states = given[1]
    rates = InputBounds(tuple(states.lows[k:]), tuple(states.highs[k:]))
    guide = routed(guide_name, start[:k], goal[:k], [rates, StateBounds(tuple(states.lows[:k]), tuple(states.highs[:k])),
                                                    given[-1]], instance.low, instance.high)
    if not guide.success:
        problem = Problem.build(start, goal, mechanism=instance.mechanism, T=first_horizon(instance), objective=None,
                                constraints=given)
        return build_result(problem, None, False, f"no first-order guide: {guide.reason.rsplit('; ', 1)[-1]}")
    T = DRIFT_HORIZON * guide.T
    problem = Problem.build(start, goal, mechanism=instance.mechanism, T=T, objective=None, constraints=given)
    grid = least_time.TIME_GRID
    t = np.linspace(0.0, T, grid + 1)
    followed = guide.controls(t * (guide.T / T)) * (guide.T / T)
    followed[0], followed[-1] = start[k:], goal[k:]
    guess = PiecewiseConstant(T, np.diff(followed, axis=0) / (T / grid))
    seed = build_result(problem, None, False, (f"the first-order guide ({guide_name}) in {guide.T:.6g} s, "
                                               f"its rates followed in {T:.6g} s"))
    return least_time.least_time_with_drift(problem, seed, guess=guess, step=instance.dt)


def at_horizon(problem, result, T: float, label: str, fixed: bool = False):
    """The path of least use of the bounds in ``T`` from ``result``'s controls stretched to it
    (:func:`nonholo.planning.least_time.least_use`; ``fixed``: the sides off zero kept as they
    are), certified; or why there is none.

    Parameters
    ----------
    problem : Problem
        The problem at ``T``.
    result : PlanResult
        The least-time path.
    T : float
        The horizon (s).
    label : str
        What the reason adds.
    fixed : bool, default False
        Keep the sides off zero unscaled.

    Returns
    -------
    PlanResult or str
        The path, or why there is none.
    """
    from ..planning import least_time

    power = 2 if result.kinematics.has_drift else 0
    used = least_time.least_use(problem, least_time.stretched(result.controls, result.T, T, power=power), fixed=fixed)
    if isinstance(used, str) or used.use > least_time.KEPT:
        return used if isinstance(used, str) else f"it needs {used.use:.6g} of the bounds"
    return least_time.finished(problem, result, used, f"{result.reason}; {label}")


#: The models planned by the fewest Euler steps from the chain of their own arcs
#: (:func:`by_arcs`): the car with a trailer, whose steering angle is Dynobench's action.
BY_ARCS = ("car_with_trailers",)


def by_arcs(instance, start, goal, kept, share: float, started: float) -> Solution:
    """A car with a trailer: the chain of its arcs among the obstacles
    (:func:`nonholo.planning.car_route.search`; the steering held along an arc and changed at
    once between arcs, as Dynobench's action allows; its arcs the model's own Euler steps),
    its actions the first guess of the fewest Euler steps of the whole trajectory, one sparse
    program (:func:`nonholo.dynobench.sparse_steps.fewest_steps`).

    Parameters
    ----------
    instance : Instance
        The instance.
    start, goal : numpy.ndarray
        The catalog car's coordinates at the ends.
    kept : Obstacles
        The obstacles, the bodies and the margin kept.
    share : float
        The fraction of Dynobench's thresholds on the bounds and the goal used.
    started : float
        When the solve started (``time.perf_counter``).

    Returns
    -------
    Solution
        The trajectory and its check, or why there is none.
    """
    from ..planning import car_route

    arcs = car_route.search(kept, catalog.get(instance.mechanism), start, goal, instance.low, instance.high,
                            float(instance.input_high[0]), float(-instance.input_low[0]),
                            float(instance.input_high[1]), math.inf, step=instance.dt)
    if isinstance(arcs, str):
        return Solution(False, f"no route: {arcs}", seconds=time.perf_counter() - started)
    route = f"a route of {len(arcs.moves)} arcs in {len(arcs.moves) * arcs.steps} steps"
    fewer = sparse_steps.fewest_steps(instance, np.repeat(arcs.moves, arcs.steps, axis=0), kept, share)
    if fewer is None:
        return Solution(False, f"{route}: no Euler steps from it keep the bounds, the obstacles and the goal",
                        seconds=time.perf_counter() - started)
    kept_how = "exactly" if share == 0 else f"to {share:g} of Dynobench's thresholds"
    reason = (f"cost {fewer.report.cost:.6g} s ({len(fewer.actions)} Euler steps of {instance.dt:g} s, the bounds "
              f"and the goal kept {kept_how}, the obstacles cleared by {kept.margin:g}; from {route})")
    return Solution(True, reason, None, {"states": fewer.states.tolist(), "actions": fewer.actions.tolist()},
                    fewer.report, time.perf_counter() - started)


def solve(instance, share: float = SHARE) -> Solution:
    """Plan an instance (see the module).

    Parameters
    ----------
    instance : Instance
        The instance.
    share : float, default :data:`SHARE`
        The fraction of Dynobench's thresholds on the bounds and the goal the trajectory of
        fewer Euler steps may use; 0 keeps them exactly.

    Returns
    -------
    Solution
        The trajectory and its check, or why there is none.
    """
    from ..planning import least_time
    from ..planning.api import plan
    from ..planning.problem import Problem
    from ..planning.retime import retime

    started = time.perf_counter()
    if instance.mechanism not in catalog.names():
        return Solution(False, f"the {instance.dynamics} model ({instance.robot}) is not planned yet",
                        seconds=time.perf_counter() - started)
    given = constraints(instance) + [obstacles(instance, MARGIN)]
    start, goal = mechanism_state(instance, instance.start), mechanism_state(instance, instance.goal)
    if instance.dynamics in BY_ARCS:
        return by_arcs(instance, start, goal, obstacles(instance, STEP_MARGIN), share, started)
    try:
        if instance.mechanism in ROUTED:
            result = routed(instance.mechanism, start, goal, given, instance.low, instance.high)
        elif instance.mechanism in ROUTED_WITH_DRIFT:
            result = routed_with_drift(instance, start, goal, given)
        else:
            result = plan(start, goal, mechanism=instance.mechanism, T=first_horizon(instance),
                          objective="time", constraints=given)
    except ValueError as exc:                 # a bound the planner does not keep yet
        return Solution(False, f"not planned: {exc}", seconds=time.perf_counter() - started)
    if not result.success:
        # the reason's last clause says what stopped it (the ones before, how far it came)
        return Solution(False, f"no plan: {result.reason.rsplit('; ', 1)[-1]}", result,
                        seconds=time.perf_counter() - started)
    K = max(1, math.ceil(result.T / instance.dt - 1e-9))
    T = K * instance.dt
    if not result.kinematics.has_drift and given[0].holds_zero:
        played = retime(result, T=T, input_bounds=given[0])
    else:
        problem = Problem.build(start, goal, mechanism=instance.mechanism, T=T,
                                objective=None if result.kinematics.has_drift else "time",
                                constraints=given)     # the obstacles kept in the least use at T too
        label = f"played in {K} steps of {instance.dt:g} s"
        if not result.kinematics.has_drift and T <= given[0].slack(result.parametrisation.values).min() * result.T:
            # bounds off zero: the least time's path slowed by one factor, where its inputs allow
            played = least_time.played_in(problem, result, T, label)
        else:
            # with drift, or where slowing down would take an input off a side off zero
            played = at_horizon(problem, result, T, label, fixed=not result.kinematics.has_drift)
            if isinstance(played, str):
                return Solution(False, f"the least time {result.T:.6g} s found, but not at {T:g} s: {played}", result,
                                seconds=time.perf_counter() - started)
        played = dataclasses.replace(played, options={**played.options, "input_bounds": given[0].record()})
    if not played.success:
        return Solution(False, f"not at {T:g} s: {played.reason}", played, seconds=time.perf_counter() - started)
    trajectory = to_dynobench(played, instance)
    report = check(instance, trajectory["states"], trajectory["actions"])
    if not report.feasible:
        return Solution(False, f"the trajectory fails Dynobench's checks: {'; '.join(report.failures())}", played,
                        trajectory, report, time.perf_counter() - started)
    reason = f"cost {report.cost:.6g} s ({K} steps of {instance.dt:g} s; the least time {result.T:.6g} s)"
    kept_clear = obstacles(instance, STEP_MARGIN)
    fewer, how = None, ""
    if K <= euler_steps.STEPS_AT_MOST:
        fewer = euler_steps.fewest_steps(instance, trajectory["actions"], kept_clear, share)
    elif instance.dynamics in sparse_steps.MODELS:
        # too long for SLSQP: the whole trajectory as one sparse program (not with drift, whose
        # least-time search is the longer part already)
        fewer, how = sparse_steps.fewest_steps(instance, trajectory["actions"], kept_clear, share), ", one sparse program"
    if fewer is not None and len(fewer.actions) < K:
        trajectory = {"states": fewer.states.tolist(), "actions": fewer.actions.tolist()}
        report = fewer.report
        kept = "exactly" if share == 0 else f"to {share:g} of Dynobench's thresholds"
        reason = (f"cost {report.cost:.6g} s ({len(fewer.actions)} Euler steps of {instance.dt:g} s{how}, the bounds and "
                  f"the goal kept {kept}, the obstacles cleared by {STEP_MARGIN:g}; the continuous plan's {K} steps, its "
                  f"least time {result.T:.6g} s)")
    return Solution(True, reason, played, trajectory, report, time.perf_counter() - started)
