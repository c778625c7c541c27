"""The frames of an animation (:func:`nonholo.viz.animation.animate`), drawn per kind of
mechanism: a plan's motion at the frames' times (:class:`Motion`), and for each kind a
figure with ``draw(k)``, which draws frame ``k``: :func:`platform_scene` (a platform's legs
and disk), :func:`ball_scene` (a ball rolling on the plane), :func:`vehicle_scene` (a
vehicle's drawing on the plane) and :func:`state_scene` (any state).
"""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Polygon
from matplotlib.ticker import MaxNLocator

from ..model.drawing import Drawing
from ..model.names import ANGLES, NONE
from ..spaces import so3
from .platform_drawing import MECHANISM_VIEW, delta_along, draw_platform, geometry_for, result_mechanism
from .quantities import coordinate_units, label, plane_position, unit_groups
from .style import TRIPLE_COLORS


class Motion:
    """A plan's motion at the frames' times.

    Parameters
    ----------
    result : PlanResult
        The plan (with a trajectory).
    frames : int
        The number of frames.

    Attributes
    ----------
    times : numpy.ndarray
        The frames' times, equally spaced from the first sample's to the last's.
    R : numpy.ndarray
        The orientations there, ``(frames, 3, 3)`` (interpolated on SO(3)).
    q : numpy.ndarray
        The coordinates there, ``(frames, k)`` (linearly between samples; ``k = 0``
        without any).
    t_all, R_all, q_all : numpy.ndarray
        The plan's own samples: times, orientations and coordinates.
    """

    def __init__(self, result, frames: int):
        t = np.asarray(result.t, dtype=float)
        R = np.asarray(result.R, dtype=float)
        q = getattr(result, "q", None)
        q = np.zeros((len(t), 0)) if q is None else np.asarray(q, dtype=float).reshape(len(t), -1)
        self.times = np.linspace(t[0], t[-1], frames)
        increasing = len(t) > 1 and bool(np.all(np.diff(t) > 0))
        if increasing:
            from scipy.spatial.transform import Rotation, Slerp

            self.R = Slerp(t, Rotation.from_matrix(R))(self.times).as_matrix()
            self.q = np.stack([np.interp(self.times, t, q[:, i]) for i in range(q.shape[1])], axis=1) \
                if q.shape[1] else np.zeros((frames, 0))
        else:
            nearest = np.linspace(0, len(t) - 1, frames).round().astype(int)
            self.R, self.q = R[nearest], q[nearest]
        self.t_all, self.R_all, self.q_all = t, R, q


def _so_far(motion: Motion, whole: np.ndarray, now: np.ndarray, k: int) -> np.ndarray:
    """The samples of ``whole`` (one per sample time) up to frame ``k``'s time, ending at
    ``now`` (its value at that time)."""
    n = int(np.searchsorted(motion.t_all, motion.times[k], side="right"))
    return np.concatenate([whole[:n], now[None]])


def _title(result, mech) -> str:
    method = getattr(result, "method", "")
    return f"{mech.name}" + (f", {method} plan" if method else "")


def _time_text(motion: Motion, k: int) -> str:
    return f"t = {motion.times[k]:.2f} s of {motion.times[-1]:.2f} s"


# -- the platform ----------------------------------------------------------------------------

def platform_scene(result, motion: Motion, geometry=None, view: dict | None = None):
    """The platform's frames: :func:`~nonholo.viz.platform_drawing.draw_platform` at each
    orientation, the path of the body z axis' tip so far, the time and ``Δ``.

    Parameters
    ----------
    result : PlanResult
        The plan.
    motion : Motion
        Its motion at the frames' times.
    geometry : object, optional
        The platform's geometry (default: the mechanism's).
    view : dict, optional
        Overrides of :data:`~nonholo.viz.platform_drawing.MECHANISM_VIEW`.

    Returns
    -------
    figure : matplotlib.figure.Figure
        The figure.
    draw : callable
        ``draw(k)`` draws frame ``k``.

    Raises
    ------
    ValueError
        If the mechanism has no legs/disk geometry and none is given.
    """
    mech = result_mechanism(result)
    g = geometry_for([result], geometry)
    if g is None:
        raise ValueError(f"geometry: mechanism {mech.name!r} has no legs/disk geometry to draw; pass geometry=")
    deltas = delta_along(motion.R, mech)
    view = {**MECHANISM_VIEW, **(view or {})}
    tip_path = 1.4 * g.radius * motion.R[:, :, 2]
    fig = Figure(figsize=(5.4, 5.4), layout="constrained")
    ax = fig.add_subplot(projection="3d")
    title = _title(result, mech)

    def draw(k):
        ax.clear()
        draw_platform(ax, motion.R[k], g, view=view)
        ax.plot(*tip_path[: k + 1].T, color=TRIPLE_COLORS[2], lw=1.0, alpha=0.8)
        dtxt = f"   Δ = {deltas[k]:+.3f}" if deltas is not None else ""
        ax.set_title(f"{title}\n{_time_text(motion, k)}{dtxt}")

    return fig, draw


# -- the rolling ball ------------------------------------------------------------------------

def body_lines(parallels: int = 3, meridians: int = 6, n: int = 49) -> list[tuple[str, np.ndarray]]:
    """Body-fixed lines of the unit sphere: parallels (the equator among them) and
    meridians.

    Parameters
    ----------
    parallels : int
        The number of parallels (odd: the equator is one).
    meridians : int
        The number of half meridians' planes (each drawn as a whole circle).
    n : int
        Points per line.

    Returns
    -------
    list of tuple
        ``(kind, points)``: ``"equator"``, ``"parallel"`` or ``"meridian"``, and the line's
        points ``(n, 3)`` on the unit sphere in the body frame.
    """
    s = np.linspace(0.0, 2.0 * np.pi, n)
    lines = []
    for lat in np.linspace(-np.pi / 2, np.pi / 2, parallels + 2)[1:-1]:
        kind = "equator" if abs(lat) < 1e-9 else "parallel"
        lines.append((kind, np.stack([np.cos(lat) * np.cos(s), np.cos(lat) * np.sin(s),
                                      np.full_like(s, np.sin(lat))], axis=1)))
    for lon in np.linspace(0.0, np.pi, meridians, endpoint=False):
        lines.append(("meridian", np.stack([np.cos(s) * np.cos(lon), np.cos(s) * np.sin(lon), np.sin(s)], axis=1)))
    return lines


def ball_scene(result, motion: Motion, view: dict | None = None):
    """The rolling ball's frames: left, the ball (radius 1) on the plane in 3-D, with its
    body-fixed lines and axes and the contact path; right, seen from above, its upper
    half's lines and its axes projected (thin where they point down), the contact path so
    far, the start and the goal.

    Parameters
    ----------
    result : PlanResult
        A plan of a mechanism with an orientation and a position on the plane.
    motion : Motion
        Its motion at the frames' times.
    view : dict, optional
        Elevation and azimuth of the 3-D view (degrees).

    Returns
    -------
    figure : matplotlib.figure.Figure
        The figure.
    draw : callable
        ``draw(k)`` draws frame ``k``.
    """
    mech = result_mechanism(result)
    units = coordinate_units(mech)
    p, p_all = motion.q[:, :2], motion.q_all[:, :2]
    goal = np.asarray(result.qd, dtype=float)[:2] if getattr(result, "qd", None) is not None else p[-1]
    lo = np.minimum(p_all.min(axis=0), goal) - 1.35
    hi = np.maximum(p_all.max(axis=0), goal) + 1.35
    centre_span = 0.5 * max(hi[0] - lo[0], hi[1] - lo[1])
    mid = 0.5 * (lo + hi)
    lo, hi = mid - centre_span, mid + centre_span
    lines = body_lines()
    view = {"elev": 28.0, "azim": -60.0, **(view or {})}

    fig = Figure(figsize=(9.6, 4.8), layout="constrained")
    ax3 = fig.add_subplot(1, 2, 1, projection="3d")
    ax2 = fig.add_subplot(1, 2, 2)
    heading = fig.suptitle("")
    title = _title(result, mech)

    # seen from above: static path, start and goal; moving outline, marks and axes
    ax2.plot(*p_all.T, color="0.55", lw=1.0, ls="--", label="contact path")
    ax2.plot(*p_all[0], "o", color="tab:green", ms=6, label="start")
    ax2.plot(*goal, "x", color="tab:red", ms=8, mew=2, label="goal")
    so_far, = ax2.plot([], [], color="0.2", lw=1.6)
    outline = Circle((0.0, 0.0), 1.0, fill=True, facecolor="0.93", edgecolor="0.3", lw=1.2, zorder=2)
    ax2.add_patch(outline)
    marks = [ax2.plot([], [], color="0.35" if kind == "equator" else "0.6", lw=1.1 if kind == "equator" else 0.6,
                      zorder=3)[0] for kind, _ in lines]
    axes2 = [ax2.plot([], [], color=c, lw=2.0, zorder=4)[0] for c in TRIPLE_COLORS]
    contact, = ax2.plot([], [], "o", color="k", ms=3, zorder=5)
    tips2 = [ax2.plot([], [], "o", color=c, ms=4, zorder=4)[0] for c in TRIPLE_COLORS]
    ax2.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), aspect="equal")
    ax2.set_xlabel(label(mech.coordinates[0], units[0]))
    ax2.set_ylabel(label(mech.coordinates[1], units[1]))
    ax2.set_title("seen from above")
    ax2.legend(fontsize=7, loc="upper right")

    def draw(k):
        R, c2 = motion.R[k], p[k]
        centre = np.array([c2[0], c2[1], 1.0])
        # 3-D: redrawn
        ax3.clear()
        gx, gy = np.meshgrid(np.linspace(lo[0], hi[0], 2), np.linspace(lo[1], hi[1], 2))
        ax3.plot_surface(gx, gy, np.zeros_like(gx), color="0.85", alpha=0.35, linewidth=0, shade=False)
        ax3.plot(*p_all.T, np.zeros(len(p_all)), color="0.6", lw=0.8, ls=":")
        path = _so_far(motion, p_all, c2, k)
        ax3.plot(*path.T, np.zeros(len(path)), color="0.2", lw=1.6)
        for kind, pts in lines:
            w = centre + pts @ R.T
            ax3.plot(*w.T, color="0.3" if kind == "equator" else "0.55", lw=1.1 if kind == "equator" else 0.5)
        for i, colour in enumerate(TRIPLE_COLORS):
            tip = centre + 1.45 * R[:, i]
            ax3.plot(*np.stack([centre, tip]).T, color=colour, lw=2.0)
        ax3.scatter([c2[0]], [c2[1]], [0.0], color="k", s=12, depthshade=False)
        ax3.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(0.0, 2.6))
        ax3.set_box_aspect((hi[0] - lo[0], hi[1] - lo[1], 2.6))
        for axis in (ax3.xaxis, ax3.yaxis):
            axis.set_major_locator(MaxNLocator(4))
        ax3.set_zticks((0, 1, 2))
        ax3.view_init(**view)
        ax3.set_xlabel(label(mech.coordinates[0], units[0]), fontsize=8)
        ax3.set_ylabel(label(mech.coordinates[1], units[1]), fontsize=8)
        ax3.set_zlabel(label("z", units[0]), fontsize=8)
        ax3.tick_params(labelsize=7, pad=0)
        ax3.set_title("the ball on the plane")
        # from above: moved
        so_far.set_data(path[:, 0], path[:, 1])
        outline.center = tuple(c2)
        contact.set_data([c2[0]], [c2[1]])
        for line, (_, pts) in zip(marks, lines):
            w = pts @ R.T
            xy = np.where(w[:, 2:3] >= 0.0, w[:, :2], np.nan) + c2
            line.set_data(xy[:, 0], xy[:, 1])
        for i, (line, tip) in enumerate(zip(axes2, tips2)):
            d = 1.45 * R[:, i]
            line.set_data([c2[0], c2[0] + d[0]], [c2[1], c2[1] + d[1]])
            line.set_linewidth(2.0 if d[2] >= 0 else 0.8)
            tip.set_data([c2[0] + d[0]], [c2[1] + d[1]])
        heading.set_text(f"{title}: {_time_text(motion, k)}")

    return fig, draw


# -- a vehicle -------------------------------------------------------------------------------

def vehicle_scene(result, motion: Motion, drawing: Drawing):
    """A vehicle's frames: its bodies and wheels (:meth:`~nonholo.model.drawing.Drawing.outlines`) on the plane to
    scale, the path of the first body's ``(x, y)`` so far, the whole path dotted, and the
    goal's pose dashed.

    Parameters
    ----------
    result : PlanResult
        The plan.
    motion : Motion
        Its motion at the frames' times.
    drawing : Drawing
        The vehicle's drawing.

    Returns
    -------
    figure : matplotlib.figure.Figure
        The figure.
    draw : callable
        ``draw(k)`` draws frame ``k``.

    Raises
    ------
    ValueError
        If ``drawing`` is ``None``.
    """
    if drawing is None:
        raise ValueError("drawing: the mechanism has no drawing; pass drawing=")
    mech = result_mechanism(result)
    shapes = drawing.outlines(motion.q)
    reference = drawing.poses(motion.q_all)["bodies"][:, 0, :2]
    goal_q = getattr(result, "qd", None)
    goal = drawing.outlines(np.asarray(goal_q, dtype=float)) if goal_q is not None else None
    every = [drawing.outlines(motion.q_all[:: max(1, len(motion.q_all) // 200)])["bodies"].reshape(-1, 2),
             shapes["bodies"].reshape(-1, 2), shapes["wheels"].reshape(-1, 2)]
    if goal is not None:
        every.append(goal["bodies"].reshape(-1, 2))
    points = np.concatenate(every)
    points = points[np.all(np.isfinite(points), axis=1)]
    lo, hi = points.min(axis=0), points.max(axis=0)
    pad = 0.08 * max(hi - lo) + 1e-6
    lo, hi = lo - pad, hi + pad

    fig = Figure(figsize=(5.6, 5.0), layout="constrained")
    ax = fig.add_subplot()
    ax.plot(*reference.T, color="0.55", lw=1.0, ls="--", label="path")
    ax.plot(*reference[0], "o", color="tab:green", ms=6, label="start")
    if goal is not None:
        for corners in goal["bodies"][0]:
            ax.add_patch(Polygon(corners, closed=True, fill=False, ec="tab:red", ls="--", lw=1.0))
        ax.plot([], [], color="tab:red", ls="--", lw=1.0, label="goal")
    so_far, = ax.plot([], [], color="0.2", lw=1.6)
    bodies = [ax.add_patch(Polygon(c, closed=True, fc="#9ecae1", ec="#08519c", lw=1.4, alpha=0.9, zorder=3))
              for c in shapes["bodies"][0]]
    wheels = [ax.add_patch(Polygon(c, closed=True, fc="0.15", ec="0.15", zorder=4)) for c in shapes["wheels"][0]]
    plane = plane_position(mech)
    units = coordinate_units(mech)
    if plane is not None:
        i, j = plane
        ax.set_xlabel(label(mech.coordinates[i], units[i]))
        ax.set_ylabel(label(mech.coordinates[j], units[j]))
    else:
        ax.set_xlabel("x")
        ax.set_ylabel("y")
    ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]))
    ax.set_aspect("equal", adjustable="box")
    ax.legend(fontsize=7, loc="best")
    title = _title(result, mech)
    now = drawing.poses(motion.q)["bodies"][:, 0, :2]

    def draw(k):
        for patch, corners in zip(bodies, shapes["bodies"][k]):
            patch.set_xy(corners)
        for patch, corners in zip(wheels, shapes["wheels"][k]):
            patch.set_xy(corners)
        path = _so_far(motion, reference, now[k], k)
        so_far.set_data(path[:, 0], path[:, 1])
        ax.set_title(f"{title}\n{_time_text(motion, k)}")

    return fig, draw


# -- any state -------------------------------------------------------------------------------

def state_scene(result, motion: Motion, view: dict | None = None):
    """The frames of any mechanism: left, the body axes in 3-D (an orientation: their
    tips' paths so far, the goal's axes dashed) or the path of the first three (two)
    coordinates with a moving marker; right, the coordinates (one axes per unit; the RPY
    angles without coordinates) against time with a moving cursor.

    Parameters
    ----------
    result : PlanResult
        The plan.
    motion : Motion
        Its motion at the frames' times.
    view : dict, optional
        Elevation and azimuth of a 3-D view (degrees).

    Returns
    -------
    figure : matplotlib.figure.Figure
        The figure.
    draw : callable
        ``draw(k)`` draws frame ``k``.
    """
    mech = result_mechanism(result)
    k_coords = motion.q.shape[1]
    if mech.space.axes("rotation"):
        left = "axes"
    elif k_coords >= 3:
        left = "path3"
    elif k_coords == 2:
        left = "path2"
    else:
        left = None
    if k_coords:
        groups = unit_groups(mech)
        series = [(unit, [(mech.coordinates[i], motion.q_all[:, i], motion.q[:, i]) for i in idx])
                  for unit, idx in groups]
    else:
        rpy_all = np.array([so3.as_rpy(R) for R in motion.R_all])
        rpy = np.array([so3.as_rpy(R) for R in motion.R])
        series = [("rad", [(name, rpy_all[:, i], rpy[:, i]) for i, name in enumerate(a.text for a in ANGLES)])]
    rows = len(series)
    fig = Figure(figsize=(9.6 if left else 6.0, max(4.4, 2.0 * rows)), layout="constrained")
    grid = fig.add_gridspec(rows, 2 if left else 1, width_ratios=(1.0, 1.1) if left else None)
    heading = fig.suptitle("")
    title = _title(result, mech)
    updates = []
    units = coordinate_units(mech)
    view = {"elev": 24.0, "azim": -55.0, **(view or {})}

    if left == "axes":
        ax = fig.add_subplot(grid[:, 0], projection="3d")
        s = np.linspace(0.0, 2.0 * np.pi, 61)
        for pts in (np.stack([np.cos(s), np.sin(s), 0 * s], 1), np.stack([np.cos(s), 0 * s, np.sin(s)], 1),
                    np.stack([0 * s, np.cos(s), np.sin(s)], 1)):
            ax.plot(*pts.T, color="0.8", lw=0.6)
        Rd = np.asarray(getattr(result, "Rd", motion.R[-1]), dtype=float)
        for i, colour in enumerate(TRIPLE_COLORS):
            ax.plot(*np.stack([np.zeros(3), Rd[:, i]]).T, color=colour, lw=1.0, ls="--", alpha=0.7)
        axis_lines = [ax.plot([], [], [], color=c, lw=2.4)[0] for c in TRIPLE_COLORS]
        trails = [ax.plot([], [], [], color=c, lw=0.9, alpha=0.7)[0] for c in TRIPLE_COLORS]
        tips = [ax.plot([], [], [], "o", color=c, ms=4)[0] for c in TRIPLE_COLORS]
        ax.set(xlim=(-1.1, 1.1), ylim=(-1.1, 1.1), zlim=(-1.1, 1.1),
               xticks=(-1, 0, 1), yticks=(-1, 0, 1), zticks=(-1, 0, 1))
        ax.set_box_aspect((1, 1, 1))
        ax.view_init(**view)
        ax.set_xlabel(label("x", NONE), fontsize=8)
        ax.set_ylabel(label("y", NONE), fontsize=8)
        ax.set_zlabel(label("z", NONE), fontsize=8)
        ax.tick_params(labelsize=7, pad=0)
        ax.set_title("body axes (dashed: the goal's)")

        def move_axes(k):
            for i in range(3):
                d = motion.R[k][:, i]
                axis_lines[i].set_data_3d([0.0, d[0]], [0.0, d[1]], [0.0, d[2]])
                tips[i].set_data_3d([d[0]], [d[1]], [d[2]])
                trail = motion.R[: k + 1, :, i]
                trails[i].set_data_3d(trail[:, 0], trail[:, 1], trail[:, 2])

        updates.append(move_axes)
    elif left in ("path3", "path2"):
        dims = 3 if left == "path3" else 2
        ax = fig.add_subplot(grid[:, 0], projection="3d" if dims == 3 else None)
        whole = motion.q_all[:, :dims]
        ax.plot(*whole.T, color="0.55", lw=1.0, ls="--", label="path")
        ax.plot(*whole[0], "o", color="tab:green", ms=6, label="start")
        qd = getattr(result, "qd", None)
        if qd is not None:
            ax.plot(*np.asarray(qd, dtype=float)[:dims], "x", color="tab:red", ms=8, mew=2, label="goal")
        so_far, = ax.plot(*([[]] * dims), color="0.2", lw=1.6)
        marker, = ax.plot(*([[]] * dims), "o", color="tab:blue", ms=8)
        for setter, i in zip((ax.set_xlabel, ax.set_ylabel, getattr(ax, "set_zlabel", None)), range(dims)):
            setter(label(mech.coordinates[i], units[i]))
        if dims == 3:
            ax.view_init(**view)
            ax.tick_params(labelsize=7, pad=0)
            for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
                axis.set_major_locator(MaxNLocator(4))
        else:
            ax.set_aspect("equal", adjustable="datalim")
        ax.set_title("the state's path")
        ax.legend(fontsize=7, loc="upper left")

        def move_path(k):
            pts = _so_far(motion, whole, motion.q[k, :dims], k)
            if dims == 3:
                so_far.set_data_3d(pts[:, 0], pts[:, 1], pts[:, 2])
                marker.set_data_3d(pts[-1:, 0], pts[-1:, 1], pts[-1:, 2])
            else:
                so_far.set_data(pts[:, 0], pts[:, 1])
                marker.set_data(pts[-1:, 0], pts[-1:, 1])

        updates.append(move_path)

    column = 1 if left else 0
    time_axes = []
    for r, (unit, curves) in enumerate(series):
        ax = fig.add_subplot(grid[r, column], sharex=time_axes[0] if time_axes else None)
        time_axes.append(ax)
        dots = []
        for name, values, sampled in curves:
            line, = ax.plot(motion.t_all, values, label=name, lw=1.3)
            dots.append((ax.plot([], [], "o", color=line.get_color(), ms=5)[0], sampled))
        cursor = ax.axvline(motion.times[0], color="0.3", lw=1.0)
        shown = ", ".join(name for name, _, _ in curves) if len(curves) < 4 else "coordinates"
        ax.set_ylabel(label("RPY angles" if not k_coords else shown, unit))
        ax.legend(fontsize=7, loc="best")

        def move_cursor(k, cursor=cursor, dots=dots):
            t = motion.times[k]
            cursor.set_xdata([t, t])
            for dot, sampled in dots:
                dot.set_data([t], [sampled[k]])

        updates.append(move_cursor)
    for ax in time_axes[:-1]:
        ax.tick_params(labelbottom=False)
    time_axes[-1].set_xlabel(label("time t", "s"))

    def draw(k):
        for update in updates:
            update(k)
        heading.set_text(f"{title}: {_time_text(motion, k)}")

    return fig, draw
