"""The global route's budget is effort (nonholo/numerics/effort.py), not wall time: a plan does not
depend on how fast the machine runs it."""
import json
import time

import numpy as np
import pytest
from conftest import far_pair

from nonholo.controls import stages
from nonholo.controls.parametrisations import Fourier
from nonholo.integrate.compiled import compiled_system
from nonholo.model import catalog
from nonholo.numerics import effort
from nonholo.planning.api import plan


def test_kernels_count_their_steps():
    mech = catalog.get("platform")
    kern = compiled_system(mech, False)
    u = Fourier(1.0, [[0.1, 0.0, 0.0], [0.2, 0.0, 0.0]])
    U = np.ascontiguousarray(stages.stage_table(u, 400))
    before = effort.seconds()
    kern.forward(np.eye(3) @ np.diag([1.0, -1.0, -1.0]), np.zeros(0), U, 1 / 400, 1.0, -np.inf, *kern.nodes(400))
    assert effort.seconds() - before == pytest.approx(effort.FORWARD_WEIGHT * 400 / effort.STEPS_PER_SECOND,
                                                      rel=0, abs=1e-12)


@pytest.mark.slow
def test_a_global_route_is_the_same_on_a_slow_clock(monkeypatch):
    p = far_pair()
    first = plan(p["R0"], p["Rd"])
    assert first.route == "global" and first.success
    real = time.perf_counter
    slow = {"t": real()}

    def crawling():                 # every reading ten seconds later than the last
        slow["t"] += 10.0
        return slow["t"]

    monkeypatch.setattr(time, "perf_counter", crawling)
    again = plan(p["R0"], p["Rd"])
    monkeypatch.setattr(time, "perf_counter", real)
    a, b = first.to_dict(), again.to_dict()
    a.pop("seconds"), b.pop("seconds")
    assert json.dumps(a) == json.dumps(b)


@pytest.mark.slow
def test_a_plan_does_not_depend_on_the_effort_counted_before():
    """The default plan (its least-energy stage ends on a budget of effort) of a car pair
    whose budget once ended on a tie, after different amounts of effort counted before in
    the process: the same plan every time (the count and its readings are exact)."""
    def car():
        result = plan([0.0, 0.0, 0.0, 0.0], [0.517410922309838, 0.7569603693325078, -0.3976800780779256, 0.0],
                      mechanism="car")
        d = result.to_dict()
        d.pop("seconds")
        return json.dumps(d)

    first = car()
    for before in (0.2, 12345.6, 526160.0, 3.0e7 + 0.4):
        effort.add(before)
        assert car() == first
