"""Vehicles' bounds (``nonholo.constraints``): ``InputBounds`` kept by re-timing the planned
path, ``StateBounds`` at every node like a leg stroke, the catalog's defaults, the least time
along the path (``T=None``, ``nonholo plan --T min``), plan files and the certificate.

Plans are checked against an independent integrator: SciPy's DOP853 on the mechanism's own
rates ``mech.rates`` (``G(x) u``), between the controls' breakpoints, not the planner's CF4."""
import json
import math
import re

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import nonholo
from nonholo import PlanResult
from nonholo.certify import certificate as certify
from nonholo.cli.entry import main
from nonholo.constraints import InputBounds, LegSpeed, StateBounds, as_data, of_mechanism
from nonholo.model import catalog
from nonholo.model.bounds import BOUND_RTOL
from nonholo.model.limits import Limits
from nonholo.motion.speed_limits import FLOOR
from nonholo.motion.time_scaling import planned

CAR, UNICYCLE = catalog.get("car"), catalog.get("unicycle")
CAR_INPUTS = InputBounds((-1.0, -1.0), (1.0, 1.0))
CAR_STATE = StateBounds((-math.inf,) * 3 + (-0.6,), (math.inf,) * 3 + (0.6,))
PARK = ([0.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0])          # one wheelbase sideways
#: Dynobench's obstacle-free unicycle park (MODEL.md: time-optimal ≈ 2.90 s)
UNICYCLE_PARK = ([0.7, 0.8, 0.0], [1.9, 0.3, 0.0])


def dop853(result, mech, samples: int = 4001):
    """The plan's controls played by DOP853 on ``mech.rates``: sample times, states."""
    bp = result.breakpoints
    bp = np.unique(np.concatenate([[0.0, result.T], [] if bp is None else np.asarray(bp, dtype=float)]))
    R, x = np.eye(3), np.asarray(result.q0, dtype=float)
    ts, xs = [], []
    for a, b in zip(bp[:-1], bp[1:]):
        if not b > a:
            continue
        sol = solve_ivp(lambda t, y: mech.rates(R, y, np.asarray(result.controls(t), dtype=float).reshape(-1)),
                        (a, b), x, method="DOP853", rtol=1e-12, atol=1e-13, dense_output=True)
        t = np.linspace(a, b, max(3, int(samples * (b - a) / result.T)))
        ts.append(t), xs.append(sol.sol(t).T)
        x = sol.y[:, -1]
    return np.concatenate(ts), np.concatenate(xs)


def usage(bounds, u):
    """``max_i max(u_i/high_i, u_i/low_i)``, computed here (not by the package)."""
    u = np.asarray(u, dtype=float)
    lo, hi = np.asarray(bounds.low), np.asarray(bounds.high)
    return np.max(np.maximum(u / hi, u / lo), axis=-1)


@pytest.fixture(scope="module")
def car_least():
    return nonholo.plan(*PARK, mechanism="car", T=None)


@pytest.fixture(scope="module")
def unicycle_least():
    return nonholo.plan(*UNICYCLE_PARK, mechanism="unicycle", T=None)


# -- the objects ---------------------------------------------------------------------------

@pytest.mark.parametrize("build, match", [
    (lambda: InputBounds(float("nan"), 1.0), "InputBounds: low"),
    (lambda: InputBounds(-1.0, (1.0, float("nan"))), r"InputBounds: high\[1\]"),
    (lambda: InputBounds(1.0, 0.5), "low = 1 must be below high = 0.5"),
    (lambda: StateBounds((0.0, 2.0), (1.0, 1.0)), r"StateBounds: low\[1\] = 2 must be below high\[1\] = 1"),
    (lambda: StateBounds((0.0, 1.0), (1.0, 2.0, 3.0)), "low has 2 entries, high 3"),
    (lambda: StateBounds("x", 1.0), "StateBounds: low must be"),
    (lambda: InputBounds((-1, -1, -1), (1, 1, 1)).check(CAR), r"low has 3 entries, mechanism 'car' has 2 inputs \(v, u2\)"),
    (lambda: StateBounds(-1.0, (1.0, 1.0)).check(CAR), r"high has 2 entries, mechanism 'car' has 4 coordinates"),
    (lambda: StateBounds(-1.0, 1.0).check(catalog.get("platform")), "has no coordinates"),
    (lambda: nonholo.plan(*PARK, mechanism="car", T=1.0, constraints=[InputBounds((-1.0, 0.0), (1.0, 1.0))]),
     "0 ≤ u2 ≤ 1 .* does not hold 0 inside"),
])
def test_bad_bounds_name_the_argument(build, match):
    with pytest.raises(ValueError, match=match):
        build()


def test_a_start_or_goal_outside_the_state_bounds_is_refused_naming_it_and_the_coordinate():
    for start, goal, name in (([0, 0, 0, 0.7], PARK[1], "start"), (PARK[0], [0, 1, 0, -0.65], "goal")):
        with pytest.raises(ValueError, match=f"^{name}: the {name} is outside "
                                             r"the coordinates' bounds: phi = -?0\.\d+ passes"):
            nonholo.plan(start, goal, mechanism="car", T=None)
        with pytest.raises(ValueError, match=f"^{name}: .* phi"):
            nonholo.plan(start, goal, mechanism="car", constraints=[CAR_STATE])


def test_bad_combinations_name_the_arguments():
    with pytest.raises(ValueError, match="T=None asks for the least time, which needs a LegSpeed"):
        nonholo.plan(np.eye(3), np.eye(3), mechanism="rolling_ball", T=None)
    R0, Rd = nonholo.spaces.so3.from_rpy(0.5, 1.2, -0.5), nonholo.spaces.so3.from_rpy(1.0, 0.9, -0.5)
    with pytest.raises(ValueError, match="LegSpeed and InputBounds"):
        nonholo.plan(R0, Rd, T=None, constraints=[InputBounds(-1.0, 1.0), LegSpeed(1.0)])
    with pytest.raises(TypeError, match=r"constraints\[1\]"):
        nonholo.plan(*PARK, mechanism="car", constraints=[CAR_INPUTS, (-1, 1)])
    with pytest.raises(ValueError, match="at most one"):
        nonholo.plan(*PARK, mechanism="car", constraints=[CAR_INPUTS, CAR_INPUTS])


def test_the_catalog_vehicles_carry_their_bounds_as_data_and_as_objects():
    assert of_mechanism("car") == [CAR_INPUTS, CAR_STATE]
    assert of_mechanism(UNICYCLE) == [InputBounds((-0.5, -0.5), (0.5, 0.5))]
    assert of_mechanism("rolling_ball") == [] and of_mechanism("platform") == []
    assert CAR.bounds == {"inputs": {"v": (-1.0, 1.0), "u2": (-1.0, 1.0)}, "coordinates": {"phi": (-0.6, 0.6)}}
    # data -> objects -> data, and a mechanism given the data (as a mechanism file's [bounds]) the same objects
    assert as_data(of_mechanism(CAR), CAR) == CAR.bounds
    import dataclasses
    own = dataclasses.replace(catalog.get("brockett"), bounds={"inputs": {"u1": (-2.0, 3.0)},
                                                                "coordinates": {"z": (-math.inf, 5.0)}})
    assert of_mechanism(own) == [InputBounds((-2.0, -math.inf), (3.0, math.inf)),
                                 StateBounds(-math.inf, (math.inf, math.inf, 5.0)).check(own)]
    # a plan file's record round-trips, null where free
    record = CAR_STATE.check(CAR).record()
    assert record[:3] == [[None, None]] * 3 and StateBounds.from_record(record, CAR) == CAR_STATE.check(CAR)


# -- least time ----------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["car", "unicycle"])
@pytest.mark.slow
def test_least_time_plans_keep_the_bounds_and_reach_the_goal_under_dop853(name, car_least, unicycle_least):
    res, goal = (car_least, PARK[1]) if name == "car" else (unicycle_least, UNICYCLE_PARK[1])
    mech = catalog.get(name)
    bounds = of_mechanism(name)[0]
    assert res.success, res.reason
    assert res.options["input_bounds"] == bounds.record()
    # the inputs within the bounds at every sample and on a fine grid, to 1e-9 relative
    t = np.linspace(0.0, res.T, 200001)
    u = np.asarray(res.controls(t), dtype=float)
    assert usage(bounds, u).max() <= 1.0 + BOUND_RTOL
    assert usage(bounds, res.u).max() <= 1.0 + BOUND_RTOL
    # one input at its bound nearly throughout (the least time along the path)
    assert usage(bounds, u).max() >= 1.0 - 1e-9
    assert np.mean(usage(bounds, u) >= 1.0 - 1e-6) > 0.5
    # DOP853 on the mechanism's rates ends at the goal
    _, x = dop853(res, mech)
    assert np.max(np.abs(x[-1] - np.asarray(goal))) <= 1e-8
    if name == "car":
        assert np.max(np.abs(x[:, 3])) <= 0.6 * (1.0 + BOUND_RTOL)


@pytest.mark.parametrize("name", ["car", "unicycle"])
def test_the_least_time_is_the_integral_of_the_most_loaded_inputs_share(name, car_least, unicycle_least):
    """``T̃ = ∫ max(max_i |u_i(τ)|/b_i, FLOOR·peak) dτ`` of the planned controls, by an
    independent quadrature (Simpson on a fine grid), is the re-timed plan's ``T``."""
    res = car_least if name == "car" else unicycle_least
    bounds = of_mechanism(name)[0]
    base = planned(res.parametrisation)
    tau = np.linspace(0.0, base.T, 200001)
    share = usage(bounds, np.asarray(base(tau), dtype=float))
    rho = np.maximum(share, FLOOR * share.max())
    h = tau[1] - tau[0]
    simpson = h / 3.0 * (rho[0] + rho[-1] + 4.0 * rho[1:-1:2].sum() + 2.0 * rho[2:-1:2].sum())
    assert res.T == pytest.approx(simpson, rel=1e-6)
    assert res.T > base.T          # the planned path broke the bounds in its planning time


@pytest.mark.parametrize("T, kind", [(8.0, "InputRetimed"), (15.0, "Fourier")])
@pytest.mark.slow
def test_a_plan_in_a_given_time_keeps_the_bounds_re_timed_in_it_or_as_planned(T, kind):
    """With the car's bounds asked for and ``T`` given: a plan whose path needs no more than
    ``T`` is played in ``T`` — re-timed where its inputs broke the bounds (T = 8 s), as
    planned where they did not (T = 15 s)."""
    res = nonholo.plan(*PARK, mechanism="car", T=T, constraints=of_mechanism("car"))
    assert res.success, res.reason
    assert res.T == T and type(res.parametrisation).__name__ == kind
    t = np.linspace(0.0, res.T, 100001)
    assert usage(CAR_INPUTS, res.controls(t)).max() <= 1.0 + BOUND_RTOL
    _, x = dop853(res, CAR)
    assert np.max(np.abs(x[-1] - np.asarray(PARK[1]))) <= 1e-8
    assert np.max(np.abs(x[:, 3])) <= 0.6 * (1.0 + BOUND_RTOL)


@pytest.mark.slow
def test_a_plan_in_too_short_a_time_fails_saying_the_time_it_needs():
    short = nonholo.plan(*PARK, mechanism="car", T=2.0, constraints=of_mechanism("car"))
    assert not short.success
    assert re.search(r"needs T >= \d", short.reason) and "T=None" in short.reason
    assert "input v reaches" in short.reason
    assert short.options["input_bounds"] == CAR_INPUTS.record()


def test_bounds_shape_a_plan_in_a_given_time_whose_path_cannot_keep_them():
    """The unicycle's park in T = 3 s under |v|, |ω| ≤ 0.5: the path as found needs 3.44 s,
    so the bounds shape the motion inside the optimisation (the path of least use of them
    in T) rather than refuse the goal; in 2.5 s, below the least time 2.897 s, no path
    keeps them and the failure says the time the least-use path needs."""
    bounds = InputBounds((-0.5, -0.5), (0.5, 0.5))
    res = nonholo.plan(*UNICYCLE_PARK, mechanism="unicycle", T=3.0, constraints=[bounds])
    assert res.success, res.reason
    assert res.T == 3.0 and "path of least use" in res.reason
    assert res.options["input_bounds"] == bounds.record()
    t = np.linspace(0.0, res.T, 100001)
    assert usage(bounds, res.controls(t)).max() <= 1.0 + BOUND_RTOL
    _, x = dop853(res, UNICYCLE)
    assert np.max(np.abs(x[-1] - np.asarray(UNICYCLE_PARK[1]))) <= 1e-8
    short = nonholo.plan(*UNICYCLE_PARK, mechanism="unicycle", T=2.5, constraints=[bounds])
    assert not short.success
    need = float(re.search(r"least use of the bounds in T uses [\d.]+ of them \(it needs T >= ([\d.]+) s", short.reason)[1])
    assert 2.85 < need < 3.0


def test_retime_plays_a_stored_plan_under_input_bounds():
    res = nonholo.plan(*UNICYCLE_PARK, mechanism="unicycle")          # T = 1, no bounds
    assert usage(of_mechanism("unicycle")[0], res.u).max() > 1.0
    fast = nonholo.retime(res, input_bounds=InputBounds(-0.5, 0.5))
    assert fast.success and fast.T > res.T and "least time" in fast.reason
    slow = nonholo.retime(res, T=2 * fast.T, input_bounds=InputBounds(-0.5, 0.5))
    assert usage(of_mechanism("unicycle")[0], slow.u).max() == pytest.approx(0.5, rel=1e-6)
    with pytest.raises(ValueError, match="too short"):
        nonholo.retime(res, T=0.5 * fast.T, input_bounds=InputBounds(-0.5, 0.5))
    with pytest.raises(ValueError, match="input_bounds"):
        nonholo.retime(res, input_bounds=(-0.5, 0.5))


# -- state bounds ----------------------------------------------------------------------------

@pytest.mark.slow
def test_state_bounds_are_kept_along_the_motion():
    """The car's default parking plan swings the steering beyond 0.6 rad; under
    ``StateBounds`` the certified motion keeps it inside (under DOP853 too)."""
    free = nonholo.plan(*PARK, mechanism="car")
    _, x = dop853(free, CAR)
    assert np.max(np.abs(x[:, 3])) > 0.6
    kept = nonholo.plan(*PARK, mechanism="car", constraints=[CAR_STATE])
    assert kept.success, kept.reason
    assert kept.options["state_bounds"] == CAR_STATE.check(CAR).record()
    _, x = dop853(kept, CAR)
    assert np.max(np.abs(x[:, 3])) <= 0.6 * (1.0 + BOUND_RTOL)
    assert np.max(np.abs(x[-1] - np.asarray(PARK[1]))) <= 1e-8


# -- plan files and the certificate --------------------------------------------------------

def test_a_least_time_plan_saves_and_loads_and_tampered_bounds_are_refused(car_least, tmp_path):
    path = car_least.save(tmp_path / "car.json")
    back = PlanResult.load(path)
    assert back == car_least and back.T == car_least.T
    d = json.loads(path.read_text())
    assert d["controls"]["kind"] == "retimed_inputs" and d["controls"]["bounds"] == CAR_INPUTS.record()
    # bounds recorded tighter than the controls keep
    tampered = dict(d, options={**d["options"], "input_bounds": [[-0.9, 0.9], [-1.0, 1.0]]})
    (tmp_path / "a.json").write_text(json.dumps(tampered))
    with pytest.raises(ValueError, match="'options' record input_bounds"):
        PlanResult.load(tmp_path / "a.json")
    tampered = dict(d, options={**d["options"], "state_bounds": [[None, None]] * 3 + [[-0.4, 0.4]]})
    (tmp_path / "s.json").write_text(json.dumps(tampered))
    with pytest.raises(ValueError, match="'success' is true, but the replayed motion leaves the coordinates' bounds: phi"):
        PlanResult.load(tmp_path / "s.json")
    tampered = dict(d, options={**d["options"], "state_bounds": [[None, None]] * 3 + [[0.4, -0.4]]})
    (tmp_path / "b.json").write_text(json.dumps(tampered))
    with pytest.raises(ValueError, match="'options' has a bad state_bounds"):
        PlanResult.load(tmp_path / "b.json")


def test_the_certificate_refuses_controls_beyond_the_bounds():
    res = nonholo.plan(*PARK, mechanism="car", T=15.0, constraints=of_mechanism("car"))
    assert res.success and not type(res.parametrisation).__name__.endswith("Retimed")
    kw = dict(tol=1e-10, delta_min=1e-2, sign=1.0)
    args = (res.start, res.goal, res.T, CAR, res.parametrisation, res.replay_steps)
    assert certify.measure(*args, **kw, input_bounds=CAR_INPUTS.check(CAR),
                           limits=Limits.of(CAR_STATE.check(CAR))).passed
    peak = float(np.max(np.abs(res.u[:, 0])))
    tight = InputBounds((-0.9 * peak, -1.0), (0.9 * peak, 1.0)).check(CAR)
    bad = certify.measure(*args, **kw, input_bounds=tight)
    assert not bad.passed and "inputs leave their bounds: input v reaches" in bad.reason
    phi = float(np.max(np.abs(res.q[:, 3])))
    box = StateBounds((-math.inf,) * 3 + (-0.9 * phi,), (math.inf,) * 3 + (0.9 * phi,)).check(CAR)
    bad = certify.measure(*args, **kw, limits=Limits.of(box))
    assert not bad.passed and "coordinates' bounds" in bad.reason and "phi" in bad.reason
    # and a file whose successful controls break the bounds it records is refused on load
    d = res.to_dict()
    d["options"]["input_bounds"] = tight.record()
    with pytest.raises(ValueError, match="'success' is true, but input v reaches"):
        PlanResult.from_dict(json.loads(json.dumps(d)))


# -- the command line ------------------------------------------------------------------------

def test_cli_plans_the_car_in_the_least_time_and_prints_it(capsys, car_least):
    status = main(["plan", "--mechanism", "car", "--from", "0", "0", "0", "0", "--to", "0", "1", "0", "0",
                   "--T", "min", "--quiet"])
    out = capsys.readouterr().out
    assert status == 0, out
    T = float(re.search(r"T = ([0-9.]+) s", out).group(1))
    assert T == pytest.approx(car_least.T, rel=1e-5)
    assert "least time" in out


PYTHON = re.compile(r"T=None|\b(leg_speed|leg_length|delta_min|max_iter|allow_imports|csv_rate|R0|Rd)\b|"
                    r"\w=None|InputBounds|StateBounds|LegSpeed|LegStroke|Clearance|Settings|constraints|"
                    r"nonholo\.Mechanism|Strategy subclass")


@pytest.mark.parametrize("argv", [
    ["--T", "min"],
    ["--T", "0"],
    ["--T", "1e-12"],
    ["--leg-speed", "-1"],
    ["--leg-length", "2", "1"],
    ["--delta-min", "-1"],
    ["--max-iter", "-1"],
    ["--steps", "3"],
    ["--strategy", "a.b:C"],
    ["--mechanism", "car", "--from", "0", "0", "0", "0", "--to", "0", "1", "0", "0", "--leg-speed", "1"],
    ["--mechanism", "car", "--from", "0", "0", "0", "0", "--to", "0", "1", "0", "0", "--leg-length", "1", "2"],
    ["--mechanism", "car", "--from", "0", "0", "0", "0.7", "--to", "0", "1", "0", "0", "--T", "min"],
    ["--mechanism", "car", "--from", "0", "0", "0", "0", "--to", "0", "1", "0", "0.7", "--T", "min"],
    ["--mechanism", "car", "--from", "0", "0", "0", "0", "--to", "0", "1", "0", "0", "--T", "min", "--leg-speed", "1"],
    ["--mechanism", "rolling_ball", "--from", "0", "0", "0", "0", "0", "--to", "0", "0", "0", "1", "0", "--T", "min"],
    ["--from", "0", "0", "0", "--to", "1", "0.9", "-0.5"],
])
def test_cli_errors_name_flags_not_python_arguments(capsys, argv):
    if "--from" not in argv:
        argv = ["--from", "0.5", "1.2", "-0.5", "--to", "1.0", "0.9", "-0.5"] + argv
    status = main(["plan", "--quiet"] + argv)
    err = capsys.readouterr().err
    assert status == 2, err
    assert err.startswith("nonholo plan: error: ") and "--" in err
    assert not PYTHON.search(err), err


# -- bounds off zero: a vehicle that only drives forward -------------------------------------

FORWARD = InputBounds((0.25, -0.5), (0.5, 0.5))


def dubins_time(goal, radius: float, speed: float) -> float:
    """The length of the shortest Dubins path of ``radius`` from the origin to ``goal``, over
    ``speed`` (OMPL's Dubins state space)."""
    from ompl import base as ob

    space = ob.DubinsStateSpace(radius)
    a, b = space.allocState(), space.allocState()
    for s, (x, y, th) in ((a, (0.0, 0.0, 0.0)), (b, goal)):
        s.setX(x), s.setY(y), s.setYaw(th)
    return space.distance(a, b) / speed


@pytest.mark.parametrize("goal", [(2.0, 0.5, 0.0), (1.0, 1.5, 2.0), (3.0, -1.0, -1.0), (-1.0, 0.5, 3.0)])
def test_the_least_time_of_a_vehicle_that_only_drives_forward_is_between_its_dubins_times(goal):
    """v in [0.25, 0.5], |ω| ≤ 0.5: the plan reaches the goal under DOP853 with every input in
    its bounds (v never below 0.25), in a time between the Dubins paths' at the top speed of
    the tightest radius (0.5 m, a lower bound) and of the radius at the top speed (1 m, a
    motion it may take)."""
    res = nonholo.plan((0.0, 0.0, 0.0), goal, mechanism="unicycle", T=5.0, objective="time",
                       constraints=[FORWARD])
    assert res.success, res.reason
    _, xs = dop853(res, UNICYCLE)
    assert np.abs(xs[-1] - np.asarray(goal)).max() < 1e-8
    u = np.asarray(res.controls(np.linspace(0.0, res.T, 4001)))
    assert u[:, 0].min() >= 0.25 * (1 - 1e-9) and u[:, 0].max() <= 0.5 * (1 + 1e-9)
    assert np.abs(u[:, 1]).max() <= 0.5 * (1 + 1e-9)
    assert dubins_time(goal, 0.5, 0.5) * (1 - 1e-9) <= res.T <= dubins_time(goal, 1.0, 0.5) * (1 + 1e-3)


def test_bounds_off_zero_are_refused_where_only_a_re_timing_would_keep_them():
    """A plan at a given T, the least time by re-timing (T=None), a mechanism with drift, and
    retime(): each refused naming the bound."""
    for kwargs in ({"T": 5.0}, {"T": 5.0, "objective": "energy"}, {"T": None}):
        with pytest.raises(ValueError, match=r"InputBounds: the bound 0.25 ≤ v ≤ 0.5 .* does not hold 0 inside"):
            nonholo.plan((0.0, 0.0, 0.0), (1.0, 0.5, 0.0), mechanism="unicycle", constraints=[FORWARD], **kwargs)
    with pytest.raises(ValueError, match="does not hold 0 inside.*drift"):
        nonholo.plan(np.zeros(5), (1.0, 0.5, 0.0, 0.0, 0.0), mechanism="unicycle2", T=6.0, objective="time",
                     constraints=[InputBounds((0.05, -0.25), (0.25, 0.25))])
    res = nonholo.plan((0.0, 0.0, 0.0), (1.0, 0.5, 0.0), mechanism="unicycle", T=5.0)
    with pytest.raises(ValueError, match=r"input_bounds: the bound 0.25 ≤ v ≤ 0.5 does not hold 0 inside"):
        nonholo.retime(res, input_bounds=FORWARD)


def test_a_forward_only_path_in_a_longer_time_keeps_its_least_speed():
    """Slowed by one factor, the least-time path would drop below v = 0.25 where it runs at
    it; the path of least use with the sides off zero fixed (``least_use(fixed=True)``) in
    1.2 times the least time keeps every bound and reaches the goal under DOP853."""
    from nonholo.planning import least_time
    from nonholo.planning.problem import Problem

    goal = (-1.0, 0.5, 3.0)
    fastest = nonholo.plan((0.0, 0.0, 0.0), goal, mechanism="unicycle", T=5.0, objective="time",
                           constraints=[FORWARD])
    assert fastest.success, fastest.reason
    T = 1.2 * fastest.T
    problem = Problem.build((0.0, 0.0, 0.0), goal, mechanism="unicycle", T=T, objective="time", constraints=[FORWARD])
    used = least_time.least_use(problem, least_time.stretched(fastest.controls, fastest.T, T), fixed=True)
    assert not isinstance(used, str), used
    assert used.use <= least_time.KEPT
    played = least_time.finished(problem, fastest, used, "in 1.2 times the least time")
    assert played.success and played.T == pytest.approx(T)
    _, xs = dop853(played, UNICYCLE)
    assert np.abs(xs[-1] - np.asarray(goal)).max() < 1e-8
    u = np.asarray(played.controls(np.linspace(0.0, T, 4001)))
    assert u[:, 0].min() >= 0.25 * (1 - 1e-9) and u[:, 0].max() <= 0.5 * (1 + 1e-9)
    assert np.abs(u[:, 1]).max() <= 0.5 * (1 + 1e-9)
