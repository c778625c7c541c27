"""Stroke limits of a platform's legs, ``lo ≤ l_i(R) ≤ hi`` for every leg ``i``, and the
clearances a motion keeps at every node (:class:`Limits`: the stroke, bounds on coordinates).

A motion is kept inside the limits the way it is kept clear of ``Δ = 0``: a trajectory
is admissible only if every node's *clearances* ``c = l_i − lo`` and ``c = hi − l_i``
are non-negative (:meth:`LegLimits.least_clearance`), the certified replay checks the same
on its finer grid, and the strategy ``"robust"`` adds a null-space barrier on the
clearances below :data:`BARRIER_CLEARANCE` (:meth:`LegLimits.clearance_terms`). Lengths
are in the units of the mechanism's geometry (:meth:`nonholo.model.mechanism.Mechanism.leg_lengths`).

Any box of clearances ``c(x) ≥ 0`` with gradients plugs into the same machinery: it gives
``clearances``, ``least_clearance``, ``describe``, ``clearance_terms`` (all taking the
nodes' orientations ``R`` and coordinates ``q``) and a ``slack``, how far a replayed node may
pass it. :class:`Limits` holds those a problem keeps — :class:`LegLimits` and
:class:`~nonholo.model.bounds.StateBounds` — and is what the planner, the barrier and the
certificate read.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..numerics.checks import is_number

#: The barrier of strategy ``"robust"`` acts on clearances below this (geometry units).
BARRIER_CLEARANCE = 0.05


@dataclass(frozen=True)
class LegLimits:
    """Every leg's length within ``[lo, hi]`` (geometry units).

    Parameters
    ----------
    lo, hi : float
        The stroke's ends, ``0 ≤ lo < hi``.
    """

    lo: float
    hi: float

    @classmethod
    def from_argument(cls, value, mechanism) -> "LegLimits | None":
        """``leg_length`` as :func:`nonholo.plan` takes it.

        Parameters
        ----------
        value : tuple of float or None
            ``None`` (no limits) or ``(lo, hi)`` with ``0 ≤ lo < hi`` finite.
        mechanism : Mechanism
            The mechanism planned, one with legs.

        Returns
        -------
        LegLimits or None
            The limits, ``None`` for none.

        Raises
        ------
        ValueError
            Naming ``leg_length``, if ``value`` is not such a pair or the mechanism has no
            legs.
        """
        if value is None:
            return None
        if not mechanism.has_legs:
            raise ValueError(f"leg_length: mechanism {mechanism.name!r} has no legs (only platforms do)")
        return cls.parsed(value)

    @classmethod
    def parsed(cls, value, name: str = "leg_length") -> "LegLimits":
        """The limits of a pair ``(lo, hi)``, checked.

        Parameters
        ----------
        value : tuple of float
            ``(lo, hi)`` with ``0 ≤ lo < hi`` finite.
        name : str
            What the caller calls the pair, for messages.

        Returns
        -------
        LegLimits
            The limits.

        Raises
        ------
        ValueError
            Naming ``name``, if ``value`` is not such a pair.
        """
        try:
            if isinstance(value, (str, bytes)):
                raise TypeError
            lo, hi = value
        except (TypeError, ValueError):
            raise ValueError(f"{name} must be a pair (lo, hi), got {value!r}") from None
        for end, x in (("lo", lo), ("hi", hi)):
            if not is_number(x) or not math.isfinite(x) or x < 0:
                raise ValueError(f"{name}: {end} must be a finite number >= 0, got {x!r}")
        if not lo < hi:
            raise ValueError(f"{name}: lo must be below hi, got ({lo!r}, {hi!r})")
        return cls(float(lo), float(hi))

    def as_tuple(self) -> tuple[float, float]:
        """The limits as :func:`nonholo.plan` takes them.

        Returns
        -------
        tuple of float
            ``(lo, hi)``.
        """
        return (self.lo, self.hi)

    # -- clearances --------------------------------------------------------------------------
    #: how far a replayed node may pass the stroke and still keep it (none)
    slack = 0.0
    #: what a motion that passes these limits leaves, for messages
    kept_text = "the legs' stroke"

    def clearances(self, mechanism, R, q=None) -> np.ndarray:
        """``(l_i − lo, hi − l_i)`` for every leg.

        Parameters
        ----------
        mechanism : Mechanism
            The platform (:meth:`~nonholo.model.mechanism.Mechanism.leg_lengths`).
        R : array_like
            A stack of orientations ``(n, 3, 3)`` (or one).
        q : array_like, optional
            Unused (a platform has no coordinates).

        Returns
        -------
        numpy.ndarray
            Shape ``(n, 2k)``: column ``2i`` leg ``i + 1`` above ``lo``, ``2i + 1`` below
            ``hi``.
        """
        lengths = mechanism.leg_lengths(np.asarray(R, dtype=float).reshape(-1, 3, 3))
        out = np.empty((lengths.shape[0], 2 * lengths.shape[1]))
        out[:, 0::2] = lengths - self.lo
        out[:, 1::2] = self.hi - lengths
        return out

    def least_clearance(self, mechanism, R, q=None) -> float:
        """The least clearance over a stack of orientations.

        Parameters
        ----------
        mechanism : Mechanism
            The platform.
        R : array_like
            Orientations ``(n, 3, 3)``.
        q : array_like, optional
            Unused.

        Returns
        -------
        float
            The least of :meth:`clearances` (negative: a leg left its stroke).
        """
        return float(self.clearances(mechanism, R).min())

    def _worst(self, mechanism, R) -> tuple[int, int, int, float]:
        """``(node, leg, bound, clearance)`` of the least clearance over the stack ``R``
        (``leg`` from 1; ``bound`` 0: the lower limit, 1: the upper)."""
        c = self.clearances(mechanism, R)
        n, j = np.unravel_index(int(np.argmin(c)), c.shape)
        return int(n), int(j) // 2 + 1, int(j) % 2, float(c[n, j])

    def violation(self, mechanism, R, what: str) -> str | None:
        """Why an orientation is outside the limits.

        Parameters
        ----------
        mechanism : Mechanism
            The platform.
        R : array_like
            The orientation (3, 3).
        what : str
            What it is, e.g. ``"the start"``.

        Returns
        -------
        str or None
            The message, naming the leg that is out the most and by how much; ``None``
            inside.
        """
        _, leg, bound, c = self._worst(mechanism, R)
        if c >= 0.0:
            return None
        length = float(mechanism.leg_lengths(np.asarray(R, dtype=float))[leg - 1])
        side, end, limit = (("below", "lower", self.lo), ("above", "upper", self.hi))[bound]
        return (f"{what} is outside the legs' stroke: leg {leg} is {length:.4g} long, "
                f"{-c:.3g} {side} leg_length's {end} end {limit:g}")

    def describe(self, mechanism, R, times=None, q=None) -> str:
        """Where a stack of orientations leaves the limits the most (for a failure's reason).

        Parameters
        ----------
        mechanism : Mechanism
            The platform.
        R : array_like
            Orientations ``(n, 3, 3)``.
        times : array_like, optional
            Their times (s), to say when.
        q : array_like, optional
            Unused.

        Returns
        -------
        str
            The leg, the limit it passes and by how much.
        """
        n, leg, bound, c = self._worst(mechanism, R)
        when = f" at t ≈ {times[n]:.4g} s" if times is not None else ""
        return (f"leg {leg} passes its {('lower', 'upper')[bound]} stroke limit by {-c:.3g}{when} "
                f"(leg_length = ({self.lo:g}, {self.hi:g}))")

    def clearance_terms(self, mechanism, R, threshold: float = BARRIER_CLEARANCE, q=None):
        """The active terms of a log barrier ``Σ −log(c/c₀)`` on the clearances of nodes.

        Parameters
        ----------
        mechanism : Mechanism
            The platform.
        R : array_like
            The nodes' orientations ``(n, 3, 3)``.
        threshold : float
            Only clearances below it are active.
        q : array_like, optional
            Unused.

        Returns
        -------
        tuple of numpy.ndarray or None
            ``(nodes, c, ∇c)`` for every clearance ``c < threshold`` (``∇c``: rows with
            ``dc = ∇c · s`` along ``∂R = [s] R``), or ``None`` if none is.
        """
        c = self.clearances(mechanism, R)
        nodes, cols = np.nonzero(c < threshold)
        if nodes.size == 0:
            return None
        G = mechanism.leg_gradients(np.asarray(R)[nodes])               # (a, k, 3)
        rows = G[np.arange(nodes.size), cols // 2]
        rows[cols % 2 == 1] *= -1.0                                        # hi − l_i decreases with l_i
        return nodes, c[nodes, cols], rows


class Limits:
    """The clearances a motion keeps at every node: several boxes of clearances (a
    platform's :class:`LegLimits`, :class:`~nonholo.model.bounds.StateBounds`) as one.

    The planner's trajectories are admissible where :meth:`least_clearance` ``≥ 0`` (every
    node inside every box); a replay keeps them where :meth:`kept` (each box within its
    ``slack``).

    Parameters
    ----------
    parts : sequence
        The boxes (``None`` entries are left out, the parts of a :class:`Limits` taken).
    """

    def __init__(self, parts):
        flat = []
        for p in parts:
            if isinstance(p, Limits):
                flat.extend(p.parts)
            elif p is not None:
                flat.append(p)
        self.parts = tuple(flat)

    @classmethod
    def of(cls, *parts) -> "Limits | None":
        """The limits of some boxes, or ``None`` without any.

        Parameters
        ----------
        *parts
            Boxes of clearances, or ``None``.

        Returns
        -------
        Limits or None
            ``None`` when every part is ``None``.
        """
        limits = cls(parts)
        return limits if limits.parts else None

    def least_clearance(self, mechanism, R, q=None) -> float:
        """The least clearance of any box over the nodes.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism.
        R, q : array_like
            The nodes' orientations and coordinates.

        Returns
        -------
        float
            Negative where a node is outside a box.
        """
        return min(p.least_clearance(mechanism, R, q) for p in self.parts)

    def kept(self, mechanism, R, q=None) -> bool:
        """Whether every node keeps every box to within its ``slack``.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism.
        R, q : array_like
            The nodes' orientations and coordinates.

        Returns
        -------
        bool
            ``True`` where no box is passed by more than its slack.
        """
        return all(p.least_clearance(mechanism, R, q) >= -p.slack for p in self.parts)

    def broken(self, mechanism, R, q=None):
        """The first box some node passes beyond its ``slack``.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism.
        R, q : array_like
            The nodes' orientations and coordinates.

        Returns
        -------
        object or None
            The box, ``None`` if every one is kept.
        """
        for p in self.parts:
            if p.least_clearance(mechanism, R, q) < -p.slack:
                return p
        return None

    def describe(self, mechanism, R, times=None, q=None) -> str:
        """Where the nodes pass a box the most (the first box passed beyond its slack,
        else the one with the least clearance).

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism.
        R : array_like
            The nodes' orientations.
        times : array_like, optional
            Their times (s).
        q : array_like, optional
            The nodes' coordinates.

        Returns
        -------
        str
            What passes which limit and by how much.
        """
        least = [(p.least_clearance(mechanism, R, q), p) for p in self.parts]
        broken = [p for c, p in least if c < -p.slack]
        part = broken[0] if broken else min(least, key=lambda cp: cp[0])[1]
        return part.describe(mechanism, R, times, q)

    def clearance_terms(self, mechanism, R, threshold: float = BARRIER_CLEARANCE, q=None):
        """The active barrier terms of every box (:meth:`LegLimits.clearance_terms`).

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism.
        R : array_like
            The nodes' orientations.
        threshold : float
            Only clearances below it are active.
        q : array_like, optional
            The nodes' coordinates.

        Returns
        -------
        tuple of numpy.ndarray or None
            ``(nodes, c, ∇c)`` of every active clearance, or ``None``.
        """
        terms = [t for t in (p.clearance_terms(mechanism, R, threshold, q=q) for p in self.parts)
                 if t is not None]
        if not terms:
            return None
        return tuple(np.concatenate(parts) for parts in zip(*terms))
