"""Public arguments are checked up front: a ValueError naming the argument, never an
OverflowError, a bare TypeError, a huge allocation or an out-of-bounds read."""
import numpy as np
import pytest
from conftest import example
from scipy.spatial.transform import Rotation

from nonholo import plan, simulate
from nonholo.controls.parametrisations import Fourier
from nonholo.model import platform

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
        plan(R0, RD, **kwargs)


def test_a_large_grid_is_refused_before_allocating():
    with pytest.raises(ValueError, match="steps"):
        plan(R0, RD, method="nonparametric", grid=10**7)


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
        plan(R0, RD, steps=10**400)
