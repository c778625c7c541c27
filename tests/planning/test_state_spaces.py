"""Mechanisms whose state goes beyond SO(3): the rolling ball (SO(3) × R²) and the car (R⁴).

Derivation against the definitions, generated code against the symbolic source and
finite differences, kernels against DOP853 and finite differences, plans re-simulated
independently on hand-written models (:mod:`nonholo.certify.resimulate`), save/load, bad input.
"""
import numpy as np
import pytest
import sympy as sp

import nonholo
from derivations import definitions as symbolic
from derivations import state_space
from nonholo.certify.resimulate import resimulate_state, state_errors
from nonholo.controls import stages
from nonholo.controls.parametrisations import Fourier
from nonholo.model import catalog
from nonholo.spaces import so3

NAMES = ("rolling_ball", "car")
rng = np.random.default_rng(7)


def random_state(mech):
    R = so3.exp(rng.normal(size=3)) if mech.orientation else np.eye(3)
    q = rng.uniform(-1.0, 1.0, mech.n_coordinates)
    return R, q


@pytest.mark.slow
def test_derived_from_constraints():
    """The ball's ω is e₃ × v; the car's rates are the textbook ones with Δ = cos φ."""
    ball, car = symbolic.get("rolling_ball"), symbolic.get("car")
    v = sp.Matrix(sp.symbols("v1:3", real=True))
    assert sp.simplify(ball.Omega * v - sp.Matrix([0, 0, 1]).cross(sp.Matrix([v[0], v[1], 0]))) == sp.zeros(3, 1)
    x, y, th, ph = car.coordinates
    assert sp.simplify(car.X[:, 0] - sp.Matrix([sp.cos(th), sp.sin(th), sp.tan(ph), 0])) == sp.zeros(4, 1)
    assert sp.simplify(car.delta - sp.cos(ph)) == 0
    # the frame spans the same rates and is finite: N = G W
    assert sp.simplify(car.frame - car.X * car.frame_inputs) == sp.zeros(4, 2)


@pytest.mark.parametrize("name", NAMES)
def test_generated_matches_symbolic(name):
    sym, mech = symbolic.get(name), catalog.get(name)
    for _ in range(3):
        R, q = random_state(mech)
        subs = {c: float(v) for c, v in zip(sym.coordinates, q)}
        if sym.orientation:
            from derivations.rotations import r
            subs |= {r[i, j]: R[i, j] for i in range(3) for j in range(3)}
        G = np.array(sym.field.subs(subs).evalf(), dtype=float)
        assert np.allclose(mech.G(R, q), G, atol=1e-13)


@pytest.mark.parametrize("name", NAMES)
def test_variational_matrix_against_finite_differences(name):
    """QG s = d/dε G(exp(ε[s_R]) R, q + ε s_q) v (central differences)."""
    mech = catalog.get(name)
    mod = mech.module
    for _ in range(3):
        R, q = random_state(mech)
        v = rng.normal(size=2)
        s = rng.normal(size=mech.n_rates)
        eps = 1e-6
        r = 3 if mech.orientation else 0

        def moved(e):
            Rm = so3.exp(e * s[:3]) @ R if r else R
            return mod.G(Rm, q + e * s[r:]) @ v

        fd = (moved(eps) - moved(-eps)) / (2 * eps)
        assert np.allclose(mod.QG(R, q, v) @ s, fd, atol=1e-7)


def _table(T, N, m=2):
    ts = stages.stage_times(T, N)
    return np.stack([0.8 * np.sin(2 * np.pi * ts) + 0.3, 0.7 * np.cos(2 * np.pi * ts)], axis=-1)


@pytest.mark.parametrize("name", NAMES)
def test_kernel_against_dop853_and_jacobian_against_finite_differences(name):
    mech = catalog.get(name)
    R0, q0 = random_state(mech)
    q0[-1] = 0.2 if name == "car" else q0[-1]
    T, N = 1.0, 200
    f = Fourier(T, rng.normal(scale=0.5, size=(2, 5)))
    start = mech.space.public((R0, q0))
    tr = nonholo.simulate(start, f, T, mechanism=mech, steps=N)
    _, R, q, _ = resimulate_state(start, f, T, mech.name)
    assert np.abs(tr.R[-1] - R[-1]).max() < 1e-8 and np.abs(tr.q[-1] - q[-1]).max() < 1e-8
    var = nonholo.motion.simulation.variational(start, f, T, mechanism=mech, steps=N)
    eps = 1e-6
    fd = np.empty_like(var.J)
    for c in range(f.params.size):
        ends = []
        for sgn in (1, -1):
            p = f.params.copy()
            p[c] += sgn * eps
            t2 = nonholo.simulate(start, f.with_params(p), T, mechanism=mech, steps=N)
            ends.append(mech.space.error((t2.R[-1], t2.q[-1]), (tr.R[-1], tr.q[-1]))[0])
        fd[:, c] = (ends[0] - ends[1]) / (2 * eps)
    assert np.allclose(var.J, fd, atol=1e-7)


def _independent(result):
    t, R, q, delta = resimulate_state(result.start, result.controls, result.T,
                                      result.mechanism, result.breakpoints)
    errors = state_errors(result.mechanism, R[-1], q[-1], result.Rd, result.qd)
    return errors, delta


@pytest.mark.parametrize("strategy, harmonics", [("robust", 2), ("paper", 4)])
def test_ball_reorients_in_place(strategy, harmonics):
    """Same position, rotated by π/2 about a horizontal axis. (The paper's algorithm with
    K = 2 converges on the planner's grid to inputs so large that the replay's
    sensitivity overflows, which the certificate refuses; K = 4 is certified.)"""
    R0 = so3.from_rpy(0.3, -0.2, 0.1)
    Rd = so3.exp(np.array([np.pi / 2, 0.0, 0.0])) @ R0
    res = nonholo.plan((R0, [0.5, -0.5]), (Rd, [0.5, -0.5]), mechanism="rolling_ball", strategy=strategy,
                       settings=nonholo.Settings(harmonics=harmonics))
    assert res.success, res.reason
    errors, _ = _independent(res)
    assert errors["rotation"] < 1e-8 and errors["coordinates"] < 1e-8
    assert set(res.errors) == {"rotation", "coordinates"} and max(res.errors.values()) <= 1e-10


@pytest.mark.slow
def test_car_parks_sideways():
    """Parallel parking: move 1 sideways, same heading and steering."""
    res = nonholo.plan([0, 0, 0, 0], [0, 1, 0, 0], mechanism="car")
    assert res.success, res.reason
    errors, delta = _independent(res)
    assert errors["coordinates"] < 1e-8
    assert np.abs(delta).min() >= 1e-2 and res.min_delta >= 1e-2
    assert res.q.shape == (res.steps + 1, 4) and np.allclose(res.R, np.eye(3))


@pytest.mark.slow
def test_car_random_goals_are_certified_and_confirmed():
    r = np.random.default_rng(3)
    for _ in range(3):
        q0 = np.array([*r.uniform(-2, 2, 2), r.uniform(-np.pi, np.pi), r.uniform(-0.5, 0.5)])
        qd = np.array([*r.uniform(-2, 2, 2), r.uniform(-np.pi, np.pi), r.uniform(-0.5, 0.5)])
        res = nonholo.plan(q0, qd, mechanism="car")
        assert res.success, res.reason
        errors, delta = _independent(res)
        assert errors["coordinates"] < 1e-8 and np.abs(delta).min() >= 1e-2


def test_save_load_keeps_the_coordinates(tmp_path):
    res = nonholo.plan([0, 0, 0, 0.1], [1, 0.5, 0.3, 0.0], mechanism="car")
    path = res.save(tmp_path / "car.json")
    back = nonholo.PlanResult.load(path)
    assert back == res and np.array_equal(back.q, res.q) and back.errors == res.errors
    assert back.goal == res.goal
    text = path.read_text().replace('"q0": [\n  0.0', '"q0": [\n  0.25', 1)
    assert text != path.read_text()
    (tmp_path / "bad.json").write_text(text)
    with pytest.raises(ValueError, match="q"):
        nonholo.PlanResult.load(tmp_path / "bad.json")


def test_wrong_kind_of_state_says_what_is_expected():
    with pytest.raises(ValueError, match=r"start must be a pair \(R, q\)"):
        nonholo.plan(np.eye(3), (np.eye(3), [0, 0]), mechanism="rolling_ball")
    with pytest.raises(ValueError, match="goal must be a vector of its 4 coordinates"):
        nonholo.plan([0, 0, 0, 0], (np.eye(3), [0, 0, 0, 0]), mechanism="car")
    with pytest.raises(ValueError, match="expected \\(4,\\)"):
        nonholo.plan([0, 0, 0], [0, 1, 0, 0], mechanism="car")
    with pytest.raises(ValueError, match="rotation matrix"):
        nonholo.plan((np.eye(3), [0, 0]), np.eye(3), mechanism="platform")


@pytest.mark.slow
def test_far_car_goal_is_reached_by_the_global_route(tmp_path):
    """A goal 40 car lengths away that the local planner alone does not reach: the global
    route steers the straight path of states hop by hop, and DOP853 confirms the plan."""
    start, goal = [28.031, -9.619, -1.535, -0.27], [11.942, 26.89, 2.611, 0.018]
    local = nonholo.plan(start, goal, mechanism="car", settings=nonholo.Settings(tol=1e-8), route="local")
    assert not local.success
    res = nonholo.plan(start, goal, mechanism="car", settings=nonholo.Settings(tol=1e-8))
    assert res.success and res.route == "global", res.reason
    hops = res.hops
    assert hops.n_pieces >= 5 and hops.coordinates.shape == (hops.n_pieces + 1, 4)
    np.testing.assert_allclose(hops.coordinates[0], start)
    np.testing.assert_allclose(hops.coordinates[-1], goal)
    t, R, q, delta = resimulate_state(res.start, res.controls, res.T, "car", res.breakpoints)
    assert state_errors("car", R[-1], q[-1], res.Rd, res.qd)["coordinates"] <= 1e-8
    assert np.min(np.abs(delta)) >= 1e-2
    path = tmp_path / "far.json"
    res.save(path)
    back = nonholo.PlanResult.load(path)
    assert back.hops == hops and back.route == "global"


def test_far_ball_goal_by_the_global_route():
    """Without a singular set the straight path is not checked; route 'global' steers it."""
    start = (so3.exp(np.array([0.3, -1.0, 0.4])), np.zeros(2))
    goal = (so3.exp(np.array([-1.2, 0.5, 0.8])), np.array([6.0, -4.0]))
    res = nonholo.plan(start, goal, mechanism="rolling_ball", route="global")
    assert res.success and res.route == "global", res.reason
    t, R, q, _ = resimulate_state(res.start, res.controls, res.T, "rolling_ball", res.breakpoints)
    errors = state_errors("rolling_ball", R[-1], q[-1], res.Rd, res.qd)
    assert max(errors.values()) <= 1e-8


def test_stitched_coordinates_are_checked():
    from nonholo.controls.stitched import Stitched
    piece = Fourier(1.0, np.zeros((2, 3)))
    with pytest.raises(ValueError, match="coordinates must be finite with shape \\(3, n\\)"):
        Stitched(2.0, [piece, piece], [np.eye(3)] * 3, np.zeros((2, 4)))
    s = Stitched(2.0, [piece, piece], [np.eye(3)] * 3, np.zeros((3, 4)))
    assert s != Stitched(2.0, [piece, piece], [np.eye(3)] * 3)


def test_resimulation_takes_the_ends_inputs_from_inside():
    """A fast smooth control: DOP853 on the hand-written car agrees with a fine CF4 replay
    (an input sampled a nudge inside the ends would be off by u'·ε, far above this)."""
    k = np.arange(1, 33)
    coefficients = np.zeros((2, 65))
    coefficients[0, 0] = 20.0
    coefficients[:, 1:33] = np.array([[30.0], [1.0]]) / k * np.cos(k)
    coefficients[:, 33:] = np.array([[30.0], [1.0]]) / k * np.sin(3 * k)
    control = Fourier(1.0, coefficients)
    start = np.array([0.0, 0.0, 0.0, 0.3])
    _, _, q, _ = resimulate_state(start, control, 1.0, "car")
    fine = nonholo.simulate(start, control, T=1.0, mechanism="car", steps=40000)
    assert np.max(np.abs(q[-1] - fine.q[-1])) <= 1e-10


def test_goal_across_the_singular_set_is_refused():
    res = nonholo.plan([0, 0, 0, 0.2], [0, 1, 0, 2.0], mechanism="car")
    assert not res.success and "across" in res.reason and res.iterations == 0


def test_state_space_derivation_is_shared():
    """The SO(3) block of the product variational matrix is eq. (12)'s Q (rolling ball: [ω])."""
    ball = symbolic.get("rolling_ball")
    A = state_space.A_matrix(ball)
    u = sp.Matrix(sp.symbols("u1:3", real=True))
    from derivations.rotations import hat
    assert sp.simplify(A[:3, :3] - hat(ball.Omega * u)) == sp.zeros(3, 3)


def test_only_sums_are_simplified():
    """The variational matrix simplifies a sum (sin² + cos² → 1) and keeps a single term."""
    x, u = sp.symbols("x u", real=True)
    assert state_space.simplified(u * sp.sin(x) ** 2 + u * sp.cos(x) ** 2) == u
    term = u * sp.cos(x - 1)
    assert state_space.simplified(term) is term


@pytest.mark.slow
def test_figures_draw_the_plans(tmp_path):
    import matplotlib
    matplotlib.use("Agg")
    from nonholo.paper import reproduce
    from nonholo.viz import state_figures

    for name, draw in (("rolling_ball", state_figures.ball_figure), ("car", state_figures.car_figure)):
        start, goal = reproduce.STATE_PROBLEMS[name]
        res = nonholo.plan(start, goal, mechanism=name, **reproduce.STATE_OPTIONS[name])
        fig = draw(res)
        path, angles, inputs = fig.axes
        assert len(path.lines) >= 3 and len(angles.lines) == 2 and len(inputs.lines) == 2
        np.testing.assert_array_equal(path.lines[0].get_xydata(), res.q[:, :2])
        if name == "rolling_ball":      # the angle to the goal ends at 0
            assert angles.lines[1].get_ydata()[-1] < 1e-8
        fig.savefig(tmp_path / f"{name}.png")
        assert (tmp_path / f"{name}.png").stat().st_size > 10_000
    with pytest.raises(ValueError, match="rolling_ball"):
        state_figures.ball_figure(res)


@pytest.mark.slow
def test_command_line_plans_states(tmp_path, capsys):
    """``nonholo plan`` takes a car's coordinates and a ball's RPY angles then position; the
    plan file, CSV (coordinates as columns) and figure are written."""
    import argparse
    import csv

    from nonholo.cli import plan_command as cli_plan

    def cli(argv):
        parser = argparse.ArgumentParser(prog="nonholo")
        cli_plan.add_parser(parser.add_subparsers(dest="command"))
        return cli_plan.run(parser.parse_args(["plan", *argv]))

    out, table, fig = tmp_path / "car.json", tmp_path / "car.csv", tmp_path / "car.png"
    assert cli(["--mechanism", "car", "--from", "0", "0", "0", "0", "--to", "0", "1", "0", "0", "--quiet",
                "--out", str(out), "--csv", str(table), "--plot", str(fig)]) == 0
    assert "terminal error coordinates" in capsys.readouterr().out
    res = nonholo.PlanResult.load(out)
    np.testing.assert_array_equal(res.goal.q, [0, 1, 0, 0])
    rows = list(csv.DictReader(table.open()))
    assert list(rows[0]) == ["t", "u1", "u2", "x", "y", "theta", "phi", "delta"]
    last = rows[-1]
    assert abs(float(last["t"]) - 1.0) < 1e-12 and abs(float(last["y"]) - 1.0) < 1e-9
    assert abs(float(last["delta"]) - np.cos(float(last["phi"]))) < 1e-12
    middle = rows[len(rows) // 2]         # a CSV row between stored samples: CF4 from the one below
    t, R, q, _ = resimulate_state(res.start, res.controls, res.T, "car", samples=len(rows))
    np.testing.assert_allclose([float(middle[k]) for k in ("x", "y", "theta", "phi")],
                               q[np.argmin(np.abs(t - float(middle["t"])))], atol=1e-8)
    assert fig.stat().st_size > 10_000

    ball = tmp_path / "ball.csv"
    assert cli(["--mechanism", "rolling_ball", "--from", "0.4", "-0.3", "0.2", "0", "0",
                "--to", "1.0", "0.2", "0.1", "1", "0.5", "--quiet", "--csv", str(ball)]) == 0
    header = ball.read_text().splitlines()[0].split(",")
    assert header == ["t", "u1", "u2", "p1", "p2", "qx", "qy", "qz", "qw"]
    capsys.readouterr()
    assert cli(["--mechanism", "car", "--from", "0", "0", "0", "--to", "0", "1", "0", "0"]) == 2
    assert "--from takes 4 numbers for mechanism 'car' (x y theta phi), got 3" in capsys.readouterr().err
