"""Dynobench's own problem, ``K`` Euler steps of the model (``nonholo.dynobench.euler_steps``):
the steps' sensitivities against central differences, the states against the project's
checker's Euler step (written from Dynobench's models, apart from the mechanisms), and the
trajectories found against the checker: the bounds and the goal kept exactly (``share = 0``)
and within half its thresholds, the bodies clear of the obstacles."""
from pathlib import Path

import numpy as np
import pytest
import yaml

from nonholo import dynobench
from nonholo.dynobench import checker, euler_steps
from nonholo.constraints import InputBounds, StateBounds
from nonholo.dynobench.solve import constraints, obstacles

COPIES = Path(__file__).resolve().parents[2] / "benchmarks" / "dynobench"


def instance(robot, name="parallelpark_0"):
    return dynobench.load(COPIES / "envs" / robot / f"{name}.yaml")


def problem(inst, share=0.0):
    bounds, states = constraints(inst)
    return euler_steps.EulerProblem(inst, bounds, states, obstacles(inst), share)


def reference_actions(robot):
    """The repository's reference solution's actions (more steps than the least)."""
    return np.array(yaml.safe_load((COPIES / "solutions" / robot / "parallelpark_0.yaml").read_text())["actions"])


@pytest.mark.parametrize("robot", ["unicycle1_v0", "unicycle2_v0", "car1_v0"])
def test_the_euler_steps_are_the_checkers_and_their_sensitivities_central_differences(robot):
    inst = instance(robot)
    euler = euler_steps.EulerProblem(inst, InputBounds(tuple(inst.input_low), tuple(inst.input_high)),
                                     StateBounds(tuple(inst.state_low), tuple(inst.state_high)), obstacles(inst), 0.0)
    rng = np.random.default_rng(3)
    U = rng.uniform(-0.25, 0.25, size=(12, 2))
    X, S = euler.rollout(U)
    for k in range(12):
        gap = X[k + 1] - checker.step(inst, X[k], U[k])
        gap[checker.angles(inst)] = checker.wrap(gap[checker.angles(inst)])
        assert np.abs(gap).max() < 1e-12
    h = 1e-6
    for j in rng.choice(U.size, 6, replace=False):
        up, down = U.copy().ravel(), U.copy().ravel()
        up[j] += h
        down[j] -= h
        numeric = (euler.rollout(up.reshape(U.shape))[0] - euler.rollout(down.reshape(U.shape))[0]) / (2 * h)
        assert np.abs(S[:, :, j] - numeric).max() < 1e-7


def test_fewer_steps_kept_exactly_pass_the_checker_with_nothing_to_spare():
    """From the reference solution's 36 steps, ``share = 0``: fewer steps, every action
    inside its bounds, the states Euler steps of the actions, the goal reached, no overlap."""
    inst = instance("unicycle1_v0")
    found = euler_steps.fewest_steps(inst, reference_actions("unicycle1_v0"), obstacles(inst, 5e-3), 0.0)
    assert found is not None and len(found.actions) < 36
    report = dynobench.check(inst, found.states, found.actions)
    assert report.feasible
    assert report.cost == pytest.approx(0.1 * len(found.actions))
    assert np.abs(found.actions).max() <= 0.5 * (1 + 1e-9)
    assert report.max_jump < 1e-12 and report.goal_distance < 1e-8
    assert report.max_collision < 1e-9 and report.x_bound_distance == 0.0


def test_half_the_thresholds_gives_no_more_steps_and_stays_within_that_half():
    """``share = 0.5``: no more steps than exactly; the actions and the goal within half the
    checker's thresholds, the bodies clear of the obstacles."""
    inst = instance("unicycle1_v0")
    start = reference_actions("unicycle1_v0")
    exact = euler_steps.fewest_steps(inst, start, obstacles(inst, 5e-3), 0.0)
    half = euler_steps.fewest_steps(inst, start, obstacles(inst, 5e-3), 0.5)
    assert half is not None and len(half.actions) <= len(exact.actions)
    report = dynobench.check(inst, half.states, half.actions)
    assert report.feasible and report.max_jump < 1e-12
    assert report.u_bound_distance <= 0.5 * checker.BOUND_TOL + 1e-9
    assert report.goal_distance <= 0.5 * checker.GOAL_TOL + 1e-9
    assert report.max_collision == 0.0


def test_a_side_off_zero_is_kept_as_it_is_and_the_others_scaled():
    """``0.25 ≤ v ≤ 0.5`` (unicycle1_v1): at ``s = 0.5`` the action ``v = 0.25`` meets both
    the fixed side and the scaled one, and ``v = 0.2`` breaks the fixed side."""
    euler = problem(instance("unicycle1_v1", "kink_0"))
    A, b = euler.bounds_rows(1)
    for v, kept in ((0.25, True), (0.2, False)):
        z = np.array([v, 0.0, 0.5])
        assert bool(np.all(A @ z - b >= -1e-12)) is kept


def test_what_fewest_steps_does_not_solve_and_a_bad_share():
    uni = instance("unicycle1_v0")
    long = np.zeros((euler_steps.STEPS_AT_MOST + 1, 2))
    assert euler_steps.fewest_steps(uni, long, obstacles(uni, 5e-3), 0.5) is None
    for share in (1.0, -0.1, "half"):
        with pytest.raises(ValueError, match="share"):
            euler_steps.fewest_steps(uni, long, obstacles(uni, 5e-3), share)


def test_the_car_routes_arcs_are_the_models_euler_steps_and_clear_of_the_boxes():
    """Dynobench's car with a trailer in the parallel park, searched with the model's step: each
    arc, played from the search's last state by the checker's own Euler step (Dynobench's model,
    written apart from the catalog car) with the arc's speed and steering, ends at the search's
    state — the car's pose to rounding, the trailer's heading to the table's interpolation in
    the hitch angle — and every step's state is clear of the boxes by the margin (the checker's
    signed distance)."""
    import math

    from nonholo.dynobench.solve import mechanism_state
    from nonholo.model import catalog
    from nonholo.planning import car_route

    inst = instance("car1_v0")
    arcs = car_route.search(obstacles(inst, 5e-3), catalog.get("car_with_trailer"), mechanism_state(inst, inst.start),
                            mechanism_state(inst, inst.goal), inst.low, inst.high, 0.5, 0.1, float(inst.input_high[1]),
                            math.inf, step=inst.dt)
    assert isinstance(arcs, car_route.Arcs), arcs
    assert arcs.tau == pytest.approx(arcs.steps * inst.dt)
    assert np.all(arcs.moves[:, 0] >= -0.1 - 1e-12) and np.all(arcs.moves[:, 0] <= 0.5 + 1e-12)
    assert np.abs(arcs.moves[:, 1]).max() <= inst.input_high[1] + 1e-12
    for (v, phi), begin, end in zip(arcs.moves, arcs.states[:-1], arcs.states[1:]):
        x = begin[[0, 1, 2, 4]]
        for _ in range(arcs.steps):
            x = checker.step(inst, x, (v, phi))
            assert checker.state_clearance(inst, x)[0] >= 5e-3 - 1e-9
        np.testing.assert_allclose(x[:3], end[:3], atol=1e-9)
        assert abs(x[3] - end[4]) < 1e-3
    with pytest.raises(ValueError, match="step"):
        car_route.search(obstacles(inst, 5e-3), catalog.get("car_with_trailer"), mechanism_state(inst, inst.start),
                         mechanism_state(inst, inst.goal), inst.low, inst.high, 0.5, 0.1, 1.0, math.inf, step=0.0)
