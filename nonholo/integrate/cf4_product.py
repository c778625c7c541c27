"""The CF4 integrator and the variational system on ``SO(3) × Rᵏ`` and ``Rᵏ``.

Conventions
-----------
- A *system* is ``dR/dt = [ω] R``, ``dq/dt = ẋ`` with the stacked rates ``(ω, ẋ) = G(R, q) v``
  (``d = 3 + k`` rows; ``d = k`` and no ``R`` for a mechanism without orientation, whose
  kernels carry ``R = I`` untouched). ``G`` is the generated ``G_into`` of the mechanism
  (physical inputs ``u``) or ``N_into`` (its desingularised field, frame coordinates ``w``).
- Steps, stage table ``U`` ``(N, 3, m)`` and stage basis exactly as in :mod:`nonholo.integrate.cf4`.

One step (:func:`product_step`) is CF4 on the product group ``SO(3) × (Rᵏ, +)``: the
orientation moves by the exponentials of :mod:`nonholo.integrate.cf4` and ``q`` by the same
combinations of the stage rates, which on the additive factor is the classical RK4
tableau evaluated at CF4's stage points; the coupled scheme is of order 4::

    F1 = G(R, q) v0
    Y2 = exp(h/2 ω1) R,          P2 = q + h/2 f1,        F2 = G(Y2, P2) v½
    Y3 = exp(h/2 ω2) R,          P3 = q + h/2 f2,        F3 = G(Y3, P3) v½
    Y4 = exp(h ω3 − h/2 ω1) Y2,  P4 = q + h f3,          F4 = G(Y4, P4) v1
    R' = exp(h/12 (−ω1 + 2ω2 + 2ω3 + 3ω4)) exp(h/12 (3ω1 + 2ω2 + 2ω3 − ω4)) R
    q' = q + h/6 (f1 + 2 f2 + 2 f3 + f4)

(``F_i = (ω_i, f_i)``). The variational system ``ds/dt = A s + B ∂v/∂θ`` on the stacked
variation ``s = (s_R, s_q)`` (``∂R = [s_R] R``, ``∂q = s_q``) has ``A = QG(R, q, v) + [ω] ⊕ 0``
and ``B = G``; it is integrated through ``Z = Φ(t, 0)^{-1}`` as in :mod:`nonholo.integrate.cf4`, with
``d × d`` matrices, and gives ``J = ∂s_T/∂λ`` (``d × p``) and ``M(T)`` (``d × d``).

The singularity function ``Δ(R, q)`` is watched at every stage point and node, as on
SO(3). The kernels are compiled per system with the mechanism's generated functions
bound to ``field_into``, ``field_derivative_into``, ``delta`` and ``W_into``
(:func:`nonholo.integrate.cf4.specialise`), and ``ROTATION``/``D``/``OFFSET`` bound to the state's
layout, so that the branches of a state without orientation compile away.
"""
from __future__ import annotations

import numpy as np

from ..numerics import effort
from ..numerics.jit import jit
from ..numerics.kernels import exp_times
from . import cf4

# bound per system by compile_system (see the module docstring)
field_into = cf4.field_into
field_derivative_into = cf4.field_derivative_into
delta = cf4.delta
W_into = cf4.W_into
#: whether the state has an orientation; its dimension ``d``; the index of ``q``'s first
#: rate in ``G``'s rows (3 with orientation, else 0)
ROTATION = True
D = 3
OFFSET = 3


def no_singularity(R, q):
    """``Δ ≡ +inf``: the singularity function of a mechanism without a singular set."""
    return np.inf


@jit
def rates(B, v, out):
    """``out = B v`` (d×m times m); ``False`` if not finite."""
    ok = True
    for i in range(B.shape[0]):
        s = 0.0
        for k in range(B.shape[1]):
            s += B[i, k] * v[k]
        out[i] = s
        ok = ok and np.isfinite(s)
    return ok


@jit
def advance(q, h, f, out):
    """``out = q + h f[OFFSET:]`` for the coordinates (``f`` a stage's stacked rates)."""
    off = f.shape[0] - q.shape[0]
    for i in range(q.shape[0]):
        out[i] = q[i] + h * f[off + i]


def product_stage(aR, base, Y, P, v, sgn, delta_stop, dmin, B, Fout, E):
    """One stage of :func:`product_step`: the orientation ``Y = exp([aR]) base`` (the
    coordinates ``P`` are filled by the caller), its ``sgnΔ`` (lowering ``dmin``), the field
    ``B = G(Y, P)`` and the rates ``Fout = B v``. Returns ``(ok, dmin)``."""
    ok = False
    if ROTATION:
        exp_times(aR[0], aR[1], aR[2], base, E, Y)
    d = sgn * delta(Y, P)
    dmin = min(dmin, d)
    if d >= delta_stop:
        field_into(Y, P, B)
        ok = rates(B, v, Fout)
    return ok, dmin


def product_step(R, q, Rn, qn, v0, v1, v2, h, sgn, delta_stop, dmin, Y2, Y3, Y4, P2, P3, P4,
                 Rh, E, a, B1, B2, B3, B4, F1, F2, F3, F4):
    """One CF4 step of length ``h`` from ``(R, q)`` into ``(Rn, qn)`` (module docstring).

    Fills the stage points ``(Y_i, P_i)``, the fields ``B_i = G(Y_i, P_i)`` and the stacked
    rates ``F_i = B_i v`` (``Rh``, ``E``, ``a``: scratch). Returns ``(stop, dmin)`` as
    :func:`nonholo.integrate.cf4.cf4_step` does (``stop = -1`` if the step completed)."""
    stop = -1.0
    for _ in range(1):
        h2 = 0.5 * h
        h12 = h / 12.0
        field_into(R, q, B1)
        if not rates(B1, v0, F1):
            stop = 0.0
            break
        if ROTATION:
            for i in range(3):
                a[i] = h2 * F1[i]
        advance(q, h2, F1, P2)
        ok, dmin = product_stage(a, R, Y2, P2, v1, sgn, delta_stop, dmin, B2, F2, E)
        if not ok:
            stop = 0.5
            break
        if ROTATION:
            for i in range(3):
                a[i] = h2 * F2[i]
        advance(q, h2, F2, P3)
        ok, dmin = product_stage(a, R, Y3, P3, v1, sgn, delta_stop, dmin, B3, F3, E)
        if not ok:
            stop = 0.5
            break
        if ROTATION:
            for i in range(3):
                a[i] = h * F3[i] - h2 * F1[i]
        advance(q, h, F3, P4)
        ok, dmin = product_stage(a, Y2, Y4, P4, v2, sgn, delta_stop, dmin, B4, F4, E)
        if not ok:
            stop = 1.0
            break
        if ROTATION:
            cf4.cf4_close(F1, F2, F3, F4, h12, R, E, Rh, Rn)
        h6 = h / 6.0
        for i in range(q.shape[0]):
            j = OFFSET + i
            qn[i] = q[i] + h6 * (F1[j] + 2.0 * F2[j] + 2.0 * F3[j] + F4[j])
        d = sgn * delta(Rn, qn)
        dmin = min(dmin, d)
        if not d >= delta_stop:
            stop = 1.0
    return stop, dmin


@jit
def product_workspace(k, d, m):
    """The arrays :func:`product_step` fills: ``(Rn, qn, Y2, Y3, Y4, P2, P3, P4, Rh, E, a,
    B1, B2, B3, B4, F1, F2, F3, F4)`` for ``k`` coordinates, ``d`` rates and ``m`` inputs;
    the orientation arrays start as the identity (they stay so without orientation)."""
    eye = np.eye(3)
    return (eye.copy(), np.empty(k), eye.copy(), eye.copy(), eye.copy(), np.empty(k),
            np.empty(k), np.empty(k), eye.copy(), np.empty((3, 3)), np.zeros(3),
            np.empty((d, m)), np.empty((d, m)), np.empty((d, m)), np.empty((d, m)),
            np.empty(d), np.empty(d), np.empty(d), np.empty(d))


def forward(R0, q0, U, h, sgn, delta_stop, Rs, Qs):
    """CF4 over ``N = len(U)`` steps; ``Rs[n]``, ``Qs[n]`` = the state at ``t_n``. Returns what
    :func:`nonholo.integrate.cf4.forward` returns."""
    N = U.shape[0]
    m = U.shape[2]
    k = q0.shape[0]
    R = R0.copy()
    q = q0.copy()
    (Rn, qn, Y2, Y3, Y4, P2, P3, P4, Rh, E, a, B1, B2, B3, B4,
     F1, F2, F3, F4) = product_workspace(k, D, m)
    Rs[0] = R0
    Qs[0] = q0
    dmin = sgn * delta(R, q)
    if not dmin >= delta_stop:
        return 0, dmin, 0.0
    for n in range(N):
        stop, dmin = product_step(R, q, Rn, qn, U[n, 0], U[n, 1], U[n, 2], h, sgn, delta_stop,
                                  dmin, Y2, Y3, Y4, P2, P3, P4, Rh, E, a, B1, B2, B3, B4,
                                  F1, F2, F3, F4)
        if stop >= 0.0:
            return n, dmin, n * h + stop * h
        R[:, :] = Rn
        q[:] = qn
        Rs[n + 1] = Rn
        Qs[n + 1] = qn
    return N, dmin, -1.0


def zstage(Zc, Y, P, v, F, B, Qm, f, K):
    """One stage of ``dZ/dt = -Z A``, ``A = QG(Y, P, v) + [ω] ⊕ 0``: ``f = -Zc A``, ``K = Zc B``."""
    field_derivative_into(Y, P, v, Qm)
    if ROTATION:
        Qm[0, 1] -= F[2]
        Qm[0, 2] += F[1]
        Qm[1, 0] += F[2]
        Qm[1, 2] -= F[0]
        Qm[2, 0] -= F[1]
        Qm[2, 1] += F[0]
    f[:, :] = -np.dot(Zc, Qm)
    K[:, :] = np.dot(Zc, B)


def forward_variational(R0, q0, U, h, sgn, delta_stop, Bidx, Bval, stride_b, stride_i,
                        Rs, Qs, Zs, J, Mq, Wd, full):
    """:func:`forward` with ``Z = Φ(t,0)^{-1}``, the Jacobian ``J`` (``d × p``) and ``M(T)``
    (``d × d``): the arguments and outputs of :func:`nonholo.integrate.cf4.forward_variational` with
    ``d``-row matrices (``Zs`` ``(N+1, d, d)``, ``Wd`` ``(3N, d·m)``) and the coordinates'
    initial value ``q0`` and trajectory ``Qs`` ``(N+1, k)``."""
    N = U.shape[0]
    m = U.shape[2]
    k = q0.shape[0]
    dense = Bidx.shape[0] == 0 and Bval.shape[0] == N
    keep_w = Wd.shape[0] == 3 * N
    nq = 0 if dense else Bidx.shape[2]
    R = R0.copy()
    q = q0.copy()
    (Rn, qn, Y2, Y3, Y4, P2, P3, P4, Rh, E, a, B1, B2, B3, B4,
     F1, F2, F3, F4) = product_workspace(k, D, m)
    Z = np.eye(D)
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
    Mq[:, :] = 0.0
    Rs[0] = R0
    Qs[0] = q0
    Zs[0] = Z
    dmin = sgn * delta(R, q)
    if not dmin >= delta_stop:
        return 0, dmin, 0.0
    h2 = 0.5 * h
    h6 = h / 6.0
    h3 = h / 3.0
    for n in range(N):
        stop, dmin = product_step(R, q, Rn, qn, U[n, 0], U[n, 1], U[n, 2], h, sgn, delta_stop,
                                  dmin, Y2, Y3, Y4, P2, P3, P4, Rh, E, a, B1, B2, B3, B4,
                                  F1, F2, F3, F4)
        if stop >= 0.0:
            return n, dmin, n * h + stop * h
        zstage(Z, R, q, U[n, 0], F1, B1, Qm, f1, K1)
        Zc[:, :] = Z + h2 * f1
        zstage(Zc, Y2, P2, U[n, 1], F2, B2, Qm, f2, K2)
        Zc[:, :] = Z + h2 * f2
        zstage(Zc, Y3, P3, U[n, 1], F3, B3, Qm, f3, K3)
        Zc[:, :] = Z + h * f3
        zstage(Zc, Y4, P4, U[n, 2], F4, B4, Qm, f4, K4)
        R[:, :] = Rn
        q[:] = qn
        Rs[n + 1] = Rn
        Qs[n + 1] = qn
        Z += h6 * (f1 + 2.0 * f2 + 2.0 * f3 + f4)
        W[0] = h6 * K1
        W[1] = h3 * (K2 + K3)
        W[2] = h6 * K4
        if keep_w:
            for c in range(3):
                for i in range(D):
                    for j in range(m):
                        Wd[3 * n + c, i * m + j] = W[c, i, j]
        for c in range(3):
            for j in range(m):
                off = j * stride_i
                for s in range(nq):
                    v = Bval[n, c, s]
                    col = Bidx[n, c, s] * stride_b + off
                    for i in range(D):
                        J[i, col] += v * W[c, i, j]
        if full:
            Zs[n + 1] = Z
            Mq += h6 * (np.dot(K1, K1.T) + 2.0 * np.dot(K2, K2.T) + 2.0 * np.dot(K3, K3.T)
                        + np.dot(K4, K4.T))
    Zs[N] = Z
    finite = np.all(np.isfinite(Z))
    Zi = np.empty((D, D))                  # one C-contiguous array for both branches
    if not finite or np.linalg.det(Z) == 0.0:
        Zi[:, :] = np.nan                  # Φ(T, 0) does not exist (the motion blew up)
    else:
        Zi[:, :] = np.linalg.inv(Z)
    if dense:
        nb = Bval.shape[2]
        A = np.dot(Wd.T, Bval.reshape((3 * N, nb)))        # (d·m, nb)
        for j in range(m):
            for s in range(nb):
                col = s * stride_b + j * stride_i
                for i in range(D):
                    J[i, col] = A[i * m + j, s]
    J[:, :] = np.dot(Zi, J)
    if full:
        X = np.dot(np.dot(Zi, Mq), Zi.T)
        Mq[:, :] = 0.5 * (X + X.T)
    return N, dmin, -1.0


def frame_inputs(nodes, qnodes, idx, s, Wst, w_end, Rout, Qout, out):
    """Physical inputs ``u = W(R, q) w`` along a motion planned in frame coordinates, as
    :func:`nonholo.integrate.cf4.frame_inputs` (``qnodes``, ``Qout``: the coordinates)."""
    n_t = idx.shape[0]
    m = Wst.shape[2]
    k = qnodes.shape[1]
    R = np.empty((3, 3))
    q = np.empty(k)
    (Rn, qn, Y2, Y3, Y4, P2, P3, P4, Rh, E, a, B1, B2, B3, B4,
     F1, F2, F3, F4) = product_workspace(k, D, m)
    Wm = np.empty((m, m))
    for t in range(n_t):
        R[:, :] = nodes[idx[t]]
        q[:] = qnodes[idx[t]]
        Rn[:, :] = R
        qn[:] = q
        if s[t] != 0.0:
            stop, dmin = product_step(R, q, Rn, qn, Wst[t, 0], Wst[t, 1], Wst[t, 2], s[t], 1.0,
                                      -np.inf, np.inf, Y2, Y3, Y4, P2, P3, P4, Rh, E, a,
                                      B1, B2, B3, B4, F1, F2, F3, F4)
        Rout[t] = Rn
        Qout[t] = qn
        W_into(Rn, qn, Wm)
        for i in range(m):
            v = 0.0
            for j in range(m):
                v += Wm[i, j] * w_end[t, j]
            out[t, i] = v


#: The kernels' functions, compiled per system in this order (later ones call earlier ones).
TEMPLATES = (product_stage, product_step, zstage, forward, forward_variational, frame_inputs)


def compile_system(module, frame: bool = False) -> cf4.Kernels:
    """The kernels of a system of the generated ``module`` of a mechanism on ``SO(3) × Rᵏ``
    or ``Rᵏ`` (``frame``: its desingularised field ``N``), compiled once per process and
    cached on disk as :func:`nonholo.integrate.cf4.compile_system` does. The kernels take ``(R0, q0,
    ...)`` where the SO(3) ones take ``R0`` (see :func:`forward`)."""
    key = (module, frame)
    if key in _COMPILED:
        return _COMPILED[key]
    if frame and not getattr(module, "HAS_FRAME", False):
        raise ValueError(f"mechanism {module.NAME!r} has no desingularised frame N(R, q)")
    G, QG = (module.N_into, module.QN_into) if frame else (module.G_into, module.QG_into)
    d = (3 if module.ORIENTATION else 0) + len(module.COORDINATES)
    bindings = {
        "field_into": jit(G, cache=False),
        "field_derivative_into": jit(QG, cache=False),
        "delta": jit(module.delta if module.HAS_SINGULAR_SET else no_singularity, cache=False),
        "ROTATION": bool(module.ORIENTATION), "D": d, "OFFSET": 3 if module.ORIENTATION else 0,
    }
    if frame:
        bindings["W_into"] = jit(module.W_into, cache=False)
    tag = cf4.system_tag(module, frame)
    cache = cf4.importable(module)
    for template in TEMPLATES:
        if template.__name__ == "frame_inputs" and not frame:
            continue
        bindings[template.__name__] = cf4.specialise(template, globals(), bindings, tag, cache)
    frame_kernel = bindings.get("frame_inputs")
    kern = cf4.Kernels(name=module.NAME, frame=frame, n_inputs=module.N_INPUTS,
                       has_singular_set=module.HAS_SINGULAR_SET,
                       forward=cf4.metered(bindings["forward"], effort.FORWARD_WEIGHT, 2),
                       forward_variational=cf4.metered(bindings["forward_variational"], 1.0, 2),
                       frame_inputs=None if frame_kernel is None else cf4.metered(
                           frame_kernel, effort.FORWARD_WEIGHT, 2))
    _COMPILED[key] = kern
    return kern


_COMPILED: dict[tuple, cf4.Kernels] = {}
