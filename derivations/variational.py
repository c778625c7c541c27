"""The variational system of the planner, for any mechanism (appendix eqs. (8), (9), (12)).

Along a family of controls ``u_θ`` the trajectories vary as ``∂R/∂θ = [s] R``. The
appendix writes ``(∂L/∂θ) u = Q(R, u) s`` (eq. (12) for the platform) and the linear
system ``ds/dt = A s + B du/dθ`` with ``A = Q + [L u]``, ``B = L`` (eq. (9)).
"""
from __future__ import annotations

import sympy as sp

from .mechanisms import Mechanism
from .rotations import hat, r

#: Symbols of the inputs and of the variation ``s``.
u_symbols = sp.Matrix(sp.symbols("u1:3", real=True))
s_symbols = sp.Matrix(sp.symbols("s1:4", real=True))


def inputs(m: int) -> sp.Matrix:
    """Input symbols ``u1 … um`` as a column."""
    return sp.Matrix(sp.symbols(f"u1:{m + 1}", real=True))


def directional_derivative_L(L: sp.Matrix, u: sp.Matrix, s: sp.Matrix = s_symbols) -> sp.Matrix:
    """``d/dε L(exp(ε[s]) R) u`` at ``ε = 0``: the chain rule with ``δR = [s] R``."""
    Lu = L * u
    dR = hat(s) * r
    return sp.Matrix(3, 1, lambda k, _: sum(
        sp.diff(Lu[k], r[i, j]) * dR[i, j] for i in range(3) for j in range(3)))


def Q_matrix(L: sp.Matrix, u: sp.Matrix | None = None) -> sp.Matrix:
    """``Q(R, u)`` with ``(∂L/∂θ) u = Q s`` (the appendix's eq. (12) for the platform)."""
    u = inputs(L.shape[1]) if u is None else u
    return directional_derivative_L(L, u).jacobian(s_symbols)


def A_matrix(L: sp.Matrix, Q: sp.Matrix, u: sp.Matrix | None = None) -> sp.Matrix:
    """``A = Q + [L u]`` of eq. (9)."""
    u = inputs(L.shape[1]) if u is None else u
    return Q + hat(L * u)


def variational_system(mechanism: Mechanism) -> dict[str, sp.Matrix]:
    """``Q``, ``A`` and ``B`` of eq. (9) for any mechanism."""
    u = inputs(mechanism.n_inputs)
    Q = Q_matrix(mechanism.L, u)
    return {"Q": Q, "A": A_matrix(mechanism.L, Q, u), "B": mechanism.L, "u": u}


def Q_factored(mechanism: Mechanism) -> sp.Matrix:
    """``Q`` with each entry over the common denominator ``Δ²`` (for display/codegen)."""
    Q = Q_matrix(mechanism.L)
    if mechanism.delta is None:
        return Q.applyfunc(sp.expand)
    d2 = mechanism.delta ** 2
    return Q.applyfunc(lambda q: sp.factor(sp.cancel(q * d2)) / d2)
