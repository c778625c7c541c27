"""The plan file's codec: a plan file's JSON object decoded field by field into the fields
of a :class:`~nonholo.io.result.PlanResult` (types, shapes, the controls rebuilt), the JSON
text read from a file. Decoding only: the checks that the numbers
agree with each other (replaying the stored controls) are
:mod:`nonholo.certify.plan_checks`'s.

File format (``PlanResult.save``): one JSON object, ``"format": "nonholo.plan/3"``, with
the scalar fields, ``R0``/``Rd`` as nested 3×3 lists, the samples ``t`` (n), ``R``
(n×3×3), ``u`` (n×m) and ``delta`` (n, or null), ``history`` (a list of per-iteration
records) and ``controls``, the parametrisation (``{"kind": "fourier", "T", "harmonics",
"coeffs"}``, ``{"kind": "piecewise_constant", "T", "grid", "values"}`` or, for a motion
planned in frame coordinates (strategy ``"robust"``), ``{"kind": "frame", "T",
"mechanism", "steps", "R0", "frame": <the w parametrisation>}``, or, for a global route
(``"route": "global"``), ``{"kind": "stitched", "T", "pieces": [<one of those per hop>],
"waypoints"}``, unless the route was re-planned as one smooth control: then ``controls``
is that control and ``"stitched"`` the route's stitched control (absent otherwise); a
time-changed plan wraps one of those as ``{"kind": "retimed", "T", "leg_speed", "nodes",
"mechanism", "R0", "base"}`` (a leg-speed bound) or ``{"kind": "retimed_inputs", "T",
"bounds", "nodes", "base"}`` (input bounds, one ``[low, high]`` per input, ``null`` where
free) and/or ``{"kind": "rest_to_rest", "T", "base"}`` (played from rest to rest); see :mod:`nonholo.controls.parametrisations`,
:mod:`nonholo.motion.frame_controls`, :mod:`nonholo.controls.stitched` and
:mod:`nonholo.motion.time_scaling`) from which ``controls(t)`` is rebuilt (identically: the frame
motion's nodes are recomputed by the same kernel). Floats are written with
``repr`` precision, so a save/load round trip reproduces every number exactly. Quantities
that do not exist (``min_delta`` for a mechanism without a singular set, the terminal
error of a run stopped before any simulation) are ``null``/``None``, never NaN.
``made_by`` records what made the file: the nonholo version and commit, and the versions
of Python, NumPy, SciPy, SymPy and the C compiler (:mod:`nonholo.io.provenance`); files
without it (written before it was recorded) load as well. A plan of a mechanism with a
definition as data (:meth:`~nonholo.model.mechanism.Mechanism.from_equations`,
:meth:`~nonholo.model.mechanism.Mechanism.from_file`) carries it, ``mechanism_definition``
(:func:`nonholo.model.definition_forms.json_data`), and its SHA-256, ``mechanism_digest``
(:func:`nonholo.model.definition_forms.digest`): such a file loads without ``mechanism=``; a
digest that does not match is refused, and the definition is checked as a mechanism file
is before the mechanism is built. A catalog mechanism's plans hold its name only.

Saving (:mod:`nonholo.io.safe_write`) is atomic (a complete new file replaces the old
one, or the old one stays), never replaces what is not a regular file (a directory is
refused; a character device or FIFO is written in place), and writes only what loading
accepts: the text is decoded and checked exactly as :meth:`~nonholo.io.result.PlanResult.load`
does before anything is written.
Loading (:meth:`~nonholo.io.result.PlanResult.load`) decodes the file (:func:`decode`) and
checks it (:mod:`nonholo.certify.plan_checks`): every
field's type and shape, finite numbers, and that the numbers agree with each other — the
stored samples are those of the stored controls replayed from ``R0`` (``n`` samples at the
integrator's step points ``t = kT/steps``; ``n = steps + 1`` when the motion reached
``T``, fewer when it stopped early, none when the planner refused the goal), ``u =
controls(t)``, ``delta = Δ(R)``, and ``terminal_error``, ``min_delta``, ``success``,
``mechanism``, ``method``, ``T``, ``steps`` agree with them. A file that does not is
rejected with a ``ValueError`` naming the field, so a plan cannot be changed — by a
damaged byte or by hand — without the change being noticed (fields that are records, not
results, are checked only for their type: ``reason``, ``history``, ``options``,
``seconds`` (``null``: the wall time not recorded), ``sensitivity``; but ``options`` must hold every option the planner
records, with a value it accepts, and a success is judged from the replay at the plan's
own ``tol``, with a ``sensitivity`` the certificate accepts for it). A missing field is refused, never taken as "unchecked". Files written by
earlier versions of the format load, checked to the same standard: ``nonholo.plan/2``
(no ``route``: local) and ``nonholo.plan/1`` (no certificates: a success's controls are
certified on load, as :func:`nonholo.plan` certifies them).
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..certify.plan_fields import (
    FORMAT,
    FORMAT_1,
    FORMAT_2,
    METHOD_OF_KIND,
    fail,
    integer_field,
    json_type,
    number_field,
    rotation_field,
    short,
    string_field,
)
from ..controls.parametrisations import Controls
from ..controls.stitched import Stitched
from ..model import catalog, definition_forms
from ..model.bounds import InputBounds
from ..motion.frame_controls import FrameControls, from_dict
from ..motion.speed_limits import InputRetimed, Retimed
from ..motion.time_scaling import RestToRest
from ..numerics.checks import is_number
from ..spaces.state import State

#: the fields of a plan file
_REQUIRED = ("format", "success", "reason", "terminal_error", "min_delta", "iterations", "history",
             "mechanism", "method", "strategy", "T", "steps", "seconds", "options", "R0", "Rd",
             "controls", "t", "R", "u", "delta")
#: fields every file since ``nonholo.plan/2`` has (the certificate's record)
_CERTIFIED = ("sensitivity", "error_bound", "replay_steps")
#: fields only some files have: the certificate's, absent from ``nonholo.plan/1`` files
#: (``null`` there); ``route`` (``nonholo.plan/3``); a smoothed route's stitched controls;
#: the coordinates of a mechanism whose state has them; what made the file (``made_by``);
#: the definition of a mechanism that has one, and its SHA-256
_OPTIONAL = ("sensitivity", "error_bound", "replay_steps", "route", "stitched",
             "q0", "qd", "q", "errors", "made_by", "mechanism_definition", "mechanism_digest")
#: the longest text of a ``made_by`` entry
_MADE_BY_TEXT = 200
#: the fields of each kind of ``controls``
_CONTROL_FIELDS = {"fourier": ("kind", "T", "harmonics", "coeffs"),
                   "legendre": ("kind", "T", "degree", "coeffs"),
                   "piecewise_constant": ("kind", "T", "grid", "values"),
                   "frame": ("kind", "T", "mechanism", "steps", "R0", "frame"),
                   "stitched": ("kind", "T", "pieces", "waypoints"),
                   "retimed": ("kind", "T", "leg_speed", "nodes", "mechanism", "R0", "base"),
                   "retimed_inputs": ("kind", "T", "bounds", "nodes", "base"),
                   "rest_to_rest": ("kind", "T", "base")}



def _coordinates(d: dict, mech) -> dict:
    """The coordinate fields of a plan: those of a file's mechanism with coordinates, empty
    ones on SO(3) (whose files have none)."""
    k = mech.n_coordinates
    shapes = mech.space.recorded("coordinates", {"q0": (k,), "qd": (k,), "q": (None, k)}, {})
    missing = [key for key in shapes if key not in d]
    if missing:
        fail(missing[0], f"is missing: mechanism {mech.name!r} has coordinates ({', '.join(mech.coordinates)})")
    errors = mech.space.recorded("coordinates", d.get("errors"))
    if errors is not None and not (isinstance(errors, dict) and all(is_number(v) for v in errors.values())):
        fail("errors", "must be an object of numbers or null")
    return {"q0": np.zeros(0), "qd": np.zeros(0), "q": None, "errors": errors,
            **{key: _array(d[key], key, shape) for key, shape in shapes.items()}}


def _unique_keys(pairs):
    """``object_pairs_hook`` of :func:`json.loads`: an object with a key twice is an error."""
    d = {}
    for k, v in pairs:
        if k in d:
            raise ValueError(f"duplicate key {short(k)} in a JSON object")
        d[k] = v
    return d


def _shape_text(shape) -> str:
    return "(" + ", ".join("n" if s is None else str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"


def _array(value, field: str, shape: tuple) -> np.ndarray:
    """``value`` (nested lists of numbers) as a float array of ``shape`` (``None``: any
    length); ``ValueError`` naming ``field`` for anything else (non-finite entries are
    left to :mod:`nonholo.certify.plan_checks`)."""
    bad = f"must be an array of numbers of shape {_shape_text(shape)}"
    if isinstance(value, np.ndarray):
        if value.dtype.kind not in "iuf" or value.ndim != len(shape):
            fail(field, bad)
        a = value.astype(float)
    else:
        flat = []
        dims = list(shape)
        stack = [(value, 0)]
        while stack:
            x, k = stack.pop()
            if k == len(shape):
                if not is_number(x):
                    fail(field, f"{bad}: found {json_type(x)}")
                flat.append(x)
                continue
            if not isinstance(x, (list, tuple)):
                fail(field, f"{bad}: found {json_type(x)}")
            if dims[k] is None:
                dims[k] = len(x)
            if len(x) != dims[k]:
                fail(field, f"{bad}: got a row of length {len(x)} where {dims[k]} were expected")
            stack.extend((y, k + 1) for y in reversed(x))
        dims = [0 if s is None else s for s in dims]
        try:
            a = np.array(flat, dtype=float).reshape(dims)
        except OverflowError:
            fail(field, "has an integer too large for a float")
    if any(s is not None and s != a.shape[i] for i, s in enumerate(shape)):
        fail(field, f"{bad}, got {a.shape}")
    return a



def _fields(d: dict, expected: tuple, where: str) -> None:
    missing = [k for k in expected if k not in d]
    unknown = [k for k in d if k not in expected]
    if missing:
        fail(where, f"lacks the field{'s' if len(missing) > 1 else ''} {', '.join(map(repr, missing))}")
    if unknown:
        fail(where, f"has unknown field{'s' if len(unknown) > 1 else ''} {', '.join(short(k) for k in unknown)}")


def _parametrisation(d, where: str, m: int) -> None:
    """Check the description of Fourier, Legendre or grid controls with ``m`` inputs (``where``: its field)."""
    if not isinstance(d, dict):
        fail(where, f"must be an object, got {json_type(d)}")
    kind = d.get("kind")
    if kind not in METHOD_OF_KIND:
        fail(where + ".kind", f"must be one of {', '.join(map(repr, METHOD_OF_KIND))}, got {short(kind)}")
    _fields(d, _CONTROL_FIELDS[kind], where)
    T = number_field(d, "T", where=where + ".")
    if T <= 0:
        fail(where + ".T", f"must be positive, got {T}")
    if kind == "fourier":
        K = integer_field(d, "harmonics", 1, where=where + ".")
        _array(d["coeffs"], where + ".coeffs", (m, 2 * K + 1))
    elif kind == "legendre":
        K = integer_field(d, "degree", 0, where=where + ".")
        _array(d["coeffs"], where + ".coeffs", (m, K + 1))
    else:
        g = integer_field(d, "grid", 1, where=where + ".")
        _array(d["values"], where + ".values", (g, m))


def _physical(d, mech, where: str) -> None:
    """Check the description of physical controls (a parametrisation or frame controls)."""
    m = mech.n_inputs
    if isinstance(d, dict) and d.get("kind") == FrameControls.kind:
        _fields(d, _CONTROL_FIELDS["frame"], where)
        _parametrisation(d["frame"], where + ".frame", m)
        if number_field(d, "T", where=where + ".") != d["frame"]["T"]:
            fail(where + ".T", f"differs from the frame controls' T ({d['frame']['T']!r})")
        if string_field(d, "mechanism", where=where + ".") != mech.name:
            fail(where + ".mechanism", f"is {d['mechanism']!r}, but the plan's 'mechanism' is {mech.name!r}")
        integer_field(d, "steps", 1, where=where + ".")
        rotation_field(_array(d["R0"], where + ".R0", (3, 3)), where + ".R0")
    else:
        _parametrisation(d, where, m)


def _controls(d, mech, where: str = "controls", timed: bool = True,
              rest: bool = True) -> Controls | FrameControls | Stitched | Retimed | RestToRest:
    """The ``controls`` field (or another field ``where`` holding controls) of a plan of
    mechanism ``mech``, checked, as an object (``timed``: may be re-timed; ``rest``: may be
    played rest to rest)."""
    if isinstance(d, dict) and d.get("kind") == RestToRest.kind and rest:
        _fields(d, _CONTROL_FIELDS["rest_to_rest"], where)
        if number_field(d, "T", where=f"{where}.") <= 0:
            fail(f"{where}.T", f"must be positive, got {d['T']}")
        _controls(d["base"], mech, f"{where}.base", timed=timed, rest=False)
    elif isinstance(d, dict) and d.get("kind") == Retimed.kind and timed:
        _fields(d, _CONTROL_FIELDS["retimed"], where)
        for key in ("T", "leg_speed"):
            if number_field(d, key, where=f"{where}.") <= 0:
                fail(f"{where}.{key}", f"must be positive, got {d[key]}")
        integer_field(d, "nodes", 2, where=f"{where}.")
        if string_field(d, "mechanism", where=f"{where}.") != mech.name:
            fail(f"{where}.mechanism", f"is {d['mechanism']!r}, but the plan's 'mechanism' is {mech.name!r}")
        rotation_field(_array(d["R0"], f"{where}.R0", (3, 3)), f"{where}.R0")
        _controls(d["base"], mech, f"{where}.base", timed=False, rest=False)
    elif isinstance(d, dict) and d.get("kind") == InputRetimed.kind and timed:
        _fields(d, _CONTROL_FIELDS["retimed_inputs"], where)
        if number_field(d, "T", where=f"{where}.") <= 0:
            fail(f"{where}.T", f"must be positive, got {d['T']}")
        integer_field(d, "nodes", 2, where=f"{where}.")
        try:
            InputBounds.from_record(d["bounds"], mech, "bounds")
        except ValueError as exc:
            fail(f"{where}.bounds", f"is not a plan's input bounds: {exc}")
        _controls(d["base"], mech, f"{where}.base", timed=False, rest=False)
    elif isinstance(d, dict) and d.get("kind") == Stitched.kind:
        coordinates = mech.space.recorded("coordinates", ("coordinates",), ())
        _fields(d, _CONTROL_FIELDS["stitched"] + coordinates, where)
        if number_field(d, "T", where=f"{where}.") <= 0:
            fail(f"{where}.T", f"must be positive, got {d['T']}")
        pieces = d["pieces"]
        if not isinstance(pieces, list) or not pieces:
            fail(f"{where}.pieces", "must be a non-empty list")
        for i, p in enumerate(pieces):
            _physical(p, mech, f"{where}.pieces[{i}]")
        W = _array(d["waypoints"], f"{where}.waypoints", (len(pieces) + 1, 3, 3))
        for i, R in enumerate(W):
            rotation_field(R, f"{where}.waypoints[{i}]")
        for key in coordinates:
            _array(d[key], f"{where}.{key}", (len(pieces) + 1, mech.n_coordinates))
    else:
        _physical(d, mech, where)
    try:
        return from_dict(d, mech)
    except (ValueError, TypeError, KeyError, IndexError, AttributeError) as exc:
        fail(where, f"cannot be rebuilt: {exc}")


def decode(d, mechanism=None) -> tuple[dict, bool]:
    """The fields of the plan described by a plan file's object, each checked for its type
    and shape and the controls rebuilt.

    Parameters
    ----------
    d : dict
        The plan file's JSON object.
    mechanism : Mechanism, optional
        The :class:`~nonholo.model.mechanism.Mechanism` of the name the file gives, for one
        that is not in the catalog (by default the catalog's of that name).

    Returns
    -------
    fields : dict
        Keyword arguments of :class:`~nonholo.io.result.PlanResult` (``kinematics``: the
        mechanism).
    version_1 : bool
        Whether ``d`` is of format ``nonholo.plan/1`` (no certificates).

    Raises
    ------
    ValueError
        Naming the field, if ``d`` is not a plan file's object, lacks a field or has one
        of the wrong type or shape; if ``mechanism`` is not of the file's name, or the
        catalog does not know the name.
    """
    if not isinstance(d, dict):
        raise ValueError(f"not a nonholo plan file: expected a JSON object, got {json_type(d)}")
    if d.get("format") not in (FORMAT, FORMAT_2, FORMAT_1):
        raise ValueError(f"not a nonholo plan file (format {short(d.get('format'))}, expected {FORMAT!r})")
    required = (_REQUIRED + (() if d["format"] == FORMAT_1 else _CERTIFIED)
                + (("route",) if d["format"] == FORMAT else ()))
    missing = [k for k in required if k not in d]
    if missing:
        raise ValueError(f"invalid plan: missing field{'s' if len(missing) > 1 else ''} "
                         f"{', '.join(map(repr, missing))}")
    unknown = [k for k in d if k not in _REQUIRED and k not in _OPTIONAL]
    if unknown:
        raise ValueError(f"invalid plan: unknown field{'s' if len(unknown) > 1 else ''} "
                         f"{', '.join(short(k) for k in unknown)}")
    for key in ("route", "stitched"):
        if key in d and d["format"] != FORMAT:
            raise ValueError(f"invalid plan: {key!r} is set in a file of format {d['format']!r}, "
                             "which has no global routes")
    d = {"sensitivity": None, "error_bound": None, "replay_steps": None,
         "route": "local", "stitched": None, **d}
    if not isinstance(d["success"], bool):
        raise ValueError(f"invalid plan: 'success' must be true or false, got {short(d['success'])}")
    name = string_field(d, "mechanism")
    mech = _mechanism(name, mechanism, d)
    par = _controls(d["controls"], mech)
    stitched = None
    if d["stitched"] is not None:
        if not isinstance(d["stitched"], dict) or d["stitched"].get("kind") != Stitched.kind:
            fail("stitched", "must be stitched controls ({\"kind\": \"stitched\", ...}) or null")
        stitched = _controls(d["stitched"], mech, "stitched")
    m = par.n_inputs
    options = d["options"]
    if not isinstance(options, dict):
        raise ValueError(f"invalid plan: 'options' must be an object, got {json_type(options)}")
    history = d["history"]
    if not isinstance(history, list) or not all(isinstance(r, dict) for r in history):
        raise ValueError("invalid plan: 'history' must be a list of objects")
    delta = d["delta"]
    coordinates = _coordinates(d, mech)
    fields = dict(
        success=d["success"], reason=string_field(d, "reason", empty=True),
        terminal_error=number_field(d, "terminal_error", null=True),
        min_delta=number_field(d, "min_delta", null=True),
        iterations=integer_field(d, "iterations", minimum=0), history=list(history),
        t=_array(d["t"], "t", (None,)), R=_array(d["R"], "R", (None, 3, 3)),
        u=_array(d["u"], "u", (None, m)),
        delta=None if delta is None else _array(delta, "delta", (None,)),
        parametrisation=par, mechanism=name, kinematics=mech, method=string_field(d, "method"),
        strategy=string_field(d, "strategy"), T=number_field(d, "T"),
        start=State(_array(d["R0"], "R0", (3, 3)), coordinates["q0"]),
        goal=State(_array(d["Rd"], "Rd", (3, 3)), coordinates["qd"]),
        steps=integer_field(d, "steps", minimum=1), seconds=number_field(d, "seconds", null=True),
        options=dict(options), sensitivity=number_field(d, "sensitivity", null=True),
        error_bound=number_field(d, "error_bound", null=True),
        replay_steps=None if d["replay_steps"] is None else integer_field(d, "replay_steps", minimum=2),
        route=string_field(d, "route"), stitched=stitched, made_by=_made_by(d.get("made_by")),
        q=coordinates["q"], errors=coordinates["errors"])
    return fields, d["format"] == FORMAT_1


def _made_by(value) -> dict | None:
    """The record of what made the plan (:mod:`nonholo.io.provenance`): names to short
    texts or nulls; a record, not a result, so only its type is checked."""
    if value is None:
        return None
    if not isinstance(value, dict) or len(value) > 32 or not all(
            isinstance(k, str) and len(k) <= 64 and (v is None or (isinstance(v, str) and len(v) <= _MADE_BY_TEXT))
            for k, v in value.items()):
        fail("made_by", f"must be an object of short texts or nulls, got {short(value)}")
    return dict(value)


def definition_fields(mechanism) -> dict:
    """The fields a plan file holds for a mechanism with a definition as data
    (:attr:`~nonholo.model.mechanism.Mechanism.definition`): ``mechanism_definition`` (its
    JSON form) and ``mechanism_digest`` (its SHA-256); none for one without (a catalog
    mechanism: its plans name it only).

    Parameters
    ----------
    mechanism : Mechanism
        The plan's mechanism.

    Returns
    -------
    dict
        The fields, or an empty dict.
    """
    definition = getattr(mechanism, "definition", None)
    if definition is None:
        return {}
    return {"mechanism_definition": definition_forms.json_data(definition),
            "mechanism_digest": definition_forms.digest(definition)}


def _defined(name: str, mechanism, d: dict):
    """The mechanism of a file carrying ``mechanism_definition``: its digest checked, then
    the definition checked as a mechanism file is and built (or ``mechanism``, if given,
    of the same definition)."""
    for key in ("mechanism_definition", "mechanism_digest"):
        if key not in d:
            other = ({"mechanism_definition", "mechanism_digest"} - {key}).pop()
            fail(key, f"is missing, but {other!r} is set (a plan carries both or neither)")
    definition, digest = d["mechanism_definition"], d["mechanism_digest"]
    if not isinstance(digest, str):
        fail("mechanism_digest", f"must be text (a SHA-256), got {json_type(digest)}")
    if not isinstance(definition, dict):
        fail("mechanism_definition", f"must be an object (a mechanism's definition), got {json_type(definition)}")
    try:
        actual = definition_forms.digest(definition)
    except ValueError as exc:
        fail("mechanism_definition", str(exc))
    if actual != digest:
        fail("mechanism_digest", f"does not match 'mechanism_definition' (whose SHA-256 is {actual}): the "
                                 "definition or its digest was changed")
    if mechanism is not None:
        mech = mechanism
        if mech.definition is None or definition_forms.digest(mech.definition) != digest:
            fail("mechanism_definition", f"differs from the definition of the mechanism given ({mech.name!r})")
    else:
        try:
            mech = _from_definition(definition)
        except ValueError as exc:
            raise ValueError(f"invalid plan: {exc}") from None
    if mech.name != name:
        fail("mechanism", f"is {name!r}, but 'mechanism_definition' defines {mech.name!r}")
    return mech


def _from_definition(definition: dict):
    """The mechanism of a plan's definition (user data: checked as a mechanism file is),
    built once per process (:func:`nonholo.model.catalog.resolve`)."""
    return catalog.resolve(definition, where=lambda field: f"'mechanism_definition.{field}'")


def _mechanism(name: str, mechanism, d: dict | None = None):
    """The mechanism of a plan whose file names ``name``: the one its definition gives
    (:func:`_defined`), else ``mechanism`` if given (it must be of that name), else the
    catalog's; ``ValueError`` saying to pass ``mechanism=`` for a name the catalog does not
    know."""
    if d is not None and ("mechanism_definition" in d or "mechanism_digest" in d):
        return _defined(name, mechanism, d)
    if mechanism is not None:
        mech = mechanism
        if mech.name != name:
            raise ValueError(f"invalid plan: 'mechanism': the plan is of mechanism {name!r}, but the "
                             f"mechanism given is {mech.name!r}")
        return mech
    try:
        return catalog.get(name)
    except ValueError:
        raise ValueError(f"invalid plan: 'mechanism': unknown mechanism {name!r}; known: "
                         f"{', '.join(catalog.names())}. A plan of a mechanism that is not in the catalog "
                         f"loads with PlanResult.load(path, mechanism=m), m the nonholo.Mechanism "
                         f"{name!r}") from None


def parse(text: str):
    """The JSON value of a plan file's text.

    Parameters
    ----------
    text : str
        The file's text.

    Returns
    -------
    object
        The JSON value.

    Raises
    ------
    ValueError
        If ``text`` is not JSON, is nested too deeply, or has an object with a key twice.
    """
    try:
        return json.loads(text, object_pairs_hook=_unique_keys)
    except RecursionError:
        raise ValueError("not a nonholo plan file: JSON nested too deeply") from None
    except ValueError as exc:      # json.JSONDecodeError, duplicate keys, huge integers
        raise ValueError(f"not a nonholo plan file: {exc}") from None


def read(path):
    """The JSON value in a plan file.

    Parameters
    ----------
    path : str or pathlib.Path
        The file (UTF-8, a byte-order mark accepted).

    Returns
    -------
    object
        The JSON value.

    Raises
    ------
    ValueError
        Starting with ``path``, if the file is not UTF-8 text or not JSON :func:`parse`
        accepts.
    """
    raw = Path(path).read_bytes()
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: not a nonholo plan file: not UTF-8 text ({exc.reason} at byte "
                         f"{exc.start})") from None
    try:
        return parse(text)
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None

