"""nonholo's disk caches, whose entries are verified before anything in them runs.

Where they are (:func:`cache_dir`, :func:`generated_cache_dir`), the digest that keys an
entry by what it is built from (:func:`digest`), and the generated sources kept there
(:func:`cached_source`).

Nothing in the cache runs unverified. Every entry nonholo writes there (a compiled module,
:mod:`nonholo.codegen.build`, or a generated module's source,
:mod:`nonholo.codegen.mechanism_modules`) gets a record beside it,
``<entry>.sha256.json``: the SHA-256 of the file and the key of what it was built from
(:func:`write_entry`). An entry is read (:func:`read_entry`) only if it is a regular file
of the user's own (or root's), not writable by others, opened without following a link or
waiting on a FIFO, and its bytes hash to its record; otherwise it is passed over, with a
warning naming the file, and rebuilt. A compiled module's own ``SOURCE_DIGEST`` can only be read
once it is imported, which runs its initialisation: so the file's hash is checked first,
and the module is imported from a private copy of the very bytes checked
(:func:`import_verified`). The modules built at install (``nonholo.generated.native``) are
part of the installation, not of the cache.
"""
from __future__ import annotations

import errno
import hashlib
import importlib.machinery
import importlib.util
import json
import keyword
import os
import stat
import tempfile
import warnings
from pathlib import Path
from typing import Callable

__all__ = ["CACHE_ENV", "RECORD_SUFFIX", "ENTRY_LIMIT", "RECORD_LIMIT", "RefusedEntry", "cache_dir",
           "generated_cache_dir", "digest", "warn_once", "record_path", "read_entry", "write_entry",
           "import_verified", "cached_source"]

#: Environment variable naming the disk cache of compiled modules (default: the user's cache).
CACHE_ENV = "NONHOLO_CACHE_DIR"

#: The suffix of the record nonholo writes beside a cache entry (:func:`write_entry`).
RECORD_SUFFIX = ".sha256.json"
#: The largest cache entry read (bytes).
ENTRY_LIMIT = 256 * 2**20
#: The largest record read (bytes).
RECORD_LIMIT = 4096

_WARNED: set[str] = set()


class RefusedEntry(Exception):
    """A cache entry that is not used (the message says why)."""


def cache_dir() -> Path:
    """The disk cache of compiled modules.

    Returns
    -------
    pathlib.Path
        ``$NONHOLO_CACHE_DIR``, else ``$XDG_CACHE_HOME/nonholo/native``, else
        ``~/.cache/nonholo/native``.
    """
    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV])
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "nonholo" / "native"


def generated_cache_dir() -> Path:
    """Where generated modules are cached.

    Returns
    -------
    pathlib.Path
        ``$NONHOLO_CACHE_DIR/generated`` when that is set (beside the compiled kernels,
        :func:`cache_dir`), else ``generated`` beside the default kernel cache
        (``~/.cache/nonholo/generated``).
    """
    kernels = cache_dir()
    return kernels / "generated" if os.environ.get(CACHE_ENV) else kernels.parent / "generated"


def digest(*texts: str) -> str:
    """SHA-256 of what a native module is translated from.

    Parameters
    ----------
    *texts : str
        The Python sources and the translator's.

    Returns
    -------
    str
        The hex digest; the module records it as ``SOURCE_DIGEST``.
    """
    h = hashlib.sha256()
    for t in texts:
        h.update(hashlib.sha256(t.encode()).digest())
    return h.hexdigest()


def warn_once(key: str, message: str) -> None:
    """A warning said once per process.

    Parameters
    ----------
    key : str
        What the warning is about; a second warning with the key is not said.
    message : str
        The warning (a ``RuntimeWarning``).
    """
    if key not in _WARNED:
        _WARNED.add(key)
        warnings.warn(message, RuntimeWarning, stacklevel=3)


def record_path(path: Path) -> Path:
    """The record of a cache entry (:data:`RECORD_SUFFIX` appended to its name).

    Parameters
    ----------
    path : pathlib.Path
        The entry.

    Returns
    -------
    pathlib.Path
        Its record.
    """
    return path.with_name(path.name + RECORD_SUFFIX)


def _read_regular(path: Path, limit: int) -> bytes:
    """The bytes of ``path`` if it is a regular file of the user's (or root's), not
    writable by others: opened without following a symbolic link and without blocking (a
    FIFO is never waited on), checked on the open file. ``FileNotFoundError`` if absent, else
    :class:`RefusedEntry`."""
    flags = os.O_RDONLY
    for flag in ("O_NOFOLLOW", "O_NONBLOCK", "O_CLOEXEC", "O_BINARY"):
        flags |= getattr(os, flag, 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise
    except OSError as exc:
        raise RefusedEntry("is a symbolic link" if exc.errno == errno.ELOOP
                           else f"cannot be opened ({exc.strerror})") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise RefusedEntry("is not a regular file")
        if hasattr(os, "getuid") and st.st_uid not in (os.getuid(), 0):
            raise RefusedEntry("is owned by another user")
        if st.st_mode & 0o022:
            raise RefusedEntry("is writable by others")
        if st.st_size > limit:
            raise RefusedEntry(f"is larger than {limit} bytes")
        chunks, size = [], 0
        while size <= limit:
            chunk = os.read(fd, 1 << 20)
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
        if size > limit:
            raise RefusedEntry(f"is larger than {limit} bytes")
        return b"".join(chunks)
    finally:
        os.close(fd)


def read_entry(path: Path, key: str) -> bytes | None:
    """The bytes of a cache entry, verified against the record nonholo wrote beside it
    (:func:`write_entry`), before anything in them is used.

    Parameters
    ----------
    path : pathlib.Path
        The entry.
    key : str
        What it must have been built from (recorded with it).

    Returns
    -------
    bytes or None
        Its bytes; ``None`` if it is absent, or refused — not a regular file of the user's
        or root's (a symbolic link, a FIFO, a directory, another user's file), writable by
        others, without a record, or not the bytes or the key recorded (edited or
        damaged) — said once in a warning naming the file, so that the caller rebuilds it.
    """
    try:
        return _verified(path, key)
    except FileNotFoundError:
        return None
    except RefusedEntry as why:
        warn_once(f"cache entry {path}", f"nonholo: ignored the cache entry {path}: it {why}; rebuilding it")
        return None


def _verified(path: Path, key: str) -> bytes:
    """The bytes of ``path`` if its record (:func:`record_path`) names it, ``key`` and their
    hash; ``FileNotFoundError`` if absent, else :class:`RefusedEntry`."""
    data = _read_regular(path, ENTRY_LIMIT)
    try:
        record = json.loads(_read_regular(record_path(path), RECORD_LIMIT))
    except FileNotFoundError:
        raise RefusedEntry("has no record of its hash (not written by this version of nonholo)") from None
    except (UnicodeDecodeError, ValueError):
        raise RefusedEntry("has a damaged record") from None
    if not isinstance(record, dict) or record.get("file") != path.name or record.get("key") != key:
        raise RefusedEntry("has a record of another entry")
    if record.get("sha256") != hashlib.sha256(data).hexdigest():
        raise RefusedEntry("does not hash to the record nonholo wrote with it (edited or damaged)")
    return data


def _write_atomically(path: Path, data: bytes) -> None:
    """``data`` into ``path`` by a private file (mode 0600) renamed into place."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def write_entry(path: Path, data: bytes, key: str) -> None:
    """Write a cache entry and its record (:func:`record_path`: the SHA-256 of ``data`` and
    ``key``), each atomically, the entry first.

    Parameters
    ----------
    path : pathlib.Path
        The entry (its directory is made if need be; a FIFO or a link there is replaced,
        not written through).
    data : bytes
        Its content.
    key : str
        What it was built from.

    Raises
    ------
    OSError
        If the cache cannot be written (a directory in the way, no permission).
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    _write_atomically(path, data)
    record = {"file": path.name, "key": key, "sha256": hashlib.sha256(data).hexdigest()}
    _write_atomically(record_path(path), json.dumps(record, sort_keys=True).encode())


def import_verified(name: str, data: bytes, origin: Path):
    """An extension module imported from ``data`` — bytes already verified
    (:func:`read_entry`) — through a private copy (mode 0600, removed once loaded), so that
    what runs is what was checked, whatever happens to ``origin`` meanwhile.

    Parameters
    ----------
    name : str
        The module's full name.
    data : bytes
        The compiled module.
    origin : pathlib.Path
        The cache entry it was read from (the module's ``__file__``).

    Returns
    -------
    module
        The module.

    Raises
    ------
    OSError
        If no private copy can be written (neither beside the entry nor in the temporary
        directory).
    ImportError
        If the bytes are not an extension module of that name.
    """
    last_error = None
    for where in (origin.parent, None):                 # beside the entry, else the temporary directory
        try:
            fd, tmp = tempfile.mkstemp(dir=where, prefix=".load-", suffix=origin.suffix)
        except OSError as exc:
            last_error = exc
            continue
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(data)
            loader = importlib.machinery.ExtensionFileLoader(name, tmp)
            spec = importlib.util.spec_from_file_location(name, tmp, loader=loader)
            module = importlib.util.module_from_spec(spec)
            loader.exec_module(module)
        finally:
            try:
                os.unlink(tmp)
            except OSError:
                pass
        module.__file__ = str(origin)
        return module
    raise last_error


def cached_source(name: str, key: str, build: Callable[[], str]) -> str:
    """A generated source, read from the cache — verified before it is used — or built and
    written to it.

    An entry is used only if :func:`read_entry` verifies it: a regular file of the user's
    whose bytes hash to the record nonholo wrote beside it with this ``key``. An entry
    edited, damaged (truncated, empty, not text), without a record, or not a regular file
    (a FIFO, a directory, a symbolic link) is passed over with a warning naming it and
    rebuilt, so that what runs is what the definition generates.

    Parameters
    ----------
    name : str
        The mechanism's name (a Python identifier: it names the file).
    key : str
        The definition's digest; the file is ``<name>_<key[:24]>.py`` in
        :func:`generated_cache_dir` (written atomically with its record; a cache that
        cannot be written is reported once and skipped).
    build : callable
        ``build()``: the source, when it is not cached.

    Returns
    -------
    str
        The module's source.

    Raises
    ------
    ValueError
        If ``name`` is not an identifier or is a keyword.
    """
    if not isinstance(name, str) or not name.isidentifier() or keyword.iskeyword(name):
        raise ValueError(f"name must be a Python identifier that is not a keyword (it names the generated "
                         f"module's file), got {name!r}")
    path = generated_cache_dir() / f"{name}_{key[:24]}.py"
    data = read_entry(path, key)
    if data is not None:
        try:
            return data.decode("utf-8")
        except UnicodeDecodeError:          # recorded as written: only a foreign record gets here
            warn_once(f"cache entry {path}", f"nonholo: ignored the cache entry {path}: it is not "
                                             "text; rebuilding it")
    source = build()
    try:
        write_entry(path, source.encode("utf-8"), key)
    except OSError as exc:
        warn_once("generated cache", f"nonholo: could not cache the generated module of {name!r} ({exc})")
    return source
