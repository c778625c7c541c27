"""The figure of one plan of any mechanism (:func:`plan_figure`; ``nonholo plan --plot``).

Against time, one axes per quantity: the inputs, the RPY angles of an orientation, the
coordinates (one axes per unit), ``Δ`` and, with legs, their lengths and speeds. A
vehicle (coordinates with a plane position, :func:`nonholo.viz.quantities.plane_position`)
gets its path on the plane to scale on the left. Names and units come from the
mechanism's data (:mod:`nonholo.viz.quantities`).
"""
from __future__ import annotations

import numpy as np

from ..model.names import ANGLES, NONE, RADIUS, RAD, SECOND, angle_label, per_second
from ..spaces import so3
from .platform_drawing import result_mechanism
from .quantities import coordinate_units, input_units, label, plane_position, unit_groups
from .style import NotebookFigure, styled

#: Height of one time axes (inches).
ROW_HEIGHT = 2.2


def error_text(result, mechanism, spec: str = ".2e") -> str:
    """The terminal error in words with its units.

    Parameters
    ----------
    result : PlanResult
        The plan.
    mechanism : Mechanism
        Its mechanism.
    spec : str
        The numbers' format spec.

    Returns
    -------
    str
        ``|l_T| = 2e-11 rad`` on SO(3), else by part (``rotation 1e-12 rad, coordinates
        3e-12 radius``).
    """
    space = mechanism.space
    if result.errors is None:
        return f"|l_T| = {space.amount(result.terminal_error, spec)}"
    return ", ".join(f"{part} {space.amount(value, spec, part)}" for part, value in result.errors.items())


def _mechanism(result):
    mech = result_mechanism(result)
    if mech is None:
        raise ValueError(f"result's mechanism {result.mechanism!r} is not in the catalog and the "
                         "result does not carry it")
    return mech


def plot_plane_path(ax, result, mechanism=None) -> None:
    """A vehicle's path on the plane, to scale: start, goal and, for a global route, the
    waypoints of its hops.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes drawn into.
    result : PlanResult
        The plan.
    mechanism : Mechanism, optional
        Its mechanism (default: the result's).

    Raises
    ------
    ValueError
        For a mechanism without a plane position, or one the result does not name in the
        catalog.
    """
    mech = _mechanism(result) if mechanism is None else mechanism
    plane = plane_position(mech)
    if plane is None:
        raise ValueError(f"mechanism {mech.name!r} has no position on a plane (two coordinates "
                         "that are not angles and share a unit)")
    i, j = plane
    units = coordinate_units(mech)
    if len(result.q):
        ax.plot(result.q[:, i], result.q[:, j], color="0.3", lw=1.5, label="path")
        ax.plot(result.q[0, i], result.q[0, j], "o", color="tab:green", ms=8, label="start")
    hops = getattr(result, "hops", None)
    waypoints = getattr(hops, "coordinates", None)
    if waypoints is not None and len(waypoints) > 2:
        ax.plot(waypoints[:, i], waypoints[:, j], "o--", ms=3, lw=0.8, color="tab:blue",
                label="waypoints of the hops")
    ax.plot(result.qd[i], result.qd[j], "x", color="tab:red", ms=10, mew=2, label="goal")
    ax.set_aspect("equal", adjustable="datalim")
    ax.margins(0.15)
    ax.set_xlabel(label(mech.coordinates[i], units[i]))
    ax.set_ylabel(label(mech.coordinates[j], units[j]))
    ax.set_title("path on the plane")
    ax.legend(fontsize=8, loc="best")


def _inputs(ax, result, mech) -> None:
    tt = np.linspace(0.0, result.T, 1001)
    u = result.controls(tt)
    units = input_units(mech)
    shared = len(set(units)) == 1
    for i in range(u.shape[1]):
        ax.plot(tt, u[:, i], label=mech.inputs[i] if shared else label(mech.inputs[i], units[i]))
    ax.set_ylabel(label("input u", units[0]) if shared else "inputs")
    ax.legend(fontsize="small")


def _rpy(ax, result) -> None:
    if len(result.R):
        rpy = np.array([so3.as_rpy(R) for R in result.R])
        goal = so3.as_rpy(result.Rd)
        for k, name in enumerate(angle_label(i, unit=False) for i in range(len(ANGLES))):
            line, = ax.plot(result.t, rpy[:, k], label=name)
            ax.axhline(goal[k], color=line.get_color(), ls=":", lw=0.8)
        ax.legend(fontsize="small", title="dotted: goal", title_fontsize="small")
    ax.set_ylabel(label("RPY angles", RAD))


def _coordinates(ax, result, mech, unit: str, indices) -> None:
    if len(result.q):
        for k in indices:
            line, = ax.plot(result.t, result.q[:, k], label=mech.coordinates[k])
            ax.axhline(result.qd[k], color=line.get_color(), ls=":", lw=0.8)
        ax.legend(fontsize="small", title="dotted: goal", title_fontsize="small")
    ax.set_ylabel(label(", ".join(mech.coordinates[k] for k in indices), unit))


def _delta(ax, result) -> None:
    ax.plot(result.t, result.delta, label="Δ at the integrator's steps")
    dmin = result.options.get("delta_min", 0.0)
    sgn = np.sign(result.delta[0]) if len(result.delta) else 1.0
    ax.axhline(sgn * dmin, color="r", ls="--", label=f"threshold {sgn * dmin:+g}")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_ylabel(label("Δ", NONE))
    ax.legend(fontsize="small")


def _legs(lengths_ax, speeds_ax, result, mech) -> None:
    lengths = mech.leg_lengths(result.R)
    for i in range(lengths.shape[1]):
        lengths_ax.plot(result.t, lengths[:, i], label=f"l{i + 1}")
    for k, y in enumerate(result.options.get("leg_length") or ()):
        lengths_ax.axhline(y, color="r", ls="--", label="stroke limits" if k == 0 else None)
    lengths_ax.set_ylabel(label("leg length", RADIUS))
    lengths_ax.legend(fontsize="small")
    speeds = mech.leg_speeds(result.R, result.u)
    for i in range(speeds.shape[1]):
        speeds_ax.plot(result.t, speeds[:, i], label=f"dl{i + 1}/dt")
    v = result.options.get("leg_speed")
    if v is not None:
        for k, y in enumerate((v, -v)):
            speeds_ax.axhline(y, color="r", ls="--", label="speed limit" if k == 0 else None)
    speeds_ax.axhline(0.0, color="k", lw=0.5)
    speeds_ax.set_ylabel(label("leg speed", per_second(RADIUS)))
    speeds_ax.legend(fontsize="small")


@styled
def plan_figure(result) -> NotebookFigure:
    """One plan of any mechanism at a glance: see the module. The title names the
    mechanism, method and strategy and the terminal error with its units.

    Parameters
    ----------
    result : PlanResult
        The plan (a :class:`~nonholo.io.result.PlanResult`).

    Returns
    -------
    NotebookFigure
        The figure.

    Raises
    ------
    ValueError
        If the result's mechanism is not in the catalog and it carries none.
    """
    mech = _mechanism(result)
    drawn = len(result.R) > 0
    groups = unit_groups(mech)
    panels = [("inputs",)]
    if mech.space.axes("rotation"):         # the rotation's numbers: its RPY angles
        panels.append(("rpy",))
    panels += [("coordinates", unit, indices) for unit, indices in groups]
    if result.delta is not None:
        panels.append(("delta",))
    if mech.has_legs and drawn:
        panels += [("lengths",), ("speeds",)]
    plane = plane_position(mech)
    rows = len(panels)
    width = 7.0 + (5.6 if plane else 0.0)
    fig = NotebookFigure(figsize=(width, max(ROW_HEIGHT * rows, 4.8)), layout="constrained")
    grid = fig.add_gridspec(rows, 2 if plane else 1, width_ratios=(1.0, 1.1) if plane else None)
    if plane:
        plot_plane_path(fig.add_subplot(grid[:, 0]), result, mech)
    column = 1 if plane else 0
    axes = []
    for r in range(rows):
        axes.append(fig.add_subplot(grid[r, column], sharex=axes[0] if axes else None))
    by_kind = {panel[0]: ax for panel, ax in zip(panels, axes)}
    for panel, ax in zip(panels, axes):
        kind = panel[0]
        if kind == "inputs":
            _inputs(ax, result, mech)
        elif kind == "rpy":
            _rpy(ax, result)
        elif kind == "coordinates":
            _coordinates(ax, result, mech, panel[1], panel[2])
        elif kind == "delta":
            _delta(ax, result)
        elif kind == "lengths":
            _legs(ax, by_kind["speeds"], result, mech)
    for ax in axes[:-1]:
        ax.tick_params(labelbottom=False)
    axes[-1].set_xlabel(label("time t", SECOND))
    fig.suptitle(f"{result.mechanism}, {result.method}/{result.strategy}: "
                 + error_text(result, mech, ".2e"))
    return fig
