"""The platform drawn: its numeric geometry (:func:`as_geometry`, :func:`leg_lengths`),
``Δ`` at its orientations (:func:`delta_along`), the 3D schematic
(:func:`draw_platform`) and :func:`mechanism_figure` -- a platform at one or two
orientations.

Lengths are in units of the sphere's radius (``radius``, :mod:`nonholo.model.names`: the
sphere's radius is 1); the default geometry is the paper's placement with ``a = 1.6``,
``b = ρ = 1`` (platform joints on the sphere's surface, base joints at 1.6).
"""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d import proj3d
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from ..model import catalog
from ..model.geometry import Geometry, paper_geometry
from ..model.mechanism import Mechanism
from ..model.names import RADIUS, label
from ..spaces import so3
from .style import NotebookFigure, PAIR_COLORS, TRIPLE_COLORS, styled


def _numeric_vector(v, dims) -> np.ndarray:
    out = []
    for c in v:
        try:
            out.append(float(c))
        except TypeError:  # a SymPy expression in the symbols a, b, rho
            expr = c.subs({s: dims[s.name] for s in c.free_symbols})
            out.append(float(expr))
    return np.array(out, dtype=float)


def as_geometry(geometry=None, a: float | None = None, b: float | None = None,
                rho: float | None = None) -> Geometry:
    """A numeric :class:`~nonholo.model.geometry.Geometry`.

    ``geometry`` may be ``None`` (the paper's platform: the generated one, or at other
    dimensions :func:`~nonholo.model.geometry.paper_geometry`: leg 1 from ``a e_2`` to
    ``R (b e_2)``, leg 2 from ``a e_1`` to ``R (b e_1)``, the disk at the pole ``ρ e_3`` with
    its axle along ``(e_1 - e_2)/√2``), a :class:`Geometry`, a
    :class:`~nonholo.model.mechanism.Mechanism` or a mechanism name (its geometry), a mapping
    with the six fields, or any object with the six attributes -- e.g. a symbolic
    ``PlatformGeometry``, whose symbols ``a, b, rho`` are replaced by the given numbers
    (default: the generated platforms' ``DRAWING_DIMENSIONS``).

    Parameters
    ----------
    geometry : object, optional
        The geometry in any of those forms.
    a, b, rho : float, optional
        The dimensions of a symbolic geometry.

    Returns
    -------
    Geometry
        The numeric geometry.

    Raises
    ------
    ValueError
        For a mechanism without a legs/disk geometry.
    """
    if isinstance(geometry, Geometry):
        return geometry
    platform = catalog.get("platform")
    given = {"a": a, "b": b, "rho": rho}
    dims = {k: platform.module.DRAWING_DIMENSIONS[k] if v is None else v for k, v in given.items()}
    if geometry is None:
        if all(v is None for v in given.values()):
            return platform.geometry
        return paper_geometry(dims["a"], dims["b"], dims["rho"])
    if isinstance(geometry, (str, Mechanism)):
        mech = catalog.get(geometry)
        if mech.geometry is None:
            raise ValueError(f"mechanism {mech.name!r} has no legs/disk geometry to draw")
        return mech.geometry
    if isinstance(geometry, dict):
        vals = {k: _numeric_vector(geometry[k], dims) for k in Geometry.FIELDS}
    else:
        vals = {k: _numeric_vector(getattr(geometry, k), dims) for k in Geometry.FIELDS}
    return Geometry.from_mapping(vals)


def geometry_for(results, geometry) -> Geometry | None:
    """The geometry to draw results with.

    Parameters
    ----------
    results : sequence of PlanResult
        The results.
    geometry : object or None
        A geometry as :func:`as_geometry` takes it.

    Returns
    -------
    Geometry or None
        The geometry given, else that of the results' mechanism (``None`` if it has no
        legs or is unknown), else (results without a mechanism) the paper's.
    """
    if geometry is not None:
        return as_geometry(geometry)
    if results and getattr(results[0], "mechanism", None) is not None:
        mech = result_mechanism(results[0])
        return None if mech is None else mech.geometry
    return as_geometry(None)


def leg_lengths(R, geometry=None) -> np.ndarray:
    """Leg lengths ``l_i = |R tip_i - base_i|``.

    Parameters
    ----------
    R : array_like
        One rotation or a stack of rotations (n, 3, 3).
    geometry : object, optional
        A geometry as :func:`as_geometry` takes it.

    Returns
    -------
    numpy.ndarray
        Shape (2,) for one ``R``, (n, 2) for a stack.
    """
    return as_geometry(geometry).leg_lengths(R)


def mechanism_named(name):
    """The catalog's mechanism of a name.

    Parameters
    ----------
    name : str or None
        The name (``None``: ``"platform"``).

    Returns
    -------
    Mechanism or None
        The mechanism, ``None`` if the catalog does not know the name.
    """
    try:
        return catalog.get(name if name is not None else "platform")
    except ValueError:
        return None


def result_mechanism(res):
    """The mechanism of a result.

    Parameters
    ----------
    res : PlanResult
        The result.

    Returns
    -------
    Mechanism or None
        The one it carries (``kinematics``) or its controls were replayed with (a
        mechanism built in the session need not be in the catalog), else the one its name
        gives (``None`` if unknown).
    """
    for mech in (getattr(res, "kinematics", None),
                 getattr(getattr(res, "parametrisation", None), "mechanism", None)):
        if isinstance(mech, Mechanism):
            return mech
    return mechanism_named(getattr(res, "mechanism", "platform"))


def delta_along(R, mechanism="platform") -> np.ndarray | None:
    """``Δ(R)`` for each rotation of a stack.

    Parameters
    ----------
    R : array_like
        Rotations (n, 3, 3).
    mechanism : str
        The mechanism's name.

    Returns
    -------
    numpy.ndarray or None
        ``Δ``, shape (n,); ``None`` if the mechanism has no singular set.
    """
    mech = mechanism_named(mechanism)
    if mech is None:
        return None
    return mech.singular.samples(np.asarray(R, dtype=float).reshape(-1, 3, 3))


def _sphere_lines(n_lat=5, n_lon=12, n=73):
    """Parallels and meridians of the unit sphere (body-fixed lines), as (k, 3) arrays."""
    s = np.linspace(0.0, 2.0 * np.pi, n)
    lines = []
    for lat in np.linspace(-np.pi / 2, np.pi / 2, n_lat + 2)[1:-1]:
        lines.append(("equator" if abs(lat) < 1e-9 else "parallel",
                      np.stack([np.cos(lat) * np.cos(s), np.cos(lat) * np.sin(s),
                                np.full_like(s, np.sin(lat))], axis=1)))
    t = np.linspace(-np.pi / 2, np.pi / 2, n // 2 + 1)
    for lon in np.linspace(0.0, np.pi, n_lon // 2, endpoint=False):
        for sgn in (1.0, -1.0):
            lines.append(("meridian",
                          np.stack([sgn * np.cos(t) * np.cos(lon), sgn * np.cos(t) * np.sin(lon),
                                    np.sin(t)], axis=1)))
    return lines


def draw_platform(ax, R, geometry=None, *, labels: bool = True, disk_radius: float = 0.3,
                  limit: float | None = None, view: dict | None = None) -> None:
    """Draw the platform at orientation ``R`` into the 3D axes ``ax``.

    The sphere (translucent, with body-fixed parallels and meridians, the body equator
    thicker), the body axes ``x_b, y_b, z_b`` (columns of ``R``) as arrows, the legs as
    thick segments from their base joints (squares) to the platform joints (circles) with
    their lengths, and the disk (radius ``disk_radius`` times the sphere's, in the plane
    orthogonal to its axle) tangent to the sphere at the contact point, with its axle.

    Parameters
    ----------
    ax : mpl_toolkits.mplot3d.axes3d.Axes3D
        The 3D axes.
    R : array_like
        The orientation.
    geometry : object, optional
        A geometry as :func:`as_geometry` takes it.
    labels : bool
        Label the legs, joints and axes.
    disk_radius : float
        The disk's radius as a fraction of the sphere's.
    limit : float, optional
        Half-width of the (cubic) box.
    view : dict, optional
        Elevation and azimuth in degrees (default :data:`MECHANISM_VIEW`).
    """
    g = as_geometry(geometry)
    R = np.asarray(R, dtype=float)
    rho = g.radius
    if limit is None:
        reach = [np.linalg.norm(x) for x in g.bases] + [1.5 * rho, (1.0 + 2.0 * disk_radius) * rho]
        limit = 1.08 * max(reach)
    ax.set(xlim=(-limit, limit), ylim=(-limit, limit), zlim=(-limit, limit))
    ticks = np.arange(-np.floor(limit), np.floor(limit) + 1)
    ax.set_xticks(ticks)
    ax.set_yticks(ticks)
    ax.set_zticks(ticks)
    ax.set_box_aspect((1, 1, 1), zoom=0.95)
    ax.view_init(**{**MECHANISM_VIEW, **(view or {})})
    ax.set_xlabel(label("x", RADIUS))
    ax.set_ylabel(label("y", RADIUS))
    ax.zaxis.set_rotate_label(False)
    ax.set_zlabel(label("z", RADIUS), rotation=90)
    ax.tick_params(labelsize=8, pad=0)
    projection = ax.get_proj()

    def screen(point):
        x, y, _ = proj3d.proj_transform(*point, projection)
        return np.array([x, y])

    # sphere: a fixed translucent surface and body-fixed grid lines
    uu, vv = np.meshgrid(np.linspace(0, 2 * np.pi, 41), np.linspace(0, np.pi, 21))
    ax.plot_surface(rho * np.cos(uu) * np.sin(vv), rho * np.sin(uu) * np.sin(vv),
                    rho * np.cos(vv), color="0.75", alpha=0.12, linewidth=0, shade=False,
                    zorder=0)
    for kind, pts in _sphere_lines():
        w = rho * pts @ R.T
        if kind == "equator":
            ax.plot(*w.T, color="0.35", lw=1.1, alpha=0.8)
        else:
            ax.plot(*w.T, color="0.55", lw=0.5, alpha=0.55)

    # body axes
    arrow = 1.4 * rho
    for k, (name, col) in enumerate(zip(("x_b", "y_b", "z_b"), TRIPLE_COLORS)):
        d = R[:, k]
        ax.quiver(0, 0, 0, *(arrow * d), color=col, lw=2.0, arrow_length_ratio=0.13)
        if labels:
            ax.text(*(1.07 * arrow * d), f"${name[0]}_b$", color=col, fontsize=10,
                    ha="center", va="center", fontweight="bold")

    # legs; their labels go beside the base joints, where nothing else is drawn (on screen)
    lengths = leg_lengths(R, g)
    s01 = np.linspace(0.0, 1.0, 12)[:, None]
    obstacles = [np.outer(s01, arrow * R[:, k]) for k in range(3)]
    obstacles += [base + s01 * (R @ tip - base) for base, tip in zip(g.bases, g.tips)]
    obstacles = np.array([screen(q) for q in np.concatenate(obstacles)])
    unit = np.linalg.norm(screen(np.zeros(3)) - screen(rho * np.array([0.0, 0.0, 1.0])))
    for i, (base, tip, col) in enumerate(zip(g.bases, g.tips, PAIR_COLORS)):
        p = R @ tip
        ax.plot(*np.stack([base, p]).T, color=col, lw=4.5, solid_capstyle="round", zorder=5)
        ax.scatter(*base, marker="s", s=55, color=col, edgecolor="k", depthshade=False,
                   zorder=6)
        ax.scatter(*p, marker="o", s=45, color="white", edgecolor=col, linewidths=2.0,
                   depthshade=False, zorder=6)
        if labels:
            b2 = screen(base)
            best = None
            for ang in np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False):
                d = np.array([np.cos(ang), np.sin(ang)])
                ha = "left" if d[0] > 0.4 else "right" if d[0] < -0.4 else "center"
                va = "bottom" if d[1] > 0.4 else "top" if d[1] < -0.4 else "center"
                # the label's box (about 0.85 ρ × 0.36 ρ on screen), sampled
                w, h = 0.85 * unit, 0.36 * unit
                cx = b2[0] + 0.17 * unit * d[0] + {"left": w / 2, "right": -w / 2, "center": 0.0}[ha]
                cy = b2[1] + 0.17 * unit * d[1] + {"bottom": h / 2, "top": -h / 2, "center": 0.0}[va]
                gx, gy = np.meshgrid(cx + np.linspace(-w / 2, w / 2, 7),
                                     cy + np.linspace(-h / 2, h / 2, 3))
                box = np.stack([gx.ravel(), gy.ravel()], axis=1)
                clear = np.min(np.linalg.norm(obstacles[:, None] - box[None], axis=2))
                if best is None or clear > best[0] + 1e-9:
                    best = (clear, d, ha, va, box)
            _, d, ha, va, box = best
            obstacles = np.concatenate([obstacles, box])
            ax.annotate(f"leg {i + 1}\n$l_{i + 1}$ = {lengths[i]:.3f}", xy=b2, xycoords="data",
                        xytext=9.0 * d, textcoords="offset points", ha=ha, va=va,
                        color=col, fontsize=9, linespacing=1.1)

    # the disk, tangent at the contact point, in the plane orthogonal to its axle
    n = g.contact / rho
    w = np.cross(g.axle, n)
    rd = disk_radius * rho
    c = g.contact + rd * n
    s = np.linspace(0, 2 * np.pi, 61)
    rim = c + rd * (np.outer(np.cos(s), n) + np.outer(np.sin(s), w))
    ax.add_collection3d(Poly3DCollection([rim], facecolor="tab:orange", alpha=0.55,
                                         edgecolor="saddlebrown", linewidths=1.2))
    ax.plot(*np.stack([c - 0.45 * rho * g.axle, c + 0.45 * rho * g.axle]).T,
            color="k", lw=2.2)
    ax.scatter(*g.contact, marker="o", s=18, color="k", depthshade=False)
    if labels:
        ax.text(*(c + 0.5 * rho * g.axle + 0.05 * rho * n), "disk", fontsize=9,
                ha="left", va="bottom", color="saddlebrown")

    # the base joints are fixed to the ground: dotted posts down to the floor
    for base in g.bases:
        ax.plot([base[0]] * 2, [base[1]] * 2, [base[2], -limit], color="0.4", lw=1.0, ls=":")


#: View of the mechanism: the disk's plane is seen obliquely, both legs visible.
MECHANISM_VIEW = {"elev": 24.0, "azim": 68.0}


def rpy_text(R) -> str:
    """An orientation's RPY angles as text.

    Parameters
    ----------
    R : array_like
        A rotation matrix.

    Returns
    -------
    str
        ``"RPY = (φ, ϑ, ψ) rad"``.
    """
    phi, th, psi = so3.as_rpy(R)
    return f"RPY = ({phi:.2f}, {th:.2f}, {psi:.2f}) rad"


def drawn_mechanism(mechanism) -> Mechanism:
    """The platform a drawing is of, checked to have a geometry to draw.

    Parameters
    ----------
    mechanism : str or Mechanism
        A catalog name or a numeric mechanism.

    Returns
    -------
    Mechanism
        The mechanism.

    Raises
    ------
    TypeError
        If ``mechanism`` is neither a name nor a :class:`~nonholo.model.mechanism.Mechanism`
        (a symbolic ``derivations.mechanisms.Mechanism`` is told to go through
        ``nonholo.Mechanism.from_symbolic``).
    ValueError
        If the name is unknown, or the mechanism has no legs/disk geometry (it is not a
        two-leg platform).
    """
    if not isinstance(mechanism, (str, Mechanism)):
        hint = ""
        if type(mechanism).__module__.startswith("derivations"):
            hint = " (a symbolic mechanism: pass nonholo.Mechanism.from_symbolic(m))"
        raise TypeError(f"mechanism must be a mechanism's name or a nonholo.Mechanism, got "
                        f"{type(mechanism).__name__}{hint}")
    mech = catalog.get(mechanism)
    if mech.geometry is None:
        raise ValueError(f"mechanism {mech.name!r} has no legs/disk geometry to draw: a platform's "
                         "drawing needs a two-leg platform (a mechanism with a geometry)")
    return mech


@styled
def mechanism_figure(R_start, R_goal=None, geometry=None, title: str | None = None,
                     mechanism=None, view: dict | None = None) -> Figure:
    """3D schematic of a platform at ``R_start`` (and at ``R_goal``, side by side).

    Each panel shows the sphere with body-fixed grid lines, the body axes as arrows,
    both legs with their current lengths, and the rolling disk with its axle; the panel
    titles give the RPY angles and ``Δ(R)``.

    The figure is of one platform: ``mechanism``'s (its geometry drawn, its ``Δ`` and name
    in the titles); without it, of ``geometry`` (a geometry alone, without a ``Δ``: no
    mechanism gives it one; a mechanism or its name given as ``geometry`` is taken as
    ``mechanism``); without either, of the paper's platform. ``geometry`` and
    ``mechanism`` both given draw that geometry with that mechanism's ``Δ``.

    Parameters
    ----------
    R_start : array_like
        The start.
    R_goal : array_like, optional
        The goal.
    geometry : object, optional
        A geometry as :func:`as_geometry` takes it.
    title : str, optional
        The figure's title (default: the mechanism's name and description).
    mechanism : str or Mechanism, optional
        The platform drawn (a catalog name or a :class:`~nonholo.model.mechanism.Mechanism`
        with a geometry).
    view : dict, optional
        ``elev``/``azim`` in degrees.

    Returns
    -------
    NotebookFigure
        The figure.

    Raises
    ------
    TypeError
        If ``mechanism`` is neither a name nor a mechanism.
    ValueError
        If ``mechanism`` is unknown or has no geometry to draw, or a pose is not a rotation.
    """
    if mechanism is None and isinstance(geometry, (str, Mechanism)):
        mechanism, geometry = geometry, None
    if mechanism is not None:
        mech = drawn_mechanism(mechanism)
    else:
        mech = catalog.get("platform") if geometry is None else None
    g = mech.geometry if geometry is None else as_geometry(geometry)
    view = {**MECHANISM_VIEW, **(view or {})}
    poses = [("start", R_start)] if R_goal is None else [("start", R_start), ("goal", R_goal)]
    fig = NotebookFigure(figsize=(5.2 * len(poses), 5.2), layout="constrained")
    name = "platform" if mech is None else mech.name
    for k, (pose, R) in enumerate(poses):
        ax = fig.add_subplot(1, len(poses), k + 1, projection="3d")
        R = so3.check_rotation(R, f"R_{pose}")
        draw_platform(ax, R, g, view=view)
        dtxt = "" if mech is None else mech.singular.text(R, prefix=",  ")
        ax.set_title(f"{pose if len(poses) > 1 else name}\n{rpy_text(R)}{dtxt}")
    if title is None:
        title = f"{mech.name}: {mech.description}" if mech is not None else "a platform of the given geometry"
    fig.suptitle(title)
    return fig
