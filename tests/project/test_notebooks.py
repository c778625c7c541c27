"""Every notebook in notebooks/ runs clean (nbclient) and shows its figures as images.

The kernel runs with its own default Matplotlib backend, as a user's does. A cell that
calls one of the library's figure functions (``viz.*_figure(...)``) must show an
``image/png``, and no output may be a figure shown only as text (``<Figure size …>``).
"""
import base64
import io
import re
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient
from PIL import Image

NOTEBOOKS = sorted((Path(__file__).resolve().parents[2] / "notebooks").glob("*.ipynb"))
#: a call of a figure function (``save_figure`` writes files, it draws nothing)
FIGURE_CALL = re.compile(r"\b(?!save_figure\b)\w+_figure\(")
#: a figure displayed as its text form
FIGURE_AS_TEXT = re.compile(r"<[\w.]*Figure size \d+(\.\d+)?x\d+(\.\d+)?")


def images(cell) -> list[bytes]:
    return [base64.b64decode(o["data"]["image/png"]) for o in cell.get("outputs", [])
            if "image/png" in o.get("data", {})]


def test_the_checks_see_figure_calls():
    assert FIGURE_CALL.search("viz.convergence_figure(list(results.values()))")
    assert FIGURE_CALL.search("fig = viz.car_figure(parking)")
    assert not FIGURE_CALL.search("viz.save_figure(fig, 'x', out)")
    assert not FIGURE_CALL.search("fig.savefig(out / 'x.png')")
    assert FIGURE_AS_TEXT.search("<Figure size 1600x940 with 6 Axes>")
    assert FIGURE_AS_TEXT.search("<nonholo.viz.style.NotebookFigure size 640x440 with 1 Axes>")


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
@pytest.mark.slow
def test_notebook_runs_and_shows_its_figures(path, tmp_path, monkeypatch):
    monkeypatch.delenv("MPLBACKEND", raising=False)
    monkeypatch.setenv("NONHOLO_FIGURE_DIR", str(tmp_path))
    nb = nbformat.read(path, as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert all(not c.get("outputs") for c in code), "notebooks are stored with outputs stripped"
    client = NotebookClient(nb, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(path.parent)}})
    client.execute()  # raises CellExecutionError on any error
    errors = [o for c in code for o in c.get("outputs", []) if o.get("output_type") == "error"]
    assert not errors
    for k, cell in enumerate(code):
        as_text = [o["data"]["text/plain"] for o in cell.get("outputs", [])
                   if "text/plain" in o.get("data", {}) and "image/png" not in o["data"]
                   and FIGURE_AS_TEXT.search(o["data"]["text/plain"])]
        assert not as_text, f"code cell {k} shows a figure as text: {as_text}"
        if FIGURE_CALL.search(cell.source):
            shown = images(cell)
            assert shown, f"code cell {k} draws a figure but shows no image:\n{cell.source}"
            for png in shown:
                width, height = Image.open(io.BytesIO(png)).size
                assert width >= 200 and height >= 200, (k, width, height)
