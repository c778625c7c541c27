"""Outputs that stay as they are where only rounding moved: the tolerant comparison of texts
and arrays (:mod:`nonholo.io.numeric_diff`), what a figure draws as data
(:mod:`nonholo.viz.figure_data`), the main job's writer (:mod:`nonholo.paper.outputs`) and
the record of what made a file (:mod:`nonholo.io.provenance`)."""
from __future__ import annotations

import json

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

from matplotlib.figure import Figure  # noqa: E402

from nonholo.io import numeric_diff, provenance  # noqa: E402
from nonholo.paper.outputs import DATA_DIR, Outputs  # noqa: E402
from nonholo.viz import figure_data  # noqa: E402


# -- numbers in texts and arrays -----------------------------------------------------------

def test_texts_agree_where_only_rounding_moved():
    a = '{"terminal_error": 1.96139e-11, "T": 1.0000000000000002, "iterations": 12}'
    b = '{"terminal_error": 1.96146e-11, "T": 1.0, "iterations": 12}'
    assert numeric_diff.agree(a, b)                 # an error at rounding level is noise
    assert numeric_diff.text_distance(a, a) == 0.0


def test_texts_differ_beyond_the_tolerance_or_in_words():
    assert not numeric_diff.agree('{"T": 1.0}', '{"T": 1.00001}')
    assert numeric_diff.text_distance('{"T": 1.0}', '{"T": 1.00001}') == pytest.approx(1e-5, rel=1e-3)
    assert not numeric_diff.agree('{"iterations": 12}', '{"iterations": 13}')
    assert numeric_diff.text_distance('"success": true', '"success": false') == float("inf")
    assert numeric_diff.text_distance("a 1 b", "a 1 b 2") == float("inf")


def test_large_numbers_are_compared_relatively():
    assert numeric_diff.agree("x = 123456789.0", "x = 123456789.05")
    assert not numeric_diff.agree("x = 123456789.0", "x = 123456790.0")


def test_array_distance():
    a = np.linspace(0.0, 5.0, 11)
    assert numeric_diff.array_distance(a, a * (1 + 1e-13)) <= numeric_diff.RTOL
    assert numeric_diff.array_distance(a, a + 1e-6) == pytest.approx(1e-6, rel=1e-6)   # at |a| <= 1
    assert numeric_diff.array_distance(a[-1:], a[-1:] + 1e-6) == pytest.approx(1e-6 / 5.0, rel=1e-6)
    assert numeric_diff.array_distance(a, a[:-1]) == float("inf")
    assert numeric_diff.array_distance([np.nan, 1.0], [np.nan, 1.0]) == 0.0
    assert numeric_diff.array_distance([np.nan, 1.0], [0.0, 1.0]) == float("inf")


# -- what a figure draws ---------------------------------------------------------------------

def _figure(scale: float = 1.0, title: str = "error 1.8e-11 rad") -> Figure:
    t = np.linspace(0.0, 1.0, 200)
    fig = Figure(figsize=(6, 3))
    ax, right = fig.subplots(1, 2)
    ax.semilogy(t, scale * (1e-12 + np.exp(-10 * t)), color="C1", label="error")
    ax.scatter(t[::20], scale * np.sin(t[::20]))
    right.imshow(scale * np.outer(t[:10], t[:10]), extent=(0, 1, 0, 1))
    ax.set_title(title)
    ax.set_xlabel("t [s]")
    ax.legend()
    return fig


def test_a_figure_records_its_data_not_its_pixels():
    words, numbers = figure_data.figure_data(_figure())
    assert any(w.startswith("line[") and w.endswith(":error") for w in words)
    assert any(w.endswith(":t [s]") for w in words)
    assert any(w.startswith("image[") for w in words)
    assert not any("0.0" == w.split(":")[-1] for w in words)      # no tick labels
    again_words, again = figure_data.figure_data(_figure(1 + 1e-14, "error 1.9e-11 rad"))
    assert again_words != words                                   # the title's number moved ...
    moved = [(a, b) for a, b in zip(words, again_words) if a != b]
    assert all(numeric_diff.agree(a, b) for a, b in moved)        # ... within the tolerance
    assert numeric_diff.array_distance(numbers, again) <= numeric_diff.RTOL
    _, far = figure_data.figure_data(_figure(1 + 1e-6))
    assert numeric_diff.array_distance(numbers, far) > numeric_diff.RTOL


def test_a_figure_record_is_stored_byte_for_byte_and_damage_is_refused():
    words, numbers = figure_data.figure_data(_figure())
    data = figure_data.to_bytes(words, numbers)
    assert data == figure_data.to_bytes(*figure_data.figure_data(_figure()))
    back_words, back = figure_data.from_bytes(data)
    assert back_words == words
    np.testing.assert_array_equal(back, numbers)        # the same file read back
    for bad in (b"", b"PNG", data[:20], data[:-5]):
        with pytest.raises(ValueError):
            figure_data.from_bytes(bad)


# -- the main job's writer -------------------------------------------------------------------

def _snapshot(folder):
    return {p.relative_to(folder): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_outputs_keep_files_whose_content_agrees(tmp_path):
    first = Outputs(tmp_path)
    first.text("table.md", "| a | 1.0000000000000002 |\n")
    first.json("summary.json", json.dumps({"made_by": {"commit": "aaa"}, "x": [1.0, 2e-11]}))
    first.figure(_figure(), "fig")
    assert {p.name for p in first.written} == {"table.md", "summary.json", "fig.png", "fig.pdf", "fig.data"}
    assert (tmp_path / DATA_DIR / "fig.data").is_file()
    before = _snapshot(tmp_path)

    second = Outputs(tmp_path)                  # rounding moved, and the commit changed
    second.text("table.md", "| a | 1.0 |\n")
    second.json("summary.json", json.dumps({"made_by": {"commit": "bbb"}, "x": [1.0 + 1e-15, 2.1e-11]}))
    second.figure(_figure(1 + 1e-14), "fig")
    assert second.written == [] and second.differences == [] and len(second.kept) == 3
    assert _snapshot(tmp_path) == before        # nothing rewritten: the first maker stays recorded

    third = Outputs(tmp_path)
    third.text("table.md", "| a | 1.5 |\n")
    third.json("summary.json", json.dumps({"made_by": {"commit": "ccc"}, "x": [1.0, 3.0]}))
    third.figure(_figure(1.01), "fig")
    assert {d.path.name for d in third.differences} == {"table.md", "summary.json", "fig.png"}
    assert json.loads((tmp_path / "summary.json").read_text())["made_by"] == {"commit": "ccc"}
    assert (tmp_path / "fig.png").read_bytes() != before[tmp_path.joinpath("fig.png").relative_to(tmp_path)]


def test_check_writes_nothing_and_says_how_far(tmp_path):
    Outputs(tmp_path).text("a.csv", "t,x\n0,1.0\n")
    before = _snapshot(tmp_path)
    check = Outputs(tmp_path, check=True)
    check.text("a.csv", "t,x\n0,1.001\n")
    check.text("b.csv", "t\n")
    check.figure(_figure(), "fig")
    assert _snapshot(tmp_path) == before and check.written == []
    why = {d.path.name: d for d in check.differences}
    assert set(why) == {"a.csv", "b.csv", "fig.png"}
    assert why["a.csv"].distance == pytest.approx(1e-3 / 1.001, rel=1e-6) and "1.0e-03" in str(why["a.csv"])
    assert "missing" in str(why["b.csv"]) and "missing" in str(why["fig.png"])


@pytest.mark.slow
def test_a_damaged_figure_record_is_redrawn(tmp_path):
    Outputs(tmp_path).figure(_figure(), "fig")
    (tmp_path / DATA_DIR / "fig.data").write_bytes(b"garbage")
    again = Outputs(tmp_path)
    again.figure(_figure(), "fig")
    assert [d.path.name for d in again.differences] == ["fig.png"]
    figure_data.from_bytes((tmp_path / DATA_DIR / "fig.data").read_bytes())    # repaired


# -- what made a file --------------------------------------------------------------------------

def test_made_by_names_the_code_and_the_libraries():
    made = provenance.made_by()
    assert tuple(made) == provenance.KEYS
    import numpy
    import scipy
    import sympy
    assert (made["numpy"], made["scipy"], made["sympy"]) == (numpy.__version__, scipy.__version__,
                                                             sympy.__version__)
    assert made["kernels"] in ("native", "numba")


def test_a_plan_file_records_what_made_it_and_old_files_load(tmp_path):
    import nonholo
    from nonholo.spaces import so3

    res = nonholo.plan(so3.from_rpy(0.1, 0.2, 0.3), so3.from_rpy(0.3, 0.1, 0.2), objective=None)
    path = res.save(tmp_path / "plan.json")
    d = json.loads(path.read_text())
    assert d["made_by"] == provenance.made_by()
    back = nonholo.PlanResult.load(path)
    assert back == res and back.made_by == d["made_by"]
    del d["made_by"]                                      # a file written before it was recorded
    (tmp_path / "old.json").write_text(json.dumps(d))
    old = nonholo.PlanResult.load(tmp_path / "old.json")
    assert old == res and old.made_by is None
    assert json.loads(old.to_json())["made_by"] == provenance.made_by()
    for bad in ("x", [1], {"numpy": 2}, {"numpy": "x" * 1000}):
        d["made_by"] = bad
        (tmp_path / "bad.json").write_text(json.dumps(d))
        with pytest.raises(ValueError, match="made_by"):
            nonholo.PlanResult.load(tmp_path / "bad.json")
