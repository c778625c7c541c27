"""Figures of a planner's iterations: the terminal error ``‖l_T‖`` against iteration, the
θ-flow's steps told from Newton's (:func:`newton_switch`), and the closest approach of each
iterate to ``Δ = 0`` (:func:`plot_min_delta`).

Results are objects with the attributes of :class:`nonholo.io.result.PlanResult` (``history``:
dicts with ``"error"``, ``"step"``, ``"min_delta"`` and optionally ``"phase"``;
``terminal_error``, ``method``, ``strategy``, ``mechanism``); several are told apart as
:mod:`nonholo.viz.result_lines` does.
"""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from ..model.names import NONE, RAD, label
from .result_lines import as_results, line_color, line_style, note_no_singular_set, result_labels
from .style import NotebookFigure, styled


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
    results = as_results(results)
    labels = labels or result_labels(results)
    annotated = False
    for i, (res, lab) in enumerate(zip(results, labels)):
        err = _errors(res)
        if not len(err):
            continue
        it = np.arange(len(err))
        ok = np.isfinite(err) & (err > 0)
        ax.semilogy(it[ok], err[ok], ls=line_style(i), color=line_color(i), marker="o", ms=2.5, label=lab)
        k = newton_switch(res.history)
        if k is not None:
            ax.axvline(k, color=line_color(i), ls=":", lw=1.2)
            if not annotated:
                ax.annotate("Newton steps", xy=(k, 0.98),
                            xycoords=("data", "axes fraction"), xytext=(-3, 0),
                            textcoords="offset points", rotation=90, ha="right", va="top",
                            fontsize=8.5, color=line_color(i))
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
    results = as_results(results)
    labels = labels or result_labels(results)
    ax.set_xlabel(label("iteration", NONE))
    ax.set_ylabel(label("min over t of |Δ(R(t))|", NONE))
    ax.set_title("closest approach to Δ = 0 per iteration")
    if note_no_singular_set(ax, results):
        return
    for i, (res, lab) in enumerate(zip(results, labels)):
        md = np.abs([np.nan if h.get("min_delta") is None else float(h["min_delta"])
                     for h in res.history])
        if not len(md):
            continue
        ax.semilogy(np.arange(len(md)), md, color=line_color(i), ls=line_style(i), marker="o", ms=2.5,
                    label=lab)
    if threshold:
        ax.axhline(threshold, color="0.3", lw=0.9, ls="--", label=f"|Δ| = {threshold:g}")
    ax.legend(loc="best", framealpha=0.9)
