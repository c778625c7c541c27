"""``sweep()``: :func:`nonholo.plan` over a table of problems, in parallel, resumable.

The problems (:mod:`nonholo.io.problems`: a JSON Lines file or a list of dicts) are checked
first, all of them — their columns, and every row's options by the checks :func:`nonholo.plan`
makes (:meth:`nonholo.planning.problem.Problem.build`), a bad one refused naming the row and
the option; a strategy named by its import path only with ``allow_imports=True``. Then they
are planned in batches — in this process (``workers=1``), on local worker processes
(``workers=N``, default: one per core), or on a Dask distributed cluster (``client=`` a
``distributed.Client``, or ``scheduler=`` its address) — and every finished batch is written
at once, so nothing computed is lost. A table may mix mechanisms and kinds of state (SO(3),
``Rᵏ``, ``SO(3) × Rᵏ``): each row is planned with its own mechanism. A row's mechanism file
(``"mechanism": "trailer.toml"``, relative to the table's directory) is read once, here;
the workers are sent its definition as data (:func:`nonholo.io.problems.as_json`) and
rebuild it from the cache of generated modules and kernels, never a pickled module.

The results are a Parquet file, one row per problem, written crash-safe batch by batch
(:mod:`nonholo.batch.result_store`): a sweep killed at any moment and started again with the
same problems and output plans only what no finished batch holds.

Local worker processes end with their sweep: each asks the kernel for ``SIGKILL`` when its
parent dies (``prctl(PR_SET_PDEATHSIG)`` on Linux) and also watches its parent's pid, so a
killed sweep leaves no worker planning on behind it.
"""
from __future__ import annotations

import contextlib
import json
import math
import multiprocessing
import os
import re
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures import as_completed as local_completed
from pathlib import Path

import pyarrow as pa

from ..io import problems as problem_table
from .result_store import (
    collect,
    finish,
    finished_results,
    locked,
    open_parts,
    problem_json,
    tidy,
    write_part,
)

#: Problems per batch at most (small batches keep every worker busy to the end).
MAX_BATCH = 8


def solve(index: int, row: dict) -> dict:
    """Plan one problem with its mechanism.

    Parameters
    ----------
    index : int
        The problem's row, from 0.
    row : dict
        A JSON row of :mod:`nonholo.io.problems` (any mechanism), already checked by
        :func:`sweep`.

    Returns
    -------
    dict
        Its results row (:data:`~nonholo.batch.result_store.SCHEMA`'s columns); an exception
        the plan raised is recorded in ``error``.
    """
    from ..planning.api import plan
    from ..planning.settings import arguments_of

    problem = problem_table.check_row(row, index, allow_imports=True)
    out = {"index": index, "label": problem["label"], "mechanism": problem["mechanism"],
           "problem": problem_json(row)}
    started = time.perf_counter()
    try:
        res = plan(problem["start"], problem["goal"], mechanism=problem["kinematics"],
                   **arguments_of(problem["options"], problem["kinematics"]))
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
    """:func:`solve` on every problem of a batch (the unit of work of a worker), with the
    BLAS libraries held to one thread: the workers are the parallelism (a planner's small
    matrices gain nothing from BLAS threads, which only take cores from the other
    workers).

    Parameters
    ----------
    batch : list of tuple
        ``(index, row)`` pairs.

    Returns
    -------
    list of dict
        Their results rows.
    """
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        return [solve(i, row) for i, row in batch]


def solve_and_keep(batch: list[tuple[int, dict]], parts: str) -> list[int]:
    """:func:`solve_batch`, its rows written as a part by the worker itself (the parent then
    handles no plan).

    Parameters
    ----------
    batch : list of tuple
        ``(index, row)`` pairs.
    parts : str
        The parts directory (:func:`~nonholo.batch.result_store.write_part`).

    Returns
    -------
    list of int
        The indices done.
    """
    rows = solve_batch(batch)
    write_part(rows, Path(parts))
    return [r["index"] for r in rows]


# -- checking the table ----------------------------------------------------------------------
def check_options(problems: list[dict]) -> None:
    """Every problem built as :func:`nonholo.plan` builds it
    (:meth:`~nonholo.planning.problem.Problem.build`: its options, and its start and goal
    against them), nothing planned.

    Parameters
    ----------
    problems : list of dict
        Checked problems (:func:`nonholo.io.problems.check`).

    Raises
    ------
    ValueError
        Naming the first bad row and the option (or ``start``/``goal``).
    """
    from ..planning.problem import Problem
    from ..planning.settings import arguments_of

    for i, p in enumerate(problems):
        try:
            mech = p.get("kinematics", p["mechanism"])
            Problem.build(p["start"], p["goal"], mechanism=mech, **arguments_of(p["options"], mech))
        except (ValueError, TypeError, OverflowError) as exc:
            raise ValueError(f"problem row {i}, column {_column_of(str(exc), p['options'])!r}: {exc}") from None


def _column_of(message: str, options: dict) -> str:
    """The column a message of :meth:`Problem.build` is about: the option (of ``options``) or
    the state it names first, else ``options``."""
    names = {f"options.{k}": k for k in options} | {"start": "start", "goal": "goal"}
    found = [(m.start(), column) for column, word in names.items()
             for m in [re.search(rf"(?<![\w.]){re.escape(word)}(?!\w)", message)] if m]
    return min(found)[1] if found else "options"


def _output(out) -> Path:
    """``out`` checked: a path that is not a directory nor another kind of non-regular file."""
    if not isinstance(out, (str, os.PathLike)):
        raise TypeError(f"out must be the results file's path (str or os.PathLike), got {type(out).__name__}")
    text = os.fspath(out)
    if not isinstance(text, str):
        text = os.fsdecode(text)
    path = Path(text)
    if not text or text.endswith(("/", os.sep)) or path.is_dir():
        raise ValueError(f"out must be the results file's path, got the directory {text!r} "
                         f"(e.g. {str(path / 'results.parquet')!r})")
    if path.exists() and not path.is_file():
        raise ValueError(f"out {text!r} exists and is not a regular file: choose a results file's path")
    return path


# -- running ----------------------------------------------------------------------------------
def batches(todo: list[int], rows: list[dict], workers: int, size: int | None = None) -> list[list[tuple[int, dict]]]:
    """Problems cut into batches.

    Parameters
    ----------
    todo : list of int
        The indices of the problems to plan.
    rows : list of dict
        Every problem's JSON row.
    workers : int
        The number of workers.
    size : int, optional
        Problems per batch (default: at most :data:`MAX_BATCH`, small enough that every
        worker gets several).

    Returns
    -------
    list of list of tuple
        The batches of ``(index, row)`` pairs.
    """
    if size is None:
        size = max(1, min(MAX_BATCH, math.ceil(len(todo) / (4 * max(1, workers)))))
    return [[(i, rows[i]) for i in todo[k:k + size]] for k in range(0, len(todo), size)]


def _positive(value, name: str) -> None:
    if value is not None and (not isinstance(value, int) or isinstance(value, bool) or value < 1):
        raise ValueError(f"{name} must be a positive integer, got {value!r}")


def sweep(problems, out, *, workers: int | None = None, client=None, scheduler: str | None = None,
          progress: bool = True, batch: int | None = None, allow_imports: bool = False) -> pa.Table:
    """Plan every problem and write the results to a Parquet file (see the module).

    Finished results of the same problems at ``out`` are returned (checked against their
    checksum).

    Parameters
    ----------
    problems : str, os.PathLike or list of dict
        A JSON Lines path or a list of dicts, see :mod:`nonholo.io.problems`.
    out : str or os.PathLike
        The results file.
    workers : int, optional
        Local processes (default ``os.cpu_count()``; ``1``: in this process).
    client : distributed.Client, optional
        Run on this Dask distributed cluster instead.
    scheduler : str, optional
        Or on the cluster of this scheduler's address, e.g. ``"tcp://127.0.0.1:8786"``.
    progress : bool
        A progress bar on standard error.
    batch : int, optional
        Problems per unit of work, each written as it finishes (default: chosen from the
        number of problems and workers, at most :data:`MAX_BATCH`).
    allow_imports : bool
        Let a row name its strategy by import path (``"package.module:Class"``, imported —
        its code run — in this process and the workers); without it such a row is refused
        before anything is imported.

    Returns
    -------
    pyarrow.Table
        The results, one row per problem, sorted by ``index``.

    Raises
    ------
    ValueError
        Naming them, for bad arguments; naming the row and column (the option) for bad
        problems, before anything runs; for an ``out`` that holds other results or is
        damaged.
    TypeError
        Naming them, for arguments of the wrong type.
    SweepBusy
        If another sweep is running on ``out``.
    RuntimeError
        If problems are still missing after three runs.
    """
    out = _output(out)
    _positive(workers, "workers")
    _positive(batch, "batch")
    if client is not None and scheduler is not None:
        raise ValueError("give a Dask client or a scheduler address, not both")
    if scheduler is not None and not isinstance(scheduler, str):
        raise TypeError(f"scheduler must be a Dask scheduler's address (text), got {type(scheduler).__name__}")
    if client is not None:
        _check_client(client)
    if not isinstance(allow_imports, bool):
        raise TypeError(f"allow_imports must be True or False, got {allow_imports!r}")
    if isinstance(problems, (str, os.PathLike)):
        checked = problem_table.read(problems, allow_imports=allow_imports)
    else:
        checked = problem_table.check(problems, allow_imports=allow_imports)
    check_options(checked)
    rows = [problem_table.as_json(p) for p in checked]
    n = len(rows)
    fingerprint = problem_table.fingerprint(checked)
    out.parent.mkdir(parents=True, exist_ok=True)
    with locked(out) as lock:
        tidy(out)
        finished = finished_results(out, fingerprint)
        if finished is not None:
            return finished
        parts = open_parts(out, fingerprint, n)
        tables, where = collect(parts, rows)
        bar = _progress_bar(n, len(where), progress)
        try:
            for _ in range(3):                        # a part lost meanwhile is planned again
                todo = [i for i in range(n) if i not in where]
                if not todo:
                    break
                del tables
                _run(todo, rows, parts, bar, workers, client, scheduler, batch, lock)
                tables, where = collect(parts, rows)
        finally:
            bar.close()
        if len(where) != n:
            missing = sorted(set(range(n)) - set(where))
            raise RuntimeError(f"the sweep's parts in {parts} still miss problems {missing[:5]} after "
                               "three runs")
        return finish(out, parts, fingerprint, n, tables, where)


def _check_client(client) -> None:
    try:
        from distributed import Client
    except ImportError:
        Client = None
    if Client is None or not isinstance(client, Client):
        hint = " (a scheduler's address goes to scheduler=)" if isinstance(client, str) else ""
        raise TypeError(f"client must be a distributed.Client{hint}, got {type(client).__name__}")


def _run(todo, rows, parts, bar, workers, client, scheduler, size, lock) -> None:
    if client is not None or scheduler is not None:
        def keep(rows_done: list[dict]) -> None:
            write_part(rows_done, parts)
            bar.update(len(rows_done))

        _run_dask(todo, rows, keep, client, scheduler, size)
    else:
        workers = (os.cpu_count() or 1) if workers is None else workers
        _run_local(batches(todo, rows, workers, size), parts, bar.update, workers, lock)


def _progress_bar(total: int, initial: int, show: bool):
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, unit="plan", disable=not show, smoothing=0.1)


def _die_with(parent: int, lock: int | None) -> None:
    """A local worker's start: it closes its copy of the sweep's lock (which stays the
    parent's) and ends when ``parent`` does — by the kernel's ``SIGKILL``
    (``PR_SET_PDEATHSIG``, Linux) and by a thread that watches the parent's pid."""
    if lock is not None:
        with contextlib.suppress(OSError):
            os.close(lock)
    if sys.platform.startswith("linux"):
        import ctypes
        import signal

        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None, use_errno=True).prctl(1, int(signal.SIGKILL), 0, 0, 0)   # PR_SET_PDEATHSIG
    if os.getppid() != parent:                           # the parent died before the kernel was asked
        os._exit(1)

    def watch() -> None:
        while True:
            time.sleep(0.5)
            if os.getppid() != parent:
                os._exit(1)

    threading.Thread(target=watch, name="nonholo-parent-watch", daemon=True).start()


def _run_local(work: list, parts: Path, done, workers: int, lock: int | None = None) -> None:
    """The batches in this process (``workers=1``) or on local worker processes, each
    written as a part by whoever planned it (:func:`solve_and_keep`; ``done(count)`` after
    each); the first batch always here, so that the workers — forked where the platform
    allows — start with the kernels compiled. The workers end with this process
    (:func:`_die_with`)."""
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
    inherited = lock if context.get_start_method() == "fork" else None
    with ProcessPoolExecutor(max_workers=workers, mp_context=context, initializer=_die_with,
                             initargs=(os.getpid(), inherited)) as pool:
        try:
            futures = [pool.submit(solve_and_keep, batch, str(parts)) for batch in rest]
            for future in local_completed(futures):
                done(len(future.result()))
        except BaseException:
            pool.shutdown(wait=False, cancel_futures=True)     # interrupted: no new batch starts
            raise


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
