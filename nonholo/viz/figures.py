"""Figures of the orienting platform, its singular set and of planned motions.

Every function returns a :class:`matplotlib.figure.Figure` built without pyplot (no
global figure state, nothing is shown); :func:`save_figure` writes it as PNG and PDF.

Figures of the mechanism and its singular set:

- :func:`mechanism_figure` -- 3D schematic of the platform at one or two orientations;
- :func:`singular_set_figure` -- the surface ``Δ(φ, ϑ, ψ) = 0`` in RPY coordinates with
  the sign regions, and a slice ``ψ = const``;
- :func:`singular_slices_figure` -- several slices ``ψ = const``;
- :func:`normal_form_figure` -- the normal form ``z³ + x y = 0`` near the identity with the
  image of the actual singular set.

Figures of plans (objects with the attributes of :class:`nonholo.io.result.PlanResult`: ``t``
(n,), ``R`` (n, 3, 3), ``u`` (n, 2), ``history`` (dicts with ``"error"``, ``"step"``,
``"min_delta"`` and optionally ``"phase"``), ``terminal_error``, ``min_delta``, ``method``,
``strategy``, ``mechanism``, ``success``, ``iterations``; ``Rd`` and ``reason`` are used
when present): :func:`convergence_figure`, :func:`controls_figure`, :func:`rpy_figure`,
:func:`leg_lengths_figure`, :func:`delta_figure`, :func:`body_axes_figure` and
:func:`example_overview_figure`; each draws through a ``plot_*(ax, results, ...)``
function that can fill any axes. :func:`animate_platform` writes a GIF of a motion.

The controls of the platform are the scaled leg-extension rates
``u_i = d(l_i²)/dt / (4ab)`` (``a = |A_i|``, ``b = |B_i|``, the distances of the base and
platform joints from the sphere's centre); with lengths measured in units of the sphere's
radius they are plotted in ``1/s``.

Lengths are in units of the sphere's radius ``ρ``; the default geometry is the paper's
placement with ``a = 1.6``, ``b = ρ = 1`` (platform joints on the sphere's surface).
"""
from __future__ import annotations

import functools
import textwrap
import warnings
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from mpl_toolkits.mplot3d import proj3d
from mpl_toolkits.mplot3d.art3d import Poly3DCollection
from scipy.spatial.transform import Rotation

from ..generated import platform_singularity
from ..model import catalog
from ..model.mechanism import Geometry, Mechanism
from ..spaces import so3

# --------------------------------------------------------------------------------------
# Style
# --------------------------------------------------------------------------------------

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


def _styled(func):
    """Build the figure under :data:`STYLE` (rc settings are read when artists are made)."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with matplotlib.rc_context(STYLE):
            return func(*args, **kwargs)

    return wrapper


def save_figure(fig: Figure, stem: str, outdir=".", dpi: int = 150) -> tuple[Path, Path]:
    """Write ``fig`` as ``<outdir>/<stem>.png`` (``dpi``) and ``<outdir>/<stem>.pdf``.

    Creates ``outdir`` if needed and returns the two paths.
    """
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    png, pdf = outdir / f"{stem}.png", outdir / f"{stem}.pdf"
    fig.savefig(png, dpi=dpi)
    fig.savefig(pdf)
    return png, pdf


# --------------------------------------------------------------------------------------
# Geometry
# --------------------------------------------------------------------------------------


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
    """A numeric :class:`~nonholo.model.mechanism.Geometry`.

    ``geometry`` may be ``None`` (the paper's platform, from its derivation: leg 1 from
    ``a e_2`` to ``R (b e_2)``, leg 2 from ``a e_1`` to ``R (b e_1)``, the disk at the pole
    ``ρ e_3`` with its axle along ``(e_1 - e_2)/√2``), a :class:`Geometry`, a
    :class:`~nonholo.model.mechanism.Mechanism` or a mechanism name (its geometry), a mapping
    with the six fields, or any object with the six attributes -- e.g. a symbolic
    ``PlatformGeometry``, whose symbols ``a, b, rho`` are replaced by the given numbers
    (default: the generated platforms' ``DRAWING_DIMENSIONS``).
    """
    if isinstance(geometry, Geometry):
        return geometry
    platform = catalog.get("platform")
    given = {"a": a, "b": b, "rho": rho}
    dims = {k: platform.module.DRAWING_DIMENSIONS[k] if v is None else v for k, v in given.items()}
    if geometry is None:
        if all(v is None for v in given.values()):
            return platform.geometry
        from derivations.mechanisms import (
            PAPER_GEOMETRY,  # SymPy: only for other dimensions
        )

        geometry = PAPER_GEOMETRY
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


def _geometry_for(results, geometry) -> Geometry | None:
    """The geometry given, else that of the results' mechanism (``None`` if it has no
    legs or is unknown), else (results without a mechanism) the paper's."""
    if geometry is not None:
        return as_geometry(geometry)
    if results and getattr(results[0], "mechanism", None) is not None:
        mech = _result_mechanism(results[0])
        return None if mech is None else mech.geometry
    return as_geometry(None)


def leg_lengths(R, geometry=None) -> np.ndarray:
    """Leg lengths ``l_i = |R tip_i - base_i|``: shape (2,) for one ``R``, (n, 2) for a
    stack of rotations (n, 3, 3)."""
    return as_geometry(geometry).leg_lengths(R)


def _mechanism(name):
    try:
        return catalog.get(name if name is not None else "platform")
    except ValueError:
        return None


def _result_mechanism(res):
    """The :class:`Mechanism` of a result: the one its controls were replayed with (a
    mechanism built in the session need not be in the catalog), else the one its name
    gives (``None`` if unknown)."""
    mech = getattr(getattr(res, "parametrisation", None), "mechanism", None)
    if isinstance(mech, Mechanism):
        return mech
    return _mechanism(getattr(res, "mechanism", "platform"))


def delta_along(R, mechanism="platform") -> np.ndarray | None:
    """``Δ(R)`` for each rotation of a stack (n, 3, 3); ``None`` if the mechanism has no
    singular set."""
    mech = _mechanism(mechanism)
    if mech is None or not mech.has_singular_set:
        return None
    R = np.asarray(R, dtype=float)
    return np.array([float(mech.delta(Ri)) for Ri in R.reshape(-1, 3, 3)])


# --------------------------------------------------------------------------------------
# The mechanism
# --------------------------------------------------------------------------------------


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
    their lengths, and the disk (radius ``disk_radius · ρ``, in the plane orthogonal to its
    axle) tangent to the sphere at the contact point, with its axle. ``view``: elevation
    and azimuth in degrees (default :data:`MECHANISM_VIEW`); ``limit``: half-width of the
    (cubic) box.
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
    ax.set_xlabel("x [ρ]")
    ax.set_ylabel("y [ρ]")
    ax.zaxis.set_rotate_label(False)
    ax.set_zlabel("z [ρ]", rotation=90)
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


def _rpy_text(R) -> str:
    phi, th, psi = so3.as_rpy(R)
    return f"RPY = ({phi:.2f}, {th:.2f}, {psi:.2f}) rad"


@_styled
def mechanism_figure(R_start, R_goal=None, geometry=None, title: str | None = None,
                     mechanism: str = "platform", view: dict | None = None) -> Figure:
    """3D schematic of the platform at ``R_start`` (and at ``R_goal``, side by side).

    Each panel shows the sphere with body-fixed grid lines, the body axes as arrows,
    both legs with their current lengths, and the rolling disk with its axle; the panel
    titles give the RPY angles and ``Δ(R)`` (of ``mechanism``). ``geometry``: see
    :func:`as_geometry` (default: the paper's). ``view``: ``elev``/``azim`` in degrees.
    """
    g = as_geometry(geometry)
    view = {**MECHANISM_VIEW, **(view or {})}
    poses = [("start", R_start)] if R_goal is None else [("start", R_start), ("goal", R_goal)]
    fig = Figure(figsize=(5.2 * len(poses), 5.2), layout="constrained")
    for k, (name, R) in enumerate(poses):
        ax = fig.add_subplot(1, len(poses), k + 1, projection="3d")
        R = so3.check_rotation(R, name)
        draw_platform(ax, R, g, view=view)
        d = delta_along(R[None], mechanism)
        dtxt = f",  Δ = {d[0]:+.3f}" if d is not None else ""
        label = name if len(poses) > 1 else "platform"
        ax.set_title(f"{label}\n{_rpy_text(R)}{dtxt}")
    if title is None:
        title = "Non-holonomic orienting platform"
    fig.suptitle(title)
    return fig


# --------------------------------------------------------------------------------------
# The singular set Δ = 0
# --------------------------------------------------------------------------------------


def delta_rpy(phi, theta, psi):
    """``Δ(RPY(φ, ϑ, ψ))`` (vectorised)."""
    return platform_singularity.delta_rpy(phi, theta, psi)


def _wrap(a):
    return (np.asarray(a) + np.pi) % (2.0 * np.pi) - np.pi


def singular_set_points(n_theta: int = 91, n_psi: int = 181):
    """Points of ``Δ(φ, ϑ, ψ) = 0`` over a grid of ``(ϑ, ψ) ∈ [-π/2, π/2] × [-π, π]``.

    ``Δ = P sin φ - Q cos φ`` with ``P = sin ϑ cos ψ + sin ψ cos² ϑ``,
    ``Q = sin ψ sin² ϑ``, hence ``Δ = √(P² + Q²) sin(φ - φ_0)``, ``φ_0 = atan2(Q, P)``:
    over every ``(ϑ, ψ)`` the surface has exactly two points ``φ_0`` and ``φ_0 + π``
    (wrapped to ``[-π, π)``), and ``Δ > 0`` between them (``φ_0 < φ < φ_0 + π``).
    (Where ``P = Q = 0`` -- ``ϑ = 0, ψ ∈ {0, ±π}`` -- the whole line of ``φ`` lies on it.)

    Returns ``(phi, theta, psi)``, each of shape ``(2, n_theta, n_psi)`` (the two sheets).
    """
    th, ps = np.meshgrid(np.linspace(-np.pi / 2, np.pi / 2, n_theta),
                         np.linspace(-np.pi, np.pi, n_psi), indexing="ij")
    P = np.sin(th) * np.cos(ps) + np.sin(ps) * np.cos(th) ** 2
    Q = np.sin(ps) * np.sin(th) ** 2
    phi0 = np.arctan2(Q, P)
    phi = np.stack([_wrap(phi0), _wrap(phi0 + np.pi)])
    return phi, np.stack([th, th]), np.stack([ps, ps])


def _sheet_quads(X, Y, Z, jump=np.pi):
    """Quads of a parametric grid, without those that straddle a wrap of ``X``."""
    quads = np.stack([np.stack([X[:-1, :-1], Y[:-1, :-1], Z[:-1, :-1]], -1),
                      np.stack([X[1:, :-1], Y[1:, :-1], Z[1:, :-1]], -1),
                      np.stack([X[1:, 1:], Y[1:, 1:], Z[1:, 1:]], -1),
                      np.stack([X[:-1, 1:], Y[:-1, 1:], Z[:-1, 1:]], -1)], axis=2)
    quads = quads.reshape(-1, 4, 3)
    span = quads[:, :, 0].max(axis=1) - quads[:, :, 0].min(axis=1)
    return quads[span < jump]


def _draw_singular_surface(ax, n_theta=61, n_psi=121, cmap="viridis", alpha: float = 1.0):
    """The two sheets of Δ = 0 as height φ over (ψ, ϑ) (axes x = ψ, y = ϑ, z = φ)."""
    phi, th, ps = singular_set_points(n_theta, n_psi)
    quads = np.concatenate([_sheet_quads(phi[k], ps[k], th[k]) for k in range(2)])
    quads = quads[:, :, [1, 2, 0]]
    # colour by the height φ, darken faces turned away from a light for depth
    height = quads[:, :, 2].mean(axis=1)
    colors = matplotlib.colormaps[cmap]((height + np.pi) / (2 * np.pi) * 0.85 + 0.1)
    normals = np.cross(quads[:, 1] - quads[:, 0], quads[:, 3] - quads[:, 0])
    normals = normals / np.array([2 * np.pi, np.pi, 2 * np.pi])  # box-aspect scaling
    norm = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.divide(normals, norm, out=np.zeros_like(normals), where=norm > 0)
    light = np.array([0.5, -0.6, 0.6]) / np.linalg.norm([0.5, -0.6, 0.6])
    colors[:, :3] *= (0.55 + 0.45 * np.abs(normals @ light))[:, None]
    colors[:, 3] = alpha
    ax.add_collection3d(Poly3DCollection(quads, facecolors=colors, edgecolors="none"))


def _draw_sign_walls(ax, n=121, alpha=0.45):
    """The sign of Δ on three faces of the box (axes x = ψ, y = ϑ, z = φ): the floor
    φ = -π, the back walls ψ = -π and ϑ = π/2; Δ = 0 on them as thin black curves."""
    levels = [-2.0, 0.0, 2.0]
    colors = [NEGATIVE_COLOR, POSITIVE_COLOR]
    a = np.linspace(-np.pi, np.pi, n)
    h = np.linspace(-np.pi / 2, np.pi / 2, n // 2 + 1)
    kw = dict(levels=levels, colors=colors, alpha=alpha)
    kz = dict(levels=[0.0], colors="k", linewidths=0.8)
    # floor φ = -π over (ψ, ϑ)
    S, T = np.meshgrid(a, h)
    D = delta_rpy(-np.pi, T, S)
    ax.contourf(S, T, D, zdir="z", offset=-np.pi, **kw)
    ax.contour(S, T, D, zdir="z", offset=-np.pi, **kz)
    # wall ψ = -π over (ϑ, φ)
    T, Fi = np.meshgrid(h, a)
    D = delta_rpy(Fi, T, -np.pi)
    ax.contourf(D, T, Fi, zdir="x", offset=-np.pi, **kw)
    ax.contour(D, T, Fi, zdir="x", offset=-np.pi, **kz)
    # wall ϑ = π/2 over (ψ, φ)
    S, Fi = np.meshgrid(a, a)
    D = delta_rpy(Fi, np.pi / 2, S)
    ax.contourf(S, D, Fi, zdir="y", offset=np.pi / 2, **kw)
    ax.contour(S, D, Fi, zdir="y", offset=np.pi / 2, **kz)


_PI_TICKS = ([-np.pi, -np.pi / 2, 0, np.pi / 2, np.pi], ["−π", "−π/2", "0", "π/2", "π"])
_HALF_PI_TICKS = ([-np.pi / 2, 0, np.pi / 2], ["−π/2", "0", "π/2"])


def mechanism_delta_rpy(mechanism, phi, theta, psi) -> np.ndarray:
    """``Δ(RPY(φ, ϑ, ψ))`` of any mechanism with a singular set, on arrays of angles.

    The generated ``delta(R)`` reads the entries ``R[i, j]``: given a stack of rotations
    transposed to shape (3, 3, ...) it evaluates all of them at once.
    """
    mech = catalog.get(mechanism)
    phi, theta, psi = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (phi, theta, psi)))
    R = Rotation.from_euler("ZYX", np.stack([phi, theta, psi], -1).reshape(-1, 3)).as_matrix()
    return np.asarray(mech.delta(np.moveaxis(R, 0, -1)), dtype=float).reshape(phi.shape)


def _draw_slice(ax, psi: float, n: int = 241, marks=None, mechanism: str = "platform"):
    F, T = np.meshgrid(np.linspace(-np.pi, np.pi, n), np.linspace(-np.pi / 2, np.pi / 2, n))
    if mechanism == "platform":
        D = delta_rpy(F, T, psi)
    else:
        D = mechanism_delta_rpy(mechanism, F, T, psi)
        D = D / np.max(np.abs(D))  # the colour scale is [-1, 1]
    levels = np.linspace(-1.0, 1.0, 21)
    cs = ax.contourf(F, T, D, levels=levels, cmap="RdBu_r", vmin=-1.05, vmax=1.05)
    ax.contour(F, T, D, levels=levels[levels != 0], colors="k", linewidths=0.3, alpha=0.35)
    ax.contour(F, T, D, levels=[0.0], colors="k", linewidths=2.4)
    ax.set_xticks(*_PI_TICKS)
    ax.set_yticks(*_HALF_PI_TICKS)
    ax.set_xlabel("φ (about z) [rad]")
    ax.set_ylabel("ϑ (about y) [rad]")
    ax.set_title(f"slice ψ = {psi:+.2f} rad")
    ax.grid(False)
    # sign labels at the extremes of this slice
    m = n // 8  # away from the frame
    inner = D[m:-m, m:-m]
    i_max = tuple(np.add(np.unravel_index(inner.argmax(), inner.shape), m))
    i_min = tuple(np.add(np.unravel_index(inner.argmin(), inner.shape), m))
    for idx, txt in ((i_max, "Δ > 0"), (i_min, "Δ < 0")):
        ax.text(F[idx], T[idx], txt, ha="center", va="center", fontsize=10, fontweight="bold",
                bbox=dict(boxstyle="round,pad=0.2", fc="white", ec="none", alpha=0.8))
    for label, (phi, th, mk) in (marks or {}).items():
        ax.plot(phi, th, mk, color="k", ms=7, mfc="yellow", mew=1.2, label=label)
    if marks:
        ax.legend(loc="lower left", framealpha=0.9)
    return cs


@_styled
def singular_set_figure(psi_slice: float = -0.5, marks: dict | None = None,
                        view: dict | None = None) -> Figure:
    """The singular surface ``Δ = 0`` in RPY coordinates, and one slice of it.

    Left: the surface over ``φ, ψ ∈ [-π, π]``, ``ϑ ∈ [-π/2, π/2]``, drawn as the two
    sheets ``φ = φ_0(ϑ, ψ)`` and ``φ_0 + π`` (see :func:`singular_set_points`; φ upwards,
    coloured by φ), with the sign of Δ painted on three faces of the box (red: Δ > 0,
    blue: Δ < 0; the surface meets them along the thin black curves) and the outline
    of the slice plane ``ψ = psi_slice``. Right: ``Δ(φ, ϑ, psi_slice)`` with ``Δ = 0`` thick;
    ``marks`` maps labels to ``(φ, ϑ, marker)`` points drawn on the slice.
    """
    fig = Figure(figsize=(12.5, 5.6), layout="constrained")
    gs = fig.add_gridspec(1, 2, width_ratios=[1.25, 1.0])
    ax = fig.add_subplot(gs[0], projection="3d")
    _draw_sign_walls(ax)
    _draw_singular_surface(ax)
    # the slice plane ψ = psi_slice
    a = np.array([-np.pi, np.pi])
    h = np.array([-np.pi / 2, np.pi / 2])
    ax.plot([psi_slice] * 5, [h[0], h[1], h[1], h[0], h[0]], [a[0], a[0], a[1], a[1], a[0]],
            color="k", ls="--", lw=1.0)
    # ... and the curves Δ = 0 in it (the thick curves of the right panel)
    th = np.linspace(-np.pi / 2, np.pi / 2, 721)
    P = np.sin(th) * np.cos(psi_slice) + np.sin(psi_slice) * np.cos(th) ** 2
    Q = np.sin(psi_slice) * np.sin(th) ** 2
    for shift in (0.0, np.pi):
        ph = _wrap(np.arctan2(Q, P) + shift)
        ph[1:][np.abs(np.diff(ph)) > np.pi] = np.nan
        ax.plot(np.full_like(th, psi_slice), th, ph, color="k", lw=2.0, zorder=10)
    ax.set(xlim=(-np.pi, np.pi), ylim=(-np.pi / 2, np.pi / 2), zlim=(-np.pi, np.pi))
    ax.set_xticks(_PI_TICKS[0], _PI_TICKS[1][:-1] + [""])  # π would collide with ϑ's −π/2
    ax.set_yticks(*_HALF_PI_TICKS)
    ax.set_zticks(*_PI_TICKS)
    ax.set_xlabel("ψ [rad]")
    ax.set_ylabel("ϑ [rad]")
    ax.zaxis.set_rotate_label(False)
    ax.set_zlabel("φ [rad]", rotation=0, labelpad=14)
    ax.set_box_aspect((2, 1, 2), zoom=0.88)
    v = {"elev": 35.0, "azim": -60.0, **(view or {})}
    ax.view_init(**v)
    ax.set_title("singular surface Δ(φ, ϑ, ψ) = 0")
    ax.legend(handles=[Patch(color=POSITIVE_COLOR, alpha=0.6, label="Δ > 0 (on the walls)"),
                       Patch(color=NEGATIVE_COLOR, alpha=0.6, label="Δ < 0 (on the walls)"),
                       Line2D([], [], color="k", ls="--", lw=1, label=f"slice ψ = {psi_slice:+.2f} (right)")],
              loc="upper left", bbox_to_anchor=(-0.02, 1.0), framealpha=0.9)
    ax2 = fig.add_subplot(gs[1])
    cs = _draw_slice(ax2, psi_slice, marks=marks)
    cb = fig.colorbar(cs, ax=ax2, shrink=0.9, ticks=np.linspace(-1, 1, 5))
    cb.set_label("Δ [-]")
    fig.suptitle("Singular set of the platform, RPY(φ, ϑ, ψ) = R(Z, φ) R(Y, ϑ) R(X, ψ)")
    return fig


@_styled
@_styled
def mechanism_card_figure(mechanism: str, R=None, result=None, psi_slice: float = 0.0) -> Figure:
    """One mechanism at a glance: the platform's schematic at ``R`` (default: identity) and
    its singular set on the slice ``ψ = psi_slice``; for a mechanism without legs, the
    paths of the body axes along ``result`` (a planned motion) and its inputs."""
    mech = catalog.get(mechanism)
    fig = Figure(figsize=(12.0, 5.2), layout="constrained")
    gs = fig.add_gridspec(1, 2, width_ratios=[1.0, 1.1])
    ax = fig.add_subplot(gs[0], projection="3d")
    R = np.eye(3) if R is None else np.asarray(R, dtype=float)
    if mech.geometry is not None:
        draw_platform(ax, R, mechanism)
        dtext = f",  Δ = {float(mech.delta(R)):+.3f}" if mech.has_singular_set else ""
        ax.set_title(f"{_rpy_text(R)}{dtext}")
    elif result is not None:
        plot_body_axes(ax, result)
        ax.set_title("paths of the body axes $R(t)e_k$")
    ax2 = fig.add_subplot(gs[1])
    if mech.has_singular_set:
        cs = _draw_slice(ax2, psi_slice, n=181, mechanism=mechanism)
        cb = fig.colorbar(cs, ax=ax2, shrink=0.9, ticks=np.linspace(-1, 1, 5))
        cb.set_label("Δ / max|Δ| [-]")
    elif result is not None:
        plot_controls(ax2, result)
        ax2.set_title("planned inputs")
    fig.suptitle(f"{mechanism}: {mech.description}")
    return fig


def singular_slices_figure(psi_values=(-2.0, -0.5, 0.5, 2.0), marks: dict | None = None) -> Figure:
    """``Δ(φ, ϑ, ψ)`` on slices ``ψ = const``: colour = value (red Δ > 0, blue Δ < 0),
    thick black = ``Δ = 0``. ``marks``: ``{label: (φ, ϑ, ψ, marker)}``, drawn on the slice
    whose ψ is nearest."""
    psi_values = list(psi_values)
    ncols = min(len(psi_values), 2 if len(psi_values) == 4 else 3)
    nrows = -(-len(psi_values) // ncols)
    fig = Figure(figsize=(5.0 * ncols + 0.8, 3.4 * nrows + 0.5), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False)
    cs = None
    for k, ax in enumerate(axes.flat):
        if k >= len(psi_values):
            ax.set_visible(False)
            continue
        psi = psi_values[k]
        here = {}
        for label, (phi, th, ps, mk) in (marks or {}).items():
            if int(np.argmin([abs(ps - p) for p in psi_values])) == k:
                here[label] = (phi, th, mk)
        cs = _draw_slice(ax, psi, n=181, marks=here)
    cb = fig.colorbar(cs, ax=axes, shrink=0.9, ticks=np.linspace(-1, 1, 5))
    cb.set_label("Δ [-]")
    fig.suptitle("Δ(φ, ϑ, ψ) on slices ψ = const (thick: Δ = 0)")
    return fig


def normal_form_surface(n: int = 81, extent: float = 1.0):
    """The surface ``z³ + x y = 0`` as the graph ``z = -∛(x y)`` over ``[-extent, extent]²``:
    ``(x, y, z)`` arrays of shape ``(n, n)``."""
    x, y = np.meshgrid(np.linspace(-extent, extent, n), np.linspace(-extent, extent, n))
    return x, y, -np.cbrt(x * y)


def normal_form_image(radius: float = 0.6, n: int = 61):
    """Normal-form coordinates ``(x, y, z)`` of points of ``Δ = 0`` near the identity.

    The points are those of :func:`singular_set_points` (``n`` values of ϑ, ``2n`` of ψ)
    and of the line ``ϑ = ψ = 0`` with ``|φ|, |ϑ|, |ψ| ≤ radius``, mapped by ``platform_singularity.normal_form``;
    returns ``(rpy, xyz)``, each (k, 3).
    """
    phi, th, ps = singular_set_points(n, 2 * n)
    rpy = np.stack([phi.ravel(), th.ravel(), ps.ravel()], axis=1)
    # the line ϑ = ψ = 0 (all φ) lies on Δ = 0 too; the sheets meet it in single points
    line = np.linspace(-radius, radius, max(n // 4, 11))
    rpy = np.concatenate([rpy, np.stack([line, 0 * line, 0 * line], axis=1)])
    rpy = rpy[np.all(np.abs(rpy) <= radius, axis=1)]
    xyz = np.stack(platform_singularity.normal_form(*rpy.T), axis=1)
    return rpy, xyz


def _normal_form_curves(radius: float, psi_values, n: int = 401):
    """Images under the normal-form map of the curves ``Δ = 0`` on slices ``ψ = const``
    (restricted to ``|φ|, |ϑ| ≤ radius``), as a list of (k, 3) arrays."""
    curves = []
    th = np.linspace(-radius, radius, n)
    for psi in psi_values:
        P = np.sin(th) * np.cos(psi) + np.sin(psi) * np.cos(th) ** 2
        Q = np.sin(psi) * np.sin(th) ** 2
        for shift in (0.0, np.pi):
            ph = _wrap(np.arctan2(Q, P) + shift)
            ok = np.abs(ph) <= radius
            xyz = np.stack(platform_singularity.normal_form(ph, th, np.full_like(th, psi)), 1)
            xyz[~ok] = np.nan
            xyz[1:][np.abs(np.diff(ph)) > np.pi] = np.nan
            curves.append(xyz)
    return curves


@_styled
def normal_form_figure(extent: float = 1.0, radius: float = 0.6,
                       view: dict | None = None) -> Figure:
    """The A2 normal form of the singular set at the identity.

    Left: the surface ``z³ + x y = 0`` (``z = -∛(x y)``) over ``[-extent, extent]²``
    (coloured by z), with the images (black curves) of the curves ``Δ(φ, ϑ, ψ) = 0`` on
    slices ``ψ = const``, ``|φ|, |ϑ|, |ψ| ≤ radius``, under the normal-form coordinates
    ``x = ξ + ζ``, ``y = η``, ``z = ξ ((sin φ + cos φ)/(1 - ζ²))^{1/3}``: they lie on the
    surface. Right: its level curves ``x y = -z³`` (hyperbolas that switch quadrants as z
    changes sign; the two axes at z = 0), with the images of points of ``Δ = 0`` whose z
    is within 0.01 of the level.
    """
    fig = Figure(figsize=(12.5, 5.6), layout="constrained")
    gs = fig.add_gridspec(1, 2, width_ratios=[1.1, 1.0])
    ax = fig.add_subplot(gs[0], projection="3d")
    x, y, z = normal_form_surface(61, extent)
    zmax = extent ** (2.0 / 3.0)
    ax.plot_surface(x, y, z, cmap="coolwarm", vmin=-zmax, vmax=zmax, alpha=0.55,
                    linewidth=0.2, edgecolor="0.4", rstride=3, cstride=3)
    line = np.linspace(-radius, radius, 101)
    curves = _normal_form_curves(radius, np.linspace(-radius, radius, 13))
    curves.append(np.stack(platform_singularity.normal_form(line, 0 * line, 0 * line), 1))
    for xyz in curves:
        xyz = np.where(np.all(np.abs(xyz[:, :2]) <= extent, axis=1)[:, None], xyz, np.nan)
        ax.plot(*xyz.T, color="k", lw=1.0)
    ax.scatter(0, 0, 0, s=50, color="yellow", edgecolor="k", depthshade=False, zorder=10)
    ticks = [-extent, -extent / 2, 0.0, extent / 2, extent]
    ax.set_xticks(ticks)
    ax.set_yticks(ticks)
    ax.set_xlabel("x [-]")
    ax.set_ylabel("y [-]")
    ax.zaxis.set_rotate_label(False)
    ax.set_zlabel("z [-]", rotation=0, labelpad=8)
    ax.set_box_aspect((1, 1, 0.8), zoom=0.9)
    ax.view_init(**{"elev": 24.0, "azim": -55.0, **(view or {})})
    ax.set_title("surface z³ + x y = 0")
    ax.legend(handles=[Line2D([], [], color="k", lw=1.0,
                              label=f"image of Δ(φ, ϑ, ψ) = 0, ψ = const, |·| ≤ {radius:g} rad"),
                       Line2D([], [], marker="o", ls="", ms=7, mfc="yellow", mec="k",
                              label="identity RPY = 0 (singular point)")],
              loc="upper left", framealpha=0.9)

    fig.get_layout_engine().set(wspace=0.12)
    ax2 = fig.add_subplot(gs[1])
    _, pts = normal_form_image(radius, n=201)
    s = np.linspace(-extent, extent, 801)
    levels = (-0.6, -0.3, 0.0, 0.3, 0.6)
    cmap = matplotlib.colormaps["coolwarm"]
    for zl in levels:
        col = "k" if zl == 0 else cmap(0.5 + 0.5 * np.sign(zl) * (0.55 + 0.45 * abs(zl) / 0.6))
        if zl == 0:
            ax2.axhline(0, color=col, lw=1.5)
            ax2.axvline(0, color=col, lw=1.5, label="z = 0:  x y = 0")
        else:
            with np.errstate(divide="ignore"):
                yy = -zl ** 3 / s
            yy[np.abs(yy) > extent] = np.nan
            ax2.plot(s, yy, color=col, lw=2, label=f"z = {zl:+.1f}:  x y = {-zl ** 3:+.3f}")
        near = pts[(np.abs(pts[:, 2] - zl) < 0.01) & np.all(np.abs(pts[:, :2]) <= extent, axis=1)]
        ax2.plot(near[:, 0], near[:, 1], "o", color="k", mfc="white", ms=3.0, mew=0.8)
    ax2.plot([], [], "o", color="k", mfc="white", ms=3.0, mew=0.8,
             label="images of Δ = 0 with |z − level| < 0.01")
    ax2.set(xlim=(-extent, extent), ylim=(-extent, extent), aspect="equal")
    ax2.set_xlabel("x [-]")
    ax2.set_ylabel("y [-]")
    ax2.set_title("level curves z = const of z³ + x y = 0")
    ax2.legend(loc="center left", bbox_to_anchor=(1.02, 0.5), framealpha=0.9)
    fig.suptitle("Normal form of the singular set at the identity: Δ = z³ + x y "
                 "(an A2 surface singularity)")
    return fig


# --------------------------------------------------------------------------------------
# Plans
# --------------------------------------------------------------------------------------


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


def _has_trajectory(res) -> bool:
    return len(np.asarray(getattr(res, "t", ()))) > 0


def _no_trajectory(ax, results) -> bool:
    """Say so on ``ax`` when none of the results has a trajectory (e.g. a goal across
    Δ = 0, refused before any simulation)."""
    if any(_has_trajectory(r) for r in results):
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
    (the initial record, of step 0, does not count)."""
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
    θ-flow to full Newton steps (see :func:`newton_switch`)."""
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
    ax.set_xlabel("iteration [-]")
    ax.set_ylabel("terminal error ‖l_T‖ [rad]")
    ax.set_title("convergence")
    ax.legend(loc="lower left", framealpha=0.9)


@_styled
def convergence_figure(results, tol: float | None = None, title: str | None = None) -> Figure:
    """Terminal error ``‖l_T‖ = ‖log(R(T) R_dᵀ)‖`` against iteration for one or several
    results (log scale; colour and line style by result, legend by method): the
    exponential decrease of the θ-flow, then the quadratic Newton phase (the switch,
    inferred from the step sizes, as a dotted vertical). ``tol``: a dashed tolerance line."""
    fig = Figure(figsize=(6.4, 4.4), layout="constrained")
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
    """``u_i(t)``: colour by input, line style by result."""
    results = _as_list(results)
    labels = labels or _labels(results)
    _no_trajectory(ax, results)
    for i, res in enumerate(results):
        if not _has_trajectory(res):
            continue
        t, u, style = _control_series(res)
        for j in components:
            ax.plot(t, u[:, j], color=PAIR_COLORS[j], ls=_ls(i), drawstyle=style,
                    label=f"$u_{j + 1}$" if i == 0 else None)
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_xlabel("time t [s]")
    legs = _geometry_for(results, None) is not None
    ax.set_ylabel(("scaled leg rate u [1/s]" if legs else "input u [1/s]")
                  if len(components) > 1 else f"$u_{components[0] + 1}$ [1/s]")
    ax.set_title("controls")
    _legend(ax, results, labels)


@_styled
def controls_figure(results, title: str | None = None) -> Figure:
    """Controls ``u_1(t)`` (top) and ``u_2(t)`` (bottom) of one or several results
    (line style by result).

    ``u_i = d(l_i²)/dt / (4ab)`` are the scaled leg-extension rates, in 1/s."""
    results = _as_list(results)
    labels = _labels(results)
    legs = _geometry_for(results, None) is not None
    fig = Figure(figsize=(6.4, 5.2), layout="constrained")
    axes = fig.subplots(2, 1)
    for j, ax in enumerate(axes):
        _no_trajectory(ax, results)
        for i, (res, lab) in enumerate(zip(results, labels)):
            if not _has_trajectory(res):
                continue
            t, u, style = _control_series(res)
            ax.plot(t, u[:, j], color=_color(i), ls=_ls(i), drawstyle=style, label=lab)
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_xlabel("time t [s]")
        ax.set_ylabel(f"$u_{j + 1}$ [1/s]")
        ax.set_title(f"leg {j + 1}: $u_{j + 1}$ = d($l_{j + 1}^2$)/dt / (4ab)" if legs
                     else f"input $u_{j + 1}$")
    axes[0].legend(loc="best", framealpha=0.9)
    if title:
        fig.suptitle(title)
    return fig


def rpy_along(R) -> np.ndarray:
    """RPY angles (n, 3) of a stack of rotations, unwrapped in time."""
    R = np.asarray(R, dtype=float)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # gimbal lock at ϑ = ±π/2
        ang = np.array([so3.as_rpy(Ri) for Ri in R])
    return np.unwrap(ang, axis=0)


def plot_rpy(ax, results, labels=None) -> None:
    results = _as_list(results)
    labels = labels or _labels(results)
    names = ("φ (about z)", "ϑ (about y)", "ψ (about x)")
    _no_trajectory(ax, results)
    for i, res in enumerate(results):
        if not _has_trajectory(res):
            continue
        ang = rpy_along(res.R)
        for j in range(3):
            ax.plot(res.t, ang[:, j], color=TRIPLE_COLORS[j], ls=_ls(i),
                    label=names[j] if i == 0 else None)
            ax.plot(res.t[0], ang[0, j], "o", color=TRIPLE_COLORS[j], ms=4)
            ax.plot(res.t[-1], ang[-1, j], "s", color=TRIPLE_COLORS[j], ms=4)
    goal = getattr(results[0], "Rd", None)
    if goal is not None and _has_trajectory(results[0]):
        # the goal's angles, shifted by multiples of 2π next to the unwrapped final ones
        end = rpy_along(results[0].R)[-1]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            g = so3.as_rpy(goal)
        g = g + 2 * np.pi * np.round((end - g) / (2 * np.pi))
        ax.plot([results[0].t[-1]] * 3, g, "x", color="k", ms=8, mew=1.5, ls="none",
                label="goal $R_d$")
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("RPY angle [rad]")
    ax.set_title("orientation R(t) = RPY(φ, ϑ, ψ)")
    _legend(ax, results, labels)


@_styled
def rpy_figure(results, title: str | None = None) -> Figure:
    """RPY angles ``(φ, ϑ, ψ)`` of ``R(t)`` (unwrapped; ``R = R(Z, φ) R(Y, ϑ) R(X, ψ)``),
    colour by angle, line style by result; circles at t = 0, squares at t = T, crosses at
    the goal's angles (when the results carry the goal ``Rd``)."""
    fig = Figure(figsize=(6.4, 4.4), layout="constrained")
    plot_rpy(fig.add_subplot(), results)
    if title:
        fig.suptitle(title)
    return fig


def plot_leg_lengths(ax, results, geometry=None, labels=None) -> None:
    results = _as_list(results)
    labels = labels or _labels(results)
    g = _geometry_for(results, geometry)
    if g is None:
        ax.text(0.5, 0.5, f"no legs ({results[0].mechanism})", transform=ax.transAxes,
                ha="center", va="center", color="0.4")
    elif _no_trajectory(ax, results):
        g = None
    for i, res in enumerate(results):
        if g is None or not _has_trajectory(res):
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
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("leg length [ρ]")
    ax.set_title("leg lengths $l_i = |R\\,B_i - A_i|$")
    _legend(ax, results, labels)


@_styled
def leg_lengths_figure(results, geometry=None, title: str | None = None) -> Figure:
    """Leg lengths ``l_i(t) = |R(t) tip_i - base_i|`` in units of the sphere's radius
    (geometry: see :func:`as_geometry`; default from the result's mechanism, else the
    paper's), colour by leg, line style by result."""
    fig = Figure(figsize=(6.4, 4.4), layout="constrained")
    plot_leg_lengths(fig.add_subplot(), results, geometry)
    if title:
        fig.suptitle(title)
    return fig


def _singular(results) -> bool:
    """Whether the results' mechanism has a singular set (the platform's by default)."""
    mech = _result_mechanism(results[0]) if results else _mechanism("platform")
    return mech is None or mech.has_singular_set


def plot_delta(ax, results, threshold: float | None = 1e-2, labels=None) -> None:
    """``Δ(R(t))`` with ``Δ = 0`` and the band ``|Δ| < threshold``."""
    results = _as_list(results)
    labels = labels or _labels(results)
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("Δ(R(t)) [-]")
    ax.set_title("distance from the singular set (▼: min |Δ|)")
    if not _singular(results):
        ax.text(0.5, 0.5, f"no singular set ({results[0].mechanism})", transform=ax.transAxes,
                ha="center", va="center", color="0.4")
        return
    drawn = False
    for i, (res, lab) in enumerate(zip(results, labels)):
        if not _has_trajectory(res):
            continue
        d = getattr(res, "delta", None)     # a result's own samples, whatever its mechanism
        if d is None:
            d = delta_along(res.R, getattr(res, "mechanism", "platform"))
        if d is None:
            continue
        drawn = True
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


@_styled
def delta_figure(results, threshold: float | None = 1e-2, title: str | None = None) -> Figure:
    """``Δ(R(t))`` along one or several results, with ``Δ = 0`` (thick) and the band
    ``|Δ| < threshold`` (dashed lines ±threshold); triangles mark the minimum of ``|Δ|``."""
    fig = Figure(figsize=(6.4, 4.4), layout="constrained")
    plot_delta(fig.add_subplot(), results, threshold)
    if title:
        fig.suptitle(title)
    return fig


def plot_body_axes(ax, results, labels=None) -> None:
    """Paths of the body axes' tips ``R(t) e_k`` on the unit sphere (3D axes)."""
    results = _as_list(results)
    labels = labels or _labels(results)
    uu, vv = np.meshgrid(np.linspace(0, 2 * np.pi, 25), np.linspace(0, np.pi, 13))
    ax.plot_wireframe(np.cos(uu) * np.sin(vv), np.sin(uu) * np.sin(vv), np.cos(vv),
                      color="0.6", lw=0.3, alpha=0.5)
    names = ("$x_b$", "$y_b$", "$z_b$")
    for i, res in enumerate(results):
        if not _has_trajectory(res):
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
    ax.set_xlabel("x [-]")
    ax.set_ylabel("y [-]")
    ax.zaxis.set_rotate_label(False)
    ax.set_zlabel("z [-]", rotation=90)
    ax.set_title("body axes R(t) $e_k$ (○ start, □ end)")
    ax.legend(loc="upper left", fontsize=8, framealpha=0.9)
    ax.view_init(elev=22, azim=35)


@_styled
def body_axes_figure(results, title: str | None = None) -> Figure:
    """Paths of the tips of the body axes ``R(t) e_1, R(t) e_2, R(t) e_3`` on the unit
    sphere (circle: start, square: end; line style by result)."""
    fig = Figure(figsize=(5.6, 5.4), layout="constrained")
    plot_body_axes(fig.add_subplot(projection="3d"), results)
    if title:
        fig.suptitle(title)
    return fig


def plot_min_delta(ax, results, threshold: float | None = 1e-2, labels=None) -> None:
    """``min_t |Δ(R(t))|`` of each iterate against iteration (log scale), from
    ``history[i]["min_delta"]``: how close the planner's trajectories came to Δ = 0."""
    results = _as_list(results)
    labels = labels or _labels(results)
    ax.set_xlabel("iteration [-]")
    ax.set_ylabel("min over t of |Δ(R(t))| [-]")
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


@_styled
def global_route_figure(result, title: str | None = None) -> Figure:
    """A plan of the global route (``result.route == "global"``): left, its motion in RPY
    coordinates over the singular surface ``Δ = 0`` (axes as :func:`singular_set_figure`),
    the hops' ends marked; right, ``Δ`` along the motion and the controls — the stitched
    controls of the hops (thin, where the route was re-planned as one smooth control) and
    the plan's — the hand-overs between hops dotted."""
    par = result.hops
    smoothed = result.stitched is not None
    fig = Figure(figsize=(13.0, 5.6), layout="constrained")
    gs = fig.add_gridspec(2, 2, width_ratios=[1.2, 1.0])
    ax = fig.add_subplot(gs[:, 0], projection="3d")
    _draw_singular_surface(ax, n_theta=31, n_psi=61, cmap="Greys", alpha=0.25)
    a = _rpy_curve(result.R)
    ax.plot(a[:, 2], a[:, 1], a[:, 0], color="C3", lw=2.6, label="motion R(t)", zorder=20)
    w = Rotation.from_matrix(np.asarray(par.waypoints)).as_euler("ZYX")
    ax.scatter(w[1:-1, 2], w[1:-1, 1], w[1:-1, 0], color="k", s=18, depthshade=False, label="ends of hops")
    for (phi, th, psi), mk, lab in ((w[0], "o", "start"), (w[-1], "*", "goal")):
        ax.scatter([psi], [th], [phi], marker=mk, s=110, color="gold", edgecolor="k", depthshade=False,
                   label=lab)
    ax.set(xlim=(-np.pi, np.pi), ylim=(-np.pi / 2, np.pi / 2), zlim=(-np.pi, np.pi))
    ax.set_xticks(*_PI_TICKS)
    ax.set_yticks(*_HALF_PI_TICKS)
    ax.set_zticks(*_PI_TICKS)
    ax.set_xlabel("ψ [rad]")
    ax.set_ylabel("ϑ [rad]")
    ax.set_zlabel("φ [rad]")
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


@_styled
def leg_limits_figure(free, limited, title: str | None = None) -> Figure:
    """Leg lengths ``l_i(t)`` of a plan without stroke limits (dashed) and of the same
    problem planned with ``leg_length`` (solid, ``limited.options["leg_length"]``, drawn as
    grey lines), in the geometry's units."""
    mech = catalog.get(limited.mechanism)
    lo, hi = limited.options["leg_length"]
    fig = Figure(figsize=(7.2, 4.4), layout="constrained")
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
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("leg length (geometry units)")
    ax.legend(fontsize=8, loc="best")
    ax.set_title(title or f"{mech.name}: the legs' stroke kept by plan(..., leg_length=({lo:g}, {hi:g}))")
    return fig


@_styled
def motion_quality_figure(plain, cheap, fast, title: str | None = None) -> Figure:
    """Two refinements of one plan ``plain``: the inputs of ``cheap`` (``objective="energy"``,
    solid) against ``plain``'s (dashed), with their energies ``∫|u|² dt``; and the legs'
    speeds of ``fast`` (``plain`` re-timed in the least time under
    ``fast.options["leg_speed"]``, solid) against ``plain``'s (dashed), with the bound."""
    mech = catalog.get(plain.mechanism)
    fig = Figure(figsize=(12.0, 4.4), layout="constrained")
    left, right = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    for res, ls, what in ((plain, "--", "as planned"), (cheap, "-", "least energy")):
        t = np.linspace(0.0, res.T, 2001)
        u = res.controls(t)
        e = float(np.trapezoid(np.sum(u ** 2, axis=1), t))
        for j in range(u.shape[1]):
            left.plot(t, u[:, j], color=PAIR_COLORS[j], ls=ls, lw=1.4,
                      label=f"$u_{j + 1}$, {what} (∫|u|² dt = {e:.4f})" if j == 0 else f"$u_{j + 1}$")
    left.set_xlabel("time t [s]")
    left.set_ylabel("input u [1/s]")
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
    right.set_xlabel("time t [s]")
    right.set_ylabel("leg speed (geometry units / s)")
    right.legend(fontsize=8, loc="best")
    right.set_title(f"nonholo.retime(..., leg_speed={v:g}): the least time")
    fig.suptitle(title or f"{mech.name}: one path, its least energy and its least time", fontsize=11)
    return fig


@_styled
def example_overview_figure(results, title: str = "", geometry=None, tol: float | None = None,
                            threshold: float | None = 1e-2) -> Figure:
    """One example in a 2 × 3 grid: convergence, controls ``u_1, u_2`` [1/s] (scaled leg
    rates ``u_i = d(l_i²)/dt / (4ab)``), RPY angles, leg lengths, ``Δ(R(t))`` along the
    final trajectories, and the closest approach to ``Δ = 0`` of every iterate. Line
    style distinguishes the results; the title lists iterations, terminal error and
    ``min |Δ|`` of each."""
    results = _as_list(results)
    labels = _labels(results)
    fig = Figure(figsize=(16.0, 9.4), layout="constrained")
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


# --------------------------------------------------------------------------------------
# Animation
# --------------------------------------------------------------------------------------


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
    """Write a GIF of the platform moving along ``result.R`` (``frames`` frames at ``fps``).

    Each frame shows the mechanism (as in :func:`mechanism_figure`), the path of the body
    z axis' tip so far, the current time and ``Δ(R(t))``. Returns the path written.
    """
    from matplotlib.animation import FuncAnimation, PillowWriter

    if not _has_trajectory(result):
        raise ValueError("the result has no trajectory to animate")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    g = _geometry_for([result], geometry)
    if g is None:
        raise ValueError(f"mechanism {result.mechanism!r} has no legs/disk geometry to draw; "
                         "pass geometry=")
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
