"""Normal extremals of the energy: the kernel that integrates a state together with its
costate (:func:`extremal`), its stage (:func:`extremal_stage`) and the pull-back of a stage's
angular velocity (:func:`dexp_inverse`).

Least energy ``∫|u|² dt`` for the system ``(ω, q̇) = G(R, q) u`` (conventions of
:mod:`nonholo.integrate.cf4`): with the stacked variation ``s = (s_R, s_q)`` of
:mod:`nonholo.integrate.variational_kernels`, ``ds/dt = A s``, ``A = QG(R, q, u) + [ω] ⊕ 0``,
the Hamiltonian ``H = pᵀ G u − ½|u|²`` is largest at ``u = Gᵀ p`` and the costate — the
right-trivialised one on SO(3) — obeys ``dp/dt = −Aᵀ p``. A normal extremal is the motion
of ``(R, q, p)`` from ``(R0, q0, p0)``; its controls are ``u(t) = G(R, q)ᵀ p``. With drift,
``ẋ = f(x) + G(x) u`` (:data:`~nonholo.integrate.cf4.DRIFT_COLUMNS`), ``H`` gains ``pᵀ f``:
the controls are the same, and ``A`` — the derivative of ``f + G u`` — carries the drift's.

The scheme is RKMK4 (Munthe-Kaas, BIT 38, 1998) on ``(R, q, p)``: classical RK4 on ``q``
and ``p``; for ``R``, the stages' angular velocities pulled back by ``dexp⁻¹`` truncated
after its second commutator, ``K = ω − ½ θ × ω + θ × (θ × ω)/12`` at the stage rotation
``θ``, and ``R ← exp(h/6 (K₁ + 2K₂ + 2K₃ + K₄)) R``: order 4.

The kernel writes the controls as a stage table (:mod:`nonholo.controls.stages`): the
inputs at ``t_n`` and ``t_n + h`` (the first and last stage) and the mean of the two
middle stages' at ``t_n + h/2``.
"""
from __future__ import annotations

import numpy as np

from ..numerics.kernels import exp_times
from .cf4 import D, DRIFT_COLUMNS, OFFSET, ROTATION, delta, field_derivative_into, field_into, rates


def extremal_stage(Y, P, p, sgn, delta_stop, dmin, B, A, u, F, dp):
    """The rates of state and costate at one stage point ``(Y, P, p)``.

    Parameters
    ----------
    Y, P : numpy.ndarray
        The stage's orientation and coordinates.
    p : numpy.ndarray
        The stage's costate, d entries.
    sgn : float
        The sign of ``Δ`` at the start.
    delta_stop : float
        The least ``sgnΔ`` accepted.
    dmin : float
        The least ``sgnΔ`` so far.
    B : numpy.ndarray
        The field ``G(Y, P)`` (output), d×(m + ``DRIFT_COLUMNS``).
    A : numpy.ndarray
        ``QG(Y, P, u) + [ω] ⊕ 0`` (output), d×d.
    u : numpy.ndarray
        The inputs ``Gᵀ p`` (output), m entries.
    F : numpy.ndarray
        The state's stacked rates ``G u`` (output), d entries.
    dp : numpy.ndarray
        The costate's rate ``−Aᵀ p`` (output), d entries.

    Returns
    -------
    ok : bool
        False where ``sgnΔ < delta_stop`` (or is NaN) or a rate is not finite.
    dmin : float
        ``dmin`` lowered to the stage's ``sgnΔ``.
    """
    ok = False
    d = sgn * delta(Y, P)
    dmin = min(dmin, d)
    if d >= delta_stop:
        field_into(Y, P, B)
        m = u.shape[0]
        for i in range(m):
            s = 0.0
            for j in range(D):
                s += B[j, i] * p[j]
            u[i] = s
        ok = rates(B, u, F)
        field_derivative_into(Y, P, u, A)
        if ROTATION:
            A[0, 1] -= F[2]
            A[0, 2] += F[1]
            A[1, 0] += F[2]
            A[1, 2] -= F[0]
            A[2, 0] -= F[1]
            A[2, 1] += F[0]
        for j in range(D):
            s = 0.0
            for i in range(D):
                s += A[i, j] * p[i]
            dp[j] = -s
            ok = ok and np.isfinite(s)
    return ok, dmin


def dexp_inverse(tx, ty, tz, F):
    """``F[:3] ← K = ω − ½ θ × ω + θ × (θ × ω)/12``: the stage's angular velocity ``ω = F[:3]``
    pulled back by ``dexp⁻¹`` at ``θ = (tx, ty, tz)``, truncated after its second commutator.

    Parameters
    ----------
    tx, ty, tz : float
        The stage rotation ``θ``.
    F : numpy.ndarray
        The stage's stacked rates (updated in place).
    """
    cx = ty * F[2] - tz * F[1]
    cy = tz * F[0] - tx * F[2]
    cz = tx * F[1] - ty * F[0]
    F[0] = F[0] - 0.5 * cx + (ty * cz - tz * cy) / 12.0
    F[1] = F[1] - 0.5 * cy + (tz * cx - tx * cz) / 12.0
    F[2] = F[2] - 0.5 * cz + (tx * cy - ty * cx) / 12.0


def extremal(R0, q0, p0, h, sgn, delta_stop, Rs, Qs, Ps, U):
    """The normal extremal from ``(R0, q0)`` with initial costate ``p0``: ``N = len(U)`` RKMK4
    steps of length ``h`` (see the module docstring).

    Parameters
    ----------
    R0, q0 : numpy.ndarray
        The start.
    p0 : numpy.ndarray
        The initial costate, d entries.
    h : float
        The step.
    sgn : float
        The sign of ``Δ`` at the start.
    delta_stop : float
        Stop where ``sgnΔ`` falls below this.
    Rs, Qs, Ps : numpy.ndarray
        The output: state and costate at every ``t_n``, ``(N+1, 3, 3)``, ``(N+1, k)``,
        ``(N+1, d)``.
    U : numpy.ndarray
        The output: the controls' stage table, ``(N, 3, m)``.

    Returns
    -------
    n_done : int
        The number of completed steps (``N`` unless the motion reached ``sgnΔ <
        delta_stop`` or a non-finite rate).
    dmin : float
        The least ``sgnΔ`` over the stage points of the completed steps.
    t_stop : float
        The step's start time where it stopped (``-1`` if it did not).
    """
    N = U.shape[0]
    m = U.shape[2]
    k = q0.shape[0]
    R = R0.copy()
    Y = R0.copy()
    E = np.empty((3, 3))
    q = q0.copy()
    P = np.empty(k)
    p = p0.copy()
    pc = np.empty(D)
    B = np.empty((D, m + DRIFT_COLUMNS))
    A = np.empty((D, D))
    u = np.empty(m)
    F1 = np.empty(D)
    F2 = np.empty(D)
    F3 = np.empty(D)
    F4 = np.empty(D)
    G1 = np.empty(D)
    G2 = np.empty(D)
    G3 = np.empty(D)
    G4 = np.empty(D)
    K = np.empty(3)
    for i in range(3):
        for j in range(3):
            Rs[0, i, j] = R0[i, j]
    for i in range(k):
        Qs[0, i] = q0[i]
    for i in range(D):
        Ps[0, i] = p0[i]
    dmin = np.inf
    n_done = 0
    t_stop = -1.0
    for n in range(N):
        # stage 1 at (R, q, p)
        ok, dmin = extremal_stage(R, q, p, sgn, delta_stop, dmin, B, A, u, F1, G1)
        if not ok:
            t_stop = n * h
            break
        for i in range(m):
            U[n, 0, i] = u[i]
        # stage 2 at θ = h/2 ω1
        if ROTATION:
            exp_times(0.5 * h * F1[0], 0.5 * h * F1[1], 0.5 * h * F1[2], R, E, Y)
        for i in range(k):
            P[i] = q[i] + 0.5 * h * F1[OFFSET + i]
        for i in range(D):
            pc[i] = p[i] + 0.5 * h * G1[i]
        ok, dmin = extremal_stage(Y, P, pc, sgn, delta_stop, dmin, B, A, u, F2, G2)
        if not ok:
            t_stop = n * h
            break
        for i in range(m):
            U[n, 1, i] = 0.5 * u[i]
        if ROTATION:
            dexp_inverse(0.5 * h * F1[0], 0.5 * h * F1[1], 0.5 * h * F1[2], F2)
            exp_times(0.5 * h * F2[0], 0.5 * h * F2[1], 0.5 * h * F2[2], R, E, Y)
        # stage 3 at θ = h/2 K2
        for i in range(k):
            P[i] = q[i] + 0.5 * h * F2[OFFSET + i]
        for i in range(D):
            pc[i] = p[i] + 0.5 * h * G2[i]
        ok, dmin = extremal_stage(Y, P, pc, sgn, delta_stop, dmin, B, A, u, F3, G3)
        if not ok:
            t_stop = n * h
            break
        for i in range(m):
            U[n, 1, i] += 0.5 * u[i]
        if ROTATION:
            dexp_inverse(0.5 * h * F2[0], 0.5 * h * F2[1], 0.5 * h * F2[2], F3)
            exp_times(h * F3[0], h * F3[1], h * F3[2], R, E, Y)
        # stage 4 at θ = h K3
        for i in range(k):
            P[i] = q[i] + h * F3[OFFSET + i]
        for i in range(D):
            pc[i] = p[i] + h * G3[i]
        ok, dmin = extremal_stage(Y, P, pc, sgn, delta_stop, dmin, B, A, u, F4, G4)
        if not ok:
            t_stop = n * h
            break
        for i in range(m):
            U[n, 2, i] = u[i]
        if ROTATION:
            dexp_inverse(h * F3[0], h * F3[1], h * F3[2], F4)
            for i in range(3):
                K[i] = h / 6.0 * (F1[i] + 2.0 * F2[i] + 2.0 * F3[i] + F4[i])
            exp_times(K[0], K[1], K[2], R, E, Y)
            for i in range(3):
                for j in range(3):
                    R[i, j] = Y[i, j]
        for i in range(k):
            j = OFFSET + i
            q[i] = q[i] + h / 6.0 * (F1[j] + 2.0 * F2[j] + 2.0 * F3[j] + F4[j])
        for i in range(D):
            p[i] = p[i] + h / 6.0 * (G1[i] + 2.0 * G2[i] + 2.0 * G3[i] + G4[i])
        d = sgn * delta(R, q)
        dmin = min(dmin, d)
        if not d >= delta_stop:
            t_stop = (n + 1) * h
            break
        for i in range(3):
            for j in range(3):
                Rs[n + 1, i, j] = R[i, j]
        for i in range(k):
            Qs[n + 1, i] = q[i]
        for i in range(D):
            Ps[n + 1, i] = p[i]
        n_done = n + 1
    return n_done, dmin, t_stop
