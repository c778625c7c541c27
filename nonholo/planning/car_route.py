"""A route among obstacles for a car that steers (and pulls trailers): a search over its poses by
short arcs of its own kinematics, as the first guess of a local method.

A car turns no tighter than its steering allows and pulls its trailers behind it, so neither
the lattice of straight steps and turns in place (:mod:`nonholo.planning.lattice_route`) nor
the curves of a car alone give it a route it can follow. :func:`search` searches its poses
(a hybrid A*, with the grid, bins, budget and heuristic of :mod:`nonholo.planning.arc_route`,
weighted by its own :data:`GREEDY`). From a pose the moves are arcs at the top speed forward
and at the top speed back (:data:`STEERING`: the steering at these fractions of its bound),
each held for the time that covers ``ARC_CELLS`` cells forward; the car stops to steer
between arcs, at the top steering rate (an infinite one: it steers at once, as where the
steering angle is an action). An arc is a whole number of explicit Euler steps of the
mechanism's own rates (of a given step, the one a benchmark judges the motion by, or
:data:`ARC_STEPS` of them), computed once from the pose at the origin: the car's pose moves
with the pose exactly, and the trailers' headings change as the table's, interpolated in the
hitch angle (:data:`TABLE_BINS` of them; exact to rounding for one trailer at the table's
angles). A pose is kept where every body clears every obstacle by the margin at every step
(:class:`~nonholo.planning.clearance_grid.ClearanceGrid` proves most clear, shapely's
distances settle the rest). Poses are merged on the grid's cells, the heading bins and the
hitch angles' bins. The cost is time, the heuristic the distance to the goal through the
free cells at the top speed (:class:`~nonholo.planning.arc_route.FreeDistance`) — at least
the way through the point :data:`APPROACH` vehicle's lengths behind the goal along its
heading, where that is free, so that the car and its trailers arrive in line with it. The
search ends at a pose within ``GOAL_CELLS`` cells and a bin of each angle of the goal,
within ``MAX_EXPANSIONS`` poses expanded (a budget of work, not of wall time); the result is
the chain of arcs and the states at their ends.

The car's coordinates are ``(x, y, θ, φ, θ₁, …)`` — the position, heading, steering angle and
the trailers' headings — and its inputs the speed and the steering rate.
"""
from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np

from ..model.obstacles import body_corners, body_pose
from .arc_route import ARC_CELLS, CELL_OF_WIDTH, GOAL_CELLS, HEADING_BINS, MAX_EXPANSIONS, FreeDistance, chain_to
from .clearance_grid import ClearanceGrid

#: Bins of each hitch angle ``θ − θ₁`` (over a full turn) the poses are merged in.
HITCH_BINS = 24
#: Hitch angles (over a full turn) the arcs' table is computed at, and interpolated between.
TABLE_BINS = 96
#: The steering of the arcs, as fractions of its bound.
STEERING = (-1.0, -0.5, 0.0, 0.5, 1.0)
#: The heuristic counts the way through the point this many vehicle's lengths behind the goal.
APPROACH = 0.25
#: Euler steps of an arc, where no step is given.
ARC_STEPS = 8
#: The clearance grid's spacing, as a fraction of the grid's cell.
GRID_OF_CELL = 0.25
#: The heuristic's weight: greedier than the unicycle's search (the route is a first guess the
#: sparse program of :mod:`nonholo.dynobench.sparse_steps` shortens within its class of
#: motions; a greedier search finds one sooner).
GREEDY = 3.0


def _wrap(a):
    return (np.asarray(a) + np.pi) % (2.0 * np.pi) - np.pi


@dataclass(frozen=True)
class Arcs:
    """The chain of arcs :func:`search` found.

    Parameters
    ----------
    tau : float
        Each arc's duration (s).
    moves : numpy.ndarray
        Each arc's speed and steering angle ``(v, φ)``, ``(n, 2)``.
    states : numpy.ndarray
        The car's coordinates at the arcs' ends, the start's first, ``(n + 1, k)``.
    steps : int
        The Euler steps of an arc (each ``tau / steps`` long).
    """

    tau: float
    moves: np.ndarray
    states: np.ndarray
    steps: int = ARC_STEPS


def search(obstacles, mechanism, start, goal, low, high, speed: float, reverse: float, steering: float,
           steering_rate: float, step: float | None = None) -> Arcs | str:
    """The chain of arcs of the search from ``start`` to ``goal`` inside the box
    ``low ≤ (x, y) ≤ high`` clear of the obstacles (see the module); or why there is none.

    Parameters
    ----------
    obstacles : Obstacles
        The obstacles, the car's bodies and the margin kept.
    mechanism : Mechanism
        The car (coordinates ``x, y, θ, φ, θ₁, …``; inputs speed and steering rate).
    start, goal : array_like
        Its coordinates at the ends.
    low, high : array_like
        The workspace's corners.
    speed, reverse : float
        The top speeds forward and back (positive).
    steering, steering_rate : float
        The steering angle's bound and its rate's.
    step : float, optional
        The Euler step of the arcs (default: an arc's time over :data:`ARC_STEPS`).

    Returns
    -------
    Arcs or str
        The arcs, or the reason there is none.

    Raises
    ------
    ValueError
        If ``step`` is given and not a positive number.
    """
    import shapely

    start, goal = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    k = start.size
    trailers = list(range(4, k))
    cell = CELL_OF_WIDTH * min(b.width for b in obstacles.bodies)
    polygons = [np.asarray(p) for p in obstacles.polygons]
    union = shapely.union_all(shapely.polygons(polygons)) if polygons else None
    if union is not None:
        shapely.prepare(union)

    # -- the arcs: (direction, steering) held for tau, in whole Euler steps
    tau = ARC_CELLS * cell / speed
    if step is None:
        n_steps, h = ARC_STEPS, tau / ARC_STEPS
    else:
        if not (isinstance(step, (int, float)) and step > 0 and math.isfinite(step)):
            raise ValueError(f"step must be a positive number, got {step!r}")
        n_steps, h = max(1, math.ceil(tau / step - 1e-9)), float(step)
        tau = n_steps * h
    moves = [(v, f * steering) for v in (speed, -reverse) for f in STEERING]
    R = np.eye(3)

    # table[m, j, i]: the state after step i + 1 of move m from the pose at the origin, heading
    # 0, every trailer at the hitch angle of bin j; the trailers' columns their change
    angles = (np.arange(TABLE_BINS) + 0.5) * (2.0 * np.pi / TABLE_BINS) - np.pi
    table = np.empty((len(moves), TABLE_BINS, n_steps, k))
    for m, (v, phi) in enumerate(moves):
        for j, beta in enumerate(angles):
            q = np.zeros(k)
            q[3] = phi
            q[trailers] = -beta
            for i in range(n_steps):
                q = q + h * mechanism.rates(R, q, np.array([v, 0.0]))
                table[m, j, i] = q
            table[m, j, :, trailers] += beta

    def placed(q):
        """The moves' states from the pose ``q`` (the table interpolated in its hitch angle)."""
        if trailers:
            f = (_wrap(q[2] - q[trailers[0]]) + np.pi) / (2.0 * np.pi / TABLE_BINS) - 0.5
            j0 = int(math.floor(f))
            w = f - j0
            rows = (1.0 - w) * table[:, j0 % TABLE_BINS] + w * table[:, (j0 + 1) % TABLE_BINS]
        else:
            rows = table[:, 0]
        x, y, th = q[0], q[1], q[2]
        c, s = math.cos(th), math.sin(th)
        out = rows.copy()
        out[..., 0] = x + c * rows[..., 0] - s * rows[..., 1]
        out[..., 1] = y + s * rows[..., 0] + c * rows[..., 1]
        out[..., 2] = rows[..., 2] + th
        out[..., trailers] = rows[..., trailers] + q[trailers]
        return out

    grid = (ClearanceGrid(union, obstacles.bodies, low, high, GRID_OF_CELL * cell, obstacles.margin)
            if union is not None else None)

    def clear(q):
        q = q.reshape(-1, k)
        ok = np.all((q[:, :2] >= low) & (q[:, :2] <= high), axis=1)
        if union is None:
            return ok
        for i, b in enumerate(obstacles.bodies):
            centres, headings = body_pose(mechanism, q, b)
            unsure = ok & ~grid.clear(centres, headings, i)
            if unsure.any():
                d = shapely.distance(shapely.polygons(body_corners(mechanism, q[unsure], b)), union)
                ok[unsure] = d >= obstacles.margin
        return ok

    # -- the heuristic: the distance to the goal through the free cells, at the top speed
    far = FreeDistance(union, obstacles.bodies, low, high, cell, goal)
    # ... and, where the vehicle's length behind the goal is free, at least the distance
    # through that point: the car and its trailers arrive in line with the goal's heading
    length = max(b.behind + b.length / 2 for b in obstacles.bodies) + obstacles.bodies[0].length / 2
    behind = goal[:2] - APPROACH * length * np.array([math.cos(goal[2]), math.sin(goal[2])])
    approach = FreeDistance(union, obstacles.bodies, low, high, cell, behind)
    if not (np.all((behind >= low) & (behind <= high)) and approach(*goal[:2]) <= 1.5 * length):
        approach = None

    def remaining(xy):
        """The heuristic's time to the goal from positions ``(n, 2)``."""
        d = far.at(xy)
        if approach is not None:
            d = np.maximum(d, approach.at(xy) + APPROACH * length)
        return d / speed

    heading_bin, hitch_bin = 2.0 * np.pi / HEADING_BINS, 2.0 * np.pi / HITCH_BINS

    def keys(q):
        """The bins of states ``(n, k)``: cells, heading bin, hitch angles' bins."""
        cols = [np.rint((q[:, 0] - low[0]) / cell), np.rint((q[:, 1] - low[1]) / cell),
                np.rint(_wrap(q[:, 2]) / heading_bin) % HEADING_BINS]
        cols += [np.floor((_wrap(q[:, 2] - q[:, t]) + np.pi) / hitch_bin) % HITCH_BINS for t in trailers]
        return list(map(tuple, np.column_stack(cols).astype(int).tolist()))

    def near_goal(q):
        if math.hypot(q[0] - goal[0], q[1] - goal[1]) > GOAL_CELLS * cell:
            return False
        if abs(_wrap(q[2] - goal[2])) > heading_bin:
            return False
        return all(abs(_wrap(q[t] - goal[t])) <= 0.5 * hitch_bin for t in trailers)

    # -- the search
    q0 = start.copy()
    q0[3] = 0.0
    key0 = keys(q0[None, :])[0]
    nodes = [(q0, -1, None, key0)]                      # state, parent, move, bins
    g = {key0: 0.0}
    heap = [(GREEDY * float(remaining(q0[None, :2])[0]), 0.0, 0)]
    expanded, found = 0, None
    while heap and expanded < MAX_EXPANSIONS:
        _, cost, n = heapq.heappop(heap)
        q, _, _, kq = nodes[n]
        if cost > g.get(kq, math.inf) + 1e-12:
            continue
        expanded += 1
        if near_goal(q):
            found = n
            break
        states = placed(q)                                                   # (moves, steps, k)
        ok = np.nonzero(clear(states).reshape(len(moves), n_steps).all(axis=1))[0]
        if not ok.size:
            continue
        ends = states[ok, -1]
        rest = remaining(ends[:, :2])
        for m, new, kk, hm in zip(ok.tolist(), ends, keys(ends), rest.tolist()):
            c = cost + tau + abs(moves[m][1] - q[3]) / steering_rate
            if c < g.get(kk, math.inf) - 1e-12:
                g[kk] = c
                nodes.append((new, n, m, kk))
                heapq.heappush(heap, (c + GREEDY * hm, c, len(nodes) - 1))
    if found is None:
        return (f"no route of the car's arcs clear of the obstacles ({expanded} poses expanded"
                f"{', the budget' if expanded >= MAX_EXPANSIONS else ''})")
    chain = chain_to(nodes, found)
    return Arcs(tau, np.array([moves[nodes[n][2]] for n in chain], dtype=float).reshape(-1, 2),
                np.array([q0] + [nodes[n][0] for n in chain]), n_steps)
