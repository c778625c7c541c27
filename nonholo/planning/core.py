"""The planning core shared by every strategy: the options, the step loop of the θ-flow, its
step control and metric, and what a strategy is (:class:`Strategy`), starts from
(:class:`Start`) and returns (:class:`Outcome`). The endpoint map the loop steps on is
:class:`nonholo.planning.endpoint_map.EndpointMap`, the problem itself
:class:`nonholo.planning.problem.Problem`; a run's result is assembled by
:func:`nonholo.planning.result_builder.build_result`.

The task: steer ``dR/dt = [L(R) u] R`` (spatial form) from ``R(0) = R0`` to ``R(T) = R_d``
(Tchoń & Jakubiak, appendix eqs. (4)–(11)). Along a family of controls ``u_θ`` the error
``e = log(R_T R_dᵀ) = [l_T]`` is asked to decay as ``dl_T/dθ = −γ l_T`` (4)–(5); with
``s_T = P(l_T) dl_T/dθ`` (7), ``P`` the left Jacobian of SO(3) (:func:`nonholo.spaces.so3.dexp`)
and ``P(l) l = l``, this asks for ``s_T = −γ l_T``, ``s_T = J ∂λ/∂θ`` with the Jacobian
``J = ∂s_T/∂λ`` of the variational system (9)–(10)
(:meth:`~nonholo.planning.endpoint_map.EndpointMap.evaluate`). Its minimum-norm solution in
a diagonal metric ``W`` is the update (11):
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
during a run lives in the :class:`Start` and
:class:`~nonholo.planning.endpoint_map.EndpointMap` it is given.
"""
from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Callable, ClassVar

import numpy as np

from ..certify.certificate import Certificate
from ..controls.parametrisations import Controls
from ..model.mechanism import Mechanism
from ..numerics.checks import check_count, is_number
from .endpoint_map import EndpointMap, Evaluation


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


@lru_cache(maxsize=16)
def _ones(p: int) -> np.ndarray:
    a = np.ones(p)
    a.setflags(write=False)
    return a


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
    """A way of following the θ-flow (see :data:`nonholo.planning.settings.STRATEGIES`).

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
