"""Compilation with numba: the package's options, and a disk cache that never stops a run.

Numba keeps compiled code on disk (next to the source, or in ``NUMBA_CACHE_DIR``), so that
only the first run compiles. Two situations must not break the package:

- no writable cache location (a system installation, a container with a read-only
  home): numba refuses ``cache=True`` when the function is decorated, which would make
  ``import nonholo`` fail. Such functions are compiled without a disk cache instead (one
  warning per process); a failed write of a cache entry is likewise only a warning;
- a damaged cache entry (e.g. a file truncated when a run was killed): numba raises when
  it loads it, in every later run. Loading is guarded: the function's cache index is
  emptied, the entry counts as missing and is compiled and written anew (one warning).
"""
from __future__ import annotations

import warnings

import numba
from numba.core.caching import FunctionCache

#: Options of every compiled function of the package: no GIL held, IEEE arithmetic with
#: NumPy's error model (a division by zero gives inf, not an exception).
JIT_OPTIONS = dict(nogil=True, error_model="numpy", fastmath=False)

_warned: set[str] = set()


def _warn_once(key: str, message: str) -> None:
    if key not in _warned:
        _warned.add(key)
        warnings.warn(message, RuntimeWarning, stacklevel=3)


class TolerantCache(FunctionCache):
    """numba's on-disk cache of one function, where a damaged entry is a miss, not an error.

    Parameters
    ----------
    py_func : callable
        The Python function compiled.
    """

    def load_overload(self, sig, target_context):
        """numba's load of a cache entry; a damaged entry is discarded (one warning).

        Parameters
        ----------
        sig : numba signature
            The entry's signature.
        target_context : numba target context
            Where the code is loaded.

        Returns
        -------
        object or None
            The compiled overload, or ``None`` (a miss) for a missing or damaged entry.
        """
        try:
            return super().load_overload(sig, target_context)
        except Exception as exc:                    # pickle, zlib, EOF, OS errors of a bad entry
            _warn_once(f"load {self._name}", f"nonholo: discarded a damaged numba cache entry of "
                       f"{self._name} ({type(exc).__name__}: {exc}); compiling it again")
            try:
                self.flush()
            except OSError:
                pass
            return None

    def save_overload(self, sig, data):
        """numba's write of a cache entry; a failed write is a warning (once), not an error.

        Parameters
        ----------
        sig : numba signature
            The entry's signature.
        data : object
            The compiled overload.
        """
        try:
            super().save_overload(sig, data)
        except Exception as exc:                    # full disk, lost permission, damaged index
            _warn_once(f"save {self._name}", f"nonholo: could not write the numba cache of "
                       f"{self._name} ({type(exc).__name__}: {exc}); it will be compiled again "
                       "in the next process")


def jit(func=None, *, cache: bool = True, **options):
    """``numba.njit`` with :data:`JIT_OPTIONS` and the tolerant disk cache (see the module
    docstring). Usable as ``@jit`` or ``jit(f, ...)``.

    Parameters
    ----------
    func : callable, optional
        The function to compile (``None``: return a decorator).
    cache : bool
        Keep the compiled code on disk (:class:`TolerantCache`).
    **options
        numba options, overriding :data:`JIT_OPTIONS`.

    Returns
    -------
    numba.core.registry.CPUDispatcher or callable
        The compiled function, or a decorator without ``func``.
    """
    opts = {**JIT_OPTIONS, **options}

    def compile_lazily(f):
        if cache:
            try:
                dispatcher = numba.njit(cache=True, **opts)(f)
            except RuntimeError as exc:             # "cannot cache function ...: no locator"
                _warn_once("no cache", f"nonholo: no writable numba cache ({exc}); compiled "
                           "code is kept in memory only (set NUMBA_CACHE_DIR to a writable "
                           "directory to keep it between runs)")
            else:
                # numba keeps its cache object in Dispatcher._cache (set by enable_caching)
                dispatcher._cache = TolerantCache(f)
                return dispatcher
        return numba.njit(cache=False, **opts)(f)

    return compile_lazily(func) if func is not None else compile_lazily
