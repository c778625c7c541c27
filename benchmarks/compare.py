"""Compare the Jacobian planners of ``nonholo`` with a CasADi/IPOPT baseline on the goal set.

Run by hand::

    python -m benchmarks.compare [--limit N] [--bands near far across]
                                 [--solvers robust paper casadi casadi-fine]
    python -m benchmarks.compare --set random [--per-band 500] [--peer-pairs 15]
                                 [--peers nonholo-local casadi ompl]

The second form runs the uniform random band set with OMPL's control planner as a
further peer (:mod:`benchmarks.random_set`, ``global.md``); what follows is the first.

Solvers (all with ``T`` from the goal, ``delta_min = 0.01``):

- ``robust``, ``paper``: :func:`nonholo.planning.api.plan` with ``strategy="robust"`` /
  ``"paper"`` and ``route="local"`` (the strategy alone; defaults otherwise: parametric,
  ``harmonics = 2``, ``tol = 1e-10``). A
  strategy that the installed planner does not know is reported as unavailable.
- ``casadi``: :func:`benchmarks.casadi_ms.solve`, minimum ``∫|u|² dt`` by multiple
  shooting, ``N = 40`` piecewise-constant intervals, 2 RKMK4/Cayley substeps per
  interval, path constraint ``sgn(Δ(R0)) Δ ≥ 0.01`` at the nodes and at the substeps.
- ``casadi-fine``: the same with 8 substeps per interval (smaller discretisation error,
  slower).

The CasADi part is skipped with a message when ``casadi`` is not installed.

Protocol
--------
- Every solver is warmed up once before timing (on Example 1, ``RPY(0.5, 1.2, −0.5) →
  RPY(1.0, 0.9, −0.5)``): this compiles numba kernels and builds the CasADi NLP. The
  CasADi build time is reported separately and is *not* in the solve times (the built
  solver is reused, ``build_seconds = 0`` for every timed call).
- Wall time: ``time.perf_counter()`` around the solver call only (the whole
  ``plan(...)`` call; the whole ``casadi_ms.solve(...)`` call, which includes its
  initial-guess rollout; IPOPT's own time is recorded too). Goals run one after the
  other in one process.
- Verification, the same for every solver: the returned control is re-simulated by
  :func:`nonholo.certify.resimulate.resimulate` (SciPy DOP853, ``rtol = atol = 1e-13``, the
  generated ``L``; breakpoints at the CasADi grid for piecewise-constant controls) →
  terminal error ``|log(R_T R_dᵀ)|``. The least ``sgn(Δ(R0)) Δ`` along the motion is
  taken on a dense path from :func:`resimulate_path` (the same integrator settings with
  dense output, ~2000 samples plus every integrator step).
- Success = re-simulated terminal error ≤ 1e-8 rad AND least ``sgn(Δ(R0)) Δ`` ≥ 1e-2
  on the dense path. A solver's own success flag is recorded but not used.
- Control energy ``∫_0^T |u|² dt``: composite 8-point Gauss–Legendre quadrature of
  ``controls(t)`` on 256 subintervals, split at the breakpoints (exact for
  piecewise-constant controls, to round-off for the Fourier controls).
- Goals across the singular surface: the planner must refuse them (``plan`` returns
  ``success = False`` with a reason; ``casadi_ms.solve`` raises ``ValueError``); the
  time to refuse is recorded.

Outputs (``benchmarks/results/``, or ``--out DIR``)
--------------------------------------------------
- ``compare.md``: tables per solver and band (success rate, median/max wall time,
  median terminal error, median least Δ, median energy, energy relative to the CasADi
  minimum-energy solution on goals both solved, runs whose own success flag was wrong),
  speed ratios, the rejection of the ``"across"`` goals, the failed runs; machine
  (processor, cores, versions), date and command.
- ``compare.json``: ``{"meta", "summary", "speed_ratios", "records"}``. ``records`` has
  one object per (goal, solver): ``id``, ``band``, ``start``, ``solver``, ``distance``,
  ``delta0``, ``deltad``, ``status`` (``"ok"``, ``"failed"``, ``"error"`` (the solver
  raised), ``"unavailable"``, ``"rejected"``, ``"not rejected"``), ``wall_seconds``,
  ``solver_seconds`` (the solver's own timer; IPOPT only for CasADi),
  ``solver_success``, ``reason`` (planner reason / IPOPT status / exception text),
  ``iterations``, ``solver_terminal_error``, ``solver_min_delta`` (as the solver reports
  them), ``controls`` (the returned control, ``nonholo.controls.parametrisations`` dict format) and, for
  reachable goals, the verification: ``terminal_error``, ``resim_message``,
  ``min_delta``, ``path_ok``, ``path_vs_verify`` (max entry difference between the
  dense path's endpoint and ``nonholo.certify.resimulate.resimulate``), ``energy``,
  ``verify_seconds``, ``success``; for ``"across"`` goals ``rejected``. Infinite values
  are written as the string ``"inf"``, missing ones as ``null``.
- ``compare.png``: success rate per band and solver; wall time per goal (log scale)
  per solver and band, failed runs marked.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
import traceback
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from nonholo.model import catalog
from nonholo.spaces import so3

from .goalset import load_goals
from .report import RESULTS_DIR, header_lines, machine_info, utc_now
from .report import command as command_line

DELTA_MIN = 1e-2
SUCCESS_TOL = 1e-8
RTOL = 1e-13
ATOL = 1e-13
PATH_SAMPLES = 2000
ENERGY_PIECES = 256
ENERGY_ORDER = 8
BANDS = ("near", "far", "across")
REACHABLE = ("near", "far")
DEFAULT_SOLVERS = ("robust", "paper", "casadi", "casadi-fine")

#: Solver configurations (name -> settings).
SOLVERS = {
    "robust": {"kind": "nonholo", "strategy": "robust"},
    "paper": {"kind": "nonholo", "strategy": "paper"},
    "casadi": {"kind": "casadi", "N": 40, "substeps": 2, "path_at_substeps": True},
    "casadi-fine": {"kind": "casadi", "N": 40, "substeps": 8, "path_at_substeps": True},
}

#: Warm-up problem (Example 1), not part of the goal set.
WARMUP = ((0.5, 1.2, -0.5), (1.0, 0.9, -0.5))


def _log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


# --------------------------------------------------------------------------------------
# Verification helpers
# --------------------------------------------------------------------------------------
def _segments(T: float, breakpoints) -> list[tuple[float, float]]:
    if breakpoints is None:
        return [(0.0, T)]
    b = np.unique(np.clip(np.asarray(breakpoints, dtype=float), 0.0, T))
    b = np.union1d(b, [0.0, T])
    return list(zip(b[:-1], b[1:]))


def resimulate_path(R0, controls, T: float, breakpoints=None, mechanism: str = "platform",
                    samples: int = PATH_SAMPLES, rtol: float = RTOL, atol: float = ATOL) -> dict:
    """Dense re-simulation of ``dR/dt = [L(R) u(t)] R`` (DOP853, as :func:`nonholo.certify.resimulate.resimulate`).

    Each interval between ``breakpoints`` is integrated separately with the control
    evaluated strictly inside it. Returns a dict: ``ok`` (reached ``T`` with finite
    values), ``message``, ``R_T`` (``None`` unless ``ok``), ``t`` (m,) and ``R`` (m, 3, 3):
    about ``samples`` dense-output points spread over ``[0, T]`` plus every integrator
    step, in time order (up to where the integration stopped if it failed).
    """
    mech = catalog.get(mechanism)
    L, m = mech.L, mech.n_inputs
    y = np.asarray(R0, dtype=float).ravel()
    ts, Rs = [np.array([0.0])], [y.reshape(1, 3, 3)]
    ok, message = True, "ok"
    for a, b in _segments(float(T), breakpoints):
        eps = 1e-9 * (b - a)

        def rhs(t, yy, a=a, b=b, eps=eps):
            tt = min(max(t, a + eps), b - eps)
            u = np.asarray(controls(np.array([tt])), dtype=float).reshape(m)
            R = yy.reshape(3, 3)
            return (so3.hat(L(R) @ u) @ R).ravel()

        try:
            sol = solve_ivp(rhs, (a, b), y, method="DOP853", rtol=rtol, atol=atol,
                            dense_output=True)
        except (FloatingPointError, ValueError, ZeroDivisionError) as exc:
            ok, message = False, f"integration raised {type(exc).__name__} on [{a:g}, {b:g}]: {exc}"
            break
        n = max(3, int(math.ceil(samples * (b - a) / T)))
        good = np.all(np.isfinite(sol.y), axis=0)
        tt = sol.t[good]
        ts.append(tt)
        Rs.append(sol.y[:, good].T.reshape(-1, 3, 3))
        if not sol.success or not good.all():
            ok, message = False, f"DOP853 failed on [{a:g}, {b:g}] at t = {tt[-1] if len(tt) else a:.6g}: {sol.message}"
            break
        td = np.linspace(a, b, n)
        ts.append(td)
        Rs.append(sol.sol(td).T.reshape(-1, 3, 3))
        y = sol.y[:, -1]
    t = np.concatenate(ts)
    R = np.concatenate(Rs, axis=0)
    order = np.argsort(t, kind="stable")
    return {"ok": ok, "message": message, "R_T": y.reshape(3, 3) if ok else None,
            "t": t[order], "R": R[order]}


def control_energy(controls, T: float, breakpoints=None, pieces: int = ENERGY_PIECES,
                   order: int = ENERGY_ORDER) -> float:
    """``∫_0^T |u(t)|² dt`` by composite Gauss–Legendre quadrature (split at the breakpoints)."""
    x, w = np.polynomial.legendre.leggauss(order)
    total = 0.0
    for a, b in _segments(float(T), breakpoints):
        k = max(1, int(math.ceil(pieces * (b - a) / T)))
        edges = np.linspace(a, b, k + 1)
        lo, hi = edges[:-1, None], edges[1:, None]
        t = (0.5 * (hi - lo) * x[None, :] + 0.5 * (hi + lo)).ravel()
        u = np.asarray(controls(t), dtype=float).reshape(len(t), -1)
        total += float(np.sum((0.5 * (hi - lo) * w[None, :]).ravel() * np.sum(u * u, axis=1)))
    return total


def verify_solution(goal: dict, controls, breakpoints) -> dict:
    """Terminal error (nonholo.certify.resimulate.resimulate), least sgnΔ on the dense path, energy."""
    from nonholo.certify.resimulate import resimulate, terminal_error

    R0, Rd, T = goal["R0"], goal["Rd"], goal["T"]
    out = {}
    t0 = time.perf_counter()
    try:
        RT = resimulate(R0, controls, T, breakpoints=breakpoints)
        out["terminal_error"] = terminal_error(RT, Rd)
        out["resim_message"] = "ok"
    except (RuntimeError, FloatingPointError, ValueError, ZeroDivisionError) as exc:
        RT = None
        out["terminal_error"] = math.inf
        out["resim_message"] = f"{type(exc).__name__}: {exc}"
    path = resimulate_path(R0, controls, T, breakpoints)
    sgn = float(np.sign(goal["delta0"]))
    Rp = path["R"]
    d = sgn * (Rp[:, 0, 1] * Rp[:, 2, 0] + Rp[:, 1, 0] * Rp[:, 2, 1])
    out["min_delta"] = float(np.min(d)) if path["ok"] else min(float(np.min(d)), 0.0)
    out["path_ok"] = path["ok"]
    if RT is not None and path["ok"]:
        out["path_vs_verify"] = float(np.max(np.abs(path["R_T"] - RT)))
    out["energy"] = control_energy(controls, T, breakpoints)
    out["verify_seconds"] = time.perf_counter() - t0
    out["success"] = bool(out["terminal_error"] <= SUCCESS_TOL and out["min_delta"] >= DELTA_MIN)
    return out


# --------------------------------------------------------------------------------------
# Solvers
# --------------------------------------------------------------------------------------
class Unavailable(Exception):
    pass


class NonholoSolver:
    def __init__(self, name: str, strategy: str):
        self.name = name
        self.strategy = strategy
        self.config = {"function": "nonholo.planning.api.plan", "strategy": strategy,
                       "delta_min": DELTA_MIN}
        self.warmup_seconds = None

    def warm_up(self):
        from nonholo.constraints import Clearance
        from nonholo.planning.api import plan

        R0, Rd = (so3.from_rpy(*a) for a in WARMUP)
        t0 = time.perf_counter()
        try:
            plan(R0, Rd, T=1.0, strategy=self.strategy, constraints=[Clearance(DELTA_MIN)], route="local")
        except ValueError as exc:
            if "strategy" in str(exc):
                raise Unavailable(str(exc)) from None
            raise
        self.warmup_seconds = time.perf_counter() - t0

    def prepare(self, goals: list[dict]) -> None:
        """Plan every goal now, through :func:`benchmarks.sweeps.plan_all` (timed one by one,
        resumable); :meth:`run` then reads the plans."""
        from .sweeps import plan_all

        planned = plan_all(f"compare-{self.name}", goals,
                           {"strategy": self.strategy, "delta_min": DELTA_MIN, "route": "local"})
        self.planned = {g["id"]: p for g, p in zip(goals, planned)}

    def run(self, goal: dict) -> dict:
        wall, res = self.planned.pop(goal["id"])
        rec = {"wall_seconds": wall, "solver_seconds": getattr(res, "seconds", None),
               "solver_success": bool(res.success), "reason": res.reason,
               "iterations": int(res.iterations),
               "solver_terminal_error": res.terminal_error, "solver_min_delta": res.min_delta}
        if goal["band"] == "across":
            rec["rejected"] = not res.success
            return rec
        par = getattr(res, "parametrisation", None)
        if par is not None and hasattr(par, "to_dict"):
            rec["controls"] = par.to_dict()
        rec.update(verify_solution(goal, res.controls, getattr(res, "breakpoints", None)))
        return rec


class CasadiSolver:
    def __init__(self, name: str, N: int, substeps: int, path_at_substeps: bool):
        from . import casadi_ms  # raises ImportError without casadi

        self.cms = casadi_ms
        self.name = name
        self.kw = {"N": N, "substeps": substeps, "delta_min": DELTA_MIN,
                   "path_at_substeps": path_at_substeps}
        self.config = {"function": "benchmarks.casadi_ms.solve", **self.kw,
                       "max_iter": 500, "tol": 1e-10, "expand": True}
        self.build_seconds = None
        self.warmup_seconds = None

    def warm_up(self):
        R0, Rd = (so3.from_rpy(*a) for a in WARMUP)
        t0 = time.perf_counter()
        r = self.cms.solve(R0, Rd, T=1.0, **self.kw)
        self.warmup_seconds = time.perf_counter() - t0
        self.build_seconds = r.build_seconds

    def run(self, goal: dict) -> dict:
        t0 = time.perf_counter()
        try:
            r = self.cms.solve(goal["R0"], goal["Rd"], T=goal["T"], **self.kw)
        except ValueError as exc:
            wall = time.perf_counter() - t0
            return {"wall_seconds": wall, "solver_success": False, "rejected": True,
                    "reason": f"ValueError: {exc}"}
        wall = time.perf_counter() - t0
        rec = {"wall_seconds": wall, "solver_seconds": r.seconds, "build_seconds": r.build_seconds,
               "solver_success": bool(r.success), "reason": r.status,
               "iterations": int(r.iterations),
               "solver_terminal_error": r.terminal_violation, "solver_min_delta": r.min_delta,
               "controls": {"kind": "piecewise_constant", "T": r.T, "grid": int(r.N),
                            "values": np.asarray(r.u).tolist()}}
        if goal["band"] == "across":
            rec["rejected"] = False
            return rec
        rec.update(verify_solution(goal, r.controls, r.t_grid))
        return rec


def make_solver(name: str):
    cfg = SOLVERS[name]
    if cfg["kind"] == "nonholo":
        return NonholoSolver(name, cfg["strategy"])
    return CasadiSolver(name, cfg["N"], cfg["substeps"], cfg["path_at_substeps"])


# --------------------------------------------------------------------------------------
# Statistics
# --------------------------------------------------------------------------------------
def _median(xs):
    xs = [x for x in xs if x is not None and not (isinstance(x, float) and math.isnan(x))]
    return float(np.median(xs)) if xs else None


def _max(xs):
    xs = [x for x in xs if x is not None]
    return float(np.max(xs)) if xs else None


def summarise(records: list[dict], solvers: list[str]) -> dict:
    """Per solver and band: counts, success rate, times, errors, least Δ, energy."""
    out = {}
    for s in solvers:
        out[s] = {}
        for band in BANDS:
            rs = [r for r in records if r["solver"] == s and r["band"] == band
                  and r["status"] not in ("unavailable", "skipped")]
            if not rs:
                continue
            st = {"n": len(rs), "errors": sum(r["status"] == "error" for r in rs)}
            walls = [r.get("wall_seconds") for r in rs]
            st["median_wall"] = _median(walls)
            st["max_wall"] = _max(walls)
            if band == "across":
                st["rejected"] = sum(bool(r.get("rejected")) for r in rs)
                st["all_rejected"] = st["rejected"] == len(rs)
            else:
                ok = [r for r in rs if r.get("success")]
                st["success"] = len(ok)
                st["rate"] = len(ok) / len(rs)
                st["claimed"] = sum(bool(r.get("solver_success")) for r in rs)
                st["claimed_but_failed"] = sum(bool(r.get("solver_success")) and not r.get("success")
                                               for r in rs)
                st["median_wall_success"] = _median([r["wall_seconds"] for r in ok])
                st["median_terminal_error"] = _median([r.get("terminal_error") for r in rs])
                st["median_min_delta"] = _median([r.get("min_delta") for r in rs])
                st["median_energy_success"] = _median([r.get("energy") for r in ok])
            out[s][band] = st
    # energy relative to the CasADi minimum-energy solutions, on goals both solved
    ref = next((c for c in ("casadi-fine", "casadi") if c in solvers), None)
    if ref is not None:
        e_ref = {r["id"]: r["energy"] for r in records
                 if r["solver"] == ref and r.get("success") and r.get("energy")}
        for s in solvers:
            for band in REACHABLE:
                if band not in out[s]:
                    continue
                ratios = [r["energy"] / e_ref[r["id"]] for r in records
                          if r["solver"] == s and r["band"] == band and r.get("success")
                          and r["id"] in e_ref]
                out[s][band]["energy_ratio_ref"] = ref
                out[s][band]["median_energy_ratio"] = _median(ratios)
                out[s][band]["energy_ratio_n"] = len(ratios)
    return out


def speed_ratios(summary: dict) -> dict:
    """Median wall time of each CasADi solver over that of ``robust`` (and ``paper``), per band.

    Keys ``"<casadi solver>/<planner>/<band>"`` (medians over all runs) and
    ``"<casadi solver>/<planner> (successes)/<band>"`` (medians over each solver's
    successful runs).
    """
    out = {}
    for c in [s for s in summary if SOLVERS[s]["kind"] == "casadi"]:
        for base in ("robust", "paper"):
            if base not in summary:
                continue
            for band in REACHABLE:
                for key, suffix in (("median_wall", ""), ("median_wall_success", " (successes)")):
                    a = summary[c].get(band, {}).get(key)
                    b = summary[base].get(band, {}).get(key)
                    if a and b:
                        out[f"{c}/{base}{suffix}/{band}"] = a / b
    return out


# --------------------------------------------------------------------------------------
# Reports
# --------------------------------------------------------------------------------------
def _fmt(x, spec=".3g", none="–"):
    if x is None:
        return none
    if isinstance(x, float) and math.isinf(x):
        return "inf"
    return format(x, spec)


def _ms(x):
    return _fmt(None if x is None else 1e3 * x, ".1f")


def write_markdown(path: Path, meta: dict, summary: dict, ratios: dict, records: list[dict]) -> None:
    L = header_lines("Planner comparison on the benchmark goal set", meta["command"], meta["date"],
                     meta["machine"])
    L.pop()                         # the header's closing blank line: the list goes on
    L.append(f"- Goals: `{meta['goals_file']}`, bands {', '.join(meta['bands'])} "
             f"({', '.join(f'{b}: {n}' for b, n in meta['goal_counts'].items())})"
             + (f", at most {meta['limit']} per band" if meta.get("limit") else ""))
    L.append(f"- Total run time: {meta['total_seconds']:.0f} s")
    L.append("")
    L.append("## Solvers")
    L.append("")
    for s, info in meta["solvers"].items():
        line = f"- **{s}**: " + ", ".join(f"{k}={v}" for k, v in info["config"].items())
        if info.get("unavailable"):
            line += f" — **unavailable**: {info['unavailable']}"
        else:
            line += f"; warm-up {info['warmup_seconds']:.2f} s"
            if info.get("build_seconds") is not None:
                line += f" (of which NLP build {info['build_seconds']:.2f} s, excluded from all solve times)"
        L.append(line)
    L.append("")
    L.append("Success = re-simulated terminal error ≤ 1e-8 rad (nonholo.certify.resimulate.resimulate, DOP853, "
             "rtol = atol = 1e-13) and least sgn(Δ(R0))·Δ ≥ 0.01 on the dense re-simulated path. "
             "Wall time: the solver call only, after warm-up, all runs (successful or not). "
             "Terminal error and least Δ: medians over all runs; energy ∫|u|² dt: median over "
             "successful runs. \"Claimed ✗\": runs whose own success flag was set but which fail "
             "the check above.")
    L.append("")
    L.append("## Reachable goals")
    L.append("")
    L.append("| solver | band | n | success | rate | median wall [ms] | max wall [ms] | "
             "median wall, successes [ms] | median terminal error [rad] | median min Δ | "
             "median energy | energy / min-energy | claimed ✗ |")
    L.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for s, bands in summary.items():
        for band in REACHABLE:
            st = bands.get(band)
            if not st:
                continue
            er = st.get("median_energy_ratio")
            er_s = "–" if er is None else f"{er:.2f} ({st['energy_ratio_n']} goals, vs {st['energy_ratio_ref']})"
            L.append(f"| {s} | {band} | {st['n']} | {st['success']} | {100 * st['rate']:.0f}% | "
                     f"{_ms(st['median_wall'])} | {_ms(st['max_wall'])} | "
                     f"{_ms(st['median_wall_success'])} | {_fmt(st['median_terminal_error'], '.2e')} | "
                     f"{_fmt(st['median_min_delta'], '.3f')} | {_fmt(st['median_energy_success'], '.3f')} | "
                     f"{er_s} | {st['claimed_but_failed']} |")
    unavailable = [s for s, info in meta["solvers"].items() if info.get("unavailable")]
    if unavailable:
        L.append("")
        L.append(f"Not run (unavailable): {', '.join(unavailable)}.")
    if ratios:
        L.append("")
        L.append("Speed ratio: median wall time of the CasADi solver / median wall time of the "
                 "nonholo planner (over all runs, and over each solver's successful runs):")
        L.append("")
        L.append("| ratio | " + " | ".join(REACHABLE) + " |")
        L.append("|---|" + "---|" * len(REACHABLE))
        pairs = sorted({k.rsplit("/", 1)[0] for k in ratios})
        for p in pairs:
            L.append(f"| {p.replace('/', ' / ')} | "
                     + " | ".join(_fmt(ratios.get(f"{p}/{b}"), ".1f") for b in REACHABLE) + " |")
    if any("across" in b for b in summary.values()):
        L.append("")
        L.append("## Goals across the singular surface (unreachable)")
        L.append("")
        L.append("| solver | n | rejected | all rejected | median time to reject [ms] | max [ms] |")
        L.append("|---|---|---|---|---|---|")
        for s, bands in summary.items():
            st = bands.get("across")
            if st:
                L.append(f"| {s} | {st['n']} | {st['rejected']} | {'yes' if st['all_rejected'] else 'NO'} | "
                         f"{_fmt(None if st['median_wall'] is None else 1e3 * st['median_wall'], '.3f')} | "
                         f"{_fmt(None if st['max_wall'] is None else 1e3 * st['max_wall'], '.3f')} |")
        ex = {}
        for r in records:
            if r["band"] == "across" and r.get("reason") and r["solver"] not in ex:
                ex[r["solver"]] = r["reason"]
        if ex:
            L.append("")
            L.append("Example reasons:")
            L.append("")
            for s, reason in ex.items():
                L.append(f"- {s}: {reason}")
    fails = [r for r in records if r["band"] in REACHABLE and r["status"] in ("failed", "error")]
    if fails:
        L.append("")
        L.append("## Failed runs")
        L.append("")
        L.append("| goal | solver | terminal error | min Δ | solver says | reason |")
        L.append("|---|---|---|---|---|---|")
        for r in fails:
            reason = str(r.get("reason") or r.get("exception") or "").replace("|", "\\|").replace("\n", " ")
            if len(reason) > 160:
                reason = reason[:157] + "..."
            L.append(f"| {r['id']} | {r['solver']} | {_fmt(r.get('terminal_error'), '.1e')} | "
                     f"{_fmt(r.get('min_delta'), '.3f')} | "
                     f"{'success' if r.get('solver_success') else 'failure'} | {reason} |")
    L.append("")
    path.write_text("\n".join(L))


def write_figure(path: Path, summary: dict, records: list[dict], solvers: list[str]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    run = [s for s in solvers if s in summary and summary[s]]
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.6))
    width = 0.8 / max(1, len(run))
    bands = [b for b in REACHABLE if any(b in summary[s] for s in run)]
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, s in enumerate(run):
        rates = [100 * summary[s][b]["rate"] if b in summary[s] else 0 for b in bands]
        x = np.arange(len(bands)) + (i - (len(run) - 1) / 2) * width
        bars = ax1.bar(x, rates, width, label=s, color=colors[i % len(colors)])
        for bx, r in zip(bars, rates):
            ax1.text(bx.get_x() + bx.get_width() / 2, r + 1, f"{r:.0f}", ha="center", fontsize=8)
    ax1.set_xticks(np.arange(len(bands)))
    ax1.set_xticklabels([f"{b}\n({summary[run[0]][b]['n'] if run and b in summary[run[0]] else 0} goals)"
                         for b in bands])
    ax1.set_ylim(0, 125)
    ax1.set_ylabel("success rate [%]")
    ax1.set_title("Verified success (re-simulated error ≤ 1e-8 rad, min Δ ≥ 0.01)")
    ax1.legend(fontsize=8, loc="upper center", ncol=max(1, len(run)), frameon=False)

    rng = np.random.default_rng(0)
    markers = {"near": "o", "far": "s", "across": "x"}
    pos = 0
    ticks = []
    for i, s in enumerate(run):
        for b in [b for b in BANDS if b in summary[s]]:
            w = np.array([r["wall_seconds"] for r in records if r["solver"] == s and r["band"] == b
                          and r.get("wall_seconds") is not None])
            if len(w) == 0:
                continue
            succ = np.array([bool(r.get("success")) or (b == "across" and bool(r.get("rejected")))
                             for r in records if r["solver"] == s and r["band"] == b
                             and r.get("wall_seconds") is not None])
            ax2.boxplot(w, positions=[pos], widths=0.6, showfliers=False,
                        medianprops={"color": "k"})
            jit = pos + rng.uniform(-0.2, 0.2, len(w))
            c = colors[i % len(colors)]
            ax2.scatter(jit[succ], w[succ], s=9, marker=markers[b], color=c, alpha=0.6, zorder=3)
            if (~succ).any():
                ax2.scatter(jit[~succ], w[~succ], s=16, marker="x", color="red", alpha=0.8, zorder=4)
            ticks.append((pos, f"{s}\n{b}"))
            pos += 1
        pos += 0.5
    if ticks:
        ax2.set_xticks([p for p, _ in ticks])
        ax2.set_xticklabels([t for _, t in ticks], fontsize=7, rotation=45, ha="right")
    ax2.set_yscale("log")
    ax2.set_ylabel("wall time per goal [s] (log scale)")
    ax2.set_title("Wall time after warm-up (red x: failed; across: time to reject)")
    ax2.grid(True, which="both", axis="y", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


# --------------------------------------------------------------------------------------
# Driver
# --------------------------------------------------------------------------------------
def select_goals(goals: list[dict], bands, limit: int | None) -> list[dict]:
    """Goals of ``bands``, round-robin over the starts so that a ``limit`` covers every start."""
    out = []
    for band in bands:
        gs = [g for g in goals if g["band"] == band]
        by_start = {}
        for g in gs:
            by_start.setdefault(g["start"], []).append(g)
        rr = []
        k = 0
        while len(rr) < len(gs):
            for s in sorted(by_start):
                if k < len(by_start[s]):
                    rr.append(by_start[s][k])
            k += 1
        out += rr[:limit] if limit else rr
    return out


def _jsonable(x):
    if isinstance(x, dict):
        return {k: _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        x = float(x)
        return None if math.isnan(x) else ("inf" if math.isinf(x) else x)
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    return x


def _progress_line(i: int, n: int, goal: dict, recs: list[dict]) -> str:
    parts = []
    for r in recs:
        if r["status"] == "unavailable":
            continue
        if goal["band"] == "across":
            parts.append(f"{r['solver']}: {'rejected' if r.get('rejected') else 'NOT rejected'} "
                         f"{1e3 * r['wall_seconds']:.2f} ms")
        elif r["status"] == "error":
            parts.append(f"{r['solver']}: ERROR {r.get('exception', '')[:60]}")
        else:
            parts.append(f"{r['solver']}: {'ok' if r['success'] else 'FAIL'} "
                         f"{r['wall_seconds']:.3f} s err {_fmt(r.get('terminal_error'), '.1e')}")
    return f"[{i}/{n}] {goal['id']:14s} " + " | ".join(parts)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.compare",
                                 description="Compare nonholo planners with CasADi/IPOPT on the goal set.")
    ap.add_argument("--limit", type=int, default=None, help="at most N goals per band (spread over the starts)")
    ap.add_argument("--bands", nargs="+", default=list(BANDS), choices=BANDS)
    ap.add_argument("--solvers", nargs="+", default=list(DEFAULT_SOLVERS), choices=list(SOLVERS))
    ap.add_argument("--goals", type=Path, default=None, help="goal file (default benchmarks/goals.json)")
    ap.add_argument("--out", type=Path, default=RESULTS_DIR, help="output directory (default %(default)s)")
    ap.add_argument("--set", choices=("goals", "random"), default="goals",
                    help="goals: benchmarks/goals.json (compare.md); random: the uniform random band set, "
                         "the default plan() on every pair and its peers on a subset (global.md, "
                         "benchmarks.random_set)")
    ap.add_argument("--per-band", type=int, default=500, help="random set: pairs per band and mechanism")
    ap.add_argument("--peer-pairs", type=int, default=15, help="random set: platform pairs per band for the peers")
    ap.add_argument("--peers", nargs="*", default=["nonholo-local", "casadi", "ompl"],
                    choices=["nonholo-local", "casadi", "ompl"], help="random set: the peers to run")
    args = ap.parse_args(argv)
    if args.set == "random":
        from . import random_set

        return random_set.main(argv, args.per_band, args.peer_pairs, args.peers, args.out)
    command = command_line("benchmarks.compare", argv)
    t_all = time.perf_counter()

    goals_all = load_goals(args.goals)
    goals = select_goals(goals_all, args.bands, args.limit)
    _log(f"{len(goals)} goals ({', '.join(args.bands)}), solvers: {', '.join(args.solvers)}")

    solvers, meta_solvers = {}, {}
    for name in args.solvers:
        cfg = SOLVERS[name]
        try:
            solver = make_solver(name)
        except ImportError as exc:
            _log(f"{name}: skipped ({exc}); install casadi to include it")
            meta_solvers[name] = {"config": {k: v for k, v in cfg.items() if k != "kind"},
                                  "unavailable": f"not installed: {exc}"}
            continue
        _log(f"{name}: warming up ...")
        try:
            solver.warm_up()
        except Unavailable as exc:
            _log(f"{name}: unavailable ({exc})")
            meta_solvers[name] = {"config": solver.config, "unavailable": str(exc)}
            continue
        solvers[name] = solver
        meta_solvers[name] = {"config": solver.config, "warmup_seconds": solver.warmup_seconds,
                              "build_seconds": getattr(solver, "build_seconds", None)}
        _log(f"{name}: warm-up {solver.warmup_seconds:.2f} s"
             + (f" (NLP build {solver.build_seconds:.2f} s)" if getattr(solver, "build_seconds", None) else ""))

    for name, solver in solvers.items():
        if hasattr(solver, "prepare"):
            _log(f"{name}: planning every goal ...")
            solver.prepare(goals)
    records = []
    for i, goal in enumerate(goals, 1):
        recs = []
        for name in args.solvers:
            base = {"id": goal["id"], "band": goal["band"], "start": goal["start"], "solver": name,
                    "distance": goal["distance"], "delta0": goal["delta0"], "deltad": goal["deltad"]}
            if name not in solvers:
                recs.append({**base, "status": "unavailable"})
                continue
            try:
                rec = solvers[name].run(goal)
            except Exception as exc:  # a crash is a failed run, keep going
                rec = {"wall_seconds": None, "exception": f"{type(exc).__name__}: {exc}",
                       "traceback": traceback.format_exc(limit=5), "success": False}
                rec["status"] = "error"
            else:
                if goal["band"] == "across":
                    rec["status"] = "rejected" if rec.get("rejected") else "not rejected"
                else:
                    rec["status"] = "ok" if rec["success"] else "failed"
            recs.append({**base, **rec})
        records += recs
        _log(_progress_line(i, len(goals), goal, recs))

    run_solvers = [s for s in args.solvers if s in solvers]
    summary = summarise(records, run_solvers)
    ratios = speed_ratios(summary)
    total = time.perf_counter() - t_all
    counts = {}
    for g in goals:
        counts[g["band"]] = counts.get(g["band"], 0) + 1
    meta = {
        "date": utc_now(),
        "command": command,
        "machine": machine_info(("casadi",)),
        "goals_file": str(args.goals or "benchmarks/goals.json"),
        "bands": args.bands,
        "limit": args.limit,
        "goal_counts": counts,
        "solvers": meta_solvers,
        "criteria": {"terminal_error_max": SUCCESS_TOL, "min_delta": DELTA_MIN,
                     "resimulation": "nonholo.certify.resimulate.resimulate (DOP853, rtol=atol=1e-13)",
                     "dense_path_samples": PATH_SAMPLES},
        "total_seconds": total,
    }
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "compare.json").write_text(json.dumps(
        _jsonable({"meta": meta, "summary": summary, "speed_ratios": ratios, "records": records}),
        indent=1, allow_nan=False) + "\n")
    write_markdown(args.out / "compare.md", meta, summary, ratios, records)
    if run_solvers:
        write_figure(args.out / "compare.png", summary, records, run_solvers)
    _log(f"wrote {args.out / 'compare.md'}, compare.json, compare.png ({total:.0f} s)")
    for s in run_solvers:
        for band, st in summary[s].items():
            if band == "across":
                _log(f"  {s:12s} {band:6s} rejected {st['rejected']}/{st['n']}, "
                     f"median {1e3 * st['median_wall']:.2f} ms")
            else:
                _log(f"  {s:12s} {band:6s} {st['success']}/{st['n']} ok, median wall "
                     f"{1e3 * st['median_wall']:.1f} ms, median error {_fmt(st['median_terminal_error'], '.1e')}")
    for k, v in ratios.items():
        _log(f"  speed ratio {k}: {v:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
