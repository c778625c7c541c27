"""The uniform random band set: the default :func:`nonholo.plan` on every pair, its peers on
a subset (run as ``python -m benchmarks.compare --set random``).

Pairs: :func:`benchmarks.goalset.band_pairs` — Haar-uniform pairs in one component (same
sign of ``Δ``, ``|Δ| ≥ 0.05`` at both ends), ``--per-band`` of each distance band 0–1,
1–1.8 and 1.8–π rad, for every mechanism with a singular set (``platform``,
``platform_raised``), ``T = 1``.

Solvers:

- ``nonholo``: :func:`nonholo.plan` with its defaults (strategy ``"robust"``, route
  ``"auto"``: the local plan, then the global route if that fails), ``delta_min = 0.01``,
  on every pair, one after the other in one process, after a warm-up (numba compiled,
  the roadmaps built: their build time is reported apart).
- on the first ``--peer-pairs`` pairs of each band of ``platform``:
  ``nonholo-local`` (the same with ``route="local"``, the strategy alone); ``casadi``
  (:mod:`benchmarks.casadi_ms` with the settings of :mod:`benchmarks.compare`: minimum
  energy, multiple shooting, ``N = 40``, 2 substeps, the path constraint at the
  substeps); ``ompl`` (:mod:`benchmarks.ompl_control`: KPIECE1 with the platform's
  kinematics as the propagator, a 0.05 rad goal region, 5 s).

Verification, independent of the planners: the returned control re-simulated by SciPy's
DOP853 (:func:`nonholo.certify.resimulate.resimulate`, ``rtol = atol = 1e-13``, stopping at its
breakpoints) → final error ``|log(R_T R_dᵀ)|``, and the least ``sgn(Δ(R0)) Δ`` on a dense
DOP853 path (:func:`nonholo.certify.resimulate.resimulate_path`) — for the peers' solutions, every
tenth ``nonholo`` success and every fourth by the global route; every ``nonholo`` success
is also re-simulated by classical RK4 on the nine entries of ``R``
(:func:`benchmarks.certify.check_successes`: ``S`` and ``2S`` steps, DOP853 where they
differ by more than 1e-9), its nodes the dense path. *Solved*: final error ≤ 1e-8 rad and
least ``Δ`` ≥ 0.01 in every check. OMPL plans to a region, in its own time: *in region* is its
own criterion (final error ≤ 0.05 rad, ``Δ`` kept). A *false claim* is a success the
solver reported that the re-simulation does not confirm.

Outputs (``benchmarks/results/`` or ``--out``): ``global.md`` (header, tables per
mechanism and band and per solver and band: success, median / p95 / max wall time,
final error; the rejection time of goals across ``Δ = 0``), ``global.json`` (one record
per pair and solver) and ``global.png``.
"""
from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from nonholo.model import catalog
from nonholo.planning import roadmap
from nonholo.certify.resimulate import resimulate_path, terminal_error

from . import goalset
from .report import Report
from .sweeps import plan_all

#: Mechanisms of the set: those with a singular set.
MECHANISMS = ("platform", "platform_raised")
DELTA_MIN = 1e-2
SUCCESS_TOL = 1e-8
#: OMPL's goal region (rad) — its own success criterion.
REGION = 0.05
BANDS = tuple(goalset.UNIFORM_BANDS)
#: Every this many successes, and every this many by the global route, are also checked by
#: DOP853 with a dense path (slow: the controls are evaluated in Python at every stage).
DOP853_EVERY = 10
DOP853_EVERY_GLOBAL = 4
#: Acceptance lines drawn on the figure (s): median, p95, max.
TARGETS = (0.020, 0.300, 3.0)


def _log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def check(mechanism, R0, Rd, T: float, controls, breakpoints) -> dict:
    """Final error and least ``sgn(Δ(R0)) Δ`` of ``controls`` re-simulated by DOP853 with
    a dense path (:func:`nonholo.certify.resimulate.resimulate_path`; a failed integration counts as
    reaching ``Δ = 0``, infinitely far from the goal)."""
    mech = catalog.get(mechanism)
    try:
        _, R, d = resimulate_path(R0, controls, T, mech, breakpoints)
    except (RuntimeError, FloatingPointError, ValueError, ZeroDivisionError):
        return {"final_error": math.inf, "least_delta": 0.0}
    sign = float(np.sign(mech.delta(R0)))
    return {"final_error": terminal_error(R[-1], Rd), "least_delta": float(np.min(sign * d))}


def _within(checked: dict | None, error: float) -> bool:
    """The check ends within ``error`` rad of the goal and keeps ``delta_min``."""
    return checked is not None and checked["final_error"] <= error and checked["least_delta"] >= DELTA_MIN


def _record(solver, mechanism, pair, wall, claimed, checked, **extra) -> dict:
    return {"solver": solver, "mechanism": mechanism, "id": pair["id"], "band": pair["band"],
            "distance": pair["distance"], "seconds": wall, "claimed": bool(claimed),
            "solved": _within(checked, SUCCESS_TOL), "in_region": _within(checked, REGION),
            **(checked or {"final_error": math.inf, "least_delta": None}), **extra}


def run_nonholo(mechanism: str, pairs: list[dict], route: str = "auto", label: str = "nonholo") -> list[dict]:
    """``plan()`` on every pair (through :func:`benchmarks.sweeps.plan_all`: timed one by one,
    resumable), every claimed success checked afterwards by RK4
    (:func:`benchmarks.certify.check_successes`), and by DOP853 with its dense path too
    for every :data:`DOP853_EVERY`-th success and every :data:`DOP853_EVERY_GLOBAL`-th one
    by the global route."""
    from .certify import check_successes

    timed = plan_all(f"random-{label}-{mechanism}", pairs, {"delta_min": DELTA_MIN, "route": route},
                     mechanism=mechanism)
    results = [res for _, res in timed]
    rk4 = check_successes(results, pairs)
    out, routed = [], 0
    for i, (p, (wall, res), c) in enumerate(zip(pairs, timed, rk4)):
        checked, dop = None, None
        if res.success:
            checked = {"final_error": c["miss"], "least_delta": c["min_delta"], "checker": c["checker"]}
            routed += res.route == "global"
            if i % DOP853_EVERY == 0 or (res.route == "global" and routed % DOP853_EVERY_GLOBAL == 1):
                dop = check(mechanism, p["R0"], p["Rd"], p["T"], res.controls, res.breakpoints)
                checked["final_error"] = max(checked["final_error"], dop["final_error"])
                checked["least_delta"] = min(checked["least_delta"], dop["least_delta"])
        out.append(_record(label, mechanism, p, wall, res.success, checked, route=res.route,
                           reason=res.reason, sensitivity=res.sensitivity, dop853=dop,
                           hops=res.hops.n_pieces if res.route == "global" else None,
                           smoothed=res.stitched is not None))
    return out


def run_casadi(pairs: list[dict]) -> list[dict]:
    """:mod:`benchmarks.casadi_ms` with the settings of :mod:`benchmarks.compare`'s
    ``casadi`` (its NLP built once, on Example 1, before anything is timed)."""
    from nonholo.spaces import so3

    from . import casadi_ms

    kw = {"N": 40, "substeps": 2, "delta_min": DELTA_MIN, "path_at_substeps": True}
    casadi_ms.solve(so3.from_rpy(0.5, 1.2, -0.5), so3.from_rpy(1.0, 0.9, -0.5), T=1.0, **kw)
    out = []
    for p in pairs:
        t = time.perf_counter()
        r = casadi_ms.solve(p["R0"], p["Rd"], T=p["T"], **kw)
        wall = time.perf_counter() - t
        checked = check("platform", p["R0"], p["Rd"], p["T"], r.controls, r.t_grid)
        out.append(_record("casadi", "platform", p, wall, r.success, checked, reason=r.status))
    return out


def run_ompl(pairs: list[dict]) -> list[dict]:
    from . import ompl_control

    planner = ompl_control.Planner("platform", DELTA_MIN)
    out = []
    for p in pairs:
        sol = planner.solve(p["R0"], p["Rd"])
        checked = None
        if sol.controls is not None:
            checked = check("platform", p["R0"], p["Rd"], sol.T, sol.controls, sol.controls.breakpoints)
        out.append(_record("ompl", "platform", p, sol.seconds, sol.reached, checked, reason=sol.status,
                           duration=sol.T, ompl_error=sol.error))
    return out


def _q(xs, q):
    xs = [x for x in xs if x is not None]
    return float(np.quantile(xs, q)) if xs else None


def _ms(x) -> str:
    return "–" if x is None else (f"{1e3 * x:.1f}" if x < 1 else f"{1e3 * x:.0f}")


def _err(x) -> str:
    return "–" if x is None or not np.isfinite(x) else f"{x:.2g}"


def write(out: Path, argv, records: list[dict], meta: dict, per_band: int, peer_pairs: int) -> None:
    rep = Report("global.md", "Every reachable goal: the default plan() on uniform random pairs",
                 "benchmarks.compare", argv, extra_packages=("casadi", "ompl"), results_dir=out)
    rep.paragraph(
        f"Uniform random pairs in one component (`benchmarks.goalset.band_pairs`, seed {goalset.SEED}): "
        f"{per_band} per distance band and mechanism, T = 1 s, delta_min = {DELTA_MIN:g}. `nonholo` is "
        "`plan()` with its defaults (strategy \"robust\", route \"auto\": the local plan, then the global "
        "route when it fails, its stitched control re-planned as one smooth control where that "
        "succeeds: *smoothed*), timed one pair after another in one process after a warm-up "
        f"(numba compiled; the roadmaps' build, {meta['roadmap_seconds']:.2f} s, is not in any pair's time). "
        "Every claimed success is re-simulated by RK4 on the entries of R (S and 2S steps, S ≥ 6400 and "
        "≥ the certified replay's; DOP853 where they differ by more than 1e-9), and by DOP853 (rtol = atol = "
        "1e-13, with a dense path) for every tenth success and every fourth by the global route: *solved* = "
        f"final error ≤ {SUCCESS_TOL:g} rad and least sgnΔ on the nodes / dense path ≥ {DELTA_MIN:g} in every "
        "check; a *false claim* is a success the re-simulation does not confirm. Peers' solutions are "
        "checked by DOP853 alone.")
    rep.heading("nonholo: every pair")
    def summary(rs: list[dict]) -> list:
        ts = [r["seconds"] for r in rs]
        return [len(rs), sum(r["solved"] for r in rs), sum(r["claimed"] and not r["solved"] for r in rs),
                sum(r.get("route") == "global" and r["solved"] for r in rs),
                sum(bool(r.get("smoothed")) and r["solved"] for r in rs),
                _ms(_q(ts, 0.5)), _ms(_q(ts, 0.95)), _ms(max(ts)),
                _err(max((r["final_error"] for r in rs if r["claimed"]), default=None))]

    rs = [r for r in records if r["solver"] == "nonholo"]
    groups = [(mech, band, [r for r in rs if r["mechanism"] == mech and band in ("all", r["band"])])
              for mech in MECHANISMS for band in (*BANDS, "all")] + [("all", "all", rs)]
    rows = [[mech, band, *summary(group)] for mech, band, group in groups if group]
    rep.table(["mechanism", "band (rad)", "pairs", "solved", "false claims", "by the global route",
               "of which smoothed", "median ms", "p95 ms", "max ms", "largest final error"], rows)
    failed = [r for r in rs if not r["solved"]]
    if failed:
        rep.heading("nonholo: pairs not solved")
        rep.table(["mechanism", "pair", "distance", "ms", "reason"],
                  [[r["mechanism"], r["id"], f"{r['distance']:.2f}", _ms(r["seconds"]), r["reason"][-200:]]
                   for r in failed])
    rep.heading("Peers on a subset")
    rep.paragraph(
        f"The first {peer_pairs} pairs of each band of `platform`. `nonholo-local`: route \"local\" (the "
        "robust strategy alone). `casadi`: `benchmarks.casadi_ms` (minimum energy, multiple shooting, N = 40, "
        "2 substeps, path constraint at the substeps; IPOPT). `ompl`: OMPL's control planner "
        "(`benchmarks.ompl_control`: KPIECE1, the platform's kinematics as the propagator, |u_i| ≤ "
        f"{meta.get('ompl_u_max', '?')}, goal region {REGION:g} rad, {meta.get('ompl_budget', '?')} s; "
        "free final time). *in region*: final error ≤ 0.05 rad with Δ kept, OMPL's own goal.")
    rows = []
    for solver in ("nonholo", "nonholo-local", "casadi", "ompl"):
        for band in BANDS:
            rs = [r for r in records if r["solver"] == solver and r["mechanism"] == "platform"
                  and r["band"] == band and r.get("peer")]
            if not rs:
                continue
            ts = [r["seconds"] for r in rs]
            fe = [r["final_error"] for r in rs if np.isfinite(r["final_error"])]
            rows.append([solver, band, len(rs), sum(r["solved"] for r in rs),
                         sum(r["in_region"] for r in rs),
                         sum(r["claimed"] and not r["solved"] for r in rs) if solver != "ompl" else "–",
                         _ms(_q(ts, 0.5)), _ms(_q(ts, 0.95)), _ms(_q(ts, 1.0)),
                         _err(_q(fe, 0.5))])
    rep.table(["solver", "band (rad)", "pairs", "solved (≤ 1e-8 rad)", "in region (≤ 0.05 rad)",
               "false claims", "median ms", "p95 ms", "max ms", "median final error"], rows)
    rep.heading("Goals across Δ = 0")
    rep.paragraph(f"The {meta['across_count']} goals of `benchmarks/goals.json` across Δ = 0, `plan()` with "
                  f"its defaults, {meta['across_repeat']} calls each: all rejected: "
                  f"{meta['across_rejected']}; median {1e3 * meta['across_median']:.3f} ms, "
                  f"max {1e3 * meta['across_max']:.3f} ms per call.")
    rep.paragraph("Figure: `global.png`. Records: `global.json`.")
    rep.write()


def figure(path: Path, records: list[dict]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.3))
    ax = axes[0]
    for mech, style in zip(MECHANISMS, ("-", "--")):
        ts = np.sort([r["seconds"] for r in records if r["solver"] == "nonholo" and r["mechanism"] == mech])
        if len(ts):
            ax.step(1e3 * ts, np.arange(1, len(ts) + 1) / len(ts), style, where="post", label=mech)
    for x, lab in zip(TARGETS, ("median", "p95", "max")):
        ax.axvline(1e3 * x, color="0.6", lw=0.8, ls=":")
        ax.text(1e3 * x, 0.02, f" {lab} target", rotation=90, va="bottom", fontsize=7, color="0.4")
    ax.set_xscale("log")
    ax.set_xlabel("wall time per pair (ms)")
    ax.set_ylabel("fraction of pairs solved by then")
    ax.set_title("default plan(), every pair")
    ax.legend(fontsize=8)
    solvers = [s for s in ("nonholo", "nonholo-local", "casadi", "ompl")
               if any(r["solver"] == s and r.get("peer") for r in records)]
    width = 0.8 / max(1, len(solvers))
    for k, s in enumerate(solvers):
        rates, times = [], []
        for b in BANDS:
            rs = [r for r in records if r["solver"] == s and r.get("peer") and r["band"] == b]
            key = "in_region" if s == "ompl" else "solved"
            rates.append(np.mean([bool(r.get(key)) for r in rs]) if rs else np.nan)
            times.append([r["seconds"] for r in rs if r["seconds"] is not None])
        xs = np.arange(len(BANDS)) + (k - (len(solvers) - 1) / 2) * width
        axes[1].bar(xs, rates, width, label=s + (" (in 0.05 rad region)" if s == "ompl" else ""))
        for x, t in zip(xs, times):
            axes[2].scatter(np.full(len(t), x), 1e3 * np.asarray(t), s=8, alpha=0.6,
                            color=f"C{k}", label=s if x == xs[0] else None)
    for ax in axes[1:]:
        ax.set_xticks(np.arange(len(BANDS)))
        ax.set_xticklabels([f"{b} rad" for b in BANDS])
    axes[1].set_ylabel("success rate")
    axes[1].set_ylim(0, 1.05)
    axes[1].set_title("platform, peer subset: success")
    axes[1].legend(fontsize=7, loc="center right")
    axes[2].set_yscale("log")
    axes[2].set_ylabel("wall time (ms)")
    axes[2].set_title("platform, peer subset: time per pair")
    axes[2].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def _jsonable(rec: dict) -> dict:
    return {k: ("inf" if isinstance(v, float) and math.isinf(v) else
                None if isinstance(v, float) and math.isnan(v) else v) for k, v in rec.items()}


def across_rejection(repeat: int = 20) -> dict:
    import nonholo

    goals = [g for g in goalset.load_goals() if g["band"] == "across"]
    ts, rejected = [], True
    for _ in range(repeat):
        for g in goals:
            t = time.perf_counter()
            res = nonholo.plan(g["R0"], g["Rd"], T=g["T"])
            ts.append(time.perf_counter() - t)
            rejected &= not res.success and "across the singular surface" in res.reason
    return {"across_count": len(goals), "across_repeat": repeat, "across_rejected": rejected,
            "across_median": float(np.median(ts)), "across_max": float(np.max(ts))}


def main(argv, per_band: int, peer_pairs: int, peers: list[str], out: Path) -> int:
    import nonholo

    from . import ompl_control

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    pairs = {m: goalset.band_pairs(m, per_band) for m in MECHANISMS}
    meta = {"per_band": per_band, "peer_pairs": peer_pairs, "ompl_u_max": ompl_control.U_MAX,
            "ompl_budget": ompl_control.BUDGET}
    t = time.perf_counter()
    for m in MECHANISMS:
        mech = catalog.get(m)
        roadmap.roadmap(mech, roadmap.default_clearance(mech))
    meta["roadmap_seconds"] = time.perf_counter() - t
    for m in MECHANISMS:   # numba, the frame and the hops' kernels
        p = pairs[m][-1]
        nonholo.plan(p["R0"], p["Rd"], mechanism=m, route="global")
        nonholo.plan(p["R0"], p["Rd"], mechanism=m)
    meta.update(across_rejection())
    records = []
    for m in MECHANISMS:
        _log(f"nonholo on {len(pairs[m])} {m} pairs")
        records += run_nonholo(m, pairs[m])
    subset = [p for b in BANDS for p in [q for q in pairs["platform"] if q["band"] == b][:peer_pairs]]
    ids = {p["id"] for p in subset}
    for r in records:
        r["peer"] = r["mechanism"] == "platform" and r["id"] in ids
    runners = {"nonholo-local": lambda: run_nonholo("platform", subset, "local", "nonholo-local"),
               "casadi": lambda: run_casadi(subset), "ompl": lambda: run_ompl(subset)}
    for name in peers:
        _log(f"{name} on {len(subset)} pairs")
        try:
            records += [{**r, "peer": True} for r in runners[name]()]
        except ImportError as exc:       # an optional peer that is not installed
            _log(f"{name}: skipped ({exc})")
    with open(out / "global.json", "w") as f:
        json.dump({"meta": meta, "records": [_jsonable(r) for r in records]}, f, indent=1)
    figure(out / "global.png", records)
    write(out, argv, records, meta, per_band, peer_pairs)
    return 0
