"""Atlases: maps over two coordinates of the goal of how a planner fares from one start.

:func:`problems` lays goals on an ``n × n`` grid (cell centres) over two of the numbers of a
state of the mechanism's space (its command-line numbers,
:attr:`nonholo.spaces.product.Product.cli_names`: the RPY angles ``φ, ϑ, ψ`` with an
orientation, then the coordinates), the goal's other numbers those of the start:

- on SO(3) (the default axes ``φ, ϑ``): the RPY slices ``ψ = const`` — ``φ`` about z across
  ``[−π, π)``, ``ϑ`` about y across ``(−π/2, π/2)``, one slice per value of ``psi``;
- on ``Rᵏ`` (default: the first two coordinates), e.g. the car's goal position ``(x, y)``:
  angle coordinates across ``[−π, π)``, others across the space's sampling box
  ``[−box, box]`` (:attr:`nonholo.spaces.euclidean.Euclidean.box`), or any ``extent``;
- on ``SO(3) × Rᵏ`` either, or one angle and one coordinate.

One problem per goal and planner setting (:data:`SETTINGS`: the paper's algorithm, the
robust strategy alone, and the default ``plan()``), each labelled with its setting, axes
and goal (JSON). A sweep of them (:func:`nonholo.batch.sweep.sweep`) is drawn by
:func:`atlas_figure`: one panel per setting and slice, coloured by success, iterations or
time, over the singular set ``Δ = 0`` (black line, where a slice crosses it) with the
start marked; goals across it (or within ``delta_min`` of it) are unreachable and drawn
grey.
"""
from __future__ import annotations

import json

import numpy as np
from matplotlib.colors import BoundaryNorm, ListedColormap, LogNorm
from matplotlib.figure import Figure

from ..io.problems import row_mechanism
from ..model import catalog, definition_forms
from ..model.names import MILLISECOND, label
from ..spaces import SO3
from ..viz.style import NotebookFigure

#: The planner settings an atlas compares: name → options of :func:`nonholo.plan`.
SETTINGS = {"paper": {"strategy": "paper", "route": "local"},
            "robust": {"strategy": "robust", "route": "local"},
            "default": {}}
#: The most problems an atlas may hold (``n² × slices × settings``): each is a plan of about
#: a second, and its rows are built in memory; 31 × 31 × 3 (the default) is 2883.
MAX_PROBLEMS = 100_000
#: The quantities :func:`atlas_figure` draws.
QUANTITIES = ("success", "iterations", "time")
#: Example 1's start (RPY, rad): the atlases' default orientation (coordinates default to 0).
START = (0.5, 1.2, -0.5)
#: ASCII names of the RPY angles (``--axes phi theta``), for a space with an orientation.
ALIASES = {alias: axis.name for axis in SO3().axes() for alias in axis.aliases}
#: The RPY angles' ranges (rad).
RPY_RANGES = {axis.name: axis.bounds for axis in SO3().axes()}
#: Success map colours: solved, failed, unreachable.
_SUCCESS_COLORS = ("#2ca02c", "#d62728", "#d9d9d9")
_PI_TICKS = {(-np.pi, np.pi): ([-np.pi, -np.pi / 2, 0, np.pi / 2, np.pi], ["−π", "−π/2", "0", "π/2", "π"]),
             (-np.pi / 2, np.pi / 2): ([-np.pi / 2, 0, np.pi / 2], ["−π/2", "0", "π/2"])}


class BadArgument(ValueError):
    """A bad argument of :func:`problems`.

    Parameters
    ----------
    argument : str
        Its name.
    detail : str
        Why it is bad; the message is ``"<argument> <detail>"``.
    """

    def __init__(self, argument: str, detail: str):
        super().__init__(f"{argument} {detail}")
        self.argument, self.detail = argument, detail


def grid_angles(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The cell centres of an ``n × n`` RPY slice grid.

    Parameters
    ----------
    n : int
        Cells per axis.

    Returns
    -------
    tuple of numpy.ndarray
        ``φ`` and ``ϑ`` (rad), ``n`` each.
    """
    return cell_centres(n, RPY_RANGES["φ"]), cell_centres(n, RPY_RANGES["ϑ"])


def cell_centres(n: int, bounds) -> np.ndarray:
    """The centres of ``n`` equal cells across an interval.

    Parameters
    ----------
    n : int
        The number of cells.
    bounds : tuple of float
        ``(lo, hi)``.

    Returns
    -------
    numpy.ndarray
        The ``n`` centres.
    """
    lo, hi = bounds
    return lo + (np.arange(n) + 0.5) * ((hi - lo) / n)


def default_start(space) -> tuple[float, ...]:
    """The atlases' default start as command-line numbers.

    Parameters
    ----------
    space : Product
        The mechanism's state space.

    Returns
    -------
    tuple of float
        Example 1's RPY angles with an orientation, the coordinates 0.
    """
    return tuple(space.numbers(rotation=START).tolist())


def default_axes(space) -> tuple[str, str]:
    """The atlases' default axes.

    Parameters
    ----------
    space : Product
        The mechanism's state space.

    Returns
    -------
    tuple of str
        ``φ, ϑ`` with an orientation, else the first two coordinates.
    """
    return tuple(space.cli_names[:2])


def axis_range(space, name: str) -> tuple[float, float]:
    """The default range of one of the goal's numbers.

    Parameters
    ----------
    space : Product
        The mechanism's state space.
    name : str
        The number's name (:func:`resolve_axis`).

    Returns
    -------
    tuple of float
        :data:`RPY_RANGES`, ``[−π, π)`` for an angle coordinate, ``[−box, box]`` for
        another.
    """
    return space.axis(name).bounds


def resolve_axis(space, name: str) -> str:
    """An axis' name as one of the space's :attr:`~nonholo.spaces.product.Product.cli_names`.

    Parameters
    ----------
    space : Product
        The mechanism's state space.
    name : str
        The name (ASCII ``phi``/``theta``/``psi`` accepted for the RPY angles).

    Returns
    -------
    str
        The space's name of that number.

    Raises
    ------
    BadArgument
        Naming ``axes``, if ``name`` is not one of the state's numbers.
    """
    try:
        return space.axis(name).name
    except ValueError:
        raise BadArgument("axes", f"must be two of the state's numbers ({' '.join(space.cli_names)}), "
                                  f"got {name!r}") from None


def problems(n: int = 31, psi=None, start=None, mechanism="platform",
             settings=tuple(SETTINGS), options: dict | None = None, *, axes=None, extent=None) -> list[dict]:
    """The problems of an atlas: from ``start`` to every cell centre of an ``n × n`` grid
    over the goal's numbers ``axes``, for every setting.

    Parameters
    ----------
    n : int
        Cells per axis, ``≥ 2``, with at most :data:`MAX_PROBLEMS` problems in all.
    psi : sequence of float, optional
        The slices ``ψ = const`` (rad), with an orientation and ``ψ`` off the axes
        (default: the start's ψ).
    start : sequence of float, optional
        The start's command-line numbers (RPY angles in rad, then the coordinates; default
        :func:`default_start`); the goal's numbers off the axes are the start's.
    mechanism : str or Mechanism
        The mechanism: a name, a mechanism file (``.toml``) or a
        :class:`~nonholo.model.mechanism.Mechanism` (:func:`nonholo.model.catalog.resolve`).
    settings : sequence of str
        Keys of :data:`SETTINGS`.
    options : dict, optional
        Options of :func:`nonholo.plan` for every problem (a setting's own win).
    axes : sequence of str, optional
        Two of the space's numbers (default :func:`default_axes`).
    extent : sequence of float, optional
        ``(lo, hi, lo, hi)`` of the two axes (default :func:`axis_range`).

    Returns
    -------
    list of dict
        Rows of :mod:`nonholo.io.problems`, each labelled with its setting, axes and goal
        (JSON).

    Raises
    ------
    BadArgument
        A ``ValueError`` naming the bad argument.
    """
    if not isinstance(n, int) or isinstance(n, bool) or n < 2:
        raise BadArgument("n", f"must be an integer >= 2, got {n!r}")
    unknown = [s for s in settings if s not in SETTINGS]
    if unknown:
        raise BadArgument("settings", f"has an unknown setting {unknown[0]!r}; known: {', '.join(SETTINGS)}")
    if isinstance(mechanism, str) and not mechanism.lower().endswith(".toml") and mechanism not in catalog.names():
        raise BadArgument("mechanism", f"must be one of {', '.join(catalog.names())} or a mechanism file (.toml), "
                                       f"got {mechanism!r}")
    try:
        mech = catalog.resolve(mechanism)
    except ValueError as exc:
        raise BadArgument("mechanism", f"refused: {exc}") from None
    # the rows name a catalog mechanism, or hold another's definition (data the workers rebuild it from)
    in_rows = mech.name if mech.definition is None else definition_forms.json_data(mech.definition)
    mechanism = mech.name
    space = mech.space
    names = space.cli_names
    if start is None:
        start = default_start(space)
    start = np.asarray(start, dtype=float)
    if start.shape != (len(names),) or not np.all(np.isfinite(start)):
        raise BadArgument("start", f"must be the {len(names)} finite numbers of a state of {mechanism} "
                                   f"({' '.join(names)}), got {start.tolist()}")
    axes = default_axes(space) if axes is None else tuple(axes)
    if len(axes) != 2:
        raise BadArgument("axes", f"must be two of the state's numbers ({' '.join(names)}), got {len(axes)}")
    axes = tuple(resolve_axis(space, a) for a in axes)
    if axes[0] == axes[1]:
        raise BadArgument("axes", f"must be two different numbers, got {axes[0]!r} twice")
    if extent is None:
        bounds = [axis_range(space, a) for a in axes]
    else:
        values = np.asarray(extent, dtype=float)
        if values.shape != (4,) or not np.all(np.isfinite(values)):
            raise BadArgument("extent", f"must be four finite numbers LO HI LO HI, got {list(extent)}")
        bounds = [(float(values[0]), float(values[1])), (float(values[2]), float(values[3]))]
        for a, (lo, hi) in zip(axes, bounds):
            if not lo < hi:
                raise BadArgument("extent", f"of axis {a} must have LO < HI, got {lo:g} {hi:g}")
    # slices ψ = const of an orientation: its ψ, where the state has one, off the axes
    psi_at = names.index("ψ") if "ψ" in names else None
    slicing = psi_at is not None and "ψ" not in axes
    if psi is None:
        psi = (float(start[psi_at]),) if slicing else (None,)
    elif psi_at is None:
        raise BadArgument("psi", f"takes slices ψ = const of an orientation: {mechanism} has none")
    elif not slicing:
        raise BadArgument("psi", "takes slices ψ = const: not with ψ as an axis")
    else:
        psi = tuple(float(p) for p in psi)
        if not psi or not np.all(np.isfinite(psi)):
            raise BadArgument("psi", f"must be finite angles (rad), got {list(psi)}")
    count = n * n * len(psi) * len(settings)
    if count > MAX_PROBLEMS:
        raise BadArgument("n", f"= {n} makes {count:,} problems ({n}² goals × {len(psi)} slice"
                               f"{'s' * (len(psi) != 1)} × {len(settings)} setting{'s' * (len(settings) != 1)}), "
                               f"more than MAX_PROBLEMS = {MAX_PROBLEMS:,}: lower it")
    which = [names.index(a) for a in axes]
    centres = [cell_centres(n, b) for b in bounds]
    R0, q0 = space.from_cli(start)
    first = space.public((R0, q0))
    rows = []
    for s in settings:
        for k, p in enumerate(psi):
            for j, y in enumerate(centres[1]):
                for i, x in enumerate(centres[0]):
                    goal = start.copy()
                    if p is not None:
                        goal[psi_at] = p
                    goal[which] = (x, y)
                    label = {"atlas": s, "slice": k, "i": i, "j": j, "n": n, "axes": list(axes),
                             "extent": [float(v) for b in bounds for v in b], "goal": goal.tolist(),
                             "start": start.tolist(), **({} if p is None else {"psi": p})}
                    rows.append({"start": first, "goal": space.public(space.from_cli(goal)),
                                 "mechanism": in_rows, "options": {**(options or {}), **SETTINGS[s]},
                                 "label": json.dumps(label, separators=(",", ":"))})
    return rows


class Atlas:
    """The grids of one sweep of :func:`problems`: per setting and slice, ``n × n`` arrays of
    the outcome (``"solved"``/``"failed"``/``"unreachable"``), iterations and seconds;
    ``axes``, ``extent``, ``start`` (command-line numbers), ``slices`` (the ψ of each slice,
    ``None`` without) and ``goals`` (each slice's goal numbers off the grid's cells).

    Parameters
    ----------
    table : pyarrow.Table or iterable of dict
        The sweep's results (:func:`nonholo.batch.sweep.sweep`).

    Raises
    ------
    ValueError
        If the results hold no atlas problems.
    """

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
        self.kinematics = mech = _row_mechanism(keep[0][0], rows.index(keep[0][0]))
        self.space = space = mech.space
        # labels without axes: an RPY slice atlas
        self.axes = tuple(first.get("axes", ("φ", "ϑ")))
        extent = first.get("extent") or [v for a in self.axes for v in axis_range(space, a)]
        self.extent = tuple(float(v) for v in extent)
        self.settings = [s for s in SETTINGS if any(lab["atlas"] == s for _, lab in keep)]
        slices = sorted({(lab["slice"], lab.get("psi")) for _, lab in keep}, key=lambda x: x[0])
        self.slices = [p for _, p in slices]
        shape = (len(self.settings), len(self.slices), self.n, self.n)
        self.outcome = np.full(shape, "", dtype=object)
        self.iterations = np.full(shape, np.nan)
        self.seconds = np.full(shape, np.nan)
        self.goals = [None] * len(self.slices)
        singular = mech.singular
        sign0 = singular.sign(*space.from_cli(self.start))
        for r, lab in keep:
            k = [key for key, _ in slices].index(lab["slice"])
            idx = (self.settings.index(lab["atlas"]), k, lab["j"], lab["i"])
            problem = json.loads(r["problem"])
            if self.goals[k] is None:
                self.goals[k] = tuple(lab["goal"]) if "goal" in lab else (lab["phi"], lab["theta"], lab["psi"])
            dmin = problem["options"].get("delta_min", 1e-2)
            d = singular.value(*space.from_json(problem["goal"], "goal"))
            reachable = np.sign(d) == sign0 and abs(d) >= dmin
            self.outcome[idx] = "solved" if r["success"] else ("failed" if reachable else "unreachable")
            self.iterations[idx] = r["iterations"]
            self.seconds[idx] = r["seconds"]

    def count(self, setting: str, outcome: str) -> int:
        """The number of goals of an outcome for a setting, over every slice.

        Parameters
        ----------
        setting : str
            One of the atlas's ``settings``.
        outcome : {"solved", "failed", "unreachable"}
            The outcome.

        Returns
        -------
        int
            The count.
        """
        return int(np.sum(self.outcome[self.settings.index(setting)] == outcome))

    def holds_start(self, k: int) -> bool:
        """Whether a slice passes through the start (its goals off the axes are the start's).

        Parameters
        ----------
        k : int
            The slice.

        Returns
        -------
        bool
            Whether it does.
        """
        names = self.space.cli_names
        off = [c for c, name in enumerate(names) if name not in self.axes]
        return all(abs(self.goals[k][c] - self.start[c]) < 1e-12 for c in off)

    def describe_start(self) -> str:
        """The start in words.

        Returns
        -------
        str
            ``RPY(φ, ϑ, ψ)`` and/or ``(x, y, …) = (…)``.
        """
        return self.space.describe_numbers(self.start)

    def singular_values(self, k: int, x, y) -> np.ndarray:
        """``Δ`` over the goals of a slice.

        Parameters
        ----------
        k : int
            The slice.
        x, y : numpy.ndarray
            Values of the two axes, of one shape.

        Returns
        -------
        numpy.ndarray
            ``Δ``, of their shape.
        """
        names = self.space.cli_names
        numbers = np.broadcast_to(np.asarray(self.goals[k], dtype=float), x.shape + (len(names),)).copy()
        numbers[..., names.index(self.axes[0])] = x
        numbers[..., names.index(self.axes[1])] = y
        R, q = self.space.from_cli_many(numbers.reshape(-1, len(names)))
        D = self.kinematics.singular.values(R, q)
        return np.asarray(D, dtype=float).reshape(x.shape)


def _row_mechanism(row: dict, index: int):
    """The mechanism of the results row ``index`` (:func:`nonholo.io.problems.row_mechanism`):
    the catalog's of its name, else the one its ``problem`` holds the definition of."""
    value = row["mechanism"]
    if value not in catalog.names():
        try:
            given = json.loads(row.get("problem") or "{}").get("mechanism")
        except (ValueError, AttributeError):
            given = None
        if isinstance(given, dict):
            value = given
    return row_mechanism(value, index)


def _axis_text(space, name: str) -> str:
    axis = space.axis(name)
    return label(f"goal {axis.text}", axis.unit)


def atlas_figure(table, quantity: str = "success") -> Figure:
    """The atlas of a sweep of :func:`problems`: one panel per setting (columns) and slice
    (rows).

    Parameters
    ----------
    table : pyarrow.Table or iterable of dict
        The sweep's results.
    quantity : str
        What colours the cells, one of :data:`QUANTITIES`.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.

    Raises
    ------
    ValueError
        For an unknown ``quantity``, or results that hold no atlas problems.
    """
    if quantity not in QUANTITIES:
        raise ValueError(f"unknown quantity {quantity!r}; known: {', '.join(QUANTITIES)}")
    atlas = Atlas(table)
    space = atlas.space
    rows, cols = len(atlas.slices), len(atlas.settings)
    fig = NotebookFigure(figsize=(4.6 * cols + 1.2, 3.4 * rows + 0.8), layout="constrained")
    axes = np.array(fig.subplots(rows, cols, squeeze=False, sharex=True, sharey=True))
    bx, by = atlas.extent[:2], atlas.extent[2:]
    edges_x = np.linspace(*bx, atlas.n + 1)
    edges_y = np.linspace(*by, atlas.n + 1)
    fine_x, fine_y = np.meshgrid(np.linspace(*bx, 241), np.linspace(*by, 121))
    which = [space.cli_names.index(a) for a in atlas.axes]
    mesh, crossed = None, False
    for c, setting in enumerate(atlas.settings):
        for k, psi in enumerate(atlas.slices):
            ax = axes[k, c]
            outcome = atlas.outcome[c, k]
            unreachable = outcome == "unreachable"
            if quantity == "success":
                codes = np.select([outcome == "solved", outcome == "failed"], [0, 1], 2).astype(float)
                mesh = ax.pcolormesh(edges_x, edges_y, codes, cmap=ListedColormap(_SUCCESS_COLORS),
                                     norm=BoundaryNorm([-0.5, 0.5, 1.5, 2.5], 3))
            else:
                values = atlas.iterations[c, k] if quantity == "iterations" else 1e3 * atlas.seconds[c, k]
                values = np.where(unreachable, np.nan, values)
                finite = values[np.isfinite(values) & (values > 0)]
                norm = LogNorm(vmin=max(finite.min(), 1e-3), vmax=finite.max()) if finite.size else None
                ax.pcolormesh(edges_x, edges_y, np.where(unreachable, 1.0, np.nan),
                              cmap=ListedColormap([_SUCCESS_COLORS[2]]), vmin=0, vmax=2)
                mesh = ax.pcolormesh(edges_x, edges_y, np.where(values > 0, values, np.nan),
                                     cmap="viridis", norm=norm)
            D = atlas.singular_values(k, fine_x, fine_y)      # +inf without a singular set
            if np.nanmin(D) < 0.0 < np.nanmax(D):
                crossed = True
                ax.contour(fine_x, fine_y, D, levels=[0.0], colors="k", linewidths=1.6)
            if atlas.holds_start(k):
                ax.plot(atlas.start[which[0]], atlas.start[which[1]], "o", color="k", mfc="yellow", ms=8, mew=1.2)
            solved = atlas.count(setting, "solved")
            reachable = solved + atlas.count(setting, "failed")
            where = "" if psi is None else f" ψ = {psi:+.2f};"
            ax.set_title(f"{setting}:{where} solved {solved} of {reachable} reachable", fontsize=9)
            for name, bounds, ticks in ((atlas.axes[0], bx, ax.set_xticks), (atlas.axes[1], by, ax.set_yticks)):
                if space.axis(name).angle and tuple(bounds) in _PI_TICKS:
                    ticks(*_PI_TICKS[tuple(bounds)])
            if k == rows - 1:
                ax.set_xlabel(_axis_text(space, atlas.axes[0]))
            if c == 0:
                ax.set_ylabel(_axis_text(space, atlas.axes[1]))
    if quantity == "success":
        cb = fig.colorbar(mesh, ax=axes, ticks=[0, 1, 2], shrink=0.8)
        cb.ax.set_yticklabels(["solved", "failed", "unreachable\n(across Δ = 0)"])
    elif mesh is not None:
        fig.colorbar(mesh, ax=axes, shrink=0.8,
                     label="accepted iterations" if quantity == "iterations" else label("wall time", MILLISECOND))
    what = {"success": "which goals each planner solves", "iterations": "accepted iterations",
            "time": "wall time per plan"}[quantity]
    fig.suptitle(f"{atlas.mechanism}: {what}, from {atlas.describe_start()} (yellow "
                 f"dot), T = 1 s" + ("; black: Δ = 0" if crossed else ""), fontsize=11)
    return fig
