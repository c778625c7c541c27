"""The CF4 Lie-group integrator and the variational system (9), compiled per system.

Conventions
-----------
- A *system* is ``dR/dt = [ω] R``, ``dq/dt = ẋ`` with the stacked rates ``(ω, ẋ) = G(R, q) v``
  (spatial form; ``d = 3 + k`` rows, ``d = 3`` and ``q`` of shape ``(0,)`` on SO(3), ``d = k``
  and ``R = I`` carried untouched for a state without orientation). ``G`` is the
  mechanism's generated ``G_into`` (``G = L`` on SO(3)) and ``v`` its physical inputs
  ``u``, or ``G = N`` (its desingularised field) and ``v = w`` the frame coordinates. It
  is integrated while the mechanism's ``Δ(R, q)`` is watched (``Δ ≡ +inf`` without a
  singular set).
- Fixed step ``h = T/N``. The inputs enter through a *stage table* ``U`` of shape
  ``(N, 3, m)``: ``U[n, 0]``, ``U[n, 1]``, ``U[n, 2]`` are the inputs at ``t_n``,
  ``t_n + h/2`` and ``t_n + h`` of step ``n`` (``t_n = n h``); see :mod:`nonholo.controls.stages`.

One step (:func:`cf4_step`) is the 4th-order commutator-free method CF4 of Celledoni,
Marthinsen and Owren (2003) on the product group ``SO(3) × (Rᵏ, +)``, with the Rodrigues
exponential; every update multiplies ``R`` by a rotation, so ``R`` stays on SO(3) up to
round-off, and on the additive factor the scheme is the classical RK4 tableau evaluated
at CF4's stage points (``F_i = (ω_i, f_i)``)::

    F1 = G(R, q) v0
    Y2 = exp(h/2 ω1) R,          P2 = q + h/2 f1,        F2 = G(Y2, P2) v½
    Y3 = exp(h/2 ω2) R,          P3 = q + h/2 f2,        F3 = G(Y3, P3) v½
    Y4 = exp(h ω3 − h/2 ω1) Y2,  P4 = q + h f3,          F4 = G(Y4, P4) v1
    R½ = exp(h/12 (3ω1 + 2ω2 + 2ω3 − ω4)) R
    R' = exp(h/12 (−ω1 + 2ω2 + 2ω3 + 3ω4)) R½,  q' = q + h/6 (f1 + 2 f2 + 2 f3 + f4)

It is the only place the scheme is written; every kernel below takes its steps with it:
:func:`forward` (the motion), :func:`forward_variational` (the motion with the
variational system) and :func:`frame_inputs` (the physical inputs along a motion planned
in frame coordinates, one partial step from the nearest node). Every kernel takes the
state as ``(R0, q0)`` and writes the nodes ``Rs`` ``(N+1, 3, 3)`` and ``Qs`` ``(N+1, k)``.

The variational system on the stacked variation ``s = (s_R, s_q)`` (``∂R = [s_R] R``,
``∂q = s_q``), ``ds/dt = A s + B ∂v/∂θ`` with ``A = QG(R, q, v) + [ω] ⊕ 0`` (``QG = Q`` of
eq. (12) on SO(3)) and ``B = G``, is handled through ``Z(t) = Φ(t, 0)^{-1}`` (d×d),
``dZ/dt = -Z A``, ``Z(0) = I``. Then ``Φ(T, t) = Z(T)^{-1} Z(t)`` and

    s_T = Z(T)^{-1} ∫ Z(t) B(t) ∂v/∂θ(t) dt,
    M(T) = ∫ Φ(T,t) B Bᵀ Φ(T,t)ᵀ dt = Z(T)^{-1} [∫ Z B Bᵀ Zᵀ dt] Z(T)^{-T}.

``Z`` and the two integrals are advanced as further additive factors (RK4 at CF4's own
stage points), so the coupled scheme is of order 4. The quadrature weights of a step are
``W_0 = h/6 Z_1 B_1``, ``W_½ = h/3 (Z_2 B_2 + Z_3 B_3)``, ``W_1 = h/6 Z_4 B_4`` (d×m) at the
stage times ``c = 0, ½, 1``.

Parametrised inputs are linear in their parameters ``λ``: the kernel takes the *stage
basis* ``(Bidx, Bval, stride_b, stride_i)`` with ``U[n, c, i] = Σ_q Bval[n, c, q]
λ[Bidx[n, c, q]·stride_b + i·stride_i]`` and accumulates ``J = Z(T)^{-1} Σ_{n,c} W_c
∂U[n, c]/∂λ`` in place — one pass per planner iteration (``J = ∂s_T/∂λ`` of (10)). For
Fourier bases it can instead keep the stage weights of every step (``Wd``) and contract
them with the *dense* basis by one matrix product after the loop (BLAS): the same ``J``
at a third of the accumulation cost; the stored weights also give the sensitivity of
intermediate states (the barrier of :mod:`nonholo.planning.strategy_robust`).

Singular set: ``sgn Δ`` (``sgn = sign Δ(R0, q0)``) is checked at every stage point and
node; the kernels stop as soon as it falls below ``delta_stop`` (or a rate is not
finite) and report how many steps were completed, so a trajectory running into ``Δ = 0``
never produces NaN.

Compilation. The kernels call the system through four names — ``field_into``,
``field_derivative_into``, ``delta`` and (frame systems) ``W_into`` — and read the state's
layout from three constants — ``ROTATION`` (whether there is an orientation), ``D``
(``d``) and ``OFFSET`` (the row of ``q̇``'s first rate in ``G``: 3 with orientation, else
0) — all defined below as placeholders. :func:`compile_system` makes, per system, a copy
of each kernel whose globals bind those names to the mechanism's generated functions
(``G_into``/``QG_into`` or ``N_into``/``QN_into``, ``delta``, ``W_into``, compiled with
``numba.njit``) and its layout, so that the functions are inlined and the branches of a
state without orientation (or without coordinates) compile away; each copy has its own
qualified name (mechanism, system, a hash of the generated source), hence its own
on-disk cache entry. (A closure over the compiled functions would read the same, but
numba cannot cache it: the cache key pickles the closure's cells, and a compiled
function pickles differently in every process.)

The step is inlined too, by code generation: called, it keeps its arrays out of
registers and slows every kernel markedly, and numba's own inlining multiplies the
compilation time. ``nonholo derive`` writes :mod:`nonholo.generated.cf4_kernels`, the
kernels of this module with every call of the functions listed in
:data:`nonholo.integrate.inliner.INLINED` expanded in place
(:mod:`nonholo.integrate.inliner`); that is what gets compiled.
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
from ..numerics import effort, native
from ..numerics.jit import jit
from ..numerics.kernels import exp_times, inv33, inverse_into
from .native_kernels import kernel_source, native_kernels

# --------------------------------------------------------------------------------------
# The system a kernel integrates (bound per system by compile_system)
# --------------------------------------------------------------------------------------


def _placeholder(*args):
    """A name the kernels call, bound per system by :func:`compile_system` (see the module).

    Parameters
    ----------
    *args : object
        The arguments of the function bound in its place.

    Raises
    ------
    NotImplementedError
        Always: the name is not bound.
    """
    raise NotImplementedError("placeholder: bound per system by nonholo.integrate.cf4.compile_system")


#: ``field_into(R, q, out)``: ``out = G(R, q)`` (d×m), the mechanism's generated ``G_into``
#: or, for the frame system, ``N_into``.
#:
#: Parameters
#: ----------
#: *args : object
#:     ``(R, q, out)``: the state and the output, d×m.
#:
#: Raises
#: ------
#: NotImplementedError
#:     Until :func:`compile_system` binds the name (see the module).
field_into = _placeholder
#: ``field_derivative_into(R, q, v, out)``: ``out = QG(R, q, v)`` (d×d) with
#: ``d/dε G(exp(ε[s_R]) R, q + ε s_q) v = QG s``: the generated ``QG_into`` (eq. (12) on
#: SO(3)) or ``QN_into``.
#:
#: Parameters
#: ----------
#: *args : object
#:     ``(R, q, v, out)``: the state, the inputs and the output, d×d.
#:
#: Raises
#: ------
#: NotImplementedError
#:     Until :func:`compile_system` binds the name (see the module).
field_derivative_into = _placeholder
#: ``delta(R, q)``: the mechanism's singularity function (``+inf`` without one).
#:
#: Parameters
#: ----------
#: *args : object
#:     ``(R, q)``: the state; it returns ``Δ(R, q)``.
#:
#: Raises
#: ------
#: NotImplementedError
#:     Until :func:`compile_system` binds the name (see the module).
delta = _placeholder
#: ``W_into(R, q, out)``: ``out = W(R, q)`` (m×m), physical inputs ``u = W w`` of frame
#: coordinates ``w`` (frame system only).
#:
#: Parameters
#: ----------
#: *args : object
#:     ``(R, q, out)``: the state and the output, m×m.
#:
#: Raises
#: ------
#: NotImplementedError
#:     Until :func:`compile_system` binds the name (see the module).
W_into = _placeholder
#: Whether the state has an orientation ``R``; the dimension ``d`` of a variation; the row
#: of the first coordinate rate in ``G`` (3 with orientation, else 0).
ROTATION = True
D = 3
OFFSET = 3


def no_singularity(R, q):
    """``Δ ≡ +inf``: the singularity function of a mechanism without a singular set.

    Parameters
    ----------
    R : numpy.ndarray
        The orientation.
    q : numpy.ndarray
        The coordinates.

    Returns
    -------
    float
        ``inf``.
    """
    return np.inf


def rates(B, v, out):
    """``out = B v`` (d×m times m).

    Parameters
    ----------
    B : numpy.ndarray
        The field, d×m.
    v : numpy.ndarray
        The inputs, m entries.
    out : numpy.ndarray
        The output, d entries.

    Returns
    -------
    bool
        ``False`` if a rate is not finite.
    """
    m = B.shape[1]
    ok = True
    for i in range(D):
        s = 0.0
        for k in range(m):
            s += B[i, k] * v[k]
        out[i] = s
        ok = ok and np.isfinite(s)
    return ok


def advance(q, a, f, out):
    """``out = q + a ḟ`` for the coordinates, ``ḟ = f[OFFSET:]`` the coordinate rates of a stage.

    Parameters
    ----------
    q : numpy.ndarray
        The coordinates, k entries.
    a : float
        The step.
    f : numpy.ndarray
        The stage's stacked rates, d entries.
    out : numpy.ndarray
        The output, k entries.
    """
    for i in range(q.shape[0]):
        out[i] = q[i] + a * f[OFFSET + i]


def cf4_stage(ax, ay, az, base, Y, P, v, sgn, delta_stop, dmin, B, F, E):
    """One stage of :func:`cf4_step`.

    The stage orientation ``Y = exp([a]) base`` (with ``ROTATION``; the coordinates ``P``
    are filled by the caller), its ``sgnΔ`` (lowering ``dmin``), the field ``B = G(Y, P)``
    and the rates ``F = B v``.

    Parameters
    ----------
    ax, ay, az : float
        The rotation vector ``a``.
    base : numpy.ndarray
        The orientation the stage starts from.
    Y : numpy.ndarray
        The stage orientation (output).
    P : numpy.ndarray
        The stage coordinates.
    v : numpy.ndarray
        The inputs.
    sgn : float
        The sign of ``Δ`` at the start.
    delta_stop : float
        The least ``sgnΔ`` accepted.
    dmin : float
        The least ``sgnΔ`` so far.
    B : numpy.ndarray
        The field (output), d×m.
    F : numpy.ndarray
        The rates (output), d entries.
    E : numpy.ndarray
        Scratch, 3×3.

    Returns
    -------
    ok : bool
        False where ``sgnΔ < delta_stop`` (or is NaN) or a rate is not finite.
    dmin : float
        ``dmin`` lowered to the stage's ``sgnΔ``.
    """
    ok = False
    if ROTATION:
        exp_times(ax, ay, az, base, E, Y)
    d = sgn * delta(Y, P)
    dmin = min(dmin, d)
    if d >= delta_stop:
        field_into(Y, P, B)
        ok = rates(B, v, F)
    return ok, dmin


@jit
def cf4_close(F1, F2, F3, F4, h12, R, E, Rh, Rn):
    """CF4's two closing exponentials, from the stage rates ``F1 … F4``.

    ``Rn = exp(h/12 (−ω1 + 2ω2 + 2ω3 + 3ω4)) exp(h/12 (3ω1 + 2ω2 + 2ω3 − ω4)) R``.

    Parameters
    ----------
    F1, F2, F3, F4 : numpy.ndarray
        The stage rates (``ω_i``: the first three entries of each).
    h12 : float
        ``h/12``.
    R : numpy.ndarray
        The orientation at the start of the step.
    E, Rh : numpy.ndarray
        Scratch, 3×3.
    Rn : numpy.ndarray
        The output, 3×3.
    """
    exp_times(h12 * (3.0 * F1[0] + 2.0 * F2[0] + 2.0 * F3[0] - F4[0]),
              h12 * (3.0 * F1[1] + 2.0 * F2[1] + 2.0 * F3[1] - F4[1]),
              h12 * (3.0 * F1[2] + 2.0 * F2[2] + 2.0 * F3[2] - F4[2]), R, E, Rh)
    exp_times(h12 * (-F1[0] + 2.0 * F2[0] + 2.0 * F3[0] + 3.0 * F4[0]),
              h12 * (-F1[1] + 2.0 * F2[1] + 2.0 * F3[1] + 3.0 * F4[1]),
              h12 * (-F1[2] + 2.0 * F2[2] + 2.0 * F3[2] + 3.0 * F4[2]), Rh, E, Rn)


def cf4_step(R, q, Rn, qn, v0, v1, v2, h, sgn, delta_stop, dmin, Y2, Y3, Y4, P2, P3, P4, Rh, E,
             B1, B2, B3, B4, F1, F2, F3, F4):
    """One CF4 step of length ``h`` from ``(R, q)`` into ``(Rn, qn)`` (see the module docstring).

    Fills the stage points ``(Y_i, P_i)``, the fields ``B_i = G(Y_i, P_i)`` (``(Y1, P1) =
    (R, q)``) and the stacked rates ``F_i = B_i v``. (The workspace is passed array by
    array: views into one larger array would cost a reference count pair each, per step.
    Written with ``break`` rather than early returns so that it can be inlined, see
    :mod:`nonholo.integrate.inliner`.)

    Parameters
    ----------
    R, q : numpy.ndarray
        The state at the start of the step.
    Rn, qn : numpy.ndarray
        The state at its end (output).
    v0, v1, v2 : numpy.ndarray
        The inputs at the start, middle and end of the step.
    h : float
        The step's length.
    sgn : float
        The sign of ``Δ`` at the start of the motion.
    delta_stop : float
        The least ``sgnΔ`` accepted.
    dmin : float
        The least ``sgnΔ`` so far.
    Y2, Y3, Y4 : numpy.ndarray
        The stage orientations (output).
    P2, P3, P4 : numpy.ndarray
        The stage coordinates (output).
    Rh, E : numpy.ndarray
        Scratch, 3×3.
    B1, B2, B3, B4 : numpy.ndarray
        The stage fields (output), d×m.
    F1, F2, F3, F4 : numpy.ndarray
        The stage rates (output), d entries.

    Returns
    -------
    stop : float
        ``-1`` if the step completed, else the fraction of the step (0, ½ or 1) where
        ``sgnΔ < delta_stop`` or a rate was not finite.
    dmin : float
        ``dmin`` lowered to every ``sgnΔ`` evaluated (at the stage points 2–4 and the new
        node).
    """
    stop = -1.0
    for _ in range(1):
        h2 = 0.5 * h
        h12 = h / 12.0
        field_into(R, q, B1)
        if not rates(B1, v0, F1):
            stop = 0.0
            break
        if ROTATION:
            ax = h2 * F1[0]
            ay = h2 * F1[1]
            az = h2 * F1[2]
        else:
            ax = ay = az = 0.0
        advance(q, h2, F1, P2)
        ok, dmin = cf4_stage(ax, ay, az, R, Y2, P2, v1, sgn, delta_stop, dmin, B2, F2, E)
        if not ok:
            stop = 0.5
            break
        if ROTATION:
            ax = h2 * F2[0]
            ay = h2 * F2[1]
            az = h2 * F2[2]
        advance(q, h2, F2, P3)
        ok, dmin = cf4_stage(ax, ay, az, R, Y3, P3, v1, sgn, delta_stop, dmin, B3, F3, E)
        if not ok:
            stop = 0.5
            break
        if ROTATION:
            ax = h * F3[0] - h2 * F1[0]
            ay = h * F3[1] - h2 * F1[1]
            az = h * F3[2] - h2 * F1[2]
        advance(q, h, F3, P4)
        ok, dmin = cf4_stage(ax, ay, az, Y2, Y4, P4, v2, sgn, delta_stop, dmin, B4, F4, E)
        if not ok:
            stop = 1.0
            break
        if ROTATION:
            cf4_close(F1, F2, F3, F4, h12, R, E, Rh, Rn)
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
def step_workspace(R0, k, d, m):
    """The arrays :func:`cf4_step` fills besides ``(R, q)``.

    Parameters
    ----------
    R0 : numpy.ndarray
        The orientations' first value (they stay so without orientation).
    k : int
        Coordinates.
    d : int
        Rates.
    m : int
        Inputs.

    Returns
    -------
    tuple of numpy.ndarray
        ``(Rn, qn, Y2, Y3, Y4, P2, P3, P4, Rh, E, B1, B2, B3, B4, F1, F2, F3, F4)``.
    """
    return (R0.copy(), np.empty(k), R0.copy(), R0.copy(), R0.copy(), np.empty(k), np.empty(k),
            np.empty(k), np.empty((3, 3)), np.empty((3, 3)), np.empty((d, m)), np.empty((d, m)),
            np.empty((d, m)), np.empty((d, m)), np.empty(d), np.empty(d), np.empty(d), np.empty(d))


# --------------------------------------------------------------------------------------
# Kernels
# --------------------------------------------------------------------------------------


def forward(R0, q0, U, h, sgn, delta_stop, Rs, Qs):
    """CF4 over ``N = len(U)`` steps from ``(R0, q0)``.

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
    Rs, Qs : numpy.ndarray
        The output: the state at every ``t_n``, shapes ``(N+1, 3, 3)``, ``(N+1, k)``.

    Returns
    -------
    n_done : int
        The number of completed steps (``N`` unless the trajectory reached ``sgnΔ <
        delta_stop`` or a non-finite rate).
    dmin : float
        The least ``sgnΔ`` over all evaluation points of the completed steps.
    t_stop : float
        The stage time where it stopped (``-1`` if it did not).
    """
    N = U.shape[0]
    m = U.shape[2]
    k = q0.shape[0]
    R = R0.copy()
    q = q0.copy()
    (Rn, qn, Y2, Y3, Y4, P2, P3, P4, Rh, E, B1, B2, B3, B4,
     F1, F2, F3, F4) = step_workspace(R0, k, D, m)
    for i in range(3):
        for j in range(3):
            Rs[0, i, j] = R0[i, j]
    for i in range(k):
        Qs[0, i] = q0[i]
    dmin = sgn * delta(R, q)
    if not dmin >= delta_stop:
        return 0, dmin, 0.0
    for n in range(N):
        stop, dmin = cf4_step(R, q, Rn, qn, U[n, 0], U[n, 1], U[n, 2], h, sgn, delta_stop, dmin,
                              Y2, Y3, Y4, P2, P3, P4, Rh, E, B1, B2, B3, B4, F1, F2, F3, F4)
        if stop >= 0.0:
            return n, dmin, n * h + stop * h
        for i in range(3):
            for j in range(3):
                R[i, j] = Rn[i, j]
                Rs[n + 1, i, j] = Rn[i, j]
        for i in range(k):
            q[i] = qn[i]
            Qs[n + 1, i] = qn[i]
    return N, dmin, -1.0


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
        The stage's field, d×m.
    Qm : numpy.ndarray
        Scratch, d×d (``QG``).
    f : numpy.ndarray
        The output ``-Zc A``, d×d.
    K : numpy.ndarray
        The output ``Zc B``, d×m.
    """
    field_derivative_into(Y, P, v, Qm)
    m = B.shape[1]
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

    Inputs: as :func:`forward`, plus the stage basis ``(Bidx, Bval, stride_b, stride_i)``
    of the parametrisation: sparse (``Bidx.shape[2] == 0``: no Jacobian), or *dense* when
    ``Bidx`` is empty (``Bidx.shape[0] == 0``) and ``Bval`` has shape ``(N, 3, nb)``:
    ``Bidx[n, c, q] = q`` for every ``q < nb`` (Fourier bases); ``J`` is then one matrix
    product ``Wdᵀ Bval`` after the loop (BLAS) instead of a scatter per stage.
    Outputs (preallocated): ``Rs``, ``Qs`` (as :func:`forward`), ``Zs`` (``(N+1, d, d)``,
    ``Z(t_n)``; only ``Zs[N] = Z(T)`` unless ``full``), ``J`` (d × p) ``= ∂s_T/∂λ``, ``Mq``
    (d×d) ``= M(T)`` (only if ``full``), ``Wd``: shape ``(3N, d·m)`` (required by a dense
    basis) to receive the stage weights ``Wd[3n + c, i·m + k] = (W_c)_{ik}`` of every
    step — ``W_0 = h/6 Z_1 B_1``, ``W_½ = h/3 (Z_2 B_2 + Z_3 B_3)``, ``W_1 = h/6 Z_4 B_4``,
    so ``∫_0^T Z B v dt ≈ Σ W_c v(t_n + c h)`` for any ``v`` — or ``(0, d·m)``. Returns what
    :func:`forward` returns; ``J``, ``Mq``, ``Wd`` and ``Zs[N]`` are valid only if the run
    completed (NaN where ``Z(T)`` is singular or not finite: the motion blew up).

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
    B1 = np.empty((D, m))
    B2 = np.empty((D, m))
    B3 = np.empty((D, m))
    B4 = np.empty((D, m))
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


def frame_inputs(nodes, qnodes, idx, s, Wst, w_end, Rout, Qout, out):
    """Physical inputs ``u = W(R(t), q(t)) w(t)`` along a motion planned in frame coordinates.

    For every sample ``t_k``: the state is node ``idx[k]`` of the CF4 trajectory ``(nodes,
    qnodes)`` advanced by one CF4 step (:func:`cf4_step`) of length ``s[k]`` (none if
    ``s[k] == 0``) with frame inputs ``Wst[k, 0]``, ``Wst[k, 1]``, ``Wst[k, 2]`` at its start,
    middle and end — the same local approximation as a step of the integrator, ``O(s⁵)``
    from the exact motion.

    Parameters
    ----------
    nodes, qnodes : numpy.ndarray
        The CF4 trajectory's nodes.
    idx : numpy.ndarray
        The node of every sample.
    s : numpy.ndarray
        The partial step from it, every sample.
    Wst : numpy.ndarray
        The frame inputs at the partial step's start, middle and end, ``(n, 3, m)``.
    w_end : numpy.ndarray
        The frame inputs at the samples, ``(n, m)``.
    Rout, Qout : numpy.ndarray
        The state at every ``t_k`` (output).
    out : numpy.ndarray
        ``out[k] = W(R(t_k), q(t_k)) w_end[k]`` (output).
    """
    n_t = idx.shape[0]
    m = Wst.shape[2]
    k = qnodes.shape[1]
    R = np.empty((3, 3))
    q = np.empty(k)
    (Rn, qn, Y2, Y3, Y4, P2, P3, P4, Rh, E, B1, B2, B3, B4,
     F1, F2, F3, F4) = step_workspace(nodes[0], k, D, m)
    Wm = np.empty((m, m))
    for t in range(n_t):
        for i in range(3):
            for j in range(3):
                R[i, j] = nodes[idx[t], i, j]
                Rn[i, j] = R[i, j]
        for i in range(k):
            q[i] = qnodes[idx[t], i]
            qn[i] = q[i]
        if s[t] != 0.0:
            stop, dmin = cf4_step(R, q, Rn, qn, Wst[t, 0], Wst[t, 1], Wst[t, 2], s[t], 1.0, -np.inf,
                                  np.inf, Y2, Y3, Y4, P2, P3, P4, Rh, E, B1, B2, B3, B4,
                                  F1, F2, F3, F4)
        for i in range(3):
            for j in range(3):
                Rout[t, i, j] = Rn[i, j]
        for i in range(k):
            Qout[t, i] = qn[i]
        W_into(Rn, qn, Wm)
        for i in range(m):
            v = 0.0
            for j in range(m):
                v += Wm[i, j] * w_end[t, j]
            out[t, i] = v


# --------------------------------------------------------------------------------------
# Compilation per system
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Kernels:
    """The compiled kernels of one system of a mechanism: ``(ω, q̇) = G(R, q) u`` or, with
    ``frame``, its desingularised field ``N(R, q) w`` (then :attr:`frame_inputs` evaluates
    ``u = W(R, q) w``). Arguments: those of the functions of the same names.

    Parameters
    ----------
    name : str
        The mechanism's name.
    frame : bool
        Whether the system is the frame's.
    n_inputs : int
        ``m``.
    has_singular_set : bool
        Whether ``Δ`` is watched.
    forward, forward_variational : callable
        The kernels :func:`forward` and :func:`forward_variational`.
    frame_inputs : callable or None
        The kernel :func:`frame_inputs` (frame systems).
    n_coordinates : int, default 0
        ``k``, the number of coordinates ``q`` of the state (0 on SO(3)).
    backend : str, default "numba"
        ``"native"`` (C translated from these kernels,
        :mod:`nonholo.integrate.native_kernels`) or ``"numba"``.
    """

    name: str
    frame: bool
    n_inputs: int
    has_singular_set: bool
    forward: object
    forward_variational: object
    frame_inputs: object = None
    #: ``k``, the number of coordinates ``q`` of the state (0 on SO(3))
    n_coordinates: int = 0
    #: ``"native"`` (C translated from these kernels, :mod:`nonholo.integrate.native_kernels`)
    #: or ``"numba"``
    backend: str = "numba"

    def nodes(self, steps: int) -> tuple[np.ndarray, np.ndarray]:
        """Node arrays for a kernel's trajectory.

        Parameters
        ----------
        steps : int
            The steps.

        Returns
        -------
        Rs : numpy.ndarray
            ``(steps+1, 3, 3)``, uninitialised.
        Qs : numpy.ndarray
            ``(steps+1, k)``, uninitialised.
        """
        return np.empty((steps + 1, 3, 3)), np.empty((steps + 1, self.n_coordinates))


#: The kernels, in the form numba compiles: :mod:`nonholo.generated.cf4_kernels`, the
#: functions of this module with the calls of the step and its parts expanded in place
#: (written by ``nonholo derive``, see :mod:`nonholo.integrate.inliner`); the helpers they
#: still call, specialised first.
_TEMPLATES = (rates, zstage, kernels_inlined.forward, kernels_inlined.forward_variational,
              kernels_inlined.frame_inputs)
#: The kernels as written here (``compile_system(..., inlined=False)``).
_WRITTEN = (rates, advance, zpredict, cf4_stage, cf4_step, zstage, forward, forward_variational,
            frame_inputs)


def specialise(template, namespace: dict, bindings: dict, tag: str, cache: bool):
    """A compiled copy of a kernel with the system's names bound.

    Parameters
    ----------
    template : function
        The kernel.
    namespace : dict
        A kernel module's globals.
    bindings : dict
        The system's names.
    tag : str
        The system's tag (:func:`system_tag`): the copy's own cache entry.
    cache : bool
        Whether numba caches it on disk.

    Returns
    -------
    numba.core.registry.CPUDispatcher
        The compiled copy.
    """
    f = types.FunctionType(template.__code__, {**namespace, **bindings}, template.__name__)
    f.__qualname__ = f"{template.__name__}__{tag}"        # its own cache entry
    f.__module__ = namespace["__name__"]
    f.__doc__ = template.__doc__
    return jit(f, cache=cache, lazy=False)


def system_tag(module, frame: bool) -> str:
    """The cache name of a system: mechanism, system and a hash of the generated source.

    Parameters
    ----------
    module : module
        The mechanism's generated module.
    frame : bool
        Whether the system is the frame's.

    Returns
    -------
    str
        The tag.
    """
    src = inspect.getsource(module) if importable(module) else module.SOURCE
    return f"{module.NAME}{'_frame' if frame else ''}_{hashlib.sha256(src.encode()).hexdigest()[:12]}"


def importable(module) -> bool:
    """Whether a module can be re-imported by name (a cached kernel refers to it by name).

    Parameters
    ----------
    module : module
        A generated module.

    Returns
    -------
    bool
        Whether ``sys.modules`` holds it under its name.
    """
    return sys.modules.get(getattr(module, "__name__", None)) is module


#: Compiled kernels by system tag, and by (module, frame) (the tag hashes the source).
_COMPILED: dict[str, Kernels] = {}
_BY_MODULE: dict[tuple, Kernels] = {}


def compile_system(module, frame: bool = False, inlined: bool = True, fast_derivative: bool = True,
                   backend: str | None = None) -> Kernels:
    """The kernels of a system of the generated ``module``'s mechanism (compiled once,
    cached on disk).

    ``frame=False``: ``(ω, q̇) = G(R, q) u`` (``G_into``, ``QG_into``); ``frame=True``: the
    desingularised field ``N(R, q) w`` (``N_into``, ``QN_into``, and ``W_into`` for
    :func:`frame_inputs`). Both watch the mechanism's ``delta`` (if any). Every kernel
    takes the state as ``(R0, q0)`` (see :func:`forward`). Kernels of a
    module that cannot be re-imported by name (built in this process, see
    :meth:`nonholo.model.mechanism.Mechanism.from_symbolic`) are not cached on disk. Numba
    compiles a kernel on its first call, so a run pays only for what it uses.
    ``inlined=False`` compiles the kernels as this module writes them instead (the step
    called, not inlined; slower, not cached): the reference the generated ones are
    checked against. ``fast_derivative=False`` compiles ``QG`` without fast-math (not
    cached): LLVM may then reorder its arithmetic differently wherever it is inlined, so
    only these kernels are bit for bit the same in both forms.

    Parameters
    ----------
    module : module
        The mechanism's generated module.
    frame : bool, default False
        Whether to compile the frame system.
    inlined : bool, default True
        Whether to compile the inlined kernels.
    fast_derivative : bool, default True
        Whether to compile ``QG`` with fast-math.
    backend : str, optional
        ``"native"`` — the same kernels translated to C and compiled ahead of time
        (:mod:`nonholo.integrate.native_kernels`) — or ``"numba"``; by default native where
        available (a C compiler, ``NONHOLO_BACKEND`` not ``numba``), else numba.

    Returns
    -------
    Kernels
        The kernels.

    Raises
    ------
    ValueError
        For an unknown ``backend``, or ``frame`` for a mechanism without a frame.
    RuntimeError
        If ``backend="native"`` and native kernels are unavailable.
    """
    if backend not in (None, "native", "numba"):
        raise ValueError(f"backend must be 'native', 'numba' or None, not {backend!r}")
    if frame and not getattr(module, "HAS_FRAME", False):
        raise ValueError(f"mechanism {module.NAME!r} has no desingularised frame N(R, q)")
    if backend != "numba" and inlined and fast_derivative:
        kern = _native(module, frame, required=backend == "native")
        if kern is not None:
            return kern
    if (module, frame) in _BY_MODULE and inlined and fast_derivative:
        return _BY_MODULE[module, frame]
    if not (inlined and fast_derivative):
        tag = system_tag(module, frame) + ("" if inlined else "_written") + ("" if fast_derivative else "_exact")
        return _compile(module, frame, _TEMPLATES if inlined else _WRITTEN, tag, False, fast_derivative)
    tag = system_tag(module, frame)
    if tag in _COMPILED:
        _BY_MODULE[module, frame] = _COMPILED[tag]
        return _COMPILED[tag]
    kern = _compile(module, frame, _TEMPLATES, tag, importable(module))
    _COMPILED[tag] = _BY_MODULE[module, frame] = kern
    return kern


_NATIVE: dict[tuple, Kernels] = {}


def native_parts() -> dict:
    """The pieces of this module the native kernels are translated from besides the inlined kernels.

    Returns
    -------
    dict
        ``rates``, ``zstage``, ``no_singularity``, ``step_workspace`` by name (see
        :func:`nonholo.integrate.native_kernels.functions`).
    """
    return {"rates": rates, "zstage": zstage, "no_singularity": no_singularity, "step_workspace": step_workspace}


def native_source(module, kernels_text: str | None = None) -> str:
    """The C source of the native kernels of a generated module (``nonholo derive``).

    Parameters
    ----------
    module : module
        The mechanism's generated module.
    kernels_text : str, optional
        The inlined kernels' source (by default :mod:`nonholo.generated.cf4_kernels`').

    Returns
    -------
    str
        The C source.
    """
    return kernel_source(module, native_parts(), kernels_text)


def _native(module, frame: bool, required: bool) -> Kernels | None:
    """The native kernels of a system (see :func:`compile_system`), or None."""
    if not native.enabled():
        if required:
            raise RuntimeError("native kernels asked for, but NONHOLO_BACKEND is 'numba'")
        return None
    if (module, frame) in _NATIVE:
        return _NATIVE[module, frame]
    fns = native_kernels(module, frame, native_parts())
    if fns is None:
        if required:
            raise RuntimeError(f"no native kernels for {module.NAME!r} (no C compiler, or NONHOLO_BACKEND=numba)")
        return None
    kern = Kernels(name=module.NAME, frame=frame, n_inputs=module.N_INPUTS,
                   has_singular_set=module.HAS_SINGULAR_SET, n_coordinates=len(module.COORDINATES),
                   forward=metered(fns["forward"], effort.FORWARD_WEIGHT, 2),
                   forward_variational=metered(fns["forward_variational"], 1.0, 2),
                   frame_inputs=None if fns["frame_inputs"] is None
                   else metered(fns["frame_inputs"], effort.FORWARD_WEIGHT, 2),
                   backend="native")
    _NATIVE[module, frame] = kern
    return kern


def _compile(module, frame: bool, templates, tag: str, cache: bool, fast_derivative: bool = True) -> Kernels:
    """Compile ``templates`` for a system of ``module`` (see :func:`compile_system`)."""
    G, QG = (module.N_into, module.QN_into) if frame else (module.G_into, module.QG_into)
    bindings = {
        "field_into": jit(G, cache=False, lazy=False),
        # QG feeds only the variational system (the Jacobian): fast-math lets LLVM turn
        # its ``x**(-2.0)`` into a multiplication (the result changes at round-off level)
        "field_derivative_into": jit(QG, cache=False, lazy=False, fastmath=fast_derivative),
        "delta": jit(module.delta if module.HAS_SINGULAR_SET else no_singularity, cache=False, lazy=False),
        "ROTATION": bool(module.ORIENTATION),
        "D": (3 if module.ORIENTATION else 0) + len(module.COORDINATES),
        "OFFSET": 3 if module.ORIENTATION else 0,
    }
    if frame:
        bindings["W_into"] = jit(module.W_into, cache=False, lazy=False)
    for template in templates:
        if template.__name__ == "frame_inputs" and not frame:
            continue
        bindings[template.__name__] = specialise(template, globals(), bindings, tag, cache)
    frame_kernel = bindings.get("frame_inputs")
    kern = Kernels(name=module.NAME, frame=frame, n_inputs=module.N_INPUTS,
                   has_singular_set=module.HAS_SINGULAR_SET, n_coordinates=len(module.COORDINATES),
                   forward=metered(bindings["forward"], effort.FORWARD_WEIGHT, 2),
                   forward_variational=metered(bindings["forward_variational"], 1.0, 2),
                   frame_inputs=None if frame_kernel is None else metered(frame_kernel, effort.FORWARD_WEIGHT, 2))
    return kern


def metered(kernel, weight: float, counted: int):
    """A kernel counting its effort (:mod:`nonholo.numerics.effort`).

    Parameters
    ----------
    kernel : callable
        The kernel.
    weight : float
        Effort per element of the counted argument.
    counted : int
        The argument's position (the stage table's steps; ``frame_inputs``' node indices).

    Returns
    -------
    callable
        The kernel, counting (the kernel itself as its ``kernel`` attribute).
    """

    def run(*args):
        effort.add(weight * len(args[counted]))
        return kernel(*args)

    run.__name__ = run.__qualname__ = getattr(kernel, "__name__", "kernel")
    run.__doc__ = kernel.__doc__
    run.kernel = kernel
    return run
