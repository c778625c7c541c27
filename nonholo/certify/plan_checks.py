"""The checks of a plan result's numbers (what :meth:`nonholo.io.result.PlanResult.validate`
and :meth:`~nonholo.io.result.PlanResult.load` run, and what
:meth:`~nonholo.io.result.PlanResult.save` runs before it writes): every field's type, shape
and finiteness, the options (every one :func:`nonholo.plan` records, present and with a value
it accepts), the labels (mechanism, method, strategy, route, ``T``, ``steps``, ``R0``)
against the controls, and the stored controls replayed from ``R0`` against the stored
samples — ``R`` (and ``q``) within :data:`REPLAY_TOL`, ``u = controls(t)``, ``Δ`` of the
samples, ``terminal_error`` (within the plan's own ``tol``), ``min_delta``, ``error_bound``
(at least the replay's Richardson estimate) — and ``success``, judged from the replay
itself: the certified replay ends within ``tol − error_bound`` of ``Rd``, with a
sensitivity the certificate accepts, clear of ``Δ = 0``, within the legs' stroke and
speed, the coordinates' and the inputs' bounds (a ``nonholo.plan/1`` success, which records no certificate, is certified anew). The
result is taken by its attributes (no import of :mod:`nonholo.io`); a failed check raises
``ValueError`` naming the field."""
from __future__ import annotations

import numpy as np

from ..controls import stages
from ..controls.parametrisations import Fourier, Legendre, PiecewiseConstant
from ..controls.stitched import Stitched
from ..integrate.compiled import compiled_system
from ..model.bounds import InputBounds, StateBounds, input_names
from ..model.limits import LegLimits, Limits
from ..motion import playback
from ..motion.frame_controls import FrameControls
from ..motion.speed_limits import InputRetimed, Retimed
from ..motion.time_scaling import RestToRest, is_time_change, planned, played_time
from . import certificate as certify
from .plan_fields import (
    FORMAT_1,
    METHOD_OF_KIND,
    ROTATION_TOL,
    ROUTES,
    check_options,
    fail,
    integer_field,
    json_type,
    number_field,
    rotation_field,
    scan_finite,
    short,
    string_field,
)

#: stored samples ``R`` against the controls replayed from ``R0`` by the planning
#: integrator (largest entry difference, ≈ rad), and (at most) ``terminal_error`` against
#: ``|log(R[-1] Rdᵀ)|`` (rad). Replays on this machine reproduce both exactly; the
#: tolerance leaves room for another machine's rounding, amplified along the motion.
REPLAY_TOL = 1e-9
#: ``terminal_error`` against ``|log(R[-1] Rdᵀ)|`` is held to ``min(REPLAY_TOL, tol)`` of the
#: plan's own ``tol``, but never below this (rad): two computations of one distance
#: differ by rounding
TERMINAL_FLOOR = 1e-13
#: stored ``u`` against ``controls(t)``, ``delta`` against ``Δ(R)`` and ``min_delta``
#: against the samples, relative to ``max(1, largest value)``
VALUE_RTOL = 1e-12
#: ``t`` against the integrator's step points ``k T/steps``, relative to ``T``
TIME_RTOL = 1e-12
#: the legs' speeds at the samples of a success against its ``leg_speed``, relative (the
#: re-timing's spline moves them off the bound by less)
SPEED_RTOL = 1e-6


def check(result, legacy: bool = False) -> None:
    """Check a plan result, as :meth:`~nonholo.io.result.PlanResult.validate` describes.

    Parameters
    ----------
    result : PlanResult
        An object with the fields of :class:`~nonholo.io.result.PlanResult` and its
        ``hops``.
    legacy : bool
        It was read from a file of format ``nonholo.plan/1`` (no certificates).

    Raises
    ------
    ValueError
        Naming the field, for a result that fails a check.
    """
    PlanChecks(result, legacy).run()


class PlanChecks:
    """The checks of one plan result: its fields, then its numbers against its controls.

    Each check raises ``ValueError`` naming the field it fails on.

    Parameters
    ----------
    result : PlanResult
        As for :func:`check`.
    legacy : bool
        As for :func:`check`.
    """

    def __init__(self, result, legacy: bool = False):
        self.r = result
        #: a file of format ``nonholo.plan/1`` (no certificates)
        self.legacy = legacy

    def run(self) -> None:
        """Every check, in order (:func:`check`)."""
        r = self.r
        self.scalars()
        mech = self.labels()
        check_options(r.options, mech)
        self.tol = float(r.options["tol"])
        n = self.arrays(mech)
        complete = n == r.steps + 1
        if n == 0:
            self.nothing_simulated()
            return
        if not np.array_equal(r.R[0], r.R0):
            fail("R", "starts elsewhere than R0 (R[0] != R0)")
        if not np.array_equal(r.q[0], r.q0):
            fail("q", "starts elsewhere than q0 (q[0] != q0)")
        self.replay(mech, n)
        self.values(mech, n, complete)

    # -- field by field --------------------------------------------------------------------
    def scalars(self) -> None:
        """The scalar fields' types and ranges, ``history`` and ``options``."""
        r = self.r
        if not isinstance(r.success, (bool, np.bool_)):
            fail("success", f"must be true or false, got {json_type(r.success)}")
        v = vars(r)
        string_field(v, "reason", empty=True)
        for key in ("mechanism", "method", "strategy"):
            string_field(v, key)
        integer_field(v, "iterations", 0)
        integer_field(v, "steps", 1)
        if number_field(v, "T") <= 0:
            fail("T", f"must be a positive time (s), got {r.T}")
        seconds = number_field(v, "seconds", null=True)
        if seconds is not None and seconds < 0:
            fail("seconds", f"must be >= 0 (or null), got {r.seconds}")
        for key in ("terminal_error", "sensitivity", "error_bound"):
            x = number_field(v, key, null=True)
            if x is not None and x < 0:
                fail(key, f"must be >= 0 (or null), got {x}")
        number_field(v, "min_delta", null=True)
        if r.replay_steps is not None:
            M = integer_field(v, "replay_steps", 2)
            if M % r.steps or M % 2:
                fail("replay_steps", f"({M}) must be an even multiple of steps ({r.steps})")
            if r.error_bound is None:
                fail("error_bound", "is null, but the plan has a certified replay (replay_steps)")
        elif r.error_bound is not None:
            fail("replay_steps", "is null, but the plan has an error bound (error_bound)")
        if self.legacy and r.replay_steps is not None:
            fail("replay_steps", f"is set in a file of format {FORMAT_1!r}, which has no certificates")
        if not isinstance(r.history, list) or not all(isinstance(h, dict) for h in r.history):
            fail("history", "must be a list of objects (one per iteration)")
        if not isinstance(r.options, dict):
            fail("options", f"must be an object, got {json_type(r.options)}")
        scan_finite(r.history, "history")
        scan_finite(r.options, "options")

    def labels(self):
        """The mechanism; ``method``, ``strategy``, ``T``, ``steps``, ``R0`` against the controls.

        Returns
        -------
        Mechanism
            The plan's mechanism (its ``kinematics``).
        """
        r = self.r
        mech = r.kinematics
        if mech.name != r.mechanism:
            fail("mechanism", f"is {r.mechanism!r}, but the plan's kinematics are of {mech.name!r}")
        par = r.parametrisation
        if isinstance(par, RestToRest):
            if r.replay_steps is None:
                fail("controls", "are played rest to rest, which only the path of a certified plan can be")
            par = par.base
        if isinstance(par, Retimed):
            self.retimed(par, mech)
            par = par.base
        elif isinstance(par, InputRetimed):
            self.input_retimed(par)
            par = par.base
        if r.route not in ROUTES:
            fail("route", f"must be one of {', '.join(map(repr, ROUTES))}, got {short(r.route)}")
        stitched = isinstance(par, Stitched)
        if r.stitched is not None:
            if not isinstance(r.stitched, Stitched):
                fail("stitched", f"must be stitched controls or None, got {type(r.stitched).__name__}")
            if stitched:
                fail("stitched", "is set, but the controls are stitched themselves (a smoothed route's "
                                  "controls are one piece)")
        routed = stitched or r.stitched is not None
        if routed != (r.route == "global"):
            fail("route", f"is {r.route!r}, but the controls are "
                           f"{'stitched' if stitched else 'one piece'}"
                           f"{' with the stitched route they were smoothed from' if r.stitched is not None else ''}"
                           f" (route {'global' if routed else 'local'!r})")
        if r.method not in METHOD_OF_KIND.values():
            fail("method", f"must be one of {', '.join(map(repr, METHOD_OF_KIND.values()))}, got {r.method!r}")
        if par.n_inputs != mech.n_inputs:
            fail("controls", f"have {par.n_inputs} inputs, mechanism {mech.name!r} has {mech.n_inputs}")
        if r.parametrisation.T != r.T:
            fail("T", f"is {r.T!r}, the controls are defined on [0, {r.parametrisation.T!r}]")
        hops = r.hops                   # the route's stitched control: the controls, or their record
        if hops is not None:
            where = "controls" if stitched else "stitched"
            if r.replay_steps is None:
                fail("route", "is 'global', which only a certified path has (replay_steps, error_bound)")
            if hops.T != par.T:
                fail(where, f"is defined on [0, {hops.T!r}], the plan on [0, {par.T!r}]")
            if not np.array_equal(hops.waypoints[0], r.R0):
                fail("R0", f"differs from the first waypoint of the stitched controls ({where!r})")
            for i, piece in enumerate(hops.pieces):
                self.piece(piece, mech, f"{where}.pieces[{i}]", None, None, record=not stitched)
        if stitched:
            if r.steps % par.grid:
                fail("steps", f"({r.steps}) must be a multiple of the stitched controls' grid ({par.grid})")
        else:
            self.piece(par, mech, "controls", r.steps, r.R0)
        return mech

    def retimed(self, par: Retimed, mech) -> None:
        """Re-timed controls: of a certified success's path, from its ``R0``, of its
        mechanism, under the ``leg_speed`` the options record.

        Parameters
        ----------
        par : Retimed
            The controls.
        mech : Mechanism
            The plan's mechanism.
        """
        r = self.r
        if r.replay_steps is None:
            fail("controls", "are re-timed, which only the path of a certified plan can be")
        if par.mechanism.name != r.mechanism:
            fail("mechanism", f"is {r.mechanism!r}, the re-timed controls are of {par.mechanism.name!r}")
        if not np.array_equal(par.R0, r.R0):
            fail("R0", "differs from the re-timed controls' R0")
        if r.options.get("leg_speed") != par.leg_speed:
            fail("options", f"record leg_speed = {short(r.options.get('leg_speed'))}, the controls "
                             f"are re-timed for {par.leg_speed!r}")

    def input_retimed(self, par: InputRetimed) -> None:
        """Controls re-timed under input bounds: of a certified success's path, under the
        ``input_bounds`` the options record.

        Parameters
        ----------
        par : InputRetimed
            The controls.
        """
        r = self.r
        if r.replay_steps is None:
            fail("controls", "are re-timed, which only the path of a certified plan can be")
        if r.options.get("input_bounds") != par.bounds.record():
            fail("options", f"record input_bounds = {short(r.options.get('input_bounds'))}, the controls "
                             f"are re-timed for {par.bounds.record()!r}")

    def piece(self, par, mech, where: str, steps: int | None, R0, record: bool = False) -> None:
        """One piece of physical controls against the plan's ``method``, ``strategy``,
        ``mechanism`` (and ``steps``, ``R0``, when the piece is the whole plan).

        Parameters
        ----------
        par : Controls or FrameControls
            The piece.
        mech : Mechanism
            The plan's mechanism.
        where : str
            The field holding it, for messages.
        steps : int or None
            The plan's ``steps`` (``None``: a piece of a stitched route).
        R0 : numpy.ndarray or None
            The plan's ``R0`` (``None``: a piece of a stitched route).
        record : bool, default False
            A piece of the plan's record ``stitched`` of its route (it keeps the
            method the route planned it with; a plan lowered by the energy stage afterwards
            has the method of its own controls).
        """
        r = self.r
        frame = isinstance(par, FrameControls)
        inner = par.frame if frame else par
        if not isinstance(inner, (Fourier, Legendre, PiecewiseConstant)):
            fail(where, f"must be Fourier, Legendre, piecewise-constant or frame controls, got {type(par).__name__}")
        if r.method != METHOD_OF_KIND[inner.kind] and not record:
            fail("method", f"is {r.method!r}, but the controls are {inner.kind!r} "
                            f"(method {METHOD_OF_KIND[inner.kind]!r})")
        if frame:
            if par.mechanism.name != r.mechanism:
                fail("mechanism", f"is {r.mechanism!r}, the frame controls are of {par.mechanism.name!r}")
            if steps is not None and par.steps != steps:
                fail("steps", f"is {steps}, the frame controls replay {par.steps} steps")
            if R0 is not None and not np.array_equal(par.R0, R0):
                fail("R0", "differs from the frame controls' R0")
            if r.strategy == "paper":
                fail("strategy", "is 'paper', which plans the physical inputs, but the controls are "
                                  "frame controls (strategy 'robust')")
        if steps is not None and isinstance(inner, PiecewiseConstant) and steps % inner.grid:
            fail("steps", f"({steps}) must be a multiple of the controls' grid ({inner.grid})")

    def arrays(self, mech) -> int:
        """Shapes and finiteness of ``R0``, ``Rd``, ``t``, ``R``, ``u``, ``delta``.

        Parameters
        ----------
        mech : Mechanism
            The plan's mechanism.

        Returns
        -------
        int
            ``n``, the number of samples.
        """
        r = self.r
        for key in ("R0", "Rd"):
            rotation_field(getattr(r, key), key)
        arrays = {"t": r.t, "R": r.R, "u": r.u, "delta": r.delta}
        for key, a in arrays.items():
            if key == "delta" and a is None:
                continue
            if not isinstance(a, np.ndarray) or a.dtype.kind != "f":
                fail(key, "must be a float array")
            if not np.all(np.isfinite(a)):
                fail(key, "has non-finite entries (NaN or infinity)")
        n = r.t.shape[0] if r.t.ndim == 1 else -1
        if n < 0:
            fail("t", f"must have shape (n,), got {r.t.shape}")
        arrays["q"] = r.q
        for key in ("q", "q0", "qd"):
            if not isinstance(getattr(r, key), np.ndarray):
                fail(key, "must be a float array")
            if not np.all(np.isfinite(getattr(r, key))):
                fail(key, "has non-finite entries (NaN or infinity)")
        for key in ("q0", "qd"):
            if getattr(r, key).shape != (mech.n_coordinates,):
                fail(key, f"must have shape ({mech.n_coordinates},), got {getattr(r, key).shape}")
        for key, shape in (("R", (n, 3, 3)), ("u", (n, mech.n_inputs)), ("q", (n, mech.n_coordinates))):
            if key not in arrays:
                continue
            if arrays[key].shape != shape:
                fail(key, f"must have shape {shape} (n = {n} samples in t), got {arrays[key].shape}")
        #: ``Δ`` of the samples (``None`` without a singular set)
        self.delta = mech.singular.samples(r.R, r.q)
        if self.delta is None:
            if r.delta is not None:
                fail("delta", f"must be null: mechanism {mech.name!r} has no singular set")
        elif r.delta is None or r.delta.shape != (n,):
            fail("delta", f"must have shape ({n},): mechanism {mech.name!r} has a singular set, "
                           f"got {'null' if r.delta is None else r.delta.shape}")
        if n > r.steps + 1:
            fail("t", f"has {n} samples, more than the {r.steps + 1} step points of {r.steps} steps")
        par = r.parametrisation
        if is_time_change(par):
            # the planned step points, at their played instants
            T_planned = planned(par).T
            tau = np.arange(n) * (T_planned / r.steps)
            if n == r.steps + 1:
                tau[-1] = T_planned
            expected = played_time(par, tau)
            expected[0] = 0.0
        else:
            expected = np.arange(n) * (r.T / r.steps)
        if n == r.steps + 1:
            expected[-1] = r.T
        if n and np.max(np.abs(r.t - expected)) > TIME_RTOL * r.T:
            k = int(np.argmax(np.abs(r.t - expected)))
            what = ("the played instants of the step points" if is_time_change(par)
                    else "the integrator's step points k·T/steps")
            fail("t", f"must hold {what}: t[{k}] = {r.t[k]!r}, expected {expected[k]!r}")
        if n:
            err = np.max(np.abs(np.einsum("nji,njk->nik", r.R, r.R) - np.eye(3)), axis=(1, 2))
            k = int(np.argmax(err))
            if err[k] > ROTATION_TOL:
                fail("R", f"sample {k} is not a rotation: |RᵀR - I| = {err[k]:.3g}")
            det = np.linalg.det(r.R)
            if np.any(det < 0):
                fail("R", f"sample {int(np.argmax(det < 0))} is a reflection (det = -1)")
        return n

    def nothing_simulated(self) -> None:
        """A plan without a trajectory (refused before any simulation)."""
        r = self.r
        if r.success:
            fail("success", "is true, but nothing was simulated (no trajectory)")
        for key in ("terminal_error", "min_delta", "sensitivity", "error_bound", "replay_steps"):
            if getattr(r, key) is not None:
                fail(key, "must be null when nothing was simulated (no trajectory)")
        if r.iterations or r.history:
            fail("iterations", "must be 0, with an empty history, when nothing was simulated")
        if isinstance(r.parametrisation, FrameControls):
            fail("controls", "are frame controls, but nothing was simulated (no trajectory)")

    # -- against the controls --------------------------------------------------------------
    def replay(self, mech, n: int) -> None:
        """The controls replayed from ``R0`` pass through the stored samples; keeps the
        least ``sgnΔ`` over the replay's evaluation points. A certified plan: the
        physical inputs on ``replay_steps`` steps (:func:`nonholo.motion.playback.replay`), whose
        Richardson estimate ``error_bound`` must cover; otherwise by the integrator that
        planned them, the physical system's for controls of ``u``, the frame system's for
        frame controls.

        Parameters
        ----------
        mech : Mechanism
            The plan's mechanism.
        n : int
            The number of samples.
        """
        r = self.r
        par = planned(r.parametrisation)      # the same path: replayed as planned
        T = par.T
        frame = isinstance(par, FrameControls) and r.replay_steps is None
        self.sign = mech.singular.sign(*r.start)
        if self.sign == 0.0:
            fail("R0", "lies on the singular surface Δ = 0")
        if r.replay_steps is not None:
            if n != r.steps + 1:
                fail("replay_steps", f"is set, but the trajectory stops at t = {r.t[-1]:.6g} s < T")
            M = r.replay_steps
            U = np.ascontiguousarray(stages.stage_table(par, M))
            R_M, done, dmin, Q_M = playback.replay(r.start, par, T, mech, M, self.sign, U)
            Rs, Qs = R_M[::M // r.steps], Q_M[::M // r.steps]
            done //= M // r.steps
        else:
            kern = compiled_system(mech, frame=frame)
            U = np.ascontiguousarray(stages.stage_table(par.frame if frame else par, r.steps)[:n - 1])
            Rs, Qs = np.empty((n, 3, 3)), np.empty((n, mech.n_coordinates))
            done, dmin, _ = kern.forward(*r.start, U, T / r.steps, self.sign, -np.inf, Rs, Qs)
        if done < n - 1:
            fail("R", f"goes on to t = {r.t[-1]:.6g} s, but the controls replayed from R0 stop at "
                       f"t = {r.t[done]:.6g} s (non-finite angular velocity)")
        dev = np.max(np.abs(Rs - r.R), axis=(1, 2))
        k = int(np.argmax(dev))
        if not dev[k] <= REPLAY_TOL:
            system = "frame system" if frame else "system"
            steps = r.steps if r.replay_steps is None else r.replay_steps
            fail("R", f"disagrees with the controls replayed from R0 (the {system} of "
                       f"{mech.name!r}, {steps} steps): by {dev[k]:.3g} at t = {r.t[k]:.6g} s "
                       f"(tolerance {REPLAY_TOL:g})")
        dev = np.max(np.abs(Qs - r.q), axis=1, initial=0.0)
        k = int(np.argmax(dev))
        if not dev[k] <= REPLAY_TOL:
            fail("q", f"disagrees with the controls replayed from (R0, q0) by {dev[k]:.3g} at "
                       f"t = {r.t[k]:.6g} s (tolerance {REPLAY_TOL:g})")
        self.dmin = float(dmin)
        if r.replay_steps is not None:
            R_half, _, _, Q_half = playback.replay(r.start, par, T, mech, M // 2, self.sign, stages.halve(U))
            est = certify.richardson((R_M[-1], Q_M[-1]), (R_half[-1], Q_half[-1]), mech)
            # the estimate is a difference of two replays: their rounding (the planner may
            # take the half-step endpoint from the variational replay; another machine rounds
            # otherwise) moves it by up to a careful replay's accuracy per unit of state size
            self.rounding = certify.REPLAY_PERTURBATION * (
                1.0 + float(np.max(np.abs(Q_M), initial=0.0)))
            if not r.error_bound >= est - self.rounding:
                fail("error_bound", f"({r.error_bound:.3g}) is below the replay's own error "
                                     f"estimate ({mech.space.amount(est, '.3g')} with {M} steps)")
            #: the certified replay itself: its nodes, Richardson estimate and distance from
            #: the goal (as the certificate measures it), for the success check
            self.replayed, self.replayed_q, self.replay_T = R_M, Q_M, T
            self.estimate = est
            _, parts = mech.space.error((R_M[-1], Q_M[-1]), r.goal)
            self.end_error = float(mech.space.norm(parts))

    def values(self, mech, n: int, complete: bool) -> None:
        """``u``, ``delta``, ``terminal_error``, ``min_delta`` and ``success`` against the samples.

        Parameters
        ----------
        mech : Mechanism
            The plan's mechanism.
        n : int
            The number of samples.
        complete : bool
            Whether the trajectory reaches ``T``.
        """
        r = self.r
        u = np.asarray(r.parametrisation(r.t), dtype=float).reshape(n, mech.n_inputs)
        dev = np.max(np.abs(u - r.u))
        if not dev <= VALUE_RTOL * max(1.0, float(np.max(np.abs(u)))):
            fail("u", f"disagrees with controls(t) by {dev:.3g}")
        if self.delta is not None:
            d = self.delta
            dev = np.max(np.abs(d - r.delta))
            if not dev <= VALUE_RTOL * max(1.0, float(np.max(np.abs(d)))):
                fail("delta", f"disagrees with Δ(R) of the samples by {dev:.3g}")
        if complete:
            if r.terminal_error is None:
                fail("terminal_error", "is null, but the trajectory reaches T")
            err = mech.space.distance((r.R[-1], r.q[-1]), (r.Rd, r.qd))
            what = mech.space.distance_text(("R[-1]", "q[-1]"), ("Rd", "qd"))
            within = max(min(REPLAY_TOL, self.tol), TERMINAL_FLOOR)
            if not abs(err - r.terminal_error) <= within:
                fail("terminal_error", f"is {r.terminal_error:.6g}, but {what} = {err:.6g} (they must "
                                       f"agree within {within:g}, the plan's tol or less)")
        elif r.terminal_error is not None:
            fail("terminal_error", f"must be null: the trajectory stops at t = {r.t[-1]:.6g} s < T")
        if self.delta is not None:
            if r.min_delta is None:
                fail("min_delta", f"is null, but mechanism {mech.name!r} has a singular set")
            tol = VALUE_RTOL * max(1.0, abs(r.min_delta))
            least = float(np.min(self.sign * r.delta))
            if r.min_delta > least + tol:
                fail("min_delta", f"({r.min_delta:.6g}) exceeds the least sgnΔ of the samples ({least:.6g})")
            if complete and r.min_delta < self.dmin - tol:
                fail("min_delta", f"({r.min_delta:.6g}) is below the least sgnΔ of the replayed motion "
                                   f"({self.dmin:.6g})")
        elif r.min_delta is not None:
            fail("min_delta", f"must be null: mechanism {mech.name!r} has no singular set")
        if r.success:
            self.success(mech, complete)

    def success(self, mech, complete: bool) -> None:
        """A success is what :func:`nonholo.plan` certifies, judged from the controls
        replayed here, not from the stored numbers: the certified replay (``replay_steps``
        steps) ends within ``tol - error_bound`` of ``Rd`` (``tol``: the plan's own option),
        its ``error_bound`` covers the Richardson estimate and the sensitivity's share, the
        sensitivity is one the certificate accepts for ``tol``, the replay keeps
        ``delta_min``, the stroke and the ``state_bounds`` (to their slack), and the samples
        keep ``leg_speed`` and the ``input_bounds`` (:meth:`inputs_kept`). A file of format
        ``nonholo.plan/1`` (no certificate recorded) is certified here as the planner
        certifies a plan (:func:`nonholo.certify.certificate.measure`): the same standard.

        Parameters
        ----------
        mech : Mechanism
            The plan's mechanism.
        complete : bool
            Whether the trajectory reaches ``T``.
        """
        r = self.r
        if not complete:
            fail("success", f"is true, but the trajectory stops at t = {r.t[-1]:.6g} s < T")
        tol = self.tol
        dmin = float(r.options["delta_min"])
        stroke = r.options.get("leg_length")
        limits = None if stroke is None else LegLimits.from_argument(stroke, mech)
        state = r.options.get("state_bounds")
        box = None if state is None else StateBounds.from_record(state, mech, "options.state_bounds")
        if self.legacy:
            self.legacy_certificate(mech, tol, dmin, Limits.of(limits, box))
        elif r.replay_steps is None:
            fail("success", "is true, but the plan has no certificate (replay_steps, error_bound)")
        else:
            if not self.end_error + r.error_bound <= tol:
                fail("success", f"is true, but the controls replayed ({r.replay_steps} steps) end "
                                 f"{mech.space.amount(self.end_error, '.3g')} from the goal: + error_bound {r.error_bound:.2g} "
                                 f"> tol = {tol:g}")
            G = r.sensitivity
            if G is None:
                fail("sensitivity", "is null, but a certified success has one")
            if not G * certify.REPLAY_PERTURBATION <= certify.SENSITIVITY_FRACTION * tol:
                fail("sensitivity", f"({G:.3g}) is too large for a success at tol = {tol:g}: it amplifies "
                                    f"{mech.space.amount(certify.REPLAY_PERTURBATION, 'g')} to "
                                    f"{mech.space.amount(G * certify.REPLAY_PERTURBATION)}, more than {certify.SENSITIVITY_FRACTION:g}·tol (plan() certifies "
                                    "no such motion)")
            least = self.estimate + G * certify.REPLAY_PERTURBATION
            if not r.error_bound >= least - self.rounding:
                fail("error_bound", f"({r.error_bound:.3g}) is below the replay's error estimate plus the "
                                     f"sensitivity's share ({mech.space.amount(least, '.3g')})")
            if not mech.singular.clear(self.dmin, dmin):
                fail("success", f"is true, but the replayed motion comes within {self.dmin:.4g} of Δ = 0 "
                                 f"(delta_min = {dmin:g})")
            if not mech.singular.clear(r.min_delta, dmin):
                fail("success", f"is true, but min_delta = {r.min_delta:.4g} < delta_min = {dmin:g}")
            if limits is not None and limits.least_clearance(mech, self.replayed) < 0.0:
                fail("success", f"is true, but the replayed motion leaves the legs' stroke: "
                                 f"{limits.describe(mech, self.replayed, np.linspace(0.0, self.replay_T, len(self.replayed)))}")
            if box is not None and box.least_clearance(mech, self.replayed, self.replayed_q) < -box.slack:
                times = np.linspace(0.0, self.replay_T, len(self.replayed))
                fail("success", f"is true, but the replayed motion leaves the coordinates' bounds: "
                                 f"{box.describe(mech, self.replayed, times, self.replayed_q)}")
        if limits is not None and limits.least_clearance(mech, r.R) < -VALUE_RTOL * limits.hi:
            fail("success", f"is true, but {limits.describe(mech, r.R, r.t)}")
        if box is not None and box.least_clearance(mech, r.R, r.q) < -box.slack:
            fail("success", f"is true, but {box.describe(mech, r.R, r.t, r.q)}")
        recorded = r.options.get("input_bounds")
        if recorded is not None:
            self.inputs_kept(mech, InputBounds.from_record(recorded, mech, "options.input_bounds"))
        speed = r.options.get("leg_speed")
        if speed is not None:
            fastest = float(np.max(np.abs(mech.leg_speeds(r.R, r.u))))
            if fastest > speed * (1.0 + SPEED_RTOL):
                fail("success", f"is true, but a leg moves at {fastest:.6g} > leg_speed = {speed:g}")

    def inputs_kept(self, mech, bounds) -> None:
        """A success's inputs within the bounds its options record, to
        :data:`~nonholo.model.bounds.BOUND_RTOL`: the samples ``u``, and the controls at the
        ends and middles of the certified replay's steps.

        Parameters
        ----------
        mech : Mechanism
            The plan's mechanism.
        bounds : InputBounds
            The bounds, checked.
        """
        r = self.r
        names = input_names(mech)
        out = bounds.excess(r.u, r.t, names)
        if out is None:
            M = r.replay_steps or 2 * r.steps
            t = (np.arange(M)[:, None] + np.array([0.0, 0.5, 1.0])[None, :]).ravel() * (r.T / M)
            t[-1] = r.T
            u = np.asarray(r.parametrisation(t), dtype=float).reshape(t.size, mech.n_inputs)
            out = bounds.excess(u, t, names)
        if out is not None:
            fail("success", f"is true, but {out}")

    def legacy_certificate(self, mech, tol: float, dmin: float, limits) -> None:
        """A success read from a file of format ``nonholo.plan/1``: its physical controls
        certified now, as :func:`nonholo.plan` certifies a plan, for the file's ``tol``,
        ``delta_min`` and stroke.

        Parameters
        ----------
        mech : Mechanism
            The plan's mechanism.
        tol : float
            The plan's ``tol``.
        dmin : float
            Its ``delta_min``.
        limits : Limits or None
            Its stroke limits and coordinates' bounds.
        """
        r = self.r
        par = r.parametrisation
        steps = r.steps if r.steps % 2 == 0 else 2 * r.steps
        cert = certify.measure(r.start, r.goal, r.T, mech, par, steps, tol, dmin, self.sign,
                               leg_limits=limits)
        if not cert.passed:
            fail("success", f"is true, but the plan's controls are not certified for its tol = {tol:g} "
                             f"and delta_min = {dmin:g}: {cert.reason}")
