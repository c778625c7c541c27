"""The MuJoCo model of a two-leg platform (:mod:`nonholo.physics.platform_model`): its MJCF
loads, :meth:`reset` puts it where asked, a short plan played open loop ends near its goal,
a touch-up brings it nearer, a touch-up that friction creep would undo is not played, and a
run repeats bit for bit. Coarse time step; orders of magnitude only (the full measurement:
``benchmarks/physics.py``)."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

import nonholo
from nonholo import mechanism_named
from nonholo.model import catalog
from nonholo.paper import examples
from nonholo.physics import Contact, execute
from nonholo.physics.execution import replan_options
from nonholo.physics.platform_model import DEFAULTS, PlatformModel
from nonholo.planning.settings import arguments_of
from nonholo.planning.retime import retime
from nonholo.spaces import so3

#: Contact settings of the tests: a coarse step (the drive's gains follow it).
COARSE = SimpleNamespace(**{**DEFAULTS, "timestep": 1e-3, "solref": (0.002, 1.0)})


def built(mechanism="platform", contact=COARSE):
    pm = PlatformModel(mechanism_named(mechanism), contact)
    model = mujoco.MjModel.from_xml_string(pm.mjcf())
    return pm, model, mujoco.MjData(model)


def play(pm, model, data, res, R, settle=0.2):
    """Play ``res`` from the measured ``R``, hold the final targets ``settle`` seconds; the
    measured orientation."""
    res = retime(res, T=res.T, rest_to_rest=True)
    pm.follow(res, R, np.zeros(0))
    start = data.time
    steps = round(res.T / model.opt.timestep) + round(settle / model.opt.timestep)
    for _ in range(steps):
        pm.drive(model, data, data.time - start)
        mujoco.mj_step(model, data)
    return pm.state(model, data)[0]


def error(R, Rd, mechanism="platform"):
    return catalog.get(mechanism).space.error((R, np.zeros(0)), (Rd, np.zeros(0)))[1]["rotation"]


@pytest.fixture(scope="module")
def example1():
    ex = examples.get(1)
    return ex.R_start, ex.R_goal, nonholo.plan(ex.R_start, ex.R_goal)


@pytest.mark.parametrize("name", ["platform", "platform_raised"])
def test_the_mjcf_loads_from_text_and_from_a_file(name, tmp_path):
    pm = PlatformModel(mechanism_named(name))
    text = pm.mjcf()
    model = mujoco.MjModel.from_xml_string(text)
    path = tmp_path / f"{name}.xml"
    path.write_text(text)
    again = mujoco.MjModel.from_xml_path(str(path))
    assert (model.nq, model.nv, model.nu, model.neq) == (again.nq, again.nv, again.nu, again.neq) == (16, 13, 3, 2)
    assert model.opt.timestep == DEFAULTS["timestep"]


@pytest.mark.parametrize("name", ["platform", "platform_raised"])
def test_reset_puts_the_platform_at_R_the_legs_at_their_lengths_the_disk_on_the_sphere(name):
    pm, model, data = built(name)
    R = so3.from_rpy(0.5, 1.2, -0.5) if name == "platform" else so3.exp([0.1, -0.2, 0.1])
    pm.reset(model, data, R, np.zeros(0))
    Rm, q = pm.state(model, data)
    assert so3.distance(Rm, R) <= 1e-6 and q.shape == (0,)
    slides = [data.qpos[model.jnt_qposadr[model.joint(f"leg{i}").id]] for i in (1, 2)]
    np.testing.assert_allclose(slides, pm.geometry.leg_lengths(R), atol=1e-6)
    assert data.ncon >= 1
    assert 0.5 * DEFAULTS["preload"] < pm.contact_force(model, data) < 2 * DEFAULTS["preload"]
    assert pm.slip(model, data) < 1e-6
    assert np.abs(data.qvel).max() == 0.0


def test_a_short_plan_played_open_loop_ends_near_its_goal_and_a_touch_up_nearer(example1):
    R0, Rd, res = example1
    pm, model, data = built()
    pm.reset(model, data, R0, np.zeros(0))
    R = play(pm, model, data, res, R0)
    first = error(R, Rd)
    assert first < 1e-3 * error(R0, Rd)
    again = nonholo.plan(R, Rd)
    assert again.success
    R = play(pm, model, data, again, R)
    assert error(R, Rd) < 1e-1 * first
    assert pm.contact_force(model, data) > 0


@pytest.mark.slow
def test_a_touch_up_that_creep_would_undo_is_not_played(example1):
    """Without the no-slip pass the contact creeps under the legs' weight: a touch-up from
    near the goal would drift farther than it corrects. The drift measured at rest predicts
    it, and the touch-up is not played; played anyway, it ends farther from the goal."""
    _, Rd, res = example1
    creep = Contact(timestep=COARSE.timestep, solref=COARSE.solref, noslip_iterations=0, impratio=1.0)
    run = execute(res, touch_ups=2, duration=5.0, contact=creep)
    first, second = run.stages
    assert second["outcome"] == "predicted worse" and run.traces[1] is None
    assert second["error"] == first["error"]
    assert first["drift"] > 0 and second["predicted"] >= first["drift"] * (5.0 + run.contact.settle)
    assert second["predicted"] >= first["error"]["rotation"]
    again = nonholo.plan(run.traces[0]["R"][-1], Rd, **arguments_of(replan_options(res), res.mechanism))
    tried = execute(again, duration=5.0, contact=creep)       # from a reset where the first ended
    assert tried.stages[0]["error"]["rotation"] > first["error"]["rotation"]


def test_a_run_repeats_bit_for_bit(example1):
    R0, _, res = example1
    out = []
    for _ in range(2):
        pm, model, data = built()
        pm.reset(model, data, R0, np.zeros(0))
        out.append((play(pm, model, data, res, R0, settle=0.0), data.qpos.copy()))
    assert np.array_equal(out[0][0], out[1][0]) and np.array_equal(out[0][1], out[1][1])


def test_the_raised_platform_plays_a_plan_of_its_own():
    R0 = np.eye(3)
    Rd = so3.exp([0.3, 0.1, 0.2])
    res = nonholo.plan(R0, Rd, mechanism="platform_raised")
    assert res.success
    pm, model, data = built("platform_raised")
    pm.reset(model, data, R0, np.zeros(0))
    R = play(pm, model, data, res, R0)
    assert error(R, Rd, "platform_raised") < 1e-2 * error(R0, Rd, "platform_raised")


def test_a_mechanism_without_geometry_or_a_bad_drive_is_refused(example1):
    with pytest.raises(ValueError, match="mechanism"):
        PlatformModel(mechanism_named("car"))
    with pytest.raises(ValueError, match="actuators"):
        PlatformModel(mechanism_named("platform"), SimpleNamespace(actuators="magic"))
    pm = PlatformModel(mechanism_named("platform"), SimpleNamespace(timestep=2e-3))      # the rest: DEFAULTS
    assert pm.settings["preload"] == DEFAULTS["preload"]
    with pytest.raises(ValueError, match="platform_raised"):
        PlatformModel(mechanism_named("platform_raised")).follow(example1[2], example1[0], np.zeros(0))


def test_the_servo_drive_lags_but_still_lands_near_the_goal(example1):
    R0, Rd, res = example1
    pm, model, data = built(contact=SimpleNamespace(**{**vars(COARSE), "actuators": "servo"}))
    pm.reset(model, data, R0, np.zeros(0))
    R = play(pm, model, data, res, R0, settle=0.5)
    assert error(R, Rd) < 1e-1 * error(R0, Rd)
