"""Symbolic SO(3): the rotation-matrix symbols r_ij, skew matrices, RPY, Cayley, exp, dexp.

Conventions (as in the paper):
- ``[v]`` is the skew matrix of ``v``: ``[v] x = v × x``.
- ``RPY(φ, ϑ, ψ) = R(Z, φ) R(Y, ϑ) R(X, ψ)`` (angles in radians).
- A variation of a rotation is taken on the left (spatial frame): ``R → exp(ε[s]) R``.
"""
from __future__ import annotations

import sympy as sp

#: The entries ``r_ij`` (row i, column j, 1-based) of a generic rotation matrix.
r = sp.Matrix(3, 3, lambda i, j: sp.Symbol(f"r{i + 1}{j + 1}", real=True))
R_ENTRIES = tuple(r)

#: Unit vectors e_1, e_2, e_3 as column matrices.
e1, e2, e3 = (sp.Matrix([1, 0, 0]), sp.Matrix([0, 1, 0]), sp.Matrix([0, 0, 1]))


def hat(v) -> sp.Matrix:
    """Skew matrix ``[v]`` with ``[v] x = v × x``."""
    v = sp.Matrix(v)
    return sp.Matrix([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def vee(S) -> sp.Matrix:
    """Inverse of :func:`hat` on the skew part of ``S``."""
    S = sp.Matrix(S)
    return sp.Matrix([S[2, 1] - S[1, 2], S[0, 2] - S[2, 0], S[1, 0] - S[0, 1]]) / 2


def rot_x(a) -> sp.Matrix:
    """Rotation ``R(X, a)`` about the x axis."""
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(a) -> sp.Matrix:
    """Rotation ``R(Y, a)`` about the y axis."""
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_z(a) -> sp.Matrix:
    """Rotation ``R(Z, a)`` about the z axis."""
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def rpy(phi, theta, psi) -> sp.Matrix:
    """``RPY(φ, ϑ, ψ) = R(Z, φ) R(Y, ϑ) R(X, ψ)``; ``RPY(0, 0, 0) = I``."""
    return rot_z(phi) * rot_y(theta) * rot_x(psi)


def cayley(c) -> sp.Matrix:
    """Rational, exactly orthogonal rotation ``(I - [c])^{-1} (I + [c])
    = I + 2([c] + [c]²)/(1 + cᵀc)``.

    Symbolic identities that need ``RᵀR = I`` are checked on this parametrisation: it
    covers every rotation but the half turns and needs no trigonometric simplification.
    """
    c = sp.Matrix(c)
    C = hat(c)
    return sp.eye(3) + 2 * (C + C * C) / (1 + (c.T * c)[0])


def substitute_rotation(expr, R: sp.Matrix):
    """Replace the symbols ``r_ij`` in ``expr`` by the entries of ``R``."""
    return sp.sympify(expr).xreplace({r[i, j]: R[i, j] for i in range(3) for j in range(3)})


def exp_rodrigues(l: sp.Matrix, alpha) -> sp.Matrix:
    """``exp([l]) = I + sin α/α [l] + (1 - cos α)/α² [l]²`` with ``α = |l|`` given."""
    L = hat(l)
    return sp.eye(3) + sp.sin(alpha) / alpha * L + (1 - sp.cos(alpha)) / alpha**2 * L * L


def dexp_coefficients(alpha):
    """Closed forms of the dexp series ``Σ_k [l]^k / (k+1)!``, derived by summation.

    With ``[l]³ = -α²[l]`` the series splits into a ``[l]`` and a ``[l]²`` part whose
    coefficients are the sums below; SymPy evaluates them in closed form.
    """
    j = sp.Symbol("j", integer=True, nonnegative=True)
    c1 = sp.summation((-1) ** j * alpha ** (2 * j) / sp.factorial(2 * j + 2), (j, 0, sp.oo))
    c2 = sp.summation((-1) ** j * alpha ** (2 * j) / sp.factorial(2 * j + 3), (j, 0, sp.oo))
    return sp.simplify(c1), sp.simplify(c2)


def dexp(l: sp.Matrix, alpha) -> sp.Matrix:
    """Left Jacobian of SO(3): ``d exp([l(θ)])/dθ · exp(-[l]) = [dexp(l) dl/dθ]``."""
    c1, c2 = dexp_coefficients(alpha)
    L = hat(l)
    return sp.eye(3) + c1 * L + c2 * L * L
