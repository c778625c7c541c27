"""``import nonholo`` loads NumPy and SciPy's linear algebra only: numba, SciPy's optimisers,
sparse, spatial and interpolation modules, matplotlib and SymPy load where they are used
(a fresh interpreter, so that nothing the suite imported counts)."""
import subprocess
import sys

HEAVY = ("numba", "scipy.optimize", "scipy.sparse", "scipy.spatial", "scipy.interpolate", "matplotlib", "sympy")


def test_import_nonholo_loads_no_heavy_module():
    code = ("import sys, nonholo\n"
            f"print(','.join(m for m in {HEAVY!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)
    assert out.stdout.strip() == "", f"import nonholo loaded {out.stdout.strip()}"
