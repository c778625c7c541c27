"""Mechanisms whose state goes beyond SO(3): ``(R, x) ∈ SO(3) × Rᵏ`` or ``x ∈ Rⁿ``.

A driftless system on a product state space, in the same spatial form as the SO(3)
mechanisms of :mod:`derivations.mechanism`::

    dR/dt = [ω] R,   ω = Ω(R, x) u        (the orientation part, when there is one)
    dx/dt = X(R, x) u                      (the Euclidean part, k ≥ 1)

Stacked, ``q̇ = G(R, x) u`` with the field ``G = [Ω; X]`` of ``d = 3 + k`` rows (``d = k``
without orientation). A variation of the state is ``(∂R, ∂x) = ([s_R] R, s_x)``, taken on
the left for ``R`` as everywhere in the toolkit, and stacked as ``s = (s_R, s_x)``. The
variational system is that of eq. (9) on the product,

    ds/dt = A s + B ∂u/∂θ,   A = Q(R, x, u) + [ω] ⊕ 0,   B = G(R, x),

with ``Q s = d/dε G(exp(ε[s_R]) R, x + ε s_x) u`` at ``ε = 0`` (:func:`Q_matrix`): the
analogue of the appendix's eq. (12), whose rotation block it is. The terminal error is
``(log(R_T R_dᵀ), x_T − x_d)``; as on SO(3), the planner asks ``s_T = −γ e_T``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from .so3 import hat, r
from .variational import inputs


@dataclass(frozen=True)
class StateMechanism:
    """A driftless system on ``SO(3) × Rᵏ`` (``orientation``) or ``Rᵏ`` (see the module).

    Attributes:
        name, description, inputs: as for :class:`~derivations.mechanism.Mechanism`.
        coordinates: the symbols of the Euclidean state ``x`` (k of them).
        units: the unit of each coordinate (for reports: ``"m"``, ``"rad"``, ...).
        angles: which coordinates are angles (errors of an angle are taken modulo 2π).
        Omega: 3×m spatial angular velocity per unit input, in ``r_ij`` and ``x``
            (``None`` without orientation).
        X: k×m rates of ``x`` per unit input.
        delta: the singularity function (``G`` is finite where ``Δ ≠ 0``), or ``None``.
        frame: the desingularised field ``N`` (d×m, finite everywhere, orthonormal
            columns spanning the range of ``G``), or ``None``; the physical inputs are
            ``u = W w`` with ``W = frame_inputs``.
        derivation: named intermediate results (constraint matrix, ...).
    """

    name: str
    description: str
    inputs: tuple[str, ...]
    coordinates: tuple[sp.Symbol, ...]
    units: tuple[str, ...]
    X: sp.Matrix
    Omega: sp.Matrix | None = None
    delta: sp.Expr | None = None
    angles: tuple[bool, ...] = ()
    frame: sp.Matrix | None = None
    frame_inputs: sp.Matrix | None = None
    derivation: dict = field(default_factory=dict, compare=False, repr=False)

    @property
    def orientation(self) -> bool:
        """Whether the state includes an orientation ``R``."""
        return self.Omega is not None

    @property
    def n_inputs(self) -> int:
        return self.X.shape[1]

    @property
    def n_coordinates(self) -> int:
        return len(self.coordinates)

    @property
    def field(self) -> sp.Matrix:
        """``G = [Ω; X]`` (d×m)."""
        return sp.Matrix.vstack(self.Omega, self.X) if self.orientation else self.X

    @property
    def state_space(self) -> str:
        """``"SO(3)xR^k"`` or ``"R^k"``."""
        k = self.n_coordinates
        return f"SO(3)xR^{k}" if self.orientation else f"R^{k}"


def variation_symbols(mechanism: StateMechanism) -> sp.Matrix:
    """``s = (s_R, s_x)`` as a column (``s_R`` only with orientation)."""
    n = (3 if mechanism.orientation else 0) + mechanism.n_coordinates
    return sp.Matrix(sp.symbols(f"s1:{n + 1}", real=True))


def Q_matrix(mechanism: StateMechanism, G: sp.Matrix | None = None,
             u: sp.Matrix | None = None) -> sp.Matrix:
    """``Q(R, x, u)`` (d×d) with ``Q s = d/dε G(exp(ε[s_R]) R, x + ε s_x) u`` at ``ε = 0``:
    the chain rule with ``δR = [s_R] R`` and ``δx = s_x``. ``G`` defaults to the
    mechanism's field (pass its frame for the frame system)."""
    G = mechanism.field if G is None else G
    u = inputs(mechanism.n_inputs) if u is None else u
    s = variation_symbols(mechanism)
    Gu = G * u
    k0 = 3 if mechanism.orientation else 0
    dR = hat(s[:3]) * r if mechanism.orientation else sp.zeros(3, 3)
    rows = []
    for e in Gu:
        d = sum(sp.diff(e, r[i, j]) * dR[i, j] for i in range(3) for j in range(3))
        d += sum(sp.diff(e, x) * s[k0 + c] for c, x in enumerate(mechanism.coordinates))
        rows.append(sp.expand(d))
    return sp.Matrix(rows).jacobian(s).applyfunc(sp.simplify)


def A_matrix(mechanism: StateMechanism, u: sp.Matrix | None = None) -> sp.Matrix:
    """``A = Q + [ω] ⊕ 0`` of the variational system (module docstring)."""
    u = inputs(mechanism.n_inputs) if u is None else u
    A = Q_matrix(mechanism, u=u)
    if mechanism.orientation:
        A[:3, :3] += hat(mechanism.Omega * u)
    return A
