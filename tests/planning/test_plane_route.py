"""The routes among obstacles of a planar vehicle (OMPL's RRT-Connect in Reeds–Shepp curves,
and the lattice's quickest): checked against shapely's geometry of the boxes directly and a
closed-form replay of the unicycle along their rates."""
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import shapely

from nonholo import dynobench
from nonholo.dynobench.solve import obstacles
from nonholo.model import catalog
from nonholo.planning import arc_route, lattice_route, plane_route

ROOT = Path(__file__).resolve().parents[2]
KINK = ROOT / "benchmarks" / "dynobench" / "envs" / "unicycle1_v0" / "kink_0.yaml"
UNICYCLE = catalog.get("unicycle")


def box(x, y, theta, length, width):
    """The polygon of a box centred at ``(x, y)`` turned by ``theta`` (written here)."""
    c, s = np.cos(theta), np.sin(theta)
    half = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]]) * [length / 2, width / 2]
    return shapely.Polygon(np.array([x, y]) + half @ np.array([[c, s], [-s, c]]))


def unicycle_replay(start, times, rates):
    """The unicycle's exact motion under rates constant on each interval (arcs and lines)."""
    x, y, th = start
    for dt, (v, w) in zip(np.diff(times), rates):
        if abs(w * dt) < 1e-12:
            x, y = x + v * dt * np.cos(th), y + v * dt * np.sin(th)
        else:
            x, y = x + v / w * (np.sin(th + w * dt) - np.sin(th)), y - v / w * (np.cos(th + w * dt) - np.cos(th))
        th += w * dt
    return np.array([x, y, th])


def test_a_route_round_the_kink_is_clear_ends_at_the_goal_and_keeps_the_rates():
    """Every state of the route clear of the boxes by the margin, inside the workspace, its
    ends the instance's; its rates in their bounds, played by the unicycle to the goal."""
    inst = dynobench.load(KINK)
    kept = obstacles(inst, 5e-3)
    way = plane_route.route(kept, UNICYCLE, inst.start, inst.goal, inst.low, inst.high, 0.5, 0.5)
    assert isinstance(way, plane_route.Route), way
    np.testing.assert_allclose(way.states[0], inst.start, atol=1e-9)
    np.testing.assert_allclose(way.states[-1, :2], inst.goal[:2], atol=1e-9)
    assert abs(np.angle(np.exp(1j * (way.states[-1, 2] - inst.goal[2])))) < 1e-9
    # every state clear of every obstacle by the margin (shapely on the boxes, directly)
    walls = [box(*o.center, 0.0, *o.size) for o in inst.obstacles]
    length, width = inst.bodies[0]
    for x, y, th in way.states:
        body = box(x, y, th, length, width)
        assert min(body.distance(w) for w in walls) >= 5e-3 - 1e-9
        assert inst.low[0] <= x <= inst.high[0] and inst.low[1] <= y <= inst.high[1]
    # the rates keep their bounds and, played by the unicycle, end at the goal
    assert np.abs(way.rates[:, 0]).max() <= 0.5 * (1 + 1e-12)
    assert np.abs(way.rates[:, 1]).max() <= 0.5 * (1 + 1e-12)
    end = unicycle_replay(inst.start, way.times, way.rates)
    assert np.abs(end[:2] - inst.goal[:2]).max() < 1e-3
    assert way.T == pytest.approx(way.times[-1]) and np.allclose(way(way.times[:-1] + 1e-9), way.rates)


def walled_off(inst):
    """The instance with its goal inside a ring of walls (and no other obstacle)."""
    ring = [dynobench.instance.Box((5.5, 4.0 + d), (1.4, 0.1)) for d in (-0.55, 0.55)] + \
           [dynobench.instance.Box((5.5 + d, 4.0), (0.1, 1.2)) for d in (-0.55, 0.55)]
    return replace(inst, obstacles=tuple(ring))


def test_a_goal_walled_off_has_no_route_within_the_sample_budget():
    """The kink's goal inside a ring of walls: no route, said, after the sample budget."""
    inst = dynobench.load(KINK)
    boxed = walled_off(inst)
    why = plane_route.route(obstacles(boxed, 5e-3), UNICYCLE, inst.start, inst.goal, inst.low, inst.high, 0.5, 0.5)
    assert isinstance(why, str) and "no route" in why and str(plane_route.MAX_SAMPLES) in why


def played_states(start, times, rates, per_piece=20):
    """The unicycle's states along its rates, ``per_piece`` points within each piece."""
    out, state = [np.asarray(start, dtype=float)], np.asarray(start, dtype=float)
    for t0, t1, r in zip(times[:-1], times[1:], rates):
        for f in np.arange(1, per_piece + 1) / per_piece:
            out.append(unicycle_replay(state, [0.0, f * (t1 - t0)], [r]))
        state = out[-1]
    return np.array(out)


def test_the_lattice_route_takes_the_kinks_corridor_clear_and_quicker_than_the_way_round():
    """The lattice's route through the kink: every body along the played motion (20 points a
    piece, turns included) clear of the boxes, through the corridor between them, ending
    within a grid cell of the goal; quicker than OMPL's route round the boxes."""
    inst = dynobench.load(KINK)
    kept = obstacles(inst, 5e-3)
    way = lattice_route.route(kept, UNICYCLE, inst.start, inst.goal, inst.low, inst.high, 0.5, 0.5)
    assert isinstance(way, plane_route.Route), way
    assert np.abs(way.rates).max() <= 0.5 * (1 + 1e-12)
    walls = [box(*o.center, 0.0, *o.size) for o in inst.obstacles]
    length, width = inst.bodies[0]
    states = played_states(inst.start, way.times, way.rates)
    for x, y, th in states:
        assert min(box(x, y, th, length, width).distance(w) for w in walls) > 0.0
        assert inst.low[0] - 1e-9 <= x <= inst.high[0] + 1e-9 and inst.low[1] - 1e-9 <= y <= inst.high[1] + 1e-9
    # through the corridor: between the boxes at x = 3, 3 < y < 4.4
    assert np.any((np.abs(states[:, 0] - 3.0) < 0.3) & (states[:, 1] > 3.0) & (states[:, 1] < 4.4))
    cell = lattice_route.CELL_OF_WIDTH * width
    assert np.hypot(*(states[-1, :2] - inst.goal[:2])) <= cell
    round_about = plane_route.route(kept, UNICYCLE, inst.start, inst.goal, inst.low, inst.high, 0.5, 0.5)
    assert way.T < round_about.T


def test_the_lattice_route_of_a_shifted_instance_is_the_route_shifted():
    """The instance moved by (−7.3, 2.1): the same route, moved."""
    inst = dynobench.load(KINK)
    shift = np.array([-7.3, 2.1])
    moved = replace(inst, start=inst.start + np.r_[shift, 0.0], goal=inst.goal + np.r_[shift, 0.0],
                    low=inst.low + shift, high=inst.high + shift,
                    obstacles=tuple(dynobench.instance.Box(tuple(np.add(o.center, shift)), o.size)
                                    for o in inst.obstacles))
    a = lattice_route.route(obstacles(inst, 5e-3), UNICYCLE, inst.start, inst.goal, inst.low, inst.high, 0.5, 0.5)
    b = lattice_route.route(obstacles(moved, 5e-3), UNICYCLE, moved.start, moved.goal, moved.low, moved.high,
                            0.5, 0.5)
    assert a.states.shape == b.states.shape
    np.testing.assert_allclose(b.states[:, :2], a.states[:, :2] + shift, atol=1e-9)
    np.testing.assert_allclose(b.states[:, 2], a.states[:, 2], atol=1e-12)


def test_a_goal_walled_off_has_no_lattice_route():
    """The kink's goal inside a ring of walls: no route on the lattice, said."""
    inst = dynobench.load(KINK)
    boxed = walled_off(inst)
    why = lattice_route.route(obstacles(boxed, 5e-3), UNICYCLE, inst.start, inst.goal, inst.low, inst.high, 0.5, 0.5)
    assert isinstance(why, str) and "no route on the lattice" in why


WALL = ROOT / "benchmarks" / "dynobench" / "envs" / "unicycle1_v2" / "wall_0.yaml"


def test_the_arc_route_of_a_forward_only_unicycle_is_played_exactly_clear_and_in_its_bounds():
    """Dynobench's wall for a unicycle with ``0.25 ≤ v ≤ 0.5`` and ``−0.25 ≤ ω ≤ 0.5``: the
    arcs, replayed in closed form, pass through the route's states; every body along them (20
    points an arc) clear of the boxes and inside the workspace; the rates in their bounds; the
    end within a cell and a heading bin of the goal."""
    inst = dynobench.load(WALL)
    bounds = (np.asarray(inst.input_low), np.asarray(inst.input_high))
    assert bounds[0][0] > 0 and -bounds[0][1] != bounds[1][1]
    way = arc_route.route(obstacles(inst, 5e-3), UNICYCLE, inst.start, inst.goal, inst.low, inst.high, *bounds)
    assert isinstance(way, plane_route.Route), way
    assert np.all(way.rates >= bounds[0] - 1e-12) and np.all(way.rates <= bounds[1] + 1e-12)
    states = played_states(inst.start, way.times, way.rates)
    np.testing.assert_allclose(states[::20], way.states, atol=1e-9)
    walls = [box(*o.center, 0.0, *o.size) for o in inst.obstacles]
    length, width = inst.bodies[0]
    for x, y, th in states:
        assert min(box(x, y, th, length, width).distance(w) for w in walls) > 0.0
        assert inst.low[0] - 1e-9 <= x <= inst.high[0] + 1e-9 and inst.low[1] - 1e-9 <= y <= inst.high[1] + 1e-9
    cell = arc_route.CELL_OF_WIDTH * width
    assert np.hypot(*(states[-1, :2] - inst.goal[:2])) <= arc_route.GOAL_CELLS * cell + 1e-12
    assert abs(np.angle(np.exp(1j * (states[-1, 2] - inst.goal[2])))) <= 2 * np.pi / arc_route.HEADING_BINS


def test_the_arcs_are_the_unicycles_closed_form():
    moves = np.array([(0.5, 0.5), (0.25, -0.25), (0.4, 0.0), (0.5, 1e-12)])
    got = arc_route.arcs(moves, 0.8, np.array([0.5, 1.0]))
    for m, (v, w) in enumerate(moves):
        for f, frac in enumerate((0.5, 1.0)):
            np.testing.assert_allclose(got[m, f], unicycle_replay((0.0, 0.0, 0.0), [0.0, 0.8 * frac], [(v, w)]),
                                       atol=1e-12)


def test_a_goal_walled_off_has_no_arc_route_within_the_budget():
    inst = dynobench.load(KINK)
    boxed = walled_off(inst)
    why = arc_route.route(obstacles(boxed, 5e-3), UNICYCLE, inst.start, inst.goal, inst.low, inst.high,
                          (0.25, -0.5), (0.5, 0.5))
    assert isinstance(why, str) and "no route of the vehicle's arcs" in why
