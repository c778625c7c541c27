"""The least-energy stage's optimiser: SQP with damped BFGS updates, the endpoint fixed.

The least-energy motion of a driftless system ``ẋ = G(x) u`` between two states is a
sub-Riemannian geodesic. It is sought among piecewise-constant physical inputs (parameters
``λ``, the interval values; ``∫|u|² = λᵀMλ``, ``M = diag(h_j)``) by sequential quadratic
programming (:func:`descend`): each step is the least of the quadratic model ``gᵀd +
½dᵀBd`` on the linearised endpoint condition ``l_T + J d = 0`` (``l_T`` the stacked terminal
error, ``J = ∂s_T/∂λ`` from the variational system, as in the planner; :func:`qp_step`).
``B`` starts as the energy's Hessian ``2M`` — the Gauss–Newton step ``λ⁺ =
M⁻¹Jᵀ(JM⁻¹Jᵀ)⁻¹(Jλ − l_T)``, the least-energy point of the linearised condition — and learns
the curvature of the endpoint map by damped BFGS updates of the Lagrangian's Hessian (reset
to ``2M`` when its step runs away). A fixed point satisfies ``Mλ = Jᵀν``, ``l_T = 0``: the
first-order conditions of the least energy with the endpoint fixed (the discrete
Pontryagin condition ``u = Gᵀp``). Steps are damped by a backtracking line search on the
merit ``F + μ|l_T|`` (``μ`` above the multiplier ``|ν|``; :func:`line_search`), with a
second-order correction of a rejected full step, and shortened until the trajectory is
admissible — ``|Δ| ≥ delta_min``, the legs inside their stroke — so every iterate is; the
iteration need not start at the goal. Once a run comes within :data:`POLISH_BELOW` of the
goal, Newton steps of least energy bring it onto it (:func:`newton_steps`), and from there
on it stays at the goal: each trial step is brought back by such steps and accepted where
the objective falls (:func:`restoring_search`), so a run at the goal never trades it for
energy. ``F`` is the :class:`~nonholo.planning.energy_objective.Objective`: the energy,
plus a small barrier where the motion comes close to a limit.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import cho_factor, cho_solve
from scipy.linalg.blas import dger

from ..numerics import effort
from .core import Options, record
from .endpoint_map import Evaluation, EndpointMap
from .energy_objective import Objective, energy

# -- the iteration (:func:`descend`)
#: Seconds of effort an iteration's linear algebra counts, besides its simulations (about
#: its time on the reference machine).
ITERATION_EFFORT = 1e-3
#: The barrier's weight ``ε`` relative to the energy
#: (:class:`~nonholo.planning.energy_objective.Objective`).
BARRIER_WEIGHT = 1e-3
#: The iteration has converged when an accepted step lowers the energy by less than this
#: fraction (and the endpoint is within ``tol``).
ENERGY_RTOL = 1e-9
#: ... or when the energy's gradient is this close to the row space of ``J`` (relative, in
#: the metric ``M⁻¹``: the first-order conditions).
KKT_RTOL = 1e-8
#: A quasi-Newton step longer than this many Gauss–Newton steps (metric M) resets the
#: Hessian to ``2M`` ...
STEP_GROWTH = 4.0
#: ... or this many, once the run is at the goal: there the Gauss–Newton step is the
#: slowly contracting fixed-point step, which the quasi-Newton step outgrows as it learns
#: the curvature, and the restoring search guards every step.
STEP_GROWTH_AT_GOAL = 8.0
#: ... and so does one the line search halved more than this many times.
RESET_HALVINGS = 3
#: The merit's weight on ``|l_T|``: this many times the multiplier ``|ν|`` (at least).
MERIT_FACTOR = 2.0

# -- the line searches (:func:`line_search`, :func:`restoring_search`)
#: Step halvings of the line search at most.
MAX_HALVINGS = 12

# -- Newton steps onto the goal (:func:`polish`, :func:`newton_steps`, :func:`onto`)
#: A start whose projection on the grid ends closer to the goal than this, or a run's
#: iterate, is brought onto it by Newton steps.
POLISH_BELOW = 0.05
#: Newton steps that bring a trial step of a run at the goal back onto it, at most (a long
#: quasi-Newton step may end 0.1 from the goal; quadratic convergence needs four or five
#: steps from there, and a trial refused for want of them costs a halving and a new trial).
RESTORE_STEPS = 6


@dataclass(eq=False)
class Run:
    """One start's SQP iteration: its label, last evaluation, energy, whether it
    converged (or can make no further step), its history, the merit's weight ``mu``, the
    quasi-Newton Hessian ``B`` of the Lagrangian, the barrier's weight ``tau`` and the first
    step of the next line search ``alpha`` (carried from round to round), and the
    first-order residual ``kkt`` of its last iterate.

    Parameters
    ----------
    label : str
        The start's label.
    evaluation : Evaluation
        The last evaluation.
    energy : float
        Its energy.
    converged : bool, default False
        Whether the iteration converged.
    stuck : bool, default False
        Whether it can make no further step.
    history : list
        Its history entries.
    mu : float, default 0.0
        The merit's weight on ``|l_T|``.
    B : numpy.ndarray or None
        The quasi-Newton Hessian of the Lagrangian (a vector: diagonal).
    H : numpy.ndarray or None
        Its inverse, once ``B`` is a matrix.
    tau : float or None
        The barrier's weight, once set.
    kkt : float, default inf
        The first-order residual of the last iterate.
    alpha : float, default 1.0
        The first step of the next line search.
    joined : str, default ""
        The label of the run finished above the least energy it came close to, once it did
        (:func:`~nonholo.planning.energy_search.continue_near_best`): it is not continued.
    """

    label: str
    evaluation: Evaluation
    energy: float
    converged: bool = False
    stuck: bool = False
    history: list = field(default_factory=list)
    mu: float = 0.0
    B: np.ndarray | None = None
    H: np.ndarray | None = None
    tau: float | None = None
    kkt: float = float("inf")
    alpha: float = 1.0
    joined: str = ""


def rank_one(A: np.ndarray, alpha: float, x: np.ndarray, y: np.ndarray) -> None:
    """``A += α x yᵀ`` in place (BLAS ``dger``; ``A`` square and C-ordered).

    Parameters
    ----------
    A : numpy.ndarray
        The matrix, updated.
    alpha : float
        ``α``.
    x, y : numpy.ndarray
        The vectors.
    """
    dger(alpha, y, x, a=A.T, overwrite_a=True)


def small_solve(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``A⁻¹b`` for the small square systems of the endpoint's dimension (least squares
    where ``A`` is singular).

    Parameters
    ----------
    A : numpy.ndarray
        The matrix.
    b : numpy.ndarray
        The right-hand side.

    Returns
    -------
    numpy.ndarray
        The solution.
    """
    try:
        x = np.linalg.solve(A, b)
        if np.all(np.isfinite(x)):
            return x
    except np.linalg.LinAlgError:
        pass
    return np.linalg.lstsq(A, b, rcond=None)[0]


def qp_step(B: np.ndarray, g: np.ndarray, J: np.ndarray, l: np.ndarray,
            H: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The step of the quadratic model ``min gᵀd + ½dᵀBd`` subject to ``l + Jd = 0``.

    Parameters
    ----------
    B : numpy.ndarray
        Positive definite: a matrix, or the vector of a diagonal one.
    g : numpy.ndarray
        The gradient.
    J : numpy.ndarray
        The Jacobian of the endpoint.
    l : numpy.ndarray
        The terminal error ``l_T``.
    H : numpy.ndarray, optional
        ``B⁻¹``, where it is known (a matrix ``B`` is otherwise factorised).

    Returns
    -------
    d : numpy.ndarray
        The step.
    nu : numpy.ndarray
        Its multiplier ``ν`` (``Bd + g = Jᵀν``).
    """
    if B.ndim == 1:
        Hg, HJ = g / B, J.T / B[:, None]
    elif H is not None:
        Hg, HJ = H @ g, H @ J.T
    else:
        factor = cho_factor(B)
        Hg, HJ = cho_solve(factor, g), cho_solve(factor, J.T)
    nu = small_solve(J @ HJ, J @ Hg - l)
    return HJ @ nu - Hg, nu


def line_search(endpoint: EndpointMap, ev: Evaluation, d: np.ndarray, objective: Objective, mu: float,
                slope: float, alpha: float = 1.0) -> tuple[Evaluation | None, float, int]:
    """The step along ``d`` from ``ev`` the merit ``F + μ|l_T|`` accepts (Armijo; ``F`` the
    :class:`~nonholo.planning.energy_objective.Objective`), halved until the trajectory is
    admissible and the merit drops; a full step the merit rejects is first retried with a
    second-order correction (the least-energy ``c`` with ``J c = −l_T`` at the trial point:
    the merit's non-smooth term would otherwise reject the full steps of the fast local
    convergence).

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint.
    ev : Evaluation
        The current evaluation.
    d : numpy.ndarray
        The step.
    objective : Objective
        ``F``.
    mu : float
        The merit's weight ``μ``.
    slope : float
        The merit's directional derivative along ``d``.
    alpha : float, default 1.0
        The first step tried (the run's last accepted one, doubled: a run whose model
        overshoots does not pay the same halvings at every iteration).

    Returns
    -------
    evaluation : Evaluation or None
        The accepted evaluation, ``None`` when :data:`MAX_HALVINGS` halvings do not do.
    alpha : float
        The step ``α``.
    rejected : int
        Halvings.
    """
    merit0 = objective.value(ev) + mu * ev.error
    full = objective.near(ev)
    rejected = 0
    for _ in range(MAX_HALVINGS):
        trial = endpoint.evaluate(ev.params + alpha * d, full=full)
        if endpoint.admissible(trial):
            bound = merit0 + 1e-4 * alpha * min(slope, 0.0)
            if objective.value(trial) + mu * trial.error <= bound:
                return trial, alpha, rejected
            if alpha == 1.0:
                second = endpoint.evaluate(trial.params + least_energy_step(ev, objective.metric), full=full)
                if endpoint.admissible(second) and objective.value(second) + mu * second.error <= bound:
                    return second, alpha, rejected
        alpha *= 0.5
        rejected += 1
    return None, alpha, rejected


def restoring_search(endpoint: EndpointMap, ev: Evaluation, d: np.ndarray, objective: Objective, slope: float,
                     alpha: float, options: Options) -> tuple[Evaluation | None, float, int]:
    """The step along ``d`` from ``ev`` at the goal, brought back onto it: each trial
    ``λ + αd`` is followed by Newton steps of least energy (:func:`least_energy_step`) until it
    ends within ``tol``; it is accepted where it is admissible and ``F`` drops (Armijo),
    else ``α`` is halved. The iterates of a run at the goal stay at it, and ``F`` falls
    at every one of them: a step cannot trade the goal for energy.

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint.
    ev : Evaluation
        The current evaluation, within ``tol`` of the goal.
    d : numpy.ndarray
        The step.
    objective : Objective
        ``F``.
    slope : float
        ``F``'s directional derivative along ``d``.
    alpha : float
        The first step tried.
    options : Options
        The run's settings (``tol``).

    Returns
    -------
    evaluation : Evaluation or None
        The accepted evaluation, ``None`` when :data:`MAX_HALVINGS` halvings do not do.
    alpha : float
        The step ``α``.
    rejected : int
        Halvings.
    """
    F0 = objective.value(ev)
    full = objective.near(ev)
    metric = objective.metric
    rejected = 0
    for _ in range(MAX_HALVINGS):
        trial = endpoint.evaluate(ev.params + alpha * d, full=full)
        if endpoint.admissible(trial):
            trial = newton_steps(endpoint, trial, metric, options.tol, RESTORE_STEPS, full=full)
        if (endpoint.admissible(trial) and trial.error <= options.tol
                and objective.value(trial) <= F0 + 1e-4 * alpha * min(slope, 0.0)):
            return trial, alpha, rejected
        alpha *= 0.5
        rejected += 1
    return None, alpha, rejected


def descend(endpoint: EndpointMap, run: Run, options: Options, iterations: int, deadline: float) -> Run:
    """More SQP iterations of a run (see the module).

    It stops at convergence, at a step the line search cannot accept, or past ``deadline``.

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint.
    run : Run
        The run, updated.
    options : Options
        The run's settings.
    iterations : int
        Iterations at most.
    deadline : float
        An :func:`nonholo.numerics.effort.seconds` reading.

    Returns
    -------
    Run
        ``run``.
    """
    ev = run.evaluation
    metric = ev.parametrisation.metric()
    objective = Objective(endpoint, metric)
    gn_hessian = 2.0 * metric            # the Gauss–Newton Hessian 2M, diagonal
    if run.B is None:
        run.B = gn_hessian
    it0 = run.history[-1]["iteration"] if run.history else 0
    for it in range(it0 + 1, it0 + iterations + 1):
        if run.converged or run.stuck or effort.seconds() > deadline:
            break
        # the iteration's own work (the model, its factorisations, the limits' terms) counts
        # beside the kernels' steps
        effort.add(ITERATION_EFFORT * effort.STEPS_PER_SECOND)
        if objective.near(ev) and ev.Z is None:
            ev = endpoint.evaluate(ev.params, full=True)
        if run.tau is None:
            run.tau = BARRIER_WEIGHT * max(energy(ev, metric), 1e-12) / endpoint.T
        objective.tau = run.tau
        gE, gB, HB = objective.derivatives(ev)
        g = gE + gB
        model = run.B if HB is None else (np.diag(run.B) if run.B.ndim == 1 else run.B) + HB
        try:
            d, nu = qp_step(model, g, ev.J, ev.l, run.H if HB is None else None)
        except np.linalg.LinAlgError:       # the updates lost definiteness to rounding
            run.B, run.H = gn_hessian, None
            d, nu = qp_step(gn_hessian, g, ev.J, ev.l)
        if run.B.ndim == 2:
            gn = qp_step(gn_hessian if HB is None else np.diag(gn_hessian) + HB, g, ev.J, ev.l)
            growth = STEP_GROWTH if ev.error > options.tol else STEP_GROWTH_AT_GOAL
            if not np.dot(metric * d, d) <= growth ** 2 * np.dot(metric * gn[0], gn[0]):
                run.B, run.H = gn_hessian, None
                d, nu = gn
        run.mu = max(run.mu, MERIT_FACTOR * float(np.linalg.norm(nu)))
        E0 = energy(ev, metric)
        if ev.error <= options.tol:
            accepted, alpha, rejected = restoring_search(endpoint, ev, d, objective, float(np.dot(g, d)),
                                                         run.alpha, options)
        else:
            slope = float(np.dot(g, d)) - run.mu * ev.error
            accepted, alpha, rejected = line_search(endpoint, ev, d, objective, run.mu, slope, run.alpha)
        if accepted is None:
            run.stuck = True
            break
        run.alpha = min(1.0, 2.0 * alpha)
        if objective.near(accepted) and accepted.Z is None:
            accepted = endpoint.evaluate(accepted.params, full=True)
        gE1, gB1, _ = objective.derivatives(accepted)
        g1 = gE1 + gB1
        if rejected > RESET_HALVINGS:
            run.B, run.H = gn_hessian, None
        else:
            # damped BFGS update of the Hessian of the energy's Lagrangian E − νᵀs_T (Powell);
            # the barrier's is taken as it is
            step = accepted.params - ev.params
            y = (gE1 - accepted.J.T @ nu) - (gE - ev.J.T @ nu)
            B = np.diag(run.B) if run.B.ndim == 1 else run.B
            Bs = B @ step
            sBs, sy = float(step @ Bs), float(step @ y)
            if sBs > 0.0:
                if sy < 0.2 * sBs:
                    theta = 0.8 * sBs / (sBs - sy)
                    y = theta * y + (1.0 - theta) * Bs
                    sy = float(step @ y)
                # and of its inverse H, B⁺⁻¹ = H + ((sᵀy + yᵀHy)/(sᵀy)²) ssᵀ − (Hy sᵀ + s yᵀH)/sᵀy,
                # in place (the run's own matrices once B is one: B and H become matrices together)
                H = np.diag(1.0 / run.B) if run.B.ndim == 1 else run.H
                Hy = H @ y
                rank_one(B, 1.0 / sy, y, y)
                rank_one(B, -1.0 / sBs, Bs, Bs)
                rank_one(H, (sy + float(y @ Hy)) / sy ** 2, step, step)
                rank_one(H, -1.0 / sy, Hy, step)
                rank_one(H, -1.0 / sy, step, Hy)
                run.B, run.H = B, H
        E1 = energy(accepted, metric)
        ev = accepted
        # first-order conditions: the gradient in the row space of J (in the metric M⁻¹)
        JW = ev.J / metric
        lam = small_solve(JW @ ev.J.T, JW @ g1)
        resid = g1 - ev.J.T @ lam
        run.kkt = float(np.sqrt(np.dot(resid / metric, resid) / max(np.dot(g1 / metric, g1), 1e-300)))
        run.history.append(record(it, ev, alpha, "energy", rejected, energy=E1, start=run.label))
        settled = run.kkt <= KKT_RTOL or abs(E0 - E1) <= ENERGY_RTOL * E0
        if options.tol < ev.error <= POLISH_BELOW:
            # the goal is near: Newton steps end on it, and the run goes on at it
            # (restoring_search)
            run.evaluation = ev
            ev = polish(endpoint, run, options).evaluation
        if settled and ev.error <= options.tol:
            run.converged = True
    run.evaluation, run.energy = ev, energy(ev, metric)
    return run


def least_energy_step(ev: Evaluation, metric: np.ndarray) -> np.ndarray:
    """The least-energy parameter change ``c`` with ``J c = −l_T`` (a Newton step to the goal).

    Parameters
    ----------
    ev : Evaluation
        A complete evaluation.
    metric : numpy.ndarray
        The interval lengths ``h_j``.

    Returns
    -------
    numpy.ndarray
        ``c``.
    """
    JW = ev.J / metric
    return -JW.T @ small_solve(JW @ ev.J.T, ev.l)


def polish(endpoint: EndpointMap, run: Run, options: Options, steps: int = 4) -> Run:
    """Newton steps of least energy toward the goal (:func:`least_energy_step`).

    While they lower ``|l_T|`` and it is above ``tol``: an iteration stopped by its budget
    close to the goal ends on it.

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint.
    run : Run
        The run, updated.
    options : Options
        The run's settings.
    steps : int, default 4
        Steps at most.

    Returns
    -------
    Run
        ``run``.
    """
    metric = run.evaluation.parametrisation.metric()

    def note(ev):
        run.history.append(record(run.history[-1]["iteration"] + 1, ev, 1.0, "energy", 0,
                                  energy=energy(ev, metric), start=run.label))

    ev = newton_steps(endpoint, run.evaluation, metric, options.tol, steps, note=note)
    run.evaluation, run.energy = ev, energy(ev, metric)
    return run


def newton_steps(endpoint: EndpointMap, ev: Evaluation, metric: np.ndarray, tol: float, steps: int,
                 full: bool = False, note=None) -> Evaluation:
    """Newton steps of least energy toward the goal (:func:`least_energy_step`) from ``ev``, while
    ``|l_T|`` is above ``tol`` and each step is admissible and lowers it.

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint.
    ev : Evaluation
        The evaluation to start from.
    metric : numpy.ndarray
        The interval lengths ``h_j``.
    tol : float
        The goal's tolerance.
    steps : int
        Steps at most.
    full : bool, default False
        Keep the nodes' sensitivities (:meth:`~nonholo.planning.endpoint_map.EndpointMap.evaluate`).
    note : callable, optional
        ``note(evaluation)``, called after each step taken.

    Returns
    -------
    Evaluation
        The last evaluation taken.
    """
    for _ in range(steps):
        if not ev.complete or ev.error <= tol:      # a motion that ran into Δ = 0 has no l_T
            break
        trial = endpoint.evaluate(ev.params + least_energy_step(ev, metric), full=full)
        if not (endpoint.admissible(trial) and trial.error < ev.error):
            break
        ev = trial
        if note is not None:
            note(ev)
    return ev


def onto(endpoint: EndpointMap, ev: Evaluation, tol: float) -> Evaluation:
    """``ev``'s controls on ``endpoint``'s integrator steps, brought onto the goal there by
    Newton steps of least energy (at most :data:`RESTORE_STEPS`).

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint on the other steps.
    ev : Evaluation
        An evaluation of grid controls.
    tol : float
        The goal's tolerance.

    Returns
    -------
    Evaluation
        The last evaluation taken.
    """
    return newton_steps(endpoint, endpoint.evaluate(ev.controls), ev.parametrisation.metric(), tol, RESTORE_STEPS)
