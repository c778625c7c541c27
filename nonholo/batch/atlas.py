"""Atlases: maps over slices of the orientation space of how a planner fares from one start.

:func:`problems` lays goals on a grid of each RPY slice ``ψ = const`` — ``φ`` about z
across ``[−π, π)``, ``ϑ`` about y across ``(−π/2, π/2)``, cell centres — one problem per goal
and planner setting (:data:`SETTINGS`: the paper's algorithm, the robust strategy alone,
and the default ``plan()``), each labelled with its setting and angles (JSON). A sweep of
them (:func:`nonholo.batch.sweep.sweep`) is drawn by :func:`atlas_figure`: one panel per setting
and slice, coloured by success, iterations or time, over the singular set ``Δ = 0`` (black
line) with the start marked; goals across it (or within ``delta_min`` of it) are
unreachable and drawn grey.
"""
from __future__ import annotations

import json

import numpy as np
from matplotlib.colors import BoundaryNorm, ListedColormap, LogNorm
from matplotlib.figure import Figure

from ..model import catalog
from ..spaces import so3
from ..viz.singular_set import mechanism_delta_rpy

#: The planner settings an atlas compares: name → options of :func:`nonholo.plan`.
SETTINGS = {"paper": {"strategy": "paper", "route": "local"},
            "robust": {"strategy": "robust", "route": "local"},
            "default": {}}
#: The quantities :func:`atlas_figure` draws.
QUANTITIES = ("success", "iterations", "time")
#: Example 1's start (RPY, rad): the atlases' default.
START = (0.5, 1.2, -0.5)
#: Success map colours: solved, failed, unreachable.
_SUCCESS_COLORS = ("#2ca02c", "#d62728", "#d9d9d9")


def grid_angles(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The cell centres ``φ`` (``n``) and ``ϑ`` (``n``) of an ``n × n`` slice grid."""
    phi = -np.pi + (np.arange(n) + 0.5) * (2 * np.pi / n)
    theta = -np.pi / 2 + (np.arange(n) + 0.5) * (np.pi / n)
    return phi, theta


def problems(n: int = 31, psi=(START[2],), start=START, mechanism: str = "platform",
             settings=tuple(SETTINGS), options: dict | None = None) -> list[dict]:
    """The problems of an atlas (rows of :mod:`nonholo.io.problems`): from ``RPY(start)`` to every
    cell centre of an ``n × n`` grid of each slice ``ψ ∈ psi``, for every setting."""
    if not isinstance(n, int) or n < 2:
        raise ValueError(f"n must be an integer >= 2, got {n!r}")
    unknown = [s for s in settings if s not in SETTINGS]
    if unknown:
        raise ValueError(f"unknown setting {unknown[0]!r}; known: {', '.join(SETTINGS)}")
    R0 = so3.from_rpy(*start)
    phi, theta = grid_angles(n)
    rows = []
    for s in settings:
        for k, p in enumerate(psi):
            for j, th in enumerate(theta):
                for i, ph in enumerate(phi):
                    label = {"atlas": s, "slice": k, "i": i, "j": j, "n": n, "phi": float(ph),
                             "theta": float(th), "psi": float(p), "start": list(map(float, start))}
                    rows.append({"start": R0, "goal": so3.from_rpy(ph, th, p), "mechanism": mechanism,
                                 "options": {**(options or {}), **SETTINGS[s]},
                                 "label": json.dumps(label, separators=(",", ":"))})
    return rows


class Atlas:
    """The grids of one sweep of :func:`problems`: per setting and slice, ``n × n`` arrays of
    the outcome (``"solved"``/``"failed"``/``"unreachable"``), iterations and seconds."""

    def __init__(self, table):
        rows = table.to_pylist() if hasattr(table, "to_pylist") else list(table)
        labels = []
        for r in rows:
            try:
                labels.append(json.loads(r["label"] or ""))
            except ValueError:
                labels.append(None)
        keep = [(r, lab) for r, lab in zip(rows, labels) if isinstance(lab, dict) and "atlas" in lab]
        if not keep:
            raise ValueError("the results hold no atlas problems (labels written by nonholo.batch.atlas.problems)")
        first = keep[0][1]
        self.n, self.start = first["n"], tuple(first["start"])
        self.mechanism = keep[0][0]["mechanism"]
        self.settings = [s for s in SETTINGS if any(lab["atlas"] == s for _, lab in keep)]
        slices = sorted({(lab["slice"], lab["psi"]) for _, lab in keep})
        self.psi = [p for _, p in slices]
        shape = (len(self.settings), len(self.psi), self.n, self.n)
        self.outcome = np.full(shape, "", dtype=object)
        self.iterations = np.full(shape, np.nan)
        self.seconds = np.full(shape, np.nan)
        mech = catalog.get(self.mechanism)
        sign0 = np.sign(mech.delta(so3.from_rpy(*self.start))) if mech.singular.exists else 1.0
        for r, lab in keep:
            idx = (self.settings.index(lab["atlas"]), self.psi.index(lab["psi"]), lab["j"], lab["i"])
            problem = json.loads(r["problem"])
            dmin = problem["options"].get("delta_min", 1e-2)
            reachable = True
            if mech.singular.exists:
                d = float(mech.delta(np.array(problem["goal"])))
                reachable = np.sign(d) == sign0 and abs(d) >= dmin
            self.outcome[idx] = "solved" if r["success"] else ("failed" if reachable else "unreachable")
            self.iterations[idx] = r["iterations"]
            self.seconds[idx] = r["seconds"]

    def count(self, setting: str, outcome: str) -> int:
        return int(np.sum(self.outcome[self.settings.index(setting)] == outcome))


def atlas_figure(table, quantity: str = "success") -> Figure:
    """The atlas of a sweep of :func:`problems` (a ``pyarrow.Table`` or rows): one panel per
    setting (columns) and slice (rows), coloured by ``quantity`` (:data:`QUANTITIES`)."""
    if quantity not in QUANTITIES:
        raise ValueError(f"unknown quantity {quantity!r}; known: {', '.join(QUANTITIES)}")
    atlas = Atlas(table)
    rows, cols = len(atlas.psi), len(atlas.settings)
    fig = Figure(figsize=(4.6 * cols + 1.2, 3.4 * rows + 0.8), layout="constrained")
    axes = np.array(fig.subplots(rows, cols, squeeze=False, sharex=True, sharey=True))
    phi, theta = grid_angles(atlas.n)
    edges_phi = np.linspace(-np.pi, np.pi, atlas.n + 1)
    edges_theta = np.linspace(-np.pi / 2, np.pi / 2, atlas.n + 1)
    fine_phi, fine_theta = np.meshgrid(np.linspace(-np.pi, np.pi, 241), np.linspace(-np.pi / 2, np.pi / 2, 121))
    mesh = None
    for c, setting in enumerate(atlas.settings):
        for k, psi in enumerate(atlas.psi):
            ax = axes[k, c]
            outcome = atlas.outcome[c, k]
            unreachable = outcome == "unreachable"
            if quantity == "success":
                codes = np.select([outcome == "solved", outcome == "failed"], [0, 1], 2).astype(float)
                mesh = ax.pcolormesh(edges_phi, edges_theta, codes, cmap=ListedColormap(_SUCCESS_COLORS),
                                     norm=BoundaryNorm([-0.5, 0.5, 1.5, 2.5], 3))
            else:
                values = atlas.iterations[c, k] if quantity == "iterations" else 1e3 * atlas.seconds[c, k]
                values = np.where(unreachable, np.nan, values)
                finite = values[np.isfinite(values) & (values > 0)]
                norm = LogNorm(vmin=max(finite.min(), 1e-3), vmax=finite.max()) if finite.size else None
                ax.pcolormesh(edges_phi, edges_theta, np.where(unreachable, 1.0, np.nan),
                              cmap=ListedColormap([_SUCCESS_COLORS[2]]), vmin=0, vmax=2)
                mesh = ax.pcolormesh(edges_phi, edges_theta, np.where(values > 0, values, np.nan),
                                     cmap="viridis", norm=norm)
            if catalog.get(atlas.mechanism).singular.exists:
                D = mechanism_delta_rpy(atlas.mechanism, fine_phi, fine_theta, psi)
                ax.contour(fine_phi, fine_theta, D, levels=[0.0], colors="k", linewidths=1.6)
            if abs(psi - atlas.start[2]) < 1e-12:
                ax.plot(*atlas.start[:2], "o", color="k", mfc="yellow", ms=8, mew=1.2)
            solved = atlas.count(setting, "solved")
            reachable = solved + atlas.count(setting, "failed")
            ax.set_title(f"{setting}: ψ = {psi:+.2f}; solved {solved} of {reachable} reachable", fontsize=9)
            ax.set_xticks([-np.pi, -np.pi / 2, 0, np.pi / 2, np.pi], ["−π", "−π/2", "0", "π/2", "π"])
            ax.set_yticks([-np.pi / 2, 0, np.pi / 2], ["−π/2", "0", "π/2"])
            if k == rows - 1:
                ax.set_xlabel("goal φ (about z) [rad]")
            if c == 0:
                ax.set_ylabel("goal ϑ (about y) [rad]")
    if quantity == "success":
        cb = fig.colorbar(mesh, ax=axes, ticks=[0, 1, 2], shrink=0.8)
        cb.ax.set_yticklabels(["solved", "failed", "unreachable\n(across Δ = 0)"])
    elif mesh is not None:
        fig.colorbar(mesh, ax=axes, shrink=0.8,
                     label="accepted iterations" if quantity == "iterations" else "wall time [ms]")
    what = {"success": "which goals each planner solves", "iterations": "accepted iterations",
            "time": "wall time per plan"}[quantity]
    fig.suptitle(f"{atlas.mechanism}: {what}, from RPY{tuple(round(a, 3) for a in atlas.start)} (yellow "
                 f"dot), T = 1 s; black: Δ = 0", fontsize=11)
    return fig
