"""The size budget of the symbolic work on a mechanism: measured before anything is derived.

Deriving and generating a mechanism costs time and memory that grow with its expressions —
for SymPy's ``simplify``, ``factor`` and ``expand`` far faster than their size (a rate that
is a 300-term trigonometric sum ran for minutes with gigabytes resident; a nesting 300
deep overflowed Python's stack). So every expression of a definition — each rate, angular
velocity, constraint, singularity function and parameter value given to
:func:`derivations.equations.field_mechanism` or
:func:`~derivations.equations.constraint_mechanism`, each entry of a symbolic
:class:`~derivations.mechanisms.Mechanism` — is measured first (:func:`measure`, an
iterative walk that stops at the limit) and refused past the budget with a ``ValueError``
naming the expression and the limit:

- :data:`NODES`: nodes of the expression tree (symbols, numbers, operations, functions);
- :data:`DEPTH`: nesting depth;
- :data:`POWER`: magnitude of a numeric exponent;
- :data:`TOTAL`: nodes of all the expressions of one definition together;
- :data:`WORK`: nodes of the field (and of the desingularised field) times the dimension
  ``d`` of the state's variations: the variational derivation differentiates every entry
  along each of the ``d`` directions, and the generated code evaluates the result;
- :data:`COORDINATES`, :data:`INPUTS`, :data:`UNKNOWNS`: coordinates, inputs, and rates a
  set of constraints solves for;
- :data:`TEXT`: characters of an expression given as text;
- :data:`FACTORS`: distinct factors of the denominators a default singularity function
  multiplies.

The catalog's largest expression (the auxiliary ``QG`` form of a platform of numbers) has
564 nodes and depth 11; a rate of the tests at most 11 nodes and depth 4.

Within the budget the steps whose cost grows fastest are bounded as well: SymPy's
``simplify`` is applied only to expressions of at most :data:`SIMPLIFY_NODES` nodes, and
to at most :data:`SIMPLIFY_TOTAL` nodes in all in one derivation (:func:`simplified`,
:class:`Allowance`: a small trigonometric expression may take a second); ``together``,
``factor``, the simplification of a small system's solution and the like to at most
:data:`ALGEBRA_NODES` (:func:`is_small`); and a product or power is expanded only where its
expansion has at most :data:`EXPAND_TERMS` terms (:func:`expanded`). Larger expressions
are kept as derived — the same function, written less tidily.
"""
from __future__ import annotations

import math

import sympy as sp

#: Nodes of one expression at most.
NODES = 1_000
#: Nesting depth of one expression at most.
DEPTH = 32
#: Magnitude of a numeric exponent at most (squares, square roots, cubes ... are far below).
POWER = 16
#: Nodes of all the expressions of one definition at most.
TOTAL = 20_000
#: Nodes of the field times the dimension of the state's variations at most.
WORK = 50_000
#: Coordinates of a state at most.
COORDINATES = 24
#: Inputs at most.
INPUTS = 12
#: Rates that constraints are solved for at most.
UNKNOWNS = 6
#: Characters of an expression given as text at most.
TEXT = 5_000
#: Distinct factors of a default singularity function at most.
FACTORS = 16
#: ``simplify`` (and ``trigsimp``) only on expressions of at most this many nodes ...
SIMPLIFY_NODES = 32
#: ... and on at most this many nodes in all in one derivation (:class:`Allowance`).
SIMPLIFY_TOTAL = 512
#: ``together``, ``factor``, ``cancel`` and the determinant by elimination only up to this.
ALGEBRA_NODES = 200
#: ``expand`` only where the expansion has at most this many terms.
EXPAND_TERMS = 200


def measure(expr, key: str, limit: int = NODES) -> int:
    """The number of nodes of ``expr``, checked against the budget.

    An iterative walk (no recursion: any depth is measured safely) that stops as soon as a
    limit is passed, so its cost is bounded by the budget, whatever the expression.

    Parameters
    ----------
    expr : sympy.Basic
        The expression.
    key : str
        What it is, for the message (``"rates[2]"``).
    limit : int
        The most nodes allowed (default :data:`NODES`).

    Returns
    -------
    int
        Its nodes.

    Raises
    ------
    ValueError
        Naming ``key`` and the limit, past :data:`NODES` (or ``limit``) nodes,
        :data:`DEPTH` levels or an exponent beyond :data:`POWER`.
    """
    count = 0
    stack = [(expr, 1)]
    while stack:
        node, depth = stack.pop()
        count += 1
        if count > limit:
            raise ValueError(f"{key}: the expression has more than {limit} nodes, beyond the size budget "
                             f"of the symbolic work (derivations.budget.NODES = {NODES}); write it "
                             "with fewer terms")
        if depth > DEPTH:
            raise ValueError(f"{key}: the expression is nested more than {DEPTH} deep, beyond the "
                             f"budget of the symbolic work (derivations.budget.DEPTH = {DEPTH})")
        if isinstance(node, sp.Pow) and node.exp.is_Number and not _within(node.exp, POWER):
            raise ValueError(f"{key}: the exponent {_short(node.exp)} is beyond the budget of the "
                             f"symbolic work (magnitude at most derivations.budget.POWER = {POWER})")
        stack.extend((arg, depth + 1) for arg in getattr(node, "args", ()))
    return count


class Tally:
    """The nodes of the expressions of one definition, added up against :data:`TOTAL`.

    Parameters
    ----------
    owner : str
        What the expressions define, for the message.
    """

    def __init__(self, owner: str = "the definition"):
        self.owner = owner
        self.nodes = 0

    def add(self, expr, key: str) -> int:
        """Measure one more expression (:func:`measure`) and add its nodes.

        Parameters
        ----------
        expr : sympy.Basic
            The expression.
        key : str
            What it is, for the message.

        Returns
        -------
        int
            Its nodes.

        Raises
        ------
        ValueError
            Naming ``key``: past the budget of one expression, or past :data:`TOTAL` for all.
        """
        nodes = measure(expr, key)
        self.nodes += nodes
        if self.nodes > TOTAL:
            raise ValueError(f"{key}: with it, the expressions of {self.owner} have more than {TOTAL} "
                             "nodes together, beyond the size budget of the symbolic work "
                             f"(derivations.budget.TOTAL = {TOTAL})")
        return nodes


def check_work(nodes: int, rows: int, key: str) -> None:
    """Refuse a field whose variational derivation is past :data:`WORK`.

    Parameters
    ----------
    nodes : int
        The nodes of the field's entries (:func:`measure`).
    rows : int
        ``d``: the dimension of a state variation (3 for an orientation, plus the
        coordinates).
    key : str
        The argument, for the message.

    Raises
    ------
    ValueError
        Naming ``key``, if ``nodes * rows > WORK``.
    """
    if nodes * rows > WORK:
        raise ValueError(f"{key}: {nodes} nodes in a state of dimension {rows} ({nodes * rows} nodes to "
                         f"differentiate), beyond the budget of the symbolic work (derivations.budget.WORK "
                         f"= {WORK}); write the field with fewer terms or fewer coordinates")


def check_count(count: int, limit: int, key: str, what: str) -> None:
    """Refuse more than ``limit`` of something (coordinates, inputs, unknown rates).

    Parameters
    ----------
    count : int
        How many are given.
    limit : int
        The budget's limit (:data:`COORDINATES`, :data:`INPUTS`, :data:`UNKNOWNS`).
    key : str
        The argument, for the message.
    what : str
        What is counted, for the message.

    Raises
    ------
    ValueError
        Naming ``key``, if ``count > limit``.
    """
    if count > limit:
        raise ValueError(f"{key}: {count} {what}, beyond the budget of the symbolic work (at most {limit})")


def is_small(expr, limit: int = ALGEBRA_NODES) -> bool:
    """Whether ``expr`` has at most ``limit`` nodes (counted until the limit is passed).

    Parameters
    ----------
    expr : sympy.Basic
        The expression.
    limit : int
        The most nodes (default :data:`ALGEBRA_NODES`).

    Returns
    -------
    bool
        True if it has at most ``limit`` nodes.
    """
    return _nodes(expr, limit) <= limit


class Allowance:
    """The nodes one derivation may still simplify (:data:`SIMPLIFY_TOTAL` to start with).

    Parameters
    ----------
    nodes : int
        The allowance.
    """

    def __init__(self, nodes: int = SIMPLIFY_TOTAL):
        self.nodes = nodes

    def take(self, expr) -> bool:
        """Take ``expr``'s nodes from the allowance, if it has at most
        :data:`SIMPLIFY_NODES` and the allowance covers them.

        Parameters
        ----------
        expr : sympy.Basic
            The expression to simplify.

        Returns
        -------
        bool
            Whether it may be simplified (the allowance is reduced if so).
        """
        count = _nodes(expr, SIMPLIFY_NODES)
        if count > SIMPLIFY_NODES or count > self.nodes:
            return False
        self.nodes -= count
        return True


def simplified(expr: sp.Expr, allowance: Allowance | None = None) -> sp.Expr:
    """``sympy.simplify(expr)`` if ``expr`` has at most :data:`SIMPLIFY_NODES` nodes and the
    derivation's ``allowance`` covers them, else ``expr`` as it is.

    Parameters
    ----------
    expr : sympy.Expr
        The expression.
    allowance : Allowance, optional
        What the derivation may still simplify (by default a fresh one: this expression's
        size limit alone).

    Returns
    -------
    sympy.Expr
        The same value.
    """
    return sp.simplify(expr) if (allowance or Allowance()).take(expr) else expr


def _nodes(expr, limit: int) -> int:
    """Nodes of ``expr``, counted until ``limit`` is passed (then ``limit + 1``)."""
    count, stack = 0, [expr]
    while stack:
        count += 1
        if count > limit:
            return count
        stack.extend(getattr(stack.pop(), "args", ()))
    return count


def expansion_terms(expr, trig: bool = False) -> int:
    """An upper estimate of the terms ``sympy.expand`` (with ``trig``: ``expand_trig``
    too) makes of ``expr``, capped just above :data:`EXPAND_TERMS`.

    Sums add their terms, products multiply them, a power ``b**n`` makes the multinomial
    count of ``b``'s terms, a function's argument is expanded inside it (its work counts);
    with ``trig``, ``sin(n x)`` makes ``|n|`` terms and ``sin(a + b + …)`` one per
    combination of its terms.

    Parameters
    ----------
    expr : sympy.Basic
        The expression.
    trig : bool
        Count the expansion of trigonometric functions.

    Returns
    -------
    int
        The estimate (at most ``EXPAND_TERMS + 1``).
    """
    cap = EXPAND_TERMS + 1
    work = [0]

    def terms(e) -> int:
        if work[0] >= cap:
            return cap
        if isinstance(e, sp.Add):
            return min(cap, sum(terms(a) for a in e.args))
        if isinstance(e, sp.Mul):
            n = 1
            for a in e.args:
                n = min(cap, n * terms(a))
            return n
        if isinstance(e, sp.Pow):
            t = terms(e.base)
            exponent = e.exp
            if exponent.is_Number and _within(exponent, POWER):
                k = int(abs(math.floor(float(exponent))))
                n = min(cap, math.comb(k + t - 1, max(t - 1, 0))) if k > 1 else t
            else:
                n = t
            terms(exponent)
            if exponent.is_Number and exponent < 0:
                work[0] = min(cap, work[0] + n)     # the denominator, expanded in place
                return 1
            return n
        if isinstance(e, sp.Function):
            inner = [terms(a) for a in e.args]
            work[0] = min(cap, work[0] + sum(inner))
            if trig and isinstance(e, sp.functions.elementary.trigonometric.TrigonometricFunction):
                arg = e.args[0]
                coeff, _ = arg.as_coeff_Mul()
                multiple = abs(int(coeff)) if coeff.is_Integer else 1
                parts = len(arg.args) if isinstance(arg, sp.Add) else 1
                return min(cap, multiple * 2 ** min(parts - 1, 16))
            return 1
        return 1

    return min(cap, max(terms(expr), work[0]))


def expanded(expr: sp.Expr, trig: bool = False) -> sp.Expr:
    """``sympy.expand(expr)`` (with ``trig``, ``expand_trig`` first) where the expansion has
    at most :data:`EXPAND_TERMS` terms (:func:`expansion_terms`), else ``expr`` as it is.

    Parameters
    ----------
    expr : sympy.Expr
        The expression.
    trig : bool
        Expand trigonometric functions of sums and multiples (``expand_trig``) only.

    Returns
    -------
    sympy.Expr
        The same value.
    """
    if expansion_terms(expr, trig) > EXPAND_TERMS:
        return expr
    return sp.expand_trig(expr) if trig else sp.expand(expr)


def _within(number, limit) -> bool:
    """Whether a SymPy number is finite with magnitude at most ``limit``."""
    try:
        return bool(number.is_finite) and bool(abs(number) <= limit)
    except TypeError:
        return False


def _short(number) -> str:
    text = str(number)
    return text if len(text) <= 40 else text[:20] + "…" + text[-10:]
