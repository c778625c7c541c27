"""``nonholo execute`` and the execution figure: a saved car plan played on its MuJoCo model
with a touch-up, the record and the model file written and read back, a touch-up not played
reported, bad input refused."""
import json

import numpy as np
import pytest

pytest.importorskip("mujoco")
import mujoco

import nonholo
from nonholo.cli.entry import main
from nonholo.cli.execute_command import describe
from nonholo.physics import Execution
from nonholo.viz.execution_figures import execution_figure, tracking_distance


@pytest.fixture(scope="module")
def car_plan(tmp_path_factory):
    res = nonholo.plan(np.zeros(4), np.array([0.0, 0.5, 0.0, 0.0]), mechanism="car")
    assert res.success, res.reason
    return res.save(tmp_path_factory.mktemp("plan") / "car.json")


@pytest.mark.slow
def test_execute_plays_touches_up_and_writes_its_files(car_plan, tmp_path, capsys):
    report, figure, model = tmp_path / "r.json", tmp_path / "e.png", tmp_path / "car.xml"
    status = main(["execute", str(car_plan), "--touch-ups", "1",
                   "--json", str(report), "--plot", str(figure), "--mjcf", str(model)])
    out = capsys.readouterr().out.splitlines()
    assert status == 0
    assert [line.split(":")[0] for line in out] == ["open loop", "touch-up 1"]
    record = Execution.load(report)
    errors = [s["error"]["coordinates"] for s in record.stages]
    assert errors[0] < 2e-2 and errors[1] < 0.1 * errors[0]
    assert [s["outcome"] for s in json.loads(report.read_text())["stages"]] == ["played", "played"]
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert mujoco.MjModel.from_xml_path(str(model)).nbody > 1
    # the figure needs the run's traces: a record read back has none
    with pytest.raises(ValueError, match="traces"):
        execution_figure(record)


@pytest.mark.parametrize("outcome, words", [("predicted worse", "not played, predicted worse (why)"),
                                            ("within tolerance", "not played, within tolerance (why)"),
                                            ("not planned", "not planned (why)")])
def test_a_touch_up_not_played_is_one_line_saying_why(outcome, words):
    record = {"error": {"coordinates": 1e-3}, "outcome": outcome, "reason": "why", "max_slip": 0.0,
              "real_time_factor": 0.0}
    assert describe(record, "touch-up 2", {"coordinates": "wheelbase"}) == f"touch-up 2: {words}"
    played = dict(record, outcome="played")
    assert describe(played, "touch-up 2", {"coordinates": "wheelbase"}).startswith("touch-up 2: error coordinates 1.00e-03")


@pytest.mark.parametrize("argv, words", [
    (["nothere.json"], "cannot read the plan"),
    (["{plan}", "--touch-ups", "-1"], "--touch-ups"),
    (["{plan}", "--duration", "0"], "duration"),
    (["{plan}", "--plot", "x.nosuchformat"], "unknown figure format"),
])
def test_bad_input_is_one_line_naming_it_and_exit_status_2(car_plan, tmp_path, capsys, argv, words):
    status = main(["execute", *[a.format(plan=car_plan) for a in argv]])
    err = capsys.readouterr().err
    assert status == 2 and words in err and len(err.strip().splitlines()) == 1


def test_tracking_distance_is_the_space_error_between_simulated_and_planned():
    mech = nonholo.model.catalog.get("car")
    q = np.array([[0.0, 0.0, 0.0, 0.0], [0.1, 0.2, 0.3, 0.1]])
    trace = {"R": np.stack([np.eye(3)] * 2), "q": q, "R_planned": np.stack([np.eye(3)] * 2),
             "q_planned": q + np.array([0.0, 0.0, 2 * np.pi, 0.0])}
    d = tracking_distance(mech, trace)
    assert set(d) == {"coordinates"} and np.all(d["coordinates"] < 1e-12)      # angles wrap
