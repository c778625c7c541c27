"""Native kernels: C extension modules built from generated C, found or compiled once.

A native module ``nonholo.generated.native.<name>`` carries the digest of what its C was
translated from (``SOURCE_DIGEST``: the Python sources and the translator's, see
:func:`digest`), so that a module built from other sources is never used. :func:`load`
returns, in this order:

1. the module built at install: ``nonholo.generated.native.<name>`` (``pip install``
   compiles the catalog's C with the system compiler, see ``setup.py``), if its digest is
   the source's;
2. the module in the disk cache (:func:`cache_dir`), if built before from the same source;
3. a module compiled now with the system compiler (``cc``/``gcc``, the Python headers and
   NumPy's) into the disk cache;

or ``None`` where there is no compiler, the compilation fails, or ``NONHOLO_BACKEND=numba``
is set; the caller then compiles its kernels with numba, said once in a warning. The cache
is written atomically (a file renamed into place), so concurrent processes and killed runs
never leave a half-written module behind.

Nothing in the cache runs unverified. Every entry nonholo writes there (a compiled module,
or a generated module's source, :mod:`nonholo.model.mechanism`) gets a record beside it,
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
import importlib
import importlib.machinery
import importlib.util
import json
import os
import shutil
import stat
import subprocess
import sysconfig
import tempfile
import warnings
from pathlib import Path

from .c_translation import TranslationError

#: Environment variable choosing the kernels' backend: ``native`` (the default: C where a
#: compiler is found, else numba) or ``numba``.
BACKEND_ENV = "NONHOLO_BACKEND"
#: Environment variable naming the disk cache of compiled modules (default: the user's cache).
CACHE_ENV = "NONHOLO_CACHE_DIR"
#: The compiler's flags: optimised, no contraction into fused multiply-adds (the numba
#: kernels' arithmetic, operation for operation), position-independent.
CFLAGS = ("-O2", "-fno-math-errno", "-ffp-contract=off", "-fPIC", "-shared", "-std=gnu99",
          "-Wno-unused-variable", "-Wno-unused-but-set-variable")

#: The suffix of the record nonholo writes beside a cache entry (:func:`write_entry`).
RECORD_SUFFIX = ".sha256.json"
#: The largest cache entry read (bytes).
ENTRY_LIMIT = 256 * 2**20
#: The largest record read (bytes).
RECORD_LIMIT = 4096

_LOADED: dict[str, object] = {}
_WARNED: set[str] = set()


class RefusedEntry(Exception):
    """A cache entry that is not used (the message says why)."""


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


def enabled() -> bool:
    """Whether native kernels are wanted.

    Returns
    -------
    bool
        True unless ``NONHOLO_BACKEND`` is ``numba``.

    Raises
    ------
    ValueError
        If ``NONHOLO_BACKEND`` is neither ``native`` nor ``numba``.
    """
    value = os.environ.get(BACKEND_ENV, "native").strip().lower()
    if value not in ("native", "numba"):
        raise ValueError(f"{BACKEND_ENV} must be 'native' or 'numba', not {value!r}")
    return value == "native"


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


def compiler() -> str | None:
    """The C compiler: ``$CC``, Python's own, ``cc`` or ``gcc``, whichever is found first.

    Returns
    -------
    str or None
        Its path, ``None`` if none is found.
    """
    for cand in (os.environ.get("CC"), (sysconfig.get_config_var("CC") or "").split(" ")[0], "cc", "gcc"):
        if cand and shutil.which(cand):
            return shutil.which(cand)
    return None


def include_dirs() -> list[str]:
    """The headers a native module needs: Python's and NumPy's.

    Returns
    -------
    list of str
        The include directories.
    """
    import numpy

    return [sysconfig.get_paths()["include"], numpy.get_include()]


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


def installed(name: str, want: str):
    """The module built at install, if it is of the sources' digest.

    Parameters
    ----------
    name : str
        The module's name in ``nonholo.generated.native``.
    want : str
        The digest of the sources (:func:`digest`).

    Returns
    -------
    module or None
        The module, ``None`` if it is absent or built from other sources.
    """
    try:
        module = importlib.import_module(f"nonholo.generated.native.{name}")
    except ImportError:
        return None
    return module if getattr(module, "SOURCE_DIGEST", None) == want else None


def compile_module(name: str, source: str, target: Path, key: str | None = None) -> None:
    """Compile C into an extension module file (atomically), with its record when ``key``
    is given (:func:`write_entry`).

    Parameters
    ----------
    name : str
        The module's name.
    source : str
        Its C source.
    target : pathlib.Path
        The file to write.
    key : str, optional
        What it is built from (the sources' digest), recorded with the file's hash.

    Raises
    ------
    RuntimeError
        With the compiler's message, if there is no compiler or the compilation fails.
    """
    cc = compiler()
    if cc is None:
        raise RuntimeError("no C compiler found (set CC)")
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=target.parent) as tmp:
        src = Path(tmp) / f"{name}.c"
        src.write_text(source)
        out = Path(tmp) / target.name
        cmd = [cc, *CFLAGS, *(f"-I{d}" for d in include_dirs()), str(src), "-o", str(out), "-lm"]
        run = subprocess.run(cmd, capture_output=True, text=True, check=False)
        if run.returncode != 0:
            raise RuntimeError(f"compiling {name} failed:\n{run.stderr[-4000:]}")
        if key is None:
            os.chmod(out, 0o600)
            os.replace(out, target)
        else:
            write_entry(target, out.read_bytes(), key)


def load(name: str, want: str, source):
    """The native module ``nonholo.generated.native.<name>`` of a digest (the module
    docstring says where it is found; a cached one is verified before it is imported,
    :func:`read_entry`).

    Parameters
    ----------
    name : str
        The module's name.
    want : str
        Its ``SOURCE_DIGEST``.
    source : callable
        ``source()``: its C source, when it must be compiled.

    Returns
    -------
    module or None
        The module; ``None`` where native kernels are not wanted or cannot be built (one
        warning).

    Raises
    ------
    ValueError
        If ``NONHOLO_BACKEND`` is neither ``native`` nor ``numba`` (:func:`enabled`), or
        ``name`` is not an identifier.
    """
    if not enabled():
        return None
    if not isinstance(name, str) or not name.isidentifier():
        raise ValueError(f"name must be a Python identifier (it names the module and its file), got {name!r}")
    key = f"{name}:{want}"
    if key in _LOADED:
        return _LOADED[key]
    module = installed(name, want)
    if module is None:
        suffix = sysconfig.get_config_var("EXT_SUFFIX") or ".so"
        target = cache_dir() / f"{name}_{want[:16]}{suffix}"
        try:
            data = read_entry(target, want)            # verified before anything in it runs
            if data is None:
                compile_module(name, source(), target, key=want)
                data = read_entry(target, want)
                if data is None:
                    raise RuntimeError(f"{target} could not be read back once compiled")
            module = import_verified(f"nonholo.generated.native.{name}", data, target)
            if getattr(module, "SOURCE_DIGEST", None) != want:
                raise RuntimeError(f"{target} does not hold the expected kernels")
        except (OSError, RuntimeError, ImportError, TranslationError) as exc:
            warn_once("native", f"nonholo: native kernels unavailable ({str(exc).splitlines()[0]}); "
                                f"compiling them with numba instead (slower to start)")
            module = None
    _LOADED[key] = module
    return module
