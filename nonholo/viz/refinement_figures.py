"""Figures of one plan's refinements: the global route over the singular surface
(:func:`global_route_figure`), the legs' stroke kept by ``leg_length``
(:func:`leg_limits_figure`), and a plan's least energy and least time
(:func:`motion_quality_figure`).

Results are :class:`nonholo.io.result.PlanResult`; lengths are in units of the sphere's
radius, names and units from :mod:`nonholo.model.names`.
"""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from scipy.spatial.transform import Rotation

from ..model.names import PER_SECOND, RADIUS, SECOND, angle_label, label, per_second
from ..spaces import so3
from .plan_figures import plot_controls, plot_delta
from .singular_set import HALF_PI_TICKS, PI_TICKS, draw_singular_surface
from .style import NotebookFigure, PAIR_COLORS, styled


def _rpy_curve(R) -> np.ndarray:
    """RPY angles ``(n, 3)`` of rotations, wrapped to the box, with ``nan`` rows where a
    curve wraps (so that a line drawn through them breaks there)."""
    a = Rotation.from_matrix(np.asarray(R, dtype=float)).as_euler("ZYX")
    jump = np.any(np.abs(np.diff(a, axis=0)) > np.pi, axis=1)
    return np.insert(a, np.flatnonzero(jump) + 1, np.nan, axis=0)


@styled
def global_route_figure(result, title: str | None = None) -> Figure:
    """A plan of the global route (``result.route == "global"``): left, its motion in RPY
    coordinates over the singular surface ``Δ = 0`` (axes as :func:`singular_set_figure`),
    the hops' ends marked; right, ``Δ`` along the motion and the controls — the stitched
    controls of the hops (thin, where the route was re-planned as one smooth control) and
    the plan's — the hand-overs between hops dotted.

    Parameters
    ----------
    result : PlanResult
        A plan of the global route.
    title : str, optional
        The figure's title.

    Returns
    -------
    NotebookFigure
        The figure.
    """
    par = result.hops
    smoothed = result.stitched is not None
    fig = NotebookFigure(figsize=(13.0, 5.6), layout="constrained")
    gs = fig.add_gridspec(2, 2, width_ratios=[1.2, 1.0])
    ax = fig.add_subplot(gs[:, 0], projection="3d")
    draw_singular_surface(ax, n_theta=31, n_psi=61, cmap="Greys", alpha=0.25)
    a = _rpy_curve(result.R)
    ax.plot(a[:, 2], a[:, 1], a[:, 0], color="C3", lw=2.6, label="motion R(t)", zorder=20)
    w = Rotation.from_matrix(np.asarray(par.waypoints)).as_euler("ZYX")
    ax.scatter(w[1:-1, 2], w[1:-1, 1], w[1:-1, 0], color="k", s=18, depthshade=False, label="ends of hops")
    for (phi, th, psi), mk, lab in ((w[0], "o", "start"), (w[-1], "*", "goal")):
        ax.scatter([psi], [th], [phi], marker=mk, s=110, color="gold", edgecolor="k", depthshade=False,
                   label=lab)
    ax.set(xlim=(-np.pi, np.pi), ylim=(-np.pi / 2, np.pi / 2), zlim=(-np.pi, np.pi))
    ax.set_xticks(*PI_TICKS)
    ax.set_yticks(*HALF_PI_TICKS)
    ax.set_zticks(*PI_TICKS)
    ax.set_xlabel(angle_label(2))
    ax.set_ylabel(angle_label(1))
    ax.set_zlabel(angle_label(0))
    ax.set_box_aspect((2, 1, 2), zoom=0.88)
    ax.view_init(elev=25.0, azim=-60.0)
    ax.set_title(f"the motion and Δ = 0 (grey) in RPY angles: {par.n_pieces} hops")
    ax.legend(loc="upper left", framealpha=0.9, fontsize=8)
    hand_overs = par.segment_times[1:-1]
    ax1 = fig.add_subplot(gs[0, 1])
    plot_delta(ax1, result, threshold=result.options.get("delta_min"))
    ax2 = fig.add_subplot(gs[1, 1])
    plot_controls(ax2, result)
    if smoothed:
        ts = np.linspace(0.0, result.T, 2001)
        us = par(ts)
        for j in range(us.shape[1]):
            ax2.plot(ts, us[:, j], color=PAIR_COLORS[j], lw=0.8, alpha=0.6,
                     label=f"$u_{j + 1}$ (stitched)")
        ax2.legend(loc="best", fontsize=8)
        ax2.set_title("the stitched controls of the hops (thin) and the smooth re-plan")
    else:
        ax2.set_title("stitched controls (equal time for each hop)")
    for axis in (ax1, ax2):
        for t in hand_overs:
            axis.axvline(t, color="0.4", lw=0.8, ls=":")
    fig.suptitle(title or f"{result.mechanism}: a far goal reached by the global route "
                          f"({so3.distance(result.R0, result.Rd):.2f} rad)")
    return fig


@styled
def leg_limits_figure(free, limited, title: str | None = None) -> Figure:
    """Leg lengths ``l_i(t)`` of a plan without stroke limits (dashed) and of the same
    problem planned with ``leg_length`` (solid, ``limited.options["leg_length"]``, drawn as
    grey lines), in the geometry's units.

    Parameters
    ----------
    free : PlanResult
        The plan without stroke limits.
    limited : PlanResult
        The same problem planned with ``leg_length``.
    title : str, optional
        The figure's title.

    Returns
    -------
    NotebookFigure
        The figure.
    """
    mech = limited.kinematics
    lo, hi = limited.options["leg_length"]
    fig = NotebookFigure(figsize=(7.2, 4.4), layout="constrained")
    ax = fig.add_subplot()
    for res, ls, what in ((free, "--", "without limits"), (limited, "-", f"leg_length = ({lo:g}, {hi:g})")):
        lengths = mech.leg_lengths(res.R)
        for j in range(lengths.shape[1]):
            ax.plot(res.t, lengths[:, j], color=PAIR_COLORS[j], ls=ls, label=f"$l_{j + 1}$, {what}")
    for y in (lo, hi):
        ax.axhline(y, color="0.35", lw=1.2, ls=":")
    bottom, top = ax.get_ylim()
    for a, b in ((bottom, lo), (hi, top)):           # outside the stroke, shaded
        if b > a:
            ax.axhspan(a, b, color="0.85", zorder=0)
    ax.set_ylim(bottom, top)
    ax.set_xlabel(label("time t", SECOND))
    ax.set_ylabel(label("leg length", RADIUS))
    ax.legend(fontsize=8, loc="best")
    ax.set_title(title or f"{mech.name}: the legs' stroke kept by LegStroke({lo:g}, {hi:g})")
    return fig


@styled
def motion_quality_figure(plain, cheap, fast, title: str | None = None) -> Figure:
    """Two refinements of one plan ``plain``: the inputs of ``cheap`` (``objective="energy"``,
    solid) against ``plain``'s (dashed), with their energies ``∫|u|² dt``; and the legs'
    speeds of ``fast`` (``plain`` re-timed in the least time under
    ``fast.options["leg_speed"]``, solid) against ``plain``'s (dashed), with the bound.

    Parameters
    ----------
    plain : PlanResult
        The plan.
    cheap : PlanResult
        The same problem planned with ``objective="energy"``.
    fast : PlanResult
        ``plain`` re-timed under ``leg_speed``.
    title : str, optional
        The figure's title.

    Returns
    -------
    NotebookFigure
        The figure.
    """
    mech = plain.kinematics
    fig = NotebookFigure(figsize=(12.0, 4.4), layout="constrained")
    left, right = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    for res, ls, what in ((plain, "--", "as planned"), (cheap, "-", "least energy")):
        t = np.linspace(0.0, res.T, 2001)
        u = res.controls(t)
        e = float(np.trapezoid(np.sum(u ** 2, axis=1), t))
        for j in range(u.shape[1]):
            left.plot(t, u[:, j], color=PAIR_COLORS[j], ls=ls, lw=1.4,
                      label=f"$u_{j + 1}$, {what} (∫|u|² dt = {e:.4f})" if j == 0 else f"$u_{j + 1}$")
    left.set_xlabel(label("time t", SECOND))
    left.set_ylabel(label("input u", PER_SECOND))
    left.legend(fontsize=8, loc="best")
    left.set_title("plan(..., objective=\"energy\")")
    v = fast.options["leg_speed"]
    for res, ls, what in ((plain, "--", "as planned"), (fast, "-", "re-timed")):
        speeds = mech.leg_speeds(res.R, res.u)
        for j in range(speeds.shape[1]):
            right.plot(res.t, speeds[:, j], color=PAIR_COLORS[j], ls=ls, lw=1.4,
                       label=f"$dl_{j + 1}/dt$, {what} (T = {res.T:.3g} s)")
    for y in (v, -v):
        right.axhline(y, color="0.35", lw=1.2, ls=":")
    right.axhline(0.0, color="k", lw=0.5)
    right.set_xlabel(label("time t", SECOND))
    right.set_ylabel(label("leg speed", per_second(RADIUS)))
    right.legend(fontsize=8, loc="best")
    right.set_title(f"nonholo.retime(..., leg_speed={v:g}): the least time")
    fig.suptitle(title or f"{mech.name}: one path, its least energy and its least time", fontsize=11)
    return fig
