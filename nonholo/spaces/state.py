"""The state of a mechanism — an orientation ``R``, coordinates ``q``, or both — its
terminal error, and the integrator's kernels called alike for every kind of state.

Conventions
-----------
- Internally every state is a pair ``(R, q)``: ``R`` (3×3) is the identity, untouched, for
  a mechanism without orientation, and ``q`` has shape ``(0,)`` for an SO(3) mechanism. A
  trajectory is the pair of stacks ``R`` ``(n, 3, 3)`` and ``q`` ``(n, k)``.
- The terminal error is the stacked vector ``e = (l, δq)`` of a variation ``s = (s_R, s_q)``
  (:mod:`derivations.state_space`): ``[l] = log(R_T R_dᵀ)`` (rad) with orientation, and
  ``δq = q_T − q_d`` with each angle coordinate wrapped into ``(−π, π]``. The planner asks
  ``s_T = −γ e`` as on SO(3); its scalar error is ``|e|``, which bounds both parts.
- The caller's states: a rotation matrix for an SO(3) mechanism, a vector of ``k``
  coordinates for an ``Rᵏ`` one, a pair ``(R, q)`` for an ``SO(3) × Rᵏ`` one
  (:func:`parse`).
"""
from __future__ import annotations

import numpy as np

from ..numerics import kernels
from .so3 import check_rotation

NO_COORDINATES = np.zeros(0)
IDENTITY = np.eye(3)


def expected(mechanism) -> str:
    """What a state of ``mechanism`` is, in words (for error messages)."""
    if not mechanism.beyond_so3:
        return "a rotation matrix (3×3)"
    names = ", ".join(mechanism.coordinates)
    k = mechanism.n_coordinates
    if mechanism.orientation:
        return f"a pair (R, q): a rotation matrix R (3×3) and the {k} coordinates q = ({names})"
    return f"a vector of its {k} coordinates ({names})"


def parse(mechanism, value, name: str) -> tuple[np.ndarray, np.ndarray]:
    """The caller's state ``value`` (argument ``name``) of ``mechanism`` as ``(R, q)``
    (see the module); ``ValueError`` saying what the mechanism expects otherwise."""
    want = f"{name} must be {expected(mechanism)} for mechanism {mechanism.name!r}"
    if not mechanism.beyond_so3:
        if isinstance(value, tuple):
            raise ValueError(f"{want}, got a pair")
        return check_rotation(value, name), NO_COORDINATES
    if mechanism.orientation:
        if not (isinstance(value, (tuple, list)) and len(value) == 2):
            raise ValueError(f"{want}, got {_kind(value)}")
        R = check_rotation(value[0], f"{name}[0] (the orientation)")
        return R, coordinates(mechanism, value[1], f"{name}[1] (the coordinates)", want)
    if isinstance(value, tuple) and len(value) == 2 and np.ndim(value[0]) == 2:
        raise ValueError(f"{want}, got a pair (R, q): this mechanism has no orientation")
    return IDENTITY.copy(), coordinates(mechanism, value, name, want)


def _kind(value) -> str:
    try:
        shape = np.shape(value)
    except ValueError:
        return type(value).__name__
    return f"an array of shape {shape}" if shape else type(value).__name__


def coordinates(mechanism, value, name: str, want: str | None = None) -> np.ndarray:
    """``value`` as the ``k`` finite coordinates of ``mechanism`` (``ValueError`` naming
    ``name`` otherwise)."""
    try:
        q = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(want or f"{name} must be {mechanism.n_coordinates} numbers") from None
    if q.shape != (mechanism.n_coordinates,):
        raise ValueError(f"{want or name + ' has the wrong shape'}: {name} has shape {q.shape}, "
                         f"expected ({mechanism.n_coordinates},)")
    if not np.all(np.isfinite(q)):
        raise ValueError(f"{name} must be finite, got {q}")
    return q


def public(mechanism, R, q):
    """The state ``(R, q)`` as the caller gives it (see :func:`parse`)."""
    if not mechanism.beyond_so3:
        return R
    return (R, q) if mechanism.orientation else q


def wrap(angle):
    """``angle`` wrapped into ``(−π, π]``."""
    return np.pi - np.mod(np.pi - angle, 2.0 * np.pi)


def coordinate_difference(mechanism, q, qd) -> np.ndarray:
    """``q − qd`` with the angle coordinates wrapped (works on stacks ``(n, k)``)."""
    d = np.asarray(q, dtype=float) - np.asarray(qd, dtype=float)
    if any(mechanism.angles):
        angles = np.asarray(mechanism.angles, dtype=bool)
        d[..., angles] = wrap(d[..., angles])
    return d


def error(mechanism, R, q, Rd, qd) -> tuple[np.ndarray, float, float]:
    """``(e, rotation error, coordinate error)``: the stacked terminal error ``e`` of the
    state ``(R, q)`` from the goal ``(Rd, qd)`` (module docstring) and the norms of its two
    parts (0 for a part the state does not have)."""
    parts = []
    rot = 0.0
    if mechanism.orientation:
        l, err = kernels.log_error(np.ascontiguousarray(R), np.ascontiguousarray(Rd))
        parts.append(l)
        rot = float(err)
    if not mechanism.beyond_so3:
        return parts[0], rot, 0.0
    dq = coordinate_difference(mechanism, q, qd)
    parts.append(dq)
    return np.concatenate(parts), rot, float(np.linalg.norm(dq))


def error_parts(mechanism, rotation: float, coordinates: float) -> dict:
    """The terminal error by part, as a result reports it: ``{"rotation": rad,
    "coordinates": mechanism's units}`` (the parts the state has)."""
    parts = {"rotation": float(rotation)} if mechanism.orientation else {}
    return {**parts, "coordinates": float(coordinates)}


def distance(mechanism, R, q, Rd, qd) -> float:
    """``|e|`` of :func:`error`."""
    e, rot, coord = error(mechanism, R, q, Rd, qd)
    return float(np.hypot(rot, coord))


def offset(mechanism, R0, q0, Rd, qd) -> np.ndarray:
    """The stacked displacement from start to goal, ``(log(R_d R0ᵀ), q_d − q0)`` (angles
    wrapped): the rates a constant input would have to produce over ``[0, 1]``."""
    e, _, _ = error(mechanism, Rd, qd, R0, q0)
    return e
