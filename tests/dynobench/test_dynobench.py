"""Dynobench's instances and trajectories: reading, the project's own checker (against the
repository's reference solutions and, where installed, the ``dynobench`` bindings' collision
distances), the obstacles kept by the least-time path, and the command."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

import nonholo
from nonholo import dynobench
from nonholo.constraints import Body, Obstacles
from nonholo.dynobench import checker
from nonholo.dynobench.solve import SHARE, constraints
from nonholo.model import catalog

ROOT = Path(__file__).resolve().parents[2]


def bindings():
    """Dynobench's Python bindings (the ``dynobench`` wheel), or a skip where they are not
    installed (this folder, ``tests/dynobench``, would otherwise be imported in their place as
    a namespace package)."""
    module = pytest.importorskip("dynobench", reason="the dynobench wheel (cp311) is not installed")
    if not hasattr(module, "robot_factory_with_env"):
        pytest.skip("the dynobench wheel (cp311) is not installed")
    return module
COPIES = ROOT / "benchmarks" / "dynobench"
ENVS = sorted(COPIES.glob("envs/*/*.yaml"))


def test_every_copied_instance_is_read():
    assert len(ENVS) == 11
    for path in ENVS:
        inst = dynobench.load(path)
        assert inst.start.size == inst.goal.size == {"unicycle1": 3, "unicycle2": 5, "car_with_trailers": 4}[inst.dynamics]
        assert inst.dt == 0.1 and inst.obstacles
        assert inst.robot == path.parent.name


@pytest.mark.parametrize("robot", ["unicycle1_v0", "car1_v0", "unicycle2_v0"])
def test_the_checker_passes_the_reference_solutions_with_their_own_numbers(robot):
    inst = dynobench.load(COPIES / "envs" / robot / "parallelpark_0.yaml")
    sol = yaml.safe_load((COPIES / "solutions" / robot / "parallelpark_0.yaml").read_text())
    report = dynobench.check(inst, sol["states"], sol["actions"])
    assert report.feasible, report.failures()
    assert report.cost == pytest.approx(sol["cost"])
    # the files round their states to 6 digits: the distances agree to that
    assert report.goal_distance == pytest.approx(sol["goal_distance"], abs=1e-5)
    assert report.max_collision == sol["max_collision"] == 0


def test_the_checker_finds_what_is_wrong_with_a_trajectory():
    inst = dynobench.load(COPIES / "envs" / "unicycle1_v0" / "parallelpark_0.yaml")
    sol = yaml.safe_load((COPIES / "solutions" / "unicycle1_v0" / "parallelpark_0.yaml").read_text())
    X, U = np.array(sol["states"]), np.array(sol["actions"])
    U2 = U.copy()
    U2[5, 1] += 0.4                                     # an action the states do not follow
    assert any("dynamics residual" in f for f in dynobench.check(inst, X, U2).failures())
    U3 = U.copy()
    U3[3, 0] = 0.6                                      # beyond |v| ≤ 0.5, and not followed either
    assert any("input bounds" in f for f in dynobench.check(inst, X, U3).failures())
    X4 = X.copy()
    X4[-1, 0] += 0.1
    assert any("goal distance" in f for f in dynobench.check(inst, X4, U).failures())
    X5 = X.copy()
    X5[10] = [1.1, 0.35, 0.0]                           # inside the middle box
    assert any("collision" in f for f in dynobench.check(inst, X5, U).failures())


def test_signed_distances_are_those_of_the_dynobench_bindings():
    wheel = bindings()
    env = COPIES / "envs" / "unicycle1_v0" / "parallelpark_0.yaml"
    robot = wheel.robot_factory_with_env(str(COPIES / "models" / "unicycle1_v0.yaml"), str(env))
    inst = dynobench.load(env)
    rng = np.random.default_rng(0)
    for _ in range(20):
        x = np.array([rng.uniform(0.2, 2.9), rng.uniform(0.1, 0.6), rng.uniform(-3, 3)])
        out = wheel.CollisionOut()
        robot.collision_distance(x, out)
        # (the bindings report single precision)
        assert checker.state_clearance(inst, x)[0] == pytest.approx(out.distance, abs=1e-6)


BAD = {
    "not yaml": ("robots: [", "not YAML"),
    "no robots": ("environment: {min: [0, 0], max: [1, 1]}\n", "robots is missing"),
    "unknown robot": ("environment: {min: [0, 0], max: [3, 3]}\nrobots: [{type: hovercraft, start: [1, 1, 0], "
                      "goal: [2, 2, 0]}]\n", "robots[0].type: unknown robot type 'hovercraft'"),
    "start in an obstacle": ("environment: {min: [0, 0], max: [3, 3], obstacles: [{type: box, center: [1, 1], "
                             "size: [0.5, 0.5]}]}\nrobots: [{type: unicycle1_v0, start: [1, 1, 0], "
                             "goal: [2, 2, 0]}]\n", "robots[0].start: the robot's body overlaps obstacle 0"),
    "start of two numbers": ("environment: {min: [0, 0], max: [3, 3]}\nrobots: [{type: unicycle1_v0, "
                             "start: [1, 1], goal: [2, 2, 0]}]\n", "robots[0].start must hold 3 numbers"),
    "obstacle not a box": ("environment: {min: [0, 0], max: [3, 3], obstacles: [{type: sphere, center: [1, 1], "
                           "size: [1]}]}\nrobots: [{type: unicycle1_v0, start: [1, 2, 0], goal: [2, 2, 0]}]\n",
                           "environment.obstacles[0].type must be 'box'"),
    "an unknown field": ("script: x\nenvironment: {min: [0, 0], max: [3, 3]}\nrobots: []\n",
                         "script is not a field"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_a_bad_instance_is_refused_naming_the_field(case, tmp_path):
    text, says = BAD[case]
    env = tmp_path / "envs" / "mine" / "bad.yaml"
    env.parent.mkdir(parents=True)
    env.write_text(text)
    with pytest.raises(ValueError) as info:
        dynobench.load(env, models=COPIES / "models")
    assert str(env) in str(info.value) and says in str(info.value), str(info.value)
    run = subprocess.run([sys.executable, "-m", "nonholo", "dynobench", str(env), "--models", str(COPIES / "models")],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 2 and says in run.stderr


def test_obstacle_clearances_and_their_gradients():
    inst = dynobench.load(COPIES / "envs" / "unicycle1_v0" / "parallelpark_0.yaml")
    obstacles = Obstacles.boxes([o.center for o in inst.obstacles], [o.size for o in inst.obstacles],
                                (Body(*inst.bodies[0]),))
    mech = catalog.get("unicycle")
    rng = np.random.default_rng(3)
    q = np.column_stack([rng.uniform(0.2, 2.9, 60), rng.uniform(0.1, 0.6, 60), rng.uniform(-3, 3, 60)])
    values, grads = obstacles.clearance_rows(mech, q)
    np.testing.assert_allclose(values[:, 0], [checker.state_clearance(inst, x)[0] for x in q], atol=1e-12)
    for c in range(3):
        for e in (1e-5, -1e-5):
            moved = q.copy()
            moved[:, c] += e
            step = (obstacles.clearances(mech, moved)[:, 0] - values[:, 0]) / e
            # the clearance is smooth but where the nearest feature changes: most states agree
            assert np.mean(np.abs(step - grads[:, 0, c]) < 1e-3) > 0.9
    with pytest.raises(ValueError, match=r"bodies\[0\].heading = 'yaw' is not a coordinate"):
        nonholo.plan([0.7, 0.8, 0], [1.9, 0.8, 0], mechanism="unicycle", constraints=[
            Obstacles((((0, 0), (1, 0), (0, 1)),), (Body(0.5, 0.25, heading="yaw"),))])
    with pytest.raises(ValueError, match=r"polygons\[0\] must be a convex polygon"):
        Obstacles((((0, 0), (2, 0), (1, 0.2), (1, 2)),))


def test_the_least_time_path_keeps_clear_of_the_obstacles():
    """Dynobench's unicycle park: the obstacle-free least time runs through a parked box;
    with the obstacles kept at the nodes, the motion replayed at Dynobench's steps clears
    them within its tolerance and passes every other check."""
    inst = dynobench.load(COPIES / "envs" / "unicycle1_v0" / "parallelpark_0.yaml")
    free = nonholo.plan(inst.start, inst.goal, mechanism="unicycle", T=3.0, objective="time",
                        constraints=constraints(inst))
    assert free.success and free.T < 2.9
    obstacles = Obstacles.boxes([o.center for o in inst.obstacles], [o.size for o in inst.obstacles],
                                (Body(*inst.bodies[0]),), margin=0.01)
    assert obstacles.violation(free.kinematics, free.q) is not None
    kept = nonholo.plan(inst.start, inst.goal, mechanism="unicycle", T=3.0, objective="time",
                        constraints=constraints(inst) + [obstacles])
    assert kept.success, kept.reason
    assert kept.T > free.T
    assert np.min(obstacles.clearances(kept.kinematics, kept.q)) >= 0.0


def test_a_plan_exported_at_dynobench_steps_passes_its_checks(tmp_path):
    """Without obstacles in the way (the wall instance's start and goal moved below it), a
    least-time plan re-timed to whole steps: dynamics, goal and bounds within Dynobench's
    thresholds, written and read back."""
    inst = dynobench.load(COPIES / "envs" / "unicycle1_v0" / "parallelpark_0.yaml")
    start, goal = np.array([0.7, 0.9, 0.0]), np.array([2.0, 0.9, 0.5])
    result = nonholo.plan(start, goal, mechanism="unicycle", T=4.0, objective="time", constraints=constraints(inst))
    K = int(np.ceil(result.T / inst.dt))
    played = nonholo.retime(result, T=K * inst.dt, input_bounds=constraints(inst)[0])
    moved = type(inst)(**{**inst.__dict__, "start": start, "goal": goal})
    trajectory = dynobench.to_dynobench(played, moved)
    report = dynobench.check(moved, trajectory["states"], trajectory["actions"])
    assert report.feasible, report.failures()
    assert report.cost == pytest.approx(K * inst.dt) and report.goal_distance < 1e-8
    path = dynobench.write(tmp_path / "sol.yaml", trajectory, report)
    again = dynobench.read(path)
    np.testing.assert_allclose(again["states"], trajectory["states"])
    assert yaml.safe_load(path.read_text())["cost"] == pytest.approx(report.cost)


WALLED = """\
environment:
  min: [0.0, 0.0]
  max: [4.0, 4.0]
  obstacles:
    - {type: box, center: [3.0, 2.0], size: [1.6, 0.2]}
    - {type: box, center: [3.0, 3.0], size: [1.6, 0.2]}
    - {type: box, center: [2.3, 2.5], size: [0.2, 1.2]}
    - {type: box, center: [3.7, 2.5], size: [0.2, 1.2]}
robots:
  - {type: unicycle1_v0, start: [1.0, 1.0, 0.0], goal: [3.0, 2.5, 0.0]}
"""


def test_the_command_writes_the_trajectory_and_says_why_it_fails(tmp_path):
    """A goal walled off from the start: exit 1, the reason said, no trajectory claimed."""
    env = tmp_path / "envs" / "unicycle1_v0" / "walled.yaml"
    env.parent.mkdir(parents=True)
    env.write_text(WALLED)
    out = tmp_path / "sol.yaml"
    run = subprocess.run([sys.executable, "-m", "nonholo", "dynobench", str(env), "--models", str(COPIES / "models"),
                          "--out", str(out)], capture_output=True, text=True, timeout=600)
    assert run.returncode == 1, run.stdout + run.stderr
    assert "not solved" in run.stdout and "obstacle" in run.stdout


def test_strict_keeps_the_bounds_and_the_goal_exactly_and_the_default_the_share_of_the_thresholds(tmp_path):
    """The unicycle's park: ``--strict`` writes a trajectory whose actions and states keep their
    bounds and whose last state is the goal; the default's pass within the share of the
    thresholds, in no more steps."""
    env = COPIES / "envs" / "unicycle1_v0" / "parallelpark_0.yaml"
    inst, reports = dynobench.load(env), {}
    for flags in ((), ("--strict",)):
        out = tmp_path / f"sol{len(flags)}.yaml"
        run = subprocess.run([sys.executable, "-m", "nonholo", "dynobench", str(env), "--out", str(out), *flags],
                             capture_output=True, text=True, timeout=600)
        assert run.returncode == 0, run.stdout + run.stderr
        trajectory = dynobench.read(out)
        reports[flags] = dynobench.check(inst, trajectory["states"], trajectory["actions"])
    strict, default = reports[("--strict",)], reports[()]
    assert strict.feasible and strict.u_bound_distance == 0.0 and strict.x_bound_distance == 0.0
    assert strict.goal_distance < 1e-8 and strict.max_collision == 0.0
    assert default.feasible and default.cost <= strict.cost + 1e-9
    assert default.u_bound_distance <= SHARE * checker.BOUND_TOL + 1e-9
    assert default.goal_distance <= SHARE * checker.GOAL_TOL + 1e-9


@pytest.mark.slow
def test_the_parallel_parks_are_solved_and_pass_the_checks(tmp_path):
    """The unicycle's, the second-order unicycle's and the car with a trailer's parks: solved,
    the written trajectory passing the project's checker and, where installed, Dynobench's own
    model functions; each at most the best published cost (2.9 s, 5.6 s, 3.2 s)."""
    for robot, cost in (("unicycle1_v0", 2.9), ("unicycle2_v0", 5.6), ("car1_v0", 3.2)):
        env = COPIES / "envs" / robot / "parallelpark_0.yaml"
        out = tmp_path / f"{robot}.yaml"
        run = subprocess.run([sys.executable, "-m", "nonholo", "dynobench", str(env), "--out", str(out)],
                             capture_output=True, text=True, timeout=600)
        assert run.returncode == 0, run.stdout + run.stderr
        inst, trajectory = dynobench.load(env), dynobench.read(out)
        report = dynobench.check(inst, trajectory["states"], trajectory["actions"])
        assert report.feasible and report.cost <= cost + 1e-9
        # Dynobench's own model functions, in a process of their own (their FCL check was seen
        # to hang on a body overlapping an obstacle)
        from benchmarks.dynobench import bindings_check

        said = bindings_check(robot, env, out)
        assert said.startswith(("pass", "bindings not installed")), said


#: Instances a route leads through a corridor or out of a trap (the lattice's for the unicycles,
#: the car's own arcs for the car with a trailer), with the best published cost J_f (iDb-A*,
#: T-RO 2024 table).
ROUTED = {("unicycle1_v0", "kink_0"): 13.2, ("unicycle1_v0", "bugtrap_0"): 20.9,
          ("unicycle2_v0", "kink_0"): 17.7, ("unicycle2_v0", "bugtrap_0"): 25.0,
          ("car1_v0", "kink_0"): 15.5, ("car1_v0", "bugtrap_0"): 19.0}


def solved_and_checked(robot, name, tmp_path):
    """``nonholo dynobench`` on an instance: exit 0, its written trajectory feasible by the
    project's checker; the check and the trajectory."""
    env = COPIES / "envs" / robot / f"{name}.yaml"
    out = tmp_path / "solution.yaml"
    run = subprocess.run([sys.executable, "-m", "nonholo", "dynobench", str(env), "--out", str(out)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr
    inst, trajectory = dynobench.load(env), dynobench.read(out)
    report = dynobench.check(inst, trajectory["states"], trajectory["actions"])
    assert report.feasible, report.failures()
    return report, trajectory


@pytest.mark.slow
@pytest.mark.parametrize("robot, name", sorted(ROUTED))
def test_the_kinks_and_bugtraps_are_solved_at_or_below_the_published_cost(robot, name, tmp_path):
    """The unicycles and the car with a trailer through the kink's corridor and out of the
    bugtrap: the written trajectory passes the project's checker, its cost at most the best
    published."""
    report, _ = solved_and_checked(robot, name, tmp_path)
    assert report.cost <= ROUTED[robot, name] + 1e-9


@pytest.mark.slow
@pytest.mark.parametrize("robot, name, published", [("unicycle1_v1", "kink_0", 21.1), ("unicycle1_v2", "wall_0", 18.3)])
def test_the_forward_only_unicycles_are_solved_and_pass_the_checks(robot, name, published, tmp_path):
    """v ≥ 0.25 (and, round the wall, right turns half as tight as left ones): solved from the
    route of the search over the vehicle's own arcs, the written trajectory passing the
    project's checker with every speed above the bound less the share of Dynobench's threshold
    the Euler steps may use, at most the best published cost."""
    report, trajectory = solved_and_checked(robot, name, tmp_path)
    assert np.asarray(trajectory["actions"])[:, 0].min() >= 0.25 - SHARE * checker.BOUND_TOL - 1e-9
    assert report.cost <= published + 1e-9


def test_overlap_depths_are_those_of_the_boxes_closed_form():
    """Axis-aligned boxes: the depth of their overlap is the least of the overlaps along x and
    y; the vectorised depths equal it and the one-pair form."""
    from nonholo.model.obstacles import overlap_depth, overlap_depths

    rng = np.random.default_rng(5)
    a, bs, expected = [], [], []
    for _ in range(40):
        c1, c2 = rng.uniform(-0.15, 0.15, 2), rng.uniform(-0.15, 0.15, 2)     # overlapping: |Δc| < 0.4
        h1, h2 = rng.uniform(0.2, 0.6, 2), rng.uniform(0.2, 0.6, 2)
        box = lambda c, h: np.array([c + [-h[0], -h[1]], c + [h[0], -h[1]], c + [h[0], h[1]], c + [-h[0], h[1]]])
        a.append(box(c1, h1))
        bs.append(box(c2, h2))
        overlap = h1 + h2 - np.abs(c1 - c2)
        expected.append(overlap.min())
    depths = overlap_depths(np.array(a), bs)
    np.testing.assert_allclose(depths, expected, atol=1e-12)
    np.testing.assert_allclose(depths, [overlap_depth(x, y) for x, y in zip(a, bs)], atol=1e-12)


def test_a_plan_with_obstacles_is_saved_and_loaded_and_a_bad_record_refused(tmp_path):
    import json

    obstacles = Obstacles.boxes([(5.0, 5.0)], [(1.0, 1.0)], (Body(0.5, 0.25),), margin=0.01)
    result = nonholo.plan([0, 0, 0], [1, 0.5, 0], mechanism="unicycle", constraints=[obstacles])
    assert result.success, result.reason
    path = result.save(tmp_path / "plan.json")
    again = nonholo.PlanResult.load(path)
    assert again.success and again.options["obstacles"] == obstacles.record()
    assert Obstacles.from_record(again.options["obstacles"], result.kinematics) == obstacles
    data = json.loads(path.read_text())
    data["options"]["obstacles"]["bodies"][0]["x"] = "__import__('os')"
    path.write_text(json.dumps(data))
    with pytest.raises(ValueError, match="is not a coordinate of mechanism 'unicycle'"):
        nonholo.PlanResult.load(path)


def shifted(env: Path, offset, folder: Path) -> Path:
    """A copy of an instance moved by ``offset`` in the plane (workspace, obstacles, start and
    goal), beside a copy of its model file."""
    data = yaml.safe_load(env.read_text())
    dx, dy = offset
    space = data["environment"]
    space["min"] = [space["min"][0] + dx, space["min"][1] + dy]
    space["max"] = [space["max"][0] + dx, space["max"][1] + dy]
    for o in space["obstacles"]:
        o["center"] = [o["center"][0] + dx, o["center"][1] + dy]
    for robot in data["robots"]:
        for end in ("start", "goal"):
            robot[end] = [robot[end][0] + dx, robot[end][1] + dy, *robot[end][2:]]
    (folder / "envs" / env.parent.name).mkdir(parents=True, exist_ok=True)
    (folder / "models").mkdir(exist_ok=True)
    model = COPIES / "models" / f"{env.parent.name}.yaml"
    (folder / "models" / model.name).write_text(model.read_text())
    out = folder / "envs" / env.parent.name / env.name
    out.write_text(yaml.safe_dump(data))
    return out


@pytest.mark.parametrize("robot", ["unicycle1_v0", "car1_v0"])
def test_a_shifted_instance_is_solved_in_as_many_steps(robot, tmp_path):
    """The parks, moved by (10.3, −4.7): solved, passing the checker, in the same number of
    steps, the trajectory the original's moved (to the solvers' tolerances)."""
    from nonholo.dynobench.solve import solve

    env = COPIES / "envs" / robot / "parallelpark_0.yaml"
    here, there = solve(dynobench.load(env)), solve(dynobench.load(shifted(env, (10.3, -4.7), tmp_path)))
    assert here.solved and there.solved, (here.reason, there.reason)
    assert there.report.feasible and len(there.trajectory["actions"]) == len(here.trajectory["actions"])
    moved = np.asarray(there.trajectory["states"]) - np.asarray(here.trajectory["states"])
    np.testing.assert_allclose(moved[:, 0], 10.3, atol=1e-4)
    np.testing.assert_allclose(moved[:, 1], -4.7, atol=1e-4)
