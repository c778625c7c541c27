"""Plans under the legs' stroke limits: ``nonholo.plan(..., constraints=[LegStroke(lo, hi)])`` against
CasADi/IPOPT with the same limits, on ``benchmarks/goals.json``.

Run::

    python -m benchmarks.limits [--lo 1.2 --hi 2.0] [--leg-speed 0.5] [--no-casadi]

The goals: the platform's reachable goals of ``benchmarks/goals.json`` whose start and
goal both have every leg inside ``[lo, hi]``. Solvers, each timed per call after one
warm-up call (numba compiled, the NLP built):

- ``nonholo``: :func:`nonholo.plan` with its defaults and ``constraints=[Clearance(0.01),
  LegStroke(lo, hi)]``;
- ``casadi``: :func:`benchmarks.casadi_ms.solve` (minimum ``∫|u|² dt``, the setting of
  :mod:`benchmarks.compare`'s ``casadi``: 40 intervals, 2 substeps, the Δ constraint at
  the substeps) with ``leg_length=(lo, hi)`` at its nodes;
- ``nonholo (no limits)``: :func:`nonholo.plan` without limits, to show how often the
  limits bind.

Every claimed success is re-simulated by DOP853 (rtol = atol = 1e-13) with a dense path
(:func:`nonholo.certify.resimulate.resimulate_path`): *solved* = final error ≤ 1e-8 rad, ``sgnΔ ≥
delta_min`` and every leg inside ``[lo, hi]`` at every point of the path, the leg lengths
computed from the platform's numeric geometry (``|R tip_i − base_i|``).

Then the legs' speeds (:func:`run_retiming`, :func:`run_speed_peers`): goals planned and
re-timed by :func:`nonholo.planning.retime` in the least time under ``--leg-speed``, each re-timed
motion re-simulated against the bound and the plan's end; and the same goals in a given
time by ``plan(..., constraints=[LegSpeed(v)])`` and the CasADi baseline with the same bound. And the
least energy (:func:`run_energy`): ``plan(..., objective="energy")`` against the
baseline's fine setting on every reachable goal, in the same run.

Writes ``benchmarks/results/limits.md`` and ``limits.json``.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time

import numpy as np

from nonholo.constraints import Clearance, LegSpeed, LegStroke
from nonholo.model import catalog
from nonholo.planning.api import plan
from nonholo.spaces import so3
from nonholo.certify.resimulate import resimulate_path, terminal_error
from nonholo.planning.energy_objective import controls_energy
from nonholo.planning.energy_search import ENERGY_GRID
from nonholo.planning.retime import retime

from . import goalset
from .report import RESULTS_DIR, Report

#: Stroke limits of the acceptance (the geometry's units: the base joints at 1.6, the
#: platform joints at 1 from the centre; legs span 0.6 … 2.6).
LIMITS = (1.2, 2.0)
DELTA_MIN = 1e-2
#: The re-simulated motion must end this close to the goal (rad).
SUCCESS_TOL = 1e-8
#: The legs' speed bound of the re-timing section (geometry units per second) and its goals.
LEG_SPEED = 0.5
SPEED_GOALS = 20
#: The given time of the speed comparison, over the path's least time.
STRETCH = 1.25
#: The example used to warm each solver up.
WARMUP = ((0.5, 1.2, -0.5), (1.0, 0.9, -0.5))


def _log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def goals_inside(limits) -> list[dict]:
    """The reachable goals of ``goals.json`` whose start and goal keep every leg inside ``limits``."""
    geom = catalog.get("platform").geometry
    out = []
    for g in goalset.load_goals():
        if g["band"] == "across":
            continue
        R0, Rd = np.array(g["R0"]), np.array(g["Rd"])
        ends = np.concatenate([geom.leg_lengths(R0), geom.leg_lengths(Rd)])
        if limits[0] <= ends.min() and ends.max() <= limits[1]:
            out.append({**g, "R0": R0, "Rd": Rd})
    return out


def check(goal: dict, controls, breakpoints, T: float, limits) -> dict:
    """DOP853 with a dense path: final error, least ``sgnΔ`` and least clearance from the
    stroke limits (a failed integration: infinitely far, on ``Δ = 0``)."""
    mech = catalog.get("platform")
    try:
        _, R, d = resimulate_path(goal["R0"], controls, T, mech, breakpoints)
    except (RuntimeError, FloatingPointError, ValueError, ZeroDivisionError):
        return {"final_error": math.inf, "least_delta": 0.0, "least_clearance": -math.inf}
    lengths = mech.geometry.leg_lengths(R)
    sign = float(np.sign(mech.delta(goal["R0"])))
    return {"final_error": terminal_error(R[-1], goal["Rd"]), "least_delta": float(np.min(sign * d)),
            "least_clearance": float(min(lengths.min() - limits[0], limits[1] - lengths.max()))}


def _solved(c: dict | None) -> bool:
    return (c is not None and c["final_error"] <= SUCCESS_TOL and c["least_delta"] >= DELTA_MIN
            and c["least_clearance"] >= 0.0)


def run_nonholo(goals, limits, label: str, enforce: bool = True) -> list[dict]:
    """:func:`nonholo.plan` on every goal, with ``LegStroke(*limits)`` if ``enforce``; the
    checks measure the clearance from ``limits`` either way."""
    constraints = [Clearance(DELTA_MIN)] + ([LegStroke(*limits)] if enforce else [])
    plan(so3.from_rpy(*WARMUP[0]), so3.from_rpy(*WARMUP[1]), constraints=constraints)
    timed = []
    for g in goals:
        t = time.perf_counter()
        res = plan(g["R0"], g["Rd"], T=g["T"], constraints=constraints)
        timed.append((time.perf_counter() - t, res))
    out = []
    for g, (wall, res) in zip(goals, timed):
        c = check(g, res.controls, res.breakpoints, res.T, limits) if res.success else None
        out.append({"solver": label, "id": g["id"], "seconds": wall, "claimed": bool(res.success),
                    "solved": _solved(c), "route": res.route, "reason": res.reason[-300:], "check": c})
    return out


def run_casadi(goals, limits) -> list[dict]:
    from . import casadi_ms

    kw = {"N": 40, "substeps": 2, "delta_min": DELTA_MIN, "path_at_substeps": True, "leg_length": limits}
    casadi_ms.solve(so3.from_rpy(*WARMUP[0]), so3.from_rpy(*WARMUP[1]), T=1.0, **kw)
    out = []
    for g in goals:
        t = time.perf_counter()
        r = casadi_ms.solve(g["R0"], g["Rd"], T=g["T"], **kw)
        wall = time.perf_counter() - t
        c = check(g, r.controls, r.t_grid, r.T, limits)
        out.append({"solver": "casadi", "id": g["id"], "seconds": wall, "claimed": bool(r.success),
                    "solved": _solved(c), "reason": r.status, "check": c, "energy": r.objective})
    return out


def speed_goals(count: int) -> list[dict]:
    """``count`` reachable goals of ``goals.json``, spread over the file (both bands)."""
    reachable = [g for g in goalset.load_goals() if g["band"] != "across"]
    picked = reachable[::max(1, len(reachable) // count)][:count]
    return [{**g, "R0": np.array(g["R0"]), "Rd": np.array(g["Rd"])} for g in picked]


def speed_check(R0, controls, breakpoints, T: float, v: float) -> dict:
    """DOP853 with a dense path: the end orientation, the largest leg speed over ``v`` minus
    1, and the least — over the samples not on a breakpoint — of the fastest leg's speed
    over ``v`` (1 when the fastest leg is at the bound throughout)."""
    mech = catalog.get("platform")
    t, R, d = resimulate_path(R0, controls, T, mech, breakpoints, samples=4001)
    fastest = np.abs(mech.leg_speeds(R, controls(t))).max(axis=1) / v
    away = np.ones(len(t), bool) if breakpoints is None else (
        np.min(np.abs(t[:, None] - np.asarray(breakpoints)[None, :]), axis=1) > 1e-9)
    return {"R_T": R[-1], "excess": float(fastest.max() - 1.0), "least": float(fastest[away].min()),
            "least_delta": float(np.min(np.sign(mech.delta(R0)) * d))}


def run_retiming(goals, v: float) -> list[dict]:
    """Every goal planned by :func:`nonholo.plan`, then re-timed in the least time
    (:func:`nonholo.planning.retime`), the re-timing timed alone (after a warm-up call); each
    re-timed plan re-simulated by DOP853 against the plan's own end and the bound."""
    plans = [plan(g["R0"], g["Rd"], T=g["T"], constraints=[Clearance(DELTA_MIN)]) for g in goals]
    retime(plans[0], v)
    out = []
    for g, res in zip(goals, plans):
        if not res.success:
            out.append({"id": g["id"], "planned": False, "reason": res.reason[-200:]})
            continue
        t = time.perf_counter()
        fast = retime(res, v)
        wall = time.perf_counter() - t
        c = speed_check(g["R0"], fast.controls, fast.breakpoints, fast.T, v)
        out.append({"id": g["id"], "planned": True, "seconds": wall, "seconds_ms": 1e3 * wall, "T_planned": res.T, "T_least": fast.T,
                    "excess": c["excess"], "least": c["least"],
                    "end_vs_plan": terminal_error(c["R_T"], res.R[-1]),
                    "final_error": terminal_error(c["R_T"], g["Rd"])})
    return out


def run_speed_peers(goals, v: float, stretch: float, least: dict, casadi: bool) -> list[dict]:
    """``plan(R0, Rd, T, constraints=[LegSpeed(v)])`` and, if ``casadi``, the baseline with the same bound,
    in ``T = stretch ×`` the goal's least time under ``v`` (``least``: by goal id);
    re-simulated by DOP853: *solved* = final error ≤ SUCCESS_TOL, sgnΔ ≥ delta_min and no
    leg faster than ``v (1 + 1e-6)`` at the samples (the baseline's piecewise-constant
    controls are bounded at its nodes only: between them its speeds are checked too)."""
    out = []
    solvers = [("nonholo", None)]
    if casadi:
        from . import casadi_ms

        kw = {"N": 40, "substeps": 2, "delta_min": DELTA_MIN, "path_at_substeps": True, "leg_speed": v}
        casadi_ms.solve(so3.from_rpy(*WARMUP[0]), so3.from_rpy(*WARMUP[1]), T=2.0, **kw)
        solvers.append(("casadi", lambda g, T: casadi_ms.solve(g["R0"], g["Rd"], T=T, **kw)))
    plan(so3.from_rpy(*WARMUP[0]), so3.from_rpy(*WARMUP[1]), T=2.0, constraints=[LegSpeed(v)])
    for g in goals:
        if g["id"] not in least:
            continue
        T = stretch * least[g["id"]]
        for name, call in solvers:
            t = time.perf_counter()
            if call is None:
                res = plan(g["R0"], g["Rd"], T=T, constraints=[Clearance(DELTA_MIN), LegSpeed(v)])
                claimed, controls, bps, reason = res.success, res.controls, res.breakpoints, res.reason
            else:
                res = call(g, T)
                claimed, controls, bps, reason = res.success, res.controls, res.t_grid, res.status
            wall = time.perf_counter() - t
            c, solved = None, False
            if claimed:
                try:
                    c = speed_check(g["R0"], controls, bps, T, v)
                    solved = (terminal_error(c["R_T"], g["Rd"]) <= SUCCESS_TOL and c["excess"] <= 1e-6
                              and c["least_delta"] >= DELTA_MIN)
                except (RuntimeError, ValueError, FloatingPointError):
                    c = None
            out.append({"solver": name, "id": g["id"], "T": T, "seconds": wall, "claimed": bool(claimed),
                        "solved": solved, "reason": reason[-200:],
                        "excess": None if c is None else c["excess"]})
    return out


def run_energy(goals, casadi: bool) -> list[dict]:
    """``plan(R0, Rd, T, objective="energy")`` and the CasADi baseline's fine setting (minimum
    energy, 40 intervals, 8 substeps, Δ at the substeps: ``casadi-fine`` of
    :mod:`benchmarks.compare`) on every goal, timed per call after a warm-up call, each
    claimed success re-simulated by DOP853 (dense path): *solved* = final error ≤
    SUCCESS_TOL and sgnΔ ≥ delta_min; the energy of the returned controls by quadrature."""
    solvers = [("nonholo energy", lambda g: plan(g["R0"], g["Rd"], T=g["T"], constraints=[Clearance(DELTA_MIN)],
                                                 objective="energy"))]
    if casadi:
        from . import casadi_ms

        kw = {"N": 40, "substeps": 8, "delta_min": DELTA_MIN, "path_at_substeps": True, "max_iter": 500,
              "tol": 1e-10}
        solvers.append(("casadi-fine", lambda g: casadi_ms.solve(g["R0"], g["Rd"], T=g["T"], **kw)))
    out = []
    for name, call in solvers:
        call({"R0": so3.from_rpy(*WARMUP[0]), "Rd": so3.from_rpy(*WARMUP[1]), "T": 1.0})
        for g in goals:
            t = time.perf_counter()
            try:
                res = call(g)
            except ValueError as exc:
                out.append({"solver": name, "id": g["id"], "seconds": time.perf_counter() - t,
                            "claimed": False, "solved": False, "reason": str(exc)[-200:], "energy": None})
                continue
            wall = time.perf_counter() - t
            bps = res.breakpoints if name.startswith("nonholo") else res.t_grid
            c = check(g, res.controls, bps, res.T, (0.0, math.inf)) if res.success else None
            solved = c is not None and c["final_error"] <= SUCCESS_TOL and c["least_delta"] >= DELTA_MIN
            out.append({"solver": name, "id": g["id"], "seconds": wall, "claimed": bool(res.success),
                        "solved": solved, "energy": controls_energy(res.controls, bps, res.T) if solved else None,
                        "reason": (res.reason if name.startswith("nonholo") else res.status)[-200:]})
        _log(f"{name} done")
    return out


def energy_section(rep: Report, records: list[dict], n_goals: int) -> None:
    rep.heading("Minimum energy")
    by = by_solver(records)
    rep.paragraph(
        f"The {n_goals} reachable goals of `benchmarks/goals.json` (bands near and far), no stroke or speed "
        "limits: `plan(R0, Rd, T, objective=\"energy\")` (the default plan, then its energy lowered on "
        f"{ENERGY_GRID} piecewise-constant intervals) against the CasADi baseline's fine setting "
        "(`casadi-fine` of `benchmarks/compare.py`: minimum energy, 40 intervals, 8 substeps). Both timed per "
        "call after a warm-up call, in this run; every claimed success re-simulated by DOP853 (dense path): "
        f"*solved* = final error ≤ {SUCCESS_TOL:g} rad and sgnΔ ≥ {DELTA_MIN:g}; energy ∫|u|² dt of the "
        "returned controls by Gauss–Legendre quadrature between their breakpoints.")
    rep.table(["solver", "goals", "claimed", "solved", "false claims", "median ms", "p95 ms", "max ms"],
              [[name, *summary(rs)] for name, rs in by.items()])
    if "casadi-fine" in by:
        ours = {r["id"]: r for r in by["nonholo energy"]}
        both = [(ours[r["id"]]["energy"], r["energy"]) for r in by["casadi-fine"]
                if r["solved"] and ours[r["id"]]["solved"]]
        ratio = np.array([a / b for a, b in both])
        med = {k: float(np.median([r["seconds"] for r in by[k]])) for k in by}
        lower = int(np.sum(ratio <= 1.0 + 1e-9))
        rep.table(["goals both solve", "median energy ratio", "min", "max", "ratio ≤ 1", "median time ratio"],
                  [[len(both), f"{np.median(ratio):.6f}", f"{ratio.min():.6f}", f"{ratio.max():.6f}",
                    f"{lower} of {len(both)}", f"{med['casadi-fine'] / med['nonholo energy']:.1f}×"]])
        rep.paragraph("Energy ratio: nonholo's over casadi-fine's, per goal both solve; time ratio: casadi-fine's "
                      "median wall time over nonholo's (every goal, same run).")


def by_solver(records: list[dict]) -> dict[str, list[dict]]:
    """The records grouped by their ``solver``, in order of appearance."""
    by: dict[str, list[dict]] = {}
    for r in records:
        by.setdefault(r["solver"], []).append(r)
    return by


def _ms(x) -> str:
    return "–" if x is None else f"{1e3 * x:.1f}"


def summary(records: list[dict]) -> list:
    ts = [r["seconds"] for r in records]
    false = sum(r["claimed"] and not r["solved"] for r in records)
    return [len(records), sum(r["claimed"] for r in records), sum(r["solved"] for r in records), false,
            _ms(float(np.median(ts))), _ms(float(np.quantile(ts, 0.95))), _ms(max(ts))]


def speed_section(rep: Report, timed: list[dict], peers: list[dict], v: float) -> None:
    rep.heading("Leg speeds: re-timing")
    done = [r for r in timed if r["planned"]]
    rep.paragraph(
        f"{len(timed)} reachable goals of `benchmarks/goals.json`, spread over the file, planned by `plan` "
        f"(defaults) and re-timed by `nonholo.retime(result, leg_speed={v:g})` in the least time "
        f"({len(done)} planned). Each re-timed plan re-simulated by DOP853 (rtol = atol = 1e-13, dense path, "
        "4001 samples and every step): *largest speed* = the largest |dl_i/dt| over v, minus 1; *fastest leg "
        "at least* = the least, over the samples off the breakpoints, of the fastest leg's speed over v; "
        "*end vs plan* = the angle between the re-timed motion's end and the plan's certified end.")
    if done:
        worst = max(abs(r["excess"]) for r in done)
        rows = [["median", *(_fmt(float(np.median([r[k] for r in done])), f) for k, f in _SPEED_COLS)],
                ["worst", _fmt(max(r["T_planned"] for r in done), ".3g"),
                 _fmt(max(r["T_least"] for r in done), ".4g"), _fmt(max(r["seconds"] for r in done) * 1e3, ".2f"),
                 _fmt(max(r["excess"] for r in done), ".2e"), _fmt(min(r["least"] for r in done), ".7f"),
                 _fmt(max(r["end_vs_plan"] for r in done), ".2e"), _fmt(max(r["final_error"] for r in done), ".2e")]]
        rep.table(["", "T planned [s]", "least T [s]", "re-timing [ms]", "largest speed / v − 1",
                   "fastest leg at least [v]", "end vs plan [rad]", "final error [rad]"], rows)
        ok = sum(abs(r["excess"]) <= 1e-6 and r["end_vs_plan"] <= 1e-10 for r in done)
        rep.paragraph(f"Largest |dl_i/dt| equal to v within 1e-6 relative and end within 1e-10 rad of the "
                      f"plan's: **{ok} of {len(done)}** (largest |deviation| {worst:.2e}).")
    if peers:
        rep.heading("Leg speeds: a given time", level=3)
        rep.paragraph(
            f"The same goals in T = {STRETCH:g} × the least time found above, every leg at most v = {v:g}: "
            "`plan(R0, Rd, T=T, constraints=[LegSpeed(v)])` (the path planned in T, re-timed if its legs are too fast) and "
            "the CasADi baseline (minimum energy, 40 intervals, 2 substeps, the bound at both ends of every "
            "interval). *solved* = re-simulated final error ≤ 1e-8 rad, sgnΔ ≥ 0.01 and no leg faster than "
            "v (1 + 1e-6) at any sample (the baseline is bounded at its nodes only).")
        by = by_solver(peers)
        rep.table(["solver", "goals", "claimed", "solved", "false claims", "median ms", "p95 ms", "max ms"],
                  [[name, *summary(rs)] for name, rs in by.items()])


_SPEED_COLS = (("T_planned", ".3g"), ("T_least", ".4g"), ("seconds_ms", ".2f"), ("excess", ".2e"),
               ("least", ".7f"), ("end_vs_plan", ".2e"), ("final_error", ".2e"))


def _fmt(x, spec: str) -> str:
    return format(x, spec)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.limits", description=__doc__.splitlines()[0])
    ap.add_argument("--lo", type=float, default=LIMITS[0])
    ap.add_argument("--hi", type=float, default=LIMITS[1])
    ap.add_argument("--no-casadi", action="store_true", help="leave CasADi out (e.g. not installed)")
    ap.add_argument("--leg-speed", type=float, default=LEG_SPEED, help="the legs' speed bound")
    ap.add_argument("--speed-goals", type=int, default=SPEED_GOALS, help="goals re-timed")
    args = ap.parse_args(argv)
    limits = (args.lo, args.hi)
    goals = goals_inside(limits)
    _log(f"{len(goals)} goals with both ends inside {limits}")
    records = run_nonholo(goals, limits, "nonholo")
    _log("nonholo done")
    records += run_nonholo(goals, limits, "nonholo (no limits)", enforce=False)
    for r in records:
        if r["solver"] == "nonholo (no limits)" and r["claimed"]:
            r["inside"] = r["check"]["least_clearance"] >= 0.0 if r["check"] else None
    _log("nonholo (no limits) done")
    if not args.no_casadi:
        records += run_casadi(goals, limits)
        _log("casadi done")
    rep = Report("limits.md", "Plans under the legs' stroke limits", "benchmarks.limits", argv,
                 extra_packages=("casadi",))
    rep.paragraph(
        f"The platform's reachable goals of `benchmarks/goals.json` whose start and goal keep both legs "
        f"inside leg_length = ({limits[0]:g}, {limits[1]:g}) ({len(goals)} goals; the legs span 0.6 … 2.6). "
        "Each solver timed per call after a warm-up call. Every claimed success re-simulated by DOP853 "
        f"(rtol = atol = 1e-13, dense path): *solved* = final error ≤ {SUCCESS_TOL:g} rad, sgnΔ ≥ "
        f"{DELTA_MIN:g} and both legs inside the limits at every point (lengths from the numeric geometry); "
        "a *false claim* is a claimed success that is not solved. `nonholo`: `plan(R0, Rd, "
        "constraints=[LegStroke(lo, hi)])` "
        "with its defaults; `casadi`: `benchmarks.casadi_ms.solve` (minimum energy, 40 intervals, 2 substeps, "
        "Δ at the substeps) with the stroke constraint at its nodes; `nonholo (no limits)`: `plan` without "
        "limits (its *solved* ignores the limits: see the line below the table).")
    by = by_solver(records)
    rows = []
    for name, rs in by.items():
        if name == "nonholo (no limits)":
            for r in rs:            # solved here: without the limits' condition
                c = r["check"]
                r["solved"] = c is not None and c["final_error"] <= SUCCESS_TOL and c["least_delta"] >= DELTA_MIN
        rows.append([name, *summary(rs)])
    rep.table(["solver", "goals", "claimed", "solved", "false claims", "median ms", "p95 ms", "max ms"], rows)
    free = by.get("nonholo (no limits)", [])
    leave = sum(1 for r in free if r.get("inside") is False)
    rep.paragraph(f"Without limits, {leave} of the {sum(r['claimed'] for r in free)} plans `nonholo` finds leave "
                  "the stroke somewhere along the re-simulated motion (on those goals the limits bind).")
    if "casadi" in by:
        med = {k: float(np.median([r["seconds"] for r in by[k]])) for k in ("nonholo", "casadi")}
        rep.paragraph(f"Median time, casadi / nonholo (same run): **{med['casadi'] / med['nonholo']:.1f}×**.")
    missed = [r for r in records if r["solver"] in ("nonholo", "casadi") and not r["solved"]]
    if missed:
        rep.heading("Goals not solved")
        rep.table(["solver", "goal", "claimed", "final error", "least clearance", "reason"],
                  [[r["solver"], r["id"], r["claimed"],
                    "–" if not r["check"] else f"{r['check']['final_error']:.2g}",
                    "–" if not r["check"] else f"{r['check']['least_clearance']:.3g}", r["reason"][-160:]]
                   for r in missed])
    v = args.leg_speed
    timed = run_retiming(speed_goals(args.speed_goals), v)
    _log("re-timing done")
    least = {r["id"]: r["T_least"] for r in timed if r["planned"]}
    peers = run_speed_peers(speed_goals(args.speed_goals), v, STRETCH, least, not args.no_casadi)
    _log("speed peers done")
    speed_section(rep, timed, peers, v)
    reachable = [{**g, "R0": np.array(g["R0"]), "Rd": np.array(g["Rd"])}
                 for g in goalset.load_goals() if g["band"] != "across"]
    lowered = run_energy(reachable, not args.no_casadi)
    energy_section(rep, lowered, len(reachable))
    rep.write()
    (RESULTS_DIR / "limits.json").write_text(json.dumps(
        {"limits": limits, "records": records, "leg_speed": v, "retiming": timed, "speed_peers": peers,
         "energy": lowered},
        indent=1, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
