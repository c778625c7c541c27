"""A checked mechanism definition (:mod:`nonholo.model.definition_check`) in its other forms.

:func:`arguments` turns it into the arguments of
:meth:`~nonholo.model.mechanism.Mechanism.from_equations` and :func:`recorded` those
arguments back into it; :func:`bounds_of` gives its bounds as
:attr:`~nonholo.model.mechanism.Mechanism.bounds` holds them; :func:`json_data` makes it
JSON data (a plan file's ``mechanism_definition``) and :func:`digest` its SHA-256;
:func:`expression_text` writes an expression as the text a definition holds.
"""
from __future__ import annotations

import hashlib
import json
import math
import numbers
from collections.abc import Mapping

from .definition_check import BOUND_KINDS, check


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
        A checked definition (:func:`~nonholo.model.definition_check.check`).

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
    rows = definition.get("rotation") or ()
    units = definition.get("units")
    return dict(
        name=definition["name"], inputs=[symbol(u) for u in definition["inputs"]], coordinates=coordinates,
        rates=[definition["rates"][c] for c in definition.get("coordinates", ())],
        omega=list(definition["omega"]) if "omega" in definition else None,
        rotation=sp.Matrix([[symbol(e) for e in row] for row in rows]) if rows else None,
        angles=[by_name[a] for a in definition.get("angles", ())],
        parameters={symbol(k): v for k, v in definition.get("parameters", {}).items()} or None,
        delta=definition.get("delta"),
        units=None if units is None else {by_name[c]: u for c, u in units.items()},
        description=definition.get("description"))


def recorded(name, arguments_given: Mapping) -> dict | None:
    """The definition of :meth:`~nonholo.model.mechanism.Mechanism.from_equations`'s
    arguments as data: names as text, SymPy expressions as their text (``str``, floats
    to all their digits), parameters' values as numbers; ``None`` if that data is not a
    definition :func:`~nonholo.model.definition_check.check` accepts (a mechanism file
    cannot hold it).

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
    (which :func:`~nonholo.model.definition_check.check` reads back).

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
