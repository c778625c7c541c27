"""The clearance grid (``nonholo.planning.clearance_grid``): a body it calls clear is clear by the
margin by shapely's exact distance, at random placements among boxes; one far from every box
it calls clear; bad input refused naming it."""
import numpy as np
import pytest
import shapely

from nonholo.model.obstacles import Body, body_corners, body_pose
from nonholo.planning.clearance_grid import ClearanceGrid


class Plane:
    coordinates = ("x", "y", "theta", "theta1")


BOXES = [((1.0, 1.0), (0.5, 0.3)), ((2.2, 1.6), (0.2, 1.4)), ((1.5, 2.5), (1.2, 0.2))]
BODIES = (Body(0.5, 0.25), Body(0.3, 0.25, heading="theta1", behind=0.5))


def union():
    return shapely.union_all([shapely.box(cx - a / 2, cy - b / 2, cx + a / 2, cy + b / 2) for (cx, cy), (a, b) in BOXES])


@pytest.mark.parametrize("margin", [0.0, 0.005, 0.05])
def test_a_body_called_clear_is_clear_by_the_margin(margin):
    shapes = union()
    grid = ClearanceGrid(shapes, BODIES, (0.0, 0.0), (3.0, 3.0), 0.025, margin)
    rng = np.random.default_rng(11)
    q = np.column_stack([rng.uniform(0, 3, 4000), rng.uniform(0, 3, 4000), rng.uniform(-np.pi, np.pi, 4000),
                         rng.uniform(-np.pi, np.pi, 4000)])
    called = 0
    for i, body in enumerate(BODIES):
        centres, headings = body_pose(Plane, q, body)
        clear = grid.clear(centres, headings, i)
        exact = shapely.distance(shapely.polygons(body_corners(Plane, q, body)), shapes)
        assert np.all(exact[clear] >= margin - 1e-12)
        # the test is not useless: most placements well away from the boxes are called clear
        far = exact >= margin + 0.2
        assert clear[far].mean() > 0.9
        called += clear.sum()
    assert called > 0


def test_bad_spacing_is_refused_naming_it():
    with pytest.raises(ValueError, match="spacing"):
        ClearanceGrid(union(), BODIES, (0.0, 0.0), (3.0, 3.0), 0.0, 0.0)
