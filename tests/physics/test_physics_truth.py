"""nonholo.physics tells the truth or refuses: a mechanism plays on a model only if the
model has its kinematics (not merely its name); settings, durations, touch-ups and steps
outside their documented bounds are refused up front, naming them; a stage MuJoCo goes
unstable in is recorded as such and ends the execution; ``Execution.load`` refuses what
``Execution.save`` would not write. Cheap plans, coarse steps, no timing."""
from __future__ import annotations

import dataclasses
import json
import re

import numpy as np
import pytest
import sympy as sp
from sympy import cos, sin, tan

mujoco = pytest.importorskip("mujoco")

import nonholo
from nonholo import Mechanism
from nonholo.cli.entry import main
from nonholo.cli.execute_command import describe
from nonholo.model import catalog
from nonholo.physics import Contact, Execution, execute, model_for
from nonholo.physics import contact as contact_module
from nonholo.physics import execution as execution_module
from nonholo.physics.execution import MAX_DURATION, MAX_STAGE_STEPS, MIN_MOTION_STEPS, instability
from nonholo.physics.execution_record import MAX_TOUCH_UPS
from nonholo.physics.models import matching_model
from nonholo.physics.vehicle_models import CarModel, UnicycleModel

#: A coarse step (and the stiffest contact it allows), as in tests/physics/test_physics.py.
COARSE = Contact(timestep=0.005, solref=(0.01, 1.0))
x, y, th, phi, v, w, ell = sp.symbols("x y theta phi v w ell", real=True)


def own_car(name: str, wheelbase) -> Mechanism:
    """The kinematic car from its equations, of a wheelbase of one's own."""
    return Mechanism.from_equations(name, coordinates=[x, y, th, phi], inputs=[v, w],
                                    rates=[v * cos(th), v * sin(th), v * tan(phi) / ell, w],
                                    angles=[th, phi], parameters={ell: wheelbase})


@pytest.fixture(scope="module")
def unicycle_plan():
    res = nonholo.plan((0.0, 0.0, 0.0), (0.0, 0.3, 0.0), mechanism="unicycle")
    assert res.success, res.reason
    return res


@pytest.fixture(scope="module")
def unicycle_run(unicycle_plan):
    return execute(unicycle_plan, touch_ups=1, contact=COARSE, duration=3.0)


@pytest.fixture(scope="module")
def platform_plan():
    from nonholo.paper import examples

    ex = examples.get(1)
    res = nonholo.plan(ex.R_start, ex.R_goal)
    assert res.success, res.reason
    return res


@pytest.fixture
def elsewhere(tmp_path, monkeypatch):
    """MuJoCo writes its warnings to MUJOCO_LOG.TXT in the working directory: a temporary one."""
    monkeypatch.chdir(tmp_path)


@pytest.fixture
def unstable(monkeypatch, elsewhere):
    """From 0.2 s into a stage, the unicycle's drive also pushes with 1e300 N: MuJoCo's
    accelerations blow up, it warns and resets the simulation."""
    drive = UnicycleModel.drive

    def pushing(self, m, d, t):
        drive(self, m, d, t)
        if t > 0.2:
            d.qfrc_applied[:] = 1e300

    monkeypatch.setattr(UnicycleModel, "drive", pushing)


# -- 1. the model is chosen by the kinematics ---------------------------------------------------

@pytest.mark.slow
def test_a_car_of_ones_own_called_car_with_another_wheelbase_is_refused():
    car2 = own_car("car", 2)
    res = nonholo.plan((0.0, 0.0, 0.0, 0.0), (0.0, 0.5, 0.0, 0.0), mechanism=car2)
    assert res.success and res.kinematics is car2 and res.mechanism == "car"
    with pytest.raises(ValueError, match=r"mechanism 'car'.*no physics model matches its kinematics"):
        execute(res, contact=COARSE, duration=5.0)
    with pytest.raises(ValueError, match=r"mechanism 'car'.*no physics model matches its kinematics"):
        model_for(car2)


def test_a_mechanism_with_a_models_kinematics_plays_on_it_whatever_its_name():
    assert matching_model(own_car("my_car", 1)) == "car"
    assert isinstance(model_for(own_car("my_car", 1), COARSE), CarModel)
    for name in ("car", "unicycle", "rolling_ball"):
        assert matching_model(catalog.get(name)) == name
    assert matching_model(catalog.get("platform_raised")) == "platform"
    # a catalog mechanism renamed keeps its model; the unicycle's kinematics named "car" does not get the car's
    assert matching_model(dataclasses.replace(catalog.get("unicycle"), name="car")) == "unicycle"


def test_a_platform_whose_field_its_geometrys_disk_does_not_allow_is_refused():
    platform, raised = catalog.get("platform"), catalog.get("platform_raised")
    assert matching_model(dataclasses.replace(platform, name="mine")) == "platform"
    crossed = dataclasses.replace(platform, geometry=raised.geometry)       # the other one's disk
    with pytest.raises(ValueError, match=r"mechanism 'platform'.*no physics model matches its kinematics"):
        model_for(crossed)


# -- 2. and 4. settings in bounded ranges; steps per stage bounded --------------------------------

@pytest.mark.parametrize("field, value", [
    ("preload", 1e300), ("impratio", 1e300), ("timestep", 1e-9), ("timestep", 1e9), ("settle", 1e9),
    ("settle", 1e-9), ("friction", 1e6), ("friction", 10 ** 400), ("noslip_iterations", 10 ** 9),
    ("solref", (1e3, 1.0)), ("solref", (0.002, 1e9)), ("solref", (0.002, 0.1)), ("solimp", (0.9, 0.95, 1e6, 0.5, 2.0)),
    ("solimp", (0.9, 0.95, 0.001, 0.5, 1e9)), ("solimp", (0.9, 0.95, 0.001, float("nan"), 2.0)),
])
def test_settings_outside_their_ranges_are_refused_naming_the_field(field, value):
    with pytest.raises(ValueError, match=rf"^{field}"):
        Contact(**{field: value})


def test_the_ranges_hold_the_calibrated_settings_and_those_of_the_tests_and_benchmarks():
    from benchmarks.physics import CASES

    for name in (None, "car", "platform", "platform_raised"):
        resolved = Contact().resolved(name)
        assert Contact(**{k: v for k, v in dataclasses.asdict(resolved).items()}) == resolved
    assert all(isinstance(contact, Contact) for *_, contact in CASES)
    lo, hi = contact_module.TIMESTEP_RANGE
    assert lo * 10 <= 5e-4 and 2 * COARSE.timestep <= hi                  # the finest default, the coarsest test
    lo, hi = contact_module.PRELOAD_RANGE
    assert 10 * contact_module.CALIBRATED["platform"]["preload"] <= hi


def test_a_stage_of_too_many_or_too_few_steps_is_refused_before_it_is_played(unicycle_plan, monkeypatch):
    def never(*args, **kwargs):
        raise AssertionError("played")

    monkeypatch.setattr(execution_module, "retime", never)           # nothing is re-timed, let alone played
    fine = Contact(timestep=1e-5)
    assert (20.0 + 0.5) / fine.timestep > MAX_STAGE_STEPS
    with pytest.raises(ValueError, match=r"^duration 20 s.*MAX_STAGE_STEPS"):
        execute(unicycle_plan, duration=20.0, contact=fine)
    assert 0.02 / COARSE.timestep < MIN_MOTION_STEPS
    with pytest.raises(ValueError, match=r"^duration 0.02 s.*MIN_MOTION_STEPS"):
        execute(unicycle_plan, duration=0.02, contact=COARSE)


def test_a_model_refuses_to_prepare_a_motion_of_too_many_steps(unicycle_plan, platform_plan):
    from nonholo.planning.retime import retime

    long = retime(unicycle_plan, T=1e6, rest_to_rest=True)
    with pytest.raises(ValueError, match=r"^played: .*MAX_STAGE_STEPS"):
        model_for("unicycle", COARSE).follow(long, np.eye(3), np.zeros(3))
    long = retime(platform_plan, T=1e6, rest_to_rest=True)
    with pytest.raises(ValueError, match=r"^played: .*MAX_STAGE_STEPS"):
        model_for("platform", COARSE).follow(long, platform_plan.R0, np.zeros(0))


# -- 3. durations and touch-ups bounded ---------------------------------------------------------

@pytest.mark.parametrize("kwargs, word", [({"duration": 1e9}, "duration"), ({"duration": MAX_DURATION * 2}, "duration"),
                                          ({"touch_ups": 10 ** 9}, "touch_ups"),
                                          ({"touch_ups": MAX_TOUCH_UPS + 1}, "touch_ups")])
def test_huge_durations_and_touch_up_counts_are_refused(unicycle_plan, kwargs, word):
    with pytest.raises(ValueError, match=rf"^{word} must be"):
        execute(unicycle_plan, contact=COARSE, **kwargs)


@pytest.mark.parametrize("argv, words", [(["--touch-ups", "1000000000"], "--touch-ups"),
                                         (["--duration", "1e12"], "--duration"),
                                         (["--duration", "inf"], "--duration")])
def test_the_command_line_refuses_them_before_reading_the_plan(tmp_path, capsys, argv, words):
    status = main(["execute", str(tmp_path / "not-read.json"), *argv])
    err = capsys.readouterr().err
    assert status == 2 and words in err and "cannot read" not in err and len(err.strip().splitlines()) == 1


def test_the_command_line_refuses_a_stage_of_too_many_steps_naming_duration(unicycle_plan, tmp_path, capsys):
    path = unicycle_plan.save(tmp_path / "plan.json")
    status = main(["execute", str(path), "--duration", "900"])            # 900 s at the unicycle's 1 ms
    err = capsys.readouterr().err
    assert status == 2 and "--duration 900 s" in err and "MAX_STAGE_STEPS" in err
    assert len(err.strip().splitlines()) == 1


# -- 2. instability is reported, not hidden -----------------------------------------------------

def test_a_stage_mujoco_goes_unstable_in_is_marked_and_ends_the_execution(unicycle_plan, unstable, tmp_path):
    run = execute(unicycle_plan, touch_ups=2, contact=COARSE, duration=3.0)
    assert len(run.stages) == 1
    stage = run.stages[0]
    assert stage["outcome"] == "unstable" and "bad accelerations" in stage["reason"]
    assert stage["error"]["coordinates"] == pytest.approx(0.3, abs=1e-3)     # the error before the stage
    assert 0.2 < stage["sim_time"] < 3.0 and stage["drift"] is None
    assert np.all(run.traces[0]["t"] <= stage["sim_time"] + 1e-12)
    back = Execution.load(run.save(tmp_path / "unstable.json"))
    assert back == run and back.stages[0]["outcome"] == "unstable"
    assert describe(stage, "open loop", {"coordinates": "m"}).startswith("open loop: unstable (MuJoCo went unstable")
    assert "unstable" in repr(run)


def test_an_instability_while_settling_is_reported_too(unicycle_plan, monkeypatch, elsewhere):
    monkeypatch.setattr(UnicycleModel, "pressing",
                        lambda self, m, d: d.xfrc_applied.__setitem__(slice(None), 1e300))
    run = execute(unicycle_plan, touch_ups=1, contact=COARSE, duration=3.0)
    assert [s["outcome"] for s in run.stages] == ["unstable"]
    assert "while the model settled at the start" in run.stages[0]["reason"] and run.stages[0]["sim_time"] == 0.0


def test_a_stage_without_contact_force_left_its_contacts_and_is_marked(unicycle_plan, monkeypatch, elsewhere):
    monkeypatch.setattr(UnicycleModel, "contact_force", lambda self, m, d: 0.0)
    run = execute(unicycle_plan, touch_ups=1, contact=COARSE, duration=3.0)
    assert [s["outcome"] for s in run.stages] == ["unstable"]
    assert "no contact force" in run.stages[0]["reason"]


def test_settings_within_their_ranges_that_throw_the_platforms_disk_off_are_reported(platform_plan, elsewhere):
    """The coarsest step with the strongest press: the disk leaves the sphere at once."""
    run = execute(platform_plan, touch_ups=1, duration=2.0, contact=Contact(timestep=1e-2, preload=1e3))
    assert [s["outcome"] for s in run.stages] == ["unstable"]
    assert "no contact force" in run.stages[0]["reason"] and run.stages[0]["max_contact_force"] == 0.0


def test_non_finite_states_are_an_instability():
    m = mujoco.MjModel.from_xml_string(model_for("unicycle", COARSE).mjcf())
    d = mujoco.MjData(m)
    assert instability(m, d) is None
    d.qvel[0] = np.nan
    assert "non-finite" in instability(m, d)


def test_the_command_line_says_so_and_exits_1(unicycle_plan, unstable, tmp_path, capsys):
    path = unicycle_plan.save(tmp_path / "plan.json")
    status = main(["execute", str(path), "--touch-ups", "1", "--duration", "3", "--json", str(tmp_path / "r.json"),
                   "--plot", str(tmp_path / "e.png")])
    out = capsys.readouterr().out
    assert status == 1 and out.startswith("open loop: unstable")
    assert Execution.load(tmp_path / "r.json").stages[0]["outcome"] == "unstable"
    assert (tmp_path / "e.png").read_bytes()[:4] == b"\x89PNG"             # the samples before it, drawn


# -- 5. Execution.load refuses what save would not write -----------------------------------------

def written(tmp_path, d, name="record.json") -> str:
    path = tmp_path / name
    path.write_text(d if isinstance(d, str) else json.dumps(d))
    return str(path)


def test_a_played_record_round_trips(unicycle_run, tmp_path):
    back = Execution.load(unicycle_run.save(tmp_path / "run.json"))
    assert back == unicycle_run
    assert all(isinstance(v, float) for s in back.stages for k, v in s.items()
               if k in ("max_slip", "max_contact_force", "sim_time", "real_time_factor", "duration"))


@pytest.mark.parametrize("edit, field", [
    (lambda d: d["stages"][0]["error"].update(coordinates="NaN"), r"stages\[0\]\.error\.coordinates"),
    (lambda d: d["stages"][0].update(max_slip="Infinity"), r"stages\[0\]\.max_slip"),
    (lambda d: d["stages"][0].update(sim_time="1e400"), r"stages\[0\]\.sim_time"),
    (lambda d: d["stages"][0].update(max_contact_force="1" + "0" * 400), r"stages\[0\]\.max_contact_force"),
    (lambda d: d["stages"][0].update(size=True), r"stages\[0\]\.size"),
    (lambda d: d["stages"][0].update(extra=1), r"stages\[0\]: unknown fields \['extra'\]"),
    (lambda d: d["contact"].update(preload="1e300"), "preload"),
    (lambda d: d["contact"].update(timestep="1e-9"), "timestep"),
    (lambda d: d.update(stages=[{**d["stages"][0], "outcome": "unstable", "reason": "r"}, d["stages"][0]]),
     r"stages\[0\]\.outcome: a stage 'unstable' ends"),
])
def test_a_record_with_what_save_would_not_write_is_refused_naming_the_file_and_field(
        unicycle_run, tmp_path, edit, field):
    d = json.loads(json.dumps(unicycle_run.to_dict()))
    edit(d)
    text = json.dumps(d)
    for token in ('"NaN"', '"Infinity"', '"1e400"', '"1e300"', '"1e-9"', '"1' + "0" * 400 + '"'):
        text = text.replace(token, token.strip('"'))                    # as bare JSON numbers
    path = written(tmp_path, text)
    with pytest.raises(ValueError, match=rf"^{re.escape(path)}: .*{field}"):
        Execution.load(path)


def test_deep_nesting_is_refused_without_a_recursion_error(unicycle_run, tmp_path):
    d = unicycle_run.to_dict()
    deep = "[" * 100_000 + "]" * 100_000
    for text in (deep, json.dumps(d)[:-1] + ', "more": ' + "[" * 50 + "]" * 50 + "}"):
        path = written(tmp_path, text)
        with pytest.raises(ValueError, match=rf"^{re.escape(path)}: "):
            Execution.load(path)
    shallow = {**d, "stages": [{**d["stages"][0], "error": {"coordinates": [[[[[[1.0]]]]]]}}]}
    with pytest.raises(ValueError, match="nested deeper"):
        Execution.load(written(tmp_path, shallow))


def test_the_figure_s_title_says_how_the_run_ended():
    from nonholo.viz.execution_figures import default_title

    played, skip, unstable = ({"outcome": "played"}, {"outcome": "within tolerance"}, {"outcome": "unstable"})
    assert default_title("car", [played]) == "car on its physics model: open loop"
    assert default_title("car", [played, played, skip]) == (
        "car on its physics model: open loop and 1 touch-up; touch-up 2 not played (within tolerance)")
    assert default_title("car", [unstable]) == "car on its physics model: open loop unstable"
    assert default_title("car", [played, unstable]).endswith("the simulation went unstable in touch-up 1")
