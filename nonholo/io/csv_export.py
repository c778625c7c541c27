"""A planned motion as a table an actuator controller can play back (CSV).

Columns, one row per sample time ``t_k = k / rate`` (and ``T``), named and with the units of
the table of names and units (:data:`nonholo.model.names.CSV_COLUMNS`; :func:`column_units`
gives a plan's columns with their units):

- ``t`` [s];
- ``l1 … lk`` [radius], ``dl1_dt … dlk_dt`` [radius/s]: the leg lengths and leg speeds, in
  the length unit of the geometry (the sphere's radius, 1), for a mechanism with legs
  (:meth:`nonholo.model.mechanism.Mechanism.leg_lengths`, ``dl_i/dt = G_i(R) L(R) u``);
- ``u1 … um``: the planned inputs ``u(t)`` (``controls(t)``: the scaled leg rates of a
  platform [1/s]; a vehicle's in its units, :func:`nonholo.model.names.input_units`);
- ``qx, qy, qz, qw`` [-]: the orientation ``R(t)`` as a unit quaternion, scalar last (as
  :class:`scipy.spatial.transform.Rotation`), its sign kept continuous from row to row
  (``q`` and ``−q`` are the same orientation; a player interpolating quaternions must not
  see a jump);
- ``delta`` [-]: ``Δ(R(t))``, for a mechanism with a singular set.

A mechanism whose state goes beyond SO(3) (:mod:`nonholo.spaces.product`) has its coordinates as
columns named as the mechanism names them (the car's ``x, y, theta, phi``), in its units
(``wheelbase``, ``rad``), after the inputs; the quaternion only if it has an orientation;
``delta`` is ``Δ(R(t), q(t))``. The header holds the names alone (a controller reads the
columns by name); their units are those above.

``R(t)`` between the plan's samples is one CF4 step of the physical system from the sample
below (the integrator's own local approximation, ``O(h⁵)`` from the replayed motion), so
the rows agree with the plan's samples wherever they coincide.
"""
from __future__ import annotations

import csv
import io
import math

import numpy as np

from ..integrate.compiled import compiled_system
from ..model import names
from ..motion.time_scaling import planned, planned_time
from ..motion.simulation import DELTA_STOP
from ..numerics.checks import is_number

#: Sample rate of :func:`trajectory_table` unless given (Hz).
DEFAULT_RATE = 100.0
#: Rows at most (a rate so high that the table would be larger is refused).
MAX_ROWS = 10_000_000


def check_rate(rate) -> float:
    """``rate`` checked to be a positive, finite number of samples per second.

    Parameters
    ----------
    rate : float
        Samples per second.

    Returns
    -------
    float
        ``rate``.

    Raises
    ------
    ValueError
        Naming ``rate``, if it is not such a number.
    """
    if not is_number(rate) or not math.isfinite(rate) or rate <= 0:
        raise ValueError(f"rate must be a positive number of samples per second, got {rate!r}")
    return float(rate)


def sample_times(T: float, rate: float) -> np.ndarray:
    """``t_k = k / rate`` on ``[0, T]``, and ``T`` itself if it is not one of them.

    Parameters
    ----------
    T : float
        The horizon (s).
    rate : float
        Samples per second.

    Returns
    -------
    numpy.ndarray
        The sample times.

    Raises
    ------
    ValueError
        For a bad ``rate``, or one that gives more rows than :data:`MAX_ROWS`.
    """
    rate = check_rate(rate)
    n = math.floor(T * rate * (1 + 1e-12)) + 1
    if n > MAX_ROWS:
        raise ValueError(f"rate = {rate:g} Hz gives {n} rows over T = {T:g} s (at most {MAX_ROWS})")
    t = np.arange(n) / rate
    return t if abs(t[-1] - T) <= 1e-12 * max(1.0, T) else np.append(t, T)


def states_at(result, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(R(t), q(t))`` of a simulated plan: one CF4 step of the physical system from the
    stored sample at or below each ``t`` (none where ``t`` is a sample time); ``q`` has no
    columns on SO(3). A time-changed plan (re-timed or rest-to-rest,
    :mod:`nonholo.motion.time_scaling`) moves along its planned path: ``R(τ(t))``, stepped in
    the planned time ``τ`` with the planned controls.

    Parameters
    ----------
    result : PlanResult
        A plan.
    t : numpy.ndarray
        Times in ``[0, T]``, sorted.

    Returns
    -------
    tuple of numpy.ndarray
        ``R(t)`` of shape ``(n, 3, 3)`` and ``q(t)`` of shape ``(n, k)``.

    Raises
    ------
    ValueError
        If the plan's motion does not reach ``T`` or runs into ``Δ = 0``.
    """
    mech = result.kinematics
    kern = compiled_system(mech, False)
    n_samples = len(result.t)
    if n_samples == 0 or t[-1] > result.t[-1] * (1 + 1e-12):
        raise ValueError("the plan's motion does not reach T (a failed plan): nothing to export")
    controls, T, asked = result.controls, result.T, t
    if result.parametrisation is not planned(result.parametrisation):
        controls = planned(result.parametrisation)
        T = controls.T
        t = planned_time(result.parametrisation, t)
    h = T / result.steps
    idx = np.minimum(np.floor(t / h + 1e-9).astype(np.int64), n_samples - 1)
    s = t - idx * h
    s[np.abs(s) <= 1e-12 * max(1.0, T)] = 0.0
    Q = np.asarray(result.q, dtype=float)
    sgn = mech.singular.sign(*result.start)
    starts = idx * h
    U = np.stack([controls(starts), controls(starts + 0.5 * s), controls(starts + s)],
                 axis=1).reshape(len(t), 3, mech.n_inputs)
    out, out_q = np.empty((len(t), 3, 3)), np.empty((len(t), Q.shape[1]))
    step, step_q = kern.nodes(1)
    for k in range(len(t)):
        out[k], out_q[k] = result.R[idx[k]], Q[idx[k]]
        if s[k] > 0.0:
            done, _, _ = kern.forward(out[k].copy(), out_q[k].copy(), U[k:k + 1], s[k], sgn,
                                      DELTA_STOP, step, step_q)
            if done != 1:
                raise ValueError(f"the motion runs into Δ = 0 at t ≈ {asked[k]:g} s: not a plan to play back")
            out[k], out_q[k] = step[1], step_q[1]
    return out, out_q


def trajectory_table(result, rate: float = DEFAULT_RATE) -> dict[str, np.ndarray]:
    """The columns of the module docstring, in order, for ``result`` (a successful
    :class:`~nonholo.io.result.PlanResult`) sampled at ``rate`` Hz.

    Parameters
    ----------
    result : PlanResult
        A plan.
    rate : float
        Samples per second.

    Returns
    -------
    dict of str to numpy.ndarray
        The columns by name, in order.

    Raises
    ------
    ValueError
        For a failed plan (with its reason: it is not a motion to play on a machine) or a
        bad ``rate``.
    """
    if not result.success:
        raise ValueError(f"the plan failed ({result.reason}): not exported")
    mech = result.kinematics
    t = sample_times(result.T, rate)
    R, q = states_at(result, t)
    u = np.asarray(result.controls(t), dtype=float).reshape(len(t), mech.n_inputs)
    cols: dict[str, np.ndarray] = {"t": t}
    if mech.has_legs:
        lengths = mech.leg_lengths(R)
        speeds = mech.leg_speeds(R, u)
        for i in range(lengths.shape[1]):
            cols[f"l{i + 1}"] = lengths[:, i]
        for i in range(speeds.shape[1]):
            cols[f"dl{i + 1}_dt"] = speeds[:, i]
    for i in range(mech.n_inputs):
        cols[f"u{i + 1}"] = u[:, i]
    cols.update(mech.space.columns(R, q))
    cols.update(mech.singular.columns(R, q))
    return cols


def column_names(mechanism) -> list[str]:
    """The columns of a plan's table (:func:`trajectory_table`), in order.

    Parameters
    ----------
    mechanism : Mechanism
        The plan's mechanism.

    Returns
    -------
    list of str
        ``["t", "l1", "l2", "dl1_dt", "dl2_dt", "u1", "u2", "qx", "qy", "qz", "qw",
        "delta"]`` for the platform.
    """
    out = ["t"]
    if mechanism.has_legs:
        legs = range(1, len(mechanism.geometry.bases) + 1)
        out += [f"l{i}" for i in legs] + [f"dl{i}_dt" for i in legs]
    out += [f"u{i + 1}" for i in range(mechanism.n_inputs)]
    return out + [*mechanism.space.column_names(), *mechanism.singular.column_names]


def column_units(mechanism) -> dict[str, str]:
    """The columns of a plan's table with their units (:func:`nonholo.model.names.csv_units`).

    Parameters
    ----------
    mechanism : Mechanism
        The plan's mechanism.

    Returns
    -------
    dict of str to str
        ``{"t": "s", "l1": "radius", …, "u1": "1/s", …, "delta": "-"}``, in the columns' order.
    """
    header = column_names(mechanism)
    return dict(zip(header, names.csv_units(mechanism, header)))


def csv_text(result, rate: float = DEFAULT_RATE) -> str:
    """:func:`trajectory_table` as CSV text.

    Parameters
    ----------
    result : PlanResult
        A plan.
    rate : float
        Samples per second.

    Returns
    -------
    str
        A header row, then one row per sample (floats with ``repr`` precision).

    Raises
    ------
    ValueError
        As :func:`trajectory_table`.
    """
    cols = trajectory_table(result, rate)
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(list(cols))
    w.writerows([repr(float(x)) for x in row] for row in np.column_stack(list(cols.values())))
    return out.getvalue()
