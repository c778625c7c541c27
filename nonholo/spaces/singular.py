"""A mechanism's singular set ``Δ = 0`` as an object, and the null object of a mechanism
without one (``Δ ≡ +∞``, sign 1), so that callers never branch on whether it exists.

Conventions: ``values`` takes stacks (``R`` ``(n, 3, 3)``, ``q`` ``(n, k)``), ``value`` and
``sign`` one state; a planner keeps ``sgnΔ ≥ delta_min`` with ``sgn`` the sign at the start;
a result reports the least ``sgnΔ`` of its motion, or ``None`` without a singular set.
"""
from __future__ import annotations

import numpy as np


class SingularSet:
    """``Δ(R, q) = 0`` of a mechanism; ``samples(R, q)`` evaluates ``Δ`` on stacks."""

    exists = True

    def __init__(self, samples, on_rotations: bool = True, owner: str = ""):
        self._samples = samples
        #: how messages name the set, and ``Δ`` at the start and the goal
        if on_rotations:
            self.where, self.at_start, self.at_goal = "surface", "Δ(R0)", "Δ(Rd)"
            self.refusal = ("R0 lies on the singular surface Δ(R) = 0, where L(R) is undefined "
                            "(e.g. the identity); start from an orientation with Δ(R0) ≠ 0")
        else:
            self.where, self.at_start, self.at_goal = f"set of {owner!r}", "Δ at the start", "Δ at the goal"
            self.refusal = f"R0 lies on the singular set Δ = 0 of {owner!r}, where G is undefined"

    def values(self, R, q=None) -> np.ndarray:
        """``Δ`` at every state of the stacks ``R`` ``(n, 3, 3)`` and ``q`` ``(n, k)``: ``(n,)``."""
        return self._samples(R, q)

    def value(self, R, q=None) -> float:
        """``Δ(R, q)`` at one state."""
        R = np.asarray(R, dtype=float)[None]
        return float(self.values(R, None if q is None else np.asarray(q, dtype=float)[None])[0])

    def sign(self, R, q=None) -> float:
        """``sign Δ(R, q)``: the side of the singular set a motion from ``(R, q)`` keeps to."""
        return float(np.sign(self.value(R, q)))

    def reported(self, least: float):
        """The least ``sgnΔ`` of a motion as a result reports it."""
        return None if least is None else float(least)

    def clear(self, least: float, delta_min: float) -> bool:
        """Whether a motion whose least ``sgnΔ`` is ``least`` keeps the clearance ``delta_min``."""
        return least >= delta_min


class NoSingularSet(SingularSet):
    """The singular set of a mechanism that has none: ``Δ ≡ +∞``, sign 1, always clear."""

    exists = False

    def __init__(self):
        super().__init__(None)

    def values(self, R, q=None) -> np.ndarray:
        return np.full(np.shape(R)[0], np.inf)

    def value(self, R, q=None) -> float:
        return float("inf")

    def sign(self, R, q=None) -> float:
        return 1.0

    def reported(self, least: float):
        return None

    def clear(self, least: float, delta_min: float) -> bool:
        return True
