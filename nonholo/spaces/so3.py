"""Numeric SO(3): hat/vee, exp, log, the left Jacobian (dexp), RPY, input validation.

Conventions:

- ``hat(v) = [v]`` with ``[v] x = v × x``; ``vee`` is its inverse.
- ``exp(w)`` is the rotation by angle ``|w|`` about ``w/|w|``; ``log(R)`` its inverse
  with angle in ``[0, π]``.
- ``dexp(l)`` is the left Jacobian ``I + (1 - cos α)/α² [l] + (α - sin α)/α³ [l]²``
  (``α = |l|``): ``d exp([l(θ)])/dθ · exp(-[l]) = [dexp(l) dl/dθ]`` — the matrix the
  appendix calls ``P`` (printed there with the label ``exp([l_T])``, see the audit).
- ``from_rpy(φ, ϑ, ψ) = R(Z, φ) R(Y, ϑ) R(X, ψ)`` (radians); ``as_rpy`` its inverse.
"""
from __future__ import annotations

import numpy as np

from ..numerics.checks import real_array

#: Below this angle the closed forms lose digits to cancellation; Taylor series are used.
SMALL_ANGLE = 1e-4


def hat(v) -> np.ndarray:
    """Skew matrix ``[v]``, with ``[v] x = v × x``.

    Parameters
    ----------
    v : array_like
        A 3-vector.

    Returns
    -------
    numpy.ndarray
        The 3×3 skew matrix.
    """
    x, y, z = v
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def vee(S) -> np.ndarray:
    """Vector of the skew part of ``S`` (inverse of :func:`hat`).

    Parameters
    ----------
    S : array_like
        A 3×3 matrix.

    Returns
    -------
    numpy.ndarray
        The 3-vector ``v`` with ``[v] = (S − Sᵀ)/2``.
    """
    S = np.asarray(S)
    return 0.5 * np.array([S[2, 1] - S[1, 2], S[0, 2] - S[2, 0], S[1, 0] - S[0, 1]])


def exp(w) -> np.ndarray:
    """Rotation matrix ``exp([w])`` (Rodrigues).

    Parameters
    ----------
    w : array_like
        A rotation vector: angle ``|w|`` about ``w/|w|``.

    Returns
    -------
    numpy.ndarray
        The 3×3 rotation.
    """
    w = np.asarray(w, dtype=float)
    a2 = w @ w
    a = np.sqrt(a2)
    if a < SMALL_ANGLE:
        # sin a/a and (1 - cos a)/a² by their Taylor series: the closed forms cancel.
        c1 = 1.0 - a2 / 6.0 + a2 * a2 / 120.0
        c2 = 0.5 - a2 / 24.0 + a2 * a2 / 720.0
    else:
        c1 = np.sin(a) / a
        c2 = (1.0 - np.cos(a)) / a2
    W = hat(w)
    return np.eye(3) + c1 * W + c2 * (W @ W)


def log(R) -> np.ndarray:
    """Rotation vector ``l`` with ``exp([l]) = R`` and ``|l| ≤ π`` (robust near π).

    Parameters
    ----------
    R : array_like
        A rotation matrix.

    Returns
    -------
    numpy.ndarray
        The 3-vector ``l``.
    """
    from scipy.spatial.transform import Rotation  # loaded when first needed

    return Rotation.from_matrix(np.asarray(R, dtype=float)).as_rotvec()


def angle(R) -> float:
    """Rotation angle of ``R``.

    Parameters
    ----------
    R : array_like
        A rotation matrix.

    Returns
    -------
    float
        The angle in ``[0, π]``.
    """
    return float(np.linalg.norm(log(R)))


def distance(R1, R2) -> float:
    """Geodesic distance ``|log(R1 R2ᵀ)|`` on SO(3).

    Parameters
    ----------
    R1, R2 : array_like
        Rotation matrices.

    Returns
    -------
    float
        The distance in radians.
    """
    return angle(np.asarray(R1) @ np.asarray(R2).T)


def dexp(l) -> np.ndarray:
    """Left Jacobian of SO(3) (the appendix's ``P``); ``dexp(l) @ l == l``.

    Parameters
    ----------
    l : array_like
        A rotation vector.

    Returns
    -------
    numpy.ndarray
        The 3×3 matrix ``I + (1 − cos α)/α² [l] + (α − sin α)/α³ [l]²``, ``α = |l|``.
    """
    l = np.asarray(l, dtype=float)
    a2 = l @ l
    a = np.sqrt(a2)
    if a < SMALL_ANGLE:
        # (1 - cos a)/a² and (a - sin a)/a³ by Taylor series (cancellation near 0).
        c1 = 0.5 - a2 / 24.0 + a2 * a2 / 720.0
        c2 = 1.0 / 6.0 - a2 / 120.0 + a2 * a2 / 5040.0
    else:
        c1 = (1.0 - np.cos(a)) / a2
        c2 = (a - np.sin(a)) / (a2 * a)
    Lh = hat(l)
    return np.eye(3) + c1 * Lh + c2 * (Lh @ Lh)


def from_rpy(phi: float, theta: float, psi: float) -> np.ndarray:
    """``RPY(φ, ϑ, ψ) = R(Z, φ) R(Y, ϑ) R(X, ψ)`` as a matrix.

    Parameters
    ----------
    phi, theta, psi : float
        The RPY angles (radians): φ the yaw (about z), ϑ the pitch (about y), ψ the roll
        (about x), as :mod:`nonholo.model.names` names them.

    Returns
    -------
    numpy.ndarray
        The 3×3 rotation.
    """
    from scipy.spatial.transform import Rotation  # loaded when first needed

    return Rotation.from_euler("ZYX", [phi, theta, psi]).as_matrix()


def as_rpy(R) -> np.ndarray:
    """The RPY angles of a rotation (inverse of :func:`from_rpy`).

    Parameters
    ----------
    R : array_like
        A rotation matrix.

    Returns
    -------
    numpy.ndarray
        ``(φ, ϑ, ψ)`` with ``from_rpy(φ, ϑ, ψ) = R``; ``ϑ ∈ [-π/2, π/2]``.
    """
    from scipy.spatial.transform import Rotation  # loaded when first needed

    return Rotation.from_matrix(np.asarray(R, dtype=float)).as_euler("ZYX")


def check_rotation(R, name: str = "R", tol: float = 1e-9) -> np.ndarray:
    """``R`` checked to be a rotation: shape, finiteness, orthonormality and ``det R = +1``.

    Parameters
    ----------
    R : array_like
        The value to check.
    name : str
        The argument's name, for the message.
    tol : float
        The largest ``|RᵀR − I|`` accepted.

    Returns
    -------
    numpy.ndarray
        ``R`` as a float (3, 3) array.

    Raises
    ------
    ValueError
        Naming ``name`` and saying what is wrong with it.
    """
    A = real_array(R, name)
    if A.shape != (3, 3):
        raise ValueError(f"{name} must have shape (3, 3), got {A.shape}")
    if not np.all(np.isfinite(A)):
        raise ValueError(f"{name} has non-finite entries (NaN or inf)")
    with np.errstate(over="ignore", invalid="ignore"):     # huge entries: err = inf, refused below
        err = np.max(np.abs(A.T @ A - np.eye(3)))
    if not err <= tol:
        raise ValueError(f"{name} is not orthonormal: max |RᵀR - I| = {err:.3g} > {tol:g}")
    if np.linalg.det(A) < 0:
        raise ValueError(f"{name} is a reflection (det = -1), not a rotation")
    return A


def turns(Ra: np.ndarray, Rb: np.ndarray) -> np.ndarray:
    """The turns ``v_e = log(R_b R_aᵀ)`` between two stacks of rotations.

    Parameters
    ----------
    Ra, Rb : numpy.ndarray
        Stacks of shape ``(E, 3, 3)``.

    Returns
    -------
    numpy.ndarray
        Rotation vectors, shape ``(E, 3)``.
    """
    from scipy.spatial.transform import Rotation  # loaded when first needed

    a = Rotation.from_matrix(Ra)
    return (Rotation.from_matrix(Rb) * a.inv()).as_rotvec()


def geodesic_points(Ra: np.ndarray, v: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Points ``exp(s·[v_e]) R_a[e]`` along geodesics, for every pair ``e`` and fraction ``s``.

    Parameters
    ----------
    Ra : numpy.ndarray
        Starts, shape ``(E, 3, 3)``.
    v : numpy.ndarray
        Turns (:func:`turns`), shape ``(E, 3)``.
    s : numpy.ndarray
        Fractions, shape ``(S,)``.

    Returns
    -------
    numpy.ndarray
        Shape ``(E, S, 3, 3)``.
    """
    from scipy.spatial.transform import Rotation  # loaded when first needed

    E, S = len(v), len(s)
    turn = Rotation.from_rotvec((v[:, None, :] * s[None, :, None]).reshape(-1, 3)).as_matrix()
    return np.matmul(turn.reshape(E, S, 3, 3), np.asarray(Ra, dtype=float)[:, None])


def geodesic(Ra, Rb, s) -> np.ndarray:
    """The geodesic ``R(s) = exp(s·log(R_b R_aᵀ)) R_a`` from ``Ra`` to ``Rb``.

    Parameters
    ----------
    Ra, Rb : array_like
        Rotation matrices.
    s : array_like
        Fractions, shape ``(n,)``.

    Returns
    -------
    numpy.ndarray
        Shape ``(n, 3, 3)``.
    """
    Ra, Rb = np.asarray(Ra, dtype=float)[None], np.asarray(Rb, dtype=float)[None]
    return geodesic_points(Ra, turns(Ra, Rb), np.asarray(s, dtype=float))[0]


def continuous_quaternions(R: np.ndarray) -> np.ndarray:
    """Unit quaternions of rotations, their signs kept continuous.

    Parameters
    ----------
    R : numpy.ndarray
        Rotations, shape ``(n, 3, 3)``.

    Returns
    -------
    numpy.ndarray
        ``(x, y, z, w)`` per rotation, shape ``(n, 4)``, each with the sign nearer the
        previous one's.
    """
    from scipy.spatial.transform import Rotation  # loaded when first needed

    q = Rotation.from_matrix(R).as_quat()
    for k in range(1, len(q)):
        if np.dot(q[k], q[k - 1]) < 0.0:
            q[k] = -q[k]
    return q
