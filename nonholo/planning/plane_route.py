"""A route among obstacles for a planar vehicle, as the first guess of a local method.

Jacobian planning and the least-time search are local: a motion that must leave a trap or
go round a wall needs a route first. :func:`route` asks OMPL for one (its geometric
RRT-Connect in the Reeds–Shepp space of turning radius :data:`TURNING_RADIUS`, the path then
shortened by OMPL's simplifier), every state checked for the vehicle's bodies against the
obstacles with their margin, and plays it as the speed and turning rate of a vehicle whose
coordinates begin ``(x, y, θ)``: along each straight piece at the top speed, along each arc
at the speed that keeps the turning rate in its bound. A unicycle follows it exactly.

The route is the same on every run of a process that starts the same way: RRT-Connect stops
at its first route (no wall-time budget), and OMPL's random generator is seeded once per
process (:data:`SEED`; OMPL allows no more), before the first route.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: The turning radius of the Reeds–Shepp curves (the coordinates' length unit).
TURNING_RADIUS = 0.3
#: The spacing of the states OMPL checks along a motion, as a fraction of the space's extent.
CHECK_RESOLUTION = 0.002
#: The route's pieces are played on at least this many points along their length (each).
POINTS_PER_UNIT = 50
#: Samples of RRT-Connect at most before the route is given up (an iteration budget, not
#: wall time).
MAX_SAMPLES = 5000
#: The seed of OMPL's random generator.
SEED = 20260226

_seeded = False


@dataclass
class Route:
    """A route and its speed and turning rate in time.

    Parameters
    ----------
    states : numpy.ndarray
        ``(x, y, θ)`` along the route, ``(n, 3)``.
    times : numpy.ndarray
        The times they are passed, ``(n,)``, from 0.
    rates : numpy.ndarray
        The speed and turning rate between them, ``(n - 1, 2)``.
    length : float
        The route's length.
    """

    states: np.ndarray
    times: np.ndarray
    rates: np.ndarray
    length: float

    @property
    def T(self) -> float:
        """The route's duration (s)."""
        return float(self.times[-1])

    def __call__(self, t) -> np.ndarray:
        """The speed and turning rate at the times ``t``, shape ``(n, 2)``."""
        t = np.clip(np.asarray(t, dtype=float).reshape(-1), 0.0, self.T)
        k = np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, len(self.rates) - 1)
        return self.rates[k]


def route(obstacles, mechanism, start, goal, low, high, speed: float, turn: float,
          slowest: float = 0.0) -> Route | str:
    """A route from ``start`` to ``goal`` (their ``(x, y, θ)``) inside the box ``low ≤ (x, y) ≤
    high`` clear of the obstacles, played at most at ``speed`` and ``turn`` (see the
    module); or why there is none. A vehicle that only drives forward (``slowest > 0``)
    follows Dubins curves instead, of the radius ``slowest / turn`` its tightest turn has.

    Parameters
    ----------
    obstacles : Obstacles
        The obstacles, the vehicle's bodies and the margin kept.
    mechanism : Mechanism
        The vehicle (its first coordinates ``x, y, θ``; the bodies' other coordinates, a
        trailer's heading, follow the vehicle's).
    start, goal : array_like
        The mechanism's coordinates at the ends.
    low, high : array_like
        The workspace's corners.
    speed, turn : float
        The top speed and turning rate (positive).
    slowest : float, default 0
        The least forward speed of a vehicle that does not stop or reverse (0: it does).

    Returns
    -------
    Route or str
        The route, or the reason there is none.
    """
    from ompl import base as ob, geometric as og, util as ou    # loaded by the first route

    global _seeded
    if not _seeded:
        ou.RNG.setSeed(SEED)
        _seeded = True
    ou.setLogLevel(ou.LOG_NONE)
    start, goal = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
    q = start.copy()

    def coordinates(x, y, theta):
        q[:3] = x, y, theta
        if q.size > 3:                     # a trailer's heading along the vehicle's
            q[3:] = start[3:]
        return q

    # a state whose point (x, y) is farther from every obstacle's bounding box than any body
    # reaches is clear without the geometry
    reach = max(math.hypot(b.length, b.width) / 2 + abs(b.behind) for b in obstacles.bodies) + obstacles.margin
    boxes = [(*np.min(p, axis=0), *np.max(p, axis=0)) for p in map(np.asarray, obstacles.polygons)]

    def clear(x, y, theta) -> bool:
        if all(math.hypot(max(x0 - x, 0.0, x - x1), max(y0 - y, 0.0, y - y1)) >= reach for x0, y0, x1, y1 in boxes):
            return True
        return bool(obstacles.clearances(mechanism, coordinates(x, y, theta)[None, :]).min() >= obstacles.margin)

    space = ob.DubinsStateSpace(slowest / turn) if slowest > 0 else ob.ReedsSheppStateSpace(TURNING_RADIUS)
    bounds = ob.RealVectorBounds(2)
    for i in range(2):
        bounds.setLow(i, float(low[i]))
        bounds.setHigh(i, float(high[i]))
    space.setBounds(bounds)
    setup = og.SimpleSetup(space)
    setup.setStateValidityChecker(lambda s: clear(s.getX(), s.getY(), s.getYaw()))
    ends = []
    for q_end in (start, goal):
        state = space.allocState()
        state.setX(float(q_end[0]))
        state.setY(float(q_end[1]))
        state.setYaw(float(q_end[2]))
        ends.append(state)
    setup.setStartAndGoalStates(ends[0], ends[1])
    info = setup.getSpaceInformation()
    info.setStateValidityCheckingResolution(CHECK_RESOLUTION)
    setup.setPlanner(og.RRTConnect(info))
    setup.setup()
    samples = [0]

    def enough() -> bool:
        samples[0] += 1
        return samples[0] > MAX_SAMPLES

    setup.solve(ob.PlannerTerminationCondition(enough))
    if not setup.haveExactSolutionPath():
        return f"OMPL's RRT-Connect found no route clear of the obstacles in {MAX_SAMPLES} samples"
    setup.simplifySolution()
    path = setup.getSolutionPath()
    length = float(path.length())
    path.interpolate(max(2, int(math.ceil(POINTS_PER_UNIT * length))))
    states = np.array([[s.getX(), s.getY(), s.getYaw()] for s in (path.getState(i) for i in range(path.getStateCount()))])
    return played(states, speed, turn, length)


def played(states: np.ndarray, speed: float, turn: float, length: float) -> Route:
    """A route's states played at most at ``speed`` and ``turn``: each step's signed advance
    along the heading and its turn, in the least time that keeps both rates in their bounds.

    Parameters
    ----------
    states : numpy.ndarray
        ``(x, y, θ)`` along the route.
    speed, turn : float
        The bounds.
    length : float
        The route's length.

    Returns
    -------
    Route
        The route in time.
    """
    d = np.diff(states[:, :2], axis=0)
    mid = states[:-1, 2] + 0.5 * np.angle(np.exp(1j * np.diff(states[:, 2])))
    advance = d[:, 0] * np.cos(mid) + d[:, 1] * np.sin(mid)
    dtheta = np.angle(np.exp(1j * np.diff(states[:, 2])))
    dt = np.maximum(np.maximum(np.abs(advance) / speed, np.abs(dtheta) / turn), 1e-12)
    rates = np.stack([advance / dt, dtheta / dt], axis=1)
    return Route(states, np.concatenate([[0.0], np.cumsum(dt)]), rates, length)
