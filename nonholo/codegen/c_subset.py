"""The subset of Python translated to C: argument kinds, NumPy's element functions, the
functions to translate (:class:`Function`) and the error for anything else.

The kernels (:mod:`nonholo.generated.cf4_kernels`, the generated fields, the small
numerics of :mod:`nonholo.numerics.kernels`) are written once, in the subset of Python
that numba compiles. :func:`nonholo.codegen.c_translation.translate` turns such functions
into C99 with the same arithmetic in the same order, and
:func:`nonholo.codegen.c_extension.extension_source` wraps them as a CPython extension
module; :mod:`nonholo.codegen.build` compiles and loads it.

Conventions of the subset (checked; anything else raises :class:`TranslationError`):

- Arguments have declared kinds (:data:`KINDS`): ``"f8"``, ``"i8"``, ``"b1"`` scalars, or
  C-contiguous arrays ``"f8[1]"``, ``"f8[2]"``, ``"f8[3]"``, ``"i8[3]"`` (dtype and number of
  dimensions). An array is a pointer with its shape; an index with fewer subscripts than
  dimensions is a view (a pointer into the array). Indices are non-negative.
- Statements: assignment (also to several names, to a tuple, to an element or to every
  element ``A[:, :] = x``), augmented assignment, ``for … in range(…)``, ``if``/``else``,
  ``break``, ``continue``, ``return`` (a scalar or a tuple of scalars), calls.
- Local arrays (``np.empty``, ``np.zeros``, ``x.copy()``) live on the stack of the function
  (``alloca``), so they may not be made inside a loop. Locals are typed by what is assigned
  to them (``double`` unless every value is an integer or a truth value).
- ``/`` is true division, ``min``/``max`` keep Python's order (``min(a, b) = b if b < a else
  a``), ``**`` is ``pow`` but for a constant integer exponent ``|n| ≤ 4``, which is a product
  (and its reciprocal for ``n < 0``: what numba's fast-math makes of it, round-off apart);
  NumPy's element functions map to C's ``<math.h>``.
- A call of a function whose body is ``return (a, b, …)`` assigned to a tuple of names is
  expanded in place (the allocations of a workspace).
- ``np.dot(A.T, B.reshape((r, c)))`` (the one matrix product, of the dense Jacobian) is a
  loop over the rows of ``A`` and ``B``.
"""
from __future__ import annotations

import ast
import functools
import inspect
import textwrap
from dataclasses import dataclass, field

#: The kinds of an argument: C type and, for arrays, the number of dimensions.
KINDS = {
    "f8": ("double", 0), "i8": ("int64_t", 0), "b1": ("int", 0),
    "f8[1]": ("double", 1), "f8[2]": ("double", 2), "f8[3]": ("double", 3),
    "i8[1]": ("int64_t", 1), "i8[2]": ("int64_t", 2), "i8[3]": ("int64_t", 3),
}

#: NumPy element functions and their C names.
MATH = {
    "sqrt": "sqrt", "sin": "sin", "cos": "cos", "tan": "tan", "arctan2": "atan2", "arctan": "atan",
    "arcsin": "asin", "arccos": "acos", "exp": "exp", "log": "log", "cbrt": "cbrt", "abs": "fabs",
    "fabs": "fabs", "sinh": "sinh", "cosh": "cosh", "tanh": "tanh", "hypot": "hypot",
    "floor": "floor", "ceil": "ceil", "log1p": "log1p", "expm1": "expm1",
}
#: NumPy constants.
CONSTANTS = {"inf": "INFINITY", "nan": "NAN", "pi": "M_PI", "e": "M_E"}
NUMPY = ("np", "numpy", "math")


class TranslationError(ValueError):
    """A construct outside the translated subset (the message names function and line)."""


@dataclass
class Array:
    """A C array: element type and shape expressions.

    Parameters
    ----------
    ctype : str
        The C element type.
    shape : list of str
        The C expressions of its dimensions.
    """
    ctype: str
    shape: list


@dataclass
class Function:
    """A Python function to translate.

    Parameters
    ----------
    func : function or str
        The function, or its source.
    cname : str
        Its C name.
    kinds : dict
        The kind (:data:`KINDS`) of every argument, by name.
    calls : dict
        The names it reads that are bound to other functions (C names, or a function whose
        body returns a tuple of new arrays, expanded in place).
    constants : dict
        The names it reads that are bound to constants.
    exported : bool, default True
        Whether the extension module exposes it.
    returns : tuple
        Filled by :func:`translate`: the C types of the returned values.
    written : frozenset
        Filled by :func:`translate`: the array arguments the function writes (itself or
        through a callee).
    """
    func: object
    cname: str
    kinds: dict
    calls: dict = field(default_factory=dict)
    constants: dict = field(default_factory=dict)
    exported: bool = True
    #: filled by :func:`translate`: the C types of the returned values, and the array
    #: arguments the function writes (itself or through a callee)
    returns: tuple = ()
    written: frozenset = frozenset()


def function_tree(func) -> ast.FunctionDef:
    """A fresh syntax tree of a function (the translation rewrites it; parsing is cheaper
    than a copy).

    Parameters
    ----------
    func : function or str
        The function, or its source.

    Returns
    -------
    ast.FunctionDef
        Its definition.

    Raises
    ------
    TranslationError
        If the source is not a function definition.
    """
    node = ast.parse(function_text(func)).body[0]
    if not isinstance(node, ast.FunctionDef):
        raise TranslationError("expected a function definition")
    return node


@functools.cache
def function_text(func) -> str:
    """The source of a function, dedented.

    Parameters
    ----------
    func : function or str
        The function, or its source.

    Returns
    -------
    str
        The source.
    """
    return textwrap.dedent(func if isinstance(func, str) else inspect.getsource(func))


@functools.cache
def parameters(func) -> tuple[str, ...]:
    """The names of a function's parameters.

    Parameters
    ----------
    func : function or str
        The function, or its source.

    Returns
    -------
    tuple of str
        The names, in order.
    """
    return tuple(a.arg for a in function_tree(func).args.args)


def small_integer(node) -> int | None:
    """The exponent of ``x ** n`` when it is a constant integer (``2``, ``-2.0``) of at most 4.

    Parameters
    ----------
    node : ast.expr
        The exponent.

    Returns
    -------
    int or None
        The integer, ``None`` for any other exponent.
    """
    sign = 1
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        sign, node = -1, node.operand
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
        v = float(node.value)
        if v.is_integer() and abs(v) <= 4:
            return sign * int(v)
    return None
