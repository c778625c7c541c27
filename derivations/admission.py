"""What a user gives for a mechanism is data: checked up front, never run.

A mechanism of one's own comes with text and numbers typed by a user: a name, a
description, units, parameters' values, expressions (SymPy's, or text). None of it becomes
code, and none of it reaches the derivation unchecked:

- :func:`check_name`: a name is a Python identifier and not a keyword (it names the
  generated module, its cached file and its compiled module);
- :func:`check_text`: a description, a unit or an input's name is a line of printable text
  (the generated module holds it only as an escaped literal, ``repr``);
- :func:`constant`: a parameter's value is a finite real number within float range
  (Python's, NumPy's or SymPy's). Text is refused: SymPy's ``sympify`` would hand it to
  Python's ``eval``;
- :func:`check_constants`: every constant in an expression is one too (no ``I``, ``oo``,
  ``nan``, ``zoo``, ``1e400``, ``10**400``, ``exp(1000)`` ...);
- :func:`expression`: an expression is SymPy's, a number, or text read by :func:`parse`,
  which walks Python's syntax tree of the text and admits only numbers, the declared
  symbols, ``+ - * / **`` and the functions of :data:`FUNCTIONS`, building the SymPy
  expression itself (nothing is evaluated);

each measured against :mod:`derivations.budget` first. Every refusal is a ``ValueError``
naming the argument.
"""
from __future__ import annotations

import ast
import cmath
import keyword
import math
import numbers
from collections.abc import Mapping

import sympy as sp

from . import budget

#: The functions an expression given as text may call, by name (with their arity).
FUNCTIONS = {
    "sin": (sp.sin, 1), "cos": (sp.cos, 1), "tan": (sp.tan, 1), "cot": (sp.cot, 1), "sec": (sp.sec, 1),
    "csc": (sp.csc, 1), "asin": (sp.asin, 1), "acos": (sp.acos, 1), "atan": (sp.atan, 1),
    "atan2": (sp.atan2, 2), "sinh": (sp.sinh, 1), "cosh": (sp.cosh, 1), "tanh": (sp.tanh, 1),
    "exp": (sp.exp, 1), "log": (sp.log, 1), "sqrt": (sp.sqrt, 1), "cbrt": (sp.cbrt, 1),
    "abs": (sp.Abs, 1), "Abs": (sp.Abs, 1),
}
#: The named constants an expression given as text may use.
CONSTANTS = {"pi": sp.pi, "E": sp.E}
#: The largest magnitude of a float.
FLOAT_MAX = 1.7976931348623157e308

_BINARY = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b, ast.Mult: lambda a, b: a * b,
           ast.Div: lambda a, b: a / b, ast.Pow: lambda a, b: a ** b}
_UNARY = {ast.UAdd: lambda a: a, ast.USub: lambda a: -a}
#: Complex arithmetic of the functions a constant may hold (:func:`numeric_value`).
_NUMERIC = {sp.sin: cmath.sin, sp.cos: cmath.cos, sp.tan: cmath.tan, sp.cot: lambda z: 1 / cmath.tan(z),
            sp.sec: lambda z: 1 / cmath.cos(z), sp.csc: lambda z: 1 / cmath.sin(z), sp.asin: cmath.asin,
            sp.acos: cmath.acos, sp.atan: cmath.atan, sp.sinh: cmath.sinh, sp.cosh: cmath.cosh,
            sp.tanh: cmath.tanh, sp.asinh: cmath.asinh, sp.acosh: cmath.acosh, sp.atanh: cmath.atanh,
            sp.exp: cmath.exp, sp.log: cmath.log, sp.Abs: abs,
            sp.atan2: lambda y, x: complex(math.atan2(y.real, x.real)) if not (y.imag or x.imag) else complex("nan"),
            sp.sign: lambda z: complex((z.real > 0) - (z.real < 0)) if not z.imag else z / abs(z)}


def check_name(name) -> str:
    """A mechanism's name: a Python identifier, not a keyword.

    Parameters
    ----------
    name : str
        The name; it names the generated module, its file in the cache and its compiled
        module, so it may hold no path separator, quote or space.

    Returns
    -------
    str
        ``name``.

    Raises
    ------
    ValueError
        Naming ``name``, if it is not an identifier or is a keyword.
    """
    if not isinstance(name, str) or not name.isidentifier() or keyword.iskeyword(name):
        raise ValueError(f"name must be a Python identifier that is not a keyword (it names the generated "
                         f"module and its files), got {name!r}")
    return name


def check_text(value, key: str, limit: int = 500) -> str:
    """A description, a unit or an input's name: one line of printable text.

    Parameters
    ----------
    value : str
        The text.
    key : str
        The argument, for the message.
    limit : int
        The most characters.

    Returns
    -------
    str
        ``value``.

    Raises
    ------
    ValueError
        Naming ``key``: not a string, not printable (a line break, a control character)
        or longer than ``limit``.
    """
    if not isinstance(value, str):
        raise ValueError(f"{key} must be a string, got {type(value).__name__}")
    if not value.isprintable():
        raise ValueError(f"{key} must be one line of printable text (no line breaks or control characters), "
                         f"got {value[:80]!r}")
    if len(value) > limit:
        raise ValueError(f"{key} has {len(value)} characters, more than {limit}")
    return value


def constant(value, key: str) -> sp.Expr:
    """A constant as SymPy's number, if it is a finite real number within float range.

    Parameters
    ----------
    value
        A Python or NumPy int or float, a fraction, or a SymPy number (an expression
        without symbols, such as ``sqrt(2)``). Never text: that is refused, not parsed.
    key : str
        What it is, for the message (``"parameters: d"``).

    Returns
    -------
    sympy.Expr
        The value.

    Raises
    ------
    ValueError
        Naming ``key``: text, a boolean, a complex, infinite, NaN or beyond-float value, or
        anything that is not a number.
    """
    if isinstance(value, (str, bytes)):
        raise ValueError(f"{key} = {_shown(value)} is text, not a number (text is never evaluated: give "
                         "the number)")
    if isinstance(value, bool):
        raise ValueError(f"{key} = {value!r} is not a number")
    if isinstance(value, numbers.Complex) and not isinstance(value, (numbers.Real, sp.Basic)):
        raise ValueError(f"{key} = {_shown(value)} is complex; the kinematics are real")
    if isinstance(value, numbers.Integral) and not isinstance(value, sp.Basic):
        value = int(value)
        if abs(value) > FLOAT_MAX:
            raise ValueError(f"{key} = {_shown(value)} is beyond float range (|x| <= {FLOAT_MAX:.4g})")
        return sp.Integer(value)
    try:
        number = value if isinstance(value, sp.Basic) else sp.sympify(value, strict=True)
    except (sp.SympifyError, TypeError, ValueError):
        raise ValueError(f"{key} = {_shown(value)} is not a number") from None
    if not isinstance(number, sp.Expr) or number.free_symbols or not number.is_number:
        raise ValueError(f"{key} = {_shown(value)} is not a number")
    budget.measure(number, key)
    _check_value(number, key, value)
    return number


def check_constants(expr, key: str) -> None:
    """Refuse an expression with a constant that is not a finite real number within float
    range: a number (``nan``, ``oo``, ``zoo``, ``I``, ``Float('1e400')``, ``10**400``) or a
    part without symbols (``exp(1000)``, ``asin(2)``), evaluated in complex floats.

    Parameters
    ----------
    expr : sympy.Expr
        The expression (within :func:`derivations.budget.measure`'s depth).
    key : str
        What it is, for the message.

    Raises
    ------
    ValueError
        Naming ``key`` and the constant.
    """
    def constant_part(e) -> bool:
        """Whether ``e`` has no symbol; checks its numbers and the constant parts of it
        that have symbols beside them."""
        if isinstance(e, sp.Symbol):
            return False
        if not e.args:
            if e.is_Number or e in (sp.I, sp.zoo, sp.nan) or isinstance(e, sp.NumberSymbol):
                _check_value(e, key, e)
            return True
        parts = [constant_part(a) for a in e.args]
        if all(parts):
            return True
        for a, c in zip(e.args, parts):
            if c and a.args:
                _check_value(a, key, a)
        return False

    if constant_part(expr) and getattr(expr, "args", ()):
        _check_value(expr, key, expr)


def numeric_value(expr) -> complex:
    """A constant expression's value in complex floats (Python's arithmetic, not SymPy's
    arbitrary precision, whose evaluation of ``exp(exp(exp(100)))`` does not end).

    Parameters
    ----------
    expr : sympy.Expr
        An expression without symbols.

    Returns
    -------
    complex
        Its value: ``inf`` or ``nan`` parts where it overflows or is undefined.
    """
    try:
        return _numeric(expr)
    except OverflowError:
        return complex(math.inf, 0.0)
    except (ZeroDivisionError, ValueError):
        return complex(math.nan, 0.0)


def _numeric(e) -> complex:
    if e.is_Integer:
        return complex(float(e)) if abs(int(e)) <= FLOAT_MAX else complex(math.inf)
    if e.is_Rational:
        return complex(float(e))
    if e.is_Float:
        return complex(float(e))
    if e is sp.I:
        return 1j
    if e in (sp.nan, sp.zoo) or e in (sp.oo, -sp.oo):
        return complex(math.nan if e in (sp.nan, sp.zoo) else math.inf)
    if isinstance(e, sp.NumberSymbol):
        return complex(float(e))
    if isinstance(e, sp.Add):
        return sum((_numeric(a) for a in e.args), 0j)
    if isinstance(e, sp.Mul):
        out = 1 + 0j
        for a in e.args:
            out *= _numeric(a)
        return out
    if isinstance(e, sp.Pow):
        base, exponent = _numeric(e.base), _numeric(e.exp)
        if not exponent.imag and float(exponent.real).is_integer() and abs(exponent.real) <= 64:
            return base ** int(exponent.real) if base or exponent.real >= 0 else complex(math.inf)
        return base ** exponent
    function = _NUMERIC.get(e.func)
    if function is not None:
        return complex(function(*(_numeric(a) for a in e.args)))
    return complex(sp.N(e, 17))          # any other SymPy constant


def _check_value(expr, key: str, shown) -> None:
    value = numeric_value(expr)
    if math.isnan(value.real) or math.isnan(value.imag):
        raise ValueError(f"{key}: the constant {_shown(shown)} is not a finite number (NaN or undefined)")
    if not (abs(value.real) <= FLOAT_MAX and abs(value.imag) <= FLOAT_MAX):
        raise ValueError(f"{key}: the constant {_shown(shown)} is infinite or beyond float range "
                         f"(|x| <= {FLOAT_MAX:.4g})")
    if abs(value.imag) > 1e-12 * max(1.0, abs(value.real)):
        raise ValueError(f"{key}: the constant {_shown(shown)} is complex ({value:.6g}); the "
                         "kinematics are real")


def expression(value, key: str, symbols: Mapping[str, sp.Symbol] | None = None,
               tally: budget.Tally | None = None) -> sp.Expr:
    """An expression given by a user, checked: SymPy's, a number, or text (:func:`parse`),
    within the budget (:mod:`derivations.budget`) and with real, finite constants
    (:func:`check_constants`).

    Parameters
    ----------
    value : sympy.Expr, number or str
        The expression.
    key : str
        What it is, for the message (``"rates[1]"``).
    symbols : mapping of str to sympy.Symbol, optional
        The declared symbols by name, for text.
    tally : derivations.budget.Tally, optional
        The definition's nodes so far.

    Returns
    -------
    sympy.Expr
        The expression.

    Raises
    ------
    ValueError
        Naming ``key``: not an expression, beyond the budget, a bad constant, or text
        that :func:`parse` refuses.
    """
    if isinstance(value, str):
        expr = parse(value, symbols or {}, key)
    elif isinstance(value, (bytes, bool)) or value is None:
        raise ValueError(f"{key}: {_shown(value)} is not a SymPy expression")
    elif isinstance(value, sp.Basic):
        expr = value
    else:
        try:
            expr = sp.sympify(value, strict=True)      # numbers; never text (that is parse's)
        except (sp.SympifyError, TypeError, ValueError):
            raise ValueError(f"{key}: {_shown(value)} is not a SymPy expression") from None
    if not isinstance(expr, sp.Expr):
        raise ValueError(f"{key}: {_shown(value)} is not a SymPy expression (an equation, a matrix or a "
                         "set is not)")
    if tally is None:
        budget.measure(expr, key)
    else:
        tally.add(expr, key)
    check_constants(expr, key)
    return expr


def symbol_table(symbols) -> dict[str, sp.Symbol]:
    """The declared symbols by name, for :func:`parse` (a name two symbols share maps to
    ``None``: text cannot tell them apart).

    Parameters
    ----------
    symbols : iterable of sympy.Symbol
        The declared symbols.

    Returns
    -------
    dict
        Name → symbol.
    """
    table: dict = {}
    for s in symbols:
        table[s.name] = s if table.get(s.name, s) == s else None
    return table


def parse(text: str, symbols: Mapping[str, sp.Symbol], key: str) -> sp.Expr:
    """An expression given as text, read without evaluating anything.

    Python's parser gives the syntax tree (``ast.parse(text, mode="eval")``); the tree is
    walked and the SymPy expression built node by node. Admitted: numbers (int, float),
    the declared ``symbols`` by name, ``pi`` and ``E``, ``+ - * / **`` and unary ``+ -``,
    and calls of the functions of :data:`FUNCTIONS` with plain arguments. Anything else —
    attribute access, subscripts, strings, keywords, lambdas, comprehensions, other names —
    is refused, as is text longer than :data:`derivations.budget.TEXT` or past the budget
    of nodes, depth and exponents.

    Parameters
    ----------
    text : str
        The expression, in Python's syntax (``"v*cos(theta)"``).
    symbols : mapping of str to sympy.Symbol
        The declared symbols by name (:func:`symbol_table`).
    key : str
        What it is, for the message.

    Returns
    -------
    sympy.Expr
        The expression.

    Raises
    ------
    ValueError
        Naming ``key`` and the piece of text refused.
    """
    if len(text) > budget.TEXT:
        raise ValueError(f"{key}: the text has {len(text)} characters, beyond the budget of the symbolic "
                         f"work (derivations.budget.TEXT = {budget.TEXT})")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        if "nested" in str(exc.msg):
            raise ValueError(f"{key}: the text is nested too deeply ({exc.msg}), beyond the budget of the "
                             f"symbolic work (depth at most derivations.budget.DEPTH = {budget.DEPTH})") from None
        raise ValueError(f"{key}: {_shown(text)} is not an expression ({exc.msg})") from None
    except (RecursionError, MemoryError):
        raise ValueError(f"{key}: the text is nested too deeply to read, beyond the budget of the symbolic "
                         f"work (depth at most derivations.budget.DEPTH = {budget.DEPTH})") from None
    count = [0]

    def refuse(node, why: str):
        piece = ast.get_source_segment(text.strip(), node) or type(node).__name__
        where = "" if piece == text.strip() else f" in {_shown(text)}"
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.BitXor):
            why += " (a power is written **)"
        raise ValueError(f"{key}: {_shown(piece)}{where} {why}; an expression given as text may hold only "
                         "numbers, the declared symbols, pi, E, + - * / ** and calls of "
                         f"{', '.join(FUNCTIONS)}")

    def build(node, depth: int) -> sp.Expr:
        count[0] += 1
        if count[0] > budget.NODES:
            raise ValueError(f"{key}: the text has more than {budget.NODES} nodes, beyond the size budget of "
                             f"the symbolic work (derivations.budget.NODES = {budget.NODES})")
        if depth > budget.DEPTH:
            raise ValueError(f"{key}: the text is nested more than {budget.DEPTH} deep, beyond the budget of "
                             f"the symbolic work (derivations.budget.DEPTH = {budget.DEPTH})")
        if isinstance(node, ast.Constant):
            if type(node.value) is int:
                return sp.Integer(node.value)
            if type(node.value) is float:
                return sp.Float(node.value)
            refuse(node, "is not a number (only int and float constants)")
        if isinstance(node, ast.Name):
            if node.id in symbols:
                if symbols[node.id] is None:
                    refuse(node, "names two declared symbols")
                return symbols[node.id]
            if node.id in CONSTANTS:
                return CONSTANTS[node.id]
            if node.id in FUNCTIONS:
                refuse(node, "is a function: call it")
            refuse(node, "is not declared: give it as a coordinate, an input or a parameter")
        if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
            left, right = build(node.left, depth + 1), build(node.right, depth + 1)
            if isinstance(node.op, ast.Pow) and right.is_Number:
                if not _power_ok(right):
                    refuse(node, f"has an exponent beyond the budget (magnitude at most {budget.POWER})")
                if left.is_Number and left != 0 and float(abs(right)) * math.log10(float(abs(left)) or 1) > 310:
                    refuse(node, "is beyond float range")
            return _BINARY[type(node.op)](left, right)
        if isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
            return _UNARY[type(node.op)](build(node.operand, depth + 1))
        if isinstance(node, ast.Call):
            name = node.func.id if isinstance(node.func, ast.Name) else None
            if name not in FUNCTIONS:
                refuse(node, "is not a call of an allowed function")
            if node.keywords or any(isinstance(a, ast.Starred) for a in node.args):
                refuse(node, "passes keywords or unpacked arguments")
            function, arity = FUNCTIONS[name]
            if len(node.args) != arity:
                refuse(node, f"gives {len(node.args)} argument(s); {name} takes {arity}")
            return function(*(build(a, depth + 1) for a in node.args))
        refuse(node, "is not allowed")

    return build(tree.body, 1)


def _power_ok(exponent) -> bool:
    try:
        return bool(exponent.is_finite) and bool(abs(exponent) <= budget.POWER)
    except TypeError:
        return False


def _shown(value) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:60] + "…" + text[-12:]
