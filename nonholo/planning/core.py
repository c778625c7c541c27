"""The planning core shared by every strategy: the evaluator of a problem (its controls
simulated with the variational system), the options, the step loop of the θ-flow, its
step control, and the result builder. The problem itself is
:class:`nonholo.planning.problem.Problem`.

The task: steer ``dR/dt = [L(R) u] R`` (spatial form) from ``R(0) = R0`` to ``R(T) = R_d``
(Tchoń & Jakubiak, appendix eqs. (4)–(11)). Along a family of controls ``u_θ`` the error
``e = log(R_T R_dᵀ) = [l_T]`` is asked to decay as ``dl_T/dθ = −γ l_T`` (4)–(5); with
``s_T = P(l_T) dl_T/dθ`` (7), ``P`` the left Jacobian of SO(3) (:func:`nonholo.spaces.so3.dexp`)
and ``P(l) l = l``, this asks for ``s_T = −γ l_T``, ``s_T = J ∂λ/∂θ`` with the Jacobian
``J = ∂s_T/∂λ`` of the variational system (9)–(10) (:meth:`EndpointMap.evaluate`). Its
minimum-norm solution in a diagonal metric ``W`` is the update (11):
``Δλ = −γh W^{-1/2} (J W^{-1/2})^# l_T`` (:func:`nonholo.numerics.kernels.min_norm_step`).

Step loop (:func:`descend`). The θ-flow is integrated by explicit Euler steps
``θ → θ + h``. A step is accepted only if the new trajectory reaches ``T`` with
``|Δ| ≥ delta_min`` at every point where the integrator evaluates the field (checked by
the kernel, which stops at once otherwise) and ``|l_T|`` decreases; otherwise ``h`` is
halved (:func:`backtrack`), and the loop gives up, with the reason, once ``γh <
min_step``. After a step accepted at the first try ``h`` doubles again, up to its
initial value. Once ``|l_T| < newton_below`` the steps are full Newton steps, ``γh = 1``
(halved if rejected): exact Newton for the discrete map ``λ ↦ l_T``, whose derivative is
``P(l_T)^{-1} J`` — since ``P^{-1} l = l``, ``P^{-1} J Δλ = −l`` and ``J Δλ = −l`` have the
same minimum-norm solution — so the convergence is quadratic.

A strategy (:class:`Strategy`) chooses the coordinates of the planned control, the
initial guesses and the step direction; it keeps no state between runs — what it needs
during a run lives in the :class:`Start` and :class:`EndpointMap` it is given.
"""
from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Callable, ClassVar

import numpy as np

from ..certify.certificate import Certificate
from ..controls import stages
from ..controls.parametrisations import Controls
from ..integrate.compiled import compiled_system
from ..io.result import PlanResult, part_errors
from ..model.limits import Limits
from ..model.mechanism import Mechanism
from ..motion.frame_controls import FrameControls
from ..numerics import kernels
from ..numerics.checks import check_count, is_number
from ..spaces import so3
from ..spaces.state import State


@dataclass(frozen=True)
class Options:
    """Numerical settings of a planning run (see :func:`nonholo.plan`).

    Parameters
    ----------
    gamma : float, default 0.5
        The decay rate ``γ`` of the θ-flow.
    step : float, default 1.0
        The initial (and largest) step ``h`` of the θ-flow.
    tol : float, default 1e-10
        The terminal error ``|l_T|`` at which a run has converged.
    max_iter : int, default 200
        Accepted steps at most.
    newton_below : float, default 1e-3
        Full Newton steps once ``|l_T|`` is below this.
    min_step : float, default 1e-6
        A run gives up once ``γh`` falls below this.
    delta_min : float, default 1e-2
        The clearance ``|Δ| ≥ delta_min`` kept along the motion.

    Raises
    ------
    ValueError
        If a number is not positive (``gamma``, ``step``, ``tol``, ``min_step``), negative
        (``newton_below``, ``delta_min``) or ``max_iter`` not a count.
    """

    gamma: float = 0.5
    step: float = 1.0
    tol: float = 1e-10
    max_iter: int = 200
    newton_below: float = 1e-3
    min_step: float = 1e-6
    delta_min: float = 1e-2

    def __post_init__(self):
        for name in ("gamma", "step", "tol", "min_step"):
            v = getattr(self, name)
            if not (is_number(v) and math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be a positive number, got {v!r}")
            object.__setattr__(self, name, float(v))
        for name in ("newton_below", "delta_min"):
            v = getattr(self, name)
            if not (is_number(v) and math.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be a non-negative number, got {v!r}")
            object.__setattr__(self, name, float(v))
        object.__setattr__(self, "max_iter", check_count(self.max_iter, "max_iter", minimum=0))


class Evaluation:
    """One simulation of the planning problem for a control (with the Jacobian).

    ``params``: the control's flat parameter vector ``λ`` in the parametrisation
    ``parametrisation`` (whose own parameters are irrelevant); :attr:`controls` builds the
    control object on first use. ``complete``: the trajectory reached ``T`` (the kernel
    stops early where ``sgnΔ < delta_stop`` or ``ω`` is not finite). ``min_delta``: least
    ``sgn(Δ(R0))·Δ`` over the integrator's evaluation points (= least ``|Δ|`` unless the
    motion crossed ``Δ = 0``; ``None`` without a singular set). ``min_clearance``: least
    clearance of the nodes from the problem's limits (the legs' stroke, the coordinates'
    bounds: :class:`~nonholo.model.limits.Limits`; ``None`` without limits). ``l``, ``error``, ``J``
    only when complete; ``Z`` (``Z(t_n) = Φ(t_n, 0)^{-1}`` at every node, ``(N+1, 3, 3)``)
    and ``Wd`` (the kernel's stage weights, ``(3N, 3m)``, see
    :func:`nonholo.integrate.variational_kernels.forward_variational`) only when the evaluation was asked for
    them (``full``): with them the sensitivity of ``R(t_n)`` to ``λ`` is
    ``s_n = Z_n^{-1} Σ_{stages r before t_n} W_r ∂U_r/∂λ``.

    Parameters
    ----------
    params : numpy.ndarray
        The control's parameters ``λ``.
    parametrisation : Controls
        The parametrisation they are read in.
    complete : bool
        Whether the trajectory reached ``T``.
    steps_done : int
        Integrator steps taken.
    t_stop : float or None
        Where the kernel stopped early (``None``: complete).
    min_delta : float or None
        Least ``sgn(Δ(R0))·Δ`` along the trajectory.
    R : numpy.ndarray
        The orientations at the nodes, ``(n, 3, 3)``.
    controls : Controls, optional
        The control itself, if already built.
    q : numpy.ndarray, optional
        The coordinates at the nodes, ``(n, k)``; none on SO(3).
    """

    __slots__ = ("params", "parametrisation", "complete", "steps_done", "t_stop", "min_delta",
                 "min_clearance", "R", "q", "l", "error", "errors", "J", "Z", "Wd", "_controls")

    def __init__(self, params, parametrisation, complete, steps_done, t_stop, min_delta, R,
                 controls=None, q=None):
        self.params = params
        self.parametrisation = parametrisation
        self.complete = complete
        self.steps_done = steps_done
        self.t_stop = t_stop
        self.min_delta = min_delta
        self.min_clearance = None
        self.R = R
        #: the coordinates at the nodes, ``(n, k)`` (``k = 0`` on SO(3))
        self.q = np.zeros((len(R), 0)) if q is None else q
        #: ``(rotation, coordinates)``: the norms of the two parts of ``l`` (:mod:`nonholo.spaces.product`)
        self.errors = None
        self.l = self.error = self.J = self.Z = self.Wd = None
        self._controls = controls

    @property
    def controls(self) -> Controls:
        """The evaluated control as a :class:`~nonholo.controls.parametrisations.Controls` (validated)."""
        if self._controls is None:
            self._controls = self.parametrisation.with_params(self.params)
        return self._controls

    @property
    def R_T(self) -> np.ndarray | None:
        """The orientation at ``T`` (``None`` unless complete)."""
        return self.R[-1] if self.complete else None

    @property
    def q_T(self) -> np.ndarray | None:
        """The coordinates at ``T`` (``None`` unless complete)."""
        return self.q[-1] if self.complete else None


class EndpointMap:
    """The endpoint map of a problem, ``λ ↦ s_T``: its controls simulated from the start in
    time ``T``, with the terminal error from the goal and its Jacobian from the variational
    system, on the integrator's buffers.

    :meth:`evaluate` simulates a control with the variational system and returns the
    error ``l_T`` and the Jacobian ``J = ∂s_T/∂λ``. ``frame=True`` integrates the system
    in the desingularised frame coordinates ``w`` (``dR/dt = [N(R) w] R``; ``Δ`` is still
    monitored): ``λ`` then parametrises ``w``. ``limits``: the clearances an admissible
    trajectory keeps at every node (:class:`~nonholo.model.limits.Limits`: the legs' stroke,
    the coordinates' bounds; or a :class:`~nonholo.model.limits.LegLimits` alone), or ``None``.
    ``l_T`` is the stacked error ``(l, δq)`` of the mechanism's space
    (:mod:`nonholo.spaces.product`) and ``J`` has ``d`` rows.

    Parameters
    ----------
    start, goal : State
        Start and goal (:class:`~nonholo.spaces.state.State`).
    T : float
        The time horizon.
    mechanism : Mechanism
        The mechanism planned.
    method : str
        ``"parametric"`` or ``"nonparametric"``.
    steps : int
        Integrator steps on ``[0, T]``.
    delta_min : float
        The clearance kept.
    frame : bool, default False
        Whether to integrate in the frame coordinates ``w``.
    limits : Limits or None, optional
        The clearances kept at every node, if any.
    """

    def __init__(self, start: State, goal: State, T: float, mechanism: Mechanism, method: str, steps: int,
                 delta_min: float, frame: bool = False, limits: Limits | None = None):
        self.mechanism = mechanism
        self.limits = limits
        self.frame = frame
        self.kernels = compiled_system(mechanism, frame)
        self.start = State.of(start)
        self.goal = State.of(goal)
        self.T = T
        self.method = method
        self.steps = steps
        self.h = T / steps
        self.delta_min = delta_min
        self.singular = mechanism.singular
        self.sign = self.singular.sign(*self.start)
        d = mechanism.n_rates
        self._Rs, self._Qs = self.kernels.nodes(steps)
        self._Zs = np.empty((steps + 1, d, d))
        self._M = np.empty((d, d))
        self._U = np.empty((steps, 3, mechanism.n_inputs))
        self._Wd = np.empty((3 * steps, d * mechanism.n_inputs))
        self.parametrisation: Controls | None = None
        self.evaluations = 0

    def error_of(self, R, q) -> tuple[np.ndarray, dict]:
        """The terminal error of the state ``(R, q)`` from the goal and its parts.

        Parameters
        ----------
        R : numpy.ndarray
            An orientation.
        q : numpy.ndarray
            Coordinates.

        Returns
        -------
        l : numpy.ndarray
            The stacked error (:meth:`nonholo.spaces.product.Product.error`).
        errors : dict
            The norms of its parts.
        """
        return self.mechanism.space.error((R, q), self.goal)

    def forward(self, U, h: float, stop: float):
        """The motion of a stage table (no variational system).

        Parameters
        ----------
        U : numpy.ndarray
            The stage table, ``(N, 3, m)``.
        h : float
            The step.
        stop : float
            Stop where ``sgnΔ`` falls below this.

        Returns
        -------
        Rs : numpy.ndarray
            The orientations at the nodes.
        Qs : numpy.ndarray
            The coordinates at the nodes.
        n : int
            Steps done.
        """
        Rs, Qs = self.kernels.nodes(U.shape[0])
        n, _, _ = self.kernels.forward(*self.start, U, h, self.sign, stop, Rs, Qs)
        return Rs, Qs, int(n)

    def refined(self, steps: int) -> "EndpointMap":
        """The same problem on another grid.

        Parameters
        ----------
        steps : int
            Integrator steps on ``[0, T]``.

        Returns
        -------
        EndpointMap
            The problem on that grid.
        """
        return EndpointMap(self.start, self.goal, self.T, self.mechanism, self.method, steps, self.delta_min,
                         self.frame, self.limits)

    def use(self, controls: Controls) -> None:
        """Interpret parameter vectors passed to :meth:`evaluate` in a parametrisation.

        Parameters
        ----------
        controls : Controls
            The parametrisation.
        """
        self.parametrisation = controls
        self._fill = stages.stage_function(controls, self.steps)
        self.stage_basis = stages.kernel_basis(controls, self.steps)
        self.n_params = controls.params.size

    def evaluate(self, x, delta_stop: float | None = None, full: bool = False) -> Evaluation:
        """Simulate a control with the variational system.

        Parameters
        ----------
        x : Controls or numpy.ndarray
            A :class:`~nonholo.controls.parametrisations.Controls` (which becomes the
            parametrisation, see :meth:`use`) or a flat parameter vector ``λ`` in the
            current parametrisation.
        delta_stop : float, optional
            Stop early where ``sgnΔ`` falls below this (default ``delta_min``).
        full : bool, default False
            Keep ``Z(t_n)`` at every node and the stage weights (:attr:`Evaluation.Z`,
            :attr:`Evaluation.Wd`).

        Returns
        -------
        Evaluation
            The simulation, with ``l_T`` and ``J`` if complete.
        """
        given = None
        if isinstance(x, Controls):
            if x is not self.parametrisation:
                self.use(x)
            given, x = x, x.params
        stop = self.delta_min if delta_stop is None else delta_stop
        U = self._fill(x, self._U)
        J = np.empty((self.mechanism.n_rates, self.n_params))
        n, dmin, t_stop = self.kernels.forward_variational(
            *self.start, U, self.h, self.sign, stop, *self.stage_basis,
            self._Rs, self._Qs, self._Zs, J, self._M, self._Wd, full)
        self.evaluations += 1
        complete = n == self.steps
        if complete and not kernels.all_finite(J):
            # the variational system overflowed (Φ(T, 0) does not exist in floating point):
            # a motion no step can be taken from
            complete, n, t_stop = False, n - 1, self.T
        ev = Evaluation(x, self.parametrisation, complete, int(n), None if complete else float(t_stop),
                        self.singular.reported(dmin), self._Rs[:n + 1].copy(), given,
                        self._Qs[:n + 1].copy())
        if self.limits is not None:
            ev.min_clearance = self.limits.least_clearance(self.mechanism, ev.R, ev.q)
        if complete:
            ev.l, ev.errors = self.error_of(self._Rs[n], self._Qs[n])
            ev.error = self.mechanism.space.norm(ev.errors)
            ev.J = J
            if full:
                ev.Z = self._Zs.copy()
                ev.Wd = self._Wd.copy()
        return ev

    def admissible(self, ev: Evaluation) -> bool:
        """Whether an evaluation is admissible.

        Parameters
        ----------
        ev : Evaluation
            The evaluation.

        Returns
        -------
        bool
            Complete, ``|Δ| ≥ delta_min`` along the whole trajectory and every node inside
            the problem's limits (if any).
        """
        return (ev.complete and self.singular.clear(ev.min_delta, self.delta_min)
                and (self.limits is None or ev.min_clearance >= 0.0))

    def why_not(self, ev: Evaluation) -> str:
        """Why an evaluation is not admissible.

        Parameters
        ----------
        ev : Evaluation
            The evaluation.

        Returns
        -------
        str
            The reason (``"admissible"`` if it is).
        """
        if not self.singular.clear(ev.min_delta, self.delta_min):
            where = f" at t ≈ {ev.t_stop:.4g} s" if ev.t_stop is not None else ""
            if ev.min_delta <= 0.0:
                return (f"the trajectory ran into the singular surface Δ = 0{where} (|ω| ~ 1/|Δ| "
                        "blows up there; the fixed-step integrator stepped across it)")
            return f"|Δ| fell to {ev.min_delta:.6g} < delta_min = {self.delta_min:g}{where}"
        if not ev.complete:
            return f"the angular velocity became non-finite at t ≈ {ev.t_stop:.4g} s"
        if self.limits is not None and ev.min_clearance < 0.0:
            return self.limits.describe(self.mechanism, ev.R, np.arange(len(ev.R)) * self.h, ev.q)
        return "admissible"


@lru_cache(maxsize=16)
def _ones(p: int) -> np.ndarray:
    a = np.ones(p)
    a.setflags(write=False)
    return a


def spatial_gradient_delta(mechanism, R: np.ndarray, eps: float = 1e-6, q=None) -> np.ndarray:
    """``∇Δ`` at each ``R[n]``: ``Δ(exp([s]) R) = Δ(R) + ∇Δ·s + O(|s|²)``.

    Central differences of the generated ``Δ``, error ``O(ε²)``; beyond SO(3), at each
    state ``(R[n], q[n])`` along the stacked variation ``s = (s_R, s_q)``.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.
    R : numpy.ndarray
        Orientations, ``(n, 3, 3)``.
    eps : float, default 1e-6
        The differences' step ``ε``.
    q : numpy.ndarray, optional
        Coordinates, ``(n, k)``, beyond SO(3).

    Returns
    -------
    numpy.ndarray
        The gradients, ``(n, 3)``; ``(n, d)`` beyond SO(3).
    """
    space, values = mechanism.space, mechanism.singular.values
    q = np.zeros((len(R), mechanism.n_coordinates)) if q is None else q
    g = np.empty((len(R), space.dim))
    for i in range(space.dim):
        s = np.zeros(space.dim)
        s[i] = eps
        g[:, i] = (values(*space.retract_stack(R, q, s)) - values(*space.retract_stack(R, q, -s))) / (2.0 * eps)
    return g


def node_gradient(endpoint: EndpointMap, ev: Evaluation, a: np.ndarray) -> np.ndarray:
    """The gradient in ``λ`` of ``Σ_n a_n · s_n``, ``s_n`` the sensitivity of node ``n``'s state.

    ``s_n = Z_n^{-1} S_n``, ``S_n = Σ_{stages r before t_n} W_r ∂U_r/∂λ``; with
    ``μ_n = a_n Z_n^{-1}`` the gradient is ``Σ_r (ν_{n(r)} W_r) ∂U_r/∂λ``, ``ν_k = Σ_{n > k}
    μ_n`` (suffix sums): one backward pass over the stored stages, no extra simulation.

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint.
    ev : Evaluation
        A ``full`` evaluation.
    a : numpy.ndarray
        The weights, ``(N+1, d)``, one row per node.

    Returns
    -------
    numpy.ndarray
        The gradient, one entry per parameter.
    """
    N, m, D = endpoint.steps, endpoint.mechanism.n_inputs, endpoint.mechanism.n_rates
    mu = np.linalg.solve(np.transpose(ev.Z, (0, 2, 1)), a[:, :, None])[:, :, 0]    # a_n Z_n^{-1}
    nu = np.cumsum(mu[::-1], axis=0)[::-1]                  # Σ_{n ≥ k} μ_n
    nu = nu[1:]                                              # Σ_{n > k} μ_n, k = 0 … N−1
    v = np.einsum("ni,ncik->nck", nu, ev.Wd.reshape(N, 3, D, m)).reshape(3 * N, m)
    Bidx, Bval, sb, si = endpoint.stage_basis
    out = np.zeros(endpoint.n_params)
    if Bidx.shape[0] == 0:                                  # dense basis
        G = v.T @ Bval.reshape(3 * N, -1)                    # (m, nb)
        cols = np.arange(G.shape[1])[None, :] * sb + np.arange(m)[:, None] * si
        out[cols.ravel()] = G.ravel()
        return out
    nq = Bidx.shape[2]
    cols = Bidx.reshape(3 * N, nq, 1) * sb + np.arange(m)[None, None, :] * si
    np.add.at(out, cols.ravel(), (Bval.reshape(3 * N, nq, 1) * v[:, None, :]).ravel())
    return out


def node_sensitivities(endpoint: EndpointMap, ev: Evaluation, nodes: np.ndarray) -> np.ndarray:
    """``s_n = ∂(state at node n)/∂λ`` at some nodes, from a ``full`` evaluation.

    ``s_n = Z_n^{-1} S_n`` with ``S_n = Σ_{stages r before t_n} W_r ∂U_r/∂λ`` (no extra
    simulation). For grid controls (each step's stages in one interval ``j``, steps ``a_j …
    b_j − 1``) ``S_n``'s block of interval ``j`` is ``C(min(n, b_j)) − C(min(n, a_j))``,
    ``C`` the running sum of the steps' contributions; otherwise the contributions are
    summed over the steps before each node.

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint.
    ev : Evaluation
        A ``full`` evaluation.
    nodes : array_like of int
        The nodes.

    Returns
    -------
    numpy.ndarray
        The sensitivities, ``(len(nodes), d, p)``.
    """
    N, m, D = endpoint.steps, endpoint.mechanism.n_inputs, endpoint.mechanism.n_rates
    nodes = np.asarray(nodes, dtype=int)
    W = ev.Wd.reshape(N, 3, D, m)
    Bidx, Bval, sb, si = endpoint.stage_basis
    p = endpoint.n_params
    if Bidx.shape[0] and Bidx.shape[2] == 1 and np.all(Bidx[:, :, 0] == Bidx[:, :1, 0]):
        j = Bidx[:, 0, 0]
        C = np.zeros((N + 1, D, m))
        np.cumsum(np.einsum("nc,ncdk->ndk", Bval[:, :, 0], W), axis=0, out=C[1:])
        intervals = np.unique(j)
        first = np.searchsorted(j, intervals, side="left")
        last = np.searchsorted(j, intervals, side="right")
        blocks = (C[np.minimum(nodes[:, None], last[None, :])]
                  - C[np.minimum(nodes[:, None], first[None, :])])          # (k, J, D, m)
        cols = (intervals[:, None] * sb + np.arange(m)[None, :] * si).ravel()        # (J m)
        values = np.moveaxis(blocks, 2, 1).reshape(nodes.size, D, -1)
        if cols.size == p and np.array_equal(cols, np.arange(p)):
            S = values                                      # every interval, in the parameters' order
        else:
            S = np.zeros((nodes.size, D, p))
            S[:, :, cols] = values
        # Z_n^{-1} S_n: the small inverses times the blocks (a stacked solve with p
        # right-hand sides is many times slower)
        return np.matmul(np.linalg.inv(ev.Z[nodes]), S)
    S = np.zeros((N + 1, D, p))
    if Bidx.shape[0] == 0:                                  # dense basis (N, 3, nb)
        nb = Bval.shape[2]
        per = np.einsum("ncdk,ncb->ndkb", W, Bval)          # (N, D, m, nb)
        cols = np.arange(nb)[None, :] * sb + np.arange(m)[:, None] * si
        S[1:][:, :, cols.ravel()] = per.reshape(N, D, m * nb)
    else:                                                   # sparse basis (N, 3, nq)
        nq = Bidx.shape[2]
        steps = np.broadcast_to(np.arange(1, N + 1)[:, None, None, None], (N, 3, nq, m))
        cols = Bidx[..., None] * sb + np.arange(m) * si     # (N, 3, nq, m)
        vals = Bval[:, :, :, None, None] * W[:, :, None, :, :]     # (N, 3, nq, D, m)
        np.add.at(S, (steps.ravel(), slice(None), cols.ravel()),
                  np.moveaxis(vals, 3, -1).reshape(-1, D))
    np.cumsum(S, axis=0, out=S)
    return np.matmul(np.linalg.inv(ev.Z[nodes]), S[nodes])


def step_scale(endpoint: EndpointMap, controls: Controls) -> np.ndarray:
    """``S = W^{-1/2}`` of the metric the minimum norm is taken in.

    Euclidean on Fourier coefficients (parametric form, ``J^#``), L2 in time on grid
    controls (nonparametric form, eq. (11): ``W = diag(h_j)``).

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint (its ``method``).
    controls : Controls
        The parametrisation.

    Returns
    -------
    numpy.ndarray
        The diagonal of ``S``, one entry per parameter (read-only).
    """
    if endpoint.method == "parametric":
        return _ones(controls.params.size)
    return 1.0 / np.sqrt(controls.metric())


def record(iteration: int, ev: Evaluation, step: float, phase: str, rejected: int, **extra) -> dict:
    """One entry of a result's ``history`` (see :class:`~nonholo.io.result.PlanResult`).

    Parameters
    ----------
    iteration : int
        The step's number.
    ev : Evaluation
        The accepted evaluation.
    step : float
        The step taken, ``γh`` (1 for Newton).
    phase : str
        ``"flow"``, ``"newton"``, ``"initial"``, or a strategy's own.
    rejected : int
        Trial steps rejected before it.
    **extra
        Further entries (a strategy's tags).

    Returns
    -------
    dict
        The entry.
    """
    return {"iteration": iteration, "error": ev.error, "step": step,
            "min_delta": ev.min_delta, "phase": phase, "rejected": rejected, **extra}


def backtrack(endpoint: EndpointMap, ev: Evaluation, direction: np.ndarray, scale: float,
              min_step: float, full: bool = False):
    """Step control of the θ-flow: halve ``scale`` until ``λ − scale·direction`` is
    admissible (reaches ``T`` with ``|Δ| ≥ delta_min``) and lowers ``|l_T|``.

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint.
    ev : Evaluation
        The current evaluation, with parameters ``λ``.
    direction : numpy.ndarray
        The step direction.
    scale : float
        The first step's scale.
    min_step : float
        Give up once ``scale`` falls below this.
    full : bool, default False
        Whether trial evaluations are ``full``.

    Returns
    -------
    trial : Evaluation or None
        The accepted evaluation, ``None`` when giving up.
    scale : float
        The scale of the accepted step (or the last one tried).
    halvings : int
        Steps rejected.
    reason : str or None
        Why it gave up, ``None`` on success.
    """
    rejected = 0
    while True:
        trial = endpoint.evaluate(ev.params - scale * direction, full=full)
        if endpoint.admissible(trial) and trial.error < ev.error:
            return trial, scale, rejected, None
        last = (endpoint.why_not(trial) if not endpoint.admissible(trial) else
                f"|l_T| did not decrease ({trial.error:.3g} >= {ev.error:.3g})")
        rejected += 1
        scale *= 0.5
        if scale < min_step:
            return None, scale, rejected, (f"step size fell below min_step = {min_step:g} at "
                                           f"|l_T| = {ev.error:.3g}; last rejected step: {last}")


#: ``(window, ratio)``: every run of :func:`descend` stalls when ``|l_T|`` shrank by less
#: than a factor ``ratio`` over the last ``window`` accepted steps (at that pace it would
#: take thousands of steps to converge: a tiny ``γ``, a step control stuck at tiny steps).
PROGRESS = (50, 0.99)


@dataclass
class Descent:
    """How :func:`descend` ended: ``status`` is ``"converged"``, ``"budget"`` (``budget``
    steps taken), ``"stalled"``, ``"failed"`` (a step below ``min_step``) or
    ``"stopped"`` (by the callback); ``evaluation`` is the last accepted one.

    Parameters
    ----------
    evaluation : Evaluation
        The last accepted evaluation.
    steps : int
        Steps accepted.
    status : str
        How it ended.
    reason : str
        The ending in words.
    """

    evaluation: Evaluation
    steps: int
    status: str
    reason: str


def descend(endpoint: EndpointMap, ev: Evaluation, options: Options,
            direction: Callable[[Evaluation, bool], np.ndarray], *, budget: int, history: list,
            callback=None, first: int = 0, full: Callable[[Evaluation], bool] | None = None,
            stall: tuple[int, float] | None = None, tags: dict | None = None) -> Descent:
    """The step loop: flow steps, then Newton steps, from the admissible ``ev``.

    ``direction(ev, newton)`` gives the step direction (the step is ``−γh`` or ``−1`` times
    it); ``full(ev)`` whether trial evaluations keep the data of a full evaluation;
    ``stall = (window, ratio)``: stop when ``|l_T|`` (above ``newton_below``) shrank by
    less than a factor ``ratio`` over the last ``window`` steps; whatever ``stall``, every
    run stops, in any phase, when it shrank by less than :data:`PROGRESS` allows (no
    strategy runs ``max_iter`` steps without progress). Each accepted step is
    appended to ``history`` (numbered from ``first + 1``, with ``tags``) and passed to
    ``callback``, whose true return value stops the loop.

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint.
    ev : Evaluation
        An admissible evaluation to start from.
    options : Options
        The run's settings.
    direction : callable
        ``direction(ev, newton)``, the step direction.
    budget : int
        Steps at most.
    history : list
        The run's history, appended to.
    callback : callable, optional
        Called with each new history entry.
    first : int, default 0
        The number of the step before the first.
    full : callable, optional
        ``full(ev)``: whether trial evaluations are ``full``.
    stall : tuple of (int, float), optional
        ``(window, ratio)``.
    tags : dict, optional
        Entries added to each history entry.

    Returns
    -------
    Descent
        How the loop ended.
    """
    h = options.step
    it = 0
    errors = [ev.error]
    tags = tags or {}
    while True:
        if ev.error <= options.tol:
            return Descent(ev, it, "converged", f"converged: |l_T| = {ev.error:.3g} <= tol = {options.tol:g}")
        if it >= budget:
            return Descent(ev, it, "budget", f"|l_T| = {ev.error:.3g}")
        for w, ratio, flow_only in ((stall or (0, 1.0)) + (True,), PROGRESS + (False,)):
            if w and len(errors) > w and (ev.error >= options.newton_below or not flow_only) \
                    and ev.error > ratio * errors[-1 - w]:
                return Descent(ev, it, "stalled", f"stalled at |l_T| = {ev.error:.3g} (less than "
                               f"{100 * (1 - ratio):.3g} % in {w} steps)")
        newton = ev.error < options.newton_below
        scale = 1.0 if newton else options.gamma * h
        trial, scale, rejected, failure = backtrack(endpoint, ev, direction(ev, newton), scale,
                                                    options.min_step, full=full(ev) if full else False)
        if failure:
            return Descent(ev, it, "failed", failure)
        if not newton:
            h *= 0.5 ** rejected
        it += 1
        ev = trial
        errors.append(ev.error)
        if not newton and rejected == 0:
            h = min(2.0 * h, options.step)
        history.append(record(first + it, ev, scale, "newton" if newton else "flow", rejected, **tags))
        if callback is not None and callback(history[-1]):
            return Descent(ev, it, "stopped", "stopped by callback")


@dataclass(frozen=True)
class Start:
    """The initial control of a run in the strategy's coordinates: ``given`` if it is the
    caller's ``u0`` (converted), with a ``note`` on what happened to a ``u0`` that could
    not be used.

    Parameters
    ----------
    controls : Controls
        The initial control.
    given : bool, default False
        Whether it is the caller's ``u0``.
    note : str, default ""
        What happened to a ``u0`` that could not be used.
    """

    controls: Controls
    given: bool = False
    note: str = ""


@dataclass
class Outcome:
    """What a strategy returns to :func:`nonholo.plan`.

    Parameters
    ----------
    evaluation : Evaluation
        The final evaluation.
    success : bool
        Whether the run converged.
    reason : str
        The ending in words.
    history : list
        The history entries (:func:`record`).
    iterations : int, default 0
        Steps accepted.
    endpoint : EndpointMap or None, optional
        The endpoint map the final evaluation belongs to, when not the one
        :func:`nonholo.plan` built (e.g. on a finer integrator grid).
    certificate : Certificate or None, optional
        The certificate of a success (:mod:`nonholo.planning.correction`); a success
        without one is certified by :func:`nonholo.plan`.
    stopped : bool, default False
        The caller's callback stopped the run (no further route is tried).
    """

    evaluation: Evaluation
    success: bool
    reason: str
    history: list = field(default_factory=list)
    iterations: int = 0
    #: the endpoint map the final evaluation belongs to, when not the one :func:`nonholo.plan`
    #: built (e.g. on a finer integrator grid)
    endpoint: EndpointMap | None = None
    #: the certificate of a success (:mod:`nonholo.planning.correction`); a success
    #: without one is certified by :func:`nonholo.plan`
    certificate: Certificate | None = None
    #: the caller's callback stopped the run (no further route is tried)
    stopped: bool = False


class Strategy(ABC):
    """A way of following the θ-flow (see :data:`nonholo.planning.problem.STRATEGIES`).

    :meth:`frame` chooses the coordinates of the planned control (physical inputs ``u``
    of ``dR/dt = [L(R) u] R``, or frame coordinates ``w`` of ``dR/dt = [N(R) w] R``);
    :meth:`initial` turns the (validated, physical) initial control into those
    coordinates; :meth:`solve` plans. A strategy object holds only its options.

    Parameters
    ----------
    options : Options
        The run's settings.
    """

    name: ClassVar[str] = ""
    #: ``γ`` of :func:`nonholo.plan` when the caller gives none
    default_gamma: ClassVar[float] = 0.5

    def __init__(self, options: Options):
        self.options = options

    def frame(self, mechanism: Mechanism) -> bool:
        """Whether to plan in the desingularised frame coordinates ``w``.

        Parameters
        ----------
        mechanism : Mechanism
            The mechanism planned.

        Returns
        -------
        bool
            ``True`` for frame coordinates, ``False`` for physical inputs.
        """
        return False

    def initial(self, endpoint: EndpointMap, controls: Controls, given: bool) -> Start:
        """The initial control in this strategy's coordinates.

        Parameters
        ----------
        endpoint : EndpointMap
            The endpoint.
        controls : Controls
            The physical initial control (the default one, or the caller's ``u0``).
        given : bool
            Whether it is the caller's ``u0``.

        Returns
        -------
        Start
            The initial control.
        """
        return Start(controls, given)

    @abstractmethod
    def solve(self, endpoint: EndpointMap, start: Start,
              callback: Callable[[dict], object] | None = None) -> Outcome:
        """Plan from ``start``.

        Parameters
        ----------
        endpoint : EndpointMap
            The endpoint.
        start : Start
            The initial control.
        callback : callable, optional
            Called as ``callback(record)`` per accepted step; a true value stops the run.

        Returns
        -------
        Outcome
            The run's outcome.
        """


def build_result(problem, outcome: Outcome | None, success: bool, reason: str,
                 endpoint: EndpointMap | None = None) -> PlanResult:
    """The :class:`~nonholo.io.result.PlanResult` of a run.

    A success's samples are those of its certified replay.

    Parameters
    ----------
    problem : Problem
        The problem (:class:`~nonholo.planning.problem.Problem`).
    outcome : Outcome or None
        The run's outcome; ``None``: nothing simulated.
    success : bool
        Whether the plan succeeded.
    reason : str
        The result's reason.
    endpoint : EndpointMap or None, optional
        The evaluator of the run, unless the outcome names its own.

    Returns
    -------
    PlanResult
        The result.
    """
    mech, T = problem.mechanism, problem.T
    ev = outcome.evaluation if outcome is not None else None
    cert = outcome.certificate if outcome is not None and success else None
    if outcome is not None and outcome.endpoint is not None:
        endpoint = outcome.endpoint
    n_steps = problem.steps if endpoint is None else endpoint.steps
    n = 0 if ev is None else ev.steps_done + 1
    t = np.arange(n) * (T / n_steps)
    if ev is not None and ev.complete:
        t[-1] = T
    if ev is None:
        par = problem.controls              # nothing simulated: the physical initial control
    elif endpoint.frame:
        par = FrameControls(ev.controls, problem.start.R, mech, n_steps, nodes=ev.R if ev.complete else None)
    else:
        par = ev.controls
    R = ev.R if ev is not None else np.empty((0, 3, 3))
    q = ev.q if ev is not None else np.empty((0, mech.n_coordinates))
    terminal_error = None if ev is None else ev.error
    errors = None if ev is None else ev.errors
    min_delta = None if ev is None else ev.min_delta
    u = None
    if cert is not None:
        R = cert.R[::cert.replay_steps // n_steps]
        q = cert.q[::cert.replay_steps // n_steps]
        terminal_error, min_delta, errors = cert.terminal_error, cert.min_delta, cert.errors
        if cert.U is not None and getattr(par, "grid", None) is None:
            # smooth controls: u(t_n) is the replay's stage value (grid controls: controls(t)
            # decides which side of a jump a grid point's rounding falls on)
            u = cert.inputs_at(n_steps)
    return PlanResult(
        success=success, reason=reason,
        terminal_error=terminal_error, min_delta=min_delta,
        iterations=0 if outcome is None else outcome.iterations,
        history=[] if outcome is None else outcome.history,
        t=t, R=R, u=par(t).reshape(n, mech.n_inputs) if u is None else u, delta=mech.delta_samples(R, q),
        parametrisation=par, mechanism=mech.name, kinematics=mech, method=problem.method,
        strategy=problem.strategy, T=T, start=problem.start, goal=problem.goal, steps=n_steps,
        seconds=None,
        options=problem.recorded_options(),
        sensitivity=None if outcome is None or outcome.certificate is None else outcome.certificate.sensitivity,
        error_bound=None if cert is None else cert.error_bound,
        replay_steps=None if cert is None else cert.replay_steps,
        q=q, errors=part_errors(mech, errors))
