"""What a sweep refuses before anything runs (nonholo/batch/sweep.py, nonholo/io/problems.py,
``nonholo sweep``): options :func:`nonholo.plan` would refuse (its own checks, naming the row
and the option), a strategy named by import path without the caller's opt-in (nothing
imported), and bad arguments (``ValueError``/``TypeError`` naming them)."""
import json
import os
import subprocess
import sys

import pytest

from nonholo.batch import result_store, sweep
from nonholo.io import problems

CAR = {"start": [0.0, 0.0, 0.0, 0.0], "goal": [0.4, 0.2, 0.1, 0.0], "mechanism": "car"}


def table(tmp_path, bad_options):
    rows = [CAR, {**CAR, "options": {"T": 2.0}}, {**CAR, "options": bad_options}, CAR]
    path = tmp_path / "p.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in rows))
    return rows, path


def nothing_left(out):
    return not out.exists() and not result_store.parts_dir(out).exists() and not result_store.lock_path(out).exists()


@pytest.mark.parametrize("options, column, match", [
    ({"T": -1}, "options.T", "T must be a positive finite time"),
    ({"harmonics": 0}, "options.harmonics", "harmonics must be an integer >= 1, got 0"),
    ({"method": "xyz"}, "options.method", "unknown method 'xyz'"),
    ({"T": None, "leg_speed": 0.5}, "options.leg_speed", "mechanism 'car' has no legs"),
    ({"tol": 0}, "options.tol", "tol must be a positive number"),
    ({"steps": 3, "harmonics": 2}, "options.harmonics", "more than the integrator's steps = 3"),
    ({"route": "sideways"}, "options.route", "unknown route"),
    ({"leg_length": [0.5, 2.0]}, "options.leg_length", "leg_length"),
    ({"strategy": "fastest"}, "options.strategy", "unknown strategy 'fastest'"),
])
def test_impossible_options_are_refused_naming_row_and_option_before_anything_runs(
        tmp_path, monkeypatch, capsys, options, column, match):
    from nonholo.cli.entry import main

    rows, path = table(tmp_path, options)
    out = tmp_path / "r.parquet"
    monkeypatch.setattr(sweep, "solve_batch", lambda batch: pytest.fail("a problem ran"))
    want = f"problem row 2, column '{column}': "
    with pytest.raises(ValueError, match=f"^{want}.*{match}"):
        sweep.sweep(rows, out, workers=1, progress=False)
    assert nothing_left(out)
    # the same with plan() itself: the message is plan()'s own
    from nonholo.planning.api import plan
    from nonholo.planning.settings import arguments_of

    with pytest.raises(ValueError, match=match):
        plan(CAR["start"], CAR["goal"], mechanism="car", **arguments_of(options, "car"))
    assert main(["sweep", str(path), "--out", str(out), "--workers", "1", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert want in err and nothing_left(out)


def test_a_strategy_by_import_path_imports_nothing_without_the_opt_in(tmp_path, monkeypatch):
    """``evil.py`` beside the table writes a marker when imported: without the opt-in the
    sweep (in Python and on the command line, from the table's folder) refuses naming the
    row, and the marker never appears; with it, the module is imported."""
    marker = tmp_path / "imported"
    (tmp_path / "evil.py").write_text(f"open({str(marker)!r}, 'w').write('ran')\n")
    rows, path = table(tmp_path, {"strategy": "evil:Evil"})
    out = tmp_path / "r.parquet"
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "evil", raising=False)
    want = "problem row 2, column 'options.strategy': names a strategy by its import path 'evil:Evil'"
    for source in (rows, path):
        with pytest.raises(ValueError, match=want):
            sweep.sweep(source, out, workers=1, progress=False)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")])}
    run = subprocess.run([sys.executable, "-m", "nonholo.cli", "sweep", str(path), "--out", str(out), "--quiet"],
                         capture_output=True, text=True, cwd=tmp_path, env=env)
    assert run.returncode == 2 and want in run.stderr and "--allow-imports" in run.stderr
    assert not marker.exists() and "evil" not in sys.modules and nothing_left(out)
    # opted in: imported (and refused, evil.py having no Strategy), still before anything is planned
    monkeypatch.setattr(sweep, "solve_batch", lambda batch: pytest.fail("a problem ran"))
    with pytest.raises(ValueError, match="row 2, column 'options.strategy': strategy 'evil:Evil' cannot be imported"):
        sweep.sweep(rows, out, workers=1, progress=False, allow_imports=True)
    assert marker.read_text() == "ran"


def test_bad_arguments_are_named(tmp_path):
    rows = [CAR]
    (tmp_path / "results").mkdir()
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    cases = [
        ((None, tmp_path / "r.parquet"), {}, TypeError, "^problems must be"),
        ((5, tmp_path / "r.parquet"), {}, TypeError, "^problems must be"),
        (({"start": 1}, tmp_path / "r.parquet"), {}, TypeError, "^problems must be"),
        ((rows, tmp_path / "results"), {}, ValueError, "^out must be the results file's path, got the directory"),
        ((rows, f"{tmp_path}/new/"), {}, ValueError, "^out must be the results file's path, got the directory"),
        ((rows, fifo), {}, ValueError, "^out .* is not a regular file"),
        ((rows, 5), {}, TypeError, "^out must be"),
        ((rows, tmp_path / "r.parquet"), {"client": "tcp://x"}, TypeError,
         "^client must be a distributed.Client .*scheduler="),
        ((rows, tmp_path / "r.parquet"), {"scheduler": 8786}, TypeError, "^scheduler must be"),
        ((rows, tmp_path / "r.parquet"), {"workers": 0}, ValueError, "^workers must be"),
        ((rows, tmp_path / "r.parquet"), {"batch": 1.5}, ValueError, "^batch must be"),
        ((rows, tmp_path / "r.parquet"), {"allow_imports": "yes"}, TypeError, "^allow_imports must be"),
    ]
    for args, kwargs, kind, match in cases:
        with pytest.raises(kind, match=match):
            sweep.sweep(*args, progress=False, **kwargs)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fifo", "results"]
    assert list((tmp_path / "results").iterdir()) == []


def test_the_command_line_names_a_directory_given_as_out(tmp_path, capsys):
    from nonholo.cli.entry import main

    path = problems.write(tmp_path / "p.jsonl", [CAR])
    assert main(["sweep", str(path), "--out", str(tmp_path), "--quiet"]) == 2
    assert "error: out must be the results file's path, got the directory" in capsys.readouterr().err
