"""The endpoint map of a planning problem, ``λ ↦ s_T``: a control simulated from the start
in time ``T`` with the variational system (Tchoń & Jakubiak, appendix eqs. (9)–(10)), the
terminal error ``l_T`` from the goal and the Jacobian ``J = ∂s_T/∂λ``
(:class:`EndpointMap`, one simulation an :class:`Evaluation`), and what a ``full``
evaluation gives without another simulation: the sensitivities of the nodes' states
(:func:`node_sensitivities`) and the gradients of weighted sums of them
(:func:`node_gradient`), with the spatial gradient of ``Δ`` (:func:`spatial_gradient_delta`).

The step loop of the θ-flow that walks on it is :mod:`nonholo.planning.core`.
"""
from __future__ import annotations

import numpy as np

from ..controls import stages
from ..controls.parametrisations import Controls
from ..integrate.compiled import compiled_system
from ..model.limits import Limits
from ..model.mechanism import Mechanism
from ..numerics import kernels
from ..spaces.state import State


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
            if self.mechanism.n_coordinates == 0:
                return f"the angular velocity became non-finite at t ≈ {ev.t_stop:.4g} s"
            escaped = " (the drift carried the state to infinity)" if self.mechanism.has_drift else ""
            return f"the rates became non-finite at t ≈ {ev.t_stop:.4g} s{escaped}"
        if self.limits is not None and ev.min_clearance < 0.0:
            return self.limits.describe(self.mechanism, ev.R, np.arange(len(ev.R)) * self.h, ev.q)
        return "admissible"


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
    nodes = np.asarray(nodes, dtype=int)
    unique, inverse = np.unique(nodes, return_inverse=True)
    if unique.size < nodes.size:
        # a node asked for more than once (several limits at it): its sensitivity once
        return node_sensitivities(endpoint, ev, unique)[inverse]
    N, m, D = endpoint.steps, endpoint.mechanism.n_inputs, endpoint.mechanism.n_rates
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
