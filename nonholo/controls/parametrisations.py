"""Control parametrisations: truncated Fourier series, piecewise-constant grid controls and
Legendre series.

A parametrisation maps a flat parameter vector ``λ`` to a control ``u(t) ∈ R^m`` on
``[0, T]`` (``m`` = number of inputs of the mechanism, in the mechanism's physical input
units — for the platform the scaled leg rates ``u_i = d(l_i²)/dt / (4ab)``, 1/s):

- :class:`Fourier` (the parametric form of the appendix): ``u_i(t) = λ_i0 +
  Σ_{k=1..K} (λ_i,2k−1 sin kωt + λ_i,2k cos kωt)``, ``ω = 2π/T``; ``m(2K+1)`` parameters,
  stored as ``coeffs[i] = (λ_i0, λ_i1, λ_i2, …)`` and flattened row by row.
- :class:`PiecewiseConstant` (the nonparametric form, eq. (11), discretised):
  ``u(t) = v_j`` for ``t ∈ [t_j, t_{j+1})`` on a uniform grid ``t_j = jT/n`` (``u(T) =
  v_{n−1}``); ``n·m`` parameters ``values[j, i]``, flattened row by row.
- :class:`Legendre`: ``u_i(t) = Σ_{k=0..K} λ_ik P_k(2t/T − 1)``, a smooth control that need
  not be periodic (a least-energy extremal with drift); ``m(K+1)`` parameters.

All evaluate vectorised: ``controls(t)`` with ``t`` of shape ``(n,)`` gives ``(n, m)``
(a scalar ``t`` gives ``(m,)``), and provide the diagonal of the L2 Gram matrix
``∫ uᵀu dt = λᵀ diag(metric) λ`` and a JSON-able description. What the integrator makes of
them (stage tables, the stage basis it differentiates) is :mod:`nonholo.controls.stages`; the
physical inputs of a motion planned in frame coordinates are :mod:`nonholo.motion.frame_controls`.
"""
from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from ..numerics.checks import check_count, check_time, check_times

#: The 5-point Gauss–Legendre nodes and weights on [-1, 1] of the interval means
#: (:meth:`PiecewiseConstant.fit_with_energy`).
MEAN_NODES = np.polynomial.legendre.leggauss(5)

class Controls(ABC):
    """A control ``u(t)`` on ``[0, T]`` given by a flat parameter vector ``params``.

    Parameters
    ----------
    T : float
        The horizon (s).

    Raises
    ------
    ValueError
        If ``T`` is not a positive finite time.
    """

    kind: str = ""

    def __init__(self, T: float):
        self.T = check_time(T)

    # -- evaluation --------------------------------------------------------------------
    @abstractmethod
    def __call__(self, t) -> np.ndarray:
        """``u(t)``: shape ``(n, m)`` for ``t`` of shape ``(n,)``, ``(m,)`` for a scalar."""

    @property
    @abstractmethod
    def params(self) -> np.ndarray:
        """The flat parameter vector ``λ`` (a copy)."""

    @property
    @abstractmethod
    def n_inputs(self) -> int:
        """``m``, the number of inputs."""

    def with_params(self, params) -> "Controls":
        """The same parametrisation with other parameters.

        Parameters
        ----------
        params : array_like
            The flat parameter vector ``λ``, of the size of :attr:`params`.

        Returns
        -------
        Controls
            A new object.

        Raises
        ------
        ValueError
            If ``params`` has the wrong size or is not finite.
        """
        p = np.array(params, dtype=float)
        if p.size != self._flat.size:
            raise ValueError(f"expected {self._flat.size} parameters, got {p.size}")
        if not np.all(np.isfinite(p)):
            raise ValueError("control parameters must be finite")
        new = object.__new__(type(self))
        new.__dict__.update(self.__dict__)
        new._set(p)
        return new

    @abstractmethod
    def _set(self, params: np.ndarray) -> None:
        """Store the (validated) parameters."""

    @property
    def breakpoints(self) -> np.ndarray | None:
        """Times where ``u`` may jump (including 0 and T), or ``None`` for smooth controls."""
        return None

    @abstractmethod
    def metric(self) -> np.ndarray:
        """Diagonal of the L2 Gram matrix: ``∫_0^T |u|² dt = Σ metric_k λ_k²``.

        Returns
        -------
        numpy.ndarray
            ``metric``, of the size of :attr:`params`.
        """

    # -- description -------------------------------------------------------------------
    @abstractmethod
    def to_dict(self) -> dict:
        """A JSON-able description for :func:`from_dict`.

        Returns
        -------
        dict
            ``kind``, ``T`` and the parameters.
        """

    def __eq__(self, other) -> bool:
        return (type(self) is type(other) and self.T == other.T
                and np.array_equal(self.params, other.params)
                and self.to_dict() == other.to_dict())

    __hash__ = None


# ------------------------------------------------------------------------------------------
# Series: coefficients on a basis of functions of time
# ------------------------------------------------------------------------------------------


class Series(Controls):
    """``u_i(t) = Σ_q coeffs[i, q] φ_q(t)``: coefficients on a basis of functions of time.

    The basis is the subclass's ``basis(t)``; ``coeffs`` has shape ``(m, nb)``, flattened row
    by row. :class:`Fourier` and :class:`Legendre` are series.

    Parameters
    ----------
    T : float
        The horizon (s).

    Raises
    ------
    ValueError
        If ``T`` is not a positive finite time.
    """

    def _set(self, params):
        c = params.reshape(self.coeffs.shape if hasattr(self, "coeffs") else params.shape)
        c.setflags(write=False)
        self.coeffs = c
        self._flat = c.reshape(-1)

    @property
    def n_inputs(self) -> int:
        """``m``, the number of inputs."""
        return self.coeffs.shape[0]

    @property
    def params(self) -> np.ndarray:
        """The flat parameter vector ``λ``, ``coeffs`` row by row (a copy)."""
        return self.coeffs.ravel().copy()

    def __call__(self, t):
        return self.basis(check_times(t)) @ self.coeffs.T

    @abstractmethod
    def basis(self, t) -> np.ndarray:
        """The basis functions at times ``t``.

        Parameters
        ----------
        t : numpy.ndarray
            Times (s), shape ``(n,)``.

        Returns
        -------
        numpy.ndarray
            Shape ``(n, nb)``.
        """


# ------------------------------------------------------------------------------------------
# Truncated Fourier series (parametric form)
# ------------------------------------------------------------------------------------------


def fourier_basis(t, T: float, K: int) -> np.ndarray:
    """``φ(t) = (1, sin ωt, cos ωt, …, sin Kωt, cos Kωt)``, ``ω = 2π/T``.

    Parameters
    ----------
    t : array_like
        Times, shape ``(n,)``.
    T : float
        The period (s).
    K : int
        The number of harmonics.

    Returns
    -------
    numpy.ndarray
        ``φ(t)``, shape ``(n, 2K+1)``.
    """
    t = np.asarray(t, dtype=float)
    w = 2.0 * np.pi / T
    kwt = np.multiply.outer(t, w * np.arange(1, K + 1))
    out = np.empty(t.shape + (2 * K + 1,))
    out[..., 0] = 1.0
    out[..., 1::2] = np.sin(kwt)
    out[..., 2::2] = np.cos(kwt)
    return out


class Fourier(Series):
    """``u_i(t) = λ_i0 + Σ_k λ_i,2k−1 sin kωt + λ_i,2k cos kωt``, ``ω = 2π/T``.

    Parameters
    ----------
    T : float
        The horizon (s).
    coeffs : array_like
        ``coeffs[i] = (λ_i0, λ_i1, λ_i2, …)``, shape ``(m, 2K+1)``; ``K = harmonics ≥ 1``.

    Raises
    ------
    ValueError
        If ``T`` is not a positive finite time, or ``coeffs`` has not that shape or is not
        finite.
    """

    kind = "fourier"

    def __init__(self, T: float, coeffs):
        super().__init__(T)
        c = np.array(coeffs, dtype=float)
        if c.ndim != 2 or c.shape[1] < 3 or c.shape[1] % 2 != 1:
            raise ValueError(
                f"Fourier coefficients must have shape (m, 2K+1) with K >= 1, got {c.shape}")
        if not np.all(np.isfinite(c)):
            raise ValueError("Fourier coefficients must be finite")
        self._set(c)

    @property
    def harmonics(self) -> int:
        """``K``, the number of harmonics."""
        return (self.coeffs.shape[1] - 1) // 2

    def basis(self, t) -> np.ndarray:
        """``(1, sin ωt, cos ωt, …)`` at times ``t`` (:func:`fourier_basis`).

        Parameters
        ----------
        t : numpy.ndarray
            Times (s), shape ``(n,)``.

        Returns
        -------
        numpy.ndarray
            Shape ``(n, 2K+1)``.
        """
        return fourier_basis(t, self.T, self.harmonics)

    def metric(self) -> np.ndarray:
        """Diagonal of the L2 Gram matrix: ``T`` for the constant terms, ``T/2`` for the others.

        Returns
        -------
        numpy.ndarray
            ``metric``, of the size of ``params``.
        """
        w = np.full(self.coeffs.shape, self.T / 2.0)
        w[:, 0] = self.T
        return w.ravel()

    def to_dict(self) -> dict:
        """A JSON-able description for :func:`from_dict`.

        Returns
        -------
        dict
            ``{"kind": "fourier", "T", "harmonics", "coeffs"}``.
        """
        return {"kind": self.kind, "T": self.T, "harmonics": self.harmonics,
                "coeffs": self.coeffs.tolist()}

    @classmethod
    def fit(cls, func, T: float, harmonics: int, n_inputs: int | None = None) -> "Fourier":
        """Least-squares (L2) projection of a control on the K-harmonic basis.

        Sampled on ``n = 8K + 64`` uniform points: exact for trigonometric polynomials of
        degree below ``n − K`` (no aliasing onto the first K harmonics).

        Parameters
        ----------
        func : callable
            ``func(t) -> (n, m)``, vectorised.
        T : float
            The horizon (s).
        harmonics : int
            ``K ≥ 1``.
        n_inputs : int, optional
            ``m`` expected of ``func``.

        Returns
        -------
        Fourier
            The projection.

        Raises
        ------
        ValueError
            If ``T`` or ``harmonics`` is invalid, or ``func`` gives other than ``n_inputs``
            inputs.
        """
        T = check_time(T)
        K = check_count(harmonics, "harmonics")
        n = 8 * K + 64
        t = np.arange(n) * (T / n)
        u = np.asarray(func(t), dtype=float).reshape(n, -1)
        if n_inputs is not None and u.shape[1] != n_inputs:
            raise ValueError(f"func gives {u.shape[1]} inputs, expected {n_inputs}")
        phi = fourier_basis(t, T, K)
        scale = np.full(2 * K + 1, 2.0 / n)
        scale[0] = 1.0 / n
        return cls(T, (phi.T @ u).T * scale)

    @classmethod
    def zeros(cls, T: float, harmonics: int, n_inputs: int) -> "Fourier":
        """The zero control.

        Parameters
        ----------
        T : float
            The horizon (s).
        harmonics : int
            ``K ≥ 1``.
        n_inputs : int
            ``m ≥ 1``.

        Returns
        -------
        Fourier
            ``u ≡ 0``.
        """
        K = check_count(harmonics, "harmonics")
        return cls(T, np.zeros((check_count(n_inputs, "n_inputs"), 2 * K + 1)))

    def __repr__(self) -> str:
        return f"Fourier(T={self.T:g}, K={self.harmonics}, m={self.n_inputs})"


# ------------------------------------------------------------------------------------------
# Legendre series (smooth controls that need not be periodic)
# ------------------------------------------------------------------------------------------


def legendre_basis(t, T: float, K: int) -> np.ndarray:
    """``φ(t) = (P_0(x), …, P_K(x))`` at ``x = 2t/T − 1``: the Legendre polynomials on ``[0, T]``.

    Parameters
    ----------
    t : array_like
        Times (s), shape ``(n,)``.
    T : float
        The horizon (s).
    K : int
        The degree.

    Returns
    -------
    numpy.ndarray
        Shape ``(n, K+1)``.
    """
    return np.polynomial.legendre.legvander(2.0 * np.asarray(t, dtype=float) / T - 1.0, K)


class Legendre(Series):
    """``u_i(t) = Σ_{k=0..K} λ_ik P_k(2t/T − 1)``: a polynomial of degree ``K`` in the
    Legendre basis, orthogonal on ``[0, T]`` (``∫ P_k² dt = T/(2k+1)``). The form of a smooth
    control that is not periodic — a least-energy extremal of a system with drift.

    Parameters
    ----------
    T : float
        The horizon (s).
    coeffs : array_like
        ``coeffs[i] = (λ_i0, …, λ_iK)``, shape ``(m, K+1)``.

    Raises
    ------
    ValueError
        If ``T`` is not a positive finite time, or ``coeffs`` has not that shape or is not
        finite.
    """

    kind = "legendre"

    def __init__(self, T: float, coeffs):
        super().__init__(T)
        c = np.array(coeffs, dtype=float)
        if c.ndim != 2 or c.shape[0] < 1 or c.shape[1] < 1:
            raise ValueError(f"Legendre coefficients must have shape (m, K+1), got {c.shape}")
        if not np.all(np.isfinite(c)):
            raise ValueError("Legendre coefficients must be finite")
        self._set(c)

    @property
    def degree(self) -> int:
        """``K``, the polynomials' degree."""
        return self.coeffs.shape[1] - 1

    def basis(self, t) -> np.ndarray:
        """``(P_0, …, P_K)`` on ``[0, T]`` at times ``t`` (:func:`legendre_basis`).

        Parameters
        ----------
        t : numpy.ndarray
            Times (s), shape ``(n,)``.

        Returns
        -------
        numpy.ndarray
            Shape ``(n, K+1)``.
        """
        return legendre_basis(t, self.T, self.degree)

    def metric(self) -> np.ndarray:
        """Diagonal of the L2 Gram matrix: ``T/(2k+1)`` for ``P_k``.

        Returns
        -------
        numpy.ndarray
            ``metric``, of the size of ``params``.
        """
        return np.broadcast_to(self.T / (2.0 * np.arange(self.degree + 1) + 1.0), self.coeffs.shape).ravel()

    def to_dict(self) -> dict:
        """A JSON-able description for :func:`from_dict`.

        Returns
        -------
        dict
            ``{"kind": "legendre", "T", "degree", "coeffs"}``.
        """
        return {"kind": self.kind, "T": self.T, "degree": self.degree, "coeffs": self.coeffs.tolist()}

    @classmethod
    def fit(cls, t, u, T: float, degree: int) -> "Legendre":
        """The least-squares polynomial of degree ``degree`` through samples.

        Parameters
        ----------
        t : array_like
            Sample times in ``[0, T]``, shape ``(n,)``, ``n > degree``.
        u : array_like
            The inputs there, shape ``(n, m)``.
        T : float
            The horizon (s).
        degree : int
            ``K ≥ 0``.

        Returns
        -------
        Legendre
            The fit.

        Raises
        ------
        ValueError
            If ``T`` or ``degree`` is invalid, or there are not more samples than ``degree``.
        """
        T = check_time(T)
        K = check_count(degree, "degree", minimum=0)
        t = np.asarray(t, dtype=float)
        u = np.asarray(u, dtype=float).reshape(t.size, -1)
        if t.size <= K:
            raise ValueError(f"{t.size} samples cannot fix a polynomial of degree {K}")
        return cls(T, np.polynomial.legendre.legfit(2.0 * t / T - 1.0, u, K).T)

    def __repr__(self) -> str:
        return f"Legendre(T={self.T:g}, K={self.degree}, m={self.n_inputs})"


# ------------------------------------------------------------------------------------------
# Piecewise-constant controls on a uniform grid (nonparametric form)
# ------------------------------------------------------------------------------------------


class PiecewiseConstant(Controls):
    """``u(t) = values[j]`` on ``[t_j, t_{j+1})``, ``t_j = jT/n`` (``n = grid``); ``u(T) = values[-1]``.

    The integrator's step count must be a multiple of ``grid`` so that no step straddles a
    jump (:func:`nonholo.controls.stages.check_steps`).

    Parameters
    ----------
    T : float
        The horizon (s).
    values : array_like
        ``v_j``, shape ``(grid, m)``.

    Raises
    ------
    ValueError
        If ``T`` is not a positive finite time, or ``values`` has not that shape or is not
        finite.
    """

    kind = "piecewise_constant"

    def __init__(self, T: float, values):
        super().__init__(T)
        v = np.array(values, dtype=float)
        if v.ndim != 2 or v.shape[0] < 1 or v.shape[1] < 1:
            raise ValueError(f"piecewise-constant values must have shape (grid, m), got {v.shape}")
        if not np.all(np.isfinite(v)):
            raise ValueError("piecewise-constant values must be finite")
        self._set(v)
        bp = np.linspace(0.0, self.T, v.shape[0] + 1)
        bp.setflags(write=False)
        self._breakpoints = bp
        self._metric = np.repeat(np.diff(bp), v.shape[1])
        self._metric.setflags(write=False)

    def _set(self, params):
        v = params.reshape(self.values.shape if hasattr(self, "values") else params.shape)
        v.setflags(write=False)
        self.values = v
        self._flat = v.reshape(-1)

    @property
    def grid(self) -> int:
        """``n``, the number of intervals."""
        return self.values.shape[0]

    @property
    def n_inputs(self) -> int:
        """``m``, the number of inputs."""
        return self.values.shape[1]

    @property
    def params(self) -> np.ndarray:
        """The flat parameter vector ``λ``, ``values`` row by row (a copy)."""
        return self.values.ravel().copy()

    @property
    def breakpoints(self) -> np.ndarray:
        """The grid ``t_j = jT/n``, ``j = 0 … n``: where ``u`` may jump."""
        return self._breakpoints

    def interval(self, t) -> np.ndarray:
        """Index ``j`` of the interval ``[t_j, t_{j+1})`` holding ``t`` (clipped to the grid).

        Parameters
        ----------
        t : array_like
            Times (s).

        Returns
        -------
        numpy.ndarray
            The indices, of the shape of ``t``.
        """
        j = np.searchsorted(self._breakpoints, np.asarray(t, dtype=float), side="right") - 1
        return np.clip(j, 0, self.grid - 1)

    def __call__(self, t):
        return self.values[self.interval(check_times(t))]

    def metric(self) -> np.ndarray:
        """Diagonal of the L2 Gram matrix: each interval's length, once per input.

        Returns
        -------
        numpy.ndarray
            ``metric``, of the size of :attr:`params`.
        """
        return self._metric

    def to_dict(self) -> dict:
        """A JSON-able description for :func:`from_dict`.

        Returns
        -------
        dict
            ``{"kind": "piecewise_constant", "T", "grid", "values"}``.
        """
        return {"kind": self.kind, "T": self.T, "grid": self.grid, "values": self.values.tolist()}

    @classmethod
    def fit(cls, func, T: float, grid: int, n_inputs: int | None = None) -> "PiecewiseConstant":
        """Interval means of a control (5-point Gauss–Legendre per interval).

        Parameters
        ----------
        func : callable
            ``func(t) -> (n, m)``, vectorised.
        T : float
            The horizon (s).
        grid : int
            ``n ≥ 1``, the number of intervals.
        n_inputs : int, optional
            ``m`` expected of ``func``.

        Returns
        -------
        PiecewiseConstant
            The means.

        Raises
        ------
        ValueError
            If ``T`` or ``grid`` is invalid, or ``func`` gives other than ``n_inputs``
            inputs.
        """
        return cls.fit_with_energy(func, T, grid, n_inputs)[0]

    @classmethod
    def fit_with_energy(cls, func, T: float, grid: int, n_inputs: int | None = None) -> tuple["PiecewiseConstant", float]:
        """:meth:`fit`, and ``∫|u|² dt`` of ``func`` by the same samples (5-point
        Gauss–Legendre on each interval: exact for polynomials of degree 9 there).

        Parameters
        ----------
        func : callable
            ``func(t) -> (n, m)``, vectorised.
        T : float
            The horizon (s).
        grid : int
            The number of intervals.
        n_inputs : int, optional
            ``m`` expected of ``func``.

        Returns
        -------
        fit : PiecewiseConstant
            The means.
        energy : float
            The energy of ``func``.

        Raises
        ------
        ValueError
            If ``T`` or ``grid`` is invalid, or ``func`` gives other than ``n_inputs``
            inputs.
        """
        T = check_time(T)
        grid = check_count(grid, "grid")
        x, w = MEAN_NODES
        edges = np.linspace(0.0, T, grid + 1)
        mid = 0.5 * (edges[:-1] + edges[1:])
        half = 0.5 * np.diff(edges)
        t = (mid[:, None] + half[:, None] * x[None, :]).ravel()
        u = np.asarray(func(t), dtype=float).reshape(grid, 5, -1)
        if n_inputs is not None and u.shape[2] != n_inputs:
            raise ValueError(f"func gives {u.shape[2]} inputs, expected {n_inputs}")
        energy = float(np.einsum("j,k,jki->", half, w, u * u))
        return cls(T, 0.5 * np.einsum("k,jki->ji", w, u)), energy

    def __repr__(self) -> str:
        return f"PiecewiseConstant(T={self.T:g}, grid={self.grid}, m={self.n_inputs})"


KINDS: dict[str, type[Controls]] = {Fourier.kind: Fourier, PiecewiseConstant.kind: PiecewiseConstant,
                                    Legendre.kind: Legendre}


def from_dict(d: dict) -> Controls:
    """Inverse of :meth:`Controls.to_dict`.

    Parameters
    ----------
    d : dict
        A description, its ``kind`` a key of ``KINDS``.

    Returns
    -------
    Controls
        The parametrisation.

    Raises
    ------
    ValueError
        For an unknown ``kind`` or invalid parameters.
    """
    kind = d.get("kind")
    if kind == Fourier.kind:
        return Fourier(d["T"], d["coeffs"])
    if kind == PiecewiseConstant.kind:
        return PiecewiseConstant(d["T"], d["values"])
    if kind == Legendre.kind:
        return Legendre(d["T"], d["coeffs"])
    raise ValueError(f"unknown control parametrisation {kind!r}; known: {', '.join(KINDS)}")


def paper_initial(T: float, n_inputs: int = 2, amplitude: float = 0.3):
    """The initial control of the examples: ``u_1 = 0.3 sin ωt``, ``u_2 = 0.3 cos ωt``.

    ``ω = 2π/T``. For ``m`` inputs, ``u_{i+1} = 0.3 sin(ωt + iπ/2)`` (``i = 0 … m−1``).

    Parameters
    ----------
    T : float
        The horizon (s).
    n_inputs : int
        ``m``.
    amplitude : float
        The amplitude (0.3 in the examples).

    Returns
    -------
    callable
        The control, vectorised: ``t (n,) -> (n, m)``.
    """
    T = check_time(T)
    w = 2.0 * np.pi / T
    phase = 0.5 * np.pi * np.arange(n_inputs)

    def u0(t):
        t = np.asarray(t, dtype=float)
        return amplitude * np.sin(w * t[..., None] + phase)

    return u0
