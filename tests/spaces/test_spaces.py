"""One contract every state space passes (:mod:`nonholo.spaces`): the factors ``SO3``,
``FixedRotation`` and ``Euclidean`` on their own parts, and every ``Product`` (the catalog's
spaces among them) on :class:`~nonholo.spaces.State` values ``(R, q)``.

Independent references: SciPy's ``Rotation`` for logarithms and geodesics, plain NumPy
for the coordinates.
"""
from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from nonholo.model import catalog
from nonholo.spaces import SO3, Euclidean, FixedRotation, Product, State
from nonholo.spaces.axes import wrap

rng = np.random.default_rng(20140901)

FACTORS = {
    "SO3": SO3(),
    "fixed rotation": FixedRotation(),
    "R0": Euclidean(0),
    "R2": Euclidean(2, names=("x", "y")),
    "R4 with angles": Euclidean(4, names=("x", "y", "theta", "phi"), angles=(False, False, True, True)),
}
PRODUCTS = {
    "SO(3)": Product(SO3()),
    "SO(3)xR^2": Product(SO3(), Euclidean(2)),
    "R^4 with angles": Product(FACTORS["R4 with angles"]),
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
    assert space.dim == sum(f.dim for f in space.factors)
    assert len(space.cli_names) == (3 if space.has_orientation else 0) + space.k
    assert space.name in ("SO(3)", f"R^{space.k}", f"SO(3)xR^{space.k}")


def test_error_stacks_its_factors_and_reports_their_norms(space):
    (R, q), (Rd, qd) = states(space, 2)
    e, parts = space.error((R, q), (Rd, qd))
    assert e.shape == (space.dim,)
    expected = []
    if space.has_orientation:
        expected.append(Rotation.from_matrix(R @ Rd.T).as_rotvec())
        assert parts["rotation"] == pytest.approx(np.linalg.norm(expected[0]), rel=1e-12)
    if space.k:
        expected.append(space.coordinates.difference(q, qd))
        assert parts["coordinates"] == pytest.approx(np.linalg.norm(expected[-1]), rel=1e-12)
    assert close(e, np.concatenate(expected), 1e-12)
    assert space.distance((R, q), (Rd, qd)) == pytest.approx(np.linalg.norm(e), rel=1e-12)
    assert close(space.offset((Rd, qd), (R, q)), e, 1e-12)


def test_product_distance_axioms_and_interpolation(space):
    a, b, c = states(space, 3)
    d = space.distance
    assert d(a, a) == pytest.approx(0.0, abs=1e-12)
    assert d(a, b) == pytest.approx(d(b, a), rel=1e-9)
    assert d(a, c) <= d(a, b) + d(b, c) + 1e-12
    path = space.interpolate(a, b, [0.0, 0.5, 1.0])
    assert all(isinstance(x, State) for x in path)
    assert d(path[0], a) < 1e-12 and d(path[-1], b) < 1e-12
    assert d(a, path[1]) == pytest.approx(d(a, b) / 2, rel=1e-9)


def test_product_json_cli_and_public_round_trips(space):
    x = states(space, 1)[0]
    R, q = x
    value = json.loads(json.dumps(space.to_json(x)))
    R2, q2 = space.from_json(value, "goal")
    assert close(R2, R, 0.0) and close(q2, q, 0.0)
    assert space.distance(space.from_cli(space.to_cli(x)), x) < 1e-12
    R4, q4 = space.parse(space.public(x), "goal")
    assert close(R4, R, 0.0) and close(q4, q, 0.0)
    assert space.distance(space.parse(x, "goal"), x) == 0.0


def test_states_are_always_complete(space):
    """No part of a state is ever missing: the identity without an orientation, ``q`` of
    shape ``(0,)`` without coordinates."""
    for x in [space.identity(), *states(space, 2), space.parse(space.public(space.identity()), "x")]:
        assert isinstance(x, State)
        assert x.R.shape == (3, 3) and x.q.shape == (space.k,)
        if not space.has_orientation:
            assert np.array_equal(x.R, np.eye(3))


def test_retract_moves_a_state_by_its_variation(space):
    """``error(x ⊕ s, x) = s`` (the variation a step along ``s`` makes, within the
    injectivity radius), checked against SciPy's rotation vector and plain addition."""
    x = states(space, 1)[0]
    s = rng.uniform(-0.5, 0.5, space.dim)
    moved = space.retract(x, s)
    assert close(space.error(moved, x)[0], s, 1e-12)
    r = space.rotation.dim
    if r:
        assert close(moved.R, Rotation.from_rotvec(s[:3]).as_matrix() @ x.R, 1e-12)
    assert close(moved.q, x.q + s[r:], 1e-15)
    for i in range(space.dim):
        e = space.error(space.perturb(x, i, 1e-3), x)[0]
        assert close(e, 1e-3 * np.eye(space.dim)[i], 1e-15)


def test_products_are_built_from_their_factors_in_order():
    assert Product(SO3(), Euclidean(2)).factors[0] == SO3()
    assert Product(Euclidean(2)).rotation == FixedRotation()
    with pytest.raises(ValueError, match="rotation factor then a coordinate factor"):
        Product(Euclidean(2), SO3())
    with pytest.raises(ValueError, match="needs a rotation factor"):
        Product(Euclidean(0))


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


# -- what callers ask of a space ----------------------------------------------------------

def test_axes_are_the_command_line_numbers(space):
    axes = space.axes()
    assert tuple(a.name for a in axes) == space.cli_names
    assert space.axes("rotation") + space.axes("coordinates") == axes
    for a in axes:
        assert space.axis(a.name) == a
        assert all(space.axis(alias) == a for alias in a.aliases)
        lo, hi = a.bounds
        assert lo < hi and (not a.angle or (lo, hi) in ((-np.pi, np.pi), (-np.pi / 2, np.pi / 2)))
    rpy = space.axes("rotation")
    assert [(a.name, a.aliases, a.unit, a.angle) for a in rpy] in (
        [], [("φ", ("phi",), "rad", True), ("ϑ", ("theta",), "rad", True), ("ψ", ("psi",), "rad", True)])
    c = space.coordinates
    for a, name, unit, angle in zip(space.axes("coordinates"), c.names, c.units, c.angles):
        assert (a.name, a.text, a.unit, a.angle) == (name, name, unit, angle)
        assert a.bounds == ((-np.pi, np.pi) if angle else (-c.box, c.box))
    with pytest.raises(ValueError, match="not one of the state's numbers"):
        space.axis("no such number")


def test_states_of_many_command_line_numbers_agree_with_one_at_a_time(space):
    xs = states(space, 5)
    numbers = np.array([space.to_cli(x) for x in xs])
    R, q = space.from_cli_many(numbers)
    assert R.shape == (5, 3, 3) and q.shape == (5, space.k)
    for x, Ri, qi in zip(xs, R, q):
        assert space.distance((Ri, qi), x) < 1e-12


def test_numbers_of_the_parts_and_their_words(space):
    assert np.array_equal(space.numbers(), np.zeros(len(space.cli_names)))
    rpy, q = (0.5, 1.2, -0.5), 0.25 * np.arange(1, space.k + 1)
    numbers = space.numbers(rotation=rpy, coordinates=q)
    R, q2 = space.from_cli(numbers)
    assert np.array_equal(q2, q)
    if space.axes("rotation"):
        assert close(R, Rotation.from_euler("ZYX", rpy).as_matrix(), 1e-15)
        assert space.describe_numbers(numbers).startswith("RPY(0.5, 1.2, -0.5)")
    else:
        assert np.array_equal(R, np.eye(3))
    if space.k:
        assert space.describe_numbers(numbers).endswith(
            f"({', '.join(space.coordinates.names)}) = {tuple(round(float(v), 3) for v in q)}")


def test_rows_parts_and_what_a_record_keeps(space):
    rot, coords = space.rows("rotation"), space.rows("coordinates")
    assert (rot.start, rot.stop, coords.start, coords.stop) == (0, space.dim - space.k, space.dim - space.k, space.dim)
    assert space.recorded("coordinates", "q", "none") == ("q" if space.k else "none")
    assert space.recorded("rotation", "R") == ("R" if space.axes("rotation") else None)
    with pytest.raises(ValueError, match="part"):
        space.rows("legs")
    x = space.state()
    assert x == space.identity()
    R = SO3().sample(rng, 1)[0]
    assert np.array_equal(space.state(R).R, R) and space.state(R).q.shape == (space.k,)


def test_columns_of_a_table_of_states(space):
    xs = states(space, 6)
    R, q = np.array([x.R for x in xs]), np.array([x.q for x in xs])
    cols = space.columns(R, q)
    assert tuple(cols) == space.column_names()
    assert all(v.shape == (6,) for v in cols.values())
    for i, name in enumerate(space.coordinates.names):
        assert np.array_equal(cols[name], q[:, i])
    if space.axes("rotation"):
        quat = np.stack([cols[c] for c in ("qx", "qy", "qz", "qw")], axis=1)
        assert close(Rotation.from_quat(quat).as_matrix(), R, 1e-12)
        assert np.all(np.sum(quat[1:] * quat[:-1], axis=1) >= 0.0)      # signs kept continuous
    else:
        assert not {"qx", "qy", "qz", "qw"} & set(cols)


def test_the_distance_in_words(space):
    text = space.distance_text(("R[-1]", "q[-1]"), ("Rd", "qd"))
    expected = {"SO(3)": "|log(R[-1] Rdᵀ)|", f"R^{space.k}": "|q[-1] ⊖ qd|",
                f"SO(3)xR^{space.k}": "|(log(R[-1] Rdᵀ), q[-1] ⊖ qd)|"}[space.name]
    assert text == expected


def test_the_singular_set_and_its_null_object_answer_alike():
    """What a result, a table and a title hold of ``Δ``: the set's values, nothing for the
    null object; the messages name a surface on SO(3) and a set of the mechanism beyond."""
    from nonholo.spaces import NoSingularSet, SingularSet

    space = Product(SO3())
    real = SingularSet.on(space, lambda R, q: R[:, 0, 1] * R[:, 2, 0] + R[:, 1, 0] * R[:, 2, 1], owner="p")
    none = NoSingularSet()
    R = SO3().sample(rng, 4)
    d = R[:, 0, 1] * R[:, 2, 0] + R[:, 1, 0] * R[:, 2, 1]
    assert np.array_equal(real.samples(R), d) and none.samples(R) is None
    assert tuple(real.columns(R)) == real.column_names == ("delta",)
    assert none.columns(R) == {} and none.column_names == ()
    assert real.text(R[0], prefix=",  ") == f",  Δ = {d[0]:+.3f}" and none.text(R[0], prefix=",  ") == ""
    assert real.placeholder == "" and none.placeholder == none.summary == "no singular set"
    assert real.summary == "singular set Δ = 0"
    assert (real.blowup, none.blowup) == ("ran into Δ = 0", "overflowed")
    least = np.array([0.5, -0.25])
    assert np.array_equal(real.reported(least), least) and real.reported(0.5) == 0.5
    assert none.reported(least) is None and real.reported(None) is None
    assert real.where == "surface"
    beyond = SingularSet.on(Product(Euclidean(2)), lambda R, q: q[:, 0], owner="car")
    assert beyond.where == "set of 'car'"
