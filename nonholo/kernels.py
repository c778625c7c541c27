"""Compiled (numba) kernels: the CF4 Lie-group integrator and the variational system (9).

Conventions
-----------
- System (1) in the spatial form ``dR/dt = [ω] R``, ``ω = L(R) u``.
- Fixed step ``h = T/N``. The controls enter through a *stage table* ``U`` of shape
  ``(N, 3, m)``: ``U[n, 0]``, ``U[n, 1]``, ``U[n, 2]`` are the inputs used at the times
  ``t_n``, ``t_n + h/2`` and ``t_n + h`` of step ``n`` (``t_n = n h``). For smooth
  controls ``U[n, 2] = U[n + 1, 0]``; for controls that are constant on each step
  (piecewise constant on a grid aligned with the steps) all three are the step's value,
  so the integrator never sees a jump inside a step.

The integrator is the 4th-order commutator-free method CF4 of Celledoni, Marthinsen and
Owren (2003) with the Rodrigues exponential; every update multiplies ``R`` by a rotation,
so ``R`` stays on SO(3) up to round-off::

    F1 = L(R) U[n,0]
    Y2 = exp(h/2 F1) R,            F2 = L(Y2) U[n,1]
    Y3 = exp(h/2 F2) R,            F3 = L(Y3) U[n,1]
    Y4 = exp(h F3 - h/2 F1) Y2,    F4 = L(Y4) U[n,2]
    R½ = exp(h/12 (3F1 + 2F2 + 2F3 - F4)) R
    R' = exp(h/12 (-F1 + 2F2 + 2F3 + 3F4)) R½

The variational system (9), ``ds/dt = A s + B ∂u/∂θ`` with ``A = Q(R, u) + [L(R) u]`` and
``B = L(R)``, is handled through ``Z(t) = Φ(t, 0)^{-1} = Φ(0, t)``, ``dZ/dt = -Z A``,
``Z(0) = I``. Then ``Φ(T, t) = Z(T)^{-1} Z(t)`` and

    s_T = Z(T)^{-1} ∫ Z(t) B(t) ∂u/∂θ(t) dt,
    M(T) = ∫ Φ(T,t) B Bᵀ Φ(T,t)ᵀ dt = Z(T)^{-1} [∫ Z B Bᵀ Zᵀ dt] Z(T)^{-T}.

``Z`` and the two integrals are advanced by CF4 on the product group
``SO(3) × (R^{3×3}, +) × …`` (on the additive factors CF4 reduces to the classical RK4
tableau, evaluated at CF4's own stage values ``Y_i``), so the coupled scheme is of order
4. The quadrature weights of a step are ``W_0 = h/6 Z_1 B_1``, ``W_½ = h/3 (Z_2 B_2 +
Z_3 B_3)``, ``W_1 = h/6 Z_4 B_4`` (3×m) at the stage times ``c = 0, ½, 1``.

Parametrised controls are linear in their parameters ``λ``: every parametrisation here
is described by a *sparse stage basis* ``(Bidx, Bval, stride_b, stride_i)`` with
``U[n, c, i] = Σ_q Bval[n, c, q] λ[Bidx[n, c, q]·stride_b + i·stride_i]`` (Fourier: the
basis functions at the stage times; grid controls: one entry, the interval's index). The
kernel accumulates ``J = Z(T)^{-1} Σ_{n,c} W_c ∂U[n, c]/∂λ`` in place, so one planner
iteration costs one pass (``J`` is the Jacobian ``∂s_T/∂λ`` of (10)).

Singular set: ``sgn Δ`` (``sgn = sign Δ(R0)``) is checked at every point where ``L`` is
evaluated; the kernels stop as soon as it falls below ``delta_stop`` (or ``ω`` is not
finite) and report how many steps were completed, so a trajectory running into ``Δ = 0``
never produces NaN. Mechanisms without a singular set use ``Δ ≡ +inf``.

For Fourier bases the kernel can instead store the stage weights ``W_c`` of every step
(``Wd``) and contract them with the *dense* stage basis by one matrix product after the
loop (BLAS) — same ``J``, a third of the accumulation cost; the stored weights also give
the sensitivity of intermediate states (used by the barrier of :mod:`nonholo.robust`).

Kernels are compiled per mechanism, from the generated ``L``, ``Q`` and ``delta``
(rewritten to fill preallocated arrays instead of allocating, see :func:`into`), and
cached on disk by mechanism name and a hash of the generated module's source
(``cache=True``; not for a module registered at run time from a file, which another
process could not import by name); see :func:`get`. ``get(name, frame=True)`` binds the same templates to
the desingularised frame ``N(R)``, ``QN(R, w)`` of the generated module instead (the system
``dR/dt = [N(R) w] R``; ``Δ`` is still the mechanism's), with :func:`_frame_inputs`
(bound to ``W(R)``) evaluating the physical inputs ``u = W(R(t)) w(t)`` between nodes.

Small helpers of the planner: :func:`log_error` (``l_T`` and ``|l_T|``),
:func:`min_norm_step` (3×3 Cholesky solve with an eigen fallback),
:func:`grid_stage_values`.
"""
from __future__ import annotations

import ast
import hashlib
import inspect
import sys
import textwrap
import types
from dataclasses import dataclass
from functools import cache

import numba
import numpy as np

from . import mechanisms

_JIT = dict(cache=True, nogil=True, error_model="numpy", fastmath=False)


@numba.njit(**_JIT)
def _rodrigues(wx, wy, wz, E):
    """``E = exp([w])`` (Rodrigues; Taylor series for small angles)."""
    a2 = wx * wx + wy * wy + wz * wz
    if a2 < 1e-8:
        c1 = 1.0 - a2 / 6.0 + a2 * a2 / 120.0
        c2 = 0.5 - a2 / 24.0 + a2 * a2 / 720.0
    else:
        a = np.sqrt(a2)
        c1 = np.sin(a) / a
        c2 = (1.0 - np.cos(a)) / a2
    xx = wx * wx
    yy = wy * wy
    zz = wz * wz
    xy = wx * wy
    xz = wx * wz
    yz = wy * wz
    E[0, 0] = 1.0 - c2 * (yy + zz)
    E[1, 1] = 1.0 - c2 * (xx + zz)
    E[2, 2] = 1.0 - c2 * (xx + yy)
    E[0, 1] = -c1 * wz + c2 * xy
    E[1, 0] = c1 * wz + c2 * xy
    E[0, 2] = c1 * wy + c2 * xz
    E[2, 0] = -c1 * wy + c2 * xz
    E[1, 2] = -c1 * wx + c2 * yz
    E[2, 1] = c1 * wx + c2 * yz


@numba.njit(**_JIT)
def _exp_times(wx, wy, wz, R, E, out):
    """``out = exp([w]) R`` (``E`` is scratch; ``out`` must not alias ``R``)."""
    _rodrigues(wx, wy, wz, E)
    for i in range(3):
        e0 = E[i, 0]
        e1 = E[i, 1]
        e2 = E[i, 2]
        for j in range(3):
            out[i, j] = e0 * R[0, j] + e1 * R[1, j] + e2 * R[2, j]


@numba.njit(**_JIT)
def _omega(B, u, m, w):
    """``w = B u`` (3×m times m); returns False if not finite."""
    for i in range(3):
        s = 0.0
        for k in range(m):
            s += B[i, k] * u[k]
        w[i] = s
    return np.isfinite(w[0]) and np.isfinite(w[1]) and np.isfinite(w[2])


@numba.njit(**_JIT)
def _inv33(Z, out):
    """``out = Z^{-1}`` (cofactors)."""
    c00 = Z[1, 1] * Z[2, 2] - Z[1, 2] * Z[2, 1]
    c01 = Z[1, 2] * Z[2, 0] - Z[1, 0] * Z[2, 2]
    c02 = Z[1, 0] * Z[2, 1] - Z[1, 1] * Z[2, 0]
    d = 1.0 / (Z[0, 0] * c00 + Z[0, 1] * c01 + Z[0, 2] * c02)
    out[0, 0] = c00 * d
    out[1, 0] = c01 * d
    out[2, 0] = c02 * d
    out[0, 1] = (Z[0, 2] * Z[2, 1] - Z[0, 1] * Z[2, 2]) * d
    out[1, 1] = (Z[0, 0] * Z[2, 2] - Z[0, 2] * Z[2, 0]) * d
    out[2, 1] = (Z[0, 1] * Z[2, 0] - Z[0, 0] * Z[2, 1]) * d
    out[0, 2] = (Z[0, 1] * Z[1, 2] - Z[0, 2] * Z[1, 1]) * d
    out[1, 2] = (Z[0, 2] * Z[1, 0] - Z[0, 0] * Z[1, 2]) * d
    out[2, 2] = (Z[0, 0] * Z[1, 1] - Z[0, 1] * Z[1, 0]) * d


@numba.njit(**_JIT)
def log_rotation(R):
    """Rotation vector ``l`` with ``exp([l]) = R``, ``|l| ≤ π`` (the error of (4): ``[l] = log R``).

    ``sin α · a = vee(R − Rᵀ)/2`` and ``cos α = (tr R − 1)/2`` give ``α = atan2``; near
    ``α = π`` the axis comes from the symmetric part ``(R + Rᵀ)/2 − cos α I = (1 − cos α) a aᵀ``.
    """
    sx = 0.5 * (R[2, 1] - R[1, 2])
    sy = 0.5 * (R[0, 2] - R[2, 0])
    sz = 0.5 * (R[1, 0] - R[0, 1])
    c = 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)
    c = min(1.0, max(-1.0, c))
    s = np.sqrt(sx * sx + sy * sy + sz * sz)
    a = np.arctan2(s, c)
    out = np.empty(3)
    if c > -0.9:
        f = 1.0 + s * s / 6.0 if s < 1e-6 else a / s
        out[0] = f * sx
        out[1] = f * sy
        out[2] = f * sz
        return out
    k = 0
    for i in range(1, 3):
        if R[i, i] > R[k, k]:
            k = i
    v0 = 0.5 * (R[0, k] + R[k, 0]) - (c if k == 0 else 0.0)
    v1 = 0.5 * (R[1, k] + R[k, 1]) - (c if k == 1 else 0.0)
    v2 = 0.5 * (R[2, k] + R[k, 2]) - (c if k == 2 else 0.0)
    n = np.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    if v0 * sx + v1 * sy + v2 * sz < 0.0:
        n = -n
    out[0] = a * v0 / n
    out[1] = a * v1 / n
    out[2] = a * v2 / n
    return out


@numba.njit(**_JIT)
def log_error(R, Rd):
    """``(l, |l|)`` with ``[l] = log(R Rdᵀ)``: the planner's error ``l_T`` and its norm (rad)."""
    P = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            P[i, j] = R[i, 0] * Rd[j, 0] + R[i, 1] * Rd[j, 1] + R[i, 2] * Rd[j, 2]
    l = log_rotation(P)
    return l, np.sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2])


@numba.njit(**_JIT)
def _eigh3(A, w, V):
    """Eigen decomposition of a symmetric 3×3 ``A`` (cyclic Jacobi): ``A = V diag(w) Vᵀ``."""
    a = A.copy()
    for i in range(3):
        for j in range(3):
            V[i, j] = 1.0 if i == j else 0.0
    for _ in range(50):
        off = a[0, 1] * a[0, 1] + a[0, 2] * a[0, 2] + a[1, 2] * a[1, 2]
        scale = a[0, 0] * a[0, 0] + a[1, 1] * a[1, 1] + a[2, 2] * a[2, 2]
        if off <= 1e-36 * scale or off == 0.0:
            break
        for p in range(2):
            for q in range(p + 1, 3):
                if a[p, q] == 0.0:
                    continue
                theta = (a[q, q] - a[p, p]) / (2.0 * a[p, q])
                t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + np.sqrt(theta * theta + 1.0))
                c = 1.0 / np.sqrt(t * t + 1.0)
                s = t * c
                for k in range(3):          # a ← a Gᵀ ... rotate columns p, q
                    akp = a[k, p]
                    akq = a[k, q]
                    a[k, p] = c * akp - s * akq
                    a[k, q] = s * akp + c * akq
                for k in range(3):          # ... and rows p, q
                    apk = a[p, k]
                    aqk = a[q, k]
                    a[p, k] = c * apk - s * aqk
                    a[q, k] = s * apk + c * aqk
                for k in range(3):
                    vkp = V[k, p]
                    vkq = V[k, q]
                    V[k, p] = c * vkp - s * vkq
                    V[k, q] = s * vkp + c * vkq
    for i in range(3):
        w[i] = a[i, i]


@numba.njit(**_JIT)
def _pinv_solve3(A, l, y):
    """``y = A^# l`` for a symmetric positive semi-definite 3×3 ``A`` (eigenvalues below
    ``1e-14·max`` dropped)."""
    w = np.empty(3)
    V = np.empty((3, 3))
    _eigh3(A, w, V)
    wmax = max(w[0], max(w[1], w[2]))
    for i in range(3):
        y[i] = 0.0
    for q in range(3):
        if w[q] > wmax * 1e-14 and w[q] > 0.0:
            c = (V[0, q] * l[0] + V[1, q] * l[1] + V[2, q] * l[2]) / w[q]
            for i in range(3):
                y[i] += c * V[i, q]


#: :func:`min_norm_step` solves by Cholesky while every pivot exceeds this fraction of
#: the largest diagonal entry of ``J S² Jᵀ`` (else the eigen pseudo-inverse is used).
CHOLESKY_PIVOT = 1e-10


@numba.njit(**_JIT)
def min_norm_step(J, l, scale):
    """``x = S (J S)^# l`` with ``S = diag(scale)``: the least ``|S^{-1} x|`` minimising ``|J x − l|``.

    ``(J S)^# = (J S)ᵀ ((J S)(J S)ᵀ)^{-1}``: the 3×3 system ``J S² Jᵀ y = l`` is solved by
    Cholesky; when a pivot falls below :data:`CHOLESKY_PIVOT` times the largest diagonal
    entry (``J`` rank-deficient or nearly so) by the pseudo-inverse from an eigen
    decomposition instead (eigenvalues below ``1e-14·max`` dropped), so a rank-deficient
    ``J`` gives the minimum-norm least-squares step rather than a blow-up.
    """
    p = J.shape[1]
    A = np.zeros((3, 3))
    for k in range(p):
        s2 = scale[k] * scale[k]
        j0 = J[0, k] * s2
        j1 = J[1, k] * s2
        j2 = J[2, k] * s2
        A[0, 0] += j0 * J[0, k]
        A[1, 0] += j1 * J[0, k]
        A[1, 1] += j1 * J[1, k]
        A[2, 0] += j2 * J[0, k]
        A[2, 1] += j2 * J[1, k]
        A[2, 2] += j2 * J[2, k]
    A[0, 1] = A[1, 0]
    A[0, 2] = A[2, 0]
    A[1, 2] = A[2, 1]
    y = np.empty(3)
    amax = max(A[0, 0], max(A[1, 1], A[2, 2]))
    floor = CHOLESKY_PIVOT * amax
    ok = amax > 0.0
    # A = C Cᵀ, C lower triangular
    c00 = c10 = c11 = c20 = c21 = c22 = 0.0
    if ok:
        d = A[0, 0]
        ok = d > floor
        if ok:
            c00 = np.sqrt(d)
            c10 = A[1, 0] / c00
            c20 = A[2, 0] / c00
            d = A[1, 1] - c10 * c10
            ok = d > floor
            if ok:
                c11 = np.sqrt(d)
                c21 = (A[2, 1] - c20 * c10) / c11
                d = A[2, 2] - c20 * c20 - c21 * c21
                ok = d > floor
                if ok:
                    c22 = np.sqrt(d)
    if ok:
        z0 = l[0] / c00
        z1 = (l[1] - c10 * z0) / c11
        z2 = (l[2] - c20 * z0 - c21 * z1) / c22
        y[2] = z2 / c22
        y[1] = (z1 - c21 * y[2]) / c11
        y[0] = (z0 - c10 * y[1] - c20 * y[2]) / c00
    else:
        _pinv_solve3(A, l, y)
    x = np.empty(p)
    for k in range(p):
        x[k] = scale[k] * scale[k] * (J[0, k] * y[0] + J[1, k] * y[1] + J[2, k] * y[2])
    return x


@numba.njit(**_JIT)
def stage_values(lam, Bidx, Bval, stride_b, stride_i, m):
    """The stage table ``U[n, c, i] = Σ_q Bval[n, c, q] λ[Bidx[n, c, q]·stride_b + i·stride_i]``."""
    N = Bidx.shape[0]
    nq = Bidx.shape[2]
    U = np.zeros((N, 3, m))
    for n in range(N):
        for c in range(3):
            for q in range(nq):
                v = Bval[n, c, q]
                base = Bidx[n, c, q] * stride_b
                for i in range(m):
                    U[n, c, i] += v * lam[base + i * stride_i]
    return U


@numba.njit(**_JIT)
def grid_stage_values(values, out):
    """Stage table of grid controls: ``out[n, c] = values[n // r]`` (``r = N / grid``)."""
    g = values.shape[0]
    m = values.shape[1]
    r = out.shape[0] // g
    for j in range(g):
        for n in range(j * r, (j + 1) * r):
            for c in range(3):
                for i in range(m):
                    out[n, c, i] = values[j, i]
    return out


# --------------------------------------------------------------------------------------
# Kernel templates. They call the mechanism's ``L_into``, ``Q_into`` and ``delta`` as
# globals; :func:`get` rebinds those per mechanism and compiles (and caches) one copy each.
# --------------------------------------------------------------------------------------


def _forward(R0, U, h, sgn, delta_stop, Rs):
    """CF4 over ``N = len(U)`` steps; ``Rs[n]`` = R at ``t_n`` (shape ``(N+1, 3, 3)``).

    Returns ``(n_done, min sgnΔ, t_stop)``: the number of completed steps (``N`` unless the
    trajectory reached ``sgnΔ < delta_stop`` or a non-finite ``ω``), the least ``sgnΔ`` over
    all evaluation points of the completed steps, and the stage time where it stopped
    (``-1`` if it did not).
    """
    N = U.shape[0]
    m = U.shape[2]
    R = np.empty((3, 3))
    Y2 = np.empty((3, 3))
    Y3 = np.empty((3, 3))
    Y4 = np.empty((3, 3))
    Rh = np.empty((3, 3))
    E = np.empty((3, 3))
    B = np.empty((3, m))
    F1 = np.empty(3)
    F2 = np.empty(3)
    F3 = np.empty(3)
    F4 = np.empty(3)
    for i in range(3):
        for j in range(3):
            R[i, j] = R0[i, j]
            Rs[0, i, j] = R0[i, j]
    dmin = sgn * delta(R)
    if not dmin >= delta_stop:
        return 0, dmin, 0.0
    h2 = 0.5 * h
    h12 = h / 12.0
    for n in range(N):
        t = n * h
        # stage 1
        L_into(R, B)
        if not _omega(B, U[n, 0], m, F1):
            return n, dmin, t
        # stage 2
        _exp_times(h2 * F1[0], h2 * F1[1], h2 * F1[2], R, E, Y2)
        d = sgn * delta(Y2)
        dmin = min(dmin, d)
        if not d >= delta_stop:
            return n, dmin, t + h2
        L_into(Y2, B)
        if not _omega(B, U[n, 1], m, F2):
            return n, dmin, t + h2
        # stage 3
        _exp_times(h2 * F2[0], h2 * F2[1], h2 * F2[2], R, E, Y3)
        d = sgn * delta(Y3)
        dmin = min(dmin, d)
        if not d >= delta_stop:
            return n, dmin, t + h2
        L_into(Y3, B)
        if not _omega(B, U[n, 1], m, F3):
            return n, dmin, t + h2
        # stage 4
        _exp_times(h * F3[0] - h2 * F1[0], h * F3[1] - h2 * F1[1], h * F3[2] - h2 * F1[2],
                   Y2, E, Y4)
        d = sgn * delta(Y4)
        dmin = min(dmin, d)
        if not d >= delta_stop:
            return n, dmin, t + h
        L_into(Y4, B)
        if not _omega(B, U[n, 2], m, F4):
            return n, dmin, t + h
        # update: two exponentials
        _exp_times(h12 * (3.0 * F1[0] + 2.0 * F2[0] + 2.0 * F3[0] - F4[0]),
                   h12 * (3.0 * F1[1] + 2.0 * F2[1] + 2.0 * F3[1] - F4[1]),
                   h12 * (3.0 * F1[2] + 2.0 * F2[2] + 2.0 * F3[2] - F4[2]), R, E, Rh)
        _exp_times(h12 * (-F1[0] + 2.0 * F2[0] + 2.0 * F3[0] + 3.0 * F4[0]),
                   h12 * (-F1[1] + 2.0 * F2[1] + 2.0 * F3[1] + 3.0 * F4[1]),
                   h12 * (-F1[2] + 2.0 * F2[2] + 2.0 * F3[2] + 3.0 * F4[2]), Rh, E, R)
        for i in range(3):
            for j in range(3):
                Rs[n + 1, i, j] = R[i, j]
        d = sgn * delta(R)
        dmin = min(dmin, d)
        if not d >= delta_stop:
            return n, dmin, t + h
    return N, dmin, -1.0


def _zstage(Zc, Y, u, F, B, Qm, f, K):
    """One stage of ``dZ/dt = -Z A``, ``A = Q(Y, u) + [F]``: ``f = -Zc A``; and ``K = Zc B``."""
    Q_into(Y, u, Qm)
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


def _forward_variational(R0, U, h, sgn, delta_stop, Bidx, Bval, stride_b, stride_i,
                         Rs, Zs, J, Mq, Wd, full):
    """CF4 for ``R`` together with ``Z = Φ(t,0)^{-1}``, the Jacobian ``J`` and ``M(T)``.

    Inputs: as :func:`_forward`, plus the stage basis ``(Bidx, Bval, stride_b, stride_i)``
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
    :func:`_forward` returns; ``J``, ``Mq``, ``Wd`` and ``Zs[N]`` are valid only if the run
    completed.
    """
    N = U.shape[0]
    m = U.shape[2]
    dense = Bidx.shape[0] == 0 and Bval.shape[0] == N
    keep_w = Wd.shape[0] == 3 * N
    nq = 0 if dense else Bidx.shape[2]
    R = np.empty((3, 3))
    Y2 = np.empty((3, 3))
    Y3 = np.empty((3, 3))
    Y4 = np.empty((3, 3))
    Rh = np.empty((3, 3))
    E = np.empty((3, 3))
    Z = np.empty((3, 3))
    Zc = np.empty((3, 3))
    Qm = np.empty((3, 3))
    f1 = np.empty((3, 3))
    f2 = np.empty((3, 3))
    f3 = np.empty((3, 3))
    f4 = np.empty((3, 3))
    B1 = np.empty((3, m))
    B2 = np.empty((3, m))
    K1 = np.empty((3, m))
    K2 = np.empty((3, m))
    K3 = np.empty((3, m))
    K4 = np.empty((3, m))
    W = np.empty((3, 3, m))
    F1 = np.empty(3)
    F2 = np.empty(3)
    F3 = np.empty(3)
    F4 = np.empty(3)
    J[:, :] = 0.0
    for i in range(3):
        for j in range(3):
            R[i, j] = R0[i, j]
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
    h12 = h / 12.0
    for n in range(N):
        t = n * h
        # stage 1 (Y1 = R, Z1 = Z)
        L_into(R, B1)
        if not _omega(B1, U[n, 0], m, F1):
            return n, dmin, t
        _zstage(Z, R, U[n, 0], F1, B1, Qm, f1, K1)
        # stage 2
        _exp_times(h2 * F1[0], h2 * F1[1], h2 * F1[2], R, E, Y2)
        d = sgn * delta(Y2)
        dmin = min(dmin, d)
        if not d >= delta_stop:
            return n, dmin, t + h2
        L_into(Y2, B2)
        if not _omega(B2, U[n, 1], m, F2):
            return n, dmin, t + h2
        for i in range(3):
            for j in range(3):
                Zc[i, j] = Z[i, j] + h2 * f1[i, j]
        _zstage(Zc, Y2, U[n, 1], F2, B2, Qm, f2, K2)
        # stage 3
        _exp_times(h2 * F2[0], h2 * F2[1], h2 * F2[2], R, E, Y3)
        d = sgn * delta(Y3)
        dmin = min(dmin, d)
        if not d >= delta_stop:
            return n, dmin, t + h2
        L_into(Y3, B2)
        if not _omega(B2, U[n, 1], m, F3):
            return n, dmin, t + h2
        for i in range(3):
            for j in range(3):
                Zc[i, j] = Z[i, j] + h2 * f2[i, j]
        _zstage(Zc, Y3, U[n, 1], F3, B2, Qm, f3, K3)
        # stage 4
        _exp_times(h * F3[0] - h2 * F1[0], h * F3[1] - h2 * F1[1], h * F3[2] - h2 * F1[2],
                   Y2, E, Y4)
        d = sgn * delta(Y4)
        dmin = min(dmin, d)
        if not d >= delta_stop:
            return n, dmin, t + h
        L_into(Y4, B2)
        if not _omega(B2, U[n, 2], m, F4):
            return n, dmin, t + h
        for i in range(3):
            for j in range(3):
                Zc[i, j] = Z[i, j] + h * f3[i, j]
        _zstage(Zc, Y4, U[n, 2], F4, B2, Qm, f4, K4)
        # update R
        _exp_times(h12 * (3.0 * F1[0] + 2.0 * F2[0] + 2.0 * F3[0] - F4[0]),
                   h12 * (3.0 * F1[1] + 2.0 * F2[1] + 2.0 * F3[1] - F4[1]),
                   h12 * (3.0 * F1[2] + 2.0 * F2[2] + 2.0 * F3[2] - F4[2]), R, E, Rh)
        _exp_times(h12 * (-F1[0] + 2.0 * F2[0] + 2.0 * F3[0] + 3.0 * F4[0]),
                   h12 * (-F1[1] + 2.0 * F2[1] + 2.0 * F3[1] + 3.0 * F4[1]),
                   h12 * (-F1[2] + 2.0 * F2[2] + 2.0 * F3[2] + 3.0 * F4[2]), Rh, E, R)
        # update Z; quadrature weights of the step at c = 0, ½, 1
        for i in range(3):
            for j in range(3):
                Z[i, j] += h6 * (f1[i, j] + 2.0 * f2[i, j] + 2.0 * f3[i, j] + f4[i, j])
                Rs[n + 1, i, j] = R[i, j]
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
        d = sgn * delta(R)
        dmin = min(dmin, d)
        if not d >= delta_stop:
            return n, dmin, t + h
    # Z(T), J = Z(T)^{-1} Σ W ∂U/∂λ, M(T) = Z(T)^{-1} Mq Z(T)^{-T}
    for i in range(3):
        for j in range(3):
            Zs[N, i, j] = Z[i, j]
    _inv33(Z, E)
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


def _frame_inputs(nodes, h, idx, s, Wst, w_end, Rout, out):
    """Physical inputs ``u = W(R(t)) w(t)`` along a motion planned in frame coordinates.

    Bound with ``L_into`` = the frame ``N`` (``ω = N(R) w``) and ``W_into`` = ``W`` (``u =
    W(R) w``). For every sample ``k``: ``R(t_k)`` is node ``idx[k]`` of the CF4
    trajectory ``nodes`` (step ``h``) advanced by one CF4 step of length ``s[k]``
    (``0 ≤ s[k] < h``; none if ``s[k] == 0``) with frame inputs ``Wst[k, 0]``,
    ``Wst[k, 1]``, ``Wst[k, 2]`` at its start, middle and end — the same local
    approximation as a step of the integrator, ``O(s⁵)`` from the exact motion. Outputs
    ``Rout[k] = R(t_k)`` and ``out[k] = W(R(t_k)) w_end[k]``.
    """
    n_t = idx.shape[0]
    m = Wst.shape[2]
    R = np.empty((3, 3))
    Y2 = np.empty((3, 3))
    Y3 = np.empty((3, 3))
    Y4 = np.empty((3, 3))
    Rh = np.empty((3, 3))
    E = np.empty((3, 3))
    B = np.empty((3, m))
    Wm = np.empty((m, m))
    F1 = np.empty(3)
    F2 = np.empty(3)
    F3 = np.empty(3)
    F4 = np.empty(3)
    for k in range(n_t):
        n = idx[k]
        sk = s[k]
        if sk == 0.0:
            for i in range(3):
                for j in range(3):
                    R[i, j] = nodes[n, i, j]
        else:
            for i in range(3):
                for j in range(3):
                    Y4[i, j] = nodes[n, i, j]
            s2 = 0.5 * sk
            s12 = sk / 12.0
            L_into(Y4, B)
            _omega(B, Wst[k, 0], m, F1)
            _exp_times(s2 * F1[0], s2 * F1[1], s2 * F1[2], Y4, E, Y2)
            L_into(Y2, B)
            _omega(B, Wst[k, 1], m, F2)
            _exp_times(s2 * F2[0], s2 * F2[1], s2 * F2[2], Y4, E, Y3)
            L_into(Y3, B)
            _omega(B, Wst[k, 1], m, F3)
            _exp_times(sk * F3[0] - s2 * F1[0], sk * F3[1] - s2 * F1[1], sk * F3[2] - s2 * F1[2],
                       Y2, E, Rh)
            L_into(Rh, B)
            _omega(B, Wst[k, 2], m, F4)
            _exp_times(s12 * (3.0 * F1[0] + 2.0 * F2[0] + 2.0 * F3[0] - F4[0]),
                       s12 * (3.0 * F1[1] + 2.0 * F2[1] + 2.0 * F3[1] - F4[1]),
                       s12 * (3.0 * F1[2] + 2.0 * F2[2] + 2.0 * F3[2] - F4[2]), Y4, E, Rh)
            _exp_times(s12 * (-F1[0] + 2.0 * F2[0] + 2.0 * F3[0] + 3.0 * F4[0]),
                       s12 * (-F1[1] + 2.0 * F2[1] + 2.0 * F3[1] + 3.0 * F4[1]),
                       s12 * (-F1[2] + 2.0 * F2[2] + 2.0 * F3[2] + 3.0 * F4[2]), Rh, E, R)
        for i in range(3):
            for j in range(3):
                Rout[k, i, j] = R[i, j]
        W_into(R, Wm)
        for i in range(m):
            v = 0.0
            for j in range(m):
                v += Wm[i, j] * w_end[k, j]
            out[k, i] = v


def _no_delta(R):
    """``Δ ≡ +inf`` for mechanisms without a singular set."""
    return np.inf


def into(func):
    """``func_into(*args, out)``: the generated ``func(*args)`` filling ``out`` instead.

    The generated ``L`` and ``Q`` allocate ``out = numpy.empty(...)``, fill it and return
    it; in the kernels' inner loop that allocation costs as much as the arithmetic. The
    function's syntax tree is rewritten (the allocation removed, ``out`` made the last
    argument); any other form falls back to copying the result.
    """
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(func)))
        fn = tree.body[0]
        body, alloc, ret = [], False, False
        for st in fn.body:
            if (isinstance(st, ast.Assign) and len(st.targets) == 1
                    and isinstance(st.targets[0], ast.Name) and st.targets[0].id == "out"
                    and isinstance(st.value, ast.Call)):
                alloc = True
                continue
            if isinstance(st, ast.Return) and isinstance(st.value, ast.Name) and st.value.id == "out":
                ret = True
                continue
            body.append(st)
        if not (isinstance(fn, ast.FunctionDef) and alloc and ret):
            raise ValueError("unexpected form")
        fn.body = body or [ast.Pass()]
        fn.args.args.append(ast.arg(arg="out"))
        fn.decorator_list = []
        ast.fix_missing_locations(tree)
        ns = dict(vars(inspect.getmodule(func)))
        exec(compile(tree, f"<{func.__module__}.{func.__name__} (into)>", "exec"), ns)
        return ns[fn.name]
    except (OSError, TypeError, SyntaxError, ValueError, IndexError):
        return _copy_into(func)


def _copy_into(func):
    """Fallback of :func:`into`: call ``func`` and copy its (2-D) result into ``out``."""
    f = numba.njit(func)
    n = len(inspect.signature(func).parameters)
    if n == 1:
        def copy_into(a, out):
            out[:, :] = f(a)
    elif n == 2:
        def copy_into(a, b, out):
            out[:, :] = f(a, b)
    else:
        raise ValueError(f"cannot adapt {func.__name__} with {n} arguments")
    return copy_into


@dataclass(frozen=True)
class Kernels:
    """Compiled kernels of one mechanism (see the module docstring for the arguments)."""

    name: str
    n_inputs: int
    has_singular_set: bool
    forward: object
    forward_variational: object
    frame: bool = False
    frame_inputs: object = None


def _bind(template, tag: str, glb: dict, cache: bool = True):
    f = types.FunctionType(template.__code__, glb, template.__name__)
    # A distinct qualified name per mechanism (and per version of its generated module)
    # gives each compiled copy its own on-disk cache entry.
    f.__qualname__ = f"{template.__name__}__{tag}"
    f.__module__ = __name__
    f.__doc__ = template.__doc__
    return numba.njit(**{**_JIT, "cache": cache})(f)


def _importable(module) -> bool:
    """Whether ``module`` can be re-imported by name (a cached kernel refers to it by name)."""
    return sys.modules.get(getattr(module, "__name__", None)) is module


def has_frame(name: str) -> bool:
    """Whether mechanism ``name``'s generated module provides the frame ``N``, ``QN``, ``W``."""
    return bool(getattr(mechanisms.get(name).module, "HAS_FRAME", False))


@cache
def get(name: str = "platform", frame: bool = False) -> Kernels:
    """The compiled kernels of mechanism ``name`` (compiled once, cached on disk).

    ``frame=False``: bound to ``L``, ``Q`` — the system ``dR/dt = [L(R) u] R`` in the
    physical inputs ``u``. ``frame=True``: bound to the desingularised frame ``N``,
    ``QN`` of the generated module (``dR/dt = [N(R) w] R``, ``ω = N(R) w``), with
    :func:`_frame_inputs` (bound to ``W``) for the physical inputs ``u = W(R) w``;
    ``ValueError`` if the mechanism has no frame (``HAS_FRAME`` false). Both monitor the
    mechanism's ``Δ``.
    """
    mech = mechanisms.get(name)
    if frame and not has_frame(mech.name):
        raise ValueError(f"mechanism {mech.name!r} has no desingularised frame N(R) (HAS_FRAME)")
    src = inspect.getsource(mech.module)
    tag = f"{mech.name}{'_frame' if frame else ''}_{hashlib.sha256(src.encode()).hexdigest()[:12]}"
    # a module registered at run time from a file (mechanisms.register) is not importable
    # by name: a kernel loaded from the disk cache in another process could not resolve it
    cache = _importable(mech.module)
    plain = dict(nogil=True, error_model="numpy")
    glb = dict(globals())
    L, Q = (mech.module.N, mech.module.QN) if frame else (mech.L, mech.Q)
    glb["L_into"] = numba.njit(**plain)(into(L))
    # Q feeds only the variational system (the Jacobian): fast-math lets LLVM turn its
    # ``x**(-2.0)`` into a multiplication (the result changes at round-off level).
    glb["Q_into"] = numba.njit(fastmath=True, **plain)(into(Q))
    glb["delta"] = numba.njit(**plain)(mech.delta) if mech.has_singular_set else _no_delta_jit
    glb["_zstage"] = _bind(_zstage, tag, glb, cache)
    extra = {}
    if frame:
        glb["W_into"] = numba.njit(**plain)(into(mech.module.W))
        extra["frame_inputs"] = _bind(_frame_inputs, tag, glb, cache)
    return Kernels(
        name=mech.name,
        n_inputs=mech.n_inputs,
        has_singular_set=mech.has_singular_set,
        forward=_bind(_forward, tag, glb, cache),
        forward_variational=_bind(_forward_variational, tag, glb, cache),
        frame=frame,
        **extra,
    )


_no_delta_jit = numba.njit(**_JIT)(_no_delta)
