"""Native kernels: C extension modules built from generated C, found or compiled once.

A native module ``nonholo.generated.native.<name>`` carries the digest of what its C was
translated from (``SOURCE_DIGEST``: the Python sources and the translator's, see
:func:`nonholo.codegen.cache.digest`), so that a module built from other sources is never
used. :func:`load` returns, in this order:

1. the module built at install: ``nonholo.generated.native.<name>`` (``pip install``
   compiles the catalog's C with the system compiler, see ``setup.py``), if its digest is
   the source's;
2. the module in the disk cache (:func:`nonholo.codegen.cache.cache_dir`), if built before
   from the same source;
3. a module compiled now with the system compiler (``cc``/``gcc``, the Python headers and
   NumPy's) into the disk cache;

or ``None`` where there is no compiler, the compilation fails, or ``NONHOLO_BACKEND=numba``
is set; the caller then compiles its kernels with numba, said once in a warning. The cache
is written atomically (a file renamed into place), so concurrent processes and killed runs
never leave a half-written module behind. :func:`native_kernels` loads the integrator's
kernels of a mechanism (:mod:`nonholo.codegen.emit`) so.

Nothing in the cache runs unverified: every entry is written and read by
:mod:`nonholo.codegen.cache` (a record of its hash beside it, checked before it is
used; a compiled module imported from the very bytes checked). The modules built at install
(``nonholo.generated.native``) are part of the installation, not of the cache.
"""
from __future__ import annotations

import importlib
import os
import shutil
import subprocess
import sysconfig
import tempfile
from pathlib import Path

from .c_config import C
from .c_subset import TranslationError
from .cache import cache_dir, import_verified, read_entry, warn_once, write_entry
from .python_config import PYTHON

#: Environment variable choosing the kernels' backend: ``native`` (the default: C where a
#: compiler is found, else numba) or ``numba``.
BACKEND_ENV = "NONHOLO_BACKEND"

_LOADED: dict[str, object] = {}


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
    value = os.environ.get(BACKEND_ENV, C.backend).strip().lower()
    if value not in (C.backend, PYTHON.backend):
        raise ValueError(f"{BACKEND_ENV} must be {C.backend!r} or {PYTHON.backend!r}, not {value!r}")
    return value == C.backend


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


def installed(name: str, want: str):
    """The module built at install, if it is of the sources' digest.

    Parameters
    ----------
    name : str
        The module's name in ``nonholo.generated.native``.
    want : str
        The digest of the sources (:func:`nonholo.codegen.cache.digest`).

    Returns
    -------
    module or None
        The module, ``None`` if it is absent or built from other sources.
    """
    try:
        module = importlib.import_module(C.module_name(name))
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
        cmd = [cc, *C.cflags, *(f"-I{d}" for d in include_dirs()), str(src), "-o", str(out),
               *(f"-l{lib}" for lib in C.libraries)]
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
        target = cache_dir() / f"{name}_{want[:16]}{C.suffix()}"
        try:
            data = read_entry(target, want)            # verified before anything in it runs
            if data is None:
                compile_module(name, source(), target, key=want)
                data = read_entry(target, want)
                if data is None:
                    raise RuntimeError(f"{target} could not be read back once compiled")
            module = import_verified(C.module_name(name), data, target)
            if getattr(module, "SOURCE_DIGEST", None) != want:
                raise RuntimeError(f"{target} does not hold the expected kernels")
        except (OSError, RuntimeError, ImportError, TranslationError) as exc:
            warn_once("native", f"nonholo: native kernels unavailable ({str(exc).splitlines()[0]}); "
                                f"compiling them with numba instead (slower to start)")
            module = None
    _LOADED[key] = module
    return module


def native_kernels(module, frame: bool, parts: dict):
    """The native kernels of a system of a generated module (:func:`load`).

    Parameters
    ----------
    module : module
        The mechanism's generated module.
    frame : bool
        Whether the system is the frame's.
    parts : dict
        The integrator's own pieces (:func:`nonholo.codegen.emit.functions`).

    Returns
    -------
    dict or None
        ``{"forward": …, "forward_variational": …, "frame_inputs": …}``, or ``None`` where
        native kernels are unavailable (see :func:`load`).
    """
    if not enabled():
        return None
    from . import emit       # the emitters: loaded when a mechanism's kernels are built

    name = emit.module_name(module)
    lib = load(name, emit.source_digest(module, parts), lambda: emit.kernel_source(module, parts))
    if lib is None:
        return None
    system = "frame" if frame else "physical"
    return {kernel: getattr(lib, f"{kernel}__{system}", None) for kernel in emit.EXPORTED}
