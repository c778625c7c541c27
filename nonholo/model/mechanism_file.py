"""A mechanism in one file: its equations as text in a TOML file, read as data, never run.

A mechanism file (``docs/guide/car_trailer.toml``)::

    name = "car_trailer"
    coordinates = ["x", "y", "theta", "phi", "theta1"]
    inputs = ["v", "w"]
    angles = ["theta", "phi", "theta1"]
    [parameters]
    L = 1.0
    [rates]
    x = "v*cos(theta)"
    theta = "v*tan(phi)/L"
    ...

Top-level keys (:data:`KEYS`): ``name``, ``inputs`` and ``coordinates`` with ``[rates]``
(one expression per coordinate) and/or ``omega`` (three expressions, an orientation on
SO(3), in the entries ``r11 … r33`` of ``R`` or of ``rotation``) are required; ``description``,
``angles``, ``[parameters]`` (numbers), ``delta`` (the singularity function), ``[units]``,
``[bounds]`` (``[bounds.inputs] v = [-1, 1]``, ``[bounds.coordinates] phi = [-0.6, 0.6]``,
``inf``/``-inf`` where free) and ``[drawing]`` (:class:`nonholo.model.drawing.Drawing`)
are optional. Expressions are text read by :func:`derivations.admission.parse` (numbers,
the declared names, ``+ - * / **`` and a fixed set of functions; nothing is evaluated).

:func:`read_file` reads and checks a file: every refusal is a ``ValueError`` naming the
file, the line and the field (``trailer.toml, line 12, rates.theta: …``). :func:`check`
checks the same data from elsewhere (a plan file's ``mechanism_definition``). The checked
data, the *definition*, is a plain dict of text, numbers and lists
(:attr:`nonholo.model.mechanism.Mechanism.definition`); :func:`arguments` turns it into the
arguments of :meth:`~nonholo.model.mechanism.Mechanism.from_equations`, :func:`toml_text`
into a file's text, :func:`digest` into its SHA-256.
"""
from __future__ import annotations

import hashlib
import json
import keyword
import math
import numbers
import os
import re
import stat
from collections.abc import Mapping
from pathlib import Path
from typing import Callable

try:
    import tomllib
except ModuleNotFoundError:          # Python 3.10
    import tomli as tomllib

from . import drawing as drawings

#: The largest mechanism file read (bytes).
MAX_BYTES = 1_000_000
#: The keys a mechanism file may have, in the order :func:`toml_text` writes them.
KEYS = ("name", "description", "coordinates", "inputs", "angles", "omega", "rotation", "delta",
        "parameters", "rates", "units", "bounds", "drawing")
#: The most parameters a definition declares.
MAX_PARAMETERS = 256
#: The sections of ``[bounds]``.
BOUND_KINDS = ("inputs", "coordinates")
#: Names an expression reads as functions or constants: not to be declared.
RESERVED = frozenset(("sin", "cos", "tan", "cot", "sec", "csc", "asin", "acos", "atan", "atan2", "sinh",
                      "cosh", "tanh", "exp", "log", "sqrt", "cbrt", "abs", "Abs", "pi", "E"))

Where = Callable[[str], str]


# -- reading a file --------------------------------------------------------------------------

def read_bytes(path) -> bytes:
    """A mechanism file's bytes, if it is a regular file of at most :data:`MAX_BYTES`.

    Parameters
    ----------
    path : str or os.PathLike
        The file.

    Returns
    -------
    bytes
        Its content.

    Raises
    ------
    ValueError
        Naming ``path``, if it does not exist, is not a regular file (a directory, a FIFO,
        a device), is larger than :data:`MAX_BYTES` or cannot be read.
    """
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(path, flags)          # not blocking on a FIFO; its kind checked below
    except FileNotFoundError:
        raise ValueError(f"{path}: no such mechanism file") from None
    except OSError as exc:
        raise ValueError(f"{path}: cannot read the mechanism file ({exc.strerror or exc})") from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            kind = "a directory" if stat.S_ISDIR(info.st_mode) else "not a regular file"
            raise ValueError(f"{path}: is {kind}, not a mechanism file")
        if info.st_size > MAX_BYTES:
            raise ValueError(f"{path}: the mechanism file has {info.st_size:,} bytes, more than "
                             f"{MAX_BYTES:,}")
        chunks, size = [], 0
        while size <= MAX_BYTES:
            chunk = os.read(fd, MAX_BYTES + 1 - size)
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
        if size > MAX_BYTES:                  # grew while read
            raise ValueError(f"{path}: the mechanism file has more than {MAX_BYTES:,} bytes")
        return b"".join(chunks)
    except OSError as exc:
        raise ValueError(f"{path}: cannot read the mechanism file ({exc.strerror or exc})") from None
    finally:
        os.close(fd)


def parse_bytes(raw: bytes, name: str) -> tuple[dict, Where]:
    """The definition in a mechanism file's bytes, checked (:func:`check`).

    Parameters
    ----------
    raw : bytes
        The file's content (UTF-8 TOML).
    name : str
        The file's name, for messages.

    Returns
    -------
    definition : dict
        The checked definition.
    where : callable
        ``where(field)``: ``"<name>, line <n>, <field>"``, the place of a field in the file.

    Raises
    ------
    ValueError
        Naming the file, the line and the field.
    """
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw[:exc.start].count(b"\n") + 1
        raise ValueError(f"{name}, line {line}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(syntax_message(name, text, str(exc))) from None
    except RecursionError:
        raise ValueError(f"{name}, line 1: the TOML is nested too deeply") from None
    where = located_in(name, text)
    return check(data, where), where


def read_file(path) -> tuple[dict, Where]:
    """The definition in a mechanism file, checked.

    Parameters
    ----------
    path : str or os.PathLike
        The file (TOML, at most :data:`MAX_BYTES`).

    Returns
    -------
    definition : dict
        The checked definition (see the module).
    where : callable
        ``where(field)``: the field's place in the file, for messages.

    Raises
    ------
    ValueError
        Naming the file (and, for its content, the line and the field).
    """
    return parse_bytes(read_bytes(path), str(path))


def read(path) -> dict:
    """The definition in a mechanism file, checked (:func:`read_file`).

    Parameters
    ----------
    path : str or os.PathLike
        The file.

    Returns
    -------
    dict
        The definition.

    Raises
    ------
    ValueError
        Naming the file, the line and the field.
    """
    return read_file(path)[0]


def syntax_message(name: str, text: str, message: str) -> str:
    """A TOML syntax error's message naming the file, the line and the field there.

    Parameters
    ----------
    name : str
        The file's name.
    text : str
        Its text.
    message : str
        ``tomllib``'s message (``"Invalid value (at line 3, column 5)"``).

    Returns
    -------
    str
        ``"<name>, line 3, column 5, rates.x: invalid TOML: Invalid value"``.
    """
    match = re.search(r"\s*\(at line (\d+), column (\d+)\)\s*$", message)
    if match:
        line, column = int(match.group(1)), int(match.group(2))
        detail = message[:match.start()]
        place = f"line {line}, column {column}"
    else:
        line = max(1, text.count("\n") + (0 if text.endswith("\n") else 1))
        detail = re.sub(r"\s*\(at end of document\)\s*$", "", message)
        place = f"line {line} (the end)"
    return f"{name}, {place}, {field_at(text, line)}: invalid TOML: {detail}"


# -- where a field is -------------------------------------------------------------------------

_BARE = r"[A-Za-z0-9_-]+|\"(?:[^\"\\]|\\.)*\"|'[^']*'"
_KEY = re.compile(rf"^\s*((?:{_BARE})(?:\s*\.\s*(?:{_BARE}))*)\s*=")
_HEADER = re.compile(rf"^\s*(\[\[?)\s*((?:{_BARE})(?:\s*\.\s*(?:{_BARE}))*)\s*\]\]?")


def _key_parts(text: str) -> tuple[str, ...]:
    parts = re.findall(_BARE, text)
    return tuple(p[1:-1] if p[:1] in "\"'" else p for p in parts)


def key_lines(text: str) -> list[tuple[tuple, int]]:
    """Every table header and key of a TOML text with its line, found by scanning the
    text (it need not be valid TOML).

    Parameters
    ----------
    text : str
        The text.

    Returns
    -------
    list of tuple
        ``(path, line)``: ``path`` the keys from the top (an entry of an array of tables
        as its index, ``("drawing", "bodies", 1, "x")``), ``line`` from 1.
    """
    out, table, counts, quote = [], (), {}, None
    for n, line in enumerate(text.splitlines(), 1):
        if quote is not None:                    # inside a multi-line string
            if line.count(quote) % 2:
                quote = None
            continue
        header = _HEADER.match(line)
        if header:
            path = _key_parts(header.group(2))
            if header.group(1) == "[[":
                counts[path] = counts.get(path, -1) + 1
                path = path + (counts[path],)
            table = path
            out.append((table, n))
            continue
        key = _KEY.match(line)
        if key:
            out.append((table + _key_parts(key.group(1)), n))
            rest = line[key.end():]
            for q in ('"""', "'''"):
                if rest.count(q) % 2:
                    quote = q
    return out


def _path(field: str) -> tuple:
    """``"drawing.bodies[1].x"`` as ``("drawing", "bodies", 1, "x")``."""
    out = []
    for part in field.split("."):
        name, *indices = re.split(r"\[(\d+)\]", part)
        out.append(name)
        out += [int(i) for i in indices if i]
    return tuple(p for p in out if p != "")


def line_of(text: str, field: str) -> int:
    """The line of a field in a TOML text: its key's, else that of the nearest enclosing
    table or key (an inline table), else 1.

    Parameters
    ----------
    text : str
        The file's text.
    field : str
        The field, dotted (``"rates.theta"``, ``"bounds.inputs.v"``, ``"drawing.bodies[1].x"``).

    Returns
    -------
    int
        The line, from 1.
    """
    want = _path(field)
    best, length = 1, 0
    for path, n in key_lines(text):
        if path == want:
            return n
        if len(path) > length and want[:len(path)] == path:
            best, length = n, len(path)
    return best


def field_at(text: str, line: int) -> str:
    """The field written at a line of a TOML text (its key there, else its table).

    Parameters
    ----------
    text : str
        The text.
    line : int
        The line, from 1.

    Returns
    -------
    str
        The dotted field, or ``"(top level)"``.
    """
    lines = text.splitlines()
    table = ()
    for path, n in key_lines(text):
        if n > line:
            break
        if n == line:
            return _dotted(path)
        if _HEADER.match(lines[n - 1]):
            table = path
    return _dotted(table) if table else "(top level)"


def _dotted(path: tuple) -> str:
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else p)
    return out


def located_in(name: str, text: str) -> Where:
    """``where(field)`` for a file: ``"<name>, line <n>, <field>"``.

    Parameters
    ----------
    name : str
        The file's name.
    text : str
        Its text.

    Returns
    -------
    callable
        The locator.
    """
    return lambda field: f"{name}, line {line_of(text, field)}, {field}"


def labelled(label: str) -> Where:
    """``where(field)`` for data from elsewhere: ``"<label>.<field>"``.

    Parameters
    ----------
    label : str
        Names the data (``"definition"``, ``"'mechanism_definition"``).

    Returns
    -------
    callable
        The locator.
    """
    return lambda field: f"{label}.{field}"


# -- checking the data ---------------------------------------------------------------------

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


# -- the definition's uses ---------------------------------------------------------------------

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


def bounds_of(definition: Mapping) -> dict | None:
    """A definition's bounds as :attr:`~nonholo.model.mechanism.Mechanism.bounds` holds them.

    Parameters
    ----------
    definition : mapping
        A checked definition.

    Returns
    -------
    dict or None
        ``{"inputs": {name: (low, high)}, "coordinates": {name: (low, high)}}`` (``±inf``
        where free); ``None`` without bounds.
    """
    if "bounds" not in definition:
        return None
    return {kind: {k: (float(lo), float(hi)) for k, (lo, hi) in definition["bounds"].get(kind, {}).items()}
            for kind in BOUND_KINDS}


def arguments(definition: Mapping) -> dict:
    """The keyword arguments of :meth:`~nonholo.model.mechanism.Mechanism.from_equations`
    for a checked definition: SymPy symbols for the names, expressions as text.

    Parameters
    ----------
    definition : mapping
        A checked definition (:func:`check`).

    Returns
    -------
    dict
        ``name``, ``inputs``, ``coordinates``, ``rates``, ``omega``, ``rotation``,
        ``angles``, ``parameters``, ``delta``, ``units``, ``description``.
    """
    import sympy as sp

    symbol = sp.Symbol
    coordinates = [symbol(c) for c in definition.get("coordinates", ())]
    by_name = {str(s): s for s in coordinates}
    rotation = definition.get("rotation")
    units = definition.get("units")
    return dict(
        name=definition["name"], inputs=[symbol(u) for u in definition["inputs"]], coordinates=coordinates,
        rates=[definition["rates"][c] for c in definition.get("coordinates", ())],
        omega=list(definition["omega"]) if "omega" in definition else None,
        rotation=None if rotation is None else sp.Matrix([[symbol(e) for e in row] for row in rotation]),
        angles=[by_name[a] for a in definition.get("angles", ())],
        parameters={symbol(k): v for k, v in definition.get("parameters", {}).items()} or None,
        delta=definition.get("delta"),
        units=None if units is None else {by_name[c]: u for c, u in units.items()},
        description=definition.get("description"))


def recorded(name, arguments_given: Mapping) -> dict | None:
    """The definition of :meth:`~nonholo.model.mechanism.Mechanism.from_equations`'s
    arguments as data: names as text, SymPy expressions as their text (``str``, floats
    to all their digits), parameters' values as numbers; ``None`` if that data is not a
    definition :func:`check` accepts (a mechanism file cannot hold it).

    Parameters
    ----------
    name : str
        The mechanism's name.
    arguments_given : mapping
        The keyword arguments given (``inputs``, ``coordinates``, ``rates``, ``omega``,
        ``rotation``, ``angles``, ``parameters``, ``delta``, ``units``, ``description``).

    Returns
    -------
    dict or None
        The checked definition.
    """
    try:
        a = arguments_given
        coordinates = _texts(a.get("coordinates", ()))
        data: dict = {"name": name}
        if a.get("description") is not None:
            data["description"] = a["description"]
        if coordinates:
            data["coordinates"] = coordinates
        data["inputs"] = _texts(a["inputs"])
        if a.get("angles"):
            data["angles"] = _texts(a["angles"])
        if a.get("omega") is not None:
            data["omega"] = [expression_text(e) for e in _sequence(a["omega"])]
            if a.get("rotation") is not None:
                rows = a["rotation"].tolist() if hasattr(a["rotation"], "tolist") else a["rotation"]
                data["rotation"] = [[str(e) for e in row] for row in rows]
        if a.get("delta") is not None:
            data["delta"] = expression_text(a["delta"])
        if a.get("parameters"):
            data["parameters"] = {str(k): _number(v) for k, v in a["parameters"].items()}
        if coordinates:
            rates = [expression_text(e) for e in _sequence(a.get("rates", ()))]
            if len(rates) != len(coordinates):
                return None
            data["rates"] = dict(zip(coordinates, rates))
        units = a.get("units")
        if units is not None:
            items = units.items() if isinstance(units, Mapping) else zip(coordinates, units)
            data["units"] = {str(k): v for k, v in items}
        return check(data)
    except (ValueError, TypeError, AttributeError, KeyError):
        return None


def _sequence(values) -> list:
    if isinstance(values, (str, bytes)) or not hasattr(values, "__iter__"):
        return [values]
    return list(values)


def _texts(values) -> list[str]:
    return [str(v) for v in _sequence(values)]


def _number(value):
    if isinstance(value, bool):
        raise TypeError("a boolean is not a parameter's value")
    if isinstance(value, numbers.Integral):
        return int(value)
    return float(value)


def expression_text(value) -> str:
    """An expression as the text :func:`derivations.admission.parse` reads back: text as
    it is, a number by ``repr``, a SymPy expression by SymPy's printer with floats to all
    their digits.

    Parameters
    ----------
    value : str, number or sympy.Expr
        The expression.

    Returns
    -------
    str
        Its text.

    Raises
    ------
    TypeError
        For a boolean.
    """
    if isinstance(value, str):
        return value
    if isinstance(value, bool):
        raise TypeError("a boolean is not an expression")
    if isinstance(value, (int, float)):
        return repr(value)
    from sympy.printing.str import StrPrinter

    class Printer(StrPrinter):
        def _print_Float(self, expr):
            return repr(float(expr))

    return Printer().doprint(value)


def json_data(definition: Mapping) -> dict:
    """A definition as JSON can hold it: infinite bounds as the text ``"inf"``/``"-inf"``
    (which :func:`check` reads back).

    Parameters
    ----------
    definition : mapping
        A definition.

    Returns
    -------
    dict
        A copy without infinite floats.
    """
    def plain(x):
        if isinstance(x, float) and math.isinf(x):
            return "inf" if x > 0 else "-inf"
        if isinstance(x, Mapping):
            return {k: plain(v) for k, v in x.items()}
        if isinstance(x, (list, tuple)):
            return [plain(v) for v in x]
        return x

    return plain(definition)


def digest(definition) -> str:
    """The SHA-256 of a definition: of its canonical JSON (:func:`json_data`, keys sorted).

    Parameters
    ----------
    definition : mapping
        A definition (checked or as found in a file).

    Returns
    -------
    str
        The hex digest.

    Raises
    ------
    ValueError
        If ``definition`` is not JSON data.
    """
    try:
        text = json.dumps(json_data(definition), sort_keys=True, separators=(",", ":"), ensure_ascii=True,
                          allow_nan=False)
    except (TypeError, ValueError, RecursionError) as exc:
        raise ValueError(f"the definition is not JSON data ({exc})") from None
    return hashlib.sha256(text.encode()).hexdigest()


def toml_text(definition: Mapping) -> str:
    """A mechanism file's text for a definition, checked: it reads back (:func:`check`)
    to the same definition.

    Parameters
    ----------
    definition : mapping
        A checked definition.

    Returns
    -------
    str
        The TOML text.

    Raises
    ------
    ValueError
        If the text would not read back to ``definition``.
    """
    import tomli_w

    head = f"# the mechanism {definition['name']!r}: nonholo.Mechanism.from_file reads this file\n"
    text = head + tomli_w.dumps({k: definition[k] for k in KEYS if k in definition})
    back = check(tomllib.loads(text))
    if back != dict(definition):
        raise ValueError(f"the mechanism file of {definition['name']!r} would not read back to its definition")
    return text


def write(definition: Mapping, path) -> Path:
    """Write a mechanism file (:func:`toml_text`), atomically: a complete new file replaces
    ``path``.

    Parameters
    ----------
    definition : mapping
        A checked definition.
    path : str or os.PathLike
        The file.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    ValueError
        Naming ``path`` if it exists and is not a regular file.
    OSError
        If writing fails (an existing file is then untouched).
    """
    path = Path(path)
    if path.exists() and not path.is_file():
        raise ValueError(f"{path}: is not a regular file; not written")
    text = toml_text(definition)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


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
