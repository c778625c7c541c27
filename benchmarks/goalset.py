"""Benchmark goal set for the orienting platform: reachable goals by construction, and
goals across the singular surface.

Run ``python -m benchmarks.goalset`` to (re)write ``benchmarks/goals.json``; the output
depends only on the seed (:data:`SEED`) and the constants below, so running it again
reproduces the file.

How the goals are made
----------------------
System: ``dR/dt = [L(R) u] R`` with the generated ``L`` of the mechanism ``"platform"``
(:func:`nonholo.model.catalog.get`), ``Δ(R) = r12 r31 + r21 r32``. ``SO(3) \\ {Δ = 0}`` has
two components and no motion crosses ``Δ = 0``.

- Starts: :data:`N_STARTS` orientations, half with ``Δ > 0`` and half with ``Δ < 0``,
  each with ``|Δ(R0)| ≥`` :data:`DELTA_START`. The first two are the initial
  orientations of the two examples, ``RPY(0.5, 1.2, −0.5)`` and ``RPY(1.5, 1.4, 0.5)``
  (``RPY(φ, ϑ, ψ) = Rz(φ) Ry(ϑ) Rx(ψ)``); the others are uniformly random rotations
  (rejection-sampled for the sign and size of ``Δ``).
- Reachable goals (bands ``"near"`` and ``"far"``): from each start, random truncated
  Fourier controls ``u_i(t) = λ_i0 + Σ_{k=1..K} (λ_i,2k−1 sin kωt + λ_i,2k cos kωt)``,
  ``ω = 2π/T``, ``T = 1``, ``K`` drawn from {2, 3}; the coefficients are standard normal,
  then scaled so that the RMS of ``|u|`` over ``[0, T]`` is log-uniform in the band's
  :data:`AMPLITUDE` range. The 9 entries of ``R`` are integrated with SciPy's DOP853
  (``rtol = atol =`` :data:`RTOL`). A control is kept only if the trajectory keeps
  ``|Δ| ≥`` :data:`DELTA_KEEP` throughout (a terminal event on ``sgn(Δ(R0)) Δ = 0.1``
  plus a check on 2001 dense-output samples and every integrator step) and the geodesic
  distance ``|log(R(T) R0ᵀ)|`` lies in the band (:data:`BANDS`); ``Rd = R(T)``.
  Every such goal is reachable by construction, with a trajectory that stays at least
  0.1 away from the singular surface (in ``|Δ|``).
- Goals across the singular surface (band ``"across"``): ``Rd = exp(α [a]) R0`` with a
  uniformly random unit axis ``a`` and ``α`` uniform in ``[0.2, 1.8]``, kept if
  ``sign(Δ(Rd)) ≠ sign(Δ(R0))`` and ``|Δ(Rd)| ≥ 0.1`` (so the only obstruction is the
  sign). These are unreachable: a planner must reject them.

Each (start, band) pair uses its own random stream ``numpy.random.default_rng([SEED,
kind, start, band])``, so any slice can be regenerated alone
(:func:`reachable_goals`, :func:`across_goals`).

File format (``goals.json``)
----------------------------
One JSON object::

    {"format": "nonholo.goalset/1", "seed": ..., "parameters": {...},
     "starts": [{"index", "R0", "delta0"}, ...],
     "goals": [goal, ...]}

with every ``goal`` an object:

- ``id``: ``"<band>-s<start>-<j>"``, e.g. ``"near-s3-05"``; ``band``: ``"near"``,
  ``"far"`` or ``"across"``; ``start``: index into ``starts``;
- ``R0``, ``Rd``: 3×3 nested lists (row-major rotation matrices); ``T``: 1.0 (s);
- ``distance``: geodesic distance ``|log(Rd R0ᵀ)|`` (rad);
- ``delta0``, ``deltad``: ``Δ(R0)``, ``Δ(Rd)``;
- ``min_delta_generating``: least ``|Δ|`` along the generating trajectory (``null`` for
  ``"across"``);
- ``generating_controls``: the control that produced ``Rd`` (``null`` for ``"across"``):
  ``{"kind": "fourier", "T", "harmonics", "coeffs"}`` with ``coeffs`` of shape
  ``(2, 2K+1)`` ordered ``(λ_i0, λ_i1 (sin ωt), λ_i2 (cos ωt), …)`` — the format of
  :func:`nonholo.controls.parametrisations.from_dict`.

Floats are written with full (``repr``) precision. :func:`load_goals` returns the list
of goals with ``R0``, ``Rd`` and the coefficients as NumPy arrays.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
import zlib
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from nonholo.model import catalog
from nonholo.spaces import so3

FORMAT = "nonholo.goalset/1"
DEFAULT_PATH = Path(__file__).resolve().parent / "goals.json"

SEED = 20140901
T = 1.0
N_STARTS = 8
DELTA_START = 0.3
DELTA_KEEP = 0.1
HARMONICS = (2, 3)
BANDS = {"near": (0.2, 0.8), "far": (0.8, 1.8)}
#: RMS of |u| over [0, T] (1/s), drawn log-uniformly in this range, per band.
AMPLITUDE = {"near": (0.05, 0.8), "far": (0.3, 2.5)}
PER_START = {"near": 8, "far": 8}
ACROSS_PER_START = 3
ACROSS_ANGLE = (0.2, 1.8)
DELTA_ACROSS = 0.1
RTOL = 1e-12
ATOL = 1e-12
DENSE_SAMPLES = 2001
MAX_ATTEMPTS = 20000
#: The examples' initial orientations (RPY angles, rad), used as the first starts.
PAPER_STARTS = ((0.5, 1.2, -0.5), (1.5, 1.4, 0.5))

_KIND_STARTS, _KIND_REACHABLE, _KIND_ACROSS = 0, 1, 2
_BAND_CODE = {"near": 0, "far": 1}

_MECH = catalog.get("platform")


def delta(R) -> float:
    """``Δ(R)`` of the platform (generated)."""
    return float(_MECH.delta(np.asarray(R, dtype=float)))


def _random_rotation(rng: np.random.Generator) -> np.ndarray:
    """Uniform random rotation (normalised Gaussian quaternion)."""
    q = rng.standard_normal(4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


#: Distance bands (rad) of the uniform random pairs (:func:`uniform_pairs`).
UNIFORM_BANDS = {"0-1": (0.0, 1.0), "1-1.8": (1.0, 1.8), "1.8-pi": (1.8, np.pi + 1e-12)}
#: The uniform random pairs keep ``|Δ| ≥`` this at both ends.
UNIFORM_MIN_DELTA = 0.05


def _uniform_stream(mechanism, seed: int, min_delta: float):
    """Haar pairs ``(R0, Rd, distance, band)`` in one component, endlessly (see
    :func:`uniform_pairs`)."""
    mech = catalog.get(mechanism)
    rng = np.random.default_rng([seed, 3, zlib.crc32(mech.name.encode())])
    while True:
        A, B = _random_rotation(rng), _random_rotation(rng)
        if mech.delta is not None:
            dA, dB = float(mech.delta(A)), float(mech.delta(B))
            if np.sign(dA) != np.sign(dB) or min(abs(dA), abs(dB)) < min_delta:
                continue
        dist = so3.distance(A, B)
        band = next(b for b, (lo, hi) in UNIFORM_BANDS.items() if lo <= dist < hi)
        yield A, B, dist, band


def uniform_pairs(mechanism, count: int, seed: int = SEED, min_delta: float = UNIFORM_MIN_DELTA) -> list[dict]:
    """``count`` pairs ``(R0, Rd)`` drawn independently and uniformly (Haar) from SO(3) and
    kept when, for a mechanism with a singular set, ``Δ`` has the same sign at both ends
    and ``|Δ| ≥ min_delta`` there — the whole problem domain of a planner, every pair
    reachable (same component). ``T = 1``; ``band``: the distance band
    (:data:`UNIFORM_BANDS`). The stream depends only on ``seed`` and the mechanism's name.
    """
    name = catalog.get(mechanism).name
    out = []
    for A, B, dist, band in _uniform_stream(mechanism, seed, min_delta):
        if len(out) == count:
            break
        out.append({"id": f"uniform-{name}-{len(out):04d}", "band": band, "R0": A, "Rd": B,
                    "T": T, "distance": dist})
    return out


def band_pairs(mechanism, per_band: int, seed: int = SEED, min_delta: float = UNIFORM_MIN_DELTA) -> list[dict]:
    """The uniform random band set: the stream of :func:`uniform_pairs`, each pair kept
    while its distance band (:data:`UNIFORM_BANDS`) has fewer than ``per_band`` — so every
    band holds ``per_band`` pairs, each uniform within its band (near pairs are rare: about
    one in thirteen is closer than 1 rad). Ordered by band, then by draw; ``id``:
    ``"band-<mechanism>-<band>-<j>"``."""
    name = catalog.get(mechanism).name
    kept: dict[str, list] = {b: [] for b in UNIFORM_BANDS}
    for A, B, dist, band in _uniform_stream(mechanism, seed, min_delta):
        if all(len(v) == per_band for v in kept.values()):
            break
        if len(kept[band]) < per_band:
            kept[band].append({"id": f"band-{name}-{band}-{len(kept[band]):04d}", "band": band, "R0": A,
                               "Rd": B, "T": T, "distance": dist})
    return [p for b in UNIFORM_BANDS for p in kept[b]]


def _random_axis(rng: np.random.Generator) -> np.ndarray:
    a = rng.standard_normal(3)
    return a / np.linalg.norm(a)


def starts(seed: int = SEED, n: int = N_STARTS) -> list[np.ndarray]:
    """The start orientations: the examples' two, then random ones; signs of ``Δ`` balanced.

    Half of the starts (rounded up) have ``Δ > 0``; every start has ``|Δ| ≥ DELTA_START``.
    """
    out = [so3.from_rpy(*a) for a in PAPER_STARTS][:n]
    n_pos = (n + 1) // 2
    want = [+1.0] * (n_pos - sum(delta(R) > 0 for R in out)) + \
           [-1.0] * (n - n_pos - sum(delta(R) < 0 for R in out))
    rng = np.random.default_rng([seed, _KIND_STARTS])
    # interleave the signs still needed: +, -, +, - ... then the rest
    pos = [s for s in want if s > 0]
    neg = [s for s in want if s < 0]
    order = []
    while pos or neg:
        if pos:
            order.append(pos.pop())
        if neg:
            order.append(neg.pop())
    for sgn in order:
        while True:
            R = _random_rotation(rng)
            d = delta(R)
            if np.sign(d) == sgn and abs(d) >= DELTA_START:
                out.append(R)
                break
    return out


# --------------------------------------------------------------------------------------
# Forward simulation of Fourier controls
# --------------------------------------------------------------------------------------
def fourier(t, coeffs: np.ndarray, T: float = T) -> np.ndarray:
    """``u(t)`` for Fourier coefficients ``coeffs`` (shape ``(2, 2K+1)``); ``t`` (n,) -> (n, 2)."""
    coeffs = np.asarray(coeffs, dtype=float)
    K = (coeffs.shape[1] - 1) // 2
    t = np.atleast_1d(np.asarray(t, dtype=float))
    kwt = np.multiply.outer(t, (2.0 * np.pi / T) * np.arange(1, K + 1))
    basis = np.empty(t.shape + (2 * K + 1,))
    basis[..., 0] = 1.0
    basis[..., 1::2] = np.sin(kwt)
    basis[..., 2::2] = np.cos(kwt)
    return basis @ coeffs.T


def _rms(coeffs: np.ndarray) -> float:
    """``sqrt(∫|u|² dt / T)`` of a Fourier control (Parseval)."""
    return float(np.sqrt(np.sum(coeffs[:, 0] ** 2) + 0.5 * np.sum(coeffs[:, 1:] ** 2)))


def simulate(R0, coeffs, T: float = T, delta_keep: float = DELTA_KEEP):
    """Integrate ``dR/dt = [L(R) u(t)] R`` with DOP853 for a Fourier control.

    Returns ``(ok, R_T, min_delta)``: ``ok`` is False if ``sgn(Δ(R0)) Δ`` fell below
    ``delta_keep`` (the integration then stops at the crossing); ``min_delta`` is the least
    ``sgn(Δ(R0)) Δ`` over the integrator's steps and ``DENSE_SAMPLES`` dense-output points.
    """
    R0 = np.asarray(R0, dtype=float)
    coeffs = np.asarray(coeffs, dtype=float)
    K = (coeffs.shape[1] - 1) // 2
    w = (2.0 * np.pi / T) * np.arange(1, K + 1)
    L = _MECH.L
    sgn = float(np.sign(delta(R0)))

    def u_of(t):
        b = np.empty(2 * K + 1)
        b[0] = 1.0
        b[1::2] = np.sin(w * t)
        b[2::2] = np.cos(w * t)
        return coeffs @ b

    def rhs(t, y):
        R = y.reshape(3, 3)
        return (so3.hat(L(R) @ u_of(t)) @ R).ravel()

    def event(t, y):
        return sgn * _MECH.delta(y.reshape(3, 3)) - delta_keep

    event.terminal = True
    event.direction = -1

    sol = solve_ivp(rhs, (0.0, T), R0.ravel(), method="DOP853", rtol=RTOL, atol=ATOL,
                    events=event, dense_output=True)
    if sol.status != 0 or not np.all(np.isfinite(sol.y)):
        return False, None, -np.inf
    ys = np.concatenate([sol.y, sol.sol(np.linspace(0.0, T, DENSE_SAMPLES))], axis=1)
    Rs = ys.T.reshape(-1, 3, 3)
    dmin = float(np.min(sgn * (Rs[:, 0, 1] * Rs[:, 2, 0] + Rs[:, 1, 0] * Rs[:, 2, 1])))
    RT = sol.y[:, -1].reshape(3, 3)
    return dmin >= delta_keep, RT, dmin


def _polish(R) -> np.ndarray:
    """Nearest rotation (SVD), to remove the integrator's drift from SO(3) (~1e-12)."""
    U, _, Vt = np.linalg.svd(R)
    Rp = U @ Vt
    if np.linalg.det(Rp) < 0:
        U[:, -1] *= -1
        Rp = U @ Vt
    return Rp


def _goal(gid, band, s, R0, Rd, min_delta=None, coeffs=None) -> dict:
    return {
        "id": gid,
        "band": band,
        "start": int(s),
        "R0": np.asarray(R0).tolist(),
        "Rd": np.asarray(Rd).tolist(),
        "T": T,
        "distance": so3.distance(Rd, R0),
        "delta0": delta(R0),
        "deltad": delta(Rd),
        "min_delta_generating": None if min_delta is None else float(min_delta),
        "generating_controls": None if coeffs is None else {
            "kind": "fourier", "T": T, "harmonics": (coeffs.shape[1] - 1) // 2,
            "coeffs": coeffs.tolist()},
    }


def reachable_goals(start_index: int, band: str, count: int, seed: int = SEED,
                    R0=None) -> tuple[list[dict], int]:
    """The first ``count`` goals of ``band`` from start ``start_index``, and the attempts used.

    ``R0`` defaults to ``starts(seed)[start_index]``.
    """
    if R0 is None:
        R0 = starts(seed)[start_index]
    lo, hi = BANDS[band]
    alo, ahi = AMPLITUDE[band]
    rng = np.random.default_rng([seed, _KIND_REACHABLE, start_index, _BAND_CODE[band]])
    goals = []
    attempts = 0
    while len(goals) < count:
        attempts += 1
        if attempts > MAX_ATTEMPTS:
            raise RuntimeError(f"start {start_index}, band {band}: only {len(goals)} goals "
                               f"after {MAX_ATTEMPTS} attempts")
        K = int(rng.choice(HARMONICS))
        c = rng.standard_normal((2, 2 * K + 1))
        amp = float(np.exp(rng.uniform(np.log(alo), np.log(ahi))))
        c *= amp / _rms(c)
        ok, RT, dmin = simulate(R0, c)
        if not ok:
            continue
        Rd = _polish(RT)
        d = so3.distance(Rd, R0)
        if not lo <= d <= hi:
            continue
        gid = f"{band}-s{start_index}-{len(goals):02d}"
        goals.append(_goal(gid, band, start_index, R0, Rd, dmin, c))
    return goals, attempts


def across_goals(start_index: int, count: int, seed: int = SEED, R0=None) -> list[dict]:
    """``count`` goals with ``sign Δ(Rd) ≠ sign Δ(R0)`` from start ``start_index``."""
    if R0 is None:
        R0 = starts(seed)[start_index]
    rng = np.random.default_rng([seed, _KIND_ACROSS, start_index])
    s0 = np.sign(delta(R0))
    goals = []
    while len(goals) < count:
        a = _random_axis(rng)
        ang = rng.uniform(*ACROSS_ANGLE)
        Rd = so3.exp(ang * a) @ R0
        dd = delta(Rd)
        if np.sign(dd) != s0 and abs(dd) >= DELTA_ACROSS:
            goals.append(_goal(f"across-s{start_index}-{len(goals):02d}", "across",
                               start_index, R0, Rd))
    return goals


def generate(seed: int = SEED, progress: bool = False) -> dict:
    """The whole goal set as the JSON-able object described in the module docstring."""
    S = starts(seed)
    goals = []
    stats = {}
    for band in BANDS:
        for i, R0 in enumerate(S):
            t0 = time.perf_counter()
            g, n = reachable_goals(i, band, PER_START[band], seed, R0=R0)
            goals += g
            stats[f"{band}-s{i}"] = n
            if progress:
                print(f"  {band:5s} start {i}: {len(g)} goals from {n} random controls "
                      f"({time.perf_counter() - t0:.1f} s)", file=sys.stderr)
    for i, R0 in enumerate(S):
        goals += across_goals(i, ACROSS_PER_START, seed, R0=R0)
    return {
        "format": FORMAT,
        "seed": seed,
        "parameters": {
            "T": T, "n_starts": len(S), "delta_start": DELTA_START, "delta_keep": DELTA_KEEP,
            "harmonics": list(HARMONICS), "bands": BANDS, "amplitude_rms": AMPLITUDE,
            "per_start": PER_START, "across_per_start": ACROSS_PER_START,
            "across_angle": list(ACROSS_ANGLE), "delta_across": DELTA_ACROSS,
            "integrator": f"scipy solve_ivp DOP853, rtol={RTOL:g}, atol={ATOL:g}",
            "attempts": stats,
        },
        "starts": [{"index": i, "R0": R.tolist(), "delta0": delta(R)} for i, R in enumerate(S)],
        "goals": goals,
    }


def _arrays(goal: dict) -> dict:
    g = dict(goal)
    g["R0"] = np.array(g["R0"], dtype=float)
    g["Rd"] = np.array(g["Rd"], dtype=float)
    if g.get("generating_controls") is not None:
        gc = dict(g["generating_controls"])
        gc["coeffs"] = np.array(gc["coeffs"], dtype=float)
        g["generating_controls"] = gc
    return g


def load_goals(path=None) -> list[dict]:
    """The goals of ``path`` (default ``benchmarks/goals.json``), arrays as NumPy arrays."""
    path = DEFAULT_PATH if path is None else Path(path)
    data = json.loads(Path(path).read_text())
    if data.get("format") != FORMAT:
        raise ValueError(f"{path}: not a goal set (format {data.get('format')!r}, "
                         f"expected {FORMAT!r})")
    return [_arrays(g) for g in data["goals"]]


def write_problems(path, goals: list[dict], mechanism: str = "platform") -> Path:
    """``goals`` (of this module: ``R0``, ``Rd``, ``T``, ``id``) as a problem table for
    :func:`nonholo.batch.sweep.sweep` (JSON Lines, :mod:`nonholo.io.problems`), labelled by id."""
    from nonholo.io import problems

    return problems.write(path, [{"start": g["R0"], "goal": g["Rd"], "mechanism": g.get("mechanism", mechanism),
                                  "options": {"T": g["T"]}, "label": g["id"]} for g in goals])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.goalset", description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=DEFAULT_PATH, help="output file (default: %(default)s)")
    ap.add_argument("--seed", type=int, default=SEED, help="random seed (default: %(default)s)")
    ap.add_argument("--problems", type=Path, default=None, metavar="FILE",
                    help="instead: write a goal set as a problem table for `nonholo sweep` (JSON Lines): "
                         "benchmarks/goals.json's goals, or with --uniform N the first N uniform random pairs")
    ap.add_argument("--uniform", type=int, default=None, metavar="N", help="with --problems: N uniform random pairs")
    ap.add_argument("--mechanism", default="platform", help="with --uniform: the mechanism (default platform)")
    args = ap.parse_args(argv)
    if args.problems is not None:
        goals = (uniform_pairs(args.mechanism, args.uniform, args.seed) if args.uniform
                 else [g for g in load_goals()])
        write_problems(args.problems, goals, args.mechanism)
        print(f"wrote {args.problems}: {len(goals)} problems", file=sys.stderr)
        return 0
    t0 = time.perf_counter()
    data = generate(args.seed, progress=True)
    args.out.write_text(json.dumps(data, indent=1, allow_nan=False) + "\n")
    counts = {}
    for g in data["goals"]:
        counts[g["band"]] = counts.get(g["band"], 0) + 1
    print(f"wrote {args.out}: {len(data['goals'])} goals "
          f"({', '.join(f'{b} {n}' for b, n in counts.items())}) "
          f"in {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
