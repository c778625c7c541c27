"""Figures of plans along their time (objects with the attributes of
:class:`nonholo.io.result.PlanResult`: ``t`` (n,), ``R`` (n, 3, 3), ``u`` (n, 2), ``history``,
``terminal_error``, ``min_delta``, ``method``, ``strategy``, ``mechanism``, ``success``,
``iterations``; ``Rd`` and ``reason`` are used when present): :func:`controls_figure`,
:func:`rpy_figure`, :func:`leg_lengths_figure`, :func:`delta_figure`,
:func:`body_axes_figure`, and :func:`example_overview_figure`, which adds the iterations'
panels of :mod:`nonholo.viz.convergence_figures`; each draws through a
``plot_*(ax, results, ...)`` function that can fill any axes, several results told apart as
:mod:`nonholo.viz.result_lines` does.

The controls of the platform are the scaled leg-extension rates
``u_i = d(l_i²)/dt / (4ab)`` (``a = |A_i|``, ``b = |B_i|``, the distances of the base and
platform joints from the sphere's centre); with lengths measured in units of the sphere's
radius they are plotted in ``1/s``. Names and units come from :mod:`nonholo.model.names`
(the angles ``φ (yaw, about z)``, ``ϑ (pitch, about y)``, ``ψ (roll, about x)``; lengths in
``radius``, the sphere's radius).
"""
from __future__ import annotations

import textwrap
import warnings

import numpy as np
from matplotlib.figure import Figure

from ..model.names import NONE, PER_SECOND, RAD, RADIUS, SECOND, angle_label, label
from ..spaces import so3
from .convergence_figures import plot_convergence, plot_min_delta
from .platform_drawing import delta_along, geometry_for, leg_lengths
from .result_lines import (
    as_results,
    has_trajectory,
    line_color,
    line_style,
    note_no_singular_set,
    note_no_trajectory,
    result_labels,
    results_legend,
)
from .style import NotebookFigure, PAIR_COLORS, TRIPLE_COLORS, styled


def _control_series(res):
    """``(t, u, drawstyle)``: piecewise-constant controls (nonparametric, or one value per
    interval) are drawn as steps."""
    t, u = np.asarray(res.t, dtype=float), np.asarray(res.u, dtype=float)
    if len(u) == len(t) - 1:
        u = np.vstack([u, u[-1:]])
        return t, u, "steps-post"
    steps = getattr(res, "method", "") == "nonparametric"
    return t, u, "steps-post" if steps else "default"


def plot_controls(ax, results, components=(0, 1), labels=None) -> None:
    """``u_i(t)``: colour by input, line style by result.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes drawn into.
    results : PlanResult or sequence of PlanResult
        One or several results.
    components : sequence of int
        The inputs drawn (from 0).
    labels : sequence of str, optional
        The results' legend labels (default: by method and strategy).
    """
    results = as_results(results)
    labels = labels or result_labels(results)
    note_no_trajectory(ax, results)
    for i, res in enumerate(results):
        if not has_trajectory(res):
            continue
        t, u, style = _control_series(res)
        for j in components:
            ax.plot(t, u[:, j], color=PAIR_COLORS[j], ls=line_style(i), drawstyle=style,
                    label=f"$u_{j + 1}$" if i == 0 else None)
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_xlabel(label("time t", SECOND))
    legs = geometry_for(results, None) is not None
    ax.set_ylabel(label(("scaled leg rate u" if legs else "input u")
                        if len(components) > 1 else f"$u_{components[0] + 1}$", PER_SECOND))
    ax.set_title("controls")
    results_legend(ax, results, labels)


@styled
def controls_figure(results, title: str | None = None) -> Figure:
    """Controls ``u_1(t)`` (top) and ``u_2(t)`` (bottom) of one or several results
    (line style by result).

    ``u_i = d(l_i²)/dt / (4ab)`` are the scaled leg-extension rates, in 1/s.

    Parameters
    ----------
    results : PlanResult or sequence of PlanResult
        One or several results.
    title : str, optional
        The figure's title.

    Returns
    -------
    NotebookFigure
        The figure.
    """
    results = as_results(results)
    labels = result_labels(results)
    legs = geometry_for(results, None) is not None
    fig = NotebookFigure(figsize=(6.4, 5.2), layout="constrained")
    axes = fig.subplots(2, 1)
    for j, ax in enumerate(axes):
        note_no_trajectory(ax, results)
        for i, (res, lab) in enumerate(zip(results, labels)):
            if not has_trajectory(res):
                continue
            t, u, style = _control_series(res)
            ax.plot(t, u[:, j], color=line_color(i), ls=line_style(i), drawstyle=style, label=lab)
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_xlabel(label("time t", SECOND))
        ax.set_ylabel(label(f"$u_{j + 1}$", PER_SECOND))
        ax.set_title(f"leg {j + 1}: $u_{j + 1}$ = d($l_{j + 1}^2$)/dt / (4ab)" if legs
                     else f"input $u_{j + 1}$")
    axes[0].legend(loc="best", framealpha=0.9)
    if title:
        fig.suptitle(title)
    return fig


def rpy_along(R) -> np.ndarray:
    """RPY angles (n, 3) of a stack of rotations, unwrapped in time.

    Parameters
    ----------
    R : array_like
        Rotations (n, 3, 3).

    Returns
    -------
    numpy.ndarray
        The RPY angles (n, 3), unwrapped in time.
    """
    R = np.asarray(R, dtype=float)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # gimbal lock at ϑ = ±π/2
        ang = np.array([so3.as_rpy(Ri) for Ri in R])
    return np.unwrap(ang, axis=0)


def plot_rpy(ax, results, labels=None) -> None:
    """RPY angles of ``R(t)``: colour by angle, line style by result (as
    :func:`rpy_figure`).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes drawn into.
    results : PlanResult or sequence of PlanResult
        One or several results.
    labels : sequence of str, optional
        The results' legend labels (default: by method and strategy).
    """
    results = as_results(results)
    labels = labels or result_labels(results)
    names = tuple(angle_label(k, unit=False) for k in range(3))
    note_no_trajectory(ax, results)
    for i, res in enumerate(results):
        if not has_trajectory(res):
            continue
        ang = rpy_along(res.R)
        for j in range(3):
            ax.plot(res.t, ang[:, j], color=TRIPLE_COLORS[j], ls=line_style(i),
                    label=names[j] if i == 0 else None)
            ax.plot(res.t[0], ang[0, j], "o", color=TRIPLE_COLORS[j], ms=4)
            ax.plot(res.t[-1], ang[-1, j], "s", color=TRIPLE_COLORS[j], ms=4)
    goal = getattr(results[0], "Rd", None)
    if goal is not None and has_trajectory(results[0]):
        # the goal's angles, shifted by multiples of 2π next to the unwrapped final ones
        end = rpy_along(results[0].R)[-1]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            g = so3.as_rpy(goal)
        g = g + 2 * np.pi * np.round((end - g) / (2 * np.pi))
        ax.plot([results[0].t[-1]] * 3, g, "x", color="k", ms=8, mew=1.5, ls="none",
                label="goal $R_d$")
    ax.set_xlabel(label("time t", SECOND))
    ax.set_ylabel(label("RPY angle", RAD))
    ax.set_title("orientation R(t) = RPY(φ, ϑ, ψ)")
    results_legend(ax, results, labels)


@styled
def rpy_figure(results, title: str | None = None) -> Figure:
    """RPY angles ``(φ, ϑ, ψ)`` of ``R(t)`` (unwrapped; ``R = R(Z, φ) R(Y, ϑ) R(X, ψ)``),
    colour by angle, line style by result; circles at t = 0, squares at t = T, crosses at
    the goal's angles (when the results carry the goal ``Rd``).

    Parameters
    ----------
    results : PlanResult or sequence of PlanResult
        One or several results.
    title : str, optional
        The figure's title.

    Returns
    -------
    NotebookFigure
        The figure.
    """
    fig = NotebookFigure(figsize=(6.4, 4.4), layout="constrained")
    plot_rpy(fig.add_subplot(), results)
    if title:
        fig.suptitle(title)
    return fig


def plot_leg_lengths(ax, results, geometry=None, labels=None) -> None:
    """Leg lengths ``l_i(t)`` in units of the sphere's radius: colour by leg, line style by
    result (as :func:`leg_lengths_figure`).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes drawn into.
    results : PlanResult or sequence of PlanResult
        One or several results.
    geometry : object, optional
        The platform's geometry, as :func:`~nonholo.viz.platform_drawing.as_geometry` takes
        it (default: the results' mechanism's, else the paper's).
    labels : sequence of str, optional
        The results' legend labels (default: by method and strategy).
    """
    results = as_results(results)
    labels = labels or result_labels(results)
    g = geometry_for(results, geometry)
    if g is None:
        ax.text(0.5, 0.5, f"no legs ({results[0].mechanism})", transform=ax.transAxes,
                ha="center", va="center", color="0.4")
    elif note_no_trajectory(ax, results):
        g = None
    for i, res in enumerate(results):
        if g is None or not has_trajectory(res):
            continue
        lengths = leg_lengths(res.R, g) / g.radius
        for j in range(2):
            ax.plot(res.t, lengths[:, j], color=PAIR_COLORS[j], ls=line_style(i),
                    label=f"$l_{j + 1}$ (leg {j + 1})" if i == 0 else None)
    limits = {tuple(r.options["leg_length"]) for r in results
              if isinstance(getattr(r, "options", None), dict) and r.options.get("leg_length")}
    for k, (lo, hi) in enumerate(sorted(limits) if g is not None else ()):
        for y in (lo, hi):
            ax.axhline(y / g.radius, color="0.25", lw=1.0, ls="--",
                       label="stroke limits (leg_length)" if k == 0 and y == lo else None)
    ax.set_xlabel(label("time t", SECOND))
    ax.set_ylabel(label("leg length", RADIUS))
    ax.set_title("leg lengths $l_i = |R\\,B_i - A_i|$")
    results_legend(ax, results, labels)


@styled
def leg_lengths_figure(results, geometry=None, title: str | None = None) -> Figure:
    """Leg lengths ``l_i(t) = |R(t) tip_i - base_i|`` in units of the sphere's radius
    (geometry: see :func:`as_geometry`; default from the result's mechanism, else the
    paper's), colour by leg, line style by result.

    Parameters
    ----------
    results : PlanResult or sequence of PlanResult
        One or several results.
    geometry : object, optional
        The platform's geometry, as :func:`~nonholo.viz.platform_drawing.as_geometry` takes
        it (default: the results' mechanism's, else the paper's).
    title : str, optional
        The figure's title.

    Returns
    -------
    NotebookFigure
        The figure.
    """
    fig = NotebookFigure(figsize=(6.4, 4.4), layout="constrained")
    plot_leg_lengths(fig.add_subplot(), results, geometry)
    if title:
        fig.suptitle(title)
    return fig


def plot_delta(ax, results, threshold: float | None = 1e-2, labels=None) -> None:
    """``Δ(R(t))`` with ``Δ = 0`` and the band ``|Δ| < threshold``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes drawn into.
    results : PlanResult or sequence of PlanResult
        One or several results.
    threshold : float, optional
        Half-width of the band ``|Δ| < threshold`` drawn (``None``: none).
    labels : sequence of str, optional
        The results' legend labels (default: by method and strategy).
    """
    results = as_results(results)
    labels = labels or result_labels(results)
    ax.set_xlabel(label("time t", SECOND))
    ax.set_ylabel(label("Δ(R(t))", NONE))
    ax.set_title("distance from the singular set (▼: min |Δ|)")
    if note_no_singular_set(ax, results):
        return
    for i, (res, lab) in enumerate(zip(results, labels)):
        if not has_trajectory(res):
            continue
        d = getattr(res, "delta", None)     # a result's own samples, whatever its mechanism
        if d is None:
            d = delta_along(res.R, getattr(res, "mechanism", "platform"))
        if d is None:
            continue
        ax.plot(res.t, d, color=line_color(i), ls=line_style(i), label=lab)
        k = int(np.argmin(np.abs(d)))
        ax.plot(res.t[k], d[k], "v", color=line_color(i), ms=6)
    ax.axhline(0.0, color="k", lw=2.2, label="Δ = 0 (singular)")
    if threshold:
        ax.axhspan(-threshold, threshold, color="0.5", alpha=0.25, lw=0)
        for s in (-1, 1):
            ax.axhline(s * threshold, color="0.3", lw=0.9, ls="--",
                       label=f"|Δ| = {threshold:g}" if s > 0 else None)
    note_no_trajectory(ax, results)
    lo, hi = ax.get_ylim()
    span = max(hi, -lo, 1.5 * (threshold or 0.0))
    # keep Δ = 0 in view
    ax.set_ylim(min(lo, -0.08 * span), max(hi, 0.08 * span))
    ax.legend(loc="best", framealpha=0.9)


@styled
def delta_figure(results, threshold: float | None = 1e-2, title: str | None = None) -> Figure:
    """``Δ(R(t))`` along one or several results, with ``Δ = 0`` (thick) and the band
    ``|Δ| < threshold`` (dashed lines ±threshold); triangles mark the minimum of ``|Δ|``.

    Parameters
    ----------
    results : PlanResult or sequence of PlanResult
        One or several results.
    threshold : float, optional
        Half-width of the band ``|Δ| < threshold`` drawn (``None``: none).
    title : str, optional
        The figure's title.

    Returns
    -------
    NotebookFigure
        The figure.
    """
    fig = NotebookFigure(figsize=(6.4, 4.4), layout="constrained")
    plot_delta(fig.add_subplot(), results, threshold)
    if title:
        fig.suptitle(title)
    return fig


def plot_body_axes(ax, results, labels=None) -> None:
    """Paths of the body axes' tips ``R(t) e_k`` on the unit sphere (3D axes).

    Parameters
    ----------
    ax : mpl_toolkits.mplot3d.axes3d.Axes3D
        The 3D axes drawn into.
    results : PlanResult or sequence of PlanResult
        One or several results.
    labels : sequence of str, optional
        The results' legend labels (default: by method and strategy).
    """
    results = as_results(results)
    labels = labels or result_labels(results)
    uu, vv = np.meshgrid(np.linspace(0, 2 * np.pi, 25), np.linspace(0, np.pi, 13))
    ax.plot_wireframe(np.cos(uu) * np.sin(vv), np.sin(uu) * np.sin(vv), np.cos(vv),
                      color="0.6", lw=0.3, alpha=0.5)
    names = ("$x_b$", "$y_b$", "$z_b$")
    for i, res in enumerate(results):
        if not has_trajectory(res):
            continue
        R = np.asarray(res.R)
        for k in range(3):
            p = R[:, :, k]
            ax.plot(*p.T, color=TRIPLE_COLORS[k], ls=line_style(i), lw=2.0,
                    label=names[k] if i == 0 else None)
            ax.scatter(*p[0], marker="o", s=22, color=TRIPLE_COLORS[k], depthshade=False)
            ax.scatter(*p[-1], marker="s", s=22, color=TRIPLE_COLORS[k], depthshade=False)
    ax.set(xlim=(-1, 1), ylim=(-1, 1), zlim=(-1, 1))
    ax.set_box_aspect((1, 1, 1), zoom=0.85)
    ax.set_xticks([-1, 0, 1])
    ax.set_yticks([-1, 0, 1])
    ax.set_zticks([-1, 0, 1])
    ax.set_xlabel(label("x", NONE))
    ax.set_ylabel(label("y", NONE))
    ax.zaxis.set_rotate_label(False)
    ax.set_zlabel(label("z", NONE), rotation=90)
    ax.set_title("body axes R(t) $e_k$ (○ start, □ end)")
    ax.legend(loc="upper left", fontsize=8, framealpha=0.9)
    ax.view_init(elev=22, azim=35)


@styled
def body_axes_figure(results, title: str | None = None) -> Figure:
    """Paths of the tips of the body axes ``R(t) e_1, R(t) e_2, R(t) e_3`` on the unit
    sphere (circle: start, square: end; line style by result).

    Parameters
    ----------
    results : PlanResult or sequence of PlanResult
        One or several results.
    title : str, optional
        The figure's title.

    Returns
    -------
    NotebookFigure
        The figure.
    """
    fig = NotebookFigure(figsize=(5.6, 5.4), layout="constrained")
    plot_body_axes(fig.add_subplot(projection="3d"), results)
    if title:
        fig.suptitle(title)
    return fig


@styled
def example_overview_figure(results, title: str = "", geometry=None, tol: float | None = None,
                            threshold: float | None = 1e-2) -> Figure:
    """One example in a 2 × 3 grid: convergence, controls ``u_1, u_2`` [1/s] (scaled leg
    rates ``u_i = d(l_i²)/dt / (4ab)``), RPY angles, leg lengths, ``Δ(R(t))`` along the
    final trajectories, and the closest approach to ``Δ = 0`` of every iterate. Line
    style distinguishes the results; the title lists iterations, terminal error and
    ``min |Δ|`` of each.

    Parameters
    ----------
    results : PlanResult or sequence of PlanResult
        One or several results.
    title : str
        The figure's title.
    geometry : object, optional
        The platform's geometry, as :func:`~nonholo.viz.platform_drawing.as_geometry` takes
        it (default: the results' mechanism's, else the paper's).
    tol : float, optional
        A dashed tolerance line (``None``: none).
    threshold : float, optional
        Half-width of the band ``|Δ| < threshold`` drawn (``None``: none).

    Returns
    -------
    NotebookFigure
        The figure.
    """
    results = as_results(results)
    labels = result_labels(results)
    fig = NotebookFigure(figsize=(16.0, 9.4), layout="constrained")
    axes = [fig.add_subplot(2, 3, k + 1) for k in range(5)]  # the sixth below
    plot_convergence(axes[0], results, tol, labels)
    plot_controls(axes[1], results, labels=labels)
    plot_rpy(axes[2], results, labels)
    plot_leg_lengths(axes[3], results, geometry, labels)
    plot_delta(axes[4], results, threshold, labels)
    plot_min_delta(fig.add_subplot(2, 3, 6), results, threshold, labels)
    summary = []
    for res, lab in zip(results, labels):
        md = getattr(res, "min_delta", None)
        mdt = f", min |Δ| = {md:.3g}" if md is not None else ""
        term = getattr(res, "terminal_error", None)
        tt = f", ‖l_T‖ = {term:.2e} rad" if term is not None else ""
        why = getattr(res, "reason", "")
        why = f" ({why})" if why and getattr(res, "success", True) is False else ""
        summary.append(f"{lab}: {getattr(res, 'iterations', len(res.history))} iterations"
                       f"{tt}{mdt}{why}")
    one_line = "   |   ".join(summary)
    sep = "   |   " if len(one_line) <= 160 else "\n"
    summary = [textwrap.fill(line, 170) for line in summary]
    head = f"{title}\n" if title else ""
    fig.suptitle(head + sep.join(summary), fontsize=11)
    return fig
