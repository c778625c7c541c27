"""The global route's paths and the size of its hops (:mod:`nonholo.planning.route`): where the
route goes, and how a hop is measured, split, kept clear of ``Δ = 0`` and capped.

:class:`RoadmapPaths` gives the roadmap's paths of orientations for a state on SO(3) alone
(:mod:`nonholo.planning.roadmap`, one per cost of
:data:`nonholo.planning.roadmap.CONDITIONING_POWERS`), :class:`StraightPaths` the straight
path of states for a state with coordinates (:mod:`nonholo.planning.state_path`);
:func:`paths_for` is the one of a mechanism. A hop keeps ``|Δ|`` at least
:func:`hop_delta_min` and a sensitivity at most :func:`max_hop_sensitivity`; the route's
budget of effort is :func:`time_budget`.
"""
from __future__ import annotations

import numpy as np

from ..model.mechanism import Mechanism
from ..numerics import effort
from ..spaces import so3
from . import roadmap, state_path

#: A hop planned with a larger sensitivity is split instead: the stitched motion's
#: sensitivity grows like the product of its hops'.
MAX_HOP_SENSITIVITY = 10.0
#: Hops keep ``|Δ|`` at least this (or half what their ends have, if less): a motion close
#: to ``Δ = 0`` is ill-conditioned, and the stitched motion multiplies its hops' conditioning.
HOP_DELTA_MIN = 0.05
#: Seconds of effort (:mod:`nonholo.numerics.effort`: integration counted in steps, seconds of the
#: reference machine) after the start of :func:`nonholo.plan` (the local attempt included)
#: after which the global route tries no further hop, and no smoothing is started or
#: continued. Effort, not wall time: a plan does not depend on the machine's speed or load.
TIME_BUDGET = 2.5


class RoadmapPaths:
    """The route's paths for a state on SO(3) alone: the roadmap's paths of orientations
    (:mod:`nonholo.planning.roadmap`), hops measured in rad, the budget counted from the
    start of :func:`nonholo.plan`.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism planned.
    """

    unit = " rad"
    max_hop_sensitivity = MAX_HOP_SENSITIVITY

    def __init__(self, mechanism: Mechanism):
        self.mechanism = mechanism

    def paths(self, start, goal, delta_min: float, leg_limits):
        """The paths :func:`~nonholo.planning.route.steer` tries in turn: the roadmap's, one per
        cost.

        The costs are those of :data:`nonholo.planning.roadmap.CONDITIONING_POWERS`, in order.

        Parameters
        ----------
        start, goal : tuple
            The ends, states ``(R, q)``.
        delta_min : float
            The least ``sgnΔ`` anywhere.
        leg_limits : LegLimits or None
            Stroke limits the paths keep inside.

        Yields
        ------
        list of tuple or None
            A path of states ``(R, q)``, or ``None`` for none.
        """
        for power in roadmap.CONDITIONING_POWERS:
            path = roadmap.orientation_path(self.mechanism, start[0], goal[0], delta_min=delta_min,
                                            power=power, legs=leg_limits)
            yield None if path is None else [self.mechanism.space.state(R) for R in path]

    def no_path(self, leg_limits, start, goal) -> str:
        """Why no path of :meth:`paths` was given.

        Parameters
        ----------
        leg_limits : LegLimits or None
            The stroke limits.
        start, goal : tuple
            The ends, states ``(R, q)``.

        Returns
        -------
        str
            The reason.
        """
        within = "" if leg_limits is None else " and inside the legs' stroke limits"
        return f"no path of orientations clear of Δ = 0{within} joins the start and the goal on the roadmap"

    def length(self, a, b) -> float:
        """The length of the hop ``a → b`` (rad).

        Parameters
        ----------
        a, b : tuple
            The ends, states ``(R, q)``.

        Returns
        -------
        float
            The geodesic angle between their orientations.
        """
        return so3.distance(a[0], b[0])

    def midpoint(self, a, b) -> tuple:
        """The state halfway between ``a`` and ``b``, where a failed hop is split.

        Parameters
        ----------
        a, b : tuple
            The ends, states ``(R, q)``.

        Returns
        -------
        tuple
            The state ``(R, q)``.
        """
        return self.mechanism.space.interpolate(a, b, [0.5])[0]

    def time_budget(self, plan_started: float) -> tuple[float, float]:
        """When the route's clock starts and its budget (seconds of effort).

        Parameters
        ----------
        plan_started : float
            The :func:`nonholo.numerics.effort.seconds` reading at the start of
            :func:`nonholo.plan`.

        Returns
        -------
        started : float
            When the route's clock starts: ``plan_started``.
        budget : float
            :data:`TIME_BUDGET`.
        """
        return plan_started, TIME_BUDGET

    def through(self) -> str:
        """What the route goes through, for the result's reason.

        Returns
        -------
        str
            ``"a path of orientations clear of Δ = 0"``.
        """
        return "a path of orientations clear of Δ = 0"


class StraightPaths(RoadmapPaths):
    """The route's paths for a state with coordinates: the straight path of states
    (:mod:`nonholo.planning.state_path`), hops measured in the stacked error's norm, the
    budget counted from the route's own start (the local attempt at a far goal can take
    the whole of :data:`TIME_BUDGET`).

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism planned.
    """

    max_hop_sensitivity = state_path.MAX_HOP_SENSITIVITY

    @property
    def unit(self) -> str:
        """The stacked error's unit (:attr:`nonholo.spaces.product.Product.error_unit`), spaced."""
        unit = self.mechanism.space.error_unit
        return f" {unit}" if unit else ""

    def paths(self, start, goal, delta_min: float, leg_limits):
        """The one path :func:`~nonholo.planning.route.steer` tries: the straight path of states.

        Parameters
        ----------
        start, goal : tuple
            The ends, states ``(R, q)``.
        delta_min : float
            The least ``sgnΔ`` anywhere.
        leg_limits : LegLimits or None
            Not used (no mechanism with coordinates has legs).

        Yields
        ------
        list of tuple or None
            The path (:func:`nonholo.planning.state_path.straight_path`), or ``None``.
        """
        yield state_path.straight_path(self.mechanism, start, goal, delta_min=delta_min)

    def no_path(self, leg_limits, start, goal) -> str:
        """Why there is no straight path.

        Parameters
        ----------
        leg_limits : LegLimits or None
            Not used.
        start, goal : tuple
            The ends, states ``(R, q)``.

        Returns
        -------
        str
            The reason: too far, or too close to ``Δ = 0``.
        """
        return state_path.too_far(self.mechanism, start, goal) or (
            f"the straight path of states comes within delta_min of the singular set Δ = 0 of "
            f"{self.mechanism.name!r}")

    def length(self, a, b) -> float:
        """The length of the hop ``a → b``, in the stacked error's norm.

        Parameters
        ----------
        a, b : tuple
            The ends, states ``(R, q)``.

        Returns
        -------
        float
            The length (:func:`nonholo.planning.state_path.length`).
        """
        return state_path.length(self.mechanism, a, b)

    def time_budget(self, plan_started: float) -> tuple[float, float]:
        """When the route's clock starts and its budget (seconds of effort).

        Parameters
        ----------
        plan_started : float
            Not used: the clock starts now.

        Returns
        -------
        started : float
            The :func:`nonholo.numerics.effort.seconds` reading now.
        budget : float
            :data:`nonholo.planning.state_path.TIME_BUDGET`.
        """
        return effort.seconds(), state_path.TIME_BUDGET

    def through(self) -> str:
        """What the route goes through, for the result's reason.

        Returns
        -------
        str
            ``"a straight path of states"``, clear of ``Δ = 0`` where there is a singular set.
        """
        return "a straight path of states" + self.mechanism.singular.kept_clear


def paths_for(mechanism: Mechanism) -> RoadmapPaths:
    """The route's path provider for a mechanism's space.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.

    Returns
    -------
    RoadmapPaths
        The roadmap of orientations for a state on SO(3) alone, the straight path of
        states (:class:`StraightPaths`) otherwise.
    """
    return StraightPaths(mechanism) if mechanism.space.k else RoadmapPaths(mechanism)


def time_budget(mechanism: Mechanism, plan_started: float) -> tuple[float, float]:
    """When the route's clock starts and its budget, seconds of effort (:func:`paths_for`).

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.
    plan_started : float
        The :func:`nonholo.numerics.effort.seconds` reading at the start of :func:`nonholo.plan`.

    Returns
    -------
    started : float
        When the route's clock starts.
    budget : float
        Its budget.
    """
    return paths_for(mechanism).time_budget(plan_started)


def max_hop_sensitivity(mechanism: Mechanism) -> float:
    """The largest sensitivity of a hop the route keeps (a larger one is split).

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.

    Returns
    -------
    float
        :data:`MAX_HOP_SENSITIVITY` on SO(3),
        :data:`nonholo.planning.state_path.MAX_HOP_SENSITIVITY` with coordinates (see there
        why it is larger).
    """
    return paths_for(mechanism).max_hop_sensitivity


def hop_delta_min(mechanism: Mechanism, a, b, delta_min: float) -> float:
    """The ``delta_min`` of a hop between two states.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.
    a, b : tuple
        The hop's ends, states ``(R, q)``.
    delta_min : float
        The run's ``delta_min``.

    Returns
    -------
    float
        :data:`HOP_DELTA_MIN`, or half the least ``|Δ|`` of its ends if that is less, never
        below the run's ``delta_min`` (which is all a mechanism without a singular set has).
    """
    ends = float(np.min(np.abs(mechanism.singular.values(np.stack([a[0], b[0]]), np.stack([a[1], b[1]])))))
    if not np.isfinite(ends):         # Δ ≡ +∞: no singular set to keep clear of
        return delta_min
    return max(delta_min, min(HOP_DELTA_MIN, 0.5 * ends))
