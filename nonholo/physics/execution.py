"""Playing a plan on a MuJoCo model, with touch-ups: :func:`execute`, which records each
stage in an :class:`~nonholo.physics.execution_record.Execution`.

The plan is played from rest to rest: re-timed so that its inputs vanish at both ends, in
``duration`` seconds (:func:`nonholo.planning.retime.retime` with ``rest_to_rest``), on the
model of its mechanism (:func:`nonholo.physics.models.model_for`). The model starts at rest
at the plan's start, settled; after the motion it is left to settle again and its state is
measured. That is the open-loop stage.

Each touch-up re-plans from the measured state to the plan's goal — with the plan's own
options — and plays the new plan the same way, from where the mechanism is, at rest. A
touch-up is played only when it is predicted to end nearer the goal than the mechanism is:
a large correction loop costs more tracking error than it removes. The prediction is a
model fitted to the stages played so far, never a trial run:

- the tracking error a played stage leaves grows with the size of its motion,
  :func:`motion_size` ``s = ∫|u| dt`` of its planned inputs, as ``a·s + b·s²`` with ``a, b ≥ 0``
  (a part linear in the motion, e.g. a rolling radius slightly off, and a quadratic one,
  e.g. lag): so a stage of size ``s_j`` that
  ended at ``|e_j|`` bounds a motion of size ``s`` by ``|e_j| · max(r, r²)``, ``r = s/s_j``.
  The least bound over the stages played, times :data:`MARGIN` (a stage's error is a sample
  of the model, not a bound), is the tracking term;
- the mechanism drifts at rest (e.g. friction creeping under the legs' weight) at the
  largest rate measured over the end of any played stage's settling (:data:`DRIFT_WINDOW`),
  for the whole time of the touch-up's motion and settling;
- the re-plan's own kinematic error (its terminal error and error bound) adds.

``|e|`` is the norm of the stacked error (:meth:`~nonholo.spaces.product.Product.norm`),
the quantity a plan's ``tol`` bounds. Touching up stops at the first touch-up not played:
once ``|e| ≤ tol`` of the plan (``result.options["tol"]``), when the re-plan is predicted to
end no nearer, or when it cannot be planned; that touch-up is recorded, with its reason and
the error unchanged. Hence the recorded errors do not grow from stage to stage as long as
the prediction holds.

Nothing is played on trust. The mechanism's model is chosen by its kinematics
(:func:`nonholo.physics.models.matching_model`); the settings lie in the ranges of
:mod:`nonholo.physics.contact`; ``duration`` is at most :data:`MAX_DURATION`, ``touch_ups`` at
most :data:`~nonholo.physics.execution_record.MAX_TOUCH_UPS`, and a stage's motion spans at
least :data:`MIN_MOTION_STEPS` and its motion and settling at most
:data:`~nonholo.physics.contact.MAX_STAGE_STEPS` MuJoCo steps — all checked before anything
is allocated or played. While playing, MuJoCo's warnings of bad positions, velocities,
accelerations or controls, and non-finite positions or velocities, are checked at every
sample: MuJoCo resets an unstable simulation and carries on, so a stage in which it did is
recorded with the outcome ``"unstable"`` and its reason, its error left at the one before it
(the state after a reset says nothing), and execution stops there. So is a stage with no
contact force at any sample: the mechanism left the contacts it rolls on (contacts too stiff
for the time step, say), and what was played is no longer the model.

Everything recorded is a function of the inputs alone — MuJoCo runs single-threaded and
deterministically, and no wall-clock time enters the simulation or a decision — except each
stage's real-time factor (simulated over wall time).
"""
# ruff: noqa: TRY004 (bad input is refused by a ValueError naming the argument, as across the package)
from __future__ import annotations

import math
import time

import numpy as np

from ..io.csv_export import states_at
from ..io.result import PlanResult
from ..numerics.checks import check_time
from ..planning.api import plan
from ..planning.settings import Settings, arguments_of
from ..spaces.state import State
from ..planning.retime import planned_controls, retime
from .contact import MAX_STAGE_STEPS, Contact, shown
from .execution_record import MAX_TOUCH_UPS, Execution
from .models import model_for

#: ``duration=None`` plays a plan in this many times its planned ``T``.
SLOWDOWN = 10.0
#: Spacing (s) of the samples of the motion kept for figures.
SAMPLE = 0.01
#: Keywords of :func:`nonholo.plan` a touch-up takes over from the plan's ``options``.
REPLAN_OPTIONS = ("gamma", "step", "tol", "max_iter", "newton_below", "min_step", "delta_min",
                  "harmonics", "grid", "steps", "route", "leg_length", "leg_speed", "objective")
#: Safety factor on the tracking term of a touch-up's predicted error (module docstring).
MARGIN = 2.0
#: The last fraction of a stage's settling over which its drift at rest is measured.
DRIFT_WINDOW = 0.5
#: The tolerance of a plan whose options record none (that of :func:`nonholo.plan`).
DEFAULT_TOL = Settings().tol
#: Largest ``duration`` (s) of a stage's motion (explicit or by default :data:`SLOWDOWN` × ``T``).
MAX_DURATION = 1000.0
#: Least number of MuJoCo steps a stage's motion spans (fewer would play it in a jump).
MIN_MOTION_STEPS = 10


def check_touch_ups(touch_ups, name: str = "touch_ups") -> int:
    """A number of touch-ups: a whole number in ``[0, MAX_TOUCH_UPS]``.

    Parameters
    ----------
    touch_ups : int
        The number.
    name : str
        The argument's name, for the message (``"--touch-ups"`` on the command line).

    Returns
    -------
    int
        ``touch_ups``.

    Raises
    ------
    ValueError
        Naming ``name``.
    """
    if isinstance(touch_ups, (bool, np.bool_)) or not isinstance(touch_ups, (int, np.integer)) \
            or not 0 <= touch_ups <= MAX_TOUCH_UPS:
        raise ValueError(f"{name} must be a whole number in [0, {MAX_TOUCH_UPS}] (MAX_TOUCH_UPS), "
                         f"got {shown(touch_ups)}")
    return int(touch_ups)


def check_duration(duration, name: str = "duration") -> float | None:
    """A stage's duration: ``None`` (the default) or a positive time of at most :data:`MAX_DURATION`.

    Parameters
    ----------
    duration : float or None
        Seconds.
    name : str
        The argument's name, for the message (``"--duration"`` on the command line).

    Returns
    -------
    float or None
        ``duration``.

    Raises
    ------
    ValueError
        Naming ``name``.
    """
    if duration is None:
        return None
    duration = check_time(duration, name)
    if duration > MAX_DURATION:
        raise ValueError(f"{name} must be at most {MAX_DURATION:g} s (MAX_DURATION), got {duration:g}")
    return duration


def stage_steps(T: float, contact: Contact) -> tuple[int, int]:
    """The MuJoCo steps of a stage whose motion takes ``T`` seconds: of its motion, and of
    its motion and settling.

    Parameters
    ----------
    T : float
        The motion's duration (s).
    contact : Contact
        Resolved settings (their ``timestep`` and ``settle``).

    Returns
    -------
    tuple of int
        ``(motion, total)``.
    """
    h = float(contact.timestep)
    n_move = max(math.ceil(T / h - 1e-9), 1)
    return n_move, n_move + round(float(contact.settle) / h)


def _steps_refused(T: float, contact: Contact, what: str) -> str | None:
    """Why a stage of ``T`` seconds is not played (its steps outside the bounds), or ``None``."""
    if not T <= MAX_DURATION:
        return f"{what} {T:g} s is longer than MAX_DURATION = {MAX_DURATION:g} s"
    n_move, n_total = stage_steps(T, contact)
    h = float(contact.timestep)
    if n_move < MIN_MOTION_STEPS:
        return (f"{what} {T:g} s spans {n_move} MuJoCo step(s) of timestep {h:g} s, fewer than "
                f"MIN_MOTION_STEPS = {MIN_MOTION_STEPS}: a longer duration or a finer timestep")
    if n_total > MAX_STAGE_STEPS:
        return (f"{what} {T:g} s and settling {float(contact.settle):g} s at timestep {h:g} s take "
                f"{n_total:.3g} MuJoCo steps, more than MAX_STAGE_STEPS = {MAX_STAGE_STEPS:.3g}: a shorter "
                "duration or a coarser timestep")
    return None


def check_steps(result: PlanResult, duration: float | None, contact: Contact, name: str = "duration") -> None:
    """Refuse a plan's open-loop stage of too few or too many MuJoCo steps
    (:data:`MIN_MOTION_STEPS`, :data:`~nonholo.physics.contact.MAX_STAGE_STEPS`), before
    anything is allocated.

    Parameters
    ----------
    result : PlanResult
        The plan.
    duration : float or None
        The stage's duration (s; ``None``: :data:`SLOWDOWN` × its planned ``T``), checked by
        :func:`check_duration`.
    contact : Contact
        The resolved settings of its model (their ``timestep`` and ``settle``).
    name : str
        The duration's name, for the message (``"--duration"`` on the command line).

    Raises
    ------
    ValueError
        Naming ``name`` and the time step.
    """
    what = name if duration is not None else f"{name} (by default {SLOWDOWN:g} × the plan's T)"
    why = _steps_refused(_stage_duration(result, duration), contact, what)
    if why is not None:
        raise ValueError(why)


def _check(result, touch_ups, duration, contact, progress):
    if not isinstance(result, PlanResult):
        raise ValueError(f"result must be a PlanResult, got {type(result).__name__}")
    if not result.success:
        raise ValueError(f"result: only a successful plan can be played; this one failed: {result.reason}")
    touch_ups = check_touch_ups(touch_ups)
    duration = check_duration(duration)
    if contact is not None and not isinstance(contact, Contact):
        raise ValueError(f"contact must be a Contact or None, got {type(contact).__name__}")
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be callable or None, got {type(progress).__name__}")
    return touch_ups, duration


def replan_options(result: PlanResult) -> dict:
    """The options a touch-up re-plans ``result``'s goal with, in their flat form
    (:func:`~nonholo.planning.settings.arguments_of` makes them :func:`nonholo.plan`'s
    arguments): its horizon, method and strategy, and the options of :data:`REPLAN_OPTIONS`
    it was planned with (its objective, ``None`` where it records none).

    Parameters
    ----------
    result : PlanResult
        The plan.

    Returns
    -------
    dict
        The flat options.
    """
    opts = {k: v for k, v in result.options.items() if k in REPLAN_OPTIONS}
    opts.update(T=planned_controls(result).T, method=result.method, strategy=result.strategy)
    opts.setdefault("objective", None)       # recorded only when the plan had one
    if "leg_speed" in opts:
        opts["T"] = result.T
    return opts


#: MuJoCo's warnings that mean the simulation went wrong (it resets itself on the first three).
WARNINGS = {"mjWARN_BADQACC": "bad accelerations", "mjWARN_BADQVEL": "bad velocities",
            "mjWARN_BADQPOS": "bad positions", "mjWARN_BADCTRL": "bad controls"}


def instability(m, d) -> str | None:
    """What MuJoCo reported wrong with a simulation so far, or ``None``: its warnings of
    :data:`WARNINGS` (counted since the data were last reset) and non-finite positions or
    velocities.

    Parameters
    ----------
    m, d : mujoco.MjModel, mujoco.MjData
        The simulation.

    Returns
    -------
    str or None
        The warnings and their counts, or ``None`` if there are none.
    """
    import mujoco

    found = []
    for name, what in WARNINGS.items():
        count = int(d.warning[int(getattr(mujoco.mjtWarning, name))].number)
        if count:
            found.append(f"{what} ({count} warning{'s' if count > 1 else ''})")
    if not (np.all(np.isfinite(d.qpos)) and np.all(np.isfinite(d.qvel))):
        found.append("non-finite positions or velocities")
    return "; ".join(found) or None


def _stage(sim, played, R, q):
    """Play ``played`` from the measured ``(R, q)`` and settle; the stage's numbers and
    trace, the measured state after it, and what went wrong (``None`` if nothing): MuJoCo's
    instability (:func:`instability`; the play stops at the first sample after it), or no
    contact force at any sample (the mechanism left its contacts)."""
    import mujoco

    model, m, d = sim
    model.follow(played, R, q)
    h = float(m.opt.timestep)
    T = float(played.T)
    n_move, n_total = stage_steps(T, model.contact)
    every = max(1, round(SAMPLE / h))
    times, Rs, qs, slips = [0.0], [], [], []
    R0, q0 = model.state(m, d)
    Rs.append(R0)
    qs.append(q0)
    slips.append(float(model.slip(m, d)))
    worst_slip, worst_force = 0.0, 0.0
    wall = 0.0
    wrong, steps = None, n_total
    for k in range(n_total):
        started = time.perf_counter()
        model.drive(m, d, k * h)
        mujoco.mj_step(m, d)
        wall += time.perf_counter() - started
        if (k + 1) % every == 0 or k + 1 == n_total:
            wrong = instability(m, d)
            if wrong is not None:              # MuJoCo reset it: what it holds now says nothing
                wrong = f"MuJoCo went unstable: {wrong} by t = {(k + 1) * h:.6g} s of the stage"
                steps = k + 1
                break
            # slip and forces at the samples: measuring them costs more than a step
            slip = float(model.slip(m, d))
            worst_slip = max(worst_slip, slip)
            worst_force = max(worst_force, float(model.contact_force(m, d)))
            Rk, qk = model.state(m, d)
            times.append((k + 1) * h)
            Rs.append(Rk)
            qs.append(qk)
            slips.append(slip)
    if wrong is None:
        mujoco.mj_forward(m, d)
        wrong = instability(m, d)
        if wrong is not None:
            wrong = f"MuJoCo went unstable: {wrong} by the end of the stage"
        elif not worst_force > 0:
            wrong = ("no contact force at any sample of the stage: the mechanism left the contacts it "
                     "rolls on")
    R_end, q_end = model.state(m, d)
    t = np.array(times)
    Rp, qp = states_at(played, np.minimum(t, float(played.t[-1])))
    trace = {"t": t, "R_planned": Rp, "q_planned": qp, "R": np.array(Rs), "q": np.array(qs),
             "slip": np.array(slips)}
    sim_time = steps * h
    numbers = {"max_slip": worst_slip, "max_contact_force": worst_force, "sim_time": sim_time,
               "real_time_factor": sim_time / wall if wall > 0 else 0.0, "duration": T}
    return numbers, trace, R_end, q_end, wrong


def motion_size(result: PlanResult) -> float:
    """The size of a plan's motion: ``∫|u| dt`` of its inputs (the same for any re-timing).

    Parameters
    ----------
    result : PlanResult
        A plan.

    Returns
    -------
    float
        The integral, by the trapezoidal rule over the plan's samples (input units × s).
    """
    t = np.asarray(result.t, dtype=float)
    if len(t) < 2:
        return 0.0
    speed = np.linalg.norm(np.asarray(result.u, dtype=float).reshape(len(t), -1), axis=1)
    return float(np.sum(0.5 * (speed[1:] + speed[:-1]) * np.diff(t)))


def predicted_error(norms, stages, size: float, kinematic: float, seconds: float) -> float:
    """The ``|e|`` a motion of ``size`` is predicted to end at, from the stages played.

    ``MARGIN · tracking + drift · seconds + kinematic`` (module docstring): ``tracking`` the
    least of the bounds ``|e_j| · max(r, r²)``, ``r = size / s_j``, over the played stages
    ``j`` of size ``s_j > 0``; ``drift`` the largest drift at rest measured.

    Parameters
    ----------
    norms : sequence of float
        ``|e|`` after each stage of ``stages``.
    stages : sequence of dict
        Stages of an :class:`Execution` so far.
    size : float
        :func:`motion_size` of the motion.
    kinematic : float
        Its plan's own error bound at the goal.
    seconds : float
        Time it takes, settling included.

    Returns
    -------
    float
        The prediction; ``inf`` for a motion of non-zero size without a played motion to
        scale it from.
    """
    played = [(n, s) for n, s in zip(norms, stages) if s["outcome"] == "played"]
    bounds = [n * max(size / s["size"], (size / s["size"]) ** 2) for n, s in played if s.get("size")]
    drift = max((s.get("drift") or 0.0 for _, s in played), default=0.0)
    tracking = 0.0 if size == 0 else (MARGIN * min(bounds) if bounds else math.inf)
    return tracking + drift * seconds + kinematic


def execute(result, touch_ups=0, duration=None, contact=None, progress=None) -> Execution:
    """Play a plan on the MuJoCo model of its mechanism, open loop, then touch up.

    Everything is checked before anything is played (module docstring): the model matches
    the mechanism's kinematics, the settings lie in their ranges, and the open loop's steps
    within :data:`MIN_MOTION_STEPS` and :data:`~nonholo.physics.contact.MAX_STAGE_STEPS`. A
    stage MuJoCo goes unstable in (or without contact force) is recorded as ``"unstable"``
    and ends the execution.

    Parameters
    ----------
    result : PlanResult
        A successful plan.
    touch_ups : int
        Re-plans from the measured state to the plan's goal after the open-loop stage at
        most, each played like it if predicted to end nearer the goal (module docstring);
        at most :data:`~nonholo.physics.execution_record.MAX_TOUCH_UPS`.
    duration : float, optional
        Seconds each stage's motion takes, settling aside (default: ``SLOWDOWN``
        times the plan's ``T``); at most :data:`MAX_DURATION`.
    contact : Contact, optional
        The contact and actuation settings (default: ``Contact()``; fields left ``None``
        take the mechanism's calibrated values, :meth:`Contact.resolved`).
    progress : callable, optional
        Called with each stage's record (a dict with ``stage``, its index) once done.

    Returns
    -------
    Execution
        Per stage: the error by part, what became of it, slip, contact force, simulated
        time, real-time factor; the motions' samples in ``Execution.traces``.

    Raises
    ------
    ValueError
        Naming the argument: ``result`` not a successful :class:`PlanResult`, ``touch_ups``
        not a whole number in ``[0, MAX_TOUCH_UPS]``, ``duration`` not a positive time of at
        most ``MAX_DURATION`` or a stage of too few or too many MuJoCo steps (naming
        ``duration`` and the ``timestep``), ``contact`` not a :class:`Contact`, a mechanism
        without a physics model or whose kinematics no model matches (naming it).
    """
    import mujoco

    touch_ups, duration = _check(result, touch_ups, duration, contact, progress)
    mech = result.kinematics
    model = model_for(mech, contact)
    check_steps(result, duration, model.contact)
    m = mujoco.MjModel.from_xml_string(model.mjcf())
    d = mujoco.MjData(m)
    sim = (model, m, d)
    model.reset(m, d, result.R0, _coordinates(result.q0))
    Rd, qd = result.Rd, _coordinates(result.qd)
    wrong = instability(m, d)
    if wrong is None:
        R, q = model.state(m, d)
    else:                                      # while settling at the start: the plan's start it was
        R, q = result.R0, _coordinates(result.q0)
    options = replan_options(result)
    tol = float(result.options.get("tol", DEFAULT_TOL))
    settle = float(model.contact.settle)
    stages, traces, norms = [], [], []
    current, predicted = result, None
    for i in range(touch_ups + 1):
        if i == 0:
            played = _played(current, duration)
        else:
            record = _touch_up(mech, R, q, result, options, tol, (stages, norms), duration, model.contact)
            if isinstance(record, dict):           # not played: recorded, and touching up ends
                record["error"] = dict(stages[-1]["error"])
                stages.append(record)
                traces.append(None)
                norms.append(norms[-1])
                if progress is not None:
                    progress(dict(record, stage=i))
                break
            current, played, predicted = record
        before = _error(mech, R, q, Rd, qd)
        if wrong is not None:                      # before the open loop, while settling
            numbers, trace = _nothing_played(float(played.T)), None
            wrong = f"MuJoCo went unstable: {wrong} while the model settled at the start"
        else:
            numbers, trace, R, q, wrong = _stage(sim, played, R, q)
        if wrong is not None:
            record = {"error": before, "outcome": "unstable", **numbers, "size": motion_size(current),
                      "drift": None, "predicted": predicted,
                      "reason": f"{wrong}; the state after it says nothing of the plan: the error is "
                                "the one before the stage, and the execution stops here"}
            stages.append(record)
            traces.append(trace)
            norms.append(mech.space.norm(before))
            if progress is not None:
                progress(dict(record, stage=i))
            break
        error = _error(mech, R, q, Rd, qd)
        record = {"error": error, "outcome": "played", **numbers, "size": motion_size(current),
                  "drift": _drift(mech, trace, float(played.T), settle), "predicted": predicted}
        stages.append(record)
        traces.append(trace)
        norms.append(mech.space.norm(error))
        if progress is not None:
            progress(dict(record, stage=i))
    return Execution(mech.name, stages, model.contact, traces, kinematics=mech)


def _nothing_played(T: float) -> dict:
    """The numbers of a stage not played (its motion would have taken ``T``)."""
    return {"max_slip": 0.0, "max_contact_force": 0.0, "sim_time": 0.0, "real_time_factor": 0.0, "duration": T}


def _played(current, duration):
    """``current`` re-timed from rest to rest as it is played."""
    return retime(current, T=_stage_duration(current, duration), rest_to_rest=True)


def _stage_duration(current, duration) -> float:
    """How long ``current``'s motion takes as it is played."""
    return duration if duration is not None else SLOWDOWN * planned_controls(current).T


def _touch_up(mech, R, q, result, options, tol, so_far, duration, contact):
    """The touch-up from the measured ``(R, q)``, after the stages ``so_far`` (records and
    their ``|e|``): ``(plan, played, predicted |e|)`` to play, or the record of a touch-up not
    played (without its error)."""
    stages, norms = so_far
    now = norms[-1]
    settle = float(contact.settle)

    def skip(outcome, reason, size=None, predicted=None):
        # a prediction that is not finite (no played motion to scale from) is in the reason only
        kept = predicted if predicted is None or math.isfinite(predicted) else None
        return {"outcome": outcome, "reason": reason, **_nothing_played(0.0), "size": size, "drift": None,
                "predicted": kept}

    if now <= tol:
        return skip("within tolerance", f"|e| = {now:.3g} is within the plan's tolerance {tol:g}")
    try:
        current = plan(State(R, q), result.goal, mechanism=mech, **arguments_of(options, mech))
        reason = None if current.success else current.reason
    except ValueError as exc:              # e.g. a measured state the planner refuses
        reason = str(exc)
    if reason is not None:
        return skip("not planned", reason)
    why = _steps_refused(_stage_duration(current, duration), contact, "its duration")
    if why is not None:
        return skip("not planned", f"the re-plan cannot be played: {why}")
    played = _played(current, duration)
    size = motion_size(current)
    kinematic = (current.terminal_error or 0.0) + (current.error_bound or 0.0)
    predicted = predicted_error(norms, stages, size, kinematic, float(played.T) + settle)
    if not predicted < now:
        return skip("predicted worse", f"predicted |e| {predicted:.3g} after a motion of size {size:.3g}, "
                    f"not below the present {now:.3g}", size, predicted)
    return current, played, predicted


def _drift(mech, trace, T: float, settle: float) -> float:
    """How fast the state moved over the last :data:`DRIFT_WINDOW` of the stage's settling
    (``|e|`` between its first and last samples there, per second)."""
    t = trace["t"]
    k = min(int(np.searchsorted(t, T + (1 - DRIFT_WINDOW) * settle - 1e-9)), len(t) - 2)
    if t[-1] <= t[k]:
        return 0.0
    e = mech.space.error((trace["R"][k], trace["q"][k]), (trace["R"][-1], trace["q"][-1]))[1]
    return mech.space.norm(e) / float(t[-1] - t[k])


def _coordinates(q) -> np.ndarray:
    return np.zeros(0) if q is None else np.asarray(q, dtype=float)


def _error(mech, R, q, Rd, qd) -> dict:
    parts = mech.space.error((R, q), (Rd, qd))[1]
    return {k: float(v) for k, v in parts.items()}
