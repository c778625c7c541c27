"""The generated CF4 kernels (the step inlined by `nonholo derive`): against the kernels
as nonholo/integrate/ writes them (the step called), bit for bit, both executed by
the interpreter (``kernel_runs``), for every mechanism and both of its systems; against a
fresh generation; against DOP853 on the generated field; stopping at the singular set.
(The compiled backends are held to the interpreted source in ``test_native``.)"""
import kernel_runs
import numpy as np
import pytest
from conftest import example

from nonholo.controls import stages
from nonholo.controls.parametrisations import Fourier
from nonholo.generated import cf4_kernels
from nonholo.integrate import compiled, system_kernels
from nonholo.model import catalog

#: A start state per mechanism: ``(R0, q0)``.
STARTS = {
    "car": (np.eye(3), np.array([0.1, 0.2, 0.3, 0.2])),
    "rolling_ball": (np.ascontiguousarray(example(1)[0]), np.array([0.1, -0.2])),
    "unicycle": (np.eye(3), np.array([0.1, -0.2, 0.3])),
    "brockett": (np.eye(3), np.array([0.1, -0.2, 0.3])),
    "double_integrator": (np.eye(3), np.array([0.1, -0.2, 0.3, -0.1])),
    "car_with_trailer": (np.eye(3), np.array([0.1, 0.2, 0.3, 0.2, 0.1])),
    "unicycle2": (np.eye(3), np.array([0.1, -0.2, 0.3, 0.2, -0.1])),
}
SYSTEMS = [(name, frame) for name in catalog.names() for frame in (False, True)
           if not frame or catalog.get(name).has_frame]


def start(name):
    if name not in STARTS:
        assert catalog.get(name).state_space == "SO(3)", f"give {name!r} a start in STARTS"
    return STARTS.get(name, (np.ascontiguousarray(example(1)[0]), np.zeros(0)))


def test_generated_kernels_are_fresh():
    assert compiled.kernels_module() == open(cf4_kernels.__file__).read()


@pytest.mark.parametrize("name,frame", kernel_runs.SYSTEMS)
@pytest.mark.slow
def test_inlined_kernels_equal_the_written_ones(name, frame, interpreted_kernels):
    """Every output of the generated kernels (forward, variational with both bases, with
    and without ``M(T)``, frame inputs) bit for bit that of the kernels as written, both
    executed by the interpreter: the inlining changes no operation."""
    inlined, written = (interpreted_kernels[name, frame, form] for form in kernel_runs.FORMS)
    assert inlined.keys() == written.keys()
    assert inlined["forward_result"][0] > 0
    for key in inlined:
        np.testing.assert_array_equal(inlined[key], written[key], err_msg=key)


def test_a_stopped_run_reports_where():
    """A trajectory driven into Δ = 0 stops in the step where sgnΔ at a stage fell below
    delta_stop: the nodes before it are clear of the threshold, the reported least sgnΔ
    is below it and is Δ at one of that step's stages."""
    mech = catalog.get("platform")
    kern = system_kernels.compile_system(mech.module)
    R0 = np.ascontiguousarray(example(1)[0])
    U = stages.stage_table(Fourier(1.0, [[3.0, 0, 0, 0, 0], [-3.0, 0, 0, 0, 0]]), 100)
    Rs, Qs = kern.nodes(100)
    n, dmin, t_stop = kern.forward(R0, np.zeros(0), U, 0.01, 1.0, 0.3, Rs, Qs)
    assert 0 < n < 100 and dmin < 0.3 and n * 0.01 <= t_stop <= (n + 1) * 0.01
    assert np.all(mech.delta_samples(Rs[:n + 1], None) >= 0.3)
    full = kern.nodes(100)
    m, _, _ = kern.forward(R0, np.zeros(0), U, 0.01, 1.0, -np.inf, *full)
    assert m == 100
    np.testing.assert_array_equal(full[0][:n + 1], Rs[:n + 1])    # the same motion up to the stop


def test_a_car_stops_before_its_singular_set():
    """The car steered towards cos φ = 0 stops there, where φ's own motion (φ̇ = u₂, exact
    under CF4) says it should."""
    mech = catalog.get("car")
    kern = system_kernels.compile_system(mech.module)
    U = np.zeros((100, 3, 2))
    U[:, :, 0] = 1.0
    U[:, :, 1] = 2.0                       # φ(t) = 2t reaches arccos(0.1) at t ≈ 0.735
    Rs, Qs = kern.nodes(100)
    n, dmin, t_stop = kern.forward(np.eye(3), np.zeros(4), U, 0.01, 1.0, 0.1, Rs, Qs)
    assert n == int(np.arccos(0.1) / 2 / 0.01) == 73
    # step 73's middle (φ = 1.47) is clear, its end (φ = 1.48) is not
    assert t_stop == pytest.approx(0.74) and dmin == pytest.approx(np.cos(1.48), rel=1e-12)


def dop853_variational(mech, frame, R0, q0, controls, T):
    """The motion of the generated field (``G``, plus the drift ``F`` where there is one, or
    ``N`` with ``frame``), its sensitivity
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
        if not frame and mech.has_drift:        # the drift F(R, q): QG is already that of F + G v
            F = F + mech.module.F(R, q)
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
    kern = compiled.compiled_system(mech, frame)
    rng = np.random.default_rng(11)
    R0, q0 = start(name)
    d, m = mech.n_rates, mech.n_inputs
    controls = Fourier(1.0, 0.15 * rng.normal(size=(m, 5)))
    sign = np.sign(mech.delta_samples(R0[None], q0[None])[0]) if mech.delta is not None else 1.0
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


def test_the_certificate_replay_passes_no_dense_basis_without_stage_weights():
    """``certificate.sensitivity`` asks for no Jacobian: its basis must not read as a dense
    one (``Bidx`` of zero rows, ``Bval`` of ``steps`` rows), whose contraction reads
    ``3·steps`` rows of ``Wd`` — out of bounds of the empty ``Wd`` it passes."""
    from nonholo.certify import certificate

    steps = 8
    Bidx, Bval, _, _ = certificate.no_basis(steps)
    assert not (Bidx.shape[0] == 0 and Bval.shape[0] == steps)
