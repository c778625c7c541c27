"""The record of a plan played on its physics model (:func:`nonholo.physics.execution.execute`):
:class:`Execution`, one entry per stage, saved as JSON and read back.

:meth:`Execution.save` writes the record (traces left out, atomically);
:meth:`Execution.load` reads back only what ``save`` would write: a file of at most
:data:`MAX_RECORD_BYTES`, nested at most :data:`MAX_RECORD_DEPTH` deep, finite numbers that
floats hold, the known fields (:data:`STAGE_KEYS`), outcomes (:data:`OUTCOMES`) and at most
:data:`MAX_TOUCH_UPS` touch-ups after the open-loop stage.
"""
from __future__ import annotations

import json
import math

from ..io import safe_write
from ..numerics.checks import is_number
from .contact import Contact, shown

#: What became of a stage: played; why a touch-up was not; or ``"unstable"``: MuJoCo reported
#: the simulation unstable while playing it, or the mechanism left its contacts (execution
#: stops there).
OUTCOMES = ("played", "within tolerance", "predicted worse", "not planned", "unstable")
#: The format tag of a saved execution.
FORMAT = "nonholo.execution/1"
#: Largest number of touch-ups.
MAX_TOUCH_UPS = 100
#: The keys of a stage's record (``planned``: records saved before ``outcome``).
STAGE_KEYS = ("error", "outcome", "reason", "size", "predicted", "drift", "max_slip", "max_contact_force",
              "sim_time", "real_time_factor", "duration", "planned")
#: Largest file :meth:`Execution.load` reads (bytes); a record is a few kilobytes.
MAX_RECORD_BYTES = 4 * 1024 * 1024
#: Deepest nesting of objects and lists in a saved record (it has 4).
MAX_RECORD_DEPTH = 6


class Execution:
    """The record of :func:`~nonholo.physics.execution.execute`: one entry per stage, the
    open-loop stage first, then the touch-ups played and at most one stage not played or
    ``"unstable"``, the last.

    Parameters
    ----------
    mechanism : str
        The mechanism's name.
    stages : list of dict
        Per stage: ``error``, the state's error from the goal by part after it (as
        ``mechanism.space.error`` gives it: ``rotation`` in rad, ``coordinates`` in the
        mechanism's units; unchanged by a stage not played); ``outcome``, one of
        :data:`OUTCOMES`; ``size``, :func:`~nonholo.physics.execution.motion_size` of its plan
        (``None`` if none was planned); ``predicted``, a touch-up's predicted ``|e|`` (``None``
        for the open loop, without a plan, and for a prediction that is not finite, which its
        reason gives); ``drift``, the rate (per second) at which the state moved at rest over
        the end of its settling; ``max_slip`` (largest tangential speed at a rolling contact,
        units per second) and ``max_contact_force`` (N), both over the samples taken every
        :data:`~nonholo.physics.execution.SAMPLE` s; ``sim_time`` (s); ``real_time_factor``
        (simulated over wall time); ``duration`` (s of motion, settling aside). A stage not
        played has a ``reason``, and zero slip, force and times. A stage MuJoCo went unstable in
        (or with no contact force) has the outcome ``"unstable"``, a ``reason``, the error
        before it, and slip, force and times up to where that was seen; it is the last; its
        trace holds the samples before it. Records saved before ``outcome`` had ``planned``
        instead; :meth:`from_dict` reads them.
    contact : Contact
        The settings played with (resolved: no field ``None``).
    traces : list of dict, optional
        Per stage, samples of the motion every :data:`~nonholo.physics.execution.SAMPLE` s:
        ``t`` (from the stage's start), the planned states ``R_planned``, ``q_planned`` (held at
        the end after ``duration``), the simulated ``R``, ``q`` and ``slip``; ``None`` for a
        stage not played. Not saved.
    kinematics : Mechanism, optional
        The mechanism played (figures use it; a record read back names a catalog one).
    """

    def __init__(self, mechanism: str, stages: list, contact: Contact, traces: list | None = None,
                 kinematics=None):
        self.mechanism = mechanism
        self.stages = stages
        self.contact = contact
        self.traces = traces
        #: the :class:`~nonholo.model.mechanism.Mechanism` played (``None`` for a record read
        #: back: its name then names a catalog mechanism); not saved
        self.kinematics = kinematics

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
        """Inverse of :meth:`to_dict`: refuses what :meth:`save` would not write.

        Parameters
        ----------
        d : dict
            A record's object.

        Returns
        -------
        Execution
            The record, without traces; its numbers as floats.

        Raises
        ------
        ValueError
            Naming the field that is missing, unknown or wrong: a number that is not a finite
            float (or an integer beyond the floats), an unknown outcome, a stage after one
            not played.
        """
        if not isinstance(d, dict):
            raise ValueError(f"an execution record must be a JSON object, got {type(d).__name__}")
        if d.get("format", FORMAT) != FORMAT:
            raise ValueError(f"format: expected {FORMAT!r}, got {shown(d.get('format'))}")
        unknown = sorted(str(k) for k in d if k not in ("format", "mechanism", "stages", "contact"))
        if unknown:
            raise ValueError(f"unknown fields {unknown}: a record has format, mechanism, stages and contact")
        for key in ("mechanism", "stages", "contact"):
            if key not in d:
                raise ValueError(f"{key}: missing")
        if not isinstance(d["mechanism"], str) or not 0 < len(d["mechanism"]) <= 200:
            raise ValueError(f"mechanism must be a name, got {shown(d['mechanism'])}")
        if not isinstance(d["stages"], list) or not d["stages"]:
            raise ValueError("stages must be a non-empty list")
        if len(d["stages"]) > MAX_TOUCH_UPS + 1:
            raise ValueError(f"stages: {len(d['stages'])} stages, more than the {MAX_TOUCH_UPS + 1} an "
                             "execution has at most")
        stages = [_stage_from_dict(s, i) for i, s in enumerate(d["stages"])]
        for i, stage in enumerate(stages[:-1]):
            if stage["outcome"] != "played":
                raise ValueError(f"stages[{i}].outcome: a stage {stage['outcome']!r} ends an execution, "
                                 f"yet {len(stages) - i - 1} stage(s) follow it")
        try:
            contact = Contact.from_dict(d["contact"])
        except ValueError as exc:
            raise ValueError(f"contact: {exc}") from None
        return cls(d["mechanism"], stages, contact)

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
        """Read a record written by :meth:`save`, refusing anything it would not write: a file
        larger than :data:`MAX_RECORD_BYTES`, nested deeper than :data:`MAX_RECORD_DEPTH`,
        ``NaN`` or ``Infinity``, a number beyond the floats (``1e400``, ``10**400``), an
        unknown field (:meth:`from_dict`).

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
            For a file that is not such a record: naming the file and the field, saying why.
        OSError
            If the file cannot be read.
        """
        with open(path, "rb") as f:
            raw = f.read(MAX_RECORD_BYTES + 1)
        if len(raw) > MAX_RECORD_BYTES:
            raise ValueError(f"{path}: larger than {MAX_RECORD_BYTES} bytes: not an execution record")
        try:
            text = raw.decode("utf-8-sig")
        except UnicodeDecodeError as exc:
            raise ValueError(f"{path}: not UTF-8 text: {exc.reason} at byte {exc.start}") from None
        try:
            d = json.loads(text, parse_constant=_Unrepresentable, parse_float=_json_float, parse_int=_json_int)
        except json.JSONDecodeError as exc:
            raise ValueError(f"{path}: not JSON: {exc}") from None
        except RecursionError:
            raise ValueError(f"{path}: nested deeper than {MAX_RECORD_DEPTH} levels: not an execution "
                             "record") from None
        try:
            _check_depth(d)
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
            what = (f"max slip {s['max_slip']:.2e}" if outcome == "played"
                    else "MuJoCo unstable" if outcome == "unstable" else f"not played ({outcome})")
            parts.append(f"  {'open loop' if i == 0 else f'touch-up {i}'}: {err}, {what}")
        return f"Execution({self.mechanism}, {len(self.stages)} stages\n" + "\n".join(parts) + ")"


class _Unrepresentable:
    """A JSON number no float holds (``NaN``, ``Infinity``, ``1e400``, ``10**400``), kept as
    text for the message that refuses it: it is not a number to any check."""

    def __init__(self, text: str):
        self.text = text if len(text) <= 40 else f"{text[:20]}...({len(text)} digits)"

    def __repr__(self) -> str:
        return self.text


def _json_float(text: str):
    x = float(text)
    return x if math.isfinite(x) else _Unrepresentable(text)


def _json_int(text: str):
    if len(text.lstrip("-")) > 309:           # beyond any float, and maybe past int()'s digits limit
        return _Unrepresentable(text)
    x = int(text)
    try:
        float(x)
    except OverflowError:
        return _Unrepresentable(text)
    return x


def _check_depth(value) -> None:
    """Refuse nesting deeper than :data:`MAX_RECORD_DEPTH` (iteratively: no recursion)."""
    todo = [(value, 0, "")]
    while todo:
        v, depth, where = todo.pop()
        if isinstance(v, (dict, list)):
            if depth >= MAX_RECORD_DEPTH:
                raise ValueError(f"{where or 'the record'}: nested deeper than {MAX_RECORD_DEPTH} levels: "
                                 "not an execution record")
            if isinstance(v, dict):
                todo.extend((x, depth + 1, f"{where}.{str(k)[:40]}" if where else str(k)[:40])
                            for k, x in v.items())
            else:
                todo.extend((x, depth + 1, f"{where}[{i}]") for i, x in enumerate(v))


def _finite(value, where: str, minimum: float = -math.inf) -> float:
    """A record's number as a finite float ``≥ minimum``, or a ValueError naming ``where``."""
    if not is_number(value):
        raise ValueError(f"{where} must be a finite number, got {shown(value)}")
    try:
        x = float(value)
    except OverflowError:
        raise ValueError(f"{where} must be a finite number, got {shown(value)}") from None
    if not math.isfinite(x) or x < minimum:
        raise ValueError(f"{where} must be a finite number{'' if minimum == -math.inf else f' >= {minimum:g}'}, "
                         f"got {shown(value)}")
    return x


def _stage_from_dict(s: dict, i: int) -> dict:
    """A saved stage checked, its numbers as floats, with its ``outcome`` (from ``planned`` in
    older records)."""
    at = f"stages[{i}]"
    if not isinstance(s, dict):
        raise ValueError(f"{at} must be an object")
    unknown = sorted(str(k) for k in s if k not in STAGE_KEYS)
    if unknown:
        raise ValueError(f"{at}: unknown fields {unknown}; a stage has {', '.join(STAGE_KEYS)}")
    for key in ("error", "max_slip", "max_contact_force", "sim_time", "real_time_factor"):
        if key not in s:
            raise ValueError(f"{at}.{key}: missing")
    error = s["error"]
    if not isinstance(error, dict) or not error or not all(k in ("rotation", "coordinates") for k in error):
        raise ValueError(f"{at}.error must map 'rotation'/'coordinates' to numbers, got {shown(error)}")
    stage = dict(s, error={k: _finite(v, f"{at}.error.{k}", 0.0) for k, v in error.items()})
    for key in ("max_slip", "max_contact_force", "sim_time", "real_time_factor", "duration"):
        if key in stage:
            stage[key] = _finite(stage[key], f"{at}.{key}", 0.0)
    for key in ("size", "predicted", "drift"):
        if stage.get(key) is not None:
            stage[key] = _finite(stage[key], f"{at}.{key}", 0.0)
    if "planned" in stage and not isinstance(stage["planned"], bool):
        raise ValueError(f"{at}.planned must be true or false, got {shown(stage['planned'])}")
    if "outcome" not in stage:
        stage["outcome"] = "played" if stage.pop("planned", True) is not False else "not planned"
    if not isinstance(stage["outcome"], str) or stage["outcome"] not in OUTCOMES:
        raise ValueError(f"{at}.outcome must be one of {OUTCOMES}, got {shown(stage['outcome'])}")
    if i == 0 and stage["outcome"] not in ("played", "unstable"):
        raise ValueError(f"stages[0].outcome must be 'played' or 'unstable' (the open loop), "
                         f"got {stage['outcome']!r}")
    if stage["outcome"] != "played" and not isinstance(stage.get("reason"), str):
        raise ValueError(f"{at}.reason: a stage not played needs its reason, got {shown(stage.get('reason'))}")
    if stage.get("reason") is not None and not isinstance(stage["reason"], str):
        raise ValueError(f"{at}.reason must be text, got {shown(stage['reason'])}")
    return stage
