"""Sweeps under faults (nonholo/batch/sweep.py, nonholo/batch/result_store.py, ``nonholo sweep``):
killed with SIGKILL at random moments and resumed, two started on one output, parts of a
crashed run damaged or repeated, a kill between writing the results and removing the parts,
a flipped byte in the results: each ends with every row exactly once, equal to an
uninterrupted run's, or with a clear refusal; no worker outlives its sweep.

The problems are the car's (they plan in a fraction of a second each)."""
import fcntl
import json
import os
import random
import signal
import subprocess
import sys
import time
import warnings

import numpy as np
import pytest

from benchmarks.sweep_faults import processes_naming
from benchmarks.sweep_faults import survivors as gone
from nonholo.batch import result_store, sweep
from nonholo.io import problems

pytestmark = pytest.mark.slow

N = 24


def car_rows(count=N, seed=3):
    rng = np.random.default_rng(seed)
    return [{"start": [0.0, 0.0, 0.0, 0.0],
             "goal": [float(rng.uniform(-1, 1)), float(rng.uniform(-1, 1)), float(rng.uniform(-0.5, 0.5)), 0.0],
             "mechanism": "car", "label": f"car-{i}"} for i in range(count)]


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The rows, and an uninterrupted sweep of them in this process."""
    rows = car_rows()
    out = tmp_path_factory.mktemp("reference") / "reference.parquet"
    return rows, sweep.sweep(rows, out, workers=1, progress=False)


def command(path, out, *flags):
    return [sys.executable, "-m", "nonholo.cli", "sweep", str(path), "--out", str(out), "--quiet", *flags]


def assert_complete(out, reference_table):
    table = result_store.load(out)
    index = table.column("index").to_pylist()
    assert index == list(range(reference_table.num_rows))           # every row once, in order
    assert result_store.comparable(table) == result_store.comparable(reference_table)
    assert not result_store.parts_dir(out).exists() and not result_store.lock_path(out).exists()
    assert sorted(p.name for p in out.parent.iterdir() if p.name.startswith(out.name)
                  or p.name.startswith("." + out.name)) == [out.name]   # nothing left beside it
    return table


def parts_of(out):
    return sorted(result_store.parts_dir(out).glob("part-*.parquet"))


def test_killed_at_random_moments_then_resumed(reference, tmp_path):
    """SIGKILL of the parent (two local workers) three times at random moments — during the
    start, and after a random number of finished batches — then a run to the end: exit 0,
    every row once and equal to the uninterrupted run's; after each kill no worker remains
    and the dead sweep's lock blocks nothing."""
    rows, table = reference
    path = problems.write(tmp_path / "p.jsonl", rows)
    out = tmp_path / "r.parquet"
    cmd = command(path, out, "--workers", "2", "--batch", "2")
    rng = random.Random(31)
    kills = 0
    for moment in ("start", "batches", "batches"):
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        if moment == "start":
            time.sleep(rng.uniform(0.2, 2.0))
        else:
            target = len(parts_of(out)) + rng.randint(1, 3)
            deadline = time.monotonic() + 300
            while proc.poll() is None and len(parts_of(out)) < target and time.monotonic() < deadline:
                time.sleep(0.01)
            time.sleep(rng.uniform(0.0, 0.5))
        if proc.poll() is None:
            proc.send_signal(signal.SIGKILL)
            kills += 1
        proc.wait()
        assert gone(str(out)) == [], "a worker outlived its killed sweep"
        assert not out.exists() or proc.returncode == 0
    assert kills >= 2
    assert result_store.lock_path(out).exists()                 # a killed sweep's lock file, stale
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert f"{N} problems" in done.stdout
    assert_complete(out, table)
    assert gone(str(out)) == []


def test_a_second_sweep_on_one_output_is_refused_while_the_first_runs(reference, tmp_path, capsys):
    """The second start (here, in this process: it is up at once) refuses with exit status 2
    naming the output and the first sweep's process; the first goes on to the end."""
    from nonholo.cli.entry import main

    rows, table = reference
    path = problems.write(tmp_path / "p.jsonl", rows)
    out = tmp_path / "r.parquet"
    first = subprocess.Popen(command(path, out, "--workers", "1", "--batch", "1"),
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 300
    while first.poll() is None and not parts_of(out) and time.monotonic() < deadline:
        time.sleep(0.01)
    assert first.poll() is None, first.stderr.read()
    started = time.monotonic()
    assert main(["sweep", str(path), "--out", str(out), "--workers", "1", "--quiet"]) == 2
    assert time.monotonic() - started < 5                 # refused at once
    assert f"another sweep (process {first.pid}) is writing {out}" in capsys.readouterr().err
    assert first.poll() is None
    stdout, stderr = first.communicate(timeout=600)
    assert first.returncode == 0, stderr
    assert_complete(out, table)


def test_a_held_lock_refuses_at_once_and_a_released_one_does_not_block(reference, tmp_path, monkeypatch):
    rows, table = reference
    out = tmp_path / "r.parquet"
    monkeypatch.setattr(sweep, "solve_batch", lambda batch: pytest.fail("a problem ran"))
    fd = os.open(result_store.lock_path(out), os.O_RDWR | os.O_CREAT)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        started = time.monotonic()
        with pytest.raises(result_store.SweepBusy, match=f"is writing {out}"):
            sweep.sweep(rows, out, workers=1, progress=False)
        assert time.monotonic() - started < 5
        assert not result_store.parts_dir(out).exists()
    finally:
        os.close(fd)                                     # as a process's death releases it
    monkeypatch.undo()
    sweep.sweep(rows[:2], out, workers=1, progress=False)
    assert result_store.comparable(result_store.load(out)) == result_store.comparable(table)[:2]


def crashed_parts(out, rows):
    """A parts directory as a crashed run leaves it (see the module), empty."""
    parts = result_store.parts_dir(out)
    parts.mkdir()
    fingerprint = problems.fingerprint(problems.check(rows))
    (parts / "sweep.json").write_text(json.dumps({"fingerprint": fingerprint, "problems": len(rows)}))
    return parts


def flip(path, position):
    data = bytearray(path.read_bytes())
    data[position] ^= 0x10
    path.write_bytes(bytes(data))


def test_parts_of_a_crashed_run_are_reconciled(reference, tmp_path, monkeypatch):
    """Parts as killed and concurrent runs leave them: a batch finished twice (its rows'
    times differ), batches overlapping, a part with a flipped byte, a torn part, a part of
    rows of other problems, an old-style name, temporary files. The resume plans exactly
    the problems no sound part holds, and every row ends once, equal to the reference."""
    rows, table = reference
    done = table.to_pylist()
    out = tmp_path / "r.parquet"
    parts = crashed_parts(out, rows)

    def write(indices, seconds=None):
        chosen = [dict(done[i]) for i in indices]
        if seconds is not None:
            for r in chosen:
                r["seconds"] = seconds
        return result_store.write_part(chosen, parts)

    write([0, 1])
    write([0, 1], seconds=123.0)              # the same batch, finished by a killed run and by the next
    write([1, 2, 3])                          # an overlap
    flip(write([4, 5]), 200)                  # a flipped byte: 4 and 5 planned again
    torn = write([6, 7])
    torn.write_bytes(torn.read_bytes()[:300])                   # torn: planned again
    other = dict(done[8], problem=json.dumps({"start": [1, 2, 3, 4]}))
    result_store.write_part([other], parts)          # sound bytes, another problem's row: 8 planned again
    write([9])
    old = write([10])
    old.rename(parts / "part-000000010-a1b2c3.parquet")       # an older version's name, unchecked: again
    write([11, 12])
    (parts / ".part-0123456789ab.tmp").write_bytes(b"half a part")
    (tmp_path / f".{out.name}.0123abcd.tmp").write_bytes(b"half a results file")
    planned = []
    real = sweep.solve_batch

    def counting(batch):
        planned.extend(i for i, _ in batch)
        return real(batch)

    monkeypatch.setattr(sweep, "solve_batch", counting)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got = sweep.sweep(rows, out, workers=1, progress=False)
    discarded = [str(w.message) for w in caught if "discarded the part" in str(w.message)]
    assert len(discarded) == 4, discarded
    assert sorted(planned) == [4, 5, 6, 7, 8, 10] + list(range(13, N))
    assert got.column("index").to_pylist() == list(range(N))
    assert got.column("seconds").to_pylist()[0] in (done[0]["seconds"], 123.0)   # a duplicate kept once
    assert_complete(out, table)


def test_a_kill_between_writing_the_results_and_removing_the_parts_is_recovered(reference, tmp_path,
                                                                                monkeypatch):
    rows, table = reference
    out = tmp_path / "r.parquet"
    finished = sweep.sweep(rows, out, workers=1, progress=False)
    monkeypatch.setattr(sweep, "solve_batch", lambda batch: pytest.fail("a finished sweep ran again"))
    # the parts still there, in full
    parts = crashed_parts(out, rows)
    result_store.write_part(table.to_pylist()[:5], parts)
    assert sweep.sweep(rows, out, workers=1, progress=False).equals(finished)
    assert not parts.exists()
    # half removed (no sweep.json left), and a removal renamed aside but not done
    parts.mkdir()
    result_store.write_part(table.to_pylist()[5:9], parts)
    trash = tmp_path / f".{parts.name}.89abcdef.trash"
    trash.mkdir()
    (trash / "sweep.json").write_text("{}")
    assert sweep.sweep(rows, out, workers=1, progress=False).equals(finished)
    assert_complete(out, table)
    # the parts of other problems are not this sweep's to remove
    parts.mkdir()
    (parts / "sweep.json").write_text(json.dumps({"fingerprint": "0" * 64, "problems": 2}))
    assert sweep.sweep(rows, out, workers=1, progress=False).equals(finished)
    assert (parts / "sweep.json").exists()


def test_a_results_file_with_a_flipped_byte_is_not_returned_as_it_is(reference, tmp_path, monkeypatch):
    """Single-byte flips all over a finished results file: the sweep that finds it (and
    :func:`load`) refuses it naming the file, or — where the flip leaves every row as it
    was (padding, a name pyarrow does not read) — returns the rows as written; ``nonholo
    sweep`` exits 2. With the run's parts still there, the damaged file is written again."""
    rows, table = reference
    rows, expected = rows[:6], table.slice(0, 6)
    out = tmp_path / "r.parquet"
    sweep.sweep(rows, out, workers=1, progress=False)
    good = out.read_bytes()
    want = result_store.comparable(expected)
    monkeypatch.setattr(sweep, "solve_batch", lambda batch: pytest.fail("a damaged file was planned again"))
    rng = random.Random(5)
    positions = sorted(rng.sample(range(len(good)), 60))
    refused = 0
    for position in positions:
        out.write_bytes(good)
        flip(out, position)
        for read in (lambda: sweep.sweep(rows, out, workers=1, progress=False), lambda: result_store.load(out)):
            try:
                got = read()
            except ValueError as exc:
                assert str(out) in str(exc), exc
                refused += 1
            else:
                assert result_store.comparable(got) == want, position
    assert refused >= 0.8 * 2 * len(positions), refused
    # the command line: exit 2, naming the file
    out.write_bytes(good)
    flip(out, len(good) // 2)
    path = problems.write(tmp_path / "p.jsonl", rows)
    run = subprocess.run(command(path, out, "--workers", "1"), capture_output=True, text=True)
    assert run.returncode == 2 and f"{out}" in run.stderr and "damaged" in run.stderr
    # the parts of the run that wrote it are still there: written again from them
    parts = crashed_parts(out, rows)
    result_store.write_part(expected.to_pylist(), parts)
    assert result_store.comparable(sweep.sweep(rows, out, workers=1, progress=False)) == want
    assert result_store.comparable(result_store.load(out)) == want and not parts.exists()


def test_worker_processes_die_with_their_parent(tmp_path):
    """A parent that dies without a word (SIGKILL) takes its local workers with it, even in
    the middle of a batch."""
    rows = [{**r, "options": {"steps": 20000, "harmonics": 6}} for r in car_rows(8, seed=9)]
    path = problems.write(tmp_path / "p.jsonl", rows)
    out = tmp_path / "r.parquet"
    proc = subprocess.Popen(command(path, out, "--workers", "2", "--batch", "1"),
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 300
    while len(processes_naming(str(out))) < 3 and time.monotonic() < deadline:   # the parent and two workers
        assert proc.poll() is None
        time.sleep(0.02)
    workers = [p for p in processes_naming(str(out)) if p != proc.pid]
    assert len(workers) >= 2
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert gone(str(out)) == []
    kept = len(parts_of(out))
    time.sleep(1.0)
    assert len(parts_of(out)) == kept                     # nobody writes on
