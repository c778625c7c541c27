"""What a plan keeps along its motion, as objects in a list (as python-control's
``trajectory_constraints`` and opty's ``bounds``): the clearance from the singular set,
the legs' stroke and the legs' speed, bounds on the inputs and on the coordinates.

Each constraint is checked against its mechanism when a :class:`~nonholo.planning.problem.Problem`
is built (``ValueError`` naming the argument), and says whether a start and a goal can be
joined at all (their ``refusal``, before anything is simulated). Along the motion the planner
and the certificate keep them (:mod:`nonholo.planning.endpoint_map`, :mod:`nonholo.certify.certificate`);
the legs' speed and the inputs' bounds are kept by re-timing the planned path
(:mod:`nonholo.planning.retime`), the coordinates' bounds like the legs' stroke
(:mod:`nonholo.model.limits`). :class:`~nonholo.model.obstacles.Obstacles` (:mod:`nonholo.model.obstacles`), the
bodies of a planar vehicle kept clear of polygons, are kept inside the least-time path
(``objective="time"``); a plan whose certified motion still meets one fails saying where.

Its objects are public in :mod:`nonholo.constraints`: :class:`InputBounds` and
:class:`StateBounds` (:mod:`nonholo.model.bounds`), :class:`Clearance`, :class:`LegStroke`,
:class:`LegSpeed`, :class:`~nonholo.model.obstacles.Obstacles` with their
:class:`~nonholo.model.obstacles.Body`, and :func:`of_mechanism`, a
mechanism's own bounds as objects.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model.bounds import InputBounds, StateBounds, as_data, of_mechanism
from ..model.limits import LegLimits
from ..model.obstacles import Body, Obstacles
from ..motion.speed_limits import check_leg_speed
from ..numerics.checks import is_number

__all__ = ["InputBounds", "StateBounds", "Clearance", "LegStroke", "LegSpeed", "Obstacles", "Body", "KINDS",
           "of_mechanism", "as_data"]


@dataclass(frozen=True)
class Clearance:
    """``sgnΔ ≥ delta_min`` along the motion (``sgn`` the sign of ``Δ`` at the start); nothing
    for a mechanism without a singular set.

    Parameters
    ----------
    delta_min : float
        The clearance.

    Raises
    ------
    ValueError
        If ``delta_min`` is not a finite number.
    """

    delta_min: float

    def __post_init__(self):
        if not is_number(self.delta_min) or not math.isfinite(self.delta_min):
            raise ValueError(f"delta_min must be a finite number, got {self.delta_min!r}")

    def check(self, mechanism) -> "Clearance":
        """The constraint, checked against ``mechanism`` (any mechanism takes a clearance).

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism planned.

        Returns
        -------
        Clearance
            ``self``.
        """
        return self

    def refusal(self, mechanism, start, goal) -> str | None:
        """Why no motion keeping the clearance can join ``start`` and ``goal``.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism planned.
        start, goal : tuple
            States ``(R, q)``.

        Returns
        -------
        str or None
            The reason, or ``None``: they may be joined.
        """
        singular = mechanism.singular       # Δ ≡ +∞ without a singular set: never a reason
        d0, dd = singular.value(*start), singular.value(*goal)
        where, at0, atd = singular.where, singular.at_start, singular.at_goal
        if dd == 0.0:
            return f"the goal lies on the singular {where} Δ = 0 ({atd} = 0): unreachable with bounded inputs"
        if np.sign(dd) != np.sign(d0):
            return (f"the goal lies across the singular {where} Δ = 0 ({at0} = {d0:.4g}, "
                    f"{atd} = {dd:.4g}): no motion can cross it, unreachable")
        if abs(dd) < self.delta_min:
            return (f"the goal lies within delta_min = {self.delta_min:g} of the singular "
                    f"{where} (|{atd}| = {abs(dd):.3g})")
        if abs(d0) < self.delta_min:
            return (f"the start lies within delta_min = {self.delta_min:g} of the singular "
                    f"{where} (|{at0}| = {abs(d0):.3g})")
        return None


@dataclass(frozen=True)
class LegStroke:
    """``lo ≤ l_i(R) ≤ hi`` for every leg at every point of the motion.

    Parameters
    ----------
    lo, hi : float
        A platform's stroke, ``0 ≤ lo < hi`` (its geometry's units,
        :meth:`~nonholo.model.mechanism.Mechanism.leg_lengths`).

    Raises
    ------
    ValueError
        For ends that are not finite numbers with ``0 ≤ lo < hi``.
    """

    lo: float
    hi: float

    def __post_init__(self):
        limits = LegLimits.parsed((self.lo, self.hi), "LegStroke")
        object.__setattr__(self, "lo", limits.lo)
        object.__setattr__(self, "hi", limits.hi)

    @property
    def limits(self) -> LegLimits:
        """The stroke as :class:`~nonholo.model.limits.LegLimits`."""
        return LegLimits(self.lo, self.hi)

    @classmethod
    def of(cls, value, mechanism) -> "LegStroke | None":
        """From ``leg_length`` as :func:`nonholo.plan` takes it.

        Parameters
        ----------
        value : tuple of float or None
            ``(lo, hi)``, or ``None``: no limits.
        mechanism : Mechanism
            The mechanism planned.

        Returns
        -------
        LegStroke or None
            The constraint, or ``None``.

        Raises
        ------
        ValueError
            Naming ``leg_length``, for bad limits or a mechanism without legs.
        """
        limits = LegLimits.from_argument(value, mechanism)
        return None if limits is None else cls(limits.lo, limits.hi)

    def check(self, mechanism) -> "LegStroke":
        """The constraint, checked against ``mechanism``.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism planned.

        Returns
        -------
        LegStroke
            ``self``.

        Raises
        ------
        ValueError
            For a mechanism without legs.
        """
        LegLimits.from_argument(self.limits.as_tuple(), mechanism)
        return self

    def refusal(self, mechanism, start, goal) -> str | None:
        """Why ``start`` or ``goal`` is outside the stroke, naming the leg.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism planned.
        start, goal : tuple
            States ``(R, q)``.

        Returns
        -------
        str or None
            The reason, or ``None``: they may be joined.
        """
        return (self.limits.violation(mechanism, start[0], "the start")
                or self.limits.violation(mechanism, goal[0], "the goal"))


@dataclass(frozen=True)
class LegSpeed:
    """``|dl_i/dt| ≤ v`` for every leg: kept by re-timing the planned path.

    Parameters
    ----------
    v : float
        The legs' top speed (the geometry's units per second).
    """

    v: float

    @classmethod
    def of(cls, value, mechanism) -> "LegSpeed | None":
        """From ``leg_speed`` as :func:`nonholo.plan` takes it.

        Parameters
        ----------
        value : float or None
            ``v``, or ``None``: no bound.
        mechanism : Mechanism
            The mechanism planned.

        Returns
        -------
        LegSpeed or None
            The constraint, or ``None``.

        Raises
        ------
        ValueError
            Naming ``leg_speed``, for a bad speed or a mechanism without legs.
        """
        speed = check_leg_speed(value, mechanism)
        return None if speed is None else cls(speed)

    def check(self, mechanism) -> "LegSpeed":
        """The constraint, checked against ``mechanism``.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism planned.

        Returns
        -------
        LegSpeed
            ``self``.

        Raises
        ------
        ValueError
            For a mechanism without legs.
        """
        check_leg_speed(self.v, mechanism)
        return self

    def refusal(self, mechanism, start, goal) -> str | None:
        """Never a reason: any path can be re-timed to keep the speed.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism planned.
        start, goal : tuple
            States ``(R, q)``.

        Returns
        -------
        str or None
            The reason, or ``None``: they may be joined.
        """
        return None


#: The kinds of constraint the planner keeps.
KINDS = (Clearance, LegStroke, LegSpeed, InputBounds, StateBounds, Obstacles)


def check_all(constraints, mechanism) -> tuple:
    """:func:`nonholo.plan`'s ``constraints``, each checked against ``mechanism``.

    ``None`` means no further constraints (as ``()``); anything else must be a sequence of
    constraint objects of :data:`KINDS`: the planner keeps no other kind, so another is
    refused rather than silently ignored.

    Parameters
    ----------
    constraints : sequence or None
        The caller's constraint objects.
    mechanism : Mechanism
        The mechanism planned.

    Returns
    -------
    tuple
        The constraints, checked.

    Raises
    ------
    TypeError
        Naming ``constraints``, for something that is not a sequence of constraint objects.
    ValueError
        Naming the argument, for a constraint the mechanism cannot take.
    """
    if constraints is None:
        return ()
    kinds = ", ".join(k.__name__ for k in KINDS)
    if isinstance(constraints, (str, bytes, dict)) or isinstance(constraints, KINDS) \
            or not hasattr(constraints, "__iter__"):
        raise TypeError(f"constraints must be a sequence of constraint objects ({kinds}) or None, "
                        f"got {type(constraints).__name__}")
    items = tuple(constraints)
    for i, c in enumerate(items):
        if not isinstance(c, KINDS):
            raise TypeError(f"constraints[{i}] must be a constraint object ({kinds}), got {type(c).__name__}")
    return tuple(c.check(mechanism) for c in items)


def first_refusal(constraints, mechanism, start, goal) -> str | None:
    """The first constraint's reason why ``start`` and ``goal`` cannot be joined.

    Parameters
    ----------
    constraints : sequence
        Constraint objects.
    mechanism : Mechanism
        The mechanism planned.
    start, goal : tuple
        States ``(R, q)``.

    Returns
    -------
    str or None
        The reason, or ``None`` if no constraint rules the goal out.
    """
    for constraint in constraints:
        reason = constraint.refusal(mechanism, start, goal)
        if reason is not None:
            return reason
    return None


def one_of(constraints, kind):
    """The constraint of type ``kind`` in ``constraints``.

    Parameters
    ----------
    constraints : sequence
        Constraint objects.
    kind : type
        A constraint class.

    Returns
    -------
    object or None
        The one constraint of that type, or ``None`` if there is none.

    Raises
    ------
    ValueError
        If there is more than one.
    """
    found = [c for c in constraints if isinstance(c, kind)]
    if len(found) > 1:
        raise ValueError(f"constraints has {len(found)} {kind.__name__} constraints; give at most one")
    return found[0] if found else None
