"""Multiple-shooting motion planner for the non-holonomic orienting platform
(CasADi + IPOPT), used as the baseline competitor in benchmarks.

Model (implemented here independently of the ``nonholo`` package)
------------------------------------------------------------------
The state is a rotation matrix ``R`` in SO(3) with entries ``r_ij`` (row i,
column j, 1-based).  The system is driftless and written in *spatial* form::

    dR/dt = [w] R,      w = L(R) u,      u = (u1, u2),

where ``w`` is the spatial angular velocity, ``[v]`` is the skew matrix with
``[v] x = v x x`` and::

    Delta(R) = r12 r31 + r21 r32,
    L(R)     = (2 / Delta) [[ r21,  r12],
                            [-r21, -r12],
                            [-r31,  r32]].

``L`` is singular on ``Delta = 0``; this surface splits SO(3) into two
components and no motion can cross it.  A goal ``Rd`` with
``sign(Delta(Rd)) != sign(Delta(R0))`` is therefore unreachable.

Roll-pitch-yaw convention: ``RPY(phi, theta, psi) = Rz(phi) Ry(theta) Rx(psi)``
(see :func:`rpy`).

Optimal control problem
-----------------------
Minimise ``int_0^T |u|^2 dt`` subject to the dynamics, ``R(0) = R0``,
``R(T) = Rd`` and the path constraint ``sign(Delta(R0)) Delta(R) >= delta_min``
(enforced at the shooting nodes, optionally also at the integrator substeps);
optionally the legs' stroke ``lo <= l_i(R) <= hi`` at the nodes, with the
paper's leg lengths ``l_1^2 = a^2 + b^2 - 2ab r22``, ``l_2^2 = a^2 + b^2 - 2ab r11``
(``a = LEG_A``, ``b = LEG_B``, the drawing dimensions of ``nonholo``'s platform),
and their speeds ``|dl_i/dt| = 2ab |u_i| / l_i <= v`` (the inputs are the scaled
rates ``u_i = d(l_i^2)/dt / (4ab)``) at both ends of every interval.
It is transcribed by multiple shooting on a uniform grid of ``N`` intervals
with piecewise-constant controls and solved by IPOPT with exact Hessians; see
:func:`solve`.

State representation and integrator
-----------------------------------
Each shooting node carries the 9 entries of ``R`` (row-major).  ``Delta`` and
``L`` are polynomial/rational in these entries, so no conversion is needed and
there is no double-cover ambiguity as with unit quaternions.  Each interval is
integrated by ``substeps`` steps of a Runge-Kutta-Munthe-Kaas method of order 4
(classical RK4 tableau) that uses the Cayley map as coordinate map::

    cay(c)          = I + 4 / (4 + |c|^2) ([c] + [c]^2 / 2),
    dcay_c^{-1}(a)  = a - c x a / 2 + (c . a) c / 4.

Both maps are rational in ``c`` (no ``sin(|c|)/|c|`` removable singularities
in the derivatives) and ``cay(c)`` is exactly orthogonal, so every
integration step maps SO(3) to SO(3) up to round-off.  Consequently the
continuity constraints keep all nodes on SO(3) without any normalisation
constraint, and the terminal condition ``R(T) = Rd`` needs only 3 equations.

Accuracy caveat
---------------
Near the singular surface ``|w| ~ |u| / |Delta|`` while ``d(Delta^2)/dt`` stays
bounded, so the dynamics become fast and very sensitive there.  When the
optimal motion rides the path constraint with a small ``delta_min``, a fixed
uniform grid can be far too coarse: the discrete solution then satisfies all
NLP constraints while the continuous re-simulation of the same controls misses
the goal.  ``CasadiResult.success`` only certifies the discrete model; use
:func:`resimulate` and :func:`terminal_error` to verify a plan.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Optional, Sequence, Union

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation, Slerp

__all__ = [
    "CasadiResult",
    "solve",
    "resimulate",
    "terminal_error",
    "delta",
    "leg_lengths",
    "input_matrix",
    "rpy",
    "make_step_function",
    "SUCCESS_TOL",
]

#: Threshold on the terminal error (rotation angle, rad) of the discrete
#: rollout of the returned controls for a solve to count as successful.
SUCCESS_TOL = 1e-6

_OK_STATUSES = ("Solve_Succeeded", "Solved_To_Acceptable_Level")

#: Base-joint distance ``a`` and platform-joint distance ``b`` of the legs (the
#: geometry's units): only the stroke constraint uses them.
LEG_A = 1.6
LEG_B = 1.0


def leg_lengths(R: np.ndarray) -> np.ndarray:
    """``(l_1, l_2)`` of the paper's platform at ``R``."""
    R = np.asarray(R, dtype=float).reshape(3, 3)
    c = LEG_A**2 + LEG_B**2
    return np.sqrt([c - 2 * LEG_A * LEG_B * R[1, 1], c - 2 * LEG_A * LEG_B * R[0, 0]])


# ---------------------------------------------------------------------------
# Numeric model (numpy)
# ---------------------------------------------------------------------------
def rpy(phi: float, theta: float, psi: float) -> np.ndarray:
    """Rotation matrix ``Rz(phi) @ Ry(theta) @ Rx(psi)``."""
    return Rotation.from_euler("ZYX", [phi, theta, psi]).as_matrix()


def delta(R: np.ndarray) -> float:
    """``Delta(R) = r12 r31 + r21 r32`` (1-based indices)."""
    R = np.asarray(R, dtype=float)
    return R[0, 1] * R[2, 0] + R[1, 0] * R[2, 1]


def input_matrix(R: np.ndarray) -> np.ndarray:
    """The 3x2 matrix ``L(R)`` mapping ``u`` to the spatial angular velocity."""
    R = np.asarray(R, dtype=float)
    r12, r21, r31, r32 = R[0, 1], R[1, 0], R[2, 0], R[2, 1]
    d = r12 * r31 + r21 * r32
    return (2.0 / d) * np.array([[r21, r12], [-r21, -r12], [-r31, r32]])


def _hat(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


# ---------------------------------------------------------------------------
# Symbolic model (CasADi)
# ---------------------------------------------------------------------------
def _mat(x):
    """9-vector of row-major entries -> 3x3 matrix."""
    return ca.reshape(x, 3, 3).T


def _vec(M):
    """3x3 matrix -> 9-vector of row-major entries."""
    return ca.reshape(M.T, 9, 1)


def _delta_sym(R):
    return R[0, 1] * R[2, 0] + R[1, 0] * R[2, 1]


def _omega_sym(R, u):
    """Spatial angular velocity ``L(R) u``."""
    r12, r21, r31, r32 = R[0, 1], R[1, 0], R[2, 0], R[2, 1]
    s = 2.0 / (r12 * r31 + r21 * r32)
    a = r21 * u[0] + r12 * u[1]
    return ca.vertcat(s * a, -s * a, s * (-r31 * u[0] + r32 * u[1]))


def _cay(c):
    """Cayley map so(3) -> SO(3) in vector form."""
    C = ca.skew(c)
    return ca.SX.eye(3) + (4.0 / (4.0 + ca.dot(c, c))) * (C + 0.5 * ca.mtimes(C, C))


def _dcayinv(c, a):
    """Inverse of the right-trivialised differential of the Cayley map."""
    return a - 0.5 * ca.cross(c, a) + 0.25 * ca.dot(c, a) * c


def make_step_function(substeps: int) -> ca.Function:
    """CasADi function ``Phi(x, u, H) -> (x_next, d_inner)`` for one interval.

    ``x`` holds the 9 row-major entries of ``R``, ``u`` the (constant) control
    and ``H`` the interval length; the interval is covered by ``substeps``
    RKMK4 steps with the Cayley map (order 4, exactly orthogonal updates).
    ``d_inner`` holds ``Delta`` at the ``substeps - 1`` interior substep
    points (used for the path constraint between nodes).
    """
    x = ca.SX.sym("x", 9)
    u = ca.SX.sym("u", 2)
    H = ca.SX.sym("H")
    h = H / substeps
    R = _mat(x)
    d_inner = []
    for i in range(substeps):
        k1 = _omega_sym(R, u)
        c2 = 0.5 * h * k1
        k2 = _dcayinv(c2, _omega_sym(ca.mtimes(_cay(c2), R), u))
        c3 = 0.5 * h * k2
        k3 = _dcayinv(c3, _omega_sym(ca.mtimes(_cay(c3), R), u))
        c4 = h * k3
        k4 = _dcayinv(c4, _omega_sym(ca.mtimes(_cay(c4), R), u))
        c = (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        R = ca.mtimes(_cay(c), R)
        if i < substeps - 1:
            d_inner.append(_delta_sym(R))
    return ca.Function(
        "step",
        [x, u, H],
        [_vec(R), ca.vertcat(*d_inner) if d_inner else ca.SX(0, 1)],
        ["x", "u", "H"],
        ["x_next", "d_inner"],
    )


# ---------------------------------------------------------------------------
# NLP construction (cached per discretisation / solver options)
# ---------------------------------------------------------------------------
@dataclass
class _Problem:
    solver: ca.Function
    rollout: ca.Function  # (x0, U[2xN], H) -> X[9xN]
    n: int
    nx_w: int  # decision-variable count
    lbg: np.ndarray
    ubg: np.ndarray
    idx_u: np.ndarray  # (N, 2) indices into w
    idx_x: np.ndarray  # (N, 9) indices into w (nodes 1..N)


_CACHE: dict = {}


def _build(
    N: int,
    substeps: int,
    max_iter: int,
    tol: float,
    verbose: bool,
    path_at_substeps: bool,
    stroke: bool = False,
    speed: bool = False,
) -> _Problem:
    step = make_step_function(substeps)

    # Parameters: R0 (9), Rd (9), T, sign(Delta(R0)), delta_min, lo^2, hi^2, v_max^2.
    p = ca.MX.sym("p", 24)
    x0, xd, T, sgn, dmin, lo2, hi2, v2 = p[0:9], p[9:18], p[18], p[19], p[20], p[21], p[22], p[23]
    H = T / N

    # Decision variables interleaved as [u_0, x_1, u_1, x_2, ..., u_{N-1}, x_N]
    # so that the KKT matrix is banded.
    u_syms = [ca.MX.sym(f"u{k}", 2) for k in range(N)]
    x_syms = [ca.MX.sym(f"x{k + 1}", 9) for k in range(N)]
    w = ca.vertcat(*[v for k in range(N) for v in (u_syms[k], x_syms[k])])
    U = ca.horzcat(*u_syms)
    X = ca.horzcat(*x_syms)
    idx_u = np.array([[11 * k, 11 * k + 1] for k in range(N)])
    idx_x = np.array([[11 * k + 2 + i for i in range(9)] for k in range(N)])

    Xnext, Dinner = step.map(N)(ca.horzcat(x0, X[:, : N - 1]), U, H)

    g, lbg, ubg = [], [], []
    for k in range(N):
        g.append(Xnext[:, k] - X[:, k])  # continuity
        lbg += [0.0] * 9
        ubg += [0.0] * 9
        # Path constraint at the interior substep points and at node k+1.
        nd = (substeps - 1 if path_at_substeps else 0) + 1
        d = ca.vertcat(Dinner[:, k], _delta_sym(_mat(X[:, k])))
        g.append(sgn * d[-nd:] - dmin)
        lbg += [0.0] * nd
        ubg += [np.inf] * nd
        if stroke:  # lo^2 <= l_i^2 <= hi^2 at node k+1
            Xk = _mat(X[:, k])
            sq = LEG_A**2 + LEG_B**2 - 2 * LEG_A * LEG_B * ca.vertcat(Xk[1, 1], Xk[0, 0])
            g.append(ca.vertcat(sq - lo2, hi2 - sq))
            lbg += [0.0] * 4
            ubg += [np.inf] * 4
        if speed:  # (2ab u_i)^2 <= v^2 l_i^2 at both ends of interval k (u_k is constant on it)
            for Xe in ((_mat(x0) if k == 0 else _mat(X[:, k - 1])), _mat(X[:, k])):
                sq = LEG_A**2 + LEG_B**2 - 2 * LEG_A * LEG_B * ca.vertcat(Xe[1, 1], Xe[0, 0])
                g.append(v2 * sq - (2 * LEG_A * LEG_B * U[:, k]) ** 2)
                lbg += [0.0] * 2
                ubg += [np.inf] * 2

    # Terminal constraint: E = Rd^T R(T) is a rotation (guaranteed by the
    # dynamics); vee(E - E^T) = 0 leaves E in {I} U {rotations by pi}; the
    # inequality trace(E) >= 0 (rotation angle <= 120 deg) removes the
    # rotations by pi, so the 3 equations characterise R(T) = Rd and are
    # regular (Jacobian = identity in local coordinates) at the solution.
    E = ca.mtimes(_mat(xd).T, _mat(X[:, N - 1]))
    g.append(ca.vertcat(E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]))
    lbg += [0.0] * 3
    ubg += [0.0] * 3
    g.append(ca.trace(E))
    lbg.append(0.0)
    ubg.append(np.inf)

    f = H * ca.sumsqr(U)
    nlp = {"x": w, "p": p, "f": f, "g": ca.vertcat(*g)}
    opts = {
        "expand": True,
        "print_time": bool(verbose),
        "ipopt.print_level": 5 if verbose else 0,
        "ipopt.sb": "yes",
        "ipopt.max_iter": int(max_iter),
        "ipopt.tol": float(tol),
        "ipopt.constr_viol_tol": max(float(tol), 1e-12),
    }
    solver = ca.nlpsol("solver", "ipopt", nlp, opts)

    xs = ca.MX.sym("x0", 9)
    Us = ca.MX.sym("U", 2, N)
    Hs = ca.MX.sym("H")
    roll = step.mapaccum("rollout", N)
    rollout = ca.Function("rollout", [xs, Us, Hs], [roll(xs, Us, Hs)[0]]).expand()

    return _Problem(
        solver=solver,
        rollout=rollout,
        n=N,
        nx_w=11 * N,
        lbg=np.array(lbg),
        ubg=np.array(ubg),
        idx_u=idx_u,
        idx_x=idx_x,
    )


# ---------------------------------------------------------------------------
# Result
# ---------------------------------------------------------------------------
@dataclass
class CasadiResult:
    """Outcome of :func:`solve`.

    Attributes
    ----------
    success : IPOPT converged (``Solve_Succeeded`` or
        ``Solved_To_Acceptable_Level``) *and* the discrete rollout of ``u``
        from ``R0`` ends within ``SUCCESS_TOL`` rad of ``Rd``.
    status : IPOPT return status string.
    u : (N, 2) piecewise-constant controls, ``u[k]`` on ``[t_k, t_{k+1})``.
    t_grid : (N+1,) interval boundaries ``0 = t_0 < ... < t_N = T``.
    seconds : wall time of the IPOPT call only.
    build_seconds : wall time spent building the NLP for this call (0.0 when a
        cached solver was reused).
    iterations : IPOPT iteration count.
    objective : ``sum_k h |u_k|^2``.
    R_nodes : (N+1, 3, 3) shooting-node states of the solution.
    terminal_violation : rotation angle between the discrete rollout of ``u``
        (the model integrator, not the NLP node) and ``Rd``.
    min_delta : minimum of ``sign(Delta(R0)) Delta`` over the nodes.
    """

    success: bool
    status: str
    u: np.ndarray
    t_grid: np.ndarray
    seconds: float
    build_seconds: float
    iterations: int
    objective: float = float("nan")
    R_nodes: Optional[np.ndarray] = None
    terminal_violation: float = float("nan")
    min_delta: float = float("nan")
    N: int = 0
    substeps: int = 0
    T: float = 1.0
    info: dict = field(default_factory=dict)

    def controls(self, t) -> np.ndarray:
        """Piecewise-constant control at times ``t`` (shape (n,) -> (n, 2)).

        Right-continuous: on ``[t_k, t_{k+1})`` the value is ``u[k]``; the last
        interval is closed at ``T``.  Times outside ``[0, T]`` are clamped.
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        k = np.searchsorted(self.t_grid, t, side="right") - 1
        k = np.clip(k, 0, len(self.u) - 1)
        return self.u[k]


# ---------------------------------------------------------------------------
# Solver
# ---------------------------------------------------------------------------
def solve(
    R0,
    Rd,
    T: float = 1.0,
    N: int = 40,
    substeps: int = 4,
    delta_min: float = 0.01,
    u_init=None,
    max_iter: int = 500,
    tol: float = 1e-10,
    verbose: bool = False,
    *,
    path_at_substeps: bool = False,
    reuse_solver: bool = True,
    leg_length=None,
    leg_speed=None,
) -> CasadiResult:
    """Plan a minimum-energy motion from ``R0`` to ``Rd`` in time ``T``.

    Parameters
    ----------
    R0, Rd : (3, 3) rotation matrices (initial and goal orientation).
    T : final time.
    N : number of shooting intervals (piecewise-constant controls).
    substeps : RKMK4/Cayley steps per interval.
    delta_min : path-constraint margin, ``sign(Delta(R0)) Delta(R_k) >=
        delta_min`` at every node.
    u_init : optional (N, 2) initial guess for the controls.  Default
        ``u1 = 0.3 sin(2 pi t/T)``, ``u2 = 0.3 cos(2 pi t/T)`` at the interval
        midpoints.  Node states are initialised by forward simulation of the
        guess (falling back to geodesic interpolation R0 -> Rd if that
        simulation leaves the component of ``R0``).
    max_iter, tol : IPOPT ``max_iter`` and ``tol`` (``constr_viol_tol`` is
        set to ``tol`` as well).
    verbose : print IPOPT output.
    path_at_substeps : also impose the path constraint at the interior
        substep points of every interval (not only at the nodes).  This keeps
        the discrete trajectory from stepping over the singular surface
        between nodes, where ``|w| ~ |u| / |Delta|`` becomes large.
    leg_length : ``(lo, hi)``: keep both legs' lengths (:func:`leg_lengths`)
        within it at every node; ``None``: no stroke constraint.
    leg_speed : ``v``: keep both legs' speeds ``|dl_i/dt| = 2ab|u_i|/l_i <= v``
        at both ends of every interval (``u`` is constant on it); ``None``: no
        speed constraint.
    reuse_solver : the NLP is parametric in ``(R0, Rd, T, delta_min)``; when
        True a solver built earlier for the same ``(N, substeps, max_iter,
        tol, verbose, path_at_substeps)`` is reused and ``build_seconds`` is 0.

    Raises
    ------
    ValueError
        Immediately (before building anything) if the goal is unreachable or
        incompatible with the path constraint: ``|Delta(R0)| < delta_min``,
        ``|Delta(Rd)| < delta_min`` or ``sign(Delta(Rd)) != sign(Delta(R0))``
        (the goal lies in the other component of ``SO(3) \\ {Delta = 0}``).
    """
    R0 = np.asarray(R0, dtype=float).reshape(3, 3)
    Rd = np.asarray(Rd, dtype=float).reshape(3, 3)
    N = int(N)
    substeps = int(substeps)
    if N < 1 or substeps < 1:
        raise ValueError("N and substeps must be positive")
    if not T > 0:
        raise ValueError("T must be positive")
    d0, dd = delta(R0), delta(Rd)
    if abs(d0) < delta_min:
        raise ValueError(f"|Delta(R0)| = {abs(d0):.3g} < delta_min = {delta_min}")
    if np.sign(dd) != np.sign(d0):
        raise ValueError(
            f"unreachable goal: Delta(R0) = {d0:.3g} and Delta(Rd) = {dd:.3g} "
            "lie in different components of SO(3) minus {Delta = 0}"
        )
    if abs(dd) < delta_min:
        raise ValueError(f"|Delta(Rd)| = {abs(dd):.3g} < delta_min = {delta_min}")
    sgn = float(np.sign(d0))

    # --- build (or reuse) the NLP -------------------------------------------
    stroke = leg_length is not None
    speed = leg_speed is not None
    key = (N, substeps, int(max_iter), float(tol), bool(verbose), bool(path_at_substeps), stroke, speed)
    t_build = time.perf_counter()
    prob = _CACHE.get(key) if reuse_solver else None
    if prob is None:
        prob = _build(N, substeps, max_iter, tol, verbose, path_at_substeps, stroke, speed)
        if reuse_solver:
            _CACHE[key] = prob
        build_seconds = time.perf_counter() - t_build
    else:
        build_seconds = 0.0

    # --- initial guess ---------------------------------------------------------
    t_grid = np.linspace(0.0, T, N + 1)
    H = T / N
    if u_init is None:
        tm = 0.5 * (t_grid[:-1] + t_grid[1:])
        U0 = np.column_stack(
            [0.3 * np.sin(2 * np.pi * tm / T), 0.3 * np.cos(2 * np.pi * tm / T)]
        )
    else:
        U0 = np.asarray(u_init, dtype=float).reshape(N, 2)
    X0 = np.asarray(prob.rollout(R0.reshape(9), U0.T, H))  # (9, N)
    ok_guess = np.all(np.isfinite(X0)) and all(
        sgn * delta(X0[:, k].reshape(3, 3)) > 0 for k in range(N)
    )
    if not ok_guess:
        slerp = Slerp([0.0, T], Rotation.from_matrix(np.stack([R0, Rd])))
        X0 = slerp(t_grid[1:]).as_matrix().reshape(N, 9).T

    w0 = np.zeros(prob.nx_w)
    w0[prob.idx_u] = U0
    w0[prob.idx_x] = X0.T
    lo, hi = leg_length if stroke else (0.0, np.inf)
    v2 = float(leg_speed) ** 2 if speed else 0.0
    p = np.concatenate([R0.reshape(9), Rd.reshape(9), [T, sgn, delta_min, lo**2, min(hi**2, 1e300), v2]])

    # --- solve -----------------------------------------------------------------
    t_solve = time.perf_counter()
    sol = prob.solver(x0=w0, p=p, lbg=prob.lbg, ubg=prob.ubg)
    seconds = time.perf_counter() - t_solve
    stats = prob.solver.stats()

    w = np.asarray(sol["x"]).ravel()
    u = w[prob.idx_u]
    R_nodes = np.concatenate([R0[None], w[prob.idx_x].reshape(N, 3, 3)], axis=0)
    X_roll = np.asarray(prob.rollout(R0.reshape(9), u.T, H))
    term_viol = terminal_error(X_roll[:, -1].reshape(3, 3), Rd)
    status = str(stats.get("return_status", "unknown"))
    success = (
        status in _OK_STATUSES and np.isfinite(term_viol) and term_viol <= SUCCESS_TOL
    )
    return CasadiResult(
        success=bool(success),
        status=status,
        u=u,
        t_grid=t_grid,
        seconds=seconds,
        build_seconds=build_seconds,
        iterations=int(stats.get("iter_count", -1)),
        objective=float(sol["f"]),
        R_nodes=R_nodes,
        terminal_violation=float(term_viol),
        min_delta=float(min(sgn * delta(R) for R in R_nodes)),
        N=N,
        substeps=substeps,
        T=float(T),
        info={"initial_guess": "rollout" if ok_guess else "slerp"},
    )


# ---------------------------------------------------------------------------
# Independent verification
# ---------------------------------------------------------------------------
def _rhs(u_of_t: Callable[[float], np.ndarray]):
    def f(t, y):
        R = y.reshape(3, 3)
        w = input_matrix(R) @ u_of_t(t)
        return (_hat(w) @ R).ravel()

    return f


def resimulate(
    R0,
    controls: Union[Callable, np.ndarray],
    T: float,
    breakpoints: Optional[Sequence[float]] = None,
    *,
    return_path: bool = False,
    samples_per_segment: int = 11,
):
    """Re-simulate ``dR/dt = [L(R) u(t)] R`` from ``R0`` with DOP853.

    Integrates the 9 entries of ``R`` with
    ``solve_ivp(method="DOP853", rtol=1e-12, atol=1e-12)``.

    Parameters
    ----------
    controls : callable mapping an array ``t`` of shape (n,) to (n, 2), e.g.
        :meth:`CasadiResult.controls`; or an (N, 2) array interpreted as
        piecewise-constant controls on the uniform grid of ``[0, T]`` (its
        grid is then used as ``breakpoints`` if none are given).
    breakpoints : optional times of control discontinuities.  The integration
        is restarted at every breakpoint, and on a segment ``[a, b]`` the
        control is evaluated at ``t`` clamped to ``[a, b)`` (``b`` replaced by
        the previous floating-point number), so a right-continuous
        piecewise-constant control contributes its value on that segment only.
    return_path : also return sample times and states (``samples_per_segment``
        equally spaced points per segment, from dense output).

    Returns
    -------
    ``R(T)`` as a (3, 3) array, or ``(R(T), t, R(t))`` with ``R(t)`` of shape
    (m, 3, 3) if ``return_path``.
    """
    R0 = np.asarray(R0, dtype=float).reshape(3, 3)
    if not callable(controls):
        U = np.asarray(controls, dtype=float).reshape(-1, 2)
        grid = np.linspace(0.0, T, len(U) + 1)
        if breakpoints is None:
            breakpoints = grid

        def controls(t, U=U, grid=grid):  # noqa: F811
            k = np.clip(np.searchsorted(grid, t, side="right") - 1, 0, len(U) - 1)
            return U[k]

    pts = [0.0, float(T)]
    if breakpoints is not None:
        pts += [float(b) for b in breakpoints if 0.0 < b < T]
    pts = np.unique(pts)

    y = R0.ravel()
    ts, Rs = [], []
    for a, b in zip(pts[:-1], pts[1:]):
        b_left = np.nextafter(b, a)

        def u_of_t(t, a=a, b_left=b_left):
            tc = min(max(t, a), b_left)
            return np.asarray(controls(np.array([tc])), dtype=float).reshape(2)

        sol = solve_ivp(
            _rhs(u_of_t),
            (a, b),
            y,
            method="DOP853",
            rtol=1e-12,
            atol=1e-12,
            dense_output=return_path,
        )
        if not sol.success:
            raise RuntimeError(f"re-simulation failed on [{a}, {b}]: {sol.message}")
        if return_path:
            tt = np.linspace(a, b, samples_per_segment)
            ts.append(tt)
            Rs.append(sol.sol(tt).T.reshape(-1, 3, 3))
        y = sol.y[:, -1]
    RT = y.reshape(3, 3)
    if return_path:
        return RT, np.concatenate(ts), np.concatenate(Rs, axis=0)
    return RT


def terminal_error(RT, Rd) -> float:
    """Rotation angle (rad) of ``RT @ Rd.T``, i.e. the norm of its rotation vector.

    Returns ``inf`` if ``RT`` contains non-finite entries.
    """
    E = np.asarray(RT, dtype=float) @ np.asarray(Rd, dtype=float).T
    if not np.all(np.isfinite(E)):
        return float("inf")
    return float(np.linalg.norm(Rotation.from_matrix(E).as_rotvec()))


def _demo() -> None:  # pragma: no cover - manual timing helper
    """Time the solver on the reference example for a few discretisations."""
    R0, Rd = rpy(0.5, 1.2, -0.5), rpy(1.0, 0.9, -0.5)
    for N, sub in ((40, 4), (40, 1), (20, 2), (80, 2)):
        _CACHE.clear()
        first = solve(R0, Rd, N=N, substeps=sub)  # warm-up, includes the build
        runs = [solve(R0, Rd, N=N, substeps=sub) for _ in range(5)]
        RT = resimulate(R0, first.controls, 1.0, breakpoints=first.t_grid)
        print(
            f"N={N:3d} substeps={sub}: success={first.success} "
            f"iterations={first.iterations} build={first.build_seconds:.2f}s "
            f"solve(median of 5)={np.median([r.seconds for r in runs]) * 1e3:.1f}ms "
            f"resimulated terminal error={terminal_error(RT, Rd):.2e}"
        )


if __name__ == "__main__":  # pragma: no cover
    _demo()
