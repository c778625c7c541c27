"""How close to the least energy the plans are: ``plan(..., objective="energy")`` against
known optima, against CasADi/IPOPT, and the default ``plan()`` (``objective="auto"``) and the
plan as found (``objective=None``) against both.

Run::

    python -m benchmarks.optimality [--quick] [--no-casadi] [--sets attitude,brockett,...]

The sets (each case planned three times: with ``objective="energy"``, with the defaults —
``objective="auto"`` — and with ``objective=None``, the plan as found):

- ``attitude``: the closed-form sub-Riemannian extremals of the attitude mechanism (body
  rates about e₁, e₂): ``R(T) = R₀ exp(T[(a, b, c)]) exp(−T[c e₃])``, body rates ``u(t) =
  (a cos ct − b sin ct, a sin ct + b cos ct)``, energy ``(a² + b²) T``, minimising for
  ``|(a, b, c)| T ≤ π`` (Boscain & Rossi, SIAM J. Control Optim. 47(4), 2008); ``R₀``
  uniform, ``(a, b, c)`` uniform in direction with ``|(a, b, c)| T`` uniform in [0.3, π];
- ``brockett``: ``(0, 0, 0) → (0, 0, a)`` in ``T = 1``; least energy ``2π|a|`` (a circle);
- ``rolling_ball``: the goal reached when the contact point runs once round a circle of
  radius ``ρ`` at constant speed (``R₀`` uniform, the circle's phase random); that motion's
  energy ``(2πρ)²/T`` is an upper bound of the least (the plan must need no more);
- ``platform`` (near and far bands of ``benchmarks/goals.json``) and ``car`` (near: goals
  within 1 wheelbase and 1 rad, far: within 3 and π, steering |φ| ≤ 0.5 at both ends):
  against CasADi/IPOPT's minimum energy with the same clearance from Δ = 0 (the platform:
  :func:`benchmarks.casadi_ms.solve`, fine setting: 40 intervals, 8 substeps, Δ at the
  substeps; the car: the same multiple shooting written here for its four coordinates);
- ``random``: uniform random pairs of every catalog mechanism (same component of
  ``Δ ≠ 0``, ``|Δ| ≥ 0.1`` at both ends);
- ``time``: ``objective="time"``, the least time under bounds: the unicycle's obstacle-free
  park of Dynobench (``|v|, |ω| ≤ 0.5``) and car goals as above (``|v| ≤ 1``, ``|φ̇| ≤ 1``,
  ``|φ| ≤ 0.6``) against CasADi/IPOPT's free-time transcription (:func:`casadi_car_time`).

Every claimed success is re-simulated by DOP853 (rtol = atol = 1e-13, SciPy; on the
hand-written models beyond SO(3)): *solved* = final error ≤ 1e-8 and ``sgnΔ ≥ delta_min``
along the dense path. Energies ``∫|u|² dt`` by Gauss–Legendre quadrature between the
controls' breakpoints. Times per call, after a warm-up call per mechanism.

Writes ``benchmarks/results/optimality.md`` and ``optimality.json``.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time

import numpy as np

from nonholo.certify.resimulate import resimulate_path, resimulate_state, state_errors, terminal_error
from nonholo.constraints import Clearance
from nonholo.controls.parametrisations import Fourier
from nonholo.model import catalog
from nonholo.planning.api import plan
from nonholo.planning.energy_objective import controls_energy
from nonholo.spaces import so3

from . import goalset
from .report import RESULTS_DIR, Report

DELTA_MIN = 1e-2
SUCCESS_TOL = 1e-8
SEED = 20260226
#: Cases per set (``--quick``: the second number).
SIZES = {"attitude": (12, 4), "brockett": (8, 3), "rolling_ball": (8, 3), "platform": (8, 2), "car": (6, 2),
         "random": (4, 1), "time": (6, 2)}
SETS = tuple(SIZES)
#: How each case is planned (:func:`run_plan`).
KINDS = ("energy", "default", "found")


def _log(msg: str) -> None:
    print(f"[optimality] {msg}", file=sys.stderr, flush=True)


# --------------------------------------------------------------------------------------
# The cases: (mechanism, start, goal, T, reference energy or None, label)
# --------------------------------------------------------------------------------------

def attitude_cases(n: int, rng) -> list[dict]:
    out = []
    while len(out) < n:
        v = rng.normal(size=3)
        v *= rng.uniform(0.3, np.pi) / np.linalg.norm(v)
        a, b, c = v
        if a * a + b * b < 0.05 * float(v @ v):
            continue
        R0 = so3.exp(rng.normal(size=3) * 2.0)
        Rd = R0 @ so3.exp(v) @ so3.exp(np.array([0.0, 0.0, -c]))
        out.append({"mechanism": "attitude", "start": R0, "goal": Rd, "T": 1.0, "reference": a * a + b * b,
                    "label": f"|v|T = {np.linalg.norm(v):.3f}", "band": "extremal"})
    return out


def brockett_cases(n: int, rng) -> list[dict]:
    values = [0.1, -0.5, 1.0, -2.0, 0.3, 1.5, -0.8, 3.0][:n]
    return [{"mechanism": "brockett", "start": np.zeros(3), "goal": np.array([0.0, 0.0, a]), "T": 1.0,
             "reference": 2 * np.pi * abs(a), "label": f"a = {a:g}", "band": "circle"} for a in values]


def ball_cases(n: int, rng) -> list[dict]:
    out = []
    radii = [0.5, 1.0, 0.25, 0.75, 1.25, 0.4, 0.9, 1.5][:n]
    for rho in radii:
        T, w, phase = 1.0, 2 * np.pi, rng.uniform(0, 2 * np.pi)
        sense = rng.choice([-1.0, 1.0])
        # v(t) = ρω (−sin(ωt + φ), cos(ωt + φ)) (a sense): the contact point runs once round the circle
        c = np.zeros((2, 3))
        c[0, 1], c[0, 2] = -rho * w * np.cos(phase), -rho * w * np.sin(phase)
        c[1, 1], c[1, 2] = -rho * w * np.sin(phase) * sense, rho * w * np.cos(phase) * sense
        R0 = so3.exp(rng.normal(size=3) * 2.0)
        start = (R0, np.zeros(2))
        _, R, q, _ = resimulate_state(start, Fourier(T, c), T, "rolling_ball")
        out.append({"mechanism": "rolling_ball", "start": start, "goal": (R[-1], q[-1]), "T": T,
                    "reference": (2 * np.pi * rho) ** 2 / T, "label": f"ρ = {rho:g}", "band": "circle"})
    return out


def platform_cases(n: int, rng) -> list[dict]:
    out = []
    for band in ("near", "far"):
        goals = [g for g in goalset.load_goals() if g["band"] == band]
        for g in [goals[i] for i in rng.choice(len(goals), size=n, replace=False)]:
            out.append({"mechanism": "platform", "start": np.array(g["R0"]), "goal": np.array(g["Rd"]),
                        "T": g["T"], "reference": None, "label": g["id"], "band": band})
    return out


def car_cases(n: int, rng) -> list[dict]:
    out = []
    for band, (box, ang) in (("near", (1.0, 1.0)), ("far", (3.0, np.pi))):
        for _ in range(n):
            q0 = np.zeros(4)
            qd = np.array([*rng.uniform(-box, box, 2), rng.uniform(-ang, ang), rng.uniform(-0.5, 0.5)])
            out.append({"mechanism": "car", "start": q0, "goal": qd, "T": 1.0, "reference": None,
                        "label": f"({qd[0]:.2f}, {qd[1]:.2f}, {qd[2]:.2f}, {qd[3]:.2f})", "band": band})
    return out


def random_cases(n: int, rng) -> list[dict]:
    out = []
    for name in catalog.names():
        mech = catalog.get(name)
        while sum(c["mechanism"] == name for c in out) < n:
            a, b = mech.space.sample(rng, 2)
            if mech.singular.exists:
                da, db = mech.singular.value(*a), mech.singular.value(*b)
                if min(abs(da), abs(db)) < 0.1 or np.sign(da) != np.sign(db):
                    continue
            out.append({"mechanism": name, "start": mech.space.public(a), "goal": mech.space.public(b),
                        "T": 1.0, "reference": None,
                        "label": "random", "band": "random"})
    return out


#: The bounds of the least-time set: the car's (|v| ≤ 1, |φ̇| ≤ 1, |φ| ≤ 0.6) and the unicycle's
#: (|v|, |ω| ≤ 0.5).
CAR_TIME_BOUNDS = ((-1.0, -1.0), (1.0, 1.0), 0.6)
UNICYCLE_TIME_BOUNDS = ((-0.5, -0.5), (0.5, 0.5))


def time_cases(n: int, rng) -> list[dict]:
    out = [{"mechanism": "unicycle", "start": np.array([0.7, 0.8, 0.0]), "goal": np.array([1.9, 0.3, 0.0]),
            "T": 1.0, "reference": 2.95, "label": "park (0.7, 0.8, 0) → (1.9, 0.3, 0)", "band": "park"}]
    for band, (box, ang) in (("near", (1.0, 1.0)), ("far", (3.0, np.pi))):
        for _ in range(n):
            qd = np.array([*rng.uniform(-box, box, 2), rng.uniform(-ang, ang), rng.uniform(-0.5, 0.5)])
            out.append({"mechanism": "car", "start": np.zeros(4), "goal": qd, "T": 1.0, "reference": None,
                        "label": f"({qd[0]:.2f}, {qd[1]:.2f}, {qd[2]:.2f}, {qd[3]:.2f})", "band": band})
    return out


MAKERS = {"attitude": attitude_cases, "brockett": brockett_cases, "rolling_ball": ball_cases,
          "platform": platform_cases, "car": car_cases, "random": random_cases, "time": time_cases}


# --------------------------------------------------------------------------------------
# Checks
# --------------------------------------------------------------------------------------

def check(case: dict, controls, breakpoints, T: float) -> dict:
    """DOP853 with a dense path: the final error and the least ``sgnΔ`` (``inf`` without a
    singular set); a failed integration is infinitely far, on ``Δ = 0``."""
    mech = catalog.get(case["mechanism"])
    try:
        if not mech.space.k:
            _, R, d = resimulate_path(case["start"], controls, T, mech, breakpoints)
            final = terminal_error(R[-1], case["goal"])
            least = math.inf if d is None or not mech.singular.exists else float(np.min(np.sign(d[0]) * d))
        else:
            _, R, q, d = resimulate_state(case["start"], controls, T, mech.name, breakpoints)
            Rd, qd = mech.parse_state(case["goal"], "goal")
            final = max(state_errors(mech.name, R[-1], q[-1], Rd, qd).values())
            least = math.inf if d is None else float(np.min(np.sign(d[0]) * d))
    except (RuntimeError, FloatingPointError, ValueError, ZeroDivisionError):
        return {"final_error": math.inf, "least_delta": 0.0}
    return {"final_error": float(final), "least_delta": least}


def run_plan(case: dict, kind: str) -> dict:
    """``plan`` with ``objective="energy"`` (``kind`` ``"energy"``), with the defaults
    (``"default"``: ``objective="auto"``) or with ``objective=None`` (``"found"``: the plan as
    found)."""
    t = time.perf_counter()
    extra = {"energy": {"objective": "energy"}, "default": {}, "found": {"objective": None}}[kind]
    res = plan(case["start"], case["goal"], T=case["T"], mechanism=case["mechanism"],
               constraints=[Clearance(DELTA_MIN)], **extra)
    wall = time.perf_counter() - t
    c = check(case, res.controls, res.breakpoints, res.T) if res.success else None
    solved = c is not None and c["final_error"] <= SUCCESS_TOL and c["least_delta"] >= DELTA_MIN
    return {"seconds": wall, "reported": res.seconds, "claimed": bool(res.success), "solved": solved,
            "energy": controls_energy(res.controls, res.breakpoints, res.T) if solved else None,
            "method": res.method, "reason": res.reason[-240:]}


def time_constraints(case: dict) -> list:
    from nonholo.constraints import InputBounds, StateBounds

    if case["mechanism"] == "car":
        low, high, phi = CAR_TIME_BOUNDS
        return [InputBounds(low, high), StateBounds([-math.inf] * 3 + [-phi], [math.inf] * 3 + [phi])]
    return [InputBounds(*UNICYCLE_TIME_BOUNDS)]


def run_time(case: dict) -> dict:
    """``plan(..., objective="time")`` under the set's bounds; DOP853 on the hand-written model
    checks the goal, the clearance, the steering bound (car) along the dense path and the
    inputs' bounds on a fine grid (1e-9 relative)."""
    t = time.perf_counter()
    res = plan(case["start"], case["goal"], mechanism=case["mechanism"], objective="time",
               constraints=[Clearance(DELTA_MIN), *time_constraints(case)])
    wall = time.perf_counter() - t
    solved = False
    if res.success:
        c = check(case, res.controls, res.breakpoints, res.T)
        _, _, q, _ = resimulate_state(case["start"], res.controls, res.T, case["mechanism"], res.breakpoints)
        low, high = (CAR_TIME_BOUNDS[:2] if case["mechanism"] == "car" else UNICYCLE_TIME_BOUNDS)
        u = np.asarray(res.controls(np.linspace(0.0, res.T, 100001)), dtype=float)
        inside = np.all(u <= np.asarray(high) * (1 + 1e-9)) and np.all(u >= np.asarray(low) * (1 + 1e-9))
        if case["mechanism"] == "car":
            inside = inside and np.max(np.abs(q[:, 3])) <= CAR_TIME_BOUNDS[2] * (1 + 1e-9)
        solved = c["final_error"] <= SUCCESS_TOL and c["least_delta"] >= DELTA_MIN and bool(inside)
    return {"seconds": wall, "reported": res.seconds, "claimed": bool(res.success), "solved": solved,
            "T": res.T if solved else None, "reason": res.reason[-240:]}


def run_casadi_time(case: dict) -> dict:
    t = time.perf_counter()
    low, high, phi = CAR_TIME_BOUNDS
    ok, T = casadi_car_time(case["start"], case["goal"], N=50, v_max=high[0], rate_max=high[1], phi_max=phi)
    return {"seconds": time.perf_counter() - t, "solved": ok, "T": T if ok else None}


# --------------------------------------------------------------------------------------
# CasADi: the platform's baseline, and the same multiple shooting for the car
# --------------------------------------------------------------------------------------

CASADI_FINE = {"N": 40, "substeps": 8, "delta_min": DELTA_MIN, "path_at_substeps": True, "max_iter": 500,
               "tol": 1e-10}


class _PiecewiseControls:
    """Piecewise-constant controls on the grid ``t_grid`` (a CasADi solution's)."""

    def __init__(self, t_grid, values):
        self.t_grid, self.values = np.asarray(t_grid, float), np.asarray(values, float)

    def __call__(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        j = np.clip(np.searchsorted(self.t_grid, t, side="right") - 1, 0, len(self.values) - 1)
        return self.values[j]


def car_shooting(opti, X, U, h, N: int, substeps: int, each_substep=None) -> None:
    """The kinematic car's multiple shooting in ``opti`` (``ẋ = v cos θ``, ``ẏ = v sin θ``,
    ``θ̇ = v tan φ``, ``φ̇ = u₂``): RK4 substeps of ``h`` on each of ``N`` intervals, the states
    ``X`` continuous at the nodes; ``each_substep(x)`` is called with every substep's state."""
    import casadi as ca

    def f(x, u):
        return ca.vertcat(u[0] * ca.cos(x[2]), u[0] * ca.sin(x[2]), u[0] * ca.tan(x[3]), u[1])

    for k in range(N):
        x = X[:, k]
        for _ in range(substeps):
            k1 = f(x, U[:, k])
            k2 = f(x + h / 2 * k1, U[:, k])
            k3 = f(x + h / 2 * k2, U[:, k])
            k4 = f(x + h * k3, U[:, k])
            x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            if each_substep is not None:
                each_substep(x)
        opti.subject_to(X[:, k + 1] == x)


def casadi_car(q0, qd, T: float, N: int = 40, substeps: int = 8, delta_min: float = DELTA_MIN,
               max_iter: int = 500, tol: float = 1e-10):
    """Minimum ``∫|u|² dt`` of the kinematic car (``ẋ = v cos θ``, ``ẏ = v sin θ``, ``θ̇ = v tan φ``,
    ``φ̇ = u₂``) by multiple shooting with RK4 substeps and ``cos φ ≥ delta_min`` at every
    substep, solved by IPOPT (exact Hessians); states initialised on the straight line.
    Returns ``(success, controls, breakpoints, status)``."""
    import casadi as ca

    opti = ca.Opti()
    X, U = opti.variable(4, N + 1), opti.variable(2, N)
    car_shooting(opti, X, U, T / N / substeps, N, substeps,
                 each_substep=lambda x: opti.subject_to(ca.cos(x[3]) >= delta_min))
    opti.subject_to(X[:, 0] == np.asarray(q0, float))
    opti.subject_to(X[:, N] == np.asarray(qd, float))
    opti.minimize(T / N * ca.sumsqr(U))
    s = np.linspace(0, 1, N + 1)
    opti.set_initial(X, np.outer(np.asarray(q0, float), 1 - s) + np.outer(np.asarray(qd, float), s))
    opti.set_initial(U, np.vstack([np.full(N, np.hypot(qd[0] - q0[0], qd[1] - q0[1]) / T), np.zeros(N)]))
    opti.solver("ipopt", {"print_time": False}, {"print_level": 0, "max_iter": max_iter, "tol": tol,
                                                 "sb": "yes"})
    grid = np.linspace(0.0, T, N + 1)
    try:
        sol = opti.solve()
        return True, _PiecewiseControls(grid, np.asarray(sol.value(U)).T), grid, "Solve_Succeeded"
    except RuntimeError as exc:
        return False, None, grid, str(exc)[-120:]


def casadi_car_time(q0, qd, N: int = 50, substeps: int = 4, v_max: float = 1.0, rate_max: float = 1.0,
                    phi_max: float = 0.6, max_iter: int = 3000, tol: float = 1e-10):
    """The least time of the kinematic car under ``|v| ≤ v_max``, ``|φ̇| ≤ rate_max``, ``|φ| ≤
    phi_max``: free ``T``, ``N`` equal intervals of piecewise-constant inputs, multiple
    shooting with RK4 substeps, solved by IPOPT (exact Hessians); states initialised on the
    straight line, ``T`` on twice the distance plus the turn. Returns ``(success, T)``."""
    import casadi as ca

    q0, qd = np.asarray(q0, float), np.asarray(qd, float)
    opti = ca.Opti()
    X, U, T = opti.variable(4, N + 1), opti.variable(2, N), opti.variable()
    car_shooting(opti, X, U, T / N / substeps, N, substeps)
    opti.subject_to(opti.bounded(-v_max, U[0, :], v_max))
    opti.subject_to(opti.bounded(-rate_max, U[1, :], rate_max))
    opti.subject_to(opti.bounded(-phi_max, X[3, :], phi_max))
    opti.subject_to(T >= 1e-3)
    opti.subject_to(X[:, 0] == q0)
    opti.subject_to(X[:, N] == qd)
    opti.minimize(T)
    T0 = 2.0 * (np.hypot(*(qd[:2] - q0[:2])) + abs(qd[2] - q0[2]) + 0.5)
    s = np.linspace(0, 1, N + 1)
    opti.set_initial(T, T0)
    opti.set_initial(X, np.outer(q0, 1 - s) + np.outer(qd, s))
    opti.set_initial(U, np.vstack([np.full(N, np.hypot(*(qd[:2] - q0[:2])) / T0), np.zeros(N)]))
    opti.solver("ipopt", {"print_time": False}, {"print_level": 0, "max_iter": max_iter, "tol": tol, "sb": "yes"})
    try:
        sol = opti.solve()
        return True, float(sol.value(T))
    except RuntimeError:
        return False, math.nan


def run_casadi(case: dict) -> dict:
    t = time.perf_counter()
    if case["mechanism"] == "platform":
        from . import casadi_ms

        res = casadi_ms.solve(case["start"], case["goal"], T=case["T"], **CASADI_FINE)
        ok, controls, bps, status = bool(res.success), res.controls, res.t_grid, res.status
    else:
        kw = {k: v for k, v in CASADI_FINE.items() if k != "path_at_substeps"}
        ok, controls, bps, status = casadi_car(case["start"], case["goal"], case["T"], **kw)
    wall = time.perf_counter() - t
    c = check(case, controls, bps, case["T"]) if ok else None
    solved = c is not None and c["final_error"] <= SUCCESS_TOL and c["least_delta"] >= DELTA_MIN
    return {"seconds": wall, "claimed": ok, "solved": solved,
            "energy": controls_energy(controls, bps, case["T"]) if solved else None, "reason": status}


# --------------------------------------------------------------------------------------
# The run and the report
# --------------------------------------------------------------------------------------

def _stats(xs) -> str:
    xs = [x for x in xs if x is not None and math.isfinite(x)]
    if not xs:
        return "–"
    return f"{np.median(xs):.4f} / {max(xs):.4f}"


def _ms(xs) -> str:
    return "–" if not xs else f"{1e3 * float(np.median(xs)):.0f}"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="a few cases per set")
    p.add_argument("--no-casadi", action="store_true", help="skip the CasADi baselines")
    p.add_argument("--sets", default=",".join(SETS), help=f"comma-separated, of {', '.join(SETS)}")
    args = p.parse_args(argv)
    sets = [s for s in args.sets.split(",") if s]
    unknown = [s for s in sets if s not in SETS]
    if unknown:
        p.error(f"unknown set(s) {unknown}; known: {', '.join(SETS)}")
    rng = np.random.default_rng(SEED)
    cases = []
    for name in SETS:                       # every set drawn, so that a subset keeps its cases
        made = MAKERS[name](SIZES[name][1 if args.quick else 0], rng)
        if name in sets:
            cases += [{**c, "set": name} for c in made]
    warmed = set()
    records = []
    for i, case in enumerate(cases):
        if case["set"] == "time":
            if ("time", case["mechanism"]) not in warmed:
                run_time(case)
                warmed.add(("time", case["mechanism"]))
            rec = {k: case[k] for k in ("set", "mechanism", "band", "label", "reference", "T")}
            rec["time"] = run_time(case)
            if case["mechanism"] == "car" and not args.no_casadi:
                rec["casadi_time"] = run_casadi_time(case)
            records.append(rec)
            _log(f"{i + 1}/{len(cases)} time {case['mechanism']} {case['label']}: T {rec['time']['T']} "
                 f"({rec['time']['seconds']:.2f} s)"
                 + (f", casadi {rec['casadi_time']['T']}" if "casadi_time" in rec else ""))
            continue
        peer = case["set"] in ("platform", "car") and not args.no_casadi
        if case["mechanism"] not in warmed:
            for kind in KINDS:
                run_plan(case, kind)
            if peer:
                run_casadi(case)
            warmed.add(case["mechanism"])
        rec = {k: case[k] for k in ("set", "mechanism", "band", "label", "reference", "T")}
        for kind in KINDS:
            rec[kind] = run_plan(case, kind)
        if peer:
            rec["casadi"] = run_casadi(case)
        records.append(rec)
        e, d = rec["energy"]["energy"], rec["default"]["energy"]
        _log(f"{i + 1}/{len(cases)} {case['set']} {case['mechanism']} {case['label']}: energy {e} "
             f"({rec['energy']['seconds']:.2f} s), default {d}, reference {case['reference']}"
             + (f", casadi {rec['casadi']['energy']}" if "casadi" in rec else ""))
    report(records, argv, args)
    return 0


def report(all_records: list[dict], argv, args) -> None:
    records = [r for r in all_records if r["set"] != "time"]
    timed = [r for r in all_records if r["set"] == "time"]
    rep = Report("optimality.md", "Least-energy plans against known optima and CasADi", "benchmarks.optimality",
                 argv, extra_packages=("casadi",))
    rep.paragraph(
        "Each case planned by `plan(start, goal, T, constraints=[Clearance(0.01)], objective=\"energy\")` "
        "(*energy*), by `plan(start, goal, T, constraints=[Clearance(0.01)])` (*default*: "
        "`objective=\"auto\"`, the plan as found unless the extremal through it — or, for a wasteful plan, "
        "a quick search — finds a smooth motion of far less energy) and with `objective=None` (*found*: the plan as "
        "found), timed per call after a warm-up call per mechanism. "
        f"Every claimed success re-simulated by DOP853 (rtol = atol = 1e-13): *solved* = final error ≤ "
        f"{SUCCESS_TOL:g} and sgnΔ ≥ {DELTA_MIN:g} along the dense path. Energy ∫|u|² dt by quadrature of the "
        "returned controls. Ratios: median / max. The sets: see the module docstring "
        "(`benchmarks/optimality.py`).")
    rep.heading("Against the known optima")
    rows = []
    for name, what in (("attitude", "closed-form extremal (a² + b²)T"), ("brockett", "circle 2π|a|"),
                       ("rolling_ball", "circle of the contact point (2πρ)²/T, an upper bound")):
        rs = [r for r in records if r["set"] == name]
        if not rs:
            continue
        ok = [r for r in rs if r["energy"]["solved"]]
        rows.append([name, what, len(rs), len(ok),
                     _stats([r["energy"]["energy"] / r["reference"] for r in ok]),
                     _ms([r["energy"]["seconds"] for r in rs]),
                     sum(r["default"]["solved"] for r in rs),
                     _stats([r["default"]["energy"] / r["reference"] for r in rs if r["default"]["solved"]])])
    if rows:
        rep.table(["set", "reference", "cases", "energy solved", "energy / reference", "energy median ms",
                   "default solved", "default / reference"], rows, align="llrrrrrr")
    peers = [r for r in records if "casadi" in r]
    if peers:
        rep.heading("Against CasADi/IPOPT (the same clearance from Δ = 0)")
        rows = []
        for mech in ("platform", "car"):
            for band in ("near", "far"):
                rs = [r for r in peers if r["mechanism"] == mech and r["band"] == band]
                if not rs:
                    continue
                both = [r for r in rs if r["energy"]["solved"] and r["casadi"]["solved"]]
                t_ours = [r["energy"]["seconds"] for r in rs]
                t_peer = [r["casadi"]["seconds"] for r in rs]
                rows.append([mech, band, len(rs), sum(r["energy"]["solved"] for r in rs),
                             sum(r["casadi"]["solved"] for r in rs),
                             sum(r["casadi"]["claimed"] and not r["casadi"]["solved"] for r in rs),
                             _stats([r["energy"]["energy"] / r["casadi"]["energy"] for r in both]),
                             _ms(t_ours), _ms(t_peer),
                             f"{np.median(t_peer) / np.median(t_ours):.1f}×"])
        rep.table(["mechanism", "band", "cases", "energy solved", "casadi solved", "casadi false claims",
                   "energy / casadi", "energy median ms", "casadi median ms", "time ratio"], rows,
                  align="llrrrrrrrr")
    rep.heading("The default plan against the least-energy plan")
    rows = []
    for name in SETS:
        for mech in sorted({r["mechanism"] for r in records if r["set"] == name}):
            rs = [r for r in records if r["set"] == name and r["mechanism"] == mech]
            both = [r for r in rs if r["energy"]["solved"] and r["default"]["solved"]]
            ratios = [r["default"]["energy"] / r["energy"]["energy"] for r in both]
            found = [r["found"]["energy"] / r["energy"]["energy"] for r in rs
                     if r["energy"]["solved"] and r["found"]["solved"]]
            rows.append([name, mech, len(rs), sum(r["default"]["solved"] for r in rs),
                         sum(r["energy"]["solved"] for r in rs), _stats(ratios),
                         sum(x > 3.0 for x in ratios), _stats(found), sum(x > 3.0 for x in found),
                         _ms([r["default"]["seconds"] for r in rs]), _ms([r["found"]["seconds"] for r in rs]),
                         _ms([r["energy"]["seconds"] for r in rs])])
    rep.table(["set", "mechanism", "cases", "default solved", "energy solved", "default / energy",
               "above 3×", "found / energy", "above 3×", "default median ms", "found median ms",
               "energy median ms"], rows, align="llrrrrrrrrrr")
    if records:
        rep.heading("Time: the default and the least energy against the plan as found")
        rep.paragraph("Median wall time of each set over the median of the plan as found on the same cases "
                      "(the median over the sets' ratios last).")
        rows, d_ratios, e_ratios = [], [], []
        for name in SETS:
            rs = [r for r in records if r["set"] == name]
            if not rs:
                continue
            found = float(np.median([r["found"]["seconds"] for r in rs]))
            d = float(np.median([r["default"]["seconds"] for r in rs])) / found
            e = float(np.median([r["energy"]["seconds"] for r in rs])) / found
            d_ratios.append(d), e_ratios.append(e)
            rows.append([name, len(rs), _ms([r["found"]["seconds"] for r in rs]), f"{d:.2f}×", f"{e:.2f}×"])
        rows.append(["median of the sets", "", "", f"{np.median(d_ratios):.2f}×", f"{np.median(e_ratios):.2f}×"])
        rep.table(["set", "cases", "found median ms", "default / found", "energy / found"], rows, align="lrrrr")
    calls = [r[k] for r in all_records for k in (*KINDS, "time") if k in r and r[k].get("reported")]
    if calls:
        share = [c["reported"] / c["seconds"] for c in calls]
        rep.paragraph(f"`PlanResult.seconds` over the call's wall time: median {np.median(share):.3f}, "
                      f"least {min(share):.3f} ({len(calls)} calls).")
    if timed:
        rep.heading("The least time under bounds (`objective=\"time\"`)")
        rep.paragraph("`plan(start, goal, objective=\"time\", constraints=[Clearance(0.01), bounds])`: the "
                      "unicycle with |v|, |ω| ≤ 0.5 (Dynobench's obstacle-free park, reference T ≤ 2.95 s), the "
                      "car with |v| ≤ 1, |φ̇| ≤ 1, |φ| ≤ 0.6 against CasADi/IPOPT's free-time transcription "
                      "(`casadi_car_time`: the same 50 equal intervals, RK4 substeps, straight-line start). "
                      "*Solved*: DOP853 ends within 1e-8 of the goal, with the clearance, the steering bound "
                      "along the dense path and the inputs' bounds on a fine grid kept to 1e-9 relative.")
        rows = []
        for mech, band in (("unicycle", "park"), ("car", "near"), ("car", "far")):
            rs = [r for r in timed if r["mechanism"] == mech and r["band"] == band]
            if not rs:
                continue
            ok = [r for r in rs if r["time"]["solved"]]
            both = [r for r in ok if r.get("casadi_time", {}).get("solved")]
            rows.append([mech, band, len(rs), len(ok), _stats([r["time"]["T"] for r in ok]),
                         _stats([r["time"]["T"] / r["casadi_time"]["T"] for r in both]) if both else "–",
                         _ms([r["time"]["seconds"] for r in rs]),
                         _ms([r["casadi_time"]["seconds"] for r in rs if "casadi_time" in r])])
        rep.table(["mechanism", "goals", "cases", "solved", "T [s]", "T / casadi", "median ms", "casadi median ms"],
                  rows, align="llrrrrrr")
    false = [(r, k) for r in all_records for k in (*KINDS, "time") if k in r and r[k]["claimed"] and not r[k]["solved"]]
    rep.paragraph(f"False claims (a claimed success DOP853 does not confirm): {len(false)}.")
    missed = [r for r in records if not r["energy"]["solved"] or not r["default"]["solved"]]
    if missed:
        rep.heading("Cases not solved")
        rep.table(["set", "mechanism", "case", "energy", "default"],
                  [[r["set"], r["mechanism"], r["label"], r["energy"]["reason"][-120:] if not r["energy"]["solved"]
                    else "solved", r["default"]["reason"][-120:] if not r["default"]["solved"] else "solved"]
                   for r in missed], align="lllll")
    rep.write()
    (RESULTS_DIR / "optimality.json").write_text(json.dumps({"records": all_records}, indent=1, default=float))


if __name__ == "__main__":
    raise SystemExit(main())
