"""Strategy ``"robust"`` (the default of :func:`nonholo.plan`).

The task is that of :mod:`nonholo.planning.core`: steer ``dR/dt = [L(R) u] R`` from ``R0`` to
``R_d`` in time ``T`` while ``sgn(Δ(R0))·Δ ≥ delta_min`` along the motion (``|L| ~ 1/|Δ|``:
on ``Δ = 0`` the legs lose control of the platform). Goals across ``Δ = 0`` are rejected
by :func:`nonholo.plan` before anything is simulated. The appendix's θ-flow is
kept — Euler steps ``λ ← λ − γh d`` with ``d`` the minimum-norm solution of ``J d = l_T``
(``γ = 1`` unless the caller sets it, :attr:`RobustStrategy.default_gamma`: a step asks for
the whole error, a damped Newton step), halved on rejection, full Newton steps once
``|l_T| < newton_below``, a step accepted only if it reaches ``T`` with ``|Δ| ≥ delta_min``
at every integrator point and lowers ``|l_T|`` — with these ingredients:

1. **Frame coordinates.** The control planned is ``w`` in ``ω = N(R) w``, ``N(R)`` the
   orthonormal frame of admissible angular velocities of the generated module (platform:
   constant, ``ω = w_1 (−e_1 + e_2)/√2 + w_2 e_3``): the kernels integrate ``N`` and
   ``QN`` (:func:`nonholo.integrate.compiled.compiled_system` with ``frame=True``), ``Δ`` is still monitored, and
   the minimum norm is taken in ``w`` (Euclidean on its Fourier coefficients, L2 on the
   grid). In the physical inputs the metric degenerates near ``Δ = 0`` — ``L ~ 1/Δ``
   makes angular velocity cheap there, so minimum-norm steps steer into the singular
   surface; in ``w`` every admissible ``ω`` costs its size. The physical leg rates are
   ``u = W(R) w`` (``W = (NᵀL)^{-1}``, polynomial), evaluated along the planned motion by
   :class:`~nonholo.motion.frame_controls.FrameControls`, which is what the result's ``controls(t)``
   returns. Mechanisms without a frame are planned in ``u`` with the
   other ingredients; for the attitude mechanism ``N = L`` and nothing changes but the
   strategy's other ingredients.
2. **Initial guesses, restarts.** First the drift guess: ``w = w̄ + 0.3 (sin ωt, cos ωt)``
   with ``w̄ = N(R0)^# log(R_d R0ᵀ)/T`` (the admissible part of the geodesic; the loop
   keeps the control regular — ``w ≡ const`` gives ``rank J = 2``). Then, when an attempt
   fails (a step below ``min_step``), stalls (``|l_T|`` down by less than 3 % in 5 steps)
   or uses its 60 steps: the loop alone, a larger loop (amplitude 1, phase π/2), the drift
   guess with K+1 and K+2 harmonics, and 6 seeded random Fourier ``w`` (RMS 0.2–1.5 rad/s,
   K and K+2 harmonics). A caller's ``u0`` (physical) is converted (:func:`to_frame`) and
   tried first. ``max_iter`` bounds the accepted steps of all attempts together.
3. **Null-space barrier.** On flow steps whose trajectory comes within ``d₀ = 0.1`` of
   ``Δ = 0``, the step direction gets ``β|d| g/|g|`` (``β = 2``), ``g`` the projection on
   the null space of ``J`` of the descent direction of ``φ = Σ_n h ψ(sgnΔ(R(t_n)))``,
   ``ψ(d) = −log(d/d₀)`` below ``d₀``: ``l_T`` is unchanged to first order, the motion
   moves away from the singular surface. ``∇φ`` needs the sensitivity of the
   intermediate states, ``s_n = Z_n^{-1} ∫_0^{t_n} Z B P dt``, obtained in one backward
   pass from the ``Z(t_n)`` and the stage weights the kernel stores
   (:func:`barrier_gradient`).
4. **Accuracy.** After convergence the integrator's error at ``R(T)`` is estimated by
   Richardson (``N`` vs ``2N`` steps); above 1e-9 rad the grid is doubled (up to 6400
   steps) and Newton steps re-converge (:meth:`RobustStrategy.refine`). Then the plan is
   certified (:mod:`nonholo.planning.correction`): its physical inputs are replayed,
   corrected if the replay misses, and a plan that cannot be certified counts as a failed
   attempt — the next initial guess is tried.
5. **Conditioning.** The certificate carries ``sensitivity = max_t |Φ(T,t)|_F`` of the
   *physical* system along the plan (the factor by which an error at ``t`` is amplified
   at ``T`` when ``u(t)`` is replayed open loop). A certified plan above
   :attr:`RobustStrategy.max_sensitivity` is kept only if no later attempt converges to a
   better-conditioned one (then the reason says so); one too ill-conditioned for ``tol``
   is not certified at all.

What each ingredient buys, and the strategy's speed and success rates, are measured by
``python -m benchmarks.bench_robust`` (``benchmarks/results/bench_robust.md``; with
``--ingredients``: ``bench_robust_ingredients.md``).
"""
from __future__ import annotations

from typing import Iterator

import numpy as np

from ..controls import stages
from ..controls.parametrisations import (
    Controls,
    Fourier,
    PiecewiseConstant,
    fourier_basis,
)
from ..model.limits import BARRIER_CLEARANCE
from ..motion.simulation import DELTA_STOP, SingularTrajectoryError, simulate
from ..numerics import kernels
from .correction import certify
from .correction import note as certificate_note
from .core import (
    Outcome,
    Start,
    Strategy,
    descend,
    record,
    step_scale,
)
from .endpoint_map import Evaluation, EndpointMap, node_gradient, spatial_gradient_delta

#: Amplitude (rad/s) of the loop ``w = a (sin ωt, cos ωt)`` of the initial guesses.
LOOP_AMPLITUDE = 0.3
#: Random initial guesses (the last restarts): Fourier ``w`` with standard normal
#: coefficients scaled to an RMS log-uniform in this range (rad/s), from this seed.
RANDOM_RMS = (0.2, 1.5)
RANDOM_SEED = 20140901


def to_frame(endpoint: EndpointMap, controls: Controls) -> Controls:
    """The frame control ``w`` that reproduces the physical ``controls`` from ``endpoint.R0``.

    ``w = N(R)ᵀ ω`` with ``ω = L(R) u`` along the physical motion (simulated with
    ``endpoint.steps`` CF4 steps), projected on the parametrisation of ``controls``
    (least squares on the Fourier basis; interval means on the grid).

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint.
    controls : Controls
        The physical control.

    Returns
    -------
    Controls
        The frame control, in the parametrisation of ``controls``.

    Raises
    ------
    SingularTrajectoryError
        If the physical motion runs into ``Δ = 0``
        (:class:`~nonholo.motion.simulation.SingularTrajectoryError`).
    """
    mech = endpoint.mechanism
    tr = simulate(endpoint.start, controls, endpoint.T, mechanism=mech, steps=endpoint.steps)
    N, L = mech.frame.N, mech.L
    w = np.array([N(R).T @ (L(R) @ u) for R, u in zip(tr.R[:-1], tr.u[:-1])])
    t = tr.t[:-1]
    if isinstance(controls, Fourier):
        phi = fourier_basis(t, endpoint.T, controls.harmonics)
        coeffs = np.linalg.lstsq(phi, w, rcond=None)[0].T
        return Fourier(endpoint.T, coeffs)
    j = controls.interval(t)
    values = np.zeros((controls.grid, controls.n_inputs))
    np.add.at(values, j, w)
    values /= np.bincount(j, minlength=controls.grid)[:, None]
    return PiecewiseConstant(endpoint.T, values)


def barrier_gradient(endpoint: EndpointMap, ev: Evaluation, d0: float) -> np.ndarray | None:
    """Gradient in ``λ`` of the barrier ``φ = Σ_{n=1..N} h ψ(d_n)``, ``d_n = sgn(Δ(R0)) Δ(R(t_n))``.

    ``ψ(d) = −log(d/d₀)`` for ``d < d₀`` and 0 above, plus the same barrier on the legs'
    clearances from their stroke limits and the coordinates' from their bounds where the
    endpoint has them (:meth:`nonholo.model.limits.Limits.clearance_terms`, below
    :data:`nonholo.model.limits.BARRIER_CLEARANCE`).

    ``ev`` must hold ``Z`` and the stage weights ``Wd`` (``full`` evaluation). The
    sensitivity of a node is ``s_n = Z_n^{-1} S_n``, ``S_n = Σ_{stages r before t_n} W_r
    ∂U_r/∂λ``; with ``a_n = h ψ'(d_n) sgn ∇Δ(R_n)`` (plus ``h ψ'(c) ∇c`` per active clearance) and ``μ_n = a_n Z_n^{-1}``,
    ``∇φ = Σ_n μ_n S_n = Σ_r (ν_{n(r)} W_r) ∂U_r/∂λ`` where ``ν_k = Σ_{n > k} μ_n`` (suffix
    sums) — one backward pass over the stored stages, no extra simulation.

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint.
    ev : Evaluation
        A ``full`` evaluation.
    d0 : float
        The barrier's reach ``d₀``.

    Returns
    -------
    numpy.ndarray or None
        The gradient, one entry per parameter; ``None`` if no node is that close (or
        ``ev`` is not complete and full).
    """
    if not ev.complete or ev.Z is None:
        return None
    N, h = endpoint.steps, endpoint.h
    D = endpoint.mechanism.n_rates
    a = np.zeros((N + 1, D))
    any_active = False
    # Δ ≡ +∞ without a singular set: no node is active
    d = endpoint.sign * endpoint.singular.values(ev.R, ev.q)
    active = d < d0
    active[0] = False
    if active.any():
        grad = spatial_gradient_delta(endpoint.mechanism, ev.R[active], q=ev.q[active])
        a[active] = (h * endpoint.sign * (-1.0 / d[active]))[:, None] * grad
        any_active = True
    if endpoint.limits is not None:
        terms = endpoint.limits.clearance_terms(endpoint.mechanism, ev.R, q=ev.q)
        if terms is not None:
            nodes, c, rows = terms
            keep = nodes > 0
            np.add.at(a, nodes[keep], (h * (-1.0 / c[keep]))[:, None] * rows[keep])
            any_active = any_active or bool(keep.any())
    if not any_active:
        return None
    return node_gradient(endpoint, ev, a)


def _like(controls: Controls, func, T: float, harmonics: int | None = None) -> Controls:
    """``func`` projected on the parametrisation of ``controls`` (``harmonics`` overrides K)."""
    if isinstance(controls, Fourier):
        return Fourier.fit(func, T, harmonics or controls.harmonics, controls.n_inputs)
    return PiecewiseConstant.fit(func, T, controls.grid, controls.n_inputs)


def _loop(T: float, m: int, amplitude: float, phase: float = 0.0, mean=None):
    """``w_i(t) = mean_i + a sin(ωt + φ + iπ/2)``, ``ω = 2π/T``: a loop (plus a drift)."""
    w = 2.0 * np.pi / T
    shift = 0.5 * np.pi * np.arange(m) + phase
    mean = np.zeros(m) if mean is None else np.asarray(mean, dtype=float)

    def f(t):
        t = np.asarray(t, dtype=float)
        return mean + amplitude * np.sin(w * t[..., None] + shift)

    return f



def frame_coordinates(mechanism) -> bool:
    """Whether plans of ``mechanism`` run in its desingularised frame coordinates ``w``: a
    capability of the mechanisms on SO(3) with a frame ``N``; beyond SO(3) the physical
    inputs are planned (the barrier keeps Δ away) and the frame is not used yet.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism planned.

    Returns
    -------
    bool
        ``True`` for frame coordinates.
    """
    return mechanism.has_frame and not mechanism.space.k


class RobustStrategy(Strategy):
    """Jacobian method in the desingularised frame coordinates, with restarts (see the module).

    Parameters
    ----------
    options : Options
        The run's settings.
    """

    name = "robust"
    #: ``γ = 1``: a flow step asks for the whole error (a damped Newton step with the
    #: barrier term, halved on rejection); ``γ = 0.5`` is measured beside it by
    #: ``python -m benchmarks.bench_robust --ingredients``
    default_gamma = 1.0
    #: accepted steps of one attempt before the next initial guess is tried
    attempt_iterations = 60
    #: refine the integrator's grid when the estimated discretisation error of ``R(T)``
    #: exceeds this (rad; the acceptance of a plan re-simulated by DOP853 is 1e-8)
    refine_above = 1e-9
    #: finest grid of the refinement
    max_steps = 6400
    #: null-space barrier on ``Δ`` in the flow steps (see :meth:`direction`)
    barrier = True
    #: the barrier ``ψ(d) = −log(d/d₀)`` acts where ``d = sgn(Δ(R0)) Δ < d₀``
    barrier_d0 = 0.1
    #: size of the barrier term relative to the minimum-norm step (in the metric)
    barrier_weight = 2.0
    #: an attempt stops when ``|l_T|`` (above ``newton_below``) shrank by less than a factor
    #: ``stall_ratio`` over the last ``stall_window`` accepted steps (0: never)
    stall_window = 5
    stall_ratio = 0.97
    #: random initial guesses after the deterministic ones
    random_guesses = 6
    #: a certified plan whose physical sensitivity (:func:`nonholo.certify.certificate.sensitivity`)
    #: exceeds this is kept only if no later attempt converges to a better-conditioned one
    max_sensitivity = 100.0

    def frame(self, mechanism) -> bool:
        """Whether to plan in the frame coordinates ``w``: for a mechanism with a frame, on SO(3).

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism planned.

        Returns
        -------
        bool
            ``True`` for frame coordinates, ``False`` for physical inputs.
        """
        return frame_coordinates(mechanism)

    def initial(self, endpoint, controls, given):
        """The initial control in this strategy's coordinates.

        In frame coordinates: ``u0`` (physical) converted by :func:`to_frame`; without
        ``u0`` the default loop ``w = 0.3 (sin ωt, cos ωt)``.

        Parameters
        ----------
        endpoint : EndpointMap
            The endpoint.
        controls : Controls
            The physical initial control (the default one, or the caller's ``u0``).
        given : bool
            Whether it is the caller's ``u0``.

        Returns
        -------
        Start
            The initial control, with a note if ``u0`` could not be used.
        """
        if not (given and endpoint.frame):
            return Start(controls, given)
        try:
            return Start(to_frame(endpoint, controls), True)
        except SingularTrajectoryError as exc:
            return Start(_like(controls, _loop(endpoint.T, controls.n_inputs, LOOP_AMPLITUDE), endpoint.T),
                         False, f"u0 not used ({exc})")

    # -- initial guesses -----------------------------------------------------------------
    def attempts(self, endpoint: EndpointMap, start: Start) -> Iterator[tuple[str, Controls]]:
        """The initial controls tried in turn: ``start``'s, then other loops and drifts.

        Parameters
        ----------
        endpoint : EndpointMap
            The endpoint.
        start : Start
            The initial control.

        Yields
        ------
        label : str
            The guess's kind (``"u0"``, ``"rest"`` (a mechanism with drift), ``"drift"``,
            ``"loop"``, ``"harmonics"``, ``"random"``).
        controls : Controls
            The guess.
        """
        first = start.controls
        T, m = endpoint.T, first.n_inputs
        mech = endpoint.mechanism
        if mech.space.k:
            l0 = mech.space.offset(endpoint.start, endpoint.goal)
            frame = mech.G(*endpoint.start)
        else:
            l0 = kernels.log_rotation(endpoint.goal.R @ endpoint.start.R.T)
            frame = mech.frame.N(endpoint.start.R) if endpoint.frame else mech.L(endpoint.start.R)
        drift = np.linalg.lstsq(frame, l0, rcond=None)[0] / T
        K = first.harmonics if isinstance(first, Fourier) else None
        if start.given:
            yield "u0", first
        if mech.has_drift:
            # the inputs at rest: a motion of the drift alone, inside whatever bounds the
            # state keeps where it rests
            yield "rest", _like(first, Fourier.zeros(T, 1, m), T)
        yield "drift", _like(first, _loop(T, m, LOOP_AMPLITUDE, 0.0, drift), T)
        if not start.given:
            yield "loop", first
        yield "loop", _like(first, _loop(T, m, 1.0, 0.5 * np.pi), T)
        if K is not None:
            yield "harmonics", _like(first, _loop(T, m, LOOP_AMPLITUDE, 0.0, drift), T, K + 1)
            yield "harmonics", _like(first, _loop(T, m, LOOP_AMPLITUDE, 0.5 * np.pi, drift), T, K + 2)
        rng = np.random.default_rng(RANDOM_SEED)
        for j in range(self.random_guesses):
            Kj = (K or 2) + 2 * (j % 2)
            c = rng.standard_normal((m, 2 * Kj + 1))
            rms = np.exp(rng.uniform(*np.log(RANDOM_RMS)))
            c *= rms / np.sqrt(np.sum(c[:, 0] ** 2) + 0.5 * np.sum(c[:, 1:] ** 2))
            f = Fourier(T, c)
            yield "random", f if K is not None else _like(first, f, T)

    # -- one descent ----------------------------------------------------------------------
    def wants_full(self, endpoint: EndpointMap, ev: Evaluation) -> bool:
        """Whether the next evaluations should keep ``Z`` and the stage weights (for the barrier).

        Parameters
        ----------
        endpoint : EndpointMap
            The endpoint.
        ev : Evaluation
            The current evaluation.

        Returns
        -------
        bool
            Whether they should be ``full``.
        """
        return self.barrier and self.near_limits(endpoint, ev, 2.0)

    def near_limits(self, endpoint: EndpointMap, ev: Evaluation, factor: float = 1.0) -> bool:
        """Whether a trajectory comes within ``factor`` times a barrier's reach of a limit.

        The limits: ``Δ = 0`` (:attr:`barrier_d0`), the legs' stroke limits and the
        coordinates' bounds (:data:`nonholo.model.limits.BARRIER_CLEARANCE`).

        Parameters
        ----------
        endpoint : EndpointMap
            The endpoint.
        ev : Evaluation
            The evaluation.
        factor : float, default 1.0
            The multiple of the barriers' reach.

        Returns
        -------
        bool
            Whether it comes that close.
        """
        near_delta = ev.min_delta is not None and ev.min_delta < factor * self.barrier_d0
        near_legs = ev.min_clearance is not None and ev.min_clearance < factor * BARRIER_CLEARANCE
        return near_delta or near_legs

    def direction(self, endpoint: EndpointMap, ev: Evaluation, scale: np.ndarray,
                  newton: bool = False) -> np.ndarray:
        """The step direction (the step is ``−γh`` or ``−1`` times it).

        ``d = S (J S)^# l`` (``S = diag(scale)``: minimum norm in the metric ``S^{-2}``).
        On flow steps whose trajectory comes within :attr:`barrier_d0` of ``Δ = 0`` (and
        :attr:`barrier` is on), plus the barrier term ``β |d|_S g/|g|_S`` (``β`` = :attr:`barrier_weight`) with ``g`` the
        ``S^{-2}``-orthogonal projection of ``−S²∇φ`` on the null space of ``J``
        (:func:`barrier_gradient`): it leaves ``l_T`` unchanged to first order and moves
        the trajectory away from ``Δ = 0``.

        Parameters
        ----------
        endpoint : EndpointMap
            The endpoint.
        ev : Evaluation
            The current (complete) evaluation.
        scale : numpy.ndarray
            The diagonal of ``S``.
        newton : bool, default False
            Whether it is a Newton step (no barrier term).

        Returns
        -------
        numpy.ndarray
            The direction.
        """
        d = kernels.min_norm_step(ev.J, ev.l, scale)
        if newton or not self.barrier or not self.near_limits(endpoint, ev):
            return d
        full = ev if ev.Z is not None else endpoint.evaluate(ev.params, full=True)
        g = barrier_gradient(endpoint, full, self.barrier_d0)
        if g is None:
            return d
        g = scale * scale * g
        null = g - kernels.min_norm_step(ev.J, ev.J @ g, scale)
        size = np.linalg.norm(null / scale)
        if not size > 0.0:
            return d
        return d + (self.barrier_weight * np.linalg.norm(d / scale) / size) * null

    def descend(self, endpoint: EndpointMap, ev: Evaluation, attempt: int, first: int, budget: int,
                history: list, callback):
        """Flow then Newton steps from an admissible evaluation.

        :func:`~nonholo.planning.core.descend` with this strategy's direction, barrier
        evaluations and stall rule.

        Parameters
        ----------
        endpoint : EndpointMap
            The endpoint.
        ev : Evaluation
            The admissible evaluation to start from.
        attempt : int
            The attempt's number (a tag of the history entries).
        first : int
            The number of the step before the first.
        budget : int
            Steps at most.
        history : list
            The run's history, appended to.
        callback : callable or None
            Called with each new history entry.

        Returns
        -------
        Descent
            How the loop ended.
        """
        scale = step_scale(endpoint, ev.parametrisation)
        d = descend(endpoint, ev, self.options, lambda ev, newton: self.direction(endpoint, ev, scale, newton),
                    budget=budget, history=history, callback=callback, first=first,
                    full=lambda ev: self.wants_full(endpoint, ev),
                    stall=(self.stall_window, self.stall_ratio), tags={"attempt": attempt})
        if d.status == "budget":
            d.reason = f"{budget} steps taken with {d.reason}"
        return d

    # -- accuracy of the integrator -----------------------------------------------------
    def discretisation_error(self, endpoint: EndpointMap, ev: Evaluation) -> float:
        """Richardson estimate of the integrator's error at ``R(T)`` for an evaluation's control.

        Parameters
        ----------
        endpoint : EndpointMap
            The endpoint.
        ev : Evaluation
            The (complete) evaluation.

        Returns
        -------
        float
            ``16/15`` of the distance between the endpoints with ``N`` and ``2N`` CF4 steps
            (in the state's units, :meth:`nonholo.spaces.product.Product.amount`).
        """
        N2 = 2 * endpoint.steps
        Rs, Qs, _ = endpoint.forward(stages.stage_table(ev.controls, N2), 0.5 * endpoint.h, -np.inf)
        return endpoint.mechanism.space.distance((Rs[N2], Qs[N2]), (ev.R[-1], ev.q[-1])) * 16.0 / 15.0

    def refine(self, endpoint: EndpointMap, ev: Evaluation, attempt: int, it0: int, history: list,
               callback) -> tuple[EndpointMap, Evaluation, int, str]:
        """Double the integrator's steps while the endpoint's discretisation error is too large.

        While it (see :meth:`discretisation_error`) exceeds :attr:`refine_above`, the
        plan re-converges with Newton steps on each finer grid.

        Parameters
        ----------
        endpoint : EndpointMap
            The endpoint.
        ev : Evaluation
            The converged evaluation.
        attempt : int
            The attempt's number.
        it0 : int
            Steps accepted before.
        history : list
            The run's history, appended to.
        callback : callable or None
            Called with each new history entry.

        Returns
        -------
        endpoint : EndpointMap
            The endpoint on the finest grid reached.
        evaluation : Evaluation
            The plan on it.
        steps : int
            Steps accepted.
        note : str
            What the refinement did (empty if nothing).
        """
        opt = self.options
        it = 0
        note = ""
        est = self.discretisation_error(endpoint, ev)
        while est > self.refine_above and 2 * endpoint.steps <= self.max_steps:
            fine = endpoint.refined(2 * endpoint.steps)
            trial = fine.evaluate(ev.controls)
            if not fine.admissible(trial):
                return endpoint, ev, it, note
            d = self.descend(fine, trial, attempt, it0 + it, 20, history, callback)
            it += d.steps
            trial = d.evaluation
            if d.status == "stopped" or trial.error > opt.tol:
                return endpoint, ev, it, note + f"refinement to {fine.steps} steps failed: {d.reason}"
            note = (f"integrator refined to {fine.steps} steps (estimated discretisation error "
                    f"{endpoint.mechanism.space.amount(est)} with {endpoint.steps})")
            endpoint, ev = fine, trial
            est = self.discretisation_error(endpoint, ev)
        return endpoint, ev, it, note

    def solve(self, endpoint, start, callback=None):
        """Plan from ``start``: attempt after attempt, each refined and certified (see the module).

        Parameters
        ----------
        endpoint : EndpointMap
            The endpoint.
        start : Start
            The initial control.
        callback : callable, optional
            Called as ``callback(record)`` per accepted step; a true value stops the run.

        Returns
        -------
        Outcome
            The run's outcome.
        """
        opt = self.options
        history: list = []
        it = 0
        best: Evaluation | None = None
        first_failure: Evaluation | None = None
        converged = None        # best-conditioned converged plan above max_sensitivity
        notes = []
        tail = f"; {start.note}" if start.note else ""
        for k, (label, w0) in enumerate(self.attempts(endpoint, start)):
            if k and it >= opt.max_iter:
                break
            ev = endpoint.evaluate(w0, delta_stop=DELTA_STOP)
            if not endpoint.admissible(ev):
                notes.append(f"{label}: initial control not admissible ({endpoint.why_not(ev)})")
                first_failure = first_failure or ev
                continue
            rec = record(it, ev, 0.0, "initial" if k == 0 else "restart", 0, attempt=k)
            history.append(rec)
            if callback is not None and callback(rec):
                return Outcome(ev, False, "stopped by callback", history, it, stopped=True)
            budget = min(self.attempt_iterations, opt.max_iter - it)
            d = self.descend(endpoint, ev, k, it, budget, history, callback)
            ev, why = d.evaluation, d.reason
            it += d.steps
            if d.status == "stopped":
                return Outcome(ev, False, why, history, it, stopped=True)
            if ev.error <= opt.tol:
                why += f" (attempt {k + 1}: {label})" if k else ""
                fine, ev, n, note = self.refine(endpoint, ev, k, it, history, callback)
                it += n
                why += f"; {note}" if note else ""
                ev, cert, corrections = certify(fine, ev, opt)
                if not cert.passed:
                    notes.append(f"{label}: converged on the planner's grid, but not certified: {cert.reason}")
                    continue
                why += certificate_note(cert, corrections, endpoint.mechanism.space)
                G = cert.sensitivity
                if G <= self.max_sensitivity:
                    return Outcome(ev, True, why + tail, history, it,
                                   fine if fine is not endpoint else None, cert)
                notes.append(f"{label}: converged with sensitivity {G:.3g} > {self.max_sensitivity:g}")
                if converged is None or G < converged[0]:
                    converged = (G, ev, fine, why, cert)
                continue
            notes.append(f"{label}: {why}")
            if best is None or ev.error < best.error:
                best = ev
        if converged is not None:
            G, ev, fine, why, cert = converged
            why += (f"; sensitivity max|Φ(T,t)| = {G:.3g} > {self.max_sensitivity:g} (the best of "
                    f"{sum('converged with' in x for x in notes)} converged attempts; an open-loop "
                    "replay amplifies errors by that much)")
            return Outcome(ev, True, why + tail, history, it, fine if fine is not endpoint else None, cert)
        final = best if best is not None else first_failure
        if final is None:
            final = endpoint.evaluate(start.controls, delta_stop=DELTA_STOP)
        reason = (f"no attempt converged within max_iter = {opt.max_iter} ({len(notes)} attempts): "
                  + "; ".join(notes) + tail)
        return Outcome(final, False, reason, history, it)
