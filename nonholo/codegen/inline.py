"""Functions with the calls of others expanded in place (the integrator's kernels, one
function each, with the step inlined).

:mod:`nonholo.integrate.cf4` writes the scheme once, as a step (:func:`~nonholo.integrate.cf4.cf4_step`),
and :mod:`nonholo.integrate.motion_kernels` and :mod:`nonholo.integrate.variational_kernels`
the kernels that call it. Called, the step keeps its arrays out of registers and
slows every kernel markedly; numba's own inlining multiplies the compilation time. So
``nonholo derive`` writes :mod:`nonholo.generated.cf4_kernels`: the kernels with every call
of the integrator's inlined functions replaced by their bodies (:func:`inlined_module`,
called by :func:`nonholo.codegen.emit.python_kernels`) — which is what gets compiled.
"""
from __future__ import annotations

import ast
import copy


class Rename(ast.NodeTransformer):
    """Renames the names in ``names``.

    Parameters
    ----------
    names : dict of str to str
        Old name → new name.
    """

    def __init__(self, names: dict[str, str]):
        self.names = names

    def visit_Name(self, node):
        """A name, renamed if it is one of ``names``.

        Parameters
        ----------
        node : ast.Name
            The name.

        Returns
        -------
        ast.Name
            The renamed name, or ``node``.
        """
        if node.id in self.names:
            return ast.copy_location(ast.Name(self.names[node.id], node.ctx), node)
        return node


def expand(body: list, functions: dict) -> list:
    """Statements with every call of ``functions`` expanded in place.

    Every statement ``a, b = f(...)`` or ``f(...)`` (``f`` in ``functions``) is replaced by
    ``f``'s body: arguments that are names rename the parameters, others are assigned to
    them first; in the first form ``f`` must end in ``return x, y`` (assigned to ``a, b``
    where they differ), in the second it must not return anything.

    Parameters
    ----------
    body : list of ast.stmt
        The statements (nested blocks are expanded too).
    functions : dict of str to ast.FunctionDef
        The functions to expand, by name.

    Returns
    -------
    list of ast.stmt
        The expanded statements.

    Raises
    ------
    ValueError
        For a call with keywords or a wrong number of arguments, a call as a statement of
        a function that returns, or an assigned call of one that does not end in
        ``return x, y``.
    """
    out = []
    for stmt in body:
        for field in ("body", "orelse"):
            if isinstance(getattr(stmt, field, None), list):
                setattr(stmt, field, expand(getattr(stmt, field), functions))
        call = stmt.value if isinstance(stmt, (ast.Assign, ast.Expr)) else None
        if not (isinstance(call, ast.Call) and isinstance(call.func, ast.Name)
                and call.func.id in functions):
            out.append(stmt)
            continue
        fn = functions[call.func.id]
        params = [a.arg for a in fn.args.args]
        if len(params) != len(call.args) or call.keywords:
            raise ValueError(f"inline {fn.name}: call with {len(call.args)} positional arguments only")
        names, pre = {}, []
        for p, a in zip(params, call.args):
            if isinstance(a, ast.Name):
                if a.id != p:
                    names[p] = a.id
            else:
                pre.append(ast.Assign([ast.Name(p, ast.Store())], a, lineno=0))
        inner = [copy.deepcopy(st) for st in fn.body
                 if not (isinstance(st, ast.Expr) and isinstance(st.value, ast.Constant))]
        if isinstance(stmt, ast.Expr):
            if any(isinstance(node, ast.Return) for st in inner for node in ast.walk(st)):
                raise ValueError(f"inline {fn.name}: a call as a statement must not return")
            out += pre + expand([Rename(names).visit(st) for st in inner], functions)
            continue
        ret = inner.pop()
        if not isinstance(ret, ast.Return) or not isinstance(ret.value, ast.Tuple):
            raise ValueError(f"inline {fn.name}: must end in `return x, y`")
        inner = expand([Rename(names).visit(st) for st in inner], functions)
        targets = stmt.targets[0].elts
        values = [Rename(names).visit(copy.deepcopy(v)) for v in ret.value.elts]
        post = [ast.Assign([ast.Name(t.id, ast.Store())], v, lineno=0)
                for t, v in zip(targets, values) if not (isinstance(v, ast.Name) and v.id == t.id)]
        out += pre + inner + post
    return out


def inlined_module(sources: tuple, inlined: tuple, kernels: tuple, header: str) -> str:
    """The source of a module of ``kernels`` with every call of ``inlined`` expanded in place.

    Parameters
    ----------
    sources : tuple of str
        The sources of the modules that define them (each function defined in one).
    inlined : tuple of str
        The functions whose calls are expanded (:func:`expand`).
    kernels : tuple of str
        The functions written, in order.
    header : str
        The module's docstring statement.

    Returns
    -------
    str
        The module's source.

    Raises
    ------
    ValueError
        If two of the modules define a function of the same name.
    """
    defs = {}
    for source in sources:
        for node in ast.parse(source).body:
            if isinstance(node, ast.FunctionDef):
                if node.name in defs:
                    raise ValueError(f"inline: function {node.name!r} defined twice")
                defs[node.name] = node
    functions = {name: defs[name] for name in inlined}
    parts = [header]
    for name in kernels:
        fn = defs[name]
        fn.body = expand(fn.body, functions)
        parts.append(ast.unparse(ast.fix_missing_locations(fn)) + "\n")
    return "\n\n".join(parts)
