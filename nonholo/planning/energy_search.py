"""The multistart search for the least energy: runs of the optimiser from several starts.

An iteration of the optimiser (:mod:`nonholo.planning.energy_optimiser`) finds *a* critical
point near its start; the least one is looked for from several starts (:func:`starts`): the
certified plan's inputs, then the drift toward the goal plus loops of a few sizes and
frequency ratios in either sense (the motions that reach the bracket directions at the
least cost), then seeded random Fourier inputs, each projected on :data:`ENERGY_GRID`
equal intervals (:func:`begin`). Each start is iterated :data:`PROBE_ITERATIONS` times, or
fewer where it heads for far more energy than a run finished at the goal (:func:`probe`),
then the run heading for the least energy is continued, round by round, while it heads
for not much more than the best finished one (:data:`CONTINUE_WITHIN`; while none has
finished, one round after each start) and has not joined a run finished above it
(:data:`JOIN_DISTANCE`); no further start is taken once :data:`CONFIRMATIONS` finished
runs agree on the least energy (:func:`confirmed`; :func:`search`). The least-energy run at
the goal that is certified (:mod:`nonholo.planning.correction`,
:func:`certified_or_finer`) is the result. The search is budgeted in effort
(:mod:`nonholo.numerics.effort`), not in wall time.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..controls.parametrisations import Controls, Fourier, PiecewiseConstant
from ..motion.frame_controls import FrameControls
from ..numerics import effort
from .correction import certified
from .core import Options, Outcome, record
from .endpoint_map import EndpointMap
from .energy_objective import energy
from .energy_optimiser import POLISH_BELOW, Run, descend, least_energy_step, onto, polish
from .strategy_robust import frame_coordinates

#: Intervals of the piecewise-constant controls the energy is lowered over (the plan's
#: integrator steps are rounded up to a multiple of it).
ENERGY_GRID = 100

# -- the starts (:func:`loop_starts`)
#: Loop sizes of the starts, relative to the loop that encloses the goal's offset.
LOOP_SCALES = (1.0, 0.5, 2.0)
#: Frequencies (in ``2π/T``) of the first two inputs of the loops of the starts.
LOOP_FREQUENCIES = ((1, 1), (1, 2), (2, 1))
#: Seeded random Fourier starts after the deterministic ones.
RANDOM_STARTS = 4
RANDOM_SEED = 20240226

# -- the runs: probed, continued, given up (:func:`probe`, :func:`continue_near_best`)
#: SQP iterations of one start at most.
MAX_ITERATIONS = 80
#: SQP iterations of every start before any is continued, and of each round after.
PROBE_ITERATIONS = 12
#: ... in stages of this many (:func:`probe`), ...
PROBE_STAGE = 4
#: ... the probe ending once the run heads for more than this many times the least energy
#: of a run finished at the goal.
GIVE_UP_ABOVE = 2.0
#: A run whose controls come this close (relative, :func:`distance`) to those of a run
#: finished at the goal above the least energy is given up: it is heading for the same
#: critical point.
JOIN_DISTANCE = 0.05
#: Runs are continued while the one heading for the least energy heads below this many
#: times the least energy of a run finished at the goal (a run's heading after its probe
#: is a rough guess: one heading somewhat above the best may end below it).
CONTINUE_WITHIN = 1.15

# -- when the search stops, and what it certifies (:func:`confirmed`, :func:`search`)
#: The search starts no further run once this many runs finished at the goal agree on the
#: least energy of any (:func:`confirmed`) ...
CONFIRMATIONS = 2
#: ... within this relative difference.
AGREE_RTOL = 1e-5
#: Runs at the goal polished and certified at most, the cheapest first.
FINALISTS = 3
#: A probe is near the goal when its terminal error is below this (in the error's units).
NEAR_GOAL = 1e-3


def begin(endpoint: EndpointMap, label: str, controls: Controls, options: Options) -> Run | None:
    """A run from physical controls projected on the grid.

    A projection that ends near the goal (a plan's) is first brought onto it
    (:func:`~nonholo.planning.energy_optimiser.polish`): the iteration then lowers the energy
    of motions that reach the goal instead of trading the goal for energy.

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint (grid controls).
    label : str
        The start's label.
    controls : Controls
        The physical controls.
    options : Options
        The run's settings.

    Returns
    -------
    Run or None
        The run, or ``None`` where the projection's motion is not admissible.
    """
    grid = PiecewiseConstant.fit(controls, endpoint.T, ENERGY_GRID, endpoint.mechanism.n_inputs)
    ev = endpoint.evaluate(grid)
    if not endpoint.admissible(ev):
        return None
    E = energy(ev, grid.metric())
    run = Run(label, ev, E, history=[record(0, ev, 0.0, "energy", 0, energy=E, start=label)])
    if ev.error <= POLISH_BELOW:
        polish(endpoint, run, options)
    return run


def estimate(run: Run) -> float:
    """The energy a run is heading for.

    Parameters
    ----------
    run : Run
        The run.

    Returns
    -------
    float
        Its parameters' energy after a Newton step to the goal (its energy itself when at
        the goal).
    """
    ev = run.evaluation
    metric = ev.parametrisation.metric()
    return float(np.dot(metric, (ev.params + least_energy_step(ev, metric)) ** 2))


def loop_starts(endpoint: EndpointMap):
    """Labelled physical initial controls of the search: the drift ``ū = G(x₀)^# δ/T``
    toward the goal (``δ`` the offset of the goal from the start, a least-squares fit of
    the field at the start) plus loops ``u_i = A sin(k_i ωt ± iπ/2)`` (``ω = 2π/T``) of
    the frequencies :data:`LOOP_FREQUENCIES` (equal ones reach the first brackets, a 1:2
    pair the second), in either sense, of the sizes :data:`LOOP_SCALES` times the one whose
    enclosed area matches ``|δ|``; then :data:`RANDOM_STARTS` seeded random Fourier inputs
    of that size around the drift. For a mechanism on SO(3) with a desingularised frame
    these are the frame coordinates ``w`` (``G = N``), played as the physical inputs
    ``u = W(R) w`` along their motion (:class:`~nonholo.motion.frame_controls.FrameControls`):
    loops of ``u`` itself would run into ``Δ = 0``, where ``L`` blows up.

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint.

    Yields
    ------
    label : str
        The start's label.
    controls : Controls
        Its physical controls.
    """
    mech, T = endpoint.mechanism, endpoint.T
    m = mech.n_inputs
    in_frame = frame_coordinates(mech)
    offset = mech.space.offset(endpoint.start, endpoint.goal)
    field = mech.frame.N(endpoint.start.R) if in_frame else mech.G(*endpoint.start)
    drift = np.linalg.lstsq(field, offset, rcond=None)[0] / T
    omega = 2.0 * np.pi / T
    size = omega * np.sqrt(max(float(np.linalg.norm(offset)), 1e-2) / np.pi)

    def physical(w: Fourier) -> Controls:
        return FrameControls(w, endpoint.start.R, mech, endpoint.steps) if in_frame else w

    for scale in LOOP_SCALES:
        for pair in LOOP_FREQUENCIES:
            k = np.resize(np.asarray(pair, dtype=float), m)
            for sense in (1.0, -1.0):
                shift = 0.5 * np.pi * sense * np.arange(m)

                def loop(t, A=scale * size, k=k, shift=shift):
                    t = np.asarray(t, dtype=float)
                    return drift + A * np.sin(omega * k * t[..., None] + shift)

                label = f"loop {scale:g} {pair[0]}:{pair[1]}{'+' if sense > 0 else '-'}"
                yield label, physical(Fourier.fit(loop, T, int(max(pair)), m))
    rng = np.random.default_rng(RANDOM_SEED)
    for j in range(RANDOM_STARTS):
        K = 1 + j % 3
        c = rng.standard_normal((m, 2 * K + 1))
        c *= size / np.sqrt(np.sum(c[:, 0] ** 2) + 0.5 * np.sum(c[:, 1:] ** 2))
        c[:, 0] += drift
        yield f"random {j + 1}", physical(Fourier(T, c))


def starts(endpoint: EndpointMap, plan: Controls | None):
    """The starts of the search: the certified plan's physical inputs, then :func:`loop_starts`.

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint.
    plan : Controls or None
        The plan's physical controls, if any.

    Yields
    ------
    label : str
        The start's label.
    controls : Controls
        Its physical controls.
    """
    if plan is not None:
        yield "plan", plan
    yield from loop_starts(endpoint)


def finished_at_goal(run: Run, options: Options) -> bool:
    """Whether a run has finished (converged, or can make no further step) at the goal.

    Parameters
    ----------
    run : Run
        The run.
    options : Options
        The run's settings (``tol``).

    Returns
    -------
    bool
        Whether it has.
    """
    return (run.converged or run.stuck) and run.evaluation.error <= options.tol


def confirmed(runs: list[Run], options: Options) -> bool:
    """Whether :data:`CONFIRMATIONS` runs finished at the goal (converged, or no further
    step) agree (within :data:`AGREE_RTOL`) on the least energy of any: starts from
    different motions that end at the same critical point, the least found, make a lower
    one unlikely.

    Parameters
    ----------
    runs : list of Run
        The runs.
    options : Options
        The run's settings (``tol``).

    Returns
    -------
    bool
        Whether the search may stop starting runs.
    """
    found = sorted(r.energy for r in runs if finished_at_goal(r, options))
    return bool(found) and sum(e <= found[0] * (1.0 + AGREE_RTOL) for e in found) >= CONFIRMATIONS


def distance(run: Run, other: Run) -> float:
    """The distance of two runs' controls relative to the second's, ``|λ − λ'|_M / |λ'|_M``.

    Parameters
    ----------
    run, other : Run
        The runs (on the same grid).

    Returns
    -------
    float
        The distance.
    """
    metric = other.evaluation.parametrisation.metric()
    gap = float(np.dot(metric, (run.evaluation.params - other.evaluation.params) ** 2))
    return math.sqrt(gap / max(other.energy, 1e-300))


def probe(endpoint: EndpointMap, run: Run, runs: list[Run], options: Options, deadline: float) -> Run:
    """A new run's first :data:`PROBE_ITERATIONS` iterations, in stages of
    :data:`PROBE_STAGE`, ended once it heads (:func:`estimate`) above
    :data:`GIVE_UP_ABOVE` times the least energy of a run finished at the goal.

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint (grid controls).
    run : Run
        The new run, updated.
    runs : list of Run
        The runs before it.
    options : Options
        The run's settings.
    deadline : float
        An :func:`nonholo.numerics.effort.seconds` reading.

    Returns
    -------
    Run
        ``run``.
    """
    best = min((r.energy for r in runs if finished_at_goal(r, options)), default=math.inf)
    done = 0
    while done < PROBE_ITERATIONS and not (run.converged or run.stuck) and effort.seconds() <= deadline:
        descend(endpoint, run, options, min(PROBE_STAGE, PROBE_ITERATIONS - done), deadline)
        done += PROBE_STAGE
        if estimate(run) > GIVE_UP_ABOVE * best:
            break
    return run


def continue_near_best(endpoint: EndpointMap, runs: list[Run], options: Options, deadline: float,
                       unfinished: float = 0) -> None:
    """Continue, in rounds of :data:`PROBE_ITERATIONS`, the open run heading for the least
    energy (:func:`estimate`) while it heads below :data:`CONTINUE_WITHIN` times every run
    finished at the goal (while none is, for ``unfinished`` rounds) and the budget lasts.
    A run that comes within :data:`JOIN_DISTANCE` of one finished above the least energy
    (:func:`distance`) is not continued: it is heading for the same critical point.

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint (grid controls).
    runs : list of Run
        The runs, updated.
    options : Options
        The run's settings.
    deadline : float
        An :func:`nonholo.numerics.effort.seconds` reading.
    unfinished : float, default 0
        Rounds to continue while no run has finished at the goal (``math.inf``: until one
        has, or none is open).
    """
    while effort.seconds() <= deadline:
        open_runs = [r for r in runs if not (r.converged or r.stuck or r.joined)
                     and len(r.history) <= MAX_ITERATIONS]
        if not open_runs:
            return
        heading = [estimate(r) for r in open_runs]
        k = int(np.argmin(heading))
        finished = [r for r in runs if r.evaluation.error <= options.tol and r not in open_runs]
        if finished:
            least = min(r.energy for r in finished)
            join = next((r for r in finished if r.energy > least * (1.0 + AGREE_RTOL)
                         and distance(open_runs[k], r) <= JOIN_DISTANCE), None)
            if join is not None:
                open_runs[k].joined = join.label
                continue
        if (not finished and unfinished <= 0) or (finished and heading[k] >= CONTINUE_WITHIN * least):
            return
        if not finished:
            unfinished -= 1
        descend(endpoint, open_runs[k], options, PROBE_ITERATIONS, deadline)


def search(endpoint: EndpointMap, initial, options: Options, budget: float,
           ceiling: float = math.inf, final: EndpointMap | None = None) -> tuple[Outcome | None, str]:
    """The least-energy certified control of ``endpoint`` from the labelled physical
    controls ``initial`` (see the module) within ``budget`` seconds of effort, if its
    energy is below ``ceiling``: ``(outcome, "")``, or ``(None, why)``.

    The starts are taken in turn: each is probed (:func:`probe`), then the runs heading
    near the best finished one are continued (:func:`continue_near_best`; while none has
    finished, the one heading lowest for a round), until the runs agree on the least
    energy (:func:`confirmed`) or the starts run out; then the open runs are continued so
    once more, whether or not one has finished. The runs at the goal (after
    :func:`~nonholo.planning.energy_optimiser.polish`), cheapest first, are certified until
    one is.

    Parameters
    ----------
    endpoint : EndpointMap
        The endpoint (grid controls).
    initial : iterable of tuple
        Labelled physical controls ``(label, controls)``.
    options : Options
        The run's settings.
    budget : float
        Seconds of effort.
    ceiling : float, default inf
        The energy to beat.
    final : EndpointMap, optional
        The endpoint on the steps to certify on, if not ``endpoint``'s: each finalist is
        brought onto the goal there by Newton steps first.

    Returns
    -------
    outcome : Outcome or None
        The certified least-energy outcome, or ``None``.
    why : str
        Why there is none (empty if there is).
    """
    deadline = effort.seconds() + budget
    runs, skipped = [], 0
    for label, controls in initial:
        if effort.seconds() > deadline:
            break
        run = begin(endpoint, label, controls, options)
        if run is None:
            skipped += 1
            continue
        runs.append(probe(endpoint, run, runs, options, deadline))
        continue_near_best(endpoint, runs, options, deadline, unfinished=1)
        if confirmed(runs, options):
            break
    continue_near_best(endpoint, runs, options, deadline, unfinished=math.inf)
    near = sorted((r for r in runs if r.evaluation.error <= NEAR_GOAL), key=lambda r: r.energy)
    why = ""
    tried = f"{len(runs)} starts" + (f", {skipped} not admissible" if skipped else "")
    for run in near[:FINALISTS]:
        if run.energy >= ceiling:
            why = why or f"the least energy found, {run.energy:.6g}, is not below {ceiling:.6g}"
            break
        polish(endpoint, run, options)
        on = endpoint
        if final is not None and run.evaluation.error <= options.tol:
            ev = onto(final, run.evaluation, options.tol)
            if not final.admissible(ev):
                why = why or f"the iteration from '{run.label}' is not admissible on {final.steps} steps"
                continue
            run.evaluation, run.energy, on = ev, energy(ev, ev.parametrisation.metric()), final
        if run.evaluation.error > options.tol:
            why = why or f"the iteration from '{run.label}' ended {run.evaluation.error:.2g} from the goal"
            continue
        how = "converged" if run.converged else f"stopped after {run.history[-1]['iteration']} iterations"
        first = run.history[0]["energy"]
        outcome = Outcome(evaluation=run.evaluation, success=True,
                          reason=(f"least energy {run.energy:.6g} on {ENERGY_GRID} intervals, from the "
                                  f"start '{run.label}' (energy {first:.6g}; {how}; {tried})"),
                          history=run.history, iterations=len(run.history) - 1,
                          endpoint=on if on is not endpoint else None)
        outcome = certified_or_finer(outcome, on, options, ceiling)
        if outcome.success:
            return outcome, ""
        why = outcome.reason
    if not why:
        best = min((r.evaluation.error for r in runs), default=float("nan"))
        why = (f"no start's iteration ended within tol = {options.tol:g} of the goal on "
               f"{ENERGY_GRID} intervals ({tried}, the closest {best:.2g} from it)")
    return None, why


def certified_or_finer(found: Outcome, endpoint: EndpointMap, options: Options, ceiling: float) -> Outcome:
    """``found`` certified (:func:`~nonholo.planning.correction.certified`) — or, where
    its certificate fails, its controls on twice the integrator steps, brought back onto
    the goal there by Newton steps of least energy and certified there (its ``endpoint``
    then the finer evaluator): the motion may be faster than the planner's grid resolves,
    or so sensitive that the replay's corrections cannot close the gap between the grids.

    Parameters
    ----------
    found : Outcome
        A success at the goal on ``endpoint``'s grid.
    endpoint : EndpointMap
        Its endpoint.
    options : Options
        The run's settings.
    ceiling : float
        The energy the motion on the finer grid must stay below.

    Returns
    -------
    Outcome
        The certified motion, or the first certificate's failure.
    """
    certificate = certified(found, endpoint, options)
    if certificate.success:
        return certificate
    finer = endpoint.refined(2 * endpoint.steps)
    ev = onto(finer, found.evaluation, options.tol)
    if finer.admissible(ev) and ev.error <= options.tol and energy(ev, ev.parametrisation.metric()) < ceiling:
        again = certified(replace(found, evaluation=ev, endpoint=finer), finer, options)
        if again.success:
            return again
    return certificate
