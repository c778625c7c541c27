"""The native (C) kernels against the Python they are translated from.

Both backends compile the same Python (numba directly, the native one through
:mod:`nonholo.codegen.c_translation`); these tests hold the C kernels to that source,
executed by the interpreter, to 1e-13 on random inputs for every system of the catalog and
every kernel, and to numba's compilation of it for one mechanism of each kind of state;
and they check the build's plumbing: the digest that keeps a stale module out, the disk
cache, the fallback to numba, the arguments' checks.
"""
import os
import subprocess
import sys
import sysconfig

import kernel_runs
import numpy as np
import pytest

from nonholo.generated import MECHANISMS
from nonholo.codegen import build, c_extension, cache, emit
from nonholo.codegen.c_subset import Function
from nonholo.integrate import system_kernels
from nonholo.numerics import kernels

pytestmark = pytest.mark.skipif(build.compiler() is None, reason="no C compiler")


def _module(name):
    import importlib

    return importlib.import_module(f"nonholo.generated.{name}")


def _systems(module):
    return [False, True] if getattr(module, "HAS_FRAME", False) else [False]


def _close(a, b, tol=1e-13):
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert a.shape == b.shape
    finite = np.isfinite(a)
    np.testing.assert_array_equal(a[~finite], b[~finite])      # the same inf, nan where not finite
    if finite.any():
        scale = max(1.0, float(np.abs(a[finite]).max()))
        assert float(np.abs(a[finite] - b[finite]).max()) <= tol * scale


def _agree(got: dict, want: dict, tol=1e-13):
    """Every output of one kernel run against another's: step counts exact, values to ``tol``."""
    assert got.keys() == want.keys()
    for key in got:
        if key.endswith("_result"):
            assert got[key][0] == want[key][0], key                      # steps done
        _close(got[key], want[key], tol)


@pytest.mark.parametrize("name,frame", kernel_runs.SYSTEMS)
@pytest.mark.slow
def test_native_kernels_agree_with_their_python_source(name, frame, interpreted_kernels):
    """forward, forward_variational (sparse and dense bases, with and without M(T)) and
    frame_inputs of the C kernels: the same trajectory, Jacobian and Gramian to 1e-13 as
    the Python they are translated from, executed by the interpreter."""
    nat = system_kernels.compile_system(_module(name), frame, backend="native")
    assert nat.backend == "native"
    got = kernel_runs.run(nat, kernel_runs.inputs(name, frame), frame)
    _agree(got, interpreted_kernels[name, frame, "inlined"])


@pytest.mark.parametrize("name", ["attitude", "car"])
@pytest.mark.slow
def test_native_kernels_agree_with_numba(name, interpreted_kernels):
    """The numba fallback's compiled kernels agree with the C ones and the interpreted
    source to 1e-13: one mechanism on SO(3), one on coordinates with a singular set
    (compiling every mechanism with numba would take CI minutes; the source they all
    compile is checked for each above)."""
    module = _module(name)
    for frame in _systems(module):
        ref = system_kernels.compile_system(module, frame, backend="numba")
        nat = system_kernels.compile_system(module, frame, backend="native")
        assert (nat.backend, ref.backend) == ("native", "numba")
        inp = kernel_runs.inputs(name, frame)
        compiled = kernel_runs.run(ref, inp, frame)
        _agree(compiled, kernel_runs.run(nat, inp, frame))
        _agree(compiled, interpreted_kernels[name, frame, "inlined"])


def test_native_small_numerics_agree_with_numba():
    """log_rotation/log_error (also near a half turn), the Cholesky step, all_finite."""
    from scipy.spatial.transform import Rotation

    lib = kernels.native_lib()
    assert lib is not None
    rng = np.random.default_rng(3)
    for i in range(200):
        R = Rotation.random(random_state=i).as_matrix()
        if i % 3 == 0:                                   # near α = π: the symmetric-part branch
            axis = rng.normal(size=3)
            R = Rotation.from_rotvec(axis / np.linalg.norm(axis) * (np.pi - 10.0 ** -rng.uniform(1, 9))).as_matrix()
        Rd = Rotation.random(random_state=1000 + i).as_matrix()
        l1, l2 = np.empty(3), np.empty(3)
        n1 = lib.log_error_into(R, Rd, l1)
        n2 = kernels.log_error_into(R, Rd, l2)
        _close(l1, l2)
        _close(n1, n2)
        J = rng.normal(size=(3, 8))
        if i % 5 == 0:
            J[2] = J[0] + J[1]                           # rank-deficient: Cholesky refuses
        l = rng.normal(size=3)
        scale = rng.uniform(0.5, 2.0, size=8)
        x1, x2 = np.empty(8), np.empty(8)
        ok1, ok2 = lib.cholesky_into(J, l, scale, x1), kernels.cholesky_into(J, l, scale, x2)
        assert ok1 == ok2
        if ok1:
            _close(x1, x2, 1e-12)
    A = rng.normal(size=(4, 5))
    assert lib.all_finite_jit(A) and kernels.all_finite_jit(A)
    A[2, 3] = np.nan
    assert not lib.all_finite_jit(A) and not kernels.all_finite_jit(A)


def test_native_arguments_are_checked():
    """A written argument of the wrong dtype or layout is refused (a copy would lose the
    writes); a read-only one is converted; the message names the argument."""
    module = _module("car")
    kern = system_kernels.compile_system(module, backend="native")
    N = 4
    U = np.zeros((N, 3, 2))
    Rs, Qs = kern.nodes(N)
    with pytest.raises(TypeError, match="'Qs'"):
        kern.forward(np.eye(3), np.zeros(4), U, 0.1, 1.0, 1e-9, Rs, Qs.astype(np.float32))
    with pytest.raises(TypeError, match="'Rs'"):
        kern.forward(np.eye(3), np.zeros(4), U, 0.1, 1.0, 1e-9, np.empty((N + 1, 3, 3)).transpose(0, 2, 1), Qs)
    n, _, _ = kern.forward(np.eye(3).T, [0, 0, 0, 0], U.tolist(), 0.1, 1.0, 1e-9, Rs, Qs)
    assert n == N


def test_a_stale_module_is_not_used(tmp_path, monkeypatch):
    """A module whose recorded digest is not the sources' is passed over: the kernels are
    compiled into the cache (named by the digest) and loaded from there."""
    monkeypatch.setenv(cache.CACHE_ENV, str(tmp_path))
    src = c_extension.extension_source(
        "nonholo.generated.native.toy", "toy", [Function(_toy, "toy", {"x": "f8", "a": "f8[1]"})], "abc")
    lib = build.load("toy", "abc", lambda: src)
    assert lib is not None and lib.SOURCE_DIGEST == "abc"
    assert lib.toy(2.0, np.array([1.0, 2.0, 3.0])) == 12.0
    suffix = sysconfig.get_config_var("EXT_SUFFIX") or ".so"
    assert len(list(tmp_path.glob(f"toy_*{suffix}"))) == 1
    assert cache.record_path(next(tmp_path.glob(f"toy_*{suffix}"))).exists()   # its hash, recorded
    monkeypatch.setattr(cache, "_WARNED", set())          # said once per process
    with pytest.warns(RuntimeWarning, match="native kernels unavailable"):
        stale = build.load("toy", "def", lambda: src)   # a module built from other sources
    assert stale is None


def _toy(x, a):
    s = 0.0
    for i in range(a.shape[0]):
        s += x * a[i]
    return s


@pytest.mark.slow
def test_no_compiler_falls_back_to_numba(tmp_path):
    """Without a working compiler (and nothing cached) a user's mechanism still gets its
    kernels: from numba, said once in a warning. (The catalog's car would use the module
    built at install: its digest is the same.)"""
    code = r"""
import warnings, numpy as np
warnings.simplefilter("always")
from nonholo.model.mechanism import Mechanism
from nonholo.integrate import system_kernels
from derivations import vehicles
m = Mechanism.from_symbolic(vehicles.kinematic_car(2, name="car_wheelbase_2"), cache=False)
with warnings.catch_warnings(record=True) as w:
    kern = system_kernels.compile_system(m.module)
print(kern.backend, sum("native kernels unavailable" in str(x.message) for x in w))
"""
    env = dict(os.environ, CC="/bin/false", NONHOLO_CACHE_DIR=str(tmp_path), PATH="/nonexistent")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=600, check=False)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split()[-2:] == ["numba", "1"]


def test_the_catalog_is_built_at_install():
    """``pip install`` built every catalog module from the checked-in C (so that the first
    plan needs no compiler): each loads with the digest of its sources."""
    for name in MECHANISMS:
        module = _module(name)
        want = emit.source_digest(module, system_kernels.native_parts())
        assert build.installed(name, want) is not None, name
    assert build.installed("numerics", kernels.native_digest()) is not None
