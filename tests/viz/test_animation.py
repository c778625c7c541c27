"""Every mechanism seen moving: :func:`nonholo.viz.animate` for each catalog mechanism, the
drawings of planar vehicles (:mod:`nonholo.model.drawing`, their expressions read as data,
never run) and ``nonholo animate``."""
from __future__ import annotations

import ast
import builtins
import subprocess
import sys
from functools import cache
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
from PIL import Image

import nonholo
from nonholo import viz
from nonholo.cli import main
from nonholo.model import catalog, drawing
from nonholo.model.drawing import Drawing
from nonholo.spaces import so3
from nonholo.viz import animation

ROOT = Path(__file__).resolve().parents[2]

#: A short motion of each catalog mechanism: start, goal, and what its animation shows.
MOTIONS = {
    "platform": (so3.from_rpy(0.5, 1.2, -0.5), so3.from_rpy(0.7, 1.1, -0.5), "platform"),
    "platform_raised": (np.eye(3), so3.from_rpy(0.2, 0.1, 0.1), "platform"),
    "attitude": (so3.from_rpy(0.1, 0.2, 0.3), so3.from_rpy(0.3, 0.1, 0.4), "state"),
    "rolling_ball": ((so3.from_rpy(0.1, 0.2, 0.3), (0.0, 0.0)), (so3.from_rpy(0.3, 0.1, 0.4), (0.3, 0.2)), "ball"),
    "car": ((0.0, 0.0, 0.0, 0.0), (0.5, 0.3, 0.2, 0.0), "vehicle"),
    "brockett": ((0.0, 0.0, 0.0), (0.2, 0.1, 0.1), "state"),
    "unicycle": ((0.0, 0.0, 0.0), (0.5, 0.3, 0.3), "vehicle"),
    "double_integrator": ((0.0, 0.0, 0.0, 0.0), (0.5, 0.3, 0.0, 0.0), "state"),
    "car_with_trailer": ((0.0, 0.0, 0.0, 0.0, 0.0), (0.3, 0.2, 0.2, 0.0, 0.1), "vehicle"),
    "unicycle2": ((0.0, 0.0, 0.0, 0.0, 0.0), (0.3, 0.2, 0.3, 0.0, 0.0), "vehicle"),
}


@cache
def planned(name: str):
    start, goal, _ = MOTIONS[name]
    result = nonholo.plan(start, goal, mechanism=name)
    assert result.success, result.reason
    return result


def frames_of(path: Path) -> list[np.ndarray]:
    with Image.open(path) as image:
        out = []
        for k in range(image.n_frames):
            image.seek(k)
            out.append(np.asarray(image.convert("RGB"), dtype=np.int16))
    return out


def test_every_catalog_mechanism_has_a_motion_here():
    assert set(catalog.names()) <= set(MOTIONS)


@pytest.mark.parametrize("name", sorted(MOTIONS))
@pytest.mark.slow
def test_every_mechanism_is_seen_moving(name, tmp_path):
    result = planned(name)
    assert animation.animation_kind(result) == MOTIONS[name][2]
    out = viz.animate(result, tmp_path / "sub" / f"{name}.gif", frames=4, fps=10, dpi=36)
    assert out == tmp_path / "sub" / f"{name}.gif" and out.stat().st_size > 1000
    frames = frames_of(out)
    assert len(frames) == 4
    # the mechanism moves: beyond the title, the first and the last frames differ widely
    first, last = frames[0], frames[-1]
    body = slice(first.shape[0] // 6, None)
    changed = np.any(first[body] != last[body], axis=-1).mean()
    assert changed > 0.015, f"{name}: only {changed:.2%} of the picture moved"


def test_a_saved_plan_animates_as_the_plan(tmp_path):
    result = planned("car")
    again = nonholo.PlanResult.load(result.save(tmp_path / "car.json"))
    assert again.kinematics.drawing is not None
    a = viz.animate(result, tmp_path / "a.gif", frames=3, dpi=30)
    b = viz.animate(again, tmp_path / "b.gif", frames=3, dpi=30)
    assert all(np.array_equal(x, y) for x, y in zip(frames_of(a), frames_of(b)))


@pytest.mark.slow
def test_the_state_view_for_any_mechanism_and_a_forced_kind(tmp_path):
    result = planned("car")
    out = viz.animate(result, tmp_path / "car_state.gif", frames=3, dpi=30, kind="state")
    assert len(frames_of(out)) == 3
    with pytest.raises(ValueError, match="kind: mechanism 'car' is drawn as 'vehicle'"):
        viz.animate(result, tmp_path / "x.gif", frames=3, kind="ball")
    with pytest.raises(ValueError, match="kind must be one of"):
        viz.animate(result, tmp_path / "x.gif", frames=3, kind="movie")


@pytest.mark.parametrize("arguments, words", [
    ({"frames": 0}, "frames must be an integer >= 1"),
    ({"frames": 2.5}, "frames must be an integer"),
    ({"frames": True}, "frames must be an integer"),
    ({"fps": -1}, "fps must be an integer >= 1"),
    ({"dpi": "80"}, "dpi must be an integer"),
    ({"frames": 10 ** 6}, "frames must be at most"),
])
def test_bad_arguments_are_named(arguments, words, tmp_path):
    with pytest.raises(ValueError, match=words):
        viz.animate(planned("brockett"), tmp_path / "x.gif", **arguments)
    assert not (tmp_path / "x.gif").exists()


@pytest.mark.parametrize("name", ["x.png", "x", "x.gif.txt"])
def test_a_bad_suffix_is_named(name, tmp_path):
    with pytest.raises(ValueError, match="path: .* must end in .gif or .mp4"):
        viz.animate(planned("brockett"), tmp_path / name)


def test_a_directory_is_not_replaced(tmp_path):
    (tmp_path / "d.gif").mkdir()
    with pytest.raises(ValueError, match="path .* is a directory"):
        viz.animate(planned("brockett"), tmp_path / "d.gif", frames=2)


def test_mp4_with_ffmpeg_or_a_clear_error(tmp_path, monkeypatch):
    try:
        executable = animation.ffmpeg_executable()
    except RuntimeError as exc:
        assert "imageio-ffmpeg" in str(exc) and ".gif" in str(exc)
        executable = None
    if executable is not None:
        out = viz.animate(planned("unicycle"), tmp_path / "u.mp4", frames=4, dpi=30)
        data = out.read_bytes()
        assert len(data) > 500 and data[4:8] == b"ftyp"
    # without the package and without ffmpeg on the PATH: the error says what to install
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)
    monkeypatch.setattr(animation.shutil, "which", lambda name: None)
    with pytest.raises(RuntimeError, match="pip install imageio-ffmpeg"):
        viz.animate(planned("unicycle"), tmp_path / "v.mp4", frames=2)
    assert not (tmp_path / "v.mp4").exists()


@pytest.mark.slow
def test_the_progress_bar_is_on_stderr_when_asked(tmp_path, capsys):
    viz.animate(planned("unicycle"), tmp_path / "p.gif", frames=2, dpi=20, progress=True)
    assert "animating p.gif" in capsys.readouterr().err
    viz.animate(planned("unicycle"), tmp_path / "q.gif", frames=2, dpi=20)      # few frames: none
    viz.animate(planned("unicycle"), tmp_path / "r.gif", frames=2, dpi=20, progress=False)
    captured = capsys.readouterr()
    assert "animating" not in captured.err and captured.out == ""


# -- the drawing ---------------------------------------------------------------------------------

CAR = catalog.get("car").drawing


def test_the_car_s_drawing_against_its_geometry():
    rng = np.random.default_rng(3)
    X = rng.uniform(-1.0, 1.0, size=(20, 4))
    x, y, th, ph = X.T
    poses = CAR.poses(X)
    assert poses["bodies"].shape == (20, 1, 3) and poses["wheels"].shape == (20, 4, 3)
    np.testing.assert_allclose(poses["bodies"][:, 0], X[:, :3])
    forward, left = np.stack([np.cos(th), np.sin(th)], 1), np.stack([-np.sin(th), np.cos(th)], 1)
    rear = X[:, :2]
    # the body's centre is 0.5 ahead of the rear axle's centre
    np.testing.assert_allclose(poses["centres"][:, 0], rear + 0.5 * forward)
    # the wheels: rear right, rear left, front right, front left; the front ones steered by φ
    want = [rear - 0.35 * left, rear + 0.35 * left, rear + forward - 0.35 * left, rear + forward + 0.35 * left]
    for j, centre in enumerate(want):
        np.testing.assert_allclose(poses["wheels"][:, j, :2], centre, atol=1e-12)
    np.testing.assert_allclose(poses["wheels"][:, :2, 2], np.stack([th, th], 1))
    np.testing.assert_allclose(poses["wheels"][:, 2:, 2], np.stack([th + ph, th + ph], 1))
    # the outlines: boxes of the given sizes about those centres
    shapes = CAR.outlines(X)
    corners = shapes["bodies"][:, 0]
    np.testing.assert_allclose(np.linalg.norm(corners[:, 1] - corners[:, 0], axis=1), 1.4)
    np.testing.assert_allclose(np.linalg.norm(corners[:, 3] - corners[:, 0], axis=1), 0.8)
    np.testing.assert_allclose(corners.mean(axis=1), poses["centres"][:, 0])
    wheel = shapes["wheels"][:, 3]
    along = wheel[:, 1] - wheel[:, 0]
    np.testing.assert_allclose(np.arctan2(along[:, 1], along[:, 0]), np.arctan2(np.sin(th + ph), np.cos(th + ph)))
    # one state is n = 1; a state of the wrong size is refused
    assert CAR.poses(X[0])["bodies"].shape == (1, 1, 3)
    with pytest.raises(ValueError, match=r"X must be states of shape \(n, 4\)"):
        CAR.poses(X[:, :3])


def test_the_unicycle_s_drawing_and_mechanisms_without_one():
    d = catalog.get("unicycle").drawing
    assert isinstance(d, Drawing) and len(d.bodies) == 1 and len(d.wheels) == 1
    np.testing.assert_allclose(d.poses([0.3, -0.2, 0.7])["wheels"][0, 0], [0.3, -0.2, 0.7])
    for name in ("platform", "attitude", "rolling_ball", "brockett"):
        assert catalog.get(name).drawing is None


TRAILER = {
    "bodies": [{"x": "x", "y": "y", "heading": "theta", "length": 1.4, "width": 0.8, "offset": 0.5},
               {"x": "x - d*cos(theta1)", "y": "y - d*sin(theta1)", "heading": "theta1", "length": 1.0,
                "width": 0.7}],
    "wheels": [{"body": 0, "at": [1.0, 0.35], "steer": "atan2(sin(phi), cos(phi))", "diameter": 0.4},
               {"body": 1, "at": [0.0, -0.3], "diameter": 0.3, "width": 0.1}],
}
TRAILER_COORDINATES = ("x", "y", "theta", "phi", "theta1")


def test_a_drawing_from_data_with_parameters_and_its_round_trip():
    d = Drawing.from_mapping(TRAILER, TRAILER_COORDINATES, {"d": 1.5})
    X = np.array([[1.0, 2.0, 0.3, 0.2, -0.4]])
    poses = d.poses(X)
    np.testing.assert_allclose(poses["bodies"][0, 1], [1.0 - 1.5 * np.cos(-0.4), 2.0 - 1.5 * np.sin(-0.4), -0.4])
    np.testing.assert_allclose(poses["wheels"][0, 0, 2], 0.5)
    assert d.wheels[1].steer is None and d.wheels[0].width == pytest.approx(0.1)
    data = d.to_mapping()
    assert data["bodies"][1]["x"] == "x - d*cos(theta1)" and "steer" not in data["wheels"][1]
    again = Drawing.from_mapping(data, TRAILER_COORDINATES, {"d": 1.5})
    assert again == d and again.to_mapping() == data
    assert Drawing.from_mapping(data, TRAILER_COORDINATES, {"d": 2.0}) != d
    # a number where an expression is due is one
    const = Drawing.from_mapping({"bodies": [{"x": 1, "y": 0.5, "heading": 0, "length": 1, "width": 1}]}, ("q",))
    np.testing.assert_allclose(const.poses(np.zeros((3, 1)))["bodies"][:, 0], [[1.0, 0.5, 0.0]] * 3)


@pytest.mark.parametrize("text, words", [
    ("foo", "unknown name 'foo'"),
    ("x.real", "Attribute is not admitted"),
    ("x[0]", "Subscript is not admitted"),
    ("(lambda: 1)()", r"calls an expression \(Lambda\); only sin, cos"),
    ("lambda: 1", "Lambda is not admitted"),
    ("f'{x}'", "JoinedStr is not admitted"),
    ("[a for a in x]", "ListComp is not admitted"),
    ("{a: 1 for a in x}", "DictComp is not admitted"),
    ("__import__('os').system('true')", r"calls an expression \(Attribute\)"),
    ("open('/etc/passwd')", "calls 'open'"),
    ("eval('1')", "calls 'eval'"),
    ("sin(x, y)", r"sin\(\) takes 1 argument, got 2"),
    ("atan2(x)", r"atan2\(\) takes 2 arguments, got 1"),
    ("sin(*x)", "plain arguments"),
    ("x if y else 1", "IfExp is not admitted"),
    ("x < y", "Compare is not admitted"),
    ("x // y", "FloorDiv is not admitted"),
    ("x @ y", "MatMult is not admitted"),
    ("(x := 1)", "NamedExpr is not admitted"),
    ("True", "True is not a real number"),
    ("'x'", "is not a real number"),
    ("1j", "is not a real number"),
    ("1e400", "is not finite"),
    ("sin", "must be called"),
    ("x +", "is not an expression"),
    ("x\0", "is not an expression"),
    ("", "is empty"),
    ("-" * 40 + "x", "nested more than 32 deep"),
    ("+".join(["x"] * 300), "at most 500"),
])
def test_an_expression_is_data_and_a_refusal_names_the_field(text, words):
    data = {"bodies": [{"x": "x", "y": "y", "heading": "theta", "length": 1, "width": 1},
                       {"x": "x", "y": "y", "heading": text, "length": 1, "width": 1}]}
    with pytest.raises(ValueError, match=r"^drawing\.bodies\[1\]\.heading: .*" + words):
        Drawing.from_mapping(data, ("x", "y", "theta"))


def test_no_expression_runs_code(tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(builtins, "boom", lambda *a: calls.append(a), raising=False)
    marker = tmp_path / "ran"
    for text in ("boom()", f"__import__('os').system('touch {marker}')", "sin.__globals__", "x.__class__",
                 "exec('boom()')", "x(1)"):
        with pytest.raises(ValueError, match=r"drawing\.wheels\[0\]\.steer"):
            Drawing.from_mapping({"bodies": [{"x": "x", "y": "0", "length": 1, "width": 1}],
                                  "wheels": [{"body": 0, "steer": text, "diameter": 0.3}]}, ("x",))
    assert calls == [] and not marker.exists()
    # the module reads text with ast and calls neither eval, exec nor compile
    tree = ast.parse((ROOT / "nonholo" / "model" / "drawing.py").read_text(encoding="utf-8"))
    called = {n.func.id for n in ast.walk(tree) if isinstance(n, ast.Call) and isinstance(n.func, ast.Name)}
    assert not called & {"eval", "exec", "compile", "__import__"}


@pytest.mark.parametrize("data, words", [
    ([], r"^drawing: must be a table"),
    ({"bodies": []}, r"^drawing\.bodies: must hold at least one body"),
    ({"wheels": []}, r"^drawing\.bodies: is missing"),
    ({"bodies": [{"x": "x", "y": "x", "length": 1, "width": 1}], "colour": "red"}, r"^drawing: unknown key 'colour'"),
    ({"bodies": [{"x": "x", "length": 1, "width": 1}]}, r"^drawing\.bodies\[0\]\.y: is missing"),
    ({"bodies": [{"x": "x", "y": "x", "length": -1, "width": 1}]}, r"^drawing\.bodies\[0\]\.length: must be positive"),
    ({"bodies": [{"x": "x", "y": "x", "length": "1", "width": 1}]}, r"^drawing\.bodies\[0\]\.length: must be a number"),
    ({"bodies": [{"x": "x", "y": "x", "length": 1, "width": float("nan")}]},
     r"^drawing\.bodies\[0\]\.width: must be finite"),
    ({"bodies": [{"x": "x", "y": "x", "length": 1, "width": 1, "size": 2}]},
     r"^drawing\.bodies\[0\]: unknown key 'size'"),
    ({"bodies": [{"x": "x", "y": "x", "length": 1, "width": 1}], "wheels": [{"body": 1, "diameter": 1}]},
     r"^drawing\.wheels\[0\]\.body: must be the index of a body \(0 to 0\)"),
    ({"bodies": [{"x": "x", "y": "x", "length": 1, "width": 1}], "wheels": [{"body": True, "diameter": 1}]},
     r"^drawing\.wheels\[0\]\.body"),
    ({"bodies": [{"x": "x", "y": "x", "length": 1, "width": 1}], "wheels": [{"body": 0, "at": [1], "diameter": 1}]},
     r"^drawing\.wheels\[0\]\.at: must be two numbers"),
    ({"bodies": [{"x": "x", "y": "x", "length": 1, "width": 1}], "wheels": [{"body": 0}]},
     r"^drawing\.wheels\[0\]\.diameter: is missing"),
    ({"bodies": "x"}, r"^drawing\.bodies: must be a list of tables"),
])
def test_drawing_data_of_the_wrong_shape_is_named(data, words):
    with pytest.raises(ValueError, match=words):
        Drawing.from_mapping(data, ("x",))


def test_parameters_and_names_are_checked():
    data = {"bodies": [{"x": "x", "y": "d", "length": 1, "width": 1}]}
    with pytest.raises(ValueError, match=r"parameters: d: must be a number"):
        Drawing.from_mapping(data, ("x",), {"d": "2"})
    with pytest.raises(ValueError, match=r"parameters: x: is also a coordinate"):
        Drawing.from_mapping(data, ("x",), {"x": 2.0})
    with pytest.raises(ValueError, match=r"unknown name 'd'"):
        Drawing.from_mapping(data, ("x",))
    with pytest.raises(ValueError, match=r"^where\.bodies\[0\]\.y: unknown name 'd'"):
        Drawing.from_mapping(data, ("x",), where="where")
    # a parameter named like a constant is the parameter
    d = Drawing.from_mapping({"bodies": [{"x": "E", "y": "pi", "length": 1, "width": 1}]}, ("x",), {"E": 2.0})
    np.testing.assert_allclose(d.poses([[0.0]])["bodies"][0, 0], [2.0, np.pi, 0.0])


def test_the_functions_are_those_of_the_derivations():
    from derivations import admission

    assert set(drawing.FUNCTIONS) <= set(admission.FUNCTIONS)


@pytest.mark.slow
def test_drawings_need_neither_matplotlib_nor_sympy():
    code = ("import sys, nonholo\n"
            "d = nonholo.mechanism_named('car').drawing\n"
            "d.poses([[0, 0, 0, 0]])\n"
            "print(sorted(m for m in ('matplotlib', 'sympy') if m in sys.modules))")
    run = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "[]"


# -- nonholo animate -----------------------------------------------------------------------------

@pytest.fixture
def saved_plan(tmp_path) -> Path:
    return planned("car").save(tmp_path / "car.json")


@pytest.mark.slow
def test_the_command_animates_a_saved_plan(saved_plan, tmp_path, capsys):
    out = tmp_path / "car.gif"
    assert main(["animate", str(saved_plan), "--out", str(out), "--frames", "4", "--dpi", "30"]) == 0
    err = capsys.readouterr().err
    assert f"wrote {out}" in err and "animating car.gif" in err          # the progress bar
    assert len(frames_of(out)) == 4
    quiet = tmp_path / "quiet.gif"
    assert main(["animate", str(saved_plan), "--out", str(quiet), "--frames", "3", "--dpi", "30", "-q",
                 "--mechanism", "car"]) == 0
    assert "animating" not in capsys.readouterr().err and len(frames_of(quiet)) == 3


@pytest.mark.parametrize("arguments, words", [
    (["--out", "{tmp}/x.png"], "--out: .* must end in .gif or .mp4"),
    (["--out", "{tmp}/x.gif", "--frames", "0"], "--frames must be an integer >= 1, got 0"),
    (["--out", "{tmp}/x.gif", "--frames", "many"], "--frames must be an integer >= 1, got 'many'"),
    (["--out", "{tmp}/x.gif", "--fps", "-3"], "--fps must be an integer >= 1"),
    (["--out", "{tmp}/x.gif", "--dpi", "100000"], "--dpi must be at most 600"),
    (["--out", "{tmp}/x.gif", "--mechanism", "boat"], "--mechanism: unknown mechanism 'boat'"),
    (["--out", "{tmp}/x.gif", "--mechanism", "unicycle"], "--mechanism: .*the plan is of mechanism 'car'"),
    (["--out", "{tmp}"], "--out: .* must end in .gif or .mp4"),
])
def test_bad_input_exits_2_naming_the_flag(arguments, words, saved_plan, tmp_path, capsys):
    arguments = [a.format(tmp=tmp_path) for a in arguments]
    assert main(["animate", str(saved_plan), *arguments]) == 2
    err = capsys.readouterr().err
    assert err.startswith("nonholo animate: error: ")
    assert __import__("re").search(words, err), err
    assert not (tmp_path / "x.gif").exists() and not (tmp_path / "x.png").exists()


def test_an_unreadable_plan_exits_2(tmp_path, capsys):
    assert main(["animate", str(tmp_path / "none.json"), "--out", str(tmp_path / "x.gif")]) == 2
    assert "cannot read the plan" in capsys.readouterr().err
    (tmp_path / "bad.json").write_text("{", encoding="utf-8")
    assert main(["animate", str(tmp_path / "bad.json"), "--out", str(tmp_path / "x.gif")]) == 2


def test_a_failure_to_write_exits_1(saved_plan, tmp_path, capsys):
    (tmp_path / "file").write_text("", encoding="utf-8")
    assert main(["animate", str(saved_plan), "--out", str(tmp_path / "file" / "x.gif"), "--frames", "2"]) == 1
    assert "cannot write" in capsys.readouterr().err
