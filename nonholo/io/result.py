"""The outcome of a motion-planning run: :class:`PlanResult`, with JSON save/load.

File format (``PlanResult.save``): one JSON object, ``"format": "nonholo.plan/3"``, with
the scalar fields, ``R0``/``Rd`` as nested 3×3 lists, the samples ``t`` (n), ``R``
(n×3×3), ``u`` (n×m) and ``delta`` (n, or null), ``history`` (a list of per-iteration
records) and ``controls``, the parametrisation (``{"kind": "fourier", "T", "harmonics",
"coeffs"}``, ``{"kind": "piecewise_constant", "T", "grid", "values"}`` or, for a motion
planned in frame coordinates (strategy ``"robust"``), ``{"kind": "frame", "T",
"mechanism", "steps", "R0", "frame": <the w parametrisation>}``, or, for a global route
(``"route": "global"``), ``{"kind": "stitched", "T", "pieces": [<one of those per hop>],
"waypoints"}``, unless the route was re-planned as one smooth control: then ``controls``
is that control and ``"stitched"`` the route's stitched control (absent otherwise); see :mod:`nonholo.controls.parametrisations`, :mod:`nonholo.motion.frame_controls` and
:mod:`nonholo.controls.stitched`) from which ``controls(t)`` is rebuilt (identically: the frame
motion's nodes are recomputed by the same kernel). Floats are written with
``repr`` precision, so a save/load round trip reproduces every number exactly. Quantities
that do not exist (``min_delta`` for a mechanism without a singular set, the terminal
error of a run stopped before any simulation) are ``null``/``None``, never NaN.

Saving is atomic (a complete new file replaces the old one, or the old one stays).
Loading checks the file (:meth:`PlanResult.from_dict`, :meth:`PlanResult.validate`): every
field's type and shape, finite numbers, and that the numbers agree with each other — the
stored samples are those of the stored controls replayed from ``R0`` (``n`` samples at the
integrator's step points ``t = kT/steps``; ``n = steps + 1`` when the motion reached
``T``, fewer when it stopped early, none when the planner refused the goal), ``u =
controls(t)``, ``delta = Δ(R)``, and ``terminal_error``, ``min_delta``, ``success``,
``mechanism``, ``method``, ``T``, ``steps`` agree with them. A file that does not is
rejected with a ``ValueError`` naming the field, so a plan cannot be changed — by a
damaged byte or by hand — without the change being noticed (fields that are records, not
results, are checked only for their type: ``reason``, ``history``, ``options``,
``seconds``, ``sensitivity``). Files written by earlier versions of the format load:
``nonholo.plan/2`` (no ``route``: local) and ``nonholo.plan/1`` (no certificates).
"""
from __future__ import annotations

import contextlib
import json
import os
import secrets
import stat
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

from ..certify import certificate as certify
from ..controls import stages
from ..controls.parametrisations import Controls, Fourier, PiecewiseConstant
from ..controls.stitched import Stitched
from ..model import catalog
from ..model.limits import LegLimits
from ..motion import playback
from ..motion.frame_controls import FrameControls, from_dict
from ..motion.retimed import Retimed
from ..numerics import kernels
from ..numerics.checks import MAX_STEPS, is_number
from ..spaces import so3
from ..spaces.state import distance as state_distance
from ..spaces.state import public as public_state
from . import csv_export as export

FORMAT = "nonholo.plan/3"
#: the format before global routes (``route``, stitched controls): still loaded
FORMAT_2 = "nonholo.plan/2"
#: the format before certificates (``replay_steps``, ``error_bound``): still loaded, checked
#: against the planner's own replay
FORMAT_1 = "nonholo.plan/1"
#: how a plan reached its goal: one local plan, or a global route of stitched hops
ROUTES = ("local", "global")


@dataclass(eq=False)
class PlanResult:
    """Result of :func:`nonholo.planning.api.plan`.

    - ``success``/``reason``: whether the plan is certified (:mod:`nonholo.certify.certificate`): its
      physical controls, replayed on ``replay_steps`` CF4 steps, end within
      ``terminal_error + error_bound ≤ tol`` of the goal and keep ``|Δ| ≥ delta_min`` —
      and why not.
    - ``terminal_error``: ``|l_T|`` (rad), ``[l_T] = log(R_T R_dᵀ)`` of the final
      trajectory (``None`` if nothing was simulated, e.g. a goal across ``Δ = 0``): of the
      certified replay for a success, of the planner's own trajectory otherwise.
    - ``error_bound``, ``replay_steps`` (a success only, else ``None``): the bound on the
      replay's own error at ``T`` (rad) and the CF4 steps of that replay; ``t``, ``R``,
      ``delta`` are then the replay's nodes at the plan's ``steps`` step points.
    - ``min_delta``: least ``|Δ|`` along the final trajectory, over every point where the
      integrator evaluated ``L`` (``None`` for mechanisms without a singular set, or if
      nothing was simulated).
    - ``iterations``: accepted θ-steps; ``history``: one record per accepted iteration
      (``iteration``, ``error``, ``step`` = ``γh`` used, ``min_delta``, ``phase`` =
      ``"initial"``/``"flow"``/``"newton"``, ``rejected`` = step halvings before it;
      strategy ``"robust"`` adds ``attempt``, the index of the initial guess, and one
      record with phase ``"restart"`` where a new guess starts).
    - ``t``, ``R``, ``u``, ``delta``: samples of the final trajectory at the integrator's
      step points (``R`` spatial-frame rotations, ``u`` in the mechanism's input units);
      ``steps`` is the number of integrator steps of that trajectory.
    - ``sensitivity``: ``max_t |Φ(T, t)|_F`` of the physical system along the planned
      motion — how much a perturbation of the orientation at ``t`` is amplified at ``T``
      when the planned ``u(t)`` is played open loop (``|Φ(T,T)|_F = √3``); computed when
      a converged plan is certified (``None`` otherwise).
    - ``parametrisation``: the planned control (a :class:`~nonholo.controls.parametrisations.Controls`:
      Fourier or grid controls of ``u``, or :class:`~nonholo.motion.frame_controls.FrameControls`
      wrapping those of the frame coordinates ``w``, or for a global route a
      :class:`~nonholo.controls.stitched.Stitched` of the hops' controls, with the route's
      waypoints and the hops' breakpoints); :meth:`controls` evaluates the physical
      inputs ``u(t)``.
    - ``route``: ``"local"`` (one plan from ``R0`` to ``Rd``) or ``"global"`` (hops along a
      path of orientations clear of ``Δ = 0``, :mod:`nonholo.planning.route`).
    - ``stitched``: for a global route re-planned as one smooth control (the controls),
      the stitched control of the route it was planned from (its hops, waypoints and
      hand-overs; a record: the certificate is the smooth control's); ``None`` otherwise.
      :attr:`hops` gives a global route's stitched control either way.
    - ``q``, ``q0``, ``qd``, ``errors`` (a mechanism whose state goes beyond SO(3), else
      ``None``): the coordinates at the samples ``(n, k)``, of the start and of the goal,
      and the terminal error by part, ``{"rotation": rad, "coordinates": units}``
      (:mod:`nonholo.spaces.state`; ``terminal_error`` is then the norm of the stacked error,
      which bounds both). ``R`` is the identity throughout for a state without
      orientation. :attr:`start`, :attr:`goal` and :meth:`state` give states as
      :func:`nonholo.plan` takes them.
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
    R0: np.ndarray
    Rd: np.ndarray
    steps: int
    seconds: float
    options: dict = field(default_factory=dict)
    sensitivity: float | None = None
    error_bound: float | None = None
    replay_steps: int | None = None
    route: str = "local"
    stitched: Stitched | None = None
    q: np.ndarray | None = None
    q0: np.ndarray | None = None
    qd: np.ndarray | None = None
    errors: dict | None = None

    @property
    def start(self):
        """The start as :func:`nonholo.plan` takes it (``R0``, ``q0`` or ``(R0, q0)``)."""
        return self._public(self.R0, self.q0)

    @property
    def goal(self):
        """The goal as :func:`nonholo.plan` takes it."""
        return self._public(self.Rd, self.qd)

    def state(self, k: int = -1):
        """Sample ``k`` of the trajectory as :func:`nonholo.plan` takes a state."""
        return self._public(self.R[k], None if self.q is None else self.q[k])

    def _public(self, R, q):
        if q is None:
            return R
        return public_state(catalog.get(self.mechanism), R, q)

    # -- controls ----------------------------------------------------------------------
    def controls(self, t) -> np.ndarray:
        """Planned input ``u(t)``: ``t`` of shape ``(n,)`` gives ``(n, m)`` (physical units)."""
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
        par = par.base if isinstance(par, Retimed) else par
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
        def arr(x):
            return None if x is None else np.asarray(x, dtype=float).tolist()

        return {
            "format": FORMAT,
            "success": bool(self.success),
            "reason": self.reason,
            "terminal_error": self.terminal_error,
            "min_delta": self.min_delta,
            "iterations": int(self.iterations),
            "history": self.history,
            "mechanism": self.mechanism,
            "method": self.method,
            "strategy": self.strategy,
            "T": self.T,
            "steps": int(self.steps),
            "seconds": self.seconds,
            "options": self.options,
            "sensitivity": self.sensitivity,
            "error_bound": self.error_bound,
            "replay_steps": None if self.replay_steps is None else int(self.replay_steps),
            "route": self.route,
            **({} if self.stitched is None else {"stitched": self.stitched.to_dict()}),
            **({} if self.q0 is None else {"q0": arr(self.q0), "qd": arr(self.qd), "q": arr(self.q),
                                           "errors": self.errors}),
            "R0": arr(self.R0),
            "Rd": arr(self.Rd),
            "controls": self.parametrisation.to_dict(),
            "t": arr(self.t),
            "R": arr(self.R),
            "u": arr(self.u),
            "delta": arr(self.delta),
        }

    @classmethod
    def from_dict(cls, d: dict) -> "PlanResult":
        """The result described by ``d`` (a plan file's object, see the module docstring),
        checked field by field and for consistency (:meth:`validate`); ``ValueError``
        naming the field otherwise."""
        if not isinstance(d, dict):
            raise ValueError(f"not a nonholo plan file: expected a JSON object, got {_json_type(d)}")
        if d.get("format") not in (FORMAT, FORMAT_2, FORMAT_1):
            raise ValueError(f"not a nonholo plan file (format {_short(d.get('format'))}, expected {FORMAT!r})")
        missing = [k for k in _REQUIRED if k not in d]
        if missing:
            raise ValueError(f"invalid plan: missing field{'s' if len(missing) > 1 else ''} "
                             f"{', '.join(map(repr, missing))}")
        unknown = [k for k in d if k not in _REQUIRED and k not in _OPTIONAL]
        if unknown:
            raise ValueError(f"invalid plan: unknown field{'s' if len(unknown) > 1 else ''} "
                             f"{', '.join(_short(k) for k in unknown)}")
        for key in ("route", "stitched"):
            if key in d and d["format"] != FORMAT:
                raise ValueError(f"invalid plan: {key!r} is set in a file of format {d['format']!r}, "
                                 "which has no global routes")
        d = {"options": {}, "sensitivity": None, "error_bound": None, "replay_steps": None,
             "route": "local", "stitched": None, **d}
        if not isinstance(d["success"], bool):
            raise ValueError(f"invalid plan: 'success' must be true or false, got {_short(d['success'])}")
        mechanism = _string(d, "mechanism")
        try:
            mech = catalog.get(mechanism)
        except ValueError as exc:
            raise ValueError(f"invalid plan: 'mechanism': {exc}") from None
        par = _controls(d["controls"], mech)
        stitched = None
        if d["stitched"] is not None:
            if not isinstance(d["stitched"], dict) or d["stitched"].get("kind") != Stitched.kind:
                _fail("stitched", f"must be stitched controls ({{\"kind\": \"stitched\", ...}}) or null")
            stitched = _controls(d["stitched"], mech, "stitched")
        m = par.n_inputs
        options = d["options"]
        if not isinstance(options, dict):
            raise ValueError(f"invalid plan: 'options' must be an object, got {_json_type(options)}")
        history = d["history"]
        if not isinstance(history, list) or not all(isinstance(r, dict) for r in history):
            raise ValueError("invalid plan: 'history' must be a list of objects")
        delta = d["delta"]
        res = cls(
            success=d["success"], reason=_string(d, "reason", empty=True),
            terminal_error=_number(d, "terminal_error", null=True),
            min_delta=_number(d, "min_delta", null=True),
            iterations=_integer(d, "iterations", minimum=0), history=list(history),
            t=_array(d["t"], "t", (None,)), R=_array(d["R"], "R", (None, 3, 3)),
            u=_array(d["u"], "u", (None, m)),
            delta=None if delta is None else _array(delta, "delta", (None,)),
            parametrisation=par, mechanism=mechanism, method=_string(d, "method"),
            strategy=_string(d, "strategy"), T=_number(d, "T"),
            R0=_array(d["R0"], "R0", (3, 3)), Rd=_array(d["Rd"], "Rd", (3, 3)),
            steps=_integer(d, "steps", minimum=1), seconds=_number(d, "seconds"),
            options=dict(options), sensitivity=_number(d, "sensitivity", null=True),
            error_bound=_number(d, "error_bound", null=True),
            replay_steps=None if d["replay_steps"] is None else _integer(d, "replay_steps", minimum=2),
            route=_string(d, "route"), stitched=stitched,
            **({} if not mech.beyond_so3 else _coordinates(d, mech)))
        _Validation(res, legacy=d["format"] == FORMAT_1).run()
        return res

    def validate(self) -> "PlanResult":
        """Check that the result is one :func:`nonholo.plan` can have produced: types,
        shapes and finiteness of every field, and consistency — the controls replayed from
        ``R0`` pass through the stored samples ``R`` within ``REPLAY_TOL`` (a certified
        plan: the physical inputs on ``replay_steps`` CF4 steps, the replay of
        :mod:`nonholo.certify.certificate`; otherwise by the integrator that planned them, the physical
        system for controls of ``u``, the frame system for
        :class:`~nonholo.motion.frame_controls.FrameControls`), ``u = controls(t)``, ``Δ`` of the samples,
        ``terminal_error`` and ``min_delta`` agree with them, ``error_bound`` is at least
        the replay's Richardson estimate, a success is certified (``terminal_error +
        error_bound ≤ tol``), and the labels (mechanism, method, strategy, ``T``,
        ``steps``, ``R0``) agree with the controls.
        Returns ``self``; raises ``ValueError`` naming the field otherwise."""
        _Validation(self).run()
        return self

    def save(self, path) -> Path:
        """Write the result as JSON (format ``nonholo.plan/3``, see the module docstring).

        Atomic: the text goes to a temporary file in the same directory, flushed and
        synced to disk, which then replaces ``path`` (a symbolic link is followed, its
        target replaced). If anything fails (``OSError``, e.g. a full disk) the error
        propagates, the temporary file is removed and an existing ``path`` is untouched.
        A result holding a non-finite number, which JSON cannot, raises ``ValueError``
        before anything is written.
        """
        path = Path(path)
        text = json.dumps(self.to_dict(), allow_nan=False, indent=1)
        target = Path(os.path.realpath(path)) if path.is_symlink() else path
        _write_atomic(target, text.encode("utf-8"))
        return path

    def to_csv(self, path, rate: float = export.DEFAULT_RATE) -> Path:
        """Write the motion sampled at ``rate`` Hz as CSV for an actuator controller: ``t``,
        leg lengths ``l_i`` and speeds ``dl_i_dt`` (geometry units), inputs ``u_i``, the
        orientation as a unit quaternion ``qx, qy, qz, qw`` (scalar last) and ``delta``
        (see :mod:`nonholo.io.csv_export`). A failed plan or a bad ``rate`` raises ``ValueError``
        before anything is written; the file is written atomically, like :meth:`save`."""
        path = Path(path)
        text = export.csv_text(self, rate)
        target = Path(os.path.realpath(path)) if path.is_symlink() else path
        _write_atomic(target, text.encode("utf-8"))
        return path

    @classmethod
    def load(cls, path) -> "PlanResult":
        """Read and check a result written by :meth:`save` (see :meth:`from_dict`); a file
        that is not one — malformed JSON, wrong or missing fields, numbers that disagree
        with the controls — raises ``ValueError`` saying what is wrong. A UTF-8 byte-order
        mark is accepted."""
        raw = Path(path).read_bytes()
        try:
            text = raw.decode("utf-8-sig")
        except UnicodeDecodeError as exc:
            raise ValueError(f"{path}: not a nonholo plan file: not UTF-8 text ({exc.reason} at byte "
                             f"{exc.start})") from None
        try:
            d = json.loads(text, object_pairs_hook=_unique_keys)
        except RecursionError:
            raise ValueError(f"{path}: not a nonholo plan file: JSON nested too deeply") from None
        except ValueError as exc:      # json.JSONDecodeError, duplicate keys, huge integers
            raise ValueError(f"{path}: not a nonholo plan file: {exc}") from None
        try:
            return cls.from_dict(d)
        except RecursionError:
            raise ValueError(f"{path}: invalid plan file: nested too deeply") from None
        except ValueError as exc:
            raise ValueError(f"{path}: {exc}") from None

    # -- comparison and display --------------------------------------------------------
    def __eq__(self, other) -> bool:
        if not isinstance(other, PlanResult):
            return NotImplemented
        for f in fields(self):
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

        status = "success" if self.success else "FAILED"
        lines = [
            f"PlanResult({status}: {self.mechanism}, {self.method}/{self.strategy}, T={self.T:g} s, "
            f"{self.parametrisation!r}",
            f"  terminal error |l_T| = {num(self.terminal_error, '.3e')} rad after "
            f"{self.iterations} iterations, min |Δ| = {num(self.min_delta, '.4f')}, "
            f"{self.seconds * 1e3:.1f} ms",
        ]
        if self.replay_steps is not None:
            lines.append(f"  certified: physical controls replayed with {self.replay_steps} steps, "
                         f"error bound {num(self.error_bound, '.1e')} rad, sensitivity "
                         f"{num(self.sensitivity, '.3g')}")
        if not self.success:
            lines.append(f"  reason: {self.reason}")
        return "\n".join(lines) + ")"


# ------------------------------------------------------------------------------------------
# Plan files: fields, parsing, consistency
# ------------------------------------------------------------------------------------------

#: the fields of a plan file
_REQUIRED = ("format", "success", "reason", "terminal_error", "min_delta", "iterations", "history",
             "mechanism", "method", "strategy", "T", "steps", "seconds", "R0", "Rd", "controls",
             "t", "R", "u", "delta")
#: fields the first files of the format did not have (absent: ``{}`` and ``null``)
_OPTIONAL = ("options", "sensitivity", "error_bound", "replay_steps", "route", "stitched",
             "q0", "qd", "q", "errors")
#: the planner's methods, by the kind of the parametrisation each plans with
_METHOD_OF_KIND = {"fourier": "parametric", "piecewise_constant": "nonparametric"}
#: the fields of each kind of ``controls``
_CONTROL_FIELDS = {"fourier": ("kind", "T", "harmonics", "coeffs"),
                   "piecewise_constant": ("kind", "T", "grid", "values"),
                   "frame": ("kind", "T", "mechanism", "steps", "R0", "frame"),
                   "stitched": ("kind", "T", "pieces", "waypoints"),
                   "retimed": ("kind", "T", "leg_speed", "nodes", "mechanism", "R0", "base")}

#: stored samples ``R`` against the controls replayed from ``R0`` by the planning
#: integrator (largest entry difference, ≈ rad), and ``terminal_error`` against
#: ``|log(R[-1] Rdᵀ)|`` (rad). Replays on this machine reproduce both exactly; the
#: tolerance leaves room for another machine's rounding, amplified along the motion.
REPLAY_TOL = 1e-9
#: stored ``u`` against ``controls(t)``, ``delta`` against ``Δ(R)`` and ``min_delta``
#: against the samples, relative to ``max(1, largest value)``
VALUE_RTOL = 1e-12
#: ``t`` against the integrator's step points ``k T/steps``, relative to ``T``
TIME_RTOL = 1e-12
#: the legs' speeds at the samples of a success against its ``leg_speed``, relative (the
#: re-timing's spline moves them off the bound by less)
SPEED_RTOL = 1e-6
#: ``R0``, ``Rd`` and the samples ``R``: ``|RᵀR − I| ≤`` this (as :func:`nonholo.plan` accepts)
ROTATION_TOL = 1e-9


def _fail(field: str, message: str):
    raise ValueError(f"invalid plan: {field!r} {message}")


def _coordinates(d: dict, mech) -> dict:
    """The coordinate fields of a plan of a mechanism whose state goes beyond SO(3)."""
    k = mech.n_coordinates
    missing = [key for key in ("q0", "qd", "q") if key not in d]
    if missing:
        _fail(missing[0], f"is missing: mechanism {mech.name!r} has coordinates ({', '.join(mech.coordinates)})")
    errors = d.get("errors")
    if errors is not None and not (isinstance(errors, dict) and all(is_number(v) for v in errors.values())):
        _fail("errors", "must be an object of numbers or null")
    return {"q0": _array(d["q0"], "q0", (k,)), "qd": _array(d["qd"], "qd", (k,)),
            "q": _array(d["q"], "q", (None, k)), "errors": errors}


def _short(x) -> str:
    try:
        text = repr(x)
    except ValueError:             # an integer too long to print
        return "a very large integer"
    return text if len(text) <= 60 else text[:57] + "..."


def _json_type(x) -> str:
    if x is None:
        return "null"
    if isinstance(x, bool):
        return str(x).lower()
    if isinstance(x, dict):
        return "an object"
    if isinstance(x, (list, tuple)):
        return "an array"
    if isinstance(x, str):
        return f"the string {_short(x)}"
    return _short(x)


def _unique_keys(pairs):
    """``object_pairs_hook`` of :func:`json.loads`: an object with a key twice is an error."""
    d = {}
    for k, v in pairs:
        if k in d:
            raise ValueError(f"duplicate key {_short(k)} in a JSON object")
        d[k] = v
    return d


def _string(d: dict, key: str, empty: bool = False, where: str = "") -> str:
    v = d[key]
    if not isinstance(v, str) or (not v and not empty):
        _fail(where + key, f"must be a {'' if empty else 'non-empty '}string, got {_json_type(v)}")
    return v


def _number(d: dict, key: str, null: bool = False, where: str = "") -> float | None:
    v = d[key]
    if v is None and null:
        return None
    if not is_number(v):
        _fail(where + key, f"must be a number{' or null' if null else ''}, got {_json_type(v)}")
    try:
        x = float(v)
    except OverflowError:
        x = float("inf")
    if not np.isfinite(x):
        _fail(where + key, f"must be finite{' (or null)' if null else ''}, got {v!r}")
    return x


def _integer(d: dict, key: str, minimum: int, where: str = "") -> int:
    v = d[key]
    if not isinstance(v, (int, np.integer)) or isinstance(v, (bool, np.bool_)) or v < minimum:
        _fail(where + key, f"must be an integer >= {minimum}, got {_json_type(v)}")
    if key == "steps" and v > MAX_STEPS:
        _fail(where + key, f"must be at most {MAX_STEPS}, got {v}")
    return int(v)


def _shape_text(shape) -> str:
    return "(" + ", ".join("n" if s is None else str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"


def _array(value, field: str, shape: tuple) -> np.ndarray:
    """``value`` (nested lists of numbers) as a float array of ``shape`` (``None``: any
    length); ``ValueError`` naming ``field`` for anything else (non-finite entries are
    left to :meth:`PlanResult.validate`)."""
    bad = f"must be an array of numbers of shape {_shape_text(shape)}"
    if isinstance(value, np.ndarray):
        if value.dtype.kind not in "iuf" or value.ndim != len(shape):
            _fail(field, bad)
        a = value.astype(float)
    else:
        flat = []
        dims = list(shape)
        stack = [(value, 0)]
        while stack:
            x, k = stack.pop()
            if k == len(shape):
                if not is_number(x):
                    _fail(field, f"{bad}: found {_json_type(x)}")
                flat.append(x)
                continue
            if not isinstance(x, (list, tuple)):
                _fail(field, f"{bad}: found {_json_type(x)}")
            if dims[k] is None:
                dims[k] = len(x)
            if len(x) != dims[k]:
                _fail(field, f"{bad}: got a row of length {len(x)} where {dims[k]} were expected")
            stack.extend((y, k + 1) for y in reversed(x))
        dims = [0 if s is None else s for s in dims]
        try:
            a = np.array(flat, dtype=float).reshape(dims)
        except OverflowError:
            _fail(field, "has an integer too large for a float")
    if any(s is not None and s != a.shape[i] for i, s in enumerate(shape)):
        _fail(field, f"{bad}, got {a.shape}")
    return a


def _rotation(R, field: str) -> None:
    try:
        so3.check_rotation(R, repr(field), ROTATION_TOL)
    except ValueError as exc:
        raise ValueError(f"invalid plan: {exc}") from None


def _fields(d: dict, expected: tuple, where: str) -> None:
    missing = [k for k in expected if k not in d]
    unknown = [k for k in d if k not in expected]
    if missing:
        _fail(where, f"lacks the field{'s' if len(missing) > 1 else ''} {', '.join(map(repr, missing))}")
    if unknown:
        _fail(where, f"has unknown field{'s' if len(unknown) > 1 else ''} {', '.join(_short(k) for k in unknown)}")


def _parametrisation(d, where: str, m: int) -> None:
    """Check the description of Fourier or grid controls with ``m`` inputs (``where``: its field)."""
    if not isinstance(d, dict):
        _fail(where, f"must be an object, got {_json_type(d)}")
    kind = d.get("kind")
    if kind not in _METHOD_OF_KIND:
        _fail(where + ".kind", f"must be one of {', '.join(map(repr, _METHOD_OF_KIND))}, got {_short(kind)}")
    _fields(d, _CONTROL_FIELDS[kind], where)
    T = _number(d, "T", where=where + ".")
    if T <= 0:
        _fail(where + ".T", f"must be positive, got {T}")
    if kind == "fourier":
        K = _integer(d, "harmonics", 1, where=where + ".")
        _array(d["coeffs"], where + ".coeffs", (m, 2 * K + 1))
    else:
        g = _integer(d, "grid", 1, where=where + ".")
        _array(d["values"], where + ".values", (g, m))


def _physical(d, mech, where: str) -> None:
    """Check the description of physical controls (a parametrisation or frame controls)."""
    m = mech.n_inputs
    if isinstance(d, dict) and d.get("kind") == FrameControls.kind:
        _fields(d, _CONTROL_FIELDS["frame"], where)
        _parametrisation(d["frame"], where + ".frame", m)
        if _number(d, "T", where=where + ".") != d["frame"]["T"]:
            _fail(where + ".T", f"differs from the frame controls' T ({d['frame']['T']!r})")
        if _string(d, "mechanism", where=where + ".") != mech.name:
            _fail(where + ".mechanism", f"is {d['mechanism']!r}, but the plan's 'mechanism' is {mech.name!r}")
        _integer(d, "steps", 1, where=where + ".")
        _rotation(_array(d["R0"], where + ".R0", (3, 3)), where + ".R0")
    else:
        _parametrisation(d, where, m)


def _controls(d, mech, where: str = "controls", timed: bool = True) -> Controls | FrameControls | Stitched | Retimed:
    """The ``controls`` field (or another field ``where`` holding controls) of a plan of
    mechanism ``mech``, checked, as an object (``timed``: may be re-timed)."""
    if isinstance(d, dict) and d.get("kind") == Retimed.kind and timed:
        _fields(d, _CONTROL_FIELDS["retimed"], where)
        for key in ("T", "leg_speed"):
            if _number(d, key, where=f"{where}.") <= 0:
                _fail(f"{where}.{key}", f"must be positive, got {d[key]}")
        _integer(d, "nodes", 2, where=f"{where}.")
        if _string(d, "mechanism", where=f"{where}.") != mech.name:
            _fail(f"{where}.mechanism", f"is {d['mechanism']!r}, but the plan's 'mechanism' is {mech.name!r}")
        _rotation(_array(d["R0"], f"{where}.R0", (3, 3)), f"{where}.R0")
        _controls(d["base"], mech, f"{where}.base", timed=False)
    elif isinstance(d, dict) and d.get("kind") == Stitched.kind:
        _fields(d, _CONTROL_FIELDS["stitched"] + (("coordinates",) if mech.beyond_so3 else ()), where)
        if _number(d, "T", where=f"{where}.") <= 0:
            _fail(f"{where}.T", f"must be positive, got {d['T']}")
        pieces = d["pieces"]
        if not isinstance(pieces, list) or not pieces:
            _fail(f"{where}.pieces", "must be a non-empty list")
        for i, p in enumerate(pieces):
            _physical(p, mech, f"{where}.pieces[{i}]")
        W = _array(d["waypoints"], f"{where}.waypoints", (len(pieces) + 1, 3, 3))
        for i, R in enumerate(W):
            _rotation(R, f"{where}.waypoints[{i}]")
        if mech.beyond_so3:
            _array(d["coordinates"], f"{where}.coordinates", (len(pieces) + 1, mech.n_coordinates))
    else:
        _physical(d, mech, where)
    try:
        return from_dict(d)
    except (ValueError, TypeError, KeyError, IndexError, AttributeError) as exc:
        _fail(where, f"cannot be rebuilt: {exc}")


def _scan_finite(value, field: str) -> None:
    """Every number inside the JSON value ``value`` is finite (iteratively: no recursion)."""
    stack = [value]
    while stack:
        x = stack.pop()
        if isinstance(x, dict):
            stack.extend(x.values())
        elif isinstance(x, (list, tuple)):
            stack.extend(x)
        elif is_number(x) and not np.isfinite(float(x)):
            _fail(field, f"contains a non-finite number ({x})")


def _write_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to a new file in ``path``'s directory, sync it, then rename it to
    ``path``; on failure remove it (``path`` is untouched) and re-raise."""
    directory = path.parent
    for _ in range(100):
        tmp = directory / f".{path.name}.{secrets.token_hex(4)}.tmp"
        try:
            # mode 0o666 less the umask, as a file created by open(path, "w")
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
        except FileExistsError:
            continue
        break
    else:
        raise FileExistsError(f"no free temporary file name in {directory}")
    try:
        with os.fdopen(fd, "wb") as f:
            try:
                mode = stat.S_IMODE(os.stat(path).st_mode)
            except OSError:
                mode = None                      # no file to replace: keep the new file's mode
            if mode is not None and hasattr(os, "fchmod"):
                os.fchmod(f.fileno(), mode)      # replacing a file keeps its permissions
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    # make the rename itself durable (POSIX; where a directory cannot be opened, skip)
    with contextlib.suppress(OSError, AttributeError):
        dfd = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(dfd)
        finally:
            os.close(dfd)


class _Validation:
    """The checks of :meth:`PlanResult.validate`, on one result."""

    def __init__(self, result: PlanResult, legacy: bool = False):
        self.r = result
        #: a file of format ``nonholo.plan/1`` (no certificates)
        self.legacy = legacy

    def run(self) -> None:
        r = self.r
        self.scalars()
        mech = self.labels()
        n = self.arrays(mech)
        complete = n == r.steps + 1
        if n == 0:
            self.nothing_simulated()
            return
        if not np.array_equal(r.R[0], r.R0):
            _fail("R", "starts elsewhere than R0 (R[0] != R0)")
        if mech.beyond_so3 and not np.array_equal(r.q[0], r.q0):
            _fail("q", "starts elsewhere than q0 (q[0] != q0)")
        self.replay(mech, n)
        self.values(mech, n, complete)

    # -- field by field --------------------------------------------------------------------
    def scalars(self) -> None:
        r = self.r
        if not isinstance(r.success, (bool, np.bool_)):
            _fail("success", f"must be true or false, got {_json_type(r.success)}")
        v = vars(r)
        _string(v, "reason", empty=True)
        for key in ("mechanism", "method", "strategy"):
            _string(v, key)
        _integer(v, "iterations", 0)
        _integer(v, "steps", 1)
        if _number(v, "T") <= 0:
            _fail("T", f"must be a positive time (s), got {r.T}")
        if _number(v, "seconds") < 0:
            _fail("seconds", f"must be >= 0, got {r.seconds}")
        for key in ("terminal_error", "sensitivity", "error_bound"):
            x = _number(v, key, null=True)
            if x is not None and x < 0:
                _fail(key, f"must be >= 0 (or null), got {x}")
        _number(v, "min_delta", null=True)
        if r.replay_steps is not None:
            M = _integer(v, "replay_steps", 2)
            if M % r.steps or M % 2:
                _fail("replay_steps", f"({M}) must be an even multiple of steps ({r.steps})")
            if r.error_bound is None:
                _fail("error_bound", "is null, but the plan has a certified replay (replay_steps)")
        elif r.error_bound is not None:
            _fail("replay_steps", "is null, but the plan has an error bound (error_bound)")
        if self.legacy and r.replay_steps is not None:
            _fail("replay_steps", f"is set in a file of format {FORMAT_1!r}, which has no certificates")
        if not isinstance(r.history, list) or not all(isinstance(h, dict) for h in r.history):
            _fail("history", "must be a list of objects (one per iteration)")
        if not isinstance(r.options, dict):
            _fail("options", f"must be an object, got {_json_type(r.options)}")
        _scan_finite(r.history, "history")
        _scan_finite(r.options, "options")
        for key in ("tol", "delta_min"):
            if key in r.options and not is_number(r.options[key]):
                _fail("options", f"has {key} = {_short(r.options[key])}, not a number")

    def labels(self):
        """The mechanism; ``method``, ``strategy``, ``T``, ``steps``, ``R0`` against the controls."""
        r = self.r
        try:
            mech = catalog.get(r.mechanism)
        except ValueError as exc:
            _fail("mechanism", f"is unknown: {exc}")
        par = r.parametrisation
        if isinstance(par, Retimed):
            self.retimed(par, mech)
            par = par.base
        if r.route not in ROUTES:
            _fail("route", f"must be one of {', '.join(map(repr, ROUTES))}, got {_short(r.route)}")
        stitched = isinstance(par, Stitched)
        if r.stitched is not None:
            if not isinstance(r.stitched, Stitched):
                _fail("stitched", f"must be stitched controls or None, got {type(r.stitched).__name__}")
            if stitched:
                _fail("stitched", "is set, but the controls are stitched themselves (a smoothed route's "
                                  "controls are one piece)")
        routed = stitched or r.stitched is not None
        if routed != (r.route == "global"):
            _fail("route", f"is {r.route!r}, but the controls are "
                           f"{'stitched' if stitched else 'one piece'}"
                           f"{' with the stitched route they were smoothed from' if r.stitched is not None else ''}"
                           f" (route {'global' if routed else 'local'!r})")
        if r.method not in _METHOD_OF_KIND.values():
            _fail("method", f"must be one of {', '.join(map(repr, _METHOD_OF_KIND.values()))}, got {r.method!r}")
        if par.n_inputs != mech.n_inputs:
            _fail("controls", f"have {par.n_inputs} inputs, mechanism {mech.name!r} has {mech.n_inputs}")
        if r.parametrisation.T != r.T:
            _fail("T", f"is {r.T!r}, the controls are defined on [0, {r.parametrisation.T!r}]")
        hops = r.hops                   # the route's stitched control: the controls, or their record
        if hops is not None:
            where = "controls" if stitched else "stitched"
            if not r.success or r.replay_steps is None:
                _fail("route", "is 'global', which only a certified success has")
            if hops.T != par.T:
                _fail(where, f"is defined on [0, {hops.T!r}], the plan on [0, {par.T!r}]")
            if not np.array_equal(hops.waypoints[0], r.R0):
                _fail("R0", f"differs from the first waypoint of the stitched controls ({where!r})")
            for i, piece in enumerate(hops.pieces):
                self.piece(piece, mech, f"{where}.pieces[{i}]", None, None)
        if stitched:
            if r.steps % par.grid:
                _fail("steps", f"({r.steps}) must be a multiple of the stitched controls' grid ({par.grid})")
        else:
            self.piece(par, mech, "controls", r.steps, r.R0)
        return mech

    def retimed(self, par: Retimed, mech) -> None:
        """Re-timed controls: of a certified success's path, from its ``R0``, of its
        mechanism, under the ``leg_speed`` the options record."""
        r = self.r
        if r.replay_steps is None:
            _fail("controls", "are re-timed, which only the path of a certified plan can be")
        if par.mechanism.name != r.mechanism:
            _fail("mechanism", f"is {r.mechanism!r}, the re-timed controls are of {par.mechanism.name!r}")
        if not np.array_equal(par.R0, r.R0):
            _fail("R0", "differs from the re-timed controls' R0")
        if r.options.get("leg_speed") != par.leg_speed:
            _fail("options", f"record leg_speed = {_short(r.options.get('leg_speed'))}, the controls "
                             f"are re-timed for {par.leg_speed!r}")

    def piece(self, par, mech, where: str, steps: int | None, R0) -> None:
        """One piece of physical controls against the plan's ``method``, ``strategy``,
        ``mechanism`` (and ``steps``, ``R0``, when the piece is the whole plan)."""
        r = self.r
        frame = isinstance(par, FrameControls)
        inner = par.frame if frame else par
        if not isinstance(inner, (Fourier, PiecewiseConstant)):
            _fail(where, f"must be Fourier, piecewise-constant or frame controls, got {type(par).__name__}")
        if r.method != _METHOD_OF_KIND[inner.kind]:
            _fail("method", f"is {r.method!r}, but the controls are {inner.kind!r} "
                            f"(method {_METHOD_OF_KIND[inner.kind]!r})")
        if frame:
            if par.mechanism.name != r.mechanism:
                _fail("mechanism", f"is {r.mechanism!r}, the frame controls are of {par.mechanism.name!r}")
            if steps is not None and par.steps != steps:
                _fail("steps", f"is {steps}, the frame controls replay {par.steps} steps")
            if R0 is not None and not np.array_equal(par.R0, R0):
                _fail("R0", "differs from the frame controls' R0")
            if r.strategy == "paper":
                _fail("strategy", "is 'paper', which plans the physical inputs, but the controls are "
                                  "frame controls (strategy 'robust')")
        if steps is not None and isinstance(inner, PiecewiseConstant) and steps % inner.grid:
            _fail("steps", f"({steps}) must be a multiple of the controls' grid ({inner.grid})")

    def arrays(self, mech) -> int:
        """Shapes and finiteness of ``R0``, ``Rd``, ``t``, ``R``, ``u``, ``delta``; returns ``n``."""
        r = self.r
        for key in ("R0", "Rd"):
            _rotation(getattr(r, key), key)
        arrays = {"t": r.t, "R": r.R, "u": r.u, "delta": r.delta}
        for key, a in arrays.items():
            if key == "delta" and a is None:
                continue
            if not isinstance(a, np.ndarray) or a.dtype.kind != "f":
                _fail(key, "must be a float array")
            if not np.all(np.isfinite(a)):
                _fail(key, "has non-finite entries (NaN or infinity)")
        n = r.t.shape[0] if r.t.ndim == 1 else -1
        if n < 0:
            _fail("t", f"must have shape (n,), got {r.t.shape}")
        if mech.beyond_so3:
            if r.q is None or r.q0 is None or r.qd is None:
                _fail("q", f"must be set: mechanism {mech.name!r} has coordinates")
            arrays["q"] = r.q
            for key in ("q", "q0", "qd"):
                if not np.all(np.isfinite(getattr(r, key))):
                    _fail(key, "has non-finite entries (NaN or infinity)")
        elif r.q is not None or r.q0 is not None or r.qd is not None:
            _fail("q", f"must be null: mechanism {mech.name!r} has no coordinates")
        for key, shape in (("R", (n, 3, 3)), ("u", (n, mech.n_inputs)), ("q", (n, mech.n_coordinates))):
            if key not in arrays:
                continue
            if arrays[key].shape != shape:
                _fail(key, f"must have shape {shape} (n = {n} samples in t), got {arrays[key].shape}")
        if mech.has_singular_set:
            if r.delta is None or r.delta.shape != (n,):
                _fail("delta", f"must have shape ({n},): mechanism {mech.name!r} has a singular set, "
                               f"got {'null' if r.delta is None else r.delta.shape}")
        elif r.delta is not None:
            _fail("delta", f"must be null: mechanism {mech.name!r} has no singular set")
        if n > r.steps + 1:
            _fail("t", f"has {n} samples, more than the {r.steps + 1} step points of {r.steps} steps")
        par = r.parametrisation
        if isinstance(par, Retimed):
            # the planned step points, at their re-timed instants
            tau = np.arange(n) * (par.base.T / r.steps)
            if n == r.steps + 1:
                tau[-1] = par.base.T
            expected = par.time(tau)
            expected[0] = 0.0
        else:
            expected = np.arange(n) * (r.T / r.steps)
        if n == r.steps + 1:
            expected[-1] = r.T
        if n and np.max(np.abs(r.t - expected)) > TIME_RTOL * r.T:
            k = int(np.argmax(np.abs(r.t - expected)))
            what = ("the re-timed instants of the step points" if isinstance(par, Retimed)
                    else "the integrator's step points k·T/steps")
            _fail("t", f"must hold {what}: t[{k}] = {r.t[k]!r}, expected {expected[k]!r}")
        if n:
            err = np.max(np.abs(np.einsum("nji,njk->nik", r.R, r.R) - np.eye(3)), axis=(1, 2))
            k = int(np.argmax(err))
            if err[k] > ROTATION_TOL:
                _fail("R", f"sample {k} is not a rotation: |RᵀR - I| = {err[k]:.3g}")
            det = np.linalg.det(r.R)
            if np.any(det < 0):
                _fail("R", f"sample {int(np.argmax(det < 0))} is a reflection (det = -1)")
        return n

    def nothing_simulated(self) -> None:
        """A plan without a trajectory (refused before any simulation)."""
        r = self.r
        if r.success:
            _fail("success", "is true, but nothing was simulated (no trajectory)")
        for key in ("terminal_error", "min_delta", "sensitivity", "error_bound", "replay_steps"):
            if getattr(r, key) is not None:
                _fail(key, "must be null when nothing was simulated (no trajectory)")
        if r.iterations or r.history:
            _fail("iterations", "must be 0, with an empty history, when nothing was simulated")
        if isinstance(r.parametrisation, FrameControls):
            _fail("controls", "are frame controls, but nothing was simulated (no trajectory)")

    # -- against the controls --------------------------------------------------------------
    def replay(self, mech, n: int) -> None:
        """The controls replayed from ``R0`` pass through the stored samples; keeps the
        least ``sgnΔ`` over the replay's evaluation points. A certified plan: the
        physical inputs on ``replay_steps`` steps (:func:`nonholo.motion.playback.replay`), whose
        Richardson estimate ``error_bound`` must cover; otherwise by the integrator that
        planned them, the physical system's for controls of ``u``, the frame system's for
        frame controls."""
        r = self.r
        par = r.parametrisation
        if isinstance(par, Retimed):
            par = par.base             # the same path: replayed as planned
        T = par.T
        frame = isinstance(par, FrameControls) and r.replay_steps is None
        q0 = r.q0 if mech.beyond_so3 else None
        if mech.has_singular_set:
            self.sign = float(np.sign(mech.delta_samples(r.R0[None], None if q0 is None else q0[None])[0]))
            if self.sign == 0.0:
                _fail("R0", "lies on the singular surface Δ = 0")
        else:
            self.sign = 1.0
        if r.replay_steps is not None:
            if n != r.steps + 1:
                _fail("replay_steps", f"is set, but the trajectory stops at t = {r.t[-1]:.6g} s < T")
            M = r.replay_steps
            U = np.ascontiguousarray(stages.stage_table(par, M))
            R_M, done, dmin, Q_M = playback.replay(r.R0, par, T, mech, M, self.sign, U, q0)
            Rs, Qs = R_M[::M // r.steps], Q_M[::M // r.steps]
            done //= M // r.steps
        else:
            kern = mech.kernels(frame=frame)
            U = np.ascontiguousarray(stages.stage_table(par.frame if frame else par, r.steps)[:n - 1])
            Rs, Qs = np.empty((n, 3, 3)), np.empty((n, mech.n_coordinates))
            done, dmin, _ = kern.forward(np.ascontiguousarray(r.R0, dtype=float),
                                         np.zeros(0) if q0 is None else np.ascontiguousarray(q0),
                                         U, T / r.steps, self.sign, -np.inf, Rs, Qs)
        if done < n - 1:
            _fail("R", f"goes on to t = {r.t[-1]:.6g} s, but the controls replayed from R0 stop at "
                       f"t = {r.t[done]:.6g} s (non-finite angular velocity)")
        dev = np.max(np.abs(Rs - r.R), axis=(1, 2))
        k = int(np.argmax(dev))
        if not dev[k] <= REPLAY_TOL:
            system = "frame system" if frame else "system"
            steps = r.steps if r.replay_steps is None else r.replay_steps
            _fail("R", f"disagrees with the controls replayed from R0 (the {system} of "
                       f"{mech.name!r}, {steps} steps): by {dev[k]:.3g} at t = {r.t[k]:.6g} s "
                       f"(tolerance {REPLAY_TOL:g})")
        if mech.beyond_so3:
            dev = np.max(np.abs(Qs - r.q), axis=1)
            k = int(np.argmax(dev))
            if not dev[k] <= REPLAY_TOL:
                _fail("q", f"disagrees with the controls replayed from (R0, q0) by {dev[k]:.3g} at "
                           f"t = {r.t[k]:.6g} s (tolerance {REPLAY_TOL:g})")
        self.dmin = float(dmin)
        if r.replay_steps is not None:
            R_half, _, _, Q_half = playback.replay(r.R0, par, T, mech, M // 2, self.sign, stages.halve(U), q0)
            est = certify.richardson(R_M[-1], R_half[-1], mech, Q_M[-1], Q_half[-1])
            if not r.error_bound >= est * (1.0 - 1e-9):
                _fail("error_bound", f"({r.error_bound:.3g}) is below the replay's own error "
                                     f"estimate ({est:.3g} rad with {M} steps)")

    def values(self, mech, n: int, complete: bool) -> None:
        """``u``, ``delta``, ``terminal_error``, ``min_delta`` and ``success`` against the samples."""
        r = self.r
        u = np.asarray(r.parametrisation(r.t), dtype=float).reshape(n, mech.n_inputs)
        dev = np.max(np.abs(u - r.u))
        if not dev <= VALUE_RTOL * max(1.0, float(np.max(np.abs(u)))):
            _fail("u", f"disagrees with controls(t) by {dev:.3g}")
        if mech.has_singular_set:
            d = mech.delta_samples(r.R, r.q)
            dev = np.max(np.abs(d - r.delta))
            if not dev <= VALUE_RTOL * max(1.0, float(np.max(np.abs(d)))):
                _fail("delta", f"disagrees with Δ(R) of the samples by {dev:.3g}")
        if complete:
            if r.terminal_error is None:
                _fail("terminal_error", "is null, but the trajectory reaches T")
            if mech.beyond_so3:
                err = state_distance(mech, r.R[-1], r.q[-1], r.Rd, r.qd)
                what = "the distance of the last sample from the goal"
            else:
                err = float(kernels.log_error(np.ascontiguousarray(r.R[-1]), np.ascontiguousarray(r.Rd))[1])
                what = "|log(R[-1] Rdᵀ)|"
            if not abs(err - r.terminal_error) <= REPLAY_TOL:
                _fail("terminal_error", f"is {r.terminal_error:.6g}, but {what} = {err:.6g}")
        elif r.terminal_error is not None:
            _fail("terminal_error", f"must be null: the trajectory stops at t = {r.t[-1]:.6g} s < T")
        if mech.has_singular_set:
            if r.min_delta is None:
                _fail("min_delta", f"is null, but mechanism {mech.name!r} has a singular set")
            tol = VALUE_RTOL * max(1.0, abs(r.min_delta))
            least = float(np.min(self.sign * r.delta))
            if r.min_delta > least + tol:
                _fail("min_delta", f"({r.min_delta:.6g}) exceeds the least sgnΔ of the samples ({least:.6g})")
            if complete and r.min_delta < self.dmin - tol:
                _fail("min_delta", f"({r.min_delta:.6g}) is below the least sgnΔ of the replayed motion "
                                   f"({self.dmin:.6g})")
        elif r.min_delta is not None:
            _fail("min_delta", f"must be null: mechanism {mech.name!r} has no singular set")
        if r.success:
            if not complete:
                _fail("success", f"is true, but the trajectory stops at t = {r.t[-1]:.6g} s < T")
            if r.replay_steps is None and not self.legacy:
                _fail("success", "is true, but the plan has no certificate (replay_steps, error_bound)")
            tol = r.options.get("tol")
            bound = r.error_bound or 0.0
            if tol is not None and r.terminal_error + bound > tol:
                _fail("success", f"is true, but terminal_error + error_bound = "
                                 f"{r.terminal_error + bound:.3g} > tol = {tol:g}")
            dmin = r.options.get("delta_min")
            if mech.has_singular_set and dmin is not None and r.min_delta < dmin:
                _fail("success", f"is true, but min_delta = {r.min_delta:.4g} < delta_min = {dmin:g}")
            stroke = r.options.get("leg_length")
            if stroke is not None:
                try:
                    limits = LegLimits.from_argument(stroke, mech)
                except ValueError as exc:
                    _fail("options", f"has a bad leg_length: {exc}")
                if limits.least_clearance(mech, r.R) < -VALUE_RTOL * limits.hi:
                    _fail("success", f"is true, but {limits.describe(mech, r.R, r.t)}")
            speed = r.options.get("leg_speed")
            if speed is not None:
                if not is_number(speed) or not speed > 0:
                    _fail("options", f"has a bad leg_speed: {_short(speed)}")
                fastest = float(np.max(np.abs(mech.leg_speeds(r.R, r.u))))
                if fastest > speed * (1.0 + SPEED_RTOL):
                    _fail("success", f"is true, but a leg moves at {fastest:.6g} > leg_speed = {speed:g}")
