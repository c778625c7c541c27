"""Every mechanism goes through the same pipeline: derive → generate → plan → verify."""
import zlib

import numpy as np
import pytest
from conftest import SO3_MECHANISMS, example, reachable_goals

from nonholo import Mechanism, mechanism_named, plan
from nonholo.certify import resimulate as verify
from nonholo.cli.entry import main
from nonholo.controls.parametrisations import Fourier
from nonholo.generated import MECHANISMS
from nonholo.model import catalog
from nonholo.motion import simulation


def test_mechanism_names():
    assert {"platform", "platform_raised", "attitude"} <= set(MECHANISMS)
    assert catalog.names()[:len(MECHANISMS)] == tuple(MECHANISMS)
    for name in MECHANISMS:
        mech = catalog.get(name)
        assert isinstance(mech, Mechanism) and mech.name == name
        assert catalog.get(mech) is mech and mechanism_named(name) is mech


def test_cli_lists_mechanisms(capsys):
    """``nonholo mechanisms``: one line per name of ``catalog.names()``, in order, with its
    description, input count and whether it has a singular set."""
    assert main(["mechanisms"]) == 0
    lines = capsys.readouterr().out.splitlines()
    for name in MECHANISMS:
        assert name in catalog.names()
    assert [ln.split()[0] for ln in lines] == list(catalog.names())
    for line, name in zip(lines, catalog.names()):
        mech = catalog.get(name)
        assert mech.description in line and f"{mech.n_inputs} inputs" in line
        assert ("no singular set" in line) == (not mech.has_singular_set)


@pytest.mark.parametrize("name", SO3_MECHANISMS)
def test_planner_converges_on_reachable_goals(name):
    mech = catalog.get(name)
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
    from nonholo.io.result import PlanResult
    r = PlanResult.load(out)
    assert r.mechanism == "attitude" and r.success


def test_unknown_mechanism():
    with pytest.raises(ValueError, match="unknown mechanism"):
        plan(np.eye(3), np.eye(3), mechanism="no_such_thing")


@pytest.mark.parametrize("name", SO3_MECHANISMS)
def test_a_mechanism_object_works_wherever_its_name_does(name):
    mech = catalog.get(name)
    R0, Rd = example(1)
    u = Fourier(1.0, [[0.05, 0.1, 0.0, 0.0, 0.05], [-0.05, 0.0, 0.1, 0.05, 0.0]])
    a = simulation.simulate(R0, u, 1.0, mechanism=mech)
    b = simulation.simulate(R0, u, 1.0, mechanism=name)
    np.testing.assert_array_equal(a.R, b.R)
    assert a.mechanism == b.mechanism == name
    va, vb = (simulation.variational(R0, u, 1.0, mechanism=m) for m in (mech, name))
    np.testing.assert_array_equal(va.J, vb.J)
    np.testing.assert_array_equal(va.M, vb.M)
    np.testing.assert_array_equal(verify.resimulate(R0, u, 1.0, mech), verify.resimulate(R0, u, 1.0, name))
    np.testing.assert_array_equal(verify.mobility_lyapunov(R0, u, 1.0, mech),
                                  verify.mobility_lyapunov(R0, u, 1.0, name))
    ra, rb = plan(R0, Rd, mechanism=mech), plan(R0, Rd, mechanism=name)
    assert ra.success and rb.success and ra.mechanism == rb.mechanism == name
    np.testing.assert_array_equal(ra.params, rb.params)
    np.testing.assert_array_equal(ra.R, rb.R)
