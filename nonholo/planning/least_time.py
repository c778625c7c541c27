"""The path of least time under input bounds (``objective="time"``).

A driftless system follows a path at any pace: a control on ``[0, T]`` whose inputs use at
most the fraction ``s`` of their bounds (``s·low_i ≤ u_i(t) ≤ s·high_i``) is played in
``sT`` at full use, every input divided by ``s`` (so a bound off zero, ``0 < low_i``, is kept
as well). The least time is therefore ``T`` times the least ``s``
over the controls that reach the goal in ``T`` — a problem with a linear objective, linear
bounds on the controls, the endpoint as a nonlinear equality and the limits of the motion
(the coordinates' bounds, the legs' stroke, the clearance from ``Δ = 0``) as nonlinear
inequalities at the nodes — the same least time as a free-time transcription on the same
grid of equal intervals. It is solved on grid controls (:data:`TIME_GRID` intervals) by
SciPy's SLSQP from a given path — :func:`nonholo.plan` gives the least-energy one, short and
mostly in the time-optimal path's class, where the plan as found may loop — with the
endpoint's Jacobian and the nodes' sensitivities of the variational system (:mod:`nonholo.planning.endpoint_map`); the path
found is then brought onto the goal, certified, and re-timed to the least time along it by
:func:`nonholo.planning.retime.limit_inputs` (the caller's step) — or, under bounds off zero,
which a re-timing along the path cannot keep, played in ``sT`` (:func:`least_time_off_zero`).

SLSQP runs a fixed number of iterations at most (:data:`MAX_ITERATIONS`): the same call
gives the same path on any machine under any load.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, replace

import numpy as np

from ..controls.parametrisations import PiecewiseConstant
from ..io.result import PlanResult
from ..model.bounds import BOUND_RTOL, StateBounds
from .core import Outcome, record
from .correction import certified
from .endpoint_map import EndpointMap, node_sensitivities, spatial_gradient_delta
from .energy_optimiser import RESTORE_STEPS, newton_steps
from .result_builder import build_result

#: Intervals of the grid controls the path is sought among.
TIME_GRID = 50
#: SLSQP iterations at most.
MAX_ITERATIONS = 200
#: Where a path found crosses a limit between the nodes, SLSQP runs again from it this many
#: times at most, ...
CROSSING_ROUNDS = 2
#: ... the margin at the nodes grown by this many times the depth it crossed the limit by.
CROSSING_MARGIN = 2.0
#: Evaluations SLSQP may take beyond ``struggle`` per iteration (:func:`least_use`).
STRUGGLE_SLACK = 20
#: The least time with drift stops SLSQP at a horizon after the first once it takes this
#: many evaluations per iteration (:func:`least_time_with_drift`): a path found near the last
#: one needs about one.
STRUGGLE = 2.0
#: SLSQP's iterations at most at a horizon tried after one that keeps the bounds
#: (:func:`least_time_with_drift`).
TRIAL_ITERATIONS = 40
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
    obstacles : Obstacles, optional
        Polygons the vehicle's bodies keep clear of at the nodes.
    scaled : bool, default False
        Scale the state bounds around zero (``low_j < 0 < high_j``) by ``s`` as well.
    """

    def __init__(self, endpoint: EndpointMap, grid: int, low: np.ndarray, high: np.ndarray, obstacles=None,
                 scaled: bool = False):
        self.endpoint = endpoint
        self.obstacles = obstacles
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
        self._limits_key, self._limits_value = None, None
        #: the margin the limits are kept by at the nodes
        self.margin = MARGIN
        #: whether the state bounds around zero are scaled by ``s``
        self.scaled = scaled

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
        """The clearances of the motion's limits at the nodes and their gradients (in ``λ``),
        kept for the next call with the same ``x`` (SLSQP asks for both in turn)."""
        key = x[:self.p].tobytes()
        if key != self._limits_key:
            self._limits_value, self._limits_key = self._limits_of(x), key
        return self._limits_value

    def _limits_of(self, x):
        """:meth:`_limits`, computed."""
        ev = self.evaluation(x)
        if not ev.complete:
            return None
        mech, endpoint = self.mechanism, self.endpoint
        values, rows, at, scales = [], [], [], []
        for part in () if endpoint.limits is None else endpoint.limits.parts:
            terms = part.clearance_terms(mech, ev.R[self.nodes], math.inf, q=ev.q[self.nodes])
            if terms is not None:
                nodes, c, grad = terms
                values.append(c - self.margin)
                rows.append(grad)
                at.append(self.nodes[nodes])
                # every node's every side, in order (no threshold)
                scaled = self.scaled and isinstance(part, StateBounds)
                scales.append(np.tile(part.around_zero(), self.nodes.size) if scaled else np.zeros(c.size))
        if mech.singular.exists:
            R, q = ev.R[self.nodes], ev.q[self.nodes]
            values.append(endpoint.sign * mech.singular.values(R, q) - endpoint.delta_min - MARGIN)
            rows.append(endpoint.sign * spatial_gradient_delta(mech, R, q=q))
            at.append(self.nodes)
            scales.append(np.zeros(self.nodes.size))
        if self.obstacles is not None:
            c, grad = self.obstacles.clearance_rows(mech, ev.q[self.nodes])       # (a, b), (a, b, k)
            values.append((c - self.obstacles.margin - MARGIN).ravel())
            rows.append(grad.reshape(-1, grad.shape[-1]))
            at.append(np.repeat(self.nodes, c.shape[1]))
            scales.append(np.zeros(c.size))
        if not values:
            return np.zeros(0), np.zeros((0, self.p + 1))
        at = np.concatenate(at)
        rows = np.concatenate(rows)
        S = node_sensitivities(endpoint, ev, at)                 # (a, d, p)
        jac = np.zeros((at.size, self.p + 1))
        jac[:, :self.p] = np.einsum("ad,adp->ap", rows, S)
        # a bound scaled by s: the clearance s·|bound| − (|bound| − c), its rate |bound| in s
        jac[:, -1] = np.concatenate(scales)
        return np.concatenate(values) - jac[:, -1], jac

    def state_use(self, q) -> float:
        """The fraction of the state bounds around zero the coordinates ``q`` use (0 unless
        the problem scales them).

        Parameters
        ----------
        q : numpy.ndarray
            Coordinates, ``(n, k)``.

        Returns
        -------
        float
            The largest ``q_j / high_j`` or ``q_j / low_j``.
        """
        use = 0.0
        for part in () if not self.scaled or self.endpoint.limits is None else self.endpoint.limits.parts:
            if isinstance(part, StateBounds):
                for j in np.nonzero((np.asarray(part.lows) < 0.0) & (np.asarray(part.highs) > 0.0))[0]:
                    use = max(use, float(np.max(q[:, j] / part.highs[j])), float(np.max(q[:, j] / part.lows[j])))
        return use

    def widen(self, by: float) -> None:
        """Keep the limits at the nodes by more.

        Parameters
        ----------
        by : float
            How much more (the limits' units).
        """
        self.margin += by
        self._limits_key = None

    def crossing(self, ev) -> float:
        """How far the motion of ``ev`` crosses a limit at any step (0 where it does not):
        between the nodes a motion that rides a limit at them may cross it.

        Parameters
        ----------
        ev : Evaluation
            A complete evaluation.

        Returns
        -------
        float
            The deepest crossing, in the limit's units.
        """
        limits = self.endpoint.limits
        terms = None if limits is None or not ev.complete else limits.clearance_terms(self.mechanism, ev.R, math.inf, ev.q)
        return 0.0 if terms is None else max(0.0, -float(terms[1].min()))

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
        return -np.ones(self.nodes.size) if out is None else out[0] + x[-1] * out[1][:, -1]

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


@dataclass
class Use:
    """The least use of the input bounds found at one horizon (:func:`least_use`).

    Parameters
    ----------
    endpoint : EndpointMap
        The problem on grid controls at that horizon.
    evaluation : Evaluation
        The path found, brought onto the goal.
    use : float
        The fraction ``s`` of the bounds it uses.
    start_use : float
        The fraction its first guess used.
    message : str
        SLSQP's message.
    iterations : int
        SLSQP's iterations.
    evaluations : int
        Evaluations of the endpoint map.
    """

    endpoint: EndpointMap
    evaluation: object
    use: float
    start_use: float
    message: str
    iterations: int
    evaluations: int


def least_use(problem, controls, struggle: float = math.inf, fixed: bool = False,
              iterations_at_most: int | None = None, scale_states: bool = False) -> Use | str:
    """The path of least use ``s`` of the problem's input bounds in its ``T`` (the problem of
    :class:`PathProblem`), from the grid means of ``controls``, brought onto the goal; or why
    there is none.

    Parameters
    ----------
    problem : Problem
        The problem (its input bounds).
    controls : callable
        The first guess ``u(t)`` on ``[0, T]``.
    struggle : float, default inf
        SLSQP is stopped once its evaluations pass this many per iteration (plus
        :data:`STRUGGLE_SLACK`): line searches that keep failing, as at a horizon too short
        for any path (a search over horizons need not wait for SLSQP to say so).
    fixed : bool, default False
        Keep the sides off zero (``0 < low``, ``high < 0``) as they are, not scaled by
        ``s``: a path in this ``T`` that keeps the bounds wherever ``s ≤ 1``.
    iterations_at_most : int, optional
        SLSQP's iterations at most (default :data:`MAX_ITERATIONS`).
    scale_states : bool, default False
        Scale the state bounds around zero (``low_j < 0 < high_j``: a speed's) by ``s`` as
        well, and count their use in ``s``: with drift, where the least time may be set by
        a speed's bound rather than the inputs', ``s`` then still falls as ``T`` grows.

    Returns
    -------
    Use or str
        The path found, or the reason there is none.
    """
    bounds = problem.input_bounds
    grid = TIME_GRID
    steps = -(-problem.steps // grid) * grid
    endpoint = problem.evaluator(method="nonparametric", steps=steps)
    fitted = PiecewiseConstant.fit(controls, endpoint.T, grid, problem.mechanism.n_inputs)
    ev = endpoint.evaluate(fitted, delta_stop=-math.inf)
    if ev.complete:
        ev = newton_steps(endpoint, ev, fitted.metric(), problem.options.tol, RESTORE_STEPS)
    if not ev.complete:
        return "the first guess's grid controls do not reach T"
    from scipy.optimize import minimize      # loaded by the first least-time plan, not by `import nonholo`

    path = PathProblem(endpoint, grid, bounds.lows, bounds.highs, problem.obstacles, scaled=scale_states)
    lam = ev.params
    x0 = np.append(lam, max(float(bounds.usage(lam.reshape(grid, -1)).max()), path.state_use(ev.q), 1e-9))
    start_use = float(x0[-1])
    A = path.bounds_matrix()
    constraints = [{"type": "eq", "fun": path.goal, "jac": path.goal_jacobian},
                   {"type": "ineq", "fun": lambda x: A @ x, "jac": lambda x: A},
                   {"type": "ineq", "fun": path.limits, "jac": path.limits_jacobian}]
    if fixed:
        # the sides off zero as they are: σ (u − low) ≥ 0 (σ = +1 for 0 < low, −1 for high < 0)
        lows, highs = np.asarray(bounds.lows, dtype=float), np.asarray(bounds.highs, dtype=float)
        side = np.where(lows > 0.0, 1.0, np.where(highs < 0.0, -1.0, 0.0))
        value = np.where(lows > 0.0, lows, highs)
        rows = np.nonzero(np.tile(side, grid))[0]
        sign, level = np.tile(side, grid)[rows], np.tile(value, grid)[rows]
        B = np.zeros((rows.size, path.p + 1))
        B[np.arange(rows.size), rows] = sign
        if rows.size:
            constraints.append({"type": "ineq", "fun": lambda x: B @ x - sign * level, "jac": lambda x: B})
    objective_row = np.zeros(path.p + 1)
    objective_row[-1] = 1.0
    iterations = [0, 0]                  # this round's, and the evaluations before it

    def struggling(_):
        iterations[0] += 1
        if path.evaluations - iterations[1] > struggle * iterations[0] + STRUGGLE_SLACK:
            raise StopIteration

    for _ in range(CROSSING_ROUNDS + 1):
        iterations[:] = [0, path.evaluations]
        found = minimize(lambda x: x[-1], x0, jac=lambda x: objective_row, method="SLSQP", constraints=constraints,
                         options={"maxiter": iterations_at_most or MAX_ITERATIONS, "ftol": FTOL},
                         callback=struggling if math.isfinite(struggle) else None)
        values = found.x[:path.p].reshape(grid, -1)
        ev = endpoint.evaluate(PiecewiseConstant(endpoint.T, values))
        ev = newton_steps(endpoint, ev, fitted.metric(), problem.options.tol, RESTORE_STEPS)
        depth = path.crossing(ev)
        if not (depth > 0.0 and found.success):
            break
        # the limits kept at the nodes by more than the motion crossed them between nodes
        path.widen(CROSSING_MARGIN * depth)
        x0 = found.x
    if not endpoint.admissible(ev):
        return f"its motion {endpoint.why_not(ev)} (SLSQP: {found.message})"
    if not ev.error <= problem.options.tol:
        return f"its motion ends {ev.error:.2g} from the goal (SLSQP: {found.message})"
    use = max(float(bounds.usage(ev.params.reshape(grid, -1)).max()), path.state_use(ev.q))
    return Use(endpoint, ev, use, start_use,
               str(found.message), int(found.nit), path.evaluations)


def least_time_path(problem, result: PlanResult) -> PlanResult:
    """The path of least time under the problem's input bounds, from a plan (see the
    module), certified on grid controls; ``result`` with its reason saying why where none
    is found. The plan's grid controls need only reach ``T``: SLSQP starts where they
    break a limit or miss the goal as well. A mechanism with drift has its own search
    (:func:`least_time_with_drift`).

    Parameters
    ----------
    problem : Problem
        The problem (its input bounds).
    result : PlanResult
        Its certified plan.

    Returns
    -------
    PlanResult
        The path of least time (not re-timed), or ``result``.
    """
    options = {**result.options, "objective": "time"}
    if not result.success or problem.input_bounds is None:
        return replace(result, options=options)
    if problem.mechanism.has_drift:
        return least_time_with_drift(problem, result)
    used = least_use(problem, result.controls)
    if not problem.input_bounds.holds_zero:
        return least_time_off_zero(problem, result, used)
    if isinstance(used, str) or not used.use < used.start_use:
        why = used if isinstance(used, str) else \
            f"it is not faster than the plan's ({used.use:.6g} ≥ {used.start_use:.6g} of the bounds in T)"
        return replace(result, options=options, reason=f"{result.reason}; the least-time path not taken: {why}")
    reason = (f"{result.reason}; then the path of least time under the input bounds: {used.use:.6g} of them in "
              f"T = {problem.T:g} s (the plan's {used.start_use:.6g}; SLSQP, {used.iterations} iterations, "
              f"{used.evaluations} evaluations: {used.message})")
    return finished(problem, result, used, reason)


def least_time_off_zero(problem, result: PlanResult, used) -> PlanResult:
    """Under bounds off zero (``0 < low``: a vehicle that only drives forward), the path of
    least use played in its least time by one time factor (:func:`played_in`): the path
    of least use ``s`` in ``T`` keeps ``s·low ≤ u ≤ s·high``, so ``u/s`` keeps the bounds in
    ``s T`` — the least time of any path on the grid. (A re-timing along the path would slow it
    down to rest where it turns.)

    Parameters
    ----------
    problem : Problem
        The problem.
    result : PlanResult
        Its certified plan (the first guess of :func:`least_use`).
    used : Use or str
        The path of least use in ``T``, or why there is none.

    Returns
    -------
    PlanResult
        The path in its least time, or ``result`` failed with the reason.
    """
    options = {**result.options, "objective": "time"}
    if isinstance(used, str):
        return replace(result, success=False, options=options,
                       reason=f"{result.reason}; no path keeps the input bounds: {used}")
    bounds = problem.input_bounds
    values = used.evaluation.params.reshape(TIME_GRID, -1)
    factor = float(bounds.usage(values).max())
    room = float(bounds.slack(values).min())
    if not 0.0 < factor <= room * (1.0 + BOUND_RTOL):
        return replace(result, success=False, options=options,
                       reason=(f"{result.reason}; the path of least use of the bounds ({factor:.6g} of them) does "
                               f"not keep their sides off zero in its least time (they allow {room:.6g})"))
    base = finished(problem, result, used, (f"{result.reason}; then the path of least use of the input bounds in "
                                            f"T = {problem.T:g} s, {factor:.6g} of them (SLSQP, {used.iterations} "
                                            f"iterations: {used.message})"))
    if not base.success:
        return base
    return played_in(problem, base, factor * problem.T, "played in its least time by one time factor")


def played_in(problem, result: PlanResult, T: float, how: str) -> PlanResult:
    """A certified path of grid controls played in ``T`` by one time factor: every input times
    ``result.T / T`` (a driftless path is kept), certified on as many steps; ``result``
    failed, saying why, where the certificate fails.

    Parameters
    ----------
    problem : Problem
        The problem (any horizon).
    result : PlanResult
        The path (grid controls, ``method="nonparametric"``).
    T : float
        The horizon (s).
    how : str
        What the reason says of it.

    Returns
    -------
    PlanResult
        The path in ``T``.
    """
    at = dataclasses.replace(problem, T=T)
    endpoint = at.evaluator(method="nonparametric", steps=result.steps)
    values = np.asarray(result.parametrisation.values) * (result.T / T)
    ev = endpoint.evaluate(PiecewiseConstant(T, values))
    outcome = Outcome(evaluation=ev, success=True, reason=f"{result.reason}; {how}: T = {T:.6g} s",
                      history=result.history, iterations=result.iterations)
    outcome = certified(outcome, endpoint, at.options)
    if not outcome.success:
        return replace(result, success=False, reason=f"{result.reason}; not played in T = {T:.6g} s: {outcome.reason}")
    lowered = at.with_settings(method="nonparametric", grid=values.shape[0], steps=endpoint.steps)
    built = build_result(lowered, outcome, True, outcome.reason, endpoint)
    return replace(built, options={**built.options, "objective": result.options.get("objective")}, route=result.route)


def within_bounds(problem, result: PlanResult, limited: PlanResult) -> PlanResult:
    """At a given ``T``, a certified plan whose inputs leave the problem's bounds and whose
    path cannot be re-timed into them in ``T`` (``limited``, the failed result of
    :func:`~nonholo.planning.retime.limit_inputs`) replaced by the path of least use of the
    bounds in ``T`` (:func:`least_use`, from the plan), where that use is at most 1: the
    bounds shape the motion rather than refuse the goal. Where it is above 1, ``limited``
    with the least use found.

    Parameters
    ----------
    problem : Problem
        The problem (its ``T`` given, its input bounds around zero).
    result : PlanResult
        Its certified plan.
    limited : PlanResult
        The plan refused under the bounds.

    Returns
    -------
    PlanResult
        The path of least use, certified, or ``limited``.
    """
    used = least_use(problem, result.controls)
    if isinstance(used, str):
        return replace(limited, reason=f"{limited.reason}; no path keeps them in T either: {used}")
    if used.use > KEPT:
        need = "more time" if problem.mechanism.has_drift else f"T >= {problem.T * used.use:.6g} s along it"
        return replace(limited, reason=(f"{limited.reason}; the path of least use of the bounds in T uses "
                                        f"{used.use:.6g} of them (it needs {need})"))
    reason = (f"{result.reason}; it leaves the input bounds and cannot be re-timed into them in T: the path of least use "
              f"of them in T = {problem.T:g} s, {used.use:.6g} of them (SLSQP, {used.iterations} iterations, "
              f"{used.evaluations} evaluations: {used.message})")
    shaped = finished(problem, result, used, reason, objective=result.options.get("objective"), fallback=limited)
    if not shaped.success:                   # ``limited``, saying why the path was not taken
        return shaped
    return replace(shaped, options={**shaped.options, "input_bounds": problem.input_bounds.record()})


def finished(problem, result: PlanResult, used: Use, reason: str, objective: str | None = "time",
             fallback: PlanResult | None = None) -> PlanResult:
    """A path found by :func:`least_use`, certified, as the result (``result`` with its reason
    saying why where the certificate fails).

    Parameters
    ----------
    problem : Problem
        The problem at the path's horizon.
    result : PlanResult
        The plan it replaces.
    used : Use
        The path.
    reason : str
        The result's reason.
    objective : str or None, default "time"
        The objective the result's options record.
    fallback : PlanResult, optional
        What is returned, its reason saying why, where the certificate fails (default
        ``result``).

    Returns
    -------
    PlanResult
        The certified path, or ``fallback``.
    """
    options = {**result.options, "objective": objective}
    ev, endpoint = used.evaluation, used.endpoint
    outcome = Outcome(evaluation=ev, success=True, reason=reason,
                      history=result.history + [record(result.iterations + 1, ev, 1.0, "time", 0, use=used.use)],
                      iterations=result.iterations + used.iterations)
    outcome = certified(outcome, endpoint, problem.options)
    if not outcome.success:
        if fallback is not None:
            return replace(fallback, reason=f"{fallback.reason}; the path of least use not taken: {outcome.reason}")
        return replace(result, options=options,
                       reason=f"{result.reason}; the least-time path not taken: {outcome.reason}")
    lowered = problem.with_settings(method="nonparametric", grid=TIME_GRID, steps=endpoint.steps)
    built = build_result(lowered, outcome, True, outcome.reason, endpoint)
    return replace(built, options={**built.options, "objective": objective}, route=result.route)


def least_time_with_drift(problem, result: PlanResult, guess=None, step: float = 0.0) -> PlanResult:
    """The least time under the input bounds of a mechanism with drift, whose paths a time
    change does not keep: the horizon ``T`` at which the least use of the bounds
    (:func:`least_use`, the state bounds around zero — a speed's — scaled and counted too)
    is 1, found by the secant method on ``log s`` against ``log T`` (the first step as for a
    system driven by accelerations, ``s ∝ T⁻²``), kept inside the bracket of the horizons
    tried (bisection where it leaves it), each solve started from the last path found, its
    accelerations scaled as a path from rest to rest (``stretched(power=2)``); the path at
    the least horizon where the bounds hold.

    Parameters
    ----------
    problem : Problem
        The problem (its input bounds around zero; its ``T`` the first horizon tried).
    result : PlanResult
        Its certified plan at that horizon (or, with ``guess``, what the reasons extend).
    guess : callable, optional
        The first guess ``u(t)`` on ``[0, T]`` (default: ``result``'s controls).
    step : float, default 0
        The least time is to be rounded up to a whole number of these steps (s): the search
        ends once the least horizon that keeps the bounds and the greatest that does not
        round up to the same number, or the secant's root rounds up to the least horizon's
        number; it aims :data:`STEP_AIM` of a step past the root.

    Returns
    -------
    PlanResult
        The least-time path at its own horizon, or ``result`` with its reason saying why.
    """
    options = {**result.options, "objective": "time"}
    T, guess = problem.T, (result.controls if guess is None else guess, problem.T)
    tried, best, slow, fast = [], None, math.inf, 0.0
    for _ in range(HORIZONS):
        at = dataclasses.replace(problem, T=T)
        # once a horizon keeps the bounds, the next start from its path: a path found near it
        # needs few iterations, and one that needs many is at a horizon too short
        used = least_use(at, stretched(*guess, T, power=2), struggle=STRUGGLE if best is not None else math.inf,
                         iterations_at_most=TRIAL_ITERATIONS if best is not None else None, scale_states=True)
        if isinstance(used, str):
            s = math.inf
        else:
            s = used.use
            guess = (used.evaluation.controls, T)
            if s <= KEPT and T < slow:
                best, slow = (at, used), T
        if s > KEPT:
            fast = max(fast, T)
        tried.append((math.log(T), math.log(s) if math.isfinite(s) else math.inf))
        if best is not None and (1.0 - TIME_RTOL <= s <= KEPT or slow <= fast * (1.0 + TIME_RTOL)
                                 or (step > 0.0 and _steps(fast, step) == _steps(slow, step))):
            break
        root = _secant_root(tried)
        if best is not None and step > 0.0 and root is not None and _steps(root, step) >= _steps(slow, step):
            break                # the root rounds up to the whole steps of the least horizon found
        T = _next_horizon(tried, fast, slow, step)
    if best is None:
        return replace(result, options=options,
                       reason=(f"{result.reason}; no horizon tried ({', '.join(f'{math.exp(x):.4g}' for x, _ in tried)} s) "
                               f"keeps the input bounds"))
    at, used = best
    reason = (f"{result.reason}; then the least time under the input bounds with drift: T = {at.T:.6g} s, "
              f"{used.use:.6g} of the bounds ({len(tried)} horizons tried; SLSQP: {used.message})")
    return finished(at, result, used, reason)


#: The least-time search with drift aims this fraction of a step past the secant root, where
#: its horizon is to be rounded up to whole steps.
STEP_AIM = 0.25
#: A horizon within this fraction of a step above a whole number of steps rounds down to it.
ROUNDING = 1e-9
#: Horizons tried at most by the least-time search with drift.
HORIZONS = 14
#: The least-time search with drift ends at a horizon within this relative margin of the least.
TIME_RTOL = 1e-4
#: A path keeps the bounds where it uses at most this fraction of them (their check's
#: relative tolerance, :data:`~nonholo.model.bounds.BOUND_RTOL`).
KEPT = 1.0 + BOUND_RTOL


def stretched(controls, T0: float, T: float, power: int = 0):
    """Controls on their horizon ``T0`` read on ``[0, T]`` at the same fraction of it (the
    first guess of a path at another horizon), times ``(T0/T)^power``.

    Parameters
    ----------
    controls : callable
        ``u(t)`` on ``[0, T0]``.
    T0 : float
        Their horizon (s).
    T : float
        The new horizon (s).
    power : int, default 0
        1 keeps the path of a driftless system; 2 the path from rest to rest of a system
        driven by accelerations.

    Returns
    -------
    callable
        ``t ↦ (T0/T)^power u(t T0 / T)``.
    """
    factor = (T0 / T) ** power

    def u(t):
        return factor * controls(np.minimum(np.asarray(t, dtype=float) * (T0 / T), T0))

    return u


def _steps(T: float, step: float) -> int:
    """The whole steps ``T`` rounds up to."""
    return math.ceil(T / step - ROUNDING)


def _secant_root(tried: list) -> float | None:
    """The secant root of ``log s`` against ``log T`` through the last two finite tries (the
    first with slope −2), or ``None`` without a finite try."""
    finite = [(x, y) for x, y in tried if math.isfinite(y)]
    if not finite:
        return None
    x1, y1 = finite[-1]
    if len(finite) >= 2 and finite[-2][1] != y1:
        x0, y0 = finite[-2]
        return math.exp(x1 - y1 * (x1 - x0) / (y1 - y0))
    return math.exp(x1 + y1 / 2.0)


def _next_horizon(tried: list, fast: float, slow: float, step: float = 0.0) -> float:
    """The next horizon: :data:`STEP_AIM` of a ``step`` past the secant root (a root to be
    rounded up needs a horizon that keeps the bounds just past it, not one on it), below the
    whole steps of the least horizon that keeps the bounds; inside ``(fast, slow)``, else the
    bracket's middle (geometric) or a doubling."""
    root = _secant_root(tried)
    if root is None:
        return math.exp(tried[-1][0]) * 2.0
    T = root + STEP_AIM * step
    if step > 0.0 and math.isfinite(slow):
        T = min(T, (math.ceil(slow / step - ROUNDING) - 1) * step)
    hi = slow if math.isfinite(slow) else math.inf
    if not (fast < T < hi) or not math.isfinite(T):
        T = math.sqrt(fast * hi) if math.isfinite(hi) and fast > 0 else (2.0 * fast if fast > 0 else 0.5 * hi)
    return T
