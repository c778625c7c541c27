"""Certified success: every claimed success of :func:`nonholo.plan` re-simulated independently.

Run ``python -m benchmarks.certify`` (``--pairs 1000 --edge-pairs 100 --workers 2``) to
write ``benchmarks/results/certify.md``.

Problems: for every mechanism, ``--pairs`` pairs ``(R0, Rd)`` drawn uniformly from SO(3)
in one component (:func:`benchmarks.goalset.uniform_pairs`: same sign of ``Δ``, ``|Δ| ≥
0.05`` at both ends), ``T = 1``, planned with every strategy and method at default options
(:data:`CONFIGS`), and the first ``--edge-pairs`` of them with odd but legal options
(:data:`EDGE_CONFIGS`).

Check: every plan that claims success has its physical controls ``result.controls``
re-simulated by the classical RK4 on the nine entries of ``R``
(:func:`nonholo.certify.resimulate.resimulate_rk4`, no Lie-group integrator, no frame coordinates) on
``S`` and ``2S`` steps, ``S ≥`` :data:`RK4_STEPS` a multiple of the plan's steps (so
steps are aligned with every breakpoint); the ``2S`` endpoint is the check, ``|R_2S −
R_S|`` the checker's own error scale. A claimed success *misses* when the check ends more
than :data:`MISS` rad from the goal or comes closer than ``delta_min`` to ``Δ = 0`` at its
nodes. A sample of the successes is also integrated by SciPy's DOP853
(:func:`nonholo.certify.resimulate.resimulate`) to confirm the checker.

With ``--baseline REV`` the script also times ``plan`` on the reachable goals of
``benchmarks/goals.json`` with the code of git revision ``REV`` (a temporary worktree, run
in a subprocess) and with this checkout, alternately, ``--rounds`` rounds each: success rates and
median plan times (thread CPU time) in the same run.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np

from benchmarks import goalset
from benchmarks.report import Report
from nonholo.model import catalog
from nonholo.planning.api import plan
from nonholo.planning.settings import arguments_of
from nonholo.certify.resimulate import resimulate, resimulate_rk4, terminal_error

MECHANISMS = ("platform", "platform_raised", "attitude")
#: every strategy and method, default options (flat, as a problem table's: :func:`arguments_of`)
CONFIGS = {
    "robust / parametric (default)": {},
    "robust / nonparametric": {"method": "nonparametric"},
    "paper / parametric": {"strategy": "paper"},
    "paper / nonparametric": {"strategy": "paper", "method": "nonparametric"},
}
#: odd but legal options
EDGE_CONFIGS = {
    "steps=4, harmonics=1": {"steps": 4, "harmonics": 1},
    "paper, steps=4, harmonics=1": {"strategy": "paper", "steps": 4, "harmonics": 1},
    "paper, harmonics=20": {"strategy": "paper", "harmonics": 20},
    "T=1e4": {"T": 1e4},
    "paper, T=1e4": {"strategy": "paper", "T": 1e4},
    "tol=1e-13": {"tol": 1e-13},
    "nonparametric, grid=400, steps=400": {"method": "nonparametric", "grid": 400, "steps": 400},
    "paper, nonparametric, grid=400, steps=400": {"strategy": "paper", "method": "nonparametric",
                                                  "grid": 400, "steps": 400},
    "delta_min=0.1": {"delta_min": 0.1},
}
#: a claimed success whose check ends farther than this from the goal misses it (rad)
MISS = 1e-8
#: least RK4 steps of the check
RK4_STEPS = 6400
#: successes per (mechanism, configuration) also integrated by DOP853
DOP853_SAMPLE = 3
CHUNK = 50


def check_successes(results, pairs) -> list[dict]:
    """The RK4 checks of the successes among ``results`` (one mechanism), batched by grid:
    ``S`` and ``2S`` steps, ``S`` a multiple of the plan's steps, at least
    :data:`RK4_STEPS` and the certified replay's; DOP853 where the two differ by more
    than 1e-9. ``None`` for a failure."""
    out = [None] * len(results)
    groups: dict[int, list[int]] = {}
    for i, r in enumerate(results):
        if r.success:
            S = r.steps * -(-max(RK4_STEPS, r.replay_steps or 0) // r.steps)
            groups.setdefault(S, []).append(i)
    for S, idx in groups.items():
        R0 = np.stack([pairs[i]["R0"] for i in idx])
        pars = [results[i].parametrisation for i in idx]
        T = [results[i].T for i in idx]
        mech = results[idx[0]].mechanism
        R_S, _ = resimulate_rk4(R0, pars, T, mech, steps=S)
        R_2S, dmin = resimulate_rk4(R0, pars, T, mech, steps=2 * S)
        for j, i in enumerate(idx):
            R = R_2S[j]
            checker = float(np.max(np.abs(R - R_S[j])))
            if not checker <= 1e-9:
                # RK4 on this grid is not accurate enough (e.g. T = 1e4): DOP853 decides
                r = results[i]
                R = resimulate(pairs[i]["R0"], r.controls, r.T, r.mechanism, r.breakpoints)
                checker = None
            out[i] = {"miss": terminal_error(R, pairs[i]["Rd"]), "checker": checker,
                      "min_delta": None if dmin is None else float(dmin[j])}
    return out


def run_chunk(mechanism: str, label: str, options: dict, start: int, stop: int, count: int,
              dop853: int) -> list[dict]:
    """Plan pairs ``start:stop`` of the mechanism's ``count`` uniform pairs with ``options``
    and check every claimed success (``dop853``: how many of them DOP853 also checks)."""
    pairs = goalset.uniform_pairs(mechanism, count)[start:stop]
    results, seconds = [], []
    for p in pairs:
        t = time.thread_time()
        results.append(plan(p["R0"], p["Rd"], mechanism=mechanism,
                            **arguments_of({"route": "local", **options}, mechanism)))
        seconds.append(time.thread_time() - t)
    checks = check_successes(results, pairs)
    rows = []
    for p, r, c, s in zip(pairs, results, checks, seconds):
        row = {"mechanism": mechanism, "config": label, "id": p["id"], "band": p["band"],
               "success": bool(r.success), "seconds": s, "reason": r.reason[:200],
               "error_bound": r.error_bound, "terminal_error": r.terminal_error, **(c or {})}
        if c is not None and dop853 > 0:
            dop853 -= 1
            RT = resimulate(p["R0"], r.controls, r.T, mechanism, r.breakpoints)
            row["dop853"] = terminal_error(RT, p["Rd"])
        rows.append(row)
    return rows


def tasks(pairs: int, edge_pairs: int):
    for mech in MECHANISMS:
        for label, options in CONFIGS.items():
            for a in range(0, pairs, CHUNK):
                yield mech, label, options, a, min(a + CHUNK, pairs), pairs, DOP853_SAMPLE if a == 0 else 0
        for label, options in EDGE_CONFIGS.items():
            for a in range(0, edge_pairs, CHUNK):
                yield mech, label, options, a, min(a + CHUNK, edge_pairs), pairs, 0


def _delta_min(label: str) -> float:
    options = {**CONFIGS, **EDGE_CONFIGS}[label]
    return options.get("delta_min", 1e-2)


def summary(rows: list[dict]) -> list[list]:
    out = []
    keys = []
    for r in rows:
        if (r["mechanism"], r["config"]) not in keys:
            keys.append((r["mechanism"], r["config"]))
    for mech, label in keys:
        rs = [r for r in rows if r["mechanism"] == mech and r["config"] == label]
        ok = [r for r in rs if r["success"]]
        has_delta = catalog.get(mech).delta is not None
        miss = [r for r in ok if not r["miss"] <= MISS]
        near = [r for r in ok if has_delta and not r["min_delta"] >= _delta_min(label)]
        worst = max((r["miss"] for r in ok), default=None)
        checker = max((r["checker"] for r in ok if r["checker"] is not None), default=None)
        bound = max((r["error_bound"] for r in ok), default=None)
        out.append([mech, label, len(rs), len(ok), f"{100 * len(ok) / len(rs):.1f} %", len(miss),
                    len(near), "—" if worst is None else f"{worst:.1e}",
                    "—" if bound is None else f"{bound:.1e}", "—" if checker is None else f"{checker:.1e}",
                    f"{1e3 * np.median([r['seconds'] for r in ok]):.1f}" if ok else "—"])
    return out


# -- the same goals with an earlier revision, in the same run ---------------------------------

#: calls per goal and round; the least time counts (robust to other load on the machine)
REPEATS = 3
_TIMING = r"""
import inspect, json, sys, time
REPEATS = int(sys.argv[3])
sys.path.insert(0, sys.argv[1])
import numpy as np
import nonholo
assert nonholo.__file__.startswith(sys.argv[1]), nonholo.__file__
goals = json.load(open(sys.argv[2]))
# the strategies alone: the local route (revisions before the global route have no choice)
local = {"route": "local"} if "route" in inspect.signature(nonholo.plan).parameters else {}
out = {}
for strategy in ("robust", "paper"):
    for g in goals[:5]:
        nonholo.plan(np.array(g["R0"]), np.array(g["Rd"]), strategy=strategy, **local)
    rows = []
    for g in goals:
        best = float("inf")
        for _ in range(REPEATS):
            t = time.thread_time()
            r = nonholo.plan(np.array(g["R0"]), np.array(g["Rd"]), T=g["T"], strategy=strategy, **local)
            best = min(best, time.thread_time() - t)
        rows.append([bool(r.success), best])
    out[strategy] = rows
print(json.dumps(out))
"""


def timing(report: Report, baseline: str, rounds: int = 5) -> None:
    """Success rates and median times on goals.json: revision ``baseline`` against this checkout."""
    root = Path(__file__).resolve().parent.parent
    goals = [{"R0": g["R0"].tolist(), "Rd": g["Rd"].tolist(), "T": g["T"]}
             for g in goalset.load_goals() if g["band"] != "across"]
    with tempfile.TemporaryDirectory() as tmp:
        tree = Path(tmp) / "baseline"
        subprocess.run(["git", "-C", str(root), "worktree", "add", "-q", "--detach", str(tree), baseline],
                       check=True)
        try:
            gpath = Path(tmp) / "goals.json"
            gpath.write_text(json.dumps(goals))
            runs = {"baseline": [], "this": []}
            for _ in range(rounds):
                for name, path in (("baseline", tree), ("this", root)):
                    env = {**os.environ, "NUMBA_CACHE_DIR": str(Path(tmp) / f"numba-{name}")}
                    out = subprocess.run([sys.executable, "-c", _TIMING, str(path), str(gpath), str(REPEATS)], env=env,
                                         capture_output=True, text=True, check=True)
                    runs[name].append(json.loads(out.stdout.splitlines()[-1]))
        finally:
            subprocess.run(["git", "-C", str(root), "worktree", "remove", "--force", str(tree)], check=False)
    rows = []
    for strategy in ("robust", "paper"):
        med = {}
        for name in ("baseline", "this"):
            rs = runs[name]
            ok = sum(s for s, _ in rs[0][strategy])
            med[name] = [float(np.median([t for _, t in r[strategy]])) for r in rs]
            rows.append([strategy, baseline if name == "baseline" else "this checkout",
                         f"{ok}/{len(rs[0][strategy])}", f"{100 * ok / len(rs[0][strategy]):.1f} %",
                         " / ".join(f"{1e3 * m:.2f}" for m in med[name])])
        ratio = float(np.median(med["this"]) / np.median(med["baseline"]))
        rows.append([strategy, "ratio (median of rounds)", "", "", f"{ratio:.2f}×"])
    report.heading("Reachable goals of benchmarks/goals.json: success and plan time against "
                   f"revision {baseline} (same run)")
    report.paragraph(f"{len(goals)} goals, default options; plan times are thread CPU times, "
                     f"median per round over the goals of the least of {REPEATS} calls per goal ({rounds} "
                     "alternating rounds, first five plans of each strategy run before as warm-up).")
    report.table(["strategy", "code", "solved", "rate", "median plan time per round [ms]"], rows,
                 ["l", "l", "r", "r", "r"])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=1000, help="uniform pairs per mechanism (default 1000)")
    ap.add_argument("--edge-pairs", type=int, default=100, help="pairs per odd option set (default 100)")
    ap.add_argument("--workers", type=int, default=2, help="worker processes (default 2)")
    ap.add_argument("--baseline", help="git revision to time against on benchmarks/goals.json")
    ap.add_argument("--out", default="certify.md", help="file name in benchmarks/results/")
    ap.add_argument("--rows", help="also write every plan's row (JSON Lines) to this file")
    ap.add_argument("--rounds", type=int, default=5, help="timing rounds per revision (default 5)")
    ap.add_argument("--timing-only", action="store_true",
                    help="only the goals.json timing against --baseline (to certify_timing.md by default)")
    args = ap.parse_args(argv)
    if args.timing_only:
        if not args.baseline:
            ap.error("--timing-only needs --baseline")
        out = args.out if args.out != "certify.md" else "certify_timing.md"
        report = Report(out, "Certified success: plan time against a baseline revision",
                        "benchmarks.certify", argv)
        started = time.perf_counter()
        timing(report, args.baseline, args.rounds)
        report.paragraph(f"Total time {time.perf_counter() - started:.0f} s.")
        report.write()
        return
    report = Report(args.out, "Certified success: claimed successes re-simulated independently",
                    "benchmarks.certify", argv)
    started = time.perf_counter()
    work = list(tasks(args.pairs, args.edge_pairs))
    rows = []
    with ProcessPoolExecutor(args.workers) as pool:
        futures = [pool.submit(run_chunk, *w) for w in work]
        for k, f in enumerate(as_completed(futures), 1):
            rows += f.result()
            print(f"\r{k}/{len(futures)} chunks, {len(rows)} plans, "
                  f"{time.perf_counter() - started:.0f} s", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    order = {(m, c): i for i, (m, c) in enumerate((m, c) for m in MECHANISMS for c in {**CONFIGS, **EDGE_CONFIGS})}
    rows.sort(key=lambda r: (order[r["mechanism"], r["config"]], r["id"]))
    if args.rows:
        Path(args.rows).write_text("".join(json.dumps(r) + "\n" for r in rows))
    report.paragraph(
        f"Uniform random pairs in one component (`benchmarks.goalset.uniform_pairs`, seed "
        f"{goalset.SEED}): {args.pairs} per mechanism with every strategy and method at default "
        f"options, the first {args.edge_pairs} with odd but legal options. Every claimed success "
        f"is re-simulated by RK4 on the entries of R (`nonholo.certify.resimulate.resimulate_rk4`, S and 2S "
        f"steps, S ≥ {RK4_STEPS} aligned with the plan's steps). *misses*: the RK4 endpoint is "
        f"more than {MISS:g} rad from the goal; *near Δ = 0*: the RK4 nodes come closer than "
        "delta_min; *checker*: max |R_2S − R_S| (the check's own error scale); *error bound*: the "
        "largest certified bound of the plans. Where the RK4 check's own error scale exceeds 1e-9 "
        "(long horizons such as T = 1e4) DOP853 decides instead.")
    report.table(["mechanism", "options", "pairs", "claimed successes", "rate", "misses", "near Δ = 0",
                  "worst RK4 error [rad]", "max error bound", "checker", "median plan [ms]"],
                 summary(rows), ["l", "l", "r", "r", "r", "r", "r", "r", "r", "r", "r"])
    dop = [r for r in rows if "dop853" in r]
    if dop:
        diff = max(abs(r["dop853"] - r["miss"]) for r in dop)
        worst = max(r["dop853"] for r in dop)
        report.paragraph(f"DOP853 (`nonholo.certify.resimulate.resimulate`, rtol = atol = 1e-13) on {len(dop)} of the "
                         f"successes: worst endpoint error {worst:.1e} rad; largest difference from the "
                         f"RK4 check {diff:.1e} rad.")
    if args.baseline:
        timing(report, args.baseline, args.rounds)
    report.paragraph(f"Total time {time.perf_counter() - started:.0f} s with {args.workers} workers.")
    report.write()


if __name__ == "__main__":
    main()
