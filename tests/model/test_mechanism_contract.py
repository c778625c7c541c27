"""One contract every mechanism of the catalog passes, whatever its state space:

- its generated field ``G`` and ``Δ`` are the symbolic ones (mpmath evaluation of the
  derivation's SymPy expressions, independent of the generated printer);
- its kernels (``simulate``) agree with SciPy's DOP853 on the generated field;
- a plan to a goal its own motion reaches is certified, confirmed by DOP853 on the
  generated field (another integrator than the planner's), saved, reloaded and checked.
"""
from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from derivations import definitions
from derivations.rotations import r
from nonholo import PlanResult, plan, simulate, Settings
from nonholo.controls import Fourier
from nonholo.model import catalog
from nonholo.motion.simulation import SingularTrajectoryError
from nonholo.spaces import so3

NAMES = tuple(catalog.names())


def regular_state(mech, rng, clearance: float = 0.2):
    """A random state ``(R, q)`` at least ``clearance`` from ``Δ = 0`` (coordinates in a small
    box, so that the car's steering stays well inside ``|φ| < π/2``)."""
    while True:
        R, q = mech.space.sample(rng, 1)[0]
        q = 0.5 * q
        if not mech.singular.exists or abs(mech.singular.value(R, q)) > clearance:
            return R, q


def dop853(mech, R0, q0, controls, T):
    """``(R(T), q(T))`` of ``dR/dt = [ω] R``, ``dq/dt = q̇`` with ``(ω, q̇) = G(R, q) u(t)`` (plus the
    drift ``F(R, q)`` where there is one) by
    DOP853 (on SO(3) × Rᵏ: the nine entries of ``R`` and ``q``)."""
    k, r_rows = mech.space.k, 3 if mech.space.has_orientation else 0

    def f(t, y):
        R, q = y[:9].reshape(3, 3), y[9:]
        rates = mech.rates(np.ascontiguousarray(R), np.ascontiguousarray(q), controls(np.array([t]))[0])
        dR = so3.hat(rates[:3]) @ R if r_rows else np.zeros((3, 3))
        return np.concatenate([dR.ravel(), rates[r_rows:r_rows + k]])

    sol = solve_ivp(f, (0.0, T), np.concatenate([np.asarray(R0).ravel(), q0]), method="DOP853",
                    rtol=1e-12, atol=1e-12)
    assert sol.success
    return sol.y[:9, -1].reshape(3, 3), sol.y[9:, -1]


def clear_motion(mech, rng, scale: float, harmonics: int):
    """A random start and Fourier control whose motion over ``[0, 1]`` keeps ``|Δ| ≥ 0.05``
    (drawn again until it does), and that motion."""
    for _ in range(100):
        R0, q0 = regular_state(mech, rng)
        controls = Fourier(1.0, rng.normal(scale=scale, size=(mech.n_inputs, 2 * harmonics + 1)))
        try:
            traj = simulate(mech.space.public((R0, q0)), controls, 1.0, mechanism=mech, steps=400)
        except SingularTrajectoryError:
            continue
        if traj.min_delta is None or traj.min_delta >= 0.05:
            return (R0, q0), controls, traj
    raise AssertionError(f"no clear random motion of {mech.name!r}")


@pytest.fixture(params=NAMES)
def mech(request):
    return catalog.get(request.param)


def test_generated_field_and_delta_are_the_symbolic_ones(mech):
    sym = definitions.get(mech.name)
    args = list(r) + list(sym.coordinates)
    field = sp.lambdify(args, list(sym.field), modules="mpmath")
    delta = sp.lambdify(args, sym.delta, modules="mpmath") if sym.delta is not None else None
    assert (delta is None) == (not mech.singular.exists)
    rng = np.random.default_rng(7)
    worst = 0.0
    for _ in range(40):
        R, q = regular_state(mech, rng, 0.05)
        values = [*R.ravel(), *q]
        want = np.array([float(x) for x in field(*values)]).reshape(mech.n_rates, mech.n_inputs)
        worst = max(worst, np.max(np.abs(mech.G(R, q) - want)) / max(1.0, np.max(np.abs(want))))
        if delta is not None:
            assert mech.singular.value(R, q) == pytest.approx(float(delta(*values)), rel=1e-12, abs=1e-12)
    assert worst < 1e-12


def test_kernels_agree_with_dop853_on_the_generated_field(mech):
    (R0, q0), controls, traj = clear_motion(mech, np.random.default_rng(11), 0.3, 2)
    q_T = traj.q[-1] if traj.q is not None else np.zeros(0)
    R_ref, q_ref = dop853(mech, R0, q0, controls, 1.0)
    assert mech.space.distance((traj.R_T, q_T), (R_ref, q_ref)) < 1e-9


def test_a_reachable_goal_is_planned_certified_confirmed_and_reloaded(mech, tmp_path):
    # a goal the mechanism's own motion reaches from the start (the same component)
    (R0, q0), _, reached = clear_motion(mech, np.random.default_rng(13), 0.25, 1)
    Rd, qd = reached.R_T, (reached.q[-1] if reached.q is not None else np.zeros(0))
    if mech.singular.exists:
        assert mech.singular.sign(Rd, qd) == mech.singular.sign(R0, q0)
    tol = 1e-9
    res = plan(mech.space.public((R0, q0)), mech.space.public((Rd, qd)), mechanism=mech, settings=Settings(tol=tol))
    assert res.success, res.reason
    R_T, q_T = dop853(mech, R0, q0, res.controls, res.T)
    assert mech.space.distance((R_T, q_T), (Rd, qd)) < tol
    path = res.save(tmp_path / "plan.json")
    again = PlanResult.load(path)
    assert again == res
