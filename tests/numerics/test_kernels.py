"""The small compiled numerics of :mod:`nonholo.numerics.kernels` and the integrator kernels' entry
points (:func:`nonholo.integrate.compiled.compiled_system`)."""
import numpy as np
import pytest
from conftest import SO3_MECHANISMS, example

from nonholo.controls import stages
from nonholo.controls.parametrisations import Fourier
from nonholo.integrate.compiled import compiled_system
from nonholo.model import catalog
from nonholo.motion.frame_controls import FrameControls
from nonholo.numerics import kernels


def numpy_min_norm(J, l, scale):
    """``S (J S)^# l``, ``S = diag(scale)``, from NumPy's least squares (SVD; minimum norm)."""
    return scale * np.linalg.lstsq(J * scale, l, rcond=None)[0]


def rank_deficient(rng, rank, p=10):
    """A 3 × p matrix of exactly ``rank`` (rows combined from ``rank`` random ones)."""
    A = rng.normal(size=(rank, p))
    return rng.normal(size=(3, rank)) @ A


@pytest.mark.parametrize("rank", [1, 2])
@pytest.mark.parametrize("uniform", [True, False])
def test_rank_deficient_J_falls_back_to_the_pseudo_inverse(rank, uniform):
    """Rank-deficient ``J`` (``l`` outside its range): not a blow-up, but the minimum-norm
    least-squares step in the metric — the eigen fallback ``pinv_step``."""
    rng = np.random.default_rng(10 * rank + uniform)
    J = rank_deficient(rng, rank)
    l = rng.normal(size=3)
    scale = np.ones(10) if uniform else rng.uniform(0.5, 2.0, 10)
    assert np.linalg.matrix_rank(J) == rank
    _, ok = kernels.cholesky_step(J, l, scale)
    assert not ok                                           # Cholesky refuses: a pivot vanished
    x = kernels.min_norm_step(J, l, scale)
    np.testing.assert_array_equal(x, kernels.pinv_step(J, l, scale))
    want = numpy_min_norm(J, l, scale)
    np.testing.assert_allclose(x, want, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(x, scale * (np.linalg.pinv(J * scale, rcond=1e-10) @ l), rtol=1e-9, atol=1e-12)
    # a least-squares solution: the residual is orthogonal to the range of J
    np.testing.assert_allclose((J * scale).T @ (J @ x - l), 0.0, atol=1e-10)
    # of least norm in the metric: nothing in the null space of J S
    _, sv, Vt = np.linalg.svd(J * scale)
    null = Vt[rank:]
    np.testing.assert_allclose(null @ (x / scale), 0.0, atol=1e-12)


@pytest.mark.parametrize("uniform", [True, False])
def test_full_rank_J_is_solved_by_cholesky(uniform):
    rng = np.random.default_rng(3 + uniform)
    J = rng.normal(size=(3, 10))
    l = rng.normal(size=3)
    scale = np.ones(10) if uniform else rng.uniform(0.5, 2.0, 10)
    x_chol, ok = kernels.cholesky_step(J, l, scale)
    assert ok
    x = kernels.min_norm_step(J, l, scale)
    np.testing.assert_array_equal(x, x_chol)
    S = np.diag(scale)
    np.testing.assert_allclose(x, S @ np.linalg.pinv(J @ S) @ l, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(x, numpy_min_norm(J, l, scale), rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(J @ x, l, rtol=1e-12, atol=1e-14)       # full rank: exact solution
    # the fallback gives the same step where both apply
    np.testing.assert_allclose(kernels.pinv_step(J, l, scale), x, rtol=1e-9, atol=1e-12)


def test_zero_J_gives_the_zero_step():
    l = np.array([0.3, -0.1, 0.2])
    np.testing.assert_array_equal(kernels.min_norm_step(np.zeros((3, 4)), l, np.ones(4)), np.zeros(4))


def test_scaled_gram_and_back():
    rng = np.random.default_rng(8)
    J, s, y = rng.normal(size=(3, 7)), rng.uniform(0.5, 2.0, 7), rng.normal(size=3)
    S2 = np.diag(s * s)
    np.testing.assert_allclose(kernels.scaled_gram(J, s), J @ S2 @ J.T, rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(kernels.scaled_back(J, y, s), S2 @ J.T @ y, rtol=1e-13, atol=1e-14)


def test_inv33_and_exp_times():
    from nonholo.spaces import so3

    rng = np.random.default_rng(9)
    Z = rng.normal(size=(3, 3))
    out = np.empty((3, 3))
    kernels.inv33(Z, out)
    np.testing.assert_allclose(out, np.linalg.inv(Z), rtol=1e-12, atol=1e-12)
    w, R = rng.normal(size=3), so3.exp(rng.normal(size=3))
    E = np.empty((3, 3))
    kernels.exp_times(*w, R, E, out)
    np.testing.assert_allclose(out, so3.exp(w) @ R, atol=1e-14)
    kernels.rodrigues(*(1e-6 * w), E)               # small angle: the Taylor branch
    np.testing.assert_allclose(E, so3.exp(1e-6 * w), atol=1e-15)


# -- the integrator kernels of a mechanism ------------------------------------------------------

@pytest.mark.parametrize("name", SO3_MECHANISMS)
def test_kernels_of_a_mechanism(name):
    mech = catalog.get(name)
    plain = compiled_system(mech)
    assert (plain.name, plain.frame) == (name, False)
    if mech.has_frame:
        frame = compiled_system(mech, frame=True)
        assert (frame.name, frame.frame) == (name, True)
    else:
        with pytest.raises(ValueError, match="frame"):
            compiled_system(mech, frame=True)


def test_frame_inputs_kernel_is_W_times_w():
    """``frame_inputs(nodes, qnodes, idx, s, Wst, w_end, Rout, Qout, out)`` (no ``h``): at ``s = 0`` the
    node itself and ``u = W(R_n) w``; at ``s > 0`` one CF4 step from the node — the next
    node when ``s`` is a whole step with the step's stage inputs."""
    mech = catalog.get("platform")
    R0 = example(1)[0]
    w = Fourier(1.0, [[0.2, 0.5, 0.1, 0.0, 0.1], [0.1, 0.0, 0.4, 0.2, 0.0]])
    nodes = FrameControls(w, R0, mech, 400).nodes
    Ust = stages.stage_table(w, 400)
    idx = np.array([0, 17, 399, 250], dtype=np.int64)
    s = np.array([0.0, 0.0, 1.0 / 400, 1.0 / 400])
    Wst = np.ascontiguousarray(Ust[idx])
    w_end = np.ascontiguousarray(Ust[idx, 2])
    Rout, out = np.empty((4, 3, 3)), np.empty((4, 2))
    compiled_system(mech, frame=True).frame_inputs(nodes, np.empty((len(nodes), 0)), idx, s, Wst, w_end, Rout,
                                          np.empty((4, 0)), out)
    np.testing.assert_array_equal(Rout[:2], nodes[idx[:2]])
    np.testing.assert_allclose(Rout[2:], nodes[idx[2:] + 1], atol=1e-15)
    for k in range(4):
        np.testing.assert_allclose(out[k], mech.frame.W(Rout[k]) @ w_end[k], rtol=0, atol=1e-15)
