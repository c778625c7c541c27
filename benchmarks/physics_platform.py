"""Plans played on the MuJoCo model of the platform (:mod:`nonholo.physics.platform_model`),
open loop and with touch-ups.

Run::

    python -m benchmarks.physics_platform [--touch-ups 3] [--actuators prescribed] [--timestep 5e-4]

Cases: Examples 1 and 3 of :mod:`nonholo.paper.examples` on ``platform``, and a plan of
``platform_raised`` (from ``I`` to ``exp([0.3, 0.1, 0.2])``), whose model is written from
its geometry like any other. Each case: reset at the start, play the plan (``T = 1``,
re-timed rest to rest by the model), hold the final targets 0.3 s, measure ``R``; then
``--touch-ups`` times: plan from the measured ``R`` to the goal and play again. Reported per
play: the geodesic error to the goal (rad), the largest tangential slip speed at the disk's
contact, the least normal force during the motion, and the wall time of the play. Each
case is run twice and the final states compared bit for bit (*repeat*). The contact
settings are :data:`~nonholo.physics.platform_model.DEFAULTS` but for the options given.
"""
from __future__ import annotations

import argparse
import time
from types import SimpleNamespace

import mujoco
import numpy as np

import nonholo
from nonholo.model import catalog
from nonholo.paper import examples
from nonholo.physics.platform_model import DEFAULTS, PlatformModel
from nonholo.spaces import so3

SETTLE = 0.3


def play(pm, model, data, res, R):
    """Play ``res`` from the measured ``R`` and settle: ``(R, slip, least force, seconds)``."""
    started = time.perf_counter()
    pm.follow(res, R, np.zeros(0))
    t0 = data.time
    moving = round(res.T / model.opt.timestep)
    slip, force = 0.0, np.inf
    for k in range(moving + round(SETTLE / model.opt.timestep)):
        pm.drive(model, data, data.time - t0)
        mujoco.mj_step(model, data)
        if k < moving:
            slip = max(slip, pm.slip(model, data))
            force = min(force, pm.contact_force(model, data))
    return pm.state(model, data)[0], slip, force, time.perf_counter() - started


def case(mechanism, R0, Rd, contact, touch_ups):
    """Rows ``(play, error, slip, force, seconds)`` and the final ``qpos``."""
    mech = catalog.get(mechanism)
    pm = PlatformModel(mech, contact)
    model = mujoco.MjModel.from_xml_string(pm.mjcf())
    data = mujoco.MjData(model)
    pm.reset(model, data, R0, np.zeros(0))
    rows, R = [], R0
    for k in range(touch_ups + 1):
        res = nonholo.plan(R, Rd, mechanism=mechanism)
        if not res.success:
            rows.append((k, np.nan, np.nan, np.nan, 0.0))
            break
        R, slip, force, seconds = play(pm, model, data, res, R)
        err = mech.space.error(R, np.zeros(0), Rd, np.zeros(0))[1]["rotation"]
        rows.append((k, err, slip, force, seconds))
    return rows, data.qpos.copy()


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--touch-ups", type=int, default=3)
    parser.add_argument("--actuators", default=DEFAULTS["actuators"], choices=("prescribed", "servo"))
    parser.add_argument("--timestep", type=float, default=DEFAULTS["timestep"])
    args = parser.parse_args(argv)
    settings = dict(DEFAULTS, actuators=args.actuators, timestep=args.timestep)
    if args.timestep != DEFAULTS["timestep"]:
        settings["solref"] = (2 * args.timestep, 1.0)
    contact = SimpleNamespace(**settings)
    cases = [(f"Example {k}", "platform", examples.get(k).R_start, examples.get(k).R_goal) for k in (1, 3)]
    cases.append(("raised", "platform_raised", np.eye(3), so3.exp([0.3, 0.1, 0.2])))
    print(f"settings: {settings}")
    print(f"{'case':<10} {'play':<8} {'error (rad)':>12} {'max slip':>10} {'min force':>10} {'time (s)':>9}  repeat")
    for label, mechanism, R0, Rd in cases:
        rows, qpos = case(mechanism, R0, Rd, contact, args.touch_ups)
        _, again = case(mechanism, R0, Rd, contact, args.touch_ups)
        same = "bit-identical" if np.array_equal(qpos, again) else "DIFFERS"
        for k, err, slip, force, seconds in rows:
            name = "open" if k == 0 else f"touch {k}"
            tail = same if k == len(rows) - 1 else ""
            print(f"{label:<10} {name:<8} {err:12.2e} {slip:10.1e} {force:10.2f} {seconds:9.2f}  {tail}")


if __name__ == "__main__":
    main()
