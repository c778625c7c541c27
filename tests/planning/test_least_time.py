"""``objective="time"``: the path of least time under input bounds (nonholo.planning.least_time),
re-timed to full use of the bounds. Checked by DOP853 on the mechanisms' own rates (the
vehicle-bounds tests' ``dop853``), by the inputs' use computed here, against the least time
along the plan as found (``T=None``) and against CasADi/IPOPT's free-time transcription."""
import importlib.util
import math

import numpy as np
import pytest
from test_vehicle_bounds import CAR_INPUTS, CAR_STATE, UNICYCLE_PARK, dop853, usage

import nonholo
from nonholo.constraints import InputBounds, LegSpeed, StateBounds
from nonholo.model import catalog
from nonholo.model.bounds import BOUND_RTOL

UNICYCLE_BOUNDS = InputBounds([-0.5, -0.5], [0.5, 0.5])
CAR_GOAL = [0.59, -0.06, -0.39, -0.22]


@pytest.fixture(scope="module")
def unicycle_fastest():
    return nonholo.plan(*UNICYCLE_PARK, mechanism="unicycle", objective="time", constraints=[UNICYCLE_BOUNDS])


@pytest.fixture(scope="module")
def car_fastest():
    return nonholo.plan(np.zeros(4), CAR_GOAL, mechanism="car", objective="time",
                        constraints=[CAR_INPUTS, CAR_STATE])


def test_the_unicycle_parks_in_less_than_2_95_s(unicycle_fastest):
    """Dynobench's obstacle-free unicycle park with |v|, |ω| ≤ 0.5: T ≤ 2.95 s, faster than the
    plan as found re-timed along its own path; DOP853 ends at the goal with the inputs within
    their bounds at full use."""
    res = unicycle_fastest
    assert res.success, res.reason
    assert res.options["objective"] == "time" and res.T <= 2.95
    along = nonholo.plan(*UNICYCLE_PARK, mechanism="unicycle", T=None, constraints=[UNICYCLE_BOUNDS])
    assert res.T < 0.9 * along.T
    t = np.linspace(0.0, res.T, 100001)
    use = usage(UNICYCLE_BOUNDS, np.asarray(res.controls(t), dtype=float))
    assert use.max() <= 1.0 + BOUND_RTOL and use.max() >= 1.0 - 1e-9
    _, x = dop853(res, catalog.get("unicycle"))
    assert np.max(np.abs(x[-1] - np.asarray(UNICYCLE_PARK[1]))) <= 1e-8


def test_the_car_keeps_its_steering_bound_on_the_fastest_path(car_fastest):
    """The car with |v| ≤ 1, |φ̇| ≤ 1 and |φ| ≤ 0.6: the fastest path rides the steering bound
    (within 1e-6 of it) and never passes it under DOP853, and beats the plan as found."""
    res = car_fastest
    assert res.success, res.reason
    _, x = dop853(res, catalog.get("car"))
    assert np.max(np.abs(x[-1] - np.asarray(CAR_GOAL))) <= 1e-8
    assert np.max(np.abs(x[:, 3])) <= 0.6 * (1.0 + BOUND_RTOL)
    assert np.max(np.abs(x[:, 3])) >= 0.6 - 1e-6
    along = nonholo.plan(np.zeros(4), CAR_GOAL, mechanism="car", T=None, constraints=[CAR_INPUTS, CAR_STATE])
    assert res.T < along.T


@pytest.mark.skipif(importlib.util.find_spec("casadi") is None, reason="CasADi not installed")
@pytest.mark.slow
def test_the_least_time_is_casadis_free_time_optimum(car_fastest):
    """The same problem transcribed for IPOPT (free T, the same 50 equal intervals, RK4
    substeps): the times agree within 1 % (both are local optima of the same problem)."""
    from benchmarks.optimality import casadi_car_time

    ok, T = casadi_car_time(np.zeros(4), np.asarray(CAR_GOAL), N=50)
    assert ok
    assert car_fastest.T <= 1.01 * T


def test_the_same_call_gives_the_same_path():
    """No clock inside: SLSQP runs a bounded number of iterations."""
    a = nonholo.plan(*UNICYCLE_PARK, mechanism="unicycle", objective="time", constraints=[UNICYCLE_BOUNDS])
    b = nonholo.plan(*UNICYCLE_PARK, mechanism="unicycle", objective="time", constraints=[UNICYCLE_BOUNDS])
    assert a.T == b.T and np.array_equal(a.params, b.params)


def test_the_platform_under_leg_speed_is_timed_along_its_least_energy_path():
    """The platform's legs' speed is no input bound: ``objective="time"`` with a LegSpeed
    re-times the least-energy path, at least as fast as ``T=None`` re-times the plan as
    found; DOP853 confirms the goal."""
    from conftest import example
    from nonholo.certify.resimulate import resimulate_path, terminal_error

    R0, Rd = example(1)
    fastest = nonholo.plan(R0, Rd, objective="time", constraints=[LegSpeed(1.0)])
    along = nonholo.plan(R0, Rd, T=None, constraints=[LegSpeed(1.0)])
    assert fastest.success and along.success
    assert fastest.T <= along.T
    _, R, _ = resimulate_path(R0, fastest.controls, fastest.T, "platform", fastest.breakpoints)
    assert terminal_error(R[-1], Rd) <= 1e-8


def test_time_needs_bounds():
    with pytest.raises(ValueError, match="objective='time'.*InputBounds"):
        nonholo.plan([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], mechanism="brockett", objective="time")
    with pytest.raises(ValueError, match="0.25 ≤ v ≤ 0.5 .* does not hold 0 inside"):
        nonholo.plan(*UNICYCLE_PARK, mechanism="unicycle", T=None,
                     constraints=[InputBounds([0.25, -0.5], [0.5, 0.5])])


@pytest.mark.parametrize("low,high,match", [([0.5, -0.5], [-0.5, 0.5], "low"), ([math.nan, -0.5], [0.5, 0.5], "nan"),
                                            ([-0.5], [0.5], "entries")])
def test_bad_bounds_name_the_argument(low, high, match):
    with pytest.raises(ValueError, match=match):
        nonholo.plan(*UNICYCLE_PARK, mechanism="unicycle", objective="time", constraints=[InputBounds(low, high)])


def test_a_start_outside_the_state_bounds_is_refused():
    with pytest.raises(ValueError, match="start"):
        nonholo.plan([0, 0, 0, 0.7], CAR_GOAL, mechanism="car", objective="time",
                     constraints=[CAR_INPUTS, StateBounds([-math.inf] * 3 + [-0.6], [math.inf] * 3 + [0.6])])
