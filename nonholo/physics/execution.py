"""Playing a plan on a MuJoCo model, with touch-ups: :func:`execute` and its record
:class:`Execution`.

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

``|e|`` is the norm of the stacked error (:meth:`~nonholo.spaces.groups.Product.norm`),
the quantity a plan's ``tol`` bounds. Touching up stops at the first touch-up not played:
once ``|e| ≤ tol`` of the plan (``result.options["tol"]``), when the re-plan is predicted to
end no nearer, or when it cannot be planned; that touch-up is recorded, with its reason and
the error unchanged. Hence the recorded errors do not grow from stage to stage as long as
the prediction holds.

Everything recorded is a function of the inputs alone — MuJoCo runs single-threaded and
deterministically, and no wall-clock time enters the simulation or a decision — except each
stage's real-time factor (simulated over wall time).
"""
# ruff: noqa: TRY004 (bad input is refused by a ValueError naming the argument, as across the package)
from __future__ import annotations

import inspect
import json
import math
import time

import numpy as np

from ..io import safe_write
from ..io.csv_export import states_at
from ..io.result import PlanResult
from ..numerics.checks import check_time, is_number
from ..planning.api import plan
from ..planning.retime import planned_controls, retime
from .contact import Contact
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
DEFAULT_TOL = inspect.signature(plan).parameters["tol"].default
#: What became of a stage: played, or why not (a touch-up only).
OUTCOMES = ("played", "within tolerance", "predicted worse", "not planned")
#: The format tag of a saved execution.
FORMAT = "nonholo.execution/1"


# -- the record ------------------------------------------------------------------------------

class Execution:
    """The record of :func:`execute`: one entry per stage, the open-loop stage first, then
    the touch-ups played and at most one touch-up not played, the last.

    Parameters
    ----------
    mechanism : str
        The mechanism's name.
    stages : list of dict
        Per stage: ``error``, the state's error from the goal by part after it (as
        ``mechanism.space.error`` gives it: ``rotation`` in rad, ``coordinates`` in the
        mechanism's units; unchanged by a stage not played); ``outcome``, one of
        :data:`OUTCOMES`; ``size``, :func:`motion_size` of its plan (``None`` if none was
        planned); ``predicted``, a touch-up's predicted ``|e|`` (``None`` for the open loop
        and without a plan); ``drift``, the rate (per second) at which the state moved at rest
        over the end of its settling; ``max_slip`` (largest tangential speed at a rolling
        contact, units per second) and ``max_contact_force`` (N), both over the samples taken
        every :data:`SAMPLE` s; ``sim_time`` (s); ``real_time_factor`` (simulated over wall
        time); ``duration`` (s of motion, settling aside). A stage not played has a
        ``reason``, and zero slip, force and times. Records saved before ``outcome`` had
        ``planned`` instead; :meth:`from_dict` reads them.
    contact : Contact
        The settings played with (resolved: no field ``None``).
    traces : list of dict, optional
        Per stage, samples of the motion every :data:`SAMPLE` s: ``t`` (from the stage's
        start), the planned states ``R_planned``, ``q_planned`` (held at the end after
        ``duration``), the simulated ``R``, ``q`` and ``slip``; ``None`` for a stage not
        played. Not saved.
    """

    def __init__(self, mechanism: str, stages: list, contact: Contact, traces: list | None = None):
        self.mechanism = mechanism
        self.stages = stages
        self.contact = contact
        self.traces = traces

    @property
    def errors(self) -> list[dict]:
        """Each stage's error by part."""
        return [s["error"] for s in self.stages]

    def to_dict(self) -> dict:
        """The record as plain JSON values (traces left out).

        Returns
        -------
        dict
            ``{"format", "mechanism", "stages", "contact"}``.
        """
        return {"format": FORMAT, "mechanism": self.mechanism,
                "stages": [dict(s, error=dict(s["error"])) for s in self.stages],
                "contact": self.contact.to_dict()}

    @classmethod
    def from_dict(cls, d: dict) -> Execution:
        """Inverse of :meth:`to_dict`.

        Parameters
        ----------
        d : dict
            A record's object.

        Returns
        -------
        Execution
            The record, without traces.

        Raises
        ------
        ValueError
            Naming the field that is missing or wrong.
        """
        if not isinstance(d, dict):
            raise ValueError(f"an execution record must be a JSON object, got {type(d).__name__}")
        if d.get("format", FORMAT) != FORMAT:
            raise ValueError(f"format: expected {FORMAT!r}, got {d.get('format')!r}")
        for key in ("mechanism", "stages", "contact"):
            if key not in d:
                raise ValueError(f"{key}: missing")
        if not isinstance(d["mechanism"], str):
            raise ValueError(f"mechanism must be a name, got {d['mechanism']!r}")
        if not isinstance(d["stages"], list) or not d["stages"]:
            raise ValueError("stages must be a non-empty list")
        stages = []
        for i, s in enumerate(d["stages"]):
            if not isinstance(s, dict):
                raise ValueError(f"stages[{i}] must be an object")
            for key in ("error", "max_slip", "max_contact_force", "sim_time", "real_time_factor"):
                if key not in s:
                    raise ValueError(f"stages[{i}].{key}: missing")
            if not isinstance(s["error"], dict) or not s["error"] or not all(
                    k in ("rotation", "coordinates") and is_number(v) for k, v in s["error"].items()):
                raise ValueError(f"stages[{i}].error must map 'rotation'/'coordinates' to numbers, "
                                 f"got {s['error']!r}")
            for key in ("max_slip", "max_contact_force", "sim_time", "real_time_factor"):
                if not is_number(s[key]):
                    raise ValueError(f"stages[{i}].{key} must be a number, got {s[key]!r}")
            stages.append(_stage_from_dict(s, i))
        return cls(d["mechanism"], stages, Contact.from_dict(d["contact"]))

    def save(self, path):
        """Write the record as JSON (atomically, :mod:`nonholo.io.safe_write`).

        Parameters
        ----------
        path : str or pathlib.Path
            Where to write.

        Returns
        -------
        pathlib.Path
            ``path``.

        Raises
        ------
        ValueError
            If ``path`` cannot be replaced (a directory) or a number is not finite.
        """
        safe_write.check_target(path, "path")
        try:
            text = json.dumps(self.to_dict(), indent=1, allow_nan=False)
        except ValueError as exc:
            raise ValueError(f"cannot save the execution: {exc}") from None
        return safe_write.write_text(path, text + "\n", "path")

    @classmethod
    def load(cls, path) -> Execution:
        """Read a record written by :meth:`save`.

        Parameters
        ----------
        path : str or pathlib.Path
            The file.

        Returns
        -------
        Execution
            The record, without traces.

        Raises
        ------
        ValueError
            For a file that is not such a record, saying why.
        """
        try:
            with open(path, encoding="utf-8-sig") as f:
                d = json.load(f)
        except json.JSONDecodeError as exc:
            raise ValueError(f"{path}: not JSON: {exc}") from None
        try:
            return cls.from_dict(d)
        except ValueError as exc:
            raise ValueError(f"{path}: {exc}") from None

    def __eq__(self, other) -> bool:
        if not isinstance(other, Execution):
            return NotImplemented
        strip = [{k: v for k, v in s.items() if k != "real_time_factor"} for s in self.stages]
        other_strip = [{k: v for k, v in s.items() if k != "real_time_factor"} for s in other.stages]
        return (self.mechanism, strip, self.contact) == (other.mechanism, other_strip, other.contact)

    __hash__ = None

    def __repr__(self) -> str:
        parts = []
        for i, s in enumerate(self.stages):
            err = ", ".join(f"{k} {v:.2e}" for k, v in s["error"].items())
            outcome = s.get("outcome", "played")
            what = f"max slip {s['max_slip']:.2e}" if outcome == "played" else f"not played ({outcome})"
            parts.append(f"  {'open loop' if i == 0 else f'touch-up {i}'}: {err}, {what}")
        return f"Execution({self.mechanism}, {len(self.stages)} stages\n" + "\n".join(parts) + ")"


def _stage_from_dict(s: dict, i: int) -> dict:
    """A saved stage checked, with its ``outcome`` (from ``planned`` in older records)."""
    stage = dict(s, error=dict(s["error"]))
    if "outcome" not in stage:
        stage["outcome"] = "played" if stage.pop("planned", True) is not False else "not planned"
    if stage["outcome"] not in OUTCOMES:
        raise ValueError(f"stages[{i}].outcome must be one of {OUTCOMES}, got {stage['outcome']!r}")
    if i == 0 and stage["outcome"] != "played":
        raise ValueError(f"stages[0].outcome must be 'played' (the open loop), got {stage['outcome']!r}")
    if stage["outcome"] != "played" and not isinstance(stage.get("reason"), str):
        raise ValueError(f"stages[{i}].reason: a stage not played needs its reason, got {stage.get('reason')!r}")
    for key in ("size", "predicted", "drift"):
        if stage.get(key) is not None and not is_number(stage[key]):
            raise ValueError(f"stages[{i}].{key} must be a number or null, got {stage[key]!r}")
    return stage


# -- playing ----------------------------------------------------------------------------------

def _check(result, touch_ups, duration, contact, progress):
    if not isinstance(result, PlanResult):
        raise ValueError(f"result must be a PlanResult, got {type(result).__name__}")
    if not result.success:
        raise ValueError(f"result: only a successful plan can be played; this one failed: {result.reason}")
    if isinstance(touch_ups, (bool, np.bool_)) or not isinstance(touch_ups, (int, np.integer)) or touch_ups < 0:
        raise ValueError(f"touch_ups must be a whole number >= 0, got {touch_ups!r}")
    if duration is not None:
        duration = check_time(duration, "duration")
    if contact is not None and not isinstance(contact, Contact):
        raise ValueError(f"contact must be a Contact or None, got {type(contact).__name__}")
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be callable or None, got {type(progress).__name__}")
    return int(touch_ups), duration


def replan_options(result: PlanResult) -> dict:
    """The keywords a touch-up re-plans ``result``'s goal with: its horizon, method and
    strategy, and the options of :data:`REPLAN_OPTIONS` it was planned with (its objective,
    ``None`` where it records none).

    Parameters
    ----------
    result : PlanResult
        The plan.

    Returns
    -------
    dict
        Keywords of :func:`nonholo.plan`.
    """
    accepted = inspect.signature(plan).parameters
    opts = {k: v for k, v in result.options.items() if k in REPLAN_OPTIONS and k in accepted}
    opts.update(T=planned_controls(result).T, method=result.method, strategy=result.strategy)
    opts.setdefault("objective", None)       # recorded only when the plan had one
    if "leg_speed" in opts:
        opts["T"] = result.T
    return opts


def _stage(sim, played, R, q):
    """Play ``played`` from the measured ``(R, q)`` and settle; the stage's numbers and
    trace, and the measured state after it."""
    import mujoco

    model, m, d = sim
    model.follow(played, R, q)
    h = float(m.opt.timestep)
    T = float(played.T)
    n_move = math.ceil(T / h - 1e-9)
    n_total = n_move + round(model.contact.settle / h)
    every = max(1, round(SAMPLE / h))
    times, Rs, qs, slips = [0.0], [], [], []
    R0, q0 = model.state(m, d)
    Rs.append(R0)
    qs.append(q0)
    slips.append(float(model.slip(m, d)))
    worst_slip, worst_force = 0.0, 0.0
    wall = 0.0
    for k in range(n_total):
        started = time.perf_counter()
        model.drive(m, d, k * h)
        mujoco.mj_step(m, d)
        wall += time.perf_counter() - started
        if (k + 1) % every == 0 or k + 1 == n_total:
            # slip and forces at the samples: measuring them costs more than a step
            slip = float(model.slip(m, d))
            worst_slip = max(worst_slip, slip)
            worst_force = max(worst_force, float(model.contact_force(m, d)))
            Rk, qk = model.state(m, d)
            times.append((k + 1) * h)
            Rs.append(Rk)
            qs.append(qk)
            slips.append(slip)
    mujoco.mj_forward(m, d)
    R_end, q_end = model.state(m, d)
    t = np.array(times)
    Rp, qp = states_at(played, np.minimum(t, float(played.t[-1])))
    trace = {"t": t, "R_planned": Rp, "q_planned": qp, "R": np.array(Rs), "q": np.array(qs),
             "slip": np.array(slips)}
    sim_time = n_total * h
    numbers = {"max_slip": worst_slip, "max_contact_force": worst_force, "sim_time": sim_time,
               "real_time_factor": sim_time / wall if wall > 0 else float("inf"), "duration": T}
    return numbers, trace, R_end, q_end


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

    Parameters
    ----------
    result : PlanResult
        A successful plan.
    touch_ups : int
        Re-plans from the measured state to the plan's goal after the open-loop stage at
        most, each played like it if predicted to end nearer the goal (module docstring).
    duration : float, optional
        Seconds each stage's motion takes, settling aside (default: ``SLOWDOWN``
        times the plan's ``T``).
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
        not a whole number ``≥ 0``, ``duration`` not a positive time, ``contact`` not a
        :class:`Contact`, a mechanism without a physics model.
    """
    import mujoco

    touch_ups, duration = _check(result, touch_ups, duration, contact, progress)
    mech = result.kinematics
    model = model_for(mech, contact)
    m = mujoco.MjModel.from_xml_string(model.mjcf())
    d = mujoco.MjData(m)
    sim = (model, m, d)
    model.reset(m, d, result.R0, _coordinates(result.q0))
    R, q = model.state(m, d)
    Rd, qd = result.Rd, _coordinates(result.qd)
    options = replan_options(result)
    tol = float(result.options.get("tol", DEFAULT_TOL))
    settle = float(model.contact.settle)
    stages, traces, norms = [], [], []
    current, predicted = result, None
    for i in range(touch_ups + 1):
        if i == 0:
            played = _played(current, duration)
        else:
            record = _touch_up(mech, R, q, result, options, tol, (stages, norms), duration, settle)
            if isinstance(record, dict):           # not played: recorded, and touching up ends
                record["error"] = dict(stages[-1]["error"])
                stages.append(record)
                traces.append(None)
                norms.append(norms[-1])
                if progress is not None:
                    progress(dict(record, stage=i))
                break
            current, played, predicted = record
        numbers, trace, R, q = _stage(sim, played, R, q)
        error = _error(mech, R, q, Rd, qd)
        record = {"error": error, "outcome": "played", **numbers, "size": motion_size(current),
                  "drift": _drift(mech, trace, float(played.T), settle), "predicted": predicted}
        stages.append(record)
        traces.append(trace)
        norms.append(mech.space.norm(error))
        if progress is not None:
            progress(dict(record, stage=i))
    return Execution(mech.name, stages, model.contact, traces)


def _played(current, duration):
    """``current`` re-timed from rest to rest as it is played."""
    return retime(current, T=duration if duration is not None else SLOWDOWN * planned_controls(current).T,
                  rest_to_rest=True)


def _touch_up(mech, R, q, result, options, tol, so_far, duration, settle):
    """The touch-up from the measured ``(R, q)``, after the stages ``so_far`` (records and
    their ``|e|``): ``(plan, played, predicted |e|)`` to play, or the record of a touch-up not
    played (without its error)."""
    stages, norms = so_far
    now = norms[-1]

    def skip(outcome, reason, size=None, predicted=None):
        return {"outcome": outcome, "reason": reason, "max_slip": 0.0, "max_contact_force": 0.0,
                "sim_time": 0.0, "real_time_factor": 0.0, "duration": 0.0, "size": size, "drift": None,
                "predicted": predicted}

    if now <= tol:
        return skip("within tolerance", f"|e| = {now:.3g} is within the plan's tolerance {tol:g}")
    try:
        current = plan(mech.space.public(R, q), result.goal, mechanism=mech, **options)
        reason = None if current.success else current.reason
    except ValueError as exc:              # e.g. a measured state the planner refuses
        reason = str(exc)
    if reason is not None:
        return skip("not planned", reason)
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
    e = mech.space.error(trace["R"][k], trace["q"][k], trace["R"][-1], trace["q"][-1])[1]
    return mech.space.norm(e) / float(t[-1] - t[k])


def _coordinates(q) -> np.ndarray:
    return np.zeros(0) if q is None else np.asarray(q, dtype=float)


def _error(mech, R, q, Rd, qd) -> dict:
    parts = mech.space.error(R, q, Rd, qd)[1]
    return {k: float(v) for k, v in parts.items()}
