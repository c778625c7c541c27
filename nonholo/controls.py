"""Control parametrisations: truncated Fourier series and piecewise-constant grid controls.

A parametrisation maps a flat parameter vector ``λ`` to a control ``u(t) ∈ R^m`` on
``[0, T]`` (``m`` = number of inputs of the mechanism, in the mechanism's physical input
units — for the platform the scaled leg rates ``u_i = d(l_i²)/dt / (4ab)``, 1/s):

- :class:`Fourier` (the parametric form of the appendix): ``u_i(t) = λ_i0 +
  Σ_{k=1..K} (λ_i,2k−1 sin kωt + λ_i,2k cos kωt)``, ``ω = 2π/T``; ``m(2K+1)`` parameters,
  stored as ``coeffs[i] = (λ_i0, λ_i1, λ_i2, …)`` and flattened row by row.
- :class:`PiecewiseConstant` (the nonparametric form, eq. (11), discretised):
  ``u(t) = v_j`` for ``t ∈ [t_j, t_{j+1})`` on a uniform grid ``t_j = jT/n`` (``u(T) =
  v_{n−1}``); ``n·m`` parameters ``values[j, i]``, flattened row by row.

Both evaluate vectorised: ``controls(t)`` with ``t`` of shape ``(n,)`` gives ``(n, m)``
(a scalar ``t`` gives ``(m,)``). Each also provides what the integrator and the planner
need: the stage table of the CF4 integrator (and :meth:`Controls.stage_function`, the same
map from a bare parameter vector into a preallocated table), the sparse stage basis
``∂U/∂λ`` from which the kernels accumulate the Jacobian (and
:meth:`Controls.kernel_basis`, its dense form for Fourier series; see
:mod:`nonholo.kernels`), the diagonal of the L2 Gram matrix ``∫ uᵀu dt = λᵀ diag(metric) λ``,
and a JSON-able description.

:class:`FrameControls` wraps either of them as the frame coordinates ``w`` of a motion
planned in the desingularised frame ``ω = N(R) w`` and evaluates the physical inputs
``u(t) = W(R(t)) w(t)`` along it (not linear in ``λ``).
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from functools import lru_cache

import numpy as np

#: Stage times of one CF4 step, as fractions of the step.
STAGE_FRACTIONS = np.array([0.0, 0.5, 1.0])


def _check_T(T) -> float:
    try:
        T = float(T)
    except (TypeError, ValueError):
        raise ValueError(f"T must be a number, got {T!r}") from None
    if not np.isfinite(T) or T <= 0:
        raise ValueError(f"T must be a positive finite time, got {T}")
    return T


def _check_count(value, name: str) -> int:
    if isinstance(value, bool) or int(value) != value or value < 1:
        raise ValueError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


class Controls(ABC):
    """A control ``u(t)`` on ``[0, T]`` given by a flat parameter vector ``params``."""

    kind: str = ""

    def __init__(self, T: float):
        self.T = _check_T(T)

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
        """The same parametrisation with parameters ``params`` (a new object)."""
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

    # -- integrator interface ----------------------------------------------------------
    def stage_table(self, steps: int) -> np.ndarray:
        """``U`` of shape ``(steps, 3, m)``: inputs at ``t_n``, ``t_n + h/2``, ``t_n + h``.

        Evaluated from :meth:`sparse_basis` (the same map the kernels differentiate).
        """
        from .kernels import stage_values

        return stage_values(self._flat, *self.sparse_basis(steps), self.n_inputs)

    def stage_function(self, steps: int):
        """``f(params, out) -> out``: the stage table of this parametrisation with the flat
        parameters ``params``, written into ``out`` (shape ``(steps, 3, m)``).

        The planner's fast path: nothing is validated and no object is built per
        evaluation (``params`` must be a float64 vector of the right size).
        """
        from .kernels import stage_values

        Bidx, Bval, sb, si = self.sparse_basis(steps)
        m = self.n_inputs

        def fill(params, out):
            out[...] = stage_values(params, Bidx, Bval, sb, si, m)
            return out

        return fill

    @abstractmethod
    def sparse_basis(self, steps: int) -> tuple[np.ndarray, np.ndarray, int, int]:
        """``(Bidx, Bval, stride_b, stride_i)`` with
        ``U[n, c, i] = Σ_q Bval[n, c, q] λ[Bidx[n, c, q]·stride_b + i·stride_i]``.

        ``Bidx`` (int64) and ``Bval`` have shape ``(steps, 3, q)``: the parametrisation as
        the kernels see it (they accumulate ``J = ∂s_T/∂λ`` with it).
        """

    def kernel_basis(self, steps: int) -> tuple[np.ndarray, np.ndarray, int, int]:
        """The stage basis in the form the variational kernel contracts fastest: the
        :meth:`sparse_basis`, or its dense form (empty ``Bidx``, ``Bval`` of shape
        ``(steps, 3, nb)`` over every index) — see :func:`nonholo.kernels._forward_variational`."""
        return self.sparse_basis(steps)

    def check_steps(self, steps: int) -> int:
        """``steps`` if the integrator can use it with these controls, else ``ValueError``."""
        return _check_count(steps, "steps")

    @abstractmethod
    def metric(self) -> np.ndarray:
        """Diagonal of the L2 Gram matrix: ``∫_0^T |u|² dt = Σ metric_k λ_k²``."""

    # -- description -------------------------------------------------------------------
    @abstractmethod
    def to_dict(self) -> dict:
        """A JSON-able description (``kind``, ``T``, parameters) for :func:`from_dict`."""

    def __eq__(self, other) -> bool:
        return (type(self) is type(other) and self.T == other.T
                and np.array_equal(self.params, other.params)
                and self.to_dict() == other.to_dict())

    __hash__ = None


# ------------------------------------------------------------------------------------------
# Truncated Fourier series (parametric form)
# ------------------------------------------------------------------------------------------


@lru_cache(maxsize=32)
def _fourier_stage_basis(T: float, K: int, steps: int) -> np.ndarray:
    h = T / steps
    t = (np.arange(steps)[:, None] + STAGE_FRACTIONS[None, :]) * h
    return fourier_basis(t.ravel(), T, K).reshape(steps, 3, 2 * K + 1)


_EMPTY_INDEX = np.zeros((0, 3, 0), dtype=np.int64)


@lru_cache(maxsize=32)
def _fourier_indices(steps: int, nb: int) -> np.ndarray:
    idx = np.ascontiguousarray(np.broadcast_to(np.arange(nb, dtype=np.int64), (steps, 3, nb)))
    return idx


@lru_cache(maxsize=32)
def _grid_basis(grid: int, steps: int) -> tuple[np.ndarray, np.ndarray]:
    idx = np.repeat(np.arange(grid, dtype=np.int64), steps // grid)
    idx = np.ascontiguousarray(np.broadcast_to(idx[:, None, None], (steps, 3, 1)))
    return idx, np.ones((steps, 3, 1))


def fourier_basis(t, T: float, K: int) -> np.ndarray:
    """``φ(t) = (1, sin ωt, cos ωt, …, sin Kωt, cos Kωt)``, shape ``(n, 2K+1)``."""
    t = np.asarray(t, dtype=float)
    w = 2.0 * np.pi / T
    kwt = np.multiply.outer(t, w * np.arange(1, K + 1))
    out = np.empty(t.shape + (2 * K + 1,))
    out[..., 0] = 1.0
    out[..., 1::2] = np.sin(kwt)
    out[..., 2::2] = np.cos(kwt)
    return out


class Fourier(Controls):
    """``u_i(t) = λ_i0 + Σ_k λ_i,2k−1 sin kωt + λ_i,2k cos kωt``, ``ω = 2π/T``.

    ``coeffs`` has shape ``(m, 2K+1)``; ``K = harmonics``.
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

    def _set(self, params):
        c = params.reshape(self.coeffs.shape if hasattr(self, "coeffs") else params.shape)
        c.setflags(write=False)
        self.coeffs = c
        self._flat = c.reshape(-1)

    @property
    def harmonics(self) -> int:
        return (self.coeffs.shape[1] - 1) // 2

    @property
    def n_inputs(self) -> int:
        return self.coeffs.shape[0]

    @property
    def params(self) -> np.ndarray:
        return self.coeffs.ravel().copy()

    def __call__(self, t):
        t = np.asarray(t, dtype=float)
        return fourier_basis(t, self.T, self.harmonics) @ self.coeffs.T

    def stage_table(self, steps: int) -> np.ndarray:
        # the same map as the sparse basis, as one dense product (faster than the generic loop)
        steps = self.check_steps(steps)
        basis = _fourier_stage_basis(self.T, self.harmonics, steps)
        return (basis.reshape(3 * steps, -1) @ self.coeffs.T).reshape(steps, 3, self.n_inputs)

    def stage_function(self, steps: int):
        # one dense product with the cached stage basis (the map of ``sparse_basis``)
        steps = self.check_steps(steps)
        m, nb = self.coeffs.shape
        basis = _fourier_stage_basis(self.T, self.harmonics, steps).reshape(3 * steps, nb)

        def fill(params, out):
            np.dot(basis, np.ascontiguousarray(params.reshape(m, nb).T), out=out.reshape(3 * steps, m))
            return out

        return fill

    def kernel_basis(self, steps: int):
        steps = self.check_steps(steps)
        nb = self.coeffs.shape[1]
        return (_EMPTY_INDEX, _fourier_stage_basis(self.T, self.harmonics, steps), 1, nb)

    def sparse_basis(self, steps: int):
        steps = self.check_steps(steps)
        nb = self.coeffs.shape[1]
        return (_fourier_indices(steps, nb), _fourier_stage_basis(self.T, self.harmonics, steps),
                1, nb)

    def metric(self) -> np.ndarray:
        w = np.full(self.coeffs.shape, self.T / 2.0)
        w[:, 0] = self.T
        return w.ravel()

    def to_dict(self) -> dict:
        return {"kind": self.kind, "T": self.T, "harmonics": self.harmonics,
                "coeffs": self.coeffs.tolist()}

    @classmethod
    def fit(cls, func, T: float, harmonics: int, n_inputs: int | None = None) -> "Fourier":
        """Least-squares (L2) projection of ``func(t) -> (n, m)`` on the K-harmonic basis.

        Sampled on ``n = 8K + 64`` uniform points: exact for trigonometric polynomials of
        degree below ``n − K`` (no aliasing onto the first K harmonics).
        """
        T = _check_T(T)
        K = _check_count(harmonics, "harmonics")
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
        K = _check_count(harmonics, "harmonics")
        return cls(T, np.zeros((_check_count(n_inputs, "n_inputs"), 2 * K + 1)))

    def __repr__(self) -> str:
        return f"Fourier(T={self.T:g}, K={self.harmonics}, m={self.n_inputs})"


# ------------------------------------------------------------------------------------------
# Piecewise-constant controls on a uniform grid (nonparametric form)
# ------------------------------------------------------------------------------------------


class PiecewiseConstant(Controls):
    """``u(t) = values[j]`` on ``[t_j, t_{j+1})``, ``t_j = jT/n`` (``n = grid``); ``u(T) = values[-1]``.

    ``values`` has shape ``(grid, m)``. The integrator's step count must be a multiple of
    ``grid`` so that no step straddles a jump.
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
        return self.values.shape[0]

    @property
    def n_inputs(self) -> int:
        return self.values.shape[1]

    @property
    def params(self) -> np.ndarray:
        return self.values.ravel().copy()

    @property
    def breakpoints(self) -> np.ndarray:
        return self._breakpoints

    def interval(self, t) -> np.ndarray:
        """Index ``j`` of the interval ``[t_j, t_{j+1})`` holding ``t`` (clipped to the grid)."""
        j = np.searchsorted(self._breakpoints, np.asarray(t, dtype=float), side="right") - 1
        return np.clip(j, 0, self.grid - 1)

    def __call__(self, t):
        return self.values[self.interval(t)]

    def check_steps(self, steps: int) -> int:
        steps = _check_count(steps, "steps")
        if steps % self.grid:
            raise ValueError(
                f"steps ({steps}) must be a multiple of the grid ({self.grid}) so that no "
                "integration step straddles a jump of the piecewise-constant control")
        return steps

    def stage_function(self, steps: int):
        steps = self.check_steps(steps)
        from .kernels import grid_stage_values

        g, m = self.values.shape

        def fill(params, out):
            return grid_stage_values(params.reshape(g, m), out)

        return fill

    def sparse_basis(self, steps: int):
        """One entry per stage: the interval's index (so ``J``'s columns are the ``G_j``)."""
        return _grid_basis(self.grid, self.check_steps(steps)) + (self.n_inputs, 1)

    def metric(self) -> np.ndarray:
        return self._metric

    def to_dict(self) -> dict:
        return {"kind": self.kind, "T": self.T, "grid": self.grid, "values": self.values.tolist()}

    @classmethod
    def fit(cls, func, T: float, grid: int, n_inputs: int | None = None) -> "PiecewiseConstant":
        """Interval means of ``func(t) -> (n, m)`` (5-point Gauss–Legendre per interval)."""
        T = _check_T(T)
        grid = _check_count(grid, "grid")
        x, w = np.polynomial.legendre.leggauss(5)
        edges = np.linspace(0.0, T, grid + 1)
        mid = 0.5 * (edges[:-1] + edges[1:])
        half = 0.5 * np.diff(edges)
        t = (mid[:, None] + half[:, None] * x[None, :]).ravel()
        u = np.asarray(func(t), dtype=float).reshape(grid, 5, -1)
        if n_inputs is not None and u.shape[2] != n_inputs:
            raise ValueError(f"func gives {u.shape[2]} inputs, expected {n_inputs}")
        return cls(T, 0.5 * np.einsum("k,jki->ji", w, u))

    def __repr__(self) -> str:
        return f"PiecewiseConstant(T={self.T:g}, grid={self.grid}, m={self.n_inputs})"


# ------------------------------------------------------------------------------------------
# Physical inputs of a motion planned in the desingularised frame
# ------------------------------------------------------------------------------------------


class FrameControls(Controls):
    """Physical inputs ``u(t) = W(R(t)) w(t)`` of a motion planned in frame coordinates.

    The motion is planned in the desingularised input coordinates of the generated module:
    ``dR/dt = [N(R) w] R``, ``R(0) = R0``, where ``N(R)`` (3×m, orthonormal columns) spans
    the admissible angular velocities and ``w(t)`` — the control ``frame``, a
    :class:`Fourier` or :class:`PiecewiseConstant` — holds the frame coordinates of ``ω``
    (rad/s). ``W(R) = (N(R)ᵀ L(R))^{-1}`` (polynomial, finite everywhere) converts them to
    the mechanism's physical inputs, ``L(R) W(R) w = N(R) w``; this object evaluates
    ``u(t) = W(R(t)) w(t)`` in physical units, vectorised over ``t``.

    ``R(t)``: the nodes of ``steps`` CF4 steps of the frame system from ``R0`` (computed
    once, on first use, by :func:`nonholo.kernels.get` ``(mechanism, frame=True)``, or
    given as ``nodes`` by a planner that has just computed them), and
    between nodes one CF4 step of length ``t − t_n`` from the node below — the same local
    approximation as an integrator step, ``O(h⁵)`` from the exact motion (≈ 1e-13 rad with
    the default 400 steps on ``T = 1``). Parameters ``λ`` (:attr:`params`) and
    :meth:`metric` are those of ``frame``; ``u`` is not linear in them, so there is no
    sparse basis. :meth:`stage_table` gives the physical inputs at the stage times of any
    step count (grid controls: the step's own value at its end), so
    :func:`nonholo.simulation.simulate` accepts this object and re-traces the motion in
    the physical system.
    """

    kind = "frame"

    def __init__(self, frame: Controls, R0, mechanism: str = "platform", steps: int = 400,
                 nodes=None):
        from . import kernels, mechanisms, so3

        if not isinstance(frame, (Fourier, PiecewiseConstant)):
            raise ValueError(f"frame must be Fourier or PiecewiseConstant controls, got {type(frame).__name__}")
        super().__init__(frame.T)
        name = mechanisms.get(mechanism).name
        if not kernels.has_frame(name):
            raise ValueError(f"mechanism {name!r} has no desingularised frame N(R)")
        if mechanisms.get(name).n_inputs != frame.n_inputs:
            raise ValueError(f"mechanism {name!r} has {mechanisms.get(name).n_inputs} inputs, "
                             f"the frame controls {frame.n_inputs}")
        self.frame = frame
        self.mechanism = name
        self.steps = frame.check_steps(steps)
        R = np.array(so3.check_rotation(R0, "R0"), dtype=float)
        R.setflags(write=False)
        self.R0 = R
        self._nodes = None
        if nodes is not None:
            nodes = np.array(nodes, dtype=float)
            if nodes.shape != (self.steps + 1, 3, 3) or not np.array_equal(nodes[0], R):
                raise ValueError(f"nodes must be the {self.steps + 1} CF4 nodes of the frame motion "
                                 f"from R0, shape ({self.steps + 1}, 3, 3), got {nodes.shape}")
            nodes.setflags(write=False)
            self._nodes = nodes

    def _set(self, params):
        self.frame = self.frame.with_params(params)
        self._nodes = None

    def with_params(self, params) -> "FrameControls":
        return FrameControls(self.frame.with_params(params), self.R0, self.mechanism, self.steps)

    @property
    def params(self) -> np.ndarray:
        return self.frame.params

    @property
    def n_inputs(self) -> int:
        return self.frame.n_inputs

    @property
    def breakpoints(self) -> np.ndarray | None:
        return self.frame.breakpoints

    @property
    def nodes(self) -> np.ndarray:
        """``R(t_n)``, ``t_n = nT/steps``: the CF4 nodes of the frame motion, shape ``(steps+1, 3, 3)``."""
        if self._nodes is None:
            from .kernels import get

            Rs = np.empty((self.steps + 1, 3, 3))
            n, _, _ = get(self.mechanism, True).forward(
                np.ascontiguousarray(self.R0), self.frame.stage_table(self.steps), self.T / self.steps,
                1.0, -np.inf, Rs)
            if n != self.steps:
                raise ValueError("the frame motion produced a non-finite angular velocity")
            Rs.setflags(write=False)
            self._nodes = Rs
        return self._nodes

    def _evaluate(self, t, w_end=None):
        """``(R(t), u(t))`` for ``t`` of shape ``(n,)``; ``w_end``: the ``w`` to use at ``t``."""
        from .kernels import get

        t = np.clip(np.asarray(t, dtype=float).reshape(-1), 0.0, self.T)
        n_t, m = t.size, self.n_inputs
        h = self.T / self.steps
        r = t / h
        k = np.floor(r)
        near = np.rint(r)
        snap = np.abs(r - near) <= 1e-9
        k = np.minimum(np.where(snap, near, k), self.steps).astype(np.int64)
        s = np.where(snap, 0.0, t - k * h)
        tk = k * h
        if not s.any():
            # every sample on a node: u = W(R_k) w(t_k), no partial step to take
            Wst = np.empty((n_t, 3, m))
            if w_end is None:
                w_end = self.frame(t)
        elif isinstance(self.frame, PiecewiseConstant):
            # the partial step uses its step's own value (the middle of a step never lies
            # on a grid point, while t_k = k·h may round to either side of one)
            wk = self.frame(np.minimum(tk, self.T - h) + 0.5 * h)
            Wst = np.ascontiguousarray(np.broadcast_to(wk[:, None, :], (n_t, 3, m)))
            if w_end is None:
                w_end = self.frame(t)
        else:
            Wst = self.frame(np.concatenate([tk, tk + 0.5 * s, t])).reshape(3, n_t, m).transpose(1, 0, 2)
            Wst = np.ascontiguousarray(Wst)
        w_end = Wst[:, 2] if w_end is None else np.ascontiguousarray(w_end, dtype=float).reshape(n_t, m)
        Rt = np.empty((n_t, 3, 3))
        u = np.empty((n_t, m))
        get(self.mechanism, True).frame_inputs(self.nodes, h, k, s, Wst, np.ascontiguousarray(w_end), Rt, u)
        return Rt, u

    def __call__(self, t):
        scalar = np.ndim(t) == 0
        u = self._evaluate(t)[1]
        return u[0] if scalar else u.reshape(np.shape(t) + (self.n_inputs,))

    def states(self, t) -> np.ndarray:
        """``R(t)`` of the planned motion, shape ``(n, 3, 3)`` for ``t`` of shape ``(n,)``."""
        return self._evaluate(t)[0]

    def frame_inputs(self, t) -> np.ndarray:
        """``w(t)``, the frame coordinates of ``ω = N(R) w`` (the planner's controls)."""
        return self.frame(t)

    def stage_table(self, steps: int) -> np.ndarray:
        steps = self.check_steps(steps)
        h = self.T / steps
        t = ((np.arange(steps)[:, None] + STAGE_FRACTIONS[None, :]) * h).ravel()
        w_end = self.frame.stage_table(steps).reshape(-1, self.n_inputs)
        return self._evaluate(t, w_end)[1].reshape(steps, 3, self.n_inputs)

    def check_steps(self, steps: int) -> int:
        return self.frame.check_steps(steps)

    def sparse_basis(self, steps: int):
        raise NotImplementedError("the physical inputs u = W(R(t)) w(t) are not linear in the "
                                  "parameters; the frame controls (.frame) have a basis")

    def metric(self) -> np.ndarray:
        """The L2 metric of the frame controls ``w`` (see :meth:`Controls.metric`)."""
        return self.frame.metric()

    def to_dict(self) -> dict:
        return {"kind": self.kind, "T": self.T, "mechanism": self.mechanism, "steps": self.steps,
                "R0": self.R0.tolist(), "frame": self.frame.to_dict()}

    def __repr__(self) -> str:
        return f"FrameControls({self.frame!r} in the frame of {self.mechanism!r}, {self.steps} steps)"


KINDS: dict[str, type[Controls]] = {Fourier.kind: Fourier, PiecewiseConstant.kind: PiecewiseConstant,
                                    FrameControls.kind: FrameControls}


def from_dict(d: dict) -> Controls:
    """Inverse of :meth:`Controls.to_dict`."""
    kind = d.get("kind")
    if kind == Fourier.kind:
        return Fourier(d["T"], d["coeffs"])
    if kind == PiecewiseConstant.kind:
        return PiecewiseConstant(d["T"], d["values"])
    if kind == FrameControls.kind:
        return FrameControls(from_dict(d["frame"]), d["R0"], d["mechanism"], d["steps"])
    raise ValueError(f"unknown control parametrisation {kind!r}; known: {', '.join(KINDS)}")


def paper_initial(T: float, n_inputs: int = 2, amplitude: float = 0.3):
    """The initial control of the examples: ``u_1 = 0.3 sin ωt``, ``u_2 = 0.3 cos ωt``.

    ``ω = 2π/T``. For ``m`` inputs, ``u_{i+1} = 0.3 sin(ωt + iπ/2)`` (``i = 0 … m−1``).
    Returns a vectorised function ``t (n,) -> (n, m)``.
    """
    T = _check_T(T)
    w = 2.0 * np.pi / T
    phase = 0.5 * np.pi * np.arange(n_inputs)

    def u0(t):
        t = np.asarray(t, dtype=float)
        return amplitude * np.sin(w * t[..., None] + phase)

    return u0
