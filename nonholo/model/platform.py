"""The paper's orienting platform: ``Δ(R)``, ``L(R)``, ``Q(R, u)`` with checked inputs.

Backed by the generated module ``nonholo.generated.platform``. The system is
``dR/dt = [L(R) u] R`` (spatial angular velocity ``ω = L(R) u``), ``u = (u_1, u_2)`` the
scaled leg-extension rates ``u_i = d(l_i²)/dt / (4ab)``.
"""
from __future__ import annotations

import numpy as np

from ..generated import platform as _gen
from ..spaces.so3 import check_rotation

#: The coordinates the generated functions take: the platform's state is ``R`` alone.
_Q = np.zeros(0)


def _inputs(u) -> np.ndarray:
    v = np.asarray(u, dtype=float)
    if v.shape != (2,):
        raise ValueError(f"u must have length 2, got shape {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError("u has non-finite entries")
    return v


def delta(R) -> float:
    """Singularity function ``Δ(R) = r12 r31 + r21 r32`` (appendix, App. 1.1).

    Parameters
    ----------
    R : array_like
        A rotation matrix.

    Returns
    -------
    float
        ``Δ(R)``.
    """
    return float(_gen.delta(check_rotation(R), _Q))


def _finite(value: np.ndarray, name: str, R) -> np.ndarray:
    """``value`` if finite; else ``ValueError``: ``R`` is (numerically) on ``Δ = 0``."""
    if not np.all(np.isfinite(value)):
        d = _gen.delta(R, _Q)
        raise ValueError(f"R is too close to the singular surface Δ = 0 (Δ(R) = {d:.3g}): "
                         f"{name} is not representable in floating point there")
    return value


def L(R) -> np.ndarray:
    """``L(R)``: the spatial angular velocity ``ω = L(R) u``.

    Parameters
    ----------
    R : array_like
        A rotation matrix.

    Returns
    -------
    numpy.ndarray
        ``L(R)``, 3×2.

    Raises
    ------
    ValueError
        If ``R`` is not a rotation, or is on or numerically too close to the singular
        surface ``Δ(R) = 0`` (``L ~ 1/Δ``).
    """
    R = check_rotation(R)
    if _gen.delta(R, _Q) == 0.0:
        raise ValueError("R lies on the singular surface Δ(R) = 0, where L(R) is undefined")
    with np.errstate(all="ignore"):         # overflow is reported by _finite
        return _finite(_gen.L(R), "L(R)", R)


def Q(R, u) -> np.ndarray:
    """``Q(R, u)`` of eq. (12): ``(∂L/∂θ) u = Q s`` for ``∂R/∂θ = [s] R``.

    Parameters
    ----------
    R : array_like
        A rotation matrix.
    u : array_like
        The inputs ``(u_1, u_2)``.

    Returns
    -------
    numpy.ndarray
        ``Q(R, u)``, 3×3.

    Raises
    ------
    ValueError
        If ``R`` is not a rotation, ``u`` not two finite numbers, or ``R`` on or
        numerically too close to ``Δ = 0`` (``Q ~ 1/Δ²``).
    """
    R = check_rotation(R)
    if _gen.delta(R, _Q) == 0.0:
        raise ValueError("R lies on the singular surface Δ(R) = 0, where Q(R, u) is undefined")
    u = _inputs(u)
    with np.errstate(all="ignore"):         # overflow is reported by _finite
        return _finite(_gen.Q(R, u), "Q(R, u)", R)
