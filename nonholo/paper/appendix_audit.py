"""The audit of the appendix (:mod:`derivations.audit`) with its numeric checks on Example 1.

The derivation holds eqs. (9) and (10)–(11) symbolically; the numbers that back them
come from the simulator: the sensitivity ``∂s_T/∂λ`` that the variational system (9)
gives against central differences of the simulated endpoint, and the mobility matrix
``M(T)`` by quadrature against the Lyapunov equation solved by DOP853.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from derivations import audit

from ..certify import resimulate
from ..controls.parametrisations import Fourier
from ..motion import simulation
from ..spaces import so3
from . import examples


@lru_cache(maxsize=1)
def example_variational():
    """Example 1's initial control (Fourier, K = 2), its variational system and the central
    differences of the simulated endpoint.

    Returns
    -------
    tuple
        ``(example, controls, variational, differences)``: the differences
        ``(R_T(λ + ε e_k) R_T(λ − ε e_k)ᵀ)^∨ / 2ε``, one column per parameter.
    """
    ex = examples.get(1)
    controls = Fourier.fit(ex.initial_control, ex.T, ex.harmonics)
    var = simulation.variational(ex.R_start, controls, ex.T)
    eps = 1e-6
    fd = np.empty_like(var.J)
    for k in range(controls.params.size):
        dp = np.zeros(controls.params.size)
        dp[k] = eps
        plus = simulation.simulate(ex.R_start, controls.with_params(controls.params + dp), ex.T).R_T
        minus = simulation.simulate(ex.R_start, controls.with_params(controls.params - dp), ex.T).R_T
        fd[:, k] = so3.log(plus @ minus.T) / (2 * eps)
    return ex, controls, var, fd


def sensitivity_error() -> float:
    """Eq. (9) on Example 1.

    Returns
    -------
    float
        ``max |J − differences| / max |differences|``.
    """
    _, _, var, fd = example_variational()
    return float(np.max(np.abs(var.J - fd)) / np.max(np.abs(fd)))


def mobility_error() -> float:
    """Eqs. (10)–(11) on Example 1.

    Returns
    -------
    float
        ``M(T)`` by quadrature against the Lyapunov equation's solution (DOP853), relative.
    """
    ex, controls, var, _ = example_variational()
    M_lyap = resimulate.mobility_lyapunov(ex.R_start, controls, ex.T)
    return float(np.max(np.abs(var.M - M_lyap)) / np.max(np.abs(M_lyap)))


def run() -> list[audit.Finding]:
    """The audit of the appendix.

    Returns
    -------
    list of derivations.audit.Finding
        Every finding of :func:`derivations.audit.run`, the numeric checks included.
    """
    return audit.run(sensitivity_error, mobility_error)
