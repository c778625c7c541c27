"""The variational system (9) along a CF4 motion: :func:`forward_variational`, the motion
with ``Z = Φ(t, 0)^{-1}``, the Jacobian of the end state in the inputs' parameters and
``M(T)``, and its stages (:func:`zstage`, :func:`zpredict`).

The variational system on the stacked variation ``s = (s_R, s_q)`` (``∂R = [s_R] R``,
``∂q = s_q``), ``ds/dt = A s + B ∂v/∂θ`` with ``A = QG(R, q, v) + [ω] ⊕ 0`` (``QG = Q`` of
eq. (12) on SO(3)) and ``B = G``, is handled through ``Z(t) = Φ(t, 0)^{-1}`` (d×d),
``dZ/dt = -Z A``, ``Z(0) = I``. Then ``Φ(T, t) = Z(T)^{-1} Z(t)`` and

    s_T = Z(T)^{-1} ∫ Z(t) B(t) ∂v/∂θ(t) dt,
    M(T) = ∫ Φ(T,t) B Bᵀ Φ(T,t)ᵀ dt = Z(T)^{-1} [∫ Z B Bᵀ Zᵀ dt] Z(T)^{-T}.

``Z`` and the two integrals are advanced as further additive factors (RK4 at CF4's own
stage points, :func:`nonholo.integrate.cf4.cf4_step`), so the coupled scheme is of order
4. The quadrature weights of a step are ``W_0 = h/6 Z_1 B_1``, ``W_½ = h/3 (Z_2 B_2 + Z_3
B_3)``, ``W_1 = h/6 Z_4 B_4`` (d×m) at the stage times ``c = 0, ½, 1``.

Parametrised inputs are linear in their parameters ``λ``: the kernel takes the *stage
basis* ``(Bidx, Bval, stride_b, stride_i)`` with ``U[n, c, i] = Σ_q Bval[n, c, q]
λ[Bidx[n, c, q]·stride_b + i·stride_i]`` and accumulates ``J = Z(T)^{-1} Σ_{n,c} W_c
∂U[n, c]/∂λ`` in place — one pass per planner iteration (``J = ∂s_T/∂λ`` of (10)). For
Fourier bases it can instead keep the stage weights of every step (``Wd``) and contract
them with the *dense* basis by one matrix product after the loop (BLAS): the same ``J``
at a third of the accumulation cost; the stored weights also give the sensitivity of
intermediate states (the barrier of :mod:`nonholo.planning.strategy_robust`).

Conventions (the system, the stage table, the singular set) as in
:mod:`nonholo.integrate.cf4`; the names of the system the kernels read are the
placeholders defined there, bound per system by
:func:`nonholo.integrate.system_kernels.compile_system`, which compiles the kernel with the
step expanded in place (:mod:`nonholo.generated.cf4_kernels`).
"""
from __future__ import annotations

import numpy as np

from ..numerics.kernels import inv33, inverse_into
from .cf4 import D, DRIFT_COLUMNS, OFFSET, ROTATION, cf4_step, delta, field_derivative_into


def zpredict(Z, a, f, out):
    """``out = Z + a f`` (d×d): the value of ``Z`` at a stage of RK4.

    Parameters
    ----------
    Z : numpy.ndarray
        ``Z`` at the start of the step.
    a : float
        The stage's step.
    f : numpy.ndarray
        The previous stage's ``dZ/dt``.
    out : numpy.ndarray
        The output, d×d.
    """
    for i in range(D):
        for j in range(D):
            out[i, j] = Z[i, j] + a * f[i, j]


def zstage(Zc, Y, P, v, F, B, Qm, f, K):
    """One stage of ``dZ/dt = -Z A``, ``A = QG(Y, P, v) + [ω] ⊕ 0`` (``ω = F[:3]``).

    Parameters
    ----------
    Zc : numpy.ndarray
        ``Z`` at the stage.
    Y, P : numpy.ndarray
        The stage's state.
    v : numpy.ndarray
        The inputs.
    F : numpy.ndarray
        The stage's rates.
    B : numpy.ndarray
        The stage's field, d×(m + ``DRIFT_COLUMNS``): its first m columns are read.
    Qm : numpy.ndarray
        Scratch, d×d (``QG``).
    f : numpy.ndarray
        The output ``-Zc A``, d×d.
    K : numpy.ndarray
        The output ``Zc B``, d×m.
    """
    field_derivative_into(Y, P, v, Qm)
    m = K.shape[1]
    if OFFSET == D:
        # on SO(3) (d = 3): A in locals (lets LLVM keep it in registers: the arrays could alias)
        a00 = Qm[0, 0]
        a01 = Qm[0, 1] - F[2]
        a02 = Qm[0, 2] + F[1]
        a10 = Qm[1, 0] + F[2]
        a11 = Qm[1, 1]
        a12 = Qm[1, 2] - F[0]
        a20 = Qm[2, 0] - F[1]
        a21 = Qm[2, 1] + F[0]
        a22 = Qm[2, 2]
        for i in range(3):
            z0 = Zc[i, 0]
            z1 = Zc[i, 1]
            z2 = Zc[i, 2]
            f[i, 0] = -(z0 * a00 + z1 * a10 + z2 * a20)
            f[i, 1] = -(z0 * a01 + z1 * a11 + z2 * a21)
            f[i, 2] = -(z0 * a02 + z1 * a12 + z2 * a22)
            for j in range(m):
                K[i, j] = z0 * B[0, j] + z1 * B[1, j] + z2 * B[2, j]
        return
    if ROTATION:
        Qm[0, 1] -= F[2]
        Qm[0, 2] += F[1]
        Qm[1, 0] += F[2]
        Qm[1, 2] -= F[0]
        Qm[2, 0] -= F[1]
        Qm[2, 1] += F[0]
    for i in range(D):
        for j in range(D):
            s = 0.0
            for c in range(D):
                s += Zc[i, c] * Qm[c, j]
            f[i, j] = -s
        for j in range(m):
            s = 0.0
            for c in range(D):
                s += Zc[i, c] * B[c, j]
            K[i, j] = s


def forward_variational(R0, q0, U, h, sgn, delta_stop, Bidx, Bval, stride_b, stride_i,
                        Rs, Qs, Zs, J, Mq, Wd, full):
    """CF4 for ``(R, q)`` together with ``Z = Φ(t,0)^{-1}``, the Jacobian ``J`` and ``M(T)``.

    Inputs: as :func:`~nonholo.integrate.motion_kernels.forward`, plus the stage basis
    ``(Bidx, Bval, stride_b, stride_i)`` of the parametrisation: sparse
    (``Bidx.shape[2] == 0``: no Jacobian), or *dense* when ``Bidx`` is empty
    (``Bidx.shape[0] == 0``) and ``Bval`` has shape ``(N, 3, nb)``: ``Bidx[n, c, q] = q``
    for every ``q < nb`` (Fourier bases); ``J`` is then one matrix product ``Wdᵀ Bval``
    after the loop (BLAS) instead of a scatter per stage.
    Outputs (preallocated): ``Rs``, ``Qs`` (as
    :func:`~nonholo.integrate.motion_kernels.forward`), ``Zs`` (``(N+1, d, d)``,
    ``Z(t_n)``; only ``Zs[N] = Z(T)`` unless ``full``), ``J`` (d × p) ``= ∂s_T/∂λ``, ``Mq``
    (d×d) ``= M(T)`` (only if ``full``), ``Wd``: shape ``(3N, d·m)`` (required by a dense
    basis) to receive the stage weights ``Wd[3n + c, i·m + k] = (W_c)_{ik}`` of every
    step — ``W_0 = h/6 Z_1 B_1``, ``W_½ = h/3 (Z_2 B_2 + Z_3 B_3)``, ``W_1 = h/6 Z_4 B_4``,
    so ``∫_0^T Z B v dt ≈ Σ W_c v(t_n + c h)`` for any ``v`` — or ``(0, d·m)``. Returns
    what :func:`~nonholo.integrate.motion_kernels.forward` returns; ``J``, ``Mq``, ``Wd``
    and ``Zs[N]`` are valid only if the run completed (NaN where ``Z(T)`` is singular or
    not finite: the motion blew up).

    Parameters
    ----------
    R0, q0 : numpy.ndarray
        The start.
    U : numpy.ndarray
        The stage table, ``(N, 3, m)``.
    h : float
        The step.
    sgn : float
        The sign of ``Δ`` at the start.
    delta_stop : float
        Stop where ``sgnΔ`` falls below this.
    Bidx, Bval : numpy.ndarray
        The stage basis' indices and values.
    stride_b, stride_i : int
        The stage basis' strides.
    Rs, Qs : numpy.ndarray
        The nodes (output).
    Zs : numpy.ndarray
        ``Z(t_n)`` (output).
    J : numpy.ndarray
        ``∂s_T/∂λ`` (output), d × p.
    Mq : numpy.ndarray
        ``M(T)`` (output), d×d.
    Wd : numpy.ndarray
        The stage weights (output), ``(3N, d·m)`` or ``(0, d·m)``.
    full : bool
        Whether to keep ``Z(t_n)`` at every node and ``M(T)``.

    Returns
    -------
    n_done : int
        The number of completed steps.
    dmin : float
        The least ``sgnΔ`` over all evaluation points of the completed steps.
    t_stop : float
        The stage time where it stopped (``-1`` if it did not).
    """
    N = U.shape[0]
    m = U.shape[2]
    k = q0.shape[0]
    dense = Bidx.shape[0] == 0 and Bval.shape[0] == N
    keep_w = Wd.shape[0] == 3 * N
    nq = 0 if dense else Bidx.shape[2]
    q = q0.copy()
    qn = np.empty(k)
    P2 = np.empty(k)
    P3 = np.empty(k)
    P4 = np.empty(k)
    R = R0.copy()
    # the step's arrays allocated here, not by step_workspace: LLVM then knows them apart,
    # which makes this kernel markedly faster (benchmarks/bench_plan.py); the coordinates'
    # arrays first: allocated in between, they made the kernel's speed on SO(3) vary from
    # one process to the next (by up to 15 %)
    Rn = np.empty((3, 3))
    Y2 = np.empty((3, 3))
    Y3 = np.empty((3, 3))
    Y4 = np.empty((3, 3))
    Rh = np.empty((3, 3))
    E = np.empty((3, 3))
    B1 = np.empty((D, m + DRIFT_COLUMNS))
    B2 = np.empty((D, m + DRIFT_COLUMNS))
    B3 = np.empty((D, m + DRIFT_COLUMNS))
    B4 = np.empty((D, m + DRIFT_COLUMNS))
    F1 = np.empty(D)
    F2 = np.empty(D)
    F3 = np.empty(D)
    F4 = np.empty(D)
    Z = np.empty((D, D))
    Zc = np.empty((D, D))
    Qm = np.empty((D, D))
    f1 = np.empty((D, D))
    f2 = np.empty((D, D))
    f3 = np.empty((D, D))
    f4 = np.empty((D, D))
    K1 = np.empty((D, m))
    K2 = np.empty((D, m))
    K3 = np.empty((D, m))
    K4 = np.empty((D, m))
    W = np.empty((3, D, m))
    J[:, :] = 0.0
    for i in range(3):
        for j in range(3):
            Rs[0, i, j] = R0[i, j]
            Rn[i, j] = R0[i, j]          # the orientations stay R0 without orientation
            Y2[i, j] = R0[i, j]
            Y3[i, j] = R0[i, j]
            Y4[i, j] = R0[i, j]
    for i in range(D - OFFSET):      # k, as a constant: the loops vanish on SO(3)
        Qs[0, i] = q0[i]
    for i in range(D):
        for j in range(D):
            Z[i, j] = 1.0 if i == j else 0.0
            Zs[0, i, j] = Z[i, j]
            Mq[i, j] = 0.0
    dmin = sgn * delta(R, q)
    if not dmin >= delta_stop:
        return 0, dmin, 0.0
    h2 = 0.5 * h
    h6 = h / 6.0
    h3 = h / 3.0
    for n in range(N):
        stop, dmin = cf4_step(R, q, Rn, qn, U[n, 0], U[n, 1], U[n, 2], h, sgn, delta_stop, dmin,
                              Y2, Y3, Y4, P2, P3, P4, Rh, E, B1, B2, B3, B4, F1, F2, F3, F4)
        if stop >= 0.0:
            return n, dmin, n * h + stop * h
        # Z at the stage points ((Y1, P1) = (R, q)(t_n), Z1 = Z), as RK4 on the additive factor
        zstage(Z, R, q, U[n, 0], F1, B1, Qm, f1, K1)
        zpredict(Z, h2, f1, Zc)
        zstage(Zc, Y2, P2, U[n, 1], F2, B2, Qm, f2, K2)
        zpredict(Z, h2, f2, Zc)
        zstage(Zc, Y3, P3, U[n, 1], F3, B3, Qm, f3, K3)
        zpredict(Z, h, f3, Zc)
        zstage(Zc, Y4, P4, U[n, 2], F4, B4, Qm, f4, K4)
        for i in range(3):
            for j in range(3):
                R[i, j] = Rn[i, j]
                Rs[n + 1, i, j] = Rn[i, j]
        for i in range(D - OFFSET):
            q[i] = qn[i]
            Qs[n + 1, i] = qn[i]
        # update Z; quadrature weights of the step at c = 0, ½, 1
        for i in range(D):
            for j in range(D):
                Z[i, j] += h6 * (f1[i, j] + 2.0 * f2[i, j] + 2.0 * f3[i, j] + f4[i, j])
            for j in range(m):
                W[0, i, j] = h6 * K1[i, j]
                W[1, i, j] = h3 * (K2[i, j] + K3[i, j])
                W[2, i, j] = h6 * K4[i, j]
        if keep_w:
            for c in range(3):
                for i in range(D):
                    for j in range(m):
                        Wd[3 * n + c, i * m + j] = W[c, i, j]
        # J += Σ_c W_c ∂U[n, c]/∂λ (sparse basis)
        for c in range(3):
            for j in range(m):
                off = j * stride_i
                if D == 3:
                    # the weights in locals (LLVM keeps them in registers: J could alias W)
                    w0 = W[c, 0, j]
                    w1 = W[c, 1, j]
                    w2 = W[c, 2, j]
                    for b in range(nq):
                        v = Bval[n, c, b]
                        col = Bidx[n, c, b] * stride_b + off
                        J[0, col] += v * w0
                        J[1, col] += v * w1
                        J[2, col] += v * w2
                else:
                    for b in range(nq):
                        v = Bval[n, c, b]
                        col = Bidx[n, c, b] * stride_b + off
                        for i in range(D):
                            J[i, col] += v * W[c, i, j]
        if full:
            for i in range(D):
                for j in range(D):
                    Zs[n + 1, i, j] = Z[i, j]
            for i in range(D):
                for j in range(i, D):
                    s1 = 0.0
                    s2 = 0.0
                    s3 = 0.0
                    s4 = 0.0
                    for c in range(m):
                        s1 += K1[i, c] * K1[j, c]
                        s2 += K2[i, c] * K2[j, c]
                        s3 += K3[i, c] * K3[j, c]
                        s4 += K4[i, c] * K4[j, c]
                    v = h6 * (s1 + 2.0 * s2 + 2.0 * s3 + s4)
                    Mq[i, j] += v
                    if j != i:
                        Mq[j, i] += v
    # Z(T), J = Z(T)^{-1} Σ W ∂U/∂λ, M(T) = Z(T)^{-1} Mq Z(T)^{-T}
    for i in range(D):
        for j in range(D):
            Zs[N, i, j] = Z[i, j]
    Zi = Qm                         # the step's scratch, free now
    if D == 3:
        inv33(Z, Zi)
    else:
        inverse_into(Z, Zi)
    p = J.shape[1]
    if dense:
        nb = Bval.shape[2]
        A = np.dot(Wd.T, Bval.reshape((3 * N, nb)))        # (d·m, nb)
        for j in range(m):
            for b in range(nb):
                col = b * stride_b + j * stride_i
                for i in range(D):
                    J[i, col] = A[i * m + j, b]
    a = F1                          # scratch
    for c in range(p):
        for i in range(D):
            a[i] = J[i, c]
        for i in range(D):
            s = 0.0
            for j in range(D):
                s += Zi[i, j] * a[j]
            J[i, c] = s
    if full:
        X = np.empty((D, D))        # X = Z(T)^{-1} Mq, then Mq = X Z(T)^{-T}
        for i in range(D):
            for j in range(D):
                s = 0.0
                for c in range(D):
                    s += Zi[i, c] * Mq[c, j]
                X[i, j] = s
        for i in range(D):
            for j in range(D):
                s = 0.0
                for c in range(D):
                    s += X[i, c] * Zi[j, c]
                Zc[i, j] = s
        for i in range(D):
            for j in range(D):
                Mq[i, j] = 0.5 * (Zc[i, j] + Zc[j, i])
    return N, dmin, -1.0

