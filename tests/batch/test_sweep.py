"""Sweeps (nonholo/batch/sweep.py, nonholo/batch/result_store.py, nonholo/io/problems.py,
nonholo/batch/atlas.py, ``nonholo sweep``):
parallel runs equal serial ones, nothing is lost when a sweep is killed, bad problem files
are refused before anything runs, a Dask cluster of separate processes gives the same rows."""
import json
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pyarrow.parquet as pq
import pytest

from benchmarks import goalset
from nonholo.batch import atlas, result_store, sweep
from nonholo.io import problems
from nonholo.io.result import PlanResult
from nonholo.spaces import so3


def pair_rows(count, offset=0):
    pairs = goalset.uniform_pairs("platform", offset + count)[offset:]
    return [{"start": p["R0"], "goal": p["Rd"], "label": p["id"]} for p in pairs]


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    rows = pair_rows(24)
    out = tmp_path_factory.mktemp("serial") / "serial.parquet"
    return rows, sweep.sweep(rows, out, workers=1, progress=False)


@pytest.mark.slow
def test_local_workers_give_the_serial_rows(serial, tmp_path):
    rows, table = serial
    assert table.column("index").to_pylist() == list(range(len(rows)))
    par = sweep.sweep(rows, tmp_path / "par.parquet", workers=2, progress=False)
    assert result_store.comparable(par) == result_store.comparable(table)
    assert not result_store.parts_dir(tmp_path / "par.parquet").exists()
    # a row's plan is the plan, checked like a plan file
    first = table.to_pylist()[0]
    res = result_store.plan_of(first)
    assert isinstance(res, PlanResult) and res.success == first["success"]
    np.testing.assert_array_equal(res.R0, np.asarray(rows[0]["start"]))


def mixed_rows():
    """Two problems of each kind of state: the platform on SO(3) (goals near Example 1's
    start), the car on R⁴ and the rolling ball on SO(3) × R²."""
    R0 = so3.from_rpy(*atlas.START)
    I = np.eye(3)
    return [
        {"start": R0, "goal": so3.from_rpy(0.7, 1.1, -0.4), "label": "platform-1"},
        {"start": [0.0, 0.0, 0.0, 0.0], "goal": [0.0, 1.0, 0.0, 0.0], "mechanism": "car", "label": "car-sideways"},
        {"start": (I, [0.0, 0.0]), "goal": (so3.from_rpy(0.0, 0.0, np.pi / 2), [0.0, 0.0]),
         "mechanism": "rolling_ball", "label": "ball-yaw"},
        {"start": R0, "goal": so3.from_rpy(0.3, 1.25, -0.6), "mechanism": "platform", "label": "platform-2"},
        {"start": np.array([0.0, 0.0, 0.0, 0.0]), "goal": np.array([0.5, 0.3, 0.2, 0.0]), "mechanism": "car",
         "label": "car-forward"},
        {"start": [I.tolist(), [0.0, 0.0]], "goal": [I.tolist(), [0.5, 0.0]], "mechanism": "rolling_ball",
         "label": "ball-roll"},
    ]


@pytest.mark.slow
def test_one_table_mixes_mechanisms(tmp_path):
    """Platform, car and ball problems in one table: the file round-trips, 1 and 2 workers
    give the same rows, and every claimed success holds under SciPy's DOP853."""
    from nonholo.certify.resimulate import resimulate, resimulate_state
    from nonholo.model import catalog

    rows = mixed_rows()
    path = problems.write(tmp_path / "mixed.jsonl", rows)
    read = problems.read(path)
    assert problems.fingerprint(read) == problems.fingerprint(problems.check(rows))
    assert [problems.as_json(p) for p in read] == [json.loads(line) for line in path.read_text().splitlines()]
    # the SO(3) rows are stored as before: nested 3×3 lists
    assert json.loads(path.read_text().splitlines()[0])["goal"] == so3.from_rpy(0.7, 1.1, -0.4).tolist()
    one = sweep.sweep(path, tmp_path / "one.parquet", workers=1, progress=False)
    two = sweep.sweep(path, tmp_path / "two.parquet", workers=2, progress=False, batch=1)
    assert result_store.comparable(two) == result_store.comparable(one)
    table = one.to_pylist()
    assert [r["mechanism"] for r in table] == [p["mechanism"] for p in read]
    assert all(r["error"] is None for r in table), [r["error"] for r in table]
    assert all(r["success"] for r in table), [(r["label"], r["reason"]) for r in table]
    for row, problem in zip(table, read):
        res = result_store.plan_of(row)
        assert res.mechanism == problem["mechanism"] and res.success
        space = catalog.get(res.mechanism).space
        start, goal = space.parse(problem["start"], "start"), space.parse(problem["goal"], "goal")
        assert res.start == start and res.goal == goal
        (R0, q0), (Rd, qd) = start, goal
        # independent: DOP853 on the hand-written model (car, ball) or on L(R) (platform)
        if space.k or not space.has_orientation:
            _, R, q, delta = resimulate_state(res.start, res.controls, res.T, res.mechanism,
                                              res.breakpoints)
            R_T, q_T = R[-1], q[-1]
            if delta is not None:
                assert np.min(np.sign(delta[0]) * delta) > 0.0
        else:
            R_T, q_T = resimulate(R0, res.controls, res.T, res.mechanism, res.breakpoints), q0
        assert space.distance((R_T, q_T), (Rd, qd)) < 1e-8, row["label"]


@pytest.mark.slow
def test_a_finished_sweep_is_not_run_again(serial, tmp_path, monkeypatch):
    rows, _ = serial
    out = tmp_path / "r.parquet"
    first = sweep.sweep(rows[:4], out, workers=1, progress=False)

    def forbidden(batch):
        raise AssertionError("a finished sweep ran again")

    monkeypatch.setattr(sweep, "solve_batch", forbidden)
    assert sweep.sweep(rows[:4], out, workers=1, progress=False).equals(first)
    with pytest.raises(ValueError, match="other results"):
        sweep.sweep(rows[1:5], out, workers=1, progress=False)


def test_a_problem_that_raises_is_recorded_and_the_sweep_goes_on(tmp_path, monkeypatch):
    import nonholo.planning.api

    rows = pair_rows(3)
    rows[1] = {**rows[1], "options": {"tol": 1e-9}}
    real = nonholo.planning.api.plan

    def plan(*args, settings=None, **kwargs):       # a failure only planning shows
        if settings is not None and settings.tol == 1e-9:
            raise ArithmeticError("the planner broke")
        return real(*args, settings=settings, **kwargs)

    monkeypatch.setattr(nonholo.planning.api, "plan", plan)
    table = sweep.sweep(rows, tmp_path / "r.parquet", workers=1, progress=False).to_pylist()
    assert table[1]["error"] == "ArithmeticError: the planner broke" and table[1]["plan"] is None
    assert not table[1]["success"]
    assert table[0]["error"] is None and table[2]["error"] is None and table[0]["plan"] is not None


@pytest.mark.parametrize("line, match", [
    ('{"goal": I}', r"row 1, column 'start': is missing"),
    ('{"start": I, "goal": [[1, 0], [0, 1]]}',
     r"row 1, column 'goal': mechanism 'platform' expects a rotation matrix \(3×3\); goal must have shape \(3, 3\)"),
    ('{"start": I, "goal": [0, 1, 0, 0], "mechanism": "car"}',
     r"row 1, column 'start': mechanism 'car' expects a vector of its 4 coordinates \(x, y, theta, phi\); start has "
     r"shape \(3, 3\)"),
    ('{"start": [I, [0, 0]], "goal": G, "mechanism": "rolling_ball"}',
     r"row 1, column 'goal': mechanism 'rolling_ball' expects a pair \(R, q\): a rotation matrix R \(3×3\) and the 2 "
     r"coordinates q = \(p1, p2\); got an array of shape \(3, 3\)"),
    ('{"start": [I, [0]], "goal": [G, [0, 0]], "mechanism": "rolling_ball"}',
     r"row 1, column 'start': .*start\[1\] \(the coordinates\) has shape \(1,\), expected \(2,\)"),
    ('{"start": I, "goal": [[1, 0, 0], [0, 1, 0], [0, 0, 2]]}', r"row 1, column 'goal': "),
    ('{"start": I, "goal": G, "mechanism": "nosuch"}', r"row 1, column 'mechanism': unknown mechanism 'nosuch'"),
    ('{"start": I, "goal": G, "options": {"speed": 1}}', r"row 1, column 'options.speed': is not an option"),
    ('{"start": I, "goal": G, "colour": "red"}', r"row 1, column 'colour': is not a column"),
    ('{"start": I, "goal": G', r"row 1: is not JSON"),
    ('', r"row 1: is blank"),
])
@pytest.mark.slow
def test_bad_problem_files_name_the_row_and_column_before_anything_runs(tmp_path, line, match, monkeypatch):
    good = pair_rows(1)[0]
    text = json.dumps(problems.as_json(problems.check_row(good, 0)))
    I = json.dumps(np.asarray(good["start"]).tolist())
    G = json.dumps(np.asarray(good["goal"]).tolist())
    path = tmp_path / "p.jsonl"
    path.write_text(text + "\n" + line.replace("I", I).replace("G", G) + "\n" + text + "\n")
    monkeypatch.setattr(sweep, "solve_batch", lambda batch: pytest.fail("a problem ran"))
    with pytest.raises(ValueError, match=match):
        sweep.sweep(path, tmp_path / "r.parquet", workers=1, progress=False)
    assert not (tmp_path / "r.parquet").exists() and not result_store.parts_dir(tmp_path / "r.parquet").exists()
    # the command line: exit status 2, the same message
    run = subprocess.run([sys.executable, "-m", "nonholo.cli", "sweep", str(path), "--out",
                          str(tmp_path / "r.parquet")], capture_output=True, text=True)
    assert run.returncode == 2 and "row 1" in run.stderr


@pytest.mark.slow
def test_a_killed_sweep_resumes_without_losing_or_repeating_a_row(tmp_path):
    # problems slow enough (a fine grid) that the sweep is killed half-way
    rows = [{**r, "options": {"steps": 3200, "harmonics": 4}} for r in pair_rows(16)]
    table = sweep.sweep(rows, tmp_path / "serial.parquet", workers=1, progress=False)
    path = problems.write(tmp_path / "p.jsonl", rows)
    out = tmp_path / "r.parquet"
    cmd = [sys.executable, "-m", "nonholo.cli", "sweep", str(path), "--out", str(out), "--workers", "1",
           "--batch", "1", "--quiet"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    parts = result_store.parts_dir(out)
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and len(list(parts.glob("part-*.parquet"))) < 3:
        assert proc.poll() is None, proc.stderr.read()
        time.sleep(0.01)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    kept = [pq.read_table(p) for p in parts.glob("part-*.parquet")]
    assert kept and not out.exists()
    done = sum(t.num_rows for t in kept)
    assert 0 < done < len(rows)
    subprocess.run(cmd, check=True, capture_output=True)
    resumed = result_store.load(out)
    assert resumed.column("index").to_pylist() == list(range(len(rows)))
    assert result_store.comparable(resumed) == result_store.comparable(table)
    assert not parts.exists()


def test_a_resumed_sweep_refuses_other_problems(tmp_path):
    out = tmp_path / "r.parquet"
    parts = result_store.parts_dir(out)
    parts.mkdir()
    (parts / "sweep.json").write_text(json.dumps({"fingerprint": "0" * 64, "problems": 2}))
    with pytest.raises(ValueError, match="other problems"):
        sweep.sweep(pair_rows(2), out, workers=1, progress=False)


@pytest.mark.skipif(shutil.which("dask") is None, reason="the dask command-line tools are not installed")
@pytest.mark.slow
def test_a_dask_cluster_of_separate_processes_gives_the_serial_rows(serial, tmp_path):
    """``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1 (started and shut
    down by the benchmark's :func:`benchmarks.sweep_scaling.dask_cluster`)."""
    from distributed import Client

    from benchmarks.sweep_scaling import dask_cluster

    rows, table = serial
    rows = rows[:8]
    with dask_cluster(tmp_path) as address:
        with Client(address, timeout="60s") as client:
            got = sweep.sweep(rows, tmp_path / "dask.parquet", client=client, progress=False)
        assert result_store.comparable(got) == result_store.comparable(table)[:8]
        # the command line takes the scheduler's address
        path = problems.write(tmp_path / "p.jsonl", rows)
        subprocess.run([sys.executable, "-m", "nonholo.cli", "sweep", str(path), "--out",
                        str(tmp_path / "cli.parquet"), "--scheduler", address, "--quiet"], check=True)
        assert result_store.comparable(result_store.load(tmp_path / "cli.parquet")) == result_store.comparable(table)[:8]


@pytest.mark.slow
def test_atlas_maps_from_a_small_sweep(tmp_path):
    rows = atlas.problems(n=4, settings=("paper", "default"))
    assert len(rows) == 2 * 16
    table = sweep.sweep(rows, tmp_path / "a.parquet", workers=1, progress=False)
    a = atlas.Atlas(table)
    assert a.settings == ["paper", "default"] and a.n == 4
    # unreachable exactly where Δ(goal) has the other sign than Δ(start), or is within delta_min of 0
    from nonholo.model import catalog

    mech = catalog.get("platform")
    sign0 = np.sign(mech.delta(so3.from_rpy(*atlas.START)))
    phi, theta = atlas.grid_angles(4)
    for j, th in enumerate(theta):
        for i, ph in enumerate(phi):
            d = mech.delta(so3.from_rpy(ph, th, atlas.START[2]))
            assert (a.outcome[0, 0, j, i] == "unreachable") == (np.sign(d) != sign0 or abs(d) < 1e-2)
    # the default solves at least what the paper's algorithm solves here
    assert a.count("default", "solved") >= a.count("paper", "solved")
    for q in atlas.QUANTITIES:
        fig = atlas.atlas_figure(table, q)
        assert len(fig.axes) >= 2
    run = subprocess.run([sys.executable, "-m", "nonholo.cli", "atlas", str(tmp_path / "a.parquet"), "--out",
                          str(tmp_path / "figs")], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert all((tmp_path / "figs" / f"atlas_{q}.{ext}").stat().st_size > 0
               for q in atlas.QUANTITIES for ext in ("png", "pdf"))


def test_a_strategy_class_goes_into_a_problem_table_by_its_import_path(tmp_path):
    """``options.strategy = "package.module:Class"``: any Strategy subclass, in JSON."""
    from benchmarks import bench_robust
    from nonholo.planning.api import strategy_class

    assert strategy_class("benchmarks.bench_robust:WBarrier") is bench_robust.WBarrier
    for bad in ("benchmarks.bench_robust:Nothing", "no.such.module:X", "nonholo.planning.api:plan"):
        with pytest.raises(ValueError, match="strategy"):
            strategy_class(bad)
    rows = [{**r, "options": {"strategy": "benchmarks.bench_robust:WBarrier", "route": "local"}}
            for r in pair_rows(2)]
    with pytest.raises(ValueError, match=r"row 0, column 'options.strategy': names a strategy by its import path"):
        sweep.sweep(rows, tmp_path / "r.parquet", workers=1, progress=False)
    table = sweep.sweep(rows, tmp_path / "r.parquet", workers=1, progress=False, allow_imports=True).to_pylist()
    assert [r["strategy"] for r in table] == [bench_robust.WBarrier.name] * 2
    assert all(r["error"] is None for r in table)


@pytest.mark.slow
def test_car_atlas_over_the_goal_position(tmp_path):
    """A goal grid in the car's (x, y) from a start, the heading and steering the start's:
    the goals are the cell centres, every claimed success holds under DOP853, the maps are
    drawn, and the command line writes the same problems."""
    from nonholo.certify.resimulate import resimulate_state
    from nonholo.model import catalog

    start = (0.0, 0.0, 0.3, 0.0)
    rows = atlas.problems(n=3, mechanism="car", axes=("x", "y"), start=start, extent=(-1.0, 1.0, -0.5, 1.5),
                          settings=("default",))
    assert len(rows) == 9
    xs, ys = [-2 / 3, 0.0, 2 / 3], [-1 / 6, 0.5, 7 / 6]
    for r in rows:
        lab = json.loads(r["label"])
        np.testing.assert_allclose(r["goal"], [xs[lab["i"]], ys[lab["j"]], 0.3, 0.0], atol=1e-15)
        np.testing.assert_array_equal(r["start"], start)
    table = sweep.sweep(rows, tmp_path / "car.parquet", workers=1, progress=False)
    a = atlas.Atlas(table)
    assert a.axes == ("x", "y") and a.slices == [None] and a.holds_start(0)
    assert a.count("default", "unreachable") == 0        # the steering angle stays 0: Δ = cos φ = 1
    space = catalog.get("car").space
    for row in table.to_pylist():
        res = result_store.plan_of(row)
        if row["success"]:
            _, R, q, _ = resimulate_state(res.start, res.controls, res.T, "car", res.breakpoints)
            goal = space.parse(json.loads(row["problem"])["goal"], "goal")
            assert space.distance((R[-1], q[-1]), goal) < 1e-8
    assert a.count("default", "solved") >= 8
    for q in atlas.QUANTITIES:
        fig = atlas.atlas_figure(table, q)
        assert fig.axes[0].get_xlabel() == "goal x [wheelbase]" and fig.axes[0].get_ylabel() == "goal y [wheelbase]"
    from nonholo.cli.entry import main

    assert main(["atlas", "--problems", str(tmp_path / "cli.jsonl"), "--mechanism", "car", "--grid", "3",
                 "--axes", "x", "y", "--start", *map(str, start), "--extent", "-1", "1", "-0.5", "1.5"]) == 0
    mine = problems.write(tmp_path / "mine.jsonl", atlas.problems(
        n=3, mechanism="car", axes=("x", "y"), start=start, extent=(-1.0, 1.0, -0.5, 1.5)))
    assert (tmp_path / "cli.jsonl").read_text() == mine.read_text()


def test_car_atlas_across_the_singular_set(tmp_path):
    """Over (x, steering φ) the car's singular set cos φ = 0 crosses the grid: goals beyond
    it (or within delta_min of it) are unreachable, exactly where cos φ says."""
    rows = atlas.problems(n=4, mechanism="car", axes=("x", "phi"), settings=("default",))
    table = sweep.sweep(rows, tmp_path / "car.parquet", workers=1, progress=False)
    a = atlas.Atlas(table)
    steering = atlas.cell_centres(4, (-np.pi, np.pi))
    for j, phi in enumerate(steering):
        for i in range(4):
            assert (a.outcome[0, 0, j, i] == "unreachable") == (np.cos(phi) < 1e-2)
    assert a.count("default", "unreachable") == 8
    fig = atlas.atlas_figure(table, "success")
    assert "Δ = 0" in fig._suptitle.get_text()


@pytest.mark.parametrize("flags, flag", [
    (["--mechanism", "car", "--axes", "x", "z"], "--axes"),
    (["--mechanism", "car", "--axes", "x", "x"], "--axes"),
    (["--mechanism", "car", "--start", "0", "0", "0"], "--start"),
    (["--mechanism", "car", "--psi", "0.1"], "--psi"),
    (["--axes", "phi", "psi", "--psi", "0.1"], "--psi"),
    (["--mechanism", "nosuch"], "--mechanism"),
    (["--grid", "1"], "--grid"),
    (["--extent", "1", "0", "-1", "1"], "--extent"),
])
def test_atlas_refuses_bad_flags_naming_them(tmp_path, capsys, flags, flag):
    from nonholo.cli.entry import main

    assert main(["atlas", "--problems", str(tmp_path / "p.jsonl"), *flags]) == 2
    assert f"error: {flag} " in capsys.readouterr().err
    assert not (tmp_path / "p.jsonl").exists()
