"""Least energy by normal extremals: shooting on the initial costate.

A motion of least energy ``∫|u|² dt`` between two states in time ``T`` is, away from
abnormal ones, a normal extremal (:mod:`nonholo.integrate.extremal_kernels`): ``u = G(x)ᵀ p``
with the costate ``dp/dt = −Aᵀ p``, fixed by its value ``p₀`` at the start — ``d`` unknowns
for ``d`` conditions at the goal. :class:`Shooting` finds ``p₀`` by Newton's method on the
terminal error ``p₀ ↦ l_T`` (the Jacobian by forward differences: ``d + 1`` extremals,
each a few hundred steps of a small compiled kernel), its steps halved until the error
falls; where Newton from the first guess stalls, the goal is approached through
intermediate goals on the straight path from where that guess ends (continuation).

The first guess comes from a plan already found (:func:`costate_guess`): along the plan's
motion the costate of an extremal through it would be ``p(t) = Z(t)ᵀ p₀``, ``Z(t) =
Φ(t, 0)^{-1}`` of the variational system (one evaluation of the plan with
:meth:`~nonholo.planning.endpoint_map.EndpointMap.evaluate` ``full``), so the ``p₀`` whose
``G(x)ᵀ Z(t)ᵀ p₀`` is closest to the plan's inputs in ``L²`` is the projection of the plan
on the extremals through its own motion. Where the plan is itself close to an extremal —
as a plan of the θ-flow from a small control mostly is — Newton converges in a few steps.

:func:`least_energy` turns the extremal into the planner's grid controls (the mean of
the inputs over each interval), brings them onto the goal on the planner's own
integrator with Newton steps of least energy and certifies them
(:func:`~nonholo.planning.energy_search.certified_or_finer`), all within an effort
budget (:mod:`nonholo.numerics.effort`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..controls.parametrisations import Controls, Legendre, PiecewiseConstant
from ..integrate.compiled import compiled_system
from ..numerics import effort
from ..spaces.state import State
from .core import Options, Outcome, record
from .endpoint_map import EndpointMap
from .energy_objective import energy
from .energy_optimiser import RESTORE_STEPS, newton_steps
from .energy_search import certified_or_finer

#: Newton steps of the shooting at most, per goal (the final one and each intermediate).
NEWTON_STEPS = 12
#: Halvings of a Newton step at most.
HALVINGS = 8
#: The forward-difference step of the Jacobian, relative to ``|p₀|`` (at least this absolutely).
DIFFERENCE_STEP = 1e-7
#: Intermediate goals of the continuation.
CONTINUATION = (8,)
#: A Newton step that leaves more than this fraction of the error is slow; two in a row end
#: the iteration.
STALL = 0.7
#: The shooting ends once the error is below this (the planner's integrator then brings
#: the grid controls onto the goal to its own tolerance).
SHOOTING_TOL = 1e-8
#: Extremals agree on the least energy within this relative difference.
AGREE_RTOL = 1e-5
#: :func:`least_energy` takes no further start once this many in a row have not reached the
#: goal: the loops' projections seldom land near an extremal at it, and the search after
#: the stage starts from them anyway.
MISSES = 8
#: The degrees of the Legendre series tried in turn for a smooth extremal's inputs
#: (:func:`smooth_extremal`).
SMOOTH_DEGREES = (8, 12, 16, 24, 32, 48)
#: A series fits an extremal's inputs where its largest residual at the nodes is below this
#: fraction of their largest value.
SMOOTH_FIT = 1e-10


@dataclass
class Shot:
    """One extremal: its initial costate, whether it reached ``T`` clear of ``Δ = 0``, its
    terminal error from the target, the controls' stage table and the least ``sgnΔ``.

    Parameters
    ----------
    p0 : numpy.ndarray
        The initial costate.
    complete : bool
        Whether the motion reached ``T`` with ``sgnΔ ≥`` the clearance.
    l : numpy.ndarray or None
        The terminal error from the target (``None`` unless complete).
    error : float
        Its norm (``inf`` unless complete).
    U : numpy.ndarray
        The controls' stage table, ``(N, 3, m)``.
    pT : numpy.ndarray or None, default None
        The costate at ``T`` (``None`` unless complete).
    """

    p0: np.ndarray
    complete: bool
    l: np.ndarray | None
    error: float
    U: np.ndarray
    pT: np.ndarray | None = None


class Shooting:
    """The terminal error of normal extremals from a start, as a function of ``p₀``.

    Parameters
    ----------
    endpoint : EndpointMap
        The problem: start, goal, horizon, clearance from ``Δ = 0``.
    steps : int
        The extremals' integrator steps on ``[0, T]``.
    """

    def __init__(self, endpoint: EndpointMap, steps: int):
        mech = endpoint.mechanism
        self.endpoint = endpoint
        self.space = mech.space
        self.kernel = compiled_system(mech).extremal
        self.steps = steps
        self.h = endpoint.T / steps
        self.d = mech.n_rates
        self._Rs = np.empty((self.steps + 1, 3, 3))
        self._Qs = np.empty((self.steps + 1, mech.n_coordinates))
        self._Ps = np.empty((self.steps + 1, self.d))
        self.shots = 0

    def shoot(self, p0: np.ndarray, target: State) -> Shot:
        """The extremal from ``p₀`` and its error from ``target``.

        Parameters
        ----------
        p0 : numpy.ndarray
            The initial costate.
        target : State
            The state it should end at.

        Returns
        -------
        Shot
            The extremal.
        """
        ep = self.endpoint
        U = np.empty((self.steps, 3, ep.mechanism.n_inputs))
        n, _, _ = self.kernel(*ep.start, p0, self.h, ep.sign, ep.delta_min, self._Rs, self._Qs, self._Ps, U)
        self.shots += 1
        if n < self.steps:
            return Shot(p0, False, None, math.inf, U)
        l, _ = self.space.error((self._Rs[-1], self._Qs[-1]), target)
        error = float(np.linalg.norm(l))
        if not math.isfinite(error):
            return Shot(p0, False, None, math.inf, U)
        return Shot(p0, True, l, error, U, self._Ps[-1].copy())

    def jacobian(self, shot: Shot, target: State) -> np.ndarray | None:
        """``∂l_T/∂p₀`` at a complete shot, by forward differences (``None`` where a
        neighbour is not complete).

        Parameters
        ----------
        shot : Shot
            A complete shot.
        target : State
            Its target.

        Returns
        -------
        numpy.ndarray or None
            The Jacobian, d×d.
        """
        eps = DIFFERENCE_STEP * max(1.0, float(np.linalg.norm(shot.p0)))
        J = np.empty((self.d, self.d))
        for j in range(self.d):
            p = shot.p0.copy()
            p[j] += eps
            other = self.shoot(p, target)
            if not other.complete:
                return None
            J[:, j] = (other.l - shot.l) / eps
        return J

    def newton(self, shot: Shot, target: State, tol: float, deadline: float, abandon: float = math.inf) -> Shot:
        """Newton steps on ``p₀`` toward ``target`` from a complete shot (least-squares
        steps where the Jacobian is singular).

        The Jacobian is taken by differences once, then kept up to date by Broyden's
        rank-one updates along the steps taken; where a full step does not lower the
        error it is taken afresh and the step halved until it does. The iteration ends at
        ``tol``, after :data:`NEWTON_STEPS` steps, or once two steps in a row lower the
        error by less than :data:`STALL`, or once the energy at the target is surely above
        ``abandon``: the shot's energy less ``4|p_T||l_T|``, twice the first-order change
        ``2p_Tᵀ δx`` of the least energy with the endpoint.

        Parameters
        ----------
        shot : Shot
            A complete shot.
        target : State
            The target.
        tol : float
            Stop below this error.
        deadline : float
            Stop once the effort passes this.
        abandon : float, default inf
            Stop once the energy at the target is surely above this.

        Returns
        -------
        Shot
            The last shot accepted.
        """
        J, fresh, slow = None, False, 0
        for _ in range(NEWTON_STEPS):
            if shot.error <= tol or effort.seconds() > deadline:
                break
            if math.isfinite(abandon) and \
                    shot_energy(shot, self.h) - 4.0 * float(np.linalg.norm(shot.pT)) * shot.error > abandon:
                break
            if J is None:
                J, fresh = self.jacobian(shot, target), True
                if J is None:
                    break
            step = np.linalg.lstsq(J, -shot.l, rcond=None)[0]
            trial = self.shoot(shot.p0 + step, target)
            if not (trial.complete and trial.error < shot.error):
                if not fresh:
                    J, fresh = self.jacobian(shot, target), True
                    if J is None:
                        break
                    step = np.linalg.lstsq(J, -shot.l, rcond=None)[0]
                scale = 1.0
                for _ in range(HALVINGS):
                    trial = self.shoot(shot.p0 + scale * step, target)
                    if trial.complete and trial.error < shot.error:
                        break
                    scale *= 0.5
                else:
                    break
                step = scale * step
            # Broyden: J s = Δl along the step taken
            J = J + np.outer(trial.l - shot.l - J @ step, step) / float(step @ step)
            fresh = False
            slow = slow + 1 if trial.error > STALL * shot.error else 0
            shot = trial
            if slow >= 2:
                break
        return shot

    def solve(self, p0: np.ndarray, deadline: float, continuation: bool = True, abandon: float = math.inf) -> Shot:
        """The extremal from ``p₀`` brought onto the goal: Newton, then, where it stalls
        and ``continuation`` is asked for, continuation through intermediate goals
        (:data:`CONTINUATION`).

        Parameters
        ----------
        p0 : numpy.ndarray
            The first guess.
        deadline : float
            Stop once the effort passes this.
        continuation : bool, default True
            Whether to try the continuation.
        abandon : float, default inf
            Newton stops once the energy at the goal is surely above this (:meth:`newton`).

        Returns
        -------
        Shot
            The best shot found (its ``error`` says whether it reached the goal).
        """
        goal = self.endpoint.goal
        first = self.shoot(p0, goal)
        if not first.complete:
            return first
        best = self.newton(first, goal, SHOOTING_TOL, deadline, abandon)
        if best.error <= SHOOTING_TOL or not continuation:
            return best
        # from where the first guess ends, along the straight path to the goal
        self.kernel(*self.endpoint.start, p0, self.h, self.endpoint.sign, self.endpoint.delta_min,
                    self._Rs, self._Qs, self._Ps, first.U)
        reached = State(self._Rs[-1].copy(), self._Qs[-1].copy())
        for pieces in CONTINUATION:
            shot = first
            targets = self.space.interpolate(reached, goal, np.arange(1, pieces + 1) / pieces)
            for i, target in enumerate(targets):
                last = i == pieces - 1
                shot = self.shoot(shot.p0, target)
                if not shot.complete:
                    break
                shot = self.newton(shot, target, SHOOTING_TOL if last else 1e-6, deadline)
                if shot.error > (SHOOTING_TOL if last else 1e-3) or effort.seconds() > deadline:
                    break
            if shot.complete and shot.error <= SHOOTING_TOL:
                return shot
            if effort.seconds() > deadline:
                break
        return best


def costate_guess(endpoint: EndpointMap, controls: Controls, grid: int) -> np.ndarray | None:
    """The ``p₀`` whose extremal inputs along a plan's motion, ``G(x)ᵀ Z(t)ᵀ p₀``, are closest
    to the plan's inputs in ``L²`` (see the module), or ``None`` where the plan's grid
    controls are not admissible.

    The products ``Z G`` at the integrator's stage points come with the evaluation: its
    stage weights (:attr:`~nonholo.planning.endpoint_map.Evaluation.Wd`) are ``w_c Z G``
    with Simpson's weights ``w = (h/6, 2h/3, h/6)`` (the middle one the mean of the two
    middle stages), so the normal equations are ``Σ_c (Wd_c Wd_cᵀ / w_c) p₀ = Σ_c Wd_c u_c``.

    The plan's grid controls are evaluated on one integrator step an interval.

    Parameters
    ----------
    endpoint : EndpointMap
        The problem.
    controls : Controls
        The plan's physical inputs (grid controls on ``grid`` intervals are taken as they are).
    grid : int
        Intervals of the grid controls the plan is evaluated as.

    Returns
    -------
    numpy.ndarray or None
        The initial costate.
    """
    mech = endpoint.mechanism
    if endpoint.steps != grid:
        endpoint = endpoint.refined(grid)             # one step an interval: the guess needs no more
    N, d, m = endpoint.steps, mech.n_rates, mech.n_inputs
    fitted = controls if isinstance(controls, PiecewiseConstant) and controls.grid == grid else \
        PiecewiseConstant.fit(controls, endpoint.T, grid, m)
    ev = endpoint.evaluate(fitted, full=True)
    if not ev.complete:
        return None
    W = ev.Wd.reshape(N, 3, d, m)
    u = np.repeat(fitted.values, N // grid, axis=0)                       # (N, m): constant on each step
    w = endpoint.h * np.array([1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0])
    A = np.einsum("ncdk,ncek,c->de", W, W, 1.0 / w)
    b = np.einsum("ncdk,nk->d", W, u)
    p0, *_ = np.linalg.lstsq(A, b, rcond=None)
    return p0


def ended(endpoint: EndpointMap, ev) -> str:
    """Where an evaluation that is no motion at the goal ended, in words.

    Parameters
    ----------
    endpoint : EndpointMap
        The problem it was evaluated on.
    ev : Evaluation
        The evaluation.

    Returns
    -------
    str
        ``"ended <error> from the goal"``, or why it is not admissible
        (:meth:`~nonholo.planning.endpoint_map.EndpointMap.why_not`).
    """
    if not endpoint.admissible(ev):
        return f"did not stay admissible ({endpoint.why_not(ev)})"
    return f"ended {ev.error:.2g} from the goal"


def grid_values(U: np.ndarray, grid: int) -> np.ndarray:
    """The mean inputs over each of ``grid`` intervals of a stage table (Simpson's rule on
    each step).

    Parameters
    ----------
    U : numpy.ndarray
        The stage table, ``(N, 3, m)``, ``N`` a multiple of ``grid``.
    grid : int
        The intervals.

    Returns
    -------
    numpy.ndarray
        The values, ``(grid, m)``.
    """
    per_step = (U[:, 0] + 4.0 * U[:, 1] + U[:, 2]) / 6.0
    return per_step.reshape(grid, -1, U.shape[2]).mean(axis=1)


def shot_energy(shot: Shot, h: float) -> float:
    """``∫|u|² dt`` of an extremal (Simpson's rule on each step).

    Parameters
    ----------
    shot : Shot
        The extremal.
    h : float
        Its step.

    Returns
    -------
    float
        The energy.
    """
    U2 = np.sum(shot.U ** 2, axis=2)
    return float(h / 6.0 * np.sum(U2[:, 0] + 4.0 * U2[:, 1] + U2[:, 2]))


def node_inputs(shooting: "Shooting", p0: np.ndarray) -> np.ndarray | None:
    """The inputs ``u_n = G(x_n)ᵀ p_n`` of the extremal from ``p₀`` at its nodes (``None`` where it
    does not reach ``T``).

    Parameters
    ----------
    shooting : Shooting
        The extremals' problem and grid.
    p0 : numpy.ndarray
        The initial costate.

    Returns
    -------
    numpy.ndarray or None
        Shape ``(N+1, m)``.
    """
    ep = shooting.endpoint
    U = np.empty((shooting.steps, 3, ep.mechanism.n_inputs))
    n, _, _ = shooting.kernel(*ep.start, p0, shooting.h, ep.sign, ep.delta_min,
                              shooting._Rs, shooting._Qs, shooting._Ps, U)
    if n < shooting.steps:
        return None
    G = ep.mechanism.G
    return np.stack([G(R, q).T @ p for R, q, p in zip(shooting._Rs, shooting._Qs, shooting._Ps)])


def smooth_extremal(endpoint: EndpointMap, shot: Shot, options: Options, label: str, deadline: float,
                    extremals: int) -> tuple[Outcome | None, str]:
    """An extremal at the goal as a smooth control: its initial costate brought onto the goal on
    the planner's own steps, its inputs at the nodes fitted by a Legendre series of the least
    degree of :data:`SMOOTH_DEGREES` that fits them to :data:`SMOOTH_FIT`, that series brought
    onto the goal by Newton steps of least energy and certified.

    A motion so found is the extremal itself up to the integrator's error, not grid controls
    near it: its inputs are those of the closed form where there is one (a linear system).

    Parameters
    ----------
    endpoint : EndpointMap
        The problem.
    shot : Shot
        An extremal at the goal.
    options : Options
        The run's settings.
    label : str
        The start it came from.
    deadline : float
        Stop once the effort passes this.
    extremals : int
        Extremals shot so far (for the reason).

    Returns
    -------
    outcome : Outcome or None
        The certified motion.
    why : str
        Why there is none (empty if there is).
    """
    fine = Shooting(endpoint, endpoint.steps)
    goal = endpoint.goal
    refined = fine.newton(fine.shoot(shot.p0, goal), goal, 0.1 * options.tol, deadline)
    u = node_inputs(fine, refined.p0) if refined.complete else None
    if u is None:
        return None, "the extremal did not reach T on the planner's steps"
    t = np.arange(fine.steps + 1) * fine.h
    scale = max(float(np.abs(u).max()), 1e-300)
    for degree in SMOOTH_DEGREES:
        series = Legendre.fit(t, u, endpoint.T, degree)
        if np.abs(series(t) - u).max() <= SMOOTH_FIT * scale:
            break
    else:
        return None, f"no Legendre series up to degree {SMOOTH_DEGREES[-1]} fits the extremal's inputs"
    ev = endpoint.evaluate(series)
    metric = series.metric()
    ev = newton_steps(endpoint, ev, metric, options.tol, RESTORE_STEPS)
    if not (endpoint.admissible(ev) and ev.error <= options.tol):
        return None, f"the extremal's Legendre series (degree {series.degree}) {ended(endpoint, ev)}"
    E = energy(ev, metric)
    outcome = Outcome(evaluation=ev, success=True,
                      reason=(f"least energy {E:.6g}: the normal extremal from the start '{label}' "
                              f"({extremals + fine.shots} extremals), as a Legendre series of degree {series.degree}"),
                      history=[record(1, ev, 1.0, "energy", 0, energy=E, start=label, extremal=True)], iterations=1)
    outcome = certified_or_finer(outcome, endpoint, options, math.inf)
    return (outcome, "") if outcome.success else (None, outcome.reason)


@dataclass
class Found:
    """What :func:`least_energy` found: the certified motion (or ``None``), why there is
    none, and whether any extremal reached the goal.

    Parameters
    ----------
    outcome : Outcome or None
        The certified least-energy motion.
    why : str
        Why there is none (empty if there is).
    reached : bool
        Whether an extremal from a start reached the goal.
    least : float, default inf
        The least energy of an extremal at the goal.
    confirmed : bool, default False
        Whether that least energy is confirmed (by enough extremals, or from the first start).
    """

    outcome: Outcome | None
    why: str
    reached: bool
    least: float = math.inf
    confirmed: bool = False


def least_energy(endpoint: EndpointMap, initial, options: Options, grid: int, budget: float,
                 confirmations: int = 2, ceiling: float = math.inf, continued: int = 1,
                 first_below: float = 0.0, first_or_none: bool = False, smooth: bool = False,
                 abandon: float = math.inf) -> Found:
    """The least-energy normal extremal through the projections of labelled controls, as
    certified grid controls (see the module).

    The starts are taken in turn until ``confirmations`` extremals at the goal agree on the
    least energy of any (relative difference below :data:`AGREE_RTOL`), the starts run out,
    :data:`MISSES` in a row miss the goal or the budget ends; only an extremal so confirmed, needing less than ``ceiling``, is
    landed on the grid (its means over the intervals, within ``O(h²)`` of the grid's own
    least-energy controls), brought onto the goal by Newton steps of least energy and
    certified.

    Parameters
    ----------
    endpoint : EndpointMap
        The problem (grid controls; its steps a multiple of ``grid``).
    initial : iterable of tuple
        Labelled physical controls ``(label, controls)``: a plan's first.
    options : Options
        The run's settings.
    grid : int
        The intervals of the grid controls.
    budget : float
        Seconds of effort.
    confirmations : int, default 2
        Extremals that must agree on the least energy.
    ceiling : float, default inf
        The energy to beat.
    continued : int, default 1
        The continuation is tried from this many first starts (a plan's, which ends at the
        goal, is the best placed for it).
    first_below : float, default 0
        An extremal from the first start needing less than this needs no confirmation.
    first_or_none : bool, default False
        Give up where the first start's extremal does not reach the goal (a plan's that
        does not is far from any extremal: its least-energy motion rides a limit).
    smooth : bool, default False
        Return the extremal as a smooth control (:func:`smooth_extremal`) where it can,
        else as grid controls.
    abandon : float, default inf
        An extremal is given up once its energy at the goal is surely above this
        (:meth:`Shooting.newton`).

    Returns
    -------
    Found
        The certified extremal, or why there is none.
    """
    deadline = effort.seconds() + budget
    shooting = Shooting(endpoint, grid)
    found, tried, closest, missed = [], 0, math.inf, 0
    for label, controls in initial:
        if effort.seconds() > deadline:
            break
        p0 = costate_guess(endpoint, controls, grid)
        tried += 1
        missed += 1
        if p0 is None or not np.all(np.isfinite(p0)):
            if missed >= MISSES:
                break
            continue
        shot = shooting.solve(p0, deadline, continuation=tried <= continued, abandon=abandon)
        closest = min(closest, shot.error)
        if first_or_none and tried == 1 and not (shot.complete and shot.error <= SHOOTING_TOL):
            break
        if shot.complete and shot.error <= SHOOTING_TOL:
            missed = 0
            found.append((shot_energy(shot, shooting.h), label, shot))
            least = min(e for e, _, _ in found)
            if tried == 1 and least < first_below:
                confirmations = 1
            if sum(e <= least * (1.0 + AGREE_RTOL) for e, _, _ in found) >= confirmations:
                break
        if missed >= MISSES:
            break
    if not found:
        return Found(None, (f"no extremal from the costates of {tried} starts reached the goal "
                            f"({shooting.shots} extremals, the closest {closest:.2g} from it)"), False)
    found.sort(key=lambda f: f[0])
    least = found[0][0]
    agree = sum(e <= least * (1.0 + AGREE_RTOL) for e, _, _ in found)
    if agree < confirmations:
        return Found(None, (f"{agree} of {len(found)} extremals at the goal ({tried} starts) agree on the "
                            f"least energy {least:.6g}, not {confirmations}"), True, least)
    if least >= ceiling:
        return Found(None, f"the least-energy extremal needs {least:.6g}, not below {ceiling:.6g}", True, least, True)
    why = ""
    for _, label, shot in found[:agree]:
        if smooth:
            outcome, why = smooth_extremal(endpoint, shot, options, label, deadline, shooting.shots)
            if outcome is not None:
                return Found(outcome, "", True, least, True)
        ev = endpoint.evaluate(PiecewiseConstant(endpoint.T, grid_values(shot.U, grid)))
        metric = ev.parametrisation.metric()
        ev = newton_steps(endpoint, ev, metric, options.tol, RESTORE_STEPS)
        if not (endpoint.admissible(ev) and ev.error <= options.tol):
            why = why or f"the extremal's grid controls {ended(endpoint, ev)}"
            continue
        E = energy(ev, metric)
        outcome = Outcome(evaluation=ev, success=True,
                          reason=(f"least energy {E:.6g}: the normal extremal from the start '{label}' "
                                  f"({len(found)} of {tried} starts at the goal, {shooting.shots} extremals), "
                                  f"on {grid} intervals"),
                          history=[record(1, ev, 1.0, "energy", 0, energy=E, start=label, extremal=True)],
                          iterations=1)
        outcome = certified_or_finer(outcome, endpoint, options, math.inf)
        if outcome.success:
            return Found(outcome, "", True, least, True)
        why = why or outcome.reason
    return Found(None, why, True, least, True)
