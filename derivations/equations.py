"""A mechanism from its equations, checked: the velocity field, or Pfaffian constraints.

- :func:`field_mechanism`: the driftless field itself — the coordinates' rates
  ``ẋ = G(x) u`` (a state in ``Rᵏ``), the spatial angular velocity ``ω = Ω(R, x) u`` of an
  orientation (``dR/dt = [ω] R``, a state on ``SO(3)``), or both (``SO(3) × Rᵏ``).
- :func:`constraint_mechanism`: the rates ``ẋ`` bound by linear equations
  ``A(x) ẋ = B(x) u`` — Pfaffian constraints ``A(x) ẋ = 0`` with the inputs chosen among the
  rates, and equations that define other inputs (a rolling speed) — solved for the rates
  that are not inputs, as :mod:`derivations.vehicles` derives the car: ``det A`` is the
  singularity function.

Both give a :class:`~derivations.mechanisms.Mechanism` for the code generator. Expressions
are SymPy's; ``parameters`` maps further symbols to numbers, substituted first (a float as
the rational of its printed digits). Every symbol must be declared — a coordinate, an input,
a parameter, or an entry of the rotation — else ``ValueError`` naming it, and every
argument is checked for the class of state it describes (the message says which argument
to use instead).
"""
from __future__ import annotations

from collections.abc import Mapping

import sympy as sp

from .generator import check_name
from .mechanisms import Mechanism, exact_number, is_free_name
from .rotations import r


def field_mechanism(name: str, *, inputs, coordinates=(), rates=(), omega=None, rotation=None,
                    angles=(), parameters=None, delta=None, units=None,
                    description: str | None = None) -> Mechanism:
    """The mechanism of a driftless field, given by its equations.

    - ``inputs``: the input symbols ``u``; ``coordinates``: the symbols ``x`` of a Euclidean
      state and ``rates`` their rates ``ẋ`` (one expression each, linear in the inputs);
    - ``omega``: the spatial angular velocity (3 expressions, linear in the inputs) of an
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
    name = check_name(name)
    u = _symbols(inputs, "inputs", at_least=1)
    x = _symbols(coordinates, "coordinates")
    values = _parameters(parameters)
    _distinct({"coordinates": x, "inputs": u, "parameters": tuple(values)})
    if not x and omega is None:
        raise ValueError("give coordinates= with rates= (a state x in R^k), omega= (an orientation R "
                         "on SO(3)) or both (SO(3) x R^k)")
    rates = _expressions(rates, "rates")
    if len(rates) != len(x):
        raise ValueError(f"rates: {len(rates)} expression(s) for {len(x)} coordinate(s); give one "
                         "rate per coordinate")
    R = None if omega is None else _rotation(rotation)
    declared = set(x) | set(u) | set(values) | (set(R) if R is not None else set())
    parts = {"rates": rates}
    if omega is not None:
        parts["omega"] = _expressions(omega, "omega")
        if len(parts["omega"]) != 3:
            raise ValueError(f"omega: the angular velocity has 3 components, got {len(parts['omega'])}")
    if delta is not None:
        parts["delta"] = _expressions([delta], "delta")
    for key, exprs in parts.items():
        _declared(exprs, key, declared, R)
    to_r = {**values, **({} if R is None else dict(zip(R, r)))}
    parts = {key: [e.xreplace(to_r) for e in exprs] for key, exprs in parts.items()}
    X = _linear(parts["rates"], u, [f"the rate of {c}" for c in x]) if x else None
    L = _linear(parts["omega"], u, [f"omega[{i}]" for i in range(3)]) if omega is not None else None
    field = X if L is None else (L if X is None else sp.Matrix.vstack(L, X))
    is_angle = _angles(angles, x)
    return Mechanism(
        name=name, description=description or f"{name} (from its equations)",
        L=L, X=X, coordinates=x, inputs=tuple(str(s) for s in u),
        delta=parts["delta"][0] if "delta" in parts else singular_factor(field),
        angles=is_angle, units=_units(units, x, is_angle),
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
    x = _symbols(coordinates, "coordinates", at_least=1)
    xdot = _symbols(velocities, "velocities")
    if len(xdot) != len(x):
        raise ValueError(f"velocities: {len(xdot)} symbol(s) for {len(x)} coordinate(s); give the "
                         "symbol of each coordinate's rate")
    u = _symbols(inputs, "inputs", at_least=1)
    values = _parameters(parameters)
    extra = tuple(s for s in u if s not in xdot)
    _distinct({"coordinates": x, "velocities": xdot, "parameters": tuple(values), "inputs": extra})
    equations = _expressions(constraints, "constraints")
    _declared(equations, "constraints", set(x) | set(xdot) | set(u) | set(values), None)
    equations = [e.xreplace(values) for e in equations]
    unknowns = [v for v in xdot if v not in u]
    if len(equations) != len(unknowns):
        raise ValueError(f"constraints: {len(equations)} equation(s) for the {len(unknowns)} rate(s) that "
                         f"are not inputs ({', '.join(map(str, unknowns)) or 'none'}); give as many "
                         "equations as those rates")
    moving = list(unknowns) + list(u)
    for i, e in enumerate(equations):
        rest = sp.expand(e - sp.Matrix([e]).jacobian(moving).dot(sp.Matrix(moving)))
        if any(e.diff(a).has(*moving) for a in moving) or rest != 0:
            raise ValueError(f"constraints[{i}] = {e} is not linear in the rates and inputs "
                             "(A(x) ẋ = B(x) u, no term without a rate or an input)")
    A = sp.Matrix(equations).jacobian(unknowns)
    B = -sp.Matrix(equations).jacobian(list(u))
    det = sp.factor_terms(_tidy(A.det()))
    if det == 0:
        raise ValueError("constraints: their matrix in the rates that are not inputs is singular "
                         "everywhere; they do not fix those rates")
    solved = dict(zip(unknowns, (A.LUsolve(B * sp.Matrix(u))).applyfunc(_tidy)))
    rates = [solved.get(v, v) for v in xdot]
    delta = None if not det.free_symbols else det.as_coeff_Mul()[1]
    return field_mechanism(name, inputs=u, coordinates=x, rates=rates, angles=angles, units=units,
                           delta=delta, description=description or f"{name} (from its constraints)")


def singular_factor(field: sp.Matrix) -> sp.Expr | None:
    """The product of the distinct non-constant factors of the denominators of ``field``'s
    entries (``tan``, ``cot``, ``sec``, ``csc`` written with ``sin`` and ``cos``), or ``None``:
    where it is not zero, the field is finite."""
    trig = {sp.tan: lambda a: sp.sin(a) / sp.cos(a), sp.cot: lambda a: sp.cos(a) / sp.sin(a),
            sp.sec: lambda a: 1 / sp.cos(a), sp.csc: lambda a: 1 / sp.sin(a)}
    factors = []
    for e in field:
        for f, g in trig.items():
            e = e.replace(f, g)
        _, den = sp.fraction(sp.together(e))
        for base, _ in sp.factor_list(den)[1]:
            if base.free_symbols and all(sp.simplify(base / b).free_symbols for b in factors):
                factors.append(base)
    return sp.Mul(*factors) if factors else None


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
    if parameters is None:
        return {}
    if not isinstance(parameters, Mapping):
        raise ValueError(f"parameters must be a mapping from symbols to numbers, got {type(parameters).__name__}")
    out = {}
    for k, v in parameters.items():
        if not isinstance(k, sp.Symbol):
            raise ValueError(f"parameters: the keys must be SymPy symbols, got {k!r}")
        try:
            value = sp.sympify(v)
        except (sp.SympifyError, TypeError):
            raise ValueError(f"parameters: {k} = {v!r} is not a number") from None
        if value.free_symbols or not value.is_number:
            raise ValueError(f"parameters: {k} = {v!r} is not a number")
        out[k] = exact_number(value)
    return out


def _expressions(values, key: str) -> list:
    values = list(values) if isinstance(values, (list, tuple, sp.MatrixBase)) else [values]
    out = []
    for i, v in enumerate(values):
        try:
            out.append(sp.sympify(v))
        except (sp.SympifyError, TypeError):
            raise ValueError(f"{key}[{i}]: {v!r} is not a SymPy expression") from None
    return out


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
    R = sp.Matrix(rotation)
    if R.shape != (3, 3) or not all(isinstance(s, sp.Symbol) for s in R) or len(set(R)) != 9:
        raise ValueError("rotation must be a 3×3 matrix of nine distinct symbols (the entries of R)")
    return R


def _linear(exprs, u, labels) -> sp.Matrix:
    """The matrix ``G`` with ``exprs = G u``; ``ValueError`` naming an expression that is not
    linear in ``u`` or has a term without an input (a drift)."""
    G = sp.Matrix(exprs).jacobian(list(u))
    for i, label in enumerate(labels):
        if G.row(i).has(*u):
            raise ValueError(f"{label} = {exprs[i]} is not linear in the inputs {', '.join(map(str, u))}")
        drift = sp.simplify(exprs[i] - (G.row(i) * sp.Matrix(u))[0])
        if drift != 0:
            raise ValueError(f"{label} = {exprs[i]} has the term {drift} without an input: the field "
                             "must be driftless (rates = G(x) u)")
    return G


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


def _tidy(e: sp.Expr) -> sp.Expr:
    """A solved rate or determinant in a tidy form (trigonometric identities applied)."""
    return sp.simplify(sp.trigsimp(sp.expand_trig(e)))
