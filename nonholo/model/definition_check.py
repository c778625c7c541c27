"""A mechanism's definition checked: the data of a mechanism file (or of a plan file's
``mechanism_definition``) refused field by field, or normalised.

Top-level keys (:data:`KEYS`): ``name``, ``inputs`` and ``coordinates`` with ``[rates]``
(one expression per coordinate) and/or ``omega`` (three expressions, an orientation on
SO(3), in the entries ``r11 … r33`` of ``R`` or of ``rotation``) are required; ``description``,
``angles``, ``[parameters]`` (numbers), ``delta`` (the singularity function), ``[units]``,
``[bounds]`` (``[bounds.inputs] v = [-1, 1]``, ``[bounds.coordinates] phi = [-0.6, 0.6]``,
``inf``/``-inf`` where free) and ``[drawing]`` (:class:`nonholo.model.drawing.Drawing`)
are optional. Expressions are text read by :func:`derivations.admission.parse` (numbers,
the declared names, ``+ - * / **`` and a fixed set of functions; nothing is evaluated).

:func:`check` checks the data: every refusal is a ``ValueError`` naming the field where a
locator (:mod:`nonholo.model.field_places`) puts it (``trailer.toml, line 12, rates.theta:
…``). The checked data, the *definition*, is a plain dict of text, numbers and lists
(:attr:`nonholo.model.mechanism.Mechanism.definition`). :func:`drawing_of` checks and builds
its drawing; :func:`located` places a message of
:meth:`~nonholo.model.mechanism.Mechanism.from_equations` about a definition at its field.
"""
from __future__ import annotations

import keyword
import math
import re
from collections.abc import Mapping

from . import drawing as drawings
from .field_places import Where

#: The keys a mechanism file may have, in the order
#: :func:`~nonholo.model.mechanism_file.toml_text` writes them.
KEYS = ("name", "description", "coordinates", "inputs", "angles", "omega", "rotation", "delta",
        "parameters", "rates", "units", "bounds", "drawing")
#: The most parameters a definition declares.
MAX_PARAMETERS = 256
#: The sections of ``[bounds]``.
BOUND_KINDS = ("inputs", "coordinates")
#: Names an expression reads as functions or constants: not to be declared.
RESERVED = frozenset(("sin", "cos", "tan", "cot", "sec", "csc", "asin", "acos", "atan", "atan2", "sinh",
                      "cosh", "tanh", "exp", "log", "sqrt", "cbrt", "abs", "Abs", "pi", "E"))


def check(data, where: Where | None = None) -> dict:
    """A mechanism's definition checked and normalised (see the module).

    Every name is a Python identifier, not a keyword nor a function's or constant's name
    (:data:`RESERVED`), declared once; every expression is read by
    :func:`derivations.admission.expression` in the declared names (never evaluated);
    parameters are finite real numbers (not text); every input is used by a rate; the
    bounds are numbers with low <= high; the drawing is checked by
    :meth:`nonholo.model.drawing.Drawing.from_mapping`.

    Parameters
    ----------
    data : mapping
        The definition as data (a TOML file's table, a plan file's JSON object).
    where : callable, optional
        ``where(field)``: the place of a field, for messages (default: the field itself).

    Returns
    -------
    dict
        The definition: keys in the order of :data:`KEYS`, optional ones only when given
        and not empty; rates by coordinate in the order of the coordinates; bounds as
        ``[low, high]`` floats.

    Raises
    ------
    ValueError
        ``"<where(field)>: <why>"`` for the first field refused.
    """
    import sympy as sp

    from derivations import admission, budget
    from derivations.mechanisms import is_free_name
    from derivations.rotations import r

    at = where or (lambda field: field)

    def refuse(field: str, why: str):
        raise ValueError(f"{at(field)}: {why}")

    if not isinstance(data, Mapping):
        refuse("(top level)", f"must be a table of the keys {', '.join(KEYS)}, got {_kind(data)}")
    for key in data:
        if key not in KEYS:
            refuse(str(key), f"is not a key of a mechanism file (known: {', '.join(KEYS)})")
    if "name" not in data:
        refuse("name", "is missing: a mechanism file needs name, inputs, and coordinates with [rates] "
                       "or omega")
    name = data["name"]
    if not isinstance(name, str) or not name.isidentifier() or keyword.iskeyword(name):
        refuse("name", f"must be a Python identifier that is not a keyword (it names the generated module), "
                       f"got {_shown(name)}")
    out: dict = {"name": name}
    if "description" in data:
        try:
            out["description"] = admission.check_text(data["description"], "description")
        except ValueError as exc:
            refuse("description", _detail(exc, "description"))
    declared: dict[str, str] = {}

    def names(key: str, limit: int, required: bool = False) -> list[str]:
        value = data.get(key, [])
        if key not in data and required:
            refuse(key, "is missing")
        if not isinstance(value, list):
            refuse(key, f"must be a list of names, got {_kind(value)}")
        if len(value) > limit:
            refuse(key, f"has {len(value)} names, more than {limit}")
        for item in value:
            if not isinstance(item, str):
                refuse(key, f"must be a list of names (text), got {_shown(item)} ({_kind(item)})")
            _name(item, key, refuse)
            if value.count(item) > 1:
                refuse(key, f"names {item!r} twice")
        return list(value)

    coordinates = names("coordinates", budget.COORDINATES)
    for c in coordinates:
        if not is_free_name(c):
            refuse("coordinates", f"{c!r} needs another name: the generated code uses R, q, v, out, numpy, "
                                  "r11 … r33 and s0, u0, v0, … itself")
        declared[c] = "coordinates"
    inputs = names("inputs", budget.INPUTS, required=True)
    if not inputs:
        refuse("inputs", "must name at least one input")
    for u in inputs:
        if u in declared:
            refuse("inputs", f"{u!r} is also one of the {declared[u]}")
        declared[u] = "inputs"
    if coordinates:
        out["coordinates"] = coordinates
    out["inputs"] = inputs
    angles = names("angles", budget.COORDINATES)
    for a in angles:
        if a not in coordinates:
            refuse("angles", f"{a!r} is not one of the coordinates ({', '.join(coordinates) or 'none'})")
    if angles:
        out["angles"] = angles
    rotation = None
    if "omega" in data:
        if "rotation" in data:
            rows = data["rotation"]
            if not (isinstance(rows, list) and len(rows) == 3 and all(isinstance(row, list) and len(row) == 3
                                                                       for row in rows)):
                refuse("rotation", f"must be 3 lists of 3 names (the entries of R), got {_shown(rows)}")
            entries = [e for row in rows for e in row]
            for e in entries:
                if not isinstance(e, str):
                    refuse("rotation", f"must hold names (text), got {_shown(e)}")
                _name(e, "rotation", refuse)
                if entries.count(e) > 1:
                    refuse("rotation", f"names {e!r} twice")
            rotation = [list(row) for row in rows]
        entries = [e for row in rotation for e in row] if rotation else [str(s) for s in r]
        for e in entries:
            if e in declared:
                refuse("rotation" if rotation else "omega", f"{e!r}, an entry of the rotation, is also one of "
                                                            f"the {declared[e]}")
            declared[e] = "rotation"
    elif "rotation" in data:
        refuse("rotation", "is given without omega (the rotation's entries are the names omega is written in)")
    elif not coordinates:
        refuse("coordinates", "is missing: give coordinates with [rates] (a state in R^k), omega (an "
                              "orientation on SO(3)) or both")
    parameters = {}
    raw = data.get("parameters", {})
    if not isinstance(raw, Mapping):
        refuse("parameters", f"must be a table of names and numbers, got {_kind(raw)}")
    if len(raw) > MAX_PARAMETERS:
        refuse("parameters", f"has {len(raw)} parameters, more than {MAX_PARAMETERS}")
    for k, v in raw.items():
        _name(k, f"parameters.{k}", refuse)
        if k in declared:
            refuse(f"parameters.{k}", f"{k!r} is also one of the {declared[k]}")
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            refuse(f"parameters.{k}", f"must be a number, got {_shown(v)} ({_kind(v)}; text is never "
                                      "evaluated)")
        try:
            admission.constant(v, f"parameters.{k}")
        except ValueError as exc:
            refuse(f"parameters.{k}", _detail(exc, f"parameters.{k}"))
        parameters[k] = v
        declared[k] = "parameters"
    rows_r = rotation if rotation else [[str(r[i, j]) for j in range(3)] for i in range(3)]
    symbols = {n: sp.Symbol(n) for n in declared}
    if "omega" in data:
        for i in range(3):
            for j in range(3):
                symbols[rows_r[i][j]] = sp.Symbol(rows_r[i][j]) if rotation else r[i, j]
    tally = budget.Tally(f"mechanism {name!r}")
    used = set()

    def expression(value, field: str) -> str:
        if isinstance(value, bool) or not isinstance(value, (str, int, float)):
            refuse(field, f"must be an expression (text), got {_shown(value)} ({_kind(value)})")
        text = value if isinstance(value, str) else repr(value)
        expr = admission.expression(text, at(field), symbols, tally)
        used.update(expr.free_symbols)
        return text

    if "omega" in data:
        omega = data["omega"]
        if not isinstance(omega, list) or len(omega) != 3:
            refuse("omega", f"must be a list of 3 expressions (the spatial angular velocity), got {_shown(omega)}")
        out["omega"] = [expression(e, f"omega[{i}]") for i, e in enumerate(omega)]
        if rotation:
            out["rotation"] = rotation
    rates = data.get("rates", {})
    if not isinstance(rates, Mapping):
        refuse("rates", f"must be a table of a rate (text) per coordinate, got {_kind(rates)}")
    for k in rates:
        if k not in coordinates:
            refuse(f"rates.{k}", f"is not one of the coordinates ({', '.join(coordinates) or 'none'})")
    for c in coordinates:
        if c not in rates:
            refuse(f"rates.{c}", "is missing: every coordinate needs its rate")
    if coordinates:
        out["rates"] = {c: expression(rates[c], f"rates.{c}") for c in coordinates}
    unused = [u for u in inputs if symbols[u] not in used]
    if unused:
        refuse("inputs", f"{unused[0]!r} is used by no rate{'' if 'omega' not in out else ' nor omega'}: "
                         "every input must move the mechanism")
    if "delta" in data:
        out["delta"] = expression(data["delta"], "delta")
    if parameters:
        out["parameters"] = parameters
    units = data.get("units", {})
    if not isinstance(units, Mapping):
        refuse("units", f"must be a table of a unit (text) per coordinate, got {_kind(units)}")
    for k, v in units.items():
        if k not in coordinates:
            refuse(f"units.{k}", f"is not one of the coordinates ({', '.join(coordinates) or 'none'})")
        try:
            admission.check_text(v, f"units.{k}", limit=40)
        except ValueError as exc:
            refuse(f"units.{k}", _detail(exc, f"units.{k}"))
    if units:
        out["units"] = {c: units[c] for c in coordinates if c in units}
    if "bounds" in data:
        bounds = _bounds(data["bounds"], {"inputs": inputs, "coordinates": coordinates}, refuse)
        if bounds:
            out["bounds"] = bounds
    if "drawing" in data:
        out["drawing"] = drawing_of({**out, "drawing": data["drawing"]}, at).to_mapping()
    return {key: out[key] for key in KEYS if key in out}


def _name(value, field: str, refuse) -> None:
    if not isinstance(value, str) or not value.isidentifier() or keyword.iskeyword(value):
        refuse(field, f"{_shown(value)} is not a name (a Python identifier that is not a keyword)")
    if value in RESERVED:
        refuse(field, f"{value!r} is the name of a function or constant of the expressions; choose another")


def _bounds(data, names: dict, refuse) -> dict:
    if not isinstance(data, Mapping):
        refuse("bounds", f"must be a table with [bounds.inputs] and/or [bounds.coordinates], got {_kind(data)}")
    out = {}
    for kind, table in data.items():
        if kind not in BOUND_KINDS:
            refuse(f"bounds.{kind}", f"is not a kind of bounds (known: {', '.join(BOUND_KINDS)})")
        if not isinstance(table, Mapping):
            refuse(f"bounds.{kind}", f"must be a table of [low, high] by name, got {_kind(table)}")
        checked = {}
        for k, pair in table.items():
            field = f"bounds.{kind}.{k}"
            if k not in names[kind]:
                refuse(field, f"is not one of the {kind} ({', '.join(names[kind]) or 'none'})")
            if not isinstance(pair, list) or len(pair) != 2:
                refuse(field, f"must be [low, high], got {_shown(pair)}")
            low, high = (_bound(v, field, refuse) for v in pair)
            if not low <= high:
                refuse(field, f"has low > high ({low!r} > {high!r})")
            checked[k] = [low, high]
        if checked:
            out[kind] = {k: checked[k] for k in names[kind] if k in checked}
    return {kind: out[kind] for kind in BOUND_KINDS if kind in out}


def _bound(value, field: str, refuse) -> float:
    if isinstance(value, str) and value.strip().lower() in ("inf", "+inf", "-inf"):
        return -math.inf if value.strip().startswith("-") else math.inf
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        refuse(field, f"must hold numbers (inf and -inf where free), got {_shown(value)} ({_kind(value)})")
    value = float(value)
    if math.isnan(value):
        refuse(field, "holds nan, not a number")
    return value


def _detail(exc: ValueError, key: str) -> str:
    """A message of :mod:`derivations.admission` without its leading ``key``."""
    text = str(exc)
    for prefix in (f"{key}: ", f"{key} "):
        if text.startswith(prefix):
            return text[len(prefix):]
    return text


def _kind(value) -> str:
    return {str: "text", bool: "a boolean", int: "a number", float: "a number", list: "a list",
            dict: "a table"}.get(type(value), type(value).__name__)


def _shown(value) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:60] + "…" + text[-12:]


def drawing_of(definition: Mapping, where: Where | None = None):
    """The :class:`~nonholo.model.drawing.Drawing` of a definition's ``drawing`` (``None``
    without one).

    Parameters
    ----------
    definition : mapping
        A definition (its coordinates and parameters name what the drawing may use).
    where : callable, optional
        ``where(field)``, for messages.

    Returns
    -------
    Drawing or None
        The drawing.

    Raises
    ------
    ValueError
        Naming the field (``drawing.bodies[0].x``), for a drawing the class refuses.
    """
    if "drawing" not in definition:
        return None
    at = where or (lambda field: field)
    try:
        return drawings.Drawing.from_mapping(definition["drawing"], tuple(definition.get("coordinates", ())),
                                             dict(definition.get("parameters", {})), where="drawing")
    except ValueError as exc:
        text = str(exc)
        field, sep, why = text.partition(": ")
        if not sep or not field.startswith("drawing"):
            field, why = "drawing", text
        raise ValueError(f"{at(field)}: {why}") from None


def located(message: str, definition: Mapping, where: Where) -> str:
    """A message of :meth:`~nonholo.model.mechanism.Mechanism.from_equations` about a
    definition, prefixed with the place of the field it is about (``rates[2]`` is the rate
    of the third coordinate).

    Parameters
    ----------
    message : str
        The message.
    definition : mapping
        The definition.
    where : callable
        ``where(field)``.

    Returns
    -------
    str
        ``"<where(field)>: <message>"``.
    """
    coordinates = list(definition.get("coordinates", ()))
    field = None
    match = re.match(r"(rates|omega)\[(\d+)\]", message)
    if match:
        i = int(match.group(2))
        field = (f"rates.{coordinates[i]}" if match.group(1) == "rates" and i < len(coordinates)
                 else match.group(1))
    elif (match := re.match(r"the rate of (\w+) ", message)) and match.group(1) in coordinates:
        field = f"rates.{match.group(1)}"
    elif match := re.match(r"(parameters|units)(?:: |\[)(\w+)", message):
        field = f"{match.group(1)}.{match.group(2)}"
    else:
        first = re.match(r"\w+", message)
        if first and first.group(0) in KEYS:
            field = first.group(0)
    if field is None:
        field = "rates" if coordinates else "omega"
    return f"{where(field)}: {message}"
