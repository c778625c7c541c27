"""The numeric geometry of a two-leg platform with one rolling disk (:class:`Geometry`), and
the paper's placement at any dimensions (:func:`paper_geometry`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Geometry:
    """Numeric geometry of a two-leg platform with one rolling disk (the symbolic one is
    ``derivations.mechanisms.PlatformGeometry``): base joints ``base_i`` (world frame),
    platform joints ``tip_i`` (platform frame, world position ``R tip_i``), the disk's
    contact point ``contact`` on the sphere and its unit axle direction ``axle`` (world).
    Lengths in the units of the derivation's drawing dimensions.

    Parameters
    ----------
    base1, tip1, base2, tip2 : numpy.ndarray
        The legs' base joints (world frame) and platform joints (platform frame), 3-vectors.
    contact : numpy.ndarray
        The disk's contact point on the sphere; the sphere's radius is ``|contact|``.
    axle : numpy.ndarray
        The disk's unit axle direction (world frame).
    """

    base1: np.ndarray
    tip1: np.ndarray
    base2: np.ndarray
    tip2: np.ndarray
    contact: np.ndarray
    axle: np.ndarray

    FIELDS = ("base1", "tip1", "base2", "tip2", "contact", "axle")

    @classmethod
    def from_mapping(cls, data) -> "Geometry":
        """From a mapping of the six fields to 3-vectors (the generated ``GEOMETRY``).

        Parameters
        ----------
        data : mapping
            The six fields by name; ``axle`` is normalised.

        Returns
        -------
        Geometry
            The geometry.
        """
        vals = {k: np.array(data[k], dtype=float) for k in cls.FIELDS}
        vals["axle"] = vals["axle"] / np.linalg.norm(vals["axle"])
        return cls(**vals)

    @property
    def radius(self) -> float:
        """The sphere's radius ``|contact|``."""
        return float(np.linalg.norm(self.contact))

    @property
    def bases(self) -> tuple[np.ndarray, np.ndarray]:
        """The legs' base joints ``(base1, base2)``."""
        return self.base1, self.base2

    @property
    def tips(self) -> tuple[np.ndarray, np.ndarray]:
        """The legs' platform joints ``(tip1, tip2)``."""
        return self.tip1, self.tip2

    def leg_lengths(self, R) -> np.ndarray:
        """The legs' lengths ``l_i = |R tip_i − base_i|``.

        Parameters
        ----------
        R : array_like
            One rotation ``(3, 3)`` or a stack ``(n, 3, 3)``.

        Returns
        -------
        numpy.ndarray
            Shape ``(2,)`` for one ``R``, ``(n, 2)`` for a stack.
        """
        R = np.asarray(R, dtype=float)
        Rs = R[None] if R.ndim == 2 else R
        out = np.stack([np.linalg.norm(Rs @ tip - base, axis=-1)
                        for base, tip in zip(self.bases, self.tips)], axis=-1)
        return out[0] if R.ndim == 2 else out


def paper_geometry(a: float, b: float, rho: float) -> Geometry:
    """The paper's placement at dimensions ``a, b, ρ`` (the symbolic one is
    ``derivations.mechanisms.PAPER_GEOMETRY``): leg 1 from ``a e_2`` to ``R (b e_2)``, leg 2
    from ``a e_1`` to ``R (b e_1)``, the disk at the pole ``ρ e_3`` with its axle along
    ``(e_1 − e_2)/√2``.

    Parameters
    ----------
    a, b, rho : float
        The base joints' distance from the centre, the platform joints' and the sphere's
        radius.

    Returns
    -------
    Geometry
        The geometry.
    """
    e1, e2, e3 = np.eye(3)
    return Geometry.from_mapping({"base1": a * e2, "tip1": b * e2, "base2": a * e1, "tip2": b * e1,
                                  "contact": rho * e3, "axle": np.sqrt(0.5) * (e1 - e2)})
