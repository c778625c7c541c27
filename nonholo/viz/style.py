"""The figures' house style: the rc settings every figure is built under (:data:`STYLE`,
:func:`styled`), the colours and line styles shared by the figures, the figure class
:class:`NotebookFigure` and :func:`save_figure` (PNG and PDF, reproducible bytes).

Every figure function returns a :class:`NotebookFigure`, a
:class:`matplotlib.figure.Figure` built without pyplot: no global figure state, nothing is
shown by itself, so scripts and tests stay headless; in IPython and Jupyter it displays as
a PNG image when it is a cell's value or passed to ``display``.
"""
from __future__ import annotations

import functools
import io
from pathlib import Path

import matplotlib
from matplotlib.figure import Figure

STYLE = {
    "font.size": 10,
    "axes.titlesize": 11,
    "axes.labelsize": 10,
    "legend.fontsize": 8.5,
    "xtick.labelsize": 9,
    "ytick.labelsize": 9,
    "figure.titlesize": 12,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "lines.linewidth": 1.6,
}

#: Line styles distinguishing results (methods) in overlays.
RESULT_STYLES = ("-", "--", ":", "-.")
#: Colours of results in single-quantity panels.
RESULT_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown")
#: Colours of components (u_1/u_2, l_1/l_2, leg 1/leg 2).
PAIR_COLORS = ("tab:blue", "tab:red")
#: Colours of the RPY angles φ, ϑ, ψ and of the body axes x, y, z.
TRIPLE_COLORS = ("tab:red", "tab:green", "tab:blue")
#: Colours of the regions Δ > 0 and Δ < 0.
POSITIVE_COLOR = "#d6604d"
NEGATIVE_COLOR = "#4393c3"


#: Metadata of every PDF written by :func:`save_figure`: no creation date, so that writing
#: the same figure twice gives the same bytes.
PDF_METADATA = {"CreationDate": None}


class NotebookFigure(Figure):
    """A :class:`matplotlib.figure.Figure` that shows itself in IPython and Jupyter.

    IPython's display asks an object for ``_repr_png_``; a plain ``Figure`` made without
    pyplot has none (pyplot's inline backend registers a formatter for it only once pyplot
    is imported), so a cell would show ``<Figure size …>``. This one renders itself with
    Agg, trimmed to its artists as the inline backend does. Where that backend's formatter
    is registered it is used instead (it matches the base class first): one image either way.
    """

    def _repr_png_(self) -> bytes:
        buffer = io.BytesIO()
        self.savefig(buffer, format="png", bbox_inches="tight")
        return buffer.getvalue()


def styled(func):
    """Build the figure under :data:`STYLE` (rc settings are read when artists are made)."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with matplotlib.rc_context(STYLE):
            return func(*args, **kwargs)

    return wrapper


def save_figure(fig: Figure, stem: str, outdir=".", dpi: int = 150) -> tuple[Path, Path]:
    """Write ``fig`` as ``<outdir>/<stem>.png`` (``dpi``) and ``<outdir>/<stem>.pdf``.

    Creates ``outdir`` if needed and returns the two paths. Neither file records when it was
    written (:data:`PDF_METADATA`): the same figure gives the same bytes.
    """
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    png, pdf = outdir / f"{stem}.png", outdir / f"{stem}.pdf"
    fig.savefig(png, dpi=dpi)
    fig.savefig(pdf, metadata=PDF_METADATA)
    return png, pdf
