"""The global route: a goal the local planner cannot reach, reached hop by hop along a path
of orientations through the start's component.

:func:`steer` takes the path of :func:`nonholo.planning.roadmap.orientation_path` (hops of at most
:data:`nonholo.planning.roadmap.MAX_HOP` rad, clear of ``Δ = 0``) and plans each hop with the
local planner (``local(R_start, R_goal, T, delta_min)``: :func:`nonholo.plan` with the
run's strategy (:func:`hop_strategy`) and options, route ``"local"``, ``delta_min`` of
:func:`hop_delta_min`), from where the previous hop's certified replay ended, so that no
hop's error carries into the next. A hop that fails, or whose sensitivity exceeds
:data:`MAX_HOP_SENSITIVITY`, is split at its geodesic midpoint (down to :data:`MIN_HOP`
rad, at most :data:`MAX_PIECES` pieces in all). The hops' physical controls are stitched
into one control on ``[0, T]``, an equal time share each
(:class:`~nonholo.controls.stitched.Stitched`); the stitched control is then certified as a whole
(:func:`nonholo.certify.certificate.measure`). Where that replay misses the goal
by more than ``tol`` allows, the last hop is planned again from where the stitched replay
enters it.

Smoothing. The stitched control jumps where one hop hands over to the next. Once it is
certified, :func:`smooth` re-plans the whole motion as one control of the run's
parametrisation, with the stitched control as the initial guess: its planned coordinates
(:meth:`~nonholo.controls.stitched.Stitched.planned`; the frame coordinates ``w`` for strategy
``"robust"``, smooth between hand-overs even where ``u`` is large near ``Δ = 0``)
projected on :data:`SMOOTHING_HARMONICS` harmonics (or on the run's grid), then the
strategy's descent from that guess alone (:func:`smoothing_strategy`). The guess starts
close to the goal along the route's corridor, so the descent is short. Where it
converges and is certified, the smooth control is the plan's and the stitched one is kept
as its record (:attr:`nonholo.io.result.PlanResult.stitched`); otherwise the plan is the
stitched control. A stitched control that is *not* certified — typically too
ill-conditioned: it multiplies its hops' sensitivities — is smoothed the same way before
the next path is tried: one smooth control along the same corridor is often far better
conditioned, and its own certificate decides.

Two legs, last. Where no path's stitched control is certified (typically each too
ill-conditioned: many hops of moderate sensitivity multiply), :func:`steer` tries routes of
two legs through one intermediate orientation ``R_m``, a roadmap node of the component
(:func:`nonholo.planning.roadmap.via_nodes`): the leg ``R_m → R_d`` first (reaching the goal is the
hard part), then ``R_0 → R_m``, each planned as a whole without the hops' sensitivity cap
(two legs multiply only two) and with a few initial guesses only
(:func:`quick_strategy`), stitched and certified as above, within :data:`VIA_TIME` more.

States beyond SO(3) (:mod:`nonholo.spaces.product`). For a mechanism whose state is ``(R, q)`` or
``q``, the path is the straight path of states (:func:`nonholo.planning.state_path.straight_path`,
hops of at most :data:`nonholo.planning.state_path.MAX_HOP`, checked clear of ``Δ = 0``), a failed
hop is split at its straight midpoint, and the hops, stitching, certification and
smoothing are the same, on the stacked state and its error.

The stitched motion is played open loop, so its sensitivity is the product of its hops'
transition matrices: each amplifies errors by a factor that grows with ``∫ |ω| dt /
|Δ|``. Paths are therefore the cheapest in ``∫ ds / |Δ|^p`` rather than the shortest,
and where the stitched control is still too ill-conditioned to certify, the route is
steered again along the path of the next cost :data:`nonholo.planning.roadmap.CONDITIONING_POWERS`
(within :data:`TIME_BUDGET`).
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import Callable

import numpy as np

from ..certify import certificate as certify
from ..certify.certificate import Certificate
from ..controls.parametrisations import Fourier, PiecewiseConstant
from ..controls.stitched import Stitched
from ..io.result import PlanResult, part_errors
from ..model.mechanism import Mechanism
from ..numerics import effort
from ..spaces import so3
from ..spaces.state import State
from . import roadmap, state_path
from .correction import certified
from .core import Outcome, EndpointMap, Start
from .core import build_result as build_local_result

#: The shortest hop a failed hop is split into (rad).
MIN_HOP = 0.02
#: Pieces of a stitched control at most.
MAX_PIECES = 64
#: A hop planned with a larger sensitivity is split instead: the stitched motion's
#: sensitivity grows like the product of its hops'.
MAX_HOP_SENSITIVITY = 10.0
#: Re-plans of the last hop from the stitched replay at most.
MAX_REPAIRS = 2
#: Hops keep ``|Δ|`` at least this (or half what their ends have, if less): a motion close
#: to ``Δ = 0`` is ill-conditioned, and the stitched motion multiplies its hops' conditioning.
HOP_DELTA_MIN = 0.05
#: The stitched control's certified replay is at most this many times finer than its hops'.
STITCHED_REFINEMENT = 8
#: Seconds of effort (:mod:`nonholo.numerics.effort`: integration counted in steps, seconds of the
#: reference machine) after the start of :func:`nonholo.plan` (the local attempt included)
#: after which the global route tries no further hop, and no smoothing is started or
#: continued. Effort, not wall time: a plan does not depend on the machine's speed or load.
TIME_BUDGET = 2.5
#: Intermediate orientations the route's last stage tries at most (:func:`steer`):
#: roadmap nodes in their random sampling order (:func:`nonholo.planning.roadmap.via_nodes`).
VIA_CANDIDATES = 64
#: Seconds of effort the last stage may take beyond :data:`TIME_BUDGET`.
VIA_TIME = 0.75
#: Initial guesses a leg of the last stage tries (:func:`quick_strategy`): a leg that the
#: first ones do not solve is skipped for the next candidate, which is cheaper than
#: insisting.
VIA_ATTEMPTS = 2
#: Harmonics of the smooth re-plan of a stitched control (method ``"parametric"``), tried
#: in turn: the guess must follow the hops' controls, which jump at the hand-overs, well
#: enough to stay in the route's corridor (fewer harmonics leave it more often than not).
SMOOTHING_HARMONICS = (16, 32)
#: Seconds of effort the smoothing may take (within :data:`TIME_BUDGET`): most routes
#: smooth in a fraction of this; the rest keep their stitched control.
SMOOTHING_TIME = 0.5


@dataclass
class Steered:
    """What :func:`steer` made of a route.

    Parameters
    ----------
    controls : Stitched or None
        The stitched control (``None`` if a hop failed or it was not certified).
    certificate : Certificate or None
        Its certificate.
    hops : list of PlanResult
        The hops' results.
    reason : str
        Why the route failed.
    path : numpy.ndarray or None
        The path's orientations.
    certify_seconds : float, default 0.0
        Seconds of effort the stitched control's last certification took.
    draft : Stitched or None
        The stitched control of a route whose hops all succeeded but whose stitched control
        was not certified (``controls`` is then ``None``).
    smoothed : tuple or None
        The route re-planned as one smooth control (:func:`smooth`), when ``steer`` was
        given a ``rescue`` that succeeded on the ``draft``.
    two_legs : bool, default False
        Whether the route is the last stage's two legs through an intermediate orientation.
    """

    controls: Stitched | None
    certificate: Certificate | None
    hops: list = field(default_factory=list)
    reason: str = ""
    path: np.ndarray | None = None
    #: seconds of effort the stitched control's last certification took
    certify_seconds: float = 0.0
    #: the stitched control of a route whose hops all succeeded but whose stitched control
    #: was not certified (``controls`` is then ``None``)
    draft: Stitched | None = None
    #: the route re-planned as one smooth control (:func:`smooth`), when ``steer`` was
    #: given a ``rescue`` that succeeded on the ``draft``
    smoothed: tuple | None = None
    #: whether the route is the last stage's two legs through an intermediate orientation
    two_legs: bool = False


def _stitch(mechanism: Mechanism, T: float, hops: list, start) -> Stitched:
    R0, q0 = start
    coordinates = mechanism.space.recorded("coordinates", [q0] + [h.qd for h in hops])
    return Stitched(T, [h.parametrisation for h in hops], [R0] + [h.Rd for h in hops], coordinates)


def _end(res: PlanResult) -> State:
    """Where a hop's result ends."""
    return State(res.R_T, res.q[-1])


class RoadmapPaths:
    """The route's paths for a state on SO(3) alone: the roadmap's paths of orientations
    (:mod:`nonholo.planning.roadmap`), hops measured in rad, the budget counted from the
    start of :func:`nonholo.plan`.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism planned.
    """

    unit = " rad"
    max_hop_sensitivity = MAX_HOP_SENSITIVITY

    def __init__(self, mechanism: Mechanism):
        self.mechanism = mechanism

    def paths(self, start, goal, delta_min: float, leg_limits):
        """The paths :func:`steer` tries in turn: the roadmap's, one per cost.

        The costs are those of :data:`nonholo.planning.roadmap.CONDITIONING_POWERS`, in order.

        Parameters
        ----------
        start, goal : tuple
            The ends, states ``(R, q)``.
        delta_min : float
            The least ``sgnΔ`` anywhere.
        leg_limits : LegLimits or None
            Stroke limits the paths keep inside.

        Yields
        ------
        list of tuple or None
            A path of states ``(R, q)``, or ``None`` for none.
        """
        for power in roadmap.CONDITIONING_POWERS:
            path = roadmap.orientation_path(self.mechanism, start[0], goal[0], delta_min=delta_min,
                                            power=power, legs=leg_limits)
            yield None if path is None else [self.mechanism.space.state(R) for R in path]

    def no_path(self, leg_limits, start, goal) -> str:
        """Why no path of :meth:`paths` was given.

        Parameters
        ----------
        leg_limits : LegLimits or None
            The stroke limits.
        start, goal : tuple
            The ends, states ``(R, q)``.

        Returns
        -------
        str
            The reason.
        """
        within = "" if leg_limits is None else " and inside the legs' stroke limits"
        return f"no path of orientations clear of Δ = 0{within} joins the start and the goal on the roadmap"

    def length(self, a, b) -> float:
        """The length of the hop ``a → b`` (rad).

        Parameters
        ----------
        a, b : tuple
            The ends, states ``(R, q)``.

        Returns
        -------
        float
            The geodesic angle between their orientations.
        """
        return so3.distance(a[0], b[0])

    def midpoint(self, a, b) -> tuple:
        """The state halfway between ``a`` and ``b``, where a failed hop is split.

        Parameters
        ----------
        a, b : tuple
            The ends, states ``(R, q)``.

        Returns
        -------
        tuple
            The state ``(R, q)``.
        """
        return self.mechanism.space.interpolate(a, b, [0.5])[0]

    def time_budget(self, plan_started: float) -> tuple[float, float]:
        """When the route's clock starts and its budget (seconds of effort).

        Parameters
        ----------
        plan_started : float
            The :func:`nonholo.numerics.effort.seconds` reading at the start of
            :func:`nonholo.plan`.

        Returns
        -------
        started : float
            When the route's clock starts: ``plan_started``.
        budget : float
            :data:`TIME_BUDGET`.
        """
        return plan_started, TIME_BUDGET

    def through(self) -> str:
        """What the route goes through, for the result's reason.

        Returns
        -------
        str
            ``"a path of orientations clear of Δ = 0"``.
        """
        return "a path of orientations clear of Δ = 0"


class StraightPaths(RoadmapPaths):
    """The route's paths for a state with coordinates: the straight path of states
    (:mod:`nonholo.planning.state_path`), hops measured in the stacked error's norm, the
    budget counted from the route's own start (the local attempt at a far goal can take
    the whole of :data:`TIME_BUDGET`).

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism planned.
    """

    max_hop_sensitivity = state_path.MAX_HOP_SENSITIVITY

    @property
    def unit(self) -> str:
        """The stacked error's unit (:attr:`nonholo.spaces.product.Product.error_unit`), spaced."""
        unit = self.mechanism.space.error_unit
        return f" {unit}" if unit else ""

    def paths(self, start, goal, delta_min: float, leg_limits):
        """The one path :func:`steer` tries: the straight path of states.

        Parameters
        ----------
        start, goal : tuple
            The ends, states ``(R, q)``.
        delta_min : float
            The least ``sgnΔ`` anywhere.
        leg_limits : LegLimits or None
            Not used (no mechanism with coordinates has legs).

        Yields
        ------
        list of tuple or None
            The path (:func:`nonholo.planning.state_path.straight_path`), or ``None``.
        """
        yield state_path.straight_path(self.mechanism, start, goal, delta_min=delta_min)

    def no_path(self, leg_limits, start, goal) -> str:
        """Why there is no straight path.

        Parameters
        ----------
        leg_limits : LegLimits or None
            Not used.
        start, goal : tuple
            The ends, states ``(R, q)``.

        Returns
        -------
        str
            The reason: too far, or too close to ``Δ = 0``.
        """
        return state_path.too_far(self.mechanism, start, goal) or (
            f"the straight path of states comes within delta_min of the singular set Δ = 0 of "
            f"{self.mechanism.name!r}")

    def length(self, a, b) -> float:
        """The length of the hop ``a → b``, in the stacked error's norm.

        Parameters
        ----------
        a, b : tuple
            The ends, states ``(R, q)``.

        Returns
        -------
        float
            The length (:func:`nonholo.planning.state_path.length`).
        """
        return state_path.length(self.mechanism, a, b)

    def time_budget(self, plan_started: float) -> tuple[float, float]:
        """When the route's clock starts and its budget (seconds of effort).

        Parameters
        ----------
        plan_started : float
            Not used: the clock starts now.

        Returns
        -------
        started : float
            The :func:`nonholo.numerics.effort.seconds` reading now.
        budget : float
            :data:`nonholo.planning.state_path.TIME_BUDGET`.
        """
        return effort.seconds(), state_path.TIME_BUDGET

    def through(self) -> str:
        """What the route goes through, for the result's reason.

        Returns
        -------
        str
            ``"a straight path of states"``, clear of ``Δ = 0`` where there is a singular set.
        """
        return "a straight path of states" + (" clear of Δ = 0" if self.mechanism.singular.exists else "")


def paths_for(mechanism: Mechanism) -> RoadmapPaths:
    """The route's path provider for a mechanism's space.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.

    Returns
    -------
    RoadmapPaths
        The roadmap of orientations for a state on SO(3) alone, the straight path of
        states (:class:`StraightPaths`) otherwise.
    """
    return StraightPaths(mechanism) if mechanism.space.k else RoadmapPaths(mechanism)


def time_budget(mechanism: Mechanism, plan_started: float) -> tuple[float, float]:
    """When the route's clock starts and its budget, seconds of effort (:func:`paths_for`).

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.
    plan_started : float
        The :func:`nonholo.numerics.effort.seconds` reading at the start of :func:`nonholo.plan`.

    Returns
    -------
    started : float
        When the route's clock starts.
    budget : float
        Its budget.
    """
    return paths_for(mechanism).time_budget(plan_started)


def max_hop_sensitivity(mechanism: Mechanism) -> float:
    """The largest sensitivity of a hop the route keeps (a larger one is split).

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.

    Returns
    -------
    float
        :data:`MAX_HOP_SENSITIVITY` on SO(3),
        :data:`nonholo.planning.state_path.MAX_HOP_SENSITIVITY` with coordinates (see there
        why it is larger).
    """
    return paths_for(mechanism).max_hop_sensitivity


@lru_cache(maxsize=8)
def hop_strategy(cls: type, limit: float = MAX_HOP_SENSITIVITY) -> type:
    """A strategy for hops: the strategy class ``cls`` with a sensitivity ``limit``.

    Parameters
    ----------
    limit : float, default MAX_HOP_SENSITIVITY
        The largest sensitivity of a hop (:func:`max_hop_sensitivity`).

    Returns
    -------
    type
        Where the strategy weighs the conditioning of its plans (``max_sensitivity``), a
        subclass that keeps searching until a hop's is below ``limit``; else ``cls``.
    """
    if not hasattr(cls, "max_sensitivity"):
        return cls
    return type(cls.__name__, (cls,), {"max_sensitivity": limit, "__module__": cls.__module__})


@lru_cache(maxsize=8)
def quick_strategy(cls: type) -> type:
    """A strategy for the legs of the route's last stage, from the strategy class ``cls``.

    Returns
    -------
    type
        A subclass trying only its first :data:`VIA_ATTEMPTS` initial guesses (``cls``
        itself for a strategy without several, ``attempts``).
    """
    if not hasattr(cls, "attempts"):
        return cls

    def attempts(self, problem, start):
        return itertools.islice(cls.attempts(self, problem, start), VIA_ATTEMPTS)

    return type(cls.__name__, (cls,), {"attempts": attempts, "__module__": cls.__module__})


@lru_cache(maxsize=8)
def smoothing_strategy(cls: type) -> type:
    """A strategy for the smooth re-plan, from the strategy class ``cls``.

    The re-plan is wanted near the stitched control, not anywhere.

    Returns
    -------
    type
        A subclass descending from the given initial control alone (``cls`` itself for a
        strategy without several initial guesses, ``attempts``).
    """
    if not hasattr(cls, "attempts"):
        return cls

    def attempts(self, problem, start):
        yield "stitched", start.controls

    return type(cls.__name__, (cls,), {"attempts": attempts, "__module__": cls.__module__})


def smoothing_guesses(stitched: Stitched, method: str, harmonics: int, grid: int, steps: int) -> list:
    """The initial controls of :func:`smooth`.

    Parameters
    ----------
    stitched : Stitched
        The stitched control.
    method : str
        The run's method.
    harmonics : int
        The run's harmonics.
    grid : int
        The run's grid.
    steps : int
        The run's integrator steps.

    Returns
    -------
    list of Controls
        The stitched control's planned coordinates projected on :data:`SMOOTHING_HARMONICS`
        harmonics (those above ``harmonics`` that ``steps`` resolve) or, for method
        ``"nonparametric"``, on the run's grid.
    """
    T, m = stitched.T, stitched.n_inputs
    if method == "nonparametric":
        return [PiecewiseConstant.fit(stitched.planned, T, grid, m)]
    return [Fourier.fit(stitched.planned, T, K, m) for K in SMOOTHING_HARMONICS if harmonics < K <= steps // 2]


def smooth(problem, stitched: Stitched, strategy: type, deadline: float,
           reserve: float = 0.0) -> tuple[Outcome, EndpointMap] | None:
    """The route's motion re-planned as one control (see the module).

    Nothing is tried unless :data:`SMOOTHING_TIME` and ``reserve`` fit before
    ``deadline``; a descent stops at its first iteration past :data:`SMOOTHING_TIME`.

    Parameters
    ----------
    problem : Problem
        The run's endpoint.
    stitched : Stitched
        The stitched control.
    strategy : type
        The run's strategy class.
    deadline : float
        An :func:`nonholo.numerics.effort.seconds` reading by which the smoothing must be done.
    reserve : float, default 0.0
        Seconds of effort kept for the certification after a descent converges (about what
        the stitched control's took), which cannot be interrupted.

    Returns
    -------
    tuple of (Outcome, EndpointMap) or None
        The certified outcome and its endpoint, or ``None`` when no guess of
        :func:`smoothing_guesses` converged to a certified plan in time.
    """
    now = effort.seconds()
    if now + SMOOTHING_TIME + reserve > deadline:
        return None
    deadline = now + SMOOTHING_TIME
    opts = problem.options
    solver = smoothing_strategy(strategy)(opts)
    frame = solver.frame(problem.mechanism)

    def out_of_time(record) -> bool:
        return effort.seconds() > deadline

    for guess in smoothing_guesses(stitched, problem.method, problem.harmonics, problem.grid, problem.steps):
        if effort.seconds() > deadline:
            return None
        endpoint = problem.evaluator(frame=frame)
        outcome = solver.solve(endpoint, Start(guess, True), out_of_time)
        if outcome.success and outcome.certificate is None:
            outcome = certified(outcome, endpoint, opts)
        if outcome.success:
            return outcome, endpoint
    return None


def hop_delta_min(mechanism: Mechanism, a, b, delta_min: float) -> float:
    """The ``delta_min`` of a hop between two states.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.
    a, b : tuple
        The hop's ends, states ``(R, q)``.
    delta_min : float
        The run's ``delta_min``.

    Returns
    -------
    float
        :data:`HOP_DELTA_MIN`, or half the least ``|Δ|`` of its ends if that is less, never
        below the run's ``delta_min`` (which is all a mechanism without a singular set has).
    """
    ends = float(np.min(np.abs(mechanism.singular.values(np.stack([a[0], b[0]]), np.stack([a[1], b[1]])))))
    if not np.isfinite(ends):         # Δ ≡ +∞: no singular set to keep clear of
        return delta_min
    return max(delta_min, min(HOP_DELTA_MIN, 0.5 * ends))


def steer(mechanism: Mechanism, start: State, goal: State, T: float, local: Callable, *, tol: float,
          delta_min: float, sign: float, budget: float | None = None, started: float | None = None,
          leg_limits=None, rescue: Callable | None = None,
          leg: Callable | None = None, limits=None) -> Steered:
    """The route ``start → goal`` steered hop by hop (see the module).

    Along the path of the first cost of :data:`nonholo.planning.roadmap.CONDITIONING_POWERS`,
    then along the path of the next (one not tried yet) while the route fails; beyond
    SO(3), along the straight path of states.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.
    start, goal : State
        Start and goal (:class:`~nonholo.spaces.state.State`).
    T : float
        The time horizon.
    local : callable
        ``local(start, goal, T, delta_min)`` plans one hop between two states ``(R, q)`` (a
        :class:`~nonholo.io.result.PlanResult`).
    tol : float
        The run's ``tol``.
    delta_min : float
        The run's ``delta_min``.
    sign : float
        ``sgnΔ`` of the start.
    budget : float, optional
        Seconds of effort (default :data:`TIME_BUDGET`) after ``started`` after which no
        further hop is tried.
    started : float, optional
        An :func:`nonholo.numerics.effort.seconds` reading (default: now).
    leg_limits : LegLimits or None, optional
        Stroke limits (:class:`~nonholo.model.limits.LegLimits`) the path of orientations and
        the stitched replay keep (``local`` keeps them in each hop).
    rescue : callable, optional
        ``rescue(draft, seconds)``: called when a path's hops all succeed but their stitched
        control is not certified (``seconds``: what its certification took); a smooth
        re-plan from it (:func:`smooth`: an ``(outcome, problem)``, or ``None``) ends the
        search (``Steered.smoothed``) — one smooth control is often far better conditioned
        than the product of its hops'.
    leg : callable, optional
        ``leg(start, goal, T, delta_min, quick)``: plans a leg of the last stage (see the
        module) with the run's strategy, without the hops' cap, ``quick``: with
        :func:`quick_strategy`; without it (or beyond SO(3)) there is no last stage.
    limits : Limits, optional
        Further clearances the stitched replay keeps (:class:`~nonholo.model.limits.Limits`,
        the coordinates' bounds; ``local`` keeps them in each hop).

    Returns
    -------
    Steered
        What became of the route.
    """
    if started is None:
        started = effort.seconds()
    if budget is None:
        budget = TIME_BUDGET
    steered, tried = None, []
    provider = paths_for(mechanism)
    for path in provider.paths(start, goal, delta_min, leg_limits):
        if path is None:
            return Steered(None, None, reason=provider.no_path(leg_limits, start, goal))
        if any(_same_path(p, path) for p in tried):
            continue        # steering is deterministic: the same path fails the same way
        tried.append(path)
        steered = _steer_path(mechanism, path, goal, T, local, tol=tol, delta_min=delta_min, sign=sign,
                              deadline=started + budget, leg_limits=leg_limits, limits=limits)
        if steered.controls is None and steered.draft is not None and rescue is not None:
            steered.smoothed = rescue(steered.draft, steered.certify_seconds)
        if steered.controls is not None or steered.smoothed is not None or effort.seconds() > started + budget:
            break
    if steered.controls is None and steered.smoothed is None and leg is not None and not mechanism.space.k:
        two_legs = _via(mechanism, start, goal, T, leg, tol=tol, delta_min=delta_min, sign=sign,
                        deadline=max(effort.seconds(), started + budget) + VIA_TIME, leg_limits=leg_limits)
        if two_legs is not None:
            return two_legs
    return steered


def _same_path(a: list, b: list) -> bool:
    return len(a) == len(b) and all(np.array_equal(x[0], y[0]) and np.array_equal(x[1], y[1])
                                    for x, y in zip(a, b))


def _steer_path(mechanism: Mechanism, path: list, goal, T: float, local: Callable, *, tol: float,
                delta_min: float, sign: float, deadline: float, leg_limits=None, limits=None) -> Steered:
    """:func:`steer` along one path of states ``(R, q)`` (``path[0]`` the start)."""
    start = State.of(path[0])
    provider = paths_for(mechanism)
    T_hop = T / (len(path) - 1)
    targets = list(path[1:])
    hops = []
    here = start
    waypoints = np.stack([p[0] for p in path])
    while targets:
        if len(hops) + len(targets) > MAX_PIECES:
            return Steered(None, None, hops, f"the route needs more than {MAX_PIECES} hops", waypoints)
        if effort.seconds() > deadline:
            return Steered(None, None, hops, f"the route ran out of its time after {len(hops)} "
                                             f"hops ({len(targets)} to go)", waypoints)
        res = local(here, targets[0], T_hop, hop_delta_min(mechanism, here, targets[0], delta_min))
        if res.success and res.sensitivity <= provider.max_hop_sensitivity:
            hops.append(res)
            here = _end(res)
            targets.pop(0)
            continue
        length = provider.length(here, targets[0])
        if length / 2 < MIN_HOP:
            why = res.reason if not res.success else f"sensitivity {res.sensitivity:.3g}"
            return Steered(None, None, hops, f"hop {len(hops) + 1} ({length:.3g}{provider.unit}) failed: {why}", waypoints)
        targets.insert(0, provider.midpoint(here, targets[0]))
    return _certify_hops(mechanism, start, goal, T, hops, local, tol=tol, delta_min=delta_min, sign=sign,
                         leg_limits=leg_limits, waypoints=waypoints, limits=limits)


def _certify_hops(mechanism: Mechanism, start, goal, T: float, hops: list, local: Callable, *, tol: float,
                  delta_min: float, sign: float, leg_limits, waypoints, limits=None) -> Steered:
    """The hops' controls stitched and certified as a whole from ``start`` to ``goal``; where
    the replay misses the goal by a correctable error, the last hop is planned again by
    ``local`` from where the stitched replay enters it (at most :data:`MAX_REPAIRS` times)."""
    cert = None
    for repair in range(MAX_REPAIRS + 1):
        stitched = _stitch(mechanism, T, hops, start)
        k = len(hops)
        M = k * max(h.replay_steps for h in hops)
        clock = effort.seconds()
        cert = certify.measure(State.of(start), State.of(goal), T, mechanism, stitched, M, tol, delta_min,
                               sign, max_steps=min(certify.MAX_REPLAY_STEPS, STITCHED_REFINEMENT * M),
                               leg_limits=leg_limits, limits=limits)
        clock = effort.seconds() - clock
        if cert.passed or not cert.correctable or repair == MAX_REPAIRS:
            break
        # the last hop again, from where the stitched replay enters it
        i = (k - 1) * (cert.replay_steps // k)
        entry = State(cert.R[i], cert.q[i])
        res = local(entry, goal, hops[-1].T, hop_delta_min(mechanism, entry, goal, delta_min))
        if not res.success:
            break
        hops[-1] = res
    if not cert.passed:
        return Steered(None, cert, hops, f"the stitched control is not certified: {cert.reason}", waypoints,
                       clock, draft=stitched)
    return Steered(stitched, cert, hops, "", waypoints, clock)


def _via(mechanism: Mechanism, start, goal, T: float, leg: Callable, *, tol: float, delta_min: float,
         sign: float, deadline: float, leg_limits=None) -> Steered | None:
    """The route's last stage (see the module): two legs ``start → R_m → goal`` through the
    first roadmap node ``R_m`` (:func:`nonholo.planning.roadmap.via_nodes`) whose stitched control is
    certified, by ``deadline`` (an :func:`nonholo.numerics.effort.seconds` reading); ``None`` if none
    is. The legs keep the run's ``delta_min``, as one local plan does."""
    def repair(a, b, T_leg, leg_delta_min):
        return leg(a, b, T_leg, leg_delta_min, False)

    for Rm in roadmap.via_nodes(mechanism, start[0], goal[0], VIA_CANDIDATES, leg_limits):
        if effort.seconds() > deadline:
            return None
        middle = mechanism.space.state(Rm)
        second = leg(middle, goal, T / 2, delta_min, True)
        if not second.success:
            continue
        first = leg(start, middle, T / 2, delta_min, True)
        if not first.success:
            continue
        steered = _certify_hops(mechanism, start, goal, T, [first, second], repair, tol=tol, delta_min=delta_min,
                                sign=sign, leg_limits=leg_limits, waypoints=np.stack([start[0], Rm, goal[0]]))
        if steered.controls is not None:
            return replace(steered, two_legs=True)
    return None


def build_result(problem, steered: Steered, local_reason: str,
                 smoothed: tuple[Outcome, EndpointMap] | None = None) -> PlanResult:
    """The :class:`~nonholo.io.result.PlanResult` of a certified global route.

    Its history: the hops' histories one after another (each record tagged with its
    ``hop``), then, if the route was ``smoothed`` (:func:`smooth`), the smooth re-plan's
    (tagged ``"hop": None``).

    Parameters
    ----------
    problem : Problem
        The run's endpoint.
    steered : Steered
        The certified route.
    local_reason : str
        Why the local planner alone did not reach the goal.
    smoothed : tuple of (Outcome, EndpointMap), optional
        The smooth re-plan.

    Returns
    -------
    PlanResult
        The smooth re-plan with the stitched control as its record, if ``smoothed``;
        otherwise the stitched control and its certified replay sampled at ``k·N`` steps
        (``N``: the hops' finest grid).
    """
    mech, T, cert = problem.mechanism, problem.T, steered.certificate
    hops = steered.hops
    history = [{**rec, "hop": i} for i, h in enumerate(hops) for rec in h.history]
    provider = paths_for(mech)
    through = provider.through()
    route = f"the global route: {len(hops)} hops through {through}, stitched (the local planner: {local_reason})"
    if steered.two_legs:
        route = ("the global route: two legs through an intermediate orientation (a roadmap node; no "
                 f"path's hops were certified), stitched (the local planner: {local_reason})")
    if smoothed is not None:
        outcome, endpoint = smoothed
        res = build_local_result(problem, outcome, True, outcome.reason, endpoint)
        uncertified = "" if steered.controls is not None else f" ({steered.reason})"
        return replace(res, route="global", stitched=steered.controls or steered.draft,
                       history=history + [{**rec, "hop": None} for rec in res.history],
                       iterations=sum(h.iterations for h in hops) + res.iterations,
                       reason=f"reached by {route}, then re-planned as one smooth control from the "
                              f"stitched one{uncertified}: {res.reason}")
    steps = len(hops) * max(h.steps for h in hops)
    par = steered.controls
    n = steps + 1
    t = np.arange(n) * (T / steps)
    t[-1] = T
    R = cert.R[::cert.replay_steps // steps]
    q = cert.q[::cert.replay_steps // steps]
    unit = provider.unit
    reason = (f"reached by {route}; certified: the physical replay ({cert.replay_steps} steps) ends "
              f"{cert.terminal_error:.2g}{unit} from the goal, error bound {cert.error_bound:.2g}{unit}")
    return PlanResult(
        success=True, reason=reason, terminal_error=cert.terminal_error, min_delta=cert.min_delta,
        iterations=sum(h.iterations for h in hops), history=history,
        t=t, R=R, u=par(t).reshape(n, mech.n_inputs), delta=mech.delta_samples(R, q),
        parametrisation=par, mechanism=mech.name, kinematics=mech, method=problem.method,
        strategy=problem.strategy, T=T, start=problem.start, goal=problem.goal, steps=steps,
        seconds=None,
        options=problem.recorded_options(),
        sensitivity=cert.sensitivity, error_bound=cert.error_bound, replay_steps=cert.replay_steps,
        route="global",
        q=q, errors=part_errors(mech, cert.errors))
