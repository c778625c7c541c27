"""Mechanisms beyond SO(3): the rolling ball and the kinematic car planned by
:func:`nonholo.plan`, the car against python-control's differential-flatness planner.

Run::

    python -m benchmarks.state_spaces [--goals 50] [--far 30] [--seed 2014] [--no-peer]

Problems (fixed seed):

- ``rolling_ball`` (state ``(R, p)``): ``--goals`` random goals, ``R0`` and ``R_d`` uniform on
  SO(3), ``p0`` uniform in ``[-1, 1]²`` and ``p_d`` uniform in the disc of radius 2 about
  it; plus the classic reorientation in place (same position, turned by π/2 about a
  horizontal axis).
- ``car`` (state ``(x, y, θ, φ)``): ``--goals`` random pairs with ``|x|, |y| ≤ 2``, any
  ``θ``, ``|φ| ≤ 0.5`` at both ends; plus the parallel parking (move 1 sideways, same
  heading and steering).
- ``car, far`` (``--far`` pairs): start and goal with ``|x|, |y| ≤ 30``, any ``θ``, ``|φ| ≤
  1.4`` — goals up to 85 car lengths away, near the singular set ``cos φ = 0``, where the
  local planner alone mostly fails and the global route (the straight path of states, hop
  by hop, :mod:`nonholo.planning.state_path`) takes over. Planned with ``tol = 1e-8``: a car's
  sensitivity grows like the square of its distance (a steering error turns the heading,
  which displaces the end), about 10³ at 50 lengths, which the certificate does not
  accept at 1e-10 (:mod:`nonholo.certify.certificate`). Run with the default route ``"auto"`` and
  with route ``"local"``, to show what the route adds.

Every plan is :func:`nonholo.plan` with its defaults (``T = 1``, strategy ``"robust"``),
timed per call after one warm-up call (numba compiled). Every claimed success is
re-simulated by SciPy's DOP853 (rtol = atol = 1e-13) on the model written out by hand
(:func:`nonholo.certify.resimulate.resimulate_state`, nothing generated): *solved* = both parts of
the re-simulated terminal error ≤ 1e-8 (rotation in rad, coordinates in the mechanism's
units, angles wrapped) and, for the car, ``|cos φ| ≥ 1e-2`` along the dense path.

The peer on the car: python-control's ``flatsys.point_to_point`` on its kinematic car
(:mod:`benchmarks.flatsys_peer`), the same pairs, its steering angle at both ends as our
``φ``; its trajectory is re-simulated by DOP853 on the same model equations with the
same criteria. Medians are of the per-call times of one run.

Writes ``benchmarks/results/state_spaces.md`` and ``state_spaces.json``.
"""
from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

import nonholo
from nonholo.spaces import so3
from nonholo.certify.resimulate import resimulate_state, state_errors

from .report import RESULTS_DIR, Report

TOL = 1e-8
FAR_TOL = 1e-8
COS_MIN = 1e-2


def ball_problems(n: int, seed: int) -> list[dict]:
    """``n`` random ball problems and the reorientation in place (see the module)."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        R0, Rd = _uniform_rotation(rng), _uniform_rotation(rng)
        p0 = rng.uniform(-1.0, 1.0, 2)
        r, a = 2.0 * np.sqrt(rng.uniform()), rng.uniform(0, 2 * np.pi)
        pd = p0 + r * np.array([np.cos(a), np.sin(a)])
        out.append({"name": f"ball-{i:02d}", "start": (R0, p0), "goal": (Rd, pd)})
    R0 = so3.from_rpy(0.4, -0.3, 0.2)
    out.append({"name": "ball-in-place", "start": (R0, np.zeros(2)),
                "goal": (so3.exp(np.array([np.pi / 2, 0.0, 0.0])) @ R0, np.zeros(2))})
    return out


def _uniform_rotation(rng) -> np.ndarray:
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def car_problems(n: int, seed: int) -> list[dict]:
    """``n`` random car problems and the parallel parking (see the module)."""
    rng = np.random.default_rng(seed + 1)

    def draw():
        return np.array([*rng.uniform(-2, 2, 2), rng.uniform(-np.pi, np.pi), rng.uniform(-0.5, 0.5)])

    out = [{"name": f"car-{i:02d}", "start": draw(), "goal": draw()} for i in range(n)]
    out.append({"name": "car-parallel-parking", "start": np.zeros(4), "goal": np.array([0.0, 1.0, 0.0, 0.0])})
    return out


def car_far_problems(n: int, seed: int) -> list[dict]:
    rng = np.random.default_rng(seed + 2)

    def draw():
        return np.array([*rng.uniform(-30, 30, 2), rng.uniform(-np.pi, np.pi), rng.uniform(-1.4, 1.4)])

    return [{"name": f"car-far-{i:02d}", "start": draw(), "goal": draw()} for i in range(n)]


def check(mechanism: str, res) -> dict:
    """Re-simulate a claimed success independently (see the module)."""
    t, R, q, delta = resimulate_state(res.start, res.controls, res.T, mechanism, res.breakpoints)
    errors = state_errors(mechanism, R[-1], q[-1], res.Rd, res.qd)
    least = None if delta is None else float(np.min(np.abs(delta)))
    ok = max(errors.values()) <= TOL and (least is None or least >= COS_MIN)
    return {"errors": errors, "min_abs_delta": least, "confirmed": bool(ok)}


def run_nonholo(mechanism: str, problems: list[dict], progress=True, **options) -> list[dict]:
    """:func:`nonholo.plan` on every problem (``options``: its keywords), each claimed success
    checked (:func:`check`)."""
    nonholo.plan(problems[0]["start"], problems[0]["goal"], mechanism=mechanism, route="local")  # warm-up
    rows = []
    for i, p in enumerate(problems):
        t0 = time.perf_counter()
        res = nonholo.plan(p["start"], p["goal"], mechanism=mechanism, **options)
        seconds = time.perf_counter() - t0
        row = {"name": p["name"], "claimed": bool(res.success), "seconds": seconds, "route": res.route,
               "reason": "" if res.success else res.reason[:300]}
        row.update(check(mechanism, res) if res.success else {"confirmed": False})
        rows.append(row)
        if progress:
            print(f"  {mechanism} {i + 1}/{len(problems)} {p['name']}: "
                  f"{'solved' if row['confirmed'] else 'FAILED'} {seconds * 1e3:.1f} ms", file=sys.stderr)
    return rows


def run_peer(problems: list[dict]) -> list[dict]:
    from . import flatsys_peer

    flatsys_peer.solve(problems[0]["start"], problems[0]["goal"])                       # warm-up
    rows = []
    for p in problems:
        out = flatsys_peer.solve(p["start"], p["goal"], tol=TOL)
        rows.append({"name": p["name"], "confirmed": bool(out["success"]), "seconds": out["seconds"],
                     "errors": {"position": out.get("error_position"), "angles": out.get("error_angles")},
                     "min_abs_delta": out.get("min_cos_phi"), "reason": out.get("reason", "")})
    return rows


def summary(rows: list[dict]) -> tuple:
    solved = sum(r["confirmed"] for r in rows)
    claimed = sum(r.get("claimed", r["confirmed"]) for r in rows)
    false = sum(r.get("claimed", False) and not r["confirmed"] for r in rows)
    t = np.array([r["seconds"] for r in rows]) * 1e3
    worst = max((max(v for v in r["errors"].values() if v is not None) for r in rows
                 if r["confirmed"]), default=float("nan"))
    return solved, claimed, false, float(np.median(t)), float(np.percentile(t, 95)), float(t.max()), worst


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--goals", type=int, default=50)
    ap.add_argument("--far", type=int, default=30)
    ap.add_argument("--seed", type=int, default=2014)
    ap.add_argument("--no-peer", action="store_true", help="skip python-control")
    args = ap.parse_args(argv)
    rep = Report("state_spaces.md", "Mechanisms beyond SO(3): rolling ball and car",
                 "benchmarks.state_spaces", argv, extra_packages=("control",))
    results = {}
    ball = ball_problems(args.goals, args.seed)
    car = car_problems(args.goals, args.seed)
    results["rolling_ball"] = run_nonholo("rolling_ball", ball)
    results["car"] = run_nonholo("car", car)
    if not args.no_peer:
        results["car (python-control flatsys)"] = run_peer(car)
    far = car_far_problems(args.far, args.seed) if args.far else []
    if far:
        far_settings = nonholo.Settings(tol=FAR_TOL)
        results["car, far"] = run_nonholo("car", far, settings=far_settings)
        results["car, far (route local)"] = run_nonholo("car", far, settings=far_settings, route="local")
    rep.paragraph(f"Problems: {len(ball)} rolling-ball goals ({args.goals} random and the reorientation "
                  f"in place) and {len(car)} car goals ({args.goals} random and the parallel parking), "
                  f"seed {args.seed}. *Solved*: re-simulated by DOP853 on the hand-written model with both "
                  f"parts of the terminal error ≤ {TOL:g} and, for the car, |cos φ| ≥ {COS_MIN:g} along the "
                  "dense path. Times per call after a warm-up; medians of this run."
                  + (f" Far car pairs: {len(far)} (|x|, |y| ≤ 30, |φ| ≤ 1.4), planned with tol = {FAR_TOL:g}, "
                     "by the default route and by the local planner alone." if far else ""))
    rows = []
    for label, res in results.items():
        solved, claimed, false, med, p95, mx, worst = summary(res)
        rows.append([label, f"{solved}/{len(res)} ({100 * solved / len(res):.0f} %)", claimed, false,
                     f"{med:.1f}", f"{p95:.1f}", f"{mx:.1f}", f"{worst:.1e}"])
    rep.table(["solver", "solved", "claimed", "false claims", "median ms", "p95 ms", "max ms",
               "largest error of the solved"], rows)
    if far:
        routed = sum(r["confirmed"] and r["route"] == "global" for r in results["car, far"])
        rep.paragraph(f"Of the far car pairs solved by the default route, {routed} were reached by the "
                      "global route (the local planner having failed).")
    if "car (python-control flatsys)" in results:
        ours = {r["name"]: r for r in results["car"]}
        both = [r for r in results["car (python-control flatsys)"] if r["confirmed"] and ours[r["name"]]["confirmed"]]
        if both:
            ratio = np.median([r["seconds"] for r in both]) / np.median([ours[r["name"]]["seconds"] for r in both])
            rep.paragraph(f"On the {len(both)} car pairs both solve, python-control's median time is "
                          f"{ratio:.2g}× nonholo's.")
    for label, res in results.items():
        bad = [r for r in res if not r["confirmed"]]
        if bad:
            rep.paragraph(f"Not solved by {label}: " + "; ".join(
                f"{r['name']} ({(r.get('reason') or 'claimed, not confirmed')[:160]})" for r in bad))
    rep.write()
    (RESULTS_DIR / "state_spaces.json").write_text(json.dumps(
        {"date": rep.date, "machine": rep.machine, "command": rep.command, "results": results},
        indent=1, default=float))
    return 0


if __name__ == "__main__":
    sys.exit(main())
