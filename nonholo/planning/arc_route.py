"""A route among obstacles for a vehicle that only drives forward: the quickest chain of arcs
a search over its poses finds (a hybrid A*), as the first guess of a local method.

A vehicle whose speed stays above zero cannot turn in place, so the lattice of straight steps
and turns (:mod:`nonholo.planning.lattice_route`) gives it no route it can follow, and Dubins
curves turn as tightly both ways, where its turning rate may not. :func:`route` searches its
poses instead. From a pose the moves are arcs held for the time that covers :data:`ARC_CELLS`
cells at the top speed: at the top speed and at the least, each with the turning rate at its
bounds, at half of them and at zero (:data:`TURNING`). An arc is kept where every body clears
every obstacle, by the margin grown by half the most a body moves between the states checked,
at :data:`ARC_CHECKS` states along it (shapely's distances). Poses are merged on cells of
:data:`CELL_OF_WIDTH` of the narrowest body's width and :data:`HEADING_BINS` headings. The
cost is time; the heuristic, the distance to the goal through the free cells at the top speed
(SciPy's Dijkstra on the grid), weighted by :data:`GREEDY`. The search ends at a pose within
:data:`GOAL_CELLS` cells and a heading bin of the goal, within :data:`MAX_EXPANSIONS` poses
expanded (a budget of work, not of wall time); the route is the chain of arcs, which the
vehicle follows exactly, and the local method brings onto the goal.

The search has no random element: the same instance gives the same route on every run.
"""
from __future__ import annotations

import heapq
import math

import numpy as np

from ..model.obstacles import body_corners
from .plane_route import Route

#: The grid's spacing, as a fraction of the narrowest body's width.
CELL_OF_WIDTH = 0.4
#: Heading bins the poses are merged in.
HEADING_BINS = 32
#: The turning rates of the arcs, as fractions of its bound on their side.
TURNING = (-1.0, -0.5, 0.0, 0.5, 1.0)
#: Cells an arc covers at the top speed.
ARC_CELLS = 2.0
#: States checked along an arc (evenly spaced, its end the last).
ARC_CHECKS = 3
#: Cells from the goal the search may end at.
GOAL_CELLS = 1.0
#: The heuristic's weight (above 1: greedier, fewer poses expanded).
GREEDY = 1.5
#: Poses expanded at most.
MAX_EXPANSIONS = 40_000


class FreeDistance:
    """The distance to the goal through the free cells of a grid over the workspace: SciPy's
    Dijkstra over each cell's eight neighbours, a cell free where its point is half the
    narrowest body's width from every obstacle; where no free chain reaches the goal, ten
    times the straight distance (the searches' heuristic).

    Parameters
    ----------
    union : shapely geometry or None
        The obstacles, as one.
    bodies : sequence of Body
        The vehicle's bodies.
    low, high : numpy.ndarray
        The workspace's corners.
    cell : float
        The grid's spacing.
    goal : numpy.ndarray
        The goal (its first two entries the position).
    """

    def __init__(self, union, bodies, low, high, cell: float, goal):
        import shapely
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import dijkstra

        nx, ny = (np.floor((np.asarray(high) - low) / cell).astype(int) + 1)
        X, Y = np.meshgrid(low[0] + cell * np.arange(nx), low[1] + cell * np.arange(ny), indexing="ij")
        free = (np.ones(X.size, dtype=bool) if union is None else
                shapely.distance(shapely.points(X.ravel(), Y.ravel()), union) >= 0.5 * min(b.width for b in bodies))
        index = np.arange(X.size).reshape(nx, ny)
        rows, cols, w = [], [], []
        for di, dj in ((1, 0), (0, 1), (1, 1), (1, -1)):
            a = index[max(0, -di):nx - max(0, di), max(0, -dj):ny - max(0, dj)].ravel()
            b = index[max(0, di):nx - max(0, -di), max(0, dj):ny - max(0, -dj)].ravel()
            keep = free[a] & free[b]
            rows.append(a[keep]), cols.append(b[keep]), w.append(np.full(keep.sum(), cell * math.hypot(di, dj)))
        graph = coo_matrix((np.concatenate(w), (np.concatenate(rows), np.concatenate(cols))), shape=(X.size, X.size))
        self.cell, self.low, self.last = cell, np.asarray(low, dtype=float), (int(nx) - 1, int(ny) - 1)
        self.goal = np.asarray(goal, dtype=float)[:2]
        self.index = index
        self.far = dijkstra(graph.tocsr(), directed=False, indices=index[self.cell_of(*self.goal)])

    def cell_of(self, x: float, y: float) -> tuple[int, int]:
        """The grid cell nearest a point (clipped to the grid).

        Parameters
        ----------
        x, y : float
            The point.

        Returns
        -------
        tuple of int
            The cell's indices.
        """
        return (min(max(round((x - self.low[0]) / self.cell), 0), self.last[0]),
                min(max(round((y - self.low[1]) / self.cell), 0), self.last[1]))

    def cells(self, xy: np.ndarray) -> np.ndarray:
        """:meth:`cell_of` of many points.

        Parameters
        ----------
        xy : numpy.ndarray
            The points, ``(n, 2)``.

        Returns
        -------
        numpy.ndarray
            The cells' indices, ``(n, 2)``.
        """
        return np.clip(np.rint((np.asarray(xy) - self.low) / self.cell).astype(int), 0, self.last)

    def __call__(self, x: float, y: float) -> float:
        """The distance from a point.

        Parameters
        ----------
        x, y : float
            The point.

        Returns
        -------
        float
            The distance to the goal.
        """
        d = self.far[self.index[self.cell_of(x, y)]]
        return d if math.isfinite(d) else 10.0 * math.hypot(x - self.goal[0], y - self.goal[1])

    def at(self, xy: np.ndarray, cells: np.ndarray | None = None) -> np.ndarray:
        """The distances from many points.

        Parameters
        ----------
        xy : numpy.ndarray
            The points, ``(n, 2)``.
        cells : numpy.ndarray, optional
            Their :meth:`cells`, if known.

        Returns
        -------
        numpy.ndarray
            The distances to the goal, ``(n,)``.
        """
        cells = self.cells(xy) if cells is None else cells
        d = self.far[self.index[cells[:, 0], cells[:, 1]]]
        return np.where(np.isfinite(d), d, 10.0 * np.hypot(xy[:, 0] - self.goal[0], xy[:, 1] - self.goal[1]))


def chain_to(nodes: list, found: int) -> list[int]:
    """The nodes of a search from its first to ``found``, each node ``(pose, parent, move)``.

    Parameters
    ----------
    nodes : list
        The search's nodes (the first the start's, its parent ``-1``).
    found : int
        The last node.

    Returns
    -------
    list of int
        The nodes after the first, in order.
    """
    chain = []
    while found > 0:
        chain.append(found)
        found = nodes[found][1]
    return chain[::-1]


def arcs(moves: np.ndarray, tau: float, fractions: np.ndarray) -> np.ndarray:
    """The displacements ``(dx, dy, dθ)`` of arcs from the pose ``(0, 0, 0)``.

    Parameters
    ----------
    moves : numpy.ndarray
        Speeds and turning rates ``(v, ω)``, ``(m, 2)``.
    tau : float
        The arcs' duration (s).
    fractions : numpy.ndarray
        The fractions of ``tau`` they are read at.

    Returns
    -------
    numpy.ndarray
        ``(m, len(fractions), 3)``.
    """
    v, w = moves[:, :1], moves[:, 1:]
    t = tau * np.asarray(fractions, dtype=float)[None, :]
    turn = w * t
    small = np.abs(turn) < 1e-9
    safe = np.where(small, 1.0, w)
    # x = v sin(ωt)/ω, y = v (1 − cos ωt)/ω; straight where ω = 0
    dx = np.where(small, v * t, v * np.sin(turn) / safe)
    dy = np.where(small, 0.5 * v * w * t ** 2, v * (1.0 - np.cos(turn)) / safe)
    return np.stack([dx, dy, turn], axis=-1)


def route(obstacles, mechanism, start, goal, low, high, lows, highs) -> Route | str:
    """The route of the search from ``start`` to ``goal`` (their ``(x, y, θ)``) inside the box
    ``low ≤ (x, y) ≤ high`` clear of the obstacles (see the module); or why there is none.

    Parameters
    ----------
    obstacles : Obstacles
        The obstacles, the vehicle's bodies and the margin kept.
    mechanism : Mechanism
        The vehicle (coordinates ``x, y, θ``; inputs its speed and turning rate).
    start, goal : array_like
        Its coordinates at the ends.
    low, high : array_like
        The workspace's corners.
    lows, highs : array_like
        The bounds of the speed (``0 < low``) and of the turning rate (``low < 0 < high``).

    Returns
    -------
    Route or str
        The route (its ``rates`` the speed and turning rate), or the reason there is none.
    """
    import shapely

    start, goal = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    (slowest, turn_low), (speed, turn_high) = np.asarray(lows, dtype=float), np.asarray(highs, dtype=float)
    k = start.size
    cell = CELL_OF_WIDTH * min(b.width for b in obstacles.bodies)
    polygons = [np.asarray(p) for p in obstacles.polygons]
    union = shapely.union_all(shapely.polygons(polygons)) if polygons else None
    if union is not None:
        shapely.prepare(union)

    # -- the arcs from the pose at the origin, read at the states checked
    tau = ARC_CELLS * cell / speed
    moves = np.array([(v, f * (turn_high if f > 0 else -turn_low)) for v in dict.fromkeys((speed, slowest))
                      for f in TURNING])
    fractions = np.arange(1, ARC_CHECKS + 1) / ARC_CHECKS
    table = arcs(moves, tau, fractions)                                     # (m, c, 3)
    reach = max(math.hypot(b.length, b.width) / 2 + abs(b.behind) for b in obstacles.bodies)
    between = tau / ARC_CHECKS
    margin = obstacles.margin + 0.5 * (speed * between + reach * max(turn_high, -turn_low) * between)

    def placed(pose, rows):
        x, y, th = pose
        c, s = math.cos(th), math.sin(th)
        out = np.empty(rows.shape[:-1] + (k,))
        out[...] = start
        out[..., 0] = x + c * rows[..., 0] - s * rows[..., 1]
        out[..., 1] = y + s * rows[..., 0] + c * rows[..., 1]
        out[..., 2] = th + rows[..., 2]
        return out

    def clear(q):
        q = q.reshape(-1, k)
        ok = np.all((q[:, :2] >= low) & (q[:, :2] <= high), axis=1)
        if union is not None:
            for b in obstacles.bodies:
                ok &= ~shapely.dwithin(shapely.polygons(body_corners(mechanism, q, b)), union, margin)
        return ok

    # -- the heuristic: the distance to the goal through the free cells, at the top speed
    far = FreeDistance(union, obstacles.bodies, low, high, cell, goal)
    cell_of = far.cell_of

    def heuristic(x, y):
        return far(x, y) / speed

    bin_width = 2.0 * np.pi / HEADING_BINS

    def key(q):
        return (*cell_of(q[0], q[1]), round(q[2] / bin_width) % HEADING_BINS)

    def near_goal(q):
        return (math.hypot(q[0] - goal[0], q[1] - goal[1]) <= GOAL_CELLS * cell
                and abs(math.remainder(q[2] - goal[2], 2.0 * np.pi)) <= bin_width)

    # -- the search
    pose0 = tuple(float(v) for v in start[:3])
    nodes = [(pose0, -1, -1)]                      # pose, parent, move
    g = {key(pose0): 0.0}
    heap = [(GREEDY * heuristic(*pose0[:2]), 0.0, 0)]
    expanded, found = 0, None
    while heap and expanded < MAX_EXPANSIONS:
        _, cost, n = heapq.heappop(heap)
        pose = nodes[n][0]
        if cost > g.get(key(pose), math.inf) + 1e-12:
            continue
        expanded += 1
        if near_goal(pose):
            found = n
            break
        states = placed(pose, table)                                       # (m, c, k)
        ok = np.nonzero(clear(states).reshape(len(moves), ARC_CHECKS).all(axis=1))[0]
        if not ok.size:
            continue
        ends = states[ok, -1, :3]
        cells = far.cells(ends[:, :2])
        bins = np.rint(ends[:, 2] / bin_width).astype(int) % HEADING_BINS
        h = far.at(ends[:, :2], cells) / speed
        c = cost + tau
        for m, new, i, j, b, hm in zip(ok.tolist(), ends.tolist(), cells[:, 0].tolist(), cells[:, 1].tolist(),
                                       bins.tolist(), h.tolist()):
            kk = (i, j, b)
            if c < g.get(kk, math.inf) - 1e-12:
                g[kk] = c
                nodes.append((tuple(new), n, m))
                heapq.heappush(heap, (c + GREEDY * hm, c, len(nodes) - 1))
    if found is None:
        return (f"no route of the vehicle's arcs clear of the obstacles ({expanded} poses expanded"
                f"{', the budget' if expanded >= MAX_EXPANSIONS else ''})")
    chain = chain_to(nodes, found)
    states = np.array([pose0] + [nodes[n][0] for n in chain])
    rates = np.array([moves[nodes[n][2]] for n in chain]).reshape(-1, 2)
    times = tau * np.arange(len(chain) + 1)
    return Route(states, times, rates, float(np.sum(rates[:, 0]) * tau))
