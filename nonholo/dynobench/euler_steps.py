"""Dynobench's own problem of an instance: ``K`` explicit Euler steps of its model at ``dt``,
the bounds kept and the bodies clear of the obstacles at the states, the last state at the
goal — solved for fewer steps than the continuous plan's.

The continuous plan (:mod:`nonholo.dynobench.solve`) is the mechanism's least time, rounded
up to whole steps. Dynobench judges something else: the Euler steps of its model, and only at
the states. :func:`fewest_steps` takes the plan's ``K`` actions and tries ``K − 1``,
``K − 2``, … steps, each from the last path's actions spread over one step fewer. At each it
seeks the least use ``s`` of the input bounds over the actions (SciPy's SLSQP; the Euler
steps' sensitivities exact, from the model's Jacobians). A path is kept where it keeps every
constraint, ``s ≤ 1``, and the project's checker passes it; the first count that fails ends
the search. Each search runs at most :data:`MAX_ITERATIONS` iterations: the same call gives
the same path on any machine.

The bounds and the goal are kept to the fraction ``share`` of Dynobench's thresholds
(:data:`~nonholo.dynobench.checker.BOUND_TOL`, :data:`~nonholo.dynobench.checker.GOAL_TOL`):
every bound widened by ``share · BOUND_TOL``, the last state within ``share · GOAL_TOL`` of
the goal in the model's distance; ``share = 0`` keeps them exactly (the goal an equality).
The bodies keep clear of the obstacles by the obstacles' margin at every state (none
overlaps one: Dynobench's own collision check was seen to hang on a body that does). The
start is kept exactly and the steps are the model's, with no gap.

The models (:data:`EULER_MODELS`): those whose state and actions are their catalog
mechanism's coordinates and inputs (:class:`MechanismModel`: its generated ``G``, drift and
variational matrix ``QG``), and Dynobench's car with a trailer, whose steering angle is an
action (:class:`CarWithTrailer`). Only short trajectories are solved
(:data:`STEPS_AT_MOST`): SLSQP's dense quadratic programs grow with the cube of the
actions' count.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model import catalog
from .checker import BOUND_TOL, GOAL_TOL, Report, check, wrap

#: The models solved here: those whose state and actions are their catalog mechanism's
#: coordinates and inputs, and the car with a trailer (:class:`CarWithTrailer`).
EULER_MODELS = ("unicycle1", "unicycle2", "car_with_trailers")
#: Trajectories of more steps than this are left as the continuous plan gives them.
STEPS_AT_MOST = 80
#: SLSQP's iterations at most, per count of steps.
MAX_ITERATIONS = 300
#: SLSQP's tolerance on ``s``.
FTOL = 1e-10
#: A path keeps a constraint it breaks by less than this (its units).
KEPT_TOL = 1e-9
#: The nonlinear constraints are kept by this much more in the optimisation (their units), so
#: that SLSQP's answer keeps them to :data:`KEPT_TOL`.
INNER = 1e-6
#: The goal's distance ``|e|`` is kept as ``√(e² + ε²)`` (smooth, never below ``|e|``) with
#: this ``ε``.
SMOOTHING = 1e-5


@dataclass(frozen=True)
class Steps:
    """A trajectory of Euler steps that passes the checks (:func:`fewest_steps`).

    Parameters
    ----------
    states : numpy.ndarray
        ``(K + 1, n)``, angles in ``[−π, π)``.
    actions : numpy.ndarray
        ``(K, m)``.
    use : float
        The fraction ``s`` of the (widened) input bounds its actions use.
    report : Report
        The project's check of it.
    """

    states: np.ndarray
    actions: np.ndarray
    use: float
    report: Report


class MechanismModel:
    """A model whose state and actions are its catalog mechanism's coordinates and inputs:
    ``f = G(x) u (+ F(x))``, its Jacobians the generated ``QG`` and ``G``.

    Parameters
    ----------
    instance : Instance
        The instance.
    """

    def __init__(self, instance):
        self.mechanism = catalog.get(instance.mechanism)
        self.coordinates = self.mechanism.coordinates
        self.angles = np.asarray(self.mechanism.angles, dtype=bool)
        self.drift = self.mechanism.drift is not None
        self._eye = np.eye(3)

    def rates(self, x, u) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The rates ``f(x, u)`` and their Jacobians ``∂f/∂x``, ``∂f/∂u``.

        Parameters
        ----------
        x, u : numpy.ndarray
            A state and an action.

        Returns
        -------
        tuple of numpy.ndarray
            ``f``, ``∂f/∂x``, ``∂f/∂u``.
        """
        mech = self.mechanism
        G = mech.G(self._eye, x)
        f = G @ u if mech.drift is None else G @ u + mech.drift(self._eye, x)
        return f, mech.module.QG(self._eye, x, u), G


class CarWithTrailer:
    """Dynobench's car with one trailer (``car_with_trailers``): state ``(x, y, θ0, θ1)``,
    actions the speed and the steering angle ``(v, φ)``, ``ẋ = v cos θ0``, ``ẏ = v sin θ0``,
    ``θ̇0 = v tan φ / l``, ``θ̇1 = v sin(θ0 − θ1) / d`` (``src/car_with_trailers.cpp``).

    Parameters
    ----------
    instance : Instance
        The instance (its wheelbase ``l`` and hitch length ``d``).
    """

    coordinates = ("x", "y", "theta", "theta1")
    angles = np.array([False, False, True, True])
    drift = False

    def __init__(self, instance):
        self.wheelbase, self.hitch = float(instance.wheelbase), float(instance.hitch)

    def rates(self, x, u) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The rates ``f(x, u)`` and their Jacobians ``∂f/∂x``, ``∂f/∂u``.

        Parameters
        ----------
        x, u : numpy.ndarray
            A state and an action.

        Returns
        -------
        tuple of numpy.ndarray
            ``f``, ``∂f/∂x``, ``∂f/∂u``.
        """
        th0, th1 = x[2], x[3]
        v, phi = u
        c, s, t = math.cos(th0), math.sin(th0), math.tan(phi)
        ch, sh = math.cos(th0 - th1), math.sin(th0 - th1)
        L, d = self.wheelbase, self.hitch
        f = np.array([v * c, v * s, v * t / L, v * sh / d])
        fx = np.zeros((4, 4))
        fx[0, 2], fx[1, 2] = -v * s, v * c
        fx[3, 2], fx[3, 3] = v * ch / d, -v * ch / d
        fu = np.array([[c, 0.0], [s, 0.0], [t / L, v / (L * math.cos(phi) ** 2)], [sh / d, 0.0]])
        return f, fx, fu


def model_of(instance):
    """The model of the Euler steps of an instance (:data:`EULER_MODELS`).

    Parameters
    ----------
    instance : Instance
        The instance.

    Returns
    -------
    MechanismModel or CarWithTrailer
        Its rates and their Jacobians.
    """
    return CarWithTrailer(instance) if instance.dynamics == "car_with_trailers" else MechanismModel(instance)


class EulerProblem:
    """The least use ``s`` of the input bounds over the actions of ``K`` Euler steps (see the
    module): variables ``(actions, s)``.

    Parameters
    ----------
    instance : Instance
        The instance (one of :data:`EULER_MODELS`).
    input_bounds : InputBounds
        The model's action bounds.
    state_bounds : StateBounds
        The model's state bounds (the workspace's on the position).
    obstacles : Obstacles
        The obstacles, the bodies and the margin they keep.
    share : float
        The fraction of Dynobench's thresholds on the bounds and the goal used.
    """

    def __init__(self, instance, input_bounds, state_bounds, obstacles, share: float):
        self.instance = instance
        self.model = model_of(instance)
        self.n, self.m = len(self.model.coordinates), len(input_bounds.lows)
        self.share = share
        widen = share * BOUND_TOL
        self.input_low = np.asarray(input_bounds.lows, dtype=float) - widen
        self.input_high = np.asarray(input_bounds.highs, dtype=float) + widen
        self.state_low = np.asarray(state_bounds.lows, dtype=float) - widen
        self.state_high = np.asarray(state_bounds.highs, dtype=float) + widen
        self.obstacles = obstacles
        self.goal_radius = share * GOAL_TOL
        self.angles = self.model.angles
        self.start = np.asarray(instance.start, dtype=float)
        self.goal = np.asarray(instance.goal, dtype=float)
        # the model's distance: the position's norm, then the other coordinates' weights
        self.weights = np.asarray(instance.weights, dtype=float)[1:]
        self._key, self._value = None, None

    def rollout(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The states of the Euler steps and their sensitivities to the actions.

        Parameters
        ----------
        actions : numpy.ndarray
            ``(K, m)``.

        Returns
        -------
        states : numpy.ndarray
            ``(K + 1, n)`` (angles not wrapped).
        sensitivities : numpy.ndarray
            ``(K + 1, n, K m)``: ``∂x_k/∂(actions)``.
        """
        dt, K, n, m = self.instance.dt, actions.shape[0], self.n, self.m
        identity = np.eye(n)
        states = np.empty((K + 1, n))
        states[0] = self.start
        sens = np.zeros((K + 1, n, K * m))
        for k in range(K):
            rate, fx, fu = self.model.rates(states[k], actions[k])
            states[k + 1] = states[k] + dt * rate
            sens[k + 1] = (identity + dt * fx) @ sens[k]
            sens[k + 1][:, k * m:(k + 1) * m] += dt * fu
        return states, sens

    def _evaluated(self, z):
        """The rollout of ``z``'s actions and the clearances' rows (kept for the same ``z``)."""
        K = (z.size - 1) // self.m
        key = z[:-1].tobytes()
        if key != self._key:
            states, sens = self.rollout(z[:-1].reshape(K, self.m))
            c, grad = self.obstacles.clearance_rows(self.model, states[1:])             # (K, b), (K, b, n)
            rows = np.einsum("kbn,knp->kbp", grad, sens[1:]).reshape(-1, K * self.m)
            self._key, self._value = key, (states, sens, c.ravel(), rows)
        return self._value

    def error(self, z) -> np.ndarray:
        """The last state's difference from the goal (angles wrapped).

        Parameters
        ----------
        z : numpy.ndarray
            The variables.

        Returns
        -------
        numpy.ndarray
            ``(n,)``.
        """
        e = self._evaluated(z)[0][-1] - self.goal
        e[self.angles] = wrap(e[self.angles])
        return e

    def goal_terms(self, inner: float = INNER):
        """The goal as SLSQP's constraint: ``e = 0`` (``share = 0``), else the smoothed
        model's distance within the goal's radius.

        Parameters
        ----------
        inner : float, default :data:`INNER`
            How much more the distance is kept within it.

        Returns
        -------
        dict
            SLSQP's constraint.
        """
        def jac_of(z, rows):
            out = np.zeros((rows.shape[0], z.size))
            out[:, :-1] = rows @ self._evaluated(z)[1][-1]
            return out

        if self.goal_radius == 0.0:
            return {"type": "eq", "fun": self.error, "jac": lambda z: jac_of(z, np.eye(self.n))}
        eps2 = SMOOTHING ** 2

        def parts(z):
            e = self.error(z)
            norm = math.sqrt(e[0] ** 2 + e[1] ** 2 + eps2)
            rest = np.sqrt(e[2:] ** 2 + eps2)
            return e, norm, rest

        def value(z):
            _, norm, rest = parts(z)
            return np.array([self.goal_radius - norm - float(self.weights @ rest)]) - inner

        def jac(z):
            e, norm, rest = parts(z)
            g = np.concatenate([e[:2] / norm, self.weights * e[2:] / rest])
            return -jac_of(z, g[None, :])

        return {"type": "ineq", "fun": value, "jac": jac}

    def limit_terms(self, inner: float = INNER):
        """The clearances and the state bounds at the states after the start (``≥ 0``).

        Parameters
        ----------
        inner : float, default :data:`INNER`
            How much more they are kept by.

        Returns
        -------
        dict
            SLSQP's constraint.
        """
        low, high = np.isfinite(self.state_low), np.isfinite(self.state_high)

        def value(z):
            states, _, c, _ = self._evaluated(z)
            later = states[1:]
            return np.concatenate([c - self.obstacles.margin, (later[:, low] - self.state_low[low]).ravel(),
                                   (self.state_high[high] - later[:, high]).ravel()]) - inner

        def jac(z):
            _, sens, _, rows = self._evaluated(z)
            p = z.size - 1
            out = np.concatenate([rows, sens[1:, low, :].reshape(-1, p), -sens[1:, high, :].reshape(-1, p)])
            return np.hstack([out, np.zeros((out.shape[0], 1))])

        return {"type": "ineq", "fun": value, "jac": jac}

    def bounds_rows(self, K: int) -> tuple[np.ndarray, np.ndarray]:
        """``A z ≥ b`` on the actions: a side that holds zero scaled by ``s``
        (``s·high − u ≥ 0``, ``u − s·low ≥ 0``), a side off zero kept as it is.

        Parameters
        ----------
        K : int
            The steps.

        Returns
        -------
        A : numpy.ndarray
            One row per finite side of every step's action, ``(rows, K m + 1)``.
        b : numpy.ndarray
            The constants.
        """
        A, b = [], []
        for k in range(K):
            for i in range(self.m):
                for sign, bound in ((-1.0, self.input_high[i]), (1.0, self.input_low[i])):
                    if not math.isfinite(bound):
                        continue
                    row = np.zeros(K * self.m + 1)
                    row[k * self.m + i] = sign
                    if sign * bound <= 0.0:          # the side holds zero: scaled by s
                        row[-1] = -sign * bound
                        b.append(0.0)
                    else:                            # off zero: as it is
                        b.append(sign * bound)
                    A.append(row)
        return np.array(A).reshape(-1, K * self.m + 1), np.array(b)

    def solve(self, guess: np.ndarray, iterations: int = MAX_ITERATIONS):
        """The least use ``s`` over ``K`` steps' actions, from ``guess``.

        Parameters
        ----------
        guess : numpy.ndarray
            ``(K, m)`` actions.
        iterations : int, default :data:`MAX_ITERATIONS`
            SLSQP's iterations at most.

        Returns
        -------
        actions : numpy.ndarray
            ``(K, m)``.
        use : float
            ``s``.
        kept : bool
            Whether they keep every constraint (to :data:`KEPT_TOL`), whether or not SLSQP
            says it converged.
        """
        from scipy.optimize import minimize

        K = guess.shape[0]
        A, b = self.bounds_rows(K)
        scale = np.where(guess > 0.0, self.input_high, -self.input_low)
        used = np.abs(guess) / np.where(np.isfinite(scale) & (scale > 0.0), scale, np.inf)
        z0 = np.append(guess.ravel(), max(float(used.max()), 1e-6))
        objective = np.zeros(z0.size)
        objective[-1] = 1.0
        goal, limits = self.goal_terms(), self.limit_terms()
        found = minimize(lambda z: z[-1], z0, jac=lambda z: objective, method="SLSQP",
                         constraints=[goal, {"type": "ineq", "fun": lambda z: A @ z - b, "jac": lambda z: A}, limits],
                         options={"maxiter": iterations, "ftol": FTOL})
        z = found.x
        return z[:-1].reshape(K, self.m), float(z[-1]), self.keeps(z)

    def keeps(self, z) -> bool:
        """Whether variables keep every constraint to :data:`KEPT_TOL`, judged on the
        constraints themselves (no inner margin).

        Parameters
        ----------
        z : numpy.ndarray
            The actions, flattened, and the use ``s``.

        Returns
        -------
        bool
            Whether they do.
        """
        A, b = self.bounds_rows((z.size - 1) // self.m)
        goal = self.goal_terms(0.0)
        reached = goal["fun"](z)
        return bool(np.all(A @ z - b >= -KEPT_TOL) and np.all(self.limit_terms(0.0)["fun"](z) >= -KEPT_TOL)
                    and (np.all(np.abs(reached) <= KEPT_TOL) if goal["type"] == "eq" else np.all(reached >= -KEPT_TOL)))


def spread(actions: np.ndarray, K: int, drift: bool) -> np.ndarray:
    """Actions over ``K`` steps from another count's: linear in the fraction of the motion,
    and — without drift, where the actions are rates — faster by the ratio of the counts.

    Parameters
    ----------
    actions : numpy.ndarray
        ``(K0, m)``.
    K : int
        The new count.
    drift : bool
        Whether the model has drift.

    Returns
    -------
    numpy.ndarray
        ``(K, m)``.
    """
    K0 = actions.shape[0]
    old, new = (np.arange(K0) + 0.5) / K0, (np.arange(K) + 0.5) / K
    out = np.column_stack([np.interp(new, old, a) for a in actions.T])
    return out if drift else out * (K0 / K)


def fewest_steps(instance, actions, obstacles, share: float, first: bool = False) -> Steps | None:
    """The trajectory of the fewest Euler steps found below the continuous plan's (see the
    module), or ``None`` where there is none, or the model or the trajectory is not one
    this solves.

    Parameters
    ----------
    instance : Instance
        The instance (its model's bounds kept).
    actions : array_like
        The continuous plan's actions, ``(K, m)``.
    obstacles : Obstacles
        The obstacles, the bodies and the margin they keep at the states.
    share : float
        The fraction of Dynobench's thresholds on the bounds and the goal used, in ``[0, 1)``.
    first : bool, default False
        Try ``K`` steps first (``actions`` a first guess, not a trajectory that passes).

    Returns
    -------
    Steps or None
        The shortest trajectory kept.

    Raises
    ------
    ValueError
        If ``share`` is not in ``[0, 1)``.
    """
    from ..model.bounds import InputBounds, StateBounds

    if not (isinstance(share, (int, float)) and 0.0 <= share < 1.0):
        raise ValueError(f"share must be a number in [0, 1), got {share!r}")
    actions = np.asarray(actions, dtype=float)
    if instance.dynamics not in EULER_MODELS or actions.shape[0] > STEPS_AT_MOST:
        return None
    problem = EulerProblem(instance, InputBounds(tuple(instance.input_low), tuple(instance.input_high)),
                           StateBounds(tuple(instance.state_low), tuple(instance.state_high)), obstacles, float(share))
    best = None
    for K in range(actions.shape[0] - (0 if first else 1), 0, -1):
        found, use, kept = problem.solve(spread(actions, K, problem.model.drift))
        if not (kept and use <= 1.0):
            break
        states = problem.rollout(found)[0]
        states[:, problem.angles] = wrap(states[:, problem.angles])
        report = check(instance, states, found)
        if not report.feasible:
            break
        best, actions = Steps(states, found, use, report), found
    return best
