"""``retime()``: a successful plan played as fast as its legs allow, or in a given time.

:func:`retime` wraps a plan's controls in :class:`~nonholo.motion.retimed.Retimed`: the same path
of orientations, with every leg at most ``leg_speed`` fast — at that speed throughout for
the least time (``T=None``), at ``leg_speed · T̃/T`` for a longer ``T``. The path is the
plan's, so its certificate carries over unchanged: the re-timed motion ends where the
plan's does, with the same error bound, least ``|Δ|``, sensitivity and legs' lengths. The
result's samples are the plan's, at the re-timed instants ``t(τ_k)`` of its step points.
:func:`limit_speed` is what :func:`nonholo.plan` does with a ``leg_speed``.
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np

from ..io.result import PlanResult
from ..motion.frame_controls import from_dict as controls_from_dict
from ..motion.retimed import RETIME_NODES, Retimed, TimeMap, check_leg_speed
from ..numerics.checks import check_time


def planned_controls(result: PlanResult):
    """The controls a plan was planned with (a re-timed plan's base).

    Parameters
    ----------
    result : PlanResult
        A plan, re-timed or not.

    Returns
    -------
    Controls or FrameControls
        Its controls before any re-timing.
    """
    par = result.parametrisation
    return par.base if isinstance(par, Retimed) else par


def time_map(result: PlanResult, leg_speed: float, nodes: int = RETIME_NODES) -> TimeMap:
    """The fastest re-timing of ``result``'s path under ``leg_speed``.

    Parameters
    ----------
    result : PlanResult
        A plan of a mechanism with legs.
    leg_speed : float
        The legs' top speed (the geometry's length units per second).
    nodes : int
        Steps of the replay the legs' speeds are splined through.

    Returns
    -------
    TimeMap
        Its ``minimum_time`` and ``peak_ratio``.
    """
    mech = result.kinematics
    return TimeMap(planned_controls(result), result.R0, mech, check_leg_speed(leg_speed, mech), None, nodes)


def retime(result: PlanResult, leg_speed: float, T: float | None = None) -> PlanResult:
    """``result`` re-timed with every leg at most ``leg_speed`` fast.

    Parameters
    ----------
    result : PlanResult
        A successful plan of a mechanism with legs.
    leg_speed : float
        The legs' top speed (the geometry's length units per second).
    T : float, optional
        The time of the re-timed motion (s); ``None``: the least time.

    Returns
    -------
    PlanResult
        A new result whose controls are :class:`~nonholo.motion.retimed.Retimed` (a
        re-timed plan is re-timed from its own base); ``options`` records ``leg_speed``.

    Raises
    ------
    ValueError
        For a failed plan, a mechanism without legs, a bad ``leg_speed`` or ``T``, or a
        ``T`` shorter than the path needs (the message says how long it needs).
    """
    started = time.perf_counter()
    if not isinstance(result, PlanResult):
        raise ValueError(f"result must be a PlanResult, got {type(result).__name__}")
    mech = result.kinematics
    v = check_leg_speed(leg_speed, mech)
    if v is None:
        raise ValueError("leg_speed must be a positive finite speed, got None")
    if T is not None:
        T = check_time(T)
    if not result.success:
        raise ValueError(f"only a successful plan can be re-timed; this one failed: {result.reason}")
    base = planned_controls(result)
    # the re-timed controls exactly as a plan file rebuilds them (its base read back from
    # its description, the time map recomputed from that): the time map is computed from a
    # replay of the base, whose rounding a kink of the fastest leg can amplify, so samples
    # computed from any other copy need not be ``controls(t)`` of the loaded plan
    timed = controls_from_dict(Retimed(base, result.R0, mech, v, T=T).to_dict(), mech)
    n = len(result.t)
    tau = np.arange(n) * (base.T / result.steps)
    tau[-1] = base.T
    t = timed.time(tau)
    t[0], t[-1] = 0.0, timed.T
    how = "in the least time" if T is None else f"in T = {timed.T:g} s"
    reason = (f"{result.reason}; re-timed {how} with every leg at most {v:g} fast "
              f"(the path needs {timed.map.minimum_time:.6g} s)")
    return dataclasses.replace(
        result, parametrisation=timed, T=timed.T, t=t, u=timed(t).reshape(n, mech.n_inputs),
        reason=reason, options={**result.options, "leg_speed": v},
        seconds=None if result.seconds is None else result.seconds + (time.perf_counter() - started))


def limit_speed(result: PlanResult, leg_speed: float | None, T: float | None) -> PlanResult:
    """What :func:`nonholo.plan` returns for a ``leg_speed``.

    Parameters
    ----------
    result : PlanResult
        The planned path.
    leg_speed : float or None
        The legs' top speed; ``None``: ``result`` itself is returned.
    T : float or None
        ``None``: a success re-timed in the least time. A given ``T``: a success whose legs
        keep to the bound is returned as planned; one that does not is re-timed in ``T`` if
        its path needs no more, else fails saying the time it needs.

    Returns
    -------
    PlanResult
        The plan under the bound; ``options`` records ``leg_speed`` either way.
    """
    if leg_speed is None:
        return result
    if not result.success:
        return dataclasses.replace(result, options={**result.options, "leg_speed": leg_speed})
    if T is None:
        return retime(result, leg_speed)
    fastest = time_map(result, leg_speed)
    if fastest.peak_ratio <= 1.0:
        return dataclasses.replace(result, options={**result.options, "leg_speed": leg_speed})
    if fastest.minimum_time <= T:
        return retime(result, leg_speed, T)
    reason = (f"the planned path needs T >= {fastest.minimum_time:.6g} s to keep every leg at most "
              f"{leg_speed:g} fast (its legs reach {fastest.peak_ratio * leg_speed:.4g} in T = {T:g} s); "
              "plan with T=None for the least time")
    return dataclasses.replace(result, success=False, reason=reason,
                               options={**result.options, "leg_speed": leg_speed})
