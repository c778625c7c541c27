"""Plans played on the MuJoCo models of the mechanisms (:mod:`nonholo.physics`), open loop and
with touch-ups.

Run::

    python -m benchmarks.physics [--touch-ups 3]

Cases: the platform's Examples 1 and 3 (:mod:`nonholo.paper.examples`), Example 3 with servo
actuators and without the no-slip pass (the friction under the legs' weight creeps), and a
plan of ``platform_raised`` (``I → exp([0.3, 0.1, 0.2])``), whose model is written from its
geometry like any other; the rolling ball's in-place reorientation by ``π/2`` about ``x`` (planned with
``strategy="paper", harmonics=4``) played in 10 s and in 1 s, without radius compensation and
with servo actuators; the car's parking problem ``(0, 0, 0, 0) → (0, 1, 0, 0)`` with both
kinds of actuators; the unicycle's ``(0, 0, 0) → (0, 1, 0)``. Each case: :func:`nonholo.physics.execution.execute`
with the calibrated contact settings but for the one named, ``--touch-ups`` re-plans from
the measured state. Reported: the state's error from the goal by part after the open-loop
play and after each touch-up, the largest slip speed at a rolling contact over all plays,
and the open-loop play's real-time factor. The first case is run twice and its records
compared (*repeat*).

Writes ``benchmarks/results/physics.md``.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

import nonholo
from nonholo.paper import examples
from nonholo.physics import Contact, execute, model_for
from nonholo.physics.vehicle_models import CarModel
from nonholo.spaces import so3

from .report import Report

BALL_R0 = so3.from_rpy(0.4, -0.3, 0.2)
BALL_RD = so3.exp(np.array([np.pi / 2, 0.0, 0.0])) @ BALL_R0


def problems() -> dict:
    """The plans played, by name."""
    ex1, ex3 = examples.get(1), examples.get(3)
    return {
        "platform, Example 1": nonholo.plan(ex1.R_start, ex1.R_goal, T=ex1.T, method=ex1.methods[0],
                                            harmonics=ex1.harmonics, objective=None),
        "platform, Example 3": nonholo.plan(ex3.R_start, ex3.R_goal, T=ex3.T, method=ex3.methods[0],
                                            harmonics=ex3.harmonics, objective=None),
        "platform_raised": nonholo.plan(np.eye(3), so3.exp(np.array([0.3, 0.1, 0.2])), mechanism="platform_raised"),
        "rolling_ball": nonholo.plan((BALL_R0, (0.0, 0.0)), (BALL_RD, (0.0, 0.0)), mechanism="rolling_ball",
                                     strategy="paper", harmonics=4),
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
    rep.paragraph(
        "Each plan is played from rest to rest (re-timed by the smoothstep time change) on its "
        "mechanism's model, left to settle, and measured; each touch-up re-plans from the measured "
        "state to the goal with the plan's options and plays that. Errors: rotation (rad) / "
        "position (radii or wheelbases); the car's and the unicycle's are the norm of the "
        "coordinates' difference (heading and steering in rad). Max slip: the largest tangential "
        "speed at a rolling contact in any play (units per second), the contact's tangential "
        "constraint velocity at each step's start: it includes the step's own O(h) discretisation "
        "of rolling, not only sliding. RTF: simulated over wall time "
        "of the open-loop play (the only figure that varies between runs). Contact settings: "
        f"time step {base.timestep:g} s, solref {base.solref}, solimp {base.solimp}, friction "
        f"{base.friction:g}, no-slip iterations {base.noslip_iterations}, impratio {base.impratio:g}, "
        f"preload {base.preload:g} N, settling {base.settle:g} s; the platforms' own: time step "
        f"{own.timestep:g} s, solref {own.solref}, solimp {own.solimp}, preload {own.preload:g} N; "
        "but for the setting named.")
    rows, runs = [], {}
    for mech, setting, duration, contact in CASES:
        started = time.perf_counter()
        ex = execute(plans[mech], touch_ups=args.touch_ups, duration=duration, contact=contact)
        print(f"[{mech}, {setting}: {time.perf_counter() - started:.1f} s]", flush=True)
        runs[(mech, setting)] = ex
        errors = [error_text(s["error"]) for s in ex.stages]
        errors += ["–"] * (args.touch_ups + 1 - len(errors))
        rows.append([mech, setting, *errors, f"{max(s['max_slip'] for s in ex.stages):.1e}",
                     f"{ex.stages[0]['real_time_factor']:.1f}"])
    rep.table(["mechanism", "setting", "open loop", *[f"after {k}" for k in range(1, args.touch_ups + 1)],
               "max slip", "RTF"], rows)
    rep.paragraph(f"Rolling radii measured after settling (unit nominal radius for the ball, "
                  f"{CarModel.WHEEL:g} for the wheels): {radii()}. Played in 1 s the ball's peak speed is "
                  "ten times that of 10 s and its accelerations a hundred times: the friction the "
                  "plates can give does not hold it: it slides away from the goal, and each touch-up, "
                  "played in 1 s too, starts farther away.")
    mech, setting, duration, contact = CASES[0]
    again = execute(plans[mech], touch_ups=args.touch_ups, duration=duration, contact=contact)
    same = again == runs[(mech, setting)]
    rep.paragraph(f"Repeat: {mech}, {setting}, run again: records "
                  f"{'bit-identical' if same else 'DIFFERENT'} (real-time factors aside).")
    rep.write()
    return 0 if same else 1


if __name__ == "__main__":
    raise SystemExit(main())
