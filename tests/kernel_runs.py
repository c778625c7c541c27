"""Every catalog system's CF4 kernels run on fixed random inputs: the shared ground of
``test_cf4`` (the inlined kernels against the step-calling ones they are generated from)
and ``test_native`` (the C kernels against the Python they are translated from).

Run as a script under ``NUMBA_DISABLE_JIT=1`` (:func:`interpreted`), the kernels' Python
source is executed by the interpreter — the semantics every backend compiles, checked
bit for bit between the two forms in seconds instead of minutes of numba compilation —
and every output is written to an ``.npz`` file. In the test process the same
:func:`inputs` feed any compiled backend (:func:`run`).
"""
from __future__ import annotations

import importlib
import os
import subprocess
import sys
import zlib
from pathlib import Path

import numpy as np

from nonholo.generated import MECHANISMS

#: ``(mechanism, frame)`` of every system of the catalog's generated modules
SYSTEMS = [(name, frame) for name in MECHANISMS
           for frame in ((False, True) if getattr(importlib.import_module(f"nonholo.generated.{name}"),
                                                  "HAS_FRAME", False) else (False,))]
#: the kernels' two Python forms: generated with the step inlined, and as the integrator's modules write them
FORMS = ("inlined", "written")
#: steps of a run; basis functions of the variational runs
STEPS, BASIS = 120, 5


def module(name: str):
    """The generated module of catalog mechanism ``name``."""
    return importlib.import_module(f"nonholo.generated.{name}")


def inputs(name: str, frame: bool) -> dict:
    """The random inputs of one system (the same in every process: seeded by the name)."""
    mod = module(name)
    rng = np.random.default_rng(zlib.crc32(f"{name}{frame}".encode()))
    m, k = mod.N_INPUTS, len(mod.COORDINATES)
    d = (3 if mod.ORIENTATION else 0) + k
    for _ in range(100):
        A = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        R0 = np.ascontiguousarray(A * np.sign(np.linalg.det(A))) if mod.ORIENTATION else np.eye(3)
        q0 = rng.normal(size=k) * 0.3
        if not mod.HAS_SINGULAR_SET or abs(mod.delta(R0, q0)) > 0.2:
            break
    else:
        raise AssertionError(f"no regular start found for {name}")
    sgn = float(np.sign(mod.delta(R0, q0))) if mod.HAS_SINGULAR_SET else 1.0
    n_t = 30
    s = rng.uniform(0, 1.0 / STEPS, size=n_t)
    s[::4] = 0.0
    return dict(
        R0=R0, q0=q0, U=rng.normal(size=(STEPS, 3, m)) * 0.4, h=1.0 / STEPS, sgn=sgn, m=m, k=k, d=d,
        sparse_idx=rng.integers(0, BASIS, size=(STEPS, 3, 2)).astype(np.int64),
        sparse_val=rng.normal(size=(STEPS, 3, 2)), dense_val=rng.normal(size=(STEPS, 3, BASIS)),
        idx=rng.integers(0, STEPS, size=n_t).astype(np.int64), s=s,
        Wst=rng.normal(size=(n_t, 3, m)), w_end=rng.normal(size=(n_t, m)), p0=rng.normal(size=d) * 0.4)


def run(kern, inp: dict, frame: bool) -> dict[str, np.ndarray]:
    """Every output of ``kern`` on ``inp``: forward; forward_variational with a sparse and
    a dense basis, each with and without ``M(T)``; frame_inputs at the forward run's nodes;
    the normal extremal (physical systems). A run stopped at the singular set gives its
    nodes up to the stop."""
    N, d, m, k = STEPS, inp["d"], inp["m"], inp["k"]
    out = {}
    Rs, Qs = kern.nodes(N)
    r = kern.forward(inp["R0"], inp["q0"], inp["U"], inp["h"], inp["sgn"], 1e-9, Rs, Qs)
    n = r[0]
    out.update(forward_result=np.array(r, dtype=float), forward_R=Rs[:n + 1], forward_q=Qs[:n + 1])
    bases = {"sparse": (inp["sparse_idx"], inp["sparse_val"], np.zeros((0, d * m))),
             "dense": (np.zeros((0, 3, 0), np.int64), inp["dense_val"], np.empty((3 * N, d * m)))}
    for basis, (idx, val, Wd0) in bases.items():
        for full in (False, True):
            Rv, Qv = kern.nodes(N)
            Zs, J, M, Wd = np.zeros((N + 1, d, d)), np.empty((d, BASIS * m)), np.empty((d, d)), Wd0.copy()
            r = kern.forward_variational(inp["R0"], inp["q0"], inp["U"], inp["h"], inp["sgn"], 1e-9,
                                         idx, val, m, 1, Rv, Qv, Zs, J, M, Wd, full)
            tag = f"variational_{basis}_{'full' if full else 'jacobian'}"
            n = r[0]
            out.update({f"{tag}_result": np.array(r, dtype=float), f"{tag}_R": Rv[:n + 1],
                        f"{tag}_q": Qv[:n + 1], f"{tag}_Z": Zs[:n + 1]})
            if n == N:                                 # J, M(T), W only of a completed run
                out.update({f"{tag}_J": J, f"{tag}_W": Wd})
                if full:
                    out[f"{tag}_M"] = M
    if frame:
        n_t = len(inp["idx"])
        Rout, Qout, u = np.empty((n_t, 3, 3)), np.empty((n_t, k)), np.empty((n_t, m))
        idx = np.minimum(inp["idx"], out["forward_R"].shape[0] - 2)
        kern.frame_inputs(Rs, Qs, idx, inp["s"], inp["Wst"], inp["w_end"], Rout, Qout, u)
        out.update(frame_R=Rout, frame_q=Qout, frame_u=u)
    else:
        Re, Qe, Pe, Ue = np.empty((N + 1, 3, 3)), np.empty((N + 1, k)), np.empty((N + 1, d)), np.empty((N, 3, m))
        r = kern.extremal(inp["R0"], inp["q0"], inp["p0"], inp["h"], inp["sgn"], 1e-9, Re, Qe, Pe, Ue)
        n = r[0]
        out.update(extremal_result=np.array(r, dtype=float), extremal_R=Re[:n + 1], extremal_q=Qe[:n + 1],
                   extremal_p=Pe[:n + 1], extremal_U=Ue[:n])
    return out


def interpreted(tmp_path: Path) -> dict[tuple[str, bool, str], dict[str, np.ndarray]]:
    """The outputs of every system in both Python forms, run by the interpreter in a
    child process (``NUMBA_DISABLE_JIT=1``): ``{(name, frame, form): outputs}``."""
    path = Path(tmp_path) / "interpreted.npz"
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1", "NONHOLO_BACKEND": "numba"}
    done = subprocess.run([sys.executable, __file__, str(path)], env=env, capture_output=True, text=True,
                          timeout=1800, check=False)
    assert done.returncode == 0, done.stderr
    got: dict = {}
    with np.load(path) as data:
        for key in data.files:
            name, frame, form, field = key.split("|")
            got.setdefault((name, frame == "frame", form), {})[field] = data[key]
    return got


def main(path: str) -> None:
    from nonholo.integrate import system_kernels

    arrays = {}
    for name, frame in SYSTEMS:
        inp = inputs(name, frame)
        for form in FORMS:
            kern = system_kernels.compile_system(module(name), frame, inlined=form == "inlined", backend="numba")
            for field, value in run(kern, inp, frame).items():
                arrays[f"{name}|{'frame' if frame else 'physical'}|{form}|{field}"] = value
    np.savez(path, **arrays)


if __name__ == "__main__":
    main(sys.argv[1])
