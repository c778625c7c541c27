"""Re-timing under a bound on the legs' speeds (``plan(..., constraints=[LegSpeed(v)])``, ``nonholo.planning.retime``,
nonholo/motion/speed_limits.py): checked against independent DOP853 re-simulations of the re-timed
controls and an independent quadrature of the least time. Where the planned path nearly
stops (its fastest leg below the floor, ``FLOOR`` of its peak) the fastest leg is slower than
the bound, in the proportion of the planned speed to the floor; at the bound elsewhere."""
import json
from dataclasses import replace

import numpy as np
import pytest
from conftest import assert_inputs_match

import nonholo
from nonholo.certify.resimulate import resimulate_path, terminal_error
from nonholo.io.result import PlanResult
from nonholo.model import catalog
from nonholo.motion.speed_limits import Retimed
from nonholo.planning.api import plan
from nonholo.planning.retime import retime, time_map
from nonholo.spaces import so3
from nonholo import Settings
from nonholo.constraints import LegSpeed, LegStroke

PLATFORM = catalog.get("platform")
R0 = so3.from_rpy(0.3, 0.2, 0.6)
RD = so3.from_rpy(0.3, 0.5, 0.6)
V = 0.5


def dense(res, samples=4001):
    """``(t, R, fastest leg speed)`` along ``res``'s controls re-simulated by DOP853 (dense)."""
    t, R, _ = resimulate_path(res.R0, res.controls, res.T, res.mechanism, res.breakpoints,
                              samples=samples)
    speeds = np.abs(PLATFORM.leg_speeds(R, res.controls(t)))
    return t, R, speeds.max(axis=1)


def share_of_bound(timed, t, R, base):
    """The fastest leg's speed over the bound's that the re-timing promises at re-timed times
    ``t`` (orientations ``R``): ``min(1, s/floor)``, ``s`` the planned path's fastest leg speed
    at ``τ(t)`` (the planned controls ``base`` at the re-simulated orientations)."""
    tau = timed.tau(t)[0]
    planned = np.abs(PLATFORM.leg_speeds(R, base(tau))).max(axis=1)
    return np.minimum(1.0, planned / timed.map.floor)


@pytest.fixture(scope="module")
def plans():
    """The plans as found (``objective=None``): the paths the re-timing is tried on."""
    return {(s, m): plan(R0, RD, strategy=s, settings=Settings(method=m), objective=None)
            for s, m in (("robust", "parametric"), ("robust", "nonparametric"), ("paper", "parametric"))}


@pytest.mark.parametrize("key", [("robust", "parametric"), ("robust", "nonparametric"), ("paper", "parametric")])
@pytest.mark.slow
def test_least_time_keeps_the_path_with_the_fastest_leg_at_the_bound(plans, key):
    res = plans[key]
    if not res.success:
        pytest.skip(f"{key} does not solve this goal")
    fast = retime(res, V)
    assert isinstance(fast.parametrisation, Retimed) and fast.success
    t, R, fastest = dense(fast)
    # the same path: the end orientation is the plan's, within 1e-10 rad
    assert terminal_error(R[-1], res.R[-1]) <= 1e-10
    # the fastest leg at the bound: at most v, v itself within 1e-6 — or the planned speed's
    # share of the floor where the path nearly stops (a jump of grid controls is an instant
    # where the speed changes: its samples are left out)
    assert fastest.max() == pytest.approx(V, rel=1e-6)
    bp = fast.breakpoints
    away = np.min(np.abs(t[:, None] - bp[None, :]), axis=1) > 1e-9
    timed = fast.parametrisation
    share = share_of_bound(timed, t, R, timed.base)
    np.testing.assert_allclose(fastest[away], V * share[away], rtol=1e-6)
    # the least time against an independent quadrature of max(max_i |dl_i/dτ|, floor) / v
    # along the plan: the trapezoid rule on the DOP853 samples, each interval with its own side
    # of a jump
    tau, Rp, _ = resimulate_path(res.R0, res.controls, res.T, res.mechanism, res.breakpoints,
                                 samples=20001)
    a, b = np.flatnonzero(np.diff(tau) > 0), np.flatnonzero(np.diff(tau) > 0) + 1
    eps = 1e-12
    floor = timed.map.floor
    speed_a = np.maximum(np.abs(PLATFORM.leg_speeds(Rp[a], res.controls(tau[a] + eps))).max(axis=1), floor)
    speed_b = np.maximum(np.abs(PLATFORM.leg_speeds(Rp[b], res.controls(tau[b] - eps))).max(axis=1), floor)
    need = np.sum(0.5 * (speed_a + speed_b) * (tau[b] - tau[a])) / V
    assert fast.T == pytest.approx(need, rel=1e-7)
    assert fast.options["leg_speed"] == V and "re-timed in the least time" in fast.reason


@pytest.mark.slow
def test_a_given_time_scales_the_least_time_map_or_fails_saying_the_time_needed(plans):
    res = plans[("robust", "parametric")]
    fastest_map = time_map(res, V)
    need = fastest_map.minimum_time
    assert 1.0 < need < fastest_map.peak_ratio        # planned in T = 1, its legs are too fast
    slow = retime(res, V, T=2 * need)
    assert slow.success and slow.T == 2 * need and isinstance(slow.parametrisation, Retimed)
    t, R, fastest = dense(slow)
    share = share_of_bound(slow.parametrisation, t, R, slow.parametrisation.base)
    np.testing.assert_allclose(fastest, V / 2 * share, rtol=1e-6)
    assert terminal_error(R[-1], res.R[-1]) <= 1e-10
    short = plan(R0, RD, T=1.0, constraints=[LegSpeed(V)], objective=None)
    assert not short.success and f"{need:.6g} s" in short.reason
    # planned in T, a plan breaking the bound is re-timed in T when its path allows
    T = 0.5 * (need + fastest_map.peak_ratio)
    within = plan(R0, RD, T=T, constraints=[LegSpeed(V)], objective=None)
    assert within.success and within.T == T and dense(within)[2].max() <= V * (1 + 1e-6)
    # a plan that keeps to the bound as planned is returned as planned
    easy = plan(R0, RD, T=1.0, constraints=[LegSpeed(10.0)], objective=None)
    assert easy.success and not isinstance(easy.parametrisation, Retimed)
    assert easy.options["leg_speed"] == 10.0 and dense(easy)[2].max() <= 10.0
    with pytest.raises(ValueError, match="too short"):
        retime(res, V, T=0.5 * need)


def test_retimed_plans_round_trip_and_their_files_stay_honest(plans, tmp_path):
    fast = retime(plans[("robust", "nonparametric")], V)
    fast.save(tmp_path / "p.json")
    back = PlanResult.load(tmp_path / "p.json")
    assert back == fast and back.T == fast.T
    # the loaded controls (frame nodes re-integrated) against the samples the re-timing stored
    # (the planner's nodes): two computations of the same inputs
    assert_inputs_match(back.controls(back.t), fast.u)
    d = json.loads((tmp_path / "p.json").read_text())
    for edit, field in ((lambda d: d["options"].update(leg_speed=0.4), "options"),
                        (lambda d: d["controls"].update(leg_speed=0.4), "t"),
                        (lambda d: d["controls"].update(T=0.5 * d["T"]), "controls"),
                        (lambda d: d.update(t=[x * 1.01 for x in d["t"]]), "t")):
        bad = json.loads(json.dumps(d))
        edit(bad)
        with pytest.raises(ValueError, match=field):
            PlanResult.from_dict(bad)
    # re-timing a re-timed plan starts from its base
    again = retime(fast, 2 * V)
    # (the same controls, as a plan file rebuilds them: not a re-timing of the re-timed ones)
    assert not isinstance(again.parametrisation.base, Retimed)
    assert again.parametrisation.base.to_dict() == fast.parametrisation.base.to_dict()
    assert again.T == pytest.approx(fast.T / 2, rel=1e-12)


def test_csv_of_a_retimed_plan_plays_the_legs_at_the_bound(plans, tmp_path):
    fast = retime(plans[("robust", "parametric")], V)
    fast.to_csv(tmp_path / "p.csv", rate=200)
    rows = np.loadtxt(tmp_path / "p.csv", delimiter=",", skiprows=1)
    header = (tmp_path / "p.csv").read_text().splitlines()[0].split(",")
    col = {name: rows[:, i] for i, name in enumerate(header)}
    assert col["t"][-1] == fast.T
    speed = np.maximum(np.abs(col["dl1_dt"]), np.abs(col["dl2_dt"]))
    timed = fast.parametrisation
    # the planned speed at τ(t) is the re-timed one over dτ/dt
    share = np.minimum(1.0, speed / timed.tau(col["t"])[1] / timed.map.floor)
    np.testing.assert_allclose(speed, V * share, rtol=1e-6)
    assert (share == 1.0).mean() > 0.9
    # the exported orientation is the plan's at the re-timed instant
    q = np.column_stack([col["qx"], col["qy"], col["qz"], col["qw"]])
    from scipy.spatial.transform import Rotation
    R_end = Rotation.from_quat(q[-1]).as_matrix()
    assert terminal_error(R_end, fast.R[-1]) <= 1e-12


def test_legs_stroke_and_speed_together():
    res = plan(R0, RD, constraints=[LegStroke(0.7, 2.0), LegSpeed(V)], T=None)
    assert res.success, res.reason
    _, R, fastest = dense(res)
    lengths = PLATFORM.leg_lengths(R)
    assert lengths.min() >= 0.7 and lengths.max() <= 2.0
    assert fastest.max() == pytest.approx(V, rel=1e-6)


@pytest.mark.parametrize("kwargs, match", [
    (dict(constraints=[LegSpeed(-1.0)]), "leg_speed"), (dict(constraints=[LegSpeed(0.0)]), "leg_speed"),
    (dict(constraints=[LegSpeed(float("nan"))]), "leg_speed"), (dict(constraints=[LegSpeed("fast")]), "leg_speed"),
    (dict(constraints=[LegSpeed(True)]), "leg_speed"),
    (dict(constraints=[LegSpeed(1.0)], mechanism="attitude"), "leg_speed"),
    (dict(T=None), "LegSpeed"), (dict(T=-1.0, constraints=[LegSpeed(1.0)]), "T"),
])
def test_bad_speed_bounds_name_the_argument(kwargs, match):
    with pytest.raises(ValueError, match=match):
        plan(R0, RD, **kwargs)


def test_retime_refuses_failed_plans_and_bad_arguments(plans):
    res = plans[("robust", "parametric")]
    failed = replace(res, success=False, reason="made up")
    with pytest.raises(ValueError, match="failed: made up"):
        nonholo.retime(failed, V)
    with pytest.raises(ValueError, match="leg_speed"):
        nonholo.retime(res, float("inf"))
    with pytest.raises(ValueError, match="T"):
        nonholo.retime(res, V, T=0.0)
