"""The motion: the kernels that take CF4 steps (:func:`nonholo.integrate.cf4.cf4_step`) along
a stage table — :func:`forward`, the nodes of a motion — and, for a motion planned in
frame coordinates, one partial step from the nearest node — :func:`frame_inputs`, the
physical inputs along it.

Conventions (the system, the stage table, the singular set) as in
:mod:`nonholo.integrate.cf4`; the names of the system the kernels read are the
placeholders defined there, bound per system by
:func:`nonholo.integrate.system_kernels.compile_system`, which compiles the kernels with
the step expanded in place (:mod:`nonholo.generated.cf4_kernels`).
"""
from __future__ import annotations

import numpy as np

from .cf4 import D, DRIFT_COLUMNS, W_into, cf4_step, delta, step_workspace


def forward(R0, q0, U, h, sgn, delta_stop, Rs, Qs):
    """CF4 over ``N = len(U)`` steps from ``(R0, q0)``.

    Parameters
    ----------
    R0, q0 : numpy.ndarray
        The start.
    U : numpy.ndarray
        The stage table, ``(N, 3, m)``.
    h : float
        The step.
    sgn : float
        The sign of ``Δ`` at the start.
    delta_stop : float
        Stop where ``sgnΔ`` falls below this.
    Rs, Qs : numpy.ndarray
        The output: the state at every ``t_n``, shapes ``(N+1, 3, 3)``, ``(N+1, k)``.

    Returns
    -------
    n_done : int
        The number of completed steps (``N`` unless the trajectory reached ``sgnΔ <
        delta_stop`` or a non-finite rate).
    dmin : float
        The least ``sgnΔ`` over all evaluation points of the completed steps.
    t_stop : float
        The stage time where it stopped (``-1`` if it did not).
    """
    N = U.shape[0]
    m = U.shape[2]
    k = q0.shape[0]
    R = R0.copy()
    q = q0.copy()
    (Rn, qn, Y2, Y3, Y4, P2, P3, P4, Rh, E, B1, B2, B3, B4,
     F1, F2, F3, F4) = step_workspace(R0, k, D, m + DRIFT_COLUMNS)
    for i in range(3):
        for j in range(3):
            Rs[0, i, j] = R0[i, j]
    for i in range(k):
        Qs[0, i] = q0[i]
    dmin = sgn * delta(R, q)
    if not dmin >= delta_stop:
        return 0, dmin, 0.0
    for n in range(N):
        stop, dmin = cf4_step(R, q, Rn, qn, U[n, 0], U[n, 1], U[n, 2], h, sgn, delta_stop, dmin,
                              Y2, Y3, Y4, P2, P3, P4, Rh, E, B1, B2, B3, B4, F1, F2, F3, F4)
        if stop >= 0.0:
            return n, dmin, n * h + stop * h
        for i in range(3):
            for j in range(3):
                R[i, j] = Rn[i, j]
                Rs[n + 1, i, j] = Rn[i, j]
        for i in range(k):
            q[i] = qn[i]
            Qs[n + 1, i] = qn[i]
    return N, dmin, -1.0



def frame_inputs(nodes, qnodes, idx, s, Wst, w_end, Rout, Qout, out):
    """Physical inputs ``u = W(R(t), q(t)) w(t)`` along a motion planned in frame coordinates.

    For every sample ``t_k``: the state is node ``idx[k]`` of the CF4 trajectory ``(nodes,
    qnodes)`` advanced by one CF4 step (:func:`~nonholo.integrate.cf4.cf4_step`) of length
    ``s[k]`` (none if ``s[k] == 0``) with frame inputs ``Wst[k, 0]``, ``Wst[k, 1]``,
    ``Wst[k, 2]`` at its start, middle and end — the same local approximation as a step of
    the integrator, ``O(s⁵)`` from the exact motion.

    Parameters
    ----------
    nodes, qnodes : numpy.ndarray
        The CF4 trajectory's nodes.
    idx : numpy.ndarray
        The node of every sample.
    s : numpy.ndarray
        The partial step from it, every sample.
    Wst : numpy.ndarray
        The frame inputs at the partial step's start, middle and end, ``(n, 3, m)``.
    w_end : numpy.ndarray
        The frame inputs at the samples, ``(n, m)``.
    Rout, Qout : numpy.ndarray
        The state at every ``t_k`` (output).
    out : numpy.ndarray
        ``out[k] = W(R(t_k), q(t_k)) w_end[k]`` (output).
    """
    n_t = idx.shape[0]
    m = Wst.shape[2]
    k = qnodes.shape[1]
    R = np.empty((3, 3))
    q = np.empty(k)
    (Rn, qn, Y2, Y3, Y4, P2, P3, P4, Rh, E, B1, B2, B3, B4,
     F1, F2, F3, F4) = step_workspace(nodes[0], k, D, m + DRIFT_COLUMNS)
    Wm = np.empty((m, m))
    for t in range(n_t):
        for i in range(3):
            for j in range(3):
                R[i, j] = nodes[idx[t], i, j]
                Rn[i, j] = R[i, j]
        for i in range(k):
            q[i] = qnodes[idx[t], i]
            qn[i] = q[i]
        if s[t] != 0.0:
            stop, dmin = cf4_step(R, q, Rn, qn, Wst[t, 0], Wst[t, 1], Wst[t, 2], s[t], 1.0, -np.inf,
                                  np.inf, Y2, Y3, Y4, P2, P3, P4, Rh, E, B1, B2, B3, B4,
                                  F1, F2, F3, F4)
        for i in range(3):
            for j in range(3):
                Rout[t, i, j] = Rn[i, j]
        for i in range(k):
            Qout[t, i] = qn[i]
        W_into(Rn, qn, Wm)
        for i in range(m):
            v = 0.0
            for j in range(m):
                v += Wm[i, j] * w_end[t, j]
            out[t, i] = v

