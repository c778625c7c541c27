"""A GIF of the platform moving along a planned motion (:func:`animate_platform`)."""
from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from .platform_drawing import MECHANISM_VIEW, delta_along, draw_platform, geometry_for
from .result_lines import has_trajectory
from .style import STYLE, TRIPLE_COLORS


def _resample(result, frames: int):
    """Times and rotations at ``frames`` equally spaced times (slerp between samples)."""
    from scipy.spatial.transform import Rotation, Slerp

    t = np.asarray(result.t, dtype=float)
    R = np.asarray(result.R, dtype=float)
    times = np.linspace(t[0], t[-1], frames)
    if len(t) > 1 and np.all(np.diff(t) > 0):
        rots = Slerp(t, Rotation.from_matrix(R))(times).as_matrix()
    else:
        rots = R[np.linspace(0, len(R) - 1, frames).round().astype(int)]
    return times, rots


def animate_platform(result, path, geometry=None, frames: int = 60, fps: int = 20,
                     dpi: int = 100, view: dict | None = None) -> Path:
    """Write a GIF of the platform moving along ``result.R``.

    Each frame shows the mechanism (as in
    :func:`~nonholo.viz.platform_drawing.mechanism_figure`), the path of the body z axis'
    tip so far, the current time and ``Δ(R(t))``.

    Parameters
    ----------
    result : PlanResult
        The planned motion.
    path : str or pathlib.Path
        The GIF's path (its directory is created if needed).
    geometry : Geometry, optional
        The platform's geometry (default: the result's mechanism's).
    frames : int
        The number of frames.
    fps : int
        Frames per second.
    dpi : int
        The frames' resolution.
    view : dict, optional
        Overrides of :data:`~nonholo.viz.platform_drawing.MECHANISM_VIEW`.

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    ValueError
        If the result has no trajectory, or its mechanism no geometry to draw and none is
        given.
    """
    from matplotlib.animation import FuncAnimation, PillowWriter

    if not has_trajectory(result):
        raise ValueError("the result has no trajectory to animate")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    g = geometry_for([result], geometry)
    if g is None:
        raise ValueError(f"mechanism {result.mechanism!r} is not a platform (it has no legs/disk geometry to "
                         "draw): nonholo.viz.animate(result, path) animates every mechanism")
    mech = getattr(result, "mechanism", "platform")
    times, rots = _resample(result, frames)
    deltas = delta_along(rots, mech)
    view = {**MECHANISM_VIEW, **(view or {})}
    arrow = 1.4 * g.radius
    tip_path = arrow * rots[:, :, 2]

    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=(5.4, 5.4), layout="constrained")
        ax = fig.add_subplot(projection="3d")
        label = f"{getattr(result, 'method', '')} plan".strip()

        def draw(k):
            ax.clear()
            draw_platform(ax, rots[k], g, view=view)
            ax.plot(*tip_path[: k + 1].T, color=TRIPLE_COLORS[2], lw=1.0, alpha=0.8)
            dtxt = f"   Δ = {deltas[k]:+.3f}" if deltas is not None else ""
            ax.set_title(f"{label}\nt = {times[k]:.2f} s{dtxt}")
            return []

        anim = FuncAnimation(fig, draw, frames=frames, blit=False)
        anim.save(path, writer=PillowWriter(fps=fps), dpi=dpi)
    return path
