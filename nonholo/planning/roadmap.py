"""Paths of orientations through the start's component, clear of ``Δ = 0``: the skeleton of
the global route (:mod:`nonholo.planning.route`).

The Jacobian planner is local: from a far start it may find no control, though every goal
with ``sgnΔ`` of the start is reachable (in the frame coordinates the admissible angular
velocities span a plane whose bracket fills R³). A path of orientations whose hops are
short and whose points keep well clear of ``Δ = 0`` splits such a problem into local ones.

The path comes from a *roadmap* of the mechanism (:class:`Roadmap`, built once per
mechanism and clearance and cached): :data:`ROADMAP_SAMPLES` Haar-uniform orientations
(a fixed seed: the same roadmap, hence the same routes, in every process) with
``|Δ| ≥ clearance``, each joined to its nearest neighbours (a k-d tree on unit
quaternions) by the geodesic between them where every point of it, at
:data:`RESOLUTION` rad, keeps ``sgnΔ ≥ clearance``. A query joins the start and the goal
to the roadmap the same way (near them the clearance may drop to what the start and goal
have: they may lie closer to ``Δ = 0`` than the roadmap), takes the cheapest path in
``∫ ds / |Δ|^power`` (Dijkstra, :mod:`scipy.sparse.csgraph`; see
:data:`CONDITIONING_POWERS` for why this cost), shortcuts it where a longer geodesic is
clear and no dearer, and cuts it into hops of at most ``max_hop`` rad along the
geodesics. A mechanism without a singular set has the geodesic itself.

Conventions: rotations are ``(n, 3, 3)`` matrices; distances are geodesic angles (rad).
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..spaces import so3

#: Orientations sampled for a roadmap (before those too close to ``Δ = 0`` are dropped).
ROADMAP_SAMPLES = 4000
#: Seed of the roadmap's samples.
ROADMAP_SEED = 20140901
#: Nearest neighbours a roadmap node is joined to (where the geodesic is clear).
NEIGHBOURS = 12
#: Longest roadmap edge (rad).
MAX_EDGE = 0.9
#: Spacing (rad) of the points at which a geodesic's clearance is checked.
RESOLUTION = 0.02
#: The clearance of a roadmap by default: this quantile of ``|Δ|`` over SO(3).
CLEARANCE_QUANTILE = 0.2
#: Longest hop (rad) of a route by default.
MAX_HOP = 3.2
#: Paths minimise ``∫ ds / |Δ|^power``, ``power`` one of these (the first by default; the
#: global route tries the next while it fails, e.g. too ill-conditioned to certify): an
#: open-loop motion amplifies errors by about ``exp(c ∫ |ω| dt / |Δ|)`` (``|∂L/∂R| ~
#: |L|/|Δ|``), so a path that keeps far from ``Δ = 0`` is better conditioned than a shorter
#: one that does not; a higher power keeps farther away at the price of length.
CONDITIONING_POWERS = (1.0, 2.0, 3.0, 0.5, 4.0)
#: With stroke limits, roadmap edges keep at least this clearance from them (geometry
#: units): a hop planned along an edge strays from its geodesic.
LEG_CLEARANCE = 0.02
#: Edges whose points are checked against stroke limits at once (bounds the memory).
EDGE_CHUNK = 4096


def _angles(qa: np.ndarray, qb: np.ndarray) -> np.ndarray:
    """Geodesic angles between unit quaternions (rows), ``2 arccos |qa·qb|``."""
    return 2.0 * np.arccos(np.clip(np.abs(np.sum(qa * qb, axis=-1)), 0.0, 1.0))


def _profile(mech, sign: float, Ra: np.ndarray, Rb: np.ndarray, points: int | None = None, legs=None):
    """``sgnΔ`` at ``points`` evenly spaced points (ends included; default: every
    :data:`RESOLUTION` rad of the longest) of the geodesic of each pair ``(Ra[e], Rb[e])``,
    ``(E, points)``, the geodesics' lengths ``(E,)`` and, with stroke limits ``legs``
    (:class:`~nonholo.model.limits.LegLimits`), the least clearance of each from them (``(E,)``;
    else ``None``)."""
    v = so3.turns(Ra, Rb)
    length = np.linalg.norm(v, axis=1)
    S = points or int(np.ceil(length.max() / RESOLUTION)) + 1
    pts = so3.geodesic_points(Ra, v, np.linspace(0.0, 1.0, S)).reshape(-1, 3, 3)
    d = sign * mech.singular.values(pts).reshape(len(Ra), S)
    within = None if legs is None else legs.clearances(mech, pts).reshape(len(Ra), -1).min(axis=1)
    return d, length, within


def _cost(d: np.ndarray, length: np.ndarray, power: float) -> np.ndarray:
    """``∫ ds / (sgnΔ)^power`` of geodesics from their profiles (:func:`_profile`),
    trapezoidal; ``inf`` where ``sgnΔ ≤ 0`` at a point."""
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.where(d > 0, d, 0.0) ** -power
    return length * (w[:, 1:] + w[:, :-1]).sum(axis=1) / (2 * (d.shape[1] - 1))


def _survey(mech, sign: float, Ra: np.ndarray, Rb: np.ndarray, level, power: float = CONDITIONING_POWERS[0],
            legs=None):
    """For each pair ``(Ra[e], Rb[e])``: whether ``sgnΔ ≥ level[e]`` at every checked point
    of the geodesic between them (the ends included) — and, with stroke limits ``legs``,
    every point inside them — and the geodesic's cost ``∫ ds / (sgnΔ)^power``
    (:func:`_cost`; ``inf`` where not clear)."""
    if len(Ra) == 0:
        return np.zeros(0, dtype=bool), np.zeros(0)
    d, length, within = _profile(mech, sign, Ra, Rb, legs=legs)
    clear = np.all(d >= np.broadcast_to(np.asarray(level, dtype=float), (len(Ra),))[:, None], axis=1)
    if within is not None:
        clear &= within >= 0.0
    return clear, np.where(clear, _cost(d, length, power), np.inf)



def has_surface(mechanism) -> bool:
    """Whether ``mechanism`` has a singular surface for a roadmap to go around (the
    roadmap's capability: a mechanism on SO(3) with ``Δ``).

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.

    Returns
    -------
    bool
        Whether it has one.
    """
    return mechanism.singular.exists


class Roadmap:
    """The roadmap of one mechanism at one clearance (see the module): ``R`` (nodes,
    ``(n, 3, 3)``), ``sign`` (``sgnΔ`` of each), ``edges`` (node pairs) and their
    :meth:`costs`.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.
    clearance : float
        The least ``|Δ|`` of the nodes and of every checked point of the edges.
    samples : int, default ROADMAP_SAMPLES
        Orientations sampled.
    seed : int, default ROADMAP_SEED
        The samples' seed.

    Raises
    ------
    ValueError
        If the mechanism has no singular set.
    """

    def __init__(self, mechanism, clearance: float, samples: int = ROADMAP_SAMPLES, seed: int = ROADMAP_SEED):
        from scipy.spatial import cKDTree  # SciPy's spatial module: loaded when first needed
        from scipy.spatial.transform import Rotation

        mech = mechanism
        if not has_surface(mech):
            raise ValueError(f"mechanism {mech.name!r} has no singular set: it needs no roadmap")
        self.mechanism = mech
        self.clearance = float(clearance)
        rot = Rotation.random(samples, random_state=np.random.default_rng(seed))
        R = rot.as_matrix()
        d = mech.singular.values(R)
        keep = np.abs(d) >= self.clearance
        self.R = R[keep]
        self.q = rot.as_quat()[keep]
        self.sign = np.sign(d[keep])
        self.tree = cKDTree(np.concatenate([self.q, -self.q]))
        n = len(self.R)
        # candidate edges: nearest neighbours of the same sign, shorter than MAX_EDGE
        _, idx = self.tree.query(self.q, k=2 * NEIGHBOURS + 1)
        i = np.repeat(np.arange(n), idx.shape[1])
        j = idx.ravel() % n
        ok = (i < j) & (self.sign[i] == self.sign[j])
        i, j = i[ok], j[ok]
        pairs = np.unique(np.stack([i, j], axis=1), axis=0)
        i, j = pairs[:, 0], pairs[:, 1]
        length = _angles(self.q[i], self.q[j])
        short = length <= MAX_EDGE
        i, j, length = i[short], j[short], length[short]
        # every edge's Δ profile at the same points, kept for the costs of every power
        S = int(np.ceil(MAX_EDGE / RESOLUTION)) + 1
        profile = np.empty((len(i), S))
        for s in (-1.0, 1.0):
            m = self.sign[i] == s
            profile[m], length[m], _ = _profile(mech, s, self.R[i[m]], self.R[j[m]], S)
        clear = np.all(profile >= self.clearance, axis=1)
        self.edges = np.stack([i[clear], j[clear]], axis=1)
        self._profile, self._length = profile[clear], length[clear]
        self._costs: dict[float, np.ndarray] = {}
        self._inside: dict = {}

    def inside(self, legs) -> np.ndarray:
        """Which edges keep every checked point at least :data:`LEG_CLEARANCE` inside stroke limits.

        Parameters
        ----------
        legs : LegLimits or None
            The stroke limits (:class:`~nonholo.model.limits.LegLimits`), or ``None``.

        Returns
        -------
        numpy.ndarray
            One bool per edge (all true without limits; cached per limits).
        """
        if legs is None:
            return np.ones(len(self.edges), dtype=bool)
        if legs not in self._inside:
            S = self._profile.shape[1]
            within = np.empty(len(self.edges))
            for start in range(0, len(self.edges), EDGE_CHUNK):
                e = self.edges[start:start + EDGE_CHUNK]
                within[start:start + len(e)] = _profile(self.mechanism, 1.0, self.R[e[:, 0]], self.R[e[:, 1]],
                                                        S, legs)[2]
            self._inside[legs] = within >= LEG_CLEARANCE
        return self._inside[legs]

    def costs(self, power: float) -> np.ndarray:
        """The edges' costs ``∫ ds / |Δ|^power`` (cached per ``power``).

        Parameters
        ----------
        power : float
            The power of ``|Δ|``.

        Returns
        -------
        numpy.ndarray
            One cost per edge.
        """
        if power not in self._costs:
            self._costs[power] = _cost(self._profile, self._length, power)
        return self._costs[power]

    def _graph(self, extra_i, extra_j, extra_cost, size, power, legs=None):
        from scipy.sparse import coo_matrix  # loaded when first needed

        keep = self.inside(legs)
        i = np.concatenate([self.edges[keep, 0], extra_i])
        j = np.concatenate([self.edges[keep, 1], extra_j])
        w = np.concatenate([self.costs(power)[keep], extra_cost])
        return coo_matrix((w, (i, j)), shape=(size, size)).tocsr()

    def _links(self, R, sign: float, level: float, node_index: int, power: float, legs=None):
        """Edges from ``R`` to its clear roadmap neighbours of the same sign."""
        from scipy.spatial.transform import Rotation  # loaded when first needed

        q = Rotation.from_matrix(R).as_quat()
        n = len(self.R)
        _, idx = self.tree.query(q, k=min(4 * NEIGHBOURS, 2 * n))
        j = np.unique(np.asarray(idx).ravel() % n)
        j = j[self.sign[j] == sign]
        length = _angles(np.broadcast_to(q, (len(j), 4)), self.q[j])
        j, length = j[length <= MAX_EDGE], length[length <= MAX_EDGE]
        ok, cost = _survey(self.mechanism, sign, np.broadcast_to(R, (len(j), 3, 3)), self.R[j], level, power, legs)
        return np.full(ok.sum(), node_index), j[ok], cost[ok]

    def path(self, R0, Rd, level: float, power: float = CONDITIONING_POWERS[0], legs=None) -> np.ndarray | None:
        """The cheapest roadmap path ``R0 → … → Rd``.

        Parameters
        ----------
        R0, Rd : numpy.ndarray
            Start and goal orientations.
        level : float
            The least ``sgnΔ`` of the links to the start and goal.
        power : float, default CONDITIONING_POWERS[0]
            The power of the cost ``∫ ds / |Δ|^power``.
        legs : LegLimits or None, optional
            Stroke limits every checked point keeps inside (see :meth:`inside`).

        Returns
        -------
        numpy.ndarray or None
            The path, ``(k, 3, 3)``, ends included; ``None`` if none joins them.
        """
        from scipy.sparse.csgraph import dijkstra  # loaded when first needed

        sign = self.mechanism.singular.sign(R0)
        n = len(self.R)
        s_i, s_j, s_l = self._links(R0, sign, level, n, power, legs)
        g_i, g_j, g_l = self._links(Rd, sign, level, n + 1, power, legs)
        direct, cost = _survey(self.mechanism, sign, R0[None], Rd[None], level, power, legs)
        d_i, d_j, d_l = (np.array([n]), np.array([n + 1]), cost) if direct[0] \
            else (np.zeros(0, int), np.zeros(0, int), np.zeros(0))
        graph = self._graph(np.concatenate([s_i, g_i, d_i]), np.concatenate([s_j, g_j, d_j]),
                            np.concatenate([s_l, g_l, d_l]), n + 2, power, legs)
        dist, pred = dijkstra(graph, directed=False, indices=n, return_predecessors=True)
        if not np.isfinite(dist[n + 1]):
            return None
        order = [n + 1]
        while order[-1] != n:
            order.append(pred[order[-1]])
        nodes = np.concatenate([self.R, R0[None], Rd[None]])
        return nodes[order[::-1]]


@lru_cache(maxsize=8)
def roadmap(mechanism, clearance: float) -> Roadmap:
    """The cached :class:`Roadmap` of a mechanism.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism (:class:`~nonholo.model.mechanism.Mechanism`).
    clearance : float
        The roadmap's clearance.

    Returns
    -------
    Roadmap
        The roadmap.
    """
    return Roadmap(mechanism, clearance)


def via_nodes(mechanism, R0, Rd, count: int, legs=None) -> np.ndarray:
    """Up to ``count`` nodes of the mechanism's roadmap (default clearance) in the start's component.

    In the order they were sampled — Haar-uniform, so a random order fixed by the
    roadmap's seed: intermediate orientations for a route of two legs (the last stage of
    :func:`nonholo.planning.route.steer`).

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.
    R0, Rd : numpy.ndarray
        Start and goal orientations.
    count : int
        Nodes at most.
    legs : LegLimits or None, optional
        Stroke limits the nodes keep at least :data:`LEG_CLEARANCE` inside.

    Returns
    -------
    numpy.ndarray
        The nodes, ``(k, 3, 3)``; none without a singular set, or where ``R0`` and ``Rd``
        lie on different sides of ``Δ = 0``.
    """
    mech = mechanism
    if not has_surface(mech):
        return np.empty((0, 3, 3))
    sign = mech.singular.sign(R0)
    if sign == 0.0 or mech.singular.sign(Rd) != sign:
        return np.empty((0, 3, 3))
    rm = roadmap(mech, default_clearance(mech))
    nodes = rm.R[rm.sign == sign]
    if legs is not None:
        nodes = nodes[legs.clearances(mech, nodes).min(axis=1) >= LEG_CLEARANCE]
    return nodes[:count]


def default_clearance(mechanism) -> float:
    """A roadmap's clearance by default.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.

    Returns
    -------
    float
        :data:`CLEARANCE_QUANTILE` of ``|Δ|`` over Haar-uniform orientations (fixed seed).
    """
    return _clearance(mechanism)


@lru_cache(maxsize=8)
def _clearance(mech) -> float:
    from scipy.spatial.transform import Rotation  # loaded when first needed

    R = Rotation.random(20000, random_state=np.random.default_rng(ROADMAP_SEED + 1)).as_matrix()
    return float(np.quantile(np.abs(mech.singular.values(R)), CLEARANCE_QUANTILE))


def shortcut(mech, sign: float, path: np.ndarray, level: float, power: float = CONDITIONING_POWERS[0],
             legs=None) -> np.ndarray:
    """A path with every waypoint dropped that a clear geodesic of no greater cost can skip.

    Greedy, from the start: the farthest such waypoint is the next.

    Parameters
    ----------
    mech : Mechanism
        The mechanism.
    sign : float
        ``sgnΔ`` of the path's component.
    path : numpy.ndarray
        The waypoints, ``(k, 3, 3)``.
    level : float
        The least ``sgnΔ`` of a clear geodesic.
    power : float, default CONDITIONING_POWERS[0]
        The power of the cost ``∫ ds / |Δ|^power``.
    legs : LegLimits or None, optional
        Stroke limits a clear geodesic keeps inside too.

    Returns
    -------
    numpy.ndarray
        The waypoints kept, ends included.
    """
    _, hops = _survey(mech, sign, path[:-1], path[1:], -np.inf, power)
    along = np.concatenate([[0.0], np.cumsum(hops)])
    out = [0]
    while out[-1] != len(path) - 1:
        a = out[-1]
        js = np.arange(len(path) - 1, a, -1)
        ok, cost = _survey(mech, sign, np.broadcast_to(path[a], (len(js), 3, 3)), path[js], level, power, legs)
        ok &= cost <= (along[js] - along[a]) * (1 + 1e-9)
        out.append(int(js[np.argmax(ok)]) if ok.any() else a + 1)
    return path[out]


def subdivide(path: np.ndarray, max_hop: float) -> np.ndarray:
    """A path with points inserted along its geodesics so that no hop exceeds ``max_hop``.

    Parameters
    ----------
    path : numpy.ndarray
        The waypoints, ``(k, 3, 3)``.
    max_hop : float
        The longest hop (rad).

    Returns
    -------
    numpy.ndarray
        The points, ends included.
    """
    out = [path[0]]
    for Ra, Rb in zip(path[:-1], path[1:]):
        k = max(1, int(np.ceil(so3.distance(Ra, Rb) / max_hop)))
        out.extend(so3.geodesic(Ra, Rb, np.arange(1, k + 1) / k))
    return np.array(out)


def orientation_path(mechanism, R0, Rd, *, delta_min: float = 1e-2, clearance: float | None = None,
                     max_hop: float = MAX_HOP, power: float = CONDITIONING_POWERS[0],
                     legs=None) -> np.ndarray | None:
    """A path of orientations from ``R0`` to ``Rd`` in the start's component (see the module).

    The cheapest in ``∫ ds / |Δ|^power`` on the roadmap, shortcut, every point of its
    geodesics with ``sgnΔ ≥ clearance`` but near the ends, where it may drop to what they
    have (never below ``delta_min``).

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.
    R0, Rd : array_like
        Start and goal orientations.
    delta_min : float, default 1e-2
        The least ``sgnΔ`` anywhere.
    clearance : float, optional
        The roadmap's clearance (default :func:`default_clearance`).
    max_hop : float, default MAX_HOP
        The longest hop (rad).
    power : float, default CONDITIONING_POWERS[0]
        The power of the cost.
    legs : LegLimits or None, optional
        Stroke limits (:class:`~nonholo.model.limits.LegLimits`) every point keeps inside.

    Returns
    -------
    numpy.ndarray or None
        The path, ``(k + 1, 3, 3)``, ``R0`` first, ``Rd`` last, hops of at most
        ``max_hop`` rad; ``None`` if the roadmap joins no such path.

    Raises
    ------
    ValueError
        If ``R0`` or ``Rd`` is not a rotation.
    """
    mech = mechanism
    R0 = so3.check_rotation(R0, "R0")
    Rd = so3.check_rotation(Rd, "Rd")
    if not has_surface(mech):
        if legs is not None and not _survey(mech, 1.0, R0[None], Rd[None], -np.inf, legs=legs)[0][0]:
            return None
        return subdivide(np.stack([R0, Rd]), max_hop)
    if clearance is None:
        clearance = default_clearance(mech)
    sign = mech.singular.sign(R0)
    if sign == 0.0 or mech.singular.sign(Rd) != sign:
        return None
    level = max(delta_min, min(clearance, 0.9 * sign * mech.singular.value(R0), 0.9 * sign * mech.singular.value(Rd)))
    path = roadmap(mech, clearance).path(R0, Rd, level, power, legs)
    if path is None:
        return None
    return subdivide(shortcut(mech, sign, path, level, power, legs), max_hop)
