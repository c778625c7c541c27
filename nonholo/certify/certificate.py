"""The certificate of a plan: its physical controls replayed, with a bound on the replay's error.

A planner judges its control on its own fixed-step trajectory — in the frame coordinates
``w`` for strategy ``"robust"``, on a grid chosen for the Jacobian, not for the endpoint.
What a plan promises is about the *physical* inputs it returns, ``u(t) =
result.controls(t)``, played on ``dR/dt = [L(R) u] R`` from ``R0``. :func:`measure` replays
them with CF4 on ``M/2`` and ``M`` steps (aligned with the plan's steps, so no step
straddles a breakpoint) and bounds the error of the ``M``-step endpoint by

    ``error_bound = SAFETY · |log(R_M(T) R_{M/2}(T)ᵀ)| / 15  +  G · REPLAY_PERTURBATION``

— the Richardson estimate of a fourth-order method (asymptotic: hence the safety factor),
refining ``M`` until it is below ``ERROR_FRACTION · tol`` (at most :data:`MAX_REPLAY_STEPS`;
each refinement jumps to the power-of-two multiple the estimate's fourth-order fall predicts,
:func:`refinements`, the stage table of the finer grid halved for its half),
plus what an error of :data:`REPLAY_PERTURBATION` rad anywhere along the motion (a careful
independent replay's own accuracy) becomes at ``T`` under the *sensitivity*
``G = max_t |Φ(T, t)|_F`` of the physical system along the motion (:func:`sensitivity`,
on grids refined until two agree: :func:`resolved_sensitivity`).
A plan is certified when the replay's terminal error plus that bound is at most ``tol`` and
the replay keeps ``sgnΔ ≥ delta_min`` at every point where it evaluates ``L``: then any
accurate re-simulation of the returned controls ends within ``tol`` of the goal. An
infinite ``G`` (the variational replay ran into ``Δ = 0``) or one so large that
``G · REPLAY_PERTURBATION`` alone exceeds ``SENSITIVITY_FRACTION · tol`` makes a plan
uncertifiable: its endpoint then depends on perturbations below any replay's accuracy. So
does a ``G`` that no grid up to :data:`MAX_REPLAY_STEPS` resolves.

:class:`Certificate` holds the numbers a :class:`~nonholo.io.result.PlanResult` stores
(``replay_steps``, ``terminal_error``, ``error_bound``, ``min_delta``, ``sensitivity``);
:func:`nonholo.motion.playback.replay` is the replay itself, which :meth:`~nonholo.io.result.PlanResult.validate`
repeats when a plan is loaded.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..controls import stages
from ..integrate.compiled import compiled_system
from ..model.bounds import input_names
from ..model.limits import Limits
from ..motion.playback import replay

#: Factor on the asymptotic Richardson estimate ``|R_M − R_{M/2}|/15`` of the error of ``R_M``.
SAFETY = 2.0
#: The replay is refined until its error estimate is below this fraction of ``tol``.
ERROR_FRACTION = 0.25
#: The finest replay (CF4 steps on ``[0, T]``): beyond it a plan is not certified.
MAX_REPLAY_STEPS = 204800
#: A replay's error estimate falls about this many times a doubling of its steps (CF4 is of
#: order four): the refinement jumps to the steps it predicts (:func:`refinements`).
ORDER_FACTOR = 16.0
#: Error (rad) anywhere along the motion that any replay may make — DOP853 at ``rtol =
#: 1e-13`` — and that reaches ``T`` amplified by the sensitivity ``G``.
REPLAY_PERTURBATION = 1e-13
#: A motion whose ``G · REPLAY_PERTURBATION`` exceeds this fraction of ``tol`` is too
#: ill-conditioned to certify (the rest of ``tol`` is left to the replay's own error and
#: its distance from the goal).
SENSITIVITY_FRACTION = 0.5
#: Sensitivities on grids a factor 2 apart agree (``Φ`` is resolved) when they differ by
#: at most this fraction of the larger.
SENSITIVITY_AGREEMENT = 0.25


@dataclass(frozen=True)
class Certificate:
    """The physical controls of a plan replayed (see the module).

    Errors and bounds are in the stacked metric of :mod:`nonholo.spaces.product`.

    Parameters
    ----------
    replay_steps : int
        CF4 steps ``M`` of the certified replay ``R_M``.
    terminal_error : float
        ``|log(R_M(T) R_dᵀ)|`` (rad).
    error_bound : float
        Bound on ``|R(T) − R_M(T)|`` of the exact motion (rad).
    min_delta : float or None
        Least ``sgn(Δ(R0))·Δ`` over the replay's evaluation points (``None`` without a
        singular set).
    sensitivity : float
        ``G``.
    passed : bool
        The plan is certified for the ``tol`` and ``delta_min`` it was measured against.
    reason : str
        Why not.
    correctable : bool
        Only the replay's terminal error is too large (the replay is accurate, well
        conditioned and clear of ``Δ = 0``).
    l : numpy.ndarray
        The replay's ``l_T``.
    R : numpy.ndarray
        Its nodes (``M + 1``).
    U : numpy.ndarray, optional
        Its stage table.
    q : numpy.ndarray, optional
        The nodes' coordinates (``(M + 1, k)``).
    errors : dict, optional
        The norms of the parts of ``l`` by name
        (:meth:`nonholo.spaces.product.Product.error`).
    """

    replay_steps: int
    terminal_error: float
    error_bound: float
    min_delta: float | None
    sensitivity: float
    passed: bool
    reason: str
    correctable: bool
    l: np.ndarray
    R: np.ndarray
    U: np.ndarray | None = None
    q: np.ndarray | None = None
    errors: dict | None = None

    def inputs_at(self, steps: int) -> np.ndarray:
        """The replayed inputs ``u(t_n)`` at the points ``t_n = nT/steps``, from the replay's
        stage table.

        Parameters
        ----------
        steps : int
            A divisor of ``replay_steps``.

        Returns
        -------
        numpy.ndarray
            ``steps + 1`` rows: each node's start-of-step value, the last step's end value
            at ``T``.
        """
        r = self.replay_steps // steps
        return np.concatenate([self.U[::r, 0], self.U[-1:, 2]])


def richardson(fine, coarse, mechanism) -> float:
    """The error estimate of the ``M``-step endpoint from the ``M/2``-step one.

    Parameters
    ----------
    fine, coarse : tuple of numpy.ndarray
        The endpoints, states ``(R, q)``.
    mechanism : Mechanism
        The mechanism (its space's distance).

    Returns
    -------
    float
        :data:`SAFETY` times their distance (``|log(R_fine R_coarseᵀ)|`` on SO(3), the
        stacked error's norm beyond) over 15.
    """
    return SAFETY * mechanism.space.distance(fine, coarse) / 15.0


def sensitivity(start, par, T: float, mechanism, steps: int, U=None, sign: float | None = None):
    """The sensitivity ``G = max_n |Φ(T, t_n)|_F`` of the physical system along a motion,
    on one grid.

    From the variational system of the physical inputs (as
    :func:`nonholo.motion.simulation.variational`); the nodes of ``R`` are those of
    :func:`~nonholo.motion.playback.replay` on the same steps. ``G`` is only as good as the
    grid resolves ``Φ``, which may take a finer grid than ``R_T`` does:
    :func:`resolved_sensitivity`. ``Φ`` is that of the stacked variation, ``d × d``.

    Parameters
    ----------
    start : State
        The start (:class:`~nonholo.spaces.state.State`).
    par : Controls or FrameControls
        The physical inputs.
    T : float
        The horizon (s).
    mechanism : Mechanism
        The mechanism.
    steps : int
        CF4 steps.
    U : numpy.ndarray, optional
        Their stage table, if known.
    sign : float, optional
        The side of ``Δ = 0`` (default: the start's).

    Returns
    -------
    G : float
        The amplification of a perturbation at ``t_n`` by ``T``; ``inf`` if the
        variational replay runs into ``Δ = 0``.
    end : tuple of numpy.ndarray or None
        The replay's endpoint ``(R_T, q_T)`` (``None`` with an infinite ``G``).
    """
    if U is None:
        U = stages.stage_table(par, steps)
    kern = compiled_system(mechanism, frame=False)
    m, d = mechanism.n_inputs, mechanism.n_rates
    R, q = start
    if sign is None:
        sign = mechanism.singular.sign(R, q)
    Rs, Qs = kern.nodes(steps)
    Zs = np.empty((steps + 1, d, d))
    n, _, _ = kern.forward_variational(
        R, q, np.ascontiguousarray(U), T / steps, sign, 0.0,
        *no_basis(steps), Rs, Qs, Zs, np.empty((d, 0)),
        np.empty((d, d)), np.empty((0, d * m)), True)
    if n < steps:
        return float("inf"), None
    with np.errstate(all="ignore"):
        try:
            Phi = np.linalg.solve(Zs[-1], Zs.transpose(1, 0, 2).reshape(d, -1))   # Φ(T, t_n) side by side
        except np.linalg.LinAlgError:       # Z(T) overflowed to a singular matrix
            return float("inf"), None
        G = float(np.sqrt(np.max(np.sum(Phi.reshape(d, -1, d) ** 2, axis=(0, 2)))))
    return (G if np.isfinite(G) else float("inf")), (Rs[-1], Qs[-1])


def agree(G_coarse: float, G_fine: float) -> bool:
    """Whether two sensitivities on grids a factor 2 apart agree.

    Parameters
    ----------
    G_coarse, G_fine : float
        The sensitivities.

    Returns
    -------
    bool
        They are within :data:`SENSITIVITY_AGREEMENT` of the larger.
    """
    return abs(G_fine - G_coarse) <= SENSITIVITY_AGREEMENT * max(G_fine, G_coarse)


def resolved_sensitivity(start, par, T: float, mechanism, steps: int, U=None, sign: float | None = None,
                         limit: float = np.inf, max_steps: int | None = None):
    """The sensitivity of ``par``'s motion resolved: ``G`` on ``steps/2`` and ``steps`` CF4
    steps (``steps`` alone where the controls' grid forbids ``steps/2``), the grid doubled
    until the last two agree (:func:`agree`) — a coarse grid can miss a fast growth of
    ``Φ`` almost entirely (a motion near ``Δ = 0`` with large inputs; ``tests/certify/test_certify.py``
    keeps one) while its endpoint looks converged. Stops early when both exceed
    ``limit`` (too ill-conditioned either way) or one is infinite, and at
    :data:`MAX_REPLAY_STEPS` (or ``max_steps``).

    Parameters
    ----------
    start, par, T, mechanism, sign
        As for :func:`sensitivity`.
    steps : int
        CF4 steps of the finer of the first two grids.
    U : numpy.ndarray, optional
        The stage table of ``2·steps`` steps, if known.
    limit : float
        Stop when both sensitivities exceed it.
    max_steps : int, optional
        The finest grid (default :data:`MAX_REPLAY_STEPS`).

    Returns
    -------
    G : float
        The larger of the last two.
    resolved : bool
        Whether they agree (or exceed ``limit``).
    grids : dict of int to float
        The sensitivities by grid.
    end : tuple of numpy.ndarray or None
        The endpoint of the ``steps``-step replay.
    """
    try:
        first = stages.check_steps(par, steps // 2) if steps % 2 == 0 else steps
    except ValueError:
        first = steps
    tables = {}
    if U is not None:
        tables[2 * steps] = U
        tables[steps] = stages.halve(U)
        if first != steps:
            tables[first] = stages.halve(tables[steps])
    cap = MAX_REPLAY_STEPS if max_steps is None else max_steps
    grids: dict[int, float] = {}
    R_T = None
    k = first
    while True:
        G, R_k = sensitivity(start, par, T, mechanism, k, tables.get(k), sign)
        grids[k] = G
        if k == steps:
            R_T = R_k
        last = list(grids.values())[-2:]
        resolved = not np.isfinite(G) or (len(last) == 2 and (agree(*last) or min(last) > limit))
        if resolved or 2 * k > cap:
            return max(last), resolved, grids, R_T
        k *= 2


def refinements(estimate: float, target: float, steps: int, cap: int) -> int:
    """The doublings of a replay's ``steps`` its error estimate predicts it needs to fall below
    ``target``: a fourth-order error falls about :data:`ORDER_FACTOR`-fold a doubling (at least
    one, and none past ``cap``). A grid still short of its asymptotic rate falls slower; the
    refinement then goes on from there.

    Parameters
    ----------
    estimate : float
        The error estimate on ``steps`` steps.
    target : float
        The estimate sought.
    steps : int
        The replay's steps.
    cap : int
        The finest replay.

    Returns
    -------
    int
        The doublings, at least one.
    """
    wanted = math.ceil(math.log(estimate / target) / math.log(ORDER_FACTOR)) if estimate > target else 1
    most = max(1, int(math.floor(math.log2(cap / steps))))
    return min(max(wanted, 1), most)


def no_basis(steps: int) -> tuple:
    """An empty *sparse* stage basis of ``steps`` steps for the variational kernel (no
    Jacobian): ``Bidx`` of shape ``(steps, 3, 0)``. (An index of zero rows with ``Bval`` of
    ``steps`` rows would be read as a dense basis, whose contraction reads ``3·steps`` rows
    of the stage weights ``Wd``, of which an empty ``Wd`` has none.)

    Parameters
    ----------
    steps : int
        The integrator steps.

    Returns
    -------
    tuple
        ``(Bidx, Bval, 0, 0)``, the basis arguments of ``forward_variational``.
    """
    return np.zeros((steps, 3, 0), np.int64), np.zeros((steps, 3, 0)), 0, 0


def measure(start, goal, T: float, mechanism, par, steps: int, tol: float, delta_min: float,
            sign: float = 1.0, G: float | None = None, R_half=None,
            max_steps: int | None = None, leg_limits=None, limits=None,
            input_bounds=None) -> Certificate:
    """The certificate of physical controls (see the module): replays on ``steps/2``·2ᵏ and
    ``steps``·2ᵏ CF4 steps, ``k`` the least with an error estimate below ``ERROR_FRACTION ·
    tol``, or ``k = 0`` when the sensitivity already rules the plan out (infinite,
    unresolved or too large for ``tol``).

    Parameters
    ----------
    start, goal : State
        The start and the goal (:class:`~nonholo.spaces.state.State`).
    T : float
        The horizon (s).
    mechanism : Mechanism
        The mechanism.
    par : Controls or FrameControls
        The physical inputs.
    steps : int
        Even, and a multiple of the controls' grid and of a
        :class:`~nonholo.motion.frame_controls.FrameControls`' steps.
    tol : float
        The goal's tolerance (stacked metric).
    delta_min : float
        The clearance from ``Δ = 0`` the replay must keep.
    sign : float
        The side of ``Δ = 0`` the motion keeps to.
    G : float, optional
        The sensitivity, if already known.
    R_half : tuple of numpy.ndarray, optional
        The endpoint ``(R, q)`` of the ``steps/2`` replay, if already known.
    max_steps : int, optional
        The finest replay (default :data:`MAX_REPLAY_STEPS`).
    leg_limits : LegLimits, optional
        Stroke limits (:class:`~nonholo.model.limits.LegLimits`) every node of the replay
        must keep.
    limits : Limits, optional
        Further clearances every node of the replay must keep, each to within its slack
        (:class:`~nonholo.model.limits.Limits`: the legs' stroke, the coordinates' bounds).
    input_bounds : InputBounds, optional
        Bounds (:class:`~nonholo.model.bounds.InputBounds`, checked) the replayed inputs
        must keep at every stage point, to :data:`~nonholo.model.bounds.BOUND_RTOL`
        relative: for controls played as they are, not for a path still to be re-timed.

    Returns
    -------
    Certificate
        The certificate, ``passed`` or with the ``reason`` why not.
    """
    singular = mechanism.singular
    limits = Limits.of(leg_limits, limits)
    cap = MAX_REPLAY_STEPS if max_steps is None else max_steps
    M = steps
    U = np.ascontiguousarray(stages.stage_table(par, M))
    resolved, grids = True, {}
    if G is None:
        # on M/8 and M/4 steps where the controls allow it (cheap; the replay on M/2 then
        # comes from the forward kernel), else on M/4 and M/2 or M/2 and M
        try:
            quarter = M % 4 == 0 and stages.check_steps(par, M // 4) == M // 4
        except ValueError:
            quarter = False
        limit = SENSITIVITY_FRACTION * tol / REPLAY_PERTURBATION
        if quarter:
            G, resolved, grids, _ = resolved_sensitivity(start, par, T, mechanism, M // 4, stages.halve(U),
                                                         sign, limit, cap)
        else:
            G, resolved, grids, R_T = resolved_sensitivity(start, par, T, mechanism, M // 2, U, sign, limit,
                                                           cap)
            if R_half is None:
                R_half = R_T
    # a sensitivity that already rules the plan out is not worth a finer replay
    hopeless = not resolved or not G * REPLAY_PERTURBATION <= SENSITIVITY_FRACTION * tol
    while True:
        if U is None:
            U = np.ascontiguousarray(stages.stage_table(par, M))
        if R_half is None:
            # the half replay from the halved table
            R_h, done, dmin, q_h = replay(start, par, T, mechanism, M // 2, sign, stages.halve(U))
            if done < M // 2:
                return _blown(M // 2, done, T, G, R_h, singular, dmin, mechanism.n_rates)
            R_half = (R_h[-1], q_h[-1])
        R, done, dmin, q = replay(start, par, T, mechanism, M, sign, U)
        if done < M:
            return _blown(M, done, T, G, R, singular, dmin, mechanism.n_rates)
        est = richardson((R[-1], q[-1]), R_half, mechanism)
        if hopeless or not est > ERROR_FRACTION * tol or 2 * M > cap:
            break
        # to the steps the estimate predicts; one doubling's half is this replay
        doublings = refinements(est, ERROR_FRACTION * tol, M, cap)
        M *= 2 ** doublings
        R_half, U = ((R[-1], q[-1]) if doublings == 1 else None), None
    space = mechanism.space
    l, errors = space.error((R[-1], q[-1]), goal)
    err = space.norm(errors)
    bound = est + G * REPLAY_PERTURBATION
    dmin = singular.reported(dmin)
    reason = ""
    correctable = False
    if not np.isfinite(G):
        reason = ("the physical replay's sensitivity is infinite (its variational system "
                  + singular.blowup + "): the endpoint cannot be certified")
    elif not resolved:
        found = ", ".join(f"{g:.3g} on {k} steps" for k, g in grids.items())
        reason = (f"the physical replay's sensitivity max|Φ(T,t)| is not resolved ({found}): "
                  f"the endpoint's conditioning is unknown")
    elif G * REPLAY_PERTURBATION > SENSITIVITY_FRACTION * tol:
        reason = (f"the motion is too ill-conditioned for tol = {tol:g}: its sensitivity "
                  f"max|Φ(T,t)| = {G:.3g} amplifies an error of {space.amount(REPLAY_PERTURBATION, 'g')} (a careful "
                  f"replay's) to {space.amount(G * REPLAY_PERTURBATION)}")
    elif est > ERROR_FRACTION * tol:
        reason = (f"the replay's integration error is still ~{space.amount(est)} with {M} steps "
                  f"(the most certified: {cap}); more than {ERROR_FRACTION:g}·tol")
    elif not singular.clear(dmin, delta_min):
        reason = (f"the physical replay comes within {dmin:.4g} of Δ = 0 (delta_min = {delta_min:g})")
    elif limits is not None and limits.broken(mechanism, R, q) is not None:
        reason = (f"the physical replay leaves {limits.broken(mechanism, R, q).kept_text}: "
                  f"{limits.describe(mechanism, R, np.arange(M + 1) * (T / M), q)}")
    elif input_bounds is not None and input_bounds.excess(U.reshape(-1, U.shape[-1])) is not None:
        steps_t = (np.arange(M)[:, None] + np.array([0.0, 0.5, 1.0])[None, :]).ravel() * (T / M)
        reason = (f"the physical replay's inputs leave their bounds: "
                  f"{input_bounds.excess(U.reshape(-1, U.shape[-1]), steps_t, input_names(mechanism))}")
    elif err + bound > tol:
        reason = (f"the physical replay ({M} steps) ends {space.amount(err, '.3g')} from the goal "
                  f"(+ error bound {bound:.2g} > tol = {tol:g})")
        correctable = True
    return Certificate(M, err, bound, dmin, G, not reason, reason, correctable, l, R, U, q, errors)


def _blown(M, done, T, G, R, singular, dmin, rates) -> Certificate:
    """The certificate of a replay on ``M`` steps that stopped at step ``done``."""
    return _failed(M, G, R, singular, dmin, f"the physical replay ({M} steps) produced a non-finite angular "
                   f"velocity at t ≈ {done * T / M:.4g} s", rates)


def _failed(M, G, R, singular, dmin, reason, rates: int = 3) -> Certificate:
    return Certificate(M, float("inf"), float("inf"), singular.reported(dmin), G, False, reason,
                       False, np.full(rates, np.nan), R)

