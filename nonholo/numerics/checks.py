"""Checks of the arguments users pass: each returns the value in canonical form or raises
``ValueError`` naming the argument."""
from __future__ import annotations

import numpy as np


def check_time(T, name: str = "T") -> float:
    """A positive finite time (s) as a float."""
    try:
        T = float(T)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be a positive finite time in seconds, got {T!r}") from None
    if not np.isfinite(T) or T <= 0:
        raise ValueError(f"{name} must be a positive finite time, got {T}")
    return T


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
