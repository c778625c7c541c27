"""The platform's singular set ``Δ = 0`` in RPY coordinates ``R = R(Z, φ) R(Y, ϑ) R(X, ψ)``:
its points (:func:`singular_set_points`), ``Δ`` on angles (:func:`delta_rpy`,
:func:`mechanism_delta_rpy` for any mechanism), and the figures

- :func:`singular_set_figure` -- the surface ``Δ(φ, ϑ, ψ) = 0`` with the sign regions,
  and a slice ``ψ = const``;
- :func:`singular_slices_figure` -- several slices ``ψ = const``;
- :func:`normal_form_figure` -- the normal form ``z³ + x y = 0`` near the identity with the
  image of the actual singular set.
"""
from __future__ import annotations

import matplotlib
import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from mpl_toolkits.mplot3d.art3d import Poly3DCollection
from scipy.spatial.transform import Rotation

from ..generated import platform_singularity
from ..model import catalog
from ..model.names import NONE, angle_label, label
from .style import NEGATIVE_COLOR, POSITIVE_COLOR, NotebookFigure, styled


def delta_rpy(phi, theta, psi):
    """The platform's ``Δ(RPY(φ, ϑ, ψ))``, vectorised.

    Parameters
    ----------
    phi, theta, psi : array_like
        RPY angles (rad), broadcast together.

    Returns
    -------
    numpy.ndarray
        ``Δ``, of their broadcast shape.
    """
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

    Parameters
    ----------
    n_theta, n_psi : int
        Grid points of ``ϑ`` and ``ψ``.

    Returns
    -------
    tuple of numpy.ndarray
        ``(phi, theta, psi)``, each of shape ``(2, n_theta, n_psi)`` (the two sheets).
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


def draw_singular_surface(ax, n_theta=61, n_psi=121, cmap="viridis", alpha: float = 1.0):
    """Draw the two sheets of Δ = 0 as height φ over (ψ, ϑ) (axes x = ψ, y = ϑ, z = φ).

    Parameters
    ----------
    ax : mpl_toolkits.mplot3d.axes3d.Axes3D
        The 3D axes.
    n_theta, n_psi : int
        Grid points of ``ϑ`` and ``ψ`` (:func:`singular_set_points`).
    cmap : str
        The colour map of φ.
    alpha : float
        The sheets' opacity.
    """
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


PI_TICKS = ([-np.pi, -np.pi / 2, 0, np.pi / 2, np.pi], ["−π", "−π/2", "0", "π/2", "π"])
HALF_PI_TICKS = ([-np.pi / 2, 0, np.pi / 2], ["−π/2", "0", "π/2"])


def mechanism_delta_rpy(mechanism, phi, theta, psi) -> np.ndarray | None:
    """``Δ(RPY(φ, ϑ, ψ))`` of a mechanism on SO(3), on arrays of angles, evaluated on the
    whole stack of rotations at once (:meth:`~nonholo.spaces.singular.SingularSet.samples`).

    Parameters
    ----------
    mechanism : str or Mechanism
        The mechanism.
    phi, theta, psi : array_like
        RPY angles (rad), broadcast together.

    Returns
    -------
    numpy.ndarray or None
        ``Δ``, of their broadcast shape (``None`` without a singular set).
    """
    mech = catalog.get(mechanism)
    phi, theta, psi = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (phi, theta, psi)))
    R = Rotation.from_euler("ZYX", np.stack([phi, theta, psi], -1).reshape(-1, 3)).as_matrix()
    D = mech.singular.samples(R.reshape(-1, 3, 3))
    return None if D is None else D.reshape(phi.shape)


def draw_slice(ax, psi: float, n: int = 241, marks=None, mechanism: str = "platform"):
    """Draw ``Δ(φ, ϑ, ψ)`` on the slice ``ψ = psi``: colour = value, thick black = ``Δ = 0``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes drawn into.
    psi : float
        The slice (rad).
    n : int
        Grid points per axis.
    marks : dict, optional
        ``{label: (φ, ϑ, marker)}``, points drawn on the slice.
    mechanism : str
        The mechanism (another than the platform's ``Δ`` is scaled to ``[-1, 1]``).

    Returns
    -------
    matplotlib.contour.QuadContourSet or None
        The filled contours (for a colour bar); ``None``, nothing drawn, for a mechanism
        without a singular set.
    """
    F, T = np.meshgrid(np.linspace(-np.pi, np.pi, n), np.linspace(-np.pi / 2, np.pi / 2, n))
    if mechanism == "platform":
        D = delta_rpy(F, T, psi)
    else:
        D = mechanism_delta_rpy(mechanism, F, T, psi)
        if D is None:
            return None
        D = D / np.max(np.abs(D))  # the colour scale is [-1, 1]
    levels = np.linspace(-1.0, 1.0, 21)
    cs = ax.contourf(F, T, D, levels=levels, cmap="RdBu_r", vmin=-1.05, vmax=1.05)
    ax.contour(F, T, D, levels=levels[levels != 0], colors="k", linewidths=0.3, alpha=0.35)
    ax.contour(F, T, D, levels=[0.0], colors="k", linewidths=2.4)
    ax.set_xticks(*PI_TICKS)
    ax.set_yticks(*HALF_PI_TICKS)
    ax.set_xlabel(angle_label(0))
    ax.set_ylabel(angle_label(1))
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
    for name, (phi, th, mk) in (marks or {}).items():
        ax.plot(phi, th, mk, color="k", ms=7, mfc="yellow", mew=1.2, label=name)
    if marks:
        ax.legend(loc="lower left", framealpha=0.9)
    return cs


@styled
def singular_set_figure(psi_slice: float = -0.5, marks: dict | None = None,
                        view: dict | None = None) -> Figure:
    """The singular surface ``Δ = 0`` in RPY coordinates, and one slice of it.

    Left: the surface over ``φ, ψ ∈ [-π, π]``, ``ϑ ∈ [-π/2, π/2]``, drawn as the two
    sheets ``φ = φ_0(ϑ, ψ)`` and ``φ_0 + π`` (see :func:`singular_set_points`; φ upwards,
    coloured by φ), with the sign of Δ painted on three faces of the box (red: Δ > 0,
    blue: Δ < 0; the surface meets them along the thin black curves) and the outline
    of the slice plane ``ψ = psi_slice``. Right: ``Δ(φ, ϑ, psi_slice)`` with ``Δ = 0`` thick.

    Parameters
    ----------
    psi_slice : float
        The slice (rad).
    marks : dict, optional
        ``{label: (φ, ϑ, marker)}``, points drawn on the slice.
    view : dict, optional
        ``elev``/``azim`` of the 3D panel in degrees.

    Returns
    -------
    NotebookFigure
        The figure.
    """
    fig = NotebookFigure(figsize=(12.5, 5.6), layout="constrained")
    gs = fig.add_gridspec(1, 2, width_ratios=[1.25, 1.0])
    ax = fig.add_subplot(gs[0], projection="3d")
    _draw_sign_walls(ax)
    draw_singular_surface(ax)
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
    ax.set_xticks(PI_TICKS[0], PI_TICKS[1][:-1] + [""])  # π would collide with ϑ's −π/2
    ax.set_yticks(*HALF_PI_TICKS)
    ax.set_zticks(*PI_TICKS)
    ax.set_xlabel(angle_label(2))
    ax.set_ylabel(angle_label(1))
    ax.zaxis.set_rotate_label(True)
    ax.set_zlabel(angle_label(0))
    ax.set_box_aspect((2, 1, 2), zoom=0.88)
    v = {"elev": 35.0, "azim": -60.0, **(view or {})}
    ax.view_init(**v)
    ax.set_title("singular surface Δ(φ, ϑ, ψ) = 0")
    ax.legend(handles=[Patch(color=POSITIVE_COLOR, alpha=0.6, label="Δ > 0 (on the walls)"),
                       Patch(color=NEGATIVE_COLOR, alpha=0.6, label="Δ < 0 (on the walls)"),
                       Line2D([], [], color="k", ls="--", lw=1, label=f"slice ψ = {psi_slice:+.2f} (right)")],
              loc="upper left", bbox_to_anchor=(-0.02, 1.0), framealpha=0.9)
    ax2 = fig.add_subplot(gs[1])
    cs = draw_slice(ax2, psi_slice, marks=marks)
    cb = fig.colorbar(cs, ax=ax2, shrink=0.9, ticks=np.linspace(-1, 1, 5))
    cb.set_label(label("Δ", NONE))
    fig.suptitle("Singular set of the platform, RPY(φ, ϑ, ψ) = R(Z, φ) R(Y, ϑ) R(X, ψ)")
    return fig


def singular_slices_figure(psi_values=(-2.0, -0.5, 0.5, 2.0), marks: dict | None = None) -> Figure:
    """``Δ(φ, ϑ, ψ)`` on slices ``ψ = const``: colour = value (red Δ > 0, blue Δ < 0),
    thick black = ``Δ = 0``.

    Parameters
    ----------
    psi_values : sequence of float
        The slices (rad).
    marks : dict, optional
        ``{label: (φ, ϑ, ψ, marker)}``, drawn on the slice whose ψ is nearest.

    Returns
    -------
    NotebookFigure
        The figure.
    """
    psi_values = list(psi_values)
    ncols = min(len(psi_values), 2 if len(psi_values) == 4 else 3)
    nrows = -(-len(psi_values) // ncols)
    fig = NotebookFigure(figsize=(5.0 * ncols + 0.8, 3.4 * nrows + 0.5), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False)
    cs = None
    for k, ax in enumerate(axes.flat):
        if k >= len(psi_values):
            ax.set_visible(False)
            continue
        psi = psi_values[k]
        here = {}
        for name, (phi, th, ps, mk) in (marks or {}).items():
            if int(np.argmin([abs(ps - p) for p in psi_values])) == k:
                here[name] = (phi, th, mk)
        cs = draw_slice(ax, psi, n=181, marks=here)
    cb = fig.colorbar(cs, ax=axes, shrink=0.9, ticks=np.linspace(-1, 1, 5))
    cb.set_label(label("Δ", NONE))
    fig.suptitle("Δ(φ, ϑ, ψ) on slices ψ = const (thick: Δ = 0)")
    return fig


def normal_form_surface(n: int = 81, extent: float = 1.0):
    """The surface ``z³ + x y = 0`` as the graph ``z = -∛(x y)`` over ``[-extent, extent]²``.

    Parameters
    ----------
    n : int
        Grid points per axis.
    extent : float
        Half-width of the square.

    Returns
    -------
    tuple of numpy.ndarray
        ``(x, y, z)``, each of shape ``(n, n)``.
    """
    x, y = np.meshgrid(np.linspace(-extent, extent, n), np.linspace(-extent, extent, n))
    return x, y, -np.cbrt(x * y)


def normal_form_image(radius: float = 0.6, n: int = 61):
    """Normal-form coordinates ``(x, y, z)`` of points of ``Δ = 0`` near the identity.

    The points are those of :func:`singular_set_points` (``n`` values of ϑ, ``2n`` of ψ)
    and of the line ``ϑ = ψ = 0`` with ``|φ|, |ϑ|, |ψ| ≤ radius``, mapped by ``platform_singularity.normal_form``.

    Parameters
    ----------
    radius : float
        The largest ``|φ|, |ϑ|, |ψ|`` (rad).
    n : int
        Values of ϑ (and half the values of ψ) of the grid.

    Returns
    -------
    tuple of numpy.ndarray
        ``(rpy, xyz)``, each (k, 3).
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


@styled
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

    Parameters
    ----------
    extent : float
        Half-width of the square of ``(x, y)``.
    radius : float
        The largest ``|φ|, |ϑ|, |ψ|`` of the points mapped (rad).
    view : dict, optional
        ``elev``/``azim`` of the 3D panel in degrees.

    Returns
    -------
    NotebookFigure
        The figure.
    """
    fig = NotebookFigure(figsize=(12.5, 5.6), layout="constrained")
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
    ax.set_xlabel(label("x", NONE))
    ax.set_ylabel(label("y", NONE))
    ax.zaxis.set_rotate_label(False)
    ax.set_zlabel(label("z", NONE), rotation=0, labelpad=8)
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
    ax2.set_xlabel(label("x", NONE))
    ax2.set_ylabel(label("y", NONE))
    ax2.set_title("level curves z = const of z³ + x y = 0")
    ax2.legend(loc="center left", bbox_to_anchor=(1.02, 0.5), framealpha=0.9)
    fig.suptitle("Normal form of the singular set at the identity: Δ = z³ + x y "
                 "(an A2 surface singularity)")
    return fig
