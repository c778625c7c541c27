"""The route among obstacles of a planar vehicle (OMPL's RRT-Connect, Reeds–Shepp curves):
checked against shapely's geometry of the boxes directly and a closed-form replay of the
unicycle along its rates."""
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import shapely

from nonholo import dynobench
from nonholo.dynobench.solve import obstacles
from nonholo.model import catalog
from nonholo.planning import plane_route

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


def test_a_goal_walled_off_has_no_route_within_the_sample_budget():
    """The kink's goal inside a ring of walls: no route, said, after the sample budget."""
    inst = dynobench.load(KINK)
    ring = [dynobench.instance.Box((5.5, 4.0 + d), (1.4, 0.1)) for d in (-0.55, 0.55)] + \
           [dynobench.instance.Box((5.5 + d, 4.0), (0.1, 1.2)) for d in (-0.55, 0.55)]
    boxed = replace(inst, obstacles=tuple(ring))
    why = plane_route.route(obstacles(boxed, 5e-3), UNICYCLE, inst.start, inst.goal, inst.low, inst.high, 0.5, 0.5)
    assert isinstance(why, str) and "no route" in why and str(plane_route.MAX_SAMPLES) in why
