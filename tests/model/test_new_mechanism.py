"""A mechanism built in-process from its geometry: derive → numeric → plan → verify, in
two calls (``Mechanism.from_symbolic``, ``plan``), then known by name (``catalog.add``).

The mechanism is the paper's platform with the disk moved off the pole: its contact point
tilted by ``arcsin(3/5)`` towards ``(e_1 + e_2)/√2``, its axle still ``(e_1 − e_2)/√2``
(tangent there). The "changed" mechanism under the same name is the paper's platform with
the disk's axle turned by 90° instead (as in ``notebooks/04_adding_a_mechanism.ipynb``).
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import sympy as sp
from conftest import assert_inputs_match, check_into_forms, check_solution, random_rotations, reachable_goals

from derivations.mechanisms import (
    PAPER_GEOMETRY,
    PlatformGeometry,
    constraint_matrix,
    input_map,
    platform_mechanism,
    rho,
)
from derivations.rotations import e1, e2, e3, r
from derivations.variational import Q_matrix, inputs
from nonholo import Mechanism, plan, simulate
from nonholo.certify.resimulate import resimulate, terminal_error
from nonholo.cli.entry import main
from nonholo.controls.parametrisations import Fourier
from nonholo.io.result import PlanResult
from nonholo.model import catalog
from nonholo.spaces import so3
from nonholo import viz

NAME = "test_moved_disk"
G = PAPER_GEOMETRY
MOVED = PlatformGeometry(
    base1=G.base1, tip1=G.tip1, base2=G.base2, tip2=G.tip2,
    contact=tuple(rho * (sp.Rational(4, 5) * e3 + sp.Rational(3, 5) * (e1 + e2) / sp.sqrt(2))),
    axle=G.axle)
TURNED = PlatformGeometry(
    base1=G.base1, tip1=G.tip1, base2=G.base2, tip2=G.tip2,
    contact=G.contact, axle=tuple((e1 + e2) / sp.sqrt(2)))


@pytest.fixture(scope="module")
def symbolic():
    return platform_mechanism(NAME, MOVED, "the paper's legs, the disk moved off the pole")


@pytest.fixture(scope="module")
def moved(symbolic):
    return Mechanism.from_symbolic(symbolic)


@pytest.fixture(scope="module")
def changed():
    """Same name, other kinematics."""
    sym = platform_mechanism(NAME, TURNED, "the paper's legs, the disk's axle turned by 90 degrees")
    return sym, Mechanism.from_symbolic(sym)


@pytest.fixture(scope="module")
def goal(moved):
    """A goal reachable by construction with the moved-disk platform."""
    return reachable_goals(moved, 1, seed=404)[0]


@pytest.fixture
def own_catalog(monkeypatch):
    """The mechanisms added by a test stay in that test."""
    monkeypatch.setattr(catalog, "_ADDED", {})


def _mp(exprs, args):
    """mpmath evaluation of SymPy expressions: independent of the generated printer."""
    return sp.lambdify(args, exprs, modules="mpmath")


def test_from_symbolic_builds_the_numeric_mechanism(symbolic, moved, own_catalog):
    assert isinstance(moved, Mechanism)
    assert (moved.name, moved.description) == (NAME, symbolic.description)
    assert moved.inputs == symbolic.inputs and moved.n_inputs == 2
    assert moved.delta is not None and moved.has_frame and moved.state_space == "SO(3)"
    # its drawing geometry: the symbolic one at the drawing dimensions a = 1.6, b = rho = 1
    num = viz.as_geometry(MOVED)
    for name in moved.geometry.FIELDS:
        np.testing.assert_allclose(getattr(moved.geometry, name), getattr(num, name), atol=1e-15)
    np.testing.assert_allclose(moved.geometry.contact, [0.3 * np.sqrt(2), 0.3 * np.sqrt(2), 0.8], atol=1e-15)
    # not known by name until added
    assert NAME not in catalog.names()
    with pytest.raises(ValueError, match="unknown mechanism"):
        catalog.get(NAME)


@pytest.mark.slow
def test_matches_the_symbolic_expressions(symbolic, moved):
    """L, Q, Δ, N, W of the generated module against the derivation (mpmath) at random
    rotations; and, independently of the derivation's solution, ``C(R) L(R) = (I₂; 0)`` and
    ``det C = κ Δ`` with the constraint matrix of the geometry."""
    u = inputs(2)
    f_L = _mp(list(symbolic.L), list(r))
    f_Q = _mp(list(Q_matrix(symbolic.L, u)), list(r) + list(u))
    f_d = _mp(symbolic.delta, list(r))
    f_N = _mp(list(symbolic.frame), list(r))
    f_W = _mp(list(input_map(symbolic.L, symbolic.frame)), list(r))
    C_sym = constraint_matrix(MOVED)
    assert C_sym.free_symbols <= set(r)
    f_C = sp.lambdify(list(r), C_sym, "numpy")
    kappa = float(symbolic.derivation["kappa"])
    rng = np.random.default_rng(2026)
    worst = 0.0
    for R in random_rotations(60, rng, 0.05, moved.delta):
        x = R.ravel()
        uu = rng.normal(size=2)
        pairs = [(moved.L(R), f_L(*x)), (moved.Q(R, uu), f_Q(*x, *uu)), (moved.delta(R), f_d(*x)),
                 (moved.frame.N(R), f_N(*x)), (moved.frame.W(R), f_W(*x))]
        for got, want in pairs:
            got = np.asarray(got, dtype=float).ravel()
            want = np.array(want, dtype=float).ravel()
            worst = max(worst, np.max(np.abs(got - want)) / max(1.0, np.max(np.abs(want))))
        C = np.array(f_C(*x), dtype=float)
        np.testing.assert_allclose(C @ moved.L(R), [[1, 0], [0, 1], [0, 0]], atol=1e-12)
        assert np.linalg.det(C) == pytest.approx(kappa * moved.delta(R), rel=1e-12, abs=1e-15)
    assert worst < 1e-12
    # not the paper's platform: Δ differs
    assert symbolic.delta != r[0, 1] * r[2, 0] + r[1, 0] * r[2, 1]
    check_into_forms(moved.module, random_rotations(20, rng, 0.05, moved.delta), rng)


@pytest.mark.slow
def test_plans_in_two_calls(moved, goal):
    R0, Rd = goal
    res = plan(R0, Rd, mechanism=moved)
    assert res.mechanism == NAME and res.parametrisation.mechanism is moved
    R_T = check_solution(res, R0, Rd, mechanism=moved)
    assert terminal_error(R_T, Rd) <= 1e-8
    # the plan drives the new kinematics, not the paper's: on the paper's platform the
    # same leg rates do not reach the goal
    assert misses(R0, res, Rd, "platform")


def test_added_mechanism_plans_by_name_and_is_listed(moved, goal, own_catalog, tmp_path, capsys):
    assert catalog.add(moved) is moved
    assert NAME in catalog.names() and catalog.get(NAME) is moved
    R0, Rd = goal
    res = plan(R0, Rd, mechanism=NAME)
    assert res.mechanism == NAME
    R_T = resimulate(R0, res.controls, 1.0, mechanism=NAME, breakpoints=res.breakpoints)
    assert terminal_error(R_T, Rd) <= 1e-8
    check_solution(res, R0, Rd)
    # the result reloads by name (its controls replay the motion with the same kernels)
    back = PlanResult.load(res.save(tmp_path / "plan.json"))
    assert back == res
    # the loaded controls at t against the certified replay's stage values: two computations
    assert_inputs_match(back.controls(res.t), res.u)
    # `nonholo mechanisms` lists it with the rest
    assert main(["mechanisms"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [ln.split()[0] for ln in lines] == list(catalog.names())
    assert any(ln.split()[0] == NAME and moved.description in ln for ln in lines)
    # the package's names cannot be taken, and only Mechanisms can be added
    with pytest.raises(ValueError, match="already exists"):
        catalog.add(dataclasses.replace(moved, name="platform"))
    with pytest.raises(ValueError, match="Mechanism"):
        catalog.add(symbolic_stand_in())


def misses(R0, res, Rd, mechanism) -> bool:
    """Whether the planned leg rates, replayed on ``mechanism`` (DOP853), end more than
    1e-3 rad from ``Rd`` — or cannot be replayed at all (the motion runs into Δ = 0)."""
    try:
        R_T = resimulate(R0, res.controls, res.T, mechanism, res.breakpoints)
    except RuntimeError:            # DOP853 stalls at the singular surface
        return True
    return terminal_error(R_T, Rd) > 1e-3


def symbolic_stand_in():
    """Something that is not a ``nonholo.Mechanism`` (a symbolic mechanism)."""
    return platform_mechanism("not_numeric", PAPER_GEOMETRY, "symbolic")


def test_re_adding_a_changed_mechanism_uses_the_new_kinematics(moved, changed, goal, own_catalog):
    """Adding again under the same name replaces the kinematics: simulations and plans by
    name use the new ones, not kernels compiled for the old."""
    sym_t, turned = changed
    assert turned.name == moved.name == NAME
    R0 = goal[0]
    assert abs(moved.delta(R0)) > 0.1 and abs(turned.delta(R0)) > 0.1
    # small leg rates: |Δ| stays above 0.25 on both mechanisms
    probe = Fourier(1.0, [[0.0125, 0.025, 0.0, 0.0, 0.0125], [-0.0125, 0.0, 0.025, 0.0125, 0.0]])

    catalog.add(moved)
    old = simulate(R0, probe, 1.0, mechanism=NAME)              # compiles the old kernels
    assert so3.distance(old.R_T, resimulate(R0, probe, 1.0, mechanism=moved)) <= 1e-9
    first = plan(*goal, mechanism=NAME)                         # ... and the old frame kernels
    assert first.success, first.reason

    catalog.add(turned)
    assert catalog.get(NAME) is turned
    new = simulate(R0, probe, 1.0, mechanism=NAME)
    assert so3.distance(new.R_T, resimulate(R0, probe, 1.0, mechanism=turned)) <= 1e-9
    assert so3.distance(new.R_T, old.R_T) > 1e-2
    np.testing.assert_allclose(new.delta, [float(turned.delta(R)) for R in new.R], atol=1e-15)

    R0c, Rdc = reachable_goals(turned, 1, seed=405)[0]
    res = plan(R0c, Rdc, mechanism=NAME)
    assert res.mechanism == NAME and res.parametrisation.mechanism is turned
    R_T = check_solution(res, R0c, Rdc, mechanism=turned)
    assert terminal_error(R_T, Rdc) <= 1e-8
    # the old kinematics would not have got there with these leg rates
    assert misses(R0c, res, Rdc, moved)


def test_figures_draw_a_mechanism_outside_the_catalog(moved, goal):
    """The Δ panel of a plan with a Mechanism nobody added draws the plan's own Δ(t)."""
    import matplotlib
    matplotlib.use("Agg")
    from nonholo import viz

    R0, Rd = goal
    res = plan(R0, Rd, mechanism=moved)
    ax = viz.delta_figure(res).axes[0]
    curves = [ln for ln in ax.lines if len(ln.get_xdata()) == len(res.t)]
    assert len(curves) == 1
    np.testing.assert_array_equal(curves[0].get_ydata(), res.delta)
