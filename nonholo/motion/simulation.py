"""Simulation of ``dR/dt = [L(R) u] R`` on SO(3) and of its variational system (9).

Conventions: spatial angular velocity ``ω = L(R) u`` (``dR/dt = [ω] R``), time in
seconds, rotations as 3×3 matrices. Variations are spatial too: ``∂R/∂θ = [s] R``.

The integrator is the 4th-order commutator-free Lie-group method CF4 with a fixed step
``h = T/steps`` (see :mod:`nonholo.integrate.cf4`): ``R`` is updated by products of Rodrigues
exponentials, so ``|RᵀR − I|`` stays at round-off level. Its discretisation error
against DOP853 is measured by ``python -m benchmarks.bench_plan``
(``benchmarks/results/bench_plan.md``).

The variational system ``ds/dt = A s + B ∂u/∂θ``, ``A = Q(R, u) + [L(R) u]``, ``B = L(R)``
is integrated alongside through ``Z(t) = Φ(t, 0)^{-1}``: :func:`variational` returns
``Φ(T, t_n) = Z(T)^{-1} Z(t_n)``, the mobility matrix
``M(T) = ∫ Φ(T,t) B Bᵀ Φ(T,t)ᵀ dt`` (by quadrature; :func:`nonholo.certify.resimulate.mobility_lyapunov`
solves the Lyapunov equation instead), and for a parametrised control ``u = u(λ)`` the
Jacobian ``J = ∂s_T/∂λ = ∫ Φ(T,t) B(t) ∂u/∂λ(t) dt``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..controls import stages
from ..controls.parametrisations import Controls
from ..integrate.compiled import compiled_system
from ..model import catalog
from ..numerics.checks import MAX_STEPS, check_count, check_time

#: Default number of CF4 steps on ``[0, T]``: chosen so that on the examples
#: (:mod:`nonholo.paper.examples`, ``T = 1``) the endpoint is within the planner's 1e-10
#: rad of a DOP853 solution (``benchmarks/results/bench_plan.md``). The method has order
#: 4: the error grows like ``(h |ω|)⁴``, so larger inputs need more steps.
DEFAULT_STEPS = 400

#: ``simulate`` stops (with :class:`SingularTrajectoryError`) where ``|Δ|`` falls below this.
DELTA_STOP = 1e-9


class SingularTrajectoryError(ValueError):
    """The trajectory reached the singular surface ``Δ = 0`` (or ``ω`` became non-finite).

    Parameters
    ----------
    message : str
        What happened, and when.
    trajectory : Trajectory
        The part simulated before that happened.
    """

    def __init__(self, message: str, trajectory: "Trajectory"):
        super().__init__(message)
        self.trajectory = trajectory


@dataclass(frozen=True)
class Trajectory:
    """Samples of a simulated motion at ``t_n = n T/steps``.

    Parameters
    ----------
    t : numpy.ndarray
        The sample times, shape ``(n,)``.
    R : numpy.ndarray
        The orientations, shape ``(n, 3, 3)`` (the identity throughout for a state without
        orientation).
    u : numpy.ndarray
        The inputs at ``t_n``, shape ``(n, m)``; with piecewise-constant controls the value
        on ``[t_n, t_{n+1})``.
    delta : numpy.ndarray or None
        ``Δ`` at the samples, shape ``(n,)``; ``None`` for mechanisms without a singular
        set.
    min_delta : float or None
        The least ``|Δ|`` over every point where the integrator evaluated ``L`` (``None``
        without a singular set).
    mechanism : str
        The mechanism's name.
    T : float
        The horizon (s).
    steps : int
        CF4 steps on ``[0, T]``.
    q : numpy.ndarray or None
        The coordinates of a state beyond SO(3), shape ``(n, k)``; ``None`` on SO(3).
    """

    t: np.ndarray
    R: np.ndarray
    u: np.ndarray
    delta: np.ndarray | None
    min_delta: float | None
    mechanism: str
    T: float
    steps: int
    q: np.ndarray | None = None

    @property
    def R_T(self) -> np.ndarray:
        """The endpoint ``R(T)``, a 3×3 matrix."""
        return self.R[-1]


@dataclass(frozen=True)
class Variational:
    """The trajectory with the variational system (9) along it (see :func:`variational`).

    Parameters
    ----------
    trajectory : Trajectory
        The simulated motion.
    Z : numpy.ndarray
        ``Z[n] = Φ(t_n, 0)^{-1}``, shape ``(n, d, d)``.
    M : numpy.ndarray
        The mobility matrix ``M(T)``.
    J : numpy.ndarray or None
        The Jacobian ``∂s_T/∂λ`` (d × len(λ)) of parametrised controls; ``None`` for a
        plain ``u(t)``.
    """

    trajectory: Trajectory
    Z: np.ndarray
    M: np.ndarray
    J: np.ndarray | None

    @property
    def Phi(self) -> np.ndarray:
        """``Φ(T, t_n)`` for every sample, shape ``(n, 3, 3)``."""
        return np.linalg.inv(self.Z[-1]) @ self.Z          # Φ(T, 0) Φ(t_n, 0)^{-1}


def stage_table(controls, T: float, steps: int, n_inputs: int) -> np.ndarray:
    """The integrator's input table ``U`` (see :mod:`nonholo.numerics.kernels`).

    Parameters
    ----------
    controls
        A :class:`~nonholo.controls.parametrisations.Controls` or a
        :class:`~nonholo.motion.frame_controls.FrameControls` (its ``T`` must equal ``T``)
        or a vectorised function ``u(t)``, ``t (n,) -> (n, m)``, evaluated at the stage
        times (use a ``Controls`` for discontinuous inputs: it keeps each step on one side
        of a jump).
    T : float
        The horizon (s).
    steps : int
        CF4 steps.
    n_inputs : int
        The mechanism's inputs ``m``.

    Returns
    -------
    numpy.ndarray
        ``U``, shape ``(steps, 3, m)``: the inputs at each step's three stage times.

    Raises
    ------
    ValueError
        If the controls are defined on another interval, return the wrong shape, have
        another number of inputs or non-finite values, or are not controls at all.
    """
    T = check_time(T)
    steps = check_count(steps, "steps", maximum=MAX_STEPS)
    if hasattr(controls, "stage_table") or isinstance(controls, Controls):
        if controls.T != T:
            raise ValueError(f"the controls are defined on [0, {controls.T:g}], not on [0, {T:g}]")
        U = stages.stage_table(controls, steps)
    elif callable(controls):
        t = stages.stage_times(T, steps).ravel()
        U = np.asarray(controls(t), dtype=float)
        if U.ndim == 1 and n_inputs == 1:
            U = U[:, None]
        if U.shape != (3 * steps, n_inputs):
            raise ValueError(
                f"controls(t) must return shape (len(t), {n_inputs}) for t of shape (n,); "
                f"got {U.shape} for n = {3 * steps}")
        U = U.reshape(steps, 3, n_inputs)
    else:
        raise ValueError("controls must be a nonholo.controls.parametrisations.Controls or a function u(t)")
    if U.shape[2] != n_inputs:
        raise ValueError(f"the controls have {U.shape[2]} inputs, the mechanism has {n_inputs}")
    if not np.all(np.isfinite(U)):
        raise ValueError("the controls have non-finite values")
    return np.ascontiguousarray(U, dtype=float)


def _sign_of_delta(mech, R0, q0) -> float:
    sign = mech.singular.sign(R0, q0)
    if sign == 0.0:
        raise ValueError(mech.singular.refusal)
    return sign


def _trajectory(mech, Rs, U, T, steps, n, dmin, sgn, Qs=None) -> Trajectory:
    h = T / steps
    t = np.arange(n + 1) * h
    if n == steps:
        t[-1] = T
    u = np.concatenate([U[:n, 0], U[steps - 1:steps, 2]]) if n == steps else U[:n + 1, 0]
    R = Rs[:n + 1].copy()
    q = None if Qs is None else mech.space.recorded("coordinates", Qs[:n + 1].copy())
    return Trajectory(t=t, R=R, u=u.copy(), delta=mech.singular.samples(R, q),
                      min_delta=mech.singular.reported(dmin),
                      mechanism=mech.name, T=T, steps=steps, q=q)


def _stopped(mech, n, t_stop, dmin, sgn, traj) -> SingularTrajectoryError:
    # without a singular set dmin is +inf (Δ ≡ +inf): the motion stopped on a non-finite rate
    if dmin <= 0.0:
        why = ("reaches the singular surface Δ = 0 (Δ changes sign between two integrator "
               "points: |ω| ~ 1/|Δ| blows up there)")
    elif dmin < DELTA_STOP:
        why = f"reaches the singular surface Δ = 0 (|Δ| = {dmin:.3g})"
    else:
        why = "produces a non-finite angular velocity"
    return SingularTrajectoryError(f"the trajectory {why} at t ≈ {t_stop:.6g} s", traj)


def _setup(R0, controls, T, mechanism, steps):
    """Checked inputs of a simulation: the mechanism, the start ``(R0, q0)``
    (:meth:`nonholo.spaces.product.Product.parse`), ``T``, ``steps``, its kernels, ``sgn Δ`` at the start and
    the controls' stage table."""
    mech = catalog.get(mechanism)
    R0, q0 = mech.parse_state(R0, "R0")
    T = check_time(T)
    steps = check_count(steps, "steps", maximum=MAX_STEPS)
    kern = compiled_system(mech)
    sgn = _sign_of_delta(mech, R0, q0)
    return mech, (R0, q0), T, steps, kern, sgn, stage_table(controls, T, steps, mech.n_inputs)


def simulate(R0, controls, T: float, *, mechanism="platform",
             steps: int = DEFAULT_STEPS) -> Trajectory:
    """Solve ``dR/dt = [L(R) u(t)] R``, ``R(0) = R0`` on ``[0, T]`` with ``steps`` CF4 steps.

    Parameters
    ----------
    R0
        The start: a rotation matrix, or for a mechanism whose state goes beyond SO(3) its
        coordinates ``q0`` or the pair ``(R0, q0)``
        (:meth:`nonholo.spaces.product.Product.parse`; the trajectory's ``q`` holds the
        coordinates).
    controls
        A :class:`~nonholo.controls.parametrisations.Controls`, a
        :class:`~nonholo.motion.frame_controls.FrameControls` or a vectorised ``u(t)``.
    T : float
        The horizon in seconds.
    mechanism : str or Mechanism
        A :class:`~nonholo.model.mechanism.Mechanism` or its name.
    steps : int
        CF4 steps on ``[0, T]``.

    Returns
    -------
    Trajectory
        The samples at ``t_n = n T/steps``.

    Raises
    ------
    ValueError
        For a bad ``R0``, ``T``, ``steps`` or controls, naming it.
    SingularTrajectoryError
        If the motion runs into ``Δ = 0``; it holds the part simulated before.
    """
    mech, (R0, q0), T, steps, kern, sgn, U = _setup(R0, controls, T, mechanism, steps)
    Rs, Qs = kern.nodes(steps)
    n, dmin, t_stop = kern.forward(R0, q0, U, T / steps, sgn, DELTA_STOP, Rs, Qs)
    traj = _trajectory(mech, Rs, U, T, steps, n, dmin, sgn, Qs)
    if n < steps:
        raise _stopped(mech, n, t_stop, dmin, sgn, traj)
    return traj


def variational(R0, controls, T: float, *, mechanism="platform",
                steps: int = DEFAULT_STEPS) -> Variational:
    """Simulate and integrate the variational system (9) along the motion.

    Parameters
    ----------
    R0, controls, T, mechanism, steps
        As for :func:`simulate`.

    Returns
    -------
    Variational
        ``Φ(T, t_n)`` (``.Phi``), ``M(T)`` (``.M``) and, when ``controls`` is a
        :class:`~nonholo.controls.parametrisations.Controls` linear in its parameters
        (Fourier or grid controls), ``J = ∂s_T/∂λ`` (``.J``): for a change ``δλ`` of the
        parameters the endpoint moves to ``exp([J δλ]) R_T`` to first order. For grid
        controls the columns ``(j, i)`` of ``J`` are the ``G_j = ∫_{I_j} Φ(T,t) B(t) dt`` of
        the nonparametric update.

    Raises
    ------
    ValueError
        For bad arguments, as :func:`simulate`.
    SingularTrajectoryError
        If the motion runs into ``Δ = 0``.
    """
    mech, (R0, q0), T, steps, kern, sgn, U = _setup(R0, controls, T, mechanism, steps)
    d = mech.n_rates
    linear = isinstance(controls, Controls)
    if linear:
        basis = stages.sparse_basis(controls, steps)
        J = np.empty((d, controls.params.size))
    else:
        # no parameters: an empty basis (the kernel then skips the Jacobian)
        basis = (np.zeros((steps, 3, 0), np.int64), np.zeros((steps, 3, 0)), 0, 0)
        J = np.empty((d, 0))
    Rs, Qs = kern.nodes(steps)
    Zs = np.empty((steps + 1, d, d))
    M = np.empty((d, d))
    n, dmin, t_stop = kern.forward_variational(R0, q0, U, T / steps, sgn, DELTA_STOP, *basis,
                                               Rs, Qs, Zs, J, M, np.empty((0, d * mech.n_inputs)), True)
    traj = _trajectory(mech, Rs, U, T, steps, n, dmin, sgn, Qs)
    if n < steps:
        raise _stopped(mech, n, t_stop, dmin, sgn, traj)
    return Variational(trajectory=traj, Z=Zs, M=M, J=J if linear else None)

