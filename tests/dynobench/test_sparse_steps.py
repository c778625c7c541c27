"""Dynobench's problem of a whole trajectory as one sparse program (``nonholo.dynobench.sparse_steps``):
the trajectories found against the project's checker (written from Dynobench's models, apart
from the program's CasADi expressions): the states the checker's own Euler steps of the
actions, the bounds and the goal kept exactly (``share = 0``) and to half the thresholds, every
body clear of the boxes by the margin; the least step against a rollout at that step."""
import math
from pathlib import Path

import numpy as np
import pytest

from nonholo import dynobench
from nonholo.dynobench import checker, sparse_steps
from nonholo.dynobench.solve import mechanism_state, obstacles
from nonholo.model import catalog
from nonholo.planning import car_route

COPIES = Path(__file__).resolve().parents[2] / "benchmarks" / "dynobench"
MARGIN = 5e-3


def park():
    """The car with a trailer's parallel park and the actions of its route of arcs."""
    inst = dynobench.load(COPIES / "envs" / "car1_v0" / "parallelpark_0.yaml")
    arcs = car_route.search(obstacles(inst, MARGIN), catalog.get("car_with_trailer"), mechanism_state(inst, inst.start),
                            mechanism_state(inst, inst.goal), inst.low, inst.high, 0.5, 0.1,
                            float(inst.input_high[1]), math.inf, step=inst.dt)
    assert isinstance(arcs, car_route.Arcs), arcs
    return inst, np.repeat(arcs.moves, arcs.steps, axis=0)


@pytest.mark.parametrize("share", [0.0, 0.5])
def test_the_fewest_steps_pass_the_checker_with_the_share_of_its_thresholds(share):
    inst, route = park()
    found = sparse_steps.fewest_steps(inst, route, obstacles(inst, MARGIN), share)
    assert found is not None and len(found.actions) <= len(route) + sparse_steps.EXTRA_STEPS
    X, U = found.states, found.actions
    for k in range(len(U)):
        gap = checker.step(inst, X[k], U[k]) - X[k + 1]
        gap[checker.angles(inst)] = checker.wrap(gap[checker.angles(inst)])
        assert np.abs(gap).max() < 1e-12
    np.testing.assert_array_equal(X[0], inst.start)
    report = checker.check(inst, X, U)
    assert report.feasible, report.failures()
    assert report.goal_distance <= share * checker.GOAL_TOL + 1e-9
    assert report.u_bound_distance <= share * checker.BOUND_TOL + 1e-9
    assert min(checker.state_clearance(inst, x)[0] for x in X) >= MARGIN - 1e-9


def test_the_least_step_is_a_motion_at_that_step():
    """From a trajectory at the model's step, the least step is no longer than it, and the
    actions' Euler steps at that step (the checker's rates) end in the goal's box, clear of
    the boxes by the margin at every state."""
    inst, route = park()
    program = sparse_steps.SparseSteps(inst, obstacles(inst, MARGIN), 0.5)
    found = sparse_steps.fewest_steps(inst, route, obstacles(inst, MARGIN), 0.5)
    solved, h, _, U = program.solve(found.states, found.actions, None)
    assert solved and h <= inst.dt + 1e-12
    x = np.asarray(inst.start, dtype=float)
    for u in U:
        x = x + h * checker.rates(inst, x, u)
        assert checker.state_clearance(inst, x)[0] >= MARGIN - 1e-9
    e = x - inst.goal
    e[checker.angles(inst)] = checker.wrap(e[checker.angles(inst)])
    assert np.all(np.abs(e) <= program.goal_box + 1e-9)
    assert np.all(U >= inst.input_low - 0.5 * checker.BOUND_TOL - 1e-9)
    assert np.all(U <= inst.input_high + 0.5 * checker.BOUND_TOL + 1e-9)


def test_the_same_call_gives_the_same_trajectory():
    inst, route = park()
    first = sparse_steps.fewest_steps(inst, route, obstacles(inst, MARGIN), 0.5)
    again = sparse_steps.fewest_steps(inst, route, obstacles(inst, MARGIN), 0.5)
    np.testing.assert_array_equal(first.actions, again.actions)


def test_bad_input_is_refused_naming_it():
    inst, route = park()
    with pytest.raises(ValueError, match="share"):
        sparse_steps.SparseSteps(inst, obstacles(inst, MARGIN), 1.5)
    drift = dynobench.load(COPIES / "envs" / "unicycle2_v0" / "parallelpark_0.yaml")
    with pytest.raises(ValueError, match="dynamics"):
        sparse_steps.SparseSteps(drift, obstacles(drift, MARGIN), 0.5)


def test_the_unicycles_reference_solution_comes_to_fewer_steps_that_pass_the_checker():
    """The first-order unicycle's park from the repository's reference solution (36 steps):
    fewer steps, the states the checker's own Euler steps of the actions, feasible, clear."""
    import yaml

    inst = dynobench.load(COPIES / "envs" / "unicycle1_v0" / "parallelpark_0.yaml")
    reference = np.array(yaml.safe_load((COPIES / "solutions" / "unicycle1_v0" / "parallelpark_0.yaml")
                                        .read_text())["actions"])
    found = sparse_steps.fewest_steps(inst, reference, obstacles(inst, MARGIN), 0.5)
    assert found is not None and len(found.actions) < len(reference)
    X, U = found.states, found.actions
    for k in range(len(U)):
        gap = checker.step(inst, X[k], U[k]) - X[k + 1]
        gap[checker.angles(inst)] = checker.wrap(gap[checker.angles(inst)])
        assert np.abs(gap).max() < 1e-12
    report = checker.check(inst, X, U)
    assert report.feasible and report.u_bound_distance <= 0.5 * checker.BOUND_TOL + 1e-9
    assert min(checker.state_clearance(inst, x)[0] for x in X) >= MARGIN - 1e-9
