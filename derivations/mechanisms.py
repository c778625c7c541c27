"""Mechanisms as data, and the orienting platform's kinematics from its geometry.

A mechanism is a driftless system in spatial form. On SO(3), ``dR/dt = [L(R) u] R``:
``ω = L(R) u`` is the spatial angular velocity, ``u`` the inputs. A state may also carry
Euclidean coordinates ``x`` (``(R, x) ∈ SO(3) × Rᵏ``) or consist of them alone (``x ∈ Rᵏ``)::

    dR/dt = [ω] R,   ω = L(R, x) u        (the orientation part, when there is one)
    dx/dt = X(R, x) u                      (the Euclidean part, k ≥ 1)

stacked as ``(ω, ẋ) = G u`` with the field ``G = [L; X]`` of ``d = 3 + k`` rows (``d = k``
without orientation; ``G = L`` on SO(3), the product with ``k = 0``). A
:class:`Mechanism` holds these as SymPy matrices in the symbols ``r_ij`` (see
:mod:`derivations.rotations`) and the coordinates and, where the field blows up, the
singularity function ``Δ``. Everything downstream (Q, A, B, the generated numeric code,
the planner) takes a mechanism as input.

The parallel orienting platform is built, not typed in: two extensible legs and a disk
rolling on the sphere give three linear equations ``C(R) ω = (u_1, u_2, 0)``; solving
them gives ``L(R)`` and ``det C(R)`` gives ``Δ(R)``.
"""
from __future__ import annotations

import keyword
import math
import re
from dataclasses import dataclass, field

import sympy as sp

from . import admission, budget
from .rotations import e1, e2, e3, hat, r


@dataclass(frozen=True)
class Mechanism:
    """A system on ``SO(3)``, ``SO(3) × Rᵏ`` or ``Rᵏ``, driftless or with a :attr:`drift`
    (see the module docstring).

    Attributes:
        name: identifier used by the CLI and the generated module's file name.
        description: one line for listings.
        L: 3×m SymPy matrix in the symbols ``r_ij`` (and the coordinates); column k is the
            spatial angular velocity ``ω`` produced by a unit input ``u_k`` — the paper's
            ``L(R)`` on SO(3), ``Ω`` of a state with coordinates; ``None`` for a state
            without orientation.
        delta: the singularity function ``Δ`` (the field is finite where ``Δ ≠ 0``), or
            ``None`` when it is finite everywhere (no singular set).
        inputs: names of the inputs, with their physical meaning.
        frame: the desingularised field ``N`` (d×m, rows as :attr:`field`'s, finite
            everywhere, orthonormal columns spanning the range of the field); the
            physical inputs are ``u = W w`` (see :func:`input_map`); ``None`` if the
            mechanism has none.
        frame_inputs: ``W`` when it is known in closed form (otherwise derived from the
            field and ``N`` by :func:`input_map`).
        coordinates: the symbols of the Euclidean state ``x`` (k of them; none on SO(3)).
        units: the unit of each coordinate (for reports: ``"m"``, ``"rad"``, ...).
        angles: which coordinates are angles (errors of an angle are taken modulo 2π).
        X: k×m rates of the coordinates per unit input (``None``: no coordinates).
        drift: the rates at rest, a column with the rows of :attr:`field` (``(ω, ẋ) = f + G u``;
            ``None``: driftless).
        derivation: named intermediate results (leg rows, constraint matrix, ...); the code
            generator takes ``auxiliary_forms`` — the generated ``G``, ``QG`` (in the inputs
            ``u1 … um``) and ``delta`` written in symbols of ``auxiliaries`` (pairs of a symbol
            and its expression, in order) — where the derivation gives them.
    """

    name: str
    description: str
    L: sp.Matrix | None = None
    delta: sp.Expr | None = None
    inputs: tuple[str, ...] = ()
    frame: sp.Matrix | None = None
    frame_inputs: sp.Matrix | None = None
    coordinates: tuple[sp.Symbol, ...] = ()
    units: tuple[str, ...] = ()
    angles: tuple[bool, ...] = ()
    X: sp.Matrix | None = None
    drift: sp.Matrix | None = None
    derivation: dict = field(default_factory=dict, compare=False, repr=False)

    def __post_init__(self):
        """Refuse a definition the generated code could not run: its user text and sizes
        (:func:`check_definition`), which class of state it is (an orientation needs ``L``
        of 3 rows, coordinates need ``X``), shapes that do not fit, and symbols that are
        neither ``R``'s entries nor coordinates (each named)."""
        check_definition(self)
        where = f"mechanism {self.name!r}"
        if self.L is None and self.X is None:
            raise ValueError(f"{where}: give L (an orientation R: 3 rows in r11 … r33), X (the rates "
                             "of coordinates=) or both; nonholo.Mechanism.from_equations builds either "
                             "from equations")
        if self.L is not None and self.L.shape[0] != 3:
            raise ValueError(f"{where}: L is the angular velocity of an orientation R (3 rows in "
                             f"r11 … r33), got {self.L.shape[0]} rows; a state of coordinates x has "
                             "no L but X (ẋ = X u) with coordinates=, as "
                             "nonholo.Mechanism.from_equations(name, coordinates=..., inputs=..., "
                             "rates=...) builds it")
        if (self.X is None) != (not self.coordinates) or (
                self.X is not None and self.X.shape[0] != len(self.coordinates)):
            raise ValueError(f"{where}: X needs one row per coordinate")
        if self.L is not None and self.X is not None and self.L.shape[1] != self.X.shape[1]:
            raise ValueError(f"{where}: L has {self.L.shape[1]} input columns, X {self.X.shape[1]}")
        if len(self.inputs) != self.n_inputs:
            raise ValueError(f"{where}: {len(self.inputs)} input names for {self.n_inputs} inputs")
        for key in ("units", "angles"):
            if getattr(self, key) and len(getattr(self, key)) != self.n_coordinates:
                raise ValueError(f"{where}: {key} needs one entry per coordinate")
        d = (3 if self.orientation else 0) + self.n_coordinates
        for key, shape in (("frame", (d, self.n_inputs)), ("frame_inputs", (self.n_inputs, self.n_inputs)),
                           ("drift", (d, 1))):
            value = getattr(self, key)
            if value is not None and value.shape != shape:
                raise ValueError(f"{where}: {key} must be {shape[0]}×{shape[1]}, got "
                                 f"{value.shape[0]}×{value.shape[1]}")
        for x in self.coordinates:
            if not isinstance(x, sp.Symbol) or not is_free_name(str(x)):
                raise ValueError(f"{where}: the coordinate {x} needs another name: a Python identifier "
                                 "other than those of the generated code (R, q, v, out, numpy, r_ij, s_i, "
                                 "u_i, v_i)")
        known = set(self.coordinates) | (set(r) if self.orientation else set())
        for key in ("L", "X", "delta", "frame", "frame_inputs", "drift"):
            value = getattr(self, key)
            stray = set() if value is None else sp.sympify(value).free_symbols - known
            if stray:
                names = ", ".join(sorted(map(str, stray)))
                if not self.orientation and stray & set(r):
                    hint = "; only a state with an orientation R (L given) has the entries r_ij"
                elif key == "L" and not self.coordinates:
                    hint = ("; a state of coordinates x takes X (ẋ = X u) with coordinates=, as "
                            "nonholo.Mechanism.from_equations(name, coordinates=..., inputs=..., "
                            "rates=...) builds it")
                else:
                    hint = ": declare them as coordinates or give them values"
                raise ValueError(f"{where}: {key} uses {names}, which {'is' if len(stray) == 1 else 'are'} "
                                 f"neither a coordinate nor an entry of R{hint}")

    @property
    def orientation(self) -> bool:
        """Whether the state includes an orientation ``R``."""
        return self.L is not None

    @property
    def Omega(self) -> sp.Matrix | None:
        """The orientation's rows of the field, ``ω = Ω u`` (:attr:`L`)."""
        return self.L

    @property
    def n_inputs(self) -> int:
        return (self.L if self.L is not None else self.X).shape[1]

    @property
    def n_coordinates(self) -> int:
        return len(self.coordinates)

    @property
    def field(self) -> sp.Matrix:
        """The stacked field ``G = [L; X]`` (d×m, ``d = 3 + k`` with orientation, else ``k``):
        the state's rates ``(ω, ẋ) = G u``; ``G = L`` on SO(3)."""
        if self.X is None:
            return self.L
        return sp.Matrix.vstack(self.L, self.X) if self.orientation else self.X

    @property
    def has_drift(self) -> bool:
        """Whether the rates at rest are not zero (:attr:`drift`)."""
        return self.drift is not None and any(e != 0 for e in self.drift)

    @property
    def state_space(self) -> str:
        """``"SO(3)"``, ``"SO(3)xR^k"`` or ``"R^k"``."""
        k = self.n_coordinates
        if not k:
            return "SO(3)"
        return f"SO(3)xR^{k}" if self.orientation else f"R^{k}"


#: The fields of a :class:`Mechanism` that hold matrices.
MATRIX_FIELDS = ("L", "X", "frame", "frame_inputs", "drift")


def check_definition(mechanism) -> None:
    """Refuse a symbolic mechanism whose user text could become code or whose size is past
    the budget of the symbolic work, before anything is derived or hashed from it.

    The name is a Python identifier (:func:`derivations.admission.check_name`); the
    description, the inputs' names and the units are lines of printable text
    (:func:`~derivations.admission.check_text`); ``L``, ``X``, ``frame`` and
    ``frame_inputs`` are SymPy matrices and ``delta`` an expression, each entry — and each
    of the derivation's ``auxiliary_forms``, ``auxiliaries`` and ``geometry`` — within
    :mod:`derivations.budget` (the field and the frame, which are differentiated, within its
    ``WORK`` too) and with real, finite constants
    (:func:`~derivations.admission.check_constants`); a platform's geometry must be one that
    can be built (:func:`check_geometry`).

    Parameters
    ----------
    mechanism : Mechanism
        The symbolic mechanism (or an object with its fields).

    Raises
    ------
    ValueError
        Naming the field (and the entry).
    """
    admission.check_name(getattr(mechanism, "name", None))
    where = f"mechanism {mechanism.name!r}"
    admission.check_text(getattr(mechanism, "description", None), f"{where}: description")
    for key in ("inputs", "units"):
        values = getattr(mechanism, key, ())
        if not isinstance(values, (tuple, list)):
            raise ValueError(f"{where}: {key} must be a tuple of strings, got {type(values).__name__}")
        for i, value in enumerate(values):
            admission.check_text(value, f"{where}: {key}[{i}]")
    tally = budget.Tally(where)
    differentiated = 0
    for key in MATRIX_FIELDS:
        value = getattr(mechanism, key, None)
        if value is None:
            continue
        if not isinstance(value, sp.MatrixBase):
            raise ValueError(f"{where}: {key} must be a SymPy matrix, got {type(value).__name__}")
        before = tally.nodes
        _check_entries(value, f"{where}: {key}", tally)
        if key != "frame_inputs":
            differentiated += tally.nodes - before
    rows = (3 if getattr(mechanism, "L", None) is not None else 0) + len(getattr(mechanism, "coordinates", ()))
    budget.check_work(differentiated, rows, f"{where}: the field")
    delta = getattr(mechanism, "delta", None)
    if delta is not None:
        admission.expression(delta, f"{where}: delta", tally=tally)
    derivation = getattr(mechanism, "derivation", None) or {}
    if not isinstance(derivation, dict):
        raise ValueError(f"{where}: derivation must be a dict, got {type(derivation).__name__}")
    for name, form in dict(derivation.get("auxiliary_forms", {})).items():
        if isinstance(form, sp.MatrixBase):
            _check_entries(form, f"{where}: auxiliary form {name}", tally)
        else:
            admission.expression(form, f"{where}: auxiliary form {name}", tally=tally)
    geometry = derivation.get("geometry")
    if geometry is not None:                # the legs' code is generated from it
        for key in GEOMETRY_FIELDS:
            check_vector(getattr(geometry, key, None), f"{where}: geometry {key}")
        check_geometry(geometry, f"{where}: geometry")
    for i, pair in enumerate(derivation.get("auxiliaries", ())):
        symbol, value = pair
        if not isinstance(symbol, sp.Symbol) or not is_free_name(symbol.name):
            raise ValueError(f"{where}: auxiliaries[{i}] must define a symbol named by an identifier, "
                             f"got {symbol!r}")
        admission.expression(value, f"{where}: auxiliaries[{i}] ({symbol})", tally=tally)


def _check_entries(matrix: sp.MatrixBase, key: str, tally: budget.Tally) -> None:
    """Every entry of ``matrix`` within the budget, with real, finite constants."""
    budget.check_count(len(matrix), (budget.COORDINATES + 3) * budget.INPUTS, key, "entries")
    rows, cols = matrix.shape
    for i in range(rows):
        for j in range(cols):
            admission.expression(matrix[i, j], f"{key}[{i}, {j}]", tally=tally)


#: Names the generated code and the variational derivation use themselves: a coordinate
#: may not take them (:func:`is_free_name`).
TAKEN_NAMES = re.compile(r"(R|q|v|out|numpy|r[1-3][1-3]|[suv][0-9]+)")


def is_free_name(name: str) -> bool:
    """Whether a coordinate may be called ``name`` in a generated module: an identifier, not a
    keyword, not one of :data:`TAKEN_NAMES`."""
    return isinstance(name, str) and name.isidentifier() and not keyword.iskeyword(name) and not TAKEN_NAMES.fullmatch(name)


# --------------------------------------------------------------------------------------
# Geometry of the orienting platform
# --------------------------------------------------------------------------------------

a, b, rho = sp.symbols("a b rho", positive=True)

#: The numbers of the symbols of a symbolic platform geometry: the sphere's radius ``ρ = 1``
#: is the unit of length, the platform joints lie on the sphere (``b = ρ``) and the base
#: joints at ``a = 8/5`` from its centre. A symbolic geometry is checked at them
#: (:func:`check_geometry`), and the generated code draws and measures the legs with them
#: (``derivations.codegen.DRAWING_DIMENSIONS``); the kinematics ``L`` and ``Δ`` do not depend
#: on them.
DIMENSIONS = {a: sp.Rational(8, 5), b: sp.Integer(1), rho: sp.Integer(1)}

#: The relative tolerance of :func:`check_geometry`: a contact point or a platform joint
#: within it of the unit sphere is on it, an axle whose cosine with the contact point is
#: within it of 0 is tangent.
GEOMETRY_TOL = 1e-9

#: The fields of a :class:`PlatformGeometry`, in order.
GEOMETRY_FIELDS = ("base1", "tip1", "base2", "tip2", "contact", "axle")


@dataclass(frozen=True)
class PlatformGeometry:
    """Geometry of a two-leg orienting platform with one rolling disk.

    The platform is a sphere of radius 1 — its radius is the unit of length — turning about
    its centre O, the origin; its orientation is ``R``. Every vector is a 3-tuple of
    numbers or SymPy expressions (text is refused, never parsed: SymPy would evaluate it);
    the symbols ``a``, ``b``, ``rho`` of this module stand for the numbers of
    :data:`DIMENSIONS` where a geometry is checked or drawn.

    The geometry is checked on construction (:func:`check_geometry`): the contact point
    and the platform joints on the unit sphere, the axle tangent to it at the contact
    point, each within :data:`GEOMETRY_TOL`. An impossible geometry is refused before
    anything is derived from it.

    Parameters
    ----------
    base1, base2 : tuple
        The legs' base joints ``A_i``, in the world frame (fixed).
    tip1, tip2 : tuple
        The legs' platform joints ``B_i``, in the platform's frame (world position
        ``R B_i``), on the sphere: ``|B_i| = 1``.
    contact : tuple
        The disk's contact point on the sphere, in the world frame: ``|contact| = 1``.
    axle : tuple
        The direction of the disk's axle, in the world frame, tangent to the sphere at the
        contact point (``axle · contact = 0``); its length does not matter.

    Raises
    ------
    ValueError
        Naming the field: a vector that is not three numbers or SymPy expressions, a
        constant that is not real and finite, or a geometry :func:`check_geometry` refuses
        (with the defect measured).

    See Also
    --------
    platform_mechanism : The platform's kinematics derived from its geometry.

    Examples
    --------
    The README's platform, its disk off the pole and its leg bases raised:

    >>> from derivations.mechanisms import PlatformGeometry
    >>> geometry = PlatformGeometry(
    ...     base1=(0.0, 1.6, 0.5), tip1=(0.0, 1.0, 0.0),
    ...     base2=(1.6, 0.0, 0.5), tip2=(1.0, 0.0, 0.0),
    ...     contact=(0.6, 0.0, 0.8), axle=(0.0, 1.0, 0.0))
    """

    base1: tuple
    tip1: tuple
    base2: tuple
    tip2: tuple
    contact: tuple
    axle: tuple

    def __post_init__(self):
        """Refuse a vector that is not three numbers or SymPy expressions, a constant that
        is not real and finite (:func:`check_vector`), and an impossible geometry
        (:func:`check_geometry`)."""
        for key in GEOMETRY_FIELDS:
            check_vector(getattr(self, key), f"geometry: {key}")
        check_geometry(self)


def numeric_vector(values, key: str) -> tuple[float, float, float]:
    """A checked vector (:func:`check_vector`) in floats, its symbols ``a``, ``b``, ``rho``
    at :data:`DIMENSIONS`.

    Parameters
    ----------
    values : sequence
        Three numbers or SymPy expressions.
    key : str
        What it is, for the message.

    Returns
    -------
    tuple of float
        The vector's value.

    Raises
    ------
    ValueError
        Naming ``key``, for an entry with other symbols (it cannot be measured) or whose
        value is not a finite real number.
    """
    out = []
    for i, value in enumerate(values):
        expr = sp.sympify(value).xreplace(DIMENSIONS)
        if expr.free_symbols:
            names = ", ".join(sorted(map(str, expr.free_symbols)))
            raise ValueError(f"{key}[{i}] = {value} has the symbol{'s' if len(expr.free_symbols) > 1 else ''} "
                             f"{names}: a platform's geometry is given by numbers, or in the symbols a, b, "
                             "rho of derivations.mechanisms (taken as a = 8/5, b = rho = 1)")
        number = admission.numeric_value(expr)
        if number.imag or not math.isfinite(number.real):
            raise ValueError(f"{key}[{i}] = {value} is not a finite real number")
        out.append(number.real)
    return tuple(out)


def measured(value: float, expected: float) -> str:
    """``value`` with the digits that tell it from ``expected`` (4 at least).

    Parameters
    ----------
    value, expected : float
        The measured and the expected number.

    Returns
    -------
    str
        ``"0.92"``, ``"1.005"``, ``"1.000000002"``.
    """
    for digits in range(4, 18):
        text = f"{value:.{digits}g}"
        if float(text) != expected:
            return text
    return repr(value)


def check_geometry(geometry, where: str = "geometry") -> None:
    """Refuse a platform geometry that cannot be built: the sphere's radius is 1, so the
    disk's contact point and the legs' platform joints must lie on the unit sphere, and the
    disk's axle must be tangent to it at the contact point; each within the relative
    tolerance :data:`GEOMETRY_TOL`. A symbolic geometry is measured at :data:`DIMENSIONS`.

    Parameters
    ----------
    geometry : PlatformGeometry
        The geometry (or an object with its six fields).
    where : str
        What it is, for the message.

    Raises
    ------
    ValueError
        Naming the field and its defect as measured, e.g. ``"geometry: contact: |contact|
        = 0.92, expected 1 (...)"``, ``"geometry: axle: axle·contact/(|axle| |contact|) =
        0.31, expected 0 (tangent ...)"``, ``"geometry: tip1: |tip1| = 1.005, expected the
        sphere's radius 1 (...)"``.
    """
    v = {key: numeric_vector(getattr(geometry, key, None), f"{where}: {key}") for key in GEOMETRY_FIELDS}
    symbolic = {key for key in GEOMETRY_FIELDS
                if any(sp.sympify(x).free_symbols for x in getattr(geometry, key))}

    def at(*keys):          # where a symbolic vector was measured
        return "; measured at a = 8/5, b = rho = 1" if symbolic.intersection(keys) else ""

    scale = "lengths are in units of the sphere's radius: divide every vector by it"
    contact = math.hypot(*v["contact"])
    if abs(contact - 1.0) > GEOMETRY_TOL:
        raise ValueError(f"{where}: contact: |contact| = {measured(contact, 1.0)}, expected 1 (the disk "
                         f"touches the sphere, of radius 1; {scale}{at('contact')})")
    axle = math.hypot(*v["axle"])
    if not axle > 0.0:
        raise ValueError(f"{where}: axle: |axle| = 0, expected a direction (tangent to the sphere at the "
                         "contact point)")
    cosine = sum(x * y for x, y in zip(v["axle"], v["contact"])) / (axle * contact)
    if abs(cosine) > GEOMETRY_TOL:
        raise ValueError(f"{where}: axle: axle·contact/(|axle| |contact|) = {measured(cosine, 0.0)}, expected 0 "
                         f"(the axle is tangent to the sphere at the contact point{at('axle', 'contact')})")
    for key in ("tip1", "tip2"):
        length = math.hypot(*v[key])
        if abs(length - 1.0) > GEOMETRY_TOL:
            raise ValueError(f"{where}: {key}: |{key}| = {measured(length, 1.0)}, expected the sphere's radius 1 "
                             f"(the platform joints are on the sphere; {scale}{at(key)})")


def check_vector(values, key: str) -> None:
    """Refuse anything but three numbers or SymPy expressions, each within the budget and
    with real, finite constants (:func:`derivations.admission.expression`; text refused).

    Parameters
    ----------
    values : sequence
        The vector.
    key : str
        What it is, for the message.

    Raises
    ------
    ValueError
        Naming ``key``.
    """
    if isinstance(values, (str, bytes)) or not hasattr(values, "__len__") or len(values) != 3:
        raise ValueError(f"{key} must be a vector of 3 numbers or SymPy expressions, got {values!r:.80}")
    for i, value in enumerate(values):
        if isinstance(value, (str, bytes)):
            raise ValueError(f"{key}[{i}] = {value!r:.80} is text; give a number or a SymPy expression "
                             "(text is never evaluated)")
        admission.expression(value, f"{key}[{i}]")


#: The paper's platform (reconstruction, ``../shared/design/MODEL.md``): leg 1 from
#: ``a e_2`` to ``R(b e_2)``, leg 2 from ``a e_1`` to ``R(b e_1)``, the disk touching the
#: pole ``ρ e_3`` with its axle along ``(e_1 - e_2)/√2``.
PAPER_GEOMETRY = PlatformGeometry(
    base1=tuple(a * e2), tip1=tuple(b * e2),
    base2=tuple(a * e1), tip2=tuple(b * e1),
    contact=tuple(rho * e3), axle=tuple((e1 - e2) / sp.sqrt(2)),
)


def leg_length_squared(base, tip, R: sp.Matrix = r) -> sp.Expr:
    """``l² = |R tip - base|² = |base|² + |tip|² - 2 baseᵀ R tip`` (uses ``RᵀR = I``).

    For the paper's leg 1 this is ``a² + b² - 2ab r_22``.
    """
    A, P = sp.Matrix(base), sp.Matrix(tip)
    return sp.expand((A.T * A)[0] + (P.T * P)[0] - 2 * (A.T * R * P)[0])


def leg_rate_row(base, tip, R: sp.Matrix = r) -> sp.Matrix:
    """Row ``c`` with ``d(l²)/dt = c ω`` along ``dR/dt = [ω] R``: ``c = -2 (R tip × base)ᵀ``.

    Differentiating ``|R tip - base|²`` along the motion gives ``2 (R tip - base)ᵀ [ω] R tip``;
    the term ``(R tip)ᵀ [ω] R tip`` vanishes identically (no orthogonality needed), and
    ``-2 baseᵀ (ω × R tip) = -2 ω · (R tip × base)``. Linear in ``R``: any 3×3 matrix may
    stand for it (``[e_k] R`` gives the row's derivative along ``∂R = [e_k] R``).
    """
    # the coefficient of R_ij in component m: -2 tip_j (e_i × base)_m (no products of sums)
    A, P = sp.Matrix(base), sp.Matrix(tip)
    axes = [sp.eye(3).col(i).cross(A) for i in range(3)]
    return sp.Matrix([[sp.expand(sp.Add(*(-2 * P[j] * axes[i][m] * R[i, j] for i in range(3) for j in range(3))))
                       for m in range(3)]])


def leg_input_scale(base, tip) -> sp.Expr:
    """The paper's control scaling: ``u_i = d(l_i²)/dt / (4 |base_i| |tip_i|)``."""
    A, P = sp.Matrix(base), sp.Matrix(tip)
    return 1 / (4 * sp.sqrt((A.T * A)[0]) * sp.sqrt((P.T * P)[0]))


def rolling_constraint_row(contact, axle) -> sp.Matrix:
    """Row ``n`` with ``n ω = 0``: no side slip of the disk on the sphere.

    The sphere's point at the contact moves with ``ω × c``; a disk rolls along
    ``axle × normal`` and cannot slide along its axle, so ``(ω × c) · axle = 0``, i.e.
    ``ω · (c × axle) = 0``. The row is normalised to unit length.
    """
    n = sp.Matrix(contact).cross(sp.Matrix(axle))
    n = sp.simplify(n / sp.sqrt((n.T * n)[0]))
    return n.T


def constraint_matrix(geometry: PlatformGeometry, R: sp.Matrix = r) -> sp.Matrix:
    """``C(R)`` with ``C(R) ω = (u_1, u_2, 0)``: two scaled leg-rate rows, the disk row."""
    g = geometry
    row1 = leg_rate_row(g.base1, g.tip1, R) * leg_input_scale(g.base1, g.tip1)
    row2 = leg_rate_row(g.base2, g.tip2, R) * leg_input_scale(g.base2, g.tip2)
    return sp.simplify(sp.Matrix.vstack(row1, row2, rolling_constraint_row(g.contact, g.axle)))


def normalized_determinant(C: sp.Matrix) -> tuple[sp.Expr, sp.Expr]:
    """``det C = κ Δ`` with ``Δ`` a polynomial in ``r_ij`` whose leading coefficient
    (lexicographic order r11 > r12 > … > r33) is 1. Returns ``(Δ, κ)``."""
    det = sp.expand(C.det())
    poly = sp.Poly(det, *r)
    kappa = sp.simplify(poly.LC())
    return sp.expand(sp.simplify(det / kappa)), kappa


def input_map(L: sp.Matrix, N: sp.Matrix) -> sp.Matrix:
    """``W(R) = (Nᵀ L)^{-1}``: the physical inputs ``u = W w`` that produce ``ω = N w``.

    Valid when the columns of ``N`` span the range of ``L`` (then ``L W = N``).
    """
    return (N.T * L).applyfunc(sp.cancel).inv().applyfunc(sp.factor)


def constraint_plane_frame(row: sp.Matrix) -> sp.Matrix:
    """Orthonormal basis (3×2) of the plane ``{ω : row ω = 0}``."""
    basis = sp.GramSchmidt(sp.Matrix(row).nullspace(), True)
    return sp.Matrix.hstack(*basis)


def platform_mechanism(name: str, geometry: PlatformGeometry, description: str) -> Mechanism:
    """Derive ``Δ(R)`` and ``L(R)`` of a two-leg/one-disk platform from its geometry.

    ``ω = C(R)^{-1} (u_1, u_2, 0)``, so ``L`` is the first two columns of
    ``C^{-1} = adj(C) / det C`` and ``det C = κ Δ``. Every admissible ``ω`` lies in the
    plane the disk allows, spanned by the constant frame ``N``, and ``u = C₁₂(R) ω`` (the leg
    rows of ``C``) gives the physical inputs of ``ω = N w`` exactly: ``W = C₁₂ N``,
    polynomial (``(Nᵀ L)^{-1}``, :func:`~derivations.mechanisms.input_map`, without
    inverting anything).

    A geometry of numbers only (floats taken as the rationals they print as) is derived by
    :func:`~derivations.mechanisms.exact_platform`, which keeps ``L`` and ``Q`` in terms of
    the entries of ``C`` (no simplification of rational functions); a symbolic one (``a``,
    ``b``, ``ρ``) as the appendix prints it.

    Parameters
    ----------
    name : str
        The mechanism's name, a Python identifier (it names the generated module).
    geometry : PlatformGeometry
        Where the legs and the disk are (checked when it was made).
    description : str
        One line for listings.

    Returns
    -------
    derivations.mechanisms.Mechanism
        The symbolic mechanism; ``nonholo.Mechanism.from_symbolic`` generates and compiles
        its numeric code.

    Raises
    ------
    ValueError
        If the mechanism's name, description or size is refused
        (:func:`~derivations.mechanisms.check_definition`), or the geometry is not one that
        can be built (:func:`check_geometry`, checked again: before anything is derived).
    """
    check_geometry(geometry)
    exact = exact_geometry(geometry)
    if exact is not None:
        return exact_platform(name, exact, description)
    C = constraint_matrix(geometry)
    delta, kappa = normalized_determinant(C)
    adj = C.adjugate()[:, :2]
    numerator = (adj / kappa).applyfunc(lambda x: sp.factor(sp.expand(x)))
    L = numerator / delta
    frame = constraint_plane_frame(C.row(2))
    return Mechanism(
        name=name,
        description=description,
        L=L,
        delta=delta,
        inputs=PLATFORM_INPUTS,
        frame=frame,
        frame_inputs=(C[:2, :] * frame).applyfunc(sp.factor),
        derivation={
            "geometry": geometry,
            "leg_length_squared": (leg_length_squared(geometry.base1, geometry.tip1),
                                   leg_length_squared(geometry.base2, geometry.tip2)),
            "constraint_matrix": C,
            "kappa": kappa,
            "L_numerator": numerator,
        },
    )


#: The inputs of a two-leg platform: the legs' scaled rates.
PLATFORM_INPUTS = ("u1 = d(l1^2)/dt / (4 |A1| |B1|)", "u2 = d(l2^2)/dt / (4 |A2| |B2|)")


def exact_geometry(geometry: PlatformGeometry) -> PlatformGeometry | None:
    """``geometry`` with exact numbers (a float as the rational of its printed digits,
    ``0.3 → 3/10``), or ``None`` if any of its entries has a symbol."""
    values = {}
    for key in ("base1", "tip1", "base2", "tip2", "contact", "axle"):
        vector = tuple(sp.sympify(x) for x in getattr(geometry, key))
        if any(x.free_symbols for x in vector):
            return None
        values[key] = tuple(exact_number(x) for x in vector)
    return PlatformGeometry(**values)


def exact_number(x: sp.Expr) -> sp.Expr:
    """``x`` with its floats as the rationals of their printed digits (``0.112 → 14/125``)."""
    if isinstance(x, sp.Float):
        return sp.Rational(repr(float(x)))
    return x.xreplace({f: sp.Rational(repr(float(f))) for f in x.atoms(sp.Float)}) if x.has(sp.Float) else x


def exact_platform(name: str, geometry: PlatformGeometry, description: str) -> Mechanism:
    """:func:`platform_mechanism` of a geometry of exact numbers, without simplifying.

    With symbols ``c_ij`` for the entries of the unscaled constraint matrix ``C₀(R)`` (leg
    rows ``-2 (R tip_i × base_i)ᵀ``, disk row ``contact × axle``; ``C = diag(s₁, s₂, 1/|contact ×
    axle|) C₀``, ``s_i = 1/k_i`` the inputs' scales): ``L = adj(C₀)[:, :2] diag(k) / det C₀`` and,
    differentiating ``C ω = (u, 0)`` along ``∂R = [e_j] R`` (``C₀`` is linear in ``R``, its disk
    row constant; ``d_j = C₀([e_j] R)``), the variational matrix
    ``Q[:, j] = -adj(C₀) d_j L u / det C₀``; ``Δ = det C₀ / κ₀`` (leading coefficient 1, as
    :func:`normalized_determinant`); ``W = diag(s) C₀[:2] N``. The derivation gives these forms in the symbols
    (``auxiliary_forms``) with the symbols' definitions (``auxiliaries``: linear forms in
    ``r_ij``, and the constants ``k_i``), so the generated code computes ``C₀``, its
    adjugate and determinant once; the mechanism's ``L`` and ``Δ`` are the same in ``r_ij``.
    """
    g = geometry
    legs = ((g.base1, g.tip1), (g.base2, g.tip2))
    disk = sp.Matrix(g.contact).cross(sp.Matrix(g.axle)).T
    C0 = sp.Matrix.vstack(*(leg_rate_row(base, tip) for base, tip in legs), disk)
    c = sp.Matrix(3, 3, lambda i, j: sp.Symbol(f"c{i + 1}{j + 1}"))
    det_c, adj_c = c.det(method="berkowitz"), c.adjugate()
    det0 = sp.Poly(det_c.xreplace(dict(zip(c, C0))), *r)
    kappa0 = det0.LC()
    scales = [leg_input_scale(base, tip) for base, tip in legs]
    k = sp.symbols("k1:3")
    auxiliaries = [*zip(c, C0), *((ki, 1 / s) for ki, s in zip(k, scales))]
    u = sp.symbols("u1:3", real=True)
    # written out entry by entry: SymPy's matrix products of symbolic entries are slower
    L_c = sp.Matrix(3, 2, lambda i, j: adj_c[i, j] * k[j] / det_c)
    omega = [adj_c[i, 0] * k[0] * u[0] / det_c + adj_c[i, 1] * k[1] * u[1] / det_c for i in range(3)]
    columns = []
    for j, e in enumerate((e1, e2, e3)):
        d = sp.Matrix(2, 3, lambda i, l: sp.Symbol(f"d{j + 1}{i + 1}{l + 1}"))
        auxiliaries += zip(d, sp.Matrix.vstack(*(leg_rate_row(base, tip, hat(e) * r) for base, tip in legs)))
        z = [sp.Add(*(d[i, l] * omega[l] for l in range(3))) for i in range(2)]
        columns.append([-(adj_c[m, 0] * z[0] + adj_c[m, 1] * z[1]) / det_c for m in range(3)])
    norm = sp.sqrt((disk * disk.T)[0])
    frame = constraint_plane_frame(disk)
    W_c = sp.Matrix(2, 2, lambda i, j: sp.Add(*(c[i, l] * frame[l, j] for l in range(3))) / k[i])
    values = dict(auxiliaries)
    return Mechanism(
        name=name, description=description, L=L_c.xreplace(values),
        delta=sp.expand(det0.as_expr() / kappa0), inputs=PLATFORM_INPUTS, frame=frame,
        frame_inputs=sp.diag(*scales) * (C0[:2, :] * frame).applyfunc(sp.expand),
        derivation={
            "geometry": geometry,
            "leg_length_squared": tuple(leg_length_squared(base, tip) for base, tip in legs),
            "constraint_matrix": sp.Matrix.vstack(C0.row(0) * scales[0], C0.row(1) * scales[1], disk / norm),
            "kappa": kappa0 * scales[0] * scales[1] / norm,
            "auxiliaries": tuple(auxiliaries),
            "auxiliary_forms": {"G": L_c, "QG": sp.Matrix(columns).T, "delta": det_c / kappa0, "W": W_c},
        },
    )


def paper_platform() -> Mechanism:
    """The non-holonomic orienting platform of the paper (``PAPER_GEOMETRY``)."""
    return platform_mechanism(
        "platform", PAPER_GEOMETRY,
        "orienting platform of Tchon & Jakubiak (2014): two legs, a disk rolling at the pole",
    )


def body_rate_mechanism(name: str, b_1, b_2, description: str) -> Mechanism:
    """A rigid body steered by two body-fixed angular-velocity inputs.

    ``dR/dt = R [u_1 b_1 + u_2 b_2]``, i.e. spatial ``ω = R (u_1 b_1 + u_2 b_2)``, so
    ``L(R) = R [b_1 b_2]``: polynomial, no singular set.
    """
    check_vector(b_1, "b_1")
    check_vector(b_2, "b_2")
    B = sp.Matrix.hstack(sp.Matrix(b_1), sp.Matrix(b_2))
    Bo = sp.Matrix.hstack(*sp.GramSchmidt([B.col(0), B.col(1)], True))
    # N = R Bo, and Nᵀ L = Boᵀ RᵀR B = Boᵀ B on SO(3): W is constant
    return Mechanism(name=name, description=description, L=r * B, delta=None,
                     inputs=("u1 = body rate about b1", "u2 = body rate about b2"),
                     frame=r * Bo, frame_inputs=(Bo.T * B).inv())
