"""Control parametrisations: evaluation, stage tables, sparse basis, metric, (de)serialisation."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import example

from nonholo import mechanism_named
from nonholo.controls import parametrisations as C
from nonholo.controls import stages
from nonholo.controls.stages import stage_values
from nonholo.model import catalog
from nonholo.motion import frame_controls as replay
from nonholo.motion.frame_controls import FrameControls

T = 1.7


def fourier(seed=0, K=2, m=2):
    return C.Fourier(T, np.random.default_rng(seed).normal(size=(m, 2 * K + 1)))


def grid_controls(seed=0, grid=10, m=2):
    return C.PiecewiseConstant(T, np.random.default_rng(seed).normal(size=(grid, m)))


def test_fourier_formula_vectorised():
    u = fourier(K=3)
    t = np.linspace(0.0, T, 7)
    w = 2 * np.pi / T
    lam = u.coeffs
    expected = np.stack([lam[i, 0] + sum(lam[i, 2 * k - 1] * np.sin(k * w * t) + lam[i, 2 * k] * np.cos(k * w * t)
                                          for k in range(1, 4)) for i in range(2)], axis=1)
    assert u(t).shape == (7, 2)
    np.testing.assert_allclose(u(t), expected, rtol=0, atol=1e-14)
    assert u(0.3).shape == (2,)
    np.testing.assert_allclose(u(0.3), u(np.array([0.3]))[0])
    assert u.params.size == 2 * (2 * 3 + 1)


def test_paper_initial_is_exact_in_fourier_basis():
    u = C.Fourier.fit(C.paper_initial(T), T, 2)
    expected = np.zeros((2, 5))
    expected[0, 1] = 0.3      # u1 = 0.3 sin ωt
    expected[1, 2] = 0.3      # u2 = 0.3 cos ωt
    np.testing.assert_allclose(u.coeffs, expected, atol=1e-15)
    t = np.linspace(0, T, 11)
    np.testing.assert_allclose(u(t), C.paper_initial(T)(t), atol=1e-15)


def test_piecewise_evaluation_right_continuous():
    u = grid_controls(grid=4)
    bp = u.breakpoints
    np.testing.assert_array_equal(bp, np.linspace(0, T, 5))
    np.testing.assert_array_equal(u(bp[:-1]), u.values)            # t_j belongs to interval j
    np.testing.assert_array_equal(u(bp[1:-1] - 1e-12), u.values[:-1])
    np.testing.assert_array_equal(u(np.array([T])), u.values[-1:])  # u(T) = last value
    assert u(0.1).shape == (2,)


def test_piecewise_fit_is_the_interval_mean():
    u = C.PiecewiseConstant.fit(lambda t: np.stack([t, t ** 2], axis=-1), T, 5)
    a, b = u.breakpoints[:-1], u.breakpoints[1:]
    np.testing.assert_allclose(u.values[:, 0], (a + b) / 2, rtol=1e-14)
    np.testing.assert_allclose(u.values[:, 1], (b ** 3 - a ** 3) / (3 * (b - a)), rtol=1e-13)


@pytest.mark.parametrize("make", [fourier, grid_controls])
def test_stage_table_matches_evaluation_and_sparse_basis(make):
    u = make()
    steps = 40
    h = T / steps
    U = stages.stage_table(u, steps)
    assert U.shape == (steps, 3, 2)
    t = (np.arange(steps)[:, None] + np.array([0, 0.5, 1.0])) * h
    np.testing.assert_array_equal(stages.STAGE_FRACTIONS, [0.0, 0.5, 1.0])
    np.testing.assert_allclose(stages.stage_times(T, steps), t, rtol=1e-15, atol=0)
    if isinstance(u, C.Fourier):
        np.testing.assert_allclose(U, u(t.ravel()).reshape(steps, 3, 2), atol=1e-13)
    else:
        # constant on each step, the value of the interval holding the step
        np.testing.assert_array_equal(U, np.broadcast_to(u(np.arange(steps) * h)[:, None, :], U.shape))
    # the sparse basis is the same linear map λ -> U (the one the kernels differentiate)
    Bidx, Bval, sb, si = stages.sparse_basis(u, steps)
    np.testing.assert_allclose(stage_values(u.params, Bidx, Bval, sb, si, 2), U, atol=1e-13)
    # ... and linear: U(λ + μ) = U(λ) + U(μ)
    v = u.with_params(np.ones_like(u.params))
    w = u.with_params(u.params + v.params)
    np.testing.assert_allclose(stages.stage_table(w, steps), U + stages.stage_table(v, steps), atol=1e-12)


@pytest.mark.parametrize("make", [fourier, grid_controls])
def test_metric_is_the_l2_gram_diagonal(make):
    u = make()
    x, w = np.polynomial.legendre.leggauss(40)
    # composite Gauss on the grid (exact for the piecewise-constant, accurate for Fourier)
    edges = np.linspace(0, T, 41)
    t = (0.5 * (edges[:-1] + edges[1:])[:, None] + 0.5 * np.diff(edges)[:, None] * x).ravel()
    wt = (0.5 * np.diff(edges)[:, None] * w).ravel()
    integral = np.sum(wt * np.sum(u(t) ** 2, axis=1))
    assert integral == pytest.approx(np.sum(u.metric() * u.params ** 2), rel=1e-12)


@pytest.mark.parametrize("make", [fourier, grid_controls])
def test_dict_round_trip(make):
    u = make()
    v = C.from_dict(u.to_dict())
    assert v == u and type(v) is type(u)
    t = np.linspace(0, T, 13)
    np.testing.assert_array_equal(v(t), u(t))
    w = replay.from_dict(u.to_dict())       # loads either kind
    assert w == u and type(w) is type(u)


def test_with_params_does_not_alias():
    u = fourier()
    p = u.params
    p[0] = 99.0
    assert u.params[0] != 99.0
    v = u.with_params(p)
    assert v.params[0] == 99.0 and u.params[0] != 99.0
    with pytest.raises(ValueError):
        u.with_params(np.full(u.params.size, np.nan))
    with pytest.raises(ValueError):
        u.with_params(np.ones(3))


@pytest.mark.parametrize("bad", [
    lambda: C.Fourier(0.0, np.zeros((2, 5))),
    lambda: C.Fourier(-1.0, np.zeros((2, 5))),
    lambda: C.Fourier(np.nan, np.zeros((2, 5))),
    lambda: C.Fourier(1.0, np.zeros((2, 4))),
    lambda: C.Fourier(1.0, np.zeros((2, 1))),
    lambda: C.Fourier(1.0, [[np.nan, 0, 0]]),
    lambda: C.Fourier.fit(C.paper_initial(1.0), 1.0, 0),
    lambda: C.PiecewiseConstant(1.0, np.zeros((0, 2))),
    lambda: C.PiecewiseConstant.fit(C.paper_initial(1.0), 1.0, 0),
    lambda: stages.stage_table(C.PiecewiseConstant(1.0, np.zeros((10, 2))), 25),
    lambda: C.from_dict({"kind": "spline"}),
])
def test_bad_parameters_raise(bad):
    with pytest.raises(ValueError):
        bad()


# -- the planner's fast stage table ------------------------------------------------------------

@pytest.mark.parametrize("make", [fourier, grid_controls])
def test_stage_function_equals_stage_table(make):
    u = make()
    steps = 40
    fill = stages.stage_function(u, steps)
    out = np.empty((steps, 3, 2))
    p = np.random.default_rng(9).normal(size=u.params.size)
    assert fill(p, out) is out
    np.testing.assert_allclose(out, stages.stage_table(u.with_params(p), steps), rtol=0, atol=1e-14)


# -- physical inputs of a motion planned in the frame coordinates ----------------------------

def frame_controls(kind="fourier", R0=None):
    R0 = example(1)[0] if R0 is None else R0
    w = (C.Fourier(1.0, [[0.2, 0.5, 0.1, 0.0, 0.1], [0.1, 0.0, 0.4, 0.2, 0.0]]) if kind == "fourier"
         else C.PiecewiseConstant(1.0, np.random.default_rng(2).normal(scale=0.4, size=(8, 2))))
    return FrameControls(w, R0, mechanism_named("platform"), 400)


@pytest.mark.parametrize("kind", ["fourier", "grid"])
def test_frame_controls_are_the_physical_inputs(kind):
    mech = catalog.get("platform")
    u = frame_controls(kind)
    t = np.random.default_rng(1).uniform(0.0, 1.0, 50)
    R, uu = u.states(t), u(t)
    assert uu.shape == (50, 2) and u(0.3).shape == (2,)
    np.testing.assert_array_equal(u(0.3), u(np.array([0.3]))[0])
    w = u.frame_inputs(t)
    for k in range(50):
        np.testing.assert_allclose(mech.L(R[k]) @ uu[k], mech.frame.N(R[k]) @ w[k], atol=1e-12)
        np.testing.assert_allclose(uu[k], mech.frame.W(R[k]) @ w[k], atol=1e-15)
    # at the nodes R(t) is the node itself; u is continuous across them (Fourier)
    h = 1.0 / 400
    np.testing.assert_array_equal(u.states(np.array([0.0, 37 * h, 1.0])), u.nodes[[0, 37, 400]])
    if kind == "fourier":
        np.testing.assert_allclose(u(np.array([37 * h - 1e-9])), u(np.array([37 * h])), atol=1e-8)


@pytest.mark.parametrize("kind", ["fourier", "grid"])
def test_frame_controls_round_trip_and_stage_table(kind):
    u = frame_controls(kind)
    v = replay.from_dict(u.to_dict(), mechanism_named("platform"))
    assert v == u and type(v) is FrameControls
    # the replay holds the Mechanism; its description names it
    assert v.mechanism is catalog.get("platform") and u.to_dict()["mechanism"] == "platform"
    with pytest.raises(ValueError, match="frame"):      # controls.from_dict: parametrisations only
        C.from_dict(u.to_dict())
    t = np.linspace(0.0, 1.0, 101)
    np.testing.assert_array_equal(v(t), u(t))
    # breakpoints: the frame's jumps and the nodes (where du/dt jumps)
    np.testing.assert_array_equal(u.breakpoints, np.linspace(0.0, 1.0, u.steps + 1))
    if kind == "grid":
        assert np.allclose(u.frame.breakpoints, u.breakpoints[::50], rtol=0, atol=1e-15)
    U = u.stage_table(80)
    np.testing.assert_array_equal(stages.stage_table(u, 80), U)     # the integrator's way in
    tt = (np.arange(80)[:, None] + np.array([0.0, 0.5, 1.0])) * (1.0 / 80)
    if kind == "fourier":
        np.testing.assert_allclose(U, u(tt.ravel()).reshape(80, 3, 2), atol=1e-13)
    else:       # the step's own value at its end (left limit at a grid jump)
        np.testing.assert_allclose(U[:, 2], u(tt[:, 2] - 1e-12), atol=1e-9)
    w = u.with_params(u.params * 0.5)
    assert isinstance(w, FrameControls) and not np.allclose(w(t), u(t))
    # u = W(R(t)) w(t) is not linear in the parameters: no stage basis, no stage function
    with pytest.raises(ValueError, match="not linear"):
        stages.sparse_basis(u, 400)
    with pytest.raises(ValueError, match="not linear"):
        stages.stage_function(u, 400)


@pytest.mark.parametrize("steps", [400, 800, 3200])
def test_frame_controls_stage_tables_on_multiples_of_their_nodes(steps):
    """Fourier frame controls on a multiple of their nodes' steps take the gathered path
    (``w`` once on the quarter grid, ``u`` at the distinct stage times): it is ``u(t)`` at the
    stage times, sample by sample, and a table halved is the table of half the steps."""
    u = frame_controls("fourier")
    U = u.stage_table(steps)
    tt = (np.arange(steps)[:, None] + np.array([0.0, 0.5, 1.0])) * (1.0 / steps)
    np.testing.assert_allclose(U, u(tt.ravel()).reshape(steps, 3, 2), rtol=0, atol=1e-13)
    np.testing.assert_array_equal(U[1:, 0], U[:-1, 2])          # a step's end is the next one's start
    if steps > 400:
        np.testing.assert_allclose(stages.halve(U), u.stage_table(steps // 2), rtol=0, atol=1e-15)


@pytest.mark.parametrize("kind", ["fourier", "grid"])
def test_frame_controls_given_nodes_and_stages_on_nodes(kind):
    """Nodes handed over by a planner are used as they are; a stage table whose stage times
    are all nodes (here 200 steps of 2h) is ``W(R_n) w(t_n)`` at those nodes."""
    u = frame_controls(kind)
    v = FrameControls(u.frame, u.R0, mechanism_named("platform"), 400, nodes=u.nodes)
    t = np.random.default_rng(3).uniform(0.0, 1.0, 20)
    np.testing.assert_array_equal(v(t), u(t))
    U = v.stage_table(200)
    W, nodes = catalog.get("platform").frame.W, u.nodes
    w_end = stages.stage_table(u.frame, 200)
    for j in (0, 57, 199):
        for c in range(3):
            np.testing.assert_allclose(U[j, c], W(nodes[2 * j + c]) @ w_end[j, c], rtol=0, atol=1e-15)
    with pytest.raises(ValueError, match="nodes"):
        FrameControls(u.frame, u.R0, mechanism_named("platform"), 400, nodes=u.nodes[:-1])
    with pytest.raises(ValueError, match="nodes"):
        FrameControls(u.frame, u.R0, mechanism_named("platform"), 400, nodes=u.nodes[::-1])


@pytest.mark.parametrize("bad", [
    lambda: FrameControls(frame_controls(), np.eye(3), mechanism_named("platform"), 400),
    lambda: FrameControls(C.Fourier(1.0, np.zeros((3, 5))), np.eye(3), mechanism_named("platform"), 400),
    lambda: FrameControls(C.Fourier(1.0, np.zeros((2, 5))), np.eye(3), mechanism_named("tripod"), 400),
    lambda: FrameControls(C.Fourier(1.0, np.zeros((2, 5))), np.ones((3, 3)), mechanism_named("platform"), 400),
    lambda: FrameControls(C.PiecewiseConstant(1.0, np.zeros((7, 2))), np.eye(3), mechanism_named("platform"), 400),
])
def test_frame_controls_bad_input(bad):
    with pytest.raises(ValueError):
        bad()


def test_fine_fourier_stage_tables_by_fft_against_direct_sums():
    """Above ``stages.FFT_ABOVE`` steps a Fourier series' stage table comes from one inverse
    FFT; it agrees with the series summed term by term at the stage times (in extended
    precision), better than the sines-and-cosines basis does."""
    import mpmath as mp

    from nonholo.controls import stages

    rng = np.random.default_rng(11)
    K, steps = 32, 2 * stages.FFT_ABOVE
    f = C.Fourier(1.7, rng.normal(size=(2, 2 * K + 1)))
    U = stages.stage_table(f, steps)
    np.testing.assert_array_equal(U, stages.fourier_stage_values(f, steps))
    mp.mp.dps = 30
    for n, c in [(0, 0), (steps - 1, 2), (123, 1), (steps // 2, 0), (7777, 2)]:
        t = mp.mpf(2 * n + c) / (2 * steps) * mp.mpf(1.7)
        w = 2 * mp.pi / mp.mpf(1.7)
        for i in range(2):
            a = f.coeffs[i]
            exact = a[0] + sum(a[2 * k - 1] * mp.sin(k * w * t) + a[2 * k] * mp.cos(k * w * t)
                               for k in range(1, K + 1))
            assert abs(float(exact - U[n, c, i])) <= 1e-14
    coarse = stages.stage_table(f, 64)          # the basis product below the threshold
    np.testing.assert_allclose(coarse, (stages._fourier_stage_basis(1.7, K, 64).reshape(192, -1)
                                        @ f.coeffs.T).reshape(64, 3, 2), rtol=0, atol=0)
