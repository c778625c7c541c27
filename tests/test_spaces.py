"""One contract every state space passes (:mod:`nonholo.spaces.groups`): the factors
``SO3`` and ``Euclidean`` on their own parts, and every ``Product`` (the catalog's spaces
among them) on states ``(R, q)``.

Independent references: SciPy's ``Rotation`` for logarithms and geodesics, plain NumPy
for the coordinates.
"""
from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from nonholo.model import catalog
from nonholo.spaces.groups import SO3, Euclidean, Product, wrap

rng = np.random.default_rng(20140901)

FACTORS = {
    "SO3": SO3(),
    "R2": Euclidean(2, names=("x", "y")),
    "R4 with angles": Euclidean(4, names=("x", "y", "theta", "phi"), angles=(False, False, True, True)),
}
PRODUCTS = {
    "SO(3)": Product(SO3()),
    "SO(3)xR^2": Product(SO3(), Euclidean(2)),
    "R^4 with angles": Product(None, FACTORS["R4 with angles"]),
    **{f"catalog {name}": catalog.get(name).space for name in catalog.names()},
}


def close(a, b, tol=1e-12) -> bool:
    return np.allclose(np.asarray(a, dtype=float), np.asarray(b, dtype=float), atol=tol, rtol=0.0)


def point(factor):
    return factor.sample(rng, 1)[0]


# -- factors ---------------------------------------------------------------------------

@pytest.fixture(params=sorted(FACTORS))
def factor(request):
    return FACTORS[request.param]


def test_difference_is_zero_at_the_point_and_antisymmetric(factor):
    x, y = point(factor), point(factor)
    assert close(factor.difference(x, x), np.zeros(factor.dim))
    assert close(factor.difference(x, y), -factor.difference(y, x), 1e-9)


def test_distance_axioms(factor):
    x, y, z = point(factor), point(factor), point(factor)
    assert factor.distance(x, x) == pytest.approx(0.0, abs=1e-12)
    assert factor.distance(x, y) == pytest.approx(factor.distance(y, x), rel=1e-9)
    assert factor.distance(x, y) >= 0.0
    assert factor.distance(x, z) <= factor.distance(x, y) + factor.distance(y, z) + 1e-12


def test_interpolation_ends_and_halfway(factor):
    x, y = point(factor), point(factor)
    path = factor.interpolate(x, y, [0.0, 0.5, 1.0])
    assert close(path[0], x, 1e-12)
    assert factor.distance(path[-1], y) < 1e-12
    half = factor.distance(x, y) / 2
    assert factor.distance(x, path[1]) == pytest.approx(half, rel=1e-9)
    assert factor.distance(path[1], y) == pytest.approx(half, rel=1e-9)


def test_json_and_cli_round_trips(factor):
    x = point(factor)
    back = factor.from_json(json.loads(json.dumps(factor.to_json(x))), "x")
    assert close(back, x, 0.0)
    assert close(factor.from_cli(factor.to_cli(x)), x, 1e-12)


def test_so3_against_scipy():
    R, Rd = point(SO3()), point(SO3())
    l = SO3().difference(R, Rd)
    assert close(l, Rotation.from_matrix(R @ Rd.T).as_rotvec(), 1e-12)
    mid = SO3().interpolate(R, Rd, [0.25])[0]
    expected = (Rotation.from_rotvec(0.25 * Rotation.from_matrix(Rd @ R.T).as_rotvec()) * Rotation.from_matrix(R))
    assert close(mid, expected.as_matrix(), 1e-12)


def test_angles_are_wrapped_and_interpolated_the_short_way():
    space = FACTORS["R4 with angles"]
    q, qd = np.array([1.0, 2.0, 3.0, -3.0]), np.array([0.0, 0.0, -3.0, 3.0])
    d = space.difference(q, qd)
    assert close(d, [1.0, 2.0, 6.0 - 2 * np.pi, -6.0 + 2 * np.pi])
    assert close(wrap(np.array([np.pi, -np.pi, 3 * np.pi])), [np.pi, np.pi, np.pi])
    mid = space.interpolate(qd, q, [0.5])[0]
    assert close(mid[2:], [-3.0 + (6.0 - 2 * np.pi) / 2, 3.0 - (6.0 - 2 * np.pi) / 2])


def test_samples_are_uniform_in_their_box():
    q = Euclidean(3, angles=(False, True, False), box=2.0).sample(np.random.default_rng(1), 20000)
    assert np.all(np.abs(q[:, 0]) <= 2.0) and np.all(np.abs(q[:, 1]) <= np.pi)
    assert np.mean(q, axis=0) == pytest.approx([0.0, 0.0, 0.0], abs=0.05)
    R = SO3().sample(np.random.default_rng(2), 20000)
    # Haar: the mean of a uniform rotation matrix is zero, and trace is 1 + 2cos(angle) with E = 0
    assert np.abs(R.mean(axis=0)).max() < 0.02


def test_bad_input_names_the_argument():
    with pytest.raises(ValueError, match="goal"):
        SO3().parse(np.eye(2), "goal")
    with pytest.raises(ValueError, match="start.*3 coordinates"):
        Euclidean(3).parse([1.0, 2.0], "start")
    with pytest.raises(ValueError, match="start must be finite"):
        Euclidean(2).parse([1.0, np.nan], "start")
    with pytest.raises(ValueError, match="names must have 2 entries"):
        Euclidean(2, names=("x",))
    with pytest.raises(ValueError, match="k must be"):
        Euclidean(-1)


# -- products --------------------------------------------------------------------------

@pytest.fixture(params=sorted(PRODUCTS))
def space(request):
    return PRODUCTS[request.param]


def states(space, n):
    return space.sample(rng, n)


def test_product_dimension_and_names(space):
    assert space.dim == sum(f.dim for f in (space.rotation, space.coordinates) if f is not None)
    assert len(space.cli_names) == (3 if space.has_orientation else 0) + space.k
    assert space.name in ("SO(3)", f"R^{space.k}", f"SO(3)xR^{space.k}")


def test_error_stacks_its_factors_and_reports_their_norms(space):
    (R, q), (Rd, qd) = states(space, 2)
    e, parts = space.error(R, q, Rd, qd)
    assert e.shape == (space.dim,)
    expected = []
    if space.has_orientation:
        expected.append(Rotation.from_matrix(R @ Rd.T).as_rotvec())
        assert parts["rotation"] == pytest.approx(np.linalg.norm(expected[0]), rel=1e-12)
    if space.k:
        expected.append(space.coordinates.difference(q, qd))
        assert parts["coordinates"] == pytest.approx(np.linalg.norm(expected[-1]), rel=1e-12)
    assert close(e, np.concatenate(expected), 1e-12)
    assert space.distance(R, q, Rd, qd) == pytest.approx(np.linalg.norm(e), rel=1e-12)
    assert close(space.offset(Rd, qd, R, q), e, 1e-12)


def test_product_distance_axioms_and_interpolation(space):
    a, b, c = states(space, 3)
    d = space.distance
    assert d(*a, *a) == pytest.approx(0.0, abs=1e-12)
    assert d(*a, *b) == pytest.approx(d(*b, *a), rel=1e-9)
    assert d(*a, *c) <= d(*a, *b) + d(*b, *c) + 1e-12
    path = space.interpolate(a, b, [0.0, 0.5, 1.0])
    assert d(*path[0], *a) < 1e-12 and d(*path[-1], *b) < 1e-12
    assert d(*a, *path[1]) == pytest.approx(d(*a, *b) / 2, rel=1e-9)


def test_product_json_cli_and_public_round_trips(space):
    R, q = states(space, 1)[0]
    value = json.loads(json.dumps(space.to_json(R, q)))
    R2, q2 = space.from_json(value, "goal")
    assert close(R2, R, 0.0) and close(q2, q, 0.0)
    R3, q3 = space.from_cli(space.to_cli(R, q))
    assert space.distance(R3, q3, R, q) < 1e-12
    R4, q4 = space.parse(space.public(R, q), "goal")
    assert close(R4, R, 0.0) and close(q4, q, 0.0)


def test_product_refuses_other_forms_naming_the_argument(space):
    with pytest.raises(ValueError, match="Rd"):
        space.parse("nonsense", "Rd")
    with pytest.raises(ValueError, match=r"takes \d+ numbers"):
        space.from_cli([0.0] * (len(space.cli_names) + 1))
    assert space.describe() in ("a rotation matrix (3×3)",) or "coordinates" in space.describe()


def test_the_catalog_spaces():
    assert catalog.get("platform").space == Product(SO3())
    assert catalog.get("car").space.name == "R^4"
    assert catalog.get("car").space.coordinates.angles == (False, False, True, True)
    assert catalog.get("rolling_ball").space.name == "SO(3)xR^2"


def test_errors_are_written_with_their_units():
    """An error's norm carries the unit its parts share, or the units it mixes."""
    planar = Product.of(False, ("x", "y"), ("m", "m"))
    car_like = Product.of(False, ("x", "y", "th"), ("m", "m", "rad"), (False, False, True))
    ball_like = Product.of(True, ("p1", "p2"), ("radius", "radius"))
    bare = Product.of(False, ("a", "b"))
    assert planar.amount(1.5e-3) == "0.0015 m" and planar.error_unit == "m"
    assert car_like.amount(2e-11, ".1e") == "2.0e-11 (m, rad)"
    assert Product.of(True).amount(3e-12) == "3e-12 rad"
    assert ball_like.units == ("rad", "rad", "rad", "radius", "radius")
    assert ball_like.amount(1e-9, part="rotation") == "1e-09 rad"
    assert ball_like.amount(1e-9, part="coordinates") == "1e-09 radius"
    assert ball_like.amount(1e-9) == "1e-09 (rad, radius)"
    assert bare.amount(0.25) == "0.25" and bare.amount(None) == "n/a"
    with pytest.raises(ValueError, match="part"):
        ball_like.amount(1.0, part="legs")
    assert catalog.get("car").space.error_unit == "(wheelbase, rad)"
