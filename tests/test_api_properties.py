"""Property tests over the public entry points: any value of any one argument gives a
result or a ``ValueError``/``TypeError`` whose message names that argument — never another
exception, never a hang (Hypothesis draws the values; the other arguments are valid)."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import nonholo
from nonholo.controls.parametrisations import Fourier
from nonholo.spaces import so3

R0 = so3.from_rpy(0.3, 0.2, 0.1)
RD = so3.from_rpy(0.5, -0.2, 0.4)

#: arbitrary values: numbers of every kind, strings, containers, arrays of odd shapes
ANYTHING = st.one_of(
    st.none(), st.booleans(), st.integers(min_value=-10**30, max_value=10**30),
    st.floats(allow_nan=True, allow_infinity=True), st.complex_numbers(), st.text(max_size=5),
    st.lists(st.floats(allow_nan=False, width=32), max_size=5),
    st.builds(lambda n, m: np.ones((n, m)), st.integers(0, 4), st.integers(0, 4)),
    st.builds(lambda x: np.full((3, 3), x), st.floats()),
    st.just(np.eye(3) * 2), st.just(object()), st.dictionaries(st.text(max_size=3), st.integers(), max_size=2),
)

#: the keywords of ``plan`` drawn (each on its own), with the cheap settings the rest keep
ARGUMENTS = ["R0", "Rd", "T", "method", "harmonics", "grid", "gamma", "step", "tol", "max_iter", "strategy",
             "mechanism", "delta_min", "steps", "newton_below", "min_step", "route", "leg_length",
             "leg_speed", "objective", "u0", "callback"]
CHEAP = {"max_iter": 3}


def _names(exc: BaseException, name: str) -> bool:
    text = str(exc)
    return name in text or (name == "Rd" and "goal" in text) or (name == "R0" and "start" in text)


@pytest.mark.parametrize("name", ARGUMENTS)
@settings(max_examples=8, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(value=ANYTHING)
def test_plan_refuses_or_plans_whatever_one_argument_is(name, value):
    kwargs = {**CHEAP, "R0": R0, "Rd": RD, name: value}
    try:
        res = nonholo.plan(kwargs.pop("R0"), kwargs.pop("Rd"), **kwargs)
    except (ValueError, TypeError) as exc:
        assert _names(exc, name), f"{name}={value!r}: {type(exc).__name__}: {exc}"
    else:
        assert isinstance(res, nonholo.PlanResult)


@settings(max_examples=40, deadline=None, derandomize=True, database=None)
@given(value=ANYTHING, name=st.sampled_from(["T", "steps", "mechanism"]))
def test_simulate_refuses_or_simulates_whatever_one_argument_is(value, name):
    kwargs = {"T": 1.0, "steps": 50, "mechanism": "attitude", name: value}
    controls = Fourier(1.0, [[0.3, 0, 0], [0, 0.2, 0]])
    try:
        tr = nonholo.simulate(R0, controls, kwargs.pop("T"), **kwargs)
    except (ValueError, TypeError) as exc:
        assert _names(exc, name), f"{name}={value!r}: {type(exc).__name__}: {exc}"
    else:
        assert np.all(np.isfinite(tr.R_T))
