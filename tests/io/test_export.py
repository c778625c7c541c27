"""The CSV an actuator controller plays back (nonholo/io/csv_export.py, ``PlanResult.to_csv``,
``nonholo plan --csv``), against independent computations: DOP853, the geometry, finite
differences in time."""
import csv

import numpy as np
import pytest
from conftest import example
from scipy.spatial.transform import Rotation

from nonholo.certify.resimulate import resimulate_path
from nonholo.cli.entry import main
from nonholo.io import csv_export as export
from nonholo.model import catalog
from nonholo.planning.api import plan
from nonholo.spaces import so3
from nonholo import Settings


def read(path):
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    header, data = rows[0], np.array(rows[1:], dtype=float)
    return {name: data[:, i] for i, name in enumerate(header)}, header


@pytest.fixture(scope="module")
def plan1():
    return plan(*example(1))


def test_columns_and_rows(plan1, tmp_path):
    path = plan1.to_csv(tmp_path / "m.csv", rate=250)
    cols, header = read(path)
    assert header == ["t", "l1", "l2", "dl1_dt", "dl2_dt", "u1", "u2", "qx", "qy", "qz", "qw", "delta"]
    np.testing.assert_allclose(cols["t"], np.arange(251) / 250, rtol=0, atol=1e-15)
    assert cols["t"][-1] == plan1.T
    q = np.column_stack([cols[k] for k in ("qx", "qy", "qz", "qw")])
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)
    assert np.all(np.sum(q[1:] * q[:-1], axis=1) > 0)          # no sign flip between rows
    np.testing.assert_allclose(np.column_stack([cols["u1"], cols["u2"]]), plan1.controls(cols["t"]), rtol=0,
                               atol=1e-15)


def test_orientations_agree_with_an_independent_integrator(plan1, tmp_path):
    cols, _ = read(plan1.to_csv(tmp_path / "m.csv", rate=330))      # times off the plan's grid
    R = Rotation.from_quat(np.column_stack([cols[k] for k in ("qx", "qy", "qz", "qw")])).as_matrix()
    t_ref, R_ref, _ = resimulate_path(plan1.R0, plan1.controls, plan1.T, "platform", plan1.breakpoints,
                                      samples=331)
    j = np.array([np.argmin(np.abs(t_ref - t)) for t in cols["t"]])
    assert np.max(np.abs(t_ref[j] - cols["t"])) <= 1e-12
    err = [so3.distance(a, b) for a, b in zip(R, R_ref[j])]
    assert max(err) <= 1e-9
    np.testing.assert_allclose(R[0], plan1.R0, rtol=0, atol=1e-15)
    mech = catalog.get("platform")
    np.testing.assert_allclose(cols["delta"], mech.delta_samples(R), rtol=0, atol=1e-12)


def test_leg_columns_against_the_geometry_and_time_differences(plan1, tmp_path):
    mech = catalog.get("platform")
    cols, _ = read(plan1.to_csv(tmp_path / "m.csv", rate=4000))
    R = Rotation.from_quat(np.column_stack([cols[k] for k in ("qx", "qy", "qz", "qw")])).as_matrix()
    L = mech.geometry.leg_lengths(R)                              # |R tip − base|, numerically
    np.testing.assert_allclose(np.column_stack([cols["l1"], cols["l2"]]), L, rtol=1e-12)
    dt = cols["t"][1] - cols["t"][0]
    for i in (1, 2):
        fd = (cols[f"l{i}"][2:] - cols[f"l{i}"][:-2]) / (2 * dt)
        np.testing.assert_allclose(cols[f"dl{i}_dt"][1:-1], fd, rtol=0, atol=1e-5)


def test_a_mechanism_without_legs_or_singular_set(tmp_path):
    p = np.eye(3), so3.from_rpy(0.3, -0.2, 0.4)
    res = plan(*p, mechanism="attitude")
    cols, header = read(res.to_csv(tmp_path / "a.csv", rate=10))
    assert header == ["t", "u1", "u2", "qx", "qy", "qz", "qw"]
    R = Rotation.from_quat(np.column_stack([cols[k] for k in ("qx", "qy", "qz", "qw")])).as_matrix()
    assert so3.distance(R[-1], p[1]) <= 1e-9


def test_bad_rate_and_failed_plans_are_refused(plan1, tmp_path):
    for rate in (0, -5, float("nan"), float("inf"), "100"):
        with pytest.raises(ValueError, match="rate"):
            plan1.to_csv(tmp_path / "x.csv", rate=rate)
    failed = plan(*example(1), settings=Settings(max_iter=1), route="local")
    assert not failed.success
    with pytest.raises(ValueError, match="failed"):
        failed.to_csv(tmp_path / "x.csv")
    assert not (tmp_path / "x.csv").exists()


def test_cli_writes_the_csv(tmp_path, capsys):
    out = tmp_path / "plan.csv"
    assert main(["plan", "--from", "0.5", "1.2", "-0.5", "--to", "1.0", "0.9", "-0.5", "--quiet",
                 "--csv", str(out), "--csv-rate", "50"]) == 0
    cols, _ = read(out)
    assert len(cols["t"]) == 51 and f"wrote {out}" in capsys.readouterr().out
    assert main(["plan", "--from", "0.5", "1.2", "-0.5", "--to", "1.0", "0.9", "-0.5", "--quiet",
                 "--csv", str(out), "--csv-rate", "0"]) == 2
    assert "--csv-rate" in capsys.readouterr().err
    assert export.sample_times(1.0, 3.0).tolist() == [0.0, 1 / 3, 2 / 3, 1.0]


def test_cli_csv_that_cannot_be_written_exits_3(tmp_path, capsys):
    out = tmp_path / "no such dir" / "plan.csv"
    assert main(["plan", "--from", "0.5", "1.2", "-0.5", "--to", "1.0", "0.9", "-0.5", "--quiet",
                 "--csv", str(out)]) == 3
    assert str(out) in capsys.readouterr().err


def test_to_csv_replaces_a_file_whole_or_not_at_all(plan1, tmp_path):
    path = tmp_path / "m.csv"
    path.write_text("old")
    with pytest.raises(ValueError, match="rate"):
        plan1.to_csv(path, rate=-1)
    assert path.read_text() == "old"
    plan1.to_csv(path, rate=10)
    text = path.read_text()
    assert text.startswith("t,l1,") and text.count("\n") == 12 and "\r" not in text
