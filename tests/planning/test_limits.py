"""Stroke limits of the legs (``plan(..., constraints=[LegStroke(lo, hi)])``, nonholo/model/limits.py): plans
re-simulated independently (DOP853, dense path) stay inside them."""
import numpy as np
import pytest

from benchmarks import goalset
from nonholo.certify import certificate as certify
from nonholo.certify.resimulate import resimulate_path, terminal_error
from nonholo.io.result import PlanResult
from nonholo.model import catalog
from nonholo.model.limits import LegLimits
from nonholo.planning.api import plan
from nonholo.planning.settings import arguments_of
from nonholo.spaces import so3
from nonholo.constraints import LegStroke

PLATFORM = catalog.get("platform")
LIMITS = (1.2, 2.0)


def goal(gid):
    g = {g["id"]: g for g in goalset.load_goals()}[gid]
    return np.array(g["R0"]), np.array(g["Rd"])


def dense_legs(res):
    """Leg lengths along the plan's physical controls re-simulated by DOP853 (dense path)."""
    _, R, _ = resimulate_path(res.R0, res.controls, res.T, res.mechanism, res.breakpoints, samples=4001)
    return PLATFORM.leg_lengths(R), terminal_error(R[-1], res.Rd)


@pytest.mark.parametrize("gid", ["near-s0-01", "near-s2-07", "far-s1-04"])
@pytest.mark.parametrize("strategy", ["robust", "paper"])
@pytest.mark.slow
def test_plans_keep_the_legs_inside_their_stroke(gid, strategy, tmp_path):
    """Goals whose ends are inside the limits but whose unconstrained (robust) plan leaves them."""
    R0, Rd = goal(gid)
    free = plan(R0, Rd)
    lengths, _ = dense_legs(free)
    assert free.success and (lengths.min() < LIMITS[0] or lengths.max() > LIMITS[1])
    res = plan(R0, Rd, strategy=strategy, constraints=[LegStroke(*LIMITS)])
    if not res.success:
        assert strategy == "paper", res.reason       # the paper's algorithm has no barrier
        return
    lengths, err = dense_legs(res)
    assert err <= 1e-8
    assert lengths.min() >= LIMITS[0] and lengths.max() <= LIMITS[1]
    assert res.options["leg_length"] == list(LIMITS)
    res.save(tmp_path / "p.json")
    assert PlanResult.load(tmp_path / "p.json") == res


@pytest.mark.slow
def test_the_robust_strategy_solves_goals_json_inside_the_limits():
    """A slice of ``benchmarks/goals.json``: every goal whose ends are inside is solved."""
    solved = 0
    for g in goalset.load_goals()[::4]:
        R0, Rd = np.array(g["R0"]), np.array(g["Rd"])
        ends = np.concatenate([PLATFORM.leg_lengths(R0), PLATFORM.leg_lengths(Rd)])
        if g["band"] == "across" or ends.min() < LIMITS[0] or ends.max() > LIMITS[1]:
            continue
        res = plan(R0, Rd, constraints=[LegStroke(*LIMITS)])
        assert res.success, (g["id"], res.reason)
        lengths, err = dense_legs(res)
        assert err <= 1e-8 and lengths.min() >= LIMITS[0] and lengths.max() <= LIMITS[1], g["id"]
        solved += 1
    assert solved >= 5


def test_a_start_or_goal_outside_the_stroke_fails_at_once_naming_the_leg():
    R0 = so3.from_rpy(0.5, 1.2, -0.5)             # legs 1.33, 1.59
    Rd = so3.from_rpy(1.2, 0.9, -0.5)
    lo, hi = PLATFORM.leg_lengths(Rd)
    res = plan(R0, Rd, constraints=[LegStroke(1.2, lo - 0.1)])
    assert not res.success and len(res.t) == 0
    assert "the goal" in res.reason and "leg 1" in res.reason and "0.1 above" in res.reason
    res = plan(R0, Rd, constraints=[LegStroke(1.4, 2.5)])
    assert not res.success and "the start" in res.reason and "leg 1" in res.reason and "below" in res.reason


@pytest.mark.parametrize("bad, what", [((2.0, 1.2), "below hi"), ((-1.0, 2.0), "lo"), ((1.0, np.nan), "hi"),
                                       ((1.0,), "pair"), ("12", "pair"), ((1.0, "2"), "hi")])
def test_bad_limits_name_the_argument(bad, what):
    R0, Rd = so3.from_rpy(0.5, 1.2, -0.5), so3.from_rpy(1.0, 0.9, -0.5)
    with pytest.raises(ValueError, match="leg_length") as info:
        plan(R0, Rd, **arguments_of({"leg_length": bad}, "platform"))
    assert what in str(info.value)


def test_limits_for_a_mechanism_without_legs():
    with pytest.raises(ValueError, match="leg_length.*no legs"):
        plan(np.eye(3), so3.from_rpy(0.1, 0.2, 0.3), mechanism="attitude", constraints=[LegStroke(*LIMITS)])


def test_the_certificate_checks_the_replay_against_the_limits():
    """The same plan, certified against limits its replay leaves, is not certified."""
    R0, Rd = goal("near-s0-01")
    res = plan(R0, Rd)
    low = float(PLATFORM.leg_lengths(res.R).min())
    kw = dict(tol=1e-10, delta_min=1e-2, sign=float(np.sign(PLATFORM.delta(R0))))
    ok = certify.measure(res.start, res.goal, res.T, PLATFORM, res.parametrisation, res.replay_steps, **kw,
                         leg_limits=LegLimits(low - 1e-3, 3.0))
    assert ok.passed, ok.reason
    bad = certify.measure(res.start, res.goal, res.T, PLATFORM, res.parametrisation, res.replay_steps, **kw,
                          leg_limits=LegLimits(low + 1e-3, 3.0))
    assert not bad.passed and "stroke" in bad.reason and "lower" in bad.reason


def test_leg_clearance_barrier_terms_against_finite_differences():
    limits = LegLimits(1.2, 2.0)
    rng = np.random.default_rng(7)
    R = np.array([so3.exp(rng.normal(size=3)) for _ in range(40)])
    nodes, c, rows = limits.clearance_terms(PLATFORM, R, threshold=10.0)      # every clearance
    assert len(nodes) == 40 * 4
    eps = 1e-6
    for n, cn, g in zip(nodes[:12], c[:12], rows[:12]):
        s = rng.normal(size=3)
        cl = limits.clearances(PLATFORM, np.stack([so3.exp(eps * s) @ R[n], so3.exp(-eps * s) @ R[n]]))
        col = np.flatnonzero(np.isclose(limits.clearances(PLATFORM, R[n][None])[0], cn, rtol=0, atol=0))[0]
        assert abs((cl[0, col] - cl[1, col]) / (2 * eps) - g @ s) <= 1e-8


def test_cli_leg_length_and_its_figure(tmp_path, capsys):
    from nonholo.cli import main

    args = ["plan", "--from", "0.5", "1.2", "-0.5", "--to", "1.0", "0.9", "-0.5", "--quiet"]
    out, png = tmp_path / "p.json", tmp_path / "p.png"
    assert main(args + ["--leg-length", "1.2", "2.0", "--out", str(out), "--plot", str(png)]) == 0
    res = PlanResult.load(out)
    assert res.options["leg_length"] == [1.2, 2.0] and png.stat().st_size > 0
    assert main(args + ["--leg-length", "2.0", "1.2"]) == 2
    assert "--leg-length" in capsys.readouterr().err


def test_a_plan_file_cannot_claim_limits_its_motion_breaks():
    R0, Rd = goal("near-s0-01")
    res = plan(R0, Rd)
    d = res.to_dict()
    low = float(PLATFORM.leg_lengths(res.R).min())
    d["options"] = {**d["options"], "leg_length": [low + 0.01, 3.0]}
    with pytest.raises(ValueError, match="success.*stroke"):
        PlanResult.from_dict(d)
    d["options"]["leg_length"] = [low - 0.01, 3.0]
    assert PlanResult.from_dict(d).success
    d["options"]["leg_length"] = [3.0, 1.0]
    with pytest.raises(ValueError, match="options.*leg_length"):
        PlanResult.from_dict(d)


@pytest.mark.slow
def test_the_global_route_keeps_the_limits():
    """A far pair the local planner misses under the limits: the route's path, hops and
    stitched replay keep them."""
    p = {q["id"]: q for q in goalset.uniform_pairs("platform", 1000)}["uniform-platform-0027"]
    stroke = (1.0, 2.3)
    assert not plan(p["R0"], p["Rd"], route="local", constraints=[LegStroke(*stroke)]).success
    res = plan(p["R0"], p["Rd"], constraints=[LegStroke(*stroke)])
    assert res.success and res.route == "global", res.reason
    lengths, err = dense_legs(res)
    assert err <= 1e-8 and lengths.min() >= stroke[0] and lengths.max() <= stroke[1]
    for W in res.hops.waypoints:
        assert stroke[0] <= PLATFORM.leg_lengths(W).min() and PLATFORM.leg_lengths(W).max() <= stroke[1]
