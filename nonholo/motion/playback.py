"""A plan's physical controls played on its mechanism's system: the one door into the
integrator's kernels for a finished plan (its certificate, its re-timing, its checks on
loading)."""
from __future__ import annotations

import numpy as np

from ..controls import stages
from ..spaces.groups import NO_COORDINATES


def replay(R0, par, T: float, mechanism, steps: int, sign: float = 1.0, U=None, q0=None):
    """The physical inputs ``par`` (controls or :class:`~nonholo.motion.frame_controls.FrameControls`)
    replayed on ``dR/dt = [L(R) u] R`` from ``R0`` with ``steps`` CF4 steps (``U``: their
    stage table, if already known); beyond SO(3), on the mechanism's system from
    ``(R0, q0)``.

    Returns ``(R, done, min_delta, q)``: the nodes ``(steps + 1, 3, 3)``, the steps
    completed (fewer where the angular velocity became non-finite), the least ``sign·Δ``
    over the evaluation points and the nodes' coordinates ``(steps + 1, k)``.
    """
    U = np.ascontiguousarray(stages.stage_table(par, steps) if U is None else U)
    kern = mechanism.kernels(frame=False)
    Rs, Qs = kern.nodes(steps)
    q0 = np.ascontiguousarray(NO_COORDINATES if q0 is None else q0, dtype=float)
    done, dmin, _ = kern.forward(np.ascontiguousarray(R0, dtype=float), q0, U, T / steps, sign,
                                 -np.inf, Rs, Qs)
    return Rs, int(done), float(dmin), Qs
