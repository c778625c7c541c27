"""OMPL's control planner as a peer on the global problem (``pip install ompl``).

The setting a researcher would reach for with OMPL 2 (its Python bindings): the state
space is OMPL's ``SO3StateSpace``, the control space ``R^m`` with ``|u_i| ≤``
:data:`U_MAX`, the state propagator is the mechanism's own kinematics ``dR/dt = [L(R) u]
R`` for a constant ``u`` (the CF4 kernel of ``nonholo``, steps that turn the platform by
at most :data:`MAX_TURN` rad at the step's start; a propagation that comes within
``delta_min / 2`` of ``Δ = 0`` ends at an invalid state across it; the steps are halved
until two propagations agree), a state is valid when
``sgn(Δ(R0)) Δ(R) ≥ delta_min``, and
the goal is the region of rotation angle :data:`GOAL_RADIUS` rad around ``R_d`` (OMPL's
SO(3) distance is half the rotation angle: the threshold passed is half of it). The
planner is what ``SimpleSetup`` picks for a control problem (KPIECE1, with the space's
default projection), given :data:`BUDGET` s of wall time. OMPL plans in free time: the
duration of its motion is its own (a sum of propagation steps), not the ``T`` of the
problem.

OMPL's random generator is seeded once per process (:data:`SEED`; OMPL allows no more),
so a run of several problems is reproducible only as a whole, in the same order.

:func:`solve` returns a :class:`Solution`; its ``controls`` (piecewise constant, with
``breakpoints``) are what :func:`nonholo.certify.resimulate.resimulate` replays independently.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from nonholo.integrate.compiled import compiled_system
from nonholo.model import catalog
from nonholo.spaces import so3

#: Rotation angle (rad) of the goal region.
GOAL_RADIUS = 0.05
#: Wall-clock seconds of planning per problem.
BUDGET = 5.0
#: Bound on each input (the platform's leg rates of the paper's examples stay below it).
U_MAX = 5.0
#: OMPL's propagation step (s) and the range of steps a control is applied for.
PROPAGATION_STEP = 0.05
CONTROL_STEPS = (1, 20)
#: Longest CF4 step (s) of the propagator, and the largest turn (rad) of one step (at its
#: start); the steps are then halved until two propagations agree within
#: ``PROPAGATION_TOL`` rad (at most ``REFINEMENTS`` times).
INTEGRATION_STEP = 0.01
MAX_TURN = 0.005
PROPAGATION_TOL = 1e-9
REFINEMENTS = 8
#: Seed of OMPL's (process-global) random generator.
SEED = 20140901

_seeded = False


def _seed_once() -> None:
    global _seeded
    if not _seeded:
        from ompl import util as ou

        ou.setLogLevel(ou.LOG_WARN)
        ou.RNG.setSeed(SEED)
        _seeded = True


def _matrix(state) -> np.ndarray:
    return Rotation.from_quat([state.x, state.y, state.z, state.w]).as_matrix()


def _set(state, R) -> None:
    state.x, state.y, state.z, state.w = Rotation.from_matrix(np.asarray(R, dtype=float)).as_quat()


class PiecewiseControls:
    """``u(t)`` constant on ``[breakpoints[k], breakpoints[k+1])``: ``values[k]``."""

    def __init__(self, values: np.ndarray, durations: np.ndarray):
        self.values = np.asarray(values, dtype=float).reshape(len(durations), -1)
        self.breakpoints = np.concatenate([[0.0], np.cumsum(durations)])
        self.T = float(self.breakpoints[-1])

    def __call__(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        k = np.clip(np.searchsorted(self.breakpoints, t, side="right") - 1, 0, len(self.values) - 1)
        return self.values[k]

    def to_dict(self) -> dict:
        return {"kind": "piecewise_durations", "values": self.values.tolist(),
                "breakpoints": self.breakpoints.tolist()}


@dataclass
class Solution:
    """What OMPL returned: ``reached`` (an exact solution: the goal region was reached),
    ``status`` (OMPL's planner status), ``seconds`` (wall time of ``solve``), ``controls``
    (:class:`PiecewiseControls`, ``None`` without a path), ``T`` (their duration),
    ``R_T`` (the path's last state as OMPL propagated it), ``error`` (its rotation angle
    from the goal, rad), ``states`` (the path's states, ``(n, 3, 3)``)."""

    reached: bool
    status: str
    seconds: float
    controls: PiecewiseControls | None
    T: float
    R_T: np.ndarray | None
    error: float
    states: np.ndarray | None


class Planner:
    """One OMPL control set-up for a mechanism, reused across problems."""

    def __init__(self, mechanism="platform", delta_min: float = 1e-2, budget: float = BUDGET):
        from ompl import base as ob
        from ompl import control as oc

        _seed_once()
        self.mechanism = catalog.get(mechanism)
        self.delta_min = float(delta_min)
        self.budget = float(budget)
        m = self.mechanism.n_inputs
        self.space = ob.SO3StateSpace()
        cspace = oc.RealVectorControlSpace(self.space, m)
        bounds = ob.RealVectorBounds(m)
        bounds.setLow(-U_MAX)
        bounds.setHigh(U_MAX)
        cspace.setBounds(bounds)
        self.setup = oc.SimpleSetup(cspace)
        si = self.setup.getSpaceInformation()
        si.setPropagationStepSize(PROPAGATION_STEP)
        si.setMinMaxControlDuration(*CONTROL_STEPS)
        self.sign = 1.0
        kern = compiled_system(self.mechanism, frame=False)
        has_delta = self.mechanism.delta is not None

        def valid(state) -> bool:
            if not has_delta:
                return True
            return bool(self.sign * float(self.mechanism.delta(_matrix(state))) >= self.delta_min)

        stop = self.delta_min / 2 if has_delta else -np.inf

        def run(R, u, duration, n):
            Rs, Qs = kern.nodes(n)
            done, _, _ = kern.forward(R, Qs[0], np.ascontiguousarray(np.broadcast_to(u, (n, 3, m))), duration / n,
                                      self.sign, stop, Rs, Qs)
            return Rs[done], done == n

        def propagate(start, control, duration, result) -> None:
            R = np.ascontiguousarray(_matrix(start))
            u = np.array([control[i] for i in range(m)])
            speed = float(np.linalg.norm(self.mechanism.L(R) @ u))
            n = max(1, int(np.ceil(duration / INTEGRATION_STEP)), int(np.ceil(duration * speed / MAX_TURN)))
            end, whole = run(R, u, duration, n)
            for _ in range(REFINEMENTS):      # halve the steps until two agree
                if not whole:
                    break
                finer, whole = run(R, u, duration, 2 * n)
                n *= 2
                agree = so3.distance(finer, end) <= PROPAGATION_TOL
                end = finer
                if agree:
                    break
            # a propagation stopped near Δ = 0 has no valid end: the far side of Δ = 0 stands for it
            _set(result, end if whole else self.invalid)

        self.invalid = np.eye(3)   # replaced per problem by an orientation across Δ = 0
        self.setup.setStateValidityChecker(valid)
        self.setup.setStatePropagator(propagate)

    def solve(self, R0, Rd) -> Solution:
        R0 = so3.check_rotation(R0, "R0")
        Rd = so3.check_rotation(Rd, "Rd")
        mech = self.mechanism
        self.sign = float(np.sign(mech.delta(R0))) if mech.delta is not None else 1.0
        if mech.delta is not None:
            # R0 turned until Δ changes sign: an orientation no valid motion can reach
            turned = (so3.exp(angle * axis) @ R0 for angle in np.linspace(0.1, np.pi, 32) for axis in np.eye(3))
            self.invalid = next((R for R in turned if self.sign * float(mech.delta(R)) < -self.delta_min),
                                self.invalid)
        self.setup.clear()
        a, b = self.space.allocState(), self.space.allocState()
        _set(a, R0)
        _set(b, Rd)
        self.setup.setStartAndGoalStates(a, b, GOAL_RADIUS / 2)
        t0 = time.perf_counter()
        status = self.setup.solve(self.budget)
        seconds = time.perf_counter() - t0
        if not self.setup.haveSolutionPath():
            return Solution(False, str(status), seconds, None, 0.0, None, float("inf"), None)
        path = self.setup.getSolutionPath()
        m = mech.n_inputs
        k = path.getControlCount()
        values = np.array([[path.getControl(i)[j] for j in range(m)] for i in range(k)]).reshape(k, m)
        durations = np.array([path.getControlDuration(i) for i in range(k)])
        states = np.array([_matrix(path.getState(i)) for i in range(path.getStateCount())])
        controls = PiecewiseControls(values, durations) if k else None
        error = so3.distance(states[-1], Rd)
        return Solution(bool(self.setup.haveExactSolutionPath()), str(status), seconds, controls,
                        float(durations.sum()), states[-1], error, states)
