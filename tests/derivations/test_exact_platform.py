"""A platform of numbers (``derivations.mechanisms.exact_platform``): ``L`` and ``Q`` kept in
terms of the constraint matrix's entries, ``W = C₁₂ N`` without inverting anything.

Checked against the symbolic route (the catalog's generated modules) on the paper's and
the raised geometries at the drawing dimensions, against ``input_map``'s Gauss elimination,
and, on a geometry of floats, against a constraint matrix written out in NumPy and central
differences.
"""
from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from scipy.spatial.transform import Rotation

from derivations import codegen
from derivations.definitions import RAISED_GEOMETRY
from derivations.mechanisms import (
    PAPER_GEOMETRY,
    PlatformGeometry,
    a,
    b,
    exact_geometry,
    input_map,
    leg_rate_row,
    paper_platform,
    platform_mechanism,
    rho,
)
from derivations.rotations import hat, r
from nonholo.codegen.mechanism_modules import load_source
from nonholo.model import catalog
from nonholo.spaces import so3

FIELDS = ("base1", "tip1", "base2", "tip2", "contact", "axle")

def on_sphere(*v) -> tuple:
    """The point of the unit sphere in the direction ``v`` (the sphere's radius is the unit of
    length: a platform's joints and contact point lie on it)."""
    n = sum(x * x for x in v) ** 0.5
    return tuple(x / n for x in v)


#: A geometry of floats, none of its vectors special.
FLOATS = PlatformGeometry(base1=(0.3, 1.5, 0.4), tip1=on_sphere(0.1, 1.0, 0.0), base2=(1.5, -0.2, 0.5),
                          tip2=on_sphere(1.0, 0.0, 0.1), contact=(0.0, 0.6, 0.8), axle=(1.0, 0.0, 0.0))


def at_dimensions(geometry):
    """``geometry`` with ``a = 8/5``, ``b = ρ = 1`` (the drawing dimensions): numbers only."""
    dims = {a: sp.Rational(8, 5), b: 1, rho: 1}
    return PlatformGeometry(**{k: tuple(sp.sympify(x).subs(dims) for x in getattr(geometry, k)) for k in FIELDS})


def rotations(n, seed, delta=None, clearance=0.05):
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        R = Rotation.random(random_state=rng.integers(1 << 31)).as_matrix()
        if delta is None or abs(delta(R)) > clearance:
            out.append(R)
    return out


@pytest.fixture(scope="module")
def floats():
    m = platform_mechanism("float_platform", FLOATS, "a platform of floats")
    return m, load_source(codegen.mechanism_module(m), m.name)


def test_a_geometry_of_numbers_is_made_exact_and_one_with_symbols_is_not():
    g = exact_geometry(FLOATS)
    assert g.base1 == (sp.Rational(3, 10), sp.Rational(3, 2), sp.Rational(2, 5))
    assert all(isinstance(x, sp.Rational) for k in FIELDS for x in getattr(g, k))
    assert exact_geometry(PAPER_GEOMETRY) is None
    assert exact_geometry(at_dimensions(PAPER_GEOMETRY)).axle == PAPER_GEOMETRY.axle


@pytest.mark.parametrize("name, geometry", [("platform", PAPER_GEOMETRY), ("platform_raised", RAISED_GEOMETRY)])
def test_the_exact_route_is_the_symbolic_one_on_the_catalog_geometries(name, geometry):
    """The generated functions of the exact route at the drawing dimensions against the
    catalog's (generated from the symbolic route; the kinematics do not depend on a, b, ρ)."""
    m = platform_mechanism("exact_" + name, at_dimensions(geometry), "exact route")
    assert set(m.derivation["auxiliary_forms"]) == {"G", "QG", "delta", "W"}
    mine, ref = load_source(codegen.mechanism_module(m), m.name), catalog.get(name).module
    q = ref.NO_COORDINATES
    rng = np.random.default_rng(3)
    worst = {}
    for R in rotations(100, 5, lambda R: ref.delta(R, q)):
        v = rng.normal(size=2)
        for f, args in (("G", (R, q)), ("QG", (R, q, v)), ("delta", (R, q)), ("N", (R, q)),
                        ("QN", (R, q, v)), ("W", (R, q)), ("leg_lengths", (R,)), ("leg_gradients", (R,))):
            got, want = np.asarray(getattr(mine, f)(*args)), np.asarray(getattr(ref, f)(*args))
            worst[f] = max(worst.get(f, 0.0), np.max(np.abs(got - want)) / max(1.0, np.max(np.abs(want))))
    assert max(worst.values()) < 1e-12, worst


def test_W_is_the_gauss_elimination_of_the_symbolic_route():
    """``W = C₁₂ N`` (the leg rows of C times the frame) is ``(Nᵀ L)^{-1}`` as ``input_map``
    inverts it, exactly, on the paper's symbolic platform."""
    m = paper_platform()
    assert m.frame_inputs == input_map(m.L, m.frame)


def test_a_geometry_of_floats_solves_its_constraints(floats):
    """``C(R) L(R) = (I₂; 0)`` and ``det C = κ Δ`` with ``C`` written out in NumPy from the
    geometry (leg rows ``-2 (R tip × base) / (4 |base| |tip|)``, the disk's unit row), and
    ``W(R) = (Nᵀ L(R))^{-1}`` by NumPy's inverse."""
    m, mod = floats
    g = {k: np.array(getattr(FLOATS, k), dtype=float) for k in FIELDS}
    disk = np.cross(g["contact"], g["axle"])
    kappa = float(m.derivation["kappa"])
    q = mod.NO_COORDINATES
    for R in rotations(60, 7, lambda R: mod.delta(R, q)):
        rows = [-2 * np.cross(R @ g[f"tip{i}"], g[f"base{i}"]) / (4 * np.linalg.norm(g[f"base{i}"])
                                                                  * np.linalg.norm(g[f"tip{i}"])) for i in (1, 2)]
        C = np.array(rows + [disk / np.linalg.norm(disk)])
        np.testing.assert_allclose(C @ mod.G(R, q), [[1, 0], [0, 1], [0, 0]], atol=1e-12)
        assert np.linalg.det(C) == pytest.approx(kappa * mod.delta(R, q), rel=1e-11, abs=1e-14)
        N = mod.N(R, q)
        np.testing.assert_allclose(N.T @ N, np.eye(2), atol=1e-14)
        np.testing.assert_allclose(mod.W(R, q), np.linalg.inv(N.T @ mod.G(R, q)), rtol=1e-10, atol=1e-12)


def test_the_generated_forms_are_the_mechanism_s_expressions(floats):
    """The generated ``G``, ``Δ``, ``W`` (from the derivation's forms in the entries of C₀)
    against the mechanism's ``L``, ``delta`` and ``frame_inputs`` in ``r_ij`` (mpmath)."""
    m, mod = floats
    f = sp.lambdify(list(r), [m.L, m.delta, m.frame_inputs], modules="mpmath")
    q = mod.NO_COORDINATES
    for R in rotations(30, 17, lambda R: mod.delta(R, q)):
        L, delta, W = (np.array(x.tolist() if hasattr(x, "tolist") else x, dtype=float) for x in f(*R.ravel()))
        np.testing.assert_allclose(mod.G(R, q), L, rtol=1e-12, atol=1e-13)
        assert mod.delta(R, q) == pytest.approx(float(delta), rel=1e-12)
        np.testing.assert_allclose(mod.W(R, q), W, rtol=1e-12, atol=1e-13)


def test_its_variational_matrix_is_the_derivative_of_its_field(floats):
    """``QG(R, v) s`` against a central difference of ``G(exp(ε[s]) R) v``."""
    _, mod = floats
    q = mod.NO_COORDINATES
    rng = np.random.default_rng(11)
    for R in rotations(30, 13, lambda R: mod.delta(R, q), 0.2):
        v, s, eps = rng.normal(size=2), rng.normal(size=3), 1e-6
        fd = (mod.G(so3.exp(eps * s) @ R, q) @ v - mod.G(so3.exp(-eps * s) @ R, q) @ v) / (2 * eps)
        np.testing.assert_allclose(mod.QG(R, q, v) @ s, fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(fd)))


def test_the_leg_row_is_the_derivative_of_the_squared_length():
    """``leg_rate_row`` (a closed form) against SymPy differentiating ``|R tip − base|²`` along
    ``dR/dt = [ω] R``, on both catalog geometries and the floats."""
    w = sp.Matrix(sp.symbols("w1:4"))
    for geometry in (PAPER_GEOMETRY, RAISED_GEOMETRY, exact_geometry(FLOATS)):
        for base, tip in ((geometry.base1, geometry.tip1), (geometry.base2, geometry.tip2)):
            d = r * sp.Matrix(tip) - sp.Matrix(base)
            rate = sp.expand(2 * (d.T * hat(w) * r * sp.Matrix(tip))[0])
            assert leg_rate_row(base, tip) == sp.Matrix([[rate.coeff(wk) for wk in w]])
