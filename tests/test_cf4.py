"""The generated CF4 kernels (the step inlined by `nonholo derive`) against the kernels of
nonholo/integrate/cf4.py compiled as written (the step called), for every mechanism and
both of its systems, and against a fresh generation.

Bit for bit with the variational matrix ``QG`` compiled without fast-math (with it, LLVM
may reorder ``QG``'s arithmetic differently where it is inlined: the platform's raised
variant's Jacobians then differ at round-off level between the two forms); the kernels
as used (fast-math ``QG``) agree with those to round-off."""
import numpy as np
import pytest
from conftest import example

from nonholo.controls import stages
from nonholo.controls.parametrisations import Fourier, PiecewiseConstant
from nonholo.generated import cf4_kernels
from nonholo.integrate import cf4, inliner
from nonholo.model import catalog

#: A start state per mechanism: ``(R0, q0)``.
STARTS = {
    "car": (np.eye(3), np.array([0.1, 0.2, 0.3, 0.2])),
    "rolling_ball": (np.ascontiguousarray(example(1)[0]), np.array([0.1, -0.2])),
}
SYSTEMS = [(name, frame) for name in catalog.names() for frame in (False, True)
           if not frame or catalog.get(name).has_frame]


def start(name):
    return STARTS.get(name, (np.ascontiguousarray(example(1)[0]), np.zeros(0)))


def test_generated_kernels_are_fresh():
    assert inliner.cf4_kernels_module() == open(cf4_kernels.__file__).read()


@pytest.mark.parametrize("name,frame", SYSTEMS)
def test_inlined_kernels_equal_the_written_ones(name, frame):
    mech = catalog.get(name)
    fast = cf4.compile_system(mech.module, frame, fast_derivative=False)
    ref = cf4.compile_system(mech.module, frame, inlined=False, fast_derivative=False)
    used = cf4.compile_system(mech.module, frame)
    rng = np.random.default_rng(7)
    R0, q0 = start(name)
    d, m = mech.n_rates, mech.n_inputs
    for controls in (Fourier(1.0, 0.4 * rng.normal(size=(m, 5))),
                     PiecewiseConstant(1.0, 0.4 * rng.normal(size=(20, m)))):
        steps = 200
        U = stages.stage_table(controls, steps)
        basis = stages.kernel_basis(controls, steps)
        outs = []
        for kern in (fast, ref, used):
            Rs, Qs = kern.nodes(steps)
            a = kern.forward(R0, q0, U, 1.0 / steps, 1.0, -np.inf, Rs, Qs)
            Rv, Qv = kern.nodes(steps)
            Zs = np.empty((steps + 1, d, d))
            J, M = np.empty((d, controls.params.size)), np.empty((d, d))
            Wd = np.empty((3 * steps, d * m))
            b = kern.forward_variational(R0, q0, U, 1.0 / steps, 1.0, -np.inf, *basis, Rv, Qv, Zs, J, M,
                                         Wd, True)
            outs.append((a, Rs, Qs, b, Rv, Qv, Zs, J, M, Wd))
        assert outs[0][0][0] == steps and outs[0][3][0] == steps
        for x, y, z in zip(*outs):
            if isinstance(x, tuple):
                assert x == y == z
            else:
                np.testing.assert_array_equal(x, y)
                np.testing.assert_allclose(z, x, rtol=1e-12, atol=1e-12 * np.abs(x).max(initial=1.0))
        if frame:
            nodes, qnodes = outs[0][1], outs[0][2]
            t = np.array([0.0, 0.1234, 0.5, 0.999])
            k = np.minimum((t * steps).astype(np.int64), steps)
            s = t - k / steps
            Wst = np.ascontiguousarray(np.broadcast_to(controls(t)[:, None, :], (4, 3, m)))
            res = []
            for kern in (fast, ref):
                Rout, Qout, u = np.empty((4, 3, 3)), np.empty((4, mech.n_coordinates)), np.empty((4, m))
                kern.frame_inputs(nodes, qnodes, k, s, Wst, np.ascontiguousarray(controls(t)), Rout, Qout, u)
                res.append((Rout, Qout, u))
            for x, y in zip(*res):
                np.testing.assert_array_equal(x, y)


def test_a_stopped_run_reports_where():
    """A trajectory driven into Δ = 0 stops at the stage where sgnΔ fell below delta_stop,
    in both forms, with the same step count."""
    mech = catalog.get("platform")
    fast = cf4.compile_system(mech.module)
    ref = cf4.compile_system(mech.module, inlined=False)
    R0 = np.ascontiguousarray(example(1)[0])
    U = stages.stage_table(Fourier(1.0, [[3.0, 0, 0, 0, 0], [-3.0, 0, 0, 0, 0]]), 100)
    got = []
    for kern in (fast, ref):
        Rs, Qs = kern.nodes(100)
        got.append(kern.forward(R0, np.zeros(0), U, 0.01, 1.0, 0.3, Rs, Qs))
    assert got[0] == got[1]
    n, dmin, t_stop = got[0]
    assert n < 100 and dmin < 0.3 and 0.0 <= t_stop <= 1.0


def test_a_car_stops_before_its_singular_set():
    """The car steered towards cos φ = 0 stops there, in both forms, where φ's own motion
    (φ̇ = u₂, exact under CF4) says it should."""
    mech = catalog.get("car")
    fast = cf4.compile_system(mech.module)
    ref = cf4.compile_system(mech.module, inlined=False)
    U = np.zeros((100, 3, 2))
    U[:, :, 0] = 1.0
    U[:, :, 1] = 2.0                       # φ(t) = 2t reaches arccos(0.1) at t ≈ 0.735
    got = []
    for kern in (fast, ref):
        Rs, Qs = kern.nodes(100)
        got.append(kern.forward(np.eye(3), np.zeros(4), U, 0.01, 1.0, 0.1, Rs, Qs))
    assert got[0] == got[1]
    n, dmin, t_stop = got[0]
    assert n == int(np.arccos(0.1) / 2 / 0.01) == 73
    # step 73's middle (φ = 1.47) is clear, its end (φ = 1.48) is not
    assert t_stop == pytest.approx(0.74) and dmin == pytest.approx(np.cos(1.48), rel=1e-12)


def dop853_variational(mech, frame, R0, q0, controls, T):
    """The motion of the generated field (``G``, or ``N`` with ``frame``), its sensitivity
    ``J = ∂s_T/∂λ`` (``ds/dt = A s + B ∂v/∂λ``, ``s(0) = 0``) and ``M(T)`` (``Ṁ = A M + M Aᵀ +
    B Bᵀ``, ``M(0) = 0``), ``A = QG + [ω] ⊕ 0``, ``B = G``, by SciPy's DOP853 on the generated
    functions: ``(R_T, q_T, J, M)``."""
    from scipy.integrate import solve_ivp

    from nonholo.spaces import so3

    G, QG = (mech.module.N, mech.module.QN) if frame else (mech.module.G, mech.module.QG)
    d, k, p = mech.n_rates, mech.n_coordinates, controls.params.size
    rot = 3 if mech.orientation else 0
    units = [controls.with_params(np.eye(p)[c]) for c in range(p)]

    def f(t, y):
        R, q = y[:9].reshape(3, 3), y[9:9 + k]
        S, M = y[9 + k:9 + k + d * p].reshape(d, p), y[9 + k + d * p:].reshape(d, d)
        tt = np.array([t])
        v = controls(tt)[0]
        B = G(R, q)
        F = B @ v
        A = QG(R, q, v).copy()
        dR = np.zeros((3, 3))
        if rot:
            A[:3, :3] += so3.hat(F[:3])
            dR = so3.hat(F[:3]) @ R
        dv = np.stack([u(tt)[0] for u in units], axis=1)
        return np.concatenate([dR.ravel(), F[rot:], (A @ S + B @ dv).ravel(),
                               (A @ M + M @ A.T + B @ B.T).ravel()])

    y0 = np.concatenate([R0.ravel(), q0, np.zeros(d * p + d * d)])
    sol = solve_ivp(f, (0.0, T), y0, method="DOP853", rtol=1e-13, atol=1e-13)
    assert sol.success
    y = sol.y[:, -1]
    return (y[:9].reshape(3, 3), y[9:9 + k], y[9 + k:9 + k + d * p].reshape(d, p),
            y[9 + k + d * p:].reshape(d, d))


@pytest.mark.parametrize("name,frame", SYSTEMS)
def test_kernels_against_dop853_on_the_generated_field(name, frame):
    """Every mechanism's kernels (motion, Jacobian ``J``, mobility ``M``) against DOP853 on
    its generated field and variational matrix: within 1e-10 with 1000 CF4 steps (the
    motion kept at |Δ| ≥ 0.2, where the field's derivatives stay moderate)."""
    mech = catalog.get(name)
    kern = mech.kernels(frame)
    rng = np.random.default_rng(11)
    R0, q0 = start(name)
    d, m = mech.n_rates, mech.n_inputs
    controls = Fourier(1.0, 0.15 * rng.normal(size=(m, 5)))
    sign = np.sign(mech.delta_samples(R0[None], q0[None])[0]) if mech.has_singular_set else 1.0
    steps = 1000
    U = stages.stage_table(controls, steps)
    Rs, Qs = kern.nodes(steps)
    J, M = np.empty((d, controls.params.size)), np.empty((d, d))
    n, _, _ = kern.forward_variational(R0, q0, U, 1.0 / steps, sign, 0.2, *stages.kernel_basis(controls, steps),
                                       Rs, Qs, np.empty((steps + 1, d, d)), J, M,
                                       np.empty((3 * steps, d * m)), True)
    assert n == steps
    R_T, q_T, J_ref, M_ref = dop853_variational(mech, frame, R0, q0, controls, 1.0)
    assert np.abs(Rs[-1] - R_T).max() < 1e-10
    assert np.abs(Qs[-1] - q_T).max(initial=0.0) < 1e-10
    assert np.abs(J - J_ref).max() < 1e-10 * max(1.0, np.abs(J_ref).max())
    assert np.abs(M - M_ref).max() < 1e-10 * max(1.0, np.abs(M_ref).max())
