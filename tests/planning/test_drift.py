"""Systems with drift, ``ẋ = f(x) + G(x) u``: planned, certified and least-energy.

The least energy of a linear system ``ẋ = A x + B u`` from ``x0`` to ``xd`` in ``T`` is known in
closed form (the controllability Gramian), computed here by Van Loan's block exponential —
independently of the planner — and checked against a quadrature of its definition.
"""
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import quad_vec, solve_ivp
from scipy.linalg import expm

import nonholo
from nonholo import Mechanism
from nonholo.certify import resimulate
from nonholo.constraints import InputBounds, StateBounds, of_mechanism


def gramian(A, B, T):
    """``W(T) = ∫₀ᵀ e^{As} B Bᵀ e^{Aᵀs} ds`` by Van Loan's block exponential."""
    n = A.shape[0]
    M = np.block([[-A, B @ B.T], [np.zeros((n, n)), A.T]])
    F = expm(M * T)
    return F[n:, n:].T @ F[:n, n:]


def closed_form(A, B, x0, xd, T):
    """The least energy and its control ``u(t) = Bᵀ e^{Aᵀ(T−t)} W⁻¹ (xd − e^{AT} x0)``."""
    W = gramian(A, B, T)
    eta = np.linalg.solve(W, xd - expm(A * T) @ x0)
    energy = float((xd - expm(A * T) @ x0) @ eta)

    def u(t):
        return np.stack([B.T @ expm(A.T * (T - s)) @ eta for s in np.atleast_1d(t)])

    return energy, u


def linear_mechanism(name, A, B):
    """``ẋ = A x + B u`` from its equations (entries as exact decimals)."""
    n, m = B.shape
    x = sp.symbols(f"x1:{n + 1}", real=True)
    u = sp.symbols(f"w1:{m + 1}", real=True)
    exact = lambda a: sp.Rational(str(a))
    rates = [sum(exact(A[i, j]) * x[j] for j in range(n)) + sum(exact(B[i, k]) * u[k] for k in range(m))
             for i in range(n)]
    return Mechanism.from_equations(name, coordinates=x, inputs=u, rates=rates, cache=False)


def random_pair(rng, n, m, unstable):
    """A controllable pair ``(A, B)`` of 2-decimal entries, ``A`` with an eigenvalue of real part
    +0.5 (``unstable``) or all at most −0.5, its Gramian on ``[0, 1]`` conditioned below 1e8."""
    while True:
        A = rng.normal(size=(n, n))
        A = np.round(A - (max(np.linalg.eigvals(A).real) + (-0.5 if unstable else 0.5)) * np.eye(n), 2)
        B = np.round(rng.normal(size=(n, m)), 2)
        C = np.hstack([np.linalg.matrix_power(A, k) @ B for k in range(n)])
        stable = max(np.linalg.eigvals(A).real) < 0
        if (np.linalg.matrix_rank(C) == n and stable != unstable
                and np.linalg.cond(gramian(A, B, 1.0)) < 1e8):
            return A, B


def test_the_gramian_by_block_exponential_is_its_definition():
    rng = np.random.default_rng(0)
    A, B = random_pair(rng, 4, 2, True)
    by_quadrature, _ = quad_vec(lambda s: expm(A * s) @ B @ B.T @ expm(A.T * s), 0.0, 1.3, epsabs=1e-13)
    np.testing.assert_allclose(gramian(A, B, 1.3), by_quadrature, rtol=1e-10, atol=1e-12)


CASES = [(n, m, unstable) for n in range(2, 7) for m in (1, 2) for unstable in (False, True)]


@pytest.mark.slow
@pytest.mark.parametrize("n, m, unstable", CASES)
def test_least_energy_of_a_linear_system_is_the_closed_form(n, m, unstable):
    """``objective="energy"`` on a random controllable linear system: the energy within 1.0001×
    of the Gramian's, the controls within 1e-6 of the closed form (relative to their size)."""
    rng = np.random.default_rng(100 * n + 10 * m + unstable)
    A, B = random_pair(rng, n, m, unstable)
    x0, xd = rng.normal(size=n), rng.normal(size=n)
    mech = linear_mechanism(f"linear_{n}_{m}_{int(unstable)}", A, B)
    assert mech.has_drift
    result = nonholo.plan(x0, xd, mechanism=mech, T=1.0, objective="energy")
    assert result.success, result.reason
    least, u_star = closed_form(A, B, x0, xd, 1.0)
    t = np.linspace(0.0, 1.0, 401)
    u, ref = result.controls(t), u_star(t)
    energy = float(np.trapezoid(np.sum(result.controls(np.linspace(0, 1, 20001)) ** 2, axis=1),
                                np.linspace(0, 1, 20001)))
    assert least * (1 - 1e-6) <= energy <= 1.0001 * least, (energy, least)
    assert np.abs(u - ref).max() <= 1e-6 * max(1.0, np.abs(ref).max()), np.abs(u - ref).max()
    # the plan reaches the goal on the system itself, integrated apart from the planner
    sol = solve_ivp(lambda s, x: A @ x + B @ result.controls(np.array([s]))[0], (0.0, 1.0), x0,
                    method="DOP853", rtol=1e-12, atol=1e-12)
    assert np.abs(sol.y[:, -1] - xd).max() < 1e-8


def test_double_integrator_rest_to_rest_is_twelve_d_squared_over_T_cubed():
    d, T = 1.5, 2.0
    result = nonholo.plan([0, 0, 0, 0], [d, 0, 0, 0], mechanism="double_integrator", T=T, objective="energy")
    assert result.success, result.reason
    t = np.linspace(0.0, T, 801)
    # u(t) = 6d/T² (1 − 2t/T) along x, none along y
    np.testing.assert_allclose(result.controls(t)[:, 0], 6 * d / T ** 2 * (1 - 2 * t / T), atol=1e-8)
    np.testing.assert_allclose(result.controls(t)[:, 1], 0.0, atol=1e-8)
    energy = float(result.parametrisation.metric() @ result.parametrisation.params ** 2)
    assert energy == pytest.approx(12 * d ** 2 / T ** 3, rel=1e-9)


@pytest.mark.parametrize("name, start, goal, T", [
    ("double_integrator", [0, 0, 0, 0], [1, 0.5, 0, 0], 1.0),
    ("unicycle2", [0, 0, 0, 0, 0], [1, 0.5, 0.3, 0, 0], 5.0),
])
@pytest.mark.parametrize("objective", [None, "auto", "energy"])
def test_a_plan_with_drift_reaches_its_goal_in_a_replay_of_the_hand_written_model(name, start, goal, T, objective):
    result = nonholo.plan(start, goal, mechanism=name, T=T, objective=objective)
    assert result.success, result.reason
    _, _, q, _ = resimulate.resimulate_state(start, result.controls, T, name,
                                             breakpoints=result.parametrisation.breakpoints)
    assert np.abs(q[-1] - np.asarray(goal, dtype=float)).max() < 1e-8


@pytest.mark.parametrize("d, a_max", [(1.0, 1.0), (0.6, 0.25)])
def test_least_time_of_the_double_integrator_is_bang_bang(d, a_max):
    """Rest to rest over ``d`` with ``|a| ≤ a_max``: full thrust, then full braking, in
    ``T = 2 √(d / a_max)`` — whatever horizon the search starts from."""
    result = nonholo.plan([0, 0, 0, 0], [d, 0, 0, 0], mechanism="double_integrator", T=1.0, objective="time",
                          constraints=[InputBounds([-a_max, -a_max], [a_max, a_max])])
    assert result.success, result.reason
    assert result.T == pytest.approx(2 * np.sqrt(d / a_max), rel=1e-4)
    t = np.linspace(0.0, result.T, 2001)
    assert np.abs(result.controls(t)).max() <= a_max * (1 + 1e-9)


@pytest.mark.parametrize("d, a_max, v_max", [(1.0, 1.0, 0.5), (2.0, 0.5, 0.4)])
def test_least_time_of_the_double_integrator_under_a_speed_bound_coasts(d, a_max, v_max):
    """Rest to rest over ``d`` with ``|a| ≤ a_max`` and ``|v| ≤ v_max`` (a bound bang-bang
    would pass): full thrust to ``v_max``, a coast, full braking, in
    ``T = d / v_max + v_max / a_max``; the speed's bound is what the search meets first (from a
    horizon the bounds allow)."""
    result = nonholo.plan([0, 0, 0, 0], [d, 0, 0, 0], mechanism="double_integrator", T=4 * d / v_max, objective="time",
                          constraints=[InputBounds([-a_max, -a_max], [a_max, a_max]),
                                       StateBounds([-np.inf, -np.inf, -v_max, -v_max], [np.inf, np.inf, v_max, v_max])])
    assert result.success, result.reason
    assert result.T == pytest.approx(d / v_max + v_max / a_max, rel=1e-3)
    t, _, q, _ = resimulate.resimulate_state([0, 0, 0, 0], result.controls, result.T, "double_integrator",
                                             breakpoints=result.parametrisation.breakpoints)
    assert np.abs(q[-1] - [d, 0, 0, 0]).max() < 1e-8
    assert np.abs(result.controls(t)).max() <= a_max * (1 + 1e-9)
    assert np.abs(q[:, 2:]).max() <= v_max * (1 + 1e-6)


def test_controls_stretched_with_power_two_keep_a_rest_to_rest_path():
    """A double integrator's control from rest to rest read on another horizon at the same
    fraction, times ``(T0/T)²``, ends at the same place at rest (closed form: its position
    is the control's double integral)."""
    from nonholo.planning.least_time import stretched

    def u(t):
        t = np.atleast_1d(t)
        return np.stack([np.sin(2 * np.pi * t / 3.0), 0.3 * np.sin(4 * np.pi * t / 3.0)], axis=1)

    for T in (2.0, 4.5):
        v = stretched(u, 3.0, T, power=2)
        t = np.linspace(0.0, T, 200001)
        a = v(t)
        speed = np.concatenate([np.zeros((1, 2)), np.cumsum((a[1:] + a[:-1]) / 2 * np.diff(t)[:, None], axis=0)])
        place = np.sum((speed[1:] + speed[:-1]) / 2 * np.diff(t)[:, None], axis=0)
        # u's own: ∫₀³ (3 − s) u(s) ds
        s = np.linspace(0.0, 3.0, 200001)
        own = np.trapezoid((3.0 - s)[:, None] * u(s), s, axis=0)
        assert np.abs(speed[-1]).max() < 1e-6
        assert place == pytest.approx(own, abs=1e-6)


def test_least_time_of_the_second_order_unicycle_keeps_every_bound():
    """Dynobench's parallel park of ``unicycle2`` without its obstacles: accelerations and
    speeds within their bounds, replayed on the hand-written model."""
    start, goal = [0.7, 0.8, 0, 0, 0], [1.9, 0.3, 0, 0, 0]
    result = nonholo.plan(start, goal, mechanism="unicycle2", T=6.0, objective="time")
    assert result.success, result.reason
    assert 3.0 < result.T < 6.0
    t, _, q, _ = resimulate.resimulate_state(start, result.controls, result.T, "unicycle2",
                                             breakpoints=result.parametrisation.breakpoints)
    assert np.abs(q[-1] - goal).max() < 1e-8
    assert np.abs(result.controls(t)).max() <= 0.25 * (1 + 1e-9)
    assert np.abs(q[:, 3:]).max() <= 0.5 * (1 + 1e-9)


def test_input_bounds_shape_a_plan_with_drift_or_fail_it_saying_so():
    """In T = 6 s the plan as found leaves the bounds and, with drift, cannot be re-timed: the
    path of least use of them in T keeps them (checked by DOP853 on the hand-written
    model); in T = 4.5 s, below the least time (5.64 s), none does and the failure says so."""
    start, goal = [0.7, 0.8, 0, 0, 0], [1.9, 0.3, 0, 0, 0]
    result = nonholo.plan(start, goal, mechanism="unicycle2", T=6.0, constraints=of_mechanism("unicycle2"))
    assert result.success, result.reason
    assert "path of least use" in result.reason
    t, _, q, _ = resimulate.resimulate_state(np.asarray(start, dtype=float), result.controls, result.T, "unicycle2",
                                             breakpoints=result.parametrisation.breakpoints)
    assert np.abs(q[-1] - goal).max() < 1e-8
    assert np.abs(result.controls(t)).max() <= 0.25 * (1 + 1e-9)
    assert np.abs(q[:, 3:]).max() <= 0.5 * (1 + 1e-9)
    short = nonholo.plan(start, goal, mechanism="unicycle2", T=4.5, constraints=of_mechanism("unicycle2"))
    assert not short.success
    assert "cannot be re-timed into them" in short.reason and "objective='time'" in short.reason
    assert "needs more time" in short.reason


def test_what_a_time_change_cannot_do_with_drift_is_refused_saying_so():
    with pytest.raises(ValueError, match="T=None.*has drift"):
        nonholo.plan([0, 0, 0, 0], [1, 0, 0, 0], mechanism="double_integrator", T=None)
    result = nonholo.plan([0, 0, 0, 0], [1, 0, 0, 0], mechanism="double_integrator", objective=None)
    with pytest.raises(ValueError, match="result: .*has drift.*cannot be re-timed"):
        nonholo.retime(result, T=2.0, rest_to_rest=True)


def test_a_rate_not_affine_in_the_inputs_is_refused_naming_the_term():
    x, vel, a = sp.symbols("x vel a", real=True)
    with pytest.raises(ValueError, match=r"the rate of vel = .*its term a\*\*3 is not affine"):
        Mechanism.from_equations("cubic", coordinates=[x, vel], inputs=[a], rates=[vel, a ** 3 + x], cache=False)
    # a term in the input times the state is affine: the term named is the square
    with pytest.raises(ValueError, match=r"its term a\*\*2 is not affine"):
        Mechanism.from_equations("square", coordinates=[x, vel], inputs=[a], rates=[vel, a * x + a * a], cache=False)
    bilinear = Mechanism.from_equations("bilinear", coordinates=[x, vel], inputs=[a], rates=[vel, a * x], cache=False)
    assert bilinear.has_drift
    np.testing.assert_allclose(bilinear.rates(np.eye(3), [2.0, 3.0], [0.5]), [3.0, 1.0])


def test_drift_that_escapes_to_infinity_gives_a_failed_result_that_says_so(recwarn):
    x, y, u = sp.symbols("x y u", real=True)
    mech = Mechanism.from_equations("blowup", coordinates=[x, y], inputs=[u], rates=[x ** 2, u], cache=False)
    # x' = x² from x = 1 escapes at t = 1, before T, whatever the inputs
    result = nonholo.plan([1.0, 0.0], [5.0, 0.0], mechanism=mech, T=3.0)
    assert not result.success
    assert "the drift carried the state to infinity" in result.reason
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


def test_a_goal_off_the_reachable_set_gives_a_failed_result():
    x, y, u = sp.symbols("x y u", real=True)
    # y' = −y whatever the inputs: from y = 1 the goal's y = 1 is out of reach
    mech = Mechanism.from_equations("decaying", coordinates=[x, y], inputs=[u], rates=[u, -y], cache=False)
    result = nonholo.plan([0.0, 1.0], [1.0, 1.0], mechanism=mech, T=1.0)
    assert not result.success
    assert "did not decrease" in result.reason
