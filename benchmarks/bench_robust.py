"""Success rate and speed of the planner's strategies on reachable goals (run by hand).

    python -m benchmarks.bench_robust                   # strategy "robust" vs "paper"
    python -m benchmarks.bench_robust --ingredients     # ... and what each ingredient buys
    python -m benchmarks.bench_robust --stress 777 4242 --hard 99 --ingredients

Measures, per strategy, goal set and band (``near``: geodesic distance 0.2–0.8 rad, ``far``:
0.8–1.8 rad): the success rate, the median and maximum wall time of
:func:`nonholo.planning.api.plan` with ``route="local"`` (the strategy alone; after JIT warm-up), the median number of iterations and how
many goals needed a restart (an initial guess after the first); the rejection time of
the goals across ``Δ = 0`` (median/max of the full ``plan`` call); and Example 3 with the
"other" parking goal.

Success = the planner reports success AND the planned physical control
``result.controls(t)``, re-simulated by :func:`nonholo.certify.resimulate.resimulate_path` (SciPy
DOP853, ``rtol = atol = 1e-13``, on ``dR/dt = [L(R) u] R``), ends within 1e-8 rad of
``Rd`` AND keeps ``sgn(Δ(R0))·Δ ≥ 1e-2`` on the dense re-simulated path (2001 samples
plus every DOP853 step).

Goal sets: ``benchmark`` is ``benchmarks/goals.json`` (:func:`benchmarks.goalset.load_goals`,
64 near + 64 far goals from 8 starts, reachable by construction, plus 24 goals across
``Δ = 0``). ``--stress SEED`` builds another set the same way (12 starts of
:func:`benchmarks.goalset.starts` with that seed, 10 goals per band and start, 240 goals);
``--hard SEED`` a harder one (:func:`hard_goals`: starts with ``|Δ(R0)| ≥ 0.1``, random
Fourier controls with K ∈ {2, 3, 4} and RMS amplitude up to 4 rad/s, generating motions
kept at ``|Δ| ≥ 0.05``, ``far`` extended to 0.8–2.5 rad). ``--random SEED``: uniformly
random pairs in one component of ``Δ ≠ 0`` with ``|Δ| ≥ 0.05`` at both ends, 80 per
distance band (:func:`random_pairs`; ``beyond``: ≥ 1.8 rad) — reachable, but not
necessarily by a motion as simple as those that generated the other sets.

Strategies (``--ingredients``), built from the ingredients of :mod:`nonholo.planning.strategy_robust`
(each a :class:`~nonholo.planning.strategy_robust.RobustStrategy` subclass passed to
:func:`nonholo.plan` as ``strategy=``):

- ``paper``: the appendix's algorithm in the physical inputs ``u`` (Euclidean minimum
  norm on the Fourier coefficients of ``u``), initial loop ``u = 0.3 (sin, cos)``;
- ``w``: the same θ-flow in the frame coordinates ``w`` (``ω = N(R) w``), initial loop
  ``w = 0.3 (sin, cos)``, one attempt;
- ``w+barrier``: ``w`` plus the null-space barrier on ``Δ`` (flow steps), one attempt;
- ``w+drift``: ``w`` started from the drift guess ``w̄ = N(R0)^# log(Rd R0ᵀ)/T`` plus the
  loop, one attempt;
- ``w+drift+rest.``: ``w+drift``, then restarts from the other guesses (the loop, a larger
  loop, K+1 and K+2 harmonics, 6 random ones) when an attempt fails or stalls;
- ``robust``: the default — ``w+drift+rest.`` with the barrier (and the integrator
  refinement);
- ``robust γ=0.5``: the default with the paper's ``γ = 0.5`` instead of ``γ = 1``;
- ``robust in u``: the default with every ingredient but the frame coordinates.

Output: ``benchmarks/results/bench_robust.md`` for the default run,
``benchmarks/results/bench_robust_ingredients.md`` with ``--ingredients`` (``--out``
names another file in ``benchmarks/results/``), echoed to standard output: markdown
tables of the measurements above (with ``--ingredients`` first a summary, the success
rate of every strategy on every set and band), headed by the date, the git commit, the
machine and the command (:mod:`benchmarks.report`). The design the ingredients belong to is described in
:mod:`nonholo.planning.strategy_robust`.
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from scipy.spatial.transform import Rotation

from nonholo import Settings
from nonholo.paper import examples
from nonholo.planning.api import METHODS, plan
from nonholo.spaces import so3
from nonholo.certify.resimulate import resimulate, resimulate_path, terminal_error
from nonholo.planning.strategy_robust import RobustStrategy

from .report import Report
from .sweeps import plan_all

RESIM_TOL = 1e-8
DELTA_MIN = 1e-2
BANDS = ("near", "far", "beyond")


# --------------------------------------------------------------------------------------
# Variants: one ingredient at a time
# --------------------------------------------------------------------------------------

class InU(RobustStrategy):
    """The default strategy in the physical inputs ``u``."""

    name = "bench:robust-in-u"

    def frame(self, mechanism):
        return False


class W(RobustStrategy):
    """Frame coordinates, the default loop only, no barrier."""

    name = "bench:w"
    barrier = False

    def attempts(self, problem, start):
        yield "loop", start.controls


class WBarrier(W):
    """Frame coordinates, the default loop only, with the null-space barrier."""

    name = "bench:w+barrier"
    barrier = True


class WDrift(RobustStrategy):
    """Frame coordinates, the drift guess only, no barrier."""

    name = "bench:w+drift"
    barrier = False

    def attempts(self, problem, start):
        yield next(iter(super().attempts(problem, start)))


class WDriftRestarts(RobustStrategy):
    """Frame coordinates, the drift guess and the restarts (stall detection, deterministic
    then random guesses), no barrier."""

    name = "bench:w+drift+restarts"
    barrier = False


class Gamma05(RobustStrategy):
    """The default strategy with the paper's ``γ = 0.5`` (flow steps ask for half the error)."""

    name = "bench:robust-gamma-0.5"
    default_gamma = 0.5


#: label -> the ``strategy`` argument of :func:`nonholo.plan` (a name or a Strategy subclass)
VARIANTS = {"paper": "paper", "w": W, "w+barrier": WBarrier, "w+drift": WDrift,
            "w+drift+rest.": WDriftRestarts, "robust": "robust", "robust γ=0.5": Gamma05,
            "robust in u": InU}


# --------------------------------------------------------------------------------------
# Goal sets
# --------------------------------------------------------------------------------------

def benchmark_goals() -> list[dict]:
    from benchmarks.goalset import load_goals

    return load_goals()


def stress_goals(seed: int, n_starts: int = 12, per_band: int = 10) -> list[dict]:
    """Reachable goals built like ``goals.json`` with another seed."""
    from benchmarks import goalset

    out = []
    for s, R0 in enumerate(goalset.starts(seed, n_starts)):
        for band in ("near", "far"):
            goals, _ = goalset.reachable_goals(s, band, per_band, seed=seed, R0=R0)
            out += [dict(g, R0=np.asarray(g["R0"]), Rd=np.asarray(g["Rd"])) for g in goals]
    return out


def hard_goals(seed: int, n_starts: int = 12, per_band: int = 10) -> list[dict]:
    """Harder reachable goals: uniformly random starts with ``|Δ(R0)| ≥ 0.1``, ``K ∈ {2, 3, 4}``, RMS amplitude
    log-uniform in 0.05–1 (near) / 0.3–4 rad/s (far), generating motions (DOP853, via
    :func:`benchmarks.goalset.simulate`) kept at ``|Δ| ≥ 0.05``; bands 0.2–0.8 / 0.8–2.5 rad."""
    from benchmarks import goalset

    rng = np.random.default_rng([seed, 7])
    bands = {"near": ((0.2, 0.8), (0.05, 1.0)), "far": ((0.8, 2.5), (0.3, 4.0))}
    out = []
    for s in range(n_starts):
        while True:
            R0 = _uniform_rotation(rng)
            if abs(goalset.delta(R0)) >= 0.1 and (goalset.delta(R0) > 0) == (s % 2 == 0):
                break
        for band, ((lo, hi), (alo, ahi)) in bands.items():
            j = 0
            while j < per_band:
                K = int(rng.choice((2, 3, 4)))
                c = rng.standard_normal((2, 2 * K + 1))
                c *= np.exp(rng.uniform(np.log(alo), np.log(ahi))) / np.sqrt(
                    np.sum(c[:, 0] ** 2) + 0.5 * np.sum(c[:, 1:] ** 2))
                ok, RT, _ = goalset.simulate(R0, c, delta_keep=0.05)
                if not ok:
                    continue
                U, _, Vt = np.linalg.svd(RT)
                Rd = U @ np.diag([1, 1, np.linalg.det(U @ Vt)]) @ Vt
                if lo <= so3.distance(Rd, R0) <= hi:
                    out.append({"id": f"hard-{band}-s{s}-{j:02d}", "band": band, "R0": R0, "Rd": Rd,
                                "T": 1.0})
                    j += 1
    return out


def random_pairs(seed: int, per_band: int = 80, min_delta: float = 0.05) -> list[dict]:
    """Uniformly random ``(R0, Rd)`` in the same component of ``Δ ≠ 0``, ``|Δ| ≥ min_delta`` at
    both ends, ``per_band`` in each distance band (near < 0.8 ≤ far < 1.8 ≤ beyond, rad) —
    reachable (the component is connected and the frame is bracket-generating), but
    nothing says by a motion as short as in the other sets."""
    from benchmarks import goalset

    rng = np.random.default_rng([seed, 11])
    out = []
    count = {"near": 0, "far": 0, "beyond": 0}
    while min(count.values()) < per_band:
        A, B = _uniform_rotation(rng), _uniform_rotation(rng)
        dA, dB = goalset.delta(A), goalset.delta(B)
        if np.sign(dA) != np.sign(dB) or min(abs(dA), abs(dB)) < min_delta:
            continue
        dist = so3.distance(A, B)
        band = "near" if dist < 0.8 else "far" if dist < 1.8 else "beyond"
        if count[band] < per_band:
            out.append({"id": f"random-{band}-{count[band]:03d}", "band": band, "R0": A, "Rd": B, "T": 1.0})
            count[band] += 1
    return out


def _uniform_rotation(rng) -> np.ndarray:
    """Haar-uniform rotation (normalised Gaussian quaternion)."""
    q = rng.standard_normal(4)
    return Rotation.from_quat(q / np.linalg.norm(q)).as_matrix()


# --------------------------------------------------------------------------------------
# Measurements
# --------------------------------------------------------------------------------------

def check(res, R0, Rd, T) -> dict:
    """Independent verification of a plan (see the module docstring)."""
    out = {"resim": None, "dense_min_delta": None, "ok": False}
    if not res.success:
        return out
    try:
        RT = resimulate(R0, res.controls, T, res.mechanism, res.breakpoints)
        _, _, d = resimulate_path(R0, res.controls, T, res.mechanism, res.breakpoints)
    except RuntimeError:            # DOP853 gave up (an extremely sensitive motion)
        out["resim"] = float("inf")
        return out
    out["resim"] = terminal_error(RT, Rd)
    out["dense_min_delta"] = float(np.min(np.sign(d[0]) * d))
    out["ok"] = out["resim"] <= RESIM_TOL and out["dense_min_delta"] >= DELTA_MIN
    return out


def run(strategy, goals: list[dict], name: str = "") -> list[dict]:
    """``plan(..., strategy=strategy, route="local")`` on every goal, through
    :func:`benchmarks.sweeps.plan_all` (timed one by one, resumable); a Strategy subclass
    goes into the problem table by its import path (``"module:Class"``)."""
    if not isinstance(strategy, str):           # a Strategy subclass: by its import path
        strategy = f"{strategy.__module__}:{strategy.__qualname__}"
    planned = plan_all(f"bench_robust-{name or strategy}", goals,
                       {"strategy": strategy, "delta_min": DELTA_MIN, "route": "local"})
    rows = []
    for g, (wall, res) in zip(goals, planned):
        restarts = max([h.get("attempt", 0) for h in res.history] or [0])
        rows.append({"id": g["id"], "band": g["band"], "wall": wall, "iterations": res.iterations,
                     "restarts": restarts, "reason": res.reason, **check(res, g["R0"], g["Rd"], g["T"])})
    return rows


def band_rows(label: str, rows: list[dict]) -> list[list]:
    """Table rows of one strategy on one set: success, times, iterations, restarts per band."""
    out = []
    for band in BANDS:
        r = [x for x in rows if x["band"] == band]
        if not r:
            continue
        ok = sum(x["ok"] for x in r)
        walls = [x["wall"] * 1e3 for x in r]
        out.append([label, band, f"{ok}/{len(r)}", f"{100 * ok / len(r):.1f} %",
                    f"{statistics.median(walls):.2f}", f"{max(walls):.2f}",
                    f"{statistics.median(x['iterations'] for x in r):.1f}",
                    sum(x["restarts"] > 0 for x in r)])
    return out


SET_HEADERS = ["strategy", "band", "solved", "rate", "median time [ms]", "max time [ms]",
               "median iterations", "restarts used"]
SET_ALIGN = ["l", "l", "r", "r", "r", "r", "r", "r"]


def warm_up(strategies) -> None:
    R0, Rd = so3.from_rpy(0.5, 1.2, -0.5), so3.from_rpy(1.0, 0.9, -0.5)
    for s in strategies:
        for method in METHODS:
            plan(R0, Rd, strategy=s, settings=Settings(method=method))


def rejection(report: Report, goals: list[dict], repeat: int = 20) -> None:
    across = [g for g in goals if g["band"] == "across"]
    ts = []
    for _ in range(repeat):
        for g in across:
            t = time.perf_counter()
            res = plan(g["R0"], g["Rd"], T=g["T"])
            ts.append(time.perf_counter() - t)
            assert not res.success and "across the singular surface" in res.reason, res.reason
    report.heading("Goals across Δ = 0")
    report.paragraph(
        f"The {len(across)} goals of the benchmark set across Δ = 0, each planned {repeat} times "
        "(default strategy): all rejected; the full `plan()` call took a median "
        f"**{statistics.median(ts) * 1e6:.0f} µs**, max {max(ts) * 1e6:.0f} µs.")


def parking(report: Report) -> None:
    ex3 = examples.get(3)
    R0 = ex3.R_start
    other = examples.parallel_parking_goal(R0, 0.6, np.array([-0.543, -0.033, -0.253]))
    report.heading("Parking goals")
    report.paragraph("From R0 = RPY(0.5, 1.2, -0.5), T = 1, K = 2: the goal of Example 3 and the "
                     "\"other\" parking goal, `Rd = exp([v]) R0`.")
    rows = []
    gamma_rows = []
    gammas = (0.1, 0.2, 0.3, 0.5, 0.7, 1.0)
    for name, Rd in (("Example 3", ex3.R_goal), ("other", other)):
        v = so3.log(Rd @ R0.T)
        vtext = f"({v[0]:+.3f}, {v[1]:+.3f}, {v[2]:+.3f})"
        for strategy in ("robust", "paper"):
            for method in METHODS:
                t = time.perf_counter()
                res = plan(R0, Rd, settings=Settings(method=method), strategy=strategy, route="local")
                wall = time.perf_counter() - t
                c = check(res, R0, Rd, 1.0)
                resim = "n/a" if c["resim"] is None else f"{c['resim']:.1e}"
                md = "n/a" if c["dense_min_delta"] is None else f"{c['dense_min_delta']:.3f}"
                rows.append([name, vtext, strategy, method, "solved" if c["ok"] else "FAILED", resim, md,
                             res.iterations, f"{wall * 1e3:.1f}", "" if c["ok"] else res.reason[:90]])
        solved = [plan(R0, Rd, strategy="paper", settings=Settings(gamma=g), route="local").success
                  for g in gammas]
        gamma_rows.append([name] + ["yes" if x else "no" for x in solved])
    report.table(["goal", "v", "strategy", "method", "result", "re-simulated |l_T|", "min Δ",
                  "iterations", "time [ms]", "reason (failures)"], rows,
                 ["l", "l", "l", "l", "l", "r", "r", "r", "r", "l"])
    report.paragraph('Solved by the strategy "paper" for each γ:')
    report.table(["goal"] + [f"γ = {g}" for g in gammas], gamma_rows, ["l"] + ["l"] * len(gammas))


def summary_table(report: Report, results: dict) -> None:
    """Success rate (%) of every strategy on every set, per band."""
    first = next(iter(results.values()))
    sets = list(first)
    headers = ["strategy"] + [f"{name} ({' / '.join(b for b in BANDS if any(r['band'] == b for r in rows))})"
                              for name, rows in first.items()]
    table = []
    for label, per_set in results.items():
        cells = [label]
        for set_name in sets:
            rows = per_set[set_name]
            rates = []
            for band in BANDS:
                r = [x for x in rows if x["band"] == band]
                if r:
                    rates.append(f"{100 * sum(x['ok'] for x in r) / len(r):.1f}")
            cells.append(" / ".join(rates))
        table.append(cells)
    report.heading("Summary: success rate (%) per set and band")
    report.table(headers, table, ["l"] + ["r"] * len(sets))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ingredients", action="store_true", help="run every variant, not only robust and paper")
    ap.add_argument("--stress", type=int, nargs="*", default=[], metavar="SEED", help="extra goal sets")
    ap.add_argument("--hard", type=int, nargs="*", default=[], metavar="SEED", help="harder goal sets")
    ap.add_argument("--random", type=int, nargs="*", default=[], metavar="SEED",
                    help="uniformly random pairs in one component (not all reachable by short motions)")
    ap.add_argument("--out", default=None, metavar="NAME",
                    help="results file in benchmarks/results/ (default: bench_robust.md, "
                         "bench_robust_ingredients.md with --ingredients)")
    args = ap.parse_args(argv)
    out = args.out or ("bench_robust_ingredients.md" if args.ingredients else "bench_robust.md")

    report = Report(out, "Strategies of the planner on reachable goals (bench_robust)"
                    + (": the ingredients" if args.ingredients else ""), "benchmarks.bench_robust", argv)
    names = list(VARIANTS) if args.ingredients else ["robust", "paper"]
    warm_up([VARIANTS[n] for n in names])
    goals = benchmark_goals()
    sets = {"benchmark": [g for g in goals if g["band"] != "across"]}
    built = []
    for seed in args.stress:
        t = time.perf_counter()
        sets[f"stress {seed}"] = stress_goals(seed)
        built.append(f"stress set {seed} built in {time.perf_counter() - t:.0f} s")
    for seed in args.hard:
        t = time.perf_counter()
        sets[f"hard {seed}"] = hard_goals(seed)
        built.append(f"hard set {seed} built in {time.perf_counter() - t:.0f} s")
    for seed in args.random:
        sets[f"random pairs {seed}"] = random_pairs(seed)
    report.paragraph(
        f"Success = plan success, DOP853 re-simulation of `controls(t)` within {RESIM_TOL:g} rad "
        f"of the goal and min sgn(Δ(R0))·Δ ≥ {DELTA_MIN:g} on the dense re-simulated path. Times: "
        "the whole `plan()` call after warm-up (T = 1, parametric, K = 2, "
        f"delta_min = {DELTA_MIN:g}); *restarts used*: goals solved or failed after more than one "
        "initial guess." + (f" ({'; '.join(built)}.)" if built else ""))

    results = {n: {} for n in names}
    detail = []
    for set_name, gs in sets.items():
        counts = ", ".join(f"{sum(g['band'] == b for g in gs)} {b}" for b in BANDS
                           if any(g["band"] == b for g in gs))
        rows = []
        for n in names:
            results[n][set_name] = run(VARIANTS[n], gs, f"{n}-{set_name}")
            rows += band_rows(n, results[n][set_name])
        detail.append((f"{set_name} ({counts})", rows))
    if args.ingredients:
        summary_table(report, results)
    for title, rows in detail:
        report.heading(f"Set: {title}")
        report.table(SET_HEADERS, rows, SET_ALIGN)
    rejection(report, goals)
    parking(report)
    report.write()


if __name__ == "__main__":
    main()
