"""The outcome of a motion-planning run: :class:`PlanResult`, the record, with its JSON
save/load (the file's format and its decoding: :mod:`nonholo.io.plan_file`; the checks a
loaded file passes: :mod:`nonholo.certify.plan_checks`).
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

from ..certify import plan_checks
from ..certify.plan_fields import FORMAT
from ..controls.parametrisations import Controls
from ..controls.stitched import Stitched
from ..model import catalog
from ..model.mechanism import Mechanism
from ..motion.frame_controls import FrameControls
from ..motion.time_scaling import planned
from ..spaces.state import State
from . import csv_export as export
from . import plan_file, provenance, safe_write


@dataclass(eq=False)
class PlanResult:
    """Result of :func:`nonholo.planning.api.plan`: the record of a plan.

    :attr:`start`, :attr:`goal` and :meth:`state` give states as :func:`nonholo.plan` takes
    them; :meth:`controls` evaluates the physical inputs ``u(t)``; :meth:`save` and
    :meth:`load` write and read the plan file (:mod:`nonholo.io.plan_file`), :meth:`to_csv`
    the motion for an actuator controller.

    Parameters
    ----------
    success, reason : bool, str
        Whether the plan is certified (:mod:`nonholo.certify.certificate`): its physical
        controls, replayed on ``replay_steps`` CF4 steps, end within ``terminal_error +
        error_bound ≤ tol`` of the goal and keep ``|Δ| ≥ delta_min`` — and why not.
    terminal_error : float or None
        ``|l_T|`` (rad), ``[l_T] = log(R_T R_dᵀ)`` of the final trajectory (``None`` if
        nothing was simulated, e.g. a goal across ``Δ = 0``): of the certified replay for a
        success, of the planner's own trajectory otherwise.
    min_delta : float or None
        Least ``|Δ|`` along the final trajectory, over every point where the integrator
        evaluated ``L`` (``None`` for mechanisms without a singular set, or if nothing was
        simulated).
    iterations : int
        Accepted θ-steps.
    history : list of dict
        One record per accepted iteration (``iteration``, ``error``, ``step`` = ``γh``
        used, ``min_delta``, ``phase`` = ``"initial"``/``"flow"``/``"newton"``, ``rejected``
        = step halvings before it; strategy ``"robust"`` adds ``attempt``, the index of the
        initial guess, and one record with phase ``"restart"`` where a new guess starts).
    t, R, u, delta : numpy.ndarray
        Samples of the final trajectory at the integrator's step points (``R``
        spatial-frame rotations, the identity throughout for a state without orientation;
        ``u`` in the mechanism's input units; ``delta`` ``None`` without a singular set).
        For a success, the certified replay's nodes at the plan's step points.
    parametrisation : Controls, FrameControls or Stitched
        The planned control: Fourier or grid controls of ``u``
        (:class:`~nonholo.controls.parametrisations.Controls`),
        :class:`~nonholo.motion.frame_controls.FrameControls` wrapping those of the frame
        coordinates ``w``, or for a global route a
        :class:`~nonholo.controls.stitched.Stitched` of the hops' controls, with the
        route's waypoints and the hops' breakpoints.
    mechanism, method, strategy : str
        The names of the mechanism, the method and the strategy planned with.
    T : float
        The horizon (s).
    start, goal : State
        The start and the goal (:class:`~nonholo.spaces.state.State`, always complete;
        :attr:`R0`, :attr:`q0`, :attr:`Rd`, :attr:`qd` give their parts).
    steps : int
        The number of integrator steps of the final trajectory.
    seconds : float or None
        The planner's wall time; ``None`` when not recorded (a plan file kept without it,
        as ``nonholo reproduce`` writes them, so that a second run writes the same bytes).
    options : dict
        The options :func:`nonholo.plan` was given, as a plan file records them.
    sensitivity : float or None
        ``max_t |Φ(T, t)|_F`` of the physical system along the planned motion — how much
        a perturbation of the orientation at ``t`` is amplified at ``T`` when the planned
        ``u(t)`` is played open loop (``|Φ(T,T)|_F = √3``); computed when a converged plan
        is certified (``None`` otherwise).
    error_bound, replay_steps : float or None, int or None
        For a success: the bound on the replay's own error at ``T`` (rad) and the CF4 steps
        of that replay; ``None`` otherwise.
    route : {"local", "global"}
        One plan from ``R0`` to ``Rd``, or hops along a path of orientations clear of
        ``Δ = 0`` (:mod:`nonholo.planning.route`).
    stitched : Stitched or None
        For a global route re-planned as one smooth control (the controls), the stitched
        control of the route it was planned from (its hops, waypoints and hand-overs; a
        record: the certificate is the smooth control's); ``None`` otherwise. :attr:`hops`
        gives a global route's stitched control either way.
    q : numpy.ndarray
        The coordinates at the samples, ``(n, k)`` (``k = 0`` on SO(3)).
    errors : dict or None
        For a mechanism with coordinates, else ``None``: the terminal error by part,
        ``{"rotation": rad, "coordinates": units}`` (:mod:`nonholo.spaces.product`;
        ``terminal_error`` is then the norm of the stacked error, which bounds both).
    kinematics : Mechanism, optional
        The :class:`~nonholo.model.mechanism.Mechanism` itself, which re-timing, export,
        saving and checks use, so that a plan of a mechanism outside the catalog works as
        one of the catalog's (by default the catalog's of that name; ``ValueError`` if it
        has none).
    made_by : dict, optional
        What made the plan (:func:`nonholo.io.provenance.made_by`): read from its file,
        ``None`` for a plan made in this process (its file records this process's). Not
        compared by ``==``.
    """

    success: bool
    reason: str
    terminal_error: float | None
    min_delta: float | None
    iterations: int
    history: list
    t: np.ndarray
    R: np.ndarray
    u: np.ndarray
    delta: np.ndarray | None
    parametrisation: Controls | FrameControls
    mechanism: str
    method: str
    strategy: str
    T: float
    start: State
    goal: State
    steps: int
    seconds: float | None
    options: dict = field(default_factory=dict)
    sensitivity: float | None = None
    error_bound: float | None = None
    replay_steps: int | None = None
    route: str = "local"
    stitched: Stitched | None = None
    q: np.ndarray | None = None
    errors: dict | None = None
    kinematics: Mechanism | None = field(default=None, repr=False)
    made_by: dict | None = field(default=None, repr=False)

    def __post_init__(self):
        if self.kinematics is None:
            self.kinematics = catalog.get(self.mechanism)
        if self.q is None:
            self.q = np.zeros((len(self.R), self.kinematics.n_coordinates))

    @property
    def R0(self) -> np.ndarray:
        """The start's orientation (the identity without one)."""
        return self.start.R

    @property
    def Rd(self) -> np.ndarray:
        """The goal's orientation (the identity without one)."""
        return self.goal.R

    @property
    def q0(self) -> np.ndarray:
        """The start's coordinates (shape ``(0,)`` without them)."""
        return self.start.q

    @property
    def qd(self) -> np.ndarray:
        """The goal's coordinates (shape ``(0,)`` without them)."""
        return self.goal.q

    def state(self, k: int = -1) -> State:
        """Sample ``k`` of the trajectory.

        Parameters
        ----------
        k : int
            The sample's index (default: the last).

        Returns
        -------
        State
            The state there (:func:`nonholo.plan` takes it as a start or a goal).
        """
        return State(self.R[k], self.q[k])

    # -- controls ----------------------------------------------------------------------
    def controls(self, t) -> np.ndarray:
        """Planned input ``u(t)`` in physical units.

        Parameters
        ----------
        t : array_like
            Times, shape ``(n,)``.

        Returns
        -------
        numpy.ndarray
            ``u(t)``, shape ``(n, m)``.
        """
        return self.parametrisation(t)

    @property
    def breakpoints(self) -> np.ndarray | None:
        """Times where the planned control or its derivative may jump (for
        :func:`nonholo.certify.resimulate.resimulate`: an adaptive integrator should not step across them)."""
        return self.parametrisation.breakpoints

    @property
    def hops(self) -> Stitched | None:
        """A global route's stitched control (the hops' controls, the route's waypoints and
        hand-overs): the controls themselves, or the record :attr:`stitched` of a smoothed
        route; ``None`` for a local plan."""
        par = self.parametrisation
        par = planned(par)
        return par if isinstance(par, Stitched) else self.stitched

    @property
    def params(self) -> np.ndarray:
        """The planned control's parameter vector ``λ`` (of ``w`` for frame controls)."""
        return self.parametrisation.params

    @property
    def R_T(self) -> np.ndarray | None:
        """Endpoint of the final trajectory (``None`` if nothing was simulated)."""
        return self.R[-1] if len(self.R) else None

    # -- persistence -------------------------------------------------------------------
    def to_dict(self) -> dict:
        """The plan file's JSON object (see :mod:`nonholo.io.plan_file`), not checked.

        Returns
        -------
        dict
            Plain Python values: lists for arrays, ``None`` for what does not exist.
        """
        def arr(x):
            return None if x is None else np.asarray(x, dtype=float).tolist()

        return {
            "format": FORMAT,
            "success": bool(self.success),
            "reason": self.reason,
            "terminal_error": self.terminal_error,
            "min_delta": self.min_delta,
            "iterations": int(self.iterations),
            "history": _plain(self.history),
            "mechanism": self.mechanism,
            **plan_file.definition_fields(self.kinematics),
            "method": self.method,
            "strategy": self.strategy,
            "T": self.T,
            "steps": int(self.steps),
            "seconds": self.seconds,
            "options": _plain(self.options),
            "sensitivity": self.sensitivity,
            "error_bound": self.error_bound,
            "replay_steps": None if self.replay_steps is None else int(self.replay_steps),
            "route": self.route,
            **({} if self.stitched is None else {"stitched": self.stitched.to_dict()}),
            **self.kinematics.space.recorded("coordinates", {"q0": arr(self.q0), "qd": arr(self.qd),
                                                             "q": arr(self.q), "errors": _plain(self.errors)}, {}),
            "R0": arr(self.R0),
            "Rd": arr(self.Rd),
            "controls": self.parametrisation.to_dict(),
            "t": arr(self.t),
            "R": arr(self.R),
            "u": arr(self.u),
            "delta": arr(self.delta),
            "made_by": dict(self.made_by) if self.made_by is not None else provenance.made_by(),
        }

    @classmethod
    def from_dict(cls, d: dict, mechanism=None) -> "PlanResult":
        """The result described by a plan file's object, checked.

        Parameters
        ----------
        d : dict
            A plan file's object (see :mod:`nonholo.io.plan_file`).
        mechanism : Mechanism, optional
            The :class:`~nonholo.model.mechanism.Mechanism` of a plan whose mechanism is
            not in the catalog (see :meth:`load`).

        Returns
        -------
        PlanResult
            The result, checked field by field (:func:`nonholo.io.plan_file.decode`) and for
            consistency (:meth:`validate`).

        Raises
        ------
        ValueError
            Naming the field that is wrong.
        """
        if mechanism is not None:
            try:
                mechanism = catalog.resolve(mechanism)
            except ValueError as exc:
                raise ValueError(f"mechanism: {exc}") from None
        values, legacy = plan_file.decode(d, mechanism)
        res = cls(**values)
        plan_checks.check(res, legacy=legacy)
        return res

    def validate(self) -> "PlanResult":
        """Check that the result is one :func:`nonholo.plan` can have produced: types,
        shapes and finiteness of every field, and consistency — the controls replayed from
        ``R0`` pass through the stored samples ``R`` within
        :data:`~nonholo.certify.plan_checks.REPLAY_TOL` (a certified
        plan: the physical inputs on ``replay_steps`` CF4 steps, the replay of
        :mod:`nonholo.certify.certificate`; otherwise by the integrator that planned them, the physical
        system for controls of ``u``, the frame system for
        :class:`~nonholo.motion.frame_controls.FrameControls`), ``u = controls(t)``, ``Δ`` of the samples,
        ``terminal_error`` and ``min_delta`` agree with them, ``error_bound`` is at least
        the replay's Richardson estimate, a success is certified (``terminal_error +
        error_bound ≤ tol``), and the labels (mechanism, method, strategy, ``T``,
        ``steps``, ``R0``) agree with the controls.

        Returns
        -------
        PlanResult
            ``self``.

        Raises
        ------
        ValueError
            Naming the field that is wrong.
        """
        plan_checks.check(self)
        return self

    def to_json(self) -> str:
        """The plan file's text (format ``nonholo.plan/3``, see :mod:`nonholo.io.plan_file`),
        checked: it is decoded and checked exactly as :meth:`load` reads a file, so text
        that :meth:`load` would refuse is never returned.

        Returns
        -------
        str
            The JSON text.

        Raises
        ------
        ValueError
            Naming the field that would not load, or for a number JSON cannot hold.
        """
        try:
            text = json.dumps(self.to_dict(), allow_nan=False, indent=1)
        except (ValueError, TypeError) as exc:
            raise ValueError(f"cannot save the plan: {exc}") from None
        try:
            type(self).from_dict(plan_file.parse(text), self.kinematics)
        except ValueError as exc:
            raise ValueError(f"cannot save the plan, its file would not load: {exc}") from None
        return text

    def save(self, path) -> Path:
        """Write the result as JSON (format ``nonholo.plan/3``, see :mod:`nonholo.io.plan_file`).

        Only what :meth:`load` accepts is written: the text is decoded and checked as a
        loaded file is (:meth:`to_json`) before anything is written, else ``ValueError``
        naming the field. The file is written by :mod:`nonholo.io.safe_write`: atomically
        (the text goes to a temporary file in the same directory, flushed and synced to
        disk, which then replaces ``path``; a symbolic link is followed, its target
        replaced; if anything fails — ``OSError``, e.g. a full disk — the error propagates,
        the temporary file is removed and an existing ``path`` is untouched); a character
        device or FIFO at ``path`` is written in place, never replaced; any other path
        that exists and is not a regular file (a directory) is refused with a
        ``ValueError`` naming ``path``, before anything is written.

        Parameters
        ----------
        path : str or pathlib.Path
            Where to write.

        Returns
        -------
        pathlib.Path
            ``path``.

        Raises
        ------
        ValueError
            If the result would not load (naming the field), or ``path`` is neither a
            regular file, a character device nor a FIFO.
        OSError
            If writing fails; an existing file at ``path`` is then untouched.
        """
        safe_write.check_target(path, "path")
        return safe_write.write_text(path, self.to_json(), "path")

    def to_csv(self, path, rate: float = export.DEFAULT_RATE) -> Path:
        """Write the motion sampled at ``rate`` Hz as CSV for an actuator controller: ``t``,
        leg lengths ``l_i`` and speeds ``dl_i_dt`` (geometry units), inputs ``u_i``, the
        orientation as a unit quaternion ``qx, qy, qz, qw`` (scalar last) and ``delta``
        (see :mod:`nonholo.io.csv_export`). The file is written atomically, like :meth:`save`.

        Parameters
        ----------
        path : str or pathlib.Path
            Where to write.
        rate : float
            Samples per second.

        Returns
        -------
        pathlib.Path
            ``path``.

        Raises
        ------
        ValueError
            For a failed plan, a bad ``rate`` or a ``path`` that cannot be replaced, before
            anything is written.
        """
        safe_write.check_target(path, "path")
        text = export.csv_text(self, rate)
        return safe_write.write_text(path, text, "path")

    @classmethod
    def load(cls, path, mechanism=None) -> "PlanResult":
        """Read and check a result written by :meth:`save` (see :meth:`from_dict`).

        A UTF-8 byte-order mark is accepted.

        Parameters
        ----------
        path : str or pathlib.Path
            The plan file.
        mechanism : Mechanism, optional
            The :class:`~nonholo.model.mechanism.Mechanism` the plan was made with, for one
            that is not in the catalog and whose definition the file does not carry (built
            by :meth:`~nonholo.model.mechanism.Mechanism.from_constraints` or
            :meth:`~nonholo.model.mechanism.Mechanism.from_symbolic`); it must have the
            name the file gives (and its definition, if the file carries one). A plan of a
            mechanism with a definition (:meth:`~nonholo.model.mechanism.Mechanism.from_equations`,
            :meth:`~nonholo.model.mechanism.Mechanism.from_file`) carries it
            (``mechanism_definition``, ``mechanism_digest``) and loads without it.

        Returns
        -------
        PlanResult
            The plan, its claimed success judged from its controls replayed.

        Raises
        ------
        ValueError
            For a file that is not a plan file — malformed JSON, wrong or missing fields,
            numbers that disagree with the controls — saying what is wrong; for a
            mechanism not in the catalog, without ``mechanism``, saying to pass it.
        """
        d = plan_file.read(path)
        try:
            return cls.from_dict(d, mechanism)
        except RecursionError:
            raise ValueError(f"{path}: invalid plan file: nested too deeply") from None
        except ValueError as exc:
            raise ValueError(f"{path}: {exc}") from None

    # -- comparison and display --------------------------------------------------------
    def __eq__(self, other) -> bool:
        if not isinstance(other, PlanResult):
            return NotImplemented
        for f in fields(self):
            if f.name in ("kinematics", "made_by"):   # the mechanism: by name; a record of the code
                continue
            a, b = getattr(self, f.name), getattr(other, f.name)
            if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
                if a is None or b is None or not np.array_equal(a, b):
                    return False
            elif a != b:
                return False
        return True

    def __repr__(self) -> str:
        def num(x, fmt):
            return "n/a" if x is None else format(x, fmt)

        amount = self.kinematics.space.amount     # errors in the state's units (rad on SO(3))
        status = "success" if self.success else "FAILED"
        wall = "wall time not recorded" if self.seconds is None else f"{self.seconds * 1e3:.1f} ms"
        lines = [
            f"PlanResult({status}: {self.mechanism}, {self.method}/{self.strategy}, T={self.T:g} s, "
            f"{self.parametrisation!r}",
            f"  terminal error |l_T| = {amount(self.terminal_error, '.3e')} after "
            f"{self.iterations} iterations, min |Δ| = {num(self.min_delta, '.4f')}, {wall}",
        ]
        if self.replay_steps is not None:
            lines.append(f"  certified: physical controls replayed with {self.replay_steps} steps, "
                         f"error bound {amount(self.error_bound, '.1e')}, sensitivity "
                         f"{num(self.sensitivity, '.3g')}")
        if not self.success:
            lines.append(f"  reason: {self.reason}")
        return "\n".join(lines) + ")"


def _plain(x):
    """``x`` (a JSON-like value of a result: options, history) with NumPy scalars and
    arrays and tuples as the plain Python numbers and lists JSON writes."""
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.bool_):
        return bool(x)
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.floating):
        return float(x)
    return x


def part_errors(mechanism, errors) -> dict | None:
    """The terminal error by part a result records: ``errors`` for a mechanism with
    coordinates, ``None`` on SO(3) (where ``terminal_error`` is the rotation's alone).

    Parameters
    ----------
    mechanism : Mechanism
        The plan's mechanism.
    errors : dict or None
        The norms of the error's parts.

    Returns
    -------
    dict or None
        What :attr:`PlanResult.errors` holds.
    """
    return mechanism.space.recorded("coordinates", errors)
