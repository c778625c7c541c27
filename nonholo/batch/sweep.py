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

Results: a Parquet file (pyarrow), one row per problem, sorted by ``index`` (the problem's
row, from 0), with :data:`SCHEMA`'s columns: the problem's ``label`` and ``mechanism``,
the plan's ``strategy``, ``method``, ``route``, ``T``, ``success``, ``terminal_error``,
``min_delta``, ``iterations``, ``reason``, the wall time ``seconds`` of the call, the
``problem`` (its start and goal in the JSON form of its mechanism's space, so a row of an
SO(3) mechanism holds 3×3 nested lists) and the ``plan`` itself as JSON
(:meth:`nonholo.io.result.PlanResult.to_dict`, with the coordinates beyond SO(3); reload
with :func:`plan_of`), and ``error``: the exception a problem raised while it was planned
(then the plan is null; recorded, not fatal). Its metadata holds the problems' fingerprint
(:data:`FINGERPRINT_KEY`) and a SHA-256 of its rows (:data:`CHECKSUM_KEY`, :func:`checksum`):
:func:`load` and a sweep that finds its results already there re-compute it, so a damaged
file is refused, not returned.

On disk, while it runs (``RESULTS`` the output):

- ``RESULTS.lock``: an exclusive lock (``flock``) held by the running sweep; a second sweep on
  the same output refuses at once (:class:`SweepBusy`, ``nonholo sweep``: exit 2) naming it.
  The lock dies with its process: a killed sweep's never blocks.
- ``RESULTS.parts/``: ``sweep.json`` (the problems' fingerprint) and one Parquet file per
  finished batch, written by the local worker that planned it (or by this process for a Dask
  cluster's, whose workers may not share its disk), in full, then renamed to
  ``part-<first index>-<SHA-256 of the file>.parquet``. Started again with the same problems
  and ``out``, a sweep reconciles the parts: one whose bytes do not match its name, that
  cannot be read or holds rows of other problems is discarded (and its problems planned
  again); a row held twice (a batch finished by a run that was killed and by the next) is
  kept once; only the problems no part holds are planned.
- At the end the rows become ``RESULTS`` (written to a temporary file, synced, renamed into
  place), then the parts are removed (renamed aside first, so a kill half-way leaves no
  half-removed directory). A run killed after ``RESULTS`` is written finds it complete,
  checked, and removes the parts.

Local worker processes end with their sweep: each asks the kernel for ``SIGKILL`` when its
parent dies (``prctl(PR_SET_PDEATHSIG)`` on Linux) and also watches its parent's pid, so a
killed sweep leaves no worker planning on behind it.
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import math
import multiprocessing
import os
import re
import secrets
import shutil
import sys
import threading
import time
import warnings
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
#: The metadata key of a finished results file: the SHA-256 of its rows (:func:`checksum`).
CHECKSUM_KEY = b"nonholo.batch.sweep.sha256"
#: Problems per batch at most (small batches keep every worker busy to the end).
MAX_BATCH = 8
#: How long a sweep waits for another one's lock on its output before it refuses (s): long
#: enough for a killed sweep's last worker to be gone, short enough to fail fast.
LOCK_WAIT = 1.0
#: A part's file name: the first index of its rows and the SHA-256 of its bytes.
PART_NAME = re.compile(r"part-(\d{9})-([0-9a-f]{64})\.parquet")


class SweepBusy(RuntimeError):
    """Another sweep holds the lock on this output (see the module)."""


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
        Its results row (:data:`SCHEMA`'s columns); an exception the plan raised is
        recorded in ``error``.
    """
    from ..planning.api import plan

    problem = problem_table.check_row(row, index, allow_imports=True)
    out = {"index": index, "label": problem["label"], "mechanism": problem["mechanism"],
           "problem": problem_json(row)}
    started = time.perf_counter()
    try:
        res = plan(problem["start"], problem["goal"], mechanism=problem["kinematics"], **problem["options"])
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


def problem_json(row: dict) -> str:
    """The ``problem`` column of a JSON row.

    Parameters
    ----------
    row : dict
        A JSON row of :mod:`nonholo.io.problems`.

    Returns
    -------
    str
        The row as canonical JSON.
    """
    return json.dumps(row, separators=(",", ":"), sort_keys=True)


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
        The parts directory (:func:`write_part`).

    Returns
    -------
    list of int
        The indices done.
    """
    rows = solve_batch(batch)
    write_part(rows, Path(parts))
    return [r["index"] for r in rows]


def plan_of(row) -> PlanResult | None:
    """The plan of a results row, checked like a plan file.

    Parameters
    ----------
    row : dict or str
        A results row, or its ``plan`` JSON text.

    Returns
    -------
    PlanResult or None
        The :class:`~nonholo.io.result.PlanResult`; ``None`` for a problem that raised.
    """
    text = row["plan"] if isinstance(row, dict) else row
    return None if text is None else PlanResult.from_dict(json.loads(text))


# -- checking the table --------------------------------------------------------------------------
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

    for i, p in enumerate(problems):
        try:
            Problem.build(p["start"], p["goal"], mechanism=p.get("kinematics", p["mechanism"]), **p["options"])
        except (ValueError, TypeError, OverflowError) as exc:
            raise ValueError(f"problem row {i}, column {_column_of(str(exc), p['options'])!r}: {exc}") from None


def _column_of(message: str, options: dict) -> str:
    """The column a message of :meth:`Problem.build` is about: the option (of ``options``) or
    the state it names first, else ``options``."""
    names = {f"options.{k}": k for k in options} | {"start": "R0", "goal": "Rd"}
    found = [(m.start(), column) for column, word in names.items()
             for m in [re.search(rf"(?<![\w.]){re.escape(word)}(?!\w)", message)] if m]
    return min(found)[1] if found else "options"


# -- files ------------------------------------------------------------------------------------
def parts_dir(out: Path) -> Path:
    """Where a running sweep keeps its finished batches.

    Parameters
    ----------
    out : pathlib.Path
        The results file.

    Returns
    -------
    pathlib.Path
        ``RESULTS.parts`` beside it.
    """
    out = Path(out)
    return out.with_name(out.name + ".parts")


def lock_path(out: Path) -> Path:
    """The lock file of a sweep.

    Parameters
    ----------
    out : pathlib.Path
        The results file.

    Returns
    -------
    pathlib.Path
        ``RESULTS.lock`` beside it.
    """
    out = Path(out)
    return out.with_name(out.name + ".lock")


def _sync_dir(directory: Path) -> None:
    with contextlib.suppress(OSError):
        fd = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _publish(tmp: Path, path: Path) -> None:
    """The complete file ``tmp`` synced and renamed to ``path`` (a small atomic write of this
    module's own: a reader sees the old file or the whole new one, never a part)."""
    fd = os.open(tmp, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
    os.replace(tmp, path)
    _sync_dir(path.parent)


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _table(rows: list[dict], metadata: dict | None = None) -> pa.Table:
    schema = SCHEMA.with_metadata(metadata) if metadata else SCHEMA
    return pa.Table.from_pylist(rows, schema=schema)


def write_part(rows: list[dict], parts: Path) -> Path:
    """Rows as one part of a running sweep: written in full, then renamed (see the module).

    Parameters
    ----------
    rows : list of dict
        Results rows.
    parts : pathlib.Path
        The parts directory.

    Returns
    -------
    pathlib.Path
        The part, ``part-<first index>-<SHA-256 of its bytes>.parquet``.
    """
    tmp = parts / f".part-{secrets.token_hex(6)}.tmp"
    try:
        pq.write_table(_table(rows), tmp)
        path = parts / f"part-{rows[0]['index']:09d}-{_sha256(tmp)}.parquet"
        _publish(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def checksum(table: pa.Table) -> str:
    """The SHA-256 of a results table's rows, independent of the file's layout and metadata.

    Parameters
    ----------
    table : pyarrow.Table
        Results with :data:`SCHEMA`'s columns.

    Returns
    -------
    str
        The hex digest of every column, in order, as JSON (floats exactly, by their
        shortest repr).
    """
    h = hashlib.sha256()
    for name in SCHEMA.names:
        h.update(name.encode() + b"\0")
        h.update(json.dumps(table.column(name).to_pylist(), separators=(",", ":")).encode())
        h.update(b"\0")
    return h.hexdigest()


def _read_checked(path: Path) -> pa.Table:
    """A finished results file, its rows held against its checksum: ``ValueError`` naming
    the file if it cannot be read or its rows are not the ones written."""
    try:
        meta = pq.read_schema(path).metadata or {}
        meta = {k: v for k, v in meta.items() if k in (FINGERPRINT_KEY, CHECKSUM_KEY)}
        table = pq.read_table(path, schema=SCHEMA).replace_schema_metadata(meta or None)
        want = meta.get(CHECKSUM_KEY)
        matches = want is None or want.decode(errors="replace") == checksum(table)
    except (OSError, pa.ArrowException, UnicodeDecodeError) as exc:
        # a flipped byte in a text column's data reads, and fails only where its rows are
        # decoded for the checksum
        raise ValueError(f"{path} is damaged or not a sweep's results: it cannot be read ({exc})") from None
    if not matches:
        raise ValueError(f"{path} is damaged: its rows do not match the checksum written with them")
    return table


def _fingerprint_of(table: pa.Table) -> str | None:
    value = (table.schema.metadata or {}).get(FINGERPRINT_KEY)
    return None if value is None else value.decode(errors="replace")


def _finished(out: Path, fingerprint: str, have_parts: bool) -> pa.Table | None:
    """The finished results of these problems at ``out``, checked, or ``None`` if there are
    none to reuse (``out`` missing; or damaged while this sweep's parts can write it again);
    ``ValueError`` naming ``out`` if it holds other results or is damaged."""
    if not out.exists():
        return None
    try:
        table = _read_checked(out)
    except ValueError as exc:
        if have_parts:
            return None
        raise ValueError(f"out: {exc}; remove it to plan again, or choose another path") from None
    if _fingerprint_of(table) != fingerprint:
        raise ValueError(f"out: {out} exists and holds other results: remove it, or choose another path")
    if CHECKSUM_KEY not in (table.schema.metadata or {}):
        if have_parts:
            return None
        raise ValueError(f"out: {out} holds these problems' results without a checksum (written by an "
                         "older version), so they cannot be verified: remove it to plan again")
    return table


@contextlib.contextmanager
def _locked(out: Path):
    """An exclusive lock on ``out`` for the block (:func:`lock_path`); :class:`SweepBusy`
    naming ``out`` if another live process holds it (after :data:`LOCK_WAIT`). Yields the
    lock's file descriptor (which worker processes close)."""
    try:
        import fcntl
    except ImportError:                                  # not POSIX: no lock
        yield None
        return
    path = lock_path(out)
    deadline = time.monotonic() + LOCK_WAIT
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT | getattr(os, "O_CLOEXEC", 0), 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 64, 0).decode(errors="replace").strip()
            os.close(fd)
            if time.monotonic() > deadline:
                who = f" (process {holder})" if holder.isdigit() else ""
                raise SweepBusy(f"another sweep{who} is writing {out} (it holds {path}): wait for it to "
                                "finish, or choose another output") from None
            time.sleep(0.05)
            continue
        try:
            same = os.path.samestat(os.fstat(fd), os.stat(path))
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)                                     # the lock file was removed meanwhile: again
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, str(os.getpid()).encode(), 0)
        yield fd
    finally:
        with contextlib.suppress(OSError):
            os.unlink(path)
        os.close(fd)


def _tidy(out: Path) -> None:
    """Remove what a killed sweep on ``out`` left half-done (under the lock): the temporary
    file of its results, parts directories being created or removed, temporary parts."""
    leftover = re.compile(rf"\.{re.escape(out.name)}\.(?:[0-9a-f]{{8}}\.tmp|parts\.[0-9a-f]{{8}}\.(?:new|trash))")
    for p in out.parent.glob(f".{_glob_escape(out.name)}.*"):
        if not leftover.fullmatch(p.name):
            continue
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p, ignore_errors=True)
        else:
            p.unlink(missing_ok=True)
    parts = parts_dir(out)
    if parts.is_dir():
        for p in parts.glob(".part-*.tmp"):
            p.unlink(missing_ok=True)


def _glob_escape(name: str) -> str:
    return re.sub(r"([*?\[])", r"[\1]", name)


def _remove_parts(parts: Path) -> None:
    """The parts directory renamed aside (one atomic step), then removed."""
    trash = parts.with_name(f".{parts.name}.{secrets.token_hex(4)}.trash")
    os.replace(parts, trash)
    shutil.rmtree(trash, ignore_errors=True)


def _manifest(parts: Path) -> str | None:
    """The fingerprint in a parts directory's ``sweep.json`` (``None`` if it has none)."""
    try:
        return str(json.loads((parts / "sweep.json").read_text())["fingerprint"])
    except (OSError, ValueError, KeyError, TypeError):
        return None


def _open_parts(out: Path, fingerprint: str, n: int) -> Path:
    """The parts directory of ``out``: created (with its ``sweep.json``, in one rename), or
    checked to belong to the same problems."""
    parts = parts_dir(out)
    if parts.exists():
        if _manifest(parts) != fingerprint:
            raise ValueError(f"out: {parts} holds a sweep of other problems (or is not a sweep's): "
                             "remove it, or choose another results path")
        return parts
    new = parts.with_name(f".{parts.name}.{secrets.token_hex(4)}.new")
    new.mkdir()
    (new / "sweep.json").write_text(json.dumps({"fingerprint": fingerprint, "problems": n}))
    os.replace(new, parts)
    _sync_dir(parts.parent)
    return parts


def _collect(parts: Path, rows: list[dict]) -> tuple[list[pa.Table], dict[int, tuple[int, int]]]:
    """The parts' tables and, for every problem held, where its first row is (``index →
    (table, row)``). A part whose bytes do not match its name, that cannot be read, or that
    holds a row of another problem is discarded (removed, with a warning)."""
    expected = [problem_json(r) for r in rows]
    tables, where = [], {}
    for path in sorted(parts.glob("part-*.parquet")):
        name = PART_NAME.fullmatch(path.name)
        try:
            if name is None or _sha256(path) != name.group(2):
                raise ValueError("its bytes do not match its name")
            table = pq.read_table(path, schema=SCHEMA)
            index, problem = table.column("index").to_pylist(), table.column("problem").to_pylist()
            if not index or len(set(index)) != len(index) or any(
                    not 0 <= i < len(rows) or p != expected[i] for i, p in zip(index, problem)):
                raise ValueError("it holds rows of other problems")
        except (OSError, ValueError, pa.ArrowException) as exc:
            warnings.warn(f"discarded the part {path} ({exc}); its problems are planned again", stacklevel=3)
            with contextlib.suppress(FileNotFoundError):
                path.unlink()
            continue
        for k, i in enumerate(index):
            where.setdefault(i, (len(tables), k))
        tables.append(table)
    return tables, where


def _finish(out: Path, parts: Path, fingerprint: str, n: int, tables, where) -> pa.Table:
    """All problems' rows (each once) as one results file, sorted by index, with the
    fingerprint and checksum in its metadata; then the parts removed."""
    offsets = [0]
    for t in tables:
        offsets.append(offsets[-1] + t.num_rows)
    take = [offsets[t] + k for _, (t, k) in sorted(where.items())]
    table = pa.concat_tables(tables).take(pa.array(take, type=pa.int64())).combine_chunks()
    assert table.column("index").to_pylist() == list(range(n))
    table = table.replace_schema_metadata({FINGERPRINT_KEY: fingerprint.encode(),
                                           CHECKSUM_KEY: checksum(table).encode()})
    tmp = out.with_name(f".{out.name}.{secrets.token_hex(4)}.tmp")
    try:
        pq.write_table(table, tmp, write_statistics=False)
        _publish(tmp, out)
    finally:
        if tmp.exists():
            tmp.unlink()
    written = _read_checked(out)
    _remove_parts(parts)
    return written


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


# -- running -----------------------------------------------------------------------------------
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
    with _locked(out) as lock:
        _tidy(out)
        parts = parts_dir(out)
        finished = _finished(out, fingerprint, _manifest(parts) == fingerprint)
        if finished is not None:
            # killed between writing the results and removing its parts (or half-way through
            # removing them, by an older version: no sweep.json left)
            if parts.is_dir() and _manifest(parts) in (fingerprint, None):
                _remove_parts(parts)
            return finished
        parts = _open_parts(out, fingerprint, n)
        tables, where = _collect(parts, rows)
        bar = _progress_bar(n, len(where), progress)
        try:
            for _ in range(3):                        # a part lost meanwhile is planned again
                todo = [i for i in range(n) if i not in where]
                if not todo:
                    break
                del tables
                _run(todo, rows, parts, bar, workers, client, scheduler, batch, lock)
                tables, where = _collect(parts, rows)
        finally:
            bar.close()
        if len(where) != n:
            missing = sorted(set(range(n)) - set(where))
            raise RuntimeError(f"the sweep's parts in {parts} still miss problems {missing[:5]} after "
                               "three runs")
        return _finish(out, parts, fingerprint, n, tables, where)


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


# -- reading -----------------------------------------------------------------------------------
def load(path) -> pa.Table:
    """A finished sweep's results, checked against the checksum written with them (a file
    written before checksums were kept is read as it is).

    Parameters
    ----------
    path : str or os.PathLike
        The results file.

    Returns
    -------
    pyarrow.Table
        The results.

    Raises
    ------
    ValueError
        Naming the file, if it cannot be read or its rows do not match the checksum.
    """
    return _read_checked(Path(path))


def comparable(table: pa.Table) -> list[dict]:
    """A results table's rows without what differs from run to run.

    Parameters
    ----------
    table : pyarrow.Table
        Results.

    Returns
    -------
    list of dict
        The rows without :data:`TIMING` and the plans' own ``seconds`` and ``made_by`` (what
        made them: a run resumed after the code's commit moved records the new one), the plans
        parsed: two runs of one sweep give equal lists.
    """
    out = []
    for row in table.to_pylist():
        row = {k: v for k, v in row.items() if k not in TIMING}
        if row["plan"] is not None:
            plan = json.loads(row["plan"])
            plan.pop("seconds", None)
            plan.pop("made_by", None)
            row["plan"] = plan
        out.append(row)
    return out
