"""``retime()``: a successful plan played as fast as its legs or its inputs' bounds allow, in a
given time, or from rest to rest.

:func:`retime` wraps a plan's controls in a time change (:mod:`nonholo.motion.time_scaling`):
:class:`~nonholo.motion.speed_limits.Retimed` keeps every leg at most ``leg_speed`` fast — at that
speed throughout for the least time (``T=None``), at ``leg_speed · T̃/T`` for a longer
``T``, slower only where the path nearly stops (:data:`~nonholo.motion.speed_limits.FLOOR`: the
inputs turn there at a bounded rate); ``rest_to_rest=True`` plays the motion by the smoothstep time change
(:class:`~nonholo.motion.time_scaling.RestToRest`), which starts and ends at zero speed, for any
mechanism. The path is the plan's, so its certificate carries over unchanged: the re-timed
motion ends where the plan's does, with the same error bound, least ``|Δ|``, sensitivity
and legs' lengths. The result's samples are the plan's, at the played instants ``t(τ_k)``
of its step points. :func:`limit_speed` is what :func:`nonholo.plan` does with a
``leg_speed``.

Under :class:`~nonholo.model.bounds.InputBounds` the same is done to the inputs
(:class:`~nonholo.motion.speed_limits.InputRetimed`): ``T=None`` plays the path in the least time
that keeps every input within its bounds — the least time *along the planned path*, not the
least time of the problem (another path may be faster; finding it is a time-optimal control
problem this does not solve). :func:`limit_inputs` is what :func:`nonholo.plan` does with
them: with ``T=None`` the least time along the path; with a given ``T`` the plan as found if
its inputs keep the bounds, else re-timed in ``T`` if its path can be, else a failure saying
the time the path needs (which :func:`nonholo.plan` then answers with the path of least use
of the bounds in ``T``, :func:`nonholo.planning.least_time.within_bounds`). Every re-timing under input bounds is checked on a fine grid
(:data:`CHECK_STEPS`): inputs beyond a bound by more than
:data:`~nonholo.model.bounds.BOUND_RTOL` (relative) make the plan a failure.
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np

from ..io.result import PlanResult
from ..motion.frame_controls import from_dict as controls_from_dict
from ..model.bounds import InputBounds, input_names
from ..motion.speed_limits import (
    RETIME_NODES,
    InputRetimed,
    InputTimeMap,
    Retimed,
    TimeMap,
    check_leg_speed,
    node_count,
)
from ..motion.time_scaling import PEAK_RATIO, RestToRest, check_horizon, planned, played_time


#: Steps of the grid on which re-timed inputs are checked against their bounds, at least (three
#: points each: the ends and the middle).
CHECK_STEPS = 4 * RETIME_NODES


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
    return planned(result.parametrisation)


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


def check_input_bounds(value, mechanism) -> InputBounds | None:
    """``input_bounds`` as :func:`retime` takes it.

    Parameters
    ----------
    value : InputBounds or None
        The bounds, or ``None``.
    mechanism : Mechanism
        The plan's mechanism.

    Returns
    -------
    InputBounds or None
        The bounds checked against ``mechanism``; ``None`` for none (or bounds free
        everywhere).

    Raises
    ------
    ValueError
        Naming ``input_bounds``, for anything else.
    """
    if value is None:
        return None
    if not isinstance(value, InputBounds):
        raise ValueError(f"input_bounds must be nonholo.constraints.InputBounds or None, got {type(value).__name__}")
    try:
        bounds = value.check(mechanism)
    except ValueError as exc:
        raise ValueError(f"input_bounds: {exc}") from None
    return None if bounds.free else bounds


def input_time_map(result: PlanResult, bounds: InputBounds, nodes: int = RETIME_NODES) -> InputTimeMap:
    """The fastest re-timing of ``result``'s path under input bounds.

    Parameters
    ----------
    result : PlanResult
        A plan.
    bounds : InputBounds
        The bounds, checked against its mechanism.
    nodes : int
        Nodes the inputs are splined through.

    Returns
    -------
    InputTimeMap
        Its ``minimum_time`` and ``peak_ratio``.
    """
    return InputTimeMap(planned_controls(result), bounds, None, nodes)


def input_excess(controls, bounds: InputBounds, mechanism, steps: int) -> str | None:
    """Where ``controls`` leave ``bounds`` by more than
    :data:`~nonholo.model.bounds.BOUND_RTOL`, on a grid of ``steps`` steps (three points
    each).

    Parameters
    ----------
    controls : Controls or TimeChange
        The physical controls as played.
    bounds : InputBounds
        The bounds, checked.
    mechanism : Mechanism
        The mechanism (the inputs' names).
    steps : int
        Steps of the grid, at least (rounded up to a multiple of the controls' grid).

    Returns
    -------
    str or None
        The input out the most, when and by how much; ``None`` within.
    """
    steps = node_count(controls, steps)
    t = (np.arange(steps)[:, None] + np.array([0.0, 0.5, 1.0])[None, :]).ravel() * (controls.T / steps)
    t[-1] = controls.T
    u = np.asarray(controls(t), dtype=float).reshape(t.size, -1)
    return bounds.excess(u, t, input_names(mechanism))


def retime(result: PlanResult, leg_speed: float | None = None, T: float | None = None, *,
           rest_to_rest: bool = False, input_bounds: InputBounds | None = None) -> PlanResult:
    """``result`` re-timed: every leg at most ``leg_speed`` fast or every input within
    ``input_bounds``, and/or from rest to rest.

    Parameters
    ----------
    result : PlanResult
        A successful plan (of a mechanism with legs, for a ``leg_speed``).
    leg_speed : float, optional
        The legs' top speed (the geometry's length units per second). With
        ``rest_to_rest``, ``None`` keeps the bound the plan's options record, if any.
    T : float, optional
        The time of the re-timed motion (s); ``None``: the least time under ``leg_speed``
        or ``input_bounds`` (along the plan's path), or, rest to rest without a bound, the
        plan's time.
    rest_to_rest : bool
        Play the motion by the smoothstep time change
        (:class:`~nonholo.motion.time_scaling.RestToRest`): its inputs are zero at ``0`` and
        ``T``. Under a bound it wraps the fastest re-timing, stretched by the smoothstep's
        peak ratio 15/8 so that no leg (or input) exceeds the bound.
    input_bounds : InputBounds, optional
        Bounds on the inputs (:class:`~nonholo.model.bounds.InputBounds`, ``low < 0 <
        high``), instead of a ``leg_speed``. With ``rest_to_rest``, ``None`` keeps the
        bounds the plan's options record, if any.

    Returns
    -------
    PlanResult
        A new result whose controls are :class:`~nonholo.motion.speed_limits.Retimed`,
        :class:`~nonholo.motion.speed_limits.InputRetimed` and/or
        :class:`~nonholo.motion.time_scaling.RestToRest` of the planned controls (a re-timed
        plan is re-timed from its planned controls); ``options`` records ``leg_speed`` or
        ``input_bounds``. Under ``input_bounds`` a re-timing whose inputs leave them on the
        check's grid (:func:`input_excess`) is returned as a failure saying where.

    Raises
    ------
    ValueError
        For a failed plan, a plan of a mechanism with drift (whose path a time change does
        not keep), a mechanism without legs under a ``leg_speed``, no bound
        without ``rest_to_rest``, both a ``leg_speed`` and ``input_bounds``, a bad
        ``leg_speed``, ``input_bounds``, ``T`` or ``rest_to_rest``, a ``T`` shorter than the
        path needs under the bound (the message says how long it needs), or a ``T`` whose
        inputs are not finite (below :data:`~nonholo.motion.time_scaling.MIN_TIME`, naming
        ``T``).
    """
    started = time.perf_counter()
    if not isinstance(result, PlanResult):
        raise ValueError(f"result must be a PlanResult, got {type(result).__name__}")
    if not isinstance(rest_to_rest, (bool, np.bool_)):
        raise ValueError(f"rest_to_rest must be True or False, got {rest_to_rest!r}")
    mech = result.kinematics
    if leg_speed is None and input_bounds is None and rest_to_rest:
        leg_speed = result.options.get("leg_speed")
        recorded = result.options.get("input_bounds")
        if leg_speed is None and recorded is not None:
            input_bounds = InputBounds.from_record(recorded, mech, "options.input_bounds")
    v = check_leg_speed(leg_speed, mech)
    bounds = check_input_bounds(input_bounds, mech)
    if bounds is not None and not bounds.holds_zero:
        raise ValueError(f"input_bounds: the bound {bounds.off_zero(mech)} does not hold 0 inside (low < 0 < high): "
                         f"a re-timing along the path slows the motion to rest where it turns; plan with "
                         f"objective='time', which scales the whole motion's time by one factor")
    if v is not None and bounds is not None:
        raise ValueError("leg_speed and input_bounds cannot be kept together yet (each re-times the path "
                         "on its own): give one of them")
    if v is None and bounds is None and not rest_to_rest:
        raise ValueError("leg_speed must be a positive finite speed, got None (or pass input_bounds, or "
                         "rest_to_rest=True)")
    if T is not None:
        T = check_horizon(T)
    if not result.success:
        raise ValueError(f"only a successful plan can be re-timed; this one failed: {result.reason}")
    if mech.has_drift:
        raise ValueError(f"result: mechanism {mech.name!r} has drift (its state moves at rest), so a plan of it "
                         "cannot be re-timed: a time change keeps the path of a driftless system only; plan "
                         "again with the time T wanted")
    base = planned_controls(result)
    timed, how = base, []
    if v is not None or bounds is not None:
        # the re-timed controls exactly as a plan file rebuilds them (its base read back from
        # its description, the time map recomputed from that): the time map is computed from a
        # replay of the base, whose rounding a kink of the fastest leg can amplify, so samples
        # computed from any other copy need not be ``controls(t)`` of the loaded plan
        T_map = None if rest_to_rest else T
        changed = (Retimed(base, result.R0, mech, v, T=T_map) if v is not None
                   else InputRetimed(base, bounds, T=T_map))
        timed = controls_from_dict(changed.to_dict(), mech)
        needs = timed.map.minimum_time * (PEAK_RATIO if rest_to_rest else 1.0)
        kept = (f"every leg at most {v:g} fast" if v is not None
                else f"every input within its bounds ({bounds.text(input_names(mech))})")
        if rest_to_rest and T is not None and T < needs:
            raise ValueError(f"T = {T:g} s is shorter than the {needs:.6g} s this path needs from rest to rest "
                             f"with {kept}")
        how.append(f"with {kept} (the path needs {needs:.6g} s"
                   + (" from rest to rest)" if rest_to_rest else ")"))
    if rest_to_rest:
        duration = T if T is not None else timed.T * (PEAK_RATIO if v is not None or bounds is not None else 1.0)
        timed = controls_from_dict(RestToRest(timed, duration).to_dict(), mech)
        how.insert(0, "from rest to rest")
    how.insert(0, "in the least time" if T is None and (v is not None or bounds is not None)
               else f"in T = {timed.T:g} s")
    n = len(result.t)
    tau = np.arange(n) * (base.T / result.steps)
    tau[-1] = base.T
    t = played_time(timed, tau)
    t[0], t[-1] = 0.0, timed.T
    u = timed(t).reshape(n, mech.n_inputs)
    if not np.all(np.isfinite(u)):
        raise ValueError(f"T = {timed.T:g} s is too short for this plan: its re-timed inputs are not finite")
    options = result.options
    if v is not None:
        options = {**options, "leg_speed": v}
    if bounds is not None:
        options = {**options, "input_bounds": bounds.record()}
    success, reason = result.success, f"{result.reason}; re-timed {' '.join(how)}"
    if bounds is not None:
        out = input_excess(timed, bounds, mech, max(CHECK_STEPS, result.replay_steps or 0))
        if out is not None:
            success, reason = False, f"{reason}, but {out}"
    return dataclasses.replace(
        result, success=success, parametrisation=timed, T=timed.T, t=t, u=u,
        reason=reason, options=options, made_by=None,
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


def limit_inputs(result: PlanResult, bounds: InputBounds | None, T: float | None) -> PlanResult:
    """What :func:`nonholo.plan` returns under input bounds (see the module).

    Parameters
    ----------
    result : PlanResult
        The planned path.
    bounds : InputBounds or None
        The bounds, checked; ``None``: ``result`` itself is returned.
    T : float or None
        ``None``: a success re-timed in the least time along its path. A given ``T``: a
        success whose inputs keep the bounds (on the check's grid) is returned as planned;
        one that does not is re-timed in ``T`` if its path needs no more, else fails saying
        the time it needs. A plan of a mechanism with drift, or under bounds off zero (played
        in its least time already, :func:`nonholo.planning.least_time.least_time_path`), is
        never re-timed: it is returned as planned where its inputs keep the bounds, else it
        fails saying so.

    Returns
    -------
    PlanResult
        The plan under the bounds; ``options`` records ``input_bounds`` either way.
    """
    if bounds is None:
        return result
    options = {**result.options, "input_bounds": bounds.record()}
    if not result.success:
        return dataclasses.replace(result, options=options)
    mech = result.kinematics
    if T is None and not mech.has_drift and bounds.holds_zero:
        return retime(result, input_bounds=bounds)
    steps = max(CHECK_STEPS, result.replay_steps or 0)
    out = input_excess(result.parametrisation, bounds, mech, steps)
    if out is None:
        return dataclasses.replace(result, options=options)
    if not bounds.holds_zero:
        # the least time played by one time factor (nonholo.planning.least_time), not re-timed
        reason = f"{result.reason}; but {out}"
        return dataclasses.replace(result, success=False, reason=reason, options=options)
    if mech.has_drift:
        reason = (f"the plan's inputs leave their bounds ({bounds.text(input_names(mech))}; {out.split(' (')[0]}), "
                  f"and a plan of a mechanism with drift cannot be re-timed into them: plan with "
                  f"objective='time' for the least time that keeps them")
        return dataclasses.replace(result, success=False, reason=reason, options=options)
    fastest = input_time_map(result, bounds)
    if fastest.minimum_time <= T:
        return retime(result, T=T, input_bounds=bounds)
    reason = (f"the planned path needs T >= {fastest.minimum_time:.6g} s to keep every input within its "
              f"bounds ({bounds.text(input_names(mech))}; in T = {T:g} s {out.split(' (')[0]}); "
              "plan with T=None for the least time")
    return dataclasses.replace(result, success=False, reason=reason, options=options)
