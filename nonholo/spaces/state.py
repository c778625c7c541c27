"""The integrator's kernels called alike for every kind of state ``(R, q)`` (the states
themselves, their errors and forms: :mod:`nonholo.spaces.groups`).

A trajectory is the pair of stacks ``R`` ``(n, 3, 3)`` and ``q`` ``(n, k)``.
"""
from __future__ import annotations

import numpy as np

from .groups import IDENTITY, NO_COORDINATES  # noqa: F401  (re-exported for the kernels' callers)

# --------------------------------------------------------------------------------------
# The kernels, called alike for every kind of state
# --------------------------------------------------------------------------------------


def buffers(mechanism, steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Node arrays ``(R (steps+1, 3, 3), q (steps+1, k))`` for a kernel."""
    return np.empty((steps + 1, 3, 3)), np.empty((steps + 1, mechanism.n_coordinates))


def forward(mechanism, kern, R0, q0, U, h: float, sign: float, stop: float, Rs, Qs):
    """``kern.forward`` from ``(R0, q0)`` into the nodes ``Rs``, ``Qs`` (see
    :func:`nonholo.integrate.cf4.forward`; ``Qs`` unused on SO(3)). Returns ``(done, min sgnΔ, t_stop)``."""
    if mechanism.space.k:
        return kern.forward(R0, q0, U, h, sign, stop, Rs, Qs)
    return kern.forward(R0, U, h, sign, stop, Rs)


def forward_variational(mechanism, kern, R0, q0, U, h: float, sign: float, stop: float, basis,
                        Rs, Qs, Zs, J, M, Wd, full: bool):
    """``kern.forward_variational`` (see :func:`nonholo.integrate.cf4.forward_variational`; ``basis``
    the stage basis' four arrays) from ``(R0, q0)``, with ``d``-row ``Zs``, ``J``, ``M``."""
    if mechanism.space.k:
        return kern.forward_variational(R0, q0, U, h, sign, stop, *basis, Rs, Qs, Zs, J, M, Wd, full)
    return kern.forward_variational(R0, U, h, sign, stop, *basis, Rs, Zs, J, M, Wd, full)


def frame_inputs(mechanism, kern, nodes, qnodes, idx, s, Wst, w_end, Rout, Qout, out):
    """``kern.frame_inputs`` (see :func:`nonholo.integrate.cf4.frame_inputs`) along the nodes
    ``(nodes, qnodes)``."""
    if mechanism.space.k:
        return kern.frame_inputs(nodes, qnodes, idx, s, Wst, w_end, Rout, Qout, out)
    return kern.frame_inputs(nodes, idx, s, Wst, w_end, Rout, out)
