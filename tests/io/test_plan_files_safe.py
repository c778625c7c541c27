"""Safe plan files: what is at a path is never destroyed by a write, a plan file cannot
claim a success its own controls do not give, and ``save`` never writes what ``load`` refuses.

- :mod:`nonholo.io.safe_write`: a regular file is replaced atomically; a character device or
  FIFO is written in place and stays what it is; a directory or socket is refused with a
  ``ValueError`` naming the argument (``PlanResult.save``, ``to_csv``, ``nonholo plan
  --out/--csv/--plot``).
- The forgeries of issue 31 — a failed plan relabelled ``nonholo.plan/1`` with ``"success":
  true``; ``options.tol`` deleted; the goal ``Rd`` moved by 9× the plan's tol — are refused,
  each confirmed false by an independent DOP853 re-simulation; option values are held to the
  rules :func:`nonholo.plan` applies (compared with :class:`nonholo.planning.core.Options`).
- Every kind of plan round-trips (leg limits, leg speed with ``T`` given and ``T=None``,
  energy, global routes, failures among them), and a result that would not load is not saved.
"""
from __future__ import annotations

import copy
import json
import os
import socket
import stat
import threading

import numpy as np
import pytest
from conftest import assert_inputs_match, example, example_rpy_args

from nonholo.certify.resimulate import resimulate, terminal_error
from nonholo.cli import plan_command as cli_plan
from nonholo.io import safe_write
from nonholo.io.result import PlanResult
from nonholo.model import catalog
from nonholo.planning.api import plan
from nonholo.planning.core import Options
from nonholo.spaces import so3
from nonholo import Settings
from nonholo.constraints import LegSpeed, LegStroke

R0, RD = example(1)


@pytest.fixture(scope="module")
def paper_plan():
    res = plan(R0, RD, strategy="paper")
    assert res.success
    return res


@pytest.fixture(scope="module")
def failed_plan():
    res = plan(R0, RD, strategy="paper", settings=Settings(max_iter=3), route="local")
    assert not res.success and res.terminal_error > 1e-3
    return res


def char_device(path):
    """A character device at ``path`` (major/minor of ``/dev/null``), or skip the test."""
    try:
        os.mknod(path, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
    except (PermissionError, OSError, AttributeError) as exc:
        pytest.skip(f"cannot make a character device here: {exc}")
    assert stat.S_ISCHR(os.stat(path).st_mode)
    return path


class FifoReader(threading.Thread):
    """Reads everything written to a FIFO (so that a writer's open does not wait forever)."""

    def __init__(self, path):
        super().__init__(daemon=True)
        self.path, self.data = path, None

    def run(self):
        with open(self.path, "rb") as f:
            self.data = f.read()


# -- safe_write on its own ------------------------------------------------------------------

def test_a_regular_file_is_replaced_whole_keeping_its_permissions(tmp_path):
    path = tmp_path / "f.txt"
    path.write_text("old")
    os.chmod(path, 0o640)
    safe_write.write_text(path, "new")
    assert path.read_text() == "new"
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o640
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.txt"]      # no temporary left


@pytest.mark.parametrize("argument", ["path", "--out"])
def test_a_directory_is_refused_naming_the_argument(tmp_path, argument):
    d = tmp_path / "results"
    d.mkdir()
    (d / "inside").write_text("kept")
    with pytest.raises(ValueError, match=rf"^{argument} .*is a directory"):
        safe_write.write_text(d, "x", argument)
    assert d.is_dir() and (d / "inside").read_text() == "kept"
    with pytest.raises(ValueError, match="names a directory"):
        safe_write.write_text(str(tmp_path / "new") + "/", "x", argument)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results"]


def test_a_socket_is_refused(tmp_path):
    path = tmp_path / "s.sock"
    s = socket.socket(socket.AF_UNIX)
    try:
        s.bind(str(path))
        with pytest.raises(ValueError, match="is a socket"):
            safe_write.write_bytes(path, b"x", "--csv")
        assert stat.S_ISSOCK(os.stat(path).st_mode)
    finally:
        s.close()


def test_a_character_device_is_written_in_place_and_stays_one(tmp_path):
    dev = char_device(tmp_path / "null")
    safe_write.write_text(dev, "discarded")
    assert stat.S_ISCHR(os.stat(dev).st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["null"]


def test_a_fifo_is_written_in_place_and_stays_one(tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    reader = FifoReader(fifo)
    reader.start()
    safe_write.write_text(fifo, "through the pipe")
    reader.join(10)
    assert reader.data == b"through the pipe"
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)


def test_a_symbolic_link_is_followed_and_kept(tmp_path):
    target = tmp_path / "target.txt"
    target.write_text("old")
    link = tmp_path / "link.txt"
    link.symlink_to(target)
    safe_write.write_text(link, "new")
    assert link.is_symlink() and target.read_text() == "new"
    (tmp_path / "dir").mkdir()
    (tmp_path / "to_dir").symlink_to(tmp_path / "dir")
    with pytest.raises(ValueError, match="is a directory"):
        safe_write.write_text(tmp_path / "to_dir", "x")


def test_replacing_puts_a_file_in_place_only_when_its_writer_succeeds(tmp_path):
    path = tmp_path / "table.bin"
    path.write_bytes(b"old")
    with pytest.raises(RuntimeError):
        with safe_write.replacing(path, "out") as tmp:
            tmp.write_bytes(b"half")
            raise RuntimeError("writer died")
    assert path.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table.bin"]
    with safe_write.replacing(path, "out") as tmp:
        assert tmp.parent == tmp_path and tmp != path
        tmp.write_bytes(b"new")
    assert path.read_bytes() == b"new"
    (tmp_path / "d").mkdir()
    with pytest.raises(ValueError, match="^out .*directory"):
        with safe_write.replacing(tmp_path / "d", "out"):
            pytest.fail("the block runs only for a path that can be written")


def test_a_path_that_is_not_a_path_is_a_type_error():
    for bad in (None, 3, b"bytes"):
        with pytest.raises(TypeError, match="path"):
            safe_write.write_text(bad, "x")


# -- PlanResult.save / to_csv at such paths ------------------------------------------------------

def test_save_leaves_a_character_device_a_character_device(tmp_path, paper_plan):
    dev = char_device(tmp_path / "plan.json")
    paper_plan.save(dev)
    assert stat.S_ISCHR(os.stat(dev).st_mode)
    paper_plan.to_csv(dev)
    assert stat.S_ISCHR(os.stat(dev).st_mode)


def test_figures_are_written_safely(tmp_path):
    """``save_figure`` (every figure ``nonholo reproduce`` and ``--plot`` write) writes a
    character device in place and refuses a directory, leaving it as it was."""
    from matplotlib.figure import Figure

    from nonholo.viz.style import save_figure

    fig = Figure()
    fig.add_subplot().plot([0, 1])
    dev = char_device(tmp_path / "f.png")
    (tmp_path / "f.pdf").mkdir()
    with pytest.raises(ValueError, match="is a directory"):
        save_figure(fig, "f", tmp_path)
    assert stat.S_ISCHR(os.stat(dev).st_mode) and not any((tmp_path / "f.pdf").iterdir())
    (tmp_path / "f.pdf").rmdir()
    png, pdf = save_figure(fig, "f", tmp_path)
    assert stat.S_ISCHR(os.stat(png).st_mode) and pdf.read_bytes().startswith(b"%PDF")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.pdf", "f.png"]     # no temporary left


def test_save_refuses_a_directory_naming_the_argument(tmp_path, paper_plan):
    d = tmp_path / "plan.json"
    d.mkdir()
    with pytest.raises(ValueError, match="^path .*is a directory"):
        paper_plan.save(d)
    with pytest.raises(ValueError, match="^path .*is a directory"):
        paper_plan.to_csv(d)
    assert d.is_dir() and not any(d.iterdir())


def test_save_writes_a_fifo_in_place_with_a_plan_that_loads(tmp_path, paper_plan):
    fifo = tmp_path / "plan.json"
    os.mkfifo(fifo)
    reader = FifoReader(fifo)
    reader.start()
    paper_plan.save(fifo)
    reader.join(60)
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert PlanResult.from_dict(json.loads(reader.data)) == paper_plan


# -- the command line ---------------------------------------------------------------------------

def cli(argv):
    import argparse

    parser = argparse.ArgumentParser(prog="nonholo")
    cli_plan.add_parser(parser.add_subparsers(dest="command"))
    return cli_plan.run(parser.parse_args(["plan", *argv]))


def test_cli_writes_devices_in_place_and_refuses_directories_naming_the_option(tmp_path, capsys):
    start, goal = example_rpy_args(1)
    dev = char_device(tmp_path / "dev")
    for flag in ("--plot", "--csv"):
        (tmp_path / flag[2:]).mkdir()
    code = cli(["--from", *start, "--to", *goal, "--strategy", "paper", "--quiet", "--out", str(dev),
                "--plot", str(tmp_path / "plot"), "--csv", str(tmp_path / "csv")])
    out, err = capsys.readouterr()
    assert code == 3
    assert stat.S_ISCHR(os.stat(dev).st_mode) and f"wrote {dev}" in out
    lines = err.splitlines()
    assert len(lines) == 2
    for line, flag in zip(lines, ("--plot", "--csv")):
        assert line.startswith(f"nonholo plan: error: cannot write {tmp_path / flag[2:]}: {flag} ")
        assert "is a directory" in line
        assert (tmp_path / flag[2:]).is_dir()


@pytest.mark.slow
def test_cli_plot_without_an_extension_keeps_its_name(tmp_path):
    start, goal = example_rpy_args(1)
    path = tmp_path / "figure"
    assert cli(["--from", *start, "--to", *goal, "--strategy", "paper", "--quiet", "--plot", str(path)]) == 0
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["figure"]


# -- plan files that cannot lie -----------------------------------------------------------------

def file_of(res) -> dict:
    return json.loads(res.to_json())


def load(tmp_path, d) -> PlanResult:
    path = tmp_path / "forged.json"
    path.write_text(json.dumps(d))
    return PlanResult.load(path)


def replayed_error(d) -> float:
    """Independent check: the file's controls re-simulated by DOP853 from its ``R0``, the
    distance of the endpoint from its ``Rd`` (rad)."""
    from nonholo.io import plan_file

    values, _ = plan_file.decode(d)
    par = values["parametrisation"]
    R_T = resimulate(values["start"].R, par, values["T"], values["mechanism"], par.breakpoints)
    return terminal_error(R_T, values["goal"].R)


def test_forgery_a_failed_plan_relabelled_format_1_with_success_true(tmp_path, failed_plan):
    d = file_of(failed_plan)
    d["format"] = "nonholo.plan/1"
    del d["route"]                     # format 1 had no routes
    for key in ("sensitivity", "error_bound", "replay_steps"):
        d.pop(key)                     # nor certificates
    assert load(tmp_path, d) == failed_plan          # as it is: a failure, loaded as one
    d["success"] = True
    assert replayed_error(d) > 1e-3 > d["options"]["tol"]     # the claim is false
    with pytest.raises(ValueError, match="'success' is true, but the plan's controls are not certified"):
        load(tmp_path, d)
    # nor with the options that would check it taken away
    del d["options"]
    with pytest.raises(ValueError, match="missing field 'options'"):
        load(tmp_path, d)


@pytest.mark.parametrize("key", ["tol", "delta_min", "gamma", "max_iter", "harmonics"])
def test_forgery_an_option_deleted_is_refused_not_unchecked(tmp_path, paper_plan, key):
    d = file_of(paper_plan)
    del d["options"][key]
    with pytest.raises(ValueError, match=rf"'options' lacks '{key}'"):
        load(tmp_path, d)


def test_forgery_tol_deleted_and_goal_moved(tmp_path, paper_plan):
    """The issue's second forgery: ``options.tol`` deleted and the goal moved 1e-3 rad."""
    d = file_of(paper_plan)
    d["Rd"] = (so3.exp([1e-3, 0.0, 0.0]) @ np.array(d["Rd"])).tolist()
    assert replayed_error(d) > 0.9e-3
    del d["options"]["tol"]
    with pytest.raises(ValueError, match="'options' lacks 'tol'"):
        load(tmp_path, d)


@pytest.mark.parametrize("consistent", [False, True])
def test_forgery_goal_moved_by_more_than_tol(tmp_path, paper_plan, consistent):
    """The issue's third forgery: ``Rd`` moved by 9e-10 rad, 9× the plan's tol. With
    ``consistent``, ``terminal_error`` is rewritten to match the moved goal, so only the
    success check itself (on the replayed endpoint) can refuse it."""
    from nonholo.numerics import kernels

    d = file_of(paper_plan)
    tol = d["options"]["tol"]
    assert tol == 1e-10 and d["terminal_error"] + d["error_bound"] <= tol
    d["Rd"] = (so3.exp([9e-10, 0.0, 0.0]) @ np.array(d["Rd"])).tolist()
    assert replayed_error(d) > 5 * tol                                    # the claim is false
    if consistent:
        R_last = np.ascontiguousarray(d["R"][-1], dtype=float)
        d["terminal_error"] = float(kernels.log_error(R_last, np.ascontiguousarray(d["Rd"]))[1])
        with pytest.raises(ValueError, match=r"'success' is true, but the controls replayed .* > tol = 1e-10"):
            load(tmp_path, d)
    else:
        with pytest.raises(ValueError, match="'terminal_error'"):
            load(tmp_path, d)
    d["success"] = False                        # the same file claiming no success is honest
    if consistent:
        assert not load(tmp_path, d).success


def test_a_goal_moved_within_tol_still_loads(tmp_path, paper_plan):
    """The tolerance is the plan's tol, not more and not less: a goal moved by a small
    fraction of tol, which the replay still reaches within tol, loads."""
    d = file_of(paper_plan)
    slack = d["options"]["tol"] - d["terminal_error"] - d["error_bound"]
    assert slack > 0
    d["Rd"] = (so3.exp([0.01 * slack, 0.0, 0.0]) @ np.array(d["Rd"])).tolist()
    res = load(tmp_path, d)
    assert res.success and replayed_error(d) <= d["options"]["tol"]


# option, value, refused by load — a value plan() accepts must load, one it refuses must not
OPTION_VALUES = [("tol", v) for v in (1e-3, 1e-16, 0.0, -1.0, 1e300, "1e-3", True, None)] + \
    [("delta_min", v) for v in (-1.0, 0.0, 0.5, "0.01", None)] + \
    [("gamma", v) for v in (0.0, 2.0, -0.5)] + [("step", v) for v in (0.0, 0.5)] + \
    [("min_step", v) for v in (-1e-6, 1e-3)] + [("newton_below", v) for v in (-1.0, 0.0)] + \
    [("max_iter", v) for v in (-1, 0, 2.5, True)]


def plan_refuses(key, value) -> bool:
    """Whether :func:`nonholo.plan` refuses ``key=value`` (its own check of the option)."""
    try:
        Options(**{key: value})
    except (ValueError, TypeError):
        return True
    return False


@pytest.mark.parametrize("key,value", OPTION_VALUES)
def test_option_values_are_checked_as_plan_checks_them(tmp_path, failed_plan, key, value):
    """On a failed plan (no success to judge), so that only the value's own check counts."""
    d = file_of(failed_plan)
    d["options"][key] = value
    if plan_refuses(key, value):
        with pytest.raises(ValueError, match=f"'options' has a bad {key}"):
            load(tmp_path, d)
    else:
        assert load(tmp_path, d).options[key] == value


@pytest.mark.parametrize("key,value,field", [
    ("tol", 1e-16, "success"),                # a success at a tol its replay does not meet
    ("delta_min", 0.9, "success"),            # nor keeps that clearance
    ("delta_min", -1.0, "options"),           # plan() refuses it
    ("tol", -1e-3, "options"),
])
def test_a_success_under_forged_options_is_refused(tmp_path, paper_plan, key, value, field):
    d = file_of(paper_plan)
    d["options"][key] = value
    with pytest.raises(ValueError, match=f"'{field}'"):
        load(tmp_path, d)


def test_a_success_without_its_certificate_is_refused_whatever_its_tol(tmp_path, failed_plan):
    """A failed plan 5e-3 rad off its goal claims success with tol loosened to 1 rad (a
    value plan() accepts): a success of format 3 needs its certificate, which it lacks."""
    d = file_of(failed_plan)
    d["success"] = True
    for key in ("sensitivity", "error_bound", "replay_steps"):
        d[key] = None
    d["options"]["tol"] = 1.0
    with pytest.raises(ValueError, match="no certificate"):    # a success needs its certificate
        load(tmp_path, d)


@pytest.mark.parametrize("value", [1e9, 5e3])
def test_a_sensitivity_plan_would_not_certify_is_refused(tmp_path, paper_plan, value):
    d = file_of(paper_plan)
    d["sensitivity"] = value
    d["error_bound"] += value * 1e-13          # even with a bound that covers it
    with pytest.raises(ValueError, match="'(sensitivity|success)'"):
        load(tmp_path, d)
    d = file_of(paper_plan)
    d["sensitivity"] = None
    with pytest.raises(ValueError, match="'sensitivity' is null"):
        load(tmp_path, d)


def test_an_unknown_option_is_refused(tmp_path, paper_plan):
    d = file_of(paper_plan)
    d["options"]["skip_checks"] = True
    with pytest.raises(ValueError, match="'options' has unknown option 'skip_checks'"):
        load(tmp_path, d)


def test_certificate_fields_are_required_in_format_3(tmp_path, paper_plan):
    for key in ("sensitivity", "error_bound", "replay_steps", "route"):
        d = file_of(paper_plan)
        del d[key]
        with pytest.raises(ValueError, match=f"missing field '{key}'"):
            load(tmp_path, d)


# -- save never writes what load refuses -------------------------------------------------------

def test_save_refuses_a_result_load_would_refuse_and_writes_nothing(tmp_path, failed_plan, paper_plan):
    path = tmp_path / "plan.json"
    paper_plan.save(path)
    before = path.read_bytes()
    forged = copy.copy(failed_plan)
    forged.success = True
    with pytest.raises(ValueError, match="cannot save the plan, its file would not load: .*'success'"):
        forged.save(path)
    with pytest.raises(ValueError, match="cannot save"):
        forged.save(tmp_path / "new.json")
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.json"]


def test_numpy_scalars_in_options_are_saved_as_numbers(tmp_path, paper_plan):
    res = copy.copy(paper_plan)
    res.options = {**paper_plan.options, "tol": np.float64(1e-10), "harmonics": np.int64(2)}
    assert PlanResult.load(res.save(tmp_path / "plan.json")) == paper_plan


def far_pair():
    """A pair of platform orientations the local plan does not solve in T = 1, whose
    plans take the global route (found by ``benchmarks/plan_roundtrip.py``)."""
    from benchmarks import goalset

    pair = goalset.uniform_pairs("platform", 39)[38]
    return pair["R0"], pair["Rd"]


ROUND_TRIP = {
    "leg limits": lambda: plan(R0, RD, constraints=[LegStroke(0.3, 2.0)]),
    "leg speed, T given, kept": lambda: plan(R0, RD, T=30.0, constraints=[LegSpeed(0.5)]),
    "leg speed, T given, re-timed": lambda: plan(R0, RD, T=1.0, constraints=[LegSpeed(0.5)]),
    "leg speed, T given, too short": lambda: plan(R0, RD, T=1.0, constraints=[LegSpeed(0.2)]),
    "leg speed, least time": lambda: plan(R0, RD, T=None, constraints=[LegSpeed(0.5)]),
    "energy": lambda: plan(R0, RD, objective="energy"),
    "global route, least time": lambda: plan(*far_pair(), T=None, constraints=[LegSpeed(0.5)]),
    "global route, too short for the leg speed": lambda: plan(*far_pair(), T=1.0, constraints=[LegSpeed(0.5)]),
    "not converged": lambda: plan(R0, RD, strategy="paper", settings=Settings(max_iter=2), route="local"),
}


@pytest.mark.parametrize("name", list(ROUND_TRIP))
@pytest.mark.slow
def test_every_kind_of_plan_saves_and_loads_back_equal(tmp_path, name):
    res = ROUND_TRIP[name]()
    expected = {"leg speed, T given, too short": False, "global route, too short for the leg speed": False,
                "not converged": False}.get(name, True)
    assert res.success == expected, res.reason
    if name.startswith("global route"):
        assert res.route == "global"
    if "least time" in name or "re-timed" in name:
        assert res.parametrisation.kind == "retimed"
    if "kept" in name:
        assert res.parametrisation.kind != "retimed" and res.options["leg_speed"] == 0.5
    res.validate()
    path = res.save(tmp_path / "plan.json")
    back = PlanResult.load(path)
    assert back == res
    if res.parametrisation.kind == "retimed":        # samples of the controls as the file rebuilds them
        # (re-integrated frame nodes) against those the plan stored (the planner's nodes):
        # two computations of the same inputs
        assert_inputs_match(back.controls(back.t), res.u)
    if res.success:              # an independent check of what the loaded file claims
        mech = catalog.get(res.mechanism)
        R_T = resimulate(back.R0, back.controls, back.T, mech, back.breakpoints)
        assert terminal_error(R_T, back.Rd) <= back.options["tol"] + 1e-12


def as_format_1(res) -> dict:
    """``res`` (physical controls) as a file of format ``nonholo.plan/1`` would hold it: no
    route, no certificate, the samples those of the planner's own replay on ``steps`` steps."""
    from nonholo.motion import playback
    from nonholo.numerics import kernels

    mech = catalog.get(res.mechanism)
    d = file_of(res)
    d["format"] = "nonholo.plan/1"
    del d["route"]
    for key in ("sensitivity", "error_bound", "replay_steps"):
        del d[key]
    sign = float(np.sign(mech.delta(res.R0)))
    R, done, dmin, _ = playback.replay(res.start, res.parametrisation, res.T, mech, res.steps, sign)
    assert done == res.steps
    d["R"] = R.tolist()
    d["delta"] = mech.delta_samples(R, None).tolist()
    d["min_delta"] = float(dmin)
    d["terminal_error"] = float(kernels.log_error(np.ascontiguousarray(R[-1]), np.ascontiguousarray(res.Rd))[1])
    return d


def test_a_format_1_success_is_certified_on_load(tmp_path, paper_plan):
    """The same standard for every format: a genuine old success loads (its controls are
    certified on load as plan() certifies them), and the same file at a tol its controls
    cannot be certified for is refused, although its stored numbers alone would pass."""
    d = as_format_1(paper_plan)
    assert d["terminal_error"] <= 1e-13
    res = load(tmp_path, d)
    assert res.success and res.replay_steps is None
    d["options"]["tol"] = 2e-13                # above the stored terminal error, below the bound
    with pytest.raises(ValueError, match="'success' is true, but the plan's controls are not certified"):
        load(tmp_path, d)
