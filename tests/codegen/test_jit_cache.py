"""The numba disk cache never stops a run: no writable cache location, a damaged entry
(the numba backend chosen, since the native kernels installed would bypass its cache)."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

SIMULATE = """
import numpy as np
from nonholo import simulate
from nonholo.spaces import so3
from nonholo.controls.parametrisations import Fourier
tr = simulate(so3.from_rpy(0.1, 0.2, 0.3), Fourier(1.0, [[0.3, 0, 0], [0, 0.2, 0]]), 1.0,
              mechanism="attitude", steps=50)
print(repr(float(tr.R_T[0, 1])))
"""

READ_ONLY = """
import numba.core.caching as caching
def refuse(self):
    raise OSError("read-only file system")
caching._CacheLocator.ensure_cache_path = refuse      # every cache location unwritable
""" + SIMULATE


def run(code: str, cache_dir: Path):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache_dir), "NONHOLO_BACKEND": "numba"}
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                          timeout=600)


@pytest.mark.slow
def test_runs_without_a_writable_cache(tmp_path):
    out = run(READ_ONLY, tmp_path / "cache")
    assert out.returncode == 0, out.stderr
    assert out.stderr.count("no writable numba cache") == 1
    reference = run(SIMULATE, tmp_path / "cache2")
    assert reference.returncode == 0 and out.stdout == reference.stdout


@pytest.mark.slow
def test_a_damaged_cache_entry_is_rebuilt(tmp_path):
    cache = tmp_path / "cache"
    first = run(SIMULATE, cache)
    assert first.returncode == 0, first.stderr
    entries = list(cache.rglob("*.nbc"))
    assert entries
    for path in entries:                       # truncated, as by a run killed while writing
        data = path.read_bytes()
        path.write_bytes(data[: len(data) // 2])
    second = run(SIMULATE, cache)
    assert second.returncode == 0, second.stderr
    assert "discarded a damaged numba cache entry" in second.stderr
    assert second.stdout == first.stdout
    third = run(SIMULATE, cache)
    assert third.returncode == 0 and "damaged" not in third.stderr and third.stdout == first.stdout
