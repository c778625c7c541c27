"""CF4 simulation on SO(3) and the variational system (9): accuracy, order, sensitivities."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import example, platform_delta

from nonholo import mechanism_named
from nonholo.certify.resimulate import mobility_lyapunov, resimulate
from nonholo.controls import parametrisations as C
from nonholo.controls import stages
from nonholo.integrate.compiled import compiled_system
from nonholo.model import catalog
from nonholo.motion import simulation as S
from nonholo.motion.frame_controls import FrameControls
from nonholo.numerics import kernels
from nonholo.planning.endpoint_map import EndpointMap
from nonholo.spaces import so3
from nonholo.spaces import State


def initial(T=1.0):
    return C.Fourier.fit(C.paper_initial(T), T, 2)


def bumpy(seed=4, T=1.0, scale=0.15):
    """A Fourier control with all coefficients non-zero (moves away from Δ = 0 on the examples)."""
    rng = np.random.default_rng(seed)
    return C.Fourier(T, initial(T).coeffs + scale * rng.normal(size=(2, 5)))


def endpoint_variation(R_plus, R_minus, eps):
    """Central difference of the spatial variation: ``s ≈ vee(log(R₊ R₋ᵀ)) / 2ε``."""
    return so3.log(R_plus @ R_minus.T) / (2 * eps)


def rel(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


@pytest.mark.parametrize("k", [1, 2])
@pytest.mark.parametrize("make", [initial, bumpy, lambda: C.PiecewiseConstant.fit(initial(), 1.0, 100)])
def test_stays_on_so3_and_matches_dop853_with_default_steps(k, make):
    R0, _ = example(k)
    u = make()
    tr = S.simulate(R0, u, 1.0)
    assert tr.R.shape == (S.DEFAULT_STEPS + 1, 3, 3) and tr.u.shape == (S.DEFAULT_STEPS + 1, 2)
    orth = np.abs(np.einsum("nji,njk->nik", tr.R, tr.R) - np.eye(3)).max()
    assert orth <= 1e-12
    assert np.all(np.linalg.det(tr.R) > 0)
    # the default step count: discretisation error ≤ 1e-9 (DOP853, rtol = atol = 1e-13)
    assert so3.distance(tr.R_T, resimulate(R0, u, 1.0)) <= 1e-9
    np.testing.assert_allclose(tr.delta, [platform_delta(R) for R in tr.R], atol=1e-15)
    assert tr.min_delta <= np.abs(tr.delta).min() + 1e-15


def test_orthonormal_under_large_rotations():
    """Many revolutions with the attitude mechanism: still orthonormal to round-off."""
    u = C.Fourier(1.0, [[20.0, 5.0, 0, 0, 3.0], [-15.0, 0, 7.0, 2.0, 0]])
    tr = S.simulate(so3.from_rpy(0.3, -0.2, 2.0), u, 1.0, mechanism="attitude", steps=2000)
    assert np.abs(np.einsum("nji,njk->nik", tr.R, tr.R) - np.eye(3)).max() <= 1e-12


@pytest.mark.parametrize("mechanism", ["platform", "attitude"])
def test_cf4_converges_at_order_four(mechanism):
    R0, _ = example(1)
    u = bumpy()
    ref = S.simulate(R0, u, 1.0, mechanism=mechanism, steps=6400).R_T
    err = [so3.distance(S.simulate(R0, u, 1.0, mechanism=mechanism, steps=n).R_T, ref)
           for n in (25, 50, 100)]
    ratios = [err[0] / err[1], err[1] / err[2]]
    assert all(12.0 < r < 20.0 for r in ratios), (err, ratios)


def test_callable_controls_equal_controls_object():
    R0, _ = example(2)
    u = bumpy()
    a = S.simulate(R0, u, 1.0, steps=100)
    b = S.simulate(R0, lambda t: u(t), 1.0, steps=100)
    np.testing.assert_allclose(a.R, b.R, atol=1e-14)


@pytest.mark.parametrize("mechanism", ["platform", "attitude"])
@pytest.mark.parametrize("k", [1, 2])
def test_parametric_jacobian_matches_finite_differences(k, mechanism):
    R0, _ = example(k)
    u = bumpy(seed=k)
    var = S.variational(R0, u, 1.0, mechanism=mechanism)
    assert var.J.shape == (3, 10)
    eps = 1e-5
    fd = np.empty_like(var.J)
    for j in range(u.params.size):
        e = np.zeros(u.params.size)
        e[j] = eps
        Rp = S.simulate(R0, u.with_params(u.params + e), 1.0, mechanism=mechanism).R_T
        Rm = S.simulate(R0, u.with_params(u.params - e), 1.0, mechanism=mechanism).R_T
        fd[:, j] = endpoint_variation(Rp, Rm, eps)
    assert rel(var.J, fd) <= 1e-6


@pytest.mark.parametrize("k", [1, 2])
def test_nonparametric_G_j_match_finite_differences(k):
    """Columns (j, i) of J for grid controls are G_j = ∫_{I_j} Φ(T,t) B(t) dt (eq. (11))."""
    R0, _ = example(k)
    u = C.PiecewiseConstant.fit(lambda t: bumpy(seed=k)(t), 1.0, 20)
    var = S.variational(R0, u, 1.0, steps=400)
    eps = 1e-5
    for col in (0, 13, 27, 39):
        e = np.zeros(u.params.size)
        e[col] = eps
        Rp = S.simulate(R0, u.with_params(u.params + e), 1.0, steps=400).R_T
        Rm = S.simulate(R0, u.with_params(u.params - e), 1.0, steps=400).R_T
        assert rel(var.J[:, col], endpoint_variation(Rp, Rm, eps)) <= 1e-6


@pytest.mark.parametrize("k", [1, 2])
def test_transition_matrix_matches_finite_differences(k):
    """Φ(T, t): perturb the state at t and compare the endpoints."""
    R0, _ = example(k)
    u = bumpy(seed=k)
    var = S.variational(R0, u, 1.0, steps=400)
    Phi = var.Phi
    np.testing.assert_allclose(Phi[-1], np.eye(3), atol=1e-14)
    eps = 1e-6
    for n in (0, 200):
        t0 = var.trajectory.t[n]
        Rt = var.trajectory.R[n]
        tail = lambda t, t0=t0: u(t + t0)                      # noqa: E731
        fd = np.empty((3, 3))
        for j in range(3):
            e = np.zeros(3)
            e[j] = eps
            Rp = S.simulate(so3.exp(e) @ Rt, tail, 1.0 - t0, steps=400 - n).R_T
            Rm = S.simulate(so3.exp(-e) @ Rt, tail, 1.0 - t0, steps=400 - n).R_T
            fd[:, j] = endpoint_variation(Rp, Rm, eps)
        assert rel(Phi[n], fd) <= 1e-6


@pytest.mark.parametrize("make", [bumpy, lambda: C.PiecewiseConstant.fit(bumpy(), 1.0, 10)])
def test_mobility_quadrature_matches_lyapunov_equation(make):
    R0, _ = example(1)
    u = make()
    var = S.variational(R0, u, 1.0)
    M_lyap = mobility_lyapunov(R0, u, 1.0)
    assert rel(var.M, M_lyap) <= 1e-8
    assert np.all(np.linalg.eigvalsh(var.M) > 0)          # rank 3: the system is controllable
    # M(T) = Σ_j G_j G_jᵀ / h_j for grid controls when every grid interval is one step
    if isinstance(u, C.PiecewiseConstant):
        fine = C.PiecewiseConstant.fit(lambda t: u(t), 1.0, 400)
        J = S.variational(R0, fine, 1.0, steps=400).J
        Md = sum(np.outer(J[:, c], J[:, c]) for c in range(J.shape[1])) / (1.0 / 400)
        assert rel(Md, M_lyap) <= 1e-2


def test_log_rotation_matches_so3_log():
    rng = np.random.default_rng(5)
    for a in [0.0, 1e-12, 1e-7, 1e-3, 0.5, 2.0, 2.9, np.pi - 1e-6, np.pi - 1e-9]:
        for _ in range(20):
            ax = rng.normal(size=3)
            R = so3.exp(a * ax / np.linalg.norm(ax))
            l = kernels.log_rotation(R)
            assert np.linalg.norm(l) <= np.pi + 1e-12
            assert np.abs(so3.exp(l) - R).max() <= 2e-15
            if a < 3.0:
                np.testing.assert_allclose(l, so3.log(R), atol=1e-15, rtol=1e-12)


def test_singular_trajectory_stops_cleanly():
    R0, _ = example(1)
    u = C.Fourier(1.0, [[1.0, 0, 0, 0, 0], [0.0, 0, 0, 0, 0]])     # u = (1, 0) runs into Δ = 0
    with pytest.raises(S.SingularTrajectoryError, match="singular surface") as info:
        S.simulate(R0, u, 1.0)
    tr = info.value.trajectory
    assert 0 < len(tr.t) < S.DEFAULT_STEPS + 1
    assert np.all(np.isfinite(tr.R)) and np.all(np.isfinite(tr.delta))
    with pytest.raises(S.SingularTrajectoryError):
        S.variational(R0, u, 1.0)


@pytest.mark.parametrize("R0, controls, T, kw", [
    (np.eye(3), initial(), 1.0, {}),                                   # Δ(I) = 0
    (np.eye(2), initial(), 1.0, {"mechanism": "attitude"}),
    (np.full((3, 3), np.nan), initial(), 1.0, {}),
    (np.diag([1.0, 1.0, -1.0]), initial(), 1.0, {"mechanism": "attitude"}),
    (example(1)[0], initial(), 2.0, {}),                               # controls defined on [0, 1]
    (example(1)[0], initial(), 0.0, {}),
    (example(1)[0], initial(), 1.0, {"steps": 0}),
    (example(1)[0], lambda t: np.zeros((len(t), 3)), 1.0, {}),         # wrong number of inputs
    (example(1)[0], lambda t: np.full((len(t), 2), np.nan), 1.0, {}),
    (example(1)[0], "sin", 1.0, {}),
    (example(1)[0], initial(), 1.0, {"mechanism": "tripod"}),
])
def test_bad_input_raises_value_error(R0, controls, T, kw):
    with pytest.raises(ValueError):
        S.simulate(R0, controls, T, **kw)


# -- planner kernels: dense Jacobian, frame coordinates, minimum-norm solve ------------------

def test_dense_basis_gives_the_sparse_jacobian():
    R0, _ = example(1)
    u = bumpy(seed=1)
    kern = compiled_system(catalog.get("platform"))
    U = stages.stage_table(u, 400)
    out = []
    for basis in (stages.sparse_basis(u, 400), stages.kernel_basis(u, 400)):
        J = np.empty((3, 10))
        Wd = np.empty((1200, 6))
        n, _, _ = kern.forward_variational(R0, np.zeros(0), U, 1 / 400, 1.0, 1e-9, *basis, *kern.nodes(400),
                                           np.empty((401, 3, 3)), J, np.empty((3, 3)), Wd, False)
        assert n == 400
        out.append(J)
    assert stages.kernel_basis(u, 400)[0].shape[0] == 0    # the dense form
    np.testing.assert_allclose(out[1], out[0], rtol=1e-13, atol=1e-15)


@pytest.mark.parametrize("mechanism", ["platform", "attitude"])
def test_frame_jacobian_matches_finite_differences(mechanism):
    """In frame coordinates (kernels bound to N, QN) J = ∂s_T/∂λ of the w-parameters."""
    R0, _ = example(2)
    w = bumpy(seed=5)
    start = State(R0, np.zeros(0))
    prob = EndpointMap(start, start, 1.0, catalog.get(mechanism), "parametric", 400, 1e-2, frame=True)
    ev = prob.evaluate(w)
    eps = 1e-6
    fd = np.empty_like(ev.J)
    for j in range(10):
        e = np.zeros(10)
        e[j] = eps
        Rp = FrameControls(w.with_params(w.params + e), R0, mechanism_named(mechanism), 400).nodes[-1]
        Rm = FrameControls(w.with_params(w.params - e), R0, mechanism_named(mechanism), 400).nodes[-1]
        fd[:, j] = endpoint_variation(Rp, Rm, eps)
    assert rel(ev.J, fd) <= 1e-7
    np.testing.assert_allclose(ev.R[-1], FrameControls(w, R0, mechanism_named(mechanism), 400).nodes[-1], atol=1e-14)


def test_min_norm_step_cholesky_and_fallback():
    rng = np.random.default_rng(0)
    J = rng.normal(size=(3, 10))
    l = rng.normal(size=3)
    s = rng.uniform(0.5, 2.0, 10)
    x = kernels.min_norm_step(J, l, s)
    S = np.diag(s)
    np.testing.assert_allclose(x, S @ np.linalg.pinv(J @ S) @ l, rtol=1e-12, atol=1e-14)
    # rank 2: the minimum-norm least-squares step (eigen fallback), not a blow-up
    J2 = J.copy()
    J2[2] = J2[0] + 2 * J2[1]
    x2 = kernels.min_norm_step(J2, l, np.ones(10))
    np.testing.assert_allclose(x2, np.linalg.pinv(J2) @ l, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(kernels.min_norm_step(np.zeros((3, 4)), l, np.ones(4)), np.zeros(4))


def test_log_error():
    rng = np.random.default_rng(3)
    for _ in range(20):
        A, B = so3.exp(rng.normal(size=3)), so3.exp(rng.normal(size=3))
        l, e = kernels.log_error(A, B)
        np.testing.assert_allclose(l, so3.log(A @ B.T), atol=1e-12)
        assert e == pytest.approx(np.linalg.norm(so3.log(A @ B.T)), abs=1e-12)


def test_physical_simulation_of_frame_controls():
    """simulate/variational accept FrameControls: the physical system re-traces the frame motion."""
    R0, _ = example(1)
    u = FrameControls(bumpy(seed=2), R0, mechanism_named("platform"), 400)
    tr = S.simulate(R0, u, 1.0, steps=800)
    assert so3.distance(tr.R_T, u.nodes[-1]) <= 1e-9
    var = S.variational(R0, u, 1.0)
    assert var.J is None and so3.distance(var.trajectory.R_T, u.nodes[-1]) <= 1e-9
