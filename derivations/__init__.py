"""Symbolic derivations of the nonholo toolkit (SymPy).

Each module rebuilds one part of the appendix of Tchoń & Jakubiak (ARK 2014) from the
mechanism's geometry:

- :mod:`derivations.rotations`    symbolic rotation matrices, skew matrices, RPY, dexp
- :mod:`derivations.mechanisms`   the Mechanism class (SO(3), SO(3) × Rᵏ, Rᵏ); the platform's
  legs, disk, Δ(R), L(R)
- :mod:`derivations.vehicles`     the rolling ball and the kinematic car
- :mod:`derivations.equations`    a mechanism from its velocity field or its constraints, checked
- :mod:`derivations.definitions`  the mechanisms the toolkit generates code for, by name
- :mod:`derivations.singularity`  Δ in RPY coordinates and its normal form z³ + xy
- :mod:`derivations.variational`  Q(R,u), A = Q + [Lu], B = L, P(l) (eqs. (6)-(9), (12))
- :mod:`derivations.state_space`  the variational matrix of the stacked field on SO(3) × Rᵏ
- :mod:`derivations.printed`      the appendix formulas transcribed as printed
- :mod:`derivations.audit`        printed vs derived, equation by equation
- :mod:`derivations.codegen`      numeric modules written into ``nonholo/generated``
- :mod:`derivations.generator`    what keys a generated module: the generator's version, a definition's text
- :mod:`derivations.admission`    a user's text and numbers as data: names, constants, expressions as text
- :mod:`derivations.budget`       the size budget of the symbolic work, checked before deriving
"""
