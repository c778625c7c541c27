"""A mechanism from its equations (``Mechanism.from_equations``, ``Mechanism.from_constraints``):
the field it generates against the equations (NumPy on the SymPy expressions as given, SciPy's
DOP853 on them for a plan), the constraint form against the field form and the catalog's
derivations, the checks on construction, and the cache of generated modules."""
from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from sympy import cos, sin, tan

import derivations.codegen
import derivations.equations
import derivations.generator
from derivations.mechanisms import Mechanism as Symbolic
from nonholo import Mechanism, mechanism_named, plan
from nonholo.codegen.cache import generated_cache_dir
from nonholo.spaces import so3

x, y, th, th0, th1, phi, v, w, ell = sp.symbols("x y theta theta0 theta1 phi v w ell", real=True)
xd, yd, thd, thd0, thd1, phid = sp.symbols("xdot ydot thetadot thetadot0 thetadot1 phidot", real=True)
TRAILER = dict(coordinates=[x, y, th0, th1], inputs=[v, w],
               rates=[v * cos(th0), v * sin(th0), w, v * sin(th0 - th1)], angles=[th0, th1])


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """A cache of generated modules (and kernels) of the test's own."""
    monkeypatch.setenv("NONHOLO_CACHE_DIR", str(tmp_path))
    return tmp_path / "generated"


@pytest.fixture(scope="module")
def trailer():
    return Mechanism.from_equations("trailer1", **TRAILER)


def field_of(coordinates, inputs, rates):
    """``G(x)`` with ``rates = G(x) u``, by NumPy on the expressions as written."""
    f = sp.lambdify([coordinates, inputs], rates, "numpy")
    m = len(inputs)
    return lambda q: np.column_stack([np.array(f(q, np.eye(m)[j]), dtype=float) for j in range(m)])


def test_the_issue_s_call_gives_the_unicycle_with_a_trailer(trailer):
    assert isinstance(trailer, Mechanism) and trailer.name == "trailer1"
    assert trailer.state_space == "R^4" and trailer.coordinates == ("x", "y", "theta0", "theta1")
    assert trailer.angles == (False, False, True, True) and trailer.units == ("", "", "rad", "rad")
    assert trailer.inputs == ("v", "w") and trailer.delta is None and not trailer.has_frame
    G = field_of(TRAILER["coordinates"], TRAILER["inputs"], TRAILER["rates"])
    rng = np.random.default_rng(1)
    I = np.eye(3)
    for _ in range(20):
        q = rng.normal(scale=2, size=4)
        np.testing.assert_allclose(trailer.G(I, q), G(q), atol=1e-15)
        # its variational matrix: a central difference of G(q) u
        u, s, eps = rng.normal(size=2), rng.normal(size=4), 1e-6
        fd = (trailer.G(I, q + eps * s) @ u - trailer.G(I, q - eps * s) @ u) / (2 * eps)
        np.testing.assert_allclose(trailer.module.QG(I, q, u) @ s, fd, atol=1e-8)


def test_it_plans_and_the_plan_holds_on_the_equations(trailer):
    """A plan of the trailer replayed by DOP853 on the rates as written reaches the goal."""
    goal = np.array([1.0, 0.5, 0.0, 0.0])
    res = plan(np.zeros(4), goal, mechanism=trailer)
    assert res.success, res.reason
    f = sp.lambdify([TRAILER["coordinates"], TRAILER["inputs"]], TRAILER["rates"], "numpy")
    sol = solve_ivp(lambda t, q: np.array(f(q, res.controls(np.array([t]))[0]), dtype=float),
                    (0.0, res.T), np.zeros(4), method="DOP853", rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(sol.y[:, -1] - goal)) < 1e-8


def test_constraints_give_the_car_of_the_catalog():
    """The car from its rolling constraints (inputs v and φ̇), from its field (tan: Δ from the
    denominators) and the catalog's ``car`` (derivations.vehicles): one field, one Δ."""
    by_constraints = Mechanism.from_constraints(
        "car_from_constraints", coordinates=[x, y, th, phi], velocities=[xd, yd, thd, phid], inputs=[v, phid],
        constraints=[xd * cos(th) + yd * sin(th) - v, -xd * sin(th) + yd * cos(th),
                     -(xd - ell * sin(th) * thd) * sin(th + phi) + (yd + ell * cos(th) * thd) * cos(th + phi)],
        angles=[th, phi], parameters={ell: 1}, cache=False)
    by_field = Mechanism.from_equations(
        "car_from_field", coordinates=[x, y, th, phi], inputs=[v, w],
        rates=[v * cos(th), v * sin(th), v * tan(phi) / ell, w], angles=[th, phi], parameters={ell: 1.0},
        cache=False)
    car = mechanism_named("car")
    rng = np.random.default_rng(2)
    I = np.eye(3)
    for _ in range(20):
        q = rng.uniform(-1.2, 1.2, size=4)
        for m in (by_constraints, by_field):
            np.testing.assert_allclose(m.G(I, q), car.G(I, q), rtol=1e-13, atol=1e-15)
            assert m.delta(I, q) == pytest.approx(car.delta(I, q), rel=1e-14)


def test_a_pfaffian_constraint_with_inputs_among_the_rates():
    """The unicycle: no side slip ``ẋ sin θ − ẏ cos θ = 0``, the inputs ẋ and θ̇: ``ẏ = ẋ tan θ``,
    singular where ``cos θ = 0``."""
    m = Mechanism.from_constraints("unicycle_xdot", coordinates=[x, y, th], velocities=[xd, yd, thd],
                                   inputs=[xd, thd], constraints=[xd * sin(th) - yd * cos(th)], cache=False)
    assert m.inputs == ("xdot", "thetadot") and m.delta is not None
    q = np.array([0.3, -0.2, 0.4])
    np.testing.assert_allclose(m.G(np.eye(3), q), [[1, 0], [np.tan(0.4), 0], [0, 1]], atol=1e-15)
    assert abs(m.delta(np.eye(3), q)) == pytest.approx(np.cos(0.4), rel=1e-14)


def test_an_orientation_from_body_rates_and_a_ball_on_the_product():
    """``omega`` in symbols of one's own: the attitude (``ω = R (u1 e1 + u2 e2)``) and the
    rolling ball (``ω = (−v2, v1, 0)``, ``ṗ = v``) are the catalog's."""
    R = sp.Matrix(3, 3, sp.symbols("R11:14 R21:24 R31:34"))
    u1, u2, p1, p2, v1, v2 = sp.symbols("u1 u2 p1 p2 v1 v2")
    attitude = Mechanism.from_equations("attitude_rates", inputs=[u1, u2], omega=R * sp.Matrix([u1, u2, 0]),
                                        rotation=R, cache=False)
    ball = Mechanism.from_equations("ball_rates", coordinates=[p1, p2], inputs=[v1, v2], rates=[v1, v2],
                                    omega=[-v2, v1, 0], cache=False)
    assert (attitude.state_space, ball.state_space) == ("SO(3)", "SO(3)xR^2")
    rng = np.random.default_rng(4)
    for _ in range(10):
        Rn, p, u = so3.exp(rng.normal(size=3)), rng.normal(size=2), rng.normal(size=2)
        np.testing.assert_allclose(attitude.L(Rn), mechanism_named("attitude").L(Rn), atol=1e-15)
        np.testing.assert_allclose(attitude.Q(Rn, u), mechanism_named("attitude").Q(Rn, u), atol=1e-15)
        np.testing.assert_allclose(ball.G(Rn, p), mechanism_named("rolling_ball").G(Rn, p), atol=1e-15)


BAD = [
    (dict(rates=[v * cos(th), v * sin(th0), w, v * sin(th0 - th1)]), "rates use theta, not declared"),
    (dict(rates=[v * cos(th0), v * sin(th0), w]), "3 expression"),              # one short
    (dict(rates=[v * cos(th0), v * sin(th0), w, w ** 2]), r"the rate of theta1 = w\*\*2: its term w\*\*2 is not affine"),
    (dict(rates=[v * cos(th0), v * sin(th0), w + v * w * sin(th1), th0]), r"its term v\*w\*sin\(theta1\) is not affine"),
    (dict(angles=[th0, phi]), "phi is not among the coordinates"),
    (dict(inputs=[v, x]), "x is given both in coordinates and in inputs"),
    (dict(rates=[v * cos(th0), v * sin(th0), w, v * sp.Symbol("r11", real=True)]), "omega="),
    (dict(parameters={ell: sp.Symbol("h")}), "ell = h is not a number"),
    (dict(coordinates=[x, y, th0, sp.Symbol("q")], angles=[th0]), "q needs another name"),
    (dict(coordinates=[], rates=[]), "coordinates= with rates="),
]


@pytest.mark.parametrize("change, message", BAD)
def test_a_bad_definition_is_refused_naming_what_is_wrong(change, message):
    with pytest.raises(ValueError, match=message):
        Mechanism.from_equations("bad", **{**TRAILER, **change}, cache=False)


def test_the_class_of_state_is_named_when_it_does_not_fit():
    with pytest.raises(ValueError, match="omega: the angular velocity has 3 components"):
        Mechanism.from_equations("bad", inputs=[v, w], omega=[v, w], cache=False)
    with pytest.raises(ValueError, match="not a Python identifier|must be a Python identifier"):
        Mechanism.from_equations("two words", **TRAILER)
    # the numeric class, built by hand, says how to build one
    with pytest.raises(TypeError, match="Mechanism.from_equations"):
        Mechanism("uni", "unicycle", ("v", "w"), None, None, None, None)
    with pytest.raises(TypeError, match="Mechanism.from_equations"):
        Mechanism.from_symbolic(TRAILER)
    # the symbolic class given a planar field for an orientation's L
    planar = sp.Matrix([[cos(th), 0], [sin(th), 0], [0, 1]])
    with pytest.raises(ValueError, match=r"L uses theta.*coordinates=.*from_equations"):
        Symbolic("uni", "unicycle", L=planar, inputs=("v", "w"))
    with pytest.raises(ValueError, match="3 rows"):
        Symbolic("uni", "unicycle", L=planar[:2, :], inputs=("v", "w"))
    with pytest.raises(ValueError, match=r"constraints: 1 equation\(s\) for the 2 rate\(s\)"):
        Mechanism.from_constraints("bad", coordinates=[x, y, th], velocities=[xd, yd, thd], inputs=[v, thd],
                                   constraints=[xd * sin(th) - yd * cos(th)], cache=False)
    with pytest.raises(ValueError, match="constraints use ell"):
        Mechanism.from_constraints("bad", coordinates=[x, y, th], velocities=[xd, yd, thd], inputs=[xd, thd],
                                   constraints=[ell * xd * sin(th) - yd * cos(th)], cache=False)


def test_the_default_singular_set_is_where_the_denominators_vanish():
    m = Mechanism.from_equations("car_tan", coordinates=[x, y, th, phi], inputs=[v, w],
                                 rates=[v * cos(th), v * sin(th), v * tan(phi) / ell, w / (1 + x ** 2)],
                                 parameters={ell: 2}, cache=False)
    symbolic = derivations.equations.field_mechanism(
        "car_tan", coordinates=[x, y, th, phi], inputs=[v, w],
        rates=[v * cos(th), v * sin(th), v * tan(phi) / ell, w / (1 + x ** 2)], parameters={ell: 2})
    assert sp.simplify(symbolic.delta - cos(phi) * (1 + x ** 2)) == 0
    q = np.array([0.5, 0.0, 0.0, 0.3])
    assert m.delta(np.eye(3), q) == pytest.approx(np.cos(0.3) * 1.25, rel=1e-14)


def test_a_second_build_reads_the_cache_and_the_generator_s_version_is_in_its_key(cache, monkeypatch):
    first = Mechanism.from_equations("trailer1", **TRAILER)
    files = sorted(cache.glob("trailer1_*.py"))
    assert len(files) == 1 and files[0].read_text() == first.module.SOURCE

    def forbidden(*args, **kwargs):
        raise AssertionError("derived or generated again")

    with monkeypatch.context() as patch:
        patch.setattr(derivations.equations, "field_mechanism", forbidden)
        patch.setattr(derivations.codegen, "mechanism_module", forbidden)
        again = Mechanism.from_equations("trailer1", **TRAILER)
    assert again.module.SOURCE == first.module.SOURCE and again is not first
    # another generator, or other equations: another file
    monkeypatch.setattr(derivations.generator, "generator_version", lambda: "another generator")
    Mechanism.from_equations("trailer1", **TRAILER)
    Mechanism.from_equations("trailer1", **{**TRAILER, "rates": TRAILER["rates"][:3] + [v * sin(th1 - th0)]})
    assert len(list(cache.glob("trailer1_*.py"))) == 3
    # the digest covers the generator's modules
    assert generated_cache_dir() == cache


def test_the_generator_s_version_follows_its_sources(tmp_path, monkeypatch):
    """``generator_version`` hashes SymPy's version and the modules that write the code."""
    import shutil
    from pathlib import Path

    here = Path(derivations.generator.__file__)
    for name in derivations.generator.GENERATOR_MODULES:
        shutil.copy(here.with_name(f"{name}.py"), tmp_path / f"{name}.py")
    monkeypatch.setattr(derivations.generator, "__file__", str(tmp_path / "generator.py"))
    before = derivations.generator.generator_version()
    with open(tmp_path / "state_space.py", "a") as f:
        f.write("\n# changed\n")
    assert derivations.generator.generator_version() != before
