"""The Jacobian planner (appendix eqs. (4)–(11)): convergence, verification, bad input, I/O, CLI.

Tests of the appendix's algorithm itself pass ``strategy="paper"``; the default strategy
(``"robust"``) has its own tests in ``test_robust.py`` and joins the generic ones here.
"""
from __future__ import annotations

import argparse
import json

import numpy as np
import pytest
from conftest import (
    assert_inputs_match,
    check_solution,
    example,
    example_rpy_args,
    forbid_simulation,
    paper_reachable_goals,
)

from nonholo.cli import plan_command as cli_plan
from nonholo.controls import parametrisations as C
from nonholo.certify.plan_fields import FORMAT
from nonholo.io.result import PlanResult
from nonholo.motion import simulation as S
from nonholo.motion.frame_controls import FrameControls
from nonholo.numerics import kernels
from nonholo.planning.api import METHODS, STRATEGIES, plan
from nonholo.planning.core import Outcome, Strategy, descend, record
from nonholo.planning.strategy_paper import PaperStrategy
from nonholo.spaces import so3
from nonholo import Settings
from nonholo.planning.settings import arguments_of

EXAMPLES = (1, 2)       # the examples (nonholo.paper.examples) solved by both strategies and both methods


# -- the examples (nonholo.paper.examples) ----------------------------------------------------

@pytest.mark.parametrize("strategy", STRATEGIES)
@pytest.mark.parametrize("k", EXAMPLES)
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.slow
def test_examples_converge_and_resimulate(k, method, strategy):
    R0, Rd = example(k)
    res = plan(R0, Rd, settings=Settings(method=method), strategy=strategy, objective=None)
    check_solution(res, R0, Rd)
    assert res.strategy == strategy
    assert res.iterations <= 20
    assert res.min_delta >= 0.3          # these stay well clear of Δ = 0
    kind = C.Fourier if method == "parametric" else C.PiecewiseConstant
    par = res.parametrisation
    if strategy == "robust":             # planned in the frame coordinates w, u = W(R) w
        assert isinstance(par, FrameControls)
        par = par.frame
    assert isinstance(par, kind)
    assert res.params.size == (10 if method == "parametric" else 200)


@pytest.mark.parametrize("strategy", STRATEGIES)
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.slow
def test_reachable_goals_converge(method, strategy):
    for R0, Rd in paper_reachable_goals(6):
        check_solution(plan(R0, Rd, settings=Settings(method=method), strategy=strategy), R0, Rd)


def test_hard_goal_fails_gracefully():
    """A reachable goal (generated as above) on which the plain θ-flow runs into the barrier."""
    R0, Rd = so3.from_rpy(2.2642, 0.0361, 1.9724), so3.from_rpy(1.6499, 0.1579, 2.7202)
    for method in METHODS:
        res = plan(R0, Rd, settings=Settings(method=method), strategy="paper", route="local")
        assert not res.success
        assert "min_step" in res.reason and "delta_min" in res.reason
        assert res.min_delta >= 1e-2                      # the last accepted trajectory
        assert np.all(np.isfinite(res.R)) and np.isfinite(res.terminal_error)


# -- the θ-flow and the Newton phase ------------------------------------------------------

@pytest.mark.parametrize("method", METHODS)
@pytest.mark.slow
def test_error_decays_as_prescribed_by_the_flow(method):
    """(4)–(5): |l_T(θ+h)|/|l_T(θ)| = e^{−γh} + O(h²) along Euler steps of the θ-flow."""
    R0, Rd = example(1)
    dev = {}
    for step in (0.1, 0.05, 0.025):
        res = plan(R0, Rd, settings=Settings(method=method, gamma=1.0, step=step, max_iter=6, newton_below=0.0),
                   strategy="paper")
        assert all(h["rejected"] == 0 and h["step"] == pytest.approx(step) for h in res.history[1:])
        e = np.array([h["error"] for h in res.history])
        dev[step] = np.abs(e[1:] / e[:-1] - np.exp(-step)).max()
    assert dev[0.1] <= 1e-2
    assert dev[0.05] <= dev[0.1] / 3 and dev[0.025] <= dev[0.05] / 3        # O(h²)


@pytest.mark.parametrize("k", EXAMPLES)
@pytest.mark.parametrize("method", METHODS)
def test_newton_phase_converges_quadratically(k, method):
    R0, Rd = example(k)
    res = plan(R0, Rd, settings=Settings(method=method), strategy="paper", objective=None)
    e = [h["error"] for h in res.history]
    phases = [h["phase"] for h in res.history]
    first = phases.index("newton")
    assert phases[first:] == ["newton"] * (len(phases) - first) and len(phases) - first >= 2
    assert all(h["step"] == 1.0 for h in res.history[first:])
    for a, b in zip(e[first - 1:-1], e[first:]):
        assert b <= 10.0 * a * a, (a, b)


def test_flow_only_converges_linearly_without_newton():
    """Control for the test above: with γh = 0.5 and no Newton phase the error halves."""
    R0, Rd = example(1)
    res = plan(R0, Rd, settings=Settings(tol=1e-30, max_iter=15, newton_below=0.0), strategy="paper")
    e = np.array([h["error"] for h in res.history])
    assert not res.success and "max_iter" in res.reason
    np.testing.assert_allclose(e[-5:] / e[-6:-1], 0.5, rtol=1e-3)


# -- other mechanisms ---------------------------------------------------------------------

@pytest.mark.parametrize("strategy", STRATEGIES)
@pytest.mark.parametrize("method", METHODS)
def test_attitude_mechanism_plans_without_delta_checks(method, strategy):
    R0 = np.eye(3)                                   # fine here: no singular set
    Rd = so3.from_rpy(0.4, -0.3, 0.8)
    res = plan(R0, Rd, settings=Settings(method=method), mechanism="attitude", strategy=strategy)
    check_solution(res, R0, Rd)
    assert all(h["min_delta"] is None for h in res.history)


# -- bad input ------------------------------------------------------------------------------

R_OK = example(1)[0]
RD_OK = example(1)[1]
NON_ORTHO = R_OK + 1e-6


@pytest.mark.parametrize("args, kw, match", [
    ((np.full((3, 3), np.nan), RD_OK), {}, "non-finite"),
    ((R_OK, np.full((3, 3), np.inf)), {}, "non-finite"),
    ((np.eye(2), RD_OK), {}, "shape"),
    ((R_OK, [[1, 0, 0], [0, 1, 0]]), {}, "shape"),
    ((R_OK, "identity"), {}, "goal"),
    ((np.diag([1.0, 1.0, -1.0]), RD_OK), {"mechanism": "attitude"}, "reflection"),
    ((R_OK @ np.diag([1.0, -1.0, 1.0]), RD_OK), {}, "reflection"),
    ((NON_ORTHO, RD_OK), {}, "orthonormal"),
    ((np.eye(3), RD_OK), {}, "singular surface"),
    ((R_OK, RD_OK), {"T": 0.0}, "T"),
    ((R_OK, RD_OK), {"T": -1.0}, "T"),
    ((R_OK, RD_OK), {"T": np.nan}, "T"),
    ((R_OK, RD_OK), {"harmonics": 0}, "harmonics"),
    ((R_OK, RD_OK), {"harmonics": 1.5}, "harmonics"),
    ((R_OK, RD_OK), {"method": "nonparametric", "grid": 0}, "grid"),
    ((R_OK, RD_OK), {"strategy": "magic"}, "strategy"),
    ((R_OK, RD_OK), {"method": "spline"}, "method"),
    ((R_OK, RD_OK), {"mechanism": "tripod"}, "mechanism"),
    ((R_OK, RD_OK), {"gamma": 0.0}, "gamma"),
    ((R_OK, RD_OK), {"tol": -1.0}, "tol"),
    ((R_OK, RD_OK), {"delta_min": np.nan}, "delta_min"),
    ((R_OK, RD_OK), {"max_iter": -1}, "max_iter"),
    ((R_OK, RD_OK), {"steps": 0}, "steps"),
    ((R_OK, RD_OK), {"method": "nonparametric", "steps": 250}, "multiple"),
    ((R_OK, RD_OK), {"u0": C.PiecewiseConstant(1.0, np.zeros((100, 2)))}, "u0"),
    ((R_OK, RD_OK), {"u0": C.Fourier(2.0, np.zeros((2, 5)))}, "u0"),
    ((R_OK, RD_OK), {"u0": "sin"}, "u0"),
])
def test_bad_input_raises_clear_value_error(args, kw, match, monkeypatch):
    """Bad input is refused before anything is simulated or compiled."""
    forbid_simulation(monkeypatch)
    with pytest.raises(ValueError, match=match):
        plan(*args, **arguments_of(kw, "platform"))


@pytest.mark.parametrize("Rd, match", [
    (so3.from_rpy(-1.0, 0.9, -0.5), "across the singular surface"),    # Δ(Rd) < 0 < Δ(R0)
    (np.eye(3), "on the singular surface"),                            # Δ(I) = 0 exactly
    (so3.from_rpy(0.004, 0.1, 0.0), "within delta_min"),               # 0 < Δ(Rd) < delta_min
])
def test_goal_beyond_the_singular_surface_returns_at_once(Rd, match, monkeypatch):
    """Decided before anything is simulated (or compiled): no problem, no kernels."""
    R0 = example(1)[0]
    forbid_simulation(monkeypatch)
    res = plan(R0, Rd)
    assert not res.success and match in res.reason
    assert res.iterations == 0 and res.terminal_error is None and res.min_delta is None
    assert len(res.t) == 0 and res.R.shape == (0, 3, 3)
    assert res.controls(np.array([0.0, 0.5])).shape == (2, 2)


def test_initial_control_into_the_singularity_fails_gracefully():
    R0, Rd = example(1)
    u0 = C.Fourier(1.0, [[1.0, 0, 0, 0, 0], [0.0, 0, 0, 0, 0]])      # runs into Δ = 0
    res = plan(R0, Rd, u0=u0, strategy="paper", route="local")
    assert not res.success and "initial control" in res.reason and "Δ = 0" in res.reason
    assert res.iterations == 0 and res.terminal_error is None
    assert 0 < len(res.t) < res.steps + 1
    assert np.all(np.isfinite(res.R)) and np.all(np.isfinite(res.delta))
    assert res.min_delta is not None and res.min_delta < 1e-2


# -- options, result object, strategies ---------------------------------------------------

def test_u0_as_function_or_controls():
    R0, Rd = example(2)
    a = plan(R0, Rd, u0=C.paper_initial(1.0), strategy="paper")
    b = plan(R0, Rd, u0=C.Fourier.fit(C.paper_initial(1.0), 1.0, 2), strategy="paper")
    c = plan(R0, Rd, strategy="paper")
    np.testing.assert_allclose(a.params, c.params, atol=1e-12)
    np.testing.assert_array_equal(b.params, c.params)


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_callback_sees_every_iteration_and_can_stop(strategy):
    R0, Rd = example(1)
    seen = []
    res = plan(R0, Rd, callback=seen.append, strategy=strategy)
    assert [r["iteration"] for r in seen] == list(range(res.iterations + 1)) and seen == res.history
    res = plan(R0, Rd, callback=lambda r: r["iteration"] >= 3, strategy=strategy)
    assert not res.success and res.iterations == 3 and "callback" in res.reason


@pytest.mark.parametrize("kw", [{}, {"settings": Settings(method="nonparametric", grid=40)},
                                {"mechanism": "attitude"}, {"Rd": so3.from_rpy(-1.0, 0.9, -0.5)},
                                {"strategy": "paper"},
                                {"strategy": "paper", "settings": Settings(method="nonparametric")}])
def test_save_load_round_trip(tmp_path, kw):
    R0, Rd = example(1)
    Rd = kw.pop("Rd", Rd)
    res = plan(R0, Rd, **kw)
    path = res.save(tmp_path / "plan.json")
    back = PlanResult.load(path)
    assert back == res
    t = np.linspace(0.0, 1.0, 1001)
    if res.parametrisation.kind == "frame":
        # the loaded frame controls re-integrate their nodes (forward kernel), the planner's
        # hold those of its variational kernel: two computations of the same inputs
        assert_inputs_match(back.controls(t), res.controls(t))
    else:   # rebuilt from the stored numbers by the same computation: bit for bit
        np.testing.assert_array_equal(back.controls(t), res.controls(t))
    if res.breakpoints is not None:
        np.testing.assert_array_equal(back.breakpoints, res.breakpoints)
    assert json.loads(path.read_text())["format"] == FORMAT
    assert repr(back) == repr(res)


def test_repr_is_readable():
    R0, Rd = example(1)
    text = repr(plan(R0, Rd))
    assert text.startswith("PlanResult(success") and "platform" in text and "|l_T|" in text
    text = repr(plan(R0, so3.from_rpy(-1.0, 0.9, -0.5)))
    assert "FAILED" in text and "across" in text


def test_a_new_strategy_plugs_in_without_touching_the_paper_one():
    class Sobolev(Strategy):
        """The paper's flow (the core's step loop), minimum norm in an H¹-like metric
        (higher harmonics cost more).

        (The plain L2 metric would give the paper's steps here: for the platform the mean
        inputs alone fix r11(T), r22(T) — u1 = −ṙ22/2, u2 = −ṙ11/2 — so J's oscillating
        columns have rank 1 and equal weights on them change nothing.)
        """

        name = "test-sobolev"
        default_gamma = PaperStrategy.default_gamma

        def metric(self, problem, controls):
            k = np.r_[0, np.repeat(np.arange(1, controls.harmonics + 1), 2)]
            return np.tile(1.0 + k ** 2, controls.n_inputs)

        def solve(self, problem, start, callback=None):
            ev = problem.evaluate(start.controls, delta_stop=S.DELTA_STOP)
            if not problem.admissible(ev):
                return Outcome(ev, False, problem.why_not(ev))
            history = [record(0, ev, 0.0, "initial", 0)]
            scale = 1.0 / np.sqrt(self.metric(problem, start.controls))
            d = descend(problem, ev, self.options,
                        lambda ev, newton: kernels.min_norm_step(ev.J, ev.l, scale),
                        budget=self.options.max_iter, history=history, callback=callback)
            return Outcome(d.evaluation, d.status == "converged", d.reason, history, d.steps)

    strategies = dict(STRATEGIES)
    R0, Rd = example(1)
    res = plan(R0, Rd, strategy=Sobolev)          # the class itself: nothing registers it
    check_solution(res, R0, Rd)
    assert res.strategy == "test-sobolev"
    assert not np.allclose(res.params, plan(R0, Rd, strategy="paper").params, atol=1e-3)
    assert STRATEGIES == strategies and "test-sobolev" not in STRATEGIES
    with pytest.raises(ValueError, match="strategy"):
        plan(R0, Rd, strategy="test-sobolev")


def test_platform_mean_inputs_fix_r11_r22():
    """u1 = −ṙ22/2, u2 = −ṙ11/2: J's oscillating Fourier columns have rank 1."""
    R0, _ = example(1)
    u = C.Fourier(1.0, [[0.1, 0.3, -0.2, 0.1, 0.05], [-0.05, 0.1, 0.3, 0.0, -0.1]])
    var = S.variational(R0, u, 1.0)
    tr = var.trajectory
    assert tr.R_T[1, 1] == pytest.approx(R0[1, 1] - 2 * 0.1, abs=1e-9)      # CF4 error ~1e-11
    assert tr.R_T[0, 0] == pytest.approx(R0[0, 0] + 2 * 0.05, abs=1e-9)
    sv = np.linalg.svd(var.J[:, [1, 2, 3, 4, 6, 7, 8, 9]], compute_uv=False)
    assert sv[1] <= 1e-9 * sv[0]


# -- command line ---------------------------------------------------------------------------

def cli(argv):
    parser = argparse.ArgumentParser(prog="nonholo")
    cli_plan.add_parser(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["plan", *argv])
    return cli_plan.run(args)


def test_cli_plans_writes_json_and_figure(tmp_path, capsys):
    out, fig = tmp_path / "plan.json", tmp_path / "plan.png"
    start, goal = example_rpy_args(1)
    code = cli(["--from", *start, "--to", *goal, "--T", "1",
                "--harmonics", "2", "--out", str(out), "--plot", str(fig)])
    text = capsys.readouterr().out
    assert code == 0
    lines = [ln for ln in text.splitlines() if ln.startswith("iter")]
    res = PlanResult.load(out)
    assert len(lines) == res.iterations + 1 and "min|Δ|" in lines[0]
    assert "success" in text and "terminal error" in text
    assert res.success and res.terminal_error <= 1e-10
    R0, Rd = example(1)
    np.testing.assert_array_equal(res.R0, R0)
    np.testing.assert_array_equal(res.Rd, Rd)
    assert fig.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and fig.stat().st_size > 10_000


def test_cli_nonparametric_and_failures(tmp_path, capsys):
    start1, goal1 = example_rpy_args(1)
    start2, goal2 = example_rpy_args(2)
    assert cli(["--from", *start2, "--to", *goal2, "--method", "nonparametric",
                "--grid", "50", "--quiet"]) == 0
    assert not [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("iter ")]
    assert cli(["--from", *start1, "--to", "-1.0", "0.9", "-0.5",
                "--plot", str(tmp_path / "f.png")]) == 1
    assert "across the singular surface" in capsys.readouterr().out
    assert cli(["--from", "0", "0", "0", "--to", *goal1]) == 2
    assert "singular surface" in capsys.readouterr().err
    assert cli(["--from", *start1, "--to", *goal1, "--strategy", "magic"]) == 2
    assert cli(["--from", *start1[:2], "--to", *goal1]) == 2
    assert "--from takes 3 numbers for mechanism 'platform' (φ ϑ ψ), got 2" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        cli(["--from", "--to", *goal1])
