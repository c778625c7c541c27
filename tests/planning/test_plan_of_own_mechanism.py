"""A plan carries its mechanism: a plan of a :class:`nonholo.Mechanism` that is not in the
catalog — a platform of numbers, a unicycle with a trailer from its field — is re-timed,
exported, saved, reloaded (``PlanResult.load(path, mechanism=m)``) and drawn as one of the
catalog's; without ``mechanism=`` the load says to pass it.

The checks are independent of the generated code: leg lengths from the geometry in NumPy on
the exported orientations, the trailer's end state against the goal.
"""
from __future__ import annotations

import csv

import matplotlib
import numpy as np
import pytest
import sympy as sp
from conftest import assert_inputs_match, check_solution, reachable_goals
from scipy.spatial.transform import Rotation

from derivations.mechanisms import PlatformGeometry, platform_mechanism
from nonholo import Mechanism, PlanResult, mechanism_named, plan, retime
from nonholo.model import catalog
from nonholo.spaces import so3

matplotlib.use("Agg")

pytestmark = pytest.mark.slow


def on_sphere(*v) -> tuple:
    """The point of the unit sphere in the direction ``v`` (the sphere's radius is the unit of
    length: a platform's joints and contact point lie on it)."""
    n = sum(x * x for x in v) ** 0.5
    return tuple(x / n for x in v)


GEOMETRY = PlatformGeometry(base1=(0.3, 1.5, 0.4), tip1=on_sphere(0.1, 1.0, 0.0), base2=(1.5, -0.2, 0.5),
                            tip2=on_sphere(1.0, 0.0, 0.1), contact=(0.0, 0.6, 0.8), axle=(1.0, 0.0, 0.0))


@pytest.fixture(scope="module")
def platform():
    return Mechanism.from_symbolic(platform_mechanism("own_platform", GEOMETRY, "a platform of floats"))


@pytest.fixture(scope="module")
def planned(platform):
    assert "own_platform" not in catalog.names()
    R0, Rd = reachable_goals(platform, 1, seed=31)[0]
    res = plan(R0, Rd, mechanism=platform)
    check_solution(res, R0, Rd, mechanism=platform)
    return res


def read_csv(path) -> dict[str, np.ndarray]:
    with open(path) as f:
        rows = list(csv.reader(f))
    return {name: np.array([float(r[i]) for r in rows[1:]]) for i, name in enumerate(rows[0])}


def lengths(R, geometry):
    """``|R tip_i − base_i|`` from the geometry's floats."""
    g = {k: np.array(v, dtype=float) for k, v in vars(geometry).items()}
    return np.stack([np.linalg.norm(R @ g[f"tip{i}"] - g[f"base{i}"], axis=-1) for i in (1, 2)], axis=-1)


def test_the_plan_holds_its_mechanism(platform, planned):
    assert planned.kinematics is platform and planned.mechanism == "own_platform"


def test_a_retimed_plan_keeps_every_leg_within_the_speed(platform, planned, tmp_path):
    fast = retime(planned, leg_speed=0.5)
    assert fast.success and fast.kinematics is platform and fast.T > 0
    table = read_csv(fast.to_csv(tmp_path / "fast.csv", rate=200))
    R = Rotation.from_quat(np.column_stack([table[k] for k in ("qx", "qy", "qz", "qw")])).as_matrix()
    np.testing.assert_allclose(np.column_stack([table["l1"], table["l2"]]), lengths(R, GEOMETRY), atol=1e-9)
    speeds = np.gradient(lengths(R, GEOMETRY), table["t"], axis=0)
    assert np.max(np.abs(speeds)) <= 0.5 * 1.02
    assert np.max(np.abs(np.column_stack([table["dl1_dt"], table["dl2_dt"]]))) <= 0.5 * (1 + 1e-9)
    assert so3.distance(R[-1], planned.Rd) < 1e-8


def test_it_is_saved_and_loaded_with_its_mechanism(platform, planned, tmp_path):
    for res in (planned, retime(planned, leg_speed=0.5)):
        path = res.save(tmp_path / "plan.json")
        with pytest.raises(ValueError, match=r"unknown mechanism 'own_platform'.*mechanism=m"):
            PlanResult.load(path)
        back = PlanResult.load(path, mechanism=platform)
        assert back == res and back.kinematics is platform
        # the loaded controls at t against the samples the plan stored (the certified replay's
        # stage values, or the re-timed controls with the planner's nodes): two computations
        assert_inputs_match(back.controls(res.t), res.u)
        with pytest.raises(ValueError, match="the plan is of mechanism 'own_platform'"):
            PlanResult.load(path, mechanism=mechanism_named("platform"))


def test_its_csv_has_the_legs_and_the_singular_function(platform, planned, tmp_path):
    table = read_csv(planned.to_csv(tmp_path / "plan.csv"))
    assert list(table)[:7] == ["t", "l1", "l2", "dl1_dt", "dl2_dt", "u1", "u2"]
    R = Rotation.from_quat(np.column_stack([table[k] for k in ("qx", "qy", "qz", "qw")])).as_matrix()
    np.testing.assert_allclose(table["delta"], platform.delta_samples(R), atol=1e-10)
    np.testing.assert_allclose(np.column_stack([table["l1"], table["l2"]]), lengths(R, GEOMETRY), atol=1e-9)


def test_its_figures_draw_its_own_motion(planned):
    from nonholo import viz

    ax = viz.leg_lengths_figure(planned).axes[0]
    want = lengths(planned.R, GEOMETRY)
    # the drawing's dimensions are the geometry's (floats: nothing to scale)
    drawn = [ln.get_ydata() for ln in ax.lines if len(ln.get_ydata()) == len(planned.t)]
    assert any(np.allclose(y, want[:, 0], atol=1e-9) for y in drawn)
    assert any(np.allclose(y, want[:, 1], atol=1e-9) for y in drawn)
    viz.example_overview_figure(planned)


def test_a_vehicle_of_one_s_own_is_exported_and_reloaded(tmp_path):
    x, y, th0, th1, v, w = sp.symbols("x y theta0 theta1 v w")
    trailer = Mechanism.from_equations("trailer1", coordinates=[x, y, th0, th1], inputs=[v, w],
                                       rates=[v * sp.cos(th0), v * sp.sin(th0), w, v * sp.sin(th0 - th1)],
                                       angles=[th0, th1])
    goal = np.array([1.0, 0.5, 0.0, 0.0])
    res = plan(np.zeros(4), goal, mechanism=trailer)
    assert res.success and res.kinematics is trailer
    table = read_csv(res.to_csv(tmp_path / "trailer.csv"))
    assert list(table) == ["t", "u1", "u2", "x", "y", "theta0", "theta1"]
    np.testing.assert_allclose([table[k][-1] for k in ("x", "y", "theta0", "theta1")], goal, atol=1e-8)
    back = PlanResult.load(res.save(tmp_path / "trailer.json"), mechanism=trailer)
    assert back == res and back.goal.q.tolist() == goal.tolist()
    with pytest.raises(ValueError, match="leg_speed: mechanism 'trailer1' has no legs"):
        retime(res, leg_speed=1.0)
