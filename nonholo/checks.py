"""Checks of the arguments users pass: each returns the value in canonical form or raises
``ValueError`` naming the argument."""
from __future__ import annotations

import numpy as np


def check_time(T, name: str = "T") -> float:
    """A positive finite time (s) as a float."""
    try:
        T = float(T)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {T!r}") from None
    if not np.isfinite(T) or T <= 0:
        raise ValueError(f"{name} must be a positive finite time, got {T}")
    return T


def check_count(value, name: str) -> int:
    """A positive integer (``harmonics``, ``grid``, ``steps``, ...)."""
    if isinstance(value, bool) or int(value) != value or value < 1:
        raise ValueError(f"{name} must be a positive integer, got {value!r}")
    return int(value)
