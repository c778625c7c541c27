"""``sweep()``: :func:`nonholo.plan` over a table of problems, in parallel, resumable.

The problems (:mod:`nonholo.io.problems`: a JSON Lines file or a list of dicts) are checked
first, all of them; then they are planned in batches — in this process (``workers=1``), on
local worker processes (``workers=N``, default: one per core), or on a Dask distributed
cluster (``client=`` a ``distributed.Client``, or ``scheduler=`` its address) — and every
finished batch is written at once, so nothing computed is lost. A table may mix
mechanisms and kinds of state (SO(3), ``Rᵏ``, ``SO(3) × Rᵏ``): each row is planned with
its own mechanism.

Results: a Parquet file (pyarrow), one row per problem, sorted by ``index`` (the problem's
row, from 0), with :data:`SCHEMA`'s columns: the problem's ``label`` and ``mechanism``,
the plan's ``strategy``, ``method``, ``route``, ``T``, ``success``, ``terminal_error``,
``min_delta``, ``iterations``, ``reason``, the wall time ``seconds`` of the call, the
``problem`` (its start and goal in the JSON form of its mechanism's space, so a row of an
SO(3) mechanism holds 3×3 nested lists) and the ``plan`` itself as JSON
(:meth:`nonholo.io.result.PlanResult.to_dict`, with the coordinates beyond SO(3); reload
with :func:`plan_of`), and ``error``: the exception a problem raised (then the
plan is null; a problem that raises is recorded, not fatal).

While it runs, each batch is a Parquet file of its own in ``RESULTS.parts/`` — written by
the local worker that planned it, or by this process for a Dask cluster's (whose workers
may not share its disk); in full, then renamed into place: a killed sweep leaves complete
parts only — beside
``sweep.json``, the problem table's fingerprint. Started again with the same problems and
``out``, a sweep runs only the problems no part holds; at the end the parts become
``RESULTS`` (written atomically, the fingerprint in its metadata) and are removed. A
finished ``RESULTS`` of the same problems is returned as it is.
"""
from __future__ import annotations

import json
import math
import multiprocessing
import os
import secrets
import shutil
import time
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures import as_completed as local_completed
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from ..io import problems as problem_table
from ..io.result import PlanResult

#: The results' columns.
SCHEMA = pa.schema([
    ("index", pa.int64()), ("label", pa.string()), ("mechanism", pa.string()), ("strategy", pa.string()),
    ("method", pa.string()), ("route", pa.string()), ("T", pa.float64()), ("success", pa.bool_()),
    ("terminal_error", pa.float64()), ("min_delta", pa.float64()), ("iterations", pa.int64()),
    ("seconds", pa.float64()), ("reason", pa.string()), ("error", pa.string()),
    ("problem", pa.string()), ("plan", pa.string()),
])
#: Columns that differ between two runs of the same sweep (wall times); :func:`comparable`
#: leaves them out.
TIMING = ("seconds",)
#: The metadata key of a finished results file: the problems' fingerprint.
FINGERPRINT_KEY = b"nonholo.batch.sweep.fingerprint"
#: Problems per batch at most (small batches keep every worker busy to the end).
MAX_BATCH = 8


def solve(index: int, row: dict) -> dict:
    """Plan one problem (a JSON row of :mod:`nonholo.io.problems`, any mechanism) with its
    mechanism: its results row. An exception is recorded in ``error``."""
    from ..planning.api import plan

    problem = problem_table.check_row(row, index)
    out = {"index": index, "label": problem["label"], "mechanism": problem["mechanism"],
           "problem": json.dumps(row, separators=(",", ":"), sort_keys=True)}
    started = time.perf_counter()
    try:
        res = plan(problem["start"], problem["goal"], mechanism=problem["mechanism"], **problem["options"])
    except Exception as exc:                              # recorded, not fatal to the sweep
        return {**out, "strategy": None, "method": None, "route": None, "T": None, "success": False,
                "terminal_error": None, "min_delta": None, "iterations": 0,
                "seconds": time.perf_counter() - started, "reason": "", "error": f"{type(exc).__name__}: {exc}",
                "plan": None}
    seconds = time.perf_counter() - started
    return {**out, "strategy": res.strategy, "method": res.method, "route": res.route, "T": res.T,
            "success": bool(res.success), "terminal_error": res.terminal_error, "min_delta": res.min_delta,
            "iterations": int(res.iterations), "seconds": seconds, "reason": res.reason, "error": None,
            "plan": json.dumps(res.to_dict(), allow_nan=False)}


def solve_batch(batch: list[tuple[int, dict]]) -> list[dict]:
    """:func:`solve` on every ``(index, row)`` of ``batch`` (the unit of work of a worker),
    with the BLAS libraries held to one thread: the workers are the parallelism (a planner's
    small matrices gain nothing from BLAS threads, which only take cores from the other
    workers)."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        return [solve(i, row) for i, row in batch]


def solve_and_keep(batch: list[tuple[int, dict]], parts: str) -> list[int]:
    """:func:`solve_batch`, its rows written as a part in the directory ``parts`` by the
    worker itself (the parent then handles no plan); returns the indices done."""
    rows = solve_batch(batch)
    write_part(rows, Path(parts))
    return [r["index"] for r in rows]


def plan_of(row) -> PlanResult | None:
    """The :class:`~nonholo.io.result.PlanResult` of a results row (a dict, or the ``plan``
    JSON text), checked like a plan file; ``None`` for a problem that raised."""
    text = row["plan"] if isinstance(row, dict) else row
    return None if text is None else PlanResult.from_dict(json.loads(text))


# -- the results on disk ---------------------------------------------------------------------
def parts_dir(out: Path) -> Path:
    """Where a running sweep keeps its finished batches."""
    return out.with_name(out.name + ".parts")


def _write_table(table: pa.Table, path: Path) -> None:
    """``table`` to ``path`` as Parquet, atomically (a temporary file renamed)."""
    tmp = path.with_name(f".{path.name}.{secrets.token_hex(4)}.tmp")
    try:
        pq.write_table(table, tmp)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def _table(rows: list[dict], metadata: dict | None = None) -> pa.Table:
    schema = SCHEMA.with_metadata(metadata) if metadata else SCHEMA
    return pa.Table.from_pylist(rows, schema=schema)


def write_part(rows: list[dict], parts: Path) -> Path:
    """``rows`` as one part of a running sweep (atomically, named by its first index)."""
    path = parts / f"part-{rows[0]['index']:09d}-{secrets.token_hex(3)}.parquet"
    _write_table(_table(rows), path)
    return path


def _read_parts(parts: Path) -> list[pa.Table]:
    return [pq.read_table(p, schema=SCHEMA) for p in sorted(parts.glob("part-*.parquet"))]


def _fingerprint_of(path: Path) -> str | None:
    meta = pq.read_schema(path).metadata or {}
    value = meta.get(FINGERPRINT_KEY)
    return None if value is None else value.decode()


def _open_parts(out: Path, fingerprint: str, n: int) -> tuple[Path, list[pa.Table]]:
    """The parts directory of ``out`` (created, or checked to belong to the same problems)
    and the tables it already holds."""
    parts = parts_dir(out)
    manifest = parts / "sweep.json"
    if parts.exists():
        try:
            mine = json.loads(manifest.read_text())["fingerprint"]
        except (OSError, ValueError, KeyError):
            mine = None
        if mine != fingerprint:
            raise ValueError(f"{parts} holds a sweep of other problems (or is not a sweep's): "
                             "remove it, or choose another results path")
    else:
        parts.mkdir(parents=True)
        manifest.write_text(json.dumps({"fingerprint": fingerprint, "problems": n}))
    return parts, _read_parts(parts)


def _finish(out: Path, parts: Path, fingerprint: str, n: int) -> pa.Table:
    """All parts as one results file, sorted by index; the parts removed."""
    tables = _read_parts(parts)
    table = pa.concat_tables(tables) if tables else _table([])
    index = table.column("index").to_pylist()
    if sorted(index) != list(range(n)):
        missing = sorted(set(range(n)) - set(index))
        raise RuntimeError(f"the sweep's parts do not hold every problem once (missing {missing[:5]}, "
                           f"{len(index) - len(set(index))} duplicated)")
    table = table.sort_by("index").replace_schema_metadata({FINGERPRINT_KEY: fingerprint.encode()})
    _write_table(table, out)
    shutil.rmtree(parts)
    return table


# -- running -----------------------------------------------------------------------------------
def batches(todo: list[int], rows: list[dict], workers: int, size: int | None = None) -> list[list[tuple[int, dict]]]:
    """``todo`` cut into batches of ``size`` problems (default: at most :data:`MAX_BATCH`,
    small enough that every worker gets several)."""
    if size is None:
        size = max(1, min(MAX_BATCH, math.ceil(len(todo) / (4 * max(1, workers)))))
    return [[(i, rows[i]) for i in todo[k:k + size]] for k in range(0, len(todo), size)]


def sweep(problems, out, *, workers: int | None = None, client=None, scheduler: str | None = None,
          progress: bool = True, batch: int | None = None) -> pa.Table:
    """Plan every problem of ``problems`` (a JSON Lines path or a list of dicts, see
    :mod:`nonholo.io.problems`) and write the results to the Parquet file ``out`` (see the
    module); returns them as a ``pyarrow.Table``.

    ``workers``: local processes (default ``os.cpu_count()``; ``1``: in this process);
    ``client`` / ``scheduler``: run on a Dask distributed cluster instead (a
    ``distributed.Client``, or the scheduler's address, e.g. ``"tcp://127.0.0.1:8786"``);
    ``progress``: a progress bar on standard error; ``batch``: problems per unit of work
    (each written as it finishes; default: chosen from the number of problems and workers,
    at most :data:`MAX_BATCH`). Bad problems raise ``ValueError``
    (naming the row and column) before anything runs.
    """
    if isinstance(problems, (str, os.PathLike)):
        checked = problem_table.read(problems)
    else:
        checked = problem_table.check(problems)
    rows = [problem_table.as_json(p) for p in checked]
    n = len(rows)
    fingerprint = problem_table.fingerprint(checked)
    out = Path(out)
    if workers is not None and (not isinstance(workers, int) or isinstance(workers, bool) or workers < 1):
        raise ValueError(f"workers must be a positive integer, got {workers!r}")
    if batch is not None and (not isinstance(batch, int) or isinstance(batch, bool) or batch < 1):
        raise ValueError(f"batch must be a positive integer, got {batch!r}")
    if client is not None and scheduler is not None:
        raise ValueError("give a Dask client or a scheduler address, not both")
    if out.exists():
        if _fingerprint_of(out) == fingerprint and not parts_dir(out).exists():
            return pq.read_table(out, schema=SCHEMA)
        if not parts_dir(out).exists():
            raise ValueError(f"{out} exists and holds other results: remove it, or choose another path")
    parts, tables = _open_parts(out, fingerprint, n)
    done = {i for t in tables for i in t.column("index").to_pylist()}
    del tables
    todo = [i for i in range(n) if i not in done]
    bar = _progress_bar(n, len(done), progress)

    def keep(rows_done: list[dict]) -> None:
        write_part(rows_done, parts)
        bar.update(len(rows_done))

    try:
        if todo and (client is not None or scheduler is not None):
            _run_dask(todo, rows, keep, client, scheduler, batch)
        elif todo:
            workers = (os.cpu_count() or 1) if workers is None else workers
            _run_local(batches(todo, rows, workers, batch), parts, bar.update, workers)
    finally:
        bar.close()
    return _finish(out, parts, fingerprint, n)


def _progress_bar(total: int, initial: int, show: bool):
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, unit="plan", disable=not show, smoothing=0.1)


def _run_local(work: list, parts: Path, done, workers: int) -> None:
    """The batches in this process (``workers=1``) or on local worker processes, each
    written as a part by whoever planned it (:func:`solve_and_keep`; ``done(count)`` after
    each); the first batch always here, so that the workers — forked where the platform
    allows — start with the kernels compiled."""
    done(len(solve_and_keep(work[0], str(parts))))
    rest = work[1:]
    if not rest:
        return
    if workers == 1:
        for batch in rest:
            done(len(solve_and_keep(batch, str(parts))))
        return
    methods = multiprocessing.get_all_start_methods()
    context = multiprocessing.get_context("fork" if "fork" in methods else None)
    with ProcessPoolExecutor(max_workers=workers, mp_context=context) as pool:
        futures = [pool.submit(solve_and_keep, batch, str(parts)) for batch in rest]
        for future in local_completed(futures):
            done(len(future.result()))


def _run_dask(todo: list[int], rows: list[dict], keep, client, scheduler, size: int | None) -> None:
    """The problems ``todo`` in batches on a Dask distributed cluster, each batch kept as it
    finishes."""
    from distributed import Client, as_completed

    own = client is None
    if own:
        client = Client(scheduler, timeout="30s")
    try:
        workers = max(1, len(client.scheduler_info().get("workers", {})))
        futures = client.map(solve_batch, batches(todo, rows, workers, size), pure=False)
        for future in as_completed(futures):
            keep(future.result())
    finally:
        if own:
            client.close()


# -- reading -----------------------------------------------------------------------------------
def load(path) -> pa.Table:
    """A finished sweep's results."""
    return pq.read_table(Path(path), schema=SCHEMA)


def comparable(table: pa.Table) -> list[dict]:
    """The rows of ``table`` without what differs from run to run (:data:`TIMING`, and the
    plans' own ``seconds``): two runs of one sweep give equal lists."""
    out = []
    for row in table.to_pylist():
        row = {k: v for k, v in row.items() if k not in TIMING}
        if row["plan"] is not None:
            plan = json.loads(row["plan"])
            plan.pop("seconds", None)
            row["plan"] = plan
        out.append(row)
    return out
