"""The benchmark goal set (benchmarks/goals.json) and its generator (benchmarks/goalset.py)."""
import json
import pathlib
import sys

import numpy as np
import pytest

try:
    from benchmarks import goalset
except ImportError:  # run from outside the repository root
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2]))
    from benchmarks import goalset
from nonholo.certify.resimulate import resimulate, terminal_error  # noqa: E402
from nonholo.controls.parametrisations import from_dict  # noqa: E402
from nonholo.spaces import so3

RAW = json.loads(goalset.DEFAULT_PATH.read_text()) if goalset.DEFAULT_PATH.exists() else None
pytestmark = pytest.mark.skipif(RAW is None, reason="run `python -m benchmarks.goalset` first")


@pytest.fixture(scope="module")
def goals():
    return goalset.load_goals()


def _by_band(goals, band):
    return [g for g in goals if g["band"] == band]


def test_file_header_and_counts(goals):
    assert RAW["format"] == goalset.FORMAT
    assert RAW["seed"] == goalset.SEED
    near, far, across = (_by_band(goals, b) for b in ("near", "far", "across"))
    assert len(near) >= 50 and len(far) >= 50 and len(near) + len(far) >= 100
    assert len(across) >= 20
    assert len(near) + len(far) + len(across) == len(goals)
    assert len({g["id"] for g in goals}) == len(goals)


def test_starts_cover_both_components(goals):
    starts = [np.array(s["R0"]) for s in RAW["starts"]]
    assert len(starts) >= 6
    d = np.array([goalset.delta(R) for R in starts])
    assert np.all(np.abs(d) >= 0.3)
    assert (d > 0).sum() >= 3 and (d < 0).sum() >= 3
    for b in ("near", "far", "across"):
        used = {g["start"] for g in _by_band(goals, b)}
        assert used == set(range(len(starts))), b
    for g in goals:
        np.testing.assert_array_equal(g["R0"], starts[g["start"]])


def test_stored_data_consistent(goals):
    for g in goals:
        R0 = so3.check_rotation(g["R0"], "R0", tol=1e-12)
        Rd = so3.check_rotation(g["Rd"], "Rd", tol=1e-12)
        assert g["T"] == 1.0
        assert g["distance"] == pytest.approx(so3.distance(Rd, R0), abs=1e-12)
        assert g["delta0"] == pytest.approx(goalset.delta(R0), abs=1e-14)
        assert g["deltad"] == pytest.approx(goalset.delta(Rd), abs=1e-14)
        assert abs(g["delta0"]) >= 0.3
        if g["band"] == "across":
            assert np.sign(g["deltad"]) != np.sign(g["delta0"]), g["id"]
            assert abs(g["deltad"]) >= 0.1
            assert g["min_delta_generating"] is None and g["generating_controls"] is None
            assert 0.2 <= g["distance"] <= 1.8
        else:
            lo, hi = goalset.BANDS[g["band"]]
            assert lo <= g["distance"] <= hi, g["id"]
            assert np.sign(g["deltad"]) == np.sign(g["delta0"]), g["id"]
            assert g["min_delta_generating"] >= 0.1, g["id"]
            assert abs(g["deltad"]) >= g["min_delta_generating"] - 1e-12
            gc = g["generating_controls"]
            assert gc["kind"] == "fourier" and gc["harmonics"] in goalset.HARMONICS
            assert gc["coeffs"].shape == (2, 2 * gc["harmonics"] + 1)


@pytest.mark.slow
def test_generating_controls_reach_the_goals(goals):
    """The stored controls, re-simulated independently (nonholo.certify.resimulate, DOP853 1e-13), reach Rd."""
    reach = [g for g in goals if g["band"] != "across"]
    for g in reach:
        c = from_dict({**g["generating_controls"], "coeffs": g["generating_controls"]["coeffs"].tolist()})
        RT = resimulate(g["R0"], c, g["T"])
        assert terminal_error(RT, g["Rd"]) < 1e-9, g["id"]


def test_generator_is_deterministic(goals):
    """Regenerating a slice with the same seed reproduces the stored goals."""
    starts = goalset.starts(goalset.SEED)
    assert len(starts) == len(RAW["starts"])
    for R, s in zip(starts, RAW["starts"]):
        np.testing.assert_allclose(R, s["R0"], rtol=0, atol=1e-15)
    stored = {g["id"]: g for g in goals}
    for start, band, count in ((0, "near", 3), (5, "near", 2), (3, "far", 1)):
        regen, _ = goalset.reachable_goals(start, band, count)
        for g in regen:
            s = stored[g["id"]]
            np.testing.assert_allclose(g["Rd"], s["Rd"], rtol=0, atol=1e-12)
            np.testing.assert_allclose(g["generating_controls"]["coeffs"],
                                       s["generating_controls"]["coeffs"], rtol=0, atol=0)
            assert g["distance"] == pytest.approx(s["distance"], abs=1e-12)
    for g in goalset.across_goals(2, goalset.ACROSS_PER_START):
        np.testing.assert_allclose(g["Rd"], stored[g["id"]]["Rd"], rtol=0, atol=1e-15)


def test_load_goals_arrays(goals):
    g = goals[0]
    assert isinstance(g["R0"], np.ndarray) and g["R0"].shape == (3, 3)
    assert isinstance(g["Rd"], np.ndarray) and g["Rd"].shape == (3, 3)


@pytest.mark.parametrize("mechanism", ["platform", "platform_raised"])
def test_band_pairs_fill_every_band_from_the_uniform_stream(mechanism):
    """Each band holds the requested number of pairs in one component, each at the distance
    its band says; the pairs are those of the uniform stream (same seed), in draw order."""
    from nonholo.model import catalog

    mech = catalog.get(mechanism)
    pairs = goalset.band_pairs(mechanism, 12)
    assert [p["band"] for p in pairs] == [b for b in goalset.UNIFORM_BANDS for _ in range(12)]
    stream = goalset.uniform_pairs(mechanism, 400)
    for p in pairs:
        lo, hi = goalset.UNIFORM_BANDS[p["band"]]
        assert so3.distance(p["R0"], p["Rd"]) == pytest.approx(p["distance"])
        assert lo <= p["distance"] < hi
        d0, dd = float(mech.delta(p["R0"])), float(mech.delta(p["Rd"]))
        assert np.sign(d0) == np.sign(dd) and min(abs(d0), abs(dd)) >= goalset.UNIFORM_MIN_DELTA
    far = [p for p in pairs if p["band"] == "1.8-pi"]
    in_stream = [q for q in stream if q["band"] == "1.8-pi"][:12]
    assert all(np.array_equal(a["R0"], b["R0"]) and np.array_equal(a["Rd"], b["Rd"]) for a, b in zip(far, in_stream))
    assert goalset.band_pairs(mechanism, 12)[5]["Rd"].tolist() == pairs[5]["Rd"].tolist()
