"""Independent checks of planned motions with SciPy's DOP853 (no numba, no Lie-group tricks).

- :func:`resimulate` integrates the nine entries of ``R`` in ``dR/dt = [L(R) u(t)] R`` with
  ``solve_ivp(method="DOP853", rtol=atol=1e-13)``, using the mechanism's generated ``L``
  in plain NumPy. For piecewise-constant controls each interval between ``breakpoints``
  is integrated separately (the control is evaluated strictly inside the interval), so
  the adaptive integrator never steps across a jump.
- :func:`resimulate_path` is the same integration with dense output, for the least ``|Δ|``
  along the re-simulated motion.
- :func:`resimulate_rk4` integrates the same nine entries with the classical RK4 on a
  fixed grid of :data:`RK4_STEPS` steps (aligned with every grid and plan of
  :func:`nonholo.plan`: the inputs are taken at the stage times, from the controls' stage
  table, so no step straddles a jump), many motions at once — the cheap independent check
  of thousands of plans (``benchmarks/certify.py``).
- :func:`terminal_error` is ``|l_T|`` with ``[l_T] = log(R_T R_dᵀ)`` (geodesic distance, rad).
- :func:`mobility_lyapunov` solves the Lyapunov equation ``dM/dt = B Bᵀ + A M + M Aᵀ``,
  ``M(0) = 0`` (``A = Q(R,u) + [L(R)u]``, ``B = L(R)``) together with ``R``: the mobility
  matrix ``M(T)`` of the appendix, to compare with the quadrature in
  :func:`nonholo.motion.simulation.variational`.
"""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from ..controls import stages
from ..model import catalog
from ..spaces import so3

RTOL = 1e-13
ATOL = 1e-13
#: RK4 steps of :func:`resimulate_rk4`: 2⁸·3·5², a multiple of every grid of 100 and of
#: every plan's 200·2ᵏ steps up to 6400.
RK4_STEPS = 19200


def _segments(T: float, controls, breakpoints):
    if breakpoints is None:
        breakpoints = getattr(controls, "breakpoints", None)
    if breakpoints is None:
        return [(0.0, T)]
    b = np.unique(np.clip(np.asarray(breakpoints, dtype=float), 0.0, T))
    b = np.union1d(b, [0.0, T])
    return list(zip(b[:-1], b[1:]))


#: How far inside a segment its ends' inputs are sampled, as a fraction of its length.
END_NUDGE = 1e-9


def _inside(controls, t, a: float, b: float, m: int) -> np.ndarray:
    """``u(t)`` for times ``t`` in ``[a, b]`` (shape ``(n, m)``), with the values at the ends
    the limits from inside the segment: a control may jump at its ends (a breakpoint), so
    ``u(a)``, ``u(b)`` are extrapolated linearly from ``ε`` and ``2ε`` inside (``ε`` =
    :data:`END_NUDGE` of the segment), which is exact to ``O(u''ε²)`` where merely nudging
    inside would be off by ``u'ε``, an error of the first order in a fixed-step
    integrator's step."""
    t = np.array(t, dtype=float).reshape(-1)
    eps = END_NUDGE * (b - a)
    at_a, at_b = t <= a + eps, t >= b - eps
    u = np.asarray(controls(np.clip(t, a + eps, b - eps)), dtype=float).reshape(-1, m)
    for mask, sgn, end in ((at_a, 1.0, a), (at_b, -1.0, b)):
        if np.any(mask):
            near = np.asarray(controls(np.array([end + sgn * eps, end + sgn * 2 * eps])), dtype=float)
            near = near.reshape(2, m)
            u[mask] = 2.0 * near[0] - near[1]
    return u


def _input(controls, a: float, b: float, m: int):
    """``u(t)`` on ``[a, b]`` with the ends' values from inside (:func:`_inside`)."""
    def u(t):
        return _inside(controls, [t], a, b, m)[0]

    return u


def _solve(rhs, y0, segments, rtol, atol):
    y = np.asarray(y0, dtype=float)
    for a, b in segments:
        sol = solve_ivp(rhs(a, b), (a, b), y, method="DOP853", rtol=rtol, atol=atol)
        if not sol.success:
            raise RuntimeError(f"DOP853 failed on [{a:g}, {b:g}]: {sol.message}")
        y = sol.y[:, -1]
        if not np.all(np.isfinite(y)):
            raise RuntimeError(f"DOP853 produced non-finite values on [{a:g}, {b:g}]")
    return y


def resimulate(R0, controls, T: float, mechanism="platform", breakpoints=None,
               *, rtol: float = RTOL, atol: float = ATOL) -> np.ndarray:
    """``R(T)`` of ``dR/dt = [L(R) u(t)] R``, ``R(0) = R0``, by DOP853 (tight tolerances).

    Parameters
    ----------
    R0 : array_like
        The start, a rotation matrix.
    controls : callable
        A vectorised ``u(t)`` (``(n,) -> (n, m)``), e.g. ``PlanResult.controls`` or a
        :class:`~nonholo.controls.parametrisations.Controls`.
    T : float
        The horizon (s).
    mechanism : str or Mechanism
        The mechanism or its name.
    breakpoints : array_like, optional
        Times where ``u`` may jump (default: the controls' ``breakpoints`` attribute, if
        any); the integrator does not step across them.
    rtol, atol : float
        DOP853's tolerances.

    Returns
    -------
    numpy.ndarray
        ``R(T)``, 3×3.

    Raises
    ------
    RuntimeError
        If DOP853 fails on a segment.
    """
    mech = catalog.get(mechanism)
    R0 = so3.check_rotation(R0, "R0")
    L, m = mech.module.L, mech.n_inputs

    def rhs(a, b):
        u = _input(controls, a, b, m)

        def f(t, y):
            R = y.reshape(3, 3)
            return (so3.hat(L(R) @ u(t)) @ R).ravel()

        return f

    return _solve(rhs, R0.ravel(), _segments(float(T), controls, breakpoints), rtol, atol).reshape(3, 3)


def resimulate_path(R0, controls, T: float, mechanism="platform", breakpoints=None,
                    samples: int = 2001, *, rtol: float = RTOL, atol: float = ATOL):
    """The motion of :func:`resimulate` on ``samples`` uniform times (DOP853 dense output).

    Parameters
    ----------
    R0, controls, T, mechanism, breakpoints
        As for :func:`resimulate`.
    samples : int
        Uniform sample times on ``[0, T]``.
    rtol, atol : float
        DOP853's tolerances.

    Returns
    -------
    tuple
        ``(t, R, delta)``: ``t`` (n,), ``R`` (n, 3, 3) at ``t`` and at every step the
        integrator took (``t`` sorted, ``t[-1] = T``), and ``Δ(R)`` there (``None`` for a
        mechanism without a singular set) — the least ``|Δ|`` along the re-simulated
        motion is ``abs(delta).min()`` up to the sampling.

    Raises
    ------
    RuntimeError
        If DOP853 fails on a segment.
    """
    mech = catalog.get(mechanism)
    R0 = so3.check_rotation(R0, "R0")
    L, m = mech.module.L, mech.n_inputs
    ts, Rs = [], []
    y = R0.ravel()
    grid = np.linspace(0.0, float(T), int(samples))
    for a, b in _segments(float(T), controls, breakpoints):
        u = _input(controls, a, b, m)

        def f(t, y, u=u):
            R = y.reshape(3, 3)
            return (so3.hat(L(R) @ u(t)) @ R).ravel()

        sol = solve_ivp(f, (a, b), y, method="DOP853", rtol=rtol, atol=atol, dense_output=True)
        if not sol.success or not np.all(np.isfinite(sol.y)):
            raise RuntimeError(f"DOP853 failed on [{a:g}, {b:g}]: {sol.message}")
        inside = grid[(grid >= a) & (grid <= b)]
        t = np.concatenate([sol.t, inside])
        Y = sol.y if not inside.size else np.concatenate([sol.y, sol.sol(inside).reshape(9, -1)], axis=1)
        ts.append(t)
        Rs.append(Y.T.reshape(-1, 3, 3))
        y = sol.y[:, -1]
    t = np.concatenate(ts)
    R = np.concatenate(Rs)
    order = np.argsort(t, kind="stable")
    t, R = t[order], R[order]
    return t, R, mech.singular.samples(R)


def terminal_error(R_T, Rd) -> float:
    """``|l_T|``, ``[l_T] = log(R_T R_dᵀ)``: the geodesic distance from ``R_T`` to ``R_d``.

    Parameters
    ----------
    R_T, Rd : array_like
        The endpoint and the goal, rotation matrices.

    Returns
    -------
    float
        The distance (rad).
    """
    return float(np.linalg.norm(so3.log(np.asarray(R_T) @ np.asarray(Rd).T)))


def mobility_lyapunov(R0, controls, T: float, mechanism="platform", breakpoints=None,
                      *, rtol: float = 1e-12, atol: float = 1e-12) -> np.ndarray:
    """``M(T)`` from ``dM/dt = B Bᵀ + A M + M Aᵀ``, ``M(0) = 0`` (integrated with ``R``).

    Parameters
    ----------
    R0, controls, T, mechanism, breakpoints
        As for :func:`resimulate`.
    rtol, atol : float
        DOP853's tolerances.

    Returns
    -------
    numpy.ndarray
        The mobility matrix ``M(T)``, 3×3.
    """
    mech = catalog.get(mechanism)
    R0 = so3.check_rotation(R0, "R0")
    L, Q, m = mech.module.L, mech.module.Q, mech.n_inputs

    def rhs(a, b):
        u = _input(controls, a, b, m)

        def f(t, y):
            R = y[:9].reshape(3, 3)
            M = y[9:].reshape(3, 3)
            ut = u(t)
            B = L(R)
            w = B @ ut
            A = Q(R, ut) + so3.hat(w)
            dR = so3.hat(w) @ R
            dM = B @ B.T + A @ M + M @ A.T
            return np.concatenate([dR.ravel(), dM.ravel()])

        return f

    y0 = np.concatenate([R0.ravel(), np.zeros(9)])
    y = _solve(rhs, y0, _segments(float(T), controls, breakpoints), rtol, atol)
    M = y[9:].reshape(3, 3)
    return 0.5 * (M + M.T)


def resimulate_rk4(R0, controls, T: float, mechanism="platform", steps: int = RK4_STEPS):
    """``(R(T), min_delta)`` of ``dR/dt = [L(R) u(t)] R``, ``R(0) = R0``, by the classical
    RK4 on the nine entries of ``R`` with ``steps`` equal steps (no projection on SO(3)).

    Batched: ``R0`` of shape ``(3, 3)`` or ``(P, 3, 3)`` with as many ``controls`` (a list)
    and ``T`` (a number or ``P`` of them), all of one mechanism. ``controls``: a
    :class:`~nonholo.controls.parametrisations.Controls` or :class:`~nonholo.motion.frame_controls.FrameControls` (its stage
    table at the RK4 stage times ``t_n``, ``t_n + h/2``, ``t_n + h`` gives the inputs) or
    ``PlanResult.parametrisation``.

    Parameters
    ----------
    R0 : array_like
        Starts, ``(3, 3)`` or ``(P, 3, 3)``.
    controls : Controls or FrameControls or list
        One per start.
    T : float or array_like
        Horizons, one or ``P``.
    mechanism : str or Mechanism
        The mechanism of every start.
    steps : int
        Equal RK4 steps.

    Returns
    -------
    tuple
        ``(R(T), min_delta)``: ``min_delta`` is the least ``sgn(Δ(R0))·Δ`` over the nodes
        (``None`` without a singular set); ``R(T)`` is NaN where ``L`` blew up.

    Raises
    ------
    ValueError
        If the numbers of starts and of controls differ.
    """
    mech = catalog.get(mechanism)
    single = np.ndim(R0) == 2
    R = np.array(R0, dtype=float).reshape(-1, 3, 3)
    P = R.shape[0]
    controls = [controls] if single else list(controls)
    if len(controls) != P:
        raise ValueError(f"{P} start orientations but {len(controls)} controls")
    h = np.broadcast_to(np.asarray(T, dtype=float), (P,)) / steps
    m = mech.n_inputs
    U = np.stack([stages.stage_table(c, steps) for c in controls], axis=-1)   # (steps, 3, m, P)
    L_into = mech.module.L_into
    Y = np.ascontiguousarray(R.transpose(1, 2, 0))                             # (3, 3, P)
    B = np.empty((3, m, P))
    singular, none = mech.singular, np.zeros((P, 0))
    sign = np.sign(singular.values(R, none))
    dmin = sign * singular.values(R, none)

    def f(Y, u):
        L_into(Y, B)
        w = np.einsum("imp,mp->ip", B, u)
        W = np.zeros((3, 3, P))
        W[0, 1], W[0, 2], W[1, 2] = -w[2], w[1], -w[0]
        W[1, 0], W[2, 0], W[2, 1] = w[2], -w[1], w[0]
        return np.einsum("ijp,jkp->ikp", W, Y)

    with np.errstate(all="ignore"):
        for n in range(steps):
            u0, u1, u2 = U[n, 0], U[n, 1], U[n, 2]
            k1 = f(Y, u0)
            k2 = f(Y + 0.5 * h * k1, u1)
            k3 = f(Y + 0.5 * h * k2, u1)
            k4 = f(Y + h * k3, u2)
            Y = Y + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
            dmin = np.fmin(dmin, sign * singular.values(Y.transpose(2, 0, 1), none))
    RT = Y.transpose(2, 0, 1)
    dmin = singular.reported(np.where(np.isfinite(RT).all(axis=(1, 2)), dmin, -np.inf))
    if single:
        return RT[0], None if dmin is None else float(dmin[0])
    return RT, dmin


# --------------------------------------------------------------------------------------
# States beyond SO(3): the models written out by hand, from their definitions
# --------------------------------------------------------------------------------------


def rolling_ball_rates(R, p, v, radius: float = 1.0):
    """The ball rolling on the plane z = 0 without slipping or spinning: the
    centre moves with ``ṗ = v`` and the spatial angular velocity is ``ω = (e₃ × v)/ρ``.

    Parameters
    ----------
    R : numpy.ndarray
        The orientation (unused: the rates do not depend on it).
    p : numpy.ndarray
        The centre's position on the plane.
    v : numpy.ndarray
        The inputs, the centre's velocity.
    radius : float
        The ball's radius ``ρ``.

    Returns
    -------
    tuple of numpy.ndarray
        ``(ω, ṗ)``.
    """
    return np.array([-v[1], v[0], 0.0]) / radius, np.asarray(v, dtype=float)


def car_rates(R, x, u, wheelbase: float = 1.0):
    """The kinematic car ``x = (x, y, θ, φ)``, ``u = (v, φ̇)``: ``ẋ = v cos θ``,
    ``ẏ = v sin θ``, ``θ̇ = (v/ℓ) tan φ``, ``φ̇ = u₂``.

    Parameters
    ----------
    R : numpy.ndarray
        Unused (the car has no orientation in SO(3)).
    x : numpy.ndarray
        The state ``(x, y, θ, φ)``.
    u : numpy.ndarray
        The inputs ``(v, φ̇)``.
    wheelbase : float
        ``ℓ``.

    Returns
    -------
    tuple of numpy.ndarray
        ``(ω = 0, ẋ)``.
    """
    _, _, th, ph = x
    v, dphi = u
    return np.zeros(3), np.array([v * np.cos(th), v * np.sin(th), v * np.tan(ph) / wheelbase, dphi])


def unicycle_rates(R, x, u):
    """The unicycle: ``ẋ = v cos θ``, ``ẏ = v sin θ``, ``θ̇ = ω``.

    Parameters
    ----------
    R : numpy.ndarray
        Unused (no orientation in SO(3)).
    x : numpy.ndarray
        The state ``(x, y, θ)``.
    u : numpy.ndarray
        The inputs ``(v, ω)``.

    Returns
    -------
    tuple of numpy.ndarray
        ``(ω = 0, ẋ)``.
    """
    v, w = u
    return np.zeros(3), np.array([v * np.cos(x[2]), v * np.sin(x[2]), w])


def brockett_rates(R, x, u):
    """Brockett's integrator: ``ẋ = u₁``, ``ẏ = u₂``, ``ż = x u₂ − y u₁``.

    Parameters
    ----------
    R : numpy.ndarray
        Unused (no orientation in SO(3)).
    x : numpy.ndarray
        The state ``(x, y, z)``.
    u : numpy.ndarray
        The inputs ``(u₁, u₂)``.

    Returns
    -------
    tuple of numpy.ndarray
        ``(ω = 0, ẋ)``.
    """
    u1, u2 = u
    return np.zeros(3), np.array([u1, u2, x[0] * u2 - x[1] * u1])


def car_with_trailer_rates(R, x, u, wheelbase: float = 0.25, hitch: float = 0.5):
    """The kinematic car towing a trailer: the car's rates (:func:`car_rates`) and
    ``θ̇₁ = (v/d) sin(θ − θ₁)``.

    Parameters
    ----------
    R : numpy.ndarray
        Unused (no orientation in SO(3)).
    x : numpy.ndarray
        The state ``(x, y, θ, φ, θ₁)``.
    u : numpy.ndarray
        The inputs ``(v, φ̇)``.
    wheelbase, hitch : float
        ``ℓ`` and ``d``.

    Returns
    -------
    tuple of numpy.ndarray
        ``(ω = 0, ẋ)``.
    """
    _, _, th, ph, th1 = x
    v, dphi = u
    return np.zeros(3), np.array([v * np.cos(th), v * np.sin(th), v * np.tan(ph) / wheelbase, dphi,
                                  v * np.sin(th - th1) / hitch])


def double_integrator_rates(R, x, u):
    """The planar double integrator: ``(ẋ, ẏ) = (v_x, v_y)``, ``(v̇_x, v̇_y) = (a_x, a_y)``.

    Parameters
    ----------
    R : numpy.ndarray
        Unused (no orientation in SO(3)).
    x : numpy.ndarray
        The state ``(x, y, v_x, v_y)``.
    u : numpy.ndarray
        The inputs ``(a_x, a_y)``.

    Returns
    -------
    tuple of numpy.ndarray
        ``(ω = 0, ẋ)``.
    """
    return np.zeros(3), np.array([x[2], x[3], u[0], u[1]])


def second_order_unicycle_rates(R, x, u):
    """The unicycle driven by accelerations: ``ẋ = v cos θ``, ``ẏ = v sin θ``, ``θ̇ = ω``,
    ``v̇ = a``, ``ω̇ = α``.

    Parameters
    ----------
    R : numpy.ndarray
        Unused (no orientation in SO(3)).
    x : numpy.ndarray
        The state ``(x, y, θ, v, ω)``.
    u : numpy.ndarray
        The inputs ``(a, α)``.

    Returns
    -------
    tuple of numpy.ndarray
        ``(ω = 0, ẋ)``.
    """
    _, _, th, v, w = x
    return np.zeros(3), np.array([v * np.cos(th), v * np.sin(th), w, u[0], u[1]])


#: The hand-written models of the mechanisms beyond SO(3), and their singularity
#: functions (``None``: no singular set), by mechanism name.
MODELS = {"rolling_ball": (rolling_ball_rates, None),
          "car": (car_rates, lambda R, x: np.cos(x[3])),
          "unicycle": (unicycle_rates, None),
          "brockett": (brockett_rates, None),
          "car_with_trailer": (car_with_trailer_rates, lambda R, x: np.cos(x[3])),
          "double_integrator": (double_integrator_rates, None),
          "unicycle2": (second_order_unicycle_rates, None)}


def resimulate_state(start, controls, T: float, mechanism, breakpoints=None, samples: int = 2001,
                     *, rtol: float = RTOL, atol: float = ATOL):
    """The motion of a mechanism whose state goes beyond SO(3) by DOP853 on its hand-written
    model (:data:`MODELS`; nothing generated is used), from ``start`` (as
    :func:`nonholo.plan` takes it), with dense output on ``samples`` uniform times.

    Parameters
    ----------
    start
        The start, as :func:`nonholo.plan` takes it.
    controls : callable
        A vectorised ``u(t)``.
    T : float
        The horizon (s).
    mechanism : str
        A name of :data:`MODELS`.
    breakpoints : array_like, optional
        Times where ``u`` may jump.
    samples : int
        Uniform sample times.
    rtol, atol : float
        DOP853's tolerances.

    Returns
    -------
    tuple
        ``(t, R, q, delta)``: times, orientations ``(n, 3, 3)`` (the identity without
        orientation), coordinates ``(n, k)`` and the model's ``Δ`` there (``None`` without
        a singular set); the last sample is the endpoint at ``T``.

    Raises
    ------
    KeyError
        For a mechanism without a hand-written model.
    RuntimeError
        If DOP853 fails on a segment.
    """
    mech = catalog.get(mechanism)
    rates, delta_of = MODELS[mech.name]
    R0, q0 = mech.parse_state(start, "start")
    m, k = mech.n_inputs, mech.n_coordinates
    grid = np.linspace(0.0, float(T), int(samples))
    ts, Ys = [], []
    y = np.concatenate([R0.ravel(), q0])
    for a, b in _segments(float(T), controls, breakpoints):
        u = _input(controls, a, b, m)

        def f(t, y, u=u):
            R = y[:9].reshape(3, 3)
            w, qdot = rates(R, y[9:], u(t))
            return np.concatenate([(so3.hat(w) @ R).ravel(), qdot])

        sol = solve_ivp(f, (a, b), y, method="DOP853", rtol=rtol, atol=atol, dense_output=True)
        if not sol.success or not np.all(np.isfinite(sol.y)):
            raise RuntimeError(f"DOP853 failed on [{a:g}, {b:g}]: {sol.message}")
        inside = grid[(grid >= a) & (grid <= b)]
        ts.append(np.concatenate([sol.t, inside]))
        Ys.append(sol.y if not inside.size else np.concatenate([sol.y, sol.sol(inside)], axis=1))
        y = sol.y[:, -1]
    t = np.concatenate(ts)
    Y = np.concatenate(Ys, axis=1).T
    order = np.argsort(t, kind="stable")
    t, Y = t[order], Y[order]
    R, q = Y[:, :9].reshape(-1, 3, 3), Y[:, 9:9 + k]
    delta = None if delta_of is None else np.array([delta_of(r, x) for r, x in zip(R, q)])
    return t, R, q, delta


def state_errors(mechanism, R_T, q_T, Rd, qd) -> dict:
    """The terminal error by part of an independently re-simulated endpoint.

    Parameters
    ----------
    mechanism : str or Mechanism
        The mechanism.
    R_T, q_T : numpy.ndarray
        The endpoint.
    Rd, qd : numpy.ndarray
        The goal.

    Returns
    -------
    dict
        ``{"rotation": rad, "coordinates": units}`` (angles wrapped,
        :mod:`nonholo.spaces.product`).
    """
    return catalog.get(mechanism).space.error((R_T, q_T), (Rd, qd))[1]
