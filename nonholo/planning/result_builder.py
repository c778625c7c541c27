"""The :class:`~nonholo.io.result.PlanResult` of a run, assembled from what the planner made:
a local run's outcome (:func:`build_result`; a success's samples are those of its
certified replay) or a certified global route (:func:`build_route_result`: its stitched
control, or the smooth re-plan of it, with the hops' histories one after another).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..io.result import PlanResult, part_errors
from ..motion.frame_controls import FrameControls
from .core import Outcome
from .endpoint_map import EndpointMap
from .route import Steered
from .route_paths import paths_for


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
        t=t, R=R, u=par(t).reshape(n, mech.n_inputs) if u is None else u, delta=mech.singular.samples(R, q),
        parametrisation=par, mechanism=mech.name, kinematics=mech, method=problem.method,
        strategy=problem.strategy, T=T, start=problem.start, goal=problem.goal, steps=n_steps,
        seconds=None,
        options=problem.recorded_options(),
        sensitivity=None if outcome is None or outcome.certificate is None else outcome.certificate.sensitivity,
        error_bound=None if cert is None else cert.error_bound,
        replay_steps=None if cert is None else cert.replay_steps,
        q=q, errors=part_errors(mech, errors))


def build_route_result(problem, steered: Steered, local_reason: str,
                       smoothed: tuple[Outcome, EndpointMap] | None = None) -> PlanResult:
    """The :class:`~nonholo.io.result.PlanResult` of a certified global route.

    Its history: the hops' histories one after another (each record tagged with its
    ``hop``), then, if the route was ``smoothed``
    (:func:`~nonholo.planning.route_smoothing.smooth`), the smooth re-plan's
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
        res = build_result(problem, outcome, True, outcome.reason, endpoint)
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
        t=t, R=R, u=par(t).reshape(n, mech.n_inputs), delta=mech.singular.samples(R, q),
        parametrisation=par, mechanism=mech.name, kinematics=mech, method=problem.method,
        strategy=problem.strategy, T=T, start=problem.start, goal=problem.goal, steps=steps,
        seconds=None,
        options=problem.recorded_options(),
        sensitivity=cert.sensitivity, error_bound=cert.error_bound, replay_steps=cert.replay_steps,
        route="global",
        q=q, errors=part_errors(mech, cert.errors))
