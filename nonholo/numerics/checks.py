"""Checks of the arguments users pass: each returns the value in canonical form or raises
``ValueError`` naming the argument."""
from __future__ import annotations

import numpy as np


#: The longest time accepted (s): about 30 years; a longer horizon scales the inputs
#: towards underflow and is a mistake of units, not a slower motion.
MAX_TIME = 1e9


def check_time(T, name: str = "T") -> float:
    """A positive finite time (s) as a float, at most :data:`MAX_TIME`: a real number
    (Python or NumPy), not a boolean or a string."""
    if not is_number(T):
        raise ValueError(f"{name} must be a positive finite time in seconds, got {T!r}")
    try:
        T = float(T)
    except OverflowError:                             # an int beyond the floats' range
        raise ValueError(f"{name} must be a positive finite time, got {T}") from None
    if not np.isfinite(T) or T <= 0:
        raise ValueError(f"{name} must be a positive finite time, got {T}")
    if T > MAX_TIME:
        raise ValueError(f"{name} must be at most {MAX_TIME:g} s, got {T:g}")
    return T


def real_array(value, name: str) -> np.ndarray:
    """``value`` (an array or nested sequences of numbers) as a float array; booleans,
    complex numbers, strings and other objects are refused with ``ValueError`` naming ``name``."""
    if isinstance(value, (str, bytes)):
        raise ValueError(f"{name} must be numbers, got a string")
    try:
        a = np.asarray(value)
    except (TypeError, ValueError) as exc:         # ragged nesting
        raise ValueError(f"{name} must be an array of numbers: {exc}") from None
    if a.dtype.kind not in "iuf" or (not isinstance(value, np.ndarray) and _holds_booleans(value)):
        what = {"b": "booleans", "c": "complex numbers", "U": "strings", "S": "strings"}.get(a.dtype.kind)
        raise ValueError(f"{name} must be real numbers, got {what or 'booleans or other objects'}")
    return a.astype(float)


def _holds_booleans(value) -> bool:
    """Whether nested sequences hold a boolean (NumPy casts ``[True, 0.5]`` to floats)."""
    if isinstance(value, (bool, np.bool_)):
        return True
    if isinstance(value, (list, tuple)):
        return any(_holds_booleans(v) for v in value)
    if isinstance(value, np.ndarray):
        return value.dtype.kind == "b"
    return False


#: Most integrator steps on ``[0, T]`` (the trajectory alone then takes 72 MB; more is a
#: mistake, not a finer plan: refine ``T``'s units or split the motion instead).
MAX_STEPS = 10**6


def is_number(x) -> bool:
    """Whether ``x`` is a real number (Python or NumPy), booleans excluded."""
    return isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, (bool, np.bool_))


def check_count(value, name: str, minimum: int = 1, maximum: int | None = None) -> int:
    """An integer ``≥ minimum`` (and ``≤ maximum``) (``harmonics``, ``grid``, ``steps``,
    ``max_iter``, ...); integral floats are accepted, booleans, infinities and non-numbers
    are not."""
    integral = isinstance(value, (int, np.integer)) or (is_number(value) and np.isfinite(value)
                                                         and int(value) == value)
    if not is_number(value) or not integral or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    if maximum is not None and value > maximum:
        raise ValueError(f"{name} must be at most {maximum}, got {int(value)}")
    return int(value)


def check_times(t, name: str = "t") -> np.ndarray:
    """Sample times as a float array, all finite (``ValueError`` naming the first bad one)."""
    try:
        t = np.asarray(t, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be a number or an array of numbers (s)") from None
    if not np.all(np.isfinite(t)):
        bad = t[~np.isfinite(t)].flat[0]
        raise ValueError(f"{name} must be finite, got {bad}")
    return t
