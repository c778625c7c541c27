"""The platform's singular set Δ = 0 near the identity: RPY form and normal form (App. 1.1).

Steps, each a function:

1. :func:`delta_rpy_derived` — ``Δ(RPY(φ, ϑ, ψ))`` from the derived ``Δ(R)``;
2. :func:`xi_eta_zeta` — the coordinates ``ξ = sin ϑ cos ψ``, ``η = sin φ cos² ϑ -
   cos φ sin² ϑ``, ``ζ = sin ψ``;
3. :func:`implicit_relation_phi` — the relation that defines ``φ(ξ, η, ζ)``;
4. :func:`delta_cubic_form` — ``Δ = ξ³ (sin φ + cos φ)/(1 - ζ²) + ξη + ηζ``;
5. :func:`normal_form_coordinates` — ``x = ξ + ζ``, ``y = η``,
   ``z = ξ ((sin φ + cos φ)/(1 - ζ²))^{1/3}`` with ``Δ = z³ + x y``;
6. :func:`coordinate_jacobian_at_zero` and :func:`classify_singular_point`.
"""
from __future__ import annotations

from functools import cache

import sympy as sp

from .mechanisms import paper_platform
from .rotations import rpy, substitute_rotation

#: RPY angles φ (yaw, about z), ϑ (pitch, about y), ψ (roll, about x).
angles = sp.symbols("phi theta psi", real=True)
phi, theta, psi = angles
#: Normal-form coordinates.
xyz = sp.symbols("x y z", real=True)


@cache
def delta_rpy_derived() -> sp.Expr:
    """``Δ(RPY(φ, ϑ, ψ))`` from the derived ``Δ(R)``, expanded in sines and cosines."""
    delta = paper_platform().delta
    return sp.expand(substitute_rotation(delta, rpy(phi, theta, psi)))


def xi_eta_zeta() -> tuple[sp.Expr, sp.Expr, sp.Expr]:
    """``(ξ, η, ζ)`` as functions of the RPY angles."""
    xi = sp.sin(theta) * sp.cos(psi)
    eta = sp.sin(phi) * sp.cos(theta) ** 2 - sp.cos(phi) * sp.sin(theta) ** 2
    zeta = sp.sin(psi)
    return xi, eta, zeta


def delta_in_xi_eta_zeta() -> sp.Expr:
    """``Δ = ξ sin φ + η ζ`` (φ understood as a function of ξ, η, ζ)."""
    xi, eta, zeta = xi_eta_zeta()
    return xi * sp.sin(phi) + eta * zeta


def implicit_relation_phi() -> sp.Expr:
    """``-sin φ + η + ξ² (cos φ + sin φ)/(1 - ζ²)``, which vanishes identically."""
    xi, eta, zeta = xi_eta_zeta()
    return -sp.sin(phi) + eta + xi**2 * (sp.cos(phi) + sp.sin(phi)) / (1 - zeta**2)


def delta_cubic_form() -> sp.Expr:
    """``Δ = ξ³ (sin φ + cos φ)/(1 - ζ²) + ξη + ηζ``."""
    xi, eta, zeta = xi_eta_zeta()
    return xi**3 * (sp.sin(phi) + sp.cos(phi)) / (1 - zeta**2) + xi * eta + eta * zeta


def normal_form_coordinates() -> tuple[sp.Expr, sp.Expr, sp.Expr]:
    """``(x, y, z)`` as functions of the RPY angles, with ``Δ = z³ + x y``."""
    xi, eta, zeta = xi_eta_zeta()
    w = (sp.sin(phi) + sp.cos(phi)) / (1 - zeta**2)
    return xi + zeta, eta, xi * w ** sp.Rational(1, 3)


def normal_form() -> sp.Expr:
    """``f(x, y, z) = z³ + x y``."""
    x, y, z = xyz
    return z**3 + x * y


def is_zero_trig(expr) -> bool:
    """Whether a trigonometric expression in the RPY angles vanishes identically.

    Substitutes the half-angle parametrisation ``sin a = 2t/(1+t²)``,
    ``cos a = (1-t²)/(1+t²)`` for each angle, which turns the expression into a rational
    function of ``t``; cancelling decides the question exactly and without heuristics.
    """
    expr = sp.sympify(expr)
    subs = {}
    for a in angles:
        t = sp.Symbol(f"t_{a.name}", real=True)
        subs[sp.sin(a)] = 2 * t / (1 + t**2)
        subs[sp.cos(a)] = (1 - t**2) / (1 + t**2)
    rational = sp.expand(expr).xreplace(subs)
    return sp.cancel(sp.together(rational)) == 0


def coordinate_jacobian_at_zero() -> sp.Matrix:
    """``∂(x, y, z)/∂(φ, ϑ, ψ)`` at the identity."""
    J = sp.Matrix(normal_form_coordinates()).jacobian(sp.Matrix(angles))
    return J.subs({phi: 0, theta: 0, psi: 0})


def classify_singular_point(f: sp.Expr | None = None, variables=xyz) -> dict:
    """Critical point, Hessian rank and cubic term of ``f`` at 0.

    A critical point whose Hessian has corank 1 and whose cubic term does not vanish
    along the Hessian's kernel is an A2 singularity (locally ``x² + y² + z³``).
    """
    f = normal_form() if f is None else f
    v = sp.Matrix(variables)
    at0 = {s: 0 for s in variables}
    grad = sp.Matrix([f]).jacobian(v).subs(at0)
    H = sp.hessian(f, v).subs(at0)
    kernel = H.nullspace()
    t = sp.Symbol("t")
    cubic = None
    if len(kernel) == 1:
        k = kernel[0]
        along = sp.expand(f.subs({s: t * k[i] for i, s in enumerate(variables)}))
        cubic = along.coeff(t, 3)
    critical = all(g == 0 for g in grad)
    a2 = critical and H.rank() == len(variables) - 1 and cubic not in (None, 0)
    return {"critical": critical, "gradient": list(grad), "hessian": H,
            "hessian_rank": H.rank(), "cubic_coefficient": cubic,
            "type": "A2" if a2 else "other"}
