"""One mechanism at a glance (:func:`mechanism_card_figure`): its schematic and its
singular set, or, without legs, the body axes and the inputs of a planned motion."""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from ..model import catalog
from ..model.names import NONE, label
from .plan_figures import plot_body_axes, plot_controls
from .platform_drawing import draw_platform, rpy_text
from .singular_set import draw_slice
from .style import NotebookFigure, styled


@styled
def mechanism_card_figure(mechanism: str, R=None, result=None, psi_slice: float = 0.0) -> Figure:
    """One mechanism at a glance: the platform's schematic and its singular set on a slice;
    for a mechanism without legs, the paths of the body axes along a planned motion and its
    inputs.

    Parameters
    ----------
    mechanism : str
        The mechanism's name.
    R : array_like, optional
        The platform's orientation (default: the identity).
    result : PlanResult, optional
        A planned motion, for a mechanism without legs.
    psi_slice : float
        The slice ``ψ = psi_slice`` of the singular set (rad).

    Returns
    -------
    NotebookFigure
        The figure.
    """
    mech = catalog.get(mechanism)
    fig = NotebookFigure(figsize=(12.0, 5.2), layout="constrained")
    gs = fig.add_gridspec(1, 2, width_ratios=[1.0, 1.1])
    ax = fig.add_subplot(gs[0], projection="3d")
    R = np.eye(3) if R is None else np.asarray(R, dtype=float)
    if mech.geometry is not None:
        draw_platform(ax, R, mechanism)
        ax.set_title(f"{rpy_text(R)}{mech.singular.text(R, prefix=',  ')}")
    elif result is not None:
        plot_body_axes(ax, result)
        ax.set_title("paths of the body axes $R(t)e_k$")
    ax2 = fig.add_subplot(gs[1])
    cs = draw_slice(ax2, psi_slice, n=181, mechanism=mechanism)     # None without a singular set
    if cs is not None:
        cb = fig.colorbar(cs, ax=ax2, shrink=0.9, ticks=np.linspace(-1, 1, 5))
        cb.set_label(label("Δ / max|Δ|", NONE))
    elif result is not None:
        plot_controls(ax2, result)
        ax2.set_title("planned inputs")
    fig.suptitle(f"{mechanism}: {mech.description}")
    return fig
