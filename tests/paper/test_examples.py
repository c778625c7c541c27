"""The examples' data, and the main job `nonholo reproduce` end to end."""
import importlib.util
import json

import numpy as np
import pytest

from nonholo.cli.entry import main
from nonholo.model import catalog
from nonholo.paper import examples
from nonholo.spaces import so3

delta = catalog.get("platform").delta


def test_examples_1_2_match_the_model():
    ex1, ex2 = examples.get(1), examples.get(2)
    assert so3.distance(ex1.R_start, ex1.R_goal) == pytest.approx(0.58, abs=0.005)
    assert delta(ex1.R_start) == pytest.approx(0.727, abs=5e-4)
    assert delta(ex1.R_goal) == pytest.approx(0.582, abs=5e-4)
    assert delta(ex2.R_start) == pytest.approx(0.844, abs=5e-4)
    assert delta(ex2.R_goal) == pytest.approx(0.882, abs=5e-4)
    np.testing.assert_allclose(so3.as_rpy(ex2.R_start @ ex2.R_goal.T @ ex2.R_goal), ex2.rpy_start)


@pytest.mark.parametrize("number", [3, 4])
def test_parking_goals_meet_the_conditions(number):
    ex = examples.get(number)
    R0, Rd = ex.R_start, ex.R_goal
    assert so3.distance(R0, Rd) == pytest.approx(0.6, abs=1e-12)
    assert Rd[0, 0] == pytest.approx(R0[0, 0], abs=1e-12)  # leg 2 ends at its initial length
    assert Rd[1, 1] == pytest.approx(R0[1, 1], abs=1e-12)  # leg 1 too
    assert np.sign(delta(Rd)) == np.sign(delta(R0))


def test_example3_is_the_parking_goal_nearest_to_the_reference():
    ex3, ex4 = examples.get(3), examples.get(4)
    ref = so3.exp(0.6 * np.array([1.0, 0, 0])) @ ex3.R_start
    assert so3.distance(ex3.R_goal, ref) < so3.distance(ex4.R_goal, ref)
    assert so3.distance(ex3.R_goal, ex4.R_goal) > 0.1


def test_unknown_example():
    with pytest.raises(ValueError):
        examples.get(7)


@pytest.mark.slow
def test_reproduce_writes_summary_and_figures(tmp_path, capsys):
    assert main(["reproduce", "--out", str(tmp_path), "--no-audit"]) == 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["made_by"]["numpy"] == np.__version__ and "commit" in summary["made_by"]
    rows = summary["examples"]
    keys = {"example", "method", "strategy", "success", "iterations", "terminal_error",
            "min_delta"}
    assert all(keys <= set(r) and "seconds" not in r for r in rows)   # times are printed, not kept
    table = (tmp_path / "summary.md").read_text()
    assert "time" not in table and len(table.splitlines()) == 2 + len(rows)
    assert "time [s]" in capsys.readouterr().out
    for number in (1, 2):
        mine = [r for r in rows if r["example"] == number]
        assert {r["method"] for r in mine} == {"parametric", "nonparametric"}
        for r in mine:
            assert r["success"] and r["terminal_error"] <= 1e-8 and r["min_delta"] >= 0.2
    assert {r["example"] for r in rows} == {1, 2, 3, 4}
    stems = ["singular_set", "singular_set_slices", "normal_form", "mechanism_platform",
             "mechanism_platform_raised", "mechanism_attitude"] + [
        f"example{k}_{what}" for k in (1, 2, 3) for what in
        ("mechanism", "overview", "convergence", "controls", "rpy", "leg_lengths", "delta")] + ["global_route",
                                                                                         "leg_limits"]
    if importlib.util.find_spec("mujoco") is not None:        # the physics extra
        stems += ["physics_example3", "physics_rolling_ball", "physics_car"]
    for stem in stems:
        for ext in ("png", "pdf"):
            assert (tmp_path / f"{stem}.{ext}").stat().st_size > 5000, stem
    assert (tmp_path / "example3_animation.gif").stat().st_size > 10000
    from nonholo.io.result import PlanResult
    again = PlanResult.load(tmp_path / "plans" / "example1_parametric.json")
    assert again.success and again.terminal_error <= 1e-10
    for plan in (tmp_path / "plans").glob("*.json"):             # no wall time kept
        assert json.loads(plan.read_text())["seconds"] is None, plan.name
    far = PlanResult.load(tmp_path / "plans" / "far_goal.json")
    assert far.success and far.route == "global"
    limited = PlanResult.load(tmp_path / "plans" / "leg_limits.json")
    assert limited.success and limited.options["leg_length"] == [1.2, 2.0]
    head = (tmp_path / "plans" / "leg_limits.csv").read_text().splitlines()
    assert head[0] == "t,l1,l2,dl1_dt,dl2_dt,u1,u2,qx,qy,qz,qw,delta" and len(head) == 1 + 101
    # a second run changes nothing; --check lists a number moved beyond rounding, and by how much
    capsys.readouterr()
    assert main(["reproduce", "--out", str(tmp_path), "--no-audit", "--no-figures", "--check"]) == 0
    text = (tmp_path / "summary.json").read_text()
    moved = text.replace(f'"min_delta": {rows[0]["min_delta"]!r}', f'"min_delta": {rows[0]["min_delta"] + 1e-3!r}')
    assert moved != text
    (tmp_path / "summary.json").write_text(moved)
    assert main(["reproduce", "--out", str(tmp_path), "--no-audit", "--no-figures", "--check"]) == 1
    out = capsys.readouterr().out
    assert "differs: " in out and "summary.json: numbers differ by" in out
    assert (tmp_path / "summary.json").read_text() == moved          # --check writes nothing
