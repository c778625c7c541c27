"""Small compiled numerics shared by the integrator and the planners.

- SO(3): :func:`rodrigues` (``exp([w])``), :func:`exp_times` (``exp([w]) R``),
  :func:`inv33` (and :func:`inverse_into` for any n×n), :func:`log_rotation` and :func:`log_error` (the planner's error
  ``l_T``, ``[l_T] = log(R_T R_dᵀ)``, and its norm).
- :func:`min_norm_step`: the minimum-norm solution of ``J x = l`` (3 × p) in a diagonal
  metric — a 3×3 Cholesky solve, with an eigen-decomposition fallback for a
  rank-deficient ``J`` that is compiled only if a run needs it.

The numba-compiled functions are the ``_into`` cores (outputs passed in). The functions the
planners call (:func:`log_rotation`, :func:`log_error`, :func:`cholesky_step`, :func:`all_finite`,
:func:`min_norm_step`) run the same cores translated to C (:data:`NATIVE`, the module
``nonholo.generated.native.numerics``) where that is available (:mod:`nonholo.codegen.build`),
else numba's. The integrator itself is :mod:`nonholo.integrate.cf4`.
"""
from __future__ import annotations

import numpy as np

from .jit import jit


@jit
def rodrigues(wx, wy, wz, E):
    """``E = exp([w])`` (Rodrigues; Taylor series for small angles).

    Parameters
    ----------
    wx, wy, wz : float
        The rotation vector ``w``.
    E : numpy.ndarray
        The output, 3×3.
    """
    a2 = wx * wx + wy * wy + wz * wz
    if a2 < 1e-8:
        c1 = 1.0 - a2 / 6.0 + a2 * a2 / 120.0
        c2 = 0.5 - a2 / 24.0 + a2 * a2 / 720.0
    else:
        a = np.sqrt(a2)
        c1 = np.sin(a) / a
        c2 = (1.0 - np.cos(a)) / a2
    xx = wx * wx
    yy = wy * wy
    zz = wz * wz
    xy = wx * wy
    xz = wx * wz
    yz = wy * wz
    E[0, 0] = 1.0 - c2 * (yy + zz)
    E[1, 1] = 1.0 - c2 * (xx + zz)
    E[2, 2] = 1.0 - c2 * (xx + yy)
    E[0, 1] = -c1 * wz + c2 * xy
    E[1, 0] = c1 * wz + c2 * xy
    E[0, 2] = c1 * wy + c2 * xz
    E[2, 0] = -c1 * wy + c2 * xz
    E[1, 2] = -c1 * wx + c2 * yz
    E[2, 1] = c1 * wx + c2 * yz


@jit
def exp_times(wx, wy, wz, R, E, out):
    """``out = exp([w]) R``.

    Parameters
    ----------
    wx, wy, wz : float
        The rotation vector ``w``.
    R : numpy.ndarray
        A 3×3 matrix.
    E : numpy.ndarray
        Scratch, 3×3.
    out : numpy.ndarray
        The output, 3×3; must not alias ``R``.
    """
    rodrigues(wx, wy, wz, E)
    for i in range(3):
        e0 = E[i, 0]
        e1 = E[i, 1]
        e2 = E[i, 2]
        for j in range(3):
            out[i, j] = e0 * R[0, j] + e1 * R[1, j] + e2 * R[2, j]


@jit
def inv33(Z, out):
    """``out = Z^{-1}`` (cofactors).

    Parameters
    ----------
    Z : numpy.ndarray
        A 3×3 matrix.
    out : numpy.ndarray
        The output, 3×3.
    """
    c00 = Z[1, 1] * Z[2, 2] - Z[1, 2] * Z[2, 1]
    c01 = Z[1, 2] * Z[2, 0] - Z[1, 0] * Z[2, 2]
    c02 = Z[1, 0] * Z[2, 1] - Z[1, 1] * Z[2, 0]
    d = 1.0 / (Z[0, 0] * c00 + Z[0, 1] * c01 + Z[0, 2] * c02)
    out[0, 0] = c00 * d
    out[1, 0] = c01 * d
    out[2, 0] = c02 * d
    out[0, 1] = (Z[0, 2] * Z[2, 1] - Z[0, 1] * Z[2, 2]) * d
    out[1, 1] = (Z[0, 0] * Z[2, 2] - Z[0, 2] * Z[2, 0]) * d
    out[2, 1] = (Z[0, 1] * Z[2, 0] - Z[0, 0] * Z[2, 1]) * d
    out[0, 2] = (Z[0, 1] * Z[1, 2] - Z[0, 2] * Z[1, 1]) * d
    out[1, 2] = (Z[0, 2] * Z[1, 0] - Z[0, 0] * Z[1, 2]) * d
    out[2, 2] = (Z[0, 0] * Z[1, 1] - Z[0, 1] * Z[1, 0]) * d


@jit
def inverse_into(A, out):
    """``out = A^{-1}`` (n×n, Gauss–Jordan with partial pivoting).

    Parameters
    ----------
    A : numpy.ndarray
        An n×n matrix.
    out : numpy.ndarray
        The output, n×n; all NaN where ``A`` is singular or not finite.
    """
    n = A.shape[0]
    M = A.copy()
    for i in range(n):
        for j in range(n):
            out[i, j] = 1.0 if i == j else 0.0
    for c in range(n):
        p = c
        for i in range(c + 1, n):
            if abs(M[i, c]) > abs(M[p, c]):
                p = i
        pivot = M[p, c]
        if not (pivot != 0.0 and np.isfinite(pivot)):
            out[:, :] = np.nan
            return
        for j in range(n):
            M[c, j], M[p, j] = M[p, j], M[c, j]
            out[c, j], out[p, j] = out[p, j], out[c, j]
        for j in range(n):
            M[c, j] /= pivot
            out[c, j] /= pivot
        for i in range(n):
            if i != c:
                f = M[i, c]
                for j in range(n):
                    M[i, j] -= f * M[c, j]
                    out[i, j] -= f * out[c, j]


@jit
def log_rotation_into(R, out):
    """``out`` = the rotation vector ``l`` with ``exp([l]) = R``, ``|l| ≤ π`` (the error of (4):
    ``[l] = log R``).

    ``sin α · a = vee(R − Rᵀ)/2`` and ``cos α = (tr R − 1)/2`` give ``α = atan2``; near
    ``α = π`` the axis comes from the symmetric part ``(R + Rᵀ)/2 − cos α I = (1 − cos α) a aᵀ``.

    Parameters
    ----------
    R : numpy.ndarray
        A rotation, 3×3.
    out : numpy.ndarray
        The output ``l``, 3 entries.
    """
    sx = 0.5 * (R[2, 1] - R[1, 2])
    sy = 0.5 * (R[0, 2] - R[2, 0])
    sz = 0.5 * (R[1, 0] - R[0, 1])
    c = 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)
    c = min(1.0, max(-1.0, c))
    s = np.sqrt(sx * sx + sy * sy + sz * sz)
    a = np.arctan2(s, c)
    if c > -0.9:
        f = 1.0 + s * s / 6.0 if s < 1e-6 else a / s
        out[0] = f * sx
        out[1] = f * sy
        out[2] = f * sz
        return
    k = 0
    for i in range(1, 3):
        if R[i, i] > R[k, k]:
            k = i
    v0 = 0.5 * (R[0, k] + R[k, 0]) - (c if k == 0 else 0.0)
    v1 = 0.5 * (R[1, k] + R[k, 1]) - (c if k == 1 else 0.0)
    v2 = 0.5 * (R[2, k] + R[k, 2]) - (c if k == 2 else 0.0)
    n = np.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    if v0 * sx + v1 * sy + v2 * sz < 0.0:
        n = -n
    out[0] = a * v0 / n
    out[1] = a * v1 / n
    out[2] = a * v2 / n


@jit
def log_error_into(R, Rd, l):
    """``l`` with ``[l] = log(R Rdᵀ)``: the planner's error ``l_T``.

    Parameters
    ----------
    R, Rd : numpy.ndarray
        Rotations, 3×3.
    l : numpy.ndarray
        The output ``l``, 3 entries.

    Returns
    -------
    float
        ``|l|`` (rad).
    """
    P = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            P[i, j] = R[i, 0] * Rd[j, 0] + R[i, 1] * Rd[j, 1] + R[i, 2] * Rd[j, 2]
    log_rotation_into(P, l)
    return np.sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2])


@jit
def _eigh3(A, w, V):
    """Eigen decomposition of a symmetric 3×3 ``A`` (cyclic Jacobi): ``A = V diag(w) Vᵀ``."""
    a = A.copy()
    for i in range(3):
        for j in range(3):
            V[i, j] = 1.0 if i == j else 0.0
    for _ in range(50):
        off = a[0, 1] * a[0, 1] + a[0, 2] * a[0, 2] + a[1, 2] * a[1, 2]
        scale = a[0, 0] * a[0, 0] + a[1, 1] * a[1, 1] + a[2, 2] * a[2, 2]
        if off <= 1e-36 * scale or off == 0.0:
            break
        for p in range(2):
            for q in range(p + 1, 3):
                if a[p, q] == 0.0:
                    continue
                theta = (a[q, q] - a[p, p]) / (2.0 * a[p, q])
                t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + np.sqrt(theta * theta + 1.0))
                c = 1.0 / np.sqrt(t * t + 1.0)
                s = t * c
                for k in range(3):          # a ← a Gᵀ ... rotate columns p, q
                    akp = a[k, p]
                    akq = a[k, q]
                    a[k, p] = c * akp - s * akq
                    a[k, q] = s * akp + c * akq
                for k in range(3):          # ... and rows p, q
                    apk = a[p, k]
                    aqk = a[q, k]
                    a[p, k] = c * apk - s * aqk
                    a[q, k] = s * apk + c * aqk
                for k in range(3):
                    vkp = V[k, p]
                    vkq = V[k, q]
                    V[k, p] = c * vkp - s * vkq
                    V[k, q] = s * vkp + c * vkq
    for i in range(3):
        w[i] = a[i, i]


@jit
def _pinv_solve3(A, l, y):
    """``y = A^# l`` for a symmetric positive semi-definite 3×3 ``A`` (eigenvalues below
    ``1e-14·max`` dropped)."""
    w = np.empty(3)
    V = np.empty((3, 3))
    _eigh3(A, w, V)
    wmax = max(w[0], max(w[1], w[2]))
    for i in range(3):
        y[i] = 0.0
    for q in range(3):
        if w[q] > wmax * 1e-14 and w[q] > 0.0:
            c = (V[0, q] * l[0] + V[1, q] * l[1] + V[2, q] * l[2]) / w[q]
            for i in range(3):
                y[i] += c * V[i, q]


#: :func:`min_norm_step` solves by Cholesky while every pivot exceeds this fraction of
#: the largest diagonal entry of ``J S² Jᵀ`` (else the eigen pseudo-inverse is used).
CHOLESKY_PIVOT = 1e-10


@jit
def scaled_gram_into(J, scale, A):
    """``A = J S² Jᵀ`` (3×3), ``S = diag(scale)``.

    Parameters
    ----------
    J : numpy.ndarray
        3 × p.
    scale : numpy.ndarray
        The diagonal of ``S``, p entries.
    A : numpy.ndarray
        The output, 3×3.
    """
    p = J.shape[1]
    for i in range(3):
        for j in range(3):
            A[i, j] = 0.0
    for k in range(p):
        s2 = scale[k] * scale[k]
        j0 = J[0, k] * s2
        j1 = J[1, k] * s2
        j2 = J[2, k] * s2
        A[0, 0] += j0 * J[0, k]
        A[1, 0] += j1 * J[0, k]
        A[1, 1] += j1 * J[1, k]
        A[2, 0] += j2 * J[0, k]
        A[2, 1] += j2 * J[1, k]
        A[2, 2] += j2 * J[2, k]
    A[0, 1] = A[1, 0]
    A[0, 2] = A[2, 0]
    A[1, 2] = A[2, 1]


@jit
def scaled_back_into(J, y, scale, x):
    """``x = S² Jᵀ y``: the step from the solution ``y`` of ``J S² Jᵀ y = l``.

    Parameters
    ----------
    J : numpy.ndarray
        3 × p.
    y : numpy.ndarray
        3 entries.
    scale : numpy.ndarray
        The diagonal of ``S``, p entries.
    x : numpy.ndarray
        The output, p entries.
    """
    p = J.shape[1]
    for k in range(p):
        x[k] = scale[k] * scale[k] * (J[0, k] * y[0] + J[1, k] * y[1] + J[2, k] * y[2])


@jit
def cholesky_into(J, l, scale, x):
    """``x = S² Jᵀ (J S² Jᵀ)^{-1} l`` by Cholesky.

    Parameters
    ----------
    J : numpy.ndarray
        3 × p.
    l : numpy.ndarray
        3 entries.
    scale : numpy.ndarray
        The diagonal of ``S``, p entries.
    x : numpy.ndarray
        The output, p entries.

    Returns
    -------
    bool
        ``False`` (``x`` unset) when a pivot falls below :data:`CHOLESKY_PIVOT` times the
        largest diagonal entry.
    """
    A = np.empty((3, 3))
    scaled_gram_into(J, scale, A)
    y = np.empty(3)
    amax = max(A[0, 0], max(A[1, 1], A[2, 2]))
    floor = CHOLESKY_PIVOT * amax
    ok = amax > 0.0
    # A = C Cᵀ, C lower triangular
    c00 = c10 = c11 = c20 = c21 = c22 = 0.0
    if ok:
        d = A[0, 0]
        ok = d > floor
        if ok:
            c00 = np.sqrt(d)
            c10 = A[1, 0] / c00
            c20 = A[2, 0] / c00
            d = A[1, 1] - c10 * c10
            ok = d > floor
            if ok:
                c11 = np.sqrt(d)
                c21 = (A[2, 1] - c20 * c10) / c11
                d = A[2, 2] - c20 * c20 - c21 * c21
                ok = d > floor
                if ok:
                    c22 = np.sqrt(d)
    if not ok:
        return False
    z0 = l[0] / c00
    z1 = (l[1] - c10 * z0) / c11
    z2 = (l[2] - c20 * z0 - c21 * z1) / c22
    y[2] = z2 / c22
    y[1] = (z1 - c21 * y[2]) / c11
    y[0] = (z0 - c10 * y[1] - c20 * y[2]) / c00
    scaled_back_into(J, y, scale, x)
    return True


@jit
def pinv_into(J, l, scale, x):
    """``x = S² Jᵀ (J S² Jᵀ)^# l`` by the eigen pseudo-inverse (eigenvalues below ``1e-14·max`` dropped).

    Parameters
    ----------
    J : numpy.ndarray
        3 × p.
    l : numpy.ndarray
        3 entries.
    scale : numpy.ndarray
        The diagonal of ``S``, p entries.
    x : numpy.ndarray
        The output, p entries.
    """
    A = np.empty((3, 3))
    scaled_gram_into(J, scale, A)
    y = np.empty(3)
    _pinv_solve3(A, l, y)
    scaled_back_into(J, y, scale, x)


#: relative cut-off of the singular values of ``J S`` for ``d ≠ 3`` rows: the square root of
#: :func:`pinv_step`'s cut-off on the eigenvalues of ``J S² Jᵀ``
PINV_RCOND = 1e-7


def min_norm_step(J, l, scale):
    """``x = S (J S)^# l`` with ``S = diag(scale)``: the least ``|S^{-1} x|`` minimising ``|J x − l|``.

    ``(J S)^# = (J S)ᵀ ((J S)(J S)ᵀ)^{-1}``: the 3×3 system ``J S² Jᵀ y = l`` is solved by
    Cholesky (:func:`cholesky_step`) or, when a pivot falls below :data:`CHOLESKY_PIVOT`
    times the largest diagonal entry (``J`` rank-deficient or nearly so), by the eigen
    pseudo-inverse (:func:`pinv_step`, called from here so that only a run that needs it
    compiles it): the minimum-norm least-squares step rather than a blow-up. For ``d ≠ 3``
    rows (a state beyond SO(3)) the pseudo-inverse of ``J S`` is NumPy's (singular values
    below :data:`PINV_RCOND` relative dropped).

    Parameters
    ----------
    J : numpy.ndarray
        The Jacobian, d × p.
    l : numpy.ndarray
        The right-hand side, d entries.
    scale : numpy.ndarray
        The diagonal of ``S``, p entries.

    Returns
    -------
    numpy.ndarray
        ``x``, p entries.
    """
    if J.shape[0] != 3:
        # a state beyond SO(3) (d rows): the pseudo-inverse of J S by NumPy's SVD
        JS = J * scale
        return scale * (np.linalg.pinv(JS, rcond=PINV_RCOND) @ l)
    x, ok = cholesky_step(J, l, scale)
    return x if ok else pinv_step(J, l, scale)


@jit
def all_finite_jit(A) -> bool:
    """Whether every entry of a 2-d array is finite (compiled).

    Parameters
    ----------
    A : numpy.ndarray
        A 2-d array.

    Returns
    -------
    bool
        Whether every entry is finite.
    """
    for i in range(A.shape[0]):
        for j in range(A.shape[1]):
            if not np.isfinite(A[i, j]):
                return False
    return True


# --------------------------------------------------------------------------------------
# The functions the planners call: native where available, else numba
# --------------------------------------------------------------------------------------

#: The functions of the native module ``nonholo.generated.native.numerics``, with the kinds
#: of their arguments (see :mod:`nonholo.codegen.c_subset`); the first ones are the
#: helpers of the others.
NATIVE = {
    "log_rotation_into": {"R": "f8[2]", "out": "f8[1]"},
    "log_error_into": {"R": "f8[2]", "Rd": "f8[2]", "l": "f8[1]"},
    "scaled_gram_into": {"J": "f8[2]", "scale": "f8[1]", "A": "f8[2]"},
    "scaled_back_into": {"J": "f8[2]", "y": "f8[1]", "scale": "f8[1]", "x": "f8[1]"},
    "cholesky_into": {"J": "f8[2]", "l": "f8[1]", "scale": "f8[1]", "x": "f8[1]"},
    "all_finite_jit": {"A": "f8[2]"},
}


def native_functions() -> list:
    """The functions of :data:`NATIVE` to translate, in order.

    Returns
    -------
    list of Function
        One :class:`~nonholo.codegen.c_subset.Function` per entry of :data:`NATIVE`.
    """
    from ..codegen.c_subset import Function

    calls = {name: name for name in NATIVE}
    calls.update(log_rotation="log_rotation_into")
    return [Function(globals()[name], name, kinds, calls=calls, constants={"CHOLESKY_PIVOT": CHOLESKY_PIVOT})
            for name, kinds in NATIVE.items()]


def native_source() -> str:
    """The C source of ``nonholo.generated.native.numerics``.

    Returns
    -------
    str
        The source (:func:`nonholo.codegen.c_extension.extension_source`).
    """
    from ..codegen.c_extension import extension_source

    header = ("Native small numerics of nonholo/numerics/kernels.py. Generated by `nonholo derive` "
              "(nonholo/codegen/c_translation.py). Do not edit.")
    return extension_source("nonholo.generated.native.numerics", header, native_functions(), native_digest())


def native_digest() -> str:
    """The digest of what the native numerics are translated from (this module, the translator).

    Returns
    -------
    str
        :func:`nonholo.codegen.cache.digest` of this module's source and the translator's.
    """
    from pathlib import Path

    from ..codegen import cache
    from ..codegen.c_extension import translator_sources

    return cache.digest(Path(__file__).read_text(), *translator_sources())


_LIB: list = []


def native_lib():
    """The native module of these numerics.

    Returns
    -------
    module or None
        The module, or ``None`` (numba then: no compiler, or ``NONHOLO_BACKEND=numba``).
    """
    from ..codegen import build     # the native build: loaded at the first kernel call

    if not build.enabled():
        return None
    if not _LIB:
        _LIB.append(build.load("numerics", native_digest(), native_source))
    return _LIB[0]


def log_rotation(R):
    """Rotation vector ``l`` with ``exp([l]) = R``, ``|l| ≤ π`` (see :func:`log_rotation_into`).

    Parameters
    ----------
    R : array_like
        A rotation, 3×3.

    Returns
    -------
    numpy.ndarray
        ``l``, 3 entries.
    """
    out = np.empty(3)
    lib = native_lib()
    (lib.log_rotation_into if lib is not None else log_rotation_into)(np.ascontiguousarray(R, dtype=float), out)
    return out


def log_error(R, Rd):
    """The planner's error ``l_T``, ``[l] = log(R Rdᵀ)``, and its norm.

    Parameters
    ----------
    R, Rd : numpy.ndarray
        Rotations, 3×3.

    Returns
    -------
    l : numpy.ndarray
        3 entries.
    norm : float
        ``|l|`` (rad).
    """
    l = np.empty(3)
    lib = native_lib()
    norm = (lib.log_error_into if lib is not None else log_error_into)(R, Rd, l)
    return l, norm


def scaled_gram(J, scale):
    """``A = J S² Jᵀ`` (3×3), ``S = diag(scale)``.

    Parameters
    ----------
    J : numpy.ndarray
        3 × p.
    scale : numpy.ndarray
        The diagonal of ``S``, p entries.

    Returns
    -------
    numpy.ndarray
        ``A``, 3×3.
    """
    A = np.empty((3, 3))
    scaled_gram_into(J, scale, A)
    return A


def scaled_back(J, y, scale):
    """``x = S² Jᵀ y``: the step from the solution ``y`` of ``J S² Jᵀ y = l``.

    Parameters
    ----------
    J : numpy.ndarray
        3 × p.
    y : numpy.ndarray
        3 entries.
    scale : numpy.ndarray
        The diagonal of ``S``, p entries.

    Returns
    -------
    numpy.ndarray
        ``x``, p entries.
    """
    x = np.empty(J.shape[1])
    scaled_back_into(J, y, scale, x)
    return x


def cholesky_step(J, l, scale):
    """``x = S² Jᵀ (J S² Jᵀ)^{-1} l`` by Cholesky.

    Parameters
    ----------
    J : numpy.ndarray
        3 × p.
    l : numpy.ndarray
        3 entries.
    scale : numpy.ndarray
        The diagonal of ``S``, p entries.

    Returns
    -------
    x : numpy.ndarray
        p entries (meaningless unless ``ok``).
    ok : bool
        ``False`` when a pivot falls below :data:`CHOLESKY_PIVOT` times the largest
        diagonal entry.
    """
    x = np.empty(J.shape[1])
    lib = native_lib()
    ok = (lib.cholesky_into if lib is not None else cholesky_into)(J, l, scale, x)
    return x, bool(ok)


def pinv_step(J, l, scale):
    """``x = S² Jᵀ (J S² Jᵀ)^# l`` by the eigen pseudo-inverse: the rank-deficient fallback.

    Eigenvalues below ``1e-14·max`` are dropped; compiled by numba on first use.

    Parameters
    ----------
    J : numpy.ndarray
        3 × p.
    l : numpy.ndarray
        3 entries.
    scale : numpy.ndarray
        The diagonal of ``S``, p entries.

    Returns
    -------
    numpy.ndarray
        ``x``, p entries.
    """
    x = np.empty(J.shape[1])
    pinv_into(J, l, scale, x)
    return x


def all_finite(A) -> bool:
    """Whether every entry of a 2-d array is finite.

    Parameters
    ----------
    A : numpy.ndarray
        A 2-d array.

    Returns
    -------
    bool
        Whether every entry is finite.
    """
    lib = native_lib()
    return bool((lib.all_finite_jit if lib is not None else all_finite_jit)(A))
