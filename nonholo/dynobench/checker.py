"""The project's own check of a Dynobench trajectory, as Dynobench's checker judges one
(``src/motions.cpp``, thresholds of ``include/dynobench/motions.hpp``): written apart from
the planner, from the models' equations.

- **Dynamics**: every step of the states from the previous one by the model's explicit
  Euler step at ``dt`` with that step's action (angles wrapped), the largest gap in the
  model's weighted distance below :data:`TRAJ_TOL`.
- **Start and goal**: the first and last states within :data:`GOAL_TOL` (weighted distance).
- **Collision**: the bodies' signed distance from every obstacle at every state — for two
  convex polygons, the distance of the origin from their Minkowski difference, the convex hull
  of the differences of their corners (negative inside: the depth of the overlap), computed
  with shapely — at least ``−``:data:`COL_TOL`.
- **Bounds**: every action and state within its bounds up to :data:`BOUND_TOL`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Dynobench's threshold on the dynamics residual of a step (``Feasibility_thresholds``).
TRAJ_TOL = 1e-2
#: Its threshold on the start's and the goal's distances.
GOAL_TOL = 3e-2
#: Its threshold on the depth of a collision.
COL_TOL = 1e-2
#: Its threshold on how far a state or an action passes its bounds.
BOUND_TOL = 1e-2


def wrap(a):
    """Angles in ``[−π, π)``.

    Parameters
    ----------
    a : array_like
        Angles (rad).

    Returns
    -------
    numpy.ndarray
        The same angles, wrapped.
    """
    return (np.asarray(a, dtype=float) + np.pi) % (2.0 * np.pi) - np.pi


def rates(instance, x, u) -> np.ndarray:
    """The model's rates ``ẋ = f(x, u)`` (Dynobench's ``calcV``).

    Parameters
    ----------
    instance : Instance
        The instance (its dynamics and lengths).
    x : numpy.ndarray
        A state.
    u : numpy.ndarray
        An action.

    Returns
    -------
    numpy.ndarray
        The rates.
    """
    th = x[2]
    if instance.dynamics == "unicycle1":
        return np.array([u[0] * math.cos(th), u[0] * math.sin(th), u[1]])
    if instance.dynamics == "unicycle2":
        return np.array([x[3] * math.cos(th), x[3] * math.sin(th), x[4], u[0], u[1]])
    v, phi = u
    return np.array([v * math.cos(th), v * math.sin(th), v / instance.wheelbase * math.tan(phi),
                     v / instance.hitch * math.sin(th - x[3])])


def angles(instance) -> np.ndarray:
    """Which entries of the state are angles.

    Parameters
    ----------
    instance : Instance
        The instance.

    Returns
    -------
    numpy.ndarray
        A boolean mask.
    """
    mask = np.zeros(instance.start.size, dtype=bool)
    mask[2] = True
    if instance.dynamics == "car_with_trailers":
        mask[3] = True
    return mask


def step(instance, x, u) -> np.ndarray:
    """The model's explicit Euler step at ``dt`` (angles wrapped).

    Parameters
    ----------
    instance : Instance
        The instance.
    x : numpy.ndarray
        A state.
    u : numpy.ndarray
        An action.

    Returns
    -------
    numpy.ndarray
        The next state.
    """
    out = np.asarray(x, dtype=float) + instance.dt * rates(instance, x, u)
    mask = angles(instance)
    out[mask] = wrap(out[mask])
    return out


def distance(instance, x, y) -> float:
    """The model's weighted distance of two states (Dynobench's ``distance``).

    Parameters
    ----------
    instance : Instance
        The instance.
    x, y : numpy.ndarray
        States.

    Returns
    -------
    float
        ``w₀ |Δ(x, y)| + w₁ |Δθ| + …`` (angles' differences wrapped).
    """
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    parts = [float(np.hypot(*(x[:2] - y[:2])))]
    for i in range(2, x.size):
        d = x[i] - y[i]
        parts.append(abs(float(wrap(d))) if angles(instance)[i] else abs(float(d)))
    return float(np.dot(instance.weights, parts))


def bodies(instance, x) -> list:
    """The robot's bodies at a state, as shapely polygons.

    Parameters
    ----------
    instance : Instance
        The instance.
    x : numpy.ndarray
        A state.

    Returns
    -------
    list of shapely.Polygon
        The vehicle's box, then a trailer's.
    """
    from shapely import affinity, geometry

    placed = []
    poses = [(x[0], x[1], x[2])]
    if instance.dynamics == "car_with_trailers":
        th1 = x[3]
        poses.append((x[0] - instance.hitch * math.cos(th1), x[1] - instance.hitch * math.sin(th1), th1))
    for (cx, cy, heading), (length, width) in zip(poses, instance.bodies):
        box = geometry.box(-length / 2, -width / 2, length / 2, width / 2)
        placed.append(affinity.translate(affinity.rotate(box, heading, origin=(0, 0), use_radians=True), cx, cy))
    return placed


def obstacle_polygons(instance) -> list:
    """The obstacles as shapely polygons.

    Parameters
    ----------
    instance : Instance
        The instance.

    Returns
    -------
    list of shapely.Polygon
        One box each.
    """
    from shapely import geometry

    return [geometry.box(c[0] - s[0] / 2, c[1] - s[1] / 2, c[0] + s[0] / 2, c[1] + s[1] / 2)
            for c, s in ((o.center, o.size) for o in instance.obstacles)]


def signed_distance(a, b) -> float:
    """The signed distance of two convex polygons: their distance apart, minus the depth of
    their overlap (the least translation that separates them) where they overlap.

    Parameters
    ----------
    a, b : shapely.Polygon
        Convex polygons.

    Returns
    -------
    float
        The signed distance.
    """
    from shapely import geometry

    if not a.intersects(b):
        return float(a.distance(b))
    pa = np.asarray(a.exterior.coords)[:-1]
    pb = np.asarray(b.exterior.coords)[:-1]
    difference = geometry.MultiPoint((pa[:, None, :] - pb[None, :, :]).reshape(-1, 2)).convex_hull
    return -float(difference.exterior.distance(geometry.Point(0.0, 0.0)))


def state_clearance(instance, x) -> tuple[float, int]:
    """The least signed distance of the bodies from the obstacles at a state.

    Parameters
    ----------
    instance : Instance
        The instance.
    x : numpy.ndarray
        A state.

    Returns
    -------
    clearance : float
        The least signed distance (``inf`` without obstacles).
    obstacle : int
        The obstacle it is to (``-1`` without obstacles).
    """
    best, which = math.inf, -1
    for body in bodies(instance, x):
        for k, obstacle in enumerate(obstacle_polygons(instance)):
            d = signed_distance(body, obstacle)
            if d < best:
                best, which = d, k
    return best, which


@dataclass(frozen=True)
class Report:
    """What the check of a trajectory found (Dynobench's names).

    Parameters
    ----------
    max_jump : float
        The largest gap of a state from the Euler step of the previous one.
    start_distance, goal_distance : float
        The first and last states' distances from the start and the goal.
    max_collision : float
        The deepest overlap of a body with an obstacle (0 without one).
    x_bound_distance, u_bound_distance : float
        How far the states and actions pass their bounds at most.
    cost : float
        The duration, steps times ``dt`` (s).
    """

    max_jump: float
    start_distance: float
    goal_distance: float
    max_collision: float
    x_bound_distance: float
    u_bound_distance: float
    cost: float

    @property
    def feasible(self) -> bool:
        """Whether every check holds within Dynobench's thresholds."""
        return not self.failures()

    def failures(self) -> list[str]:
        """The checks that fail, each saying by how much.

        Returns
        -------
        list of str
            Empty when the trajectory is feasible.
        """
        out = []
        for name, value, tol in (("dynamics residual", self.max_jump, TRAJ_TOL),
                                 ("start distance", self.start_distance, GOAL_TOL),
                                 ("goal distance", self.goal_distance, GOAL_TOL),
                                 ("collision", self.max_collision, COL_TOL),
                                 ("state bounds", self.x_bound_distance, BOUND_TOL),
                                 ("input bounds", self.u_bound_distance, BOUND_TOL)):
            if not value < tol:
                out.append(f"{name} {value:.3g} (Dynobench's threshold {tol:g})")
        return out


def _beyond(values, low, high) -> float:
    v = np.asarray(values, dtype=float)
    return float(max(np.max(low - v, initial=0.0), np.max(v - high, initial=0.0), 0.0))


def check(instance, states, actions) -> Report:
    """Check a trajectory of an instance (see the module).

    Parameters
    ----------
    instance : Instance
        The instance.
    states : array_like
        ``K + 1`` states.
    actions : array_like
        ``K`` actions, each held for ``dt``.

    Returns
    -------
    Report
        The checks' numbers.

    Raises
    ------
    ValueError
        If the shapes do not fit the instance (one state more than actions).
    """
    X = np.asarray(states, dtype=float)
    U = np.asarray(actions, dtype=float).reshape(-1, instance.input_low.size)
    if X.ndim != 2 or X.shape[1] != instance.start.size or X.shape[0] != U.shape[0] + 1:
        raise ValueError(f"states must be ({U.shape[0] + 1}, {instance.start.size}) for {U.shape[0]} actions, "
                         f"got {X.shape}")
    jump = max((distance(instance, step(instance, X[k], U[k]), X[k + 1]) for k in range(U.shape[0])),
               default=0.0)
    collision = max((max(-state_clearance(instance, x)[0], 0.0) for x in X), default=0.0)
    x_out = max(_beyond(x, instance.state_low, instance.state_high) for x in X)
    u_out = max((_beyond(u, instance.input_low, instance.input_high) for u in U), default=0.0)
    return Report(max_jump=jump, start_distance=distance(instance, X[0], instance.start),
                  goal_distance=distance(instance, X[-1], instance.goal), max_collision=collision,
                  x_bound_distance=x_out, u_bound_distance=u_out, cost=U.shape[0] * instance.dt)
