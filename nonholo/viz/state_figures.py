"""Figures of plans whose state goes beyond SO(3): the rolling ball's contact path on the
plane with its orientation, and the car's path with its body drawn along it.

Each function takes a successful :class:`~nonholo.io.result.PlanResult` of the mechanism and
returns a :class:`~nonholo.viz.style.NotebookFigure` (the caller saves or shows it); names
and units come from the mechanism's data (:mod:`nonholo.viz.quantities`).
"""
from __future__ import annotations

import matplotlib
import numpy as np
from matplotlib.patches import Polygon

from ..model.names import NONE, RAD, SECOND
from .platform_drawing import result_mechanism
from .quantities import coordinate_units, input_units, label
from .style import NotebookFigure, styled


def _check(result, mechanism: str):
    if result.mechanism != mechanism:
        raise ValueError(f"result must be a plan of mechanism {mechanism!r}, got {result.mechanism!r}")
    if result.q is None or not len(result.q):
        raise ValueError("result has no trajectory to draw")


def _layout():
    """A state figure's figure, its 2×2 grid and the path panel (the left column)."""
    fig = NotebookFigure(figsize=(10, 4.8))
    grid = fig.add_gridspec(2, 2, width_ratios=[1.1, 1])
    return fig, grid, fig.add_subplot(grid[:, 0])


def _path_labels(ax, result, title: str, margin: float):
    """The path panel's axes labelled with the first two coordinates and their units."""
    mech = result_mechanism(result)
    units = coordinate_units(mech)
    _finish_path(ax, label(mech.coordinates[0], units[0]), label(mech.coordinates[1], units[1]),
                 title, margin)


def _input_labels(result) -> tuple:
    """Each input's name with its unit."""
    mech = result_mechanism(result)
    return tuple(label(name, unit) for name, unit in zip(mech.inputs, input_units(mech)))


def _mark_ends(ax, result):
    """The start and the goal on the path panel (the first two coordinates)."""
    ax.plot(*result.q[0, :2], "o", color="tab:green", ms=8, label="start")
    ax.plot(*result.qd[:2], "x", color="tab:red", ms=10, mew=2, label="goal")


def _finish_path(ax, xlabel: str, ylabel: str, title: str, margin: float):
    """The path panel to scale (equal axes), labelled, with its legend."""
    ax.set_aspect("equal", adjustable="datalim")
    ax.margins(margin)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=8, loc="best")


def _time_panels(fig, grid, result, title: str, angles: list):
    """The right column of a state figure: ``angles`` (``(values, colour, label)`` each,
    rad) above the two inputs (named, with their units) against time; then the layout."""
    top = fig.add_subplot(grid[0, 1])
    for values, colour, name in angles:
        top.plot(result.t, values, color=colour, label=name)
    top.set_ylabel(label("angle", RAD))
    top.set_title(title)
    top.legend(fontsize=8)
    bottom = fig.add_subplot(grid[1, 1], sharex=top)
    for j, (colour, name) in enumerate(zip(("tab:blue", "tab:orange"), _input_labels(result))):
        bottom.plot(result.t, result.u[:, j], color=colour, lw=1, label=name)
    bottom.set_xlabel(label("time t", SECOND))
    bottom.set_ylabel("input")
    bottom.legend(fontsize=8)
    fig.tight_layout()


@styled
def ball_figure(result, frames: int = 9) -> NotebookFigure:
    """The ball's contact path on the plane z = 0 (left), with the ball's body axes
    ``R e₁``, ``R e₂`` projected on the plane at ``frames`` instants; right, the angles
    from the start and to the goal (``|log(R(t) R0ᵀ)|``, ``|log(R(t) R_dᵀ)|``) and the
    inputs against time.

    Parameters
    ----------
    result : PlanResult
        A plan of ``rolling_ball``.
    frames : int
        The instants the body axes are drawn at.

    Returns
    -------
    NotebookFigure
        The figure.

    Raises
    ------
    ValueError
        If ``result`` is not a plan of ``rolling_ball`` with a trajectory.
    """
    _check(result, "rolling_ball")
    from ..spaces.so3 import log

    p, R, t = result.q, result.R, result.t
    fig, grid, ax = _layout()
    ax.plot(p[:, 0], p[:, 1], color="0.3", lw=1.5, label="contact point")
    _mark_ends(ax, result)
    span = max(np.ptp(p[:, 0]), np.ptp(p[:, 1]), 0.5)
    size = 0.12 * span
    for k in np.linspace(0, len(t) - 1, frames).astype(int):
        for axis, colour in ((0, "tab:blue"), (1, "tab:orange")):
            d = R[k][:2, axis] * size
            ax.annotate("", xy=p[k] + d, xytext=p[k], arrowprops={"arrowstyle": "->", "color": colour, "lw": 1})
    ax.plot([], [], color="tab:blue", label="R e₁ (projected)")
    ax.plot([], [], color="tab:orange", label="R e₂ (projected)")
    _path_labels(ax, result, "contact path on the plane", 0.15)
    _time_panels(fig, grid, result, "orientation and inputs",
                 [([np.linalg.norm(log(Rk @ result.R0.T)) for Rk in R], "tab:green", "from the start"),
                  ([np.linalg.norm(log(Rk @ result.Rd.T)) for Rk in R], "tab:red", "to the goal")])
    return fig


def _body(x, y, th, length=1.0, width=0.5):
    """Corners of the car's body: the rear axle at ``(x, y)``, the front at ``length``."""
    c, s = np.cos(th), np.sin(th)
    pts = np.array([[-0.2, -width / 2], [length + 0.2, -width / 2], [length + 0.2, width / 2], [-0.2, width / 2]])
    return pts @ np.array([[c, s], [-s, c]]) + np.array([x, y])


@styled
def car_figure(result, frames: int = 8) -> NotebookFigure:
    """The car's path (the rear axle's midpoint) with its body and front wheels drawn at
    ``frames`` instants (left); right, ``θ``, ``φ`` and the inputs against time.

    Parameters
    ----------
    result : PlanResult
        A plan of ``car``.
    frames : int
        The instants the car is drawn at.

    Returns
    -------
    NotebookFigure
        The figure.

    Raises
    ------
    ValueError
        If ``result`` is not a plan of ``car`` with a trajectory.
    """
    _check(result, "car")
    q, t = result.q, result.t
    fig, grid, ax = _layout()
    ax.plot(q[:, 0], q[:, 1], color="0.3", lw=1.5, label="rear axle")
    shades = matplotlib.colormaps["viridis"]
    for j, k in enumerate(np.linspace(0, len(t) - 1, frames).astype(int)):
        x, y, th, ph = q[k]
        shade = shades(j / max(frames - 1, 1))
        ax.add_patch(Polygon(_body(x, y, th), closed=True, fill=False, ec=shade, lw=1))
        fx, fy = x + np.cos(th), y + np.sin(th)
        d = 0.18 * np.array([np.cos(th + ph), np.sin(th + ph)])
        ax.plot([fx - d[0], fx + d[0]], [fy - d[1], fy + d[1]], color=shade, lw=2.5)
    _mark_ends(ax, result)
    _path_labels(ax, result, "path, body and front wheels (dark → light)", 0.2)
    _time_panels(fig, grid, result, "heading, steering and inputs",
                 [(q[:, 2], "k", "heading θ"), (q[:, 3], "tab:purple", "steering φ")])
    return fig


@styled
def least_time_figure(fastest, along, bounds) -> NotebookFigure:
    """A planar vehicle's path of least time under input bounds against the plan as found
    re-timed along its own path (left, the first two coordinates), and both plans' use of
    each input's bound, ``u_i/high_i`` or ``u_i/low_i``, against time (right).

    Parameters
    ----------
    fastest : PlanResult
        The plan of ``objective="time"``.
    along : PlanResult
        The same goal with ``T=None`` (the plan as found, re-timed along its path).
    bounds : InputBounds
        The bounds both keep.

    Returns
    -------
    NotebookFigure
        The figure.

    Raises
    ------
    ValueError
        If the plans are not of one mechanism with a trajectory.
    """
    _check(fastest, fastest.mechanism)
    _check(along, fastest.mechanism)
    fig, grid, ax = _layout()
    plans = ((fastest, "tab:blue", f"least time, T = {fastest.T:.3f} s"),
             (along, "0.55", f"plan as found, re-timed: T = {along.T:.3f} s"))
    for res, colour, name in plans:
        ax.plot(res.q[:, 0], res.q[:, 1], color=colour, lw=1.8, label=name)
    _mark_ends(ax, fastest)
    _path_labels(ax, fastest, "paths on the plane", 0.15)
    low, high = np.asarray(bounds.lows, dtype=float), np.asarray(bounds.highs, dtype=float)
    names = _input_labels(fastest)
    for row, (res, colour, name) in enumerate(plans):
        panel = fig.add_subplot(grid[row, 1])
        t = np.linspace(0.0, res.T, 2001)
        u = np.asarray(res.controls(t), dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            share = np.where(u >= 0, u / high, u / -low)          # signed: ±1 at a bound
        for j, style in zip(range(u.shape[1]), ("-", "--")):
            panel.plot(t, share[:, j], style, color=colour, lw=1.2, label=names[j])
        panel.axhline(1.0, color="tab:red", lw=0.8, ls=":")
        panel.axhline(-1.0, color="tab:red", lw=0.8, ls=":")
        panel.set_ylim(-1.15, 1.15)
        panel.set_ylabel(label("input / its bound", NONE))
        panel.set_title(name, fontsize=9)
        panel.legend(fontsize=7, loc="lower right")
    panel.set_xlabel(label("time t", SECOND))
    fig.tight_layout()
    return fig
