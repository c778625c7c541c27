"""A plan's physical controls played on its mechanism's system: the one door into the
integrator's kernels for a finished plan (its certificate, its re-timing, its checks on
loading)."""
from __future__ import annotations

import numpy as np

from ..controls import stages
from ..integrate.compiled import compiled_system


def replay(start, par, T: float, mechanism, steps: int, sign: float = 1.0, U=None):
    """Physical inputs replayed on ``dR/dt = [L(R) u] R`` (beyond SO(3), on the
    mechanism's system) with CF4.

    Parameters
    ----------
    start : State
        The start (:class:`~nonholo.spaces.state.State`).
    par : Controls or FrameControls
        The physical inputs (controls or
        :class:`~nonholo.motion.frame_controls.FrameControls`).
    T : float
        The horizon (s).
    mechanism : Mechanism
        The mechanism.
    steps : int
        CF4 steps on ``[0, T]``.
    sign : float
        The side of ``Δ = 0`` the motion keeps to: ``sign·Δ`` is reported.
    U : numpy.ndarray, optional
        The stage table of ``par`` on ``steps`` steps, if already known.

    Returns
    -------
    R : numpy.ndarray
        The nodes, shape ``(steps + 1, 3, 3)``.
    done : int
        The steps completed (fewer where the angular velocity became non-finite).
    min_delta : float
        The least ``sign·Δ`` over the evaluation points.
    q : numpy.ndarray
        The nodes' coordinates, shape ``(steps + 1, k)``.
    """
    U = np.ascontiguousarray(stages.stage_table(par, steps) if U is None else U)
    kern = compiled_system(mechanism, frame=False)
    Rs, Qs = kern.nodes(steps)
    done, dmin, _ = kern.forward(*start, U, T / steps, sign,
                                 -np.inf, Rs, Qs)
    return Rs, int(done), float(dmin), Qs
