"""A route among obstacles on a lattice of poses: the quickest chain of straight moves and turns
in place, as the first guess of a local method.

A sampling planner finds a route, not the quickest: through a narrow passage it mostly finds
the wide way round. :func:`route` searches a lattice instead. Its poses are the points of a
square grid anchored at the start (spacing :data:`CELL_OF_WIDTH` of the narrowest body's
width), inside the workspace, times :data:`HEADINGS`, the directions of the eight
neighbouring points. Its moves are a step to the neighbouring point the heading faces, forward
or back, at the top speed, and a turn in place to the next heading at the top turning rate.
A pose or move is kept where every body clears every obstacle by the margin along it: a
step's bodies sweep the box they span (its length grown by the step), a turn's are checked at
:data:`TURN_CHECKS` headings between, with the margin grown by the most a body leaves the
boxes checked. SciPy's Dijkstra finds the quickest chain from the start to the pose nearest
the goal (shapely's distances keep the poses and moves clear), played as the speed and
turning rate of a vehicle whose coordinates begin ``(x, y, θ)``: a unicycle follows it
exactly, a local method then shortens it to the least time in its class of routes.

The search has no random element: the same instance gives the same route on every run.
"""
from __future__ import annotations

import math

import numpy as np

from ..model.obstacles import Body, body_corners
from .plane_route import Route, played

#: The moves to the eight neighbouring points of the grid, in steps of the grid.
MOVES = ((1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1))
#: The lattice's headings: the directions of :data:`MOVES`.
HEADINGS = len(MOVES)
#: The grid's spacing, as a fraction of the narrowest body's width.
CELL_OF_WIDTH = 0.4
#: The lattice's poses at most: a larger workspace is searched on a coarser grid.
MAX_POSES = 300_000
#: Headings checked within each turn between two of :data:`MOVES`.
TURN_CHECKS = 4


def route(obstacles, mechanism, start, goal, low, high, speed: float, turn: float) -> Route | str:
    """The quickest route of the lattice from ``start`` to ``goal`` (their ``(x, y, θ)``)
    inside the box ``low ≤ (x, y) ≤ high`` clear of the obstacles, played at most at ``speed``
    and ``turn`` (see the module); or why there is none.

    Parameters
    ----------
    obstacles : Obstacles
        The obstacles, the vehicle's bodies and the margin kept.
    mechanism : Mechanism
        The vehicle (its first coordinates ``x, y, θ``; its other coordinates kept at the
        start's along the route).
    start, goal : array_like
        The mechanism's coordinates at the ends.
    low, high : array_like
        The workspace's corners.
    speed, turn : float
        The top speed and turning rate (positive).

    Returns
    -------
    Route or str
        The route, or the reason there is none.
    """
    import shapely
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

    start, goal = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    moves = np.array(MOVES, dtype=float)
    headings = np.arctan2(moves[:, 1], moves[:, 0])
    cell = CELL_OF_WIDTH * min(b.width for b in obstacles.bodies)
    area = float(np.prod(high - low))
    cell = max(cell, math.sqrt(area * HEADINGS / MAX_POSES))
    lo = np.ceil((low - start[:2]) / cell - 1e-9).astype(int)
    hi = np.floor((high - start[:2]) / cell + 1e-9).astype(int)
    xs = start[0] + cell * np.arange(lo[0], hi[0] + 1)
    ys = start[1] + cell * np.arange(lo[1], hi[1] + 1)
    nx, ny = xs.size, ys.size
    if nx == 0 or ny == 0:
        return "the start is outside the workspace"
    X, Y = (a.ravel() for a in np.meshgrid(xs, ys, indexing="ij"))
    n = nx * ny
    polygons = [np.asarray(p) for p in obstacles.polygons]
    union = shapely.union_all(shapely.polygons(polygons)) if polygons else None

    def clear(x, y, theta, longer=0.0, wider_margin=0.0) -> np.ndarray:
        if union is None:
            return np.ones(x.size, dtype=bool)
        q = np.tile(start, (x.size, 1))
        q[:, 0], q[:, 1], q[:, 2] = x, y, theta
        ok = np.ones(x.size, dtype=bool)
        for b in obstacles.bodies:
            body = Body(b.length + longer, b.width, b.x, b.y, b.heading, b.behind)
            placed = shapely.polygons(body_corners(mechanism, q, body))
            ok &= shapely.distance(placed, union) >= obstacles.margin + wider_margin
        return ok

    # the poses, and the turns in place from each heading to the next
    turned = np.angle(np.exp(1j * (np.roll(headings, -1) - headings)))
    reach = max(math.hypot(b.length, b.width) / 2 + abs(b.behind) for b in obstacles.bodies)
    # between two headings checked a body's corners leave the two boxes by at most the sagitta
    sagitta = reach * (1.0 - math.cos(float(np.abs(turned).max()) / TURN_CHECKS / 2))
    posed = np.stack([clear(X, Y, np.full(n, h)) for h in headings])
    turns = []
    for k in range(HEADINGS):
        ok = posed[k] & posed[(k + 1) % HEADINGS]
        for m in range(1, TURN_CHECKS):
            idx = np.nonzero(ok)[0]
            ok[idx] = clear(X[idx], Y[idx], np.full(idx.size, headings[k] + turned[k] * m / TURN_CHECKS),
                            wider_margin=sagitta)
        turns.append(ok)
    # the steps along each heading: the box a body spans between the two poses
    rows, cols, cost = [], [], []
    I, J = np.divmod(np.arange(n), ny)
    for k, (di, dj) in enumerate(MOVES):
        i2, j2 = I + di, J + dj
        src = np.nonzero((i2 >= 0) & (i2 < nx) & (j2 >= 0) & (j2 < ny) & posed[k])[0]
        dst = i2[src] * ny + j2[src]
        keep = posed[k][dst]
        src, dst = src[keep], dst[keep]
        length = cell * math.hypot(di, dj)
        keep = clear(X[src] + 0.5 * cell * di, Y[src] + 0.5 * cell * dj, np.full(src.size, headings[k]),
                     longer=length)
        src, dst = src[keep], dst[keep]
        rows.append(src * HEADINGS + k)
        cols.append(dst * HEADINGS + k)
        cost.append(np.full(src.size, length / speed))
        at = np.nonzero(turns[k])[0]
        rows.append(at * HEADINGS + k)
        cols.append(at * HEADINGS + (k + 1) % HEADINGS)
        cost.append(np.full(at.size, abs(turned[k]) / turn))
    rows, cols, cost = map(np.concatenate, (rows, cols, cost))
    graph = coo_matrix((cost, (rows, cols)), shape=(n * HEADINGS, n * HEADINGS)).tocsr()

    def nearest(q, where) -> list[int]:
        """The poses at the point of the grid nearest ``q`` (``where``: clear ones), the
        nearest heading first."""
        i = int(np.clip(round((q[0] - xs[0]) / cell), 0, nx - 1))
        j = int(np.clip(round((q[1] - ys[0]) / cell), 0, ny - 1))
        order = np.argsort(np.abs(np.angle(np.exp(1j * (headings - q[2])))), kind="stable")
        return [(i * ny + j) * HEADINGS + int(k) for k in order if where[int(k)][i * ny + j]]

    sources, targets = nearest(start, posed)[:2], nearest(goal, posed)[:2]
    if not sources:
        return "no pose of the lattice at the start is clear of the obstacles"
    if not targets:
        return "no pose of the lattice at the goal is clear of the obstacles"
    times, previous, origin = dijkstra(graph, directed=False, indices=sources, return_predecessors=True,
                                       min_only=True)
    target = min(targets, key=lambda t: times[t])
    if not math.isfinite(times[target]):
        return (f"no route on the lattice ({nx}×{ny} points {cell:.3g} apart, {HEADINGS} headings) "
                f"from the start to the goal clear of the obstacles")
    chain = [target]
    while chain[-1] != origin[target]:
        chain.append(int(previous[chain[-1]]))
    point, k = np.divmod(np.array(chain[::-1]), HEADINGS)
    states = np.column_stack([np.concatenate([[start[0]], X[point], [goal[0]]]),
                              np.concatenate([[start[1]], Y[point], [goal[1]]]),
                              np.unwrap(np.concatenate([[start[2]], headings[k], [goal[2]]]))])
    length = float(np.hypot(*np.diff(states[:, :2], axis=0).T).sum())
    return played(states, speed, turn, length)
