"""Certified success (nonholo/certify.py, nonholo/planning/certification.py): no plan claims a
goal that an independent re-simulation of its physical controls does not reach."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import example

from benchmarks import goalset
from nonholo import catalog, certify, planner, verify
from nonholo.planning.core import Outcome, Strategy
from nonholo.simulation import variational

MISS = 1e-8


def rk4_check(results, pairs, least=3200):
    """Per plan: (RK4 endpoint error, least sgnΔ at the RK4 nodes), steps aligned with the plan's."""
    out = []
    for r, p in zip(results, pairs):
        S = r.steps * -(-least // r.steps)
        RT, dmin = verify.resimulate_rk4(p["R0"], r.parametrisation, r.T, r.mechanism, steps=S)
        out.append((verify.terminal_error(RT, p["Rd"]), dmin))
    return out


def assert_certified(res, R0, Rd):
    """A success is what it claims: bound within tol, RK4 replay at the goal, Δ kept."""
    assert res.success, res.reason
    assert res.replay_steps is not None and res.error_bound is not None
    assert res.terminal_error + res.error_bound <= res.options["tol"]
    assert np.isfinite(res.sensitivity)
    S = res.steps * -(-3200 // res.steps)
    RT, dmin = verify.resimulate_rk4(R0, res.parametrisation, res.T, res.mechanism, steps=S)
    assert verify.terminal_error(RT, Rd) <= MISS
    if dmin is not None:
        assert dmin >= res.options["delta_min"]


@pytest.mark.parametrize("mechanism", ["platform", "platform_raised", "attitude"])
@pytest.mark.parametrize("options", [{}, {"method": "nonparametric"}, {"strategy": "paper"},
                                     {"strategy": "paper", "method": "nonparametric"}],
                         ids=["robust", "robust-nonparametric", "paper", "paper-nonparametric"])
def test_every_claimed_success_reaches_the_goal(mechanism, options):
    """Uniform random pairs in one component (fixed seed): every claimed success, re-simulated
    by RK4 on the entries of R, ends within 1e-8 rad of the goal and keeps delta_min."""
    pairs = goalset.uniform_pairs(mechanism, 6, seed=7)
    results = [planner.plan(p["R0"], p["Rd"], mechanism=mechanism, max_iter=60, **options) for p in pairs]
    ok = [(r, p) for r, p in zip(results, pairs) if r.success]
    for (err, dmin), (r, _) in zip(rk4_check(*zip(*ok)) if ok else [], ok):
        assert err <= MISS, (r.reason, err)
        assert dmin is None or dmin >= 1e-2
        assert r.terminal_error + r.error_bound <= 1e-10
    for r in results:
        if not r.success:
            assert r.replay_steps is None and r.error_bound is None


@pytest.mark.parametrize("kw", [
    {"steps": 3, "harmonics": 1},                       # missed by 6e-3 when it claimed success
    {"steps": 2, "harmonics": 1},                       # claimed success with sensitivity = inf
    {"steps": 3, "harmonics": 1, "strategy": "paper"},
    {"strategy": "paper", "harmonics": 100},            # the most harmonics 200 steps resolve
])
def test_coarse_or_odd_options_never_claim_a_missed_goal(kw):
    R0, Rd = example(1)
    res = planner.plan(R0, Rd, **kw)
    if res.success:
        assert_certified(res, R0, Rd)
        # and within tol, up to DOP853's own accuracy (~5e-11 here)
        RT = verify.resimulate(R0, res.controls, res.T, res.mechanism, res.breakpoints)
        assert verify.terminal_error(RT, Rd) <= 3e-10
    else:
        assert res.error_bound is None


def test_a_long_horizon_does_not_claim_success_it_cannot_certify():
    """``T = 1e4`` on the attitude mechanism claimed success 2.76 rad from the goal."""
    R0, Rd = example(1)
    res = planner.plan(R0, Rd, T=1e4, mechanism="attitude", max_iter=60)
    if res.success:
        assert_certified(res, R0, Rd)
    else:
        assert "certif" in res.reason or "converged" not in res.reason.split(";")[0]


def test_a_coarse_plan_is_corrected_on_its_replay():
    """On 4 steps the planner's endpoint is far from what its controls do; the certificate
    replays them finely and corrects the control with Newton steps on that replay."""
    R0, Rd = example(1)
    res = planner.plan(R0, Rd, strategy="paper", steps=4, harmonics=1, mechanism="attitude")
    assert_certified(res, R0, Rd)
    assert res.replay_steps > 4 and "correction" in res.reason


def test_a_strategy_that_claims_success_falsely_is_not_believed():
    """``plan`` certifies a success a strategy returns without a certificate."""

    class Boastful(Strategy):
        name = "test-boastful"

        def solve(self, problem, start, callback=None):
            ev = problem.evaluate(start.controls)
            return Outcome(ev, True, "converged (it says)")

    R0, Rd = example(1)
    res = planner.plan(R0, Rd, strategy=Boastful)
    assert not res.success
    assert "not certified" in res.reason and "ends" in res.reason
    res.validate()


def test_an_ill_conditioned_or_singular_replay_is_not_certified():
    R0, Rd = example(1)
    mech = catalog.get("platform")
    ok = planner.plan(R0, Rd)
    par = ok.parametrisation
    sign = float(np.sign(mech.delta(R0)))
    base = certify.measure(R0, Rd, 1.0, mech, par, ok.replay_steps, 1e-10, 1e-2, sign)
    assert base.passed and base.terminal_error == pytest.approx(ok.terminal_error, abs=1e-15)
    bad = certify.measure(R0, Rd, 1.0, mech, par, ok.replay_steps, 1e-10, 1e-2, sign, G=1e4)
    assert not bad.passed and "ill-conditioned" in bad.reason and not bad.correctable
    inf = certify.measure(R0, Rd, 1.0, mech, par, ok.replay_steps, 1e-10, 1e-2, sign, G=float("inf"))
    assert not inf.passed and "infinite" in inf.reason
    near = certify.measure(R0, Rd, 1.0, mech, par, ok.replay_steps, 1e-10, ok.min_delta + 1e-3, sign)
    assert not near.passed and "Δ = 0" in near.reason


def test_the_error_bound_covers_the_replays_error():
    """The bound of a certificate against a replay 16 times finer (a fourth-order method's
    error shrinks 16-fold per halving: the finer replay is the truth to ~1/16 of the bound)."""
    for k in (1, 2, 3):
        R0, Rd = example(k)
        for strategy in ("robust", "paper"):
            res = planner.plan(R0, Rd, strategy=strategy)
            if not res.success:
                continue
            mech = catalog.get(res.mechanism)
            fine = certify.replay(R0, res.parametrisation, res.T, mech, 16 * res.replay_steps)[0][-1]
            assert verify.terminal_error(fine, res.R_T) <= res.error_bound


def test_sensitivity_on_every_other_node_matches_all_nodes():
    """``certify.sensitivity`` takes Φ on every other node; against ``variational`` on all."""
    pairs = goalset.uniform_pairs("platform", 4, seed=3)
    for p in pairs:
        res = planner.plan(p["R0"], p["Rd"], max_iter=60)
        if not res.success:
            continue
        Phi = variational(p["R0"], res.parametrisation, 1.0, steps=res.steps).Phi
        assert res.sensitivity == pytest.approx(np.sqrt(np.max(np.sum(Phi ** 2, axis=(1, 2)))), rel=1e-4)


def test_rk4_check_agrees_with_dop853_and_batches():
    R0, Rd = example(2)
    res = planner.plan(R0, Rd, strategy="paper")
    single, dmin = verify.resimulate_rk4(R0, res.parametrisation, 1.0, "platform", steps=3200)
    dop = verify.resimulate(R0, res.controls, 1.0, "platform")
    assert np.max(np.abs(single - dop)) < 1e-10
    R1, Rd1 = example(1)
    other = planner.plan(R1, Rd1, strategy="paper", method="nonparametric")
    batch, dmins = verify.resimulate_rk4(np.stack([R0, R1]), [res.parametrisation, other.parametrisation],
                                         [1.0, 1.0], "platform", steps=3200)
    np.testing.assert_allclose(batch[0], single, atol=1e-15)
    assert dmins[0] == pytest.approx(dmin, abs=1e-15)
    dop = verify.resimulate(R1, other.controls, 1.0, "platform", other.breakpoints)
    assert np.max(np.abs(batch[1] - dop)) < 1e-10
