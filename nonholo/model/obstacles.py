"""Obstacles in the plane and the boxes a vehicle carries: the clearance a planar vehicle
keeps, as a constraint object of ``nonholo.plan``.

:class:`Obstacles` are the polygons, :class:`Body` a box the vehicle carries.

A body is a box attached to the vehicle: centred on the point ``(x, y)`` of its coordinates
(or ``behind`` that far back along its heading, a trailer's hitch) and turned by its heading
coordinate. An obstacle is a convex polygon. The clearance of a body from an obstacle is
their signed distance — apart, the distance between them; overlapping, minus the depth of
the overlap, the least translation that separates them — which for convex polygons is the
distance of the origin from their Minkowski difference, the convex hull of the differences
of their corners (negative inside it). The geometry is shapely's (vectorised over the
nodes of a motion); its derivatives in the coordinates are central differences.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

#: The step of the central differences of a clearance in the coordinates.
DIFFERENCE_STEP = 1e-6
#: A clearance this far below the margin still keeps it (the geometry's round-off).
CLEARANCE_TOL = 1e-9


@dataclass(frozen=True)
class Body:
    """A box attached to a planar vehicle (see the module).

    Parameters
    ----------
    length, width : float
        Its sides, along and across the heading.
    x, y, heading : str, default "x", "y", "theta"
        The coordinates of the point it hangs from and of its heading.
    behind : float, default 0
        How far behind that point, along the heading, its centre is (a trailer's hitch).
    """

    length: float
    width: float
    x: str = "x"
    y: str = "y"
    heading: str = "theta"
    behind: float = 0.0


@dataclass(frozen=True)
class Obstacles:
    """Convex polygons the vehicle's bodies keep clear of (see the module): by ``margin`` at
    the nodes of the least-time path (``objective="time"``), which keeps them; a plan whose
    motion overlaps one fails.

    Parameters
    ----------
    polygons : sequence of sequence of (float, float)
        The obstacles' corners, each a convex polygon.
    bodies : sequence of Body
        The vehicle's boxes.
    margin : float, default 0
        The least clearance kept.

    Raises
    ------
    ValueError
        Naming the argument: a polygon of fewer than three finite corners or not convex, a
        body of sides that are not positive, a negative margin.
    """

    polygons: tuple
    bodies: tuple = (Body(0.5, 0.25),)
    margin: float = 0.0

    def __post_init__(self):
        polygons = []
        for i, corners in enumerate(self.polygons):
            c = np.asarray(corners, dtype=float)
            if c.ndim != 2 or c.shape[1] != 2 or c.shape[0] < 3 or not np.all(np.isfinite(c)):
                raise ValueError(f"polygons[{i}] must be three or more finite corners (x, y), got {corners!r}")
            if _hull(c).area <= 0.0 or abs(_hull(c).area - _polygon(c).area) > 1e-12 * max(1.0, _hull(c).area):
                raise ValueError(f"polygons[{i}] must be a convex polygon")
            polygons.append(tuple(map(tuple, c)))
        for i, b in enumerate(self.bodies):
            if not isinstance(b, Body):
                raise ValueError(f"bodies[{i}] must be a Body, got {type(b).__name__}")
            if not (b.length > 0 and b.width > 0 and math.isfinite(b.length) and math.isfinite(b.width)):
                raise ValueError(f"bodies[{i}]: length and width must be positive, got {b.length!r}, {b.width!r}")
        if not (self.margin >= 0 and math.isfinite(self.margin)):
            raise ValueError(f"margin must be a non-negative number, got {self.margin!r}")
        object.__setattr__(self, "polygons", tuple(polygons))
        object.__setattr__(self, "bodies", tuple(self.bodies))

    @classmethod
    def boxes(cls, centers, sizes, bodies=(Body(0.5, 0.25),), margin: float = 0.0) -> "Obstacles":
        """Axis-aligned boxes by centre and sides (Dynobench's form).

        Parameters
        ----------
        centers, sizes : sequence of (float, float)
            The boxes' centres and sides.
        bodies : sequence of Body
            The vehicle's boxes.
        margin : float, default 0
            The least clearance kept.

        Returns
        -------
        Obstacles
            The boxes.
        """
        polygons = []
        for (cx, cy), (a, b) in zip(centers, sizes):
            polygons.append(((cx - a / 2, cy - b / 2), (cx + a / 2, cy - b / 2), (cx + a / 2, cy + b / 2),
                             (cx - a / 2, cy + b / 2)))
        return cls(tuple(polygons), tuple(bodies), margin)

    def check(self, mechanism) -> "Obstacles":
        """The obstacles for ``mechanism``: its coordinates must name every body's.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism planned.

        Returns
        -------
        Obstacles
            ``self``.

        Raises
        ------
        ValueError
            Naming the body and the coordinate the mechanism does not have.
        """
        for i, b in enumerate(self.bodies):
            for key in ("x", "y", "heading"):
                if getattr(b, key) not in mechanism.coordinates:
                    raise ValueError(f"Obstacles: bodies[{i}].{key} = {getattr(b, key)!r} is not a coordinate of "
                                     f"mechanism {mechanism.name!r} ({', '.join(mechanism.coordinates)})")
        return self

    def refusal(self, mechanism, start, goal) -> str | None:
        """Why a motion cannot start or end where asked: a body that meets an obstacle there.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism.
        start, goal : tuple
            States ``(R, q)``.

        Returns
        -------
        str or None
            The reason, or ``None``.
        """
        for where, (_, q) in (("start", start), ("goal", goal)):
            c = self.clearances(mechanism, np.asarray(q, dtype=float)[None])[0]
            if np.min(c) < self.margin:
                return (f"the {where} puts body {int(np.argmin(c))} {'into' if np.min(c) < 0 else 'within'} an "
                        f"obstacle (clearance {np.min(c):.3g} < margin {self.margin:g})")
        return None

    def violation(self, mechanism, q) -> str | None:
        """Where a motion's states bring a body into an obstacle (``None`` where none does:
        the margin is kept at the nodes of the optimisation, the states between them only
        clear of the obstacles).

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism.
        q : array_like
            Its states, ``(n, k)``.

        Returns
        -------
        str or None
            The first state and by how much.
        """
        c = self.clearances(mechanism, q).min(axis=1)
        bad = np.nonzero(c < -CLEARANCE_TOL)[0]
        if bad.size == 0:
            return None
        i = int(bad[np.argmin(c[bad])])
        return f"a body overlaps an obstacle by {-c[i]:.3g} at state {i} of {len(c)}"

    def record(self) -> dict:
        """The obstacles as data, for a plan's options.

        Returns
        -------
        dict
            ``polygons``, ``bodies`` and ``margin``.
        """
        return {"polygons": [list(map(list, p)) for p in self.polygons],
                "bodies": [dict(length=b.length, width=b.width, x=b.x, y=b.y, heading=b.heading, behind=b.behind)
                           for b in self.bodies],
                "margin": self.margin}

    @classmethod
    def from_record(cls, record, mechanism, name: str = "obstacles") -> "Obstacles":
        """The obstacles of a record (:meth:`record`; a plan file's options), checked for
        ``mechanism``: numbers and names only, nothing evaluated.

        Parameters
        ----------
        record : dict
            ``polygons``, ``bodies`` and ``margin``.
        mechanism : Mechanism
            The mechanism planned.
        name : str, default "obstacles"
            The field, for messages.

        Returns
        -------
        Obstacles
            The obstacles.

        Raises
        ------
        ValueError
            Naming ``name`` and what is wrong.
        """
        if not isinstance(record, dict) or set(record) != {"polygons", "bodies", "margin"}:
            raise ValueError(f"{name}: must hold exactly polygons, bodies and margin, got {record!r:.200}")
        bodies = record["bodies"]
        if not isinstance(bodies, list) or not all(isinstance(b, dict) for b in bodies):
            raise ValueError(f"{name}: bodies must be a list of objects")
        keys = {"length", "width", "x", "y", "heading", "behind"}
        made = []
        for i, b in enumerate(bodies):
            if set(b) != keys or not all(isinstance(b[k], str) for k in ("x", "y", "heading")) \
                    or not all(isinstance(b[k], (int, float)) and not isinstance(b[k], bool)
                               for k in ("length", "width", "behind")):
                raise ValueError(f"{name}: bodies[{i}] must hold the numbers length, width, behind and the "
                                 f"coordinates' names x, y, heading")
            made.append(Body(**b))
        polygons = record["polygons"]
        if not isinstance(polygons, list) or not all(
                isinstance(p, list) and all(isinstance(c, list) and len(c) == 2 and all(
                    isinstance(v, (int, float)) and not isinstance(v, bool) for v in c) for c in p)
                for p in polygons):
            raise ValueError(f"{name}: polygons must be lists of corners [x, y] (numbers)")
        margin = record["margin"]
        if isinstance(margin, bool) or not isinstance(margin, (int, float)):
            raise ValueError(f"{name}: margin must be a number, got {margin!r}")
        try:
            return cls(tuple(tuple(map(tuple, p)) for p in polygons), tuple(made), float(margin)).check(mechanism)
        except ValueError as exc:
            raise ValueError(f"{name}: {exc}") from None

    def clearances(self, mechanism, q) -> np.ndarray:
        """The least clearance of each body from any obstacle at each state.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism.
        q : array_like
            States, ``(n, k)``.

        Returns
        -------
        numpy.ndarray
            ``(n, bodies)`` (``inf`` without obstacles).
        """
        q = np.atleast_2d(np.asarray(q, dtype=float))
        return np.stack([self._least(mechanism, q, b) for b in self.bodies], axis=1)

    def clearance_rows(self, mechanism, q) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`clearances` and their gradients in the coordinates.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism.
        q : array_like
            States, ``(n, k)``.

        Returns
        -------
        values : numpy.ndarray
            ``(n, bodies)``.
        gradients : numpy.ndarray
            ``(n, bodies, k)``: ``d value = gradient · δq``.
        """
        q = np.atleast_2d(np.asarray(q, dtype=float))
        n, k = q.shape
        values = np.empty((n, len(self.bodies)))
        grads = np.zeros((n, len(self.bodies), k))
        for j, b in enumerate(self.bodies):
            values[:, j], nearest = self._nearest(mechanism, q, b)
            if nearest is None:
                continue
            # the least over the obstacles moves with the nearest one's signed distance
            for name in dict.fromkeys((b.x, b.y, b.heading)):
                c = mechanism.coordinates.index(name)
                up, down = q.copy(), q.copy()
                up[:, c] += DIFFERENCE_STEP
                down[:, c] -= DIFFERENCE_STEP
                grads[:, j, c] = (self._signed(mechanism, up, b, nearest)
                                  - self._signed(mechanism, down, b, nearest)) / (2 * DIFFERENCE_STEP)
        return values, grads

    def _least(self, mechanism, q, body: Body) -> np.ndarray:
        """The least signed distance of ``body`` from any obstacle at each state of ``q``."""
        return self._nearest(mechanism, q, body)[0]

    def _nearest(self, mechanism, q, body: Body):
        """The least signed distance of ``body`` from any obstacle at each state of ``q``, and
        which obstacle it is to (``None`` without obstacles)."""
        import shapely

        if not self.polygons:
            return np.full(q.shape[0], np.inf), None
        corners = body_corners(mechanism, q, body)                         # (n, 4, 2)
        placed = shapely.polygons(corners)
        d = shapely.distance(placed[:, None], self._shapes[None, :])       # (n, K): 0 where they meet
        met = np.nonzero(d <= 0.0)
        if met[0].size:
            d[met] = -overlap_depths(corners[met[0]], [self._corners[j] for j in met[1]])
        nearest = d.argmin(axis=1)
        return d[np.arange(d.shape[0]), nearest], nearest

    def _signed(self, mechanism, q, body: Body, which: np.ndarray) -> np.ndarray:
        """The signed distance of ``body`` at each state of ``q`` from the obstacle ``which``
        names for it."""
        import shapely

        corners = body_corners(mechanism, q, body)
        d = shapely.distance(shapely.polygons(corners), self._shapes[which])
        met = np.nonzero(d <= 0.0)[0]
        if met.size:
            d[met] = -overlap_depths(corners[met], [self._corners[j] for j in which[met]])
        return d

    @cached_property
    def _corners(self) -> list:
        """The obstacles' corners as arrays."""
        return [np.asarray(p, dtype=float) for p in self.polygons]

    @cached_property
    def _shapes(self) -> np.ndarray:
        """The obstacles as shapely polygons."""
        import shapely

        return shapely.polygons(self._corners)


def body_pose(mechanism, q, body: Body) -> tuple[np.ndarray, np.ndarray]:
    """A body's centre and heading at each state.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.
    q : numpy.ndarray
        States, ``(n, k)``.
    body : Body
        The body.

    Returns
    -------
    centres : numpy.ndarray
        ``(n, 2)``.
    headings : numpy.ndarray
        ``(n,)``.
    """
    names = mechanism.coordinates
    x, y, h = (q[:, names.index(body.x)], q[:, names.index(body.y)], q[:, names.index(body.heading)])
    return np.column_stack([x - body.behind * np.cos(h), y - body.behind * np.sin(h)]), h


def body_corners(mechanism, q, body: Body) -> np.ndarray:
    """A body's corners at each state.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.
    q : numpy.ndarray
        States, ``(n, k)``.
    body : Body
        The body.

    Returns
    -------
    numpy.ndarray
        ``(n, 4, 2)``, counter-clockwise.
    """
    centres, h = body_pose(mechanism, q, body)
    cx, cy = centres[:, 0], centres[:, 1]
    c, s = np.cos(h), np.sin(h)
    a, b = body.length / 2, body.width / 2
    local = np.array([(-a, -b), (a, -b), (a, b), (-a, b)])
    return np.stack([cx[:, None] + c[:, None] * local[:, 0] - s[:, None] * local[:, 1],
                     cy[:, None] + s[:, None] * local[:, 0] + c[:, None] * local[:, 1]], axis=-1)


def overlap_depth(a: np.ndarray, b: np.ndarray) -> float:
    """The depth of the overlap of two convex polygons (corners ``a``, ``b``): the distance of
    the origin from the boundary of their Minkowski difference.

    Parameters
    ----------
    a, b : numpy.ndarray
        Corners, ``(p, 2)`` and ``(r, 2)``.

    Returns
    -------
    float
        The depth (0 where they only touch).
    """
    import shapely

    difference = _hull((a[:, None, :] - b[None, :, :]).reshape(-1, 2))
    return float(shapely.distance(difference.exterior, shapely.Point(0.0, 0.0)))


def overlap_depths(a: np.ndarray, bs: list) -> np.ndarray:
    """:func:`overlap_depth` of many pairs at once (shapely's vectorised hulls and distances).

    Parameters
    ----------
    a : numpy.ndarray
        The first polygons' corners, ``(n, p, 2)``.
    bs : list of numpy.ndarray
        The second polygons' corners, ``n`` arrays ``(r, 2)``.

    Returns
    -------
    numpy.ndarray
        The depths, ``(n,)``.
    """
    import shapely

    points = [(ai[:, None, :] - b[None, :, :]).reshape(-1, 2) for ai, b in zip(a, bs)]
    index = np.repeat(np.arange(len(points)), [p.shape[0] for p in points])
    hulls = shapely.convex_hull(shapely.multipoints(np.concatenate(points), indices=index))
    return shapely.distance(shapely.get_exterior_ring(hulls), shapely.Point(0.0, 0.0))


def _hull(points: np.ndarray):
    import shapely

    return shapely.convex_hull(shapely.multipoints(points))


def _polygon(points: np.ndarray):
    import shapely

    return shapely.polygons(points)
