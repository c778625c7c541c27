"""The CF4 Lie-group integrator and the variational system (9), compiled per system.

Conventions
-----------
- A *system* is ``dR/dt = [ω] R`` with ``ω = G(R) v`` (spatial form): ``G = L`` and ``v``
  the physical inputs ``u`` of a mechanism, or ``G = N`` (its desingularised frame) and
  ``v = w`` the frame coordinates. It is integrated while the mechanism's ``Δ`` is
  watched (``Δ ≡ +inf`` without a singular set).
- Fixed step ``h = T/N``. The inputs enter through a *stage table* ``U`` of shape
  ``(N, 3, m)``: ``U[n, 0]``, ``U[n, 1]``, ``U[n, 2]`` are the inputs at ``t_n``,
  ``t_n + h/2`` and ``t_n + h`` of step ``n`` (``t_n = n h``); see :mod:`nonholo.stages`.

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
intermediate states (the barrier of :mod:`nonholo.planning.robust`).

Singular set: ``sgn Δ`` (``sgn = sign Δ(R0)``) is checked at every stage point and node;
the kernels stop as soon as it falls below ``delta_stop`` (or ``ω`` is not finite) and
report how many steps were completed, so a trajectory running into ``Δ = 0`` never
produces NaN.

Compilation. The kernels call the mechanism through the names of its generated
functions — ``L_into``, ``Q_into``, ``N_into``, ``QN_into``, ``W_into``, ``delta`` — defined
below as placeholders, and take the system (``frame``: ``N``/``QN``, else ``L``/``Q``) as an
argument. :func:`compile_system` makes, per mechanism, a copy of each kernel whose globals
bind those names to the mechanism's generated functions (compiled with ``numba.njit``),
so that numba inlines them; each copy has its own qualified name (the mechanism and a
hash of its generated source), hence its own on-disk cache entry. (A closure over the compiled functions would read the same, but numba cannot
cache it: the cache key pickles the closure's cells, and a compiled function pickles
differently in every process.)
"""
from __future__ import annotations

import hashlib
import inspect
import sys
import types
import numba
import numpy as np

from .kernels import JIT_OPTIONS, exp_times, inv33

# --------------------------------------------------------------------------------------
# The mechanism a kernel integrates (bound per mechanism by compile_system)
# --------------------------------------------------------------------------------------


def _placeholder(*args):
    raise NotImplementedError("placeholder: bound per mechanism by nonholo.cf4.compile_system")


#: ``L_into(R, out)``: ``out = L(R)`` (3×m), the generated function of the mechanism.
L_into = _placeholder
#: ``Q_into(R, u, out)``: ``out = Q(R, u)`` (3×3) of eq. (12).
Q_into = _placeholder
#: ``N_into(R, out)``: ``out = N(R)``, the desingularised frame (``L`` without one).
N_into = _placeholder
#: ``QN_into(R, w, out)``: ``out = QN(R, w)``, the ``Q`` of the frame (``Q`` without one).
QN_into = _placeholder
#: ``W_into(R, out)``: ``out = W(R)`` (m×m), ``u = W(R) w`` (the identity without a frame).
W_into = _placeholder
#: ``delta(R)``: the singularity function ``Δ(R)`` (``+inf`` without a singular set).
delta = _placeholder


def no_singularity(R):
    """``Δ ≡ +inf``: the singularity function of a mechanism without a singular set."""
    return np.inf


def identity_into(R, out):
    """``out = I``: ``W`` of a mechanism without a frame (its frame coordinates are its inputs)."""
    for i in range(out.shape[0]):
        for j in range(out.shape[1]):
            out[i, j] = 1.0 if i == j else 0.0


def field_into(R, frame, out):
    """``out = G(R)``: ``N(R)`` for the frame system, ``L(R)`` for the physical one."""
    if frame:
        N_into(R, out)
    else:
        L_into(R, out)


def field_derivative_into(R, v, frame, out):
    """``out = DG(R, v)`` with ``d/dε G(exp(ε[s]) R) v = DG s``: ``QN`` or ``Q``."""
    if frame:
        QN_into(R, v, out)
    else:
        Q_into(R, v, out)


# --------------------------------------------------------------------------------------
# One CF4 step
# --------------------------------------------------------------------------------------


@numba.njit(**JIT_OPTIONS)
def angular_velocity(B, v, out):
    """``out = B v`` (3×m times m); ``False`` if not finite."""
    m = B.shape[1]
    for i in range(3):
        s = 0.0
        for k in range(m):
            s += B[i, k] * v[k]
        out[i] = s
    return np.isfinite(out[0]) and np.isfinite(out[1]) and np.isfinite(out[2])


def cf4_stage(ax, ay, az, base, Y, v, frame, sgn, delta_stop, dmin, B, F, E):
    """One stage of :func:`cf4_step`: the stage point ``Y = exp([a]) base``, its ``sgnΔ``
    (lowering ``dmin``), the field ``B = G(Y)`` and the angular velocity ``F = B v``.
    Returns ``(ok, dmin)``: ``ok`` is false where ``sgnΔ < delta_stop`` or ``ω`` is not
    finite (then ``B`` and ``F`` are not computed or not usable)."""
    exp_times(ax, ay, az, base, E, Y)
    d = sgn * delta(Y)
    dmin = min(dmin, d)
    if not d >= delta_stop:
        return False, dmin
    field_into(Y, frame, B)
    return angular_velocity(B, v, F), dmin


def cf4_step(R, Rnext, v0, v1, v2, h, frame, sgn, delta_stop, dmin, Y, B, F, E):
    """One CF4 step of length ``h`` from ``R`` into ``Rnext`` (see the module docstring).

    ``v0``, ``v1``, ``v2``: the inputs at the start, middle and end of the step (of the
    frame system if ``frame``, else of the physical one). Fills the stage points
    ``Y[0..2] = Y2, Y3, Y4``, the fields ``B[k] = G(Y_{k+1})`` (``Y_1 = R``) and the
    angular velocities ``F[k]`` (``E`` is scratch). Returns ``(stop, dmin)``: ``dmin``
    lowered to every ``sgnΔ`` evaluated (at ``Y2``, ``Y3``, ``Y4`` and ``Rnext``);
    ``stop = -1`` if the step completed, else the fraction of the step (0, ½ or 1) where
    ``sgnΔ < delta_stop`` or ``ω`` was not finite.
    """
    h2 = 0.5 * h
    h12 = h / 12.0
    field_into(R, frame, B[0])
    if not angular_velocity(B[0], v0, F[0]):
        return 0.0, dmin
    ok, dmin = cf4_stage(h2 * F[0, 0], h2 * F[0, 1], h2 * F[0, 2], R, Y[0], v1, frame, sgn,
                         delta_stop, dmin, B[1], F[1], E)
    if not ok:
        return 0.5, dmin
    ok, dmin = cf4_stage(h2 * F[1, 0], h2 * F[1, 1], h2 * F[1, 2], R, Y[1], v1, frame, sgn,
                         delta_stop, dmin, B[2], F[2], E)
    if not ok:
        return 0.5, dmin
    ok, dmin = cf4_stage(h * F[2, 0] - h2 * F[0, 0], h * F[2, 1] - h2 * F[0, 1],
                         h * F[2, 2] - h2 * F[0, 2], Y[0], Y[2], v2, frame, sgn, delta_stop, dmin,
                         B[3], F[3], E)
    if not ok:
        return 1.0, dmin
    Rh = Y[3]
    exp_times(h12 * (3.0 * F[0, 0] + 2.0 * F[1, 0] + 2.0 * F[2, 0] - F[3, 0]),
              h12 * (3.0 * F[0, 1] + 2.0 * F[1, 1] + 2.0 * F[2, 1] - F[3, 1]),
              h12 * (3.0 * F[0, 2] + 2.0 * F[1, 2] + 2.0 * F[2, 2] - F[3, 2]), R, E, Rh)
    exp_times(h12 * (-F[0, 0] + 2.0 * F[1, 0] + 2.0 * F[2, 0] + 3.0 * F[3, 0]),
              h12 * (-F[0, 1] + 2.0 * F[1, 1] + 2.0 * F[2, 1] + 3.0 * F[3, 1]),
              h12 * (-F[0, 2] + 2.0 * F[1, 2] + 2.0 * F[2, 2] + 3.0 * F[3, 2]), Rh, E, Rnext)
    d = sgn * delta(Rnext)
    dmin = min(dmin, d)
    if not d >= delta_stop:
        return 1.0, dmin
    return -1.0, dmin


@numba.njit(**JIT_OPTIONS)
def step_workspace(m):
    """Scratch of :func:`cf4_step`: ``(Y, B, F, E)`` (``Y[3]`` holds ``R½``)."""
    return np.empty((4, 3, 3)), np.empty((4, 3, m)), np.empty((4, 3)), np.empty((3, 3))


# --------------------------------------------------------------------------------------
# Kernels
# --------------------------------------------------------------------------------------


def forward(R0, U, h, frame, sgn, delta_stop, Rs):
    """CF4 over ``N = len(U)`` steps; ``Rs[n]`` = R at ``t_n`` (shape ``(N+1, 3, 3)``).

    Returns ``(n_done, min sgnΔ, t_stop)``: the number of completed steps (``N`` unless the
    trajectory reached ``sgnΔ < delta_stop`` or a non-finite ``ω``), the least ``sgnΔ`` over
    all evaluation points of the completed steps, and the stage time where it stopped
    (``-1`` if it did not).
    """
    N = U.shape[0]
    Y, B, F, E = step_workspace(U.shape[2])
    for i in range(3):
        for j in range(3):
            Rs[0, i, j] = R0[i, j]
    dmin = sgn * delta(Rs[0])
    if not dmin >= delta_stop:
        return 0, dmin, 0.0
    for n in range(N):
        stop, dmin = cf4_step(Rs[n], Rs[n + 1], U[n, 0], U[n, 1], U[n, 2], h, frame, sgn,
                              delta_stop, dmin, Y, B, F, E)
        if stop >= 0.0:
            return n, dmin, n * h + stop * h
    return N, dmin, -1.0


def zstage(Zc, Y, v, frame, F, B, Qm, f, K):
    """One stage of ``dZ/dt = -Z A``, ``A = DG(Y, v) + [F]``: ``f = -Zc A``; and ``K = Zc B``."""
    field_derivative_into(Y, v, frame, Qm)
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


def forward_variational(R0, U, h, frame, sgn, delta_stop, Bidx, Bval, stride_b, stride_i,
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
    Y, B, F, E = step_workspace(m)
    Z = np.empty((3, 3))
    Zc = np.empty((3, 3))
    Qm = np.empty((3, 3))
    f = np.empty((4, 3, 3))
    K = np.empty((4, 3, m))
    W = np.empty((3, 3, m))
    J[:, :] = 0.0
    for i in range(3):
        for j in range(3):
            Rs[0, i, j] = R0[i, j]
            Z[i, j] = 1.0 if i == j else 0.0
            Zs[0, i, j] = Z[i, j]
            Mq[i, j] = 0.0
    dmin = sgn * delta(Rs[0])
    if not dmin >= delta_stop:
        return 0, dmin, 0.0
    h2 = 0.5 * h
    h6 = h / 6.0
    h3 = h / 3.0
    for n in range(N):
        stop, dmin = cf4_step(Rs[n], Rs[n + 1], U[n, 0], U[n, 1], U[n, 2], h, frame, sgn,
                              delta_stop, dmin, Y, B, F, E)
        if stop >= 0.0:
            return n, dmin, n * h + stop * h
        # Z at the stage points (Y1 = R(t_n), Z1 = Z), as RK4 on the additive factor:
        # stage c + 1 at Y[c - 1], Zc = Z + (h/2, h/2, h)[c - 1] f[c - 1], inputs U[n, (c + 1) // 2]
        zstage(Z, Rs[n], U[n, 0], frame, F[0], B[0], Qm, f[0], K[0])
        for c in range(1, 4):
            a = h if c == 3 else h2
            for i in range(3):
                for j in range(3):
                    Zc[i, j] = Z[i, j] + a * f[c - 1, i, j]
            zstage(Zc, Y[c - 1], U[n, (c + 1) // 2], frame, F[c], B[c], Qm, f[c], K[c])
        # update Z; quadrature weights of the step at c = 0, ½, 1
        for i in range(3):
            for j in range(3):
                Z[i, j] += h6 * (f[0, i, j] + 2.0 * f[1, i, j] + 2.0 * f[2, i, j] + f[3, i, j])
            for k in range(m):
                W[0, i, k] = h6 * K[0, i, k]
                W[1, i, k] = h3 * (K[1, i, k] + K[2, i, k])
                W[2, i, k] = h6 * K[3, i, k]
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
                        s1 += K[0, i, k] * K[0, j, k]
                        s2 += K[1, i, k] * K[1, j, k]
                        s3 += K[2, i, k] * K[2, j, k]
                        s4 += K[3, i, k] * K[3, j, k]
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


def frame_inputs(nodes, idx, s, frame, Wst, w_end, Rout, out):
    """Physical inputs ``u = W(R(t)) w(t)`` along a motion planned in frame coordinates.

    For every sample ``k``: ``R(t_k)`` is node ``idx[k]`` of the CF4 trajectory ``nodes``
    advanced by one CF4 step (:func:`cf4_step`, of the frame system: ``frame`` is true)
    of length ``s[k]`` (none if ``s[k] == 0``) with frame inputs ``Wst[k, 0]``, ``Wst[k, 1]``, ``Wst[k, 2]`` at its start, middle and
    end — the same local approximation as a step of the integrator, ``O(s⁵)`` from the
    exact motion. Outputs ``Rout[k] = R(t_k)`` and ``out[k] = W(R(t_k)) w_end[k]``.
    """
    n_t = idx.shape[0]
    m = Wst.shape[2]
    Y, B, F, E = step_workspace(m)
    Wm = np.empty((m, m))
    for k in range(n_t):
        if s[k] == 0.0:
            for i in range(3):
                for j in range(3):
                    Rout[k, i, j] = nodes[idx[k], i, j]
        else:
            cf4_step(nodes[idx[k]], Rout[k], Wst[k, 0], Wst[k, 1], Wst[k, 2], s[k], frame, 1.0,
                     -np.inf, np.inf, Y, B, F, E)
        W_into(Rout[k], Wm)
        for i in range(m):
            v = 0.0
            for j in range(m):
                v += Wm[i, j] * w_end[k, j]
            out[k, i] = v


# --------------------------------------------------------------------------------------
# Compilation per system
# --------------------------------------------------------------------------------------


class Kernels:
    """The compiled kernels of one system of a mechanism: ``ω = L(R) u`` or, with
    ``frame``, its desingularised frame ``ω = N(R) w`` (then :meth:`frame_inputs`
    evaluates ``u = W(R) w``). The arguments are those of the module's functions of the
    same names, without ``frame``."""

    def __init__(self, compiled: dict, name: str, frame: bool, n_inputs: int, has_singular_set: bool):
        self._compiled = compiled
        self.name = name
        self.frame = frame
        self.n_inputs = n_inputs
        self.has_singular_set = has_singular_set

    def forward(self, R0, U, h, sgn, delta_stop, Rs):
        return self._compiled["forward"](R0, U, h, self.frame, sgn, delta_stop, Rs)

    def forward_variational(self, R0, U, h, sgn, delta_stop, Bidx, Bval, stride_b, stride_i,
                            Rs, Zs, J, Mq, Wd, full):
        return self._compiled["forward_variational"](R0, U, h, self.frame, sgn, delta_stop, Bidx, Bval,
                                                     stride_b, stride_i, Rs, Zs, J, Mq, Wd, full)

    def frame_inputs(self, nodes, idx, s, Wst, w_end, Rout, out):
        if not self.frame:
            raise ValueError("frame_inputs needs the kernels of the frame system (frame=True)")
        return self._compiled["frame_inputs"](nodes, idx, s, True, Wst, w_end, Rout, out)

    def __repr__(self) -> str:
        return f"Kernels({self.name!r}, frame={self.frame})"


#: The kernels of this module, callees first.
_TEMPLATES = (field_into, field_derivative_into, cf4_stage, cf4_step, forward, zstage, forward_variational,
              frame_inputs)
_PLAIN = dict(nogil=True, error_model="numpy")


def _specialise(template, bindings: dict, tag: str, cache: bool):
    """A compiled copy of ``template`` whose globals bind the mechanism's names (``bindings``)."""
    glb = {**template.__globals__, **bindings}
    f = types.FunctionType(template.__code__, glb, template.__name__)
    f.__qualname__ = f"{template.__name__}__{tag}"        # its own cache entry
    f.__module__ = __name__
    f.__doc__ = template.__doc__
    return numba.njit(**{**JIT_OPTIONS, "cache": cache})(f)


def mechanism_tag(module) -> str:
    """The cache name of a mechanism's kernels: its name and a hash of the generated source."""
    src = inspect.getsource(module) if _importable(module) else module.SOURCE
    return f"{module.NAME}_{hashlib.sha256(src.encode()).hexdigest()[:12]}"


def _importable(module) -> bool:
    """Whether ``module`` can be re-imported by name (a cached kernel refers to it by name)."""
    return sys.modules.get(getattr(module, "__name__", None)) is module


_COMPILED: dict[str, dict] = {}


def compile_system(module, frame: bool = False) -> Kernels:
    """The kernels of the generated ``module``'s mechanism (compiled once, cached on disk).

    ``frame=False``: the system ``ω = L(R) u`` (``L_into``, ``Q_into``); ``frame=True``: the
    desingularised frame ``ω = N(R) w`` (``N_into``, ``QN_into``, and ``W_into`` for
    :func:`frame_inputs`). Both watch the mechanism's ``delta`` (if any), and both run on
    the same compiled kernels (the system is an argument), so a run that uses both pays
    for one compilation. Kernels of a module that cannot be re-imported by name (built in
    this process, see :meth:`nonholo.mechanism.Mechanism.from_symbolic`) are not cached
    on disk. Numba compiles a kernel on its first call, so a run pays only for what it
    uses.
    """
    if frame and not getattr(module, "HAS_FRAME", False):
        raise ValueError(f"mechanism {module.NAME!r} has no desingularised frame N(R)")
    tag = mechanism_tag(module)
    if tag not in _COMPILED:
        cache = _importable(module)
        has_frame = getattr(module, "HAS_FRAME", False)
        generated = {
            "L_into": module.L_into,
            "Q_into": module.Q_into,
            "N_into": module.N_into if has_frame else module.L_into,
            "QN_into": module.QN_into if has_frame else module.Q_into,
            "W_into": module.W_into if has_frame else identity_into,
            "delta": module.delta if module.HAS_SINGULAR_SET else no_singularity,
        }
        # Q and QN feed only the variational system (the Jacobian): fast-math lets LLVM turn
        # their ``x**(-2.0)`` into a multiplication (the result changes at round-off level)
        bindings = {name: numba.njit(fastmath=name in ("Q_into", "QN_into"), **_PLAIN)(f)
                    for name, f in generated.items()}
        for template in _TEMPLATES:
            bindings[template.__name__] = _specialise(template, bindings, tag, cache)
        _COMPILED[tag] = bindings
    return Kernels(_COMPILED[tag], module.NAME, frame, module.N_INPUTS, module.HAS_SINGULAR_SET)
