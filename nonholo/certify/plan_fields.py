"""A plan's fields, value by value: the format's names (:data:`~nonholo.certify.plan_fields.FORMAT` and the earlier
formats still read), the routes and methods a plan may record, and the typed checks of
one field (a string, number, integer, rotation, finite JSON value), each raising
``ValueError("invalid plan: '<field>' ...")``. Shared by the plan file's decoding
(:mod:`nonholo.io.plan_file`) and the checks of a plan's numbers
(:mod:`nonholo.certify.plan_checks`)."""
from __future__ import annotations

import math

import numpy as np

from ..model.bounds import InputBounds, StateBounds
from ..model.obstacles import Obstacles
from ..model.limits import LegLimits
from ..motion.speed_limits import check_leg_speed
from ..numerics.checks import MAX_STEPS, check_count, is_number
from ..spaces import so3

#: the format written (``PlanResult.save``)
FORMAT = "nonholo.plan/3"
#: the format before global routes (``route``, stitched controls): still loaded
FORMAT_2 = "nonholo.plan/2"
#: the format before certificates (``replay_steps``, ``error_bound``): still loaded, checked
#: against the planner's own replay
FORMAT_1 = "nonholo.plan/1"
#: how a plan reached its goal: one local plan, or a global route of stitched hops
ROUTES = ("local", "global")

#: the planner's methods, by the kind of the parametrisation each plans with
METHOD_OF_KIND = {"fourier": "parametric", "legendre": "parametric", "piecewise_constant": "nonparametric"}
#: the options every plan records (``plan()``'s settings, :class:`nonholo.planning.core.Options`,
#: and its parametrisation's size), in every format: by the rule ``plan()`` checks each with —
#: a positive number, a non-negative number, or an integer >= the minimum
OPTION_RULES = {"gamma": "positive", "step": "positive", "tol": "positive", "min_step": "positive",
                "newton_below": "non-negative", "delta_min": "non-negative",
                "max_iter": 0, "harmonics": 1, "grid": 1}
#: the options a plan records only when they were given (absent: none)
OPTIONAL_OPTIONS = ("leg_length", "leg_speed", "objective", "input_bounds", "state_bounds", "obstacles")
#: the objectives a plan may record
OBJECTIVES = ("energy", "auto")
#: ``R0``, ``Rd`` and the samples ``R``: ``|RᵀR − I| ≤`` this (as :func:`nonholo.plan` accepts)
ROTATION_TOL = 1e-9


def fail(field: str, message: str):
    """Raise the ``ValueError`` of a bad plan field.

    Parameters
    ----------
    field : str
        The field's name.
    message : str
        What is wrong with it.

    Raises
    ------
    ValueError
        Always: ``invalid plan: '<field>' <message>``.
    """
    raise ValueError(f"invalid plan: {field!r} {message}")


def short(x) -> str:
    """``repr(x)``, cut to 60 characters.

    Parameters
    ----------
    x : object
        Any value.

    Returns
    -------
    str
        Its ``repr``, at most 60 characters.
    """
    try:
        text = repr(x)
    except ValueError:             # an integer too long to print
        return "a very large integer"
    return text if len(text) <= 60 else text[:57] + "..."


def json_type(x) -> str:
    """What ``x`` is, in JSON's words (for messages).

    Parameters
    ----------
    x : object
        A value decoded from JSON.

    Returns
    -------
    str
        ``null``, ``true``/``false``, ``an object``, ``an array``, the string or the number.
    """
    if x is None:
        return "null"
    if isinstance(x, bool):
        return str(x).lower()
    if isinstance(x, dict):
        return "an object"
    if isinstance(x, (list, tuple)):
        return "an array"
    if isinstance(x, str):
        return f"the string {short(x)}"
    return short(x)


def string_field(d: dict, key: str, empty: bool = False, where: str = "") -> str:
    """``d[key]``, a (non-empty unless ``empty``) string.

    Parameters
    ----------
    d : dict
        The plan's (or a part's) fields.
    key : str
        The field.
    empty : bool, default False
        Whether the empty string is accepted.
    where : str, default ""
        A prefix of the field's name in messages (``"controls."``).

    Returns
    -------
    str
        The value.

    Raises
    ------
    ValueError
        If the value is not such a string.
    """
    v = d[key]
    if not isinstance(v, str) or (not v and not empty):
        fail(where + key, f"must be a {'' if empty else 'non-empty '}string, got {json_type(v)}")
    return v


def number_field(d: dict, key: str, null: bool = False, where: str = "") -> float | None:
    """``d[key]``, a finite number (or ``None`` if ``null``), as a float.

    Parameters
    ----------
    d : dict
        The plan's (or a part's) fields.
    key : str
        The field.
    null : bool, default False
        Whether ``None`` is accepted.
    where : str, default ""
        A prefix of the field's name in messages.

    Returns
    -------
    float or None
        The value.

    Raises
    ------
    ValueError
        If the value is not a finite number (nor an accepted ``None``).
    """
    v = d[key]
    if v is None and null:
        return None
    if not is_number(v):
        fail(where + key, f"must be a number{' or null' if null else ''}, got {json_type(v)}")
    try:
        x = float(v)
    except OverflowError:
        x = float("inf")
    if not np.isfinite(x):
        fail(where + key, f"must be finite{' (or null)' if null else ''}, got {v!r}")
    return x


def integer_field(d: dict, key: str, minimum: int, where: str = "") -> int:
    """``d[key]``, an integer ``>= minimum`` (``steps``: at most ``MAX_STEPS``).

    Parameters
    ----------
    d : dict
        The plan's (or a part's) fields.
    key : str
        The field.
    minimum : int
        The least value accepted.
    where : str, default ""
        A prefix of the field's name in messages.

    Returns
    -------
    int
        The value.

    Raises
    ------
    ValueError
        If the value is not such an integer.
    """
    v = d[key]
    if not isinstance(v, (int, np.integer)) or isinstance(v, (bool, np.bool_)) or v < minimum:
        fail(where + key, f"must be an integer >= {minimum}, got {json_type(v)}")
    if key == "steps" and v > MAX_STEPS:
        fail(where + key, f"must be at most {MAX_STEPS}, got {v}")
    return int(v)


def rotation_field(R, field: str) -> None:
    """Check that ``R`` is a rotation within :data:`ROTATION_TOL`.

    Parameters
    ----------
    R : array_like
        The field's value, a 3×3 matrix.
    field : str
        The field's name, for the message.

    Raises
    ------
    ValueError
        If ``R`` is not such a rotation.
    """
    try:
        so3.check_rotation(R, repr(field), ROTATION_TOL)
    except ValueError as exc:
        raise ValueError(f"invalid plan: {exc}") from None


def scan_finite(value, field: str) -> None:
    """Check that every number inside a JSON value is finite (iteratively: no recursion).

    Parameters
    ----------
    value : object
        A value decoded from JSON.
    field : str
        The field's name, for the message.

    Raises
    ------
    ValueError
        If a number inside is not finite.
    """
    stack = [value]
    while stack:
        x = stack.pop()
        if isinstance(x, dict):
            stack.extend(x.values())
        elif isinstance(x, (list, tuple)):
            stack.extend(x)
        elif is_number(x) and not np.isfinite(float(x)):
            fail(field, f"contains a non-finite number ({x})")


def check_options(options, mechanism) -> None:
    """Check a plan's record of the options it was planned with.

    It holds every option of :data:`OPTION_RULES` with a value :func:`nonholo.plan` accepts
    (checked by its own rules), and otherwise only ``leg_length``, ``leg_speed`` (as
    ``plan()`` checks them for ``mechanism``), ``input_bounds``, ``state_bounds``
    (:meth:`~nonholo.model.bounds.Box.from_record`), ``obstacles``
    (:meth:`~nonholo.model.obstacles.Obstacles.from_record`) and ``objective``: a missing
    option is refused, never taken as unchecked.

    Parameters
    ----------
    options : dict
        The plan's ``options`` field.
    mechanism : Mechanism
        The mechanism planned.

    Raises
    ------
    ValueError
        If an option is missing, unknown or has a bad value.
    """
    if not isinstance(options, dict):
        fail("options", f"must be an object, got {json_type(options)}")
    missing = [k for k in OPTION_RULES if k not in options]
    if missing:
        fail("options", f"lacks {', '.join(map(repr, missing))} (every plan records "
                        f"{', '.join(OPTION_RULES)})")
    unknown = [k for k in options if k not in OPTION_RULES and k not in OPTIONAL_OPTIONS]
    if unknown:
        fail("options", f"has unknown option{'s' if len(unknown) > 1 else ''} "
                        f"{', '.join(short(k) for k in unknown)}")
    for key, rule in OPTION_RULES.items():
        v = options[key]
        if isinstance(rule, int):
            try:
                check_count(v, key, minimum=rule)
            except ValueError as exc:
                fail("options", f"has a bad {key}: {exc}")
            if not isinstance(v, (int, np.integer)):
                fail("options", f"has a bad {key}: must be an integer, got {short(v)}")
            continue
        if not is_number(v) or not math.isfinite(v) or (v <= 0 if rule == "positive" else v < 0):
            fail("options", f"has a bad {key}: must be a {rule} finite number, as plan() takes it, "
                            f"got {json_type(v)}")
    try:
        if "leg_length" in options:
            if options["leg_length"] is None:
                raise ValueError("leg_length is recorded only when given: null is not a value")
            LegLimits.from_argument(options["leg_length"], mechanism)
        if "leg_speed" in options:
            if options["leg_speed"] is None:
                raise ValueError("leg_speed is recorded only when given: null is not a value")
            check_leg_speed(options["leg_speed"], mechanism)
        for key, kind in (("input_bounds", InputBounds), ("state_bounds", StateBounds), ("obstacles", Obstacles)):
            if key in options:
                kind.from_record(options[key], mechanism, key)
    except ValueError as exc:
        fail("options", f"has a bad {str(exc).split()[0].rstrip(':')}: {exc}")
    if "objective" in options and options["objective"] not in OBJECTIVES:
        fail("options", f"has an unknown objective {short(options['objective'])} "
                        f"(known: {', '.join(map(repr, OBJECTIVES))})")
