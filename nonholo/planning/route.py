"""The global route: a goal the local planner cannot reach, reached hop by hop along a path
of orientations through the start's component.

:func:`steer` takes the path of :func:`nonholo.planning.roadmap.orientation_path` (hops of at most
:data:`nonholo.planning.roadmap.MAX_HOP` rad, clear of ``Δ = 0``; the paths and the size of the
hops: :mod:`nonholo.planning.route_paths`) and plans each hop with the local planner
(``local(R_start, R_goal, T, delta_min)``: :func:`nonholo.plan` with the run's strategy
(:func:`hop_strategy`) and options, route ``"local"``, ``delta_min`` of
:func:`~nonholo.planning.route_paths.hop_delta_min`), from where the previous hop's certified
replay ended, so that no hop's error carries into the next. A hop that fails, or whose
sensitivity exceeds :data:`~nonholo.planning.route_paths.MAX_HOP_SENSITIVITY`, is split at
its geodesic midpoint (down to :data:`MIN_HOP` rad, at most :data:`MAX_PIECES` pieces in
all). The hops' physical controls are stitched into one control on ``[0, T]``, an equal
time share each
(:class:`~nonholo.controls.stitched.Stitched`); the stitched control is then certified as a whole
(:func:`nonholo.certify.certificate.measure`). Where that replay misses the goal
by more than ``tol`` allows, the last hop is planned again from where the stitched replay
enters it.

Smoothing (:mod:`nonholo.planning.route_smoothing`). The stitched control jumps where one hop
hands over to the next: the route's motion is then re-planned as one smooth control, with
the stitched control as the initial guess; a stitched control that is not certified is
smoothed the same way before the next path is tried.

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
(within :data:`nonholo.planning.route_paths.TIME_BUDGET`).
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import Callable

import numpy as np

from ..certify import certificate as certify
from ..certify.certificate import Certificate
from ..controls.stitched import Stitched
from ..io.result import PlanResult
from ..model.mechanism import Mechanism
from ..numerics import effort
from ..spaces.state import State
from . import roadmap, route_paths

#: The shortest hop a failed hop is split into (rad).
MIN_HOP = 0.02
#: Pieces of a stitched control at most.
MAX_PIECES = 64
#: Re-plans of the last hop from the stitched replay at most.
MAX_REPAIRS = 2
#: The stitched control's certified replay is at most this many times finer than its hops'.
STITCHED_REFINEMENT = 8
#: Intermediate orientations the route's last stage tries at most (:func:`steer`):
#: roadmap nodes in their random sampling order (:func:`nonholo.planning.roadmap.via_nodes`).
VIA_CANDIDATES = 64
#: Seconds of effort the last stage may take beyond
#: :data:`nonholo.planning.route_paths.TIME_BUDGET`.
VIA_TIME = 0.75
#: Initial guesses a leg of the last stage tries (:func:`quick_strategy`): a leg that the
#: first ones do not solve is skipped for the next candidate, which is cheaper than
#: insisting.
VIA_ATTEMPTS = 2


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
        The route re-planned as one smooth control
        (:func:`~nonholo.planning.route_smoothing.smooth`), when ``steer`` was given a
        ``rescue`` that succeeded on the ``draft``.
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
    #: the route re-planned as one smooth control
    #: (:func:`~nonholo.planning.route_smoothing.smooth`), when ``steer`` was given a
    #: ``rescue`` that succeeded on the ``draft``
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


@lru_cache(maxsize=8)
def hop_strategy(cls: type, limit: float = route_paths.MAX_HOP_SENSITIVITY) -> type:
    """A strategy for hops: the strategy class ``cls`` with a sensitivity ``limit``.

    Parameters
    ----------
    limit : float, default MAX_HOP_SENSITIVITY
        The largest sensitivity of a hop
        (:func:`~nonholo.planning.route_paths.max_hop_sensitivity`).

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
        Seconds of effort (default :data:`~nonholo.planning.route_paths.TIME_BUDGET`) after
        ``started`` after which no further hop is tried.
    started : float, optional
        An :func:`nonholo.numerics.effort.seconds` reading (default: now).
    leg_limits : LegLimits or None, optional
        Stroke limits (:class:`~nonholo.model.limits.LegLimits`) the path of orientations and
        the stitched replay keep (``local`` keeps them in each hop).
    rescue : callable, optional
        ``rescue(draft, seconds)``: called when a path's hops all succeed but their stitched
        control is not certified (``seconds``: what its certification took); a smooth
        re-plan from it (:func:`~nonholo.planning.route_smoothing.smooth`: an
        ``(outcome, problem)``, or ``None``) ends the
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
        budget = route_paths.TIME_BUDGET
    steered, tried = None, []
    provider = route_paths.paths_for(mechanism)
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
    provider = route_paths.paths_for(mechanism)
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
        res = local(here, targets[0], T_hop, route_paths.hop_delta_min(mechanism, here, targets[0], delta_min))
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
        res = local(entry, goal, hops[-1].T, route_paths.hop_delta_min(mechanism, entry, goal, delta_min))
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
