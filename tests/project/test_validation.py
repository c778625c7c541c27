"""Public arguments are checked up front: a ValueError naming the argument, never an
OverflowError, a bare TypeError, a huge allocation or an out-of-bounds read."""
import numpy as np
import pytest
from conftest import example
from scipy.spatial.transform import Rotation

from nonholo import plan, simulate, Settings
from nonholo.controls.parametrisations import Fourier
from nonholo.model import platform
from nonholo.planning.settings import arguments_of

R0, RD = example(1)

BAD_OPTIONS = [
    ("harmonics", float("inf")), ("harmonics", None), ("harmonics", 2.5), ("harmonics", True),
    ("harmonics", 5000),
    ("grid", float("inf")), ("grid", None), ("grid", 0),
    ("steps", float("inf")), ("steps", 10**9), ("steps", -3),
    ("max_iter", float("inf")), ("max_iter", None), ("max_iter", -1), ("max_iter", "10"),
    ("T", 10**400), ("T", float("nan")), ("T", "1 s"), ("T", -1.0),
    ("tol", float("nan")), ("gamma", True), ("delta_min", float("inf")),
    ("mechanism", ["platform"]), ("strategy", ["robust"]), ("method", "spectral"),
]


@pytest.mark.parametrize("name,value", BAD_OPTIONS, ids=[f"{n}={v!r}" for n, v in BAD_OPTIONS])
def test_bad_options_name_the_argument(name, value):
    kwargs = {name: value}
    if name == "grid":
        kwargs["method"] = "nonparametric"
    with pytest.raises(ValueError, match=name):
        plan(R0, RD, **arguments_of(kwargs, "platform"))


def test_a_large_grid_is_refused_before_allocating():
    with pytest.raises(ValueError, match="grid must be at most"):
        plan(R0, RD, settings=Settings(method="nonparametric", grid=10**7))
    with pytest.raises(ValueError, match="steps must be at most"):
        plan(R0, RD, settings=Settings(method="nonparametric", grid=10**5, steps=10**6))


def test_a_basis_too_large_for_memory_is_refused_at_once():
    """harmonics × steps whose Fourier basis would take GiB: refused, naming both, before
    anything is allocated (the limit is the planner's, not the machine's)."""
    with pytest.raises(ValueError, match=r"harmonics = 10000 on steps = 20000.*GiB"):
        plan(R0, RD, settings=Settings(harmonics=10000, steps=20000))


@pytest.mark.parametrize("kwargs, match", [
    ({"T": "1"}, "T must be"), ({"T": True}, "T must be"), ({"callback": 5}, "callback must be callable"),
    ({"Rd": RD + 0j}, "goal must be real"), ({"R0": R0.astype(bool)}, "start must be real"),
])
def test_strings_booleans_complex_and_uncallables_are_refused(kwargs, match):
    args = {"R0": R0, "Rd": RD, **kwargs}
    with pytest.raises((ValueError, TypeError), match=match):
        plan(args.pop("R0"), args.pop("Rd"), **args)


def test_numpy_scalars_are_numbers():
    res = plan(R0, RD, T=np.float64(1.0),
               settings=Settings(harmonics=np.int64(2), tol=np.float32(1e-6), max_iter=np.int32(3)))
    assert res.options["tol"] == pytest.approx(1e-6) and isinstance(res.options["tol"], float)


def test_far_goals_beyond_so3_fail_with_a_reason():
    """Goals so far that the straight path would take more hops than the route may plan:
    a failed result saying so, not an OverflowError or MemoryError."""
    car = plan([0, 0, 0, 0], [1e15, 0, 0, 0], mechanism="car")
    ball = plan((np.eye(3), [0, 0]), (np.eye(3), [1e15, 0]), mechanism="rolling_ball")
    for res in (car, ball):
        assert not res.success and "hops" in res.reason, res.reason


def test_the_mechanism_functions_check_their_argument():
    from nonholo.model import catalog

    mech = catalog.get("platform")
    with pytest.raises(ValueError, match="R must be a 3×3"):
        mech.L(np.eye(2))
    with pytest.raises(ValueError, match="non-finite"):
        mech.L(np.full((3, 3), np.nan))
    with pytest.raises(ValueError, match="shape"):
        mech.leg_lengths(np.eye(4))


def test_simulate_bounds_its_steps():
    with pytest.raises(ValueError, match="steps"):
        simulate(R0, Fourier(1.0, np.zeros((2, 5))), 1.0, steps=10**8)


@pytest.mark.parametrize("t", [np.nan, np.inf, [0.1, np.nan], [-np.inf]])
def test_controls_reject_non_finite_times(t):
    res = plan(R0, RD)
    with pytest.raises(ValueError, match="t must be finite"):
        res.controls(t)
    with pytest.raises(ValueError, match="t must be finite"):
        res.parametrisation.frame(t)


def test_platform_kinematics_never_return_non_finite_numbers():
    """A valid rotation with |Δ| = 1e-170: Q ~ 1/Δ² overflows; ValueError, not inf/NaN."""
    R = Rotation.from_rotvec([1e-170, 0.0, 0.0]).as_matrix() @ np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])
    assert 0 < abs(platform.delta(R)) < 1e-160
    L = platform.L(R)                   # 1/Δ is still representable: finite
    assert np.all(np.isfinite(L))
    with pytest.raises(ValueError, match="too close to the singular surface"):
        platform.Q(R, [1.0, 0.5])


def test_a_huge_integer_count_is_refused_by_name():
    with pytest.raises(ValueError, match="steps must be at most"):
        plan(R0, RD, settings=Settings(steps=10**400))
