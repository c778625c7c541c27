"""Every mechanism goes through the same pipeline: derive → generate → plan → verify."""
import zlib

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from nonholo import mechanisms, plan, simulate, verify
from nonholo.cli import main
from nonholo.controls import Fourier
from nonholo.generated import MECHANISMS


def reachable_goals(name, count, seed):
    """Goals made by simulating random Fourier controls from random starts, keeping
    |Δ| ≥ 0.1 along the way (mechanisms with a singular set) — reachable by construction."""
    mech = mechanisms.get(name)
    rng = np.random.default_rng(seed)
    goals = []
    while len(goals) < count:
        R0 = Rotation.random(random_state=rng.integers(1 << 31)).as_matrix()
        if mech.has_singular_set and abs(mech.delta(R0)) < 0.3:
            continue
        controls = Fourier(1.0, rng.normal(scale=0.4, size=(mech.n_inputs, 5)))
        try:
            traj = simulate(R0, controls, 1.0, mechanism=name)
        except ValueError:  # ran into Δ = 0
            continue
        if mech.has_singular_set and np.min(np.abs(traj.delta)) < 0.1:
            continue
        goals.append((R0, traj.R_T))
    return goals


def test_mechanism_names():
    assert {"platform", "platform_raised", "attitude"} <= set(MECHANISMS)


def test_cli_lists_mechanisms(capsys):
    assert main(["mechanisms"]) == 0
    out = capsys.readouterr().out
    for name in MECHANISMS:
        assert name in out


@pytest.mark.parametrize("name", MECHANISMS)
def test_planner_converges_on_reachable_goals(name):
    mech = mechanisms.get(name)
    for R0, Rd in reachable_goals(name, 4, seed=zlib.crc32(name.encode())):
        r = plan(R0, Rd, mechanism=name)
        assert r.success, r.reason
        assert r.mechanism == name
        R_T = verify.resimulate(R0, r.controls, 1.0, mechanism=name, breakpoints=r.breakpoints)
        assert verify.terminal_error(R_T, Rd) <= 1e-8
        if mech.has_singular_set:
            assert r.min_delta >= 1e-2
        else:
            assert r.min_delta is None


def test_cli_plan_with_mechanism(tmp_path, capsys):
    out = tmp_path / "plan.json"
    status = main(["plan", "--mechanism", "attitude", "--from", "0.1", "0.2", "0.3",
                   "--to", "0.4", "-0.1", "0.2", "--out", str(out), "--quiet"])
    assert status == 0
    from nonholo.result import PlanResult
    r = PlanResult.load(out)
    assert r.mechanism == "attitude" and r.success


def test_unknown_mechanism():
    with pytest.raises(ValueError, match="unknown mechanism"):
        plan(np.eye(3), np.eye(3), mechanism="no_such_thing")
