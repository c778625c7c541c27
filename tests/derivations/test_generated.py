"""The generated modules' two forms of every matrix: ``NAME_into(..., out)`` (what the
compiled integrator calls) and the allocating ``NAME(...)`` (what everything else calls)."""
import numpy as np
import pytest
from conftest import SO3_MECHANISMS, check_into_forms, random_rotations

from nonholo.model import catalog


@pytest.mark.parametrize("name", SO3_MECHANISMS)
def test_into_forms_fill_out_with_the_allocating_result(name):
    mech = catalog.get(name)
    rng = np.random.default_rng(sum(map(ord, name)))
    Rs = random_rotations(50, rng, 0.05, mech.delta)        # away from the mechanism's own Δ = 0
    checked = check_into_forms(mech.module, Rs, rng)
    assert {"G", "QG", "L", "Q"} <= set(checked)
    assert ("W" in checked) == mech.has_frame
    # the Mechanism's callables are the module's allocating forms (on SO(3), of R alone)
    assert mech.L.generated is mech.module.L and mech.Q.generated is mech.module.Q and mech.G is mech.module.G
    if mech.has_frame:
        assert tuple(f.generated for f in (mech.frame.N, mech.frame.QN, mech.frame.W)) == (
            mech.module.N, mech.module.QN, mech.module.W)
        R, w = Rs[0], rng.normal(size=mech.n_inputs)
        q = mech.module.NO_COORDINATES
        np.testing.assert_array_equal(mech.frame.N(R), mech.module.N(R, q))
        np.testing.assert_array_equal(mech.frame.QN(R, w), mech.module.QN(R, q, w))
        np.testing.assert_array_equal(mech.frame.W(R), mech.module.W(R, q))


@pytest.mark.parametrize("name", SO3_MECHANISMS)
def test_delta_samples_is_delta_on_a_stack(name):
    mech = catalog.get(name)
    Rs = np.stack(random_rotations(30, np.random.default_rng(11), delta=None))
    d = mech.delta_samples(Rs)
    if mech.delta is None:
        assert d is None and mech.delta is None
        return
    assert d.shape == (30,)
    np.testing.assert_array_equal(d, [mech.delta(R) for R in Rs])
