"""The figure of a plan played on a physics model (:func:`nonholo.physics.execution.execute`).

:func:`execution_figure` takes an :class:`~nonholo.physics.execution_record.Execution` with its
traces (the samples kept by a run; a record loaded from a file has none) and draws four
panels: the error from the goal after each stage on a log scale (its parts: rotation,
coordinates; a touch-up not played, hollow, at the error it left unchanged), the simulated
state's distance from the played plan along each played stage's
motion, the motion itself (the first two coordinates in the plane where the state has them,
else the RPY angles against time), planned and simulated, and the slip at the rolling
contacts along each stage, a speed in the mechanism's length unit per second. Names and
units come from :mod:`nonholo.model.names`.
"""
from __future__ import annotations

import numpy as np

from ..model.names import RAD, SECOND, angle_label, length_unit, per_second
from ..spaces import so3
from .quantities import coordinate_units, label
from .style import RESULT_COLORS, TRIPLE_COLORS, NotebookFigure, styled

#: Errors and distances below this are drawn at it (a log axis has no zero).
FLOOR = 1e-16


def stage_names(n: int) -> list[str]:
    """``["open loop", "touch-up 1", …]`` for ``n`` stages.

    Parameters
    ----------
    n : int
        The number of stages.

    Returns
    -------
    list of str
        The stages' names.
    """
    return ["open loop"] + [f"touch-up {i}" for i in range(1, n)]


def tracking_distance(mechanism, trace: dict) -> dict:
    """The simulated state's distance from the played plan at each sample, by part.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism played.
    trace : dict
        One stage's samples (``R``, ``q``, ``R_planned``, ``q_planned``).

    Returns
    -------
    dict
        ``{part: array}`` with the parts of ``mechanism.space.error`` (``rotation`` in
        rad, ``coordinates`` in the mechanism's units).
    """
    rows = [mechanism.space.error((R, q), (Rp, qp))[1]
            for R, q, Rp, qp in zip(trace["R"], trace["q"], trace["R_planned"], trace["q_planned"])]
    return {part: np.array([r[part] for r in rows], dtype=float) for part in rows[0]}


@styled
def default_title(name: str, stages: list) -> str:
    """What a run did, in a line: the stages played, and how the last one not played ended.

    Parameters
    ----------
    name : str
        The mechanism's name.
    stages : list of dict
        The run's stages (:class:`~nonholo.physics.execution_record.Execution`).

    Returns
    -------
    str
        E.g. ``"car on its physics model: open loop and 2 touch-ups; touch-up 3 not played
        (within tolerance)"``.
    """
    outcomes = [s.get("outcome", "played") for s in stages]
    touched = sum(o == "played" for o in outcomes[1:])
    head = f"{name} on its physics model: open loop"
    if outcomes[0] != "played":
        return f"{head} {outcomes[0]}"
    head += f" and {touched} touch-up" + ("" if touched == 1 else "s") if touched else ""
    last = outcomes[-1]
    if last == "played":
        return head
    if last == "unstable":
        return f"{head}; the simulation went unstable in touch-up {len(outcomes) - 1}"
    return f"{head}; touch-up {len(outcomes) - 1} not played ({last})"


def execution_figure(execution, title: str | None = None) -> NotebookFigure:
    """Errors per stage, tracking, the motion and the slip of a played plan (module docstring).

    Parameters
    ----------
    execution : Execution
        A run of :func:`nonholo.physics.execution.execute`, with its traces.
    title : str, optional
        The figure's title (default: the mechanism and the number of touch-ups).

    Returns
    -------
    NotebookFigure
        The figure.

    Raises
    ------
    ValueError
        If ``execution`` has no traces (a record read back from a file) or no stage.
    """
    traces = getattr(execution, "traces", None)
    if not traces or traces[0] is None:
        raise ValueError("execution has no traces to draw (a record loaded from a file keeps only "
                         "its numbers): draw the figure from the run itself")
    mech = execution.kinematics
    stages = execution.stages
    names = stage_names(len(stages))
    fig = NotebookFigure(figsize=(10.5, 7.2))
    grid = fig.add_gridspec(2, 2)

    ax = fig.add_subplot(grid[0, 0])
    parts = list(stages[0]["error"])
    x = np.arange(len(stages))
    played = np.array([s.get("outcome", "played") == "played" for s in stages])
    units = {part: mech.space.part_unit(part) for part in parts}
    names_of = {part: label(part, unit) for part, unit in units.items()}
    shared = units[parts[0]] if len(set(units.values())) == 1 else ""   # one unit: on the axis too
    for j, part in enumerate(parts):
        values = np.maximum([s["error"][part] for s in stages], FLOOR)
        ax.semilogy(x, values, "-", color=RESULT_COLORS[j], label=names_of[part])
        ax.semilogy(x[played], values[played], "o", color=RESULT_COLORS[j])
        ax.semilogy(x[~played], values[~played], "o", mfc="none", color=RESULT_COLORS[j],
                    label="not played" if j == len(parts) - 1 and not played.all() else None)
    ticks = [f"{name}\n({s['outcome']})" if not p else name for name, s, p in zip(names, stages, played)]
    ax.set_xticks(x, ticks, rotation=20 if len(stages) > 3 else 0)
    ax.set_ylabel(label("error from the goal", shared))
    ax.set_title("after each stage (at rest)")
    ax.legend(fontsize=8)

    ax = fig.add_subplot(grid[0, 1])
    offset = 0.0
    for i, trace in enumerate(traces):
        if trace is None:
            continue
        distance = tracking_distance(mech, trace)
        for j, part in enumerate(parts):
            ax.semilogy(offset + trace["t"], np.maximum(distance[part], FLOOR), color=RESULT_COLORS[j],
                        lw=1.0, label=names_of[part] if i == 0 else None)
        if i:
            ax.axvline(offset, color="0.5", lw=0.8, ls=":")
        offset += trace["t"][-1]
    ax.set_xlabel(label("time, stages one after another", SECOND))
    ax.set_ylabel(label("simulated − played plan", shared))
    ax.set_title("tracking along the motion")
    ax.legend(fontsize=8)

    ax = fig.add_subplot(grid[1, 0])
    first = traces[0]
    if len(mech.space.axes("coordinates")) >= 2:
        cu = coordinate_units(mech)
        ax.plot(first["q_planned"][:, 0], first["q_planned"][:, 1], "--", color="0.3", label="plan")
        ax.plot(first["q"][:, 0], first["q"][:, 1], color=RESULT_COLORS[0], lw=1.2, label="simulated")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(label(mech.coordinates[0], cu[0]))
        ax.set_ylabel(label(mech.coordinates[1], cu[1]))
    else:
        planned, simulated = so3.as_rpy(first["R_planned"]), so3.as_rpy(first["R"])
        for j, (colour, name) in enumerate(zip(TRIPLE_COLORS, (angle_label(k, unit=False) for k in range(3)))):
            ax.plot(first["t"], planned[:, j], "--", color=colour, lw=1.0)
            ax.plot(first["t"], simulated[:, j], color=colour, lw=1.2, label=name)
        ax.set_xlabel(label("time t", SECOND))
        ax.set_ylabel(label("RPY angle", RAD))
    ax.set_title("open loop: plan (dashed) and simulated")
    ax.legend(fontsize=8)

    ax = fig.add_subplot(grid[1, 1])
    offset = 0.0
    for i, trace in enumerate(traces):
        if trace is None:
            continue
        ax.semilogy(offset + trace["t"], np.maximum(trace["slip"], FLOOR), color=RESULT_COLORS[i % len(RESULT_COLORS)],
                    lw=1.0, label=names[i])
        offset += trace["t"][-1]
    ax.set_xlabel(label("time, stages one after another", SECOND))
    length = length_unit(mech)
    ax.set_ylabel(label("slip speed at the contacts", per_second(length) if length else ""))
    ax.set_title("slip")
    ax.legend(fontsize=8)

    fig.suptitle(title or default_title(mech.name, stages))
    fig.tight_layout()
    return fig
