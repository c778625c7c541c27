"""The variational system on a product state space ``SO(3) × Rᵏ`` or ``Rᵏ``.

A mechanism (:class:`derivations.mechanisms.Mechanism`) has the stacked field
``q̇ = G(R, x) u``, ``G = [Ω; X]`` of ``d = 3 + k`` rows (``d = k`` without orientation,
``G = L`` on SO(3)). A variation of the state is ``(∂R, ∂x) = ([s_R] R, s_x)``, taken on
the left for ``R`` as everywhere in the toolkit, and stacked as ``s = (s_R, s_x)``. The
variational system is that of eq. (9) on the product,

    ds/dt = A s + B ∂u/∂θ,   A = Q(R, x, u) + [ω] ⊕ 0,   B = G(R, x),

with ``Q s = d/dε G(exp(ε[s_R]) R, x + ε s_x) u`` at ``ε = 0`` (:func:`Q_matrix`): the
analogue of the appendix's eq. (12), whose rotation block it is. The terminal error is
``(log(R_T R_dᵀ), x_T − x_d)``; as on SO(3), the planner asks ``s_T = −γ e_T``.
"""
from __future__ import annotations

import sympy as sp

from . import budget, variational
from .mechanisms import Mechanism
from .rotations import hat, r
from .variational import inputs


def variation_symbols(mechanism: Mechanism) -> sp.Matrix:
    """``s = (s_R, s_x)`` as a column (``s_R`` only with orientation)."""
    n = (3 if mechanism.orientation else 0) + mechanism.n_coordinates
    return sp.Matrix(sp.symbols(f"s1:{n + 1}", real=True))


def Q_matrix(mechanism: Mechanism, G: sp.Matrix | None = None,
             u: sp.Matrix | None = None) -> sp.Matrix:
    """``Q(R, x, u)`` (d×d) with ``Q s = d/dε G(exp(ε[s_R]) R, x + ε s_x) u`` at ``ε = 0``:
    the chain rule with ``δR = [s_R] R`` and ``δx = s_x``. ``G`` defaults to the
    mechanism's field (pass its frame for the frame system)."""
    G = mechanism.field if G is None else G
    u = inputs(mechanism.n_inputs) if u is None else u
    if not mechanism.n_coordinates:         # SO(3): eq. (12) as the appendix writes it
        return variational.Q_matrix(G, u)
    s = variation_symbols(mechanism)
    Gu = G * u
    k0 = 3 if mechanism.orientation else 0
    dR = hat(s[:3]) * r if mechanism.orientation else sp.zeros(3, 3)
    rows = []
    for e in Gu:
        d = sum(sp.diff(e, r[i, j]) * dR[i, j] for i in range(3) for j in range(3))
        d += sum(sp.diff(e, x) * s[k0 + c] for c, x in enumerate(mechanism.coordinates))
        # expanded where that is cheap (derivations.budget); linear in s either way
        rows.append(budget.expanded(d))
    allowance = budget.Allowance()
    return sp.Matrix(rows).jacobian(s).applyfunc(lambda e: simplified(e, allowance))


def simplified(e: sp.Expr, allowance: budget.Allowance | None = None) -> sp.Expr:
    """``sp.simplify(e)`` where ``e`` is a sum small enough for it, within the derivation's
    ``allowance`` (:func:`derivations.budget.simplified`); a single term of the expanded
    derivative is kept as it is, since ``simplify`` costs a second on its first call (it
    imports ``sympy.physics``) and a mechanism of one's own is derived on every first run."""
    return budget.simplified(e, allowance) if isinstance(e, sp.Add) else e


def A_matrix(mechanism: Mechanism, u: sp.Matrix | None = None) -> sp.Matrix:
    """``A = Q + [ω] ⊕ 0`` of the variational system (module docstring)."""
    u = inputs(mechanism.n_inputs) if u is None else u
    A = Q_matrix(mechanism, u=u)
    if mechanism.orientation:
        A[:3, :3] += hat(mechanism.Omega * u)
    return A
