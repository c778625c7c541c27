"""The mechanisms the toolkit derives and generates code for, by name.

Adding a mechanism means adding one entry here: a function returning a
:class:`~derivations.mechanisms.Mechanism` (see ``notebooks/04_adding_a_mechanism.ipynb``).
"""
from __future__ import annotations

from collections.abc import Callable

import sympy as sp

from .mechanisms import (
    Mechanism,
    PlatformGeometry,
    a,
    b,
    body_rate_mechanism,
    paper_platform,
    platform_mechanism,
    rho,
)
from .rotations import e1, e2, e3
from .vehicles import (
    brockett_integrator,
    car_with_trailer,
    double_integrator,
    kinematic_car,
    rolling_ball,
    second_order_unicycle,
    unicycle,
)

#: A second placement of the platform's legs and disk. The paper's legs are radial at
#: the identity (base and platform joints on one line through O), which makes the
#: identity the singular point of Δ = 0. Here the base joints are raised 45° above the
#: platform joints' plane and the disk rolls on the equator between the legs with a
#: horizontal axle: the identity becomes a regular home pose (Δ(I) = 1, the leg rows and
#: the disk row orthonormal there), while Δ = 0 still splits SO(3) into two regions.
RAISED_GEOMETRY = PlatformGeometry(
    base1=tuple(a * (e1 + e3) / sp.sqrt(2)), tip1=tuple(b * e1),
    base2=tuple(a * (e2 + e3) / sp.sqrt(2)), tip2=tuple(b * e2),
    contact=tuple(rho * (e1 + e2) / sp.sqrt(2)), axle=tuple((e1 - e2) / sp.sqrt(2)),
)

MECHANISMS: dict[str, Callable[[], Mechanism]] = {
    "platform": paper_platform,
    "platform_raised": lambda: platform_mechanism(
        "platform_raised", RAISED_GEOMETRY,
        "orienting platform with raised leg bases and the disk on the equator; identity regular"),
    "attitude": lambda: body_rate_mechanism(
        "attitude", (1, 0, 0), (0, 1, 0),
        "rigid body steered by two body-fixed angular rates about e1 and e2"),
    # state beyond SO(3) (derivations/vehicles.py)
    "rolling_ball": rolling_ball,
    "car": kinematic_car,
    "car_with_trailer": car_with_trailer,
    # the textbook systems whose least-energy motions are known in closed form
    "brockett": brockett_integrator,
    "unicycle": unicycle,
    # systems with drift, dx/dt = f(x) + G(x) u
    "double_integrator": double_integrator,
    "unicycle2": second_order_unicycle,
}


def get(name: str) -> Mechanism:
    """The mechanism called ``name`` (``KeyError`` lists the known names)."""
    try:
        return MECHANISMS[name]()
    except KeyError:
        raise KeyError(f"unknown mechanism {name!r}; known: {', '.join(MECHANISMS)}") from None
