"""The planning examples, as data: the problems ``nonholo reproduce`` solves.

Examples 1 and 2 reconstruct the paper's two planning problems; Example 3 ("parallel
parking") goes beyond it, and Example 4 is the other orientation that meets Example 3's
conditions (two exist; Example 3 is the one nearest to ``exp(0.6 [e_1]) R_0``). All use
``T = 1``, a Fourier basis with ``K = 2`` harmonics and the initial control
``u_1 = 0.3 sin 2πt/T``, ``u_2 = 0.3 cos 2πt/T``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache

import numpy as np
from scipy.optimize import least_squares

from ..model.names import ANGLES
from ..spaces import so3


@dataclass(frozen=True)
class Example:
    """One planning problem: reach ``R_goal`` from ``R_start`` in time ``T``.

    Parameters
    ----------
    number : int
        The example's number.
    title, description : str
        Its title and what the motion does.
    rpy_start : tuple of float
        The start's RPY angles (rad).
    R_goal : numpy.ndarray
        The goal.
    rpy_goal : tuple of float, optional
        The goal's RPY angles (rad).
    T : float
        The horizon (s).
    harmonics : int
        ``K`` of the Fourier basis.
    initial_amplitude : float
        ``A`` of the initial control.
    methods : tuple of str
        The methods ``nonholo reproduce`` plans it with.
    must_succeed : bool
        Whether a failure is an error of the reproduction.
    """

    number: int
    title: str
    description: str
    rpy_start: tuple[float, float, float]
    R_goal: np.ndarray = field(repr=False)
    rpy_goal: tuple[float, float, float] | None = None
    T: float = 1.0
    harmonics: int = 2
    initial_amplitude: float = 0.3
    methods: tuple[str, ...] = ("parametric", "nonparametric")
    must_succeed: bool = True

    @property
    def R_start(self) -> np.ndarray:
        """The start, the rotation of ``rpy_start``."""
        return so3.from_rpy(*self.rpy_start)

    def initial_control(self, t) -> np.ndarray:
        """``u_1 = A sin 2πt/T``, ``u_2 = A cos 2πt/T`` with ``A = 0.3``.

        Parameters
        ----------
        t : array_like
            Times (s), shape ``(n,)``.

        Returns
        -------
        numpy.ndarray
            ``u(t)``, shape ``(n, 2)``.
        """
        w = 2 * np.pi * np.asarray(t, dtype=float) / self.T
        return self.initial_amplitude * np.column_stack([np.sin(w), np.cos(w)])


def parallel_parking_goals(R0: np.ndarray, distance: float = 0.6,
                           axis=(1.0, 0.0, 0.0)) -> list[np.ndarray]:
    """Every orientation at geodesic distance ``distance`` from ``R0`` with the same
    ``r_11`` and ``r_22`` as ``R0`` (both legs end at their initial length), nearest to
    ``exp(distance [axis]) R0`` first.

    Writing the goal as ``exp([w]) R0`` with ``|w| = distance``, the two leg conditions cut
    finitely many points out of the sphere of such ``w``; each is found by least squares
    from a grid of directions (residual < 1e-13) and duplicates are merged.

    Parameters
    ----------
    R0 : numpy.ndarray
        The start.
    distance : float
        The geodesic distance (rad).
    axis : sequence of float
        The direction of the reference goal ``exp(distance [axis]) R0``.

    Returns
    -------
    list of numpy.ndarray
        The orientations, nearest to the reference first.

    Raises
    ------
    RuntimeError
        If no orientation satisfies the conditions.
    """
    R0 = np.asarray(R0, dtype=float)
    ref = so3.exp(distance * np.asarray(axis, dtype=float)) @ R0

    def goal(angles):
        a, b = angles
        n = np.array([np.cos(a) * np.cos(b), np.sin(a) * np.cos(b), np.sin(b)])
        return so3.exp(distance * n) @ R0

    def residual(angles):
        R = goal(angles)
        return [R[0, 0] - R0[0, 0], R[1, 1] - R0[1, 1]]

    found: list[np.ndarray] = []
    for a in np.linspace(-np.pi, np.pi, 24, endpoint=False):
        for b in np.linspace(-1.4, 1.4, 12):
            sol = least_squares(residual, [a, b], xtol=1e-15, ftol=1e-15, gtol=1e-15)
            if np.max(np.abs(sol.fun)) < 1e-13:
                R = goal(sol.x)
                if all(so3.distance(R, other) > 1e-6 for other in found):
                    found.append(R)
    if not found:
        raise RuntimeError("no orientation satisfies the parallel-parking conditions")
    return sorted(found, key=lambda R: so3.distance(R, ref))


def parallel_parking_goal(R0: np.ndarray, distance: float = 0.6, axis=(1.0, 0.0, 0.0)) -> np.ndarray:
    """Example 3's goal: the parking orientation nearest to ``exp(distance [axis]) R0``.

    Parameters
    ----------
    R0 : numpy.ndarray
        The start.
    distance : float
        The geodesic distance (rad).
    axis : sequence of float
        The reference direction.

    Returns
    -------
    numpy.ndarray
        The first of :func:`parallel_parking_goals`.
    """
    return parallel_parking_goals(R0, distance, axis)[0]


@cache
def examples() -> tuple[Example, ...]:
    """Examples 1, 2, 3 and 4.

    Returns
    -------
    tuple of Example
        The examples, in order.
    """
    yaw, pitch, roll = (angle.text for angle in ANGLES)
    ex1 = Example(1, "Example 1", f"{yaw} +0.5 rad and {pitch} -0.3 rad",
                  (0.5, 1.2, -0.5), so3.from_rpy(1.0, 0.9, -0.5), (1.0, 0.9, -0.5))
    ex2 = Example(2, "Example 2", f"{roll} turned by -1 rad",
                  (1.5, 1.4, 0.5), so3.from_rpy(1.5, 1.4, -0.5), (1.5, 1.4, -0.5))
    start3 = (0.5, 1.2, -0.5)
    goal3, goal4 = parallel_parking_goals(so3.from_rpy(*start3))[:2]
    ex3 = Example(3, "Example 3: parallel parking",
                  "turn 0.6 rad with both legs ending at their initial length",
                  start3, goal3, tuple(float(x) for x in so3.as_rpy(goal3)),
                  methods=("parametric",), must_succeed=False)
    ex4 = Example(4, "Example 4: parallel parking, the other way",
                  "the second orientation that meets Example 3's conditions",
                  start3, goal4, tuple(float(x) for x in so3.as_rpy(goal4)),
                  methods=("parametric",), must_succeed=False)
    return ex1, ex2, ex3, ex4


def get(number: int) -> Example:
    """One example by its number.

    Parameters
    ----------
    number : int
        1 to 4.

    Returns
    -------
    Example
        The example.

    Raises
    ------
    ValueError
        For another number.
    """
    for ex in examples():
        if ex.number == number:
            return ex
    raise ValueError(f"no example {number}; there are {[e.number for e in examples()]}")
