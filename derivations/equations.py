"""A mechanism from its equations, checked: the velocity field, or Pfaffian constraints.

- :func:`field_mechanism`: the field itself — the coordinates' rates ``ẋ = f(x) + G(x) u``
  (a state in ``Rᵏ``; the drift ``f`` is zero for a kinematic mechanism), the spatial
  angular velocity ``ω = f_ω + Ω(R, x) u`` of an orientation (``dR/dt = [ω] R``, a state
  on ``SO(3)``), or both (``SO(3) × Rᵏ``).
- :func:`constraint_mechanism`: the rates ``ẋ`` bound by linear equations
  ``A(x) ẋ = B(x) u`` — Pfaffian constraints ``A(x) ẋ = 0`` with the inputs chosen among the
  rates, and equations that define other inputs (a rolling speed) — solved for the rates
  that are not inputs, as :mod:`derivations.vehicles` derives the car: ``det A`` is the
  singularity function.

Both give a :class:`~derivations.mechanisms.Mechanism` for the code generator. Expressions
are SymPy's, or text in Python's syntax read by :func:`derivations.admission.parse` (never
evaluated: only numbers, the declared symbols, arithmetic and a fixed set of functions);
``parameters`` maps further symbols to numbers — finite and real, never text —
substituted first (a float as the rational of its printed digits). Every symbol must be
declared — a coordinate, an input, a parameter, or an entry of the rotation — else
``ValueError`` naming it, and every argument is checked for the class of state it
describes (the message says which argument to use instead). :func:`admitted` checks and
converts the arguments before anything is hashed or derived: the name, the text, the
constants, and the size budget of the symbolic work (:mod:`derivations.budget`), whose
costliest steps (``simplify``, ``factor``, ``expand``) are bounded here too.
"""
from __future__ import annotations

from collections.abc import Mapping

import sympy as sp
from sympy.matrices.utilities import dotprodsimp

from . import admission, budget
from .admission import check_name
from .mechanisms import Mechanism, exact_number, is_free_name
from .rotations import r

#: The forms of a definition :func:`admitted` checks: their symbol and expression arguments.
FORMS = {
    "field_mechanism": {"symbols": ("inputs", "coordinates", "angles"), "expressions": ("rates", "omega", "delta")},
    "constraint_mechanism": {"symbols": ("coordinates", "velocities", "inputs", "angles"),
                             "expressions": ("constraints",)},
}


def admitted(form: str, name, arguments: Mapping) -> dict:
    """The arguments of ``form`` (``"field_mechanism"`` or ``"constraint_mechanism"``)
    checked and converted, before anything is hashed or derived from them.

    The name is an identifier (:func:`derivations.admission.check_name`); symbols are
    SymPy symbols, no more than :mod:`derivations.budget` allows; parameters are finite
    real numbers (:func:`derivations.admission.constant`, text refused); expressions are
    SymPy's, numbers, or text read by :func:`derivations.admission.parse` in the declared
    symbols, each within the budget and with real, finite constants; the rotation a 3×3
    matrix of symbols; the description and the units lines of text.

    Parameters
    ----------
    form : str
        The function the arguments are for.
    name : str
        The mechanism's name.
    arguments : mapping
        Its keyword arguments.

    Returns
    -------
    dict
        The arguments, the expressions as SymPy's (text parsed), the parameters' values
        as SymPy numbers.

    Raises
    ------
    ValueError
        Naming the argument.
    """
    if form not in FORMS:
        raise ValueError(f"form must be one of {', '.join(FORMS)}, got {form!r}")
    check_name(name)
    out = dict(arguments)
    declared = []
    for key in FORMS[form]["symbols"]:
        if key in out:
            out[key] = _symbols(out[key], key)
            declared += out[key]
    budget.check_count(len(out.get("coordinates", ())), budget.COORDINATES, "coordinates", "coordinates")
    budget.check_count(len(out.get("inputs", ())), budget.INPUTS, "inputs", "inputs")
    if out.get("parameters") is not None:
        out["parameters"] = _parameters(out["parameters"])
        declared += list(out["parameters"])
    if out.get("rotation") is not None:
        out["rotation"] = _rotation(out["rotation"])
    if out.get("omega") is not None:
        declared += list(r if out.get("rotation") is None else out["rotation"])
    if out.get("description") is not None:
        out["description"] = admission.check_text(out["description"], "description")
    if out.get("units") is not None:
        out["units"] = _unit_texts(out["units"])
    symbols = admission.symbol_table(declared)
    tally = budget.Tally(f"mechanism {name!r}")
    field_nodes = 0
    for key in FORMS[form]["expressions"]:
        value = out.get(key)
        if value is None:
            continue
        before = tally.nodes
        if key == "delta":
            out[key] = admission.expression(value, key, symbols, tally)
        else:
            out[key] = _expressions(value, key, symbols, tally)
        if key in ("rates", "omega"):
            field_nodes += tally.nodes - before
    rows = len(out.get("coordinates", ())) + (3 if out.get("omega") is not None else 0)
    budget.check_work(field_nodes, rows, "rates" if out.get("omega") is None else "rates and omega")
    return out


def field_mechanism(name: str, *, inputs, coordinates=(), rates=(), omega=None, rotation=None,
                    angles=(), parameters=None, delta=None, units=None,
                    description: str | None = None) -> Mechanism:
    """The mechanism of a field, given by its equations.

    - ``inputs``: the input symbols ``u``; ``coordinates``: the symbols ``x`` of a Euclidean
      state and ``rates`` their rates ``ẋ`` (one expression each, affine in the inputs: the
      terms without an input are the drift ``f(x)``);
    - ``omega``: the spatial angular velocity (3 expressions, affine in the inputs) of an
      orientation ``R``, ``dR/dt = [ω] R`` (body rates ``Ω`` give ``ω = R Ω``), written in the
      entries of ``rotation`` (a 3×3 matrix of symbols; default
      :data:`derivations.rotations.r`, ``r11 … r33``);
    - ``angles``: the coordinates that are angles (their errors are taken modulo 2π);
      ``units``: a unit per coordinate (a sequence, or a mapping from the symbols; default
      ``"rad"`` for an angle, ``""`` otherwise);
    - ``parameters``: further symbols and their values (numbers);
    - ``delta``: the singularity function ``Δ`` (the field is finite where ``Δ ≠ 0``);
      default: the product of the distinct factors of the field's denominators (``tan``,
      ``sec`` … as ``sin``/``cos``), none if it has none.
    """
    given = admitted("field_mechanism", name, dict(
        inputs=inputs, coordinates=coordinates, rates=rates, omega=omega, rotation=rotation, angles=angles,
        parameters=parameters, delta=delta, units=units, description=description))
    u = _symbols(given["inputs"], "inputs", at_least=1)
    x = given["coordinates"]
    values = given["parameters"] or {}
    _distinct({"coordinates": x, "inputs": u, "parameters": tuple(values)})
    if not x and omega is None:
        raise ValueError("give coordinates= with rates= (a state x in R^k), omega= (an orientation R "
                         "on SO(3)) or both (SO(3) x R^k)")
    rates = given["rates"]
    if len(rates) != len(x):
        raise ValueError(f"rates: {len(rates)} expression(s) for {len(x)} coordinate(s); give one "
                         "rate per coordinate")
    R = None if omega is None else (given["rotation"] if given["rotation"] is not None else r)
    declared = set(x) | set(u) | set(values) | (set(R) if R is not None else set())
    parts = {"rates": rates}
    if omega is not None:
        parts["omega"] = given["omega"]
        if len(parts["omega"]) != 3:
            raise ValueError(f"omega: the angular velocity has 3 components, got {len(parts['omega'])}")
    if delta is not None:
        parts["delta"] = [given["delta"]]
    for key, exprs in parts.items():
        _declared(exprs, key, declared, R)
    to_r = {**values, **({} if R is None else dict(zip(R, r)))}
    parts = {key: _substituted(exprs, to_r, key, name) for key, exprs in parts.items()}
    X, fx = _affine(parts["rates"], u, [f"the rate of {c}" for c in x]) if x else (None, None)
    L, fw = (_affine(parts["omega"], u, [f"omega[{i}]" for i in range(3)]) if omega is not None
             else (None, None))
    field = X if L is None else (L if X is None else sp.Matrix.vstack(L, X))
    drift = None
    if fx is not None or fw is not None:
        rows = ([] if L is None else list(fw if fw is not None else sp.zeros(3, 1))) + \
               ([] if X is None else list(fx if fx is not None else sp.zeros(len(x), 1)))
        drift = sp.Matrix(rows)
    is_angle = _angles(angles, x)
    return Mechanism(
        name=name, description=given["description"] or f"{name} (from its equations)",
        L=L, X=X, drift=drift, coordinates=x, inputs=tuple(str(s) for s in u),
        delta=parts["delta"][0] if "delta" in parts else singular_factor(field),
        angles=is_angle, units=_units(given["units"], x, is_angle),
        derivation={"rates": tuple(parts["rates"]), "omega": parts.get("omega"), "parameters": values})


def constraint_mechanism(name: str, *, coordinates, velocities, constraints, inputs, angles=(),
                         parameters=None, units=None, description: str | None = None) -> Mechanism:
    """The mechanism whose rates ``ẋ`` (the symbols ``velocities``, one per coordinate) obey
    the linear equations ``constraints`` (expressions equal to zero).

    ``inputs`` are symbols: a velocity (the input *is* that coordinate's rate, as ``φ̇`` of
    the car) or another symbol that the equations define (the car's rolling speed ``v`` in
    ``ẋ cos θ + ẏ sin θ − v = 0``). The velocities that are not inputs are the unknowns:
    as many equations as unknowns, each linear in the velocities and inputs,
    ``A(x) ẋ_unknown = B(x) u``. Solved by LU; ``Δ = det A`` without its constant factor
    (none if constant) — the rates blow up where it vanishes. ``angles``, ``units``,
    ``parameters`` as for :func:`field_mechanism`.
    """
    given = admitted("constraint_mechanism", name, dict(
        coordinates=coordinates, velocities=velocities, constraints=constraints, inputs=inputs, angles=angles,
        parameters=parameters, units=units, description=description))
    x = _symbols(given["coordinates"], "coordinates", at_least=1)
    xdot = given["velocities"]
    if len(xdot) != len(x):
        raise ValueError(f"velocities: {len(xdot)} symbol(s) for {len(x)} coordinate(s); give the "
                         "symbol of each coordinate's rate")
    u = _symbols(given["inputs"], "inputs", at_least=1)
    values = given["parameters"] or {}
    extra = tuple(s for s in u if s not in xdot)
    _distinct({"coordinates": x, "velocities": xdot, "parameters": tuple(values), "inputs": extra})
    equations = given["constraints"]
    _declared(equations, "constraints", set(x) | set(xdot) | set(u) | set(values), None)
    equations = _substituted(equations, values, "constraints", name)
    unknowns = [v for v in xdot if v not in u]
    budget.check_count(len(unknowns), budget.UNKNOWNS, "constraints", "rates to solve for (velocities that are "
                       "not inputs)")
    if len(equations) != len(unknowns):
        raise ValueError(f"constraints: {len(equations)} equation(s) for the {len(unknowns)} rate(s) that "
                         f"are not inputs ({', '.join(map(str, unknowns)) or 'none'}); give as many "
                         "equations as those rates")
    moving = list(unknowns) + list(u)
    for i, e in enumerate(equations):
        # linear: no second derivative in the rates and inputs, nothing left where they are 0
        rest = budget.expanded(e.xreplace({a: 0 for a in moving}))
        if rest != 0:
            rest = budget.simplified(rest)
        if any(e.diff(a).has(*moving) for a in moving) or rest != 0:
            raise ValueError(f"constraints[{i}] = {_shown(e)} is not linear in the rates and inputs "
                             "(A(x) ẋ = B(x) u, no term without a rate or an input)")
    A = sp.Matrix(equations).jacobian(unknowns)
    B = -sp.Matrix(equations).jacobian(list(u))
    # a small system by fraction-free elimination with SymPy's simplification of the
    # products; a larger one division-free (Berkowitz) and solved without it, measured
    # against the budget at once (derivations.budget)
    small = len(unknowns) <= 3 and all(budget.is_small(a, budget.SIMPLIFY_NODES) for a in A)
    det = A.det() if small else A.det(method="berkowitz")
    if not small:
        budget.measure(det, "constraints: the determinant of their matrix in the rates that are not inputs")
    limit = budget.ALGEBRA_NODES if small else budget.SIMPLIFY_NODES
    det = _tidy(det, limit)
    det = sp.factor_terms(det) if budget.is_small(det) else det
    if det == 0:
        raise ValueError("constraints: their matrix in the rates that are not inputs is singular "
                         "everywhere; they do not fix those rates")
    if small:
        solution = A.LUsolve(B * sp.Matrix(u))
    else:
        with dotprodsimp(False):
            solution = A.LUsolve(B * sp.Matrix(u))
        for v, e in zip(unknowns, solution):
            budget.measure(e, f"constraints: the rate of {v} they solve to")
    solved = dict(zip(unknowns, solution.applyfunc(lambda e: _tidy(e, limit))))
    rates = [solved.get(v, v) for v in xdot]
    delta = None if not det.free_symbols else det.as_coeff_Mul()[1]
    try:
        return field_mechanism(name, inputs=u, coordinates=x, rates=rates, angles=given["angles"],
                               units=given["units"], delta=delta,
                               description=given["description"] or f"{name} (from its constraints)")
    except ValueError as exc:
        if "budget" not in str(exc):
            raise
        raise ValueError(f"constraints: the rates they solve to are beyond the budget ({exc})") from None


def singular_factor(field: sp.Matrix) -> sp.Expr | None:
    """The product of the distinct non-constant factors of the denominators of ``field``'s
    entries (``tan``, ``cot``, ``sec``, ``csc`` written with ``sin`` and ``cos``), or ``None``:
    where it is not zero, the field is finite."""
    trig = {sp.tan: lambda a: sp.sin(a) / sp.cos(a), sp.cot: lambda a: sp.cos(a) / sp.sin(a),
            sp.sec: lambda a: 1 / sp.cos(a), sp.csc: lambda a: 1 / sp.sin(a)}
    factors = []
    allowance = budget.Allowance()
    for e in field:
        for f, g in trig.items():
            e = e.replace(f, g)
        if budget.is_small(e):
            _, den = sp.fraction(sp.together(e))
            bases = [base for base, _ in sp.factor_list(den)[1]]
        else:                   # beyond the algebra's budget: the denominators as they are
            bases = _denominators(e)
        for base in bases:
            if base.free_symbols and all(_not_a_multiple(base, b, allowance) for b in factors):
                factors.append(base)
                budget.check_count(len(factors), budget.FACTORS, "delta", "distinct factors in the field's "
                                   "denominators; give the singularity function as delta=")
    return sp.Mul(*factors) if factors else None


def _denominators(e: sp.Expr) -> list:
    """The bases of the negative powers in ``e`` (an iterative walk)."""
    out, stack = [], [e]
    while stack:
        node = stack.pop()
        if isinstance(node, sp.Pow) and node.exp.is_Number and node.exp < 0 and node.base not in out:
            out.append(node.base)
        stack.extend(node.args)
    return out


def _not_a_multiple(base: sp.Expr, other: sp.Expr, allowance: budget.Allowance) -> bool:
    """Whether ``base`` is not a constant multiple of ``other`` (``simplify`` of the ratio,
    within the derivation's ``allowance``)."""
    return bool(budget.simplified(base / other, allowance).free_symbols)


# -- checks ------------------------------------------------------------------------------------

def _symbols(values, key: str, at_least: int = 0) -> tuple[sp.Symbol, ...]:
    values = (values,) if isinstance(values, sp.Symbol) else tuple(values)
    bad = [v for v in values if not isinstance(v, sp.Symbol)]
    if bad:
        raise ValueError(f"{key} must be SymPy symbols, got {bad[0]!r}")
    if len(set(values)) != len(values):
        twice = sorted({str(v) for v in values if values.count(v) > 1})
        raise ValueError(f"{key}: {', '.join(twice)} given twice")
    if len(values) < at_least:
        raise ValueError(f"{key}: give at least {at_least} symbol(s)")
    taken = [str(v) for v in values if key == "coordinates" and not is_free_name(str(v))]
    if taken:
        raise ValueError(f"coordinates: {taken[0]} needs another name: a Python identifier other than "
                         "those of the generated code (R, q, v, out, numpy, r_ij, s_i, u_i, v_i)")
    return values


def _distinct(groups: dict) -> None:
    """No symbol in two roles (a coordinate and an input, ...)."""
    seen = {}
    for key, symbols in groups.items():
        for s in symbols:
            if s in seen:
                raise ValueError(f"{s} is given both in {seen[s]} and in {key}")
            seen[s] = key


def _parameters(parameters) -> dict:
    """Symbol → value, each a finite real number (:func:`derivations.admission.constant`;
    text refused, not evaluated), floats as the rationals of their printed digits."""
    if parameters is None:
        return {}
    if not isinstance(parameters, Mapping):
        raise ValueError(f"parameters must be a mapping from symbols to numbers, got {type(parameters).__name__}")
    out = {}
    for k, v in parameters.items():
        if not isinstance(k, sp.Symbol):
            raise ValueError(f"parameters: the keys must be SymPy symbols, got {k!r}")
        out[k] = exact_number(admission.constant(v, f"parameters: {k}"))
    return out


def _expressions(values, key: str, symbols: Mapping, tally: budget.Tally) -> list:
    """The expressions of ``key`` (a sequence, a matrix or one), each admitted
    (:func:`derivations.admission.expression`: text parsed in ``symbols``)."""
    if isinstance(values, sp.MatrixBase):
        values = list(values)
    elif isinstance(values, (list, tuple)):
        budget.check_count(len(values), budget.COORDINATES + 3, key, "expressions")
        values = list(values)
    else:
        values = [values]
    return [admission.expression(v, f"{key}[{i}]", symbols, tally) for i, v in enumerate(values)]


def _substituted(exprs, values: Mapping, key: str, name) -> list:
    """``exprs`` with ``values`` substituted, checked again: within the budget and with
    real, finite constants (a product of parameters may leave float range)."""
    tally = budget.Tally(f"mechanism {name!r}")
    out = []
    for i, e in enumerate(exprs):
        e = e.xreplace(values)
        label = f"{key}[{i}] (with the parameters' values)"
        tally.add(e, label)
        admission.check_constants(e, label)
        out.append(e)
    return out


def _unit_texts(units):
    """``units`` (a sequence or a mapping) with each unit a line of text."""
    if isinstance(units, Mapping):
        return {k: admission.check_text(v, f"units[{k}]") for k, v in units.items()}
    if isinstance(units, (str, bytes)) or not isinstance(units, (list, tuple)):
        raise ValueError(f"units must be a sequence or a mapping of strings, got {type(units).__name__}")
    return tuple(admission.check_text(v, f"units[{i}]") for i, v in enumerate(units))


def _declared(exprs, key: str, declared: set, R) -> None:
    """Every free symbol of ``exprs`` is declared, else ``ValueError`` naming the strays."""
    stray = set().union(*(e.free_symbols for e in exprs)) - declared if exprs else set()
    if not stray:
        return
    names = ", ".join(sorted(map(str, stray)))
    if R is None and stray & set(r):
        raise ValueError(f"{key} use {names}: the entries of a rotation R belong to a state with an "
                         "orientation; give its angular velocity as omega= (Mechanism.from_equations)")
    raise ValueError(f"{key} use {names}, not declared: give {'it' if len(stray) == 1 else 'each'} as a "
                     "coordinate, an input or a parameter (coordinates=, inputs=, parameters=)")


def _rotation(rotation) -> sp.Matrix:
    if rotation is None:
        return r
    rows = rotation.tolist() if isinstance(rotation, sp.MatrixBase) else rotation
    entries = [s for row in rows for s in row] if isinstance(rows, (list, tuple)) and all(
        isinstance(row, (list, tuple)) for row in rows) else None
    # the entries are checked before a Matrix is built of them (it would sympify text)
    if (entries is None or len(rows) != 3 or any(len(row) != 3 for row in rows)
            or not all(isinstance(s, sp.Symbol) for s in entries) or len(set(entries)) != 9):
        raise ValueError("rotation must be a 3×3 matrix of nine distinct symbols (the entries of R)")
    return sp.Matrix(rows)


def _affine(exprs, u, labels) -> tuple[sp.Matrix, sp.Matrix | None]:
    """``(G, f)`` with ``exprs = f + G u`` (``f``, the drift, ``None`` where it is zero);
    ``ValueError`` naming an expression's term that is not affine in ``u``."""
    G = sp.Matrix(exprs).jacobian(list(u))
    allowance = budget.Allowance()
    drifts = []
    for i, label in enumerate(labels):
        if G.row(i).has(*u):
            terms = sp.Add.make_args(budget.expanded(exprs[i]))
            term = next((t for t in terms if any(sp.diff(t, a).has(*u) for a in u)), exprs[i])
            raise ValueError(f"{label} = {_shown(exprs[i])}: its term {_shown(term)} is not affine in the inputs "
                             f"{', '.join(map(str, u))} (rates = f(x) + G(x) u)")
        # affine in u (G free of u): the expression is G u plus its value at u = 0, the drift
        drift = exprs[i].xreplace({a: 0 for a in u})
        if drift != 0:
            drift = budget.expanded(drift)
        if drift != 0:
            drift = budget.simplified(drift, allowance)
        drifts.append(drift)
    return G, (sp.Matrix(drifts) if any(e != 0 for e in drifts) else None)


def _angles(angles, x) -> tuple[bool, ...]:
    angles = _symbols(angles, "angles")
    stray = [a for a in angles if a not in x]
    if stray:
        raise ValueError(f"angles: {', '.join(map(str, stray))} {'is' if len(stray) == 1 else 'are'} "
                         "not among the coordinates")
    return tuple(c in angles for c in x)


def _units(units, x, is_angle) -> tuple[str, ...]:
    if units is None:
        return tuple("rad" if a else "" for a in is_angle)
    if isinstance(units, Mapping):
        stray = [k for k in units if k not in x]
        if stray:
            raise ValueError(f"units: {stray[0]} is not a coordinate")
        return tuple(str(units.get(c, "rad" if a else "")) for c, a in zip(x, is_angle))
    units = tuple(str(s) for s in units)
    if len(units) != len(x):
        raise ValueError(f"units: {len(units)} unit(s) for {len(x)} coordinate(s)")
    return units


def _tidy(e: sp.Expr, limit: int) -> sp.Expr:
    """A solved rate or determinant in a tidy form (trigonometric identities applied), where
    it has at most ``limit`` nodes, expanded too (:mod:`derivations.budget`); otherwise as
    it is."""
    if not budget.is_small(e, limit):
        return e
    expanded = budget.expanded(e, trig=True)
    if not budget.is_small(expanded, limit):
        return e
    return sp.simplify(sp.trigsimp(expanded))


def _shown(e) -> str:
    """``e`` as text for a message, shortened."""
    text = str(e)
    return text if len(text) <= 200 else text[:150] + " … " + text[-40:]
