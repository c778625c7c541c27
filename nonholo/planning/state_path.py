"""Paths of states beyond SO(3) for the global route (:mod:`nonholo.planning.route`).

A state is a pair ``(R, q)`` (:mod:`nonholo.spaces.product`). The straight path from ``a`` to ``b``
moves the orientation along its geodesic and the coordinates along their difference
(angles the short way round), both at constant rate:

    ``R(s) = exp(s·log(R_b R_aᵀ)) R_a``,  ``q(s) = q_a + s·(q_b ⊖ q_a)``,  ``s ∈ [0, 1]``.

It is the global route's path for mechanisms beyond SO(3): there the local planner's
difficulty is distance (a car told to go 60 lengths away), not topology. The component
of the start is then what the path must keep to: every sample of the path (:data:`SAMPLES_PER_HOP`
a hop) keeps ``sgnΔ`` at least ``delta_min``, else there is no straight path. For the car
(``Δ = cos φ``) the straight path is always clear when its ends are, since ``φ(s)`` stays
between theirs; a mechanism whose component is not convex in its coordinates would need a
roadmap of it, which this module does not build.
"""
from __future__ import annotations

import math

import numpy as np


#: The longest hop of a straight path, in the stacked error's norm (rad and the
#: mechanism's units): goals this far are ones the local planner reaches reliably.
MAX_HOP = 4.0
#: The largest sensitivity of a hop the global route keeps beyond SO(3) (a larger one is
#: split). On SO(3) a hop's sensitivity grows with its closeness to ``Δ = 0`` and the
#: stitched motion multiplies its hops' (:data:`nonholo.planning.route_paths.MAX_HOP_SENSITIVITY`);
#: a straight path of states keeps away from ``Δ = 0`` by construction, and a hop's
#: sensitivity grows with its length as a lever arm (a heading error ``δθ`` moves a car's
#: end by about its distance times ``δθ``), which the stitched motion adds up rather than
#: multiplies.
MAX_HOP_SENSITIVITY = 100.0
#: Seconds of effort (:mod:`nonholo.numerics.effort`) the global route may take beyond SO(3), from
#: its start: a long straight path has many hops.
TIME_BUDGET = 5.0
#: Points of a hop at which the path's ``sgnΔ`` is checked.
SAMPLES_PER_HOP = 16
#: The most hops of a straight path: a goal farther than ``MAX_HOPS · MAX_HOP`` has no
#: path (its hops could not be planned within :data:`TIME_BUDGET` anyway).
MAX_HOPS = 1000


def interpolate(mechanism, a, b, s) -> list[tuple[np.ndarray, np.ndarray]]:
    """The states of the straight path ``a → b`` at some fractions of it.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.
    a, b : tuple
        The ends, states ``(R, q)``.
    s : array_like
        Fractions in ``[0, 1]``.

    Returns
    -------
    list of tuple
        The states ``(R, q)``.
    """
    return mechanism.space.interpolate(a, b, s)


def midpoint(mechanism, a, b) -> tuple[np.ndarray, np.ndarray]:
    """The state halfway along the straight path ``a → b``.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.
    a, b : tuple
        The ends, states ``(R, q)``.

    Returns
    -------
    tuple
        The state ``(R, q)``.
    """
    return interpolate(mechanism, a, b, [0.5])[0]


def length(mechanism, a, b) -> float:
    """The straight path's length: the norm of the stacked error between its ends.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.
    a, b : tuple
        The ends, states ``(R, q)``.

    Returns
    -------
    float
        The length.
    """
    return mechanism.space.distance(a, b)


def too_far(mechanism, a, b, max_hop: float = MAX_HOP) -> str | None:
    """Why the straight path ``a → b`` is not tried (more than :data:`MAX_HOPS` hops).

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.
    a, b : tuple
        The ends, states ``(R, q)``.
    max_hop : float, default MAX_HOP
        The longest hop.

    Returns
    -------
    str or None
        The reason, or ``None``: it is tried.
    """
    far = length(mechanism, a, b)
    if not far <= MAX_HOPS * max_hop:
        return (f"the goal is {far:.3g} from the start: its straight path would take more than "
                f"{MAX_HOPS} hops of at most {max_hop:g}")
    return None


def straight_path(mechanism, a, b, *, delta_min: float, max_hop: float = MAX_HOP) -> list | None:
    """The straight path ``a → b`` as its ends and inner points, hops of at most ``max_hop``.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.
    a, b : tuple
        The ends, states ``(R, q)``.
    delta_min : float
        The clearance every sample keeps (``sgnΔ``, the sign of ``Δ`` at ``a``).
    max_hop : float, default MAX_HOP
        The longest hop.

    Returns
    -------
    list of tuple or None
        The states ``(R, q)``, ``a`` first, ``b`` last; ``None`` where a sample has
        ``sgnΔ < delta_min`` or the path is :func:`too_far`.
    """
    if too_far(mechanism, a, b, max_hop) is not None:
        return None
    hops = max(1, math.ceil(length(mechanism, a, b) / max_hop))
    # Δ ≡ +∞ without a singular set: every path is clear
    s = np.linspace(0.0, 1.0, hops * SAMPLES_PER_HOP + 1)
    points = interpolate(mechanism, a, b, s)
    d = mechanism.singular.values(np.stack([p.R for p in points]), np.stack([p.q for p in points]))
    sign = np.sign(d[0])
    if sign == 0.0 or not np.all(sign * d >= delta_min):
        return None
    inner = interpolate(mechanism, a, b, np.arange(1, hops) / hops) if hops > 1 else []
    return [a, *inner, b]
