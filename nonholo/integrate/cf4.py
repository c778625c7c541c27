"""The CF4 Lie-group integrator and the variational system (9), compiled per system.

Conventions
-----------
- A *system* is ``dR/dt = [ω] R`` with ``ω = G(R) v`` (spatial form): ``G = L`` and ``v``
  the physical inputs ``u`` of a mechanism, or ``G = N`` (its desingularised frame) and
  ``v = w`` the frame coordinates. It is integrated while the mechanism's ``Δ`` is
  watched (``Δ ≡ +inf`` without a singular set).
- Fixed step ``h = T/N``. The inputs enter through a *stage table* ``U`` of shape
  ``(N, 3, m)``: ``U[n, 0]``, ``U[n, 1]``, ``U[n, 2]`` are the inputs at ``t_n``,
  ``t_n + h/2`` and ``t_n + h`` of step ``n`` (``t_n = n h``); see :mod:`nonholo.controls.stages`.

One step (:func:`cf4_step`) is the 4th-order commutator-free method CF4 of Celledoni,
Marthinsen and Owren (2003) with the Rodrigues exponential; every update multiplies ``R``
by a rotation, so ``R`` stays on SO(3) up to round-off::

    F1 = G(R) U[n,0]
    Y2 = exp(h/2 F1) R,            F2 = G(Y2) U[n,1]
    Y3 = exp(h/2 F2) R,            F3 = G(Y3) U[n,1]
    Y4 = exp(h F3 - h/2 F1) Y2,    F4 = G(Y4) U[n,2]
    R½ = exp(h/12 (3F1 + 2F2 + 2F3 - F4)) R
    R' = exp(h/12 (-F1 + 2F2 + 2F3 + 3F4)) R½

It is the only place the scheme is written; every kernel below takes its steps with it:
:func:`forward` (the motion), :func:`forward_variational` (the motion with the
variational system) and :func:`frame_inputs` (the physical inputs along a motion planned
in frame coordinates, one partial step from the nearest node).

The variational system (9), ``ds/dt = A s + B ∂v/∂θ`` with ``A = DG(R, v) + [G(R) v]``
(``DG = Q`` for ``G = L``, eq. (12)) and ``B = G(R)``, is handled through
``Z(t) = Φ(t, 0)^{-1}``, ``dZ/dt = -Z A``, ``Z(0) = I``. Then ``Φ(T, t) = Z(T)^{-1} Z(t)`` and

    s_T = Z(T)^{-1} ∫ Z(t) B(t) ∂v/∂θ(t) dt,
    M(T) = ∫ Φ(T,t) B Bᵀ Φ(T,t)ᵀ dt = Z(T)^{-1} [∫ Z B Bᵀ Zᵀ dt] Z(T)^{-T}.

``Z`` and the two integrals are advanced on the product group ``SO(3) × (R^{3×3}, +) × …``
(on the additive factors CF4 reduces to the classical RK4 tableau, evaluated at CF4's own
stage points ``Y_i``), so the coupled scheme is of order 4. The quadrature weights of a
step are ``W_0 = h/6 Z_1 B_1``, ``W_½ = h/3 (Z_2 B_2 + Z_3 B_3)``, ``W_1 = h/6 Z_4 B_4``
(3×m) at the stage times ``c = 0, ½, 1``.

Parametrised inputs are linear in their parameters ``λ``: the kernel takes the *stage
basis* ``(Bidx, Bval, stride_b, stride_i)`` with ``U[n, c, i] = Σ_q Bval[n, c, q]
λ[Bidx[n, c, q]·stride_b + i·stride_i]`` and accumulates ``J = Z(T)^{-1} Σ_{n,c} W_c
∂U[n, c]/∂λ`` in place — one pass per planner iteration (``J = ∂s_T/∂λ`` of (10)). For
Fourier bases it can instead keep the stage weights of every step (``Wd``) and contract
them with the *dense* basis by one matrix product after the loop (BLAS): the same ``J``
at a third of the accumulation cost; the stored weights also give the sensitivity of
intermediate states (the barrier of :mod:`nonholo.planning.strategy_robust`).

Singular set: ``sgn Δ`` (``sgn = sign Δ(R0)``) is checked at every stage point and node;
the kernels stop as soon as it falls below ``delta_stop`` (or ``ω`` is not finite) and
report how many steps were completed, so a trajectory running into ``Δ = 0`` never
produces NaN.

Compilation. The kernels call the system through four names — ``field_into``,
``field_derivative_into``, ``delta`` and (frame systems) ``W_into`` — defined below as
placeholders. :func:`compile_system` makes, per system, a copy of each kernel whose
globals bind those names to the mechanism's generated functions (``L_into``/``Q_into`` or
``N_into``/``QN_into``, ``delta``, ``W_into``, compiled with ``numba.njit``), so that they
are inlined; each copy has its own qualified name (mechanism, system, a hash of the
generated source), hence its own on-disk cache entry. (A closure over the compiled
functions would read the same, but numba cannot cache it: the cache key pickles the
closure's cells, and a compiled function pickles differently in every process.)

The step is inlined too, by code generation: called, it keeps its arrays out of
registers and slows every kernel markedly, and numba's own inlining multiplies the
compilation time. ``nonholo derive`` writes :mod:`nonholo.generated.cf4_kernels`, the
kernels of this module with every call of :func:`cf4_step`, :func:`cf4_stage` and
:func:`zpredict` expanded in place; that is what gets compiled.
``compile_system(..., inlined=False)`` compiles the kernels as written here, and
``tests/test_cf4.py`` checks that both give the same numbers, bit for bit.
"""
from __future__ import annotations

import hashlib
import inspect
import sys
import types
from dataclasses import dataclass

import numpy as np

from ..generated import cf4_kernels as kernels_inlined
from ..numerics import effort
from ..numerics.jit import jit
from ..numerics.kernels import exp_times, inv33

# --------------------------------------------------------------------------------------
# The system a kernel integrates (bound per system by compile_system)
# --------------------------------------------------------------------------------------


def _placeholder(*args):
    raise NotImplementedError("placeholder: bound per system by nonholo.integrate.cf4.compile_system")


#: ``field_into(R, out)``: ``out = G(R)`` (3×m), the mechanism's generated ``L_into`` or,
#: for the frame system, ``N_into``.
field_into = _placeholder
#: ``field_derivative_into(R, v, out)``: ``out = DG(R, v)`` (3×3) with
#: ``d/dε G(exp(ε[s]) R) v = DG s``: the generated ``Q_into`` (eq. (12)) or ``QN_into``.
field_derivative_into = _placeholder
#: ``delta(R)``: the mechanism's singularity function ``Δ(R)`` (``+inf`` without one).
delta = _placeholder
#: ``W_into(R, out)``: ``out = W(R)`` (m×m), physical inputs ``u = W(R) w`` of frame
#: coordinates ``w`` (frame system only).
W_into = _placeholder


def no_singularity(R):
    """``Δ ≡ +inf``: the singularity function of a mechanism without a singular set."""
    return np.inf


@jit
def angular_velocity(B, v, out):
    """``out = B v`` (3×m times m); ``False`` if not finite."""
    m = B.shape[1]
    for i in range(3):
        s = 0.0
        for k in range(m):
            s += B[i, k] * v[k]
        out[i] = s
    return np.isfinite(out[0]) and np.isfinite(out[1]) and np.isfinite(out[2])


def cf4_stage(ax, ay, az, base, Y, v, sgn, delta_stop, dmin, B, F, E):
    """One stage of :func:`cf4_step`: the stage point ``Y = exp([a]) base``, its ``sgnΔ``
    (lowering ``dmin``), the field ``B = G(Y)`` and the angular velocity ``F = B v``.
    Returns ``(ok, dmin)``: ``ok`` is false where ``sgnΔ < delta_stop`` (or is NaN) or
    ``ω`` is not finite."""
    ok = False
    exp_times(ax, ay, az, base, E, Y)
    d = sgn * delta(Y)
    dmin = min(dmin, d)
    if d >= delta_stop:
        field_into(Y, B)
        ok = angular_velocity(B, v, F)
    return ok, dmin


@jit
def cf4_close(F1, F2, F3, F4, h12, R, E, Rh, Rn):
    """CF4's two closing exponentials: ``Rn = exp(h/12 (−ω1 + 2ω2 + 2ω3 + 3ω4)) exp(h/12 (3ω1
    + 2ω2 + 2ω3 − ω4)) R`` from the stage angular velocities ``F1 … F4`` (the first three
    entries of each; ``h12 = h/12``; ``E``, ``Rh``: scratch). Shared by :func:`cf4_step` and
    the product group's step (:mod:`nonholo.integrate.cf4_product`)."""
    exp_times(h12 * (3.0 * F1[0] + 2.0 * F2[0] + 2.0 * F3[0] - F4[0]),
              h12 * (3.0 * F1[1] + 2.0 * F2[1] + 2.0 * F3[1] - F4[1]),
              h12 * (3.0 * F1[2] + 2.0 * F2[2] + 2.0 * F3[2] - F4[2]), R, E, Rh)
    exp_times(h12 * (-F1[0] + 2.0 * F2[0] + 2.0 * F3[0] + 3.0 * F4[0]),
              h12 * (-F1[1] + 2.0 * F2[1] + 2.0 * F3[1] + 3.0 * F4[1]),
              h12 * (-F1[2] + 2.0 * F2[2] + 2.0 * F3[2] + 3.0 * F4[2]), Rh, E, Rn)


def cf4_step(R, Rn, v0, v1, v2, h, sgn, delta_stop, dmin, Y2, Y3, Y4, Rh, E,
             B1, B2, B3, B4, F1, F2, F3, F4):
    """One CF4 step of length ``h`` from ``R`` into ``Rn`` (see the module docstring).

    ``v0``, ``v1``, ``v2``: the inputs at the start, middle and end of the step. Fills the
    stage points ``Y2``, ``Y3``, ``Y4``, the fields ``B1 … B4`` (``B_k = G(Y_k)``, ``Y1 = R``)
    and the angular velocities ``F1 … F4`` (``Rh``, ``E``: scratch). Returns
    ``(stop, dmin)``: ``dmin`` lowered to every ``sgnΔ`` evaluated (at ``Y2``, ``Y3``,
    ``Y4`` and ``Rn``); ``stop = -1`` if the step completed, else the fraction of the step
    (0, ½ or 1) where ``sgnΔ < delta_stop`` or ``ω`` was not finite. (The workspace is
    passed array by array: views into one larger array would cost a reference count
    pair each, per step. Written with ``break`` rather than early returns so that it can
    be inlined, see :mod:`nonholo.generated.cf4_kernels`.)
    """
    stop = -1.0
    for _ in range(1):
        h2 = 0.5 * h
        h12 = h / 12.0
        field_into(R, B1)
        if not angular_velocity(B1, v0, F1):
            stop = 0.0
            break
        ok, dmin = cf4_stage(h2 * F1[0], h2 * F1[1], h2 * F1[2], R, Y2, v1, sgn, delta_stop, dmin,
                             B2, F2, E)
        if not ok:
            stop = 0.5
            break
        ok, dmin = cf4_stage(h2 * F2[0], h2 * F2[1], h2 * F2[2], R, Y3, v1, sgn, delta_stop, dmin,
                             B3, F3, E)
        if not ok:
            stop = 0.5
            break
        ok, dmin = cf4_stage(h * F3[0] - h2 * F1[0], h * F3[1] - h2 * F1[1], h * F3[2] - h2 * F1[2],
                             Y2, Y4, v2, sgn, delta_stop, dmin, B4, F4, E)
        if not ok:
            stop = 1.0
            break
        cf4_close(F1, F2, F3, F4, h12, R, E, Rh, Rn)
        d = sgn * delta(Rn)
        dmin = min(dmin, d)
        if not d >= delta_stop:
            stop = 1.0
    return stop, dmin


@jit
def step_workspace(m):
    """The arrays :func:`cf4_step` fills besides ``R``: ``(Rn, Y2, Y3, Y4, Rh, E, B1, B2,
    B3, B4, F1, F2, F3, F4)`` for ``m`` inputs."""
    return (np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3)),
            np.empty((3, 3)), np.empty((3, 3)), np.empty((3, m)), np.empty((3, m)),
            np.empty((3, m)), np.empty((3, m)), np.empty(3), np.empty(3), np.empty(3), np.empty(3))


# --------------------------------------------------------------------------------------
# Kernels
# --------------------------------------------------------------------------------------


def forward(R0, U, h, sgn, delta_stop, Rs):
    """CF4 over ``N = len(U)`` steps; ``Rs[n]`` = R at ``t_n`` (shape ``(N+1, 3, 3)``).

    Returns ``(n_done, min sgnΔ, t_stop)``: the number of completed steps (``N`` unless the
    trajectory reached ``sgnΔ < delta_stop`` or a non-finite ``ω``), the least ``sgnΔ`` over
    all evaluation points of the completed steps, and the stage time where it stopped
    (``-1`` if it did not).
    """
    N = U.shape[0]
    m = U.shape[2]
    R = R0.copy()
    Rn, Y2, Y3, Y4, Rh, E, B1, B2, B3, B4, F1, F2, F3, F4 = step_workspace(m)
    for i in range(3):
        for j in range(3):
            Rs[0, i, j] = R0[i, j]
    dmin = sgn * delta(R)
    if not dmin >= delta_stop:
        return 0, dmin, 0.0
    for n in range(N):
        stop, dmin = cf4_step(R, Rn, U[n, 0], U[n, 1], U[n, 2], h, sgn, delta_stop, dmin,
                              Y2, Y3, Y4, Rh, E, B1, B2, B3, B4, F1, F2, F3, F4)
        if stop >= 0.0:
            return n, dmin, n * h + stop * h
        for i in range(3):
            for j in range(3):
                R[i, j] = Rn[i, j]
                Rs[n + 1, i, j] = Rn[i, j]
    return N, dmin, -1.0


@jit
def zpredict(Z, a, f, out):
    """``out = Z + a f`` (3×3): the value of ``Z`` at a stage of RK4."""
    for i in range(3):
        for j in range(3):
            out[i, j] = Z[i, j] + a * f[i, j]


def zstage(Zc, Y, v, F, B, Qm, f, K):
    """One stage of ``dZ/dt = -Z A``, ``A = DG(Y, v) + [F]``: ``f = -Zc A``; and ``K = Zc B``."""
    field_derivative_into(Y, v, Qm)
    # A in locals (lets LLVM keep it in registers: the arrays could alias)
    a00 = Qm[0, 0]
    a01 = Qm[0, 1] - F[2]
    a02 = Qm[0, 2] + F[1]
    a10 = Qm[1, 0] + F[2]
    a11 = Qm[1, 1]
    a12 = Qm[1, 2] - F[0]
    a20 = Qm[2, 0] - F[1]
    a21 = Qm[2, 1] + F[0]
    a22 = Qm[2, 2]
    m = B.shape[1]
    for i in range(3):
        z0 = Zc[i, 0]
        z1 = Zc[i, 1]
        z2 = Zc[i, 2]
        f[i, 0] = -(z0 * a00 + z1 * a10 + z2 * a20)
        f[i, 1] = -(z0 * a01 + z1 * a11 + z2 * a21)
        f[i, 2] = -(z0 * a02 + z1 * a12 + z2 * a22)
        for k in range(m):
            K[i, k] = z0 * B[0, k] + z1 * B[1, k] + z2 * B[2, k]


def forward_variational(R0, U, h, sgn, delta_stop, Bidx, Bval, stride_b, stride_i,
                        Rs, Zs, J, Mq, Wd, full):
    """CF4 for ``R`` together with ``Z = Φ(t,0)^{-1}``, the Jacobian ``J`` and ``M(T)``.

    Inputs: as :func:`forward`, plus the stage basis ``(Bidx, Bval, stride_b, stride_i)``
    of the parametrisation: sparse (``Bidx.shape[2] == 0``: no Jacobian), or *dense* when
    ``Bidx`` is empty (``Bidx.shape[0] == 0``) and ``Bval`` has shape ``(N, 3, nb)``:
    ``Bidx[n, c, q] = q`` for every ``q < nb`` (Fourier bases); ``J`` is then one matrix
    product ``Wdᵀ Bval`` after the loop (BLAS) instead of a scatter per stage.
    Outputs (preallocated): ``Rs`` (``(N+1, 3, 3)``), ``Zs`` (``(N+1, 3, 3)``, ``Z(t_n)``;
    only ``Zs[N] = Z(T)`` unless ``full``), ``J`` (3 × p) ``= ∂s_T/∂λ``, ``Mq`` (3×3)
    ``= M(T)`` (only if ``full``), ``Wd``: shape ``(3N, 3m)`` (required by a dense basis)
    to receive the stage weights ``Wd[3n + c, i·m + k] = (W_c)_{ik}`` of every step —
    ``W_0 = h/6 Z_1 B_1``, ``W_½ = h/3 (Z_2 B_2 + Z_3 B_3)``, ``W_1 = h/6 Z_4 B_4``, so
    ``∫_0^T Z B v dt ≈ Σ W_c v(t_n + c h)`` for any ``v`` — or ``(0, 3m)``. Returns what
    :func:`forward` returns; ``J``, ``Mq``, ``Wd`` and ``Zs[N]`` are valid only if the run
    completed.
    """
    N = U.shape[0]
    m = U.shape[2]
    dense = Bidx.shape[0] == 0 and Bval.shape[0] == N
    keep_w = Wd.shape[0] == 3 * N
    nq = 0 if dense else Bidx.shape[2]
    R = R0.copy()
    # the step's arrays allocated here, not by step_workspace: LLVM then knows them apart,
    # which makes this kernel markedly faster (benchmarks/bench_plan.py)
    Rn = np.empty((3, 3))
    Y2 = np.empty((3, 3))
    Y3 = np.empty((3, 3))
    Y4 = np.empty((3, 3))
    Rh = np.empty((3, 3))
    E = np.empty((3, 3))
    B1 = np.empty((3, m))
    B2 = np.empty((3, m))
    B3 = np.empty((3, m))
    B4 = np.empty((3, m))
    F1 = np.empty(3)
    F2 = np.empty(3)
    F3 = np.empty(3)
    F4 = np.empty(3)
    Z = np.empty((3, 3))
    Zc = np.empty((3, 3))
    Qm = np.empty((3, 3))
    f1 = np.empty((3, 3))
    f2 = np.empty((3, 3))
    f3 = np.empty((3, 3))
    f4 = np.empty((3, 3))
    K1 = np.empty((3, m))
    K2 = np.empty((3, m))
    K3 = np.empty((3, m))
    K4 = np.empty((3, m))
    W = np.empty((3, 3, m))
    J[:, :] = 0.0
    for i in range(3):
        for j in range(3):
            Rs[0, i, j] = R0[i, j]
            Z[i, j] = 1.0 if i == j else 0.0
            Zs[0, i, j] = Z[i, j]
            Mq[i, j] = 0.0
    dmin = sgn * delta(R)
    if not dmin >= delta_stop:
        return 0, dmin, 0.0
    h2 = 0.5 * h
    h6 = h / 6.0
    h3 = h / 3.0
    for n in range(N):
        stop, dmin = cf4_step(R, Rn, U[n, 0], U[n, 1], U[n, 2], h, sgn, delta_stop, dmin,
                              Y2, Y3, Y4, Rh, E, B1, B2, B3, B4, F1, F2, F3, F4)
        if stop >= 0.0:
            return n, dmin, n * h + stop * h
        # Z at the stage points (Y1 = R(t_n), Z1 = Z), as RK4 on the additive factor
        zstage(Z, R, U[n, 0], F1, B1, Qm, f1, K1)
        zpredict(Z, h2, f1, Zc)
        zstage(Zc, Y2, U[n, 1], F2, B2, Qm, f2, K2)
        zpredict(Z, h2, f2, Zc)
        zstage(Zc, Y3, U[n, 1], F3, B3, Qm, f3, K3)
        zpredict(Z, h, f3, Zc)
        zstage(Zc, Y4, U[n, 2], F4, B4, Qm, f4, K4)
        for i in range(3):
            for j in range(3):
                R[i, j] = Rn[i, j]
                Rs[n + 1, i, j] = Rn[i, j]
        # update Z; quadrature weights of the step at c = 0, ½, 1
        for i in range(3):
            for j in range(3):
                Z[i, j] += h6 * (f1[i, j] + 2.0 * f2[i, j] + 2.0 * f3[i, j] + f4[i, j])
            for k in range(m):
                W[0, i, k] = h6 * K1[i, k]
                W[1, i, k] = h3 * (K2[i, k] + K3[i, k])
                W[2, i, k] = h6 * K4[i, k]
        if keep_w:
            for c in range(3):
                for i in range(3):
                    for k in range(m):
                        Wd[3 * n + c, i * m + k] = W[c, i, k]
        # J += Σ_c W_c ∂U[n, c]/∂λ (sparse basis)
        for c in range(3):
            for k in range(m):
                w0 = W[c, 0, k]
                w1 = W[c, 1, k]
                w2 = W[c, 2, k]
                off = k * stride_i
                for q in range(nq):
                    v = Bval[n, c, q]
                    col = Bidx[n, c, q] * stride_b + off
                    J[0, col] += v * w0
                    J[1, col] += v * w1
                    J[2, col] += v * w2
        if full:
            for i in range(3):
                for j in range(3):
                    Zs[n + 1, i, j] = Z[i, j]
            for i in range(3):
                for j in range(i, 3):
                    s1 = 0.0
                    s2 = 0.0
                    s3 = 0.0
                    s4 = 0.0
                    for k in range(m):
                        s1 += K1[i, k] * K1[j, k]
                        s2 += K2[i, k] * K2[j, k]
                        s3 += K3[i, k] * K3[j, k]
                        s4 += K4[i, k] * K4[j, k]
                    v = h6 * (s1 + 2.0 * s2 + 2.0 * s3 + s4)
                    Mq[i, j] += v
                    if j != i:
                        Mq[j, i] += v
    # Z(T), J = Z(T)^{-1} Σ W ∂U/∂λ, M(T) = Z(T)^{-1} Mq Z(T)^{-T}
    for i in range(3):
        for j in range(3):
            Zs[N, i, j] = Z[i, j]
    inv33(Z, E)
    p = J.shape[1]
    if dense:
        nb = Bval.shape[2]
        A = np.dot(Wd.T, Bval.reshape((3 * N, nb)))        # (3m, nb)
        for k in range(m):
            for q in range(nb):
                col = q * stride_b + k * stride_i
                for i in range(3):
                    J[i, col] = A[i * m + k, q]
    for k in range(p):
        a0 = J[0, k]
        a1 = J[1, k]
        a2 = J[2, k]
        for i in range(3):
            J[i, k] = E[i, 0] * a0 + E[i, 1] * a1 + E[i, 2] * a2
    if full:
        X = np.empty((3, 3))        # X = Z(T)^{-1} Mq, then Mq = X Z(T)^{-T}
        for i in range(3):
            for j in range(3):
                X[i, j] = E[i, 0] * Mq[0, j] + E[i, 1] * Mq[1, j] + E[i, 2] * Mq[2, j]
        for i in range(3):
            for j in range(3):
                Zc[i, j] = X[i, 0] * E[j, 0] + X[i, 1] * E[j, 1] + X[i, 2] * E[j, 2]
        for i in range(3):
            for j in range(3):
                Mq[i, j] = 0.5 * (Zc[i, j] + Zc[j, i])
    return N, dmin, -1.0


def frame_inputs(nodes, idx, s, Wst, w_end, Rout, out):
    """Physical inputs ``u = W(R(t)) w(t)`` along a motion planned in frame coordinates.

    For every sample ``k``: ``R(t_k)`` is node ``idx[k]`` of the CF4 trajectory ``nodes``
    advanced by one CF4 step (:func:`cf4_step`) of length ``s[k]`` (none if ``s[k] == 0``) with frame inputs ``Wst[k, 0]``,
    ``Wst[k, 1]``, ``Wst[k, 2]`` at its start, middle and end — the same local
    approximation as a step of the integrator, ``O(s⁵)`` from the exact motion. Outputs
    ``Rout[k] = R(t_k)`` and ``out[k] = W(R(t_k)) w_end[k]``.
    """
    n_t = idx.shape[0]
    m = Wst.shape[2]
    R = np.empty((3, 3))
    Rn, Y2, Y3, Y4, Rh, E, B1, B2, B3, B4, F1, F2, F3, F4 = step_workspace(m)
    Wm = np.empty((m, m))
    for k in range(n_t):
        for i in range(3):
            for j in range(3):
                R[i, j] = nodes[idx[k], i, j]
                Rn[i, j] = R[i, j]
        if s[k] != 0.0:
            stop, dmin = cf4_step(R, Rn, Wst[k, 0], Wst[k, 1], Wst[k, 2], s[k], 1.0, -np.inf, np.inf,
                                  Y2, Y3, Y4, Rh, E, B1, B2, B3, B4, F1, F2, F3, F4)
        for i in range(3):
            for j in range(3):
                Rout[k, i, j] = Rn[i, j]
        W_into(Rn, Wm)
        for i in range(m):
            v = 0.0
            for j in range(m):
                v += Wm[i, j] * w_end[k, j]
            out[k, i] = v


# --------------------------------------------------------------------------------------
# Compilation per system
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Kernels:
    """The compiled kernels of one system of a mechanism: ``ω = L(R) u`` or, with
    ``frame``, its desingularised frame ``ω = N(R) w`` (then :attr:`frame_inputs`
    evaluates ``u = W(R) w``). Arguments: those of the functions of the same names."""

    name: str
    frame: bool
    n_inputs: int
    has_singular_set: bool
    forward: object
    forward_variational: object
    frame_inputs: object = None


#: The kernels, in the form numba compiles: :mod:`nonholo.generated.cf4_kernels`, the
#: functions of this module with the calls of :func:`cf4_step`, :func:`cf4_stage` and
#: :func:`zpredict` expanded in place (written by ``nonholo derive``).
_TEMPLATES = (zstage, kernels_inlined.forward, kernels_inlined.forward_variational,
              kernels_inlined.frame_inputs)
#: The kernels as written here (``compile_system(..., inlined=False)``).
_WRITTEN = (cf4_stage, cf4_step, zstage, forward, forward_variational, frame_inputs)


def specialise(template, namespace: dict, bindings: dict, tag: str, cache: bool):
    """A compiled copy of ``template`` whose globals are ``namespace`` (a kernel module's
    globals) with the system's names bound (``bindings``)."""
    f = types.FunctionType(template.__code__, {**namespace, **bindings}, template.__name__)
    f.__qualname__ = f"{template.__name__}__{tag}"        # its own cache entry
    f.__module__ = namespace["__name__"]
    f.__doc__ = template.__doc__
    return jit(f, cache=cache)


def system_tag(module, frame: bool) -> str:
    """The cache name of a system: mechanism, system and a hash of the generated source."""
    src = inspect.getsource(module) if importable(module) else module.SOURCE
    return f"{module.NAME}{'_frame' if frame else ''}_{hashlib.sha256(src.encode()).hexdigest()[:12]}"


def importable(module) -> bool:
    """Whether ``module`` can be re-imported by name (a cached kernel refers to it by name)."""
    return sys.modules.get(getattr(module, "__name__", None)) is module


#: Compiled kernels by system tag, and by (module, frame) (the tag hashes the source).
_COMPILED: dict[str, Kernels] = {}
_BY_MODULE: dict[tuple, Kernels] = {}


def compile_system(module, frame: bool = False, inlined: bool = True) -> Kernels:
    """The kernels of a system of the generated ``module``'s mechanism (compiled once,
    cached on disk).

    ``frame=False``: ``ω = L(R) u`` (``L_into``, ``Q_into``); ``frame=True``: the
    desingularised frame ``ω = N(R) w`` (``N_into``, ``QN_into``, and ``W_into`` for
    :func:`frame_inputs`). Both watch the mechanism's ``delta`` (if any). Kernels of a
    module that cannot be re-imported by name (built in this process, see
    :meth:`nonholo.model.mechanism.Mechanism.from_symbolic`) are not cached on disk. Numba
    compiles a kernel on its first call, so a run pays only for what it uses.
    ``inlined=False`` compiles the kernels as this module writes them instead (the step
    called, not inlined; slower, not cached): the reference the generated ones are
    checked against.
    """
    if (module, frame) in _BY_MODULE and inlined:
        return _BY_MODULE[module, frame]
    if frame and not getattr(module, "HAS_FRAME", False):
        raise ValueError(f"mechanism {module.NAME!r} has no desingularised frame N(R)")
    if not inlined:
        return _compile(module, frame, _WRITTEN, system_tag(module, frame) + "_written", False)
    tag = system_tag(module, frame)
    if tag in _COMPILED:
        _BY_MODULE[module, frame] = _COMPILED[tag]
        return _COMPILED[tag]
    kern = _compile(module, frame, _TEMPLATES, tag, importable(module))
    _COMPILED[tag] = _BY_MODULE[module, frame] = kern
    return kern


def _compile(module, frame: bool, templates, tag: str, cache: bool) -> Kernels:
    """Compile ``templates`` for a system of ``module`` (see :func:`compile_system`)."""
    G, DG = (module.N_into, module.QN_into) if frame else (module.L_into, module.Q_into)
    bindings = {
        "field_into": jit(G, cache=False),
        # DG feeds only the variational system (the Jacobian): fast-math lets LLVM turn
        # its ``x**(-2.0)`` into a multiplication (the result changes at round-off level)
        "field_derivative_into": jit(DG, cache=False, fastmath=True),
        "delta": jit(module.delta if module.HAS_SINGULAR_SET else no_singularity, cache=False),
    }
    if frame:
        bindings["W_into"] = jit(module.W_into, cache=False)
    for template in templates:
        if template.__name__ == "frame_inputs" and not frame:
            continue
        bindings[template.__name__] = specialise(template, globals(), bindings, tag, cache)
    frame_kernel = bindings.get("frame_inputs")
    kern = Kernels(name=module.NAME, frame=frame, n_inputs=module.N_INPUTS,
                   has_singular_set=module.HAS_SINGULAR_SET,
                   forward=metered(bindings["forward"], effort.FORWARD_WEIGHT, 1),
                   forward_variational=metered(bindings["forward_variational"], 1.0, 1),
                   frame_inputs=None if frame_kernel is None else metered(frame_kernel, effort.FORWARD_WEIGHT, 1))
    return kern


def metered(kernel, weight: float, counted: int):
    """``kernel`` counting its effort (:mod:`nonholo.numerics.effort`): ``weight`` per element of its
    argument number ``counted`` (the stage table's steps; ``frame_inputs``' node indices)."""

    def run(*args):
        effort.add(weight * len(args[counted]))
        return kernel(*args)

    run.__name__ = run.__qualname__ = getattr(kernel, "__name__", "kernel")
    run.__doc__ = kernel.__doc__
    run.kernel = kernel
    return run
