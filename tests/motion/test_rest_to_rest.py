"""Rest-to-rest playback (``retime(result, rest_to_rest=True)``, nonholo/motion/time_scaling.py):
the played controls start and end at rest and, re-simulated by DOP853 (independent of the
planner's CF4), end within the plan's certificate; files round-trip and stay honest."""
import json

import numpy as np
import pytest
from conftest import assert_inputs_match

import nonholo
from nonholo.certify.resimulate import resimulate, resimulate_path, resimulate_state, terminal_error
from nonholo.io.csv_export import states_at
from nonholo.io.result import PlanResult
from nonholo.model import catalog
from nonholo.motion import time_scaling
from nonholo.motion.speed_limits import Retimed
from nonholo.planning.retime import retime
from nonholo.spaces import so3

R0, RD = so3.from_rpy(0.3, 0.2, 0.6), so3.from_rpy(0.3, 0.5, 0.6)


@pytest.fixture(scope="module")
def platform_plan():
    res = nonholo.plan(R0, RD)
    assert res.success, res.reason
    return res


@pytest.fixture(scope="module")
def car_plan():
    res = nonholo.plan(np.zeros(4), np.array([0.0, 1.0, 0.0, 0.0]), mechanism="car")
    assert res.success, res.reason
    return res


def test_smoothstep_and_its_inverse():
    s = np.linspace(0.0, 1.0, 1001)
    sigma, rate = time_scaling.smoothstep(s)
    assert sigma[0] == 0.0 and sigma[-1] == 1.0 and rate[0] == 0.0 and rate[-1] == 0.0
    # σ' against central differences of σ, and the peak ratio
    h = 1e-6
    fd = (time_scaling.smoothstep(s[1:-1] + h)[0] - time_scaling.smoothstep(s[1:-1] - h)[0]) / (2 * h)
    np.testing.assert_allclose(rate[1:-1], fd, atol=1e-8)
    assert rate.max() == pytest.approx(time_scaling.PEAK_RATIO, rel=1e-12)
    np.testing.assert_allclose(time_scaling.inverse_smoothstep(sigma), s, atol=2e-15)


def test_rest_to_rest_platform_starts_and_ends_at_rest_and_keeps_the_certificate(platform_plan):
    res = platform_plan
    rr = retime(res, T=7.0, rest_to_rest=True)
    assert rr.T == 7.0 and rr.success
    assert np.all(rr.controls(np.array([0.0, rr.T])) == 0.0)
    # the inputs' speed is continuous at the ends: u(t) = O(t²)
    eps = 1e-4 * rr.T
    assert np.max(np.abs(rr.controls(np.array([eps, rr.T - eps])))) <= 1e-6 * np.max(np.abs(rr.u))
    # DOP853 on the played controls ends where the plan's certificate says
    R_T = resimulate(rr.R0, rr.controls, rr.T, rr.mechanism, rr.breakpoints)
    assert terminal_error(R_T, res.Rd) <= res.error_bound + res.terminal_error + 1e-10
    # the played path is the planned one: R̃(t) = R(τ(t))
    t = np.linspace(0.0, rr.T, 9)
    R_played, _ = states_at(rr, t)
    R_planned, _ = states_at(res, time_scaling.planned_time(rr.parametrisation, t))
    assert max(terminal_error(a, b) for a, b in zip(R_played, R_planned)) <= 1e-12


def test_rest_to_rest_beyond_so3_keeps_the_certificate(car_plan):
    res = car_plan
    rr = retime(res, T=5.0, rest_to_rest=True)
    assert np.all(rr.controls(np.array([0.0, 5.0])) == 0.0)
    _, _, q, _ = resimulate_state(res.start, rr.controls, rr.T, "car", rr.breakpoints)
    errors = catalog.get("car").space.error((np.eye(3), q[-1]), (np.eye(3), res.qd))[1]
    assert errors["coordinates"] <= res.error_bound + 1e-9


def test_under_a_leg_speed_no_leg_exceeds_it(platform_plan):
    v = 0.5
    rr = retime(platform_plan, v, rest_to_rest=True)
    fastest = retime(platform_plan, v)
    assert rr.T == pytest.approx(time_scaling.PEAK_RATIO * fastest.T, rel=1e-12)
    assert isinstance(rr.parametrisation.base, Retimed) and rr.options["leg_speed"] == v
    t, R, _ = resimulate_path(rr.R0, rr.controls, rr.T, rr.mechanism, rr.breakpoints, samples=3001)
    speeds = np.abs(catalog.get("platform").leg_speeds(R, rr.controls(t)))
    assert speeds.max() <= v * (1 + 1e-5)
    assert speeds.max() >= 0.99 * v
    # a plan planned under a bound keeps it when played rest to rest
    assert retime(fastest, rest_to_rest=True).T == pytest.approx(rr.T, rel=1e-12)
    with pytest.raises(ValueError, match="needs"):
        retime(platform_plan, v, T=0.5 * rr.T, rest_to_rest=True)


def test_rest_to_rest_files_round_trip_and_stay_honest(platform_plan, car_plan, tmp_path):
    for i, rr in enumerate((retime(platform_plan, T=4.0, rest_to_rest=True),
                            retime(platform_plan, 0.5, rest_to_rest=True),
                            retime(car_plan, rest_to_rest=True))):
        path = rr.save(tmp_path / f"p{i}.json")
        back = PlanResult.load(path)
        assert back == rr
        # the loaded controls (frame nodes re-integrated) against the samples the re-timing
        # stored (the planner's nodes): two computations of the same inputs
        assert_inputs_match(back.controls(back.t), rr.u)
    d = json.loads((tmp_path / "p0.json").read_text())
    for edit, field in ((lambda d: d["controls"].update(T=-1.0), "controls.T"),
                        (lambda d: d["controls"].update(T=2 * d["T"]), "T"),
                        (lambda d: d["controls"].pop("base"), "controls"),
                        (lambda d: d.update(t=[x * 1.01 for x in d["t"]]), "t")):
        bad = json.loads(json.dumps(d))
        edit(bad)
        with pytest.raises(ValueError, match=field):
            PlanResult.from_dict(bad)


def test_rest_to_rest_of_a_rest_to_rest_plan_starts_from_its_planned_controls(platform_plan):
    once = retime(platform_plan, T=4.0, rest_to_rest=True)
    twice = retime(once, T=6.0, rest_to_rest=True)
    assert not isinstance(twice.parametrisation.base, time_scaling.RestToRest)
    assert twice.parametrisation.base == platform_plan.parametrisation
    with pytest.raises(ValueError, match="rest-to-rest already"):
        time_scaling.RestToRest(once.parametrisation, 1.0)


def test_bad_arguments_name_the_argument(platform_plan):
    with pytest.raises(ValueError, match="rest_to_rest"):
        retime(platform_plan, rest_to_rest="yes")
    with pytest.raises(ValueError, match="leg_speed"):
        retime(platform_plan)
    with pytest.raises(ValueError, match="T"):
        retime(platform_plan, T=-2.0, rest_to_rest=True)
    with pytest.raises(ValueError, match="leg_speed"):
        retime(nonholo.plan(np.zeros(4), np.array([0.0, 0.3, 0.0, 0.0]), mechanism="car"), 1.0,
               rest_to_rest=True)
