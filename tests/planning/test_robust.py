"""Strategy "robust" (the default of `plan`): reachable goals, parking, rejection, I/O; and the
unchanged paper strategy."""
from __future__ import annotations

import inspect
import json
from pathlib import Path

import numpy as np
import pytest
from conftest import assert_inputs_match, example, forbid_simulation, verified

from nonholo.certify.resimulate import resimulate, terminal_error
from nonholo.controls import parametrisations as C
from nonholo.io.result import PlanResult
from nonholo.model import catalog
from nonholo.motion.frame_controls import FrameControls
from nonholo.paper import examples
from nonholo.planning.api import METHODS, STRATEGIES, plan
from nonholo.planning import strategy_robust as robust
from nonholo.planning.core import Start
from nonholo.planning.endpoint_map import EndpointMap
from nonholo.spaces import so3
from nonholo.spaces import State
from nonholo import Settings
from nonholo.constraints import Clearance

PLATFORM = catalog.get("platform")
DATA = Path(__file__).parents[1] / "data"


def goal_slice(per_band: int = 6) -> list[dict]:
    """``per_band`` goals of each reachable band of the benchmark set, spread over its starts."""
    from benchmarks.goalset import load_goals

    goals = load_goals()
    out = []
    for band in ("near", "far"):
        g = [x for x in goals if x["band"] == band]
        out += [g[i] for i in np.linspace(0, len(g) - 1, per_band).round().astype(int)]
    return out


def across_goals() -> list[dict]:
    from benchmarks.goalset import load_goals

    return [g for g in load_goals() if g["band"] == "across"]


def other_parking_goal():
    """The second solution of Example 3's conditions: ``Rd = exp([v]) R0``, ``v ≈ (−0.543, −0.033, −0.253)``."""
    R0 = examples.get(3).R_start
    return R0, examples.parallel_parking_goal(R0, 0.6, np.array([-0.543, -0.033, -0.253]))


def test_robust_is_the_default():
    assert inspect.signature(plan).parameters["strategy"].default == "robust"
    R0, Rd = example(1)
    res = plan(R0, Rd)
    assert res.strategy == "robust" and res.success
    assert isinstance(res.parametrisation, FrameControls)
    assert STRATEGIES["robust"] is robust.RobustStrategy


@pytest.mark.parametrize("goal", goal_slice(), ids=lambda g: g["id"])
@pytest.mark.slow
def test_benchmark_slice(goal):
    res = plan(goal["R0"], goal["Rd"], T=goal["T"])
    verified(res, goal["R0"], goal["Rd"], goal["T"])


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.slow
def test_example3_and_the_other_parking_goal(method):
    ex3 = examples.get(3)
    R0, other = other_parking_goal()
    assert so3.distance(R0, other) == pytest.approx(0.6, abs=1e-12)
    assert other[0, 0] == pytest.approx(R0[0, 0], abs=1e-12) and other[1, 1] == pytest.approx(R0[1, 1], abs=1e-12)
    assert so3.distance(other, ex3.R_goal) > 0.1
    for Rd in (ex3.R_goal, other):
        verified(plan(R0, Rd, settings=Settings(method=method)), R0, Rd)


def test_paper_strategy_fails_the_other_parking_goal():
    """What the robust strategy is for: the appendix's algorithm steers into Δ = 0 here."""
    R0, other = other_parking_goal()
    for gamma in (0.2, 0.5, 1.0):
        res = plan(R0, other, strategy="paper", settings=Settings(gamma=gamma), route="local")
        assert not res.success and "delta_min" in res.reason


@pytest.mark.slow
def test_hard_goal_of_the_paper_strategy_is_solved():
    """The reachable goal of test_planner.test_hard_goal_fails_gracefully."""
    R0, Rd = so3.from_rpy(2.2642, 0.0361, 1.9724), so3.from_rpy(1.6499, 0.1579, 2.7202)
    for method in METHODS:
        verified(plan(R0, Rd, settings=Settings(method=method)), R0, Rd)


def test_goals_across_the_singular_surface_are_rejected_fast(monkeypatch):
    """Rejected before anything is simulated or compiled (no problem, no kernels)."""
    goals = across_goals()
    assert len(goals) >= 10
    forbid_simulation(monkeypatch)
    for g in goals:
        res = plan(g["R0"], g["Rd"], T=g["T"])
        assert not res.success and "across the singular surface" in res.reason
        assert res.iterations == 0 and len(res.t) == 0 and res.terminal_error is None
        assert res.history == [] and res.min_delta is None and res.R.shape == (0, 3, 3)


@pytest.mark.parametrize("method", METHODS)
def test_save_load_keeps_the_physical_controls(tmp_path, method):
    R0, Rd = example(2)
    res = plan(R0, Rd, settings=Settings(method=method, grid=50))
    back = PlanResult.load(res.save(tmp_path / "plan.json"))
    assert back == res and back.strategy == "robust"
    t = np.linspace(0.0, 1.0, 777)
    # frame controls: the loaded ones re-integrate their nodes (forward kernel), the planner's
    # hold those of its variational kernel: two computations of the same inputs
    assert_inputs_match(back.controls(t), res.controls(t))
    np.testing.assert_array_equal(back.u, res.u)        # the stored samples, read back
    d = json.loads((tmp_path / "plan.json").read_text())
    assert d["controls"]["kind"] == "frame" and d["controls"]["frame"]["kind"] in ("fourier", "piecewise_constant")
    # u is physical: L(R) u = N(R) w along the planned motion (ω in the admissible plane)
    par = res.parametrisation
    R, u, w = par.states(t), res.controls(t), par.frame_inputs(t)
    N = PLATFORM.frame.N
    for k in range(0, len(t), 50):
        np.testing.assert_allclose(PLATFORM.L(R[k]) @ u[k], N(R[k]) @ w[k], atol=1e-12)
    assert np.abs(res.u).max() > 0.05       # leg rates, not zero placeholders


@pytest.mark.slow
def test_history_records_attempts_and_restarts():
    class BadFirst(robust.RobustStrategy):
        """First guess a loop that runs into Δ = 0 at once, then the default guesses."""

        name = "test-bad-first"

        def attempts(self, problem, start):
            assert isinstance(start, Start) and not start.given
            yield "bad", C.Fourier(1.0, [[6.0, 0, 0, 0, 0], [-6.0, 0, 0, 0, 0]])
            yield from super().attempts(problem, start)

    R0, Rd = example(1)
    res = plan(R0, Rd, strategy=BadFirst)
    verified(res, R0, Rd)
    assert res.strategy == "test-bad-first"
    assert "attempt 2: drift" in res.reason
    assert res.history[0]["phase"] == "restart" and res.history[0]["attempt"] == 1


def test_default_gamma_is_the_strategys():
    """``gamma=None`` takes the strategy's ``default_gamma`` (robust 1, paper 0.5, as in the
    paper's examples); a given ``gamma`` is used as it is."""
    R0, Rd = example(1)
    assert plan(R0, Rd).options["gamma"] == 1.0
    paper = plan(R0, Rd, strategy="paper")
    assert paper.options["gamma"] == 0.5
    # the paper strategy's first flow step asks the error to shrink by γh = 0.5
    assert paper.history[1]["step"] == 0.5
    assert plan(R0, Rd, settings=Settings(gamma=0.3)).options["gamma"] == 0.3


def test_failure_reports_every_attempt():
    R0, Rd = example(2)
    res = plan(R0, Rd, settings=Settings(max_iter=1))
    assert not res.success and "no attempt converged" in res.reason and "drift" in res.reason
    assert res.iterations <= 1 and res.terminal_error is not None
    assert np.all(np.isfinite(res.u))


@pytest.mark.slow
def test_u0_that_runs_into_the_singularity_is_replaced():
    R0, Rd = example(1)
    u0 = C.Fourier(1.0, [[1.0, 0, 0, 0, 0], [0.0, 0, 0, 0, 0]])
    res = plan(R0, Rd, u0=u0)
    verified(res, R0, Rd)
    assert "u0 not used" in res.reason


def test_physical_u0_is_converted_to_frame_coordinates():
    """``u0`` is physical: its frame version reproduces the same motion."""
    R0 = example(1)[0]
    u0 = C.Fourier(1.0, [[0.1, 0.2, 0.0, 0.05, 0.0], [0.0, 0.0, 0.25, 0.0, -0.05]])
    start = State(R0, np.zeros(0))
    problem = EndpointMap(start, start, 1.0, PLATFORM, "parametric", 400, 1e-2, frame=True)
    w0 = robust.to_frame(problem, u0)
    from nonholo.motion.simulation import simulate

    R_u = simulate(R0, u0, 1.0).R_T
    R_w = FrameControls(w0, R0, PLATFORM, 400).nodes[-1]
    assert so3.distance(R_u, R_w) < 2e-2        # K = 2 truncation of w(t) only


@pytest.mark.slow
def test_integrator_refinement():
    class Fine(robust.RobustStrategy):
        name = "test-fine"
        refine_above = 1e-13

    R0, Rd = example(1)
    res = plan(R0, Rd, strategy=Fine)
    verified(res, R0, Rd)
    assert res.strategy == "test-fine"
    assert res.steps > 400 and res.R.shape == (res.steps + 1, 3, 3) and "refined" in res.reason
    assert res.parametrisation.steps == res.steps


def test_attitude_has_no_delta_checks_with_robust():
    R0, Rd = np.eye(3), so3.from_rpy(2.0, -1.0, 0.5)
    res = plan(R0, Rd, mechanism="attitude")
    assert res.success and res.min_delta is None and res.delta is None
    RT = resimulate(R0, res.controls, 1.0, "attitude")
    assert terminal_error(RT, Rd) <= 1e-8


# -- the paper strategy, unchanged -------------------------------------------------------------

def test_paper_strategy_unchanged():
    """Examples 1–2, both methods, against tests/data/paper_strategy_examples.json.

    The fixture was recorded before the robust strategy existed with::

        for k, (a, b) in EXAMPLES.items():            # RPY angles of R0, Rd
            for method in METHODS:
                res = plan(so3.from_rpy(*a), so3.from_rpy(*b), method=method)
                record(res.iterations, [h[...] for h in res.history], res.params)

    (every option at its default; "paper" was the default strategy then, and the plan as
    found the default objective, ``objective=None`` now). Errors are
    compared with ``rtol = 1e-9`` above the round-off floor (``atol = 1e-12``: the last
    Newton step ends at ~1e-14, where the value is round-off).
    """
    fx = json.loads((DATA / "paper_strategy_examples.json").read_text())
    assert len(fx["runs"]) == 4
    for run in fx["runs"]:
        ex = fx["examples"][str(run["example"])]
        R0, Rd = example(run["example"])        # the recorded problem is nonholo.paper.examples'
        np.testing.assert_array_equal(so3.from_rpy(*ex["R0_rpy"]), R0)
        np.testing.assert_array_equal(so3.from_rpy(*ex["Rd_rpy"]), Rd)
        res = plan(R0, Rd, settings=Settings(method=run["method"]), strategy="paper", objective=None)
        assert res.success == run["success"] and res.iterations == run["iterations"]
        assert [h["phase"] for h in res.history] == run["phases"]
        assert [h["rejected"] for h in res.history] == run["rejected"]
        np.testing.assert_allclose([h["error"] for h in res.history], run["errors"], rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose([h["step"] for h in res.history], run["steps"], rtol=1e-12)
        np.testing.assert_allclose([h["min_delta"] for h in res.history], run["min_delta"], rtol=1e-9)
        np.testing.assert_allclose(res.params, run["params"], rtol=1e-8, atol=1e-10)


@pytest.mark.slow
def test_sensitivity_is_reported_and_used():
    """``sensitivity`` = max |Φ(T,t)|_F of the physical system; above ``max_sensitivity`` a
    converged plan is kept only as a last resort (and said so)."""
    R0, Rd = example(1)
    res = plan(R0, Rd)
    assert np.sqrt(3.0) - 1e-9 <= res.sensitivity <= robust.RobustStrategy.max_sensitivity
    from nonholo.motion.simulation import variational

    Phi = variational(R0, res.parametrisation, 1.0).Phi
    assert res.sensitivity == pytest.approx(np.sqrt(np.max(np.sum(Phi ** 2, axis=(1, 2)))), rel=1e-5)
    for g in goal_slice(2):     # the cheaper evaluation (steps/2, given nodes) vs all nodes
        res = plan(g["R0"], g["Rd"], T=g["T"], constraints=[Clearance(0.01)])
        Phi = variational(g["R0"], res.parametrisation, g["T"], steps=res.steps).Phi
        assert res.sensitivity == pytest.approx(np.sqrt(np.max(np.sum(Phi ** 2, axis=(1, 2)))),
                                                rel=1e-5)
    res = plan(R0, Rd, strategy="paper")        # every certified plan has one
    Phi = variational(R0, res.parametrisation, 1.0).Phi
    assert res.sensitivity == pytest.approx(np.sqrt(np.max(np.sum(Phi ** 2, axis=(1, 2)))), rel=1e-5)

    class Strict(robust.RobustStrategy):
        name = "test-strict"
        max_sensitivity = 1.0           # below √3: no plan qualifies
        random_guesses = 0

    res = plan(R0, Rd, strategy=Strict)
    verified(res, R0, Rd)
    assert res.strategy == "test-strict"
    assert "sensitivity" in res.reason and "converged attempts" in res.reason
    assert res.sensitivity > 1.0


@pytest.mark.parametrize("T, grid", [(1.0, 40), (2.0, 40), (0.5, 25)])
@pytest.mark.slow
def test_grid_controls_replay_exactly(T, grid):
    """Several integrator steps per grid interval, T ≠ 1: the physical replay matches."""
    R0, Rd = example(2)
    res = plan(R0, Rd, T=T, settings=Settings(method="nonparametric", grid=grid))
    verified(res, R0, Rd, T)
    RT = resimulate(R0, res.controls, T, breakpoints=res.breakpoints)
    assert terminal_error(RT, res.R[-1]) <= 1e-11     # the replay ends where the plan does
