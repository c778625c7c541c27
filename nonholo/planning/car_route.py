"""A route among obstacles for a car that steers (and pulls trailers): a search over its poses by
short arcs of its own kinematics, as the first guess of a local method.

A car turns no tighter than its steering allows and pulls its trailers behind it, so neither
the lattice of straight steps and turns in place (:mod:`nonholo.planning.lattice_route`) nor
the curves of a car alone give it a route it can follow. :func:`search` searches its poses
(a hybrid A*, with the grid, bins, budget and heuristic of
:mod:`nonholo.planning.arc_route`). From a pose the moves are arcs at the top speed forward
and at the top speed back (:data:`STEERING`: the steering at these fractions of its bound),
each held for the time that covers ``ARC_CELLS`` cells forward; the car stops to steer
between arcs, at the top steering rate (an infinite one: it steers at once, as where the
steering angle is an action). An arc's motion — the trailers' headings included — comes from
the mechanism's own rates, integrated once per arc and hitch angle (:data:`HITCH_BINS` of
them) and then moved with the pose. A pose is kept where every body clears every obstacle by
the margin at the arc's middle and end (shapely's distances). Poses are merged on the grid's
cells, the heading bins and the hitch angles' bins. The cost is time, the heuristic the
distance to the goal through the free cells at the top speed
(:class:`~nonholo.planning.arc_route.FreeDistance`). The search ends at a pose within
``GOAL_CELLS`` cells and a bin of each angle of the goal, within ``MAX_EXPANSIONS`` poses
expanded (a budget of work, not of wall time); the result is the chain of arcs: the car's
pose along it exact, the trailers' headings to the hitch angle's bins.

The car's coordinates are ``(x, y, θ, φ, θ₁, …)`` — the position, heading, steering angle and
the trailers' headings — and its inputs the speed and the steering rate.
"""
from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np

from ..model.obstacles import body_corners
from .arc_route import (ARC_CELLS, CELL_OF_WIDTH, GOAL_CELLS, GREEDY, HEADING_BINS, MAX_EXPANSIONS, FreeDistance,
                        chain_to)

#: Bins of each hitch angle ``θ − θ₁`` (over a full turn) the poses are merged in, and the
#: arcs integrated from.
HITCH_BINS = 24
#: The steering of the arcs, as fractions of its bound.
STEERING = (-1.0, -0.5, 0.0, 0.5, 1.0)
#: Integrator steps of an arc.
ARC_STEPS = 8


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
    """

    tau: float
    moves: np.ndarray
    states: np.ndarray


def search(obstacles, mechanism, start, goal, low, high, speed: float, reverse: float, steering: float,
           steering_rate: float) -> Arcs | str:
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

    Returns
    -------
    Arcs or str
        The arcs, or the reason there is none.
    """
    import shapely

    start, goal = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    k = start.size
    trailers = list(range(4, k))
    cell = CELL_OF_WIDTH * min(b.width for b in obstacles.bodies)
    polygons = [np.asarray(p) for p in obstacles.polygons]
    union = shapely.union_all(shapely.polygons(polygons)) if polygons else None

    # -- the arcs: (direction, steering) held for tau, from every hitch angle bin
    tau = ARC_CELLS * cell / speed
    moves = [(v, f * steering) for v in (speed, -reverse) for f in STEERING]
    hitch = (np.arange(HITCH_BINS) + 0.5) * (2.0 * np.pi / HITCH_BINS) - np.pi
    R = np.eye(3)

    def integrate(q, u, n=ARC_STEPS):
        h = tau / n
        path = [q]
        for _ in range(n):
            a = mechanism.rates(R, q, u)
            b = mechanism.rates(R, q + 0.5 * h * a, u)
            c = mechanism.rates(R, q + 0.5 * h * b, u)
            d = mechanism.rates(R, q + h * c, u)
            q = q + h / 6.0 * (a + 2 * b + 2 * c + d)
            path.append(q)
        return np.array(path)

    # table[m, j] = (middle, end) states of move m from the pose at the origin, heading 0,
    # every trailer at hitch angle bin j
    table = np.empty((len(moves), HITCH_BINS, 2, k))
    for m, (v, phi) in enumerate(moves):
        for j, beta in enumerate(hitch):
            q0 = np.zeros(k)
            q0[3] = phi
            q0[trailers] = -beta
            path = integrate(q0, np.array([v, 0.0]))
            table[m, j] = path[ARC_STEPS // 2], path[-1]

    def placed(pose, rows):
        """The table's states moved to ``pose`` (x, y, θ; trailers from the table)."""
        x, y, th = pose[0], pose[1], pose[2]
        c, s = math.cos(th), math.sin(th)
        out = rows.copy()
        out[..., 0] = x + c * rows[..., 0] - s * rows[..., 1]
        out[..., 1] = y + s * rows[..., 0] + c * rows[..., 1]
        out[..., 2] = rows[..., 2] + th
        out[..., trailers] = rows[..., trailers] + th
        return out

    def clear(q):
        q = q.reshape(-1, k)
        inside = np.all((q[:, :2] >= low) & (q[:, :2] <= high), axis=1)
        if union is None:
            return inside
        ok = inside.copy()
        for b in obstacles.bodies:
            d = shapely.distance(shapely.polygons(body_corners(mechanism, q, b)), union)
            ok &= d >= obstacles.margin
        return ok

    # -- the heuristic: the distance to the goal through the free cells
    far = FreeDistance(union, obstacles.bodies, low, high, cell, goal)

    def heuristic(x, y):
        return far(x, y) / speed

    def key(q):
        beta = _wrap(q[2] - q[trailers]) if trailers else ()
        return (int(round((q[0] - low[0]) / cell)), int(round((q[1] - low[1]) / cell)),
                int(round(_wrap(q[2]) / (2 * np.pi / HEADING_BINS))) % HEADING_BINS,
                *(int(np.floor((b + np.pi) / (2 * np.pi / HITCH_BINS))) % HITCH_BINS for b in np.atleast_1d(beta)))

    def near_goal(q):
        if math.hypot(q[0] - goal[0], q[1] - goal[1]) > GOAL_CELLS * cell:
            return False
        if abs(_wrap(q[2] - goal[2])) > 2 * np.pi / HEADING_BINS:
            return False
        return all(abs(_wrap(q[t] - goal[t])) <= 0.5 * 2 * np.pi / HITCH_BINS for t in trailers)

    # -- the search
    q0 = start.copy()
    q0[3] = 0.0
    nodes = [(q0, -1, None)]                      # state, parent, move
    g = {key(q0): 0.0}
    heap = [(GREEDY * heuristic(*q0[:2]), 0.0, 0)]
    expanded, found = 0, None
    while heap and expanded < MAX_EXPANSIONS:
        _, cost, n = heapq.heappop(heap)
        q, _, _ = nodes[n]
        if cost > g.get(key(q), math.inf) + 1e-12:
            continue
        expanded += 1
        if near_goal(q):
            found = n
            break
        betas = _wrap(q[2] - q[trailers[0]]) if trailers else 0.0
        j = int(np.floor((betas + np.pi) / (2 * np.pi / HITCH_BINS))) % HITCH_BINS
        states = placed(q, table[:, j])                          # (moves, 2, k)
        if trailers:
            # the table's trailers started at the bin's centre: moved by the pose's own offset
            states[..., trailers] += (q[trailers] - q[2]) + hitch[j]
        ok = clear(states).reshape(len(moves), 2).all(axis=1)
        for m in np.nonzero(ok)[0]:
            v, phi = moves[m]
            new = states[m, 1].copy()
            new[3] = phi
            step = tau + abs(phi - q[3]) / steering_rate
            c = cost + step
            kk = key(new)
            if c < g.get(kk, math.inf) - 1e-12:
                g[kk] = c
                nodes.append((new, n, m))
                heapq.heappush(heap, (c + GREEDY * heuristic(new[0], new[1]), c, len(nodes) - 1))
    if found is None:
        return (f"no route of the car's arcs clear of the obstacles ({expanded} poses expanded"
                f"{', the budget' if expanded >= MAX_EXPANSIONS else ''})")
    chain = chain_to(nodes, found)
    return Arcs(tau, np.array([moves[nodes[n][2]] for n in chain], dtype=float).reshape(-1, 2),
                np.array([q0] + [nodes[n][0] for n in chain]))
