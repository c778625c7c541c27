"""The normal extremals' kernel: against DOP853 on the Hamiltonian system written from the
generated fields (the state's nine entries of R, no Lie-group step), its order, and the
extremal's first-order conditions against the planner's own variational Jacobian."""
import numpy as np
import pytest
from conftest import example
from scipy.integrate import solve_ivp

from nonholo.controls.parametrisations import PiecewiseConstant
from nonholo.integrate import system_kernels
from nonholo.model import catalog
from nonholo.planning.problem import Problem
from nonholo.spaces import so3

#: A start and an initial costate per mechanism (clear of Δ = 0 for T = 1).
CASES = {
    "attitude": ((np.ascontiguousarray(example(1)[0]), np.zeros(0)), [0.4, -0.7, 0.3]),
    "platform": ((np.ascontiguousarray(example(1)[0]), np.zeros(0)), [0.02, -0.01, 0.01]),
    "car": ((np.eye(3), np.array([0.1, 0.2, 0.3, 0.2])), [0.5, -0.3, 0.4, 0.2]),
    "rolling_ball": ((so3.exp(np.array([0.3, -0.2, 0.5])), np.array([0.1, -0.2])), [0.3, 0.2, -0.4, 0.5, -0.1]),
    "brockett": ((np.eye(3), np.array([0.1, -0.2, 0.3])), [0.5, -0.4, 1.5]),
    "unicycle": ((np.eye(3), np.array([0.1, -0.2, 0.3])), [0.8, -0.5, 0.6]),
}


def run(name, p0, steps, T=1.0):
    mech = catalog.get(name)
    (R0, q0), p0 = CASES[name][0], np.asarray(p0, dtype=float)
    kern = system_kernels.compile_system(mech.module)
    Rs, Qs = np.empty((steps + 1, 3, 3)), np.empty((steps + 1, mech.n_coordinates))
    Ps, U = np.empty((steps + 1, mech.n_rates)), np.empty((steps, 3, mech.n_inputs))
    sgn = mech.singular.sign(R0, q0)
    n, dmin, t_stop = kern.extremal(R0, q0, p0, T / steps, sgn, 1e-3, Rs, Qs, Ps, U)
    assert n == steps and t_stop == -1.0
    return Rs, Qs, Ps, U


def hamiltonian(mech):
    """``d/dt (vec R, q, p)`` of the normal extremal: ``u = Gᵀp``, ``Ṙ = [ω]R``,
    ``q̇ = G_q u``, ``ṗ = −(QG(u) + [ω] ⊕ 0)ᵀ p``, from the generated ``G`` and ``QG``."""
    mod, k, d = mech.module, mech.n_coordinates, mech.n_rates
    rot = 3 if mod.ORIENTATION else 0

    def f(_, y):
        R = y[:9].reshape(3, 3)
        q, p = y[9:9 + k], y[9 + k:]
        G = mod.G(R, q)
        u = G.T @ p
        rates = G @ u
        A = mod.QG(R, q, u)
        dR = np.zeros((3, 3))
        if rot:
            A[:3, :3] += so3.hat(rates[:3])
            dR = so3.hat(rates[:3]) @ R
        return np.concatenate([dR.ravel(), rates[rot:], -A.T @ p])

    return f


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_extremal_agrees_with_dop853_on_the_hamiltonian_system(name):
    """State, costate and inputs at T = 1 against DOP853 (rtol = atol = 1e-12) on the
    nine entries of R: within 1e-8 on 400 steps."""
    mech = catalog.get(name)
    (R0, q0), p0 = CASES[name]
    Rs, Qs, Ps, U = run(name, p0, 400)
    y0 = np.concatenate([R0.ravel(), q0, p0])
    sol = solve_ivp(hamiltonian(mech), (0.0, 1.0), y0, method="DOP853", rtol=1e-12, atol=1e-12)
    k = mech.n_coordinates
    R, q, p = sol.y[:9, -1].reshape(3, 3), sol.y[9:9 + k, -1], sol.y[9 + k:, -1]
    scale = 1.0 + np.abs(p).max()
    np.testing.assert_allclose(Rs[-1], R, atol=1e-8)
    np.testing.assert_allclose(Qs[-1], q, atol=1e-8)
    np.testing.assert_allclose(Ps[-1], p, atol=1e-8 * scale)
    np.testing.assert_allclose(U[-1, 2], mech.module.G(R, q).T @ p, atol=1e-8 * scale)


@pytest.mark.parametrize("name", ["rolling_ball", "car"])
def test_the_scheme_is_of_order_four(name):
    """Halving the step divides the endpoint's error (from a run on 16× the steps) by about 16."""
    p0 = CASES[name][1]
    ref = run(name, p0, 1600)
    errors = []
    for steps in (50, 100):
        Rs, Qs, Ps, _ = run(name, p0, steps)
        errors.append(max(np.abs(Rs[-1] - ref[0][-1]).max(), np.abs(Ps[-1] - ref[2][-1]).max(),
                          np.abs(Qs[-1] - ref[1][-1]).max()))
    assert 12.0 < errors[0] / errors[1] < 20.0


@pytest.mark.parametrize("name", ["attitude", "car", "rolling_ball"])
def test_an_extremal_is_stationary_for_the_energy_with_its_end_fixed(name):
    """The extremal's inputs as controls on a fine grid: the energy's gradient ``2Mλ`` lies
    in the row space of the endpoint Jacobian of the planner's variational system (an
    independent integrator and derivative) up to the grid's resolution."""
    mech = catalog.get(name)
    (R0, q0), p0 = CASES[name]
    grid, steps = 400, 800
    _, _, _, U = run(name, p0, steps)
    values = ((U[:, 0] + 4 * U[:, 1] + U[:, 2]) / 6).reshape(grid, -1, mech.n_inputs).mean(axis=1)
    start = mech.space.public((R0, q0))
    problem = Problem.build(start, start, mechanism=name)
    endpoint = problem.evaluator(method="nonparametric", steps=steps)
    controls = PiecewiseConstant(1.0, values)
    ev = endpoint.evaluate(controls)
    grad = 2 * controls.metric() * controls.params
    nu, *_ = np.linalg.lstsq(ev.J.T, grad, rcond=None)
    assert np.linalg.norm(grad - ev.J.T @ nu) <= 1e-4 * np.linalg.norm(grad)
    # and not so for a control that is no extremal: the same inputs sped up along the way
    flipped = PiecewiseConstant(1.0, values * np.linspace(0.5, 1.5, grid)[:, None])
    ev = endpoint.evaluate(flipped)
    grad = 2 * flipped.metric() * flipped.params
    nu, *_ = np.linalg.lstsq(ev.J.T, grad, rcond=None)
    assert np.linalg.norm(grad - ev.J.T @ nu) > 1e-2 * np.linalg.norm(grad)
