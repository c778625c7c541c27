"""Plans cannot be lost or forged: atomic saving, the command line's handling of files it
cannot write and of a closed stdout, and the checks of :meth:`PlanResult.load`.

A plan file is accepted only if it is one :func:`nonholo.plan` can have written: every
field of the right type and shape, and its numbers consistent — the stored samples are the
stored controls replayed from ``R0``. Every kind of plan the planner produces loads (complete,
failed, stopped early, refused without a trajectory, frame and physical controls, a mechanism
without a singular set); each forgery below is rejected with a ``ValueError`` naming the
field; a damaged byte either makes the file invalid or leaves its results as they were.
"""
from __future__ import annotations

import argparse
import copy
import errno
import json
import os
import re
import subprocess
import sys

import numpy as np
import pytest
from conftest import example, example_rpy_args

import nonholo
from nonholo import Settings
from nonholo.cli import plan_command as cli_plan
from nonholo.io.result import PlanResult
from nonholo.spaces import so3

# -- plans of every kind (computed once) -----------------------------------------------------

R0, Rd = example(1)
ACROSS = so3.from_rpy(-1.0, 0.9, -0.5)        # Δ has the other sign: refused, no trajectory

KINDS = {
    "robust": {},                                           # frame controls (Fourier)
    "robust_grid": {"settings": Settings(method="nonparametric", grid=40)},  # frame controls (grid)
    "paper": {"strategy": "paper"},                          # physical Fourier controls
    "paper_grid": {"strategy": "paper", "settings": Settings(method="nonparametric", grid=40)},
    "failed": {"strategy": "paper", "settings": Settings(max_iter=3), "route": "local"},  # complete, not converged
    "stopped": {"strategy": "paper", "route": "local",       # trajectory stops before T
                "u0": lambda t: np.stack([5 * np.sin(9 * t), 3 * np.cos(7 * t)], -1)},
    "refused": {"Rd": ACROSS},                               # no trajectory at all
    "attitude": {"mechanism": "attitude"},                   # no singular set
    "attitude_paper": {"mechanism": "attitude", "strategy": "paper"},
}
_PLANS: dict = {}


def plan_of(kind: str) -> PlanResult:
    if kind not in _PLANS:
        kw = dict(KINDS[kind])
        _PLANS[kind] = nonholo.plan(R0, kw.pop("Rd", Rd), **kw)
    return _PLANS[kind]


def saved(tmp_path, kind: str) -> dict:
    """The JSON object of a saved plan of ``kind``."""
    return json.loads(plan_of(kind).save(tmp_path / f"{kind}.json").read_text())


def write(tmp_path, d, name="forged.json"):
    path = tmp_path / name
    path.write_text(json.dumps(d, indent=1))
    return path


def is_what_it_says(kind: str, res: PlanResult) -> bool:
    """The plan of ``kind`` is of that kind (so the tests below cover every kind)."""
    n = len(res.t)
    return {
        "robust": res.parametrisation.kind == "frame" and res.success,
        "robust_grid": res.parametrisation.kind == "frame" and res.method == "nonparametric",
        "paper": res.parametrisation.kind == "fourier" and res.success,
        "paper_grid": res.parametrisation.kind == "piecewise_constant" and res.success,
        "failed": not res.success and n == res.steps + 1 and res.terminal_error > 1e-3,
        "stopped": not res.success and 1 < n < res.steps + 1 and res.terminal_error is None,
        "refused": not res.success and n == 0 and res.terminal_error is None,
        "attitude": res.delta is None and res.min_delta is None and res.parametrisation.kind == "frame",
        "attitude_paper": res.delta is None and res.parametrisation.kind == "fourier",
    }[kind]


# -- saving is atomic ------------------------------------------------------------------------

@pytest.mark.parametrize("failing", ["os.replace", "os.fsync"])
def test_a_failed_save_leaves_the_previous_file_and_no_temporary_file(tmp_path, monkeypatch, failing):
    path = tmp_path / "plan.json"
    plan_of("paper").save(path)
    before = path.read_bytes()

    def disk_full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(os, failing.split(".")[1], disk_full)
    with pytest.raises(OSError, match="No space left"):
        plan_of("robust").save(path)
    monkeypatch.undo()
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.json"]
    assert PlanResult.load(path) == plan_of("paper")
    # and once the disk has room again the new plan replaces the old one
    plan_of("robust").save(path)
    assert PlanResult.load(path) == plan_of("robust")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.json"]


# -- the command line ------------------------------------------------------------------------

def cli(argv):
    parser = argparse.ArgumentParser(prog="nonholo")
    cli_plan.add_parser(parser.add_subparsers(dest="command"))
    return cli_plan.run(parser.parse_args(["plan", *argv]))


@pytest.mark.parametrize("broken", ["out", "plot", "both"])
@pytest.mark.parametrize("goal", ["reachable", "across"])
@pytest.mark.slow
def test_cli_a_file_it_cannot_write_is_one_error_line_and_exit_status_3(tmp_path, capsys, broken, goal):
    start, to = example_rpy_args(1)
    if goal == "across":
        to = [repr(float(x)) for x in so3.as_rpy(ACROSS)]
    (tmp_path / "a_directory").mkdir()
    unwritable = {"out": tmp_path / "a_directory", "plot": tmp_path / "missing" / "plan.png"}
    files = {"out": tmp_path / "plan.json", "plot": tmp_path / "plan.png"}
    for what in (("out", "plot") if broken == "both" else (broken,)):
        files[what] = unwritable[what]
    code = cli(["--from", *start, "--to", *to, "--quiet", "--out", str(files["out"]),
                "--plot", str(files["plot"])])
    out, err = capsys.readouterr()
    assert code == 3
    # the summary comes first; each unwritable file is one line naming it and the OS error
    assert out.startswith("success:" if goal == "reachable" else "FAILED:")
    lines = err.splitlines()
    assert len(lines) == (2 if broken == "both" else 1)
    for line, what in zip(lines, [w for w in ("out", "plot") if files[w] == unwritable[w]]):
        assert line.startswith("nonholo plan: error:") and str(unwritable[what]) in line
        assert ("is a directory" if what == "out" else "No such file or directory") in line.lower().replace("no such", "No such")
    # the file that could be written was written
    if broken == "plot":
        assert PlanResult.load(files["out"]).success == (goal == "reachable")
        assert f"wrote {files['out']}" in out
    if broken == "out":
        assert files["plot"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert f"wrote {files['plot']}" in out


def test_cli_documents_its_exit_statuses():
    doc = cli_plan.__doc__
    assert "0 on success, 1 if the planner failed, 2 on bad input, 3 if ``--out``," in doc
    assert "``--plot`` or ``--csv`` could not be written" in doc


@pytest.mark.parametrize("reader", ["head -1", "true"])
@pytest.mark.slow
def test_cli_output_closed_by_its_reader_is_not_an_error(tmp_path, reader):
    start, goal = example_rpy_args(1)
    out = tmp_path / "plan.json"
    cmd = " ".join([sys.executable, "-m", "nonholo.cli", "plan", "--from", *start, "--to", *goal,
                    "--strategy", "paper", "--out", str(out)])
    proc = subprocess.run(["bash", "-c", f'{cmd} | {reader}; exit "${{PIPESTATUS[0]}}"'],
                          capture_output=True, text=True, timeout=600)
    assert "Traceback" not in proc.stderr and "BrokenPipe" not in proc.stderr, proc.stderr
    assert proc.returncode == 0, proc.stderr
    assert len(proc.stdout.splitlines()) == (0 if reader == "true" else 1)
    assert PlanResult.load(out).success                     # the plan is not lost either


# -- loading: every kind of plan, and each forgery ------------------------------------------------

@pytest.mark.parametrize("kind", list(KINDS))
def test_every_kind_of_plan_loads_and_its_results_cannot_be_changed(tmp_path, kind):
    res = plan_of(kind)
    assert is_what_it_says(kind, res)
    path = res.save(tmp_path / "plan.json")
    assert PlanResult.load(path) == res
    d = json.loads(path.read_text())
    forged = copy.deepcopy(d)
    if not res.success:
        forged["success"] = True
        with pytest.raises(ValueError, match="'success'"):
            PlanResult.load(write(tmp_path, forged))
    if len(res.t):
        forged = copy.deepcopy(d)
        forged["R"][-1] = so3.from_rpy(*(so3.as_rpy(res.R[-1]) + 1e-6)).tolist()
        with pytest.raises(ValueError, match="'R'"):
            PlanResult.load(write(tmp_path, forged))
    else:
        forged = copy.deepcopy(d)
        forged["terminal_error"] = 0.0
        with pytest.raises(ValueError, match="'terminal_error'"):
            PlanResult.load(write(tmp_path, forged))


def test_a_byte_order_mark_is_accepted(tmp_path):
    path = plan_of("robust").save(tmp_path / "plan.json")
    path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    assert PlanResult.load(path) == plan_of("robust")


def test_a_plan_kept_without_its_wall_time_loads(tmp_path):
    """``seconds`` null (as ``nonholo reproduce`` writes plans) is "not recorded"; the rest
    of the plan is the same, and saving it again writes the same text."""
    import dataclasses

    plan = plan_of("paper")
    path = dataclasses.replace(plan, seconds=None).save(tmp_path / "plan.json")
    assert json.loads(path.read_text())["seconds"] is None
    again = PlanResult.load(path)
    assert again.seconds is None and "wall time not recorded" in repr(again)
    assert dataclasses.replace(again, seconds=plan.seconds) == plan
    assert again.to_json() == path.read_text()


def _rotated(R, angle=1e-6):
    return (so3.exp([angle, -angle, 2 * angle]) @ np.asarray(R)).tolist()


def _set(path, value):
    """A forgery: ``d[path[0]][path[1]]... = value`` (``value(old)`` if callable)."""
    def forge(d):
        *head, last = path
        target = d
        for k in head:
            target = target[k]
        target[last] = value(target[last]) if callable(value) else value
    return forge


def _delete(key):
    def forge(d):
        del d[key]
    return forge


def _scale_param(factor):
    def forge(d):
        c = d["controls"]["frame"] if d["controls"]["kind"] == "frame" else d["controls"]
        c["coeffs" if "coeffs" in c else "values"][0][0] *= factor
    return forge


# (plan kind, forgery, field named in the message, further text in the message)
FORGERIES = {
    "success as a string": ("failed", _set(["success"], "false"), "success", "true or false"),
    "success as a number": ("paper", _set(["success"], 1), "success", ""),
    "success of a failed plan": ("failed", _set(["success"], True), "success", "no certificate"),
    "success of a plan without its certificate": (
        "paper", lambda d: d.update(replay_steps=None, error_bound=None), "success", "no certificate"),
    "error bound below the replay's": ("paper", _set(["error_bound"], 1e-30), "error_bound", "estimate"),
    "success beyond tol": ("paper", _set(["options", "tol"], 1e-16), "success", "tol"),
    "replay steps not a multiple": ("paper", _set(["replay_steps"], 1000), "replay_steps", "multiple"),
    "success of a stopped plan": ("stopped", _set(["success"], True), "success", ""),
    "relabelled mechanism": ("paper", _set(["mechanism"], "platform_raised"), "R", "controls"),
    "relabelled mechanism, frame": ("robust", _set(["mechanism"], "platform_raised"), "mechanism", ""),
    "mechanism without singular set": ("paper", _set(["mechanism"], "attitude"), "delta", "null"),
    "unknown mechanism": ("paper", _set(["mechanism"], "teapot"), "mechanism", "unknown"),
    "frame controls of another mechanism": ("robust", _set(["controls", "mechanism"], "platform_raised"),
                                            "controls.mechanism", ""),
    "T against the controls": ("paper", _set(["T"], 2.0), "T", ""),
    "T of plan and controls": ("paper", lambda d: (_set(["T"], 2.0)(d), _set(["controls", "T"], 2.0)(d)),
                               "t", ""),
    "T of the frame controls": ("robust", _set(["controls", "T"], 2.0), "controls.T", ""),
    "R0 against the samples": ("paper", _set(["R0"], _rotated), "R", "R0"),
    "R0 against the frame controls": ("robust", _set(["R0"], _rotated), "R0", "frame controls"),
    "R0 not a rotation": ("refused", _set(["R0"], lambda R: (1.1 * np.array(R)).tolist()), "R0", ""),
    "Rd": ("paper", _set(["Rd"], _rotated), "terminal_error", ""),
    "a sample of R": ("robust", _set(["R", 200], _rotated), "R", "controls"),
    "a sample of R, physical": ("paper_grid", _set(["R", 200], _rotated), "R", "controls"),
    "a sample of R, stopped": ("stopped", _set(["R", 20], _rotated), "R", "controls"),
    "a sample of R, attitude": ("attitude", _set(["R", -1], _rotated), "R", "controls"),
    "an input": ("robust", _set(["u", 100, 0], lambda x: x + 1e-6), "u", ""),
    "a Fourier coefficient": ("paper", _scale_param(1.0 + 1e-6), "R", "controls"),
    "a frame coefficient": ("robust_grid", _scale_param(1.0 + 1e-6), "R", "controls"),
    "a time": ("paper", _set(["t", 5], lambda x: x + 1e-4), "t", ""),
    "times out of order": ("paper", _set(["t"], lambda t: t[::-1]), "t", ""),
    "Δ sample": ("paper", _set(["delta", 3], lambda x: x * 1.01), "delta", ""),
    "Δ missing": ("paper", _set(["delta"], None), "delta", ""),
    "terminal error": ("paper", _set(["terminal_error"], 1e-3), "terminal_error", ""),
    "terminal error of a stopped plan": ("stopped", _set(["terminal_error"], 0.1), "terminal_error", ""),
    "min_delta": ("robust", _set(["min_delta"], lambda x: x + 0.1), "min_delta", ""),
    "min_delta lowered": ("paper", _set(["min_delta"], lambda x: x - 0.1), "min_delta", ""),
    "min_delta of attitude": ("attitude", _set(["min_delta"], 0.5), "min_delta", ""),
    "too few inputs": ("paper", _set(["u"], lambda u: u[:-1]), "u", "shape"),
    "too few Δ": ("paper", _set(["delta"], lambda x: x[:-1]), "delta", "shape"),
    "a trajectory shortened": ("paper", lambda d: [d.update({k: d[k][:-1]}) for k in ("t", "R", "u", "delta")],
                               "replay_steps", "stops"),
    "a ragged R": ("paper", _set(["R", 3], lambda R: R[:2]), "R", ""),
    "steps": ("paper", _set(["steps"], 200), "t", ""),
    "steps as a float": ("paper", _set(["steps"], 400.0), "steps", "integer"),
    "steps zero": ("paper", _set(["steps"], 0), "steps", ""),
    "frame steps": ("robust", _set(["controls", "steps"], 800), "steps", ""),
    "iterations negative": ("paper", _set(["iterations"], -1), "iterations", ""),
    "iterations as a string": ("paper", _set(["iterations"], "12"), "iterations", ""),
    "reason as a number": ("paper", _set(["reason"], 3), "reason", ""),
    "method unknown": ("paper", _set(["method"], "gradient"), "method", ""),
    "method against the controls": ("paper", _set(["method"], "nonparametric"), "method", ""),
    "strategy paper with frame controls": ("robust", _set(["strategy"], "paper"), "strategy", ""),
    "strategy as null": ("robust", _set(["strategy"], None), "strategy", ""),
    "history not a list": ("paper", _set(["history"], 5), "history", ""),
    "options not an object": ("paper", _set(["options"], [1]), "options", ""),
    "seconds negative": ("paper", _set(["seconds"], -1.0), "seconds", ""),
    "sensitivity as a string": ("robust", _set(["sensitivity"], "2"), "sensitivity", ""),
    "a missing field": ("paper", _delete("u"), "u", "missing"),
    "an unknown field": ("paper", _set(["note"], "hello"), "note", "unknown"),
    "controls not an object": ("paper", _set(["controls"], []), "controls", ""),
    "controls of unknown kind": ("paper", _set(["controls", "kind"], "spline"), "controls.kind", ""),
    "controls without coefficients": ("paper", lambda d: d["controls"].pop("coeffs"), "controls", "coeffs"),
    "harmonics against the coefficients": ("paper", _set(["controls", "harmonics"], 3), "controls.coeffs", ""),
    "a number as a string": ("paper", _set(["R", 0, 0, 0], "0.5"), "R", ""),
    "a boolean as a number": ("paper", _set(["u", 0, 0], True), "u", ""),
}


@pytest.mark.parametrize("name", list(FORGERIES))
def test_a_forged_plan_is_rejected_naming_the_field(tmp_path, name):
    kind, forge, field, text = FORGERIES[name]
    d = saved(tmp_path, kind)
    forge(d)
    with pytest.raises(ValueError) as info:
        PlanResult.load(write(tmp_path, d))
    message = str(info.value)
    assert f"'{field}'" in message and text in message, message
    with pytest.raises(ValueError):
        PlanResult.from_dict(d)


# tokens JSON does not have, which Python's json module reads as non-finite floats
NON_FINITE = {
    "NaN in u": ('"u": [\n  [\n   ', "NaN", "u"),
    "Infinity as the terminal error": ('"terminal_error": ', "Infinity", "terminal_error"),
    "-Infinity as T": ('"T": ', "-Infinity", "T"),
    "NaN in R0": ('"R0": [\n  [\n   ', "NaN", "R0"),
    "NaN in the history": ('"error": ', "NaN", "history"),
    "1e999 in t": ('"t": [\n  0.0,\n  ', "1e999", "t"),
}


@pytest.mark.parametrize("name", list(NON_FINITE))
def test_non_finite_numbers_are_rejected_naming_the_field(tmp_path, name):
    anchor, token, field = NON_FINITE[name]
    text = plan_of("paper").save(tmp_path / "plan.json").read_text()
    at = text.index(anchor) + len(anchor)
    number = re.match(r"-?[0-9][0-9.eE+-]*", text[at:])     # the number after the anchor
    assert number, text[at:at + 40]
    path = tmp_path / "forged.json"
    path.write_text(text[:at] + token + text[at + number.end():])
    with pytest.raises(ValueError, match=f"'{field}'"):
        PlanResult.load(path)


MALFORMED = {
    "truncated": lambda text: text[: len(text) // 2],
    "not an object": lambda text: "[" + text + "]",
    "null": lambda text: "null",
    "deeply nested": lambda text: "[" * 200_000 + "]" * 200_000,
    "deeply nested history": lambda text: text.replace('"history": [', '"history": [' + "[" * 200_000
                                                       + "]" * 200_000 + ",", 1),
    "format only": lambda text: json.dumps({"format": "nonholo.plan/1"}),
    "a key twice": lambda text: text.replace('"success": true', '"success": true, "success": false', 1),
    "controls a string": lambda text: text.replace('"controls": {', '"controls": "x", "ctl": {', 1),
}


@pytest.mark.parametrize("name", list(MALFORMED))
def test_a_malformed_file_raises_value_error(tmp_path, name):
    path = plan_of("paper").save(tmp_path / "plan.json")
    path.write_text(MALFORMED[name](path.read_text()))
    with pytest.raises(ValueError) as info:
        PlanResult.load(path)
    assert str(path) in str(info.value)             # the message names the file


def test_a_non_object_or_incomplete_dict_raises_value_error():
    for d in ([], "plan", None, {"format": "nonholo.plan/1", "success": True}):
        with pytest.raises(ValueError):
            PlanResult.from_dict(d)


# -- a damaged byte ---------------------------------------------------------------------------

try:
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st
except ImportError:                                  # not in the "test" extra (yet)
    given = None


def _close(a, b, atol) -> bool:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return a.shape == b.shape and bool(np.all(np.abs(a - b) <= atol))


class SavedPlans(dict):
    """The bytes of a saved plan per kind (short ``repr`` for Hypothesis' reports)."""

    def __repr__(self) -> str:
        return f"<saved plans: {', '.join(self)}>"


@pytest.fixture(scope="module")
def damaged_file(tmp_path_factory):
    """A saved plan per kind and a scratch file for its damaged copies."""
    d = tmp_path_factory.mktemp("damaged")
    files = SavedPlans((k, plan_of(k).save(d / f"{k}.json").read_bytes())
                       for k in ("robust", "paper_grid", "stopped"))
    return files, d / "damaged.json"


if given is None:
    def test_a_changed_byte_is_rejected_or_changes_no_result():
        pytest.importorskip("hypothesis")
else:
    @pytest.mark.slow
    @settings(max_examples=300, deadline=None, suppress_health_check=list(HealthCheck))
    @given(data=st.data())
    def test_a_changed_byte_is_rejected_or_changes_no_result(damaged_file, data):
        files, path = damaged_file
        kind = data.draw(st.sampled_from(sorted(files)), label="kind")
        raw = files[kind]
        header = raw.index(b'"R0"')                     # the scalar fields and the history come first
        at = data.draw(st.one_of(st.integers(0, len(raw) - 1), st.integers(0, header)), label="position")
        byte = data.draw(st.integers(0, 255).filter(lambda b: b != raw[at]), label="byte")
        path.write_bytes(raw[:at] + bytes([byte]) + raw[at + 1:])
        try:
            back = PlanResult.load(path)
        except ValueError:
            return
        back.validate()                                 # what loads is consistent
        orig = plan_of(kind)
        # ... and what it says about the motion is what the plan said, up to round-off
        assert (back.mechanism, back.method, back.steps, back.success) == \
            (orig.mechanism, orig.method, orig.steps, orig.success)
        assert back.T == orig.T and back.parametrisation.kind == orig.parametrisation.kind
        assert _close(back.t, orig.t, 1e-8 * orig.T)
        for key in ("R", "R0", "Rd"):
            assert _close(getattr(back, key), getattr(orig, key), 1e-8), key
        assert _close(back.u, orig.u, 1e-8 * (1.0 + np.abs(orig.u).max()))
        assert _close(back.params, orig.params, 1e-8 * (1.0 + np.abs(orig.params).max()))
        if orig.terminal_error is None:
            assert back.terminal_error is None
        else:
            assert abs(back.terminal_error - orig.terminal_error) <= 1e-8
