"""A least-energy grid motion made smooth, for ``objective="auto"``.

Grid controls jump at every interval, which a physical mechanism cannot follow. The motion
the quick search finds is fitted by a Fourier series, brought onto the goal and lowered in
its coefficients (:func:`smoothed`, :func:`smooth_run`); where that fit cannot be brought
onto the goal, the plan's own fit is lowered instead. The fits keep most of the plan's
clearance from ``Δ = 0`` (:func:`smooth_clearance`).
"""
from __future__ import annotations

import math
from dataclasses import replace

from ..controls.parametrisations import Controls, Fourier
from ..io.result import PlanResult
from .core import Options, Outcome, record
from .endpoint_map import EndpointMap
from .energy_objective import energy, plan_energy_of
from .energy_optimiser import RESTORE_STEPS, Run, descend, newton_steps, polish
from .energy_search import certified_or_finer

#: ``objective="auto"``: the fraction of the plan's clearance from ``Δ = 0`` above
#: ``delta_min`` the motion that replaces it keeps (:func:`smooth_clearance`).
KEEP_CLEARANCE = 0.9
#: ``objective="auto"``: harmonics of the smooth motion that replaces a plan (:func:`smoothed`).
SMOOTH_HARMONICS = 16
#: ``objective="auto"``: SQP iterations of the smooth motion's energy at most.
SMOOTH_ITERATIONS = 12
#: ``objective="auto"``: ... and of the smooth motion from the plan's fit, where the least
#: energy's fit does not reach the goal ...
SMOOTH_PLAN_ITERATIONS = 40
#: ... which replaces the plan where it needs less than this fraction of its energy.
REFIT_BELOW = 0.9


def smooth_clearance(result: PlanResult | None) -> float | None:
    """The clearance from ``Δ = 0`` the motions that may replace ``result`` keep
    (``objective="auto"``): :data:`KEEP_CLEARANCE` of the plan's own above ``delta_min``. A
    motion closer to ``Δ = 0`` may need less energy, but it is more sensitive to whatever
    a mechanism does not follow exactly (``|ω| ~ 1/|Δ|``), and the default returns motions
    to execute.

    Parameters
    ----------
    result : PlanResult or None
        The certified plan.

    Returns
    -------
    float or None
        The clearance (``None`` without a plan or for a mechanism without a singular set).
    """
    if result is None or result.min_delta is None:
        return None
    delta_min = result.options["delta_min"]
    return delta_min + KEEP_CLEARANCE * max(result.min_delta - delta_min, 0.0)


def smoothed(problem, outcome: Outcome, ceiling: float, plan: PlanResult | None = None):
    """The least-energy grid motion of ``outcome`` made smooth: its Fourier fit of
    :data:`SMOOTH_HARMONICS` harmonics, Newton steps of least energy toward the goal, at
    most :data:`SMOOTH_ITERATIONS` SQP iterations in its coefficients (they bring it onto
    the goal where the Newton steps could not, and lower its energy), Newton steps again,
    certified (:func:`smooth_run`). Grid controls jump at every interval, which a physical
    mechanism cannot follow; the fit of a smooth extremal needs hardly more energy. Where
    the fit of a motion that rides a limit cannot be brought onto the goal (or not below
    ``ceiling``), the same iteration runs from the fit of the certified ``plan``, which
    reaches it, for up to :data:`SMOOTH_PLAN_ITERATIONS` iterations: it descends to a smooth
    critical point near the plan, which replaces the plan where it needs less than
    :data:`REFIT_BELOW` of its energy.

    Parameters
    ----------
    problem : Problem
        The run's endpoint.
    outcome : Outcome
        The certified grid motion.
    ceiling : float
        The energy the smooth fit of ``outcome`` must stay below (that from the plan: the
        plan's).
    plan : PlanResult, optional
        The certified plan: the smooth motion keeps its clearance from ``Δ = 0``
        (:func:`smooth_clearance`) and is integrated on at least its steps.

    Returns
    -------
    problem : Problem
        The smooth motion's endpoint (method ``"parametric"``).
    endpoint : EndpointMap
        Its evaluator.
    outcome : Outcome or None
        The certified smooth motion, or ``None`` if it does not end at the goal below
        ``ceiling`` or fails its certificate.
    why : str
        Why there is none (empty if there is).
    """
    K = SMOOTH_HARMONICS
    steps = max(problem.steps, 4 * K, 0 if plan is None else plan.steps)
    smooth = problem.with_settings(method="parametric", harmonics=K, steps=steps)
    endpoint = smooth.evaluator(method="parametric", steps=steps, delta_min=smooth_clearance(plan))
    found, why = smooth_run(endpoint, "the motion's fit", outcome.evaluation.controls, SMOOTH_ITERATIONS, ceiling,
                            problem.options)
    if found is None and plan is not None:
        found, why_plan = smooth_run(endpoint, "the plan's fit", plan.parametrisation, SMOOTH_PLAN_ITERATIONS,
                                     REFIT_BELOW * plan_energy_of(plan), problem.options)
        why = "" if found is not None else f"{why}; {why_plan}"
    if found is None:
        return smooth, endpoint, None, why
    endpoint = found.endpoint
    found = replace(found, reason=f"{outcome.reason}; made smooth: {found.reason}",
                    history=outcome.history + found.history, iterations=outcome.iterations + found.iterations)
    return smooth.with_settings(steps=endpoint.steps), endpoint, found, ""


def smooth_run(endpoint: EndpointMap, label: str, controls: Controls, iterations: int, ceiling: float,
               options: Options) -> tuple[Outcome | None, str]:
    """The Fourier fit of ``controls`` in ``endpoint``'s harmonics, Newton steps of least
    energy toward the goal, at most ``iterations`` SQP iterations, Newton steps again,
    certified — on twice the integrator steps where the certificate finds the planner's
    grid too coarse for the motion.

    Parameters
    ----------
    endpoint : EndpointMap
        The smooth endpoint (method ``"parametric"``).
    label : str
        What is fitted (for the reasons).
    controls : Controls
        The physical controls fitted.
    iterations : int
        SQP iterations at most.
    ceiling : float
        The energy the motion must stay below.
    options : Options
        The run's settings.

    Returns
    -------
    outcome : Outcome or None
        The certified smooth motion (its ``endpoint`` the evaluator it was certified on),
        or ``None``.
    why : str
        Why there is none (empty if there is).
    """
    K = SMOOTH_HARMONICS
    fit = Fourier.fit(controls, endpoint.T, K, endpoint.mechanism.n_inputs)
    ev = endpoint.evaluate(fit)
    if not endpoint.admissible(ev):
        return None, f"{label} of {K} harmonics is not admissible"
    metric = fit.metric()
    ev = newton_steps(endpoint, ev, metric, options.tol, RESTORE_STEPS + 2)
    E = energy(ev, metric)
    run = Run(label, ev, E, history=[record(0, ev, 0.0, "energy", 0, energy=E, start=label)])
    descend(endpoint, run, options, iterations, math.inf)
    polish(endpoint, run, options)
    if run.evaluation.error > options.tol:
        return None, (f"{label} of {K} harmonics ended {run.evaluation.error:.2g} from the goal "
                      f"after {len(run.history) - 1} iterations")
    if run.energy >= ceiling:
        return None, f"{label} of {K} harmonics needs {run.energy:.6g}, not below {ceiling:.6g}"
    found = Outcome(evaluation=run.evaluation, success=True,
                    reason=f"{label} of {K} harmonics, energy {run.energy:.6g}",
                    history=run.history, iterations=len(run.history) - 1, endpoint=endpoint)
    certificate = certified_or_finer(found, endpoint, options, ceiling)
    return (certificate, "") if certificate.success else (None, certificate.reason)
