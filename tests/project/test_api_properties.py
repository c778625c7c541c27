"""Property tests over the public entry points: any value of any one argument gives a
result or a ``ValueError``/``TypeError`` whose message names that argument — never another
exception, never a hang (Hypothesis draws the values; the other arguments are valid)."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import nonholo
from nonholo.constraints import Clearance, LegSpeed, LegStroke
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

#: the keywords of ``plan`` drawn (each on its own), the fields of its ``Settings`` and the
#: numbers of its constraints (each built from the value drawn), the rest valid and cheap
ARGUMENTS = ["start", "goal", "T", "strategy", "mechanism", "route", "objective", "u0", "callback",
             "constraints", "settings"]
SETTINGS_FIELDS = ["method", "harmonics", "grid", "gamma", "step", "tol", "max_iter", "steps", "newton_below",
                   "min_step"]
CONSTRAINTS = {"delta_min": lambda v: Clearance(v), "leg_length": lambda v: LegStroke(v, 2.0),
               "leg_speed": lambda v: LegSpeed(v)}
#: The word a constraint's error names it by: its field, or the class for a pair of ends.
NAMED_AS = {"leg_length": "LegStroke"}
CHEAP = {"max_iter": 3}


def _names(exc: BaseException, name: str) -> bool:
    return name in str(exc)


@pytest.mark.parametrize("name", ARGUMENTS)
@settings(max_examples=8, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(value=ANYTHING)
@pytest.mark.slow
def test_plan_refuses_or_plans_whatever_one_argument_is(name, value):
    kwargs = {"start": R0, "goal": RD, "settings": nonholo.Settings(**CHEAP), name: value}
    try:
        res = nonholo.plan(kwargs.pop("start"), kwargs.pop("goal"), **kwargs)
    except (ValueError, TypeError) as exc:
        assert _names(exc, NAMED_AS.get(name, name)), f"{name}={value!r}: {type(exc).__name__}: {exc}"
    else:
        assert isinstance(res, nonholo.PlanResult)


@pytest.mark.parametrize("name", SETTINGS_FIELDS + list(CONSTRAINTS))
@settings(max_examples=8, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(value=ANYTHING)
@pytest.mark.slow
def test_plan_refuses_or_plans_whatever_one_setting_or_constraint_is(name, value):
    try:
        if name in CONSTRAINTS:
            kwargs = {"settings": nonholo.Settings(**CHEAP), "constraints": [CONSTRAINTS[name](value)]}
        else:
            kwargs = {"settings": nonholo.Settings(**{**CHEAP, name: value})}
        res = nonholo.plan(R0, RD, **kwargs)
    except (ValueError, TypeError) as exc:
        assert _names(exc, NAMED_AS.get(name, name)), f"{name}={value!r}: {type(exc).__name__}: {exc}"
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
