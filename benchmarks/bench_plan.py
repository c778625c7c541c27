"""Timing of the Jacobian planner on the examples of MODEL.md (run by hand).

    python -m benchmarks.bench_plan [--repeat 30]

Prints, for Examples 1 and 2 and both methods (strategy "paper"): median/min/max wall time of ``plan`` (after
warm-up), iterations, terminal error; the median time of one bare forward simulation
(the CF4 kernel alone) and of one planner iteration (simulation with the variational
system + Jacobian contraction + error + minimum-norm solve), and their ratio; the
discretisation error of the default step count against DOP853 (rtol = atol = 1e-13) for
the initial and the planned controls; and the first-call (import + JIT or cache load) time.
"""
from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time

import numpy as np

EXAMPLES = {
    1: ((0.5, 1.2, -0.5), (1.0, 0.9, -0.5)),
    2: ((1.5, 1.4, 0.5), (1.5, 1.4, -0.5)),
}

FIRST_CALL = """
import time
t0 = time.perf_counter()
from nonholo import planner, so3
r = planner.plan(so3.from_rpy(0.5, 1.2, -0.5), so3.from_rpy(1.0, 0.9, -0.5), strategy="paper")
print(time.perf_counter() - t0)
"""


def _median_interleaved(fns: dict, repeat: int, number: int) -> dict:
    times = {k: [] for k in fns}
    for _ in range(repeat):
        for k, f in fns.items():
            t = time.perf_counter()
            for _ in range(number):
                f()
            times[k].append((time.perf_counter() - t) / number)
    return {k: np.array(v) for k, v in times.items()}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=30)
    args = ap.parse_args(argv)

    out = subprocess.run([sys.executable, "-c", FIRST_CALL], capture_output=True, text=True, check=True)
    print(f"first call in a fresh process (imports + kernels from the numba cache + plan): "
          f"{float(out.stdout):.2f} s")

    from nonholo import kernels, planner, so3, verify
    from nonholo.simulation import simulate

    print("\nplan() wall time after warm-up (ms):")
    print(f"{'example':>8} {'method':>14} {'median':>8} {'min':>8} {'max':>8} {'iters':>6} "
          f"{'evals':>6} {'|l_T|':>9} {'resim err':>9} {'disc. err':>9}")
    for k, (a, b) in EXAMPLES.items():
        R0, Rd = so3.from_rpy(*a), so3.from_rpy(*b)
        for method in planner.METHODS:
            res = planner.plan(R0, Rd, method=method, strategy="paper")
            ts = []
            for _ in range(args.repeat):
                t = time.perf_counter()
                res = planner.plan(R0, Rd, method=method, strategy="paper")
                ts.append(time.perf_counter() - t)
            evals = res.iterations + 1 + sum(h["rejected"] for h in res.history)
            R_ref = verify.resimulate(R0, res.controls, res.T, res.mechanism, res.breakpoints)
            disc = so3.distance(res.R_T, R_ref)
            print(f"{k:>8} {method:>14} {1e3 * statistics.median(ts):8.2f} {1e3 * min(ts):8.2f} "
                  f"{1e3 * max(ts):8.2f} {res.iterations:6d} {evals:6d} {res.terminal_error:9.2e} "
                  f"{verify.terminal_error(R_ref, Rd):9.2e} {disc:9.2e}")

    print("\ndiscretisation error of N CF4 steps vs DOP853 (geodesic distance of R(T), rad):")
    for k, (a, b) in EXAMPLES.items():
        R0, Rd = so3.from_rpy(*a), so3.from_rpy(*b)
        for method in planner.METHODS:
            for label, par in (("initial", planner.initial_controls(method, 1.0, 2, 2, 100)),
                               ("planned", planner.plan(R0, Rd, method=method, strategy="paper").parametrisation)):
                R_ref = verify.resimulate(R0, par, 1.0)
                errs = [so3.distance(simulate(R0, par, 1.0, steps=n).R_T, R_ref) for n in (100, 200, 400, 800)]
                print(f"  example {k} {method:>13} {label:>8}: " +
                      "  ".join(f"N={n}: {e:.1e}" for n, e in zip((100, 200, 400, 800), errs)))

    print("\none iteration vs one bare forward simulation (kernels called directly, µs; median and min"
          " over repeats of 20 calls, interleaved):")
    print("  iteration = what the paper strategy does per accepted step: Problem.evaluate (stage table,")
    print("  CF4 with the variational system and the Jacobian, log error), the minimum-norm solve, the")
    print("  parameter update, the admissibility test and the history record.")
    ratios = []
    for k, (a, b) in EXAMPLES.items():
        R0, Rd = so3.from_rpy(*a), so3.from_rpy(*b)
        for method in planner.METHODS:
            res = planner.plan(R0, Rd, method=method, strategy="paper")
            steps = res.steps
            prob = planner.Problem(R0, Rd, 1.0, "platform", method, steps, 1e-2)
            par = res.parametrisation
            prob.use(par)
            params = par.params
            strat = planner.PaperStrategy(planner.Options())
            metric = strat.metric(prob, par)
            scale = np.ones(params.size) if metric is None else 1.0 / np.sqrt(metric)
            U = par.stage_table(steps)
            Rs = np.empty((steps + 1, 3, 3))
            kern = prob.kernels

            def forward():
                kern.forward(prob.R0, U, prob.h, prob.sign, 1e-2, Rs)

            def iteration():
                ev = prob.evaluate(params)
                d = kernels.min_norm_step(ev.J, ev.l, scale)
                trial = params - 0.5 * d
                ok = prob.admissible(ev) and ev.error < 1.0
                planner._record(1, ev, 0.5, "flow", int(not ok))
                return trial

            Zs = np.empty((steps + 1, 3, 3))
            J = np.empty((3, params.size))
            M = np.empty((3, 3))
            U2 = np.empty_like(U)

            def variational_kernel():
                prob._fill(params, U2)
                kern.forward_variational(prob.R0, U2, prob.h, prob.sign, 1e-2, *prob._basis, Rs, Zs, J, M,
                                         prob._Wd, False)

            t = _median_interleaved({"forward": forward, "iteration": iteration,
                                     "kernel": variational_kernel}, args.repeat, 20)
            for stat in (np.median, np.min):
                f, it, kv = (stat(t[x]) * 1e6 for x in ("forward", "iteration", "kernel"))
                if stat is np.median:
                    ratios.append(it / f)
                print(f"  example {k} {method:>13} (N = {steps}, {stat.__name__:>6}): forward {f:6.1f}   "
                      f"iteration {it:6.1f}   ratio {it / f:4.2f}   "
                      f"(stage table + variational kernel {kv:6.1f}, ratio {kv / f:4.2f})")
    print(f"  largest median ratio: {max(ratios):.2f}")


if __name__ == "__main__":
    main()
