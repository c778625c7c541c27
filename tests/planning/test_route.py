"""The global route's parts: paths of orientations on the roadmap (nonholo/planning/roadmap.py) and
stitched controls (nonholo/controls/stitched.py)."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from benchmarks import goalset
from conftest import far_pair, rk4_check
from conftest import assert_inputs_match
from nonholo import mechanism_named
from nonholo.certify.resimulate import resimulate, resimulate_rk4, terminal_error
from nonholo.controls import stages
from nonholo.controls.parametrisations import Fourier
from nonholo.controls.stitched import Stitched
from nonholo.model import catalog
from nonholo.motion import frame_controls as replay
from nonholo.motion import simulation
from nonholo.motion.frame_controls import FrameControls
from nonholo.planning.api import plan
from nonholo.planning import roadmap, route, route_paths, route_smoothing
from nonholo.spaces import so3


def dense_delta(mech, path, step=0.005):
    """``Δ`` along the geodesics of ``path``, every ``step`` rad (finer than the roadmap's check)."""
    out = []
    for Ra, Rb in zip(path[:-1], path[1:]):
        k = max(2, int(np.ceil(so3.distance(Ra, Rb) / step)) + 1)
        out.append(mech.delta_samples(so3.geodesic(Ra, Rb, np.linspace(0.0, 1.0, k))))
    return np.concatenate(out)


def test_geodesic_ends_and_constant_speed():
    rng = np.random.default_rng(0)
    Ra, Rb = so3.exp(rng.normal(size=3)), so3.exp(rng.normal(size=3))
    R = so3.geodesic(Ra, Rb, [0.0, 0.25, 0.5, 1.0])
    np.testing.assert_allclose(R[0], Ra, atol=1e-12)
    np.testing.assert_allclose(R[-1], Rb, atol=1e-12)
    d = so3.distance(Ra, Rb)
    assert so3.distance(Ra, R[1]) == pytest.approx(0.25 * d, abs=1e-9)
    assert so3.distance(R[2], Rb) == pytest.approx(0.5 * d, abs=1e-9)


@pytest.mark.parametrize("mechanism", ["platform", "platform_raised"])
def test_paths_stay_in_the_component_with_short_hops(mechanism):
    """Every uniform pair of a slice gets a path: R0 first, Rd last, hops ≤ max_hop, and
    Δ of the start's sign, never below delta_min, on a check five times finer."""
    mech = catalog.get(mechanism)
    for p in goalset.uniform_pairs(mechanism, 40):
        path = roadmap.orientation_path(mech, p["R0"], p["Rd"], max_hop=0.6)
        assert path is not None
        np.testing.assert_array_equal(path[0], p["R0"])
        np.testing.assert_allclose(path[-1], p["Rd"], atol=1e-12)
        hops = [so3.distance(a, b) for a, b in zip(path[:-1], path[1:])]
        assert max(hops) <= 0.6 + 1e-9
        sign = np.sign(mech.delta(p["R0"]))
        assert np.min(sign * dense_delta(mech, path)) >= 1e-2


def test_across_the_singular_surface_there_is_no_path():
    mech = catalog.get("platform")
    p = goalset.uniform_pairs("platform", 1)[0]
    R0 = np.asarray(p["R0"])
    for R in (so3.from_rpy(0.3, 0.2, 0.1), so3.from_rpy(-0.4, 0.5, 0.2), so3.from_rpy(2.0, -0.3, 0.4)):
        if np.sign(mech.delta(R)) != np.sign(mech.delta(R0)):
            assert roadmap.orientation_path(mech, R0, R) is None
            return
    pytest.skip("no orientation of the other sign among the candidates")


def test_roadmap_is_the_same_in_every_build():
    mech = catalog.get("platform")
    a = roadmap.Roadmap(mech, 0.1, samples=500)
    b = roadmap.Roadmap(mech, 0.1, samples=500)
    np.testing.assert_array_equal(a.R, b.R)
    np.testing.assert_array_equal(a.edges, b.edges)
    assert np.all(np.abs(mech.delta_samples(a.R)) >= 0.1)


def test_without_a_singular_set_the_path_is_the_geodesic():
    p = goalset.uniform_pairs("attitude", 1)[0]
    path = roadmap.orientation_path(mechanism_named("attitude"), p["R0"], p["Rd"], max_hop=0.5)
    d = so3.distance(p["R0"], p["Rd"])
    assert len(path) - 1 == int(np.ceil(d / 0.5))
    total = sum(so3.distance(a, b) for a, b in zip(path[:-1], path[1:]))
    assert total == pytest.approx(d, abs=1e-9)


def two_pieces():
    """Two plans of Example-like hops, the second from where the first's replay ends."""
    mech = catalog.get("platform")
    p = goalset.uniform_pairs("platform", 3)[2]
    path = roadmap.orientation_path(mech, p["R0"], p["Rd"], max_hop=0.6)
    a = plan(path[0], path[1], T=0.7)
    b = plan(a.R_T, path[2], T=0.4)
    assert a.success and b.success, (a.reason, b.reason)
    return mech, path, a, b


@pytest.mark.slow
def test_stitched_controls_retime_their_pieces():
    """``u`` on slot i is the piece's, sped up by c_i = T_i/τ; a simulation of the
    stitched control passes through each piece's end (driftless: re-timing keeps the path)."""
    mech, path, a, b = two_pieces()
    s = Stitched(2.0, [a.parametrisation, b.parametrisation], [path[0], path[1], path[2]])
    assert s.slot == 1.0 and list(s.segment_times) == [0.0, 1.0, 2.0]
    t = np.array([0.25, 0.5, 1.5, 1.75])
    np.testing.assert_allclose(s(t[:2]), 0.7 * a.controls(0.7 * t[:2]), rtol=1e-12)
    np.testing.assert_allclose(s(t[2:]), 0.4 * b.controls(0.4 * (t[2:] - 1.0)), rtol=1e-12)
    # the integrator's table is the pieces' tables, scaled
    U = stages.stage_table(s, 800)
    np.testing.assert_allclose(U[:400], 0.7 * stages.stage_table(a.parametrisation, 400), rtol=1e-12)
    tr = simulation.simulate(path[0], s, 2.0, mechanism=mech, steps=2 * a.replay_steps)
    assert so3.distance(tr.R[a.replay_steps], a.R_T) < 1e-9
    RT = resimulate(path[0], s, 2.0, mech, s.breakpoints)
    assert so3.distance(RT, b.R_T) < 1e-9


@pytest.mark.slow
def test_stitched_controls_round_trip_and_refuse_bad_input():
    mech, path, a, b = two_pieces()
    s = Stitched(2.0, [a.parametrisation, b.parametrisation], [path[0], path[1], path[2]])
    back = replay.from_dict(s.to_dict(), mech)
    assert back == s
    t = np.linspace(0.0, 2.0, 41)
    # the pieces are frame controls: the loaded ones re-integrate their nodes (forward kernel),
    # the planner's hold those of its variational kernel: two computations of the same inputs
    assert_inputs_match(back(t), s(t))
    with pytest.raises(ValueError, match="waypoints"):
        Stitched(2.0, [a.parametrisation], [path[0]])
    with pytest.raises(ValueError, match="at least one piece"):
        Stitched(2.0, [], [path[0]])
    with pytest.raises(ValueError, match="inputs"):
        Stitched(1.0, [a.parametrisation, Fourier(1.0, np.zeros((3, 5)))], path[:3])
    with pytest.raises(ValueError, match="multiple"):
        stages.stage_table(Stitched(2.0, [a.parametrisation, b.parametrisation], path[:3]), 3)


# -- the global route of plan() --------------------------------------------------------------

#: a uniform pair (platform) whose goal the local planner misses


@pytest.mark.slow
def test_global_route_reaches_a_goal_the_local_planner_misses(tmp_path):
    p = far_pair()
    local = plan(p["R0"], p["Rd"], route="local")
    assert not local.success and local.route == "local"
    res = plan(p["R0"], p["Rd"])                  # the default route: "auto"
    assert res.success and res.route == "global", res.reason
    check_global_result(res, p, tmp_path)
    # by default the stitched route is re-planned as one smooth control
    assert isinstance(res.stitched, Stitched) and res.hops is res.stitched
    assert isinstance(res.parametrisation, FrameControls)
    assert res.parametrisation.frame.harmonics in route_smoothing.SMOOTHING_HARMONICS
    assert None in {rec["hop"] for rec in res.history}


@pytest.mark.slow
def test_a_route_that_is_not_smoothed_keeps_the_stitched_control(tmp_path, monkeypatch):
    monkeypatch.setattr(route_smoothing, "SMOOTHING_HARMONICS", ())
    p = far_pair()
    res = plan(p["R0"], p["Rd"])
    assert res.success and res.route == "global", res.reason
    assert res.stitched is None and res.hops is res.parametrisation
    check_global_result(res, p, tmp_path)
    assert {rec["hop"] for rec in res.history} == set(range(res.hops.n_pieces))


def check_global_result(res, p, tmp_path):
    """A certified global route: hops, independent re-simulations, waypoints, save/load."""
    assert isinstance(res.hops, Stitched) and res.hops.n_pieces >= 2
    assert res.terminal_error + res.error_bound <= res.options["tol"]
    assert set(range(res.hops.n_pieces)) <= {rec["hop"] for rec in res.history}
    # independent re-simulations of controls(t): DOP853 stopping at every breakpoint, and RK4
    RT = resimulate(p["R0"], res.controls, res.T, "platform", res.breakpoints)
    assert terminal_error(RT, p["Rd"]) <= 1e-8
    rk4, dmin = resimulate_rk4(p["R0"], res.parametrisation, res.T, "platform",
                               steps=res.steps * -(-6400 // res.steps))
    assert terminal_error(rk4, p["Rd"]) <= 1e-8 and dmin >= res.options["delta_min"]
    # the route's waypoints start at R0 and end at Rd; the file keeps everything
    W = res.hops.waypoints
    np.testing.assert_array_equal(W[0], p["R0"])
    np.testing.assert_allclose(W[-1], p["Rd"], atol=1e-12)
    path = tmp_path / "far.json"
    res.save(path)
    back = type(res).load(path)
    assert back == res and back.route == "global" and back.hops == res.hops


@pytest.mark.slow
def test_stitched_planned_coordinates_are_the_hops_own_retimed():
    """``Stitched.planned``: piece ``i``'s planned (frame) control, re-timed into slot ``i``;
    the physical ``u`` follows from it along the motion (``u = W(R) w``)."""
    p = far_pair()
    res = plan(p["R0"], p["Rd"], route="global")
    st = res.hops
    t = np.linspace(0.0, st.T, 301)[:-1]
    i = np.floor(t / st.slot).astype(int)
    w = st.planned(t)
    for j, piece in enumerate(st.pieces):
        c = piece.T / st.slot
        sel = i == j
        np.testing.assert_allclose(w[sel], c * piece.frame(c * (t[sel] - j * st.slot)), rtol=0, atol=1e-14)
        np.testing.assert_allclose(st(t[sel]), c * piece(c * (t[sel] - j * st.slot)), rtol=0, atol=1e-12)


@pytest.mark.slow
def test_plan_files_keep_the_smoothed_route_honest():
    """``stitched`` only with a one-piece control on a global route, of the plan's T and R0."""
    from dataclasses import replace

    from nonholo.certify.plan_fields import FORMAT_2
    from nonholo.io.result import PlanResult

    p = far_pair()
    res = plan(p["R0"], p["Rd"])
    assert res.stitched is not None
    d = res.to_dict()
    with pytest.raises(ValueError, match="route"):
        PlanResult.from_dict({**d, "route": "local"})
    with pytest.raises(ValueError, match="stitched"):
        PlanResult.from_dict({**d, "stitched": d["controls"]})
    with pytest.raises(ValueError, match="stitched"):
        PlanResult.from_dict({**d, "stitched": {**d["stitched"], "T": 2.0}})
    with pytest.raises(ValueError, match="stitched"):
        PlanResult.from_dict({**{k: v for k, v in d.items() if k != "route"}, "format": FORMAT_2})
    with pytest.raises(ValueError, match="stitched"):
        replace(res, parametrisation=res.stitched).validate()
    assert PlanResult.from_dict(d) == res


def test_route_global_for_a_mechanism_without_a_singular_set():
    p = goalset.uniform_pairs("attitude", 3)[2]
    res = plan(p["R0"], p["Rd"], mechanism="attitude", route="global")
    assert res.success and res.route == "global", res.reason
    RT = resimulate(p["R0"], res.controls, res.T, "attitude", res.breakpoints)
    assert terminal_error(RT, p["Rd"]) <= 1e-8


@pytest.mark.slow
def test_route_global_on_platform_raised():
    p = far_pair("platform_raised", "uniform-platform_raised-0025")
    res = plan(p["R0"], p["Rd"], mechanism="platform_raised", route="auto")
    assert res.success and res.route == "global", res.reason
    RT = resimulate(p["R0"], res.controls, res.T, "platform_raised", res.breakpoints)
    assert terminal_error(RT, p["Rd"]) <= 1e-8


def test_route_argument_and_goals_across_the_singular_surface():
    p = far_pair()
    with pytest.raises(ValueError, match="route"):
        plan(p["R0"], p["Rd"], route="roadmap")
    mech = catalog.get("platform")
    across = next(so3.from_rpy(a, b, 0.3) for a in (0.3, 2.0, -1.0) for b in (0.2, -0.4)
                  if np.sign(mech.delta(so3.from_rpy(a, b, 0.3))) != np.sign(mech.delta(p["R0"])))
    res = plan(p["R0"], across, route="auto")
    assert not res.success and "across the singular surface" in res.reason and res.route == "local"


def test_plan_files_keep_the_route_honest(tmp_path):
    """A file may not relabel a local plan as global (or back), nor carry a route in format 2."""
    import json

    from nonholo.certify.plan_fields import FORMAT_2
    from nonholo.io.result import PlanResult

    p = goalset.uniform_pairs("platform", 3)[0]
    res = plan(p["R0"], p["Rd"])
    d = res.to_dict()
    with pytest.raises(ValueError, match="route"):
        PlanResult.from_dict({**d, "route": "global"})
    with pytest.raises(ValueError, match="route"):
        PlanResult.from_dict({**d, "route": "elsewhere"})
    with pytest.raises(ValueError, match="route"):
        PlanResult.from_dict({**d, "format": FORMAT_2})
    old = {k: v for k, v in d.items() if k != "route"}
    assert PlanResult.from_dict({**old, "format": FORMAT_2}).route == "local"
    (tmp_path / "x.json").write_text(json.dumps(d))
    assert PlanResult.load(tmp_path / "x.json") == res


@pytest.mark.slow
def test_cli_takes_the_route(tmp_path, capsys):
    import argparse

    from nonholo.cli import plan_command as cli_plan
    from nonholo.io.result import PlanResult

    def cli(argv):
        parser = argparse.ArgumentParser(prog="nonholo")
        cli_plan.add_parser(parser.add_subparsers(dest="command"))
        return cli_plan.run(parser.parse_args(["plan", *argv]))

    p = far_pair()
    start = [repr(float(a)) for a in so3.as_rpy(p["R0"])]
    goal = [repr(float(a)) for a in so3.as_rpy(p["Rd"])]
    out, fig = tmp_path / "far.json", tmp_path / "far.png"
    assert cli(["--from", *start, "--to", *goal, "--quiet", "--route", "local"]) == 1
    assert cli(["--from", *start, "--to", *goal, "--quiet",          # the default route: auto
                "--out", str(out), "--plot", str(fig)]) == 0
    text = capsys.readouterr().out
    assert "global route" in text
    res = PlanResult.load(out)
    assert res.success and res.route == "global"
    assert fig.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("mechanism, first, stop", [("platform", 0, 11), ("platform_raised", 8, 10)])
@pytest.mark.slow
def test_default_plan_solves_a_slice_of_the_random_band_set(mechanism, first, stop):
    """Far pairs of ``benchmarks.goalset.band_pairs`` (1.8–π rad), some of which the local
    planner misses: the default ``plan()`` solves each, certified, and RK4 confirms it."""

    far = [p for p in goalset.band_pairs(mechanism, 500) if p["band"] == "1.8-pi"][first:stop]
    results = [plan(p["R0"], p["Rd"], mechanism=mechanism) for p in far]
    assert all(r.success for r in results), [r.reason for r in results if not r.success]
    assert any(r.route == "global" for r in results)
    for (err, dmin), r in zip(rk4_check(results, far), results):
        assert err <= 1e-8, (r.route, err)
        assert dmin >= r.options["delta_min"]


@pytest.mark.slow
def test_a_stitched_control_too_ill_conditioned_to_certify_is_rescued_by_smoothing(monkeypatch):
    """A route whose hops all succeed but whose stitched control its certificate refuses as
    too ill-conditioned is re-planned as one smooth control from the refused one, certified
    by its own certificate and confirmed by DOP853. The refusal is forced (the stitched
    controls' sensitivity limit lowered below any sensitivity) on the far pair of the tests
    above, whose stitched control is certified on its own (sensitivity ~27, far below the
    limit): which of a pair's stitched controls pass on their own is a matter of rounding
    where they pass or fail by little (``band-platform-1.8-pi-0189``'s: by less than their
    error bound; one is certified on some CPUs, refused on others). The smooth re-plan is the
    one a certified route gets by default, here from the refused control (the time budget
    lifted: the test must not depend on the machine's speed)."""
    monkeypatch.setattr(route_paths, "TIME_BUDGET", 60.0)
    measure = route.certify.measure
    refused = []

    def refuse_stitched(start, goal, T, mechanism, par, *args, **kwargs):
        cert = measure(start, goal, T, mechanism, par, *args, **kwargs)
        if not isinstance(par, Stitched):       # the smooth re-plan's own certificate: as it is
            return cert
        refused.append(par)
        return dataclasses.replace(
            cert, passed=False, correctable=False,
            reason=f"the motion is too ill-conditioned (the test's limit): its sensitivity {cert.sensitivity:.3g}")

    monkeypatch.setattr(route.certify, "measure", refuse_stitched)
    p = far_pair()
    res = plan(p["R0"], p["Rd"], objective=None)
    assert refused, "no stitched control was certified: the route was not steered"
    assert res.success and res.route == "global", res.reason
    # the rescue: the refused stitched control kept as the record, the plan one smooth control
    assert isinstance(res.stitched, Stitched) and res.hops is res.stitched
    assert any(res.stitched is par for par in refused)
    assert not isinstance(res.parametrisation, Stitched)
    assert isinstance(res.parametrisation, FrameControls)
    assert res.parametrisation.frame.harmonics in route_smoothing.SMOOTHING_HARMONICS
    assert "then re-planned as one smooth control from the stitched one" in res.reason
    assert "the stitched control is not certified: the motion is too ill-conditioned (the test's limit)" \
        in res.reason
    # certified: the smooth control's own certificate, within tol and clear of Δ = 0
    assert res.replay_steps is not None and res.sensitivity is not None
    assert res.terminal_error + res.error_bound <= res.options["tol"]
    assert res.min_delta >= res.options["delta_min"]
    # ... and confirmed by an independent DOP853 re-simulation of controls(t)
    RT = resimulate(p["R0"], res.controls, res.T, "platform", res.breakpoints)
    assert terminal_error(RT, p["Rd"]) <= 1e-8


@pytest.mark.slow
def test_a_goal_whose_routes_are_all_too_ill_conditioned_takes_two_legs(tmp_path):
    """Far pair ``band-platform_raised-1.8-pi-0000``: the stitched controls of the roadmap's
    paths, and their smooth re-plans, are all too ill-conditioned to certify (sensitivity
    above 7e3); the route's last stage reaches the goal by two legs through a roadmap node,
    certified, and DOP853 confirms it."""
    p = {q["id"]: q for q in goalset.band_pairs("platform_raised", 500)}["band-platform_raised-1.8-pi-0000"]
    local = plan(p["R0"], p["Rd"], mechanism="platform_raised", route="local")
    assert not local.success
    res = plan(p["R0"], p["Rd"], mechanism="platform_raised")
    assert res.success and res.route == "global", res.reason
    assert "two legs through an intermediate orientation" in res.reason
    legs = res.hops
    assert legs.n_pieces == 2
    assert any(np.array_equal(legs.waypoints[1], R)
               for R in roadmap.via_nodes(mechanism_named("platform_raised"), p["R0"], p["Rd"], route.VIA_CANDIDATES))
    assert res.terminal_error + res.error_bound <= res.options["tol"]
    RT = resimulate(p["R0"], res.controls, res.T, "platform_raised", res.breakpoints)
    assert terminal_error(RT, p["Rd"]) <= 1e-8
    res.save(tmp_path / "two_legs.json")
    from nonholo import PlanResult
    assert PlanResult.load(tmp_path / "two_legs.json").hops == legs


def test_via_nodes_keep_the_start_component():
    mech = catalog.get("platform")
    R0, Rd = so3.from_rpy(0.5, 1.2, -0.5), so3.from_rpy(1.0, 0.9, -0.5)
    nodes = roadmap.via_nodes(mech, R0, Rd, 20)
    assert len(nodes) == 20
    assert np.all(np.sign(mech.delta_samples(nodes)) == np.sign(mech.delta(R0)))
    assert np.all(np.abs(mech.delta_samples(nodes)) >= roadmap.default_clearance(mech))
    across = so3.from_rpy(-1.0, 0.9, -0.5)
    assert np.sign(mech.delta(across)) != np.sign(mech.delta(R0))
    assert len(roadmap.via_nodes(mech, R0, across, 20)) == 0
    assert len(roadmap.via_nodes(mechanism_named("attitude"), R0, Rd, 20)) == 0
