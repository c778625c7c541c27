"""Helpers shared by the test modules (plain functions: ``from conftest import example``).

- :func:`example`: ``(R0, Rd)`` of an example of :mod:`nonholo.paper.examples`;
- :func:`check_solution`: a planner result confirmed by an independent DOP853 re-simulation;
- :func:`verified`: the same check as the robust-strategy benchmark (dense path, ``|Δ|``);
- :func:`reachable_goals`, :func:`paper_reachable_goals`: goals reachable by construction;
- :func:`regular_motion`: a start, a reachable goal and a control, regular for a mechanism;
- :func:`random_rotations`: random rotations away from a mechanism's singular set;
- :func:`forbid_simulation`: make any simulation (or kernel compilation) fail the test;
- fixture ``interpreted_kernels``: every system's kernels run by the interpreter (:mod:`kernel_runs`).
- :func:`assert_inputs_match`: inputs computed by two different code paths, equal up to round-off.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from nonholo.certify.resimulate import resimulate, resimulate_path, resimulate_rk4, terminal_error
from nonholo.controls.parametrisations import Fourier, paper_initial
from nonholo.generated import MECHANISMS as GENERATED_MECHANISMS
from nonholo.model import catalog
from nonholo.paper import examples
from nonholo.spaces import so3


def example(k: int) -> tuple[np.ndarray, np.ndarray]:
    """``(R0, Rd)`` of example ``k`` (:func:`nonholo.paper.examples.get`)."""
    ex = examples.get(k)
    return ex.R_start, ex.R_goal


def example_rpy_args(k: int) -> tuple[list[str], list[str]]:
    """The RPY angles of example ``k``'s start and goal as command-line arguments
    (``nonholo plan --from φ ϑ ψ --to φ ϑ ψ``)."""
    ex = examples.get(k)
    return [repr(float(x)) for x in ex.rpy_start], [repr(float(x)) for x in ex.rpy_goal]


def platform_delta(R) -> float:
    """The paper's ``Δ(R) = r12 r31 + r21 r32``, written out independently of
    the generated code."""
    return R[0, 1] * R[2, 0] + R[1, 0] * R[2, 1]


#: How far apart (relative to the inputs' largest magnitude, at least 1) two samples of the
#: same inputs computed by different code paths may be: the certified replay's stage table
#: (``res.u``) and the parametrisation evaluated at ``t`` (``res.controls(t)``), or frame
#: controls whose nodes the planner's variational kernel gave and the same controls loaded
#: from a file, which re-integrate their nodes with the forward kernel. The two agree up to
#: round-off, which depends on the CPU (2e-16 to 3e-16 apart on an Intel Xeon): not bit for
#: bit. A sample taken at the wrong time, on the wrong side of a jump or of another control
#: is off by far more.
INPUTS_ROUND_OFF = 1e-12


def assert_inputs_match(actual, desired, err_msg=""):
    """``actual`` equals ``desired`` up to :data:`INPUTS_ROUND_OFF` times the larger of 1 and
    ``max|desired|`` (absolute, no relative part): for samples of inputs computed by two
    different code paths (bit-equality only where it is the same computation)."""
    desired = np.asarray(desired, dtype=float)
    scale = max(1.0, float(np.abs(desired).max(initial=0.0)))
    np.testing.assert_allclose(actual, desired, rtol=0, atol=INPUTS_ROUND_OFF * scale, err_msg=err_msg)


def check_solution(res, R0, Rd, tol=1e-10, mechanism=None):
    """Converged, Δ kept, and confirmed by an independent DOP853 re-simulation.

    ``mechanism``: the mechanism to re-simulate with (default: the result's, by name).
    """
    mech = catalog.get(res.mechanism if mechanism is None else mechanism)
    assert res.success, res.reason
    assert res.terminal_error <= tol
    R_T = resimulate(R0, res.controls, res.T, mech, res.breakpoints)
    assert terminal_error(R_T, Rd) <= 1e-8
    # the planner's own endpoint is within the integrator's discretisation error (≤ 1e-9)
    assert so3.distance(res.R_T, R_T) <= 1e-9
    if mech.delta is not None:
        assert res.min_delta >= res.options["delta_min"]
        assert np.abs(res.delta).min() >= res.min_delta - 1e-15
    else:
        assert res.min_delta is None and res.delta is None
    assert res.R.shape == (res.steps + 1, 3, 3) and res.u.shape == (res.steps + 1, mech.n_inputs)
    # the replay's stage values against the parametrisation at t: two computations
    assert_inputs_match(res.u, res.controls(res.t))
    return R_T


def verified(res, R0, Rd, T=1.0, mechanism=None):
    """Success as in the benchmark: DOP853 re-simulation of the physical ``controls(t)``
    ends within 1e-8 rad of ``Rd`` and keeps ``|Δ| ≥ 1e-2`` on the dense path."""
    mech = catalog.get(res.mechanism if mechanism is None else mechanism)
    assert res.success, res.reason
    RT = resimulate(R0, res.controls, T, mech, res.breakpoints)
    assert terminal_error(RT, Rd) <= 1e-8
    _, _, d = resimulate_path(R0, res.controls, T, mech, res.breakpoints, samples=501)
    assert np.min(np.sign(mech.delta(R0)) * d) >= 1e-2
    assert res.min_delta >= 1e-2
    # the replay's stage values against the parametrisation at t: two computations
    assert_inputs_match(res.u, res.controls(res.t))


def reachable_goals(mechanism, count, seed):
    """Goals made by simulating random Fourier controls from random starts, keeping
    |Δ| ≥ 0.1 along the way (mechanisms with a singular set) — reachable by construction.

    ``mechanism``: a :class:`nonholo.Mechanism` or a name.
    """
    from nonholo import simulate

    mech = catalog.get(mechanism)
    rng = np.random.default_rng(seed)
    goals = []
    while len(goals) < count:
        R0 = Rotation.random(random_state=rng.integers(1 << 31)).as_matrix()
        if mech.delta is not None and abs(mech.delta(R0)) < 0.3:
            continue
        controls = Fourier(1.0, rng.normal(scale=0.4, size=(mech.n_inputs, 5)))
        try:
            traj = simulate(R0, controls, 1.0, mechanism=mech)
        except ValueError:  # ran into Δ = 0
            continue
        if mech.delta is not None and np.min(np.abs(traj.delta)) < 0.1:
            continue
        goals.append((R0, traj.R_T))
    return goals


def regular_motion(mechanism, seed: int, clearance: float = 0.1):
    """``(R0, Rd, u)`` for a mechanism on SO(3), whatever its regular region: a goal ``Rd``
    reachable from ``R0`` (:func:`reachable_goals`) and a small random Fourier control ``u``
    whose motion from ``R0`` over ``[0, 1]`` keeps ``|Δ| ≥ clearance`` (drawn again until it
    does)."""
    from nonholo import simulate

    mech = catalog.get(mechanism)
    rng = np.random.default_rng(seed)
    for _ in range(100):
        R0, Rd = reachable_goals(mech, 1, seed=int(rng.integers(1 << 31)))[0]
        u = Fourier(1.0, rng.normal(scale=0.1, size=(mech.n_inputs, 5)))
        try:
            traj = simulate(R0, u, 1.0, mechanism=mech)
        except ValueError:  # ran into Δ = 0
            continue
        if mech.delta is None or np.min(np.abs(traj.delta)) >= clearance:
            return R0, Rd, u
    raise AssertionError(f"no regular start and control of {mech.name!r}")


def paper_reachable_goals(count: int, seed: int = 0):
    """Goals of the platform reachable by construction: ``Rd`` = endpoint of a random
    Fourier control.

    Start with ``|Δ(R0)| ≥ 0.5``, random coefficients (σ = 0.3), ``|Δ| ≥ 0.1`` along the
    generating motion; and (the paper's algorithm starts from an admissible control) the
    default initial control must keep ``|Δ| ≥ delta_min`` from ``R0``. Measured on 200
    such goals the plain algorithm still fails on about 5 % (the θ-flow steers into
    Δ = delta_min, see ``test_planner.test_hard_goal_fails_gracefully``); without the last
    condition another ~18 % of goals fail at once because the default initial control
    itself runs into Δ = 0.
    """
    from nonholo.motion import simulation as S

    mech = catalog.get("platform")
    u0 = Fourier.fit(paper_initial(1.0), 1.0, 2)
    rng = np.random.default_rng(seed)
    goals = []
    while len(goals) < count:
        R0 = so3.exp(1.5 * rng.normal(size=3))
        u = Fourier(1.0, 0.3 * rng.normal(size=(2, 5)))
        if abs(mech.delta(R0)) < 0.5:
            continue
        try:
            if S.simulate(R0, u0, 1.0).min_delta < 1e-2:
                continue
            tr = S.simulate(R0, u, 1.0)
        except S.SingularTrajectoryError:
            continue
        if tr.min_delta >= 0.1:
            goals.append((R0, tr.R_T))
    return goals


def random_rotations(n, rng, min_abs_delta=0.05, delta=platform_delta):
    """``n`` random rotations with ``|delta(R)| > min_abs_delta`` (away from Δ = 0, where
    L and Q are undefined); ``delta=None``: no condition."""
    out = []
    while len(out) < n:
        R = Rotation.random(random_state=rng.integers(1 << 31)).as_matrix()
        if delta is None or abs(delta(R)) > min_abs_delta:
            out.append(R)
    return out


def forbid_simulation(monkeypatch):
    """Make every way into the integrator fail the test: compiling or fetching kernels
    (:func:`nonholo.integrate.system_kernels.compile_system`, which
    :func:`nonholo.integrate.compiled.compiled_system` calls) and building a planning
    :class:`~nonholo.planning.endpoint_map.EndpointMap`. Raises ``AssertionError`` (not a
    ``ValueError``), so a ``pytest.raises(ValueError)`` around the call does not swallow it."""
    from nonholo.integrate import system_kernels
    from nonholo.planning import endpoint_map

    def forbidden(*args, **kwargs):
        raise AssertionError("simulated (or compiled kernels) although nothing should be simulated")

    monkeypatch.setattr(system_kernels, "compile_system", forbidden)
    monkeypatch.setattr(endpoint_map.EndpointMap, "__init__", forbidden)


def check_into_forms(module, rotations, rng):
    """The generated ``NAME_into(..., out)`` functions of ``module`` fill ``out`` with exactly
    what the allocating ``NAME(...)`` return, at every rotation of ``rotations``.

    ``out`` is pre-filled with NaN, so an entry the ``_into`` form leaves unwritten fails.
    Returns the names checked."""
    m = module.N_INPUTS
    q = module.NO_COORDINATES
    # name: (shape, takes the coordinates, takes inputs); L and Q: the paper's G and QG
    forms = {"G": ((3, m), True, False), "QG": ((3, 3), True, True),
             "L": ((3, m), False, False), "Q": ((3, 3), False, True)}
    if getattr(module, "HAS_FRAME", False):
        forms.update({"N": ((3, m), True, False), "QN": ((3, 3), True, True), "W": ((m, m), True, False)})
    for R in rotations:
        v = rng.normal(size=m)
        for name, (shape, takes_q, takes_inputs) in forms.items():
            args = (R,) + ((q,) if takes_q else ()) + ((v,) if takes_inputs else ())
            out = np.full(shape, np.nan)
            getattr(module, f"{name}_into")(*args, out)
            want = getattr(module, name)(*args)
            assert want.shape == shape, name
            np.testing.assert_array_equal(out, want, err_msg=f"{module.NAME}.{name}_into")
            assert np.all(np.isfinite(out)), name
    return tuple(forms)


#: The package's mechanisms whose state is an orientation alone (the rest, e.g. the
#: rolling ball and the car, are tested by ``tests/planning/test_state_spaces.py``).
SO3_MECHANISMS = tuple(n for n in GENERATED_MECHANISMS if not catalog.get(n).n_coordinates)


@pytest.fixture(scope="session")
def interpreted_kernels(tmp_path_factory):
    """Every catalog system's kernels in both Python forms, run by the interpreter on
    :mod:`kernel_runs`' inputs: ``{(name, frame, form): outputs}``."""
    import kernel_runs

    return kernel_runs.interpreted(tmp_path_factory.mktemp("kernels"))


#: A pair of the benchmark goal set the local planner misses (the global route's test case).
FAR = "uniform-platform-0021"


def far_pair(mechanism="platform", pid=FAR):
    """A pair of :func:`benchmarks.goalset.uniform_pairs` by its id (default :data:`FAR`)."""
    from benchmarks import goalset

    return {p["id"]: p for p in goalset.uniform_pairs(mechanism, 1000)}[pid]


def rk4_check(results, pairs, least=3200):
    """Per plan: (RK4 endpoint error, least sgnΔ at the RK4 nodes), steps aligned with the
    plan's, at least ``least`` and the certified replay's. Plans of one mechanism and one
    step count are replayed in one batch (on the finest step count any of them needs)."""
    groups: dict = {}
    for i, r in enumerate(results):
        groups.setdefault((r.mechanism, r.steps), []).append(i)
    out = [None] * len(results)
    for (mechanism, steps), members in groups.items():
        S = max(steps * -(-max(least, results[i].replay_steps or 0) // steps) for i in members)
        RT, dmin = resimulate_rk4(np.stack([pairs[i]["R0"] for i in members]),
                                  [results[i].parametrisation for i in members],
                                  np.array([results[i].T for i in members]), mechanism, steps=S)
        for j, i in enumerate(members):
            out[i] = (terminal_error(RT[j], pairs[i]["Rd"]), None if dmin is None else float(dmin[j]))
    return out
