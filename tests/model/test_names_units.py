"""Names and units in one place: every figure's texts and every CSV header use the table of
:mod:`nonholo.model.names`.

Every public figure function of ``nonholo.viz`` (and the atlas of ``nonholo.batch``) is drawn
on small plans of the mechanisms it draws; the test collects each figure's axis labels (x,
y, z and colour bars), titles (the axes' and the figure's), legend entries and titles, and
texts, and fails on a name or a unit outside the table. Precisely:

- **units**: every bracketed ``[...]`` is a unit or a comma-separated list of units, each
  one of the table (:data:`nonholo.model.names.UNITS`) or of the units the figure's
  mechanism gives its coordinates, or such a unit per second (``radius/s``);
- **no unit outside brackets**: no word ``unit``/``units`` (``leg length (geometry units)``),
  no ``ρ`` (a symbol defined nowhere), no unit in parentheses (``(rad)``);
- **angle names**: with the table's forms (``φ (yaw, about z)``, ``ϑ (pitch, about y)``,
  ``ψ (roll, about x)``) taken out, no text says ``yaw``, ``pitch``, ``roll`` or ``about x``
  (``y``, ``z``), and no angle symbol is glossed otherwise (``φ (roll)``, ``φ (Z)``); an axis
  label or legend entry naming an RPY angle is the table's form (``ψ [rad]`` alone is not) —
  in figures with an orientation (the car's steering angle is its own ``φ``);
- **axis labels carry a unit**, but for those listed in :data:`UNITLESS` (axes whose curves
  have different units, given in their legend).

The CSV's header names are the table's columns (:data:`nonholo.model.names.CSV_COLUMNS`),
their units those of the table or the mechanism's; the docs pages gloss the angles as the
table does.
"""
from __future__ import annotations

import inspect
import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib import animation as mpl_animation  # noqa: E402

import nonholo  # noqa: E402
from nonholo import viz  # noqa: E402
from nonholo.batch import atlas, sweep  # noqa: E402
from nonholo.io import csv_export  # noqa: E402
from nonholo.model import catalog, names  # noqa: E402
from nonholo.constraints import InputBounds  # noqa: E402
from nonholo.paper import examples, reproduce  # noqa: E402
from nonholo.spaces import so3  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SYMBOLS = "φϑψ"
#: Axis labels without a unit: their axes draw quantities of different units, each named
#: with its unit in the legend.
UNITLESS = {"input", "inputs", "error from the goal", "simulated − played plan", "accepted iterations"}
#: Figure functions of ``nonholo.viz.__all__`` that draw no figure of their own.
NOT_FIGURES = {"save_figure", "as_geometry", "leg_lengths", "delta_along", "delta_rpy", "mechanism_delta_rpy",
               "singular_set_points", "normal_form_surface", "normal_form_image", "newton_switch", "rpy_along",
               "input_units", "plane_position"}

BALL_R0 = so3.from_rpy(0.4, -0.3, 0.2)
PROBLEMS = {
    "platform": (examples.get(1).R_start, examples.get(1).R_goal),
    "platform_raised": (np.eye(3), so3.from_rpy(0.3, 0.2, 0.1)),
    "attitude": (so3.from_rpy(0.1, 0.2, 0.3), so3.from_rpy(0.8, -0.4, 0.5)),
    "rolling_ball": ((BALL_R0, (0.0, 0.0)), (so3.exp(np.array([np.pi / 2, 0, 0])) @ BALL_R0, (0.0, 0.0))),
    "car": ((0.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0)),
    "unicycle": ((0.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
    "brockett": ((0.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
}


# -- the table itself ----------------------------------------------------------------------------

def test_the_angles_are_the_papers_rpy_as_the_code_computes_them():
    """``RPY(φ, ϑ, ψ) = R(Z, φ) R(Y, ϑ) R(X, ψ)``: each angle alone turns about its axis of
    the table (the code's ``from_rpy``/``as_rpy``), and yaw, pitch, roll are the turns about
    z, y, x."""
    axes = {"x": np.array([1.0, 0, 0]), "y": np.array([0, 1.0, 0]), "z": np.array([0, 0, 1.0])}
    words = {"z": "yaw", "y": "pitch", "x": "roll"}
    assert [a.symbol for a in names.ANGLES] == list(SYMBOLS)
    for k, angle in enumerate(names.ANGLES):
        rpy = np.zeros(3)
        rpy[k] = 0.3
        np.testing.assert_allclose(so3.from_rpy(*rpy), so3.exp(0.3 * axes[angle.axis]), atol=1e-15)
        assert words[angle.axis] == angle.name
        assert angle.text == f"{angle.symbol} ({angle.name}, about {angle.axis})"
    # the composition order: R = Rz(φ) Ry(ϑ) Rx(ψ)
    phi, th, psi = 0.4, -0.7, 1.1
    composed = so3.exp(phi * axes["z"]) @ so3.exp(th * axes["y"]) @ so3.exp(psi * axes["x"])
    np.testing.assert_allclose(so3.from_rpy(phi, th, psi), composed, atol=1e-14)
    np.testing.assert_allclose(so3.as_rpy(composed), (phi, th, psi), atol=1e-12)


def test_the_module_docstring_is_the_table():
    """The page the docs show (the module's docstring) lists every angle's form and every
    unit of the data, and the CSV's columns."""
    doc = names.__doc__
    for angle in names.ANGLES:
        assert f"``{angle.text}``" in doc and f"``{angle.ascii}``" in doc
    for unit in names.UNITS:
        assert re.search(rf"^``{re.escape(unit)}``\s+\S", doc, re.MULTILINE), unit
    assert "CSV_COLUMNS" in doc


def test_the_examples_name_the_angles_they_turn():
    """The examples' descriptions (figure titles) name the angles that change from start to
    goal, by the amounts given, with the table's forms."""
    for number in (1, 2):
        ex = examples.get(number)
        change = np.subtract(ex.rpy_goal, ex.rpy_start)
        named = {k: float(m.group(1)) for k, angle in enumerate(names.ANGLES)
                 for m in [re.search(re.escape(angle.text) + r"(?: turned by)? ([-+][0-9.]+) rad", ex.description)]
                 if m}
        assert named, ex.description
        for k, amount in named.items():
            assert change[k] == pytest.approx(amount, abs=1e-12)
        for k in set(range(3)) - set(named):
            assert change[k] == 0


# -- the figures -----------------------------------------------------------------------------------

def texts(fig) -> list[tuple[str, str]]:
    """``(kind, text)`` of every text of ``fig`` a reader sees (tick labels aside)."""
    out = [("title", fig.get_suptitle())] + [("text", t.get_text()) for t in fig.texts]
    legends = list(fig.legends)
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        out += [("axis", ax.get_xlabel()), ("axis", ax.get_ylabel())]
        if hasattr(ax, "get_zlabel"):
            out.append(("axis", ax.get_zlabel()))
        out += [("title", ax.get_title(loc)) for loc in ("left", "center", "right")]
        out += [("text", t.get_text()) for t in ax.texts]
        if ax.get_legend() is not None:
            legends.append(ax.get_legend())
    for legend in legends:
        out += [("legend", t.get_text()) for t in legend.get_texts()]
        out.append(("title", legend.get_title().get_text()))
    return [(kind, text) for kind, text in out if text.strip()]


def allowed_units(mechanism) -> set[str]:
    own = set(mechanism.units) if mechanism is not None else set()
    units = (set(names.UNITS) | own) - {""}
    return units | {names.per_second(u) for u in units}


def no_units(mechanism) -> set[str]:
    """Axis labels that may go without a unit in a figure of ``mechanism``: its coordinates to
    which it gives none (Brockett's ``x, y, z``), alone or listed, and its inputs when they
    move only such coordinates."""
    if mechanism is None:
        return set()
    bare = [c for c, u in zip(mechanism.coordinates, names.coordinate_units(mechanism)) if not u]
    out = set(bare) | {", ".join(bare)}
    if "" in names.input_units(mechanism):
        out.add("input u")
    return out


def problems_of(text: str, kind: str, mechanism) -> list[str]:
    """What is wrong with one text of a figure (the module's rules)."""
    out = []
    for inside in re.findall(r"\[([^\[\]]*)\]", text):
        for unit in inside.split(", "):
            if unit not in allowed_units(mechanism):
                out.append(f"unit [{unit}] is not in the table")
    if re.search(r"\bunits?\b", text) or "ρ" in text:
        out.append("a unit outside brackets (the word 'units', or ρ)")
    table_units = "|".join(re.escape(u) for u in names.UNITS)
    if re.search(rf"\((?:{table_units})(?:/s)?\)", text):
        out.append("a unit in parentheses")
    rest = text
    for angle in names.ANGLES:
        rest = rest.replace(angle.text, angle.symbol)
    if re.search(r"\b(yaw|pitch|roll)\b", rest, re.IGNORECASE) or re.search(r"\babout [xyzXYZ]\b", rest):
        out.append("an angle named outside the table's forms")
    if re.search(rf"[{SYMBOLS}]\s*\(", rest):
        out.append("an angle glossed otherwise than the table")
    orientation = mechanism is None or mechanism.space.has_orientation
    bare = re.sub(r"\s*\[[^\]]*\]$", "", text).removeprefix("goal ").strip()
    if orientation and kind in ("axis", "legend") and bare in tuple(SYMBOLS):
        out.append("an RPY angle named by its symbol alone")
    if kind == "axis" and "[" not in text and text not in UNITLESS | no_units(mechanism):
        out.append("an axis label without a unit")
    return out


@pytest.fixture(scope="module")
def plans():
    out = {}
    for name, (start, goal) in PROBLEMS.items():
        res = nonholo.plan(start, goal, mechanism=name)
        assert res.success, (name, res.reason)
        out[name] = res
    return out


@pytest.fixture(scope="module")
def drawn(plans, tmp_path_factory):
    """``(function, figure, mechanism)`` for every figure drawn, and the names drawn."""
    from nonholo.physics.contact import Contact
    from nonholo.physics.execution import execute

    figures, used = [], set()

    def add(function, fig, mechanism):
        figures.append((function, fig, None if mechanism is None else catalog.get(mechanism)))
        used.add(function)

    def axes(function, mechanism, *args, projection=None, **kwargs):
        fig = viz.NotebookFigure()
        getattr(viz, function)(fig.add_subplot(projection=projection), *args, **kwargs)
        add(function, fig, mechanism)

    platform = plans["platform"]
    ex1 = examples.get(1)
    for function in ("convergence_figure", "controls_figure", "rpy_figure", "leg_lengths_figure",
                     "delta_figure", "body_axes_figure", "example_overview_figure"):
        add(function, getattr(viz, function)(platform), "platform")
    for function in ("plot_convergence", "plot_controls", "plot_rpy", "plot_leg_lengths", "plot_delta",
                     "plot_min_delta"):
        axes(function, "platform", platform)
    axes("plot_body_axes", "platform", platform, projection="3d")
    axes("draw_platform", "platform", ex1.R_start, projection="3d")
    for mechanism in ("platform", "platform_raised"):
        add("mechanism_figure", viz.mechanism_figure(ex1.R_start, ex1.R_goal, mechanism=mechanism), mechanism)
    add("mechanism_figure", viz.mechanism_figure(np.eye(3), geometry=catalog.get("platform_raised").geometry), None)
    add("singular_set_figure", viz.singular_set_figure(), "platform")
    add("singular_slices_figure", viz.singular_slices_figure((-0.5, 0.5)), "platform")
    add("normal_form_figure", viz.normal_form_figure(), "platform")
    far = reproduce.plan_far_goal()
    assert far.route == "global"
    add("global_route_figure", viz.global_route_figure(far), "platform")
    free, limited = reproduce.plan_limits_goal()
    add("leg_limits_figure", viz.leg_limits_figure(free, limited), "platform")
    cheap, fast = reproduce.plan_quality(free)
    add("motion_quality_figure", viz.motion_quality_figure(free, cheap, fast), "platform")
    for name, res in plans.items():
        add("plan_figure", viz.plan_figure(res), name)
        mech = catalog.get(name)
        if mech.space.k == 0:
            add("mechanism_card_figure", viz.mechanism_card_figure(name, result=res), name)
        if names.length_unit(mech) and mech.space.k:
            axes("plot_plane_path", name, res)
    add("ball_figure", viz.ball_figure(plans["rolling_ball"]), "rolling_ball")
    add("car_figure", viz.car_figure(plans["car"]), "car")
    bounds = InputBounds([-0.5, -0.5], [0.5, 0.5])
    park = ([0.7, 0.8, 0.0], [1.9, 0.3, 0.0])
    add("least_time_figure", viz.least_time_figure(
        nonholo.plan(*park, mechanism="unicycle", objective="time", constraints=[bounds]),
        nonholo.plan(*park, mechanism="unicycle", T=None, constraints=[bounds]), bounds), "unicycle")
    coarse = Contact(timestep=0.005, solref=(0.01, 1.0))
    for name in ("platform", "car", "rolling_ball"):
        add("execution_figure", viz.execution_figure(execute(plans[name], touch_ups=1, contact=coarse)), name)
    # animations: the figure of their first frame, as their writer grabs it
    original = mpl_animation.PillowWriter.grab_frame
    current, seen = {}, set()

    def grab_frame(self, **kwargs):
        if id(self) not in seen:
            seen.add(id(self))
            add(current["function"], self.fig, current["mechanism"])
        return original(self, **kwargs)

    mpl_animation.PillowWriter.grab_frame = grab_frame
    try:
        folder = tmp_path_factory.mktemp("animations")
        current.update(function="animate_platform", mechanism="platform")
        viz.animate_platform(platform, folder / "platform.gif", frames=2, dpi=30)
        if "animate" in viz.__all__:
            for name, res in plans.items():
                current.update(function="animate", mechanism=name)
                viz.animate(res, folder / f"{name}.gif", frames=2, dpi=30, progress=False)
    finally:
        mpl_animation.PillowWriter.grab_frame = original
    # the atlas of a small sweep (nonholo.batch)
    rows = atlas.problems(n=2, settings=("default",))
    table = sweep.sweep(rows, tmp_path_factory.mktemp("atlas") / "a.parquet", workers=1, progress=False)
    for quantity in atlas.QUANTITIES:
        add("atlas_figure", atlas.atlas_figure(table, quantity), "platform")
    return figures, used


@pytest.mark.slow
def test_every_figure_function_is_drawn(drawn):
    """A figure function added to ``nonholo.viz`` must be added to this test."""
    _, used = drawn
    functions = {name for name in viz.__all__ if inspect.isfunction(getattr(viz, name))} - NOT_FIGURES
    assert functions <= used, f"not drawn by this test: {sorted(functions - used)}"


@pytest.mark.slow
def test_every_figure_text_uses_the_table(drawn):
    figures, _ = drawn
    found = []
    for function, fig, mechanism in figures:
        for kind, text in texts(fig):
            found += [f"{function} ({getattr(mechanism, 'name', '-')}), {kind} {text!r}: {p}"
                      for p in problems_of(text, kind, mechanism)]
    assert not found, "\n".join(found)


@pytest.mark.slow
def test_the_slip_and_the_lengths_have_units(drawn):
    """The issue's offenders, fixed: the slip in the mechanism's length unit per second, the
    lengths in ``radius``, the angles with the table's words."""
    figures, _ = drawn
    labels = {(function, getattr(m, "name", None)): [t for _, t in texts(fig)] for function, fig, m in figures}
    assert "slip speed at the contacts [radius/s]" in labels["execution_figure", "platform"]
    assert "slip speed at the contacts [wheelbase/s]" in labels["execution_figure", "car"]
    assert "RPY angle [rad]" in labels["execution_figure", "platform"]
    assert all(a.text in labels["execution_figure", "platform"] for a in names.ANGLES)
    assert "leg length [radius]" in labels["leg_limits_figure", "platform"]
    assert "leg speed [radius/s]" in labels["motion_quality_figure", "platform"]
    assert "x [radius]" in labels["mechanism_figure", "platform"]


@pytest.mark.parametrize("text, problem", [
    ("φ (roll)", "outside the table's forms"), ("φ (about z) [rad]", "outside the table's forms"),
    ("φ (Z)", "glossed otherwise"), ("ψ [rad]", "symbol alone"), ("leg length [ρ]", "not in the table"),
    ("leg length (geometry units)", "outside brackets"), ("slip speed", "without a unit"),
    ("time (s)", "in parentheses"), ("leg length [furlong]", "not in the table"),
])
def test_the_rules_catch_the_issues_offenders(text, problem):
    assert any(problem in p for p in problems_of(text, "axis", catalog.get("platform")))


def test_the_rules_pass_the_tables_forms():
    mech = catalog.get("car")
    for text in ("φ (yaw, about z) [rad]", "goal ψ (roll, about x) [rad]", "x [wheelbase]", "u1 [wheelbase/s]",
                 "leg speed [radius/s]", "error from the goal [wheelbase, rad]", "steering φ"):
        assert not problems_of(text, "axis" if "[" in text else "legend", mech), text


# -- the CSV -------------------------------------------------------------------------------------

def column_patterns() -> list[tuple[re.Pattern, str | None]]:
    return [(re.compile(re.escape(p).replace(r"\{i\}", "[1-9][0-9]*")), unit)
            for p, unit, _ in names.CSV_COLUMNS if p != "{coordinate}"]


@pytest.mark.parametrize("name", sorted(PROBLEMS))
def test_every_csv_header_is_a_column_of_the_table(plans, name, tmp_path):
    res = plans[name]
    mech = catalog.get(name)
    header = res.to_csv(tmp_path / "plan.csv", rate=10).read_text().splitlines()[0].split(",")
    assert header == list(csv_export.column_units(mech))
    units = csv_export.column_units(mech)
    for column in header:
        known = column in mech.coordinates or any(p.fullmatch(column) for p, _ in column_patterns())
        assert known, f"{column!r} is not a column of the table"
        unit = units[column]
        assert unit == "" or unit in allowed_units(mech), (column, unit)
    if mech.geometry is not None:
        assert (units["l1"], units["dl1_dt"], units["u1"]) == (names.RADIUS, "radius/s", names.PER_SECOND)
    assert units["t"] == names.SECOND


def test_an_unknown_column_is_refused():
    with pytest.raises(ValueError, match="column 'l1' is not a column of a plan of mechanism 'car'"):
        names.csv_units(catalog.get("car"), ["t", "l1"])


# -- the docs ----------------------------------------------------------------------------------------

def doc_texts() -> list[tuple[str, str]]:
    import nbformat

    out = [(str(p.relative_to(ROOT)), p.read_text()) for p in
           [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")), *sorted((ROOT / "docs" / "guide").glob("*.md"))]]
    for p in sorted((ROOT / "notebooks").glob("*.ipynb")):
        nb = nbformat.read(p, as_version=4)
        out.append((str(p.relative_to(ROOT)), "\n".join(c.source for c in nb.cells)))
    return out


def test_the_docs_name_the_angles_and_units_as_the_table():
    """No page glosses an angle otherwise than the table (``φ (about z)``, ``φ (roll)``), or
    writes lengths in ``[ρ]`` or "geometry units"."""
    forms = {a.symbol: a for a in names.ANGLES}
    found = []
    for where, text in doc_texts():
        for m in re.finditer(rf"([{SYMBOLS}]) \(([^)]*)\)", text):
            angle = forms[m.group(1)]
            words = m.group(2)
            if re.search(r"yaw|pitch|roll|about", words) and words != f"{angle.name}, about {angle.axis}":
                found.append(f"{where}: {m.group(0)!r}")
        for m in re.finditer(r"\b(yaw|pitch|roll)\b \(about ([xyz])\)", text):
            if {"yaw": "z", "pitch": "y", "roll": "x"}[m.group(1)] != m.group(2):
                found.append(f"{where}: {m.group(0)!r}")
        for bad in ("geometry units", "geometry's units", "[ρ]", "roll–pitch–yaw"):
            if bad in text:
                found.append(f"{where}: {bad!r}")
    assert not found, "\n".join(found)
