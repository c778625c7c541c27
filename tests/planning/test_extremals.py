"""Least energy by normal extremals (nonholo.planning.extremals): the costate read off a
motion, the shooting, and the least-energy plans it gives against closed forms."""
import numpy as np
import pytest
from conftest import example

import nonholo
from nonholo.certify.resimulate import resimulate_path
from nonholo.controls.parametrisations import PiecewiseConstant
from nonholo.integrate import system_kernels
from nonholo.model import catalog
from nonholo.planning import energy, extremals
from nonholo.planning.energy_objective import controls_energy
from nonholo.planning.problem import Problem
from nonholo.spaces import so3


def extremal(name, start, p0, steps=200, T=1.0):
    """The stage table and end of the extremal from ``start`` with costate ``p0``."""
    mech = catalog.get(name)
    kern = system_kernels.compile_system(mech.module)
    Rs, Qs = np.empty((steps + 1, 3, 3)), np.empty((steps + 1, mech.n_coordinates))
    Ps, U = np.empty((steps + 1, mech.n_rates)), np.empty((steps, 3, mech.n_inputs))
    n, _, _ = kern.extremal(*start, np.asarray(p0, float), T / steps, mech.singular.sign(*start), 1e-3,
                            Rs, Qs, Ps, U)
    assert n == steps
    return U, (Rs[-1], Qs[-1])


@pytest.mark.parametrize("name,p0", [("attitude", [0.4, -0.7, 0.3]), ("car", [0.5, -0.3, 0.4, 0.2]),
                                     ("unicycle", [0.8, -0.5, 0.6])])
def test_the_costate_of_an_extremal_is_read_back_off_its_motion(name, p0):
    """The projection of an extremal's own inputs (on 100 intervals) on the extremals
    through its motion gives back its initial costate, to the grid's resolution."""
    mech = catalog.get(name)
    start = (np.ascontiguousarray(example(1)[0]) if mech.space.has_orientation else np.eye(3),
             np.zeros(mech.n_coordinates) + (0.1 if mech.n_coordinates else 0.0))
    U, end = extremal(name, start, p0)
    values = extremals.grid_values(U, 100)
    problem = Problem.build(mech.space.public(start), mech.space.public(end), mechanism=name)
    endpoint = problem.evaluator(method="nonparametric", steps=200)
    guess = extremals.costate_guess(endpoint, PiecewiseConstant(1.0, values), 100)
    np.testing.assert_allclose(guess, p0, rtol=0, atol=2e-3 * np.linalg.norm(p0))


def test_shooting_finds_the_extremal_through_a_goal_from_a_nearby_costate():
    """The goal an extremal reaches, and a costate 10 % off: Newton brings the shot onto the
    goal, at the extremal's costate."""
    start = (np.eye(3), np.array([0.1, 0.1, 0.1, 0.1]))
    p0 = np.array([0.5, -0.3, 0.4, 0.2])
    _, end = extremal("car", start, p0, steps=100)
    problem = Problem.build(start[1], end[1], mechanism="car")
    shooting = extremals.Shooting(problem.evaluator(method="nonparametric", steps=100), 100)
    shot = shooting.solve(p0 * np.array([1.1, 0.9, 1.1, 0.9]), deadline=np.inf)
    assert shot.complete and shot.error <= extremals.SHOOTING_TOL
    np.testing.assert_allclose(shot.p0, p0, atol=1e-6)


def test_the_extremals_stop_after_a_run_of_starts_that_miss_the_goal():
    """After the first start (an extremal's own inputs, which reach the goal) come starts far
    from any extremal at it: no further start is taken once :data:`extremals.MISSES` in a
    row have missed, and the one at the goal is left unconfirmed."""
    start = (np.eye(3), np.array([0.1, 0.1, 0.1, 0.1]))
    U, end = extremal("car", start, [0.5, -0.3, 0.4, 0.2], steps=100)
    problem = Problem.build(start[1], end[1], mechanism="car")
    endpoint = problem.evaluator(method="nonparametric", steps=100)
    rng = np.random.default_rng(5)
    taken = []

    def initial():
        yield "extremal", PiecewiseConstant(1.0, extremals.grid_values(U, 100))
        for j in range(3 * extremals.MISSES):
            taken.append(j)
            yield f"far {j}", PiecewiseConstant(1.0, rng.normal(scale=8.0, size=(100, 2)))

    found = extremals.least_energy(endpoint, initial(), problem.options, 100, np.inf)
    assert found.reached and not found.confirmed and found.outcome is None
    assert "1 of 1 extremals" in found.why and len(taken) == extremals.MISSES


def test_attitude_least_energy_is_the_closed_form_extremal():
    """The closed-form extremal of the attitude mechanism (Boscain & Rossi 2008, energy
    a² + b²): reached by the extremal from the plan, within 0.05 % (100 constant intervals),
    and DOP853 confirms the goal."""
    a, b, c = 1.1, -0.7, 1.6
    R0 = so3.from_rpy(0.3, -0.5, 1.2)
    Rd = R0 @ so3.exp(np.array([a, b, c])) @ so3.exp(np.array([0.0, 0.0, -c]))
    res = nonholo.plan(R0, Rd, mechanism="attitude", objective="energy")
    assert res.success and "normal extremal" in res.reason, res.reason
    _, R, _ = resimulate_path(R0, res.controls, res.T, "attitude", res.breakpoints)
    assert np.linalg.norm(so3.log(R[-1] @ Rd.T)) <= 1e-8
    E = controls_energy(res.controls, res.breakpoints, res.T)
    assert a * a + b * b <= E <= 1.0005 * (a * a + b * b)


@pytest.mark.parametrize("a", [0.3, -1.0])
def test_brockett_least_energy_is_the_circle(a):
    """Brockett's integrator to (0, 0, a): a circle of energy 2π|a|, within 0.05 %."""
    res = nonholo.plan([0.0, 0.0, 0.0], [0.0, 0.0, a], mechanism="brockett", objective="energy")
    assert res.success, res.reason
    E = controls_energy(res.controls, res.breakpoints, res.T)
    assert 2 * np.pi * abs(a) * (1 - 1e-9) <= E <= 1.0005 * 2 * np.pi * abs(a)


def test_where_no_extremal_is_confirmed_the_search_runs(monkeypatch):
    """With the extremals given no budget the least-energy stage falls back to the search,
    which finds the same least energy on a platform goal (to 1e-5)."""
    R0, Rd = example(1)[0], example(1)[1]
    fast = nonholo.plan(R0, Rd, objective="energy")
    monkeypatch.setattr(energy, "EXTREMAL_EFFORT", 0.0)
    searched = nonholo.plan(R0, Rd, objective="energy")
    assert fast.success and searched.success
    assert "normal extremal" in fast.reason and "normal extremal" not in searched.reason
    assert controls_energy(fast.controls, fast.breakpoints, fast.T) == pytest.approx(
        controls_energy(searched.controls, searched.breakpoints, searched.T), rel=1e-5)


def test_the_default_takes_the_plans_extremal_only_where_it_needs_far_less():
    """``objective="auto"``: on a platform goal the plan is near its extremal and is kept as
    found (the same controls as ``objective=None``)."""
    R0, Rd = example(1)[0], example(1)[1]
    found = nonholo.plan(R0, Rd, objective=None)
    default = nonholo.plan(R0, Rd)
    assert default.success and np.array_equal(default.params, found.params)
