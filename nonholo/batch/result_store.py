"""A sweep's results: a crash-safe Parquet store, written batch by batch and read back checked.

The results are a Parquet file (pyarrow), one row per problem, sorted by ``index`` (the
problem's row, from 0), with :data:`SCHEMA`'s columns: the problem's ``label`` and ``mechanism``,
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
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
import secrets
import shutil
import time
import warnings
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

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
#: How long a sweep waits for another one's lock on its output before it refuses (s): long
#: enough for a killed sweep's last worker to be gone, short enough to fail fast.
LOCK_WAIT = 1.0
#: A part's file name: the first index of its rows and the SHA-256 of its bytes.
PART_NAME = re.compile(r"part-(\d{9})-([0-9a-f]{64})\.parquet")


class SweepBusy(RuntimeError):
    """Another sweep holds the lock on this output (see the module)."""


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


def finished_results(out: Path, fingerprint: str) -> pa.Table | None:
    """The finished results of these problems at ``out``, checked, or ``None`` if there are
    none to reuse (``out`` missing; or damaged while this sweep's parts can write it again).

    The parts of a sweep killed between writing the results and removing its parts (or
    half-way through removing them, by an older version: no ``sweep.json`` left) are
    removed.

    Parameters
    ----------
    out : pathlib.Path
        The results file.
    fingerprint : str
        The problems' fingerprint (:func:`nonholo.io.problems.fingerprint`).

    Returns
    -------
    pyarrow.Table or None
        The results, or ``None``.

    Raises
    ------
    ValueError
        Naming ``out``, if it holds other results or is damaged.
    """
    parts = parts_dir(out)
    table = _finished(out, fingerprint, _manifest(parts) == fingerprint)
    if table is not None and parts.is_dir() and _manifest(parts) in (fingerprint, None):
        _remove_parts(parts)
    return table


@contextlib.contextmanager
def locked(out: Path):
    """An exclusive lock on ``out`` for the block (:func:`lock_path`).

    Parameters
    ----------
    out : pathlib.Path
        The results file.

    Yields
    ------
    int or None
        The lock's file descriptor (which worker processes close); ``None`` where there is
        no ``flock`` (not POSIX: no lock).

    Raises
    ------
    SweepBusy
        Naming ``out``, if another live process holds the lock (after :data:`LOCK_WAIT`).
    """
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


def tidy(out: Path) -> None:
    """Remove what a killed sweep on ``out`` left half-done (under the lock): the temporary
    file of its results, parts directories being created or removed, temporary parts.

    Parameters
    ----------
    out : pathlib.Path
        The results file.
    """
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


def open_parts(out: Path, fingerprint: str, n: int) -> Path:
    """The parts directory of ``out``: created (with its ``sweep.json``, in one rename), or
    checked to belong to the same problems.

    Parameters
    ----------
    out : pathlib.Path
        The results file.
    fingerprint : str
        The problems' fingerprint.
    n : int
        The number of problems.

    Returns
    -------
    pathlib.Path
        The parts directory (:func:`parts_dir`).

    Raises
    ------
    ValueError
        If it holds a sweep of other problems (or is not a sweep's).
    """
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


def collect(parts: Path, rows: list[dict]) -> tuple[list[pa.Table], dict[int, tuple[int, int]]]:
    """The parts' tables and, for every problem held, where its first row is.

    A part whose bytes do not match its name, that cannot be read, or that holds a row of
    another problem is discarded (removed, with a warning).

    Parameters
    ----------
    parts : pathlib.Path
        The parts directory.
    rows : list of dict
        Every problem's JSON row.

    Returns
    -------
    tables : list of pyarrow.Table
        The parts kept.
    where : dict
        ``index → (table, row)`` of every problem held.
    """
    expected = [problem_json(r) for r in rows]
    tables, where = [], {}
    for path in sorted(parts.glob("part-*.parquet")):
        try:
            table, index = _read_part(path, expected)
        except (OSError, ValueError, pa.ArrowException) as exc:
            warnings.warn(f"discarded the part {path} ({exc}); its problems are planned again", stacklevel=3)
            with contextlib.suppress(FileNotFoundError):
                path.unlink()
            continue
        for k, i in enumerate(index):
            where.setdefault(i, (len(tables), k))
        tables.append(table)
    return tables, where


def _read_part(path: Path, expected: list[str]) -> tuple[pa.Table, list[int]]:
    """A part and its rows' indices; ``ValueError`` if its bytes do not match its name or it
    holds rows of other problems (``expected``: every problem's ``problem`` column)."""
    name = PART_NAME.fullmatch(path.name)
    if name is None or _sha256(path) != name.group(2):
        raise ValueError("its bytes do not match its name")
    table = pq.read_table(path, schema=SCHEMA)
    index, problem = table.column("index").to_pylist(), table.column("problem").to_pylist()
    if not index or len(set(index)) != len(index) or any(
            not 0 <= i < len(expected) or p != expected[i] for i, p in zip(index, problem)):
        raise ValueError("it holds rows of other problems")
    return table, index


def finish(out: Path, parts: Path, fingerprint: str, n: int, tables, where) -> pa.Table:
    """All problems' rows (each once) as one results file, sorted by index, with the
    fingerprint and checksum in its metadata; then the parts removed.

    Parameters
    ----------
    out : pathlib.Path
        The results file.
    parts : pathlib.Path
        The parts directory.
    fingerprint : str
        The problems' fingerprint.
    n : int
        The number of problems.
    tables, where
        The parts' tables and where each problem's row is (:func:`collect`).

    Returns
    -------
    pyarrow.Table
        The results as written, read back and checked.
    """
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


# -- reading ----------------------------------------------------------------------------------
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
