"""A sweep killed and resumed at full size: ``nonholo sweep`` of 300 car problems on two
local workers, killed with SIGKILL three times at random moments and started again, then
run to the end; and a second sweep started on the same output while the first runs.

Passes when the resumed sweep ends with exit status 0 and 300 rows, each problem once and
equal to an uninterrupted in-process run's (:func:`nonholo.batch.result_store.comparable`: every
column but the wall times), no process of a killed sweep remains (checked 5 s after each
kill, by the output's path in ``/proc/*/cmdline``), and the second start is refused with
exit status 2 while the first goes on to finish. Run as::

    python -m benchmarks.sweep_faults [--problems 300] [--seed 31]

Writes ``benchmarks/results/sweep_faults.md``; exit status 1 if any check fails.
"""
from __future__ import annotations

import argparse
import contextlib
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from nonholo.batch import result_store, sweep
from nonholo.io import problems

from .report import Report


def car_rows(count: int, seed: int = 3) -> list[dict]:
    """``count`` car problems from rest at the origin to random nearby poses."""
    rng = np.random.default_rng(seed)
    return [{"start": [0.0, 0.0, 0.0, 0.0],
             "goal": [float(rng.uniform(-1, 1)), float(rng.uniform(-1, 1)), float(rng.uniform(-0.5, 0.5)), 0.0],
             "mechanism": "car", "label": f"car-{i}"} for i in range(count)]


def processes_naming(text: str) -> list[int]:
    """The pids of other processes whose command line holds ``text``."""
    found = []
    for d in os.listdir("/proc"):
        if d.isdigit() and int(d) != os.getpid():
            with contextlib.suppress(OSError), open(f"/proc/{d}/cmdline", "rb") as f:
                if text.encode() in f.read():
                    found.append(int(d))
    return found


def parts_count(out: Path) -> int:
    """The parts a sweep on ``out`` has written so far."""
    folder = result_store.parts_dir(out)
    return len(list(folder.glob("part-*.parquet"))) if folder.exists() else 0


def survivors(text: str, within: float = 5.0) -> list[int]:
    """The processes naming ``text`` still alive after ``within`` seconds (then killed)."""
    deadline = time.monotonic() + within
    while processes_naming(text) and time.monotonic() < deadline:
        time.sleep(0.05)
    left = processes_naming(text)
    for pid in left:
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)
    return left


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--problems", type=int, default=300)
    p.add_argument("--seed", type=int, default=31)
    args = p.parse_args(argv)
    report = Report("sweep_faults.md", "A sweep killed three times and resumed", "benchmarks.sweep_faults", argv)
    rows = car_rows(args.problems)
    rng = random.Random(args.seed)
    checks = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        path = problems.write(tmp / "problems.jsonl", rows)
        started = time.perf_counter()
        reference = sweep.sweep(rows, tmp / "reference.parquet", workers=1, progress=False)
        reference_seconds = time.perf_counter() - started
        out = tmp / "results.parquet"
        cmd = [sys.executable, "-m", "nonholo.cli", "sweep", str(path), "--out", str(out), "--quiet",
               "--workers", "2"]
        kills = []
        for round_ in range(3):
            proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
            t0 = time.perf_counter()
            if round_ == 0:                                  # during the start
                time.sleep(rng.uniform(0.2, 2.0))
            else:                                            # after a few more finished batches
                target = parts_count(out) + rng.randint(1, 5)
                deadline = time.monotonic() + 600
                while proc.poll() is None and parts_count(out) < target and time.monotonic() < deadline:
                    time.sleep(0.01)
                time.sleep(rng.uniform(0.0, 0.5))
            wait = time.perf_counter() - t0
            parts = parts_count(out)
            killed = proc.poll() is None
            if killed:
                proc.send_signal(signal.SIGKILL)
            proc.wait()
            left = survivors(str(out))
            kills.append([round_ + 1, f"{wait:.1f}", "yes" if killed else "no (it had finished)", parts, len(left)])
            checks.append((f"no process of killed sweep {round_ + 1} remains", not left))
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=3600, check=False)
        checks.append(("the resumed sweep exits 0", done.returncode == 0))
        table = result_store.load(out) if out.exists() else None
        index = [] if table is None else table.column("index").to_pylist()
        checks.append((f"{args.problems} rows, each problem once", index == list(range(args.problems))))
        checks.append(("rows equal to the uninterrupted run's",
                       table is not None and result_store.comparable(table) == result_store.comparable(reference)))
        checks.append(("no process left after the resumed sweep", not survivors(str(out))))

        # a second start on an output a sweep is writing
        second_out = tmp / "second.parquet"
        cmd2 = [*cmd[:6], str(second_out), *cmd[7:]]
        first = subprocess.Popen(cmd2, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 120
        while first.poll() is None and not result_store.lock_path(second_out).exists() and time.monotonic() < deadline:
            time.sleep(0.01)
        second = subprocess.run(cmd2, capture_output=True, text=True, timeout=600, check=False)
        first.wait(timeout=3600)
        message = second.stderr.strip().splitlines()[-1] if second.stderr.strip() else ""
        checks.append(("a second start on the same output exits 2", second.returncode == 2))
        checks.append(("the first sweep finishes (exit 0)", first.returncode == 0))
        second_table = result_store.load(second_out) if second_out.exists() else None
        checks.append(("its rows equal the uninterrupted run's", second_table is not None
                       and result_store.comparable(second_table) == result_store.comparable(reference)))
    report.paragraph(
        f"{args.problems} car problems (from rest at the origin to random poses within 1 wheelbase), "
        f"`nonholo sweep --workers 2`; the uninterrupted reference in this process took "
        f"{reference_seconds:.1f} s. The first kill comes 0.2–2 s after the start, the "
        f"others 0–0.5 s after 1–5 more batches are written; a killed sweep's processes are "
        f"looked for 5 s later.")
    report.table(["kill", "after s", "killed", "parts written", "processes left"], kills)
    report.table(["check", "holds"], [[c, "yes" if ok else "**no**"] for c, ok in checks], align=["l", "l"])
    report.paragraph(f"The second start said: `{message}`")
    report.write()
    return 0 if all(ok for _, ok in checks) else 1


if __name__ == "__main__":
    sys.exit(main())
