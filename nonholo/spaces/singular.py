"""A mechanism's singular set ``Δ = 0`` as an object, and the null object of a mechanism
without one (``Δ ≡ +∞``, sign 1), so that callers never branch on whether it exists.

Conventions: ``values`` takes stacks (``R`` ``(n, 3, 3)``, ``q`` ``(n, k)``), ``value`` and
``sign`` one state; a planner keeps ``sgnΔ ≥ delta_min`` with ``sgn`` the sign at the start;
a result reports the least ``sgnΔ`` of its motion, or ``None`` without a singular set;
``samples``, ``columns`` and ``text`` give what a result, a table and a title hold of ``Δ``
(nothing without a singular set).
"""
from __future__ import annotations

import numpy as np


class SingularSet:
    """``Δ(R, q) = 0`` of a mechanism.

    Parameters
    ----------
    samples : callable
        ``samples(R, q)``: ``Δ`` on stacks, ``R`` ``(n, 3, 3)`` and ``q`` ``(n, k)`` or
        ``None``, as an array ``(n,)``.
    on_rotations : bool
        Whether ``Δ`` is a function of the orientation (the set a surface in SO(3)); the
        messages say so.
    owner : str
        The mechanism's name, for the messages of a set that is not on rotations.
    """

    exists = True
    #: the set in a few words
    summary = "singular set Δ = 0"
    #: what a panel of ``Δ`` says in its place (``""``: it draws ``Δ``)
    placeholder = ""
    #: what made a variational replay's sensitivity infinite
    blowup = "ran into Δ = 0"
    #: what a path kept away from the set is, in words (appended to its description)
    kept_clear = " clear of Δ = 0"
    #: the columns of a table of states (:meth:`columns`)
    column_names = ("delta",)

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
        """``Δ`` at every state of stacks.

        Parameters
        ----------
        R : numpy.ndarray
            Rotations, shape ``(n, 3, 3)``.
        q : numpy.ndarray, optional
            Coordinates, shape ``(n, k)``.

        Returns
        -------
        numpy.ndarray
            ``Δ``, shape ``(n,)``.
        """
        return self._samples(R, q)

    @classmethod
    def on(cls, space, samples, owner: str = "") -> "SingularSet":
        """The singular set of a mechanism on ``space``: the messages name a surface in SO(3)
        where the states have no coordinates, a set of ``owner`` otherwise.

        Parameters
        ----------
        space : Product
            The mechanism's state space.
        samples : callable
            As for :class:`SingularSet`.
        owner : str
            The mechanism's name.

        Returns
        -------
        SingularSet
            The set.
        """
        return cls(samples, on_rotations=not space.coordinates.dim, owner=owner)

    def samples(self, R, q=None) -> np.ndarray | None:
        """``Δ`` at every state of stacks, as a result records it (:meth:`values`).

        Parameters
        ----------
        R : numpy.ndarray
            Rotations, shape ``(n, 3, 3)``.
        q : numpy.ndarray, optional
            Coordinates, shape ``(n, k)``.

        Returns
        -------
        numpy.ndarray or None
            ``Δ``, shape ``(n,)`` (``None`` without a singular set).
        """
        return self.values(R, q)

    def columns(self, R, q=None) -> dict:
        """``Δ`` at stacks of states as a table's column.

        Parameters
        ----------
        R : numpy.ndarray
            Rotations, shape ``(n, 3, 3)``.
        q : numpy.ndarray, optional
            Coordinates, shape ``(n, k)``.

        Returns
        -------
        dict
            ``{"delta": Δ}`` (``{}`` without a singular set).
        """
        return {"delta": self.values(R, q)}

    def text(self, R, q=None, spec: str = "+.3f", prefix: str = "") -> str:
        """``Δ`` at one state in words, for titles.

        Parameters
        ----------
        R : array_like
            A rotation matrix.
        q : array_like, optional
            Coordinates, shape ``(k,)``.
        spec : str
            The value's format spec.
        prefix : str
            Put before the text.

        Returns
        -------
        str
            ``prefix + "Δ = +0.123"`` (``""`` without a singular set).
        """
        return f"{prefix}Δ = {self.value(R, q):{spec}}"

    def value(self, R, q=None) -> float:
        """``Δ(R, q)`` at one state.

        Parameters
        ----------
        R : array_like
            A rotation matrix.
        q : array_like, optional
            Coordinates, shape ``(k,)``.

        Returns
        -------
        float
            ``Δ``.
        """
        R = np.asarray(R, dtype=float)[None]
        return float(self.values(R, None if q is None else np.asarray(q, dtype=float)[None])[0])

    def sign(self, R, q=None) -> float:
        """``sign Δ(R, q)``: the side of the singular set a motion from ``(R, q)`` keeps to.

        Parameters
        ----------
        R : array_like
            A rotation matrix.
        q : array_like, optional
            Coordinates, shape ``(k,)``.

        Returns
        -------
        float
            ``-1.0``, ``0.0`` or ``1.0``.
        """
        return float(np.sign(self.value(R, q)))

    def reported(self, least: float):
        """The least ``sgnΔ`` of a motion (or of each of a batch) as a result reports it.

        Parameters
        ----------
        least : float, numpy.ndarray or None
            The least ``sgnΔ`` along the motion (along each motion).

        Returns
        -------
        float, numpy.ndarray or None
            ``least`` as floats (``None`` if nothing was simulated).
        """
        if least is None:
            return None
        return float(least) if np.ndim(least) == 0 else np.asarray(least, dtype=float)

    def clear(self, least: float, delta_min: float) -> bool:
        """Whether a motion whose least ``sgnΔ`` is ``least`` keeps the clearance ``delta_min``.

        Parameters
        ----------
        least : float
            The least ``sgnΔ`` along the motion.
        delta_min : float
            The clearance.

        Returns
        -------
        bool
            ``least ≥ delta_min`` (false when nothing was simulated, ``least`` ``None``).
        """
        return least is not None and least >= delta_min


class NoSingularSet(SingularSet):
    """The singular set of a mechanism that has none: ``Δ ≡ +∞``, sign 1, always clear."""

    exists = False
    summary = placeholder = "no singular set"
    blowup = "overflowed"
    kept_clear = ""
    column_names = ()

    def __init__(self):
        super().__init__(None)

    def samples(self, R, q=None) -> None:
        """Nothing to record without a singular set.

        Parameters
        ----------
        R : numpy.ndarray
            Rotations (unused).
        q : numpy.ndarray, optional
            Coordinates (unused).

        Returns
        -------
        None
            Always.
        """
        return None

    def columns(self, R, q=None) -> dict:
        """No column without a singular set.

        Parameters
        ----------
        R : numpy.ndarray
            Rotations (unused).
        q : numpy.ndarray, optional
            Coordinates (unused).

        Returns
        -------
        dict
            ``{}``.
        """
        return {}

    def text(self, R, q=None, spec: str = "+.3f", prefix: str = "") -> str:
        """Nothing to say without a singular set.

        Parameters
        ----------
        R : array_like
            A rotation matrix (unused).
        q : array_like, optional
            Coordinates (unused).
        spec : str
            Unused.
        prefix : str
            Unused.

        Returns
        -------
        str
            ``""``.
        """
        return ""

    def values(self, R, q=None) -> np.ndarray:
        """``Δ ≡ +∞`` at every state of stacks.

        Parameters
        ----------
        R : numpy.ndarray
            Rotations, shape ``(n, 3, 3)``.
        q : numpy.ndarray, optional
            Coordinates (unused).

        Returns
        -------
        numpy.ndarray
            ``+∞``, shape ``(n,)``.
        """
        return np.full(np.shape(R)[0], np.inf)

    def value(self, R, q=None) -> float:
        """``Δ ≡ +∞``.

        Parameters
        ----------
        R : array_like
            A rotation matrix (unused).
        q : array_like, optional
            Coordinates (unused).

        Returns
        -------
        float
            ``inf``.
        """
        return float("inf")

    def sign(self, R, q=None) -> float:
        """The one side there is.

        Parameters
        ----------
        R : array_like
            A rotation matrix (unused).
        q : array_like, optional
            Coordinates (unused).

        Returns
        -------
        float
            ``1.0``.
        """
        return 1.0

    def reported(self, least: float):
        """Nothing to report without a singular set.

        Parameters
        ----------
        least : float or None
            The least ``sgnΔ`` along the motion (unused).

        Returns
        -------
        None
            Always.
        """
        return None

    def clear(self, least: float, delta_min: float) -> bool:
        """Always clear.

        Parameters
        ----------
        least : float
            The least ``sgnΔ`` along the motion (unused).
        delta_min : float
            The clearance (unused).

        Returns
        -------
        bool
            ``True``.
        """
        return True
