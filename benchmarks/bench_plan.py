"""Timing of the Jacobian planner on the examples (:mod:`nonholo.paper.examples`; run by hand).

    python -m benchmarks.bench_plan [--repeat 30] [--cold-runs 3]

Measures, and writes to ``benchmarks/results/bench_plan.md`` (also echoed to standard
output; the file is headed by the date, the git commit, the machine and the command, see
:mod:`benchmarks.report`):

Every timing is made for both backends of the kernels (``NONHOLO_BACKEND``): *native* (C
translated from the kernels, the catalog's built at install) and *numba* (compiled at run time).

- start-up: the first :func:`nonholo.plan` of Example 1 (default strategy) in a fresh
  Python process whose caches (``NUMBA_CACHE_DIR``, ``NONHOLO_CACHE_DIR``) are new, empty
  directories — the import time and the first plan's time, which includes compiling or
  loading the kernels — then the same in a second fresh process with those caches, now
  warm; and the first plan with the strategy ``"paper"`` in two more processes on the same
  caches. Median (and range) over ``--cold-runs`` fresh cache directories;
- the cold first plan of each mechanism kind (:data:`FIRST_GOALS`: the platform's Example
  1, the car's ``(0, 0, 0, 0) → (0, 1, 0, 0)``, the ball's ``(I, (0, 0)) → (R_z(π/2), (0,
  0))``), each in a fresh process on new, empty caches; and a mechanism of one's own
  (:data:`OWN_MECHANISM`, the unicycle towing a trailer defined in the script), its first
  and second run;
- for Examples 1 and 2 and both methods (strategy ``"paper"``): median/min/max wall time
  of ``plan`` after warm-up (the backends interleaved), iterations, simulations
  (evaluations), terminal error, the error of a DOP853 re-simulation (rtol = atol = 1e-13)
  of the planned control, the discretisation error of the planner's own endpoint against
  it, and the largest difference of the planned parameters between the backends;
- for Examples 1 and 2, the default call (strategy "robust", ``objective="auto"``) against
  the plan as found, the strategy "paper" and the least energy, interleaved after warm-up;
- the discretisation error of N = 100 … 800 CF4 steps against DOP853 for the initial and
  the planned controls;
- the median time of one bare forward simulation (the CF4 kernel alone) and of one
  planner iteration (simulation with the variational system + Jacobian contraction +
  error + minimum-norm solve + update + admissibility test + history record), their
  ratio (and the largest median ratio), and the ratio of the stage table + variational
  kernel alone; the ratio of the forward kernel's time native / numba.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

from .report import Report

EXAMPLES = {
    1: ((0.5, 1.2, -0.5), (1.0, 0.9, -0.5)),
    2: ((1.5, 1.4, 0.5), (1.5, 1.4, -0.5)),
}

#: The first plan of each mechanism kind in a fresh process: start, goal (Python
#: expressions over ``np`` and ``so3``).
FIRST_GOALS = {
    "platform": ("so3.from_rpy(0.5, 1.2, -0.5)", "so3.from_rpy(1.0, 0.9, -0.5)"),
    "car": ("np.zeros(4)", "np.array([0.0, 1.0, 0.0, 0.0])"),
    "rolling_ball": ("(np.eye(3), np.zeros(2))", "(so3.from_rpy(np.pi / 2, 0.0, 0.0), np.zeros(2))"),
}

#: Run in a fresh interpreter: import nonholo, plan the first goal of mechanism argv[2]
#: (strategy argv[1], or the default), print the times as JSON.
FIRST_PLAN = r"""
import json, sys, time
t0 = time.perf_counter()
import numpy as np
import nonholo
from nonholo.spaces import so3
t1 = time.perf_counter()
kw = {} if sys.argv[1] == "default" else {"strategy": sys.argv[1]}
start, goal = eval(sys.argv[3]), eval(sys.argv[4])
res = nonholo.plan(start, goal, mechanism=sys.argv[2], **kw)
t2 = time.perf_counter()
print(json.dumps({"import": t1 - t0, "plan": t2 - t1, "success": bool(res.success),
                  "strategy": res.strategy}))
"""


#: A mechanism of one's own, built in the script (symbolic definition → generated module →
#: kernels): the unicycle towing one trailer, planned from rest at the origin.
OWN_MECHANISM = r"""
import json, sys, time
t0 = time.perf_counter()
import numpy as np
import sympy as sp
import nonholo
from nonholo.model.mechanism import Mechanism
from derivations.mechanisms import Mechanism as Symbolic
t1 = time.perf_counter()
x, y, th0, th1 = sp.symbols("x y theta0 theta1", real=True)
X = sp.Matrix([[sp.cos(th0), 0], [sp.sin(th0), 0], [0, 1], [sp.sin(th0 - th1), 0]])
sym = Symbolic(name="unicycle_trailer", description="unicycle towing one trailer (hitch length 1)",
               inputs=("v = speed", "w = turn rate"), coordinates=(x, y, th0, th1),
               units=("m", "m", "rad", "rad"), angles=(False, False, True, True), X=X)
mech = Mechanism.from_symbolic(sym)
res = nonholo.plan(np.zeros(4), np.array([1.0, 0.5, 0.0, 0.0]), mechanism=mech)
t2 = time.perf_counter()
print(json.dumps({"import": t1 - t0, "plan": t2 - t1, "success": bool(res.success), "strategy": res.strategy}))
"""

#: The kernels' backends (``NONHOLO_BACKEND``).
BACKENDS = ("native", "numba")


def _env(cache_dir: str, backend: str) -> dict:
    """A fresh process' environment: its numba cache, its native cache (the modules built at
    install stay found), the backend."""
    return dict(os.environ, NUMBA_CACHE_DIR=os.path.join(cache_dir, "numba"),
                NONHOLO_CACHE_DIR=os.path.join(cache_dir, "native"), NONHOLO_BACKEND=backend)


def _own_mechanism(cache_dir: str, backend: str) -> dict:
    t = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", OWN_MECHANISM], capture_output=True, text=True,
                         env=_env(cache_dir, backend), check=False)
    wall = time.perf_counter() - t
    if out.returncode != 0:
        raise RuntimeError(f"fresh process failed (own mechanism):\n{out.stderr}")
    return {**json.loads(out.stdout.strip().splitlines()[-1]), "process": wall}


def _first_plan(cache_dir: str, strategy: str, mechanism: str = "platform", backend: str = "native") -> dict:
    env = _env(cache_dir, backend)
    t = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", FIRST_PLAN, strategy, mechanism, *FIRST_GOALS[mechanism]],
                         capture_output=True, text=True, env=env, check=False)
    wall = time.perf_counter() - t
    if out.returncode != 0:
        raise RuntimeError(f"fresh process failed ({strategy}):\n{out.stderr}")
    return {**json.loads(out.stdout.strip().splitlines()[-1]), "process": wall}


def start_up(report: Report, runs: int) -> None:
    """Cold (empty caches) and warm first plans in fresh processes, for both backends."""
    cases = [(backend, label, strategy) for backend in BACKENDS
             for label, strategy in (("empty caches", "default"), ("warm caches", "default"),
                                     ("caches warmed by the default strategy", "paper"), ("warm caches", "paper"))]
    times = {c: [] for c in cases}
    for _ in range(runs):
        for backend in BACKENDS:
            cache = tempfile.mkdtemp(prefix="nonholo_cache_")
            try:
                for case in cases:
                    if case[0] == backend:
                        times[case].append(_first_plan(cache, case[2], backend=backend))
            finally:
                shutil.rmtree(cache, ignore_errors=True)

    def cell(xs):
        return f"{statistics.median(xs):.2f} ({min(xs):.2f}–{max(xs):.2f})"

    report.heading("Start-up: the first plan in a fresh process")
    report.paragraph(
        "Example 1 (`nonholo.plan(RPY(0.5, 1.2, -0.5), RPY(1.0, 0.9, -0.5))`) in a fresh Python "
        "process, with the kernels' backend `NONHOLO_BACKEND` (*native*: C built at install, "
        "the default; *numba*: compiled by numba at run time), `NUMBA_CACHE_DIR` and "
        "`NONHOLO_CACHE_DIR` new empty directories per run and backend; the processes of one run "
        f"share them, in the order of the rows. Median (min–max) over {runs} runs, seconds. *import*: "
        "`import nonholo`; *first plan*: the `plan` call (with the kernels' compilation or their "
        "loading); *process*: the whole child process as timed by the parent "
        "(interpreter start-up and exit included).")
    rows = []
    for (backend, label, strategy), ts in times.items():
        rows.append([backend, label, f"{ts[0]['strategy']} (default)" if strategy == "default" else strategy,
                     cell([t["import"] for t in ts]), cell([t["plan"] for t in ts]),
                     cell([t["process"] for t in ts]),
                     "yes" if all(t["success"] for t in ts) else "NO"])
    report.table(["backend", "caches", "strategy", "import [s]", "first plan [s]", "process [s]", "success"],
                 rows, ["l", "l", "l", "r", "r", "r", "l"])


def cold_by_mechanism(report: Report, runs: int) -> None:
    """The first plan of each mechanism kind in a fresh process on empty caches, both
    backends; a mechanism of one's own, first and second run."""
    times = {(b, name): [] for b in BACKENDS for name in FIRST_GOALS}
    own = {(b, run): [] for b in BACKENDS for run in ("first run", "second run")}
    for _ in range(runs):
        for backend in BACKENDS:
            for name in FIRST_GOALS:
                cache = tempfile.mkdtemp(prefix="nonholo_cache_")
                try:
                    times[backend, name].append(_first_plan(cache, "default", name, backend))
                finally:
                    shutil.rmtree(cache, ignore_errors=True)
            cache = tempfile.mkdtemp(prefix="nonholo_cache_")
            try:
                for run in ("first run", "second run"):
                    own[backend, run].append(_own_mechanism(cache, backend))
            finally:
                shutil.rmtree(cache, ignore_errors=True)

    def cell(xs):
        return f"{statistics.median(xs):.2f} ({min(xs):.2f}–{max(xs):.2f})"

    report.heading("Start-up by mechanism: the first plan on empty caches")
    report.paragraph(
        "`nonholo.plan(start, goal, mechanism=...)` with the default strategy in a fresh Python "
        "process, `NUMBA_CACHE_DIR` and `NONHOLO_CACHE_DIR` new empty directories per process "
        "(native: the catalog's modules built at install; numba: every kernel the plan needs "
        "compiled). *own mechanism*: a script that defines the unicycle towing one trailer "
        "symbolically, builds it with `Mechanism.from_symbolic` and plans `0 → (1, 0.5, 0, 0)`; "
        "*first run* on empty caches (generation, compilation), *second run* on what the first "
        "left in them; its *first plan* includes `from_symbolic`. "
        f"Median (min–max) over {runs} runs, seconds.")
    rows = [[backend, name, f"`{a}` → `{b}`", cell([t["import"] for t in times[backend, name]]),
             cell([t["plan"] for t in times[backend, name]]), cell([t["process"] for t in times[backend, name]]),
             "yes" if all(t["success"] for t in times[backend, name]) else "NO"]
            for backend in BACKENDS for name, (a, b) in FIRST_GOALS.items()]
    rows += [[backend, f"own mechanism, {run}", "`0` → `(1, 0.5, 0, 0)`",
              cell([t["import"] for t in own[backend, run]]), cell([t["plan"] for t in own[backend, run]]),
              cell([t["process"] for t in own[backend, run]]),
              "yes" if all(t["success"] for t in own[backend, run]) else "NO"]
             for backend in BACKENDS for run in ("first run", "second run")]
    report.table(["backend", "mechanism", "start → goal", "import [s]", "first plan [s]", "process [s]", "success"],
                 rows, ["l", "l", "l", "r", "r", "r", "l"])


def _median_interleaved(fns: dict, repeat: int, number: int) -> dict:
    """CPU time of this thread per call (``time.thread_time``: what other processes on a
    shared machine do stays out of the ratios), ``repeat`` samples of ``number`` calls,
    the functions interleaved."""
    times = {k: [] for k in fns}
    for _ in range(repeat):
        for k, f in fns.items():
            t = time.thread_time()
            for _ in range(number):
                f()
            times[k].append((time.thread_time() - t) / number)
    return {k: np.array(v) for k, v in times.items()}


class _backend:
    """``with _backend("numba"):`` — the kernels' backend in this process, for a while."""

    def __init__(self, backend: str):
        self.backend = backend

    def __enter__(self):
        self.old = os.environ.get("NONHOLO_BACKEND")
        os.environ["NONHOLO_BACKEND"] = self.backend

    def __exit__(self, *exc):
        if self.old is None:
            os.environ.pop("NONHOLO_BACKEND", None)
        else:
            os.environ["NONHOLO_BACKEND"] = self.old


def plan_times(report: Report, repeat: int) -> None:
    from nonholo import Settings
    from nonholo.certify.resimulate import resimulate, terminal_error
    from nonholo.planning.api import METHODS, plan
    from nonholo.spaces import so3

    report.heading('plan() after warm-up (strategy "paper")')
    report.paragraph(
        f"Wall time of `plan` over {repeat} calls after one warm-up call (ms); *evaluations*: "
        "simulations with the variational system (iterations + 1 + rejected steps); *|l_T|*: the "
        "planner's terminal error; *re-simulated*: terminal error of the planned control "
        "re-simulated by DOP853 (rtol = atol = 1e-13); *discretisation*: geodesic distance "
        "between the planner's R(T) and DOP853's (rad).")
    rows = []
    medians = {}
    for k, (a, b) in EXAMPLES.items():
        R0, Rd = so3.from_rpy(*a), so3.from_rpy(*b)
        for method in METHODS:
            ts = {backend: [] for backend in BACKENDS}
            results = {}
            for backend in BACKENDS:                       # warm-up
                with _backend(backend):
                    plan(R0, Rd, settings=Settings(method=method), strategy="paper")
            for _ in range(repeat):                        # the backends interleaved
                for backend in BACKENDS:
                    with _backend(backend):
                        t = time.perf_counter()
                        results[backend] = plan(R0, Rd, settings=Settings(method=method), strategy="paper")
                        ts[backend].append(time.perf_counter() - t)
            for backend in BACKENDS:
                res = results[backend]
                medians[k, method, backend] = statistics.median(ts[backend])
                evals = res.iterations + 1 + sum(h["rejected"] for h in res.history)
                R_ref = resimulate(R0, res.controls, res.T, res.mechanism, res.breakpoints)
                rows.append([k, method, backend, f"{1e3 * statistics.median(ts[backend]):.2f}",
                             f"{1e3 * min(ts[backend]):.2f}", f"{1e3 * max(ts[backend]):.2f}", res.iterations,
                             evals, f"{res.terminal_error:.2e}", f"{terminal_error(R_ref, Rd):.2e}",
                             f"{so3.distance(res.R_T, R_ref):.2e}"])
            a_, b_ = results["native"], results["numba"]
            rows[-1].append(f"{float(np.abs(a_.parametrisation.params - b_.parametrisation.params).max()):.1e}")
            rows[-2].append("")
    report.table(["example", "method", "backend", "median [ms]", "min [ms]", "max [ms]", "iterations",
                  "evaluations", "|l_T|", "re-simulated", "discretisation", "|Δλ| native vs numba"], rows,
                 ["r", "l", "l"] + ["r"] * 9)
    ratio = max(medians[k, m, "native"] / medians[k, m, "numba"] for k in EXAMPLES for m in METHODS)
    report.paragraph(f"Largest ratio of median plan times native / numba: **{ratio:.2f}**.")


def discretisation(report: Report) -> None:
    from nonholo import Settings
    from nonholo.certify.resimulate import resimulate
    from nonholo.motion.simulation import simulate
    from nonholo.planning.api import METHODS, initial_controls, plan
    from nonholo.spaces import so3

    counts = (100, 200, 400, 800)
    report.heading("Discretisation error of N CF4 steps")
    report.paragraph(
        "Geodesic distance (rad) between R(T) after N CF4 steps and DOP853 (rtol = atol = 1e-13), "
        "T = 1, for the initial control `u = 0.3 (sin 2πt, cos 2πt)` and the control planned by "
        'the strategy "paper".')
    rows = []
    for k, (a, b) in EXAMPLES.items():
        R0, Rd = so3.from_rpy(*a), so3.from_rpy(*b)
        for method in METHODS:
            for label, par in (("initial", initial_controls(method, 1.0, 2, 2, 100)),
                               ("planned", plan(R0, Rd, settings=Settings(method=method),
                                                strategy="paper").parametrisation)):
                R_ref = resimulate(R0, par, 1.0)
                rows.append([k, method, label] + [f"{so3.distance(simulate(R0, par, 1.0, steps=n).R_T, R_ref):.1e}"
                                                  for n in counts])
    report.table(["example", "method", "control"] + [f"N = {n}" for n in counts], rows,
                 ["r", "l", "l"] + ["r"] * len(counts))


def iteration_cost(report: Report, repeat: int) -> None:
    from nonholo.model import catalog
    from nonholo.planning.api import METHODS
    from nonholo.spaces import so3

    report.heading("One iteration vs one bare forward simulation")
    report.paragraph(
        "Kernels called directly, µs of CPU time of the measuring thread per call; median and min over "
        f"{repeat} repeats of 20 calls, the three measurements interleaved. *forward*: the CF4 "
        "kernel alone on a precomputed stage table; *iteration*: what the strategy \"paper\" does "
        "per accepted step — `EndpointMap.evaluate` (stage table, CF4 with the variational system and "
        "the Jacobian, log error), the minimum-norm solve, the parameter update, the "
        "admissibility test and the history record; *kernel*: the stage table "
        "(`stages.stage_function`) and the variational kernel alone.")
    mech = catalog.get("platform")
    rows = []
    ratios = {backend: [] for backend in BACKENDS}
    forwards = {}
    for k, (a, b) in EXAMPLES.items():
        R0, Rd = so3.from_rpy(*a), so3.from_rpy(*b)
        for method, backend in ((m, b) for m in METHODS for b in BACKENDS):
            with _backend(backend):
                _iteration_rows(rows, ratios, forwards, k, R0, Rd, method, backend, mech, repeat)
    report.table(["example", "method", "backend", "N", "statistic", "forward [µs]", "iteration [µs]",
                  "iteration / forward", "kernel [µs]", "kernel / forward"], rows,
                 ["r", "l", "l", "r", "l"] + ["r"] * 5)
    report.paragraph("Largest median ratio iteration / forward: " + ", ".join(
        f"{b} **{max(r):.2f}**" for b, r in ratios.items()) + "; largest ratio of the forward "
        "kernel's median time native / numba: " + f"**{max(forwards[k, m, 'native'] / forwards[k, m, 'numba'] for k, m, _ in forwards):.2f}**.")


def _iteration_rows(rows, ratios, forwards, k, R0, Rd, method, backend, mech, repeat) -> None:
    """One row pair of :func:`iteration_cost` (median and min) in the current backend."""
    from nonholo import Settings, State
    from nonholo.controls import stages
    from nonholo.numerics import kernels
    from nonholo.planning.api import plan
    from nonholo.planning.core import record, step_scale
    from nonholo.planning.endpoint_map import EndpointMap

    res = plan(R0, Rd, settings=Settings(method=method), strategy="paper")
    steps = res.steps
    par = res.parametrisation
    prob = EndpointMap(State(R0, np.zeros(0)), State(Rd, np.zeros(0)), 1.0, mech, method, steps, 1e-2)
    prob.use(par)
    params = par.params.copy()
    scale = step_scale(prob, par)
    U = stages.stage_table(par, steps)
    kern = prob.kernels
    Rs, Qs = kern.nodes(steps)

    def forward():
        kern.forward(*prob.start, U, prob.h, prob.sign, 1e-2, Rs, Qs)

    def iteration():
        ev = prob.evaluate(params)
        d = kernels.min_norm_step(ev.J, ev.l, scale)
        trial = params - 0.5 * d
        ok = prob.admissible(ev) and ev.error < 1.0
        record(1, ev, 0.5, "flow", int(not ok))
        return trial

    fill = stages.stage_function(par, steps)
    basis = prob.stage_basis
    m = mech.n_inputs
    U2 = np.empty((steps, 3, m))
    Zs = np.empty((steps + 1, 3, 3))
    J = np.empty((3, params.size))
    M = np.empty((3, 3))
    Wd = np.empty((3 * steps, 3 * m))

    def variational_kernel():
        fill(params, U2)
        kern.forward_variational(*prob.start, U2, prob.h, prob.sign, 1e-2, *basis, Rs, Qs, Zs,
                                 J, M, Wd, False)

    t = _median_interleaved({"forward": forward, "iteration": iteration,
                             "kernel": variational_kernel}, repeat, 20)
    for stat in (np.median, np.min):
        f, it, kv = (stat(t[x]) * 1e6 for x in ("forward", "iteration", "kernel"))
        if stat is np.median:
            ratios[backend].append(it / f)
            forwards[k, method, backend] = f
        rows.append([k, method, backend, steps, stat.__name__, f"{f:.1f}", f"{it:.1f}", f"{it / f:.2f}",
                     f"{kv:.1f}", f"{kv / f:.2f}"])


#: The calls of :func:`default_times`: the default, then its parts (keywords of ``plan``).
DEFAULT_CALLS = {"default (robust, objective \"auto\")": {},
                 "plan as found (robust, objective=None)": {"objective": None},
                 "paper, objective \"auto\"": {"strategy": "paper"},
                 "paper, objective=None": {"strategy": "paper", "objective": None},
                 "least energy (objective \"energy\")": {"objective": "energy"}}


def default_times(report: Report, repeat: int) -> None:
    """Warm Examples 1 and 2 with ``plan()``'s defaults against the plan as found, the
    strategy "paper" and the least energy: median wall time, the calls interleaved."""
    from nonholo.planning.api import plan
    from nonholo.spaces import so3

    report.heading("The default call after warm-up")
    report.paragraph(
        f"Wall time of `plan(R0, Rd, **keywords)` (native kernels), median (min) over {repeat} calls "
        "after one warm-up call each, the calls interleaved (ms); */ as found*: the median over the "
        "plan as found's (`objective=None`, the default strategy).")
    rows = []
    for k, (a, b) in EXAMPLES.items():
        R0, Rd = so3.from_rpy(*a), so3.from_rpy(*b)
        ts = {label: [] for label in DEFAULT_CALLS}
        for kw in DEFAULT_CALLS.values():
            plan(R0, Rd, **kw)
        for _ in range(repeat):
            for label, kw in DEFAULT_CALLS.items():
                t = time.perf_counter()
                plan(R0, Rd, **kw)
                ts[label].append(time.perf_counter() - t)
        found = statistics.median(ts["plan as found (robust, objective=None)"])
        for label, xs in ts.items():
            rows.append([k, label, f"{1e3 * statistics.median(xs):.2f}", f"{1e3 * min(xs):.2f}",
                         f"{statistics.median(xs) / found:.2f}"])
    report.table(["example", "call", "median [ms]", "min [ms]", "/ as found"], rows, ["r", "l", "r", "r", "r"])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=30)
    ap.add_argument("--cold-runs", type=int, default=3, help="fresh numba caches for the start-up times")
    args = ap.parse_args(argv)

    report = Report("bench_plan.md", "Planner timing on Examples 1 and 2 (bench_plan)",
                    "benchmarks.bench_plan", argv)
    start_up(report, args.cold_runs)
    cold_by_mechanism(report, args.cold_runs)
    plan_times(report, args.repeat)
    default_times(report, args.repeat)
    discretisation(report)
    iteration_cost(report, args.repeat)
    report.write()


if __name__ == "__main__":
    main()
