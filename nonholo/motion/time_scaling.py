"""Time changes of controls: rest-to-rest playback, and reading a time-changed control back.

The mechanisms are driftless, so for controls ``u(τ)`` on ``[0, T_b]`` and an increasing
map ``τ(t)`` of ``[0, T]`` onto ``[0, T_b]`` the controls ``ũ(t) = u(τ(t)) dτ/dt`` move
along the same path, ``x̃(t) = x(τ(t))``, and end where ``u`` does. Two time changes exist:

- :class:`~nonholo.motion.speed_limits.Retimed`: the fastest one under a bound on the legs'
  speed (or a given longer time);
- :class:`RestToRest`: ``τ(t) = T_b σ(t/T)`` with the quintic smoothstep
  ``σ(s) = 10s³ − 15s⁴ + 6s⁵``, ``σ'(s) = 30 s²(1 − s)²``. The motion starts and ends at
  rest (``ũ(0) = ũ(T) = 0``, and so do the inputs' first derivatives, ``σ'' = 0`` there),
  which a physical mechanism can follow without the lag of a jump in speed. Its peak
  speed is ``σ'(1/2) = 15/8`` times the mean.

A rest-to-rest motion may be taken of a re-timed one (a leg-speed bound, then rest to rest);
:func:`planned` and :func:`planned_time` unwrap any chain of time changes down to the planned
controls, :func:`played_time` maps planned times up to the played ones.
"""
from __future__ import annotations

import numpy as np

from ..numerics.checks import check_time

#: Bisection steps that invert ``σ`` (each halves the bracket of ``[0, 1]``: below the
#: spacing of doubles after 53, so the inverse is exact to round-off).
BISECTIONS = 60
#: ``max σ' = σ'(1/2)``: a rest-to-rest motion's peak speed over its mean speed.
PEAK_RATIO = 15.0 / 8.0
#: The shortest horizon accepted (s), a nanosecond: inputs scale as ``1/T``, so a shorter
#: horizon is a mistake of units whose inputs overflow (``T = 1e-310``: ``±inf``) or whose
#: Jacobians underflow, not a faster motion (the counterpart of
#: :data:`~nonholo.numerics.checks.MAX_TIME`).
MIN_TIME = 1e-9


def check_horizon(T, name: str = "T") -> float:
    """A horizon of a motion: a positive finite time (:func:`~nonholo.numerics.checks.check_time`)
    of at least :data:`MIN_TIME`.

    Parameters
    ----------
    T : float
        The horizon (s).
    name : str
        The argument's name, for the message.

    Returns
    -------
    float
        ``T``.

    Raises
    ------
    ValueError
        Naming ``name``, if ``T`` is not such a time.
    """
    T = check_time(T, name)
    if T < MIN_TIME:
        raise ValueError(f"{name} must be at least {MIN_TIME:g} s, got {T:g} (the inputs scale as 1/{name}: "
                         "a shorter horizon is a mistake of units whose inputs are not finite)")
    return T


def smoothstep(s) -> tuple[np.ndarray, np.ndarray]:
    """``σ(s) = 10s³ − 15s⁴ + 6s⁵`` and ``σ'(s) = 30 s²(1 − s)²`` on ``[0, 1]``.

    Parameters
    ----------
    s : array_like
        Points of ``[0, 1]`` (clipped to it).

    Returns
    -------
    tuple of numpy.ndarray
        ``(σ(s), σ'(s))``.
    """
    s = np.clip(np.asarray(s, dtype=float), 0.0, 1.0)
    return s * s * s * (10.0 + s * (-15.0 + 6.0 * s)), 30.0 * s * s * (1.0 - s) ** 2


def inverse_smoothstep(y) -> np.ndarray:
    """The ``s ∈ [0, 1]`` with ``σ(s) = y`` (``σ`` increases strictly: one root), by bisection.

    Parameters
    ----------
    y : array_like
        Values of ``[0, 1]`` (clipped to it).

    Returns
    -------
    numpy.ndarray
        ``σ⁻¹(y)``; exactly 0 and 1 at the ends.
    """
    y = np.clip(np.asarray(y, dtype=float), 0.0, 1.0)
    lo, hi = np.zeros_like(y), np.ones_like(y)
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        below = smoothstep(mid)[0] < y
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    s = 0.5 * (lo + hi)
    s[y == 0.0], s[y == 1.0] = 0.0, 1.0
    return s


class TimeChange:
    """Controls ``ũ(t) = u(τ(t)) dτ/dt`` of base controls ``u`` (the attribute ``base``), on
    ``[0, T]``: what every time change shares. A subclass gives :meth:`tau` and ``time``.

    Evaluates like a control (``u = self(t)``, vectorised).
    """

    base = None
    T: float

    @property
    def n_inputs(self) -> int:
        """``m``, the number of inputs."""
        return self.base.n_inputs

    @property
    def params(self) -> np.ndarray:
        """The base controls' parameters."""
        return self.base.params

    @property
    def grid(self) -> None:
        """The base's jumps move off any grid: none to align steps with."""
        return None

    def tau(self, t) -> tuple[np.ndarray, np.ndarray]:
        """The base's time at these times.

        Parameters
        ----------
        t : array_like
            Times in ``[0, T]``.

        Returns
        -------
        tuple of numpy.ndarray
            ``(τ(t), dτ/dt)``.

        Raises
        ------
        NotImplementedError
            Here: each time change defines its own.
        """
        raise NotImplementedError

    def __call__(self, t):
        scalar = np.ndim(t) == 0
        tau, rate = self.tau(np.reshape(t, -1))
        u = np.asarray(self.base(tau), dtype=float).reshape(-1, self.n_inputs) * rate[:, None]
        return u[0] if scalar else u.reshape(np.shape(t) + (self.n_inputs,))

    def __eq__(self, other) -> bool:
        return type(self) is type(other) and self.to_dict() == other.to_dict()

    __hash__ = None


class RestToRest(TimeChange):
    """Controls played from rest to rest: ``ũ(t) = u(τ(t)) dτ/dt``, ``τ = T_b σ(t/T)``
    (module docstring).

    Evaluates like a control (``u = self(t)``, vectorised); :meth:`tau` maps its times to
    the base's, :meth:`time` back.

    Parameters
    ----------
    base : Controls, FrameControls, Stitched or Retimed
        The controls played, on ``[0, T_b]``; not rest-to-rest already.
    T : float
        The duration of the played motion (s).

    Raises
    ------
    ValueError
        If ``base`` is rest-to-rest already or ``T`` is not a horizon
        (:func:`check_horizon`).
    """

    kind = "rest_to_rest"

    def __init__(self, base, T: float):
        if isinstance(base, RestToRest):
            raise ValueError("base is rest-to-rest already: time its own base instead")
        self.base = base
        self.T = check_horizon(T)

    def tau(self, t) -> tuple[np.ndarray, np.ndarray]:
        """The base's time at played times.

        Parameters
        ----------
        t : array_like
            Played times in ``[0, T]``.

        Returns
        -------
        tuple of numpy.ndarray
            ``(τ(t), dτ/dt)``.
        """
        sigma, rate = smoothstep(np.asarray(t, dtype=float) / self.T)
        return self.base.T * sigma, (self.base.T / self.T) * rate

    def time(self, tau) -> np.ndarray:
        """The played time of the base's times.

        Parameters
        ----------
        tau : array_like
            Times of the base, in ``[0, T_b]``.

        Returns
        -------
        numpy.ndarray
            ``t(τ) = T σ⁻¹(τ/T_b)``.
        """
        return self.T * inverse_smoothstep(np.asarray(tau, dtype=float) / self.base.T)

    @property
    def breakpoints(self) -> np.ndarray:
        """The played images of the base's breakpoints (and of ``0``, ``T_b``)."""
        b = getattr(self.base, "breakpoints", None)
        inner = [[0.0, self.base.T]] + ([] if b is None else [np.asarray(b, dtype=float)])
        out = self.time(np.unique(np.concatenate(inner)))
        out[0], out[-1] = 0.0, self.T
        return np.unique(out)

    def to_dict(self) -> dict:
        """A JSON-able description for :func:`from_dict`.

        Returns
        -------
        dict
            ``{"kind": "rest_to_rest", "T", "base"}``.
        """
        return {"kind": self.kind, "T": self.T, "base": self.base.to_dict()}

    def __repr__(self) -> str:
        return f"RestToRest({self.base!r} on [0, {self.T:.6g}], from rest to rest)"


def from_dict(d: dict, base_from_dict) -> RestToRest:
    """Inverse of :meth:`RestToRest.to_dict`.

    Parameters
    ----------
    d : dict
        The description.
    base_from_dict : callable
        Reads the base controls.

    Returns
    -------
    RestToRest
        The controls.
    """
    return RestToRest(base_from_dict(d["base"]), d["T"])


def is_time_change(controls) -> bool:
    """Whether ``controls`` are a time change of other controls.

    Parameters
    ----------
    controls : object
        Controls.

    Returns
    -------
    bool
        ``True`` for a :class:`TimeChange` (:class:`RestToRest`,
        :class:`~nonholo.motion.speed_limits.Retimed`).
    """
    return isinstance(controls, TimeChange)


def planned(controls):
    """The planned controls under any chain of time changes.

    Parameters
    ----------
    controls : object
        Controls, time-changed or not.

    Returns
    -------
    Controls, FrameControls or Stitched
        The controls the chain starts from (``controls`` itself if not time-changed).
    """
    while is_time_change(controls):
        controls = controls.base
    return controls


def planned_time(controls, t) -> np.ndarray:
    """The planned time of played times ``t`` (through every time change).

    Parameters
    ----------
    controls : object
        Controls, time-changed or not.
    t : array_like
        Times of ``controls``.

    Returns
    -------
    numpy.ndarray
        The times of :func:`planned` ``(controls)``.
    """
    t = np.asarray(t, dtype=float)
    while is_time_change(controls):
        t = controls.tau(t)[0]
        controls = controls.base
    return t


def played_time(controls, tau) -> np.ndarray:
    """The played times of planned times ``tau`` (the inverse of :func:`planned_time`).

    Parameters
    ----------
    controls : object
        Controls, time-changed or not.
    tau : array_like
        Times of :func:`planned` ``(controls)``.

    Returns
    -------
    numpy.ndarray
        The times of ``controls``.
    """
    chain = []
    while is_time_change(controls):
        chain.append(controls)
        controls = controls.base
    t = np.asarray(tau, dtype=float)
    for change in reversed(chain):
        t = change.time(t)
    return t
