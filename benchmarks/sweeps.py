"""The benchmarks' calls of :func:`nonholo.plan`, made through :func:`nonholo.batch.sweep.sweep`.

:func:`plan_all` turns a list of goals into a problem table and sweeps it in this process,
one problem after another (``workers=1``: each plan timed alone, as a plain loop times
it; the sweep's ``seconds`` is the wall time of the ``plan`` call). The results of a
clean checkout are kept in ``benchmarks/results/runs/<commit>/<name>.parquet`` (not
committed), so a benchmark interrupted half-way resumes its plans where it stopped; with
uncommitted changes they go to a temporary directory and are not resumed (the code that
made them is not the code that would finish them).
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from nonholo.batch.result_store import plan_of
from nonholo.batch.sweep import sweep

from .report import RESULTS_DIR, git_revision

#: Where the plans of a clean checkout's benchmark runs are kept, by commit.
RUNS_DIR = RESULTS_DIR / "runs"


def runs_dir() -> Path:
    """``RUNS_DIR/<commit>`` for a clean checkout, else a new temporary directory."""
    rev = git_revision()
    if rev is None or " " in rev:
        return Path(tempfile.mkdtemp(prefix="nonholo-bench-"))
    return RUNS_DIR / rev


def problems_of(goals: list[dict], options: dict | None = None, mechanism: str = "platform") -> list[dict]:
    """One problem per goal (``R0``, ``Rd``, ``T``, ``id``; ``mechanism`` if a goal has one)."""
    return [{"start": g["R0"], "goal": g["Rd"], "mechanism": g.get("mechanism", mechanism),
             "options": {"T": g["T"], **(options or {})}, "label": g["id"]} for g in goals]


def plan_all(name: str, goals: list[dict], options: dict | None = None, mechanism: str = "platform",
             directory: Path | None = None):
    """``[(seconds, PlanResult)]``: ``plan(R0, Rd, T=T, mechanism=..., **arguments_of(options))``
    for every goal, in order, through a sweep named ``name`` (see the module); ``options`` are
    flat, as a problem table holds them (``"delta_min"``, ``"harmonics"``, ...:
    :func:`nonholo.planning.settings.arguments_of` makes them constraints and settings). A plan
    that raised raises ``RuntimeError`` with its error."""
    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in name)
    out = (directory or runs_dir()) / f"{safe}.parquet"
    out.parent.mkdir(parents=True, exist_ok=True)
    # the benchmarks' own tables may name their strategies by import path
    table = sweep(problems_of(goals, options, mechanism), out, workers=1, progress=sys.stderr.isatty(),
                  allow_imports=True)
    planned = []
    for row in table.to_pylist():
        if row["error"] is not None:
            raise RuntimeError(f"{name}: problem {row['index']} ({row['label']}) raised {row['error']}")
        planned.append((row["seconds"], plan_of(row)))
    return planned
