"""nonholo.physics: plans played on MuJoCo models, compared with the planned motion and
the mechanisms' kinematics (orders of magnitude only: MuJoCo versions shift digits).

The runs use a coarse time step (:data:`COARSE`); the acceptance measurements at the
default settings are ``benchmarks/physics.py``'s.
"""
from __future__ import annotations

import dataclasses
import importlib
import importlib.util
import json

import numpy as np
import pytest

import nonholo
from nonholo.physics import Contact, Execution, execute, model_for, write_mjcf
from nonholo.physics.execution import MARGIN, motion_size, predicted_error
from nonholo.planning.retime import retime
from nonholo.spaces import so3
from nonholo.viz.execution_figures import execution_figure

mujoco = pytest.importorskip("mujoco")

#: A coarse step (and the stiffest contact it allows) keeps the tests fast.
COARSE = Contact(timestep=0.005, solref=(0.01, 1.0))
BALL_R0 = so3.from_rpy(0.4, -0.3, 0.2)
BALL_RD = so3.exp(np.array([np.pi / 2, 0, 0])) @ BALL_R0


@pytest.fixture(scope="module")
def ball_plan():
    res = nonholo.plan((BALL_R0, (0.0, 0.0)), (BALL_RD, (0.0, 0.0)), mechanism="rolling_ball",
                       strategy="paper", settings=nonholo.Settings(harmonics=4))
    assert res.success
    return res


@pytest.fixture(scope="module")
def ball_run(ball_plan):
    return execute(ball_plan, touch_ups=1, contact=COARSE)


@pytest.fixture(scope="module")
def fast_ball(ball_plan):
    """The ball played ten times faster than its default, with a touch-up offered."""
    return execute(ball_plan, touch_ups=1, duration=1.0, contact=COARSE)


@pytest.fixture(scope="module")
def car_plan():
    res = nonholo.plan((0.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0), mechanism="car")
    assert res.success
    return res


@pytest.fixture(scope="module")
def car_run(car_plan):
    return execute(car_plan, touch_ups=1, contact=COARSE)


@pytest.fixture(scope="module")
def unicycle_plan():
    res = nonholo.plan((0.0, 0.0, 0.0), (0.0, 1.0, 0.0), mechanism="unicycle")
    assert res.success
    return res


def rotation_gap(Ra, Rb) -> np.ndarray:
    """``|log(R_a R_bᵀ)|`` of two stacks of rotations."""
    return np.array([np.linalg.norm(so3.log(a @ b.T)) for a, b in zip(Ra, Rb)])


def norms(run) -> list[float]:
    """``|e|`` after each stage of ``run``."""
    space = nonholo.mechanism_named(run.mechanism).space
    return [space.norm(s["error"]) for s in run.stages]


def assert_never_worse(run):
    e = norms(run)
    assert all(b <= a for a, b in zip(e, e[1:])), e


# -- the ball --------------------------------------------------------------------------------

def test_the_ball_rolls_along_the_planned_motion(ball_run):
    tr = ball_run.traces[0]
    assert np.max(rotation_gap(tr["R"], tr["R_planned"])) < 5e-2
    assert np.max(np.abs(tr["q"] - tr["q_planned"])) < 5e-2
    assert ball_run.stages[0]["error"]["rotation"] < 2e-2


def test_a_touch_up_from_rest_cuts_the_ball_error_by_orders(ball_run):
    first, second = (s["error"]["rotation"] for s in ball_run.stages)
    assert second < 1e-2 * first
    assert second < 1e-4
    assert ball_run.stages[1]["error"]["coordinates"] < 1e-4


def test_stage_errors_are_those_of_the_final_state(ball_run):
    for stage, tr in zip(ball_run.stages, ball_run.traces):
        assert stage["error"]["rotation"] == pytest.approx(rotation_gap(tr["R"][-1:], [BALL_RD])[0], abs=1e-12)
        assert stage["error"]["coordinates"] == pytest.approx(np.linalg.norm(tr["q"][-1]), abs=1e-12)
        assert stage["sim_time"] == pytest.approx(tr["t"][-1])


def test_radius_compensation_measures_the_rolling_radius_of_the_soft_contacts():
    """Rolling radii ``ρ − δ/2`` from the settled ball's height and the plate's."""
    model = model_for("rolling_ball", COARSE)
    m = mujoco.MjModel.from_xml_string(model.mjcf())
    d = mujoco.MjData(m)
    model.reset(m, d, BALL_R0, np.zeros(2))
    z = d.xpos[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "ball")][2]
    plate = d.xpos[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "plate")][2]
    assert 0 < 1 - z < 1e-2 and 0 < z + 1 - plate < 1e-2      # the contacts are soft
    assert model.radii["floor"] == pytest.approx((1 + z) / 2, abs=1e-9)
    assert model.radii["plate"] == pytest.approx((plate - z + 1) / 2, abs=1e-9)
    R, q = model.state(m, d)
    assert rotation_gap([R], [BALL_R0])[0] < 1e-6 and np.linalg.norm(q) < 1e-6


def test_played_too_fast_the_ball_slips_and_is_not_touched_up(fast_ball, ball_run):
    """Far off the goal, the re-plan is nearly as large a motion as the plan, played as fast:
    its predicted error is not below the present one, and it is not played."""
    first, second = fast_ball.stages
    assert first["error"]["rotation"] > 0.1
    assert first["max_slip"] > 100 * ball_run.stages[0]["max_slip"]
    assert second["outcome"] == "predicted worse" and "predicted" in second["reason"]
    assert second["predicted"] >= norms(fast_ball)[0] and second["size"] > 0.1 * first["size"]
    assert second["error"] == first["error"] and second["sim_time"] == 0.0 and fast_ball.traces[1] is None
    assert_never_worse(fast_ball)
    assert "touch-up 1 not played" in execution_figure(fast_ball).get_suptitle()


# -- the car and the unicycle ----------------------------------------------------------------

def test_the_car_parks(car_run):
    tr = car_run.traces[0]
    assert np.max(np.abs(tr["q"] - tr["q_planned"])) < 5e-2
    first, second = (s["error"]["coordinates"] for s in car_run.stages)
    assert first < 5e-2
    assert second < 1e-2 and second < first / 10
    assert car_run.stages[1]["outcome"] == "played" and second <= car_run.stages[1]["predicted"]


def test_two_runs_are_identical(unicycle_plan):
    seen = []
    a = execute(unicycle_plan, contact=COARSE, duration=5.0, progress=seen.append)
    b = execute(unicycle_plan, contact=COARSE, duration=5.0)
    assert [s["stage"] for s in seen] == [0]
    assert a == b
    strip = [{k: v for k, v in s.items() if k != "real_time_factor"} for s in a.stages]
    assert strip == [{k: v for k, v in s.items() if k != "real_time_factor"} for s in b.stages]
    assert np.array_equal(a.traces[0]["q"], b.traces[0]["q"])
    assert a.stages[0]["error"]["coordinates"] < 1e-2


# -- the record --------------------------------------------------------------------------------

def test_the_record_saves_and_loads(car_run, tmp_path):
    d = car_run.to_dict()
    assert set(d) >= {"mechanism", "stages", "contact"} and d["mechanism"] == "car"
    assert set(d["stages"][0]) >= {"error", "max_slip", "max_contact_force", "sim_time", "real_time_factor"}
    assert d["contact"]["timestep"] == COARSE.timestep
    path = car_run.save(tmp_path / "run.json")
    assert json.loads(path.read_text())["stages"] == json.loads(json.dumps(d["stages"]))
    back = Execution.load(path)
    assert back == car_run and back.contact == COARSE.resolved("car") and back.traces is None
    with pytest.raises(ValueError, match="stages"):
        Execution.from_dict({**d, "stages": []})


def test_a_record_with_a_touch_up_not_played_saves_and_loads(fast_ball, tmp_path):
    back = Execution.load(fast_ball.save(tmp_path / "fast.json"))
    assert back == fast_ball
    assert [s["outcome"] for s in back.stages] == ["played", "predicted worse"]
    assert back.stages[1]["reason"] == fast_ball.stages[1]["reason"] and back.stages[1]["drift"] is None
    d = fast_ball.to_dict()
    with pytest.raises(ValueError, match=r"stages\[1\]\.outcome"):
        Execution.from_dict({**d, "stages": [d["stages"][0], {**d["stages"][1], "outcome": "skipped"}]})
    with pytest.raises(ValueError, match=r"stages\[1\]\.reason"):
        Execution.from_dict({**d, "stages": [d["stages"][0], {**d["stages"][1], "reason": None}]})


def test_a_record_saved_before_outcomes_loads(fast_ball):
    """Older records had ``planned`` (``False`` for a touch-up that could not be planned)."""
    keys = ("error", "max_slip", "max_contact_force", "sim_time", "real_time_factor", "duration")
    d = fast_ball.to_dict()
    old = [{**{k: s[k] for k in keys}, "planned": True} for s in d["stages"]]
    old[1].update(planned=False, reason="no plan")
    back = Execution.from_dict({**d, "stages": old})
    assert [s["outcome"] for s in back.stages] == ["played", "not planned"]
    assert "planned" not in back.stages[0] and back.stages[1]["reason"] == "no plan"
    assert "not played" in repr(back)


# -- touch-ups: played only when predicted to help ----------------------------------------------

def test_execution_stops_within_the_plans_tolerance():
    loose = nonholo.plan((0.0, 0.0, 0.0), (0.0, 1.0, 0.0), mechanism="unicycle", settings=nonholo.Settings(tol=1e-2))
    run = execute(loose, touch_ups=3, contact=COARSE, duration=5.0)
    assert [s["outcome"] for s in run.stages] == ["played", "within tolerance"]
    assert norms(run)[0] <= 1e-2 and "tolerance" in run.stages[1]["reason"]
    assert run.stages[1]["size"] is None and run.stages[1]["predicted"] is None and run.traces[1] is None
    assert_never_worse(run)


def test_the_prediction_scales_the_stages_played():
    """Each played stage bounds a motion ``r`` times its size by ``|e| max(r, r²)``; the least
    bound, times the margin, plus the drift over the time and the plan's own error."""
    stages = [{"outcome": "played", "size": 2.0, "drift": 0.0},
              {"outcome": "played", "size": 0.5, "drift": 1e-9},
              {"outcome": "predicted worse", "size": 0.01, "drift": None}]
    e = [1e-4, 1e-7, 1e-7]
    assert predicted_error(e, stages, 0.1, 0.0, 0.0) == pytest.approx(MARGIN * 1e-7 * 0.2)
    assert predicted_error(e, stages, 1.0, 0.0, 0.0) == pytest.approx(MARGIN * 1e-7 * 4.0)
    assert predicted_error(e, stages, 8.0, 0.0, 0.0) == pytest.approx(MARGIN * 1e-7 * 16.0 ** 2)
    assert predicted_error(e[:1], stages[:1], 8.0, 0.0, 0.0) == pytest.approx(MARGIN * 1e-4 * 4.0 ** 2)
    assert predicted_error(e, stages, 0.1, 1e-12, 10.0) == pytest.approx(MARGIN * 2e-8 + 1e-8 + 1e-12)
    assert predicted_error(e[:1], [{"outcome": "not planned", "size": None}], 1.0, 0.0, 0.0) == np.inf
    assert predicted_error(e[:1], stages[:1], 0.0, 1e-12, 0.0) == pytest.approx(1e-12)


def test_the_size_of_a_motion_does_not_depend_on_its_timing(unicycle_plan):
    size = motion_size(unicycle_plan)
    assert size >= 1.0             # ∫|v| dt alone covers the distance to the goal
    assert motion_size(retime(unicycle_plan, T=10.0, rest_to_rest=True)) == pytest.approx(size, rel=1e-2)


# -- settings, models, refusals -----------------------------------------------------------------

@pytest.mark.parametrize("field, value", [("timestep", 0.0), ("timestep", float("nan")), ("solref", (1.0,)),
                                          ("solimp", (2, 0.9, 0.001, 0.5, 2)), ("friction", -1.0),
                                          ("noslip_iterations", -1), ("noslip_iterations", 1.5),
                                          ("impratio", 0.5), ("preload", -1.0), ("radius_compensation", 1),
                                          ("actuators", "magic"), ("settle", 0)])
def test_bad_contact_settings_are_refused(field, value):
    with pytest.raises(ValueError, match=field):
        Contact(**{field: value})


def test_contact_settings_round_trip_and_resolve():
    c = Contact(timestep=0.002, actuators="servo", radius_compensation=False)
    assert Contact.from_dict(json.loads(json.dumps(c.to_dict()))) == c
    car = c.resolved("car")
    assert None not in car.to_dict().values()
    assert (car.timestep, car.actuators, car.radius_compensation) == (0.002, "servo", False)
    assert model_for("car", c).contact == car
    assert Contact().resolved("platform").timestep < Contact().resolved("car").timestep
    with pytest.raises(ValueError, match="unknown"):
        Contact.from_dict({"stiffness": 1})


@pytest.mark.parametrize("name", ["rolling_ball", "car", "unicycle"])
def test_the_models_load_and_hold_their_state(name, tmp_path):
    """A written model file loads, and a model placed at a state measures that state back."""
    mech = nonholo.mechanism_named(name)
    path = write_mjcf(mech, tmp_path / f"{name}.xml", contact=COARSE)
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    model = model_for(name, COARSE)
    R = BALL_R0 if mech.space.has_orientation else np.eye(3)
    q = {"rolling_ball": [0.5, -0.25], "car": [0.5, -0.25, 0.3, 0.2], "unicycle": [0.5, -0.25, 0.3]}[name]
    model.reset(m, d, R, np.array(q))
    R_m, q_m = model.state(m, d)
    assert rotation_gap([R_m], [R])[0] < 1e-5
    assert np.max(np.abs(q_m - q)) < 1e-4
    assert model.slip(m, d) < 1e-3 and model.contact_force(m, d) > 0


def test_a_mechanism_without_a_model_is_refused():
    with pytest.raises(ValueError, match="mechanism 'brockett'"):
        model_for("brockett")
    with pytest.raises(ValueError, match="contact"):
        model_for("car", contact={"timestep": 0.01})


@pytest.mark.skipif(importlib.util.find_spec("nonholo.physics.platform_model") is None,
                    reason="no platform model in this checkout")
def test_the_platform_has_a_model():
    model = model_for("platform", COARSE)
    assert type(model).__name__ == "PlatformModel"
    mujoco.MjModel.from_xml_string(model.mjcf())


@pytest.mark.parametrize("kwargs, word", [({"touch_ups": -1}, "touch_ups"), ({"touch_ups": 1.5}, "touch_ups"),
                                          ({"touch_ups": True}, "touch_ups"), ({"duration": 0.0}, "duration"),
                                          ({"duration": -2.0}, "duration"), ({"contact": "soft"}, "contact"),
                                          ({"progress": 3}, "progress")])
def test_bad_arguments_are_refused(car_plan, kwargs, word):
    with pytest.raises(ValueError, match=word):
        execute(car_plan, **kwargs)


def test_only_a_successful_plan_is_played(car_plan):
    with pytest.raises(ValueError, match="result"):
        execute(car_plan.to_dict())
    with pytest.raises(ValueError, match="result"):
        execute(dataclasses.replace(car_plan, success=False, reason="made up"))


def test_touch_ups_re_plan_with_the_plans_objective(unicycle_plan):
    """A touch-up re-plans as its plan was planned: with the default objective ``"auto"``, and
    with ``None`` for a plan as found (which records no objective)."""
    from nonholo.physics.execution import replan_options

    found = nonholo.plan((0.0, 0.0, 0.0), (0.0, 1.0, 0.0), mechanism="unicycle", objective=None)
    assert "objective" not in found.options and replan_options(found)["objective"] is None
    assert replan_options(unicycle_plan)["objective"] == "auto"


def test_the_defaults_smooth_replacement_is_played_like_any_plan(ball_plan, ball_run):
    """The ball's quarter turn as found rolls a long detour; the default replaces it by a
    smooth least-energy motion (a Fourier series), which the model plays and a touch-up
    brings onto the goal."""
    assert ball_plan.options["objective"] == "auto" and ball_plan.method == "parametric"
    assert ball_plan.breakpoints is None and "made smooth" in ball_plan.reason
    first, last = (s["error"]["rotation"] for s in (ball_run.stages[0], ball_run.stages[-1]))
    assert last < first / 10


def test_a_touch_up_that_cannot_be_planned_ends_the_run(unicycle_plan, monkeypatch):
    module = importlib.import_module("nonholo.physics.execution")

    def refuse(*args, **kwargs):
        raise ValueError("no plan from here")

    monkeypatch.setattr(module, "plan", refuse)
    ex = execute(unicycle_plan, touch_ups=3, contact=COARSE, duration=5.0)
    assert [s["outcome"] for s in ex.stages] == ["played", "not planned"]
    assert ex.stages[1]["error"] == ex.stages[0]["error"] and "no plan" in ex.stages[1]["reason"]
    assert ex.traces[1] is None
