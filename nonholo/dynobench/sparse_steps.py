"""Dynobench's own problem of a whole trajectory, hundreds of steps long, as one sparse nonlinear
program: IPOPT through CasADi.

:mod:`nonholo.dynobench.euler_steps` seeks the actions alone by SLSQP, whose dense quadratic
programs grow with the cube of the steps. Here the states are variables too: each Euler step
``x_{k+1} = x_k + h f(x_k, u_k)`` is an equality touching two states and one action, and
IPOPT (CasADi's, with exact sparse derivatives) solves a problem of two hundred steps in about
a second.

A body keeps clear of an obstacle where a line separates them: the line's direction and
offset are variables, the body's corners on one side, the obstacle's on the other, each at
least half the margin from it. For convex polygons that is exact (two convex sets are the
margin apart exactly where such a line exists) and smooth, where their distance is not. Each
solve keeps the states within a trust region of its first guess (:data:`REACH` on the
position, :data:`TURN` on the angles), so a body moves at most ``REACH + r TURN`` (``r`` its
reach from the vehicle's point); the lines are set up for each state and body and every
obstacle within that (and the margin) of it along the first guess — every obstacle for the
last state, which is kept in the goal's box instead — started at shapely's nearest points.
Where the solution still brings a body closer than the margin to an obstacle, the pairs are
set up again along it and the problem solved again (:data:`ROUNDS`).

:func:`fewest_steps` solves, from a route's actions at the model's step ``dt``:

1. the problem on the route's count of steps ``K`` (or up to :data:`EXTRA_STEPS` more);
2. from that trajectory, the least step ``h`` on its count — the least time ``K h`` in its
   class of motions, where the model's step allows only whole steps — and the problem at
   ``dt`` on ``K' = ⌈K h / dt⌉`` steps, from that motion resampled (:data:`LEAST_ROUNDS`
   times at most, while the count falls);
3. the problem one step fewer while it solves — or, below a count that did not solve, on the
   count halfway to it, until the two are a step apart.

The bounds are kept as in :mod:`nonholo.dynobench.euler_steps`: widened by ``share ·
BOUND_TOL``. The goal is a box inside the ball of the model's distance of radius ``share ·
GOAL_TOL`` (half of it on the position, half on the other coordinates; smooth, where the
distance is not); ``share = 0`` makes it the goal itself. Every constraint is kept by
:data:`~nonholo.dynobench.euler_steps.INNER` more, and a trajectory is kept only where the
states of its actions' exact Euler steps keep every one to
:data:`~nonholo.dynobench.euler_steps.KEPT_TOL` (:meth:`EulerProblem.keeps
<nonholo.dynobench.euler_steps.EulerProblem.keeps>`) and the project's checker passes it.
IPOPT runs a fixed number of iterations at most: the same call gives the same trajectory on
any machine under any load.

The models (:data:`MODELS`): Dynobench's first-order unicycle and its car with a trailer.
"""
from __future__ import annotations

import math

import numpy as np

from ..model.bounds import InputBounds, StateBounds
from ..model.obstacles import body_corners
from .checker import BOUND_TOL, GOAL_TOL, check, wrap
from .euler_steps import INNER, SMOOTHING, EulerProblem, Steps, model_of

#: The models solved here.
MODELS = ("unicycle1", "car_with_trailers")
#: Each solve keeps every state but the last within this distance of the first guess's
#: position ...
REACH = 0.25
#: ... and its angles within this of the guess's (rad).
TURN = 0.3
#: Times the problem is solved again with the lines of the pairs its solution brings too near.
ROUNDS = 2
#: Where a solve fails, it is tried again with the trust region this many times wider, in turn
#: (a route's first guess may be far from a motion at the goal).
WIDER = (2.0, 4.0)
#: IPOPT's iterations at most ...
MAX_ITERATIONS = 400
#: ... and at a count one step fewer than one that solved.
TRIAL_ITERATIONS = 100
#: Steps added to the route's, at most, where its count does not solve at the model's step.
EXTRA_STEPS = 2
#: Rounds of the least step and the count it needs, at most.
LEAST_ROUNDS = 3
#: The least step is sought within these multiples of the model's.
STEP_RANGE = (0.2, 5.0)
#: The weight of the actions' changes from step to step in the objective.
SMOOTHER = 1e-4
#: IPOPT's tolerances (its overall and its constraints').
TOL = 1e-10


def rates(instance, X, U):
    """The model's rates at states ``X`` and actions ``U`` (CasADi's expressions, a row each;
    Dynobench's models, as :func:`nonholo.dynobench.checker.rates`).

    Parameters
    ----------
    instance : Instance
        The instance (its dynamics and lengths).
    X, U : casadi.SX
        States ``(K, n)`` and actions ``(K, m)``.

    Returns
    -------
    casadi.SX
        ``(K, n)``.

    Raises
    ------
    ValueError
        If the dynamics are not one of :data:`MODELS`.
    """
    import casadi as ca

    th = X[:, 2]
    if instance.dynamics == "unicycle1":
        return ca.horzcat(U[:, 0] * ca.cos(th), U[:, 0] * ca.sin(th), U[:, 1])
    if instance.dynamics == "car_with_trailers":
        v, phi = U[:, 0], U[:, 1]
        return ca.horzcat(v * ca.cos(th), v * ca.sin(th), v * ca.tan(phi) / instance.wheelbase,
                          v * ca.sin(th - X[:, 3]) / instance.hitch)
    raise ValueError(f"no sparse program for the dynamics {instance.dynamics!r}; known: {', '.join(MODELS)}")


def rollout(instance, model, actions: np.ndarray) -> np.ndarray:
    """The states of the model's Euler steps (of ``dt``) of actions from the instance's start.

    Parameters
    ----------
    instance : Instance
        The instance.
    model : MechanismModel or CarWithTrailer
        Its model.
    actions : numpy.ndarray
        ``(K, m)``.

    Returns
    -------
    numpy.ndarray
        ``(K + 1, n)``, angles not wrapped.
    """
    h = instance.dt
    states = np.empty((actions.shape[0] + 1, len(model.coordinates)))
    states[0] = instance.start
    for k, u in enumerate(actions):
        states[k + 1] = states[k] + h * model.rates(states[k], u)[0]
    return states


def resampled(states: np.ndarray, actions: np.ndarray, K: int) -> tuple[np.ndarray, np.ndarray]:
    """A motion's states and actions spread over ``K`` steps (linear in the fraction of it).

    Parameters
    ----------
    states, actions : numpy.ndarray
        ``(K0 + 1, n)`` and ``(K0, m)``.
    K : int
        The new count.

    Returns
    -------
    tuple of numpy.ndarray
        ``(K + 1, n)`` and ``(K, m)``.
    """
    K0 = actions.shape[0]
    at_nodes, new_nodes = np.arange(K0 + 1) / K0, np.arange(K + 1) / K
    at_middles, new_middles = (np.arange(K0) + 0.5) / K0, (np.arange(K) + 0.5) / K
    return (np.column_stack([np.interp(new_nodes, at_nodes, c) for c in states.T]),
            np.column_stack([np.interp(new_middles, at_middles, c) for c in actions.T]))


class SparseSteps:
    """Dynobench's problem of an instance as a sparse program (see the module).

    Parameters
    ----------
    instance : Instance
        The instance (one of :data:`MODELS`).
    obstacles : Obstacles
        The obstacles, the bodies and the margin kept.
    share : float
        The fraction of Dynobench's thresholds on the bounds and the goal used, in ``[0, 1)``.
    """

    def __init__(self, instance, obstacles, share: float):
        import shapely

        if instance.dynamics not in MODELS:
            raise ValueError(f"no sparse program for the dynamics {instance.dynamics!r}; known: {', '.join(MODELS)}")
        if not (isinstance(share, (int, float)) and 0.0 <= share < 1.0):
            raise ValueError(f"share must be a number in [0, 1), got {share!r}")
        self.instance, self.obstacles, self.share = instance, obstacles, float(share)
        self.model = model_of(instance)
        self.n, self.m = len(self.model.coordinates), instance.input_low.size
        self.judge = EulerProblem(instance, InputBounds(tuple(instance.input_low), tuple(instance.input_high)),
                                  StateBounds(tuple(instance.state_low), tuple(instance.state_high)), obstacles,
                                  float(share))
        corners = [np.asarray(p, dtype=float) for p in obstacles.polygons]
        most = max((len(c) for c in corners), default=0)
        # every obstacle's corners, the last repeated up to the most any has
        self.corners = np.array([np.vstack([c, np.repeat(c[-1:], most - len(c), axis=0)]) for c in corners])
        self.shapes = shapely.polygons(corners) if corners else None
        widen = self.share * BOUND_TOL
        self.input_low = np.asarray(instance.input_low, dtype=float) - widen + INNER
        self.input_high = np.asarray(instance.input_high, dtype=float) + widen - INNER
        self.state_low = np.asarray(instance.state_low, dtype=float) - widen + INNER
        self.state_high = np.asarray(instance.state_high, dtype=float) + widen - INNER
        # the goal's box: half its radius on the position's norm, half shared by the others
        # (inside the judge's smoothed distance too)
        radius = max(self.share * GOAL_TOL - INNER - 2.0 * self.n * SMOOTHING, 0.0)
        weights = np.asarray(instance.weights, dtype=float)
        others = self.n - 2
        self.goal_box = np.concatenate([np.full(2, radius / (2.0 * math.sqrt(2.0) * weights[0])),
                                        radius / (2.0 * others * weights[1:])])

    def pairs(self, states: np.ndarray, scale: float = 1.0) -> np.ndarray:
        """The states (after the start), bodies and obstacles a solve from ``states`` may bring
        within the margin of each other (see the module).

        Parameters
        ----------
        states : numpy.ndarray
            ``(K + 1, n)``.
        scale : float, default 1
            The trust region's size, in :data:`REACH` and :data:`TURN`.

        Returns
        -------
        numpy.ndarray
            ``(p, 3)``: state, body, obstacle.
        """
        import shapely

        if self.shapes is None:
            return np.empty((0, 3), dtype=int)
        found = []
        for b, body in enumerate(self.obstacles.bodies):
            placed = shapely.polygons(body_corners(self.model, states[1:], body))
            reach = abs(body.behind) + math.hypot(body.length, body.width) / 2
            near = shapely.distance(placed[:, None], self.shapes[None, :]) < \
                scale * (REACH + reach * TURN) + 2.0 * self.obstacles.margin                          # (K, obstacles)
            near[-1] = True
            k, o = np.nonzero(near)
            found.append(np.column_stack([k + 1, np.full(k.size, b), o]))
        return np.vstack(found).astype(int)

    def lines(self, states: np.ndarray, pairs: np.ndarray) -> np.ndarray:
        """First lines between the pairs' bodies and obstacles: the direction from the
        obstacle's nearest point to the body's (their centres' where they overlap), the offset
        of the midpoint.

        Parameters
        ----------
        states : numpy.ndarray
            ``(K + 1, n)``.
        pairs : numpy.ndarray
            ``(p, 3)``.

        Returns
        -------
        numpy.ndarray
            ``(p, 2)``: the direction's angle and the offset.
        """
        import shapely

        out = np.empty((len(pairs), 2))
        for b, body in enumerate(self.obstacles.bodies):
            rows = np.nonzero(pairs[:, 1] == b)[0]
            if not rows.size:
                continue
            placed = shapely.polygons(body_corners(self.model, states[pairs[rows, 0]], body))
            shapes = self.shapes[pairs[rows, 2]]
            line = shapely.get_coordinates(shapely.shortest_line(placed, shapes)).reshape(-1, 2, 2)
            direction = line[:, 0] - line[:, 1]
            apart = np.linalg.norm(direction, axis=1)
            centres = (shapely.get_coordinates(shapely.centroid(placed))
                       - shapely.get_coordinates(shapely.centroid(shapes)))
            direction = np.where(apart[:, None] > 1e-9, direction, centres)
            length = np.linalg.norm(direction, axis=1)
            # (a body on an obstacle's centre: any direction)
            direction = np.where(length[:, None] > 1e-12, direction / np.maximum(length, 1e-300)[:, None], [1.0, 0.0])
            middle = np.where(apart[:, None] > 1e-9, 0.5 * (line[:, 0] + line[:, 1]),
                              0.5 * (shapely.get_coordinates(shapely.centroid(placed))
                                     + shapely.get_coordinates(shapely.centroid(shapes))))
            out[rows, 0] = np.arctan2(direction[:, 1], direction[:, 0])
            out[rows, 1] = np.sum(direction * middle, axis=1)
        return out

    def solve(self, states: np.ndarray, actions: np.ndarray, step: float | None,
              iterations: int = MAX_ITERATIONS, widen: bool = False) -> tuple[bool, float, np.ndarray, np.ndarray]:
        """The problem on ``K`` steps from a first guess: with ``step`` the steps are of that
        length and any motion that keeps the constraints is sought, without it the least step.

        Parameters
        ----------
        states, actions : numpy.ndarray
            The first guess, ``(K + 1, n)`` and ``(K, m)``.
        step : float or None
            The step, or ``None`` for the least.
        iterations : int, default :data:`MAX_ITERATIONS`
            IPOPT's iterations at most (each round).
        widen : bool, default False
            Where it fails, try again with the trust region wider (:data:`WIDER`).

        Returns
        -------
        solved : bool
            Whether IPOPT says it solved the problem and every body clears every obstacle by
            the margin at the solution's states.
        h : float
            The step.
        states, actions : numpy.ndarray
            The solution (IPOPT's states, not a rollout).
        """
        first = states, actions
        for scale in (1.0, *WIDER) if widen else (1.0,):
            states, actions = first
            pairs = self.pairs(states, scale)
            for _ in range(ROUNDS + 1):
                solved, h, states, actions = self._solve(states, actions, step, pairs, iterations, scale)
                if not solved:
                    break
                if self.obstacles.clearances(self.model, states[1:]).min() >= self.obstacles.margin:
                    return solved, h, states, actions
                # the pairs near the solution as well
                pairs = np.unique(np.vstack([pairs, self.pairs(states, scale)]), axis=0)
                solved = False
        return solved, h, states, actions

    def _solve(self, states, actions, step, pairs, iterations, scale):
        """One IPOPT run (:meth:`solve`) with the lines of ``pairs``."""
        import casadi as ca

        K, n, m = actions.shape[0], self.n, self.m
        names = self.model.coordinates
        X, U, h = ca.SX.sym("X", K + 1, n), ca.SX.sym("U", K, m), ca.SX.sym("h")
        P = ca.SX.sym("P", len(pairs), 2)
        constraints, low, high = [], [], []

        def add(expression, lo, hi):
            expression = ca.vec(expression)
            constraints.append(expression)
            low.append(np.broadcast_to(lo, (expression.shape[0],)))
            high.append(np.broadcast_to(hi, (expression.shape[0],)))

        add(X[1:, :] - X[:K, :] - h * rates(self.instance, X[:K, :], U), 0.0, 0.0)
        half = 0.5 * self.obstacles.margin + INNER
        if len(pairs):
            c, s = ca.cos(P[:, 0]), ca.sin(P[:, 0])
            for b, body in enumerate(self.obstacles.bodies):
                rows = np.nonzero(pairs[:, 1] == b)[0]
                if not rows.size:
                    continue
                Xk = X[pairs[rows, 0].tolist(), :]
                x, y = Xk[:, names.index(body.x)], Xk[:, names.index(body.y)]
                heading = Xk[:, names.index(body.heading)]
                hc, hs = ca.cos(heading), ca.sin(heading)
                cx, cy = x - body.behind * hc, y - body.behind * hs
                cb, sb, offset = c[rows.tolist()], s[rows.tolist()], P[rows.tolist(), 1]
                a, w = body.length / 2, body.width / 2
                for lx, ly in ((-a, -w), (a, -w), (a, w), (-a, w)):
                    vx, vy = cx + hc * lx - hs * ly, cy + hs * lx + hc * ly
                    add(cb * vx + sb * vy - offset, half, np.inf)
                for j in range(self.corners.shape[1]):
                    wx, wy = self.corners[pairs[rows, 2], j, 0], self.corners[pairs[rows, 2], j, 1]
                    add(cb * ca.DM(wx) + sb * ca.DM(wy) - offset, -np.inf, -half)
        # the variables' bounds: the start, the goal's box, the workspace, the actions
        goal = np.asarray(self.instance.goal, dtype=float).copy()
        angles = np.asarray(self.model.angles, dtype=bool)
        goal[angles] += 2.0 * np.pi * np.round((states[-1, angles] - goal[angles]) / (2.0 * np.pi))
        x_low = np.tile(self.state_low, (K + 1, 1))
        x_high = np.tile(self.state_high, (K + 1, 1))
        # the trust region round the first guess
        region = np.where(angles, scale * TURN, np.inf)
        region[[names.index(body.x) for body in self.obstacles.bodies]] = scale * REACH
        region[[names.index(body.y) for body in self.obstacles.bodies]] = scale * REACH
        x_low = np.maximum(x_low, states - region)
        x_high = np.minimum(x_high, states + region)
        x_low[0] = x_high[0] = self.instance.start
        x_low[-1] = np.maximum(np.tile(self.state_low, 1), goal - self.goal_box)
        x_high[-1] = np.minimum(np.tile(self.state_high, 1), goal + self.goal_box)
        u_low, u_high = np.tile(self.input_low, (K, 1)), np.tile(self.input_high, (K, 1))
        dt = self.instance.dt
        h_low, h_high = (STEP_RANGE[0] * dt, STEP_RANGE[1] * dt) if step is None else (step, step)
        z = ca.veccat(ca.vec(X), ca.vec(U), h, ca.vec(P))
        free = np.full(2 * len(pairs), np.inf)
        z_low = np.concatenate([x_low.T.ravel(), u_low.T.ravel(), [h_low], -free])
        z_high = np.concatenate([x_high.T.ravel(), u_high.T.ravel(), [h_high], free])
        # the least step (relative to the model's); and the smoothest actions, which makes the
        # problem well posed (the least step leaves the actions free where it is not tight)
        objective = SMOOTHER * ca.sumsqr(U[1:, :] - U[:-1, :]) + (h / dt if step is None else 0.0)
        solver = ca.nlpsol("steps", "ipopt", {"x": z, "f": objective, "g": ca.vertcat(*constraints)},
                           {"print_time": False,
                            "ipopt": {"print_level": 0, "sb": "yes", "max_iter": int(iterations), "tol": TOL,
                                      "constr_viol_tol": TOL, "mu_init": 1e-4, "warm_start_init_point": "yes",
                                      "bound_push": 1e-8, "bound_frac": 1e-8, "slack_bound_push": 1e-8,
                                      "slack_bound_frac": 1e-8}})
        z0 = np.concatenate([states.T.ravel(), np.clip(actions, u_low, u_high).T.ravel(),
                             [np.clip(dt if step is None else step, h_low, h_high)],
                             self.lines(states, pairs).T.ravel()])
        found = solver(x0=np.clip(z0, z_low, z_high), lbx=z_low, ubx=z_high,
                       lbg=np.concatenate(low), ubg=np.concatenate(high))
        zz = np.asarray(found["x"], dtype=float).ravel()
        cut = (K + 1) * n
        solved = solver.stats()["return_status"] in ("Solve_Succeeded", "Solved_To_Acceptable_Level")
        return (solved, float(zz[cut + K * m]), zz[:cut].reshape(n, K + 1).T,
                zz[cut:cut + K * m].reshape(m, K).T)

    def kept(self, actions: np.ndarray) -> Steps | None:
        """The trajectory of actions at the model's step, where its exact Euler steps keep
        every constraint (:meth:`EulerProblem.keeps
        <nonholo.dynobench.euler_steps.EulerProblem.keeps>`) and the project's checker passes it.

        Parameters
        ----------
        actions : numpy.ndarray
            ``(K, m)``.

        Returns
        -------
        Steps or None
            The trajectory.
        """
        if not self.judge.keeps(np.append(actions.ravel(), 1.0)):
            return None
        states = rollout(self.instance, self.model, actions)
        states[:, self.model.angles] = wrap(states[:, self.model.angles])
        report = check(self.instance, states, actions)
        return Steps(states, actions.copy(), 1.0, report) if report.feasible else None


def fewest_steps(instance, actions, obstacles, share: float) -> Steps | None:
    """The trajectory of the fewest Euler steps found from a route's actions (see the module),
    or ``None``.

    Parameters
    ----------
    instance : Instance
        The instance (one of :data:`MODELS`).
    actions : array_like
        The route's actions at the model's step, ``(K, m)``.
    obstacles : Obstacles
        The obstacles, the bodies and the margin kept.
    share : float
        The fraction of Dynobench's thresholds on the bounds and the goal used, in ``[0, 1)``.

    Returns
    -------
    Steps or None
        The shortest trajectory kept.

    Raises
    ------
    ValueError
        If the model is not one of :data:`MODELS` or ``share`` is not in ``[0, 1)``.
    """
    program = SparseSteps(instance, obstacles, share)
    actions = np.asarray(actions, dtype=float)
    states, count, best = rollout(instance, program.model, actions), actions.shape[0], None
    # a trajectory at the model's step: the route's count, or a few steps more
    for more in range(EXTRA_STEPS + 1):
        solved, _, found_states, found = program.solve(*resampled(states, actions, count + more), instance.dt,
                                                       widen=True)
        best = program.kept(found) if solved else None
        if best is not None:
            break
    if best is None:
        return None
    failed = None                      # the most steps known not to solve
    for _ in range(LEAST_ROUNDS):
        # the least step on its count, from it; the count that time needs at the model's step
        solved, h, least_states, least_actions = program.solve(found_states, best.actions, None)
        fewer = math.ceil(len(best.actions) * h / instance.dt - 1e-9) if solved else len(best.actions)
        if fewer >= len(best.actions):
            break
        solved, _, fewer_states, found = program.solve(*resampled(least_states, least_actions, fewer), instance.dt)
        kept = program.kept(found) if solved else None
        if kept is None:
            failed = fewer
            break
        best, found_states = kept, fewer_states
    # then the fewest between: one step fewer while that solves, or halving the gap to a count
    # that did not
    while len(best.actions) > 1 and (failed is None or len(best.actions) - failed > 1):
        count = len(best.actions) - 1 if failed is None else (failed + len(best.actions)) // 2
        solved, _, fewer_states, found = program.solve(*resampled(found_states, best.actions, count), instance.dt,
                                                       TRIAL_ITERATIONS)
        kept = program.kept(found) if solved else None
        if kept is None:
            failed = count
            continue
        best, found_states = kept, fewer_states
    return best
