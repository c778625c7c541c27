"""The CF4 Lie-group step: one step of the integrator, and the system it integrates.

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

It is the only place the scheme is written; every kernel takes its steps with it:
:func:`~nonholo.integrate.motion_kernels.forward` (the motion),
:func:`~nonholo.integrate.variational_kernels.forward_variational` (the motion with the
variational system) and :func:`~nonholo.integrate.motion_kernels.frame_inputs` (the
physical inputs along a motion planned in frame coordinates, one partial step from the
nearest node). Every kernel takes the state as ``(R0, q0)`` and writes the nodes ``Rs``
``(N+1, 3, 3)`` and ``Qs`` ``(N+1, k)``.

Singular set: ``sgn Δ`` (``sgn = sign Δ(R0, q0)``) is checked at every stage point and
node; the kernels stop as soon as it falls below ``delta_stop`` (or a rate is not
finite) and report how many steps were completed, so a trajectory running into ``Δ = 0``
never produces NaN.

The step calls the system through four names — ``field_into``, ``field_derivative_into``,
``delta`` and (frame systems) ``W_into`` — and reads the state's layout from three
constants — ``ROTATION`` (whether there is an orientation), ``D`` (``d``) and ``OFFSET``
(the row of ``q̇``'s first rate in ``G``: 3 with orientation, else 0) — all defined below
as placeholders, bound per system with the kernels that call the step
(:func:`nonholo.integrate.system_kernels.compile_system`). The step and its parts are
written so that ``nonholo derive`` can expand their calls in place
(:mod:`nonholo.codegen.inline`).
"""
from __future__ import annotations

import numpy as np

from ..numerics.jit import jit
from ..numerics.kernels import exp_times

# --------------------------------------------------------------------------------------
# The system a kernel integrates (bound per system by compile_system)
# --------------------------------------------------------------------------------------


def _placeholder(*args):
    """A name the kernels call, bound per system (see the module and
    :func:`~nonholo.integrate.system_kernels.compile_system`).

    Parameters
    ----------
    *args : object
        The arguments of the function bound in its place.

    Raises
    ------
    NotImplementedError
        Always: the name is not bound.
    """
    raise NotImplementedError("placeholder: bound per system by "
                              "nonholo.integrate.system_kernels.compile_system")


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
#:     Until :func:`~nonholo.integrate.system_kernels.compile_system` binds the name (see
#:     the module).
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
#:     Until :func:`~nonholo.integrate.system_kernels.compile_system` binds the name (see
#:     the module).
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
#:     Until :func:`~nonholo.integrate.system_kernels.compile_system` binds the name (see
#:     the module).
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
#:     Until :func:`~nonholo.integrate.system_kernels.compile_system` binds the name (see
#:     the module).
W_into = _placeholder
#: Whether the state has an orientation ``R``; the dimension ``d`` of a variation; the row
#: of the first coordinate rate in ``G`` (3 with orientation, else 0).
ROTATION = True
D = 3
OFFSET = 3
#: The field's columns past the inputs: 1 for a system with drift ``ẋ = f(x) + G(x) u``,
#: whose ``field_into`` fills ``[G | f]`` (the drift a last column, played at the input 1;
#: ``field_derivative_into`` is then that of ``f + G v``), else 0.
DRIFT_COLUMNS = 0


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
    """``out = B v`` (d×m times m), plus the drift column of a system with drift
    (:data:`DRIFT_COLUMNS`).

    Parameters
    ----------
    B : numpy.ndarray
        The field, d×(m + ``DRIFT_COLUMNS``).
    v : numpy.ndarray
        The inputs, m entries.
    out : numpy.ndarray
        The output, d entries.

    Returns
    -------
    bool
        ``False`` if a rate is not finite.
    """
    m = v.shape[0]
    ok = True
    for i in range(D):
        s = 0.0
        for k in range(m):
            s += B[i, k] * v[k]
        for k in range(DRIFT_COLUMNS):
            s += B[i, m + k]
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
    :mod:`nonholo.codegen.inline`.)

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
        The stage fields (output), d×(m + ``DRIFT_COLUMNS``).
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
        The field's columns (the inputs, and the drift's: :data:`DRIFT_COLUMNS`).

    Returns
    -------
    tuple of numpy.ndarray
        ``(Rn, qn, Y2, Y3, Y4, P2, P3, P4, Rh, E, B1, B2, B3, B4, F1, F2, F3, F4)``.
    """
    return (R0.copy(), np.empty(k), R0.copy(), R0.copy(), R0.copy(), np.empty(k), np.empty(k),
            np.empty(k), np.empty((3, 3)), np.empty((3, 3)), np.empty((d, m)), np.empty((d, m)),
            np.empty((d, m)), np.empty((d, m)), np.empty(d), np.empty(d), np.empty(d), np.empty(d))

