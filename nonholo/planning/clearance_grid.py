"""A quick test that a vehicle's bodies clear the obstacles: each box covered by circles, each
circle's centre looked up in a grid of the obstacles' distances.

The searches of routes (:mod:`nonholo.planning.car_route`) test thousands of bodies per
second. Most are far from every obstacle, and a test that can only say "clear" or "ask
shapely" settles them at the cost of a table look-up. :class:`ClearanceGrid` holds the
distance to the obstacles (shapely's) at the nodes of a square grid of spacing ``r``; at any
point ``p`` it is at least the nearest node's less ``r/√2``. A box of sides ``L × W`` is
covered by ``n = ⌈2L/W⌉`` circles along its length, of radius ``√((L/2n)² + (W/2)²)``; a body
whose every circle's centre is at least that radius plus the margin from the obstacles
(by the grid's bound) is clear. The rest — and every body off the grid — are left to the
exact test, so the answer never differs from shapely's by more than its rounding.
"""
from __future__ import annotations

import math

import numpy as np


class ClearanceGrid:
    """The obstacles' distance on a grid, and the bodies it proves clear (see the module).

    Parameters
    ----------
    union : shapely geometry
        The obstacles, as one.
    bodies : sequence of Body
        The vehicle's bodies.
    low, high : array_like
        The corners of the region the vehicle's reference point stays in; the grid covers
        it grown by the bodies' reach.
    spacing : float
        The grid's spacing.
    margin : float
        The clearance a body must keep.
    """

    def __init__(self, union, bodies, low, high, spacing: float, margin: float):
        import shapely

        if not (spacing > 0 and math.isfinite(spacing)):
            raise ValueError(f"spacing must be a positive number, got {spacing!r}")
        reach = max(abs(b.behind) + math.hypot(b.length, b.width) / 2 for b in bodies)
        self.low = np.asarray(low, dtype=float) - reach
        top = np.asarray(high, dtype=float) + reach
        self.shape = tuple(int(v) for v in np.floor((top - self.low) / spacing).astype(int) + 1)
        X, Y = np.meshgrid(self.low[0] + spacing * np.arange(self.shape[0]),
                           self.low[1] + spacing * np.arange(self.shape[1]), indexing="ij")
        self.distance = shapely.distance(shapely.points(X.ravel(), Y.ravel()), union).reshape(self.shape)
        self.spacing = spacing
        self.bodies = tuple(bodies)
        # per body: the circles' offsets along the heading from its centre, their radius
        self.circles = []
        for b in self.bodies:
            n = max(1, math.ceil(2.0 * b.length / b.width))
            offsets = b.length * ((np.arange(n) + 0.5) / n - 0.5)
            radius = math.hypot(b.length / (2 * n), b.width / 2)
            self.circles.append((offsets, radius + margin + spacing / math.sqrt(2.0)))

    def clear(self, centres: np.ndarray, headings: np.ndarray, body: int) -> np.ndarray:
        """Whether the grid proves a body clear at each of its placements (``False``: ask the
        exact test).

        Parameters
        ----------
        centres : numpy.ndarray
            The body's centres, ``(n, 2)``.
        headings : numpy.ndarray
            Its headings, ``(n,)``.
        body : int
            Which of the bodies.

        Returns
        -------
        numpy.ndarray
            ``(n,)`` booleans.
        """
        offsets, needed = self.circles[body]
        c, s = np.cos(headings)[:, None], np.sin(headings)[:, None]
        x = centres[:, :1] + c * offsets
        y = centres[:, 1:2] + s * offsets
        i = np.rint((x - self.low[0]) / self.spacing).astype(np.intp)
        j = np.rint((y - self.low[1]) / self.spacing).astype(np.intp)
        inside = (i >= 0) & (i < self.shape[0]) & (j >= 0) & (j < self.shape[1])
        d = self.distance[np.where(inside, i, 0), np.where(inside, j, 0)]
        return np.all(inside & (d >= needed), axis=1)
