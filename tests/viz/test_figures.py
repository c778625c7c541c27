"""Figures: structure (axes, labels with units), saved files, and the numbers behind them."""
import re
from types import SimpleNamespace

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
from conftest import example
from matplotlib.figure import Figure
from PIL import Image
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from nonholo.model import catalog
from nonholo.model.geometry import Geometry
from nonholo.paper import examples
from nonholo.spaces import so3
from nonholo import viz

RNG = np.random.default_rng(7)
PLATFORM = catalog.get("platform")
UNITS = re.compile(r"\[[^\]]+\]")


def simulate(R0, ufun, T=1.0, n=61):
    """Trajectory of dR/dt = [L(R) u(t)] R for a test control."""
    def rhs(t, y):
        R = y.reshape(3, 3)
        return (so3.hat(PLATFORM.L(R) @ ufun(t)) @ R).ravel()

    t = np.linspace(0.0, T, n)
    sol = solve_ivp(rhs, (0.0, T), R0.ravel(), t_eval=t, rtol=1e-9, atol=1e-11)
    assert sol.success
    R = sol.y.T.reshape(-1, 3, 3)
    return t, R, np.array([ufun(s) for s in t])


def stand_in(method, amplitude, n_flow=8, n_newton=3, gamma=0.3):
    """An object with the attributes of a planner result, from a simulated trajectory."""
    def ufun(t):
        return amplitude * np.array([np.sin(2 * np.pi * t), np.cos(2 * np.pi * t)])

    t, R, u = simulate(example(1)[0], ufun)
    d = np.array([PLATFORM.delta(Ri) for Ri in R])
    history, e = [], 0.58
    for k in range(n_flow):
        history.append({"error": e, "step": gamma, "min_delta": float(d.min()) - 0.01 * k})
        e *= 1.0 - gamma
    for _ in range(n_newton):
        history.append({"error": e, "step": 1.0, "min_delta": float(d.min())})
        e = 2.0 * e ** 2
    return SimpleNamespace(t=t, R=R, u=u, history=history, terminal_error=e,
                           min_delta=float(np.abs(d).min()), method=method, strategy="plain",
                           mechanism="platform", controls=ufun, success=True,
                           iterations=len(history))


@pytest.fixture(scope="module")
def results():
    return [stand_in("parametric", 0.3), stand_in("nonparametric", 0.4, n_flow=12)]


def check_figure(fig, n_axes, tmp_path, stem):
    """Figure with n_axes visible axes, each with labelled x/y axes carrying units; the
    saved PNG and PDF are non-empty."""
    assert isinstance(fig, Figure)
    axes = [ax for ax in fig.axes if ax.get_visible() and ax.get_label() != "<colorbar>"]
    assert len(axes) == n_axes
    for ax in axes:
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            assert label.strip(), f"unlabelled axis in {stem}"
            assert UNITS.search(label), f"no unit in brackets: {label!r} ({stem})"
        if hasattr(ax, "get_zlabel"):
            assert UNITS.search(ax.get_zlabel())
    png, pdf = viz.save_figure(fig, stem, tmp_path, dpi=60)
    assert png.stat().st_size > 1000 and pdf.stat().st_size > 1000
    with Image.open(png) as im:
        assert im.format == "PNG" and min(im.size) > 200
    assert pdf.read_bytes().startswith(b"%PDF")


def test_mechanism_figure(tmp_path):
    R0, R1 = example(1)
    check_figure(viz.mechanism_figure(R0), 1, tmp_path, "mech1")
    fig = viz.mechanism_figure(R0, R1, title="Example 1")
    check_figure(fig, 2, tmp_path, "mech2")
    titles = [ax.get_title() for ax in fig.axes]
    assert titles[0].startswith("start") and titles[1].startswith("goal")
    assert "Δ = +0.727" in titles[0] and "Δ = +0.582" in titles[1]
    texts = " ".join(t.get_text() for t in fig.axes[0].texts)
    assert "leg 1" in texts and "leg 2" in texts
    l1, l2 = viz.leg_lengths(R0)
    assert f"{l1:.3f}" in texts and f"{l2:.3f}" in texts


def test_mechanism_figure_other_geometry(tmp_path):
    from derivations.definitions import RAISED_GEOMETRY

    g = viz.as_geometry(RAISED_GEOMETRY)
    assert isinstance(g, Geometry)
    assert np.allclose(g.base1, 1.6 * np.array([1, 0, 1]) / np.sqrt(2))
    assert np.allclose(g.contact, np.array([1, 1, 0]) / np.sqrt(2))
    fig = viz.mechanism_figure(np.eye(3), geometry=g, mechanism="platform_raised")
    assert "Δ = +1.000" in fig.axes[0].get_title()
    # the generated module's drawing geometry is the same one (a = 1.6, b = rho = 1)
    raised = catalog.get("platform_raised")
    for name in Geometry.FIELDS:
        assert np.allclose(getattr(raised.geometry, name), getattr(g, name))
    fig = viz.mechanism_figure(np.eye(3), mechanism=raised)       # a Mechanism object
    assert "Δ = +1.000" in fig.axes[0].get_title()


def test_mechanism_figure_draws_and_titles_one_mechanism():
    """The figure is of the mechanism given: its geometry drawn, its Δ and name in the titles;
    a geometry alone has no Δ (no mechanism gives it one); only both given pair a drawing with
    another mechanism's Δ. A mechanism without legs is refused, a wrong type too."""
    from derivations.mechanisms import paper_platform

    R = so3.from_rpy(0.3, 0.2, 0.1)
    raised, paper = catalog.get("platform_raised"), catalog.get("platform")

    def base_joints(fig):
        """The squares drawn: the base joints, in the world frame."""
        out = []
        for coll in fig.axes[0].collections:
            if getattr(coll, "_offsets3d", None) is not None and len(coll._offsets3d[0]) == 1:
                out.append(np.array([c[0] for c in coll._offsets3d]))
        return out

    def drawn_from(fig, geometry):
        return any(np.allclose(p, geometry.base1) for p in base_joints(fig))

    for given in ("platform_raised", raised):
        fig = viz.mechanism_figure(R, mechanism=given)
        title = fig.axes[0].get_title()
        assert title.startswith("platform_raised\n") and f"Δ = {float(raised.delta(R)):+.3f}" in title
        assert fig.get_suptitle() == f"platform_raised: {raised.description}"
        assert drawn_from(fig, raised.geometry) and not drawn_from(fig, paper.geometry)
    # a mechanism given as geometry= is that mechanism, not the paper's Δ on its drawing
    fig = viz.mechanism_figure(R, geometry="platform_raised")
    assert f"Δ = {float(raised.delta(R)):+.3f}" in fig.axes[0].get_title()
    assert f"{float(paper.delta(R)):+.3f}" not in fig.axes[0].get_title()
    # a geometry alone: drawn, no Δ
    fig = viz.mechanism_figure(R, geometry=raised.geometry)
    assert "Δ" not in fig.axes[0].get_title() and drawn_from(fig, raised.geometry)
    # both: the caller pairs them
    fig = viz.mechanism_figure(R, geometry=raised.geometry, mechanism="platform")
    assert f"Δ = {float(paper.delta(R)):+.3f}" in fig.axes[0].get_title() and drawn_from(fig, raised.geometry)
    # the default: the paper's platform
    fig = viz.mechanism_figure(R)
    assert f"Δ = {float(paper.delta(R)):+.3f}" in fig.axes[0].get_title() and drawn_from(fig, paper.geometry)
    with pytest.raises(ValueError, match="mechanism 'attitude' has no legs/disk geometry to draw"):
        viz.mechanism_figure(R, mechanism="attitude")
    with pytest.raises(ValueError, match="mechanism 'car' has no legs/disk geometry to draw"):
        viz.mechanism_figure(R, mechanism=catalog.get("car"))
    with pytest.raises(ValueError, match="unknown mechanism 'no_such'"):
        viz.mechanism_figure(R, mechanism="no_such")
    with pytest.raises(TypeError, match="mechanism must be a mechanism's name or a nonholo.Mechanism, got int"):
        viz.mechanism_figure(R, mechanism=3)
    with pytest.raises(TypeError, match=r"from_symbolic"):
        viz.mechanism_figure(R, mechanism=paper_platform())


def test_default_geometry_is_the_papers():
    from derivations.mechanisms import PAPER_GEOMETRY

    sym = viz.as_geometry(PAPER_GEOMETRY)  # a = 1.6, b = rho = 1 substituted
    num = viz.as_geometry()
    gen = viz.as_geometry("platform")
    assert gen is PLATFORM.geometry and viz.as_geometry(PLATFORM) is PLATFORM.geometry
    assert Geometry.FIELDS == ("base1", "tip1", "base2", "tip2", "contact", "axle")
    for name in Geometry.FIELDS:
        assert np.allclose(getattr(sym, name), getattr(num, name))
        assert np.allclose(getattr(gen, name), getattr(num, name))
    assert num.radius == 1.0
    with pytest.raises(ValueError, match="no legs"):
        viz.as_geometry("attitude")


def test_leg_lengths_closed_form():
    a, b = 1.6, 1.0
    Rs = Rotation.random(50, random_state=3).as_matrix()
    lengths = viz.leg_lengths(Rs)
    assert lengths.shape == (50, 2)
    assert np.allclose(lengths[:, 0] ** 2, a * a + b * b - 2 * a * b * Rs[:, 1, 1], atol=1e-12)
    assert np.allclose(lengths[:, 1] ** 2, a * a + b * b - 2 * a * b * Rs[:, 0, 0], atol=1e-12)
    assert np.allclose(viz.leg_lengths(Rs[0]), lengths[0])
    np.testing.assert_array_equal(PLATFORM.geometry.leg_lengths(Rs), lengths)
    # other dimensions
    g = viz.as_geometry(None, a=2.0, b=0.5, rho=0.5)
    l = viz.leg_lengths(Rs, g)
    assert np.allclose(l[:, 0] ** 2, 4.25 - 2.0 * Rs[:, 1, 1])


def test_singular_set_points_are_on_the_surface():
    phi, theta, psi = viz.singular_set_points(31, 61)
    assert phi.shape == (2, 31, 61)
    assert np.all(np.abs(phi) <= np.pi) and np.all(np.abs(theta) <= np.pi / 2)
    idx = RNG.choice(phi.size, 300, replace=False)
    for p, t, s in zip(phi.ravel()[idx], theta.ravel()[idx], psi.ravel()[idx]):
        assert abs(PLATFORM.delta(so3.from_rpy(p, t, s))) < 1e-8
    assert np.max(np.abs(viz.delta_rpy(phi, theta, psi))) < 1e-12
    # Δ > 0 between the two sheets, Δ < 0 beyond
    p0 = np.arctan2(np.sin(psi[0]) * np.sin(theta[0]) ** 2,
                    np.sin(theta[0]) * np.cos(psi[0]) + np.sin(psi[0]) * np.cos(theta[0]) ** 2)
    regular = np.abs(viz.delta_rpy(p0 + np.pi / 2, theta[0], psi[0])) > 1e-9
    assert np.all(viz.delta_rpy(p0 + np.pi / 2, theta[0], psi[0])[regular] > 0)
    assert np.all(viz.delta_rpy(p0 - np.pi / 2, theta[0], psi[0])[regular] < 0)


def test_normal_form_points():
    x, y, z = viz.normal_form_surface(41)
    assert np.max(np.abs(z ** 3 + x * y)) < 1e-12
    rpy, xyz = viz.normal_form_image(0.5, n=41)
    assert len(rpy) > 50 and np.all(np.abs(rpy) <= 0.5)
    x, y, z = xyz.T
    assert np.max(np.abs(z ** 3 + x * y)) < 1e-10  # the image of Δ = 0 lies on it


@pytest.mark.slow
def test_singular_figures(tmp_path):
    fig = viz.singular_set_figure(marks={"start": (0.5, 1.2, "o")})
    check_figure(fig, 2, tmp_path, "singular")
    check_figure(viz.singular_slices_figure((-1.0, 0.0, 1.0)), 3, tmp_path, "slices")
    check_figure(viz.normal_form_figure(), 2, tmp_path, "normal_form")


@pytest.mark.slow
def test_plan_figures(results, tmp_path):
    check_figure(viz.convergence_figure(results, tol=1e-10), 1, tmp_path, "conv")
    check_figure(viz.controls_figure(results), 2, tmp_path, "controls")
    check_figure(viz.rpy_figure(results), 1, tmp_path, "rpy")
    check_figure(viz.leg_lengths_figure(results), 1, tmp_path, "legs")
    check_figure(viz.delta_figure(results, threshold=1e-2), 1, tmp_path, "delta")
    check_figure(viz.body_axes_figure(results[0]), 1, tmp_path, "axes")
    check_figure(viz.example_overview_figure(results, "Example"), 6, tmp_path, "overview")


def test_plotted_data(results):
    res = results[0]
    fig = viz.leg_lengths_figure(res)
    lines = [ln for ln in fig.axes[0].get_lines() if len(ln.get_xdata()) == len(res.t)]
    assert np.allclose(lines[0].get_ydata(), viz.leg_lengths(res.R)[:, 0])
    fig = viz.delta_figure(results, threshold=0.05)
    ax = fig.axes[0]
    d = np.array([PLATFORM.delta(R) for R in res.R])
    assert any(np.allclose(ln.get_ydata(), d) for ln in ax.get_lines()
               if len(ln.get_ydata()) == len(d))
    levels = {float(ln.get_ydata()[0]) for ln in ax.get_lines() if len(ln.get_ydata()) == 2}
    assert {0.0, 0.05, -0.05} <= levels
    # the switch to Newton steps is found from the step sizes
    assert viz.newton_switch(res.history) == 8
    assert viz.newton_switch([{"step": 1.0}] * 3) is None
    rpy = viz.rpy_along(res.R)
    assert np.allclose(rpy[0], examples.get(1).rpy_start)       # (0.5, 1.2, -0.5)


def test_animation(results, tmp_path):
    path = viz.animate_platform(results[0], tmp_path / "anim.gif", frames=4, fps=10)
    with Image.open(path) as im:
        assert im.format == "GIF"
        assert im.n_frames == 4


def test_mechanism_delta_rpy_matches_the_analytic_form():
    from nonholo import viz
    rng = np.random.default_rng(5)
    a = rng.uniform(-3, 3, size=(3, 7, 5))
    np.testing.assert_allclose(viz.mechanism_delta_rpy("platform", *a), viz.delta_rpy(*a), atol=1e-14)
    R = so3.from_rpy(*a[:, 2, 3])
    assert viz.mechanism_delta_rpy("platform_raised", *a)[2, 3] == pytest.approx(
        float(catalog.get("platform_raised").delta(R)), abs=1e-14)


@pytest.mark.parametrize("name", ["platform", "platform_raised"])
def test_mechanism_card(name):
    from nonholo import viz
    fig = viz.mechanism_card_figure(name)
    assert len(fig.axes) == 3  # schematic, slice, colour bar
    assert "[" in fig.axes[1].get_xlabel()


# -- figures in notebooks, plans of any mechanism, units from the mechanism's data --------------

def test_figures_show_themselves_as_images(results):
    """IPython's display (a fresh formatter: no backend has registered anything) gets a PNG
    of the figure's size from a library figure, and nothing but text from a plain one."""
    import io

    from IPython.core.formatters import DisplayFormatter

    fig = viz.convergence_figure(results)
    assert isinstance(fig, viz.NotebookFigure)
    data, _ = DisplayFormatter().format(fig)
    with Image.open(io.BytesIO(data["image/png"])) as im:
        width, height = im.size
    w, h = fig.get_size_inches() * fig.dpi      # trimmed to the artists, with a small pad
    assert 0.7 * w <= width <= 1.2 * w and 0.7 * h <= height <= 1.2 * h
    plain, _ = DisplayFormatter().format(Figure())
    assert "image/png" not in plain


@pytest.mark.slow
def test_figures_are_made_without_pyplot():
    """Building every kind of figure leaves pyplot unimported: no global state in scripts."""
    import subprocess
    import sys

    code = ("import sys, nonholo\nfrom nonholo import viz\nfrom nonholo.cli import entry\n"
            "r = nonholo.plan([0, 0, 0, 0], [0, 1, 0, 0], mechanism='car')\n"
            "figs = [viz.plan_figure(r), viz.car_figure(r), viz.singular_slices_figure((0.0,)),"
            " viz.mechanism_figure(__import__('numpy').eye(3))]\n"
            "[f._repr_png_() for f in figs]\n"
            "assert 'matplotlib.pyplot' not in sys.modules, 'pyplot imported'\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]


def test_saved_figures_are_the_same_bytes_twice(results, tmp_path):
    """No creation date in the PDF: the same figure saved twice (a second apart) is equal."""
    import time

    a = viz.save_figure(viz.rpy_figure(results), "a", tmp_path, dpi=50)
    time.sleep(1.1)
    b = viz.save_figure(viz.rpy_figure(results), "b", tmp_path, dpi=50)
    for first, second in zip(a, b):
        assert first.read_bytes() == second.read_bytes(), first.suffix
    assert b"CreationDate" not in a[1].read_bytes()


@pytest.fixture(scope="module")
def car_plan():
    import nonholo
    return nonholo.plan([0.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], mechanism="car")


def symbolic_input_units(name):
    """Each input's unit from the symbolic field: the unit of the first coordinate whose
    rate it drives (``X[i, j] ≠ 0``), per second (none shown where that coordinate has no
    unit given); ``1/s`` if it drives none."""
    from derivations import definitions

    m = definitions.MECHANISMS[name]()
    out = []
    for j in range(len(m.inputs)):
        rows = [i for i in range(len(m.coordinates)) if m.X is not None and m.X[i, j] != 0]
        out.append(("" if not m.units[rows[0]] else f"{m.units[rows[0]]}/s") if rows else "1/s")
    return tuple(out)


@pytest.mark.parametrize("name", catalog.names())
def test_input_units_follow_the_field(name):
    assert viz.input_units(catalog.get(name)) == symbolic_input_units(name)


def test_units_come_from_the_data_not_the_name(car_plan):
    """The car's data with other units and another name: the labels follow the data."""
    import dataclasses

    car = catalog.get("car")
    other = dataclasses.replace(car, name="vehicle", units=("m", "m", "rad", "rad"))
    assert viz.input_units(other) == ("m/s", "rad/s")
    assert viz.plane_position(other) == (0, 1)
    fig = Figure()
    viz.plot_plane_path(fig.add_subplot(), car_plan, mechanism=other)
    assert (fig.axes[0].get_xlabel(), fig.axes[0].get_ylabel()) == ("x [m]", "y [m]")
    bare = dataclasses.replace(car, name="vehicle", units=("",) * 4)   # no units given: none shown
    assert viz.input_units(bare) == ("", "") and viz.plane_position(bare) == (0, 1)
    fig = Figure()
    viz.plot_plane_path(fig.add_subplot(), car_plan, mechanism=bare)
    assert (fig.axes[0].get_xlabel(), fig.axes[0].get_ylabel()) == ("x", "y")
    turned = dataclasses.replace(car, name="vehicle", angles=(True, False, True, True))
    assert viz.plane_position(turned) is None          # one length coordinate: no plane
    mixed = dataclasses.replace(car, name="vehicle", units=("m", "wheelbase", "m", "rad"),
                                angles=(False, False, False, True))
    assert viz.plane_position(mixed) == (0, 2)          # the first two lengths in one unit


def plane_axes(fig):
    return [ax for ax in fig.axes if ax.get_aspect() == 1.0]


def test_a_car_plans_figure_has_its_path_on_the_plane(car_plan, tmp_path):
    fig = viz.plan_figure(car_plan)
    (plane,) = plane_axes(fig)
    assert (plane.get_xlabel(), plane.get_ylabel()) == ("x [wheelbase]", "y [wheelbase]")
    np.testing.assert_array_equal(plane.lines[0].get_xydata(), car_plan.q[:, :2])
    goal = [ln for ln in plane.lines if ln.get_label() == "goal"][0]
    np.testing.assert_array_equal(goal.get_xydata()[0], car_plan.qd[:2])
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert "x, y [wheelbase]" in labels and "theta, phi [rad]" in labels and "Δ [-]" in labels
    legend = [t.get_text() for ax in fig.axes if ax.get_legend() for t in ax.get_legend().get_texts()]
    assert any(t.endswith("[wheelbase/s]") for t in legend) and any(t.endswith("[rad/s]") for t in legend)
    assert not any("1/s" in label for label in labels + legend)
    assert "(wheelbase, rad)" in fig.get_suptitle()
    png, pdf = viz.save_figure(fig, "car_plan", tmp_path, dpi=50)
    assert png.stat().st_size > 1000


def test_a_platform_plans_figure_has_no_plane(tmp_path):
    import nonholo

    res = nonholo.plan(*example(1), strategy="paper")
    fig = viz.plan_figure(res)
    assert not plane_axes(fig)
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert labels[:2] == ["input u [1/s]", "RPY angles [rad]"]
    assert "leg length [radius]" in labels and "|l_T| = " in fig.get_suptitle()
    assert fig.get_suptitle().endswith(" rad")


def test_the_balls_figures_measure_its_position_in_radii():
    import nonholo
    from nonholo.paper import reproduce

    start, goal = reproduce.STATE_PROBLEMS["rolling_ball"]
    res = nonholo.plan(start, goal, mechanism="rolling_ball", **reproduce.STATE_OPTIONS["rolling_ball"])
    for fig in (viz.plan_figure(res), viz.ball_figure(res)):
        (plane,) = plane_axes(fig)
        assert (plane.get_xlabel(), plane.get_ylabel()) == ("p1 [radius]", "p2 [radius]")
    legend = [t.get_text() for t in fig.axes[2].get_legend().get_texts()]
    assert all(t.endswith("[radius/s]") for t in legend)
    assert "rotation" in viz.plan_figure(res).get_suptitle()


def test_reasons_give_errors_in_the_states_units(car_plan):
    import nonholo

    assert car_plan.success
    assert "(wheelbase, rad) from the goal" in car_plan.reason
    assert " rad from the goal" not in car_plan.reason
    assert "(wheelbase, rad)" in repr(car_plan)
    platform = nonholo.plan(*example(1), strategy="paper")
    assert platform.reason.endswith(" rad") and "rad from the goal" in platform.reason
