"""A fault and attack round, one test per defect found: user text is only data, bad sizes
and horizons are refused naming the argument (the flag, exit 2, on the command line), and
what a result says is what its controls do.

A. a plan file's ``strategy`` label never imports code (an import path needs the caller's
   ``allow_imports=True``); B. a horizon whose inputs are not finite is refused naming ``T``;
C. an atlas too large is refused naming the bound; D. ``derive --dir`` somewhere it cannot
   use is one line naming ``--dir``; E. ``nonholo plan`` succeeds under an ASCII encoding;
F. a failed certification describes the controls the result holds; G. every strategy stops
   when it makes no progress; H. least-time inputs turn at a bounded rate where the path
   nearly stops; I. the largest accepted sizes can be certified; J. a huge integer in a
   problem table names the row and column; K. ``constraints`` that are not constraint
   objects are refused naming ``constraints``; L. a field that is not finite at the start
   or the goal gives a failed result that says so.
"""
from __future__ import annotations

import json
import os
import re
import subprocess
import sys

import numpy as np
import pytest
from conftest import example, example_rpy_args

import nonholo
from nonholo.certify.resimulate import resimulate, terminal_error
from nonholo.certify.certificate import MAX_REPLAY_STEPS
from nonholo.cli.entry import main
from nonholo.io import problems as problem_table
from nonholo.io.result import PlanResult
from nonholo.model import catalog
from nonholo.planning.api import STRATEGIES, plan
from nonholo.planning import correction
from nonholo.planning.problem import Problem
from nonholo.planning.settings import MAX_PLAN_STEPS, arguments_of
from nonholo import Settings

R0, RD = example(1)
QUICK = {"strategy": "paper", "objective": None, "route": "local"}


@pytest.fixture(scope="module")
def quick_plan():
    """A certified plan found in milliseconds."""
    res = plan(R0, RD, **QUICK)
    assert res.success, res.reason
    return res


def test_a_plan_file_s_strategy_label_never_imports_code(quick_plan, tmp_path, monkeypatch):
    """A: a plan file whose ``strategy`` names a module loads (a label is data), but re-planning
    with it, as ``nonholo execute --touch-ups`` does, imports nothing; only the caller's opt-in
    does."""
    from nonholo.physics.execution import replan_options

    marker = tmp_path / "marker"
    (tmp_path / "evil_mod.py").write_text(f"open({str(marker)!r}, 'w').write('ran')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "evil_mod", raising=False)
    d = quick_plan.to_dict()
    d["strategy"] = "evil_mod:X"
    (tmp_path / "p.json").write_text(json.dumps(d))
    loaded = PlanResult.load(tmp_path / "p.json")
    assert loaded.strategy == "evil_mod:X"
    with pytest.raises(ValueError, match="^strategy 'evil_mod:X' is an import path"):
        plan(loaded.start, loaded.goal, mechanism=loaded.mechanism,
             **arguments_of(replan_options(loaded), loaded.mechanism))
    this_before = "this" in sys.modules
    with pytest.raises(ValueError, match="^strategy 'this:x'"):
        plan(R0, RD, strategy="this:x")
    assert not marker.exists() and "evil_mod" not in sys.modules
    assert "this" in sys.modules if this_before else "this" not in sys.modules
    # the explicit opt-in is what imports (X is no strategy: refused after the import)
    with pytest.raises(ValueError, match="cannot be imported"):
        plan(R0, RD, strategy="evil_mod:X", allow_imports=True)
    sys.modules.pop("evil_mod", None)
    assert marker.read_text() == "ran"


def test_a_horizon_whose_inputs_are_not_finite_is_refused_naming_T(quick_plan):
    """B: ``retime`` and ``plan`` refuse a horizon below a nanosecond, naming ``T``."""
    for T in (5e-324, 1e-310, 1e-300):
        with pytest.raises(ValueError, match="^T must be at least"):
            nonholo.retime(quick_plan, T=T, rest_to_rest=True)
        with pytest.raises(ValueError, match="^T must be at least"):
            plan(R0, RD, T=T, **QUICK)
    fast = nonholo.retime(quick_plan, T=1e-6, rest_to_rest=True)
    assert fast.success and np.all(np.isfinite(fast.u)) and np.abs(fast.u).max() > 1e5


def test_an_atlas_too_large_is_refused_naming_the_bound(tmp_path, capsys):
    """C: ``atlas --grid 3000`` (27 million problems) is refused at once, exit 2."""
    out = tmp_path / "atlas.jsonl"
    assert main(["atlas", "--problems", str(out), "--grid", "3000"]) == 2
    err = capsys.readouterr().err
    assert "--grid" in err and "MAX_PROBLEMS = 100,000" in err and "27,000,000" in err
    assert not out.exists()


def test_derive_where_it_cannot_use_the_directory_is_one_line_naming_dir(tmp_path, capsys):
    """D: an unwritable ``--dir`` and ``--check --dir <missing>``: one line naming ``--dir``, exit 2."""
    blocker = tmp_path / "file"
    blocker.write_text("")
    for argv, why in ((["derive", "--dir", str(blocker / "sub")], "is not a directory"),
                      (["derive", "--check", "--dir", str(tmp_path / "missing")], "no such directory")):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "--dir" in err and why in err and "differs" not in err


def test_plan_succeeds_under_an_ascii_output_encoding(tmp_path):
    """E: ``PYTHONIOENCODING=ascii``: "Δ" is written escaped, the exit status is 0."""
    start, goal = example_rpy_args(1)
    env = {**os.environ, "PYTHONIOENCODING": "ascii"}
    run = subprocess.run([sys.executable, "-m", "nonholo.cli", "plan", "--from", *start, "--to", *goal,
                          "--strategy", "paper", "--objective", "none", "--route", "local"],
                         capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300)
    assert run.returncode == 0, run.stderr
    assert "success" in run.stdout and "min|\\u0394|" in run.stdout


def test_a_failed_certification_describes_the_controls_the_result_holds(monkeypatch):
    """F: one correction allowed where two are needed: the plan fails, and the distance its
    reason gives is that of an independent replay of the controls it holds."""
    monkeypatch.setattr(correction, "MAX_CORRECTIONS", 1)
    res = plan(R0, RD, settings=Settings(steps=16), **QUICK)
    assert not res.success and "not certified" in res.reason
    said = float(re.search(r"not certified: the physical replay \(\d+ steps\) ends ([0-9.e+-]+) rad",
                           res.reason).group(1))
    replayed = terminal_error(resimulate(R0, res.controls, res.T, catalog.get("platform"),
                                         res.breakpoints), RD)
    assert said == pytest.approx(replayed, rel=1e-2)


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_every_strategy_stops_when_it_makes_no_progress(strategy):
    """G: a tiny γ with a huge ``max_iter``: a failure saying it stalled, within a few windows."""
    res = plan(R0, RD, strategy=strategy, settings=Settings(gamma=1e-7, max_iter=10**6), route="local", objective=None)
    assert not res.success and "stalled" in res.reason
    assert res.iterations < 1000


def test_least_time_inputs_turn_at_a_bounded_rate_where_the_path_nearly_stops():
    """H: a path whose inputs pass within 1e-3 of zero: the least-time inputs' difference
    quotient, away from the breakpoints, is bounded and does not grow as the sampling is
    refined (the exact least-time map swings them faster the finer one looks)."""
    from nonholo.controls.parametrisations import Fourier
    from nonholo.motion.speed_limits import Retimed

    def u(t):
        return np.stack([0.3 * np.cos(2 * np.pi * t), 0.2 * np.cos(2 * np.pi * t) + 1e-3], axis=-1)

    timed = Retimed(Fourier.fit(u, 1.0, 2, 2), R0, nonholo.mechanism_named("platform"), 0.5)
    bp = timed.breakpoints

    def quotient(n):
        t = np.linspace(0.0, timed.T, n)
        q = np.abs(np.diff(timed(t), axis=0)).max(axis=1) / np.diff(t)
        k = np.searchsorted(t, bp)
        near = np.zeros(n - 1, bool)
        near[np.clip(k - 1, 0, n - 2)] = near[np.clip(k, 0, n - 2)] = True
        return q[~near].max()

    coarse, fine = quotient(80001), quotient(320001)
    assert fine < 1e3 and fine <= 1.1 * coarse


def test_the_largest_accepted_sizes_can_be_certified():
    """I: ``steps`` and ``grid`` at most half the finest certified replay: more could never be
    certified, and a plan on them would spend its whole ``max_iter`` for a certain failure."""
    assert 2 * MAX_PLAN_STEPS <= MAX_REPLAY_STEPS
    with pytest.raises(ValueError, match=f"^steps must be at most {MAX_PLAN_STEPS}"):
        plan([0, 0, 0, 0], [0, 1, 0, 0], mechanism="car", settings=Settings(steps=MAX_PLAN_STEPS + 1))
    with pytest.raises(ValueError, match=f"^grid must be at most {MAX_PLAN_STEPS}"):
        plan([0, 0, 0, 0], [0, 1, 0, 0], mechanism="car",
             settings=Settings(method="nonparametric", grid=MAX_PLAN_STEPS + 1))
    problem = Problem.build([0, 0, 0, 0], [0, 1, 0, 0], mechanism="car", settings=Settings(steps=MAX_PLAN_STEPS))
    assert problem.steps == MAX_PLAN_STEPS


def test_a_huge_integer_in_a_problem_table_names_the_row_and_column(tmp_path):
    """J: an integer beyond a float's range in a row's options."""
    good = {"start": [0, 0, 0, 0], "goal": [0, 1, 0, 0], "mechanism": "car"}
    path = tmp_path / "p.jsonl"
    path.write_text(json.dumps(good) + "\n" + json.dumps({**good, "options": {"leg_length": [1, 10**400]}}) + "\n")
    with pytest.raises(ValueError, match=r"^problem row 1, column 'options.leg_length': is an integer too large"):
        problem_table.read(path)


def test_constraints_that_are_not_constraint_objects_are_refused_naming_constraints():
    """K: ``constraints`` a string, a number or a list of non-constraints: ``TypeError``
    naming it; ``None`` means none."""
    for bad, where in (("x", "constraints must be"), (5, "constraints must be"), ([1], r"constraints\[0\] must be")):
        with pytest.raises(TypeError, match=f"^{where}"):
            plan(R0, RD, constraints=bad)
    default = Problem.build(R0, RD)
    assert Problem.build(R0, RD, constraints=None).constraints == default.constraints


def test_a_field_not_finite_at_the_start_or_the_goal_is_a_failed_result_that_says_so(tmp_path, monkeypatch):
    """L. ``ẋ = v log x``: G is -inf at x = 0 (before: LAPACK's complaints and a LinAlgError)."""
    import sympy as sp

    monkeypatch.setenv("NONHOLO_CACHE_DIR", str(tmp_path))
    x, y, v, w = sp.symbols("x y v w")
    mech = nonholo.Mechanism.from_equations("log_rate", inputs=[v, w], coordinates=[x, y],
                                            rates=[v * sp.log(x), w])
    for start, goal, where in (([0.0, 0.0], [2.0, 1.0], "start"), ([2.0, 0.0], [0.0, 1.0], "goal")):
        res = plan(start, goal, mechanism=mech, objective=None)
        assert not res.success
        assert f"the field G of 'log_rate' is not finite at the {where}" in res.reason, res.reason
    assert plan([2.0, 0.0], [1.5, 1.0], mechanism=mech, objective=None).success   # elsewhere it plans
