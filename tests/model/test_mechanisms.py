"""Every mechanism goes through the same pipeline: derive → generate → plan → verify."""
import zlib

import numpy as np
import pytest
from conftest import SO3_MECHANISMS, example, reachable_goals, regular_motion

from derivations.mechanisms import PlatformGeometry, platform_mechanism
from nonholo import Mechanism, mechanism_named, plan
from nonholo.certify.resimulate import mobility_lyapunov, resimulate, terminal_error
from nonholo.cli.entry import main
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
        assert ("no singular set" in line) == (mech.delta is None)


@pytest.mark.parametrize("name", SO3_MECHANISMS)
@pytest.mark.slow
def test_planner_converges_on_reachable_goals(name):
    mech = catalog.get(name)
    for R0, Rd in reachable_goals(name, 4, seed=zlib.crc32(name.encode())):
        r = plan(R0, Rd, mechanism=name)
        assert r.success, r.reason
        assert r.mechanism == name
        R_T = resimulate(R0, r.controls, 1.0, mechanism=name, breakpoints=r.breakpoints)
        assert terminal_error(R_T, Rd) <= 1e-8
        if mech.delta is not None:
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


def on_sphere(*v) -> tuple:
    """The point of the unit sphere in the direction ``v`` (the sphere's radius is the unit of
    length: a platform's joints and contact point lie on it)."""
    n = sum(x * x for x in v) ** 0.5
    return tuple(x / n for x in v)


#: A platform whose singular set separates example 1's start from its goal (Δ of opposite
#: signs there): a start and control fixed for the paper's platform are not for it.
ACROSS = PlatformGeometry(base1=(0.1, 1.4, 0.6), tip1=on_sphere(0.0, 0.8, 0.1), base2=(2.8, 0.9, -0.7),
                          tip2=on_sphere(0.6, -0.2, 0.0), contact=on_sphere(-2.3, -0.2, -1.2),
                          axle=(-0.6, 0.3, 1.1))


@pytest.fixture
def named(request, monkeypatch):
    """A mechanism's name: one of the package's, or the platform ``ACROSS`` added in the test."""
    if request.param == "across":
        monkeypatch.setattr(catalog, "_ADDED", {})
        catalog.add(Mechanism.from_symbolic(platform_mechanism("across", ACROSS, "example 1 across its Δ = 0")))
    return request.param


@pytest.mark.parametrize("named", SO3_MECHANISMS + ("across",), indirect=True)
def test_a_mechanism_object_works_wherever_its_name_does(named):
    name = named
    mech = catalog.get(name)
    if name == "across":            # the fixed start and goal of example 1 would not do
        R0, Rd = example(1)
        assert mech.delta(R0) * mech.delta(Rd) < 0
    R0, Rd, u = regular_motion(mech, seed=zlib.crc32(name.encode()))
    a = simulation.simulate(R0, u, 1.0, mechanism=mech)
    b = simulation.simulate(R0, u, 1.0, mechanism=name)
    np.testing.assert_array_equal(a.R, b.R)
    assert a.mechanism == b.mechanism == name
    va, vb = (simulation.variational(R0, u, 1.0, mechanism=m) for m in (mech, name))
    np.testing.assert_array_equal(va.J, vb.J)
    np.testing.assert_array_equal(va.M, vb.M)
    np.testing.assert_array_equal(resimulate(R0, u, 1.0, mech), resimulate(R0, u, 1.0, name))
    np.testing.assert_array_equal(mobility_lyapunov(R0, u, 1.0, mech),
                                  mobility_lyapunov(R0, u, 1.0, name))
    ra, rb = plan(R0, Rd, mechanism=mech), plan(R0, Rd, mechanism=name)
    assert ra.success and rb.success and ra.mechanism == rb.mechanism == name
    np.testing.assert_array_equal(ra.params, rb.params)
    np.testing.assert_array_equal(ra.R, rb.R)
