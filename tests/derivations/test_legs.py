"""Leg lengths from the derivation (``leg_lengths``, ``leg_gradients`` in the generated
modules) against independent computations: the numeric geometry, finite differences and
the definition of the scaled inputs."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from nonholo.generated import MECHANISMS
from nonholo.model import catalog
from nonholo.spaces import so3

PLATFORMS = [n for n in MECHANISMS if catalog.get(n).has_legs]


def random_rotations(n, seed=0):
    return Rotation.random(n, random_state=seed).as_matrix()


def test_which_mechanisms_have_legs():
    assert {"platform", "platform_raised"} <= set(PLATFORMS)
    att = catalog.get("attitude")
    assert not att.has_legs
    with pytest.raises(ValueError, match="no legs"):
        att.leg_lengths(np.eye(3))


@pytest.mark.parametrize("name", PLATFORMS)
def test_leg_lengths_are_the_geometry_s_distances(name):
    mech = catalog.get(name)
    R = random_rotations(50, seed=1)
    got = mech.leg_lengths(R)
    assert got.shape == (50, 2)
    np.testing.assert_allclose(got, mech.geometry.leg_lengths(R), rtol=1e-13, atol=0)
    np.testing.assert_array_equal(mech.leg_lengths(R[7]), got[7])


@pytest.mark.parametrize("name", PLATFORMS)
def test_leg_gradients_against_central_differences(name):
    mech = catalog.get(name)
    rng = np.random.default_rng(2)
    eps = 1e-6
    for R in random_rotations(10, seed=3):
        G = mech.leg_gradients(R)
        assert G.shape == (2, 3)
        s = rng.standard_normal(3)
        fd = (mech.leg_lengths(so3.exp(eps * s) @ R) - mech.leg_lengths(so3.exp(-eps * s) @ R)) / (2 * eps)
        np.testing.assert_allclose(G @ s, fd, rtol=0, atol=1e-8)
    Rs = random_rotations(5, seed=4)
    np.testing.assert_array_equal(mech.leg_gradients(Rs)[2], mech.leg_gradients(Rs[2]))


@pytest.mark.parametrize("name", PLATFORMS)
def test_leg_speeds_follow_from_the_scaled_inputs(name):
    """``u_i = d(l_i²)/dt / (4 |A_i| |B_i|)``, so ``dl_i/dt = 2 |A_i| |B_i| u_i / l_i``."""
    mech = catalog.get(name)
    g = mech.geometry
    scale = np.array([2 * np.linalg.norm(A) * np.linalg.norm(B) for A, B in zip(g.bases, g.tips)])
    rng = np.random.default_rng(5)
    R = np.array([Ri for Ri in random_rotations(40, seed=6) if abs(mech.delta(Ri)) > 0.05])
    u = rng.standard_normal((len(R), 2))
    got = mech.leg_speeds(R, u)
    np.testing.assert_allclose(got, scale * u / mech.leg_lengths(R), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(mech.leg_speeds(R[0], u[0]), got[0], rtol=1e-14)
