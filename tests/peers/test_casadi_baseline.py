"""Tests for the CasADi/IPOPT multiple-shooting baseline (benchmarks/casadi_ms.py)."""

import importlib.util
import pathlib
import sys

import numpy as np
import pytest

pytest.importorskip("casadi")
from conftest import example  # noqa: E402

from nonholo.model import catalog
from nonholo.spaces import so3  # noqa: E402


def _load_module():
    try:
        from benchmarks import casadi_ms

        return casadi_ms
    except ImportError:
        path = pathlib.Path(__file__).resolve().parents[2] / "benchmarks" / "casadi_ms.py"
        spec = importlib.util.spec_from_file_location("casadi_ms", path)
        mod = importlib.util.module_from_spec(spec)
        sys.modules[spec.name] = mod  # needed by dataclasses
        spec.loader.exec_module(mod)
        return mod


cms = _load_module()


Delta = catalog.get("platform").delta      # the generated Δ(R), independent of the baseline's

R0, RD = example(1)                         # Example 1 (nonholo.paper.examples)
DELTA_MIN = 0.01


@pytest.fixture(scope="module")
def result():
    return cms.solve(R0, RD, T=1.0, delta_min=DELTA_MIN)


@pytest.mark.slow
def test_solves_reference_example(result):
    assert result.success, result.status
    assert result.u.shape == (40, 2)
    assert result.t_grid.shape == (41,)
    assert result.seconds > 0 and result.iterations > 0

    RT, _, R_path = cms.resimulate(
        R0, result.controls, 1.0, breakpoints=result.t_grid, return_path=True
    )
    err = cms.terminal_error(RT, RD)
    print(f"re-simulated terminal error: {err:.3e}")
    assert err <= 1e-8
    sgn = np.sign(Delta(R0))
    assert min(sgn * Delta(R) for R in R_path) >= DELTA_MIN - 1e-9


@pytest.mark.slow
def test_controls_are_piecewise_constant(result):
    t = result.t_grid
    u = result.controls(np.array([0.0, 0.5 * (t[0] + t[1]), t[1], t[-1]]))
    assert u.shape == (4, 2)
    np.testing.assert_array_equal(u[0], result.u[0])
    np.testing.assert_array_equal(u[1], result.u[0])
    np.testing.assert_array_equal(u[2], result.u[1])  # right-continuous
    np.testing.assert_array_equal(u[3], result.u[-1])  # last interval closed


def test_goal_across_singular_surface_is_rejected(monkeypatch):
    """Rejected immediately: before the NLP is built (or a cached one fetched) and before
    the initial guess is simulated."""
    Rd_bad = so3.from_rpy(-1.0, 0.9, -0.5)
    assert np.sign(Delta(Rd_bad)) != np.sign(Delta(R0))

    def forbidden(*args, **kwargs):
        raise AssertionError("the baseline built or solved something for an unreachable goal")

    class NoCache(dict):
        get = __getitem__ = forbidden

    monkeypatch.setattr(cms, "_build", forbidden)
    monkeypatch.setattr(cms, "make_step_function", forbidden)
    monkeypatch.setattr(cms, "_CACHE", NoCache())
    monkeypatch.setattr(cms.ca, "nlpsol", forbidden)
    monkeypatch.setattr(cms, "solve_ivp", forbidden)
    with pytest.raises(ValueError, match="unreachable"):
        cms.solve(R0, Rd_bad)


@pytest.mark.slow
def test_leg_speed_bound_holds_at_the_nodes_and_binds(result):
    """With ``leg_speed`` the baseline's legs keep ``|dl_i/dt| ≤ v`` at both ends of every
    interval (speeds from the generated geometry: ``G_i(R) L(R) u``), and the bound binds
    when the unbounded minimum-energy motion is faster."""
    platform = catalog.get("platform")

    def fastest(res):
        u = np.repeat(res.u, 2, axis=0)
        R = np.repeat(res.R_nodes, 2, axis=0)[1:-1]            # both ends of every interval
        return np.abs(platform.leg_speeds(R, u)).max()

    free = fastest(result)
    v = 0.95 * free
    bounded = cms.solve(R0, RD, T=1.0, delta_min=DELTA_MIN, leg_speed=v)
    assert bounded.success, bounded.status
    assert fastest(bounded) <= v * (1 + 1e-6)
    assert fastest(bounded) >= v * (1 - 1e-3)
    RT = cms.resimulate(R0, bounded.controls, 1.0, breakpoints=bounded.t_grid)
    assert cms.terminal_error(RT, RD) <= 1e-8
