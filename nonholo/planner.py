"""Jacobian motion planning on SO(3) (Tchoń & Jakubiak, appendix eqs. (4)–(11)).

Problem: steer ``dR/dt = [L(R) u] R`` (spatial form) from ``R(0) = R0`` to ``R(T) = R_d``.

The θ-flow. Along a family of controls ``u_θ`` the error ``e = log(R_T R_dᵀ) = [l_T]``
is required to decay as ``dl_T/dθ = −γ l_T`` (4)–(5). With ``s_T = P(l_T) dl_T/dθ`` (7),
``P`` the left Jacobian of SO(3) (:func:`nonholo.so3.dexp`) and ``P(l) l = l``, this asks
for ``s_T = −γ l_T``; ``s_T = J ∂u/∂θ`` with the Jacobian operator
``J u' = ∫ Φ(T,t) B(t) u'(t) dt`` of the variational system (9)–(10). Its Moore–Penrose
inverse gives the update (11):

- parametric form (Fourier coefficients ``λ``, :class:`~nonholo.controls.Fourier`):
  ``dλ/dθ = −γ J^# l_T`` with ``J = ∫ Φ(T,t) B(t) P(t) dt`` (3 × m(2K+1)) and ``J^#`` the
  Euclidean Moore–Penrose pseudo-inverse;
- nonparametric form (values ``v_j`` on a grid, :class:`~nonholo.controls.PiecewiseConstant`):
  the pseudo-inverse in the L2 metric of the controls, ``∫|u'|² dt = Σ h_j |u'_j|²``:
  ``u'_j = −γ G_jᵀ M_d^{-1} l_T / h_j`` with ``G_j = ∫_{I_j} Φ(T,t) B(t) dt`` and
  ``M_d = Σ_j G_j G_jᵀ / h_j`` — the grid version of
  ``u'(t) = −γ Bᵀ(t) Φᵀ(T,t) M(T)^{-1} l_T`` (11), to which it converges as the grid is
  refined (``M_d → M(T)``).

Both are ``Δλ = −γh W^{-1/2} (J W^{-1/2})^# l_T`` for the diagonal metric ``W`` (identity,
resp. ``h_j``), computed as ``X^# = Xᵀ (X Xᵀ)^#`` with a 3×3 eigen decomposition, which
also copes with a rank-deficient ``J`` (:func:`min_norm_step`). (For the platform the
Euclidean and the L2 metric give the same Fourier steps: the mean inputs alone fix
``r11(T)``, ``r22(T)`` — ``u1 = −ṙ22/2``, ``u2 = −ṙ11/2`` — so the oscillating columns of
``J`` have rank 1, and both metrics weigh all oscillating coefficients alike.)

Step control (strategy ``"paper"``). The θ-flow is integrated by explicit Euler steps
``θ → θ + h``: ``λ ← λ − γh W^{-1/2}(J W^{-1/2})^# l_T``. A step is accepted only if the
new trajectory reaches ``T`` with ``|Δ| ≥ delta_min`` at every point where the integrator
evaluates ``L`` (checked by the kernel, which stops at once otherwise) and ``|l_T|``
decreases; otherwise ``h`` is halved, and the run gives up, with the reason, once
``γh < min_step``. After a step accepted at the first try ``h`` doubles again, up to its
initial value.
Once ``|l_T| < newton_below`` the steps are full Newton steps, ``γh = 1`` (halved if
rejected). That is exact Newton for the discrete map ``λ ↦ l_T``: its derivative is
``P(l_T)^{-1} J`` and, since ``P^{-1} l = l``, the equations ``P^{-1} J Δλ = −l`` and
``J Δλ = −l`` have the same solutions, hence the same minimum-norm one; the convergence
is quadratic (the computed ``J`` is that of the continuous variational system, within
the integrator's ``O(h⁴)`` of the discrete one).

Strategies are classes registered in :data:`STRATEGIES`; a new one subclasses
:class:`Strategy` and implements :meth:`Strategy.solve` on top of :class:`Problem`, without
touching :class:`PaperStrategy`. Two are provided: ``"paper"`` (above) and ``"robust"``, the
default of :func:`plan` (:mod:`nonholo.robust`: the same flow in the desingularised frame
coordinates ``w`` of ``ω = N(R) w``, with a drift initial guess, restarts and a null-space
barrier on ``Δ``; the result's controls are the physical inputs ``u = W(R) w``, see
:class:`~nonholo.controls.FrameControls`). Measured by ``python -m benchmarks.bench_robust``
on the benchmark set (``benchmarks/goals.json``, success = DOP853 re-simulation of the
physical controls within 1e-8 rad and ``|Δ| ≥ 1e-2`` on the dense path): ``"paper"``
73 % near / 69 % far, ``"robust"`` 100 % / 100 % in a median 3.6 / 4.0 ms; goals across
``Δ = 0`` rejected in a median 90 µs. Per-ingredient numbers: :mod:`nonholo.robust`.

Cost of an iteration. :class:`Problem` keeps, per parametrisation, the stage-table
function and the stage basis (dense for Fourier series: the kernel contracts the stored
stage weights with one BLAS product), and takes parameter vectors directly (no control
object per trial); the error is one compiled call (:func:`nonholo.kernels.log_error`), the
minimum-norm step a 3×3 Cholesky solve (:func:`nonholo.kernels.min_norm_step`). Measured
by ``python -m benchmarks.bench_plan`` (Examples 1–2, 400 steps, median of 30 repeats of
20 calls, interleaved, 2-core machine): one paper iteration (evaluation with the Jacobian,
solve, update, admissibility, record) costs 1.82–1.88 times one bare forward simulation
(≈ 190 µs vs ≈ 105 µs; the variational kernel with its stage table alone 1.75–1.80×).
"""
from __future__ import annotations

import math
import time
from abc import ABC, abstractmethod
from dataclasses import asdict, dataclass, field
from functools import lru_cache
from typing import Callable, ClassVar

import numpy as np

from . import kernels as _kernels
from . import mechanisms, so3
from .controls import (Controls, Fourier, FrameControls, PiecewiseConstant, _check_count, _check_T,
                       paper_initial)
from .result import PlanResult
from .simulation import DEFAULT_STEPS, DELTA_STOP, delta_samples

METHODS = ("parametric", "nonparametric")


@dataclass(frozen=True)
class Options:
    """Numerical settings of a planning run (see :func:`plan`)."""

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
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be a positive number, got {v!r}")
        for name in ("newton_below", "delta_min"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be a non-negative number, got {v!r}")
        if isinstance(self.max_iter, bool) or int(self.max_iter) != self.max_iter or self.max_iter < 0:
            raise ValueError(f"max_iter must be a non-negative integer, got {self.max_iter!r}")


class Evaluation:
    """One simulation of the planning problem for a control (with the Jacobian).

    ``params``: the control's flat parameter vector ``λ`` in the parametrisation
    ``parametrisation`` (whose own parameters are irrelevant); :attr:`controls` builds the
    control object on first use. ``complete``: the trajectory reached ``T`` (the kernel
    stops early where ``sgnΔ < delta_stop`` or ``ω`` is not finite). ``min_delta``: least
    ``sgn(Δ(R0))·Δ`` over the integrator's evaluation points (= least ``|Δ|`` unless the
    motion crossed ``Δ = 0``; ``None`` without a singular set). ``l``, ``error``, ``J``
    only when complete; ``Z`` (``Z(t_n) = Φ(t_n, 0)^{-1}`` at every node, ``(N+1, 3, 3)``)
    and ``Wd`` (the kernel's stage weights, ``(3N, 3m)``, see
    :func:`nonholo.kernels._forward_variational`) only when the evaluation was asked for
    them (``full``): with them the sensitivity of ``R(t_n)`` to ``λ`` is
    ``s_n = Z_n^{-1} Σ_{stages r before t_n} W_r ∂U_r/∂λ``.
    """

    __slots__ = ("params", "parametrisation", "complete", "steps_done", "t_stop", "min_delta",
                 "R", "l", "error", "J", "Z", "Wd", "_controls")

    def __init__(self, params, parametrisation, complete, steps_done, t_stop, min_delta, R,
                 l=None, error=None, J=None, Z=None, Wd=None):
        self.params = params
        self.parametrisation = parametrisation
        self.complete = complete
        self.steps_done = steps_done
        self.t_stop = t_stop
        self.min_delta = min_delta
        self.R = R
        self.l = l
        self.error = error
        self.J = J
        self.Z = Z
        self.Wd = Wd
        self._controls = None

    @property
    def controls(self) -> Controls:
        """The evaluated control as a :class:`~nonholo.controls.Controls` (validated)."""
        if self._controls is None:
            self._controls = self.parametrisation.with_params(self.params)
        return self._controls

    @property
    def R_T(self) -> np.ndarray | None:
        return self.R[-1] if self.complete else None


class Problem:
    """``R0 → R_d`` in time ``T`` for one mechanism, with the integrator's buffers.

    :meth:`evaluate` simulates a control with the variational system and returns the
    error ``l_T`` and the Jacobian ``J = ∂s_T/∂λ``. ``frame=True`` integrates the system
    in the desingularised frame coordinates ``w`` (``dR/dt = [N(R) w] R``, kernels bound
    to ``N``, ``QN``; ``Δ`` is still monitored): ``λ`` then parametrises ``w``.
    """

    def __init__(self, R0, Rd, T: float, mechanism: str, method: str, steps: int,
                 delta_min: float, frame: bool = False):
        self.mechanism = mechanisms.get(mechanism)
        self.frame = frame
        self.kernels = _kernels.get(self.mechanism.name, frame)
        self.R0 = np.ascontiguousarray(R0, dtype=float)
        self.Rd = np.ascontiguousarray(Rd, dtype=float)
        self.T = T
        self.method = method
        self.steps = steps
        self.h = T / steps
        self.delta_min = delta_min
        self.has_delta = self.mechanism.has_singular_set
        self.delta0 = float(self.mechanism.delta(self.R0)) if self.has_delta else None
        self.deltad = float(self.mechanism.delta(self.Rd)) if self.has_delta else None
        self.sign = float(np.sign(self.delta0)) if self.has_delta else 1.0
        self._Rs = np.empty((steps + 1, 3, 3))
        self._Zs = np.empty((steps + 1, 3, 3))
        self._M = np.empty((3, 3))
        self._U = np.empty((steps, 3, self.mechanism.n_inputs))
        self._Wd = np.empty((3 * steps, 3 * self.mechanism.n_inputs))
        self.parametrisation: Controls | None = None
        self.evaluations = 0

    def use(self, controls: Controls) -> None:
        """Interpret parameter vectors passed to :meth:`evaluate` in ``controls``' parametrisation."""
        self.parametrisation = controls
        self._fill = controls.stage_function(self.steps)
        self._basis = controls.kernel_basis(self.steps)
        self._p = controls.params.size

    @property
    def stage_basis(self) -> tuple:
        """The stage basis of the current parametrisation as the kernel takes it
        (:meth:`~nonholo.controls.Controls.kernel_basis`)."""
        return self._basis

    @property
    def n_params(self) -> int:
        """The number of parameters of the current parametrisation."""
        return self._p

    def evaluate(self, x, delta_stop: float | None = None, full: bool = False) -> Evaluation:
        """Simulate a control: a :class:`~nonholo.controls.Controls` (which becomes the
        parametrisation, see :meth:`use`) or a flat parameter vector ``λ`` in the current
        parametrisation. Stops early where ``sgnΔ < delta_stop`` (default ``delta_min``).
        ``full``: keep ``Z(t_n)`` at every node and the stage weights (:attr:`Evaluation.Z`,
        :attr:`Evaluation.Wd`)."""
        if isinstance(x, Controls):
            if x is not self.parametrisation:
                self.use(x)
            params = x._flat
        else:
            params = x
        stop = self.delta_min if delta_stop is None else delta_stop
        U = self._fill(params, self._U)
        J = np.empty((3, self._p))
        n, dmin, t_stop = self.kernels.forward_variational(
            self.R0, U, self.h, self.sign, stop, *self._basis, self._Rs, self._Zs, J, self._M, self._Wd, full)
        self.evaluations += 1
        complete = n == self.steps
        ev = Evaluation(params, self.parametrisation, complete, int(n),
                        None if complete else float(t_stop),
                        float(dmin) if self.has_delta else None, self._Rs[:n + 1].copy())
        if params is not x:
            ev._controls = x
        if complete:
            ev.l, err = _kernels.log_error(self._Rs[n], self.Rd)
            ev.error = float(err)
            ev.J = J
            if full:
                ev.Z = self._Zs.copy()
                ev.Wd = self._Wd.copy()
        return ev

    def admissible(self, ev: Evaluation) -> bool:
        """Complete and ``|Δ| ≥ delta_min`` along the whole trajectory."""
        return ev.complete and (not self.has_delta or ev.min_delta >= self.delta_min)

    def why_not(self, ev: Evaluation) -> str:
        """Why ``ev`` is not admissible."""
        if self.has_delta and (ev.min_delta is None or ev.min_delta < self.delta_min):
            where = f" at t ≈ {ev.t_stop:.4g} s" if ev.t_stop is not None else ""
            if ev.min_delta <= 0.0:
                return (f"the trajectory ran into the singular surface Δ = 0{where} (|ω| ~ 1/|Δ| "
                        "blows up there; the fixed-step integrator stepped across it)")
            return f"|Δ| fell to {ev.min_delta:.6g} < delta_min = {self.delta_min:g}{where}"
        if not ev.complete:
            return f"the angular velocity became non-finite at t ≈ {ev.t_stop:.4g} s"
        return "admissible"


@dataclass
class Outcome:
    """What a strategy returns to :func:`plan`."""

    evaluation: Evaluation
    success: bool
    reason: str
    history: list = field(default_factory=list)
    iterations: int = 0
    #: the problem the final evaluation belongs to, when not the one :func:`plan` built
    #: (e.g. a finer integrator grid)
    problem: Problem | None = None
    #: ``max_t |Φ(T, t)|_F`` of the physical system along the final motion, if computed
    sensitivity: float | None = None


class Strategy(ABC):
    """A way of following the θ-flow; subclasses are registered in :data:`STRATEGIES`.

    :meth:`frame` chooses the coordinates of the planned control (physical inputs ``u``
    of ``dR/dt = [L(R) u] R``, or frame coordinates ``w`` of ``dR/dt = [N(R) w] R``);
    :meth:`initial` turns the (validated, physical) initial control into those coordinates.
    """

    name: ClassVar[str] = ""
    #: ``γ`` of :func:`plan` when the caller gives none
    default_gamma: ClassVar[float] = 0.5

    def __init__(self, options: Options):
        self.options = options

    def frame(self, mechanism: str) -> bool:
        """Plan in the desingularised frame coordinates ``w`` (``False``: physical inputs)."""
        return False

    def initial(self, problem: Problem, controls: Controls, given: bool) -> Controls:
        """The initial control in this strategy's coordinates, from the physical ``controls``
        (the default initial control, or the caller's ``u0`` when ``given``)."""
        return controls

    @abstractmethod
    def solve(self, problem: Problem, controls: Controls,
              callback: Callable[[dict], object] | None = None) -> Outcome:
        """Plan from the initial ``controls``; call ``callback(record)`` per accepted step."""


STRATEGIES: dict[str, type[Strategy]] = {}


def register_strategy(cls: type[Strategy]) -> type[Strategy]:
    """Class decorator: make ``cls`` available as ``plan(..., strategy=cls.name)``."""
    STRATEGIES[cls.name] = cls
    return cls


def min_norm_step(J: np.ndarray, l: np.ndarray, metric: np.ndarray | None = None) -> np.ndarray:
    """``x = W^{-1/2} (J W^{-1/2})^# l``: the least-W-norm ``x`` minimising ``|J x − l|``.

    ``metric`` is the diagonal of ``W`` (``None``: Euclidean, ``x = J^# l``).
    """
    J = np.ascontiguousarray(J, dtype=float)
    scale = _ones(J.shape[1]) if metric is None else 1.0 / np.sqrt(metric)
    return _kernels.min_norm_step(J, np.ascontiguousarray(l, dtype=float), scale)


@lru_cache(maxsize=16)
def _ones(p: int) -> np.ndarray:
    a = np.ones(p)
    a.setflags(write=False)
    return a


def _record(iteration: int, ev: Evaluation, step: float, phase: str, rejected: int) -> dict:
    return {"iteration": iteration, "error": ev.error, "step": step,
            "min_delta": ev.min_delta, "phase": phase, "rejected": rejected}


@register_strategy
class PaperStrategy(Strategy):
    """The appendix's algorithm: Euler steps of the θ-flow (11), then Newton steps.

    Metric: Euclidean in the Fourier coefficients (parametric form, ``J^#``), L2 in time
    for grid controls (nonparametric form, eq. (11)). See the module docstring for the
    step control.
    """

    name = "paper"

    def metric(self, problem: Problem, controls: Controls) -> np.ndarray | None:
        return controls.metric() if problem.method == "nonparametric" else None

    def solve(self, problem, controls, callback=None):
        opt = self.options
        ev = problem.evaluate(controls, delta_stop=DELTA_STOP)
        if not problem.admissible(ev):
            return Outcome(ev, False, f"the initial control is not admissible: {problem.why_not(ev)}; "
                           "choose another initial control (u0)")
        history = [_record(0, ev, 0.0, "initial", 0)]
        if callback is not None and callback(history[-1]):
            return Outcome(ev, False, "stopped by callback", history, 0)
        metric = self.metric(problem, controls)
        scale_vec = _ones(controls.params.size) if metric is None else 1.0 / np.sqrt(metric)
        h = opt.step
        it = 0
        while True:
            if ev.error <= opt.tol:
                return Outcome(ev, True, f"converged: |l_T| = {ev.error:.3g} <= tol = {opt.tol:g}",
                               history, it)
            if it >= opt.max_iter:
                return Outcome(ev, False, f"max_iter = {opt.max_iter} reached with |l_T| = {ev.error:.3g}",
                               history, it)
            newton = ev.error < opt.newton_below
            scale = 1.0 if newton else opt.gamma * h
            direction = _kernels.min_norm_step(ev.J, ev.l, scale_vec)
            trial, scale, rejected, failure = backtrack(problem, ev, direction, scale, opt.min_step)
            if failure:
                return Outcome(ev, False, failure, history, it)
            if not newton:
                h *= 0.5 ** rejected
            it += 1
            ev = trial
            if not newton and rejected == 0:
                h = min(2.0 * h, opt.step)
            history.append(_record(it, ev, scale, "newton" if newton else "flow", rejected))
            if callback is not None and callback(history[-1]):
                return Outcome(ev, False, "stopped by callback", history, it)


def backtrack(problem: Problem, ev: Evaluation, direction: np.ndarray, scale: float,
              min_step: float, full: bool = False):
    """Step control of the θ-flow: halve ``scale`` until ``λ − scale·direction`` is
    admissible (reaches ``T`` with ``|Δ| ≥ delta_min``) and lowers ``|l_T|``.

    Returns ``(trial, scale, halvings, None)``, or ``(None, scale, halvings, reason)`` once
    ``scale`` falls below ``min_step``.
    """
    rejected = 0
    while True:
        trial = problem.evaluate(ev.params - scale * direction, full=full)
        if problem.admissible(trial) and trial.error < ev.error:
            return trial, scale, rejected, None
        last = (problem.why_not(trial) if not problem.admissible(trial) else
                f"|l_T| did not decrease ({trial.error:.3g} >= {ev.error:.3g})")
        rejected += 1
        scale *= 0.5
        if scale < min_step:
            return None, scale, rejected, (f"step size fell below min_step = {min_step:g} at "
                                           f"|l_T| = {ev.error:.3g}; last rejected step: {last}")


def initial_controls(method: str, T: float, n_inputs: int, harmonics: int, grid: int, u0=None) -> Controls:
    """The initial control in the parametrisation of ``method``.

    ``u0``: ``None`` (the examples' ``u_1 = 0.3 sin 2πt/T``, ``u_2 = 0.3 cos 2πt/T``), a
    :class:`~nonholo.controls.Controls` of the right kind and size, or a vectorised
    function ``u(t)`` (projected: least squares on the Fourier basis, interval means on
    the grid).
    """
    cls, size = (Fourier, harmonics) if method == "parametric" else (PiecewiseConstant, grid)
    if isinstance(u0, Controls):
        if not isinstance(u0, cls):
            raise ValueError(f"u0 is a {type(u0).__name__}, method {method!r} needs a {cls.__name__}")
        if u0.T != T or u0.n_inputs != n_inputs:
            raise ValueError(f"u0 is defined for T = {u0.T:g}, m = {u0.n_inputs}; the problem has "
                             f"T = {T:g}, m = {n_inputs}")
        got = u0.harmonics if cls is Fourier else u0.grid
        if got != size:
            what = "harmonics" if cls is Fourier else "grid"
            raise ValueError(f"u0 has {what} = {got}, the planner was asked for {what} = {size}")
        return u0
    func = paper_initial(T, n_inputs) if u0 is None else u0
    if not callable(func):
        raise ValueError("u0 must be None, a nonholo.controls.Controls or a function u(t)")
    c = cls.fit(func, T, size, n_inputs)
    return c


def default_steps(method: str, grid: int) -> int:
    """:data:`~nonholo.simulation.DEFAULT_STEPS`, rounded up to a multiple of ``grid`` for grid controls."""
    if method == "nonparametric":
        return -(-DEFAULT_STEPS // grid) * grid
    return DEFAULT_STEPS


def plan(R0, Rd, *, T: float = 1.0, method: str = "parametric", harmonics: int = 2,
         grid: int = 100, u0=None, gamma: float | None = None, step: float = 1.0, tol: float = 1e-10,
         max_iter: int = 200, strategy: str = "robust", mechanism: str = "platform",
         delta_min: float = 1e-2, steps: int | None = None, newton_below: float = 1e-3,
         min_step: float = 1e-6, callback: Callable[[dict], object] | None = None) -> PlanResult:
    """Plan a control steering ``R0`` to ``Rd`` in time ``T`` (seconds).

    - ``strategy``: ``"robust"`` (default, :mod:`nonholo.robust`) or ``"paper"`` (the
      appendix's algorithm, see the module docstring), or any registered one.
    - ``method``: ``"parametric"`` (Fourier series with ``harmonics`` = K) or
      ``"nonparametric"`` (piecewise constant on ``grid`` equal intervals) — of the
      physical inputs ``u`` (``"paper"``) or of the frame coordinates ``w`` (``"robust"``;
      the result's :meth:`~nonholo.result.PlanResult.controls` are physical either way).
    - ``u0``: initial control in physical units (see :func:`initial_controls`; default:
      the examples'). ``"robust"`` converts it to frame coordinates
      (:func:`nonholo.robust.to_frame`) and tries it first.
    - ``gamma`` (γ), ``step`` (initial θ-step h): each flow step asks the error to shrink
      by ``γh`` (default γ: the strategy's ``default_gamma``, 0.5 for ``"paper"`` as in
      the paper's examples, 1 for ``"robust"``); ``newton_below``: below this ``|l_T|``
      take full Newton steps (``γh = 1``);
      ``min_step``: give up when a step halved below this ``γh``; ``tol``: stop when
      ``|l_T| ≤ tol`` (rad); ``max_iter``: accepted steps at most.
    - ``delta_min``: every trajectory accepted keeps ``|Δ| ≥ delta_min`` (ignored for
      mechanisms without a singular set).
    - ``steps``: CF4 steps on ``[0, T]`` (default :func:`default_steps`).
    - ``callback(record)``: called after each accepted iteration with the history record;
      returning a true value stops the run.

    Raises ``ValueError`` for bad input (``R0``/``Rd`` not rotations, ``Δ(R0) = 0``,
    ``T ≤ 0``, ``harmonics``/``grid``/``steps`` < 1, unknown method/strategy/mechanism, bad
    numerical options). A goal on or across the singular surface ``Δ = 0`` (or within
    ``delta_min`` of it) returns at once a failed :class:`~nonholo.result.PlanResult`
    with the reason.
    """
    t_start = time.perf_counter()
    mech = mechanisms.get(mechanism)
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; known: {', '.join(METHODS)}")
    if strategy not in STRATEGIES:
        raise ValueError(f"unknown strategy {strategy!r}; known: {', '.join(STRATEGIES)}")
    T = _check_T(T)
    harmonics = _check_count(harmonics, "harmonics")
    grid = _check_count(grid, "grid")
    R0 = so3.check_rotation(R0, "R0")
    Rd = so3.check_rotation(Rd, "Rd")
    if gamma is None:
        gamma = STRATEGIES[strategy].default_gamma
    options = Options(gamma=gamma, step=step, tol=tol, max_iter=max_iter,
                      newton_below=newton_below, min_step=min_step, delta_min=delta_min)
    if mech.has_singular_set and float(mech.delta(R0)) == 0.0:
        raise ValueError("R0 lies on the singular surface Δ(R) = 0, where L(R) is undefined "
                         "(e.g. the identity); start from an orientation with Δ(R0) ≠ 0")
    controls = initial_controls(method, T, mech.n_inputs, harmonics, grid, u0)
    steps = default_steps(method, grid) if steps is None else _check_count(steps, "steps")
    controls.check_steps(steps)
    solver = STRATEGIES[strategy](options)

    def result(outcome: Outcome | None, success: bool, reason: str, problem=None) -> PlanResult:
        ev = outcome.evaluation if outcome is not None else None
        if outcome is not None and outcome.problem is not None:
            problem = outcome.problem
        n_steps = steps if problem is None else problem.steps
        n = 0 if ev is None else ev.steps_done + 1
        t = np.arange(n) * (T / n_steps)
        if ev is not None and ev.complete:
            t[-1] = T
        if ev is None:
            par = controls                  # nothing simulated: the physical initial control
        elif problem.frame:
            par = FrameControls(ev.controls, R0, mech.name, n_steps,
                                nodes=ev.R if ev.complete else None)
        else:
            par = ev.controls
        R = ev.R if ev is not None else np.empty((0, 3, 3))
        return PlanResult(
            success=success, reason=reason,
            terminal_error=None if ev is None else ev.error,
            min_delta=None if ev is None else ev.min_delta,
            iterations=0 if outcome is None else outcome.iterations,
            history=[] if outcome is None else outcome.history,
            t=t, R=R, u=par(t).reshape(n, mech.n_inputs), delta=delta_samples(mech, R),
            parametrisation=par, mechanism=mech.name, method=method, strategy=strategy,
            T=T, R0=R0, Rd=Rd, steps=n_steps, seconds=time.perf_counter() - t_start,
            options={**asdict(options), "harmonics": harmonics, "grid": grid},
            sensitivity=None if outcome is None else outcome.sensitivity)

    # goals that cannot be reached: decided before anything is simulated (or compiled)
    if mech.has_singular_set:
        d0, dd = float(mech.delta(R0)), float(mech.delta(Rd))
        if dd == 0.0:
            return result(None, False, "the goal lies on the singular surface Δ = 0 "
                          "(Δ(Rd) = 0): unreachable with bounded inputs")
        if np.sign(dd) != np.sign(d0):
            return result(None, False, f"the goal lies across the singular surface Δ = 0 "
                          f"(Δ(R0) = {d0:.4g}, Δ(Rd) = {dd:.4g}): no motion can cross it, unreachable")
        if abs(dd) < options.delta_min:
            return result(None, False, f"the goal lies within delta_min = {options.delta_min:g} of "
                          f"the singular surface (|Δ(Rd)| = {abs(dd):.3g})")
        if abs(d0) < options.delta_min:
            return result(None, False, f"the start lies within delta_min = {options.delta_min:g} of "
                          f"the singular surface (|Δ(R0)| = {abs(d0):.3g})")

    problem = Problem(R0, Rd, T, mech.name, method, steps, options.delta_min,
                      frame=solver.frame(mech.name))
    start = solver.initial(problem, controls, u0 is not None)
    outcome = solver.solve(problem, start, callback)
    return result(outcome, outcome.success, outcome.reason, problem)


# registers the strategy "robust" (imports this module)
from . import robust as _robust  # noqa: E402,F401
