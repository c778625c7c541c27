"""Peer on the kinematic car: python-control's differential-flatness planner.

``control.flatsys.point_to_point`` on python-control's own kinematic car (its
"vehicle steering" example): flat outputs ``(x, y)``, states ``(x, y, θ)``, inputs
``(v, δ)`` with the steering angle ``δ`` an input. The flat maps are the example's::

    θ = atan2(ẏ, ẋ),   v = ẋ cos θ + ẏ sin θ,   δ = atan2(ℓ (ÿ cos θ − ẍ sin θ), v²)

(ℓ = 1, as our car). Our car has the steering angle as a state, so ``δ`` at both ends is
our ``φ`` at start and goal. The flat map recovers the heading from the velocity's
direction, so the speed at the ends must be positive: ``v`` at both ends is the
distance between the end positions over ``T`` (at least 0.5). The basis is a polynomial
of degree 7 (``fs.PolyFamily(8)``): enough coefficients for the end conditions on the
outputs and their first two derivatives; no cost (the flat interpolation itself).

The peer's trajectory is re-simulated by SciPy's DOP853 (rtol = atol = 1e-13) on the
hand-written model :func:`nonholo.certify.resimulate.car_rates` with ``φ(t) = δ(t)`` taken from the
peer, the same model and tolerances that confirm nonholo's plans.
"""
from __future__ import annotations

import time

import numpy as np
from scipy.integrate import solve_ivp

from nonholo.certify.resimulate import car_rates

WHEELBASE = 1.0
BASIS_SIZE = 8


def _forward(x, u, params=None):
    """State and input → flat flag ``[(x, ẋ, ẍ), (y, ẏ, ÿ)]``."""
    th, v, d = x[2], u[0], u[1]
    thdot = v / WHEELBASE * np.tan(d)
    return [np.array([x[0], v * np.cos(th), -v * thdot * np.sin(th)]),
            np.array([x[1], v * np.sin(th), v * thdot * np.cos(th)])]


def _reverse(z, params=None):
    """Flat flag → state ``(x, y, θ)`` and input ``(v, δ)``."""
    th = np.arctan2(z[1][1], z[0][1])
    v = z[0][1] * np.cos(th) + z[1][1] * np.sin(th)
    thdot_v = z[1][2] * np.cos(th) - z[0][2] * np.sin(th)
    return np.array([z[0][0], z[1][0], th]), np.array([v, np.arctan2(thdot_v * WHEELBASE, v ** 2)])


def _update(t, x, u, params=None):
    return np.array([u[0] * np.cos(x[2]), u[0] * np.sin(x[2]), u[0] / WHEELBASE * np.tan(u[1])])


def _system():
    import control.flatsys as fs

    return fs.FlatSystem(_forward, _reverse, updfcn=_update, inputs=("v", "delta"),
                         outputs=("x", "y", "theta"), states=("x", "y", "theta"), name="kincar")


def _state(q, name):
    q = np.asarray(q, dtype=float)
    if q.shape != (4,) or not np.all(np.isfinite(q)):
        raise ValueError(f"{name} must be 4 finite numbers (x, y, θ, φ), got shape {q.shape}")
    return q


def solve(q0, qd, T: float = 1.0, *, tol: float = 1e-8, samples: int = 2001) -> dict:
    """Plan ``q0 → qd`` (car states ``(x, y, θ, φ)``) with the peer and re-simulate it.

    Returns ``success`` (the re-simulated end within ``tol`` of ``qd`` in every component,
    angles wrapped, and ``|cos φ| ≥ 1e-2`` on the dense path), ``seconds`` (the solver call
    alone), ``error_position``, ``error_angles``, ``min_cos_phi`` and ``reason``."""
    q0, qd = _state(q0, "q0"), _state(qd, "qd")
    if not T > 0:
        raise ValueError(f"T must be positive, got {T}")
    import control.flatsys as fs

    speed = max(0.5, float(np.hypot(*(qd[:2] - q0[:2]))) / T)
    sys_ = _system()
    t0 = time.perf_counter()
    try:
        traj = fs.point_to_point(sys_, T, q0[:3], [speed, q0[3]], qd[:3], [speed, qd[3]],
                                 basis=fs.PolyFamily(BASIS_SIZE))
    except Exception as exc:          # the peer's failure is a result, not a crash
        return {"success": False, "seconds": time.perf_counter() - t0, "reason": f"{type(exc).__name__}: {exc}",
                "error_position": None, "error_angles": None, "min_cos_phi": None}
    seconds = time.perf_counter() - t0

    def inputs(t):
        return traj.eval(np.atleast_1d(t))[1][:, 0]

    t, q = resimulate(q0, inputs, T, samples=samples)
    err = q[-1] - qd
    err[2:] = np.pi - np.mod(np.pi - err[2:], 2 * np.pi)
    pos, ang = float(np.hypot(err[0], err[1])), float(np.max(np.abs(err[2:])))
    least = float(np.min(np.abs(np.cos(q[:, 3]))))
    ok = max(np.max(np.abs(err[:2])), ang) <= tol and least >= 1e-2
    reason = "" if ok else (f"re-simulated end off by {pos:.2g} (position), {ang:.2g} rad (angles); "
                            f"least |cos φ| on the path {least:.3g}")
    return {"success": bool(ok), "seconds": seconds, "error_position": pos, "error_angles": ang,
            "min_cos_phi": least, "reason": reason, "t": t, "q": q}


def resimulate(q0, inputs, T: float, *, samples: int = 2001, rtol: float = 1e-13, atol: float = 1e-13):
    """``(t, q)``: the peer's inputs ``inputs(t) = (v, δ)`` played on the hand-written car
    (:func:`nonholo.certify.resimulate.car_rates`) from ``q0`` with ``φ(t) = δ(t)``, by DOP853 with dense
    output on ``samples`` uniform times; ``q`` ``(samples, 4)``."""
    q0 = _state(q0, "q0")

    def f(t, y):
        v, d = inputs(t)
        _, qdot = car_rates(None, (y[0], y[1], y[2], d), (v, 0.0), WHEELBASE)
        return qdot[:3]

    grid = np.linspace(0.0, T, samples)
    sol = solve_ivp(f, (0.0, T), q0[:3], method="DOP853", rtol=rtol, atol=atol, dense_output=True)
    if not sol.success:
        raise RuntimeError(f"DOP853 failed: {sol.message}")
    Y = sol.sol(grid).T
    phi = np.array([inputs(t)[1] for t in grid])
    return grid, np.column_stack([Y, phi])
