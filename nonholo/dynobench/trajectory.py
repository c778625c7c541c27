"""A plan as a Dynobench trajectory, and back.

:func:`to_dynobench` exports a plan, :func:`write` and :func:`read` the trajectory's file.

Dynobench's trajectory file holds top-level ``states`` (``K + 1``) and ``actions`` (``K``, each
held for the model's ``dt``); its cost is ``K dt``. A plan's motion is sampled at the steps
``t_k = k dt`` of its horizon (a whole number of them), from its certified replay on the
mechanism's hand-written model (DOP853, :func:`nonholo.certify.resimulate.resimulate_state`);
the actions are the model's inputs averaged over each step, in Dynobench's form — a car's steering angle, a state of the catalog's
``car_with_trailer``, is its action there.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .checker import wrap

#: Points of the midpoint rule an action (the inputs' mean over a step) is taken from.
MEAN_SAMPLES = 256


def steps_of(T: float, dt: float) -> int:
    """The whole number of steps ``dt`` in a horizon ``T``.

    Parameters
    ----------
    T : float
        The horizon (s).
    dt : float
        The step (s).

    Returns
    -------
    int
        ``K`` with ``K dt = T``.

    Raises
    ------
    ValueError
        If ``T`` is not a whole number of steps (to 1e-9 relative).
    """
    K = round(T / dt)
    if K < 1 or abs(K * dt - T) > 1e-9 * max(T, 1.0):
        raise ValueError(f"T = {T:g} s is not a whole number of Dynobench's steps dt = {dt:g} s")
    return int(K)


def to_dynobench(result, instance) -> dict:
    """A successful plan of an instance as a Dynobench trajectory.

    Parameters
    ----------
    result : PlanResult
        The plan (of the instance's mechanism, its ``T`` a whole number of ``dt``).
    instance : Instance
        The instance.

    Returns
    -------
    dict
        ``{"states": [...], "actions": [...]}`` (lists of floats), the states' angles in
        ``[−π, π)``.

    Raises
    ------
    ValueError
        For a failed plan, a plan of another mechanism, or a horizon that is not a whole
        number of steps.
    """
    if not result.success:
        raise ValueError(f"result: only a successful plan is a trajectory; this one failed: {result.reason}")
    if result.mechanism != instance.mechanism:
        raise ValueError(f"result: a plan of {result.mechanism!r}, not of the instance's {instance.mechanism!r}")
    from ..certify.resimulate import resimulate_state

    K = steps_of(result.T, instance.dt)
    # the motion at every half step: DOP853 on the mechanism's hand-written model
    mech = result.kinematics
    half = np.linspace(0.0, result.T, 2 * K + 1)
    t, _, q, _ = resimulate_state(mech.space.public(result.start), result.controls, result.T, mech.name,
                                  breakpoints=getattr(result.parametrisation, "breakpoints", None),
                                  samples=2 * K + 1)
    q = q[np.searchsorted(t, half, side="right") - 1]         # the samples at the half steps
    # the inputs' mean over each step, by the midpoint rule on MEAN_SAMPLES points (exact
    # enough across a jump of grid controls inside a step)
    mid = (np.arange(K)[:, None] + (np.arange(MEAN_SAMPLES) + 0.5)[None, :] / MEAN_SAMPLES) * (result.T / K)
    u = result.controls(mid.ravel()).reshape(K, MEAN_SAMPLES, -1).mean(axis=1)
    if instance.dynamics == "car_with_trailers":
        # the catalog's state (x, y, θ0, φ, θ1): Dynobench's (x, y, θ0, θ1), its action (v, φ)
        phi = q[:, 3]
        actions = np.column_stack([u[:, 0], (phi[0:-1:2] + 4.0 * phi[1::2] + phi[2::2]) / 6.0])
        states = q[::2][:, [0, 1, 2, 4]]
    else:
        actions, states = u, q[::2].copy()
    mask = np.zeros(states.shape[1], dtype=bool)
    mask[2] = True
    if instance.dynamics == "car_with_trailers":
        mask[3] = True
    states[:, mask] = wrap(states[:, mask])
    return {"states": states.tolist(), "actions": actions.tolist()}


def write(path, trajectory: dict, report=None) -> Path:
    """Write a trajectory in Dynobench's format (YAML), with its check's numbers.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    trajectory : dict
        ``states`` and ``actions`` (:func:`to_dynobench`).
    report : Report, optional
        Its check (:func:`~nonholo.dynobench.checker.check`): ``cost``, ``feasible`` and the
        distances are written first, under Dynobench's names.

    Returns
    -------
    Path
        The file written.
    """
    import yaml

    out = {}
    if report is not None:
        out.update(cost=float(report.cost), feasible=int(report.feasible), max_jump=float(report.max_jump),
                   goal_distance=float(report.goal_distance), start_distance=float(report.start_distance),
                   max_collision=float(report.max_collision), x_bound_distance=float(report.x_bound_distance),
                   u_bound_distance=float(report.u_bound_distance))
    out["num_states"] = len(trajectory["states"])
    out["states"] = [[float(v) for v in x] for x in trajectory["states"]]
    out["num_actions"] = len(trajectory["actions"])
    out["actions"] = [[float(v) for v in a] for a in trajectory["actions"]]
    path = Path(path)
    path.write_text(yaml.safe_dump(out, default_flow_style=None, sort_keys=False))
    return path


def read(path) -> dict:
    """A Dynobench trajectory file's ``states`` and ``actions``.

    Parameters
    ----------
    path : str or os.PathLike
        The file.

    Returns
    -------
    dict
        ``{"states": numpy.ndarray, "actions": numpy.ndarray}``.

    Raises
    ------
    ValueError
        Naming the file and the field, for a file that is not a trajectory.
    """
    from .instance import read_yaml

    data = read_yaml(Path(path), "Dynobench trajectory")
    out = {}
    for key in ("states", "actions"):
        if key not in data:
            raise ValueError(f"{path}: {key} is missing")
        try:
            value = np.array(data[key], dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"{path}: {key} must be a list of lists of numbers") from None
        if value.ndim != 2 or not np.all(np.isfinite(value)):
            raise ValueError(f"{path}: {key} must be a list of lists of finite numbers")
        out[key] = value
    return out
