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

from dataclasses import dataclass, field

import sympy as sp

from .rotations import e1, e2, e3, hat, r


@dataclass(frozen=True)
class Mechanism:
    """A driftless system on ``SO(3)``, ``SO(3) × Rᵏ`` or ``Rᵏ`` (see the module docstring).

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
        derivation: named intermediate results (leg rows, constraint matrix, ...).
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
    derivation: dict = field(default_factory=dict, compare=False, repr=False)

    def __post_init__(self):
        if self.L is None and self.X is None:
            raise ValueError(f"mechanism {self.name!r}: give L (an orientation), X (coordinates) or both")
        if (self.X is None) != (not self.coordinates):
            raise ValueError(f"mechanism {self.name!r}: X needs one row per coordinate")

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
    def state_space(self) -> str:
        """``"SO(3)"``, ``"SO(3)xR^k"`` or ``"R^k"``."""
        k = self.n_coordinates
        if not k:
            return "SO(3)"
        return f"SO(3)xR^{k}" if self.orientation else f"R^{k}"


# --------------------------------------------------------------------------------------
# Geometry of the orienting platform
# --------------------------------------------------------------------------------------

a, b, rho = sp.symbols("a b rho", positive=True)


@dataclass(frozen=True)
class PlatformGeometry:
    """Geometry of a two-leg orienting platform with one rolling disk.

    All vectors are 3-tuples (numbers or SymPy expressions). The sphere's centre O is
    the origin; the platform's orientation is R.

    Attributes:
        base1, base2: base joints ``A_i`` of the legs, in the world frame.
        tip1, tip2: platform joints of the legs, in the platform frame (world position
            ``R tip_i``).
        contact: the disk's contact point on the sphere, world frame.
        axle: direction of the disk's axle, world frame (tangent to the sphere at the
            contact point).
    """

    base1: tuple
    tip1: tuple
    base2: tuple
    tip2: tuple
    contact: tuple
    axle: tuple


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
    """Row ``c`` with ``d(l²)/dt = c ω`` along ``dR/dt = [ω] R``.

    Differentiates ``|R tip - base|²`` along the motion (no orthogonality needed: the
    term ``(R tip)ᵀ [ω] R tip`` vanishes identically); equals ``-2 (R tip × base)ᵀ``.
    """
    w = sp.Matrix(sp.symbols("omega1:4", real=True))
    A, P = sp.Matrix(base), sp.Matrix(tip)
    d = R * P - A
    rate = sp.expand(2 * (d.T * hat(w) * R * P)[0])
    return sp.Matrix([[rate.coeff(w[k]) for k in range(3)]])


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
    ``C^{-1} = adj(C) / det C`` and ``det C = κ Δ``.
    """
    C = constraint_matrix(geometry)
    delta, kappa = normalized_determinant(C)
    adj = C.adjugate()[:, :2]
    numerator = (adj / kappa).applyfunc(lambda x: sp.factor(sp.expand(x)))
    L = numerator / delta
    return Mechanism(
        name=name,
        description=description,
        L=L,
        delta=delta,
        inputs=("u1 = d(l1^2)/dt / (4 |A1| |B1|)", "u2 = d(l2^2)/dt / (4 |A2| |B2|)"),
        # every admissible ω lies in the plane the disk allows: a constant frame
        frame=constraint_plane_frame(C.row(2)),
        derivation={
            "geometry": geometry,
            "leg_length_squared": (leg_length_squared(geometry.base1, geometry.tip1),
                                   leg_length_squared(geometry.base2, geometry.tip2)),
            "constraint_matrix": C,
            "kappa": kappa,
            "L_numerator": numerator,
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
    B = sp.Matrix.hstack(sp.Matrix(b_1), sp.Matrix(b_2))
    Bo = sp.Matrix.hstack(*sp.GramSchmidt([B.col(0), B.col(1)], True))
    # N = R Bo, and Nᵀ L = Boᵀ RᵀR B = Boᵀ B on SO(3): W is constant
    return Mechanism(name=name, description=description, L=r * B, delta=None,
                     inputs=("u1 = body rate about b1", "u2 = body rate about b2"),
                     frame=r * Bo, frame_inputs=(Bo.T * B).inv())
