"""C from the package's compiled Python: one source for the numba kernels and the native ones.

:func:`translate` turns functions written in the subset of Python that numba compiles
(:mod:`nonholo.codegen.c_subset`: the conventions, the argument kinds) into C99 with the
same arithmetic in the same order; :func:`nonholo.codegen.c_extension.extension_source`
wraps them as a CPython extension module.
"""
from __future__ import annotations

import ast

from .c_subset import (
    CONSTANTS,
    KINDS,
    MATH,
    NUMPY,
    Array,
    Function,
    TranslationError,
    function_tree,
    parameters,
    small_integer,
)


class _Translator:
    """Translate one function (see the module docstring)."""

    def __init__(self, fn: Function, known: dict):
        self.fn = fn
        self.known = known                   # C name → Function (already translated callees)
        self.tree = function_tree(fn.func)
        self.name = self.tree.name
        self.arrays: dict[str, Array] = {}
        self.scalars: dict[str, str] = {}
        self.lines: list[str] = []
        self.tmp = 0
        self.written: set[str] = set()
        args = [a.arg for a in self.tree.args.args]
        missing = [a for a in args if a not in fn.kinds]
        if missing:
            raise TranslationError(f"{self.name}: no kind declared for argument(s) {missing}")
        self.args = args
        for a in args:
            ctype, nd = KINDS[fn.kinds[a]]
            if nd:
                self.arrays[a] = Array(ctype, [f"{a}_s{i}" for i in range(nd)])
            else:
                self.scalars[a] = ctype
        self.body = [s for s in self.tree.body
                     if not (isinstance(s, ast.Expr) and isinstance(s.value, ast.Constant))]
        self.body = self._expand_workspaces(self.body)
        self.nodes = list(ast.walk(ast.Module(body=self.body, type_ignores=[])))

    # ---- errors -------------------------------------------------------------------
    def fail(self, node, what: str):
        raise TranslationError(f"{self.name}, line {getattr(node, 'lineno', '?')}: {what}")

    # ---- workspace expansion ------------------------------------------------------------
    def _expand_workspaces(self, body):
        out = []
        for s in body:
            if (isinstance(s, ast.Assign) and len(s.targets) == 1 and isinstance(s.targets[0], ast.Tuple)
                    and isinstance(s.value, ast.Call) and isinstance(s.value.func, ast.Name)
                    and s.value.func.id in self.fn.calls and callable(self.fn.calls[s.value.func.id])):
                callee = function_tree(self.fn.calls[s.value.func.id])
                ret = [b for b in callee.body if isinstance(b, ast.Return)]
                if len(ret) != 1 or not isinstance(ret[0].value, ast.Tuple):
                    self.fail(s, f"{s.value.func.id} is not a workspace (one `return (…)`)")
                params = {a.arg: v for a, v in zip(callee.args.args, s.value.args)}

                class Sub(ast.NodeTransformer):
                    def visit_Name(self, n, params=params):
                        return params.get(n.id, n)

                for t, v in zip(s.targets[0].elts, ret[0].value.elts):
                    v = Sub().visit(ast.parse(ast.unparse(v), mode="eval").body)
                    out.append(ast.copy_location(ast.Assign(targets=[t], value=v), s))
                continue
            for f in ("body", "orelse"):
                if hasattr(s, f):
                    setattr(s, f, self._expand_workspaces(getattr(s, f)))
            out.append(s)
        return out

    # ---- types --------------------------------------------------------------------
    def const(self, name):
        return self.fn.constants.get(name)

    def is_np(self, node, attr=None):
        return (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                and node.value.id in NUMPY and (attr is None or node.attr == attr))

    def array_of(self, node):
        """The :class:`Array` an expression denotes (a name, a view, ``x.T``), or None."""
        if isinstance(node, ast.Name) and node.id in self.arrays:
            return self.arrays[node.id]
        if isinstance(node, ast.Subscript):
            base = self.array_of(node.value)
            if base is None:
                return None
            idx = node.slice.elts if isinstance(node.slice, ast.Tuple) else [node.slice]
            if any(isinstance(i, ast.Slice) for i in idx):
                return None
            if len(idx) < len(base.shape):
                return Array(base.ctype, base.shape[len(idx):])
        return None

    def typeof(self, node) -> str:
        """C type of a scalar expression."""
        if isinstance(node, ast.Constant):
            if isinstance(node.value, bool):
                return "int"
            return "int64_t" if isinstance(node.value, int) else "double"
        if isinstance(node, ast.Name):
            c = self.const(node.id)
            if c is not None:
                return self.typeof(ast.Constant(c))
            if node.id in self.scalars:
                return self.scalars[node.id]
            if node.id in ("True", "False"):
                return "int"
            return "double"
        if isinstance(node, ast.Attribute):
            if self.is_np(node):
                return "double"
            return "double"
        if isinstance(node, ast.Subscript):
            if (isinstance(node.value, ast.Attribute) and node.value.attr == "shape"):
                return "int64_t"
            a = self.array_of(node.value)
            if a is None and isinstance(node.value, ast.Name) and node.value.id in self.arrays:
                a = self.arrays[node.value.id]
            return a.ctype if a else "double"
        if isinstance(node, ast.BinOp):
            if isinstance(node.op, (ast.Div, ast.Pow)):
                if isinstance(node.op, ast.Pow) and {self.typeof(node.left), self.typeof(node.right)} <= {"int64_t"}:
                    return "int64_t"
                return "double"
            lt, rt = self.typeof(node.left), self.typeof(node.right)
            return "double" if "double" in (lt, rt) else "int64_t"
        if isinstance(node, ast.UnaryOp):
            if isinstance(node.op, ast.Not):
                return "int"
            t = self.typeof(node.operand)
            return "int64_t" if t == "int" else t
        if isinstance(node, (ast.Compare, ast.BoolOp)):
            return "int"
        if isinstance(node, ast.IfExp):
            a, b = self.typeof(node.body), self.typeof(node.orelse)
            return "double" if "double" in (a, b) else a
        if isinstance(node, ast.Call):
            f = node.func
            if isinstance(f, ast.Name):
                if f.id in ("min", "max"):
                    ts = [self.typeof(a) for a in node.args]
                    return "double" if "double" in ts else ts[0]
                if f.id == "abs":
                    return self.typeof(node.args[0])
                if f.id == "len":
                    return "int64_t"
                if f.id == "int":
                    return "int64_t"
                if f.id == "float":
                    return "double"
                if f.id == "bool":
                    return "int"
                callee = self.callee(f.id)
                if callee is not None:
                    if len(callee.returns) != 1:
                        self.fail(node, f"{f.id} returns {len(callee.returns)} values")
                    return callee.returns[0]
            if self.is_np(f, "isfinite") or self.is_np(f, "isnan"):
                return "int"
            return "double"
        return "double"

    def callee(self, name):
        target = self.fn.calls.get(name)
        if isinstance(target, str):
            return self.known.get(target)
        return None

    def infer(self):
        """Types of the locals (fixed point over their assignments)."""
        assigns = []
        for node in self.nodes:
            if isinstance(node, ast.Assign):
                for t in node.targets:
                    if isinstance(t, ast.Name):
                        assigns.append((t.id, node.value))
                    elif isinstance(t, ast.Tuple) and isinstance(node.value, ast.Tuple):
                        assigns.extend((e.id, v) for e, v in zip(t.elts, node.value.elts)
                                       if isinstance(e, ast.Name))
                    elif isinstance(t, ast.Tuple) and isinstance(node.value, ast.Call):
                        callee = self.callee(getattr(node.value.func, "id", ""))
                        if callee is None:
                            self.fail(node, "tuple assignment from an unknown call")
                        assigns.extend((e.id, r) for e, r in zip(t.elts, callee.returns))
            elif isinstance(node, ast.AugAssign) and isinstance(node.target, ast.Name):
                assigns.append((node.target.id, node.value))
            elif isinstance(node, ast.For):
                if not isinstance(node.target, ast.Name):
                    self.fail(node, "a loop over one name only")
                self.scalars[node.target.id] = "int64_t"
        # arrays first
        for name, value in assigns:
            if isinstance(value, str):
                continue
            a = self.new_array(value, exprs=False)
            if a is None:
                a = self.array_of(value)
            if a is None and isinstance(value, ast.Call) and self.is_np(value.func, "dot"):
                a = Array("double", [None, None])
            if a is not None:
                if name in self.arrays and name not in self.args and len(self.arrays[name].shape) != len(a.shape):
                    self.fail(value, f"{name} holds arrays of different dimensions")
                if name not in self.arrays:
                    self.arrays[name] = Array(a.ctype, [f"{name}_s{i}" for i in range(len(a.shape))])
        rank = {"int": 0, "int64_t": 1, "double": 2}
        for _ in range(10):
            changed = False
            for name, value in assigns:
                if name in self.arrays:
                    continue
                t = value if isinstance(value, str) else self.typeof(value)
                old = self.scalars.get(name)
                if old is None or (rank[t] > rank[old] and name not in self.args):
                    if old is not None and name in self.args:
                        continue
                    self.scalars[name] = t
                    changed = True
            if not changed:
                break

    def new_array(self, node, exprs: bool = True):
        """The :class:`Array` an allocation makes (``np.empty``/``np.zeros``/``x.copy()``);
        without ``exprs``, only its number of dimensions counts."""
        if isinstance(node, ast.Call):
            f = node.func
            if self.is_np(f, "empty") or self.is_np(f, "zeros"):
                shp = node.args[0]
                dims = shp.elts if isinstance(shp, ast.Tuple) else [shp]
                return Array("double", [self.expr(d) if exprs else None for d in dims])
            if isinstance(f, ast.Attribute) and f.attr == "copy" and not node.args:
                a = self.array_of(f.value)
                if a is None:
                    self.fail(node, "copy of something not an array")
                return Array(a.ctype, list(self.shape_of(f.value)))
        return None

    # ---- expressions --------------------------------------------------------------
    def shape_of(self, node):
        """Shape expressions of an array expression."""
        if isinstance(node, ast.Name):
            return self.arrays[node.id].shape
        if isinstance(node, ast.Subscript):
            base = self.shape_of(node.value)
            idx = node.slice.elts if isinstance(node.slice, ast.Tuple) else [node.slice]
            return base[len(idx):]
        self.fail(node, "not an array")

    def pointer(self, node):
        """C pointer expression of an array expression (a name or a view)."""
        if isinstance(node, ast.Name):
            return node.id
        if isinstance(node, ast.Subscript):
            base = self.pointer(node.value)
            shape = self.shape_of(node.value)
            idx = node.slice.elts if isinstance(node.slice, ast.Tuple) else [node.slice]
            off = self.offset(idx, shape, node)
            return f"({base} + {off})"
        self.fail(node, "not an array")

    def offset(self, idx, shape, node):
        """Linear offset of the (leading) indices ``idx`` in a C-contiguous array of ``shape``."""
        if len(idx) > len(shape):
            self.fail(node, "too many indices")
        off = self.expr(idx[0])
        for i in range(1, len(shape)):
            off = f"({off}) * {shape[i]}" + (f" + ({self.expr(idx[i])})" if i < len(idx) else "")
        return off

    def base_name(self, node):
        """The array name under a view or an element (``A`` of ``A[i, 0]``)."""
        while isinstance(node, ast.Subscript):
            node = node.value
        return node.id if isinstance(node, ast.Name) else None

    def lvalue(self, node):
        """C lvalue of an element written (the array is recorded as written)."""
        self.written.add(self.base_name(node))
        return self.element(node)

    def element(self, node):
        """C lvalue of a full index ``A[i, j]``."""
        base = node.value
        if self.array_of(base) is None and not (isinstance(base, ast.Name) and base.id in self.arrays):
            self.fail(node, f"indexing something not an array: {ast.unparse(base)}")
        shape = self.shape_of(base)
        idx = node.slice.elts if isinstance(node.slice, ast.Tuple) else [node.slice]
        if len(idx) != len(shape):
            self.fail(node, "an element needs every index")
        return f"{self.pointer(base)}[{self.offset(idx, shape, node)}]"

    def expr(self, node) -> str:
        if isinstance(node, ast.Constant):
            v = node.value
            if isinstance(v, bool):
                return "1" if v else "0"
            if isinstance(v, int):
                return f"INT64_C({v})"
            if isinstance(v, float):
                r = repr(v)
                return {"inf": "INFINITY", "-inf": "(-INFINITY)", "nan": "NAN"}.get(r, r if ("." in r or "e" in r) else r + ".0")
            self.fail(node, f"constant {v!r}")
        if isinstance(node, ast.Name):
            c = self.const(node.id)
            if c is not None:
                return self.expr(ast.Constant(c))
            if node.id in ("True", "False"):
                return "1" if node.id == "True" else "0"
            if node.id in self.scalars or node.id in self.arrays:
                return node.id
            self.fail(node, f"unknown name {node.id}")
        if isinstance(node, ast.Attribute):
            if self.is_np(node) and node.attr in CONSTANTS:
                return CONSTANTS[node.attr]
            self.fail(node, f"attribute {ast.unparse(node)}")
        if isinstance(node, ast.Subscript):
            v = node.value
            if isinstance(v, ast.Attribute) and v.attr == "shape":
                i = node.slice.value if isinstance(node.slice, ast.Constant) else None
                if i is None:
                    self.fail(node, "shape index must be a constant")
                return self.shape_of(v.value)[i]
            return self.element(node)
        if isinstance(node, ast.BinOp):
            a, b = self.expr(node.left), self.expr(node.right)
            op = node.op
            if isinstance(op, ast.Div):
                return f"((double)({a}) / (double)({b}))"
            if isinstance(op, ast.Pow):
                if self.typeof(node) == "int64_t":
                    return f"((int64_t)pow((double)({a}), (double)({b})))"
                n = small_integer(node.right)
                if n is not None:            # x**n by products, as LLVM's fast-math does (pow is slow)
                    self.tmp += 1
                    x = f"_p{self.tmp}"
                    prod = " * ".join([x] * abs(n)) if n else "1.0"
                    value = f"(1.0 / ({prod}))" if n < 0 else f"({prod})"
                    return f"({{ double {x} = {a}; {value}; }})"
                return f"pow({a}, {b})"
            if isinstance(op, ast.FloorDiv):
                if self.typeof(node) == "double":
                    return f"floor(({a}) / ({b}))"
                return f"(({a}) / ({b}))"
            if isinstance(op, ast.Mod):
                if self.typeof(node) == "double":
                    self.fail(node, "% of real numbers")
                return f"(({a}) % ({b}))"
            sym = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*"}.get(type(op))
            if sym is None:
                self.fail(node, f"operator {type(op).__name__}")
            return f"({a} {sym} {b})"
        if isinstance(node, ast.UnaryOp):
            a = self.expr(node.operand)
            if isinstance(node.op, ast.USub):
                return f"(-{a})"
            if isinstance(node.op, ast.UAdd):
                return a
            if isinstance(node.op, ast.Not):
                return f"(!({a}))"
            self.fail(node, "unary operator")
        if isinstance(node, ast.BoolOp):
            sym = " && " if isinstance(node.op, ast.And) else " || "
            return "(" + sym.join(f"({self.expr(v)})" for v in node.values) + ")"
        if isinstance(node, ast.Compare):
            parts = []
            left = node.left
            for op, right in zip(node.ops, node.comparators):
                sym = {ast.Lt: "<", ast.LtE: "<=", ast.Gt: ">", ast.GtE: ">=", ast.Eq: "==", ast.NotEq: "!="}.get(type(op))
                if sym is None:
                    self.fail(node, f"comparison {type(op).__name__}")
                parts.append(f"(({self.expr(left)}) {sym} ({self.expr(right)}))")
                left = right
            return "(" + " && ".join(parts) + ")"
        if isinstance(node, ast.IfExp):
            return f"(({self.expr(node.test)}) ? ({self.expr(node.body)}) : ({self.expr(node.orelse)}))"
        if isinstance(node, ast.Call):
            return self.call(node)
        self.fail(node, f"expression {type(node).__name__}")

    def minmax(self, node, which):
        args = [self.expr(a) for a in node.args]
        if len(args) != 2:
            self.fail(node, f"{which} of two values only")
        t = self.typeof(node)
        self.tmp += 1
        a, b = f"_a{self.tmp}", f"_b{self.tmp}"
        cmp = "<" if which == "min" else ">"
        return f"({{ {t} {a} = {args[0]}; {t} {b} = {args[1]}; ({b} {cmp} {a}) ? {b} : {a}; }})"

    def call(self, node, outs=()):
        f = node.func
        if isinstance(f, ast.Name):
            if f.id in ("min", "max"):
                return self.minmax(node, f.id)
            if f.id == "abs":
                t = self.typeof(node.args[0])
                return f"{'fabs' if t == 'double' else 'llabs'}({self.expr(node.args[0])})"
            if f.id == "float":
                return f"((double)({self.expr(node.args[0])}))"
            if f.id == "int":
                return f"((int64_t)({self.expr(node.args[0])}))"
            if f.id == "len":
                return self.shape_of(node.args[0])[0]
            callee = self.callee(f.id)
            if callee is None:
                self.fail(node, f"call of {f.id}, which is not bound to a translated function")
            args = []
            params = parameters(callee.func)
            if len(node.args) != len(params) or node.keywords:
                self.fail(node, f"{f.id} takes {len(params)} positional arguments")
            for p, a in zip(params, node.args):
                kind = callee.kinds[p]
                nd = KINDS[kind][1]
                if nd:
                    shape = self.shape_of(a)
                    if len(shape) != nd:
                        self.fail(node, f"{f.id}: argument {p} must have {nd} dimensions")
                    args.append(self.pointer(a))
                    args.extend(shape)
                    if p in callee.written:
                        self.written.add(self.base_name(a))
                else:
                    args.append(self.expr(a))
            args.extend(outs)
            return f"{callee.cname}({', '.join(args)})"
        if isinstance(f, ast.Attribute) and self.is_np(f):
            if f.attr in MATH:
                return f"{MATH[f.attr]}({', '.join(self.expr(a) for a in node.args)})"
            if f.attr == "isfinite":
                return f"isfinite({self.expr(node.args[0])})"
            if f.attr == "isnan":
                return f"isnan({self.expr(node.args[0])})"
        self.fail(node, f"call {ast.unparse(node)}")

    # ---- statements ---------------------------------------------------------------
    def emit(self, depth, text):
        self.lines.append("    " * depth + text)

    def allocate(self, name, node, depth, in_loop):
        """``name = np.empty(...)`` / ``np.zeros`` / ``x.copy()``."""
        if in_loop:
            self.fail(node, f"{name}: an array made inside a loop")
        a = self.new_array(node)
        arr = self.arrays[name]
        for s, e in zip(arr.shape, a.shape):
            self.emit(depth, f"{s} = {e};")
        size = " * ".join(f"({s})" for s in arr.shape) or "1"
        self.emit(depth, f"{name} = ({arr.ctype} *)alloca(sizeof({arr.ctype}) * ({size} + 1));")
        if isinstance(node.func, ast.Attribute) and node.func.attr == "copy":
            src = self.pointer(node.func.value)
            self.emit(depth, f"memcpy({name}, {src}, sizeof({arr.ctype}) * ({size}));")
        elif node.func.attr == "zeros":
            self.emit(depth, f"memset({name}, 0, sizeof({arr.ctype}) * ({size}));")

    def fill(self, target, value, depth):
        """``A[:, :] = x``: every element."""
        name = target.value
        self.written.add(self.base_name(name))
        shape = self.shape_of(name)
        size = " * ".join(f"({s})" for s in shape)
        self.emit(depth, f"for (int64_t _i = 0; _i < {size}; _i++) {self.pointer(name)}[_i] = {self.expr(value)};")

    def dot(self, name, node, depth):
        """``name = np.dot(A.T, B.reshape((r, c)))``: ``name[a, b] = Σ_r A[r, a] B[r, b]``."""
        A, B = node.args
        if not (isinstance(A, ast.Attribute) and A.attr == "T" and isinstance(B, ast.Call)
                and isinstance(B.func, ast.Attribute) and B.func.attr == "reshape"):
            self.fail(node, "np.dot(A.T, B.reshape((r, c))) only")
        a = A.value
        b = B.func.value
        r, c = B.args[0].elts
        sa = self.shape_of(a)
        rows, cols = self.expr(r), self.expr(c)
        arr = self.arrays[name]
        self.emit(depth, f"{arr.shape[0]} = {sa[1]}; {arr.shape[1]} = {cols};")
        self.emit(depth, f"{name} = (double *)alloca(sizeof(double) * ({arr.shape[0]} * {arr.shape[1]} + 1));")
        self.emit(depth, f"memset({name}, 0, sizeof(double) * {arr.shape[0]} * {arr.shape[1]});")
        pa, pb = self.pointer(a), self.pointer(b)
        self.emit(depth, f"for (int64_t _r = 0; _r < {rows}; _r++) {{")
        self.emit(depth + 1, f"for (int64_t _a = 0; _a < {sa[1]}; _a++) {{")
        self.emit(depth + 2, f"double _w = {pa}[_r * {sa[1]} + _a];")
        self.emit(depth + 2, f"double *_o = {name} + _a * {cols};")
        self.emit(depth + 2, f"const double *_b = {pb} + _r * {cols};")
        self.emit(depth + 2, f"for (int64_t _c = 0; _c < {cols}; _c++) _o[_c] += _w * _b[_c];")
        self.emit(depth + 1, "}")
        self.emit(depth, "}")

    def assign(self, target, value, depth, in_loop, node):
        if isinstance(target, ast.Name):
            name = target.id
            if name in self.arrays:
                if self.new_array(value) is not None:
                    return self.allocate(name, value, depth, in_loop)
                if isinstance(value, ast.Call) and self.is_np(value.func, "dot"):
                    return self.dot(name, value, depth)
                arr = self.arrays[name]
                for s, e in zip(arr.shape, self.shape_of(value)):
                    self.emit(depth, f"{s} = {e};")
                return self.emit(depth, f"{name} = {self.pointer(value)};")
            return self.emit(depth, f"{name} = {self.expr(value)};")
        if isinstance(target, ast.Subscript):
            idx = target.slice.elts if isinstance(target.slice, ast.Tuple) else [target.slice]
            if all(isinstance(i, ast.Slice) and i.lower is None and i.upper is None for i in idx):
                return self.fill(target, value, depth)
            return self.emit(depth, f"{self.lvalue(target)} = {self.expr(value)};")
        self.fail(node, f"assignment to {ast.unparse(target)}")

    def statement(self, s, depth, in_loop):
        if isinstance(s, ast.Assign):
            if len(s.targets) == 1 and isinstance(s.targets[0], ast.Tuple):
                t = s.targets[0]
                if isinstance(s.value, ast.Tuple):       # a, b = x, y (a swap): through temporaries
                    temps = []
                    for v in s.value.elts:
                        self.tmp += 1
                        temps.append(f"_t{self.tmp}")
                        self.emit(depth, f"{self.typeof(v)} {temps[-1]} = {self.expr(v)};")
                    for e, tv in zip(t.elts, temps):
                        lhs = self.lvalue(e) if isinstance(e, ast.Subscript) else self.expr(e)
                        self.emit(depth, f"{lhs} = {tv};")
                    return
                if isinstance(s.value, ast.Call):
                    callee = self.callee(getattr(s.value.func, "id", ""))
                    if callee is None or len(callee.returns) != len(t.elts):
                        self.fail(s, "tuple assignment from a call")
                    outs = [f"&{e.id}" for e in t.elts]
                    return self.emit(depth, self.call(s.value, outs) + ";")
                self.fail(s, "tuple assignment")
            for t in s.targets[:-1]:
                if not isinstance(t, ast.Name):
                    self.fail(s, "chained assignment to names only")
            self.assign(s.targets[-1], s.value, depth, in_loop, s)
            for t in reversed(s.targets[:-1]):
                self.emit(depth, f"{t.id} = {self.expr(s.targets[-1])};")
            return
        if isinstance(s, ast.AugAssign):
            sym = {ast.Add: "+=", ast.Sub: "-=", ast.Mult: "*=", ast.Div: "/="}.get(type(s.op))
            if sym is None:
                self.fail(s, "augmented operator")
            lhs = self.lvalue(s.target) if isinstance(s.target, ast.Subscript) else self.expr(s.target)
            val = self.expr(s.value)
            if isinstance(s.op, ast.Div):
                val = f"(double)({val})"
            return self.emit(depth, f"{lhs} {sym} {val};")
        if isinstance(s, ast.For):
            it = s.iter
            if not (isinstance(it, ast.Call) and isinstance(it.func, ast.Name) and it.func.id == "range") or s.orelse:
                self.fail(s, "for over range() only")
            a = [self.expr(x) for x in it.args]
            lo, hi, st = ("0", a[0], "1") if len(a) == 1 else (a[0], a[1], a[2] if len(a) == 3 else "1")
            v = s.target.id
            self.emit(depth, f"for ({v} = {lo}; {v} < {hi}; {v} += {st}) {{")
            for b in s.body:
                self.statement(b, depth + 1, True)
            return self.emit(depth, "}")
        if isinstance(s, ast.If):
            test = s.test
            if isinstance(test, ast.Name) and self.const(test.id) is not None:   # a constant branch
                for b in (s.body if self.const(test.id) else s.orelse):
                    self.statement(b, depth, in_loop)
                return
            self.emit(depth, f"if ({self.expr(test)}) {{")
            for b in s.body:
                self.statement(b, depth + 1, in_loop)
            if s.orelse:
                self.emit(depth, "} else {")
                for b in s.orelse:
                    self.statement(b, depth + 1, in_loop)
            return self.emit(depth, "}")
        if isinstance(s, ast.Break):
            return self.emit(depth, "break;")
        if isinstance(s, ast.Continue):
            return self.emit(depth, "continue;")
        if isinstance(s, ast.Pass):
            return
        if isinstance(s, ast.Return):
            vals = [] if s.value is None else (s.value.elts if isinstance(s.value, ast.Tuple) else [s.value])
            if len(vals) != len(self.fn.returns):
                self.fail(s, "every return must give the same number of values")
            if len(vals) <= 1:
                return self.emit(depth, f"return {self.expr(vals[0])};" if vals else "return;")
            for i, v in enumerate(vals):
                self.emit(depth, f"*_r{i} = {self.expr(v)};")
            return self.emit(depth, "return;")
        if isinstance(s, ast.Expr) and isinstance(s.value, ast.Call):
            return self.emit(depth, self.call(s.value) + ";")
        self.fail(s, f"statement {type(s).__name__}")

    # ---- the function -------------------------------------------------------------
    def returns(self):
        """C types of the returned values (from the first ``return`` with a value)."""
        types = None
        for node in self.nodes:
            if isinstance(node, ast.Return) and node.value is not None:
                vals = node.value.elts if isinstance(node.value, ast.Tuple) else [node.value]
                ts = [self.typeof(v) for v in vals]
                if types is None:
                    types = ts
                else:
                    if len(ts) != len(types):
                        self.fail(node, "returns of different lengths")
                    types = ["double" if "double" in (a, b) else a for a, b in zip(types, ts)]
        return tuple(types or ())

    def translate(self) -> str:
        self.infer()
        self.fn.returns = self.returns()
        self.infer()                      # again, with the return types known
        self.fn.returns = self.returns()
        params = []
        for a in self.args:
            if a in self.arrays:
                arr = self.arrays[a]
                params.append(f"{arr.ctype} *{a}")
                params.extend(f"int64_t {s}" for s in arr.shape)
            else:
                params.append(f"{self.scalars[a]} {a}")
        rets = self.fn.returns
        if len(rets) > 1:
            params.extend(f"{t} *_r{i}" for i, t in enumerate(rets))
        ctype = rets[0] if len(rets) == 1 else "void"
        head = f"static {ctype} {self.fn.cname}({', '.join(params)})"
        self.lines = []
        for name, t in self.scalars.items():
            if name not in self.args:
                self.emit(1, f"{t} {name} = 0;")
        for name, arr in self.arrays.items():
            if name not in self.args:
                self.emit(1, f"{arr.ctype} *{name} = NULL;")
                self.emit(1, "int64_t " + ", ".join(f"{s} = 0" for s in arr.shape) + ";")
        for s in self.body:
            self.statement(s, 1, False)
        unused = [f"(void){s};" for a in self.args if a in self.arrays for s in self.arrays[a].shape]
        body = "\n".join(["    " + " ".join(unused)] + self.lines) if unused else "\n".join(self.lines)
        aliases = {}
        for node in self.nodes:
            if (isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name)
                    and node.targets[0].id in self.arrays and self.base_name(node.value) in self.arrays
                    and self.new_array(node.value) is None):
                aliases.setdefault(node.targets[0].id, set()).add(self.base_name(node.value))
        written = set(self.written)
        for _ in range(5):
            for a, bases in aliases.items():
                if a in written:
                    written |= bases
        self.fn.written = frozenset(w for w in written if w in self.args)
        return f"{head}\n{{\n{body}\n}}\n", head + ";"


def translate(functions: list[Function]) -> tuple[str, dict]:
    """C definitions of functions (callees first: a function may call only those before it).

    Parameters
    ----------
    functions : list of Function
        The functions, in order.

    Returns
    -------
    code : str
        The C text.
    known : dict
        The functions by C name (with their return types).

    Raises
    ------
    TranslationError
        For a construct outside the translated subset.
    """
    known: dict[str, Function] = {}
    out = []
    for fn in functions:
        code, _ = _Translator(fn, known).translate()
        known[fn.cname] = fn
        out.append(code)
    return "\n".join(out), known
