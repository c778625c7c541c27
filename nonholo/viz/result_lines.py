"""Several plans on one axes, told apart: the results as a list, their legend labels, a
line style and a colour per result, one legend for the components and the results, and a
note where none of them has a trajectory to draw.

The figures of plans (:mod:`nonholo.viz.plan_figures`, :mod:`nonholo.viz.convergence_figures`)
draw through these; colours and line styles come from :mod:`nonholo.viz.style`.
"""
from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D

from .platform_drawing import mechanism_named, result_mechanism
from .style import RESULT_COLORS, RESULT_STYLES


def as_results(results) -> list:
    """One result or several, as a list.

    Parameters
    ----------
    results : PlanResult or sequence of PlanResult
        One or several results.

    Returns
    -------
    list
        The results.
    """
    if isinstance(results, (list, tuple)):
        return list(results)
    return [results]


def result_labels(results) -> list[str]:
    """Legend labels: method (and strategy), made unique.

    Parameters
    ----------
    results : sequence of PlanResult
        The results.

    Returns
    -------
    list of str
        One label per result (``"parametric (robust)"``, ``" — failed"`` appended to a
        failed one, ``" #2"`` to a repeated one).
    """
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


def note_no_trajectory(ax, results) -> bool:
    """Say so on ``ax`` when none of the results has a trajectory (e.g. a goal across
    Δ = 0, refused before any simulation).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes.
    results : sequence of PlanResult
        The results.

    Returns
    -------
    bool
        True if none has a trajectory (the note is then written).
    """
    if any(has_trajectory(r) for r in results):
        return False
    ax.text(0.5, 0.5, "no trajectory", transform=ax.transAxes, ha="center", va="center",
            color="0.4", bbox=dict(fc="white", ec="none"))
    return True


def line_style(i: int) -> str:
    """The line style of the ``i``-th result (:data:`~nonholo.viz.style.RESULT_STYLES`, in turn).

    Parameters
    ----------
    i : int
        The result's index.

    Returns
    -------
    str
        A matplotlib line style.
    """
    return RESULT_STYLES[i % len(RESULT_STYLES)]


def line_color(i: int) -> str:
    """The colour of the ``i``-th result (:data:`~nonholo.viz.style.RESULT_COLORS`, in turn).

    Parameters
    ----------
    i : int
        The result's index.

    Returns
    -------
    str
        A matplotlib colour.
    """
    return RESULT_COLORS[i % len(RESULT_COLORS)]


def results_legend(ax, results, labels, loc="best") -> None:
    """One legend: the components (the labelled lines of ``ax``, by colour) and, for
    several results, the results (by line style).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes.
    results : sequence of PlanResult
        The results drawn.
    labels : sequence of str
        Their labels.
    loc : str
        The legend's place.
    """
    handles, _ = ax.get_legend_handles_labels()
    handles = [Line2D([], [], color=h.get_color(), lw=h.get_linewidth(), ls=h.get_linestyle(),
                      marker=h.get_marker(), ms=h.get_markersize(), mew=h.get_markeredgewidth(),
                      label=h.get_label())
               for h in handles]
    if len(results) > 1:
        handles += [Line2D([], [], color="0.3", ls=line_style(i), label=lab)
                    for i, lab in enumerate(labels)]
    if handles:
        ax.legend(handles=handles, loc=loc, framealpha=0.9)


def note_no_singular_set(ax, results) -> bool:
    """Say so on ``ax`` in place of ``Δ`` when the results' mechanism has no singular set
    (the platform's by default, like :func:`note_no_trajectory` for a missing trajectory).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes of a panel of ``Δ``.
    results : sequence of PlanResult
        The results (the first one's mechanism is theirs).

    Returns
    -------
    bool
        True if the mechanism has none (``"no singular set (car)"`` is then written); False
        for one with a singular set, or an unknown mechanism (the panel draws ``Δ``).
    """
    mech = result_mechanism(results[0]) if results else mechanism_named("platform")
    note = "" if mech is None else mech.singular.placeholder
    if not note:
        return False
    ax.text(0.5, 0.5, f"{note} ({results[0].mechanism})", transform=ax.transAxes, ha="center", va="center",
            color="0.4")
    return True
