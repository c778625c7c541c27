"""Controls played one after another: the physical inputs of a motion planned segment by
segment (the global route, :mod:`nonholo.planning.route`).

Piece ``i`` — physical controls on its own ``[0, T_i]`` (a
:class:`~nonholo.controls.parametrisations.Controls` or :class:`~nonholo.motion.frame_controls.FrameControls`) — plays on
the ``i``-th of ``k`` equal slots of ``[0, T]``, re-timed: with ``τ = T/k`` and ``c_i =
T_i/τ``,

    ``u(t) = c_i · u_i(c_i · (t − iτ))``,  ``t ∈ [iτ, (i+1)τ)``.

The mechanisms are driftless (``dR/dt = [L(R) u] R``), so the re-timed piece moves along
the same path of orientations, only faster or slower; on a CF4 grid with the same number
of steps per piece the discrete motion is the same as the piece's own. Equal slots keep
the integrator's steps equal: a stage table of ``steps`` steps (a multiple of ``k``) is
the pieces' tables of ``steps/k`` steps each, scaled.

``waypoints`` (``(k + 1, 3, 3)``) are the orientations the pieces were planned between
(the route); the motion passes within the planner's tolerance of the inner ones. A
mechanism whose state goes beyond SO(3) (:mod:`nonholo.spaces.product`) adds the waypoints'
``coordinates`` (``(k + 1, n)``; its waypoint orientations are the identity without
orientation).
"""
from __future__ import annotations

import math

import numpy as np

from ..numerics.checks import check_time, check_times
from ..spaces import so3
from . import stages
from .parametrisations import PiecewiseConstant
from .parametrisations import from_dict as controls_from_dict


class Stitched:
    """Pieces of physical controls re-timed into equal slots of ``[0, T]`` (see the module).

    Parameters
    ----------
    T : float
        The horizon (s).
    pieces : iterable of Controls or FrameControls
        The ``k`` pieces, each on its own ``[0, T_i]``, with the same number of inputs.
    waypoints : array_like
        The orientations the pieces were planned between, shape ``(k + 1, 3, 3)``.
    coordinates : array_like, optional
        The waypoints' coordinates, shape ``(k + 1, n)``, for a mechanism whose state
        goes beyond SO(3).

    Raises
    ------
    ValueError
        If ``T`` is not a positive finite time, there are no pieces or their inputs
        differ, a waypoint is not a rotation, or ``waypoints`` or ``coordinates`` has the
        wrong shape.
    """

    kind = "stitched"

    def __init__(self, T: float, pieces, waypoints, coordinates=None):
        self.T = check_time(T)
        pieces = list(pieces)
        if not pieces:
            raise ValueError("a stitched control needs at least one piece")
        m = pieces[0].n_inputs
        if any(p.n_inputs != m for p in pieces):
            raise ValueError("the pieces of a stitched control must have the same number of inputs")
        W = np.array(waypoints, dtype=float)
        if W.shape != (len(pieces) + 1, 3, 3):
            raise ValueError(f"waypoints must have shape ({len(pieces) + 1}, 3, 3) for {len(pieces)} "
                             f"pieces, got {W.shape}")
        for i, R in enumerate(W):
            so3.check_rotation(R, f"waypoints[{i}]")
        W.setflags(write=False)
        if coordinates is not None:
            C = np.array(coordinates, dtype=float)
            if C.ndim != 2 or C.shape[0] != len(pieces) + 1 or not np.all(np.isfinite(C)):
                raise ValueError(f"coordinates must be finite with shape ({len(pieces) + 1}, n) for "
                                 f"{len(pieces)} pieces, got {C.shape}")
            C.setflags(write=False)
            coordinates = C
        self.pieces = tuple(pieces)
        self.waypoints = W
        self.coordinates = coordinates

    # -- the slots ------------------------------------------------------------------------
    @property
    def n_pieces(self) -> int:
        """``k``, the number of pieces."""
        return len(self.pieces)

    @property
    def n_inputs(self) -> int:
        """``m``, the number of inputs."""
        return self.pieces[0].n_inputs

    @property
    def slot(self) -> float:
        """``τ = T/k``, the duration of every piece's slot."""
        return self.T / len(self.pieces)

    @property
    def segment_times(self) -> np.ndarray:
        """The slots' ends ``iτ``, ``i = 0 … k``: where one piece hands over to the next."""
        return np.linspace(0.0, self.T, len(self.pieces) + 1)

    def _rates(self) -> np.ndarray:
        """``c_i = T_i/τ``: each piece's speed-up in its slot."""
        return np.array([p.T for p in self.pieces]) / self.slot

    @property
    def grid(self) -> int:
        """The steps of a stage table must be a multiple of this: ``k`` times the least
        common multiple of the pieces' grids (1 for smooth pieces)."""
        g = 1
        for p in self.pieces:
            inner = getattr(p, "frame", p)
            if isinstance(inner, PiecewiseConstant):
                g = math.lcm(g, inner.grid)
        return len(self.pieces) * g

    # -- evaluation -----------------------------------------------------------------------
    def __call__(self, t):
        """The physical inputs ``u(t)`` (``(n, m)`` for ``t`` of shape ``(n,)``)."""
        return self._retimed(t, list(self.pieces))

    def planned(self, t):
        """The pieces' controls in the coordinates they were planned in, re-timed like
        calling the object (frame systems are driftless too).

        The initial guess of a re-plan of the whole motion
        (:func:`nonholo.planning.route_smoothing.smooth`).

        Parameters
        ----------
        t : array_like
            Times (s), shape ``(n,)`` or a scalar.

        Returns
        -------
        numpy.ndarray
            The frame coordinates ``w`` of
            :class:`~nonholo.motion.frame_controls.FrameControls` pieces, ``u`` of the
            others: shape ``(n, m)``, ``(m,)`` for a scalar ``t``.
        """
        return self._retimed(t, [getattr(p, "frame", p) for p in self.pieces])

    def _retimed(self, t, functions):
        """``c_i · f_i(c_i · (t − iτ))`` on slot ``i`` (see the module)."""
        scalar = np.ndim(t) == 0
        t = np.clip(check_times(t).reshape(-1), 0.0, self.T)
        k = len(self.pieces)
        i = np.minimum(np.floor(t / self.slot).astype(np.int64), k - 1)
        c = self._rates()
        u = np.empty((t.size, self.n_inputs))
        for j in np.unique(i):
            sel = i == j
            local = np.clip(c[j] * (t[sel] - j * self.slot), 0.0, self.pieces[j].T)
            u[sel] = c[j] * np.asarray(functions[j](local)).reshape(-1, self.n_inputs)
        return u[0] if scalar else u

    def stage_table(self, steps: int) -> np.ndarray:
        """The inputs at the stage times of ``steps`` steps: each piece's table of
        ``steps/k`` steps, scaled by its ``c_i``.

        Parameters
        ----------
        steps : int
            The number of CF4 steps, a multiple of :attr:`grid`.

        Returns
        -------
        numpy.ndarray
            ``U``, shape ``(steps, 3, m)``.
        """
        steps = stages.check_steps(self, steps)
        r = steps // len(self.pieces)
        return np.concatenate([c * stages.stage_table(p, r) for p, c in zip(self.pieces, self._rates())])

    @property
    def breakpoints(self) -> np.ndarray:
        """The slots' ends and every piece's breakpoints, re-timed."""
        out = [self.segment_times]
        for j, (p, c) in enumerate(zip(self.pieces, self._rates())):
            b = getattr(p, "breakpoints", None)
            if b is not None:
                out.append(j * self.slot + np.asarray(b) / c)
        return np.unique(np.clip(np.concatenate(out), 0.0, self.T))

    @property
    def params(self) -> np.ndarray:
        """The pieces' parameters, one after another."""
        return np.concatenate([p.params for p in self.pieces])

    # -- description ----------------------------------------------------------------------
    def to_dict(self) -> dict:
        """A JSON-able description for :func:`from_dict`.

        Returns
        -------
        dict
            ``{"kind": "stitched", "T", "pieces", "waypoints"}`` (and ``"coordinates"``
            if there are some), the pieces by their own ``to_dict``.
        """
        return {"kind": self.kind, "T": self.T, "pieces": [p.to_dict() for p in self.pieces],
                "waypoints": self.waypoints.tolist(),
                **({} if self.coordinates is None else {"coordinates": self.coordinates.tolist()})}

    def __eq__(self, other) -> bool:
        return (type(self) is type(other) and self.T == other.T
                and len(self.pieces) == len(other.pieces)
                and all(a == b for a, b in zip(self.pieces, other.pieces))
                and np.array_equal(self.waypoints, other.waypoints)
                and (self.coordinates is None) == (other.coordinates is None)
                and (self.coordinates is None or np.array_equal(self.coordinates, other.coordinates)))

    __hash__ = None

    def __repr__(self) -> str:
        return f"Stitched({len(self.pieces)} pieces on [0, {self.T:g}])"


def from_dict(d: dict, piece_from_dict=controls_from_dict) -> Stitched:
    """Inverse of :meth:`Stitched.to_dict`.

    Parameters
    ----------
    d : dict
        The description.
    piece_from_dict : callable
        Reads one piece (default
        :func:`nonholo.controls.parametrisations.from_dict`).

    Returns
    -------
    Stitched
        The control.

    Raises
    ------
    ValueError
        If ``pieces`` is not a list, or the description is otherwise invalid.
    """
    pieces = d.get("pieces")
    if not isinstance(pieces, list):
        raise ValueError("a stitched control's 'pieces' must be a list")
    return Stitched(d["T"], [piece_from_dict(p) for p in pieces], d["waypoints"], d.get("coordinates"))

