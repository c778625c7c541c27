"""The physical inputs of a motion planned in the desingularised frame coordinates.

A planner working in frame coordinates (strategy ``"robust"``) steers ``dR/dt = [N(R) w] R``,
``R(0) = R0``, where ``N(R)`` (3×m, orthonormal columns) spans the admissible angular
velocities and ``w(t)`` — a :class:`~nonholo.controls.parametrisations.Fourier` or
:class:`~nonholo.controls.parametrisations.PiecewiseConstant` control — holds the frame coordinates of
``ω``. The mechanism's physical inputs along that motion are ``u(t) = W(R(t)) w(t)``
(``W = (NᵀL)^{-1}``, polynomial, finite everywhere; ``L(R) W(R) w = N(R) w``):
:class:`FrameControls` replays the motion and evaluates them.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..controls import stages, stitched
from ..controls.parametrisations import Controls, Fourier, PiecewiseConstant
from ..controls.parametrisations import from_dict as controls_from_dict
from ..integrate.compiled import compiled_system
from ..numerics.checks import check_times
from ..spaces import so3
from . import speed_limits, time_scaling


class FrameControls:
    """Physical inputs ``u(t) = W(R(t)) w(t)`` of a motion planned in frame coordinates.

    ``R(t)``: the nodes of ``steps`` CF4 steps of the frame system from ``R0``, and between
    nodes one CF4 step of length ``t − t_n`` from the node below — the same local
    approximation as an integrator step, ``O(h⁵)`` from the exact motion.

    Evaluates like a control (``u = self(t)``, vectorised, physical units) and gives the
    integrator its stage table (:meth:`stage_table`), so
    :func:`nonholo.motion.simulation.simulate` re-traces the motion in the physical system.
    ``params`` and ``metric`` are those of ``frame``; ``u`` is not linear in the
    parameters; ``breakpoints`` are the nodes.

    Parameters
    ----------
    frame : Fourier or PiecewiseConstant
        The planned ``w`` (rad/s).
    R0 : array_like
        The start, a rotation matrix.
    mechanism : Mechanism
        A :class:`~nonholo.model.mechanism.Mechanism` with a frame.
    steps : int
        CF4 steps of the frame motion (a multiple of a grid's).
    nodes : array_like, optional
        The nodes ``(steps + 1, 3, 3)``, given by a planner that has just computed them
        (by default computed once, on first use).

    Raises
    ------
    ValueError
        If ``frame`` is not Fourier or grid controls, the mechanism has no frame or
        another number of inputs, ``steps`` is refused
        (:func:`~nonholo.controls.stages.check_steps`), ``R0`` is not a rotation, or
        ``nodes`` are not the motion's from ``R0``.
    """

    kind = "frame"

    def __init__(self, frame: Controls, R0, mechanism, steps: int = 400, nodes=None):
        if not isinstance(frame, (Fourier, PiecewiseConstant)):
            raise ValueError(f"frame must be Fourier or PiecewiseConstant controls, got {type(frame).__name__}")
        mech = mechanism
        if not mech.has_frame:
            raise ValueError(f"mechanism {mech.name!r} has no desingularised frame N(R)")
        if mech.n_inputs != frame.n_inputs:
            raise ValueError(f"mechanism {mech.name!r} has {mech.n_inputs} inputs, "
                             f"the frame controls {frame.n_inputs}")
        self.frame = frame
        self.T = frame.T
        self.mechanism = mech
        self.steps = stages.check_steps(frame, steps)
        R = np.array(so3.check_rotation(R0, "R0"), dtype=float)
        R.setflags(write=False)
        self.R0 = R
        self._nodes = None
        if nodes is not None:
            nodes = np.array(nodes, dtype=float)
            if nodes.shape != (self.steps + 1, 3, 3) or not np.array_equal(nodes[0], R):
                raise ValueError(f"nodes must be the {self.steps + 1} CF4 nodes of the frame motion "
                                 f"from R0, shape ({self.steps + 1}, 3, 3), got {nodes.shape}")
            self._nodes = nodes

    def with_params(self, params) -> "FrameControls":
        """The same replay with other frame parameters.

        Parameters
        ----------
        params : array_like
            The flat parameters of ``frame``.

        Returns
        -------
        FrameControls
            A new object (its nodes computed on first use).
        """
        return FrameControls(self.frame.with_params(params), self.R0, self.mechanism, self.steps)

    @property
    def params(self) -> np.ndarray:
        """The frame controls' flat parameters (a copy)."""
        return self.frame.params

    @property
    def n_inputs(self) -> int:
        """``m``, the number of inputs."""
        return self.frame.n_inputs

    @property
    def grid(self) -> int | None:
        """The frame's grid (grid controls), else ``None``: steps must be a multiple of it."""
        return getattr(self.frame, "grid", None)

    @property
    def breakpoints(self) -> np.ndarray:
        """Where ``u`` or its derivative may jump: every node — the frame's breakpoints
        are among them (``steps`` is a multiple of a grid), and ``R(t)`` is a different CF4
        step on each side of a node, so ``du/dt`` jumps by ``O(h⁴)`` there: enough to cost
        an adaptive integrator that steps across it its accuracy."""
        return np.linspace(0.0, self.T, self.steps + 1)

    def metric(self) -> np.ndarray:
        """The L2 metric of the frame controls ``w``.

        Returns
        -------
        numpy.ndarray
            :meth:`Controls.metric <nonholo.controls.parametrisations.Controls.metric>` of
            ``frame``.
        """
        return self.frame.metric()

    @property
    def nodes(self) -> np.ndarray:
        """``R(t_n)``, ``t_n = nT/steps``: the CF4 nodes of the frame motion, shape ``(steps+1, 3, 3)``."""
        if self._nodes is None:
            kern = compiled_system(self.mechanism, frame=True)
            Rs, Qs = kern.nodes(self.steps)
            n, _, _ = kern.forward(np.ascontiguousarray(self.R0), Qs[0], stages.stage_table(self.frame, self.steps),
                                   self.T / self.steps, 1.0, -np.inf, Rs, Qs)
            if n != self.steps:
                raise ValueError("the frame motion produced a non-finite angular velocity")
            self._nodes = Rs
        return self._nodes

    def _evaluate(self, t, w_end=None):
        """``(R(t), u(t))`` for ``t`` of shape ``(n,)``; ``w_end``: the ``w`` to use at ``t``."""
        t = np.clip(check_times(t).reshape(-1), 0.0, self.T)
        n_t, m = t.size, self.n_inputs
        h = self.T / self.steps
        r = t / h
        k = np.floor(r)
        near = np.rint(r)
        snap = np.abs(r - near) <= 1e-9
        k = np.minimum(np.where(snap, near, k), self.steps).astype(np.int64)
        s = np.where(snap, 0.0, t - k * h)
        tk = k * h
        if not s.any():
            # every sample on a node: u = W(R_k) w(t_k), no partial step to take
            Wst = np.empty((n_t, 3, m))
            if w_end is None:
                w_end = self.frame(t)
        elif isinstance(self.frame, PiecewiseConstant):
            # the partial step uses its step's own value (the middle of a step never lies
            # on a grid point, while t_k = k·h may round to either side of one)
            wk = self.frame(np.minimum(tk, self.T - h) + 0.5 * h)
            Wst = np.ascontiguousarray(np.broadcast_to(wk[:, None, :], (n_t, 3, m)))
            if w_end is None:
                w_end = self.frame(t)
        else:
            Wst = self.frame(np.concatenate([tk, tk + 0.5 * s, t])).reshape(3, n_t, m).transpose(1, 0, 2)
            Wst = np.ascontiguousarray(Wst)
        w_end = Wst[:, 2] if w_end is None else np.ascontiguousarray(w_end, dtype=float).reshape(n_t, m)
        return self._inputs(k, s, Wst, w_end)

    def _inputs(self, k, s, Wst, w_end):
        """``(R, u)`` at ``t_k + s`` (node ``k``, offsets ``s``) from the frame inputs ``Wst``
        of the partial steps and ``w_end`` at the samples."""
        n_t, m = k.size, self.n_inputs
        Rt = np.empty((n_t, 3, 3))
        u = np.empty((n_t, m))
        nodes = self.nodes              # on SO(3): no coordinates
        compiled_system(self.mechanism, frame=True).frame_inputs(
            nodes, np.empty((len(nodes), 0)), k, s, np.ascontiguousarray(Wst),
            np.ascontiguousarray(w_end), Rt, np.empty((n_t, 0)), u)
        return Rt, u

    def __call__(self, t):
        scalar = np.ndim(t) == 0
        u = self._evaluate(t)[1]
        return u[0] if scalar else u.reshape(np.shape(t) + (self.n_inputs,))

    def states(self, t) -> np.ndarray:
        """``R(t)`` of the planned motion.

        Parameters
        ----------
        t : array_like
            Times (s), shape ``(n,)``.

        Returns
        -------
        numpy.ndarray
            The orientations, shape ``(n, 3, 3)``.
        """
        return self._evaluate(t)[0]

    def frame_inputs(self, t) -> np.ndarray:
        """``w(t)``, the frame coordinates of ``ω = N(R) w`` (the planner's controls).

        Parameters
        ----------
        t : array_like
            Times (s).

        Returns
        -------
        numpy.ndarray
            ``w(t)``, shape ``(n, m)`` (``(m,)`` for a scalar ``t``).
        """
        return self.frame(t)

    def stage_table(self, steps: int) -> np.ndarray:
        """The physical inputs at the stage times of ``steps`` steps, for
        :func:`nonholo.controls.stages.stage_table`.

        Parameters
        ----------
        steps : int
            The number of CF4 steps (a multiple of a grid's).

        Returns
        -------
        numpy.ndarray
            ``U``, shape ``(steps, 3, m)`` (grid controls: the step's own value at its end).
        """
        steps = stages.check_steps(self.frame, steps)
        if isinstance(self.frame, Fourier) and steps % self.steps == 0:
            return self._aligned_stage_table(steps)
        t = stages.stage_times(self.T, steps).ravel()
        w_end = stages.stage_table(self.frame, steps).reshape(-1, self.n_inputs)
        return self._evaluate(t, w_end)[1].reshape(steps, 3, self.n_inputs)

    def _aligned_stage_table(self, steps: int) -> np.ndarray:
        """:meth:`stage_table` for Fourier frame controls and ``steps`` a multiple ``r`` of
        the nodes' steps: every time a partial step needs ``w`` at — its start (a node),
        middle and end — is a multiple of ``T/(4·steps)``, so ``w`` is evaluated once on that
        grid (the stage table of ``2·steps`` steps, a cached basis) and indexed. ``w`` is
        continuous, so a step's end value is the next step's start value: ``u`` is computed
        at the ``2·steps + 1`` distinct stage times only."""
        m = self.n_inputs
        fine = stages.stage_table(self.frame, 2 * steps).reshape(-1, m)  # w at i·T/(4·steps)
        k, quarters, gather = _aligned_indices(steps, self.steps)
        Wst = np.take(fine, gather, axis=0).reshape(-1, 3, m)           # (2·steps + 1, 3, m)
        u = self._inputs(k, quarters * (self.T / (4 * steps)), Wst, Wst[:, 2])[1]
        return np.take(u, stages.stage_rows(steps), axis=0).reshape(steps, 3, m)

    def to_dict(self) -> dict:
        """A JSON-able description for :func:`from_dict`.

        Returns
        -------
        dict
            ``{"kind": "frame", "T", "mechanism", "steps", "R0", "frame"}``.
        """
        return {"kind": self.kind, "T": self.T, "mechanism": self.mechanism.name, "steps": self.steps,
                "R0": self.R0.tolist(), "frame": self.frame.to_dict()}

    def __eq__(self, other) -> bool:
        return (type(self) is type(other) and self.T == other.T
                and np.array_equal(self.params, other.params) and self.to_dict() == other.to_dict())

    __hash__ = None

    def __repr__(self) -> str:
        return (f"FrameControls({self.frame!r} in the frame of {self.mechanism.name!r}, "
                f"{self.steps} steps)")


@lru_cache(maxsize=16)
def _aligned_indices(steps: int, nodes: int):
    """For :meth:`FrameControls._aligned_stage_table`: per distinct stage time ``i_t`` (in
    quarters of the fine step: ``0, 2, …, 4·steps``), the node ``k`` below it, the offset
    from it in quarters, the rows of ``w`` at the partial step's start, middle and end in
    the flattened stage table of ``2·steps`` steps (flat, three a time: quarter ``i`` is row
    ``3(i//2) + i%2`` of it, the last quarter the last row; flat indices for :func:`numpy.take`,
    which gathers rows several times faster than indexing by an array of shape ``(n, 3)``).
    (Each stage's distinct time: :func:`~nonholo.controls.stages.stage_rows`.)"""
    r = steps // nodes
    i_t = 2 * np.arange(2 * steps + 1)
    k = np.minimum(i_t // (4 * r), nodes)
    i_k = 4 * r * k
    quarter = np.stack([i_k, (i_k + i_t) // 2, i_t], axis=1).reshape(-1)
    gather = np.where(quarter == 4 * steps, 3 * (2 * steps) - 1, 3 * (quarter // 2) + quarter % 2)
    quarters = (i_t - i_k).astype(float)
    for a in (k, gather, quarters):
        a.setflags(write=False)
    return k, quarters, gather


def from_dict(d: dict, mechanism=None):
    """Inverse of ``to_dict`` for a parametrisation (:func:`nonholo.controls.parametrisations.from_dict`), a
    :class:`FrameControls`, a :class:`~nonholo.controls.stitched.Stitched` of them, or any of those
    :class:`~nonholo.motion.speed_limits.Retimed`, :class:`~nonholo.motion.speed_limits.InputRetimed` or
    :class:`~nonholo.motion.time_scaling.RestToRest`.

    Parameters
    ----------
    d : dict
        The description.
    mechanism : Mechanism, optional
        The :class:`~nonholo.model.mechanism.Mechanism` controls that name their mechanism
        (frame controls, re-timed under a leg speed) are rebuilt with; it must have that
        name (it need not be in the catalog); controls that name none are rebuilt without it.

    Returns
    -------
    Controls, FrameControls, Stitched, Retimed or RestToRest
        The controls.

    Raises
    ------
    ValueError
        If the description names a mechanism and ``mechanism`` is not given or has another
        name, or is otherwise invalid.
    """
    def rebuilt(p):
        return from_dict(p, mechanism)

    if d.get("kind") in (speed_limits.Retimed.kind, FrameControls.kind):
        if mechanism is None:
            raise ValueError(f"the controls are of mechanism {d.get('mechanism')!r}: they are rebuilt "
                             "with its Mechanism (mechanism=)")
        if d.get("mechanism") != mechanism.name:
            raise ValueError(f"the controls are of mechanism {d.get('mechanism')!r}, not {mechanism.name!r}")
    if d.get("kind") == speed_limits.Retimed.kind:
        return speed_limits.from_dict(d, rebuilt, mechanism)
    if d.get("kind") == speed_limits.InputRetimed.kind:
        return speed_limits.input_from_dict(d, rebuilt)
    if d.get("kind") == time_scaling.RestToRest.kind:
        return time_scaling.from_dict(d, rebuilt)
    if d.get("kind") == stitched.Stitched.kind:
        return stitched.from_dict(d, rebuilt)
    if d.get("kind") == FrameControls.kind:
        return FrameControls(controls_from_dict(d["frame"]), d["R0"], mechanism, d["steps"])
    return controls_from_dict(d)
