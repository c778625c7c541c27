"""The outcome of a motion-planning run: :class:`PlanResult`, with JSON save/load.

File format (``PlanResult.save``): one JSON object, ``"format": "nonholo.plan/1"``, with
the scalar fields, ``R0``/``Rd`` as nested 3×3 lists, the samples ``t`` (n), ``R``
(n×3×3), ``u`` (n×m) and ``delta`` (n, or null), ``history`` (a list of per-iteration
records) and ``controls``, the parametrisation (``{"kind": "fourier", "T", "harmonics",
"coeffs"}``, ``{"kind": "piecewise_constant", "T", "grid", "values"}`` or, for a motion
planned in frame coordinates (strategy ``"robust"``), ``{"kind": "frame", "T",
"mechanism", "steps", "R0", "frame": <the w parametrisation>}``, see
:mod:`nonholo.controls` and :mod:`nonholo.replay`) from which ``controls(t)`` is rebuilt (identically: the frame
motion's nodes are recomputed by the same kernel). Floats are written with
``repr`` precision, so a save/load round trip reproduces every number exactly. Quantities
that do not exist (``min_delta`` for a mechanism without a singular set, the terminal
error of a run stopped before any simulation) are ``null``/``None``, never NaN.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

from .controls import Controls
from .replay import FrameControls, from_dict

FORMAT = "nonholo.plan/1"


@dataclass(eq=False)
class PlanResult:
    """Result of :func:`nonholo.planner.plan`.

    - ``success``/``reason``: whether ``terminal_error ≤ tol`` was reached, and why not.
    - ``terminal_error``: ``|l_T|`` (rad), ``[l_T] = log(R_T R_dᵀ)`` of the final
      trajectory (``None`` if nothing was simulated, e.g. a goal across ``Δ = 0``).
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
      when the planned ``u(t)`` is played open loop (``|Φ(T,T)|_F = √3``); computed by the
      ``"robust"`` strategy (``None`` otherwise). Above ~100 an independent re-simulation
      can no longer reproduce ``R(T)`` to 1e-8 rad (see :mod:`nonholo.planning.robust`).
    - ``parametrisation``: the planned control (a :class:`~nonholo.controls.Controls`:
      Fourier or grid controls of ``u``, or :class:`~nonholo.replay.FrameControls`
      wrapping those of the frame coordinates ``w``); :meth:`controls` evaluates the
      physical inputs ``u(t)``.
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

    # -- controls ----------------------------------------------------------------------
    def controls(self, t) -> np.ndarray:
        """Planned input ``u(t)``: ``t`` of shape ``(n,)`` gives ``(n, m)`` (physical units)."""
        return self.parametrisation(t)

    @property
    def breakpoints(self) -> np.ndarray | None:
        """Times where the planned control may jump (for :func:`nonholo.verify.resimulate`)."""
        return self.parametrisation.breakpoints

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
        if d.get("format") != FORMAT:
            raise ValueError(f"not a nonholo plan file (format {d.get('format')!r}, expected {FORMAT!r})")
        par = from_dict(d["controls"])
        m = par.n_inputs

        def arr(x, shape=None):
            if x is None:
                return None
            a = np.asarray(x, dtype=float)
            return a.reshape(shape) if shape is not None else a

        return cls(
            success=bool(d["success"]), reason=d["reason"],
            terminal_error=d["terminal_error"], min_delta=d["min_delta"],
            iterations=int(d["iterations"]), history=list(d["history"]),
            t=arr(d["t"], (-1,)), R=arr(d["R"], (-1, 3, 3)), u=arr(d["u"], (-1, m)),
            delta=arr(d["delta"], (-1,)), parametrisation=par,
            mechanism=d["mechanism"], method=d["method"], strategy=d["strategy"],
            T=float(d["T"]), R0=arr(d["R0"], (3, 3)), Rd=arr(d["Rd"], (3, 3)),
            steps=int(d["steps"]), seconds=float(d["seconds"]), options=dict(d.get("options", {})),
            sensitivity=d.get("sensitivity"),
        )

    def save(self, path) -> Path:
        """Write the result as JSON (format ``nonholo.plan/1``, see the module docstring)."""
        path = Path(path)
        path.write_text(json.dumps(self.to_dict(), allow_nan=False, indent=1))
        return path

    @classmethod
    def load(cls, path) -> "PlanResult":
        """Read a result written by :meth:`save`."""
        return cls.from_dict(json.loads(Path(path).read_text()))

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
        if not self.success:
            lines.append(f"  reason: {self.reason}")
        return "\n".join(lines) + ")"
