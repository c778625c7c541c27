"""The integrator's input tables: the controls at the stage times of every CF4 step.

A CF4 step of length ``h`` evaluates the inputs at ``t_n``, ``t_n + h/2`` and ``t_n + h``
(:data:`STAGE_FRACTIONS`); the kernels of :mod:`nonholo.integrate.cf4` take them as a *stage
table* ``U`` of shape ``(steps, 3, m)``. For smooth controls ``U[n, 2] = U[n + 1, 0]``; for
controls that are constant on each step (piecewise constant on a grid aligned with the
steps) all three are the step's value, so the integrator never sees a jump inside a step.

For a parametrisation linear in its parameters ``λ`` (:mod:`nonholo.controls.parametrisations`) the table
is described by a *stage basis* ``(Bidx, Bval, stride_b, stride_i)``:
``U[n, c, i] = Σ_q Bval[n, c, q] λ[Bidx[n, c, q]·stride_b + i·stride_i]`` — the map the
variational kernel differentiates to accumulate the Jacobian ``∂s_T/∂λ``
(:func:`sparse_basis`; :func:`kernel_basis` gives the dense form it contracts fastest for
Fourier and Legendre series). :func:`stage_function` is the same map from a bare parameter vector
into a preallocated table (the planner's fast path).
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..numerics.checks import MAX_STEPS, check_count
from ..numerics.jit import jit
from .parametrisations import Fourier, Legendre, PiecewiseConstant, Series, fourier_basis, legendre_basis

#: Stage times of one CF4 step, as fractions of the step.
STAGE_FRACTIONS = np.array([0.0, 0.5, 1.0])
#: Above this many steps (finer than any grid the planner itself runs on: the replays that
#: certify a plan) a Fourier series' stage table is evaluated by one inverse FFT instead of
#: through its stage basis (``3 · steps × (2K + 1)`` sines and cosines).
FFT_ABOVE = 6400


def stage_times(T: float, steps: int) -> np.ndarray:
    """The stage times ``t_n + c h`` of ``steps`` steps on ``[0, T]``.

    Parameters
    ----------
    T : float
        The horizon (s).
    steps : int
        The number of CF4 steps.

    Returns
    -------
    numpy.ndarray
        The times, shape ``(steps, 3)``.
    """
    return (np.arange(steps)[:, None] + STAGE_FRACTIONS[None, :]) * (T / steps)


@jit
def stage_values(lam, Bidx, Bval, stride_b, stride_i, m):
    """The stage table ``U[n, c, i] = Σ_q Bval[n, c, q] λ[Bidx[n, c, q]·stride_b + i·stride_i]``.

    Parameters
    ----------
    lam : numpy.ndarray
        The flat parameters ``λ``.
    Bidx, Bval, stride_b, stride_i : numpy.ndarray, numpy.ndarray, int, int
        The stage basis (:func:`sparse_basis`).
    m : int
        The number of inputs.

    Returns
    -------
    numpy.ndarray
        ``U``, shape ``(steps, 3, m)``.
    """
    N = Bidx.shape[0]
    nq = Bidx.shape[2]
    U = np.zeros((N, 3, m))
    for n in range(N):
        for c in range(3):
            for q in range(nq):
                v = Bval[n, c, q]
                base = Bidx[n, c, q] * stride_b
                for i in range(m):
                    U[n, c, i] += v * lam[base + i * stride_i]
    return U


def grid_stage_values(values, out):
    """Stage table of grid controls: ``out[n, c] = values[n // r]`` (``r = N / grid``): one broadcast
    assignment, NumPy's (no compiled kernel to load for grid controls).

    Parameters
    ----------
    values : numpy.ndarray
        The grid's values, shape ``(grid, m)``.
    out : numpy.ndarray
        The table to fill, shape ``(N, 3, m)``, ``N`` a multiple of ``grid``.

    Returns
    -------
    numpy.ndarray
        ``out``.
    """
    out[:] = np.repeat(values, out.shape[0] // values.shape[0], axis=0)[:, None, :]
    return out


@lru_cache(maxsize=32)
def _fourier_stage_basis(T: float, K: int, steps: int) -> np.ndarray:
    return fourier_basis(stage_times(T, steps).ravel(), T, K).reshape(steps, 3, 2 * K + 1)


@lru_cache(maxsize=32)
def _legendre_stage_basis(T: float, K: int, steps: int) -> np.ndarray:
    return legendre_basis(stage_times(T, steps).ravel(), T, K).reshape(steps, 3, K + 1)


#: The series: controls ``coeffs @ φ(t)ᵀ`` on a basis of functions of time, whose stage
#: basis is dense.
SERIES = (Series,)


def series_stage_basis(controls, steps: int) -> np.ndarray:
    """The basis functions of a series at the stage times.

    Parameters
    ----------
    controls : Fourier or Legendre
        A series.
    steps : int
        The number of CF4 steps.

    Returns
    -------
    numpy.ndarray
        ``φ`` at the stage times, shape ``(steps, 3, nb)`` (cached: read only).
    """
    if isinstance(controls, Fourier):
        return _fourier_stage_basis(controls.T, controls.harmonics, steps)
    return _legendre_stage_basis(controls.T, controls.degree, steps)


_EMPTY_INDEX = np.zeros((0, 3, 0), dtype=np.int64)


@lru_cache(maxsize=32)
def _fourier_indices(steps: int, nb: int) -> np.ndarray:
    return np.ascontiguousarray(np.broadcast_to(np.arange(nb, dtype=np.int64), (steps, 3, nb)))


@lru_cache(maxsize=32)
def _grid_basis(grid: int, steps: int) -> tuple[np.ndarray, np.ndarray]:
    idx = np.repeat(np.arange(grid, dtype=np.int64), steps // grid)
    idx = np.ascontiguousarray(np.broadcast_to(idx[:, None, None], (steps, 3, 1)))
    return idx, np.ones((steps, 3, 1))


def check_steps(controls, steps) -> int:
    """``steps`` if the integrator can take that many steps with ``controls``.

    Grid controls need a multiple of the grid, so that no step straddles a jump.

    Parameters
    ----------
    controls : Controls
        The controls (any with a ``grid`` is grid controls).
    steps : int
        The number of CF4 steps.

    Returns
    -------
    int
        ``steps``.

    Raises
    ------
    ValueError
        If ``steps`` is not a whole number in ``[1, MAX_STEPS]`` or not a multiple of the
        grid.
    """
    steps = check_count(steps, "steps", maximum=MAX_STEPS)
    grid = getattr(controls, "grid", None)
    if grid is not None and steps % grid:
        raise ValueError(
            f"steps ({steps}) must be a multiple of the grid ({grid}) so that no "
            "integration step straddles a jump of the piecewise-constant control")
    return steps


def sparse_basis(controls, steps: int) -> tuple[np.ndarray, np.ndarray, int, int]:
    """The stage basis of a control linear in its parameters (see the module docstring).

    Grid controls: one entry per stage, the interval's index (so the Jacobian's columns
    are the ``G_j`` of the nonparametric update).

    Parameters
    ----------
    controls : Fourier, Legendre or PiecewiseConstant
        A series (:data:`SERIES`) or
        :class:`~nonholo.controls.parametrisations.PiecewiseConstant` control.
    steps : int
        The number of CF4 steps (:func:`check_steps`).

    Returns
    -------
    tuple
        ``(Bidx, Bval, stride_b, stride_i)``: ``Bidx`` (int64) and ``Bval`` of shape
        ``(steps, 3, q)``, the strides ints.

    Raises
    ------
    ValueError
        For other controls, or ``steps`` :func:`check_steps` refuses.
    """
    steps = check_steps(controls, steps)
    if isinstance(controls, SERIES):
        nb = controls.coeffs.shape[1]
        return _fourier_indices(steps, nb), series_stage_basis(controls, steps), 1, nb
    if isinstance(controls, PiecewiseConstant):
        return _grid_basis(controls.grid, steps) + (controls.n_inputs, 1)
    raise ValueError(f"{type(controls).__name__} is not linear in its parameters: no stage basis")


def kernel_basis(controls, steps: int) -> tuple[np.ndarray, np.ndarray, int, int]:
    """The stage basis in the form the variational kernel contracts fastest.

    Parameters
    ----------
    controls : Fourier or PiecewiseConstant
        A control linear in its parameters.
    steps : int
        The number of CF4 steps.

    Returns
    -------
    tuple
        ``(Bidx, Bval, stride_b, stride_i)``: for a series the dense form (empty
        ``Bidx``, ``Bval`` of shape ``(steps, 3, nb)`` over every index, see
        :func:`nonholo.integrate.variational_kernels.forward_variational`), else :func:`sparse_basis`'s.
    """
    if isinstance(controls, SERIES):
        steps = check_steps(controls, steps)
        return _EMPTY_INDEX, series_stage_basis(controls, steps), 1, controls.coeffs.shape[1]
    return sparse_basis(controls, steps)


def stage_table(controls, steps: int) -> np.ndarray:
    """``U``: the inputs of ``controls`` at the stage times.

    A parametrisation is evaluated through its stage basis (the same map the kernels
    differentiate; for Fourier series as one dense product); any other input source —
    a motion replay such as :class:`~nonholo.motion.frame_controls.FrameControls` — through its own
    ``stage_table(steps)``.

    Parameters
    ----------
    controls : Controls or object
        A parametrisation, or an input source with a ``stage_table(steps)`` method.
    steps : int
        The number of CF4 steps.

    Returns
    -------
    numpy.ndarray
        ``U``, shape ``(steps, 3, m)``.
    """
    if isinstance(controls, Fourier):
        steps = check_steps(controls, steps)
        if steps > FFT_ABOVE and 2 * controls.harmonics < steps:
            return fourier_stage_values(controls, steps)
        basis = _fourier_stage_basis(controls.T, controls.harmonics, steps)
        return (basis.reshape(3 * steps, -1) @ controls.coeffs.T).reshape(steps, 3, controls.n_inputs)
    if isinstance(controls, Legendre):
        basis = _legendre_stage_basis(controls.T, controls.degree, check_steps(controls, steps))
        return (basis.reshape(3 * steps, -1) @ controls.coeffs.T).reshape(steps, 3, controls.n_inputs)
    if isinstance(controls, PiecewiseConstant):
        out = np.empty((check_steps(controls, steps), 3, controls.n_inputs))
        return grid_stage_values(controls.values, out)
    return controls.stage_table(steps)


def fourier_stage_values(controls: Fourier, steps: int) -> np.ndarray:
    """The stage table of a Fourier series by an inverse real FFT.

    The stage times are the ``2·steps`` points ``j T/(2 steps)`` of a uniform grid of one
    period (and ``T``, which is ``0`` again), where ``w(t_j) = Σ_k X_k e^{2πi kj/n}/n``
    with ``X_0 = n a_0``, ``X_k = (n/2)(b_k − i a_k)`` (``a_k``, ``b_k``: the coefficients
    of ``sin kωt``, ``cos kωt``). Equal to the stage basis' product up to round-off
    (``O(ε log n)`` relative to the coefficients).

    Parameters
    ----------
    controls : Fourier
        The series (``2K < 2·steps``).
    steps : int
        The number of CF4 steps.

    Returns
    -------
    numpy.ndarray
        ``U``, shape ``(steps, 3, m)``.
    """
    n = 2 * steps
    c = controls.coeffs                                  # (m, 2K+1): a0, (sin k, cos k)…
    X = np.zeros((c.shape[0], n // 2 + 1), dtype=complex)
    X[:, 0] = n * c[:, 0]
    X[:, 1:controls.harmonics + 1] = 0.5 * n * (c[:, 2::2] - 1j * c[:, 1::2])
    x = np.fft.irfft(X, n, axis=1)                       # (m, n) at t_j, j = 0 … n−1
    x = np.concatenate([x, x[:, :1]], axis=1).T          # (n + 1, m); t = T: one period on
    return np.take(x, stage_rows(steps), axis=0).reshape(steps, 3, -1)


@lru_cache(maxsize=32)
def stage_rows(steps: int) -> np.ndarray:
    """The rows ``2n, 2n + 1, 2n + 2`` of the stages of step ``n`` in the ``2·steps + 1`` values of a
    uniform grid of half steps, flat (for :func:`numpy.take`, which gathers rows several
    times faster than indexing by an array of shape ``(steps, 3)``).

    Parameters
    ----------
    steps : int
        The number of CF4 steps.

    Returns
    -------
    numpy.ndarray
        The rows, ``3·steps`` of them (read-only, cached).
    """
    rows = (2 * np.arange(steps)[:, None] + np.arange(3)[None, :]).reshape(-1)
    rows.setflags(write=False)
    return rows


def stage_function(controls, steps: int):
    """The stage table of ``controls``' parametrisation as a function of its parameters.

    Nothing is validated and no object is built per call (``params`` must be a float64
    vector of the right size).

    Parameters
    ----------
    controls : Fourier or PiecewiseConstant
        A control linear in its parameters.
    steps : int
        The number of CF4 steps.

    Returns
    -------
    callable
        ``f(params, out) -> out``: the table with the flat parameters ``params``, written
        into ``out`` (shape ``(steps, 3, m)``).

    Raises
    ------
    ValueError
        For other controls, or ``steps`` :func:`check_steps` refuses.
    """
    steps = check_steps(controls, steps)
    if isinstance(controls, SERIES):
        m, nb = controls.coeffs.shape
        basis = series_stage_basis(controls, steps).reshape(3 * steps, nb)

        def fill(params, out):
            np.dot(basis, np.ascontiguousarray(params.reshape(m, nb).T), out=out.reshape(3 * steps, m))
            return out

        return fill
    if isinstance(controls, PiecewiseConstant):
        g, m = controls.values.shape

        def fill(params, out):
            return grid_stage_values(params.reshape(g, m), out)

        return fill
    raise ValueError(f"{type(controls).__name__} is not linear in its parameters: no stage function")


def halve(U: np.ndarray) -> np.ndarray:
    """The stage table of ``steps/2`` steps from that of ``steps`` (even).

    Every stage time of a coarse step is a node of the fine grid (for grid controls, whose
    cells hold whole coarse steps, all three are the step's value).

    Parameters
    ----------
    U : numpy.ndarray
        The fine table, shape ``(steps, 3, m)``.

    Returns
    -------
    numpy.ndarray
        ``[U[2n, 0], U[2n, 2], U[2n+1, 2]]``, shape ``(steps/2, 3, m)``.
    """
    return np.ascontiguousarray(np.stack([U[0::2, 0], U[0::2, 2], U[1::2, 2]], axis=1))
