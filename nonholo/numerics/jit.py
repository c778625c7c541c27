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

import functools
import types
import warnings

#: Options of every compiled function of the package: no GIL held, IEEE arithmetic with
#: NumPy's error model (a division by zero gives inf, not an exception).
JIT_OPTIONS = dict(nogil=True, error_model="numpy", fastmath=False)

_warned: set[str] = set()
_cache_class = None


def _warn_once(key: str, message: str) -> None:
    if key not in _warned:
        _warned.add(key)
        warnings.warn(message, RuntimeWarning, stacklevel=3)


def tolerant_cache_class() -> type:
    """numba's on-disk cache of one function, where a damaged entry is a miss, not an error
    (a subclass of numba's ``FunctionCache``, made when numba is first needed).

    Returns
    -------
    type
        The class; ``TolerantCache(py_func)`` is the cache of ``py_func``.
    """
    global _cache_class
    if _cache_class is None:
        from numba.core.caching import FunctionCache

        class TolerantCache(FunctionCache):
            def load_overload(self, sig, target_context):
                try:
                    return super().load_overload(sig, target_context)
                except Exception as exc:        # pickle, zlib, EOF, OS errors of a bad entry
                    _warn_once(f"load {self._name}", f"nonholo: discarded a damaged numba cache entry of "
                               f"{self._name} ({type(exc).__name__}: {exc}); compiling it again")
                    try:
                        self.flush()
                    except OSError:
                        pass
                    return None

            def save_overload(self, sig, data):
                try:
                    super().save_overload(sig, data)
                except Exception as exc:        # full disk, lost permission, damaged index
                    _warn_once(f"save {self._name}", f"nonholo: could not write the numba cache of "
                               f"{self._name} ({type(exc).__name__}: {exc}); it will be compiled again "
                               "in the next process")

        _cache_class = TolerantCache
    return _cache_class


class LazyDispatcher:
    """A function to be compiled by numba, which is imported and asked to compile only when
    the function is first used (called, or read as an attribute such as ``py_func``), so
    that ``import nonholo`` does not load numba where the native kernels serve.

    Parameters
    ----------
    func : callable
        The Python function.
    cache : bool
        Keep the compiled code on disk.
    options : dict
        numba options.
    """

    def __init__(self, func, cache: bool, options: dict):
        functools.update_wrapper(self, func)        # name, module, docstring, __wrapped__
        self._args = (cache, options)
        self._dispatcher = None

    def dispatcher(self):
        """The numba dispatcher, made on first use.

        Returns
        -------
        numba.core.registry.CPUDispatcher
            The compiled function.
        """
        if self._dispatcher is None:
            cache, options = self._args
            self._dispatcher = compile_now(self.__wrapped__, cache, options, resolve=False)
            resolve_lazy(self.__wrapped__)          # after: it may refer to itself
        return self._dispatcher

    def __call__(self, *args, **kwargs):
        return self.dispatcher()(*args, **kwargs)

    def __get__(self, obj, objtype=None):
        # a routine, as numba's dispatcher is (a method descriptor): documented as a function
        return self if obj is None else types.MethodType(self, obj)

    def __getattr__(self, name):
        if name.startswith("__") or name in ("_args", "_dispatcher"):
            raise AttributeError(name)
        return getattr(self.dispatcher(), name)

    def __repr__(self) -> str:
        state = "compiled" if self._dispatcher is not None else "not yet compiled"
        return f"<numba function {self.__name__} ({state})>"


def resolve_lazy(func) -> None:
    """Replace the :class:`LazyDispatcher` objects ``func`` refers to (its globals and
    closure) by their numba dispatchers, as numba's typing of ``func`` requires.

    Parameters
    ----------
    func : callable
        A Python function about to be compiled.
    """
    namespace = getattr(func, "__globals__", None) or {}
    for key, value in list(namespace.items()):
        if isinstance(value, LazyDispatcher):
            namespace[key] = value.dispatcher()
    for cell in getattr(func, "__closure__", None) or ():
        try:
            value = cell.cell_contents
        except ValueError:                          # an empty cell
            continue
        if isinstance(value, LazyDispatcher):
            cell.cell_contents = value.dispatcher()


def compile_now(f, cache: bool, opts: dict, resolve: bool = True):
    """``numba.njit(**opts)(f)`` with the tolerant disk cache (see the module docstring).

    Parameters
    ----------
    f : callable
        The Python function.
    cache : bool
        Keep the compiled code on disk.
    opts : dict
        numba options.
    resolve : bool
        First :func:`resolve_lazy` ``f`` (numba compiles at the first call, so a caller may
        resolve it afterwards instead).

    Returns
    -------
    numba.core.registry.CPUDispatcher
        The compiled function.
    """
    import numba

    if resolve:
        resolve_lazy(f)
    if cache:
        try:
            dispatcher = numba.njit(cache=True, **opts)(f)
        except RuntimeError as exc:             # "cannot cache function ...: no locator"
            _warn_once("no cache", f"nonholo: no writable numba cache ({exc}); compiled "
                       "code is kept in memory only (set NUMBA_CACHE_DIR to a writable "
                       "directory to keep it between runs)")
        else:
            # numba keeps its cache object in Dispatcher._cache (set by enable_caching)
            dispatcher._cache = tolerant_cache_class()(f)
            return dispatcher
    return numba.njit(cache=False, **opts)(f)


def jit(func=None, *, cache: bool = True, lazy: bool = True, **options):
    """``numba.njit`` with :data:`JIT_OPTIONS` and the tolerant disk cache (see the module
    docstring). Usable as ``@jit`` or ``jit(f, ...)``.

    Parameters
    ----------
    func : callable, optional
        The function to compile (``None``: return a decorator).
    cache : bool
        Keep the compiled code on disk (:func:`tolerant_cache_class`).
    lazy : bool
        Import numba and make the dispatcher on first use (:class:`LazyDispatcher`).
    **options
        numba options, overriding :data:`JIT_OPTIONS`.

    Returns
    -------
    LazyDispatcher or numba.core.registry.CPUDispatcher or callable
        The compiled function, or a decorator without ``func``.
    """
    opts = {**JIT_OPTIONS, **options}

    def decorate(f):
        return LazyDispatcher(f, cache, opts) if lazy else compile_now(f, cache, opts)

    return decorate(func) if func is not None else decorate
