"""A plan's physical controls played on its mechanism's system: the one door into the
integrator's kernels for a finished plan (its certificate, its re-timing, its checks on
loading)."""
from __future__ import annotations

import numpy as np

from ..controls import stages
from ..spaces.groups import NO_COORDINATES


def replay(R0, par, T: float, mechanism, steps: int, sign: float = 1.0, U=None, q0=None):
    """Physical inputs replayed on ``dR/dt = [L(R) u] R`` (beyond SO(3), on the
    mechanism's system) with CF4.

    Parameters
    ----------
    R0 : array_like
        The start's orientation (the identity without one).
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
    q0 : array_like, optional
        The start's coordinates, beyond SO(3).

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
    kern = mechanism.kernels(frame=False)
    Rs, Qs = kern.nodes(steps)
    q0 = np.ascontiguousarray(NO_COORDINATES if q0 is None else q0, dtype=float)
    done, dmin, _ = kern.forward(np.ascontiguousarray(R0, dtype=float), q0, U, T / steps, sign,
                                 -np.inf, Rs, Qs)
    return Rs, int(done), float(dmin), Qs
