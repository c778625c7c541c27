"""The global route's motion re-planned as one smooth control (:mod:`nonholo.planning.route`).

The stitched control jumps where one hop hands over to the next. Once it is certified,
:func:`smooth` re-plans the whole motion as one control of the run's parametrisation,
with the stitched control as the initial guess: its planned coordinates
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
"""
from __future__ import annotations

from functools import lru_cache

from ..controls.parametrisations import Fourier, PiecewiseConstant
from ..controls.stitched import Stitched
from ..numerics import effort
from .core import Outcome, Start
from .correction import certified
from .endpoint_map import EndpointMap

#: Harmonics of the smooth re-plan of a stitched control (method ``"parametric"``), tried
#: in turn: the guess must follow the hops' controls, which jump at the hand-overs, well
#: enough to stay in the route's corridor (fewer harmonics leave it more often than not).
SMOOTHING_HARMONICS = (16, 32)
#: Seconds of effort the smoothing may take (within
#: :data:`nonholo.planning.route_paths.TIME_BUDGET`): most routes smooth in a fraction of
#: this; the rest keep their stitched control.
SMOOTHING_TIME = 0.5


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
