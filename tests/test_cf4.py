"""The generated CF4 kernels (the step inlined by `nonholo derive`) against the kernels of
nonholo/cf4.py compiled as written (the step called), and against a fresh generation."""
import numpy as np
import pytest
from conftest import example

from derivations import codegen
from nonholo.controls import stages
from nonholo.controls.parametrisations import Fourier, PiecewiseConstant
from nonholo.generated import cf4_kernels
from nonholo.integrate import cf4
from nonholo.model import catalog


def test_generated_kernels_are_fresh():
    assert codegen.cf4_kernels_module() == open(cf4_kernels.__file__).read()


@pytest.mark.parametrize("name,frame", [("platform", False), ("platform", True), ("attitude", True)])
def test_inlined_kernels_equal_the_written_ones(name, frame):
    mech = catalog.get(name)
    fast = cf4.compile_system(mech.module, frame)
    ref = cf4.compile_system(mech.module, frame, inlined=False)
    rng = np.random.default_rng(7)
    R0 = np.ascontiguousarray(example(1)[0])
    for controls in (Fourier(1.0, 0.4 * rng.normal(size=(2, 5))),
                     PiecewiseConstant(1.0, 0.4 * rng.normal(size=(20, 2)))):
        steps = 200
        U = stages.stage_table(controls, steps)
        basis = stages.kernel_basis(controls, steps)
        outs = []
        for kern in (fast, ref):
            Rs = np.empty((steps + 1, 3, 3))
            a = kern.forward(R0, U, 1.0 / steps, 1.0, -np.inf, Rs)
            Rv, Zs = np.empty((steps + 1, 3, 3)), np.empty((steps + 1, 3, 3))
            J, M = np.empty((3, controls.params.size)), np.empty((3, 3))
            Wd = np.empty((3 * steps, 3 * mech.n_inputs))
            b = kern.forward_variational(R0, U, 1.0 / steps, 1.0, -np.inf, *basis, Rv, Zs, J, M, Wd, True)
            outs.append((a, Rs, b, Rv, Zs, J, M, Wd))
        for x, y in zip(*outs):
            if isinstance(x, tuple):
                assert x == y
            else:
                np.testing.assert_array_equal(x, y)
        if frame:
            nodes = outs[0][1]
            t = np.array([0.0, 0.1234, 0.5, 0.999])
            k = np.minimum((t * steps).astype(np.int64), steps)
            s = t - k / steps
            Wst = np.ascontiguousarray(np.broadcast_to(controls(t)[:, None, :], (4, 3, 2)))
            res = []
            for kern in (fast, ref):
                Rout, u = np.empty((4, 3, 3)), np.empty((4, 2))
                kern.frame_inputs(nodes, k, s, Wst, np.ascontiguousarray(controls(t)), Rout, u)
                res.append((Rout, u))
            np.testing.assert_array_equal(res[0][0], res[1][0])
            np.testing.assert_array_equal(res[0][1], res[1][1])


def test_a_stopped_run_reports_where():
    """A trajectory driven into Δ = 0 stops at the stage where sgnΔ fell below delta_stop,
    in both forms, with the same step count."""
    mech = catalog.get("platform")
    fast = cf4.compile_system(mech.module)
    ref = cf4.compile_system(mech.module, inlined=False)
    R0 = np.ascontiguousarray(example(1)[0])
    U = stages.stage_table(Fourier(1.0, [[3.0, 0, 0, 0, 0], [-3.0, 0, 0, 0, 0]]), 100)
    got = []
    for kern in (fast, ref):
        Rs = np.empty((101, 3, 3))
        got.append(kern.forward(R0, U, 0.01, 1.0, 0.3, Rs))
    assert got[0] == got[1]
    n, dmin, t_stop = got[0]
    assert n < 100 and dmin < 0.3 and 0.0 <= t_stop <= 1.0
