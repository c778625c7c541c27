"""The documentation site: the gallery's staleness check, the ``Raises`` check, the build
itself (``sphinx-build -W``, with the packages of the extras other than ``docs`` not
importable) with every internal link of the built site resolved, and the landing page opened
in a headless Chromium (when there is one)."""
from __future__ import annotations

import fcntl
import functools
import html.parser
import http.server
import importlib.util
import os
import re
import shutil
import struct
import subprocess
import sys
import threading
import urllib.error
import urllib.request
from pathlib import Path
from urllib.parse import unquote, urljoin, urlsplit

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
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


#: The top-level packages of the extras other than ``docs`` (``physics``: MuJoCo; ``cluster``:
#: Dask; ``bench``; ``notebooks``): ``pip install -e ".[docs]"`` alone builds the site, so the
#: build (conf.py, docs/ext/, autosummary's imports of every public module) imports none of
#: them — a public module that needs one imports it where it is used.
NOT_IN_THE_DOCS_EXTRA = ("mujoco", "dask", "distributed", "casadi", "ompl", "control", "jupyterlab")

#: A ``sitecustomize`` that makes those packages not importable, as in an environment with the
#: ``docs`` extra alone, and writes each attempt, with its stack, to a log.
BLOCKER = """\
import sys
import traceback

BLOCKED = {blocked!r}
LOG = {log!r}


class NotInstalled:
    \"\"\"Import of a package of another extra: ModuleNotFoundError, the attempt logged.\"\"\"

    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] not in BLOCKED:
            return None
        with open(LOG, "a", encoding="utf-8") as log:
            log.write(f"import {{name}}\\n" + "".join(traceback.format_stack()) + "\\n")
        raise ModuleNotFoundError(f"No module named {{name!r}} (tests/project/test_docs.py: not in the docs extra)",
                                  name=name)


sys.meta_path.insert(0, NotInstalled())
"""


def without_other_extras(folder: Path) -> tuple[dict, Path]:
    """The environment of a process in which :data:`NOT_IN_THE_DOCS_EXTRA` cannot be imported
    (a ``sitecustomize`` in ``folder``, first on ``PYTHONPATH``), and the log of its attempts."""
    log = folder / "blocked_imports.log"
    (folder / "sitecustomize.py").write_text(BLOCKER.format(blocked=NOT_IN_THE_DOCS_EXTRA, log=str(log)),
                                             encoding="utf-8")
    path = os.pathsep.join(p for p in (str(folder), str(ROOT), os.environ.get("PYTHONPATH", "")) if p)
    return dict(os.environ, PYTHONPATH=path), log


def test_the_blocker_makes_the_other_extras_not_importable_and_logs_the_attempt(tmp_path):
    env, log = without_other_extras(tmp_path)
    code = ("import importlib\n"
            "for name in ('mujoco', 'dask.array', 'json'):\n"
            "    try:\n"
            "        importlib.import_module(name)\n"
            "        print(name, 'imported')\n"
            "    except ModuleNotFoundError as e:\n"
            "        print(name, 'missing', e.name)\n")
    run = subprocess.run([sys.executable, "-c", code], check=False, env=env, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert run.stdout.splitlines() == ["mujoco missing mujoco", "dask.array missing dask", "json imported"]
    logged = log.read_text(encoding="utf-8")
    assert "import mujoco\n" in logged and "import dask\n" in logged and "import json" not in logged


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The site built once for the tests of this module (the build is the slow part), with
    the packages of the other extras not importable (:data:`NOT_IN_THE_DOCS_EXTRA`): its
    ``html`` folder."""
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_nb")
    # one build for the whole run: the build writes its API stubs into docs/, so two
    # workers of pytest-xdist building at once would race; the first builds, under a lock
    # in the run's shared temporary folder, the others wait for it and read its site
    shared = tmp_path_factory.getbasetemp().parent
    out = shared / "docs_site" / "html"
    with open(shared / "docs_site.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        done = shared / "docs_site" / "built"
        if not done.exists():
            shutil.rmtree(out, ignore_errors=True)
            env, blocked = without_other_extras(tmp_path_factory.mktemp("docs_extra_only"))
            run = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-j", "auto", "-b",
                                  "html", str(ROOT / "docs"), str(out)], check=False, cwd=ROOT, env=env,
                                 capture_output=True, text=True)
            # nothing of another extra was imported while building, not even in a try/except
            assert not blocked.exists(), ("the docs build imports packages the docs extra does not install:\n"
                                          + blocked.read_text(encoding="utf-8")[-6000:])
            assert run.returncode == 0, run.stderr[-6000:]
            done.write_text("ok\n")
    return out


@pytest.mark.slow
def test_the_site_builds_without_warnings_and_its_internal_links_resolve(site):
    out = site
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


# -- the landing page in a real browser --------------------------------------------------------

#: Chromium, if installed (Debian's package, else one on the PATH).
CHROMIUM = next((c for c in ("/usr/bin/chromium", shutil.which("chromium"), shutil.which("chromium-browser"))
                 if c and os.path.exists(c)), None)
#: Headless, offline, nothing of a user's profile (root needs ``--no-sandbox``).
CHROMIUM_FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync",
                  "--hide-scrollbars", "--window-size=1280,1400")
#: The landing page's figure and the top-level entries of its navigation.
LANDING_FIGURE = "example3_overview.png"
NAVIGATION = ("guide/index.html", "gallery/index.html", "api/index.html", "benchmarks/index.html")
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


class Served(http.server.SimpleHTTPRequestHandler):
    """A static file server of the built site that keeps every request's path and status."""

    requests: list

    def log_request(self, code="-", size="-"):
        self.requests.append((urlsplit(self.path).path, int(code) if isinstance(code, int) else code))

    def log_message(self, format, *args):
        pass


class Server(http.server.ThreadingHTTPServer):
    """The local server; a browser that exits before reading a reply (its favicon's) is no error."""

    daemon_threads = True

    def handle_error(self, request, client_address):
        if not isinstance(sys.exc_info()[1], ConnectionError):
            super().handle_error(request, client_address)


class Rendered(html.parser.HTMLParser):
    """What a rendered page holds: its images, and its links (in or out of a ``<nav>``)."""

    def __init__(self):
        super().__init__()
        self.images, self.links, self.nav_links = [], [], []
        self.nav_depth = 0

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "nav":
            self.nav_depth += 1
        if tag == "img" and attrs.get("src"):
            self.images.append(attrs["src"])
        for key in ("href", "src"):
            if attrs.get(key) and not (tag == "link" and attrs.get("rel") == "preload"):
                self.links.append(attrs[key])
        if tag == "a" and attrs.get("href") and self.nav_depth:
            self.nav_links.append(attrs["href"])

    def handle_endtag(self, tag):
        if tag == "nav" and self.nav_depth:
            self.nav_depth -= 1


def chromium(tmp_path: Path, name: str, *args: str) -> subprocess.CompletedProcess:
    """Chromium headless with a new empty profile ``tmp_path / name``."""
    profile = tmp_path / name
    profile.mkdir()
    run = subprocess.run([CHROMIUM, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *args],
                         check=False, capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr[-3000:]
    return run


def fetch(url: str) -> tuple[int, bytes]:
    """``(status, body)`` of a GET from the local server."""
    try:
        with urllib.request.urlopen(url, timeout=10) as response:
            return response.status, response.read()
    except urllib.error.HTTPError as exc:
        return exc.code, b""


def png_size(data: bytes) -> tuple[int, int]:
    """A PNG's width and height from its header (``(0, 0)`` if it is not a PNG)."""
    if not (data.startswith(PNG_SIGNATURE) and data[12:16] == b"IHDR"):
        return 0, 0
    return struct.unpack(">II", data[16:24])


def read_png(path: Path) -> np.ndarray:
    """A PNG's pixels, by Pillow if installed, else by matplotlib."""
    try:
        from PIL import Image
    except ImportError:
        import matplotlib.image

        return np.asarray(matplotlib.image.imread(path))
    with Image.open(path) as image:
        return np.asarray(image.convert("RGB"))


@pytest.mark.skipif(CHROMIUM is None, reason="no Chromium (/usr/bin/chromium, or chromium on the PATH): "
                                             "the landing page is not opened in a browser")
@pytest.mark.slow
def test_the_landing_page_in_a_headless_browser_shows_the_figure_and_the_navigation(site, tmp_path):
    requests: list = []
    handler = functools.partial(type("Site", (Served,), {"requests": requests}), directory=str(site))
    server = Server(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        base = f"http://127.0.0.1:{server.server_address[1]}/"
        landing = base + "index.html"
        dom = chromium(tmp_path, "dom", "--dump-dom", landing).stdout
        shot = tmp_path / "landing.png"
        chromium(tmp_path, "shot", f"--screenshot={shot}", landing)

        page = Rendered()
        page.feed(dom)
        # the figure: in the rendered DOM, served, a PNG of a non-zero size
        figures = [urljoin(landing, src) for src in page.images if src.endswith(LANDING_FIGURE)]
        assert figures, f"no <img> of {LANDING_FIGURE} in the rendered landing page"
        status, data = fetch(figures[0])
        assert status == 200, (figures[0], status)
        width, height = png_size(data)
        assert width > 0 and height > 0, f"{figures[0]} is not a PNG of a non-zero size"
        assert (urlsplit(figures[0]).path, 200) in requests, "the browser did not load the figure"
        # the navigation: the toctree's top entries, as links in a <nav> of the rendered page
        nav = {urlsplit(urljoin(landing, href)).path for href in page.nav_links}
        missing = [p for p in NAVIGATION if urlsplit(urljoin(base, p)).path not in nav]
        assert not missing, f"the navigation lacks {missing} (has {sorted(nav)})"
        # every internal link of the rendered page answers 200
        internal = set()
        for link in page.links:
            url = urljoin(landing, link)
            if url.startswith(base):
                internal.add(url.split("#", 1)[0])
        broken = [(url, status) for url in sorted(internal) if (status := fetch(url)[0]) != 200]
        assert not broken, broken
        # what the browser itself asked for while rendering was served (but the favicon it
        # asks for unasked)
        failed = [(p, c) for p, c in requests if c != 200 and p != "/favicon.ico"]
        assert not failed, failed
    finally:
        server.shutdown()
        server.server_close()
        thread.join(5)

    # the screenshot shows something: not one colour
    pixels = read_png(shot)
    assert pixels.ndim == 3 and pixels.shape[0] > 0 and pixels.shape[1] > 0
    flat = pixels.reshape(-1, pixels.shape[2])
    assert (flat != flat[0]).any(), "the screenshot of the landing page is blank (one colour)"


#: The gallery's page of animations and the GIFs it shows (one per catalog mechanism).
ANIMATIONS_PAGE = "gallery/animations.html"
ANIMATIONS = sorted(p.name for p in (ROOT / "docs" / "gallery" / "animations").glob("*.gif"))


@pytest.mark.skipif(CHROMIUM is None, reason="no Chromium (/usr/bin/chromium, or chromium on the PATH): "
                                             "the animations page is not opened in a browser")
@pytest.mark.slow
def test_the_animations_page_in_a_headless_browser_loads_its_gifs(site, tmp_path):
    assert ANIMATIONS, "no GIF in docs/gallery/animations (python docs/ext/animations.py writes them)"
    requests: list = []
    handler = functools.partial(type("Site", (Served,), {"requests": requests}), directory=str(site))
    server = Server(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        page_url = f"http://127.0.0.1:{server.server_address[1]}/{ANIMATIONS_PAGE}"
        page = Rendered()
        page.feed(chromium(tmp_path, "dom", "--dump-dom", page_url).stdout)
        gifs = [urljoin(page_url, src) for src in page.images if src.endswith(".gif")]
        assert len(gifs) == len(ANIMATIONS), (gifs, ANIMATIONS)
        for url in gifs:
            # loaded by the browser itself, and a GIF of more than one frame
            assert (urlsplit(url).path, 200) in requests, f"the browser did not load {url}"
            status, data = fetch(url)
            assert status == 200 and data[:6] in (b"GIF87a", b"GIF89a"), url
            assert data.count(b"\x21\xf9\x04") > 1, f"{url} has one frame"       # graphic control blocks
    finally:
        server.shutdown()
        server.server_close()
        thread.join(5)


def table_rows_of_the_wrong_width(text: str) -> list[tuple[int, int, int]]:
    """``(line, cells, expected)`` of every Markdown table row whose number of cells is not
    its header's: cells split at ``|`` not escaped as ``\\|`` (a ``|`` inside a code span
    splits a row as well, in GitHub's and MyST's tables alike)."""
    bad, width = [], None
    for number, line in enumerate(text.splitlines(), 1):
        stripped = line.strip()
        if not (stripped.startswith("|") and stripped.endswith("|") and len(stripped) > 1):
            width = None
            continue
        cells = len(re.split(r"(?<!\\)\|", stripped)) - 2
        if width is None:
            width = cells
        elif cells != width:
            bad.append((number, cells, width))
    return bad


def test_the_table_check_sees_a_pipe_that_splits_a_cell():
    table = "| a | b |\n|---|---|\n| `x|y` | 1 |\n| `x\\|y` | 2 |\n"
    assert table_rows_of_the_wrong_width(table) == [(3, 3, 2)]


#: The Markdown pages written by hand (the build's copies and outputs are not: the same on
#: every worker of a parallel run, whether or not the docs were built before)
HAND_WRITTEN = sorted(p.relative_to(ROOT).as_posix() for p in [ROOT / "README.md", *ROOT.glob("docs/**/*.md")]
                      if not {"_build", "jupyter_execute", "generated"} & set(p.parts)
                      and "docs/benchmarks/results" not in p.as_posix())


@pytest.mark.parametrize("page", HAND_WRITTEN)
def test_every_table_row_has_its_header_s_cells(page):
    assert table_rows_of_the_wrong_width((ROOT / page).read_text(encoding="utf-8")) == [], page
