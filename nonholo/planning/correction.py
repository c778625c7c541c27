"""Certifying a converged plan (:mod:`nonholo.certify.certificate`) and correcting it until the certificate holds.

A plan converged on the planner's grid ends within ``tol`` of the goal *on that grid*; its
physical controls, replayed accurately, may end a discretisation error away (for strategy
``"robust"`` the grid is that of the frame system, and the physical inputs ``u = W(R) w``
follow the planner's nodes). When the certified replay is accurate and well conditioned
but misses the goal by more than ``tol`` allows, :func:`certify` corrects the control with
the planner's own Jacobian: ``λ ← λ − J^# l_T`` with ``l_T`` the *replay's* terminal
error — a Newton step on the replayed endpoint map, whose derivative differs from the
planner's ``J`` by the relative discretisation error, so each correction shrinks the
error by about that factor. At most :data:`MAX_CORRECTIONS`; one that does not halve the
replay's error ends the corrections. Corrections that end uncertified are dropped: a
failed certificate is that of the controls the failed plan holds.
"""
from __future__ import annotations

from dataclasses import replace

from ..certify import certificate as replay_certificate
from ..certify.certificate import Certificate
from ..motion.frame_controls import FrameControls
from ..numerics import kernels
from .core import Options, Outcome, step_scale
from .endpoint_map import Evaluation, EndpointMap

#: Newton corrections on the replayed endpoint at most.
MAX_CORRECTIONS = 4


def physical(endpoint: EndpointMap, ev: Evaluation):
    """The physical inputs of an evaluation's control.

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint.
    ev : Evaluation
        The evaluation.

    Returns
    -------
    Controls
        The control itself, or for a plan in frame coordinates the
        :class:`~nonholo.motion.frame_controls.FrameControls` along ``ev``'s nodes.
    """
    if not endpoint.frame:
        return ev.controls
    return FrameControls(ev.controls, endpoint.start.R, endpoint.mechanism, endpoint.steps, nodes=ev.R)


def certify(endpoint: EndpointMap, ev: Evaluation, options: Options) -> tuple[Evaluation, Certificate, int]:
    """The certificate of a converged plan, after corrections where they help (see the module).

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint.
    ev : Evaluation
        The converged (complete) evaluation.
    options : Options
        The run's settings (``tol``, ``delta_min``).

    Returns
    -------
    evaluation : Evaluation
        The evaluation the certificate belongs to: the corrected one if it passed, else
        ``ev`` (a failure describes the controls it leaves, never an uncertified correction).
    certificate : Certificate
        Its certificate.
    corrections : int
        The corrections made (0 for a failure).
    """
    mech = endpoint.mechanism

    def measure(ev: Evaluation, steps: int, G=None) -> Certificate:
        # planned in the physical inputs: the planner's trajectory is the replay on steps/2
        half = None
        if not endpoint.frame and steps == 2 * endpoint.steps:
            half = (ev.R[-1], ev.q[-1])
        return replay_certificate.measure(endpoint.start, endpoint.goal, endpoint.T, mech, physical(endpoint, ev),
                                          steps, options.tol, options.delta_min, endpoint.sign, G, half,
                                          limits=endpoint.limits)

    # the first replays: on N and 2N steps (N: the planner's) when the planner's trajectory
    # is the replay on N, else on N/2 and N where the controls allow it
    N = endpoint.steps
    grid = getattr(ev.parametrisation, "grid", None)
    halves = N % 2 == 0 and (grid is None or (N // 2) % grid == 0)
    first = N if endpoint.frame and halves else 2 * N
    given = ev, measure(ev, first)
    cert = given[1]
    G = cert.sensitivity
    corrections = 0
    while not cert.passed and cert.correctable and corrections < MAX_CORRECTIONS:
        d = kernels.min_norm_step(ev.J, cert.l, step_scale(endpoint, ev.parametrisation))
        trial = endpoint.evaluate(ev.params - d)
        if not endpoint.admissible(trial):
            break
        trial_cert = measure(trial, cert.replay_steps, G)
        if not trial_cert.terminal_error < 0.5 * cert.terminal_error:
            break
        ev, cert = trial, trial_cert
        corrections += 1
    if not cert.passed:
        # corrections that did not certify are dropped: the evaluation returned is the one
        # given, and the certificate (its reason) is of that evaluation's controls
        return given[0], given[1], 0
    return ev, cert, corrections


def certified(outcome: Outcome, endpoint: EndpointMap, options: Options) -> Outcome:
    """A success without a certificate, certified.

    Parameters
    ----------
    outcome : Outcome
        The success.
    endpoint : EndpointMap
        The endpoint, unless the outcome names its own.
    options : Options
        The run's settings.

    Returns
    -------
    Outcome
        With its certificate and the evaluation it belongs to, or turned into a failure
        whose reason says why.
    """
    prob = outcome.endpoint if outcome.endpoint is not None else endpoint
    ev, cert, corrections = certify(prob, outcome.evaluation, options)
    if not cert.passed:
        return replace(outcome, success=False,
                       reason=f"{outcome.reason} on the planner's grid, but not certified: {cert.reason}")
    return replace(outcome, evaluation=ev, certificate=cert, reason=outcome.reason + note(cert, corrections, prob.mechanism.space))


def note(cert: Certificate, corrections: int, space) -> str:
    """What a success's reason says of its certificate.

    Parameters
    ----------
    cert : Certificate
        The certificate.
    corrections : int
        The corrections made.
    space : Product
        The mechanism's state space (:class:`~nonholo.spaces.product.Product`), whose units
        the errors are given in.

    Returns
    -------
    str
        The text appended to the reason.
    """
    fixed = f" after {corrections} correction{'s' * (corrections > 1)}" if corrections else ""
    return (f"; certified{fixed}: the physical replay ({cert.replay_steps} steps) ends "
            f"{space.amount(cert.terminal_error)} from the goal, error bound {space.amount(cert.error_bound)}")
