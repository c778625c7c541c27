"""A mechanism of one's own: how long a script waits for it (run by hand).

    python -m benchmarks.bench_own_mechanism [--runs 3]

Writes ``benchmarks/results/own_mechanism.md`` (headed by the date, the git commit, the
machine and the command, see :mod:`benchmarks.report`):

- the unicycle towing one trailer, defined in a script by the call of
  ``Mechanism.from_equations`` and planned ``0 → (1, 0.5, 0, 0)``: a first run in a fresh
  process on a new, empty cache (``NONHOLO_CACHE_DIR``: derivation, generation,
  compilation), then a second run in another fresh process on what the first left there;
  the import, the definition, the first plan and the whole process;
- the car towing a trailer of ``docs/guide/car_trailer.toml``, read by
  ``Mechanism.from_file`` and planned ``0 → (1, 0.5, 0, 0, 0)``, and ``nonholo plan
  --mechanism`` on the file, first and second runs as above;
- platforms of numbers (``platform_mechanism`` on a geometry of floats, the exact route of
  ``derivations.mechanisms.exact_platform``), each in a fresh process: the derivation and
  the generation of its module, then (``Mechanism.from_symbolic`` on an empty cache) the
  compilation and first plan; the paper's symbolic geometry beside them;
- the exact route against the symbolic one on the paper's and the raised geometries (at the
  drawing dimensions): the largest relative difference of every generated function at
  random rotations with ``|Δ| > 0.05``.

The kernels' backend is the default (native).
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

#: The script of one's own: the issue's call, then the first plan (times printed as JSON).
TRAILER = r"""
import json, time
t0 = time.perf_counter()
import numpy as np
import sympy as sp
from sympy import cos, sin
import nonholo
t1 = time.perf_counter()
x, y, th0, th1, v, w = sp.symbols("x y theta0 theta1 v w")
rates = [v*cos(th0), v*sin(th0), w, v*sin(th0 - th1)]
t2 = time.perf_counter()
m = nonholo.Mechanism.from_equations("trailer1", coordinates=[x, y, th0, th1], inputs=[v, w],
                                     rates=rates, angles=[th0, th1])
t3 = time.perf_counter()
res = nonholo.plan(np.zeros(4), np.array([1.0, 0.5, 0.0, 0.0]), mechanism=m)
t4 = time.perf_counter()
print(json.dumps({"import": t1 - t0, "equations": t2 - t1, "define": t3 - t2, "plan": t4 - t3,
                  "success": bool(res.success)}))
"""

#: A mechanism file (argv[1]): read, then the first plan (times printed as JSON).
FROM_FILE = r"""
import json, sys, time
t0 = time.perf_counter()
import numpy as np
import nonholo
t1 = time.perf_counter()
m = nonholo.Mechanism.from_file(sys.argv[1])
t2 = time.perf_counter()
res = nonholo.plan(np.zeros(5), np.array([1.0, 0.5, 0.0, 0.0, 0.0]), mechanism=m)
t3 = time.perf_counter()
again = nonholo.plan(np.zeros(5), np.array([1.0, 0.5, 0.0, 0.0, 0.0]), mechanism=m)
t4 = time.perf_counter()
print(json.dumps({"import": t1 - t0, "define": t2 - t1, "plan": t3 - t2, "again": t4 - t3,
                  "success": bool(res.success and again.success)}))
"""

#: The mechanism file of the docs (a car towing a trailer).
CAR_TRAILER = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "docs", "guide",
                           "car_trailer.toml")

#: A platform of numbers (argv[1]: a geometry as JSON, or "paper"): derivation and
#: generation, then compilation and the first plan from argv[2] to argv[3] (RPY).
PLATFORM = r"""
import json, sys, time
import numpy as np
import sympy as sp
import nonholo
from derivations import codegen
from derivations.mechanisms import PAPER_GEOMETRY, PlatformGeometry, platform_mechanism
from nonholo.spaces import so3
geometry = PAPER_GEOMETRY if sys.argv[1] == "paper" else PlatformGeometry(**json.loads(sys.argv[1]))
t0 = time.perf_counter()
sym = platform_mechanism("bench_platform", geometry, "a platform of the benchmark")
t1 = time.perf_counter()
source = codegen.mechanism_module(sym)
t2 = time.perf_counter()
m = nonholo.Mechanism.from_symbolic(sym)
R0, Rd = so3.from_rpy(*json.loads(sys.argv[2])), so3.from_rpy(*json.loads(sys.argv[3]))
res = nonholo.plan(R0, Rd, mechanism=m)
t3 = time.perf_counter()
print(json.dumps({"derive": t1 - t0, "generate": t2 - t1, "first plan": t3 - t2, "success": bool(res.success),
                  "lines": source.count("\n")}))
"""

def on_sphere(*v) -> tuple:
    """The point of the unit sphere in the direction ``v`` (the sphere's radius is the unit of
    length: a platform's joints and contact point lie on it)."""
    return tuple(float(x) for x in np.asarray(v, dtype=float) / np.linalg.norm(v))


def tangent(axle, contact) -> tuple:
    """``axle`` without its component along ``contact``: tangent to the sphere there."""
    axle, n = np.asarray(axle, dtype=float), np.asarray(on_sphere(*contact))
    return tuple(float(x) for x in axle - (axle @ n) * n)


#: Geometries of floats (``PlatformGeometry`` fields), a start and a goal of each (RPY). The
#: CAD-like placement's measurements (three decimals) are put on the sphere: its platform
#: joints and contact point moved along their directions, its axle made tangent.
GEOMETRIES = {
    "legs and disk placed at will (notebook 07)": (
        dict(base1=(0.3, 1.5, 0.4), tip1=on_sphere(0.1, 1.0, 0.0), base2=(1.5, -0.2, 0.5),
             tip2=on_sphere(1.0, 0.0, 0.1), contact=(0.0, 0.6, 0.8), axle=(1.0, 0.0, 0.0)),
        (0, 0, 0), (0.6, 0.4, -0.3)),
    "bases raised, disk off the pole (README)": (
        dict(base1=(0.0, 1.6, 0.5), tip1=(0.0, 1.0, 0.0), base2=(1.6, 0.0, 0.5), tip2=(1.0, 0.0, 0.0),
             contact=(0.6, 0.0, 0.8), axle=(0.0, 1.0, 0.0)), (0.5, 1.2, -0.5), (1.0, 0.9, -0.5)),
    "a CAD-like placement (three decimals, put on the sphere)": (
        dict(base1=(0.112, 1.487, 0.613), tip1=on_sphere(0.021, 0.804, 0.113), base2=(1.734, 0.288, -0.171),
             tip2=on_sphere(0.792, -0.214, 0.036), contact=on_sphere(-0.437, 0.218, 0.873),
             axle=tangent((0.894, 0.0, 0.447), (-0.437, 0.218, 0.873))),
        (0, 0, 0), (-0.3, 0.2, 0.1)),
}


def fresh(script: str, args, cache: str) -> dict:
    """Run ``script`` in a fresh interpreter on the cache directory ``cache``; its JSON and wall time."""
    env = dict(os.environ, NONHOLO_CACHE_DIR=cache, NUMBA_CACHE_DIR=os.path.join(cache, "numba"))
    t = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", script, *args], capture_output=True, text=True, env=env, check=False)
    wall = time.perf_counter() - t
    if out.returncode != 0:
        raise RuntimeError(f"fresh process failed:\n{out.stderr}")
    return {**json.loads(out.stdout.strip().splitlines()[-1]), "process": wall}


def cell(xs) -> str:
    return f"{statistics.median(xs):.2f} ({min(xs):.2f}–{max(xs):.2f})"


def trailer(report: Report, runs: int) -> None:
    times = {run: [] for run in ("first run", "second run")}
    for _ in range(runs):
        cache = tempfile.mkdtemp(prefix="nonholo_own_")
        try:
            for run in times:
                times[run].append(fresh(TRAILER, [], cache))
        finally:
            shutil.rmtree(cache, ignore_errors=True)
    report.heading("The unicycle with one trailer, defined in a script")
    report.paragraph(
        "`Mechanism.from_equations(\"trailer1\", coordinates=[x, y, th0, th1], inputs=[v, w], "
        "rates=[v*cos(th0), v*sin(th0), w, v*sin(th0 - th1)], angles=[th0, th1])`, then "
        "`nonholo.plan(0, (1, 0.5, 0, 0))`, in a fresh process: the *first run* on a new, empty "
        "cache directory (derivation, generation, compilation of the kernels), the *second run* "
        f"in another fresh process on what the first left there. Median (min–max) over {runs} "
        "cache directories, seconds. *equations*: writing the SymPy expressions (SymPy's own "
        "first use); *definition*: the `from_equations` call; *first goal*: definition + first "
        "plan; *process*: the whole child process as timed by the parent (interpreter start-up "
        "and `import nonholo` included).")
    rows = [[run, cell([t["import"] for t in ts]), cell([t["equations"] for t in ts]),
             cell([t["define"] for t in ts]), cell([t["plan"] for t in ts]),
             cell([t["define"] + t["plan"] for t in ts]), cell([t["process"] for t in ts]),
             "yes" if all(t["success"] for t in ts) else "NO"]
            for run, ts in times.items()]
    report.table(["run", "import [s]", "equations [s]", "definition [s]", "first plan [s]", "first goal [s]",
                  "process [s]", "success"], rows, ["l", "r", "r", "r", "r", "r", "r", "l"])


def command(args: list, cache: str) -> float:
    """Wall time of ``python -m nonholo.cli ARGS`` in a fresh process on the cache ``cache``."""
    env = dict(os.environ, NONHOLO_CACHE_DIR=cache, NUMBA_CACHE_DIR=os.path.join(cache, "numba"))
    t = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "nonholo.cli", *args], capture_output=True, text=True, env=env,
                         check=False)
    wall = time.perf_counter() - t
    if out.returncode != 0:
        raise RuntimeError(f"nonholo {' '.join(args)} failed:\n{out.stderr}")
    return wall


def mechanism_file(report: Report, runs: int) -> None:
    times = {run: [] for run in ("first run", "second run")}
    cli = {run: [] for run in times}
    plan = ["plan", "--mechanism", CAR_TRAILER, "--from", *["0"] * 5, "--to", "1", "0.5", "0", "0", "0", "--quiet"]
    for _ in range(runs):
        for store in (times, cli):
            cache = tempfile.mkdtemp(prefix="nonholo_file_")
            try:
                for run in store:
                    store[run].append(fresh(FROM_FILE, [CAR_TRAILER], cache) if store is times
                                      else command(plan, cache))
            finally:
                shutil.rmtree(cache, ignore_errors=True)
    report.heading("The car with a trailer, in a mechanism file")
    report.paragraph(
        "`Mechanism.from_file(\"docs/guide/car_trailer.toml\")` (*definition*: reading and checking "
        "the file, deriving, generating and compiling its kernels, or reading them from the cache), "
        "then `nonholo.plan(0, (1, 0.5, 0, 0, 0))`, in a fresh process on a new, empty cache "
        "directory (*first run*) and in another on what it left (*second run*); *command*: "
        "`nonholo plan --mechanism docs/guide/car_trailer.toml --from 0 0 0 0 0 --to 1 0.5 0 0 0` "
        "as a whole process, on a cache of its own. "
        "*plan again*: the same plan once more in the same process (the planning itself, nothing "
        "left to derive or compile); *cache's share*: definition + first plan − plan again, what "
        "the cache of generated modules and kernels serves. "
        f"Median (min–max) over {runs} cache directories, seconds.")
    rows = [[run, cell([t["import"] for t in ts]), cell([t["define"] for t in ts]), cell([t["plan"] for t in ts]),
             cell([t["again"] for t in ts]), cell([t["define"] + t["plan"] - t["again"] for t in ts]),
             cell([t["process"] for t in ts]), cell(cli[run]), "yes" if all(t["success"] for t in ts) else "NO"]
            for run, ts in times.items()]
    report.table(["run", "import [s]", "definition [s]", "first plan [s]", "plan again [s]", "cache's share [s]",
                  "process [s]", "command [s]", "success"], rows, ["l", "r", "r", "r", "r", "r", "r", "r", "l"])


def platforms(report: Report, runs: int) -> None:
    cases = {name: (json.dumps(g), json.dumps(start), json.dumps(goal)) for name, (g, start, goal) in GEOMETRIES.items()}
    cases["the paper's geometry, symbolic a, b, ρ (the symbolic route)"] = (
        "paper", json.dumps((0.5, 1.2, -0.5)), json.dumps((1.0, 0.9, -0.5)))
    times = {name: [] for name in cases}
    for _ in range(runs):
        for name, args in cases.items():
            cache = tempfile.mkdtemp(prefix="nonholo_own_")
            try:
                times[name].append(fresh(PLATFORM, list(args), cache))
            finally:
                shutil.rmtree(cache, ignore_errors=True)
    report.heading("Platforms of numbers: derivation and generation")
    report.paragraph(
        "`platform_mechanism(name, geometry, ...)` (*derive*) and `codegen.mechanism_module` "
        "(*generate*) in a fresh process (SymPy imported, its caches empty), a geometry of floats "
        "taking the exact route (`derivations.mechanisms.exact_platform`: no simplification of "
        "rational functions, W = C₁₂ N without inversion); then `Mechanism.from_symbolic` on an "
        "empty cache and the first plan between two orientations on one side of its Δ = 0 — that "
        "column includes compiling the kernels. "
        f"Median (min–max) over {runs} runs, seconds; *lines*: the generated module's.")
    rows = [[name, cell([t["derive"] for t in ts]), cell([t["generate"] for t in ts]),
             cell([t["derive"] + t["generate"] for t in ts]), cell([t["first plan"] for t in ts]),
             ts[0]["lines"], "yes" if all(t["success"] for t in ts) else "NO"]
            for name, ts in times.items()]
    report.table(["geometry", "derive [s]", "generate [s]", "derive + generate [s]",
                  "compile + first plan [s]", "lines", "success"], rows, ["l", "r", "r", "r", "r", "r", "l"])


def agreement(report: Report) -> None:
    import sympy as sp

    from derivations import codegen
    from derivations.definitions import RAISED_GEOMETRY
    from derivations.mechanisms import PAPER_GEOMETRY, PlatformGeometry, a, b, platform_mechanism, rho
    from nonholo.codegen.mechanism_modules import load_source
    from nonholo.model import catalog
    from scipy.spatial.transform import Rotation

    dims = {a: sp.Rational(8, 5), b: 1, rho: 1}
    functions = ("G", "QG", "delta", "N", "QN", "W", "leg_lengths", "leg_gradients")
    rows = []
    for name, geometry in (("platform", PAPER_GEOMETRY), ("platform_raised", RAISED_GEOMETRY)):
        numbers = PlatformGeometry(**{k: tuple(sp.sympify(x).subs(dims) for x in getattr(geometry, k))
                                      for k in ("base1", "tip1", "base2", "tip2", "contact", "axle")})
        mine = load_source(codegen.mechanism_module(platform_mechanism("exact_" + name, numbers, "")), "exact")
        ref = catalog.get(name).module
        q = ref.NO_COORDINATES
        rng = np.random.default_rng(2026)
        worst, n = dict.fromkeys(functions, 0.0), 0
        while n < 500:
            R = Rotation.random(random_state=rng.integers(1 << 31)).as_matrix()
            if abs(ref.delta(R, q)) <= 0.05:
                continue
            n += 1
            v = rng.normal(size=2)
            for f in functions:
                args = (R,) if f.startswith("leg") else (R, q, v) if f.startswith("Q") else (R, q)
                got, want = np.asarray(getattr(mine, f)(*args)), np.asarray(getattr(ref, f)(*args))
                worst[f] = max(worst[f], float(np.max(np.abs(got - want)) / max(1.0, np.max(np.abs(want)))))
        rows.append([f"`{name}`", n] + [f"{worst[f]:.1e}" for f in functions])
    report.heading("The exact route against the symbolic route")
    report.paragraph(
        "The catalog's platforms at the drawing dimensions (a = 8/5, b = ρ = 1: numbers, so the "
        "exact route) against their generated modules (the symbolic route, a, b, ρ symbols; the "
        "kinematics do not depend on them): the largest difference of each generated function, "
        "relative to max(1, its largest entry), at random rotations with |Δ| > 0.05.")
    report.table(["mechanism", "rotations", *functions], rows)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=3, help="fresh cache directories per measurement")
    args = ap.parse_args(argv)
    report = Report("own_mechanism.md", "A mechanism of one's own (bench_own_mechanism)",
                    "benchmarks.bench_own_mechanism", argv, extra_packages=("sympy",))
    load = os.getloadavg()[0]
    trailer(report, args.runs)
    mechanism_file(report, args.runs)
    platforms(report, args.runs)
    agreement(report)
    report.paragraph(f"Load average (1 min) of the machine when the measurements started and ended: "
                     f"{load:.1f} and {os.getloadavg()[0]:.1f}, on {os.cpu_count()} cores (other work "
                     "beside these processes slows every row alike).")
    report.write()


if __name__ == "__main__":
    main()
