"""Dynobench's instances planned by ``nonholo dynobench``, beside the best published results.

For each instance copied under ``benchmarks/dynobench/``: the whole command's wall time (a
fresh process: imports, reading, planning, export and check), whether the trajectory passes
the project's own checker and — where the ``dynobench`` bindings are installed — Dynobench's
own model functions (its Euler step, distance and FCL collision distance), and its cost
beside the best final cost J_f and iDb-A*'s time to its first solution, medians over 20 runs
from the 2024 table of the iDb-A* paper (T-RO preprint arXiv 2311.03553; Intel i9-14900KF).
The command returns one solution, so its time is also its time to the first feasible one.
Same command twice: the trajectories are compared (the same on a busy machine as on an idle
one: every budget counts effort).

Usage: ``python -m benchmarks.dynobench [--instances robot/instance,...]``; the full run also
draws ``benchmarks/results/dynobench.png``, the solved instances' motions among their obstacles.
"""
from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

from benchmarks.report import Report

ROOT = Path(__file__).resolve().parent
COPIES = ROOT / "dynobench"
#: Best final cost J_f [s] and iDb-A*'s first solution t_st [s], iDb-A* T-RO 2024 table.
PUBLISHED = {
    "unicycle1_v0/parallelpark_0": (2.9, 0.1), "unicycle1_v0/kink_0": (13.2, 0.2),
    "unicycle1_v0/bugtrap_0": (20.9, 0.3), "unicycle1_v1/kink_0": (21.1, 0.1),
    "unicycle1_v2/wall_0": (18.3, 0.5), "car1_v0/parallelpark_0": (3.2, 0.1),
    "car1_v0/kink_0": (15.5, 0.8), "car1_v0/bugtrap_0": (19.0, 0.5),
    "unicycle2_v0/parallelpark_0": (5.6, None), "unicycle2_v0/kink_0": (17.7, None),
    "unicycle2_v0/bugtrap_0": (25.0, None),
}


#: Seconds the bindings' check of one trajectory may take: their FCL collision check was seen
#: to hang on a body that grazes an obstacle.
BINDINGS_TIMEOUT = 60


def bindings_numbers(robot: str, env, solution) -> dict | None:
    """Dynobench's own model functions on a trajectory file (run it in a process of its own,
    :func:`bindings_check`): the largest Euler-step gap, the deepest collision, how far past
    the input bounds, the goal's distance; ``None`` where the bindings are not installed."""
    try:
        import dynobench as bindings
    except ImportError:
        return None
    env, solution = Path(env), Path(solution)
    robot_model = bindings.robot_factory_with_env(str(COPIES / "models" / f"{robot}.yaml"), str(env))
    sol = yaml.safe_load(solution.read_text())
    X, U = [np.array(x) for x in sol["states"]], [np.array(u) for u in sol["actions"]]
    jump = 0.0
    for k in range(len(U)):
        nxt = np.zeros(X[0].size)
        robot_model.step(nxt, X[k], U[k], 0.1)
        jump = max(jump, robot_model.distance(nxt, X[k + 1]))
    depth = 0.0
    for x in X:
        out = bindings.CollisionOut()
        robot_model.collision_distance(x, out)
        depth = max(depth, -out.distance)
    goal = np.array(yaml.safe_load(env.read_text())["robots"][0]["goal"], dtype=float)
    lo, hi = np.array(robot_model.get_u_lb()), np.array(robot_model.get_u_ub())
    past = max(max(float(np.max(lo - u)), float(np.max(u - hi)), 0.0) for u in U)
    return {"jump": float(jump), "depth": float(depth), "past": float(past),
            "goal": float(robot_model.distance(X[-1], goal))}


def bindings_check(robot: str, env: Path, solution: Path) -> str:
    """:func:`bindings_numbers` in a process of its own, at most :data:`BINDINGS_TIMEOUT` s,
    in words; or why not run."""
    code = ("import json, sys; from benchmarks.dynobench import bindings_numbers; "
            "print(json.dumps(bindings_numbers(*sys.argv[1:])))")
    try:
        done = subprocess.run([sys.executable, "-c", code, robot, str(env), str(solution)], cwd=ROOT.parent,
                              capture_output=True, text=True, timeout=BINDINGS_TIMEOUT)
    except subprocess.TimeoutExpired:
        return f"did not return in {BINDINGS_TIMEOUT} s (their FCL check hangs on a body grazing an obstacle)"
    lines = done.stdout.strip().splitlines()
    if done.returncode != 0 or not lines:
        return f"failed to run ({done.stderr.strip().splitlines()[-1:]})"
    n = json.loads(lines[-1])
    if n is None:
        return "bindings not installed"
    ok = n["jump"] < 1e-2 and n["depth"] < 1e-2 and n["past"] < 1e-2 and n["goal"] < 3e-2
    return (f"{'pass' if ok else 'FAIL'} (gap {n['jump']:.1e}, collision {n['depth']:.1e}, inputs past "
            f"{n['past']:.1e}, goal {n['goal']:.1e})")


def draw(solved: dict, path: Path) -> None:
    """One panel per solved instance: the workspace, the obstacles, and the robot's bodies
    along its trajectory (every fifth state, the last darker)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Polygon, Rectangle

    from nonholo import dynobench
    from nonholo.dynobench.checker import bodies

    columns = min(4, len(solved))
    rows = -(-len(solved) // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(4.2 * columns, 4.2 * rows), squeeze=False)
    for ax in axes.ravel()[len(solved):]:
        ax.set_visible(False)
    for ax, (name, (env, trajectory, cost)) in zip(axes.ravel(), solved.items()):
        inst = dynobench.load(env)
        ax.add_patch(Rectangle(inst.low, *(inst.high - inst.low), fill=False, lw=1.2, color="k"))
        for o in inst.obstacles:
            ax.add_patch(Rectangle((o.center[0] - o.size[0] / 2, o.center[1] - o.size[1] / 2), *o.size,
                                   color="0.45"))
        states = np.asarray(trajectory["states"])
        for k, x in enumerate(states):
            if k % 5 and k != len(states) - 1:
                continue
            last = k == len(states) - 1
            for body in bodies(inst, x):
                ax.add_patch(Polygon(np.asarray(body.exterior.coords), closed=True, fill=False,
                                     lw=1.2 if last else 0.6, color="C3" if last else "C0"))
        ax.plot(states[:, 0], states[:, 1], "C0", lw=0.8)
        ax.plot(*inst.start[:2], "go", ms=4)
        ax.plot(*inst.goal[:2], "r*", ms=7)
        ax.set_aspect("equal")
        ax.set_xlim(inst.low[0] - 0.1, inst.high[0] + 0.1)
        ax.set_ylim(inst.low[1] - 0.1, inst.high[1] + 0.1)
        ax.set_title(f"{name}: {cost:.1f} s", fontsize=9)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def run(name: str, out: Path) -> tuple[int, float, str]:
    """``nonholo dynobench`` on one instance in a fresh process: exit status, wall time, output."""
    env = COPIES / "envs" / f"{name}.yaml"
    started = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "nonholo", "dynobench", str(env), "--out", str(out)],
                          capture_output=True, text=True, timeout=600)
    return done.returncode, time.perf_counter() - started, (done.stdout + done.stderr).strip().splitlines()[-1]


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--instances", default=None, help="comma-separated robot/instance (default: all)")
    args = ap.parse_args(argv)
    names = args.instances.split(",") if args.instances else list(PUBLISHED)
    report = Report("dynobench.md", "Dynobench instances (nonholo dynobench)", "benchmarks.dynobench", argv,
                    extra_packages=("shapely", "casadi", "dynobench"))
    report.paragraph(
        "Each instance: `nonholo dynobench ENV.yaml --out SOLUTION.yaml` in a fresh process, twice; the wall "
        "time is the whole command's (median of the two), which is also its time to the first feasible "
        "solution (it returns one). *checker*: the project's own (`nonholo.dynobench.check`); *bindings*: "
        "Dynobench's own model functions through its Python bindings (`dynobench` wheel), where installed. "
        "Published: the best final cost J_f and iDb-A*'s first-solution time t_st, medians over 20 runs "
        "(iDb-A* T-RO 2024 table, Intel i9-14900KF; unicycle2's t_st not quoted). Costs are durations, "
        "steps of dt = 0.1 s. The command's default: the trajectory is brought to as few Euler steps of the "
        "model as keep its bounds and goal to 0.9 of Dynobench's thresholds (the table's *past* and *goal*; "
        "`--strict` keeps them exactly) and its bodies clear of the obstacles at its states by 1 mm — the "
        "unicycles' of at most 80 steps by SLSQP over the actions, the car with a trailer's whole, as one "
        "sparse program (IPOPT).")
    rows, details, solved = [], [], {}
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            outs = [Path(tmp) / f"{name.replace('/', '_')}_{i}.yaml" for i in range(2)]
            runs = [run(name, out) for out in outs]
            status, _, line = runs[0]
            seconds = statistics.median(r[1] for r in runs)
            same = (all(o.is_file() for o in outs)
                    and yaml.safe_load(outs[0].read_text())["states"] == yaml.safe_load(outs[1].read_text())["states"])
            cost = yaml.safe_load(outs[0].read_text())["cost"] if outs[0].is_file() else None
            robot = name.split("/")[0]
            bind = (bindings_check(robot, COPIES / "envs" / f"{name}.yaml", outs[0]) if status == 0
                    else "–")
            best, first = PUBLISHED[name]
            rows.append([name, "solved" if status == 0 else "not solved",
                         f"{cost:.1f}" if status == 0 else "–", f"{best:.1f}",
                         "yes" if status == 0 and cost <= best + 1e-9 else "no", f"{seconds:.2f}",
                         "–" if first is None else f"{first:.1f}", bind,
                         "yes" if same else ("–" if not all(o.is_file() for o in outs) else "NO")])
            details.append(f"- `{name}`: {line}")
            if status == 0:
                solved[name] = (COPIES / "envs" / f"{name}.yaml", yaml.safe_load(outs[0].read_text()), cost)
            print(rows[-1], flush=True)
    report.heading("Results")
    report.table(["instance", "result", "cost [s]", "best published J_f [s]", "≤ J_f", "wall time [s]",
                  "iDb-A* t_st [s]", "bindings", "same twice"], rows, ["l", "l", "r", "r", "l", "r", "r", "l", "l"])
    report.heading("What the command said")
    report.paragraph(*details)
    if solved and not args.instances:
        draw(solved, report.path.with_suffix(".png"))
        report.paragraph("The figure below: the solved instances' workspaces, obstacles (grey), and the robot's "
                         "bodies every fifth state along its trajectory (the last in red); start green, goal red.")
    report.write()


if __name__ == "__main__":
    main()
