"""The documentation site: the gallery's staleness check, the ``Raises`` check, and the
build itself (``sphinx-build -W``) with every internal link of the built site resolved."""
from __future__ import annotations

import html.parser
import importlib.util
import os
import subprocess
import sys
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

ROOT = Path(__file__).resolve().parents[1]
nbformat = pytest.importorskip("nbformat")


def load(name: str):
    spec = importlib.util.spec_from_file_location(f"docs_ext_{name}", ROOT / "docs" / "ext" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


gallery = load("gallery")
reference = load("reference")


def notebook(*cells):
    nb = nbformat.v4.new_notebook()
    for kind, source, outputs in cells:
        if kind == "markdown":
            nb.cells.append(nbformat.v4.new_markdown_cell(source))
        else:
            cell = nbformat.v4.new_code_cell(source)
            if outputs is not None:
                cell.execution_count = 1
                cell.outputs = [nbformat.from_dict(o) for o in outputs]
            nb.cells.append(cell)
    return nb


PNG = {"output_type": "display_data", "metadata": {},
       "data": {"image/png": "iVBORw0KGgo=", "text/plain": "<Figure size 640x480 with 1 Axes>"}}
FIGURE_AS_TEXT = {"output_type": "execute_result", "execution_count": 1, "metadata": {},
                  "data": {"text/plain": "<Figure size 640x480 with 1 Axes>"}}
ERROR = {"output_type": "error", "ename": "ValueError", "evalue": "x", "traceback": []}


@pytest.fixture
def folders(tmp_path):
    notebooks, copies = tmp_path / "notebooks", tmp_path / "gallery"
    notebooks.mkdir()
    copies.mkdir()
    source = notebook(("markdown", "# Title", None), ("code", "plot()", None))
    nbformat.write(source, notebooks / "01_a.ipynb")
    return notebooks, copies


def write_copy(copies, *cells, note=True):
    nb = notebook(*cells)
    if note:
        cell = nbformat.v4.new_markdown_cell("*Executed on ...*")
        cell.metadata["tags"] = [gallery.NOTE_TAG]
        nb.cells.insert(1, cell)
    nbformat.write(nb, copies / "01_a.ipynb")


def test_a_current_copy_with_its_figure_is_no_problem(folders):
    notebooks, copies = folders
    write_copy(copies, ("markdown", "# Title", None), ("code", "plot()", [PNG]))
    assert gallery.problems(notebooks, copies) == []


def test_a_new_notebook_without_a_copy_is_named(folders):
    notebooks, copies = folders
    write_copy(copies, ("markdown", "# Title", None), ("code", "plot()", [PNG]))
    nbformat.write(notebook(("code", "1 + 1", None)), notebooks / "07_new.ipynb")
    [message] = gallery.problems(notebooks, copies)
    assert "07_new.ipynb has no executed copy" in message and gallery.REFRESH in message


def test_an_edited_notebook_makes_its_copy_stale(folders):
    notebooks, copies = folders
    write_copy(copies, ("markdown", "# Title", None), ("code", "plot()", [PNG]))
    nbformat.write(notebook(("markdown", "# Title", None), ("code", "plot(2)", None)),
                   notebooks / "01_a.ipynb")
    [message] = gallery.problems(notebooks, copies)
    assert "01_a.ipynb is stale" in message


@pytest.mark.parametrize("outputs, words", [([FIGURE_AS_TEXT], "shows a figure as text"),
                                            ([ERROR], "raised ValueError"),
                                            (None, "was not executed")])
def test_a_copy_that_does_not_show_its_outputs_is_refused(folders, outputs, words):
    notebooks, copies = folders
    write_copy(copies, ("markdown", "# Title", None), ("code", "plot()", outputs))
    [message] = gallery.problems(notebooks, copies)
    assert "code cell 1 " + words in message


def test_a_copy_without_its_notebook_is_named(folders):
    notebooks, copies = folders
    write_copy(copies, ("markdown", "# Title", None), ("code", "plot()", [PNG]))
    (notebooks / "01_a.ipynb").unlink()
    [message] = gallery.problems(notebooks, copies)
    assert "01_a.ipynb has no notebook" in message


def test_raises_is_found_in_the_body_not_in_nested_functions():
    def raises(x):
        if x < 0:
            raise ValueError("x")
        return x

    def nested(x):
        def inner():
            raise ValueError("x")
        return inner

    def reraises(x):
        try:
            return 1 / x
        except ZeroDivisionError:
            raise

    assert reference.raises_something(raises)
    assert not reference.raises_something(nested)
    assert not reference.raises_something(reraises)


class Links(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.links, self.ids = [], set()

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if "id" in attrs:
            self.ids.add(attrs["id"])
        for key in ("href", "src"):
            if attrs.get(key) and not (tag == "link" and attrs.get("rel") == "preload"):
                self.links.append(attrs[key])


def test_the_site_builds_without_warnings_and_its_internal_links_resolve(tmp_path):
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_nb")
    out = tmp_path / "html"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    run = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-j", "auto", "-b", "html",
                          str(ROOT / "docs"), str(out)], cwd=ROOT, env=env, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-6000:]

    pages = {p: Links() for p in out.rglob("*.html") if "_static" not in p.relative_to(out).parts}
    for path, parser in pages.items():
        parser.feed(path.read_text(encoding="utf-8"))
    broken = []
    for path, parser in pages.items():
        for link in parser.links:
            parts = urlsplit(link)
            if parts.scheme or link.startswith(("//", "mailto:", "javascript:", "data:")):
                continue
            target = (path.parent / unquote(parts.path)).resolve() if parts.path else path
            if target.is_dir():
                target = target / "index.html"
            if not target.exists():
                broken.append(f"{path.relative_to(out)} → {link}")
            elif parts.fragment and target.suffix == ".html" and target in pages \
                    and unquote(parts.fragment) not in pages[target].ids:
                broken.append(f"{path.relative_to(out)} → {link} (no such anchor)")
    assert not broken, "\n".join(broken[:40])

    # the landing page shows its figure; every gallery page shows figures as images
    assert "example3_overview.png" in (out / "index.html").read_text(encoding="utf-8")
    for copy in sorted((ROOT / "docs" / "gallery").glob("*.ipynb")):
        page = (out / "gallery" / copy.with_suffix(".html").name).read_text(encoding="utf-8")
        images = sum(1 for c in nbformat.read(copy, 4).cells for o in c.get("outputs", [])
                     if any(k.startswith("image/") for k in o.get("data", {})))
        assert page.count("<img") >= images, copy.name
    # the package's surface: each name a page with its parameters, returns and raises
    import nonholo

    for name in nonholo.__all__:
        obj = getattr(nonholo, name)
        page = out / "api" / "generated" / f"{obj.__module__}.{obj.__qualname__}.html"
        assert page.exists(), name
    plan = (out / "api" / "generated" / "nonholo.planning.api.plan.html").read_text(encoding="utf-8")
    for section in ("Parameters", "Returns", "Raises"):
        assert section in plan
