"""Plans played on the MuJoCo models of the mechanisms (:mod:`nonholo.physics`), open loop and
with touch-ups.

Run::

    python -m benchmarks.physics [--touch-ups 3]

Cases: the platform's Examples 1 and 3 (:mod:`nonholo.paper.examples`), Example 3 with servo
actuators and without the no-slip pass (the friction under the legs' weight creeps), and a
plan of ``platform_raised`` (``I → exp([0.3, 0.1, 0.2])``), whose model is written from its
geometry like any other; the rolling ball's in-place reorientation by ``π/2`` about ``x`` (planned with
``strategy="paper", settings=Settings(harmonics=4)``) played in 10 s and in 1 s, without radius
compensation and with servo actuators; the car's parking problem ``(0, 0, 0, 0) → (0, 1, 0, 0)`` with both
kinds of actuators; the unicycle's ``(0, 0, 0) → (0, 1, 0)``. Each case: :func:`nonholo.physics.execution.execute`
with the calibrated contact settings but for the one named, at most ``--touch-ups`` re-plans
from the measured state, each played only if predicted to end nearer the goal, none once
within the plan's tolerance. Reported: the norm ``|e|`` of the state's error from the goal
after the open-loop play and after each touch-up (with the touch-up's prediction, or why it
was not played), the last error by part, the largest slip speed at a rolling contact over
all plays, and the open-loop play's real-time factor; and whether ``|e|`` never grows from
stage to stage in every row. The first case is run twice and its records compared
(*repeat*). Exit status 1 if a row's errors grow, a stage went unstable
(:func:`nonholo.physics.execution.execute`) or the repeat differs.

Writes ``benchmarks/results/physics.md``.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

import nonholo
from nonholo.paper import examples
from nonholo.physics import Contact, execute, model_for
from nonholo.physics.execution import MARGIN
from nonholo.physics.vehicle_models import CarModel
from nonholo.spaces import so3

from .report import Report

BALL_R0 = so3.from_rpy(0.4, -0.3, 0.2)
BALL_RD = so3.exp(np.array([np.pi / 2, 0.0, 0.0])) @ BALL_R0


def problems() -> dict:
    """The plans played, by name."""
    ex1, ex3 = examples.get(1), examples.get(3)
    Settings = nonholo.Settings
    return {
        "platform, Example 1": nonholo.plan(ex1.R_start, ex1.R_goal, T=ex1.T, objective=None,
                                            settings=Settings(method=ex1.methods[0], harmonics=ex1.harmonics)),
        "platform, Example 3": nonholo.plan(ex3.R_start, ex3.R_goal, T=ex3.T, objective=None,
                                            settings=Settings(method=ex3.methods[0], harmonics=ex3.harmonics)),
        "platform_raised": nonholo.plan(np.eye(3), so3.exp(np.array([0.3, 0.1, 0.2])), mechanism="platform_raised"),
        "rolling_ball": nonholo.plan((BALL_R0, (0.0, 0.0)), (BALL_RD, (0.0, 0.0)), mechanism="rolling_ball",
                                     strategy="paper", settings=Settings(harmonics=4)),
        "car": nonholo.plan((0.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0), mechanism="car"),
        "unicycle": nonholo.plan((0.0, 0.0, 0.0), (0.0, 1.0, 0.0), mechanism="unicycle"),
    }


#: (mechanism, setting, duration or None for the default, contact settings).
CASES = [
    ("platform, Example 1", "played in 10 s", 10.0, Contact()),
    ("platform, Example 3", "played in 10 s", 10.0, Contact()),
    ("platform, Example 3", "10 s, servo actuators", 10.0, Contact(actuators="servo")),
    ("platform, Example 3", "10 s, no no-slip pass (creep)", 10.0, Contact(noslip_iterations=0, impratio=1.0)),
    ("platform_raised", "played in 10 s", 10.0, Contact()),
    ("rolling_ball", "played in 10 s", 10.0, Contact()),
    ("rolling_ball", "played in 1 s", 1.0, Contact()),
    ("rolling_ball", "10 s, no radius compensation", 10.0, Contact(radius_compensation=False)),
    ("rolling_ball", "10 s, servo actuators", 10.0, Contact(actuators="servo")),
    ("car", "played in 10 s", 10.0, Contact()),
    ("car", "10 s, servo actuators", 10.0, Contact(actuators="servo")),
    ("unicycle", "played in 10 s", 10.0, Contact()),
]


def error_text(error: dict) -> str:
    """``rotation rad / coordinates`` of a stage's error."""
    return " / ".join(f"{error[k]:.1e}" for k in ("rotation", "coordinates") if k in error)


def stage_text(stage: dict, norm: float) -> str:
    """A stage's cell: ``|e|`` after it (a touch-up's prediction in brackets), or why it
    was not played."""
    outcome = stage["outcome"]
    if outcome == "played":
        return f"{norm:.1e}" + ("" if stage["predicted"] is None else f" (pred. {stage['predicted']:.1e})")
    if outcome == "predicted worse":
        return f"not played: pred. {stage['predicted']:.1e}"
    if outcome == "unstable":
        return "UNSTABLE"
    return "not played: within tol." if outcome == "within tolerance" else "not planned"


def radii() -> str:
    """The rolling radii each model measures when it settles at its start, as text."""
    import mujoco

    out = []
    for name, R, q in (("rolling_ball", BALL_R0, np.zeros(2)), ("car", np.eye(3), np.zeros(4)),
                       ("unicycle", np.eye(3), np.zeros(3))):
        model = model_for(name)
        m = mujoco.MjModel.from_xml_string(model.mjcf())
        model.reset(m, mujoco.MjData(m), R, q)
        out.append(f"{name} " + ", ".join(f"{k} {v:.9f}" for k, v in model.radii.items()))
    return "; ".join(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.physics", description=__doc__.splitlines()[0])
    ap.add_argument("--touch-ups", type=int, default=3)
    args = ap.parse_args(argv)
    plans = problems()
    rep = Report("physics.md", "Plans played on MuJoCo models, with touch-ups", "benchmarks.physics", argv,
                 extra_packages=("mujoco",))
    base = Contact().resolved("rolling_ball")
    own = Contact().resolved("platform")
    tols = ", ".join(sorted({f"{r.options['tol']:g}" for r in plans.values()}))
    rep.paragraph(
        "Each plan is played from rest to rest (re-timed by the smoothstep time change) on its "
        "mechanism's model, left to settle, and measured; each touch-up re-plans from the measured "
        "state to the goal with the plan's options and plays that only if it is predicted to end "
        "nearer the goal (pred.): by a model of the stages played so far, not by a trial run — "
        "tracking error a·s + b·s² (a, b ≥ 0) in the motion's size s = ∫|u| dt, so a played stage "
        "of size s_j and error e_j bounds it by e_j·max(r, r²), r = s/s_j: the least such bound, "
        f"times a safety factor {MARGIN:g}; drift at rest at the largest rate measured; the "
        "re-plan's own error. Touching up ends at the first touch-up not played: within the plan's "
        f"tolerance ({tols} here), predicted to end no nearer, or not planned. |e|: the norm of "
        "the stacked error, rotation (rad) and "
        "position (radii or wheelbases); the car's and the unicycle's are the norm of the "
        "coordinates' difference (heading and steering in rad); \"last, by part\": rotation / "
        "position of the last stage. Max slip: the largest tangential "
        "speed at a rolling contact in any play (units per second), the contact's tangential "
        "constraint velocity at each step's start: it includes the step's own O(h) discretisation "
        "of rolling, not only sliding. RTF: simulated over wall time "
        "of the open-loop play (the only figure that varies between runs). Contact settings: "
        f"time step {base.timestep:g} s, solref {base.solref}, solimp {base.solimp}, friction "
        f"{base.friction:g}, no-slip iterations {base.noslip_iterations}, impratio {base.impratio:g}, "
        f"preload {base.preload:g} N, settling {base.settle:g} s; the platforms' own: time step "
        f"{own.timestep:g} s, solref {own.solref}, solimp {own.solimp}, preload {own.preload:g} N; "
        "but for the setting named.")
    rows, runs, growing, unstable = [], {}, [], []
    for mech, setting, duration, contact in CASES:
        started = time.perf_counter()
        ex = execute(plans[mech], touch_ups=args.touch_ups, duration=duration, contact=contact)
        print(f"[{mech}, {setting}: {time.perf_counter() - started:.1f} s]", flush=True)
        runs[(mech, setting)] = ex
        norms = [plans[mech].kinematics.space.norm(s["error"]) for s in ex.stages]
        if any(b > a for a, b in zip(norms, norms[1:])):
            growing.append(f"{mech}, {setting}")
        if any(s["outcome"] == "unstable" for s in ex.stages):
            unstable.append(f"{mech}, {setting}")
        cells = [stage_text(s, n) for s, n in zip(ex.stages, norms)]
        cells += ["–"] * (args.touch_ups + 1 - len(cells))
        rows.append([mech, setting, *cells, error_text(ex.stages[-1]["error"]),
                     f"{max(s['max_slip'] for s in ex.stages):.1e}", f"{ex.stages[0]['real_time_factor']:.1f}"])
    rep.table(["mechanism", "setting", "open loop", *[f"touch-up {k}" for k in range(1, args.touch_ups + 1)],
               "last, by part", "max slip", "RTF"], rows)
    rep.paragraph("|e| non-increasing from stage to stage: "
                  + (f"NOT in {'; '.join(growing)}." if growing else "in every row.")
                  + (f" The simulation went UNSTABLE in {'; '.join(unstable)}." if unstable else ""))
    rep.paragraph(f"Rolling radii measured after settling (unit nominal radius for the ball, "
                  f"{CarModel.WHEEL:g} for the wheels): {radii()}. Played in 1 s the ball's peak speed is "
                  "ten times that of 10 s and its accelerations a hundred times: the friction the "
                  "plates can give does not hold it: it slides away from the goal, and a touch-up "
                  "re-planned from there, played in 1 s too, would be nearly as large a motion: it is "
                  "predicted to end no nearer and is not played.")
    mech, setting, duration, contact = CASES[0]
    again = execute(plans[mech], touch_ups=args.touch_ups, duration=duration, contact=contact)
    same = again == runs[(mech, setting)]
    rep.paragraph(f"Repeat: {mech}, {setting}, run again: records "
                  f"{'bit-identical' if same else 'DIFFERENT'} (real-time factors aside).")
    rep.write()
    return 0 if same and not growing and not unstable else 1


if __name__ == "__main__":
    raise SystemExit(main())
