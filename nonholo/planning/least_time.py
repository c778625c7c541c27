"""The path of least time under input bounds (``objective="time"``).

A driftless system follows a path at any pace: a control on ``[0, T]`` whose inputs use at
most the fraction ``s`` of their bounds (``s·low_i ≤ u_i(t) ≤ s·high_i``, bounds around zero)
is played in ``sT`` at full use. The least time is therefore ``T`` times the least ``s``
over the controls that reach the goal in ``T`` — a problem with a linear objective, linear
bounds on the controls, the endpoint as a nonlinear equality and the limits of the motion
(the coordinates' bounds, the legs' stroke, the clearance from ``Δ = 0``) as nonlinear
inequalities at the nodes — the same least time as a free-time transcription on the same
grid of equal intervals. It is solved on grid controls (:data:`TIME_GRID` intervals) by
SciPy's SLSQP from a given path — :func:`nonholo.plan` gives the least-energy one, short and
mostly in the time-optimal path's class, where the plan as found may loop — with the
endpoint's Jacobian and the nodes' sensitivities of the variational system (:mod:`nonholo.planning.endpoint_map`); the path
found is then brought onto the goal, certified, and re-timed to the least time along it by
:func:`nonholo.planning.retime.limit_inputs` (the caller's step).

SLSQP runs a fixed number of iterations at most (:data:`MAX_ITERATIONS`): the same call
gives the same path on any machine under any load.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..controls.parametrisations import PiecewiseConstant
from ..io.result import PlanResult
from .core import Outcome, record
from .correction import certified
from .endpoint_map import EndpointMap, node_sensitivities, spatial_gradient_delta
from .energy_optimiser import RESTORE_STEPS, newton_steps
from .result_builder import build_result

#: Intervals of the grid controls the path is sought among.
TIME_GRID = 50
#: SLSQP iterations at most.
MAX_ITERATIONS = 200
#: SLSQP's tolerance on the objective ``s``.
FTOL = 1e-10
#: The limits of the motion are kept with this margin (their units) in the optimisation, so
#: that the path found is inside them when it is brought onto the goal.
MARGIN = 1e-7


class PathProblem:
    """The least-``s`` problem on grid controls (see the module): variables ``x = (λ, s)``.

    Parameters
    ----------
    endpoint : EndpointMap
        The problem on grid controls.
    grid : int
        The intervals.
    low, high : numpy.ndarray
        The inputs' bounds (``±inf`` where free; ``low ≤ 0 ≤ high``).
    """

    def __init__(self, endpoint: EndpointMap, grid: int, low: np.ndarray, high: np.ndarray):
        self.endpoint = endpoint
        self.mechanism = endpoint.mechanism
        self.grid = grid
        self.m = self.mechanism.n_inputs
        self.p = grid * self.m
        self.low, self.high = low, high
        r = endpoint.steps // grid
        # the nodes at the ends and the middles of the intervals (not the start: it is given)
        self.nodes = np.arange(max(r // 2, 1), endpoint.steps + 1, max(r // 2, 1))
        self.evaluations = 0
        self._key, self._ev = None, None

    def evaluation(self, x: np.ndarray):
        """The full evaluation of ``x``'s controls (kept for the next call with the same ``x``).

        Parameters
        ----------
        x : numpy.ndarray
            The variables ``(λ, s)``.

        Returns
        -------
        Evaluation
            The evaluation, with the nodes' sensitivities.
        """
        key = x[:self.p].tobytes()
        if key != self._key:
            self._ev = self.endpoint.evaluate(PiecewiseConstant(self.endpoint.T, x[:self.p].reshape(self.grid, self.m)),
                                              full=True)
            self._key = key
            self.evaluations += 1
        return self._ev

    def bounds_matrix(self) -> np.ndarray:
        """``A x ≥ 0``: ``s·high_i − u_ji ≥ 0`` and ``u_ji − s·low_i ≥ 0`` for the finite sides.

        Returns
        -------
        numpy.ndarray
            ``A``, one row per finite side of every interval's input.
        """
        rows = []
        for j in range(self.grid):
            for i in range(self.m):
                for side, bound in ((1.0, self.high[i]), (-1.0, self.low[i])):
                    if not math.isfinite(bound):
                        continue
                    row = np.zeros(self.p + 1)
                    row[j * self.m + i] = -side
                    row[-1] = side * bound
                    rows.append(row)
        return np.array(rows).reshape(-1, self.p + 1)

    def goal(self, x):
        """The terminal error ``l_T`` (the equality ``l_T = 0``); a motion that stops short
        of ``T`` is far from the goal.

        Parameters
        ----------
        x : numpy.ndarray
            The variables ``(λ, s)``.

        Returns
        -------
        numpy.ndarray
            ``l_T``, d entries.
        """
        ev = self.evaluation(x)
        if not ev.complete:
            return np.full(self.mechanism.n_rates, 1e3)
        return ev.l

    def goal_jacobian(self, x):
        """``∂l_T/∂x`` (``J``, and no dependence on ``s``).

        Parameters
        ----------
        x : numpy.ndarray
            The variables ``(λ, s)``.

        Returns
        -------
        numpy.ndarray
            The Jacobian, ``(d, p + 1)``.
        """
        ev = self.evaluation(x)
        out = np.zeros((self.mechanism.n_rates, self.p + 1))
        if ev.complete:
            out[:, :self.p] = ev.J
        return out

    def _limits(self, x):
        """The clearances of the motion's limits at the nodes and their gradients (in ``λ``)."""
        ev = self.evaluation(x)
        if not ev.complete:
            return None
        mech, endpoint = self.mechanism, self.endpoint
        values, rows, at = [], [], []
        if endpoint.limits is not None:
            terms = endpoint.limits.clearance_terms(mech, ev.R[self.nodes], math.inf, ev.q[self.nodes])
            if terms is not None:
                nodes, c, grad = terms
                values.append(c - MARGIN)
                rows.append(grad)
                at.append(self.nodes[nodes])
        if mech.singular.exists:
            R, q = ev.R[self.nodes], ev.q[self.nodes]
            values.append(endpoint.sign * mech.singular.values(R, q) - endpoint.delta_min - MARGIN)
            rows.append(endpoint.sign * spatial_gradient_delta(mech, R, q=q))
            at.append(self.nodes)
        if not values:
            return np.zeros(0), np.zeros((0, self.p + 1))
        at = np.concatenate(at)
        rows = np.concatenate(rows)
        S = node_sensitivities(endpoint, ev, at)                 # (a, d, p)
        jac = np.zeros((at.size, self.p + 1))
        jac[:, :self.p] = np.einsum("ad,adp->ap", rows, S)
        return np.concatenate(values), jac

    def limits(self, x):
        """The clearances (``≥ 0``); a motion that stops short of ``T`` breaks them.

        Parameters
        ----------
        x : numpy.ndarray
            The variables ``(λ, s)``.

        Returns
        -------
        numpy.ndarray
            One clearance per node and limit.
        """
        out = self._limits(x)
        return -np.ones(self.nodes.size) if out is None else out[0]

    def limits_jacobian(self, x):
        """The clearances' gradients.

        Parameters
        ----------
        x : numpy.ndarray
            The variables ``(λ, s)``.

        Returns
        -------
        numpy.ndarray
            One row per clearance.
        """
        out = self._limits(x)
        return np.zeros((self.nodes.size, self.p + 1)) if out is None else out[1]


def least_time_path(problem, result: PlanResult) -> PlanResult:
    """The path of least time under the problem's input bounds, from a plan (see the
    module), certified on grid controls; ``result`` with its reason saying why where none
    is found. The plan's grid controls need only reach ``T``: SLSQP starts where they
    break a limit or miss the goal as well.

    Parameters
    ----------
    problem : Problem
        The problem (its input bounds around zero).
    result : PlanResult
        Its certified plan.

    Returns
    -------
    PlanResult
        The path of least time (not re-timed), or ``result``.
    """
    options = {**result.options, "objective": "time"}
    bounds = problem.input_bounds
    if not result.success or bounds is None:
        return replace(result, options=options)
    low, high = bounds.lows, bounds.highs
    grid = TIME_GRID
    steps = -(-problem.steps // grid) * grid
    endpoint = problem.evaluator(method="nonparametric", steps=steps)
    fitted = PiecewiseConstant.fit(result.controls, endpoint.T, grid, problem.mechanism.n_inputs)
    ev = endpoint.evaluate(fitted, delta_stop=-math.inf)
    if ev.complete:
        ev = newton_steps(endpoint, ev, fitted.metric(), problem.options.tol, RESTORE_STEPS)
    if not ev.complete:
        return replace(result, options=options,
                       reason=f"{result.reason}; the least-time path not sought: the plan's grid controls do "
                              f"not reach T")
    from scipy.optimize import minimize      # loaded by the first least-time plan, not by `import nonholo`

    path = PathProblem(endpoint, grid, low, high)
    lam = ev.params
    x0 = np.append(lam, max(float(bounds.usage(lam.reshape(grid, -1)).max()), 1e-9))
    A = path.bounds_matrix()
    constraints = [{"type": "eq", "fun": path.goal, "jac": path.goal_jacobian},
                   {"type": "ineq", "fun": lambda x: A @ x, "jac": lambda x: A},
                   {"type": "ineq", "fun": path.limits, "jac": path.limits_jacobian}]
    objective_row = np.zeros(path.p + 1)
    objective_row[-1] = 1.0
    found = minimize(lambda x: x[-1], x0, jac=lambda x: objective_row, method="SLSQP", constraints=constraints,
                     options={"maxiter": MAX_ITERATIONS, "ftol": FTOL})
    ev = endpoint.evaluate(PiecewiseConstant(endpoint.T, found.x[:path.p].reshape(grid, -1)))
    ev = newton_steps(endpoint, ev, fitted.metric(), problem.options.tol, RESTORE_STEPS)
    s0, s = float(x0[-1]), float(found.x[-1])
    if not (endpoint.admissible(ev) and ev.error <= problem.options.tol) or not s < s0:
        why = ("its motion is not admissible or does not end at the goal" if s < s0
               else f"it is not faster than the plan's ({s:.6g} ≥ {s0:.6g} of the bounds in T)")
        return replace(result, options=options,
                       reason=f"{result.reason}; the least-time path not taken ({found.message}): {why}")
    outcome = Outcome(evaluation=ev, success=True,
                      reason=(f"{result.reason}; then the path of least time under the input bounds: "
                              f"{s:.6g} of them in T = {endpoint.T:g} s (the plan's {s0:.6g}; SLSQP, "
                              f"{found.nit} iterations, {path.evaluations} evaluations: {found.message})"),
                      history=result.history + [record(result.iterations + 1, ev, 1.0, "time", 0, use=s)],
                      iterations=result.iterations + int(found.nit))
    outcome = certified(outcome, endpoint, problem.options)
    if not outcome.success:
        return replace(result, options=options,
                       reason=f"{result.reason}; the least-time path not taken: {outcome.reason}")
    lowered = problem.with_settings(method="nonparametric", grid=grid, steps=steps)
    built = build_result(lowered, outcome, True, outcome.reason, endpoint)
    return replace(built, options={**built.options, "objective": "time"}, route=result.route)
