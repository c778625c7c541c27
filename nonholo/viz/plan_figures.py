"""Figures of plans (objects with the attributes of :class:`nonholo.io.result.PlanResult`: ``t``
(n,), ``R`` (n, 3, 3), ``u`` (n, 2), ``history`` (dicts with ``"error"``, ``"step"``,
``"min_delta"`` and optionally ``"phase"``), ``terminal_error``, ``min_delta``, ``method``,
``strategy``, ``mechanism``, ``success``, ``iterations``; ``Rd`` and ``reason`` are used
when present): :func:`convergence_figure`, :func:`controls_figure`, :func:`rpy_figure`,
:func:`leg_lengths_figure`, :func:`delta_figure`, :func:`body_axes_figure` and
:func:`example_overview_figure`; each draws through a ``plot_*(ax, results, ...)``
function that can fill any axes. And figures of one plan's refinements:
:func:`global_route_figure`, :func:`leg_limits_figure`, :func:`motion_quality_figure`.

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
from matplotlib.lines import Line2D
from scipy.spatial.transform import Rotation

from ..model import catalog
from ..model.names import NONE, PER_SECOND, RAD, RADIUS, SECOND, angle_label, label, per_second
from ..spaces import so3
from .platform_drawing import (
    delta_along,
    geometry_for,
    leg_lengths,
    mechanism_named,
    result_mechanism,
)
from .singular_set import HALF_PI_TICKS, PI_TICKS, draw_singular_surface
from .style import NotebookFigure, PAIR_COLORS, RESULT_COLORS, RESULT_STYLES, TRIPLE_COLORS, styled


def _as_list(results):
    if isinstance(results, (list, tuple)):
        return list(results)
    return [results]


def _labels(results) -> list[str]:
    """Legend labels: method (and strategy), made unique."""
    labels = []
    for res in results:
        lab = str(getattr(res, "method", "plan"))
        strategy = getattr(res, "strategy", None)
        if strategy:
            lab += f" ({strategy})"
        if getattr(res, "success", True) is False:
            lab += " — failed"
        labels.append(lab)
    counts: dict[str, int] = {}
    for i, lab in enumerate(labels):
        if labels.count(lab) > 1:
            counts[lab] = counts.get(lab, 0) + 1
            labels[i] = f"{lab} #{counts[lab]}"
    return labels


def has_trajectory(res) -> bool:
    """Whether a result has a trajectory (samples ``t``).

    Parameters
    ----------
    res : PlanResult
        The result.

    Returns
    -------
    bool
        True if it has samples.
    """
    return len(np.asarray(getattr(res, "t", ()))) > 0


def _no_trajectory(ax, results) -> bool:
    """Say so on ``ax`` when none of the results has a trajectory (e.g. a goal across
    Δ = 0, refused before any simulation)."""
    if any(has_trajectory(r) for r in results):
        return False
    ax.text(0.5, 0.5, "no trajectory", transform=ax.transAxes, ha="center", va="center",
            color="0.4", bbox=dict(fc="white", ec="none"))
    return True


def _ls(i: int) -> str:
    return RESULT_STYLES[i % len(RESULT_STYLES)]


def _color(i: int) -> str:
    return RESULT_COLORS[i % len(RESULT_COLORS)]


def _legend(ax, results, labels, loc="best"):
    """One legend: the components (the labelled lines of ``ax``, by colour) and, for
    several results, the results (by line style)."""
    handles, _ = ax.get_legend_handles_labels()
    handles = [Line2D([], [], color=h.get_color(), lw=h.get_linewidth(), ls=h.get_linestyle(),
                      marker=h.get_marker(), ms=h.get_markersize(), mew=h.get_markeredgewidth(),
                      label=h.get_label())
               for h in handles]
    if len(results) > 1:
        handles += [Line2D([], [], color="0.3", ls=_ls(i), label=lab)
                    for i, lab in enumerate(labels)]
    if handles:
        ax.legend(handles=handles, loc=loc, framealpha=0.9)


def newton_switch(history) -> int | None:
    """Index of the first Newton step in ``history``, or ``None``.

    Taken from the records' ``"phase"`` (``"newton"``) when they have one, else from the
    step sizes: the first full step (``step ≥ 1``) preceded by shorter θ-flow steps
    (the initial record, of step 0, does not count).

    Parameters
    ----------
    history : list of dict
        A result's history.

    Returns
    -------
    int or None
        The index of the first Newton step, ``None`` if there is none.
    """
    if not history:
        return None
    if any("phase" in h for h in history):
        for i, h in enumerate(history):
            if h.get("phase") == "newton":
                return i if any(g.get("phase") == "flow" for g in history[:i]) else None
        return None
    steps = np.array([float(h.get("step", np.nan)) for h in history])
    full = steps >= 1.0 - 1e-9
    for i in range(1, len(steps)):
        if full[i] and np.any((steps[:i] > 0) & (steps[:i] < 1.0 - 1e-9)):
            return i
    return None


def _errors(res) -> np.ndarray:
    err = [float(h.get("error", np.nan)) for h in res.history]
    term = getattr(res, "terminal_error", None)
    if term is not None and (not err or not np.isclose(term, err[-1], rtol=1e-9, atol=0.0)):
        err.append(float(term))
    return np.array(err)


def plot_convergence(ax, results, tol: float | None = None, labels=None) -> None:
    """``‖l_T‖`` against iteration (log scale); dotted verticals mark the switch from the
    θ-flow to full Newton steps (see :func:`newton_switch`).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes drawn into.
    results : PlanResult or sequence of PlanResult
        One or several results.
    tol : float, optional
        A dashed tolerance line (``None``: none).
    labels : sequence of str, optional
        The results' legend labels (default: by method and strategy).
    """
    results = _as_list(results)
    labels = labels or _labels(results)
    annotated = False
    for i, (res, lab) in enumerate(zip(results, labels)):
        err = _errors(res)
        if not len(err):
            continue
        it = np.arange(len(err))
        ok = np.isfinite(err) & (err > 0)
        ax.semilogy(it[ok], err[ok], ls=_ls(i), color=_color(i), marker="o", ms=2.5, label=lab)
        k = newton_switch(res.history)
        if k is not None:
            ax.axvline(k, color=_color(i), ls=":", lw=1.2)
            if not annotated:
                ax.annotate("Newton steps", xy=(k, 0.98),
                            xycoords=("data", "axes fraction"), xytext=(-3, 0),
                            textcoords="offset points", rotation=90, ha="right", va="top",
                            fontsize=8.5, color=_color(i))
                annotated = True
    if not any(len(r.history) for r in results):
        ax.text(0.5, 0.5, "no iterations", transform=ax.transAxes, ha="center", va="center",
                color="0.4")
    if tol is not None:
        ax.axhline(tol, color="k", lw=0.9, ls="--", label=f"tolerance {tol:g}")
    ax.set_xlabel(label("iteration", NONE))
    ax.set_ylabel(label("terminal error ‖l_T‖", RAD))
    ax.set_title("convergence")
    ax.legend(loc="lower left", framealpha=0.9)


@styled
def convergence_figure(results, tol: float | None = None, title: str | None = None) -> Figure:
    """Terminal error ``‖l_T‖ = ‖log(R(T) R_dᵀ)‖`` against iteration for one or several
    results (log scale; colour and line style by result, legend by method): the
    exponential decrease of the θ-flow, then the quadratic Newton phase (the switch,
    inferred from the step sizes, as a dotted vertical).

    Parameters
    ----------
    results : PlanResult or sequence of PlanResult
        One or several results.
    tol : float, optional
        A dashed tolerance line (``None``: none).
    title : str, optional
        The figure's title.

    Returns
    -------
    NotebookFigure
        The figure.
    """
    fig = NotebookFigure(figsize=(6.4, 4.4), layout="constrained")
    ax = fig.add_subplot()
    plot_convergence(ax, results, tol)
    if title:
        fig.suptitle(title)
    return fig


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
    results = _as_list(results)
    labels = labels or _labels(results)
    _no_trajectory(ax, results)
    for i, res in enumerate(results):
        if not has_trajectory(res):
            continue
        t, u, style = _control_series(res)
        for j in components:
            ax.plot(t, u[:, j], color=PAIR_COLORS[j], ls=_ls(i), drawstyle=style,
                    label=f"$u_{j + 1}$" if i == 0 else None)
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_xlabel(label("time t", SECOND))
    legs = geometry_for(results, None) is not None
    ax.set_ylabel(label(("scaled leg rate u" if legs else "input u")
                        if len(components) > 1 else f"$u_{components[0] + 1}$", PER_SECOND))
    ax.set_title("controls")
    _legend(ax, results, labels)


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
    results = _as_list(results)
    labels = _labels(results)
    legs = geometry_for(results, None) is not None
    fig = NotebookFigure(figsize=(6.4, 5.2), layout="constrained")
    axes = fig.subplots(2, 1)
    for j, ax in enumerate(axes):
        _no_trajectory(ax, results)
        for i, (res, lab) in enumerate(zip(results, labels)):
            if not has_trajectory(res):
                continue
            t, u, style = _control_series(res)
            ax.plot(t, u[:, j], color=_color(i), ls=_ls(i), drawstyle=style, label=lab)
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
    results = _as_list(results)
    labels = labels or _labels(results)
    names = tuple(angle_label(k, unit=False) for k in range(3))
    _no_trajectory(ax, results)
    for i, res in enumerate(results):
        if not has_trajectory(res):
            continue
        ang = rpy_along(res.R)
        for j in range(3):
            ax.plot(res.t, ang[:, j], color=TRIPLE_COLORS[j], ls=_ls(i),
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
    _legend(ax, results, labels)


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
    results = _as_list(results)
    labels = labels or _labels(results)
    g = geometry_for(results, geometry)
    if g is None:
        ax.text(0.5, 0.5, f"no legs ({results[0].mechanism})", transform=ax.transAxes,
                ha="center", va="center", color="0.4")
    elif _no_trajectory(ax, results):
        g = None
    for i, res in enumerate(results):
        if g is None or not has_trajectory(res):
            continue
        lengths = leg_lengths(res.R, g) / g.radius
        for j in range(2):
            ax.plot(res.t, lengths[:, j], color=PAIR_COLORS[j], ls=_ls(i),
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
    _legend(ax, results, labels)


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


def _singular(results) -> bool:
    """Whether the results' mechanism has a singular set (the platform's by default)."""
    mech = result_mechanism(results[0]) if results else mechanism_named("platform")
    return mech is None or mech.singular.exists


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
    results = _as_list(results)
    labels = labels or _labels(results)
    ax.set_xlabel(label("time t", SECOND))
    ax.set_ylabel(label("Δ(R(t))", NONE))
    ax.set_title("distance from the singular set (▼: min |Δ|)")
    if not _singular(results):
        ax.text(0.5, 0.5, f"no singular set ({results[0].mechanism})", transform=ax.transAxes,
                ha="center", va="center", color="0.4")
        return
    for i, (res, lab) in enumerate(zip(results, labels)):
        if not has_trajectory(res):
            continue
        d = getattr(res, "delta", None)     # a result's own samples, whatever its mechanism
        if d is None:
            d = delta_along(res.R, getattr(res, "mechanism", "platform"))
        if d is None:
            continue
        ax.plot(res.t, d, color=_color(i), ls=_ls(i), label=lab)
        k = int(np.argmin(np.abs(d)))
        ax.plot(res.t[k], d[k], "v", color=_color(i), ms=6)
    ax.axhline(0.0, color="k", lw=2.2, label="Δ = 0 (singular)")
    if threshold:
        ax.axhspan(-threshold, threshold, color="0.5", alpha=0.25, lw=0)
        for s in (-1, 1):
            ax.axhline(s * threshold, color="0.3", lw=0.9, ls="--",
                       label=f"|Δ| = {threshold:g}" if s > 0 else None)
    _no_trajectory(ax, results)
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
    results = _as_list(results)
    labels = labels or _labels(results)
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
            ax.plot(*p.T, color=TRIPLE_COLORS[k], ls=_ls(i), lw=2.0,
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


def plot_min_delta(ax, results, threshold: float | None = 1e-2, labels=None) -> None:
    """``min_t |Δ(R(t))|`` of each iterate against iteration (log scale), from
    ``history[i]["min_delta"]``: how close the planner's trajectories came to Δ = 0.

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
    results = _as_list(results)
    labels = labels or _labels(results)
    ax.set_xlabel(label("iteration", NONE))
    ax.set_ylabel(label("min over t of |Δ(R(t))|", NONE))
    ax.set_title("closest approach to Δ = 0 per iteration")
    if not _singular(results):
        ax.text(0.5, 0.5, f"no singular set ({results[0].mechanism})", transform=ax.transAxes,
                ha="center", va="center", color="0.4")
        return
    for i, (res, lab) in enumerate(zip(results, labels)):
        md = np.abs([np.nan if h.get("min_delta") is None else float(h["min_delta"])
                     for h in res.history])
        if not len(md):
            continue
        ax.semilogy(np.arange(len(md)), md, color=_color(i), ls=_ls(i), marker="o", ms=2.5,
                    label=lab)
    if threshold:
        ax.axhline(threshold, color="0.3", lw=0.9, ls="--", label=f"|Δ| = {threshold:g}")
    ax.legend(loc="best", framealpha=0.9)


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
    mech = catalog.get(limited.mechanism)
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
    ax.set_title(title or f"{mech.name}: the legs' stroke kept by plan(..., leg_length=({lo:g}, {hi:g}))")
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
    mech = catalog.get(plain.mechanism)
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
    results = _as_list(results)
    labels = _labels(results)
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
