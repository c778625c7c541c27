"""The gallery: every notebook of ``notebooks/``, stored executed in ``docs/gallery/``.

The notebooks are kept without outputs in ``notebooks/`` (the test suite runs them); the
documentation shows a copy of each one executed, with its outputs and figures, stored in
``docs/gallery/`` under the same name. The documentation build does not execute them (all
of them take minutes); it checks that every copy is current instead, and a copy that is
not is a build warning, an error under ``sphinx-build -W``:

- a notebook of ``notebooks/`` without a copy (a new notebook is picked up by its name);
- a copy whose cells differ from its notebook's (*stale*: the notebook was edited);
- a copy with a code cell that was not executed, or that raised;
- a copy that shows a figure as text (``<Figure size ...>``) instead of an image;
- a copy whose notebook is gone.

``python docs/ext/gallery.py`` executes the notebooks whose copies are not current and
writes their copies (``--all`` every notebook, or name them); ``--check`` only reports.
Notebooks run in ``notebooks/`` as a reader's Jupyter would run them, with the inline
backend for matplotlib (``InteractiveShellApp.matplotlib = "inline"``), and each copy
opens with a note saying when, at which commit, and from which notebook it was executed.
"""
from __future__ import annotations

import argparse
import datetime
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = ROOT / "notebooks"
GALLERY = ROOT / "docs" / "gallery"
#: tag of the note cell a stored copy opens with (not part of the notebook)
NOTE_TAG = "gallery-note"
REFRESH = "python docs/ext/gallery.py"
FIGURE_TEXT = re.compile(r"<(matplotlib\.figure\.)?\w*Figure size [^>]*>")


def _read(path: Path):
    import nbformat

    return nbformat.read(path, as_version=4)


def cells(nb) -> list[tuple[str, str]]:
    """A notebook's cells as ``(cell type, source)``, the gallery's note left out.

    Parameters
    ----------
    nb : nbformat.NotebookNode
        The notebook.

    Returns
    -------
    list of tuple of str
        ``(cell_type, source)`` for every cell that is not the gallery's note.
    """
    return [(c.cell_type, c.source) for c in nb.cells
            if NOTE_TAG not in c.get("metadata", {}).get("tags", [])]


def copy_problems(copy) -> list[str]:
    """What keeps an executed copy from the gallery, whatever its notebook.

    Parameters
    ----------
    copy : nbformat.NotebookNode
        A stored executed notebook.

    Returns
    -------
    list of str
        One phrase per problem (a code cell not executed, an error output, a figure shown
        as text); empty if there is none.
    """
    out = []
    code = [c for c in copy.cells if c.cell_type == "code"]
    for i, c in enumerate(code, 1):
        where = f"code cell {i}"
        if c.source.strip() and c.get("execution_count") is None:
            out.append(f"{where} was not executed")
        for o in c.get("outputs", []):
            if o.get("output_type") == "error":
                out.append(f"{where} raised {o.get('ename', 'an error')}")
            data = o.get("data", {})
            text = data.get("text/plain", "")
            text = "".join(text) if isinstance(text, list) else text
            if FIGURE_TEXT.search(text) and not any(k.startswith("image/") for k in data):
                out.append(f"{where} shows a figure as text ({FIGURE_TEXT.search(text).group(0)}), "
                           "not as an image")
    return out


def problems(notebooks: Path = NOTEBOOKS, gallery: Path = GALLERY) -> list[str]:
    """Every reason the gallery is not the current notebooks executed.

    Parameters
    ----------
    notebooks : pathlib.Path
        The folder of the notebooks (stored without outputs), found by ``*.ipynb``.
    gallery : pathlib.Path
        The folder of their executed copies, one per notebook under the same name.

    Returns
    -------
    list of str
        One message per problem, naming the notebook and the command that refreshes it;
        empty when every notebook has a current, executed copy that shows its figures.
    """
    out = []
    sources = {p.name: p for p in sorted(notebooks.glob("*.ipynb"))}
    copies = {p.name: p for p in sorted(gallery.glob("*.ipynb"))}
    for name, path in sources.items():
        fix = f"run `{REFRESH} {name}`"
        if name not in copies:
            out.append(f"notebook {name} has no executed copy in the gallery: {fix}")
            continue
        copy = _read(copies[name])
        if cells(copy) != cells(_read(path)):
            out.append(f"the gallery's copy of {name} is stale (its cells differ from "
                       f"notebooks/{name}): {fix}")
            continue
        out.extend(f"the gallery's copy of {name}: {p}: {fix}" for p in copy_problems(copy))
    for name in copies.keys() - sources.keys():
        out.append(f"the gallery's {name} has no notebook in notebooks/: delete "
                   f"docs/gallery/{name}")
    return out


def _commit() -> str:
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, text=True,
                              capture_output=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--", "nonholo", "derivations",
                                "notebooks"], cwd=ROOT, text=True, capture_output=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + (" with uncommitted changes" if dirty.strip() else "")


def execute(path: Path, gallery: Path = GALLERY, timeout: int = 1200) -> Path:
    """Execute one notebook and store its copy in the gallery.

    Parameters
    ----------
    path : pathlib.Path
        The notebook, in ``notebooks/``.
    gallery : pathlib.Path
        Where the copy is written, under the notebook's name.
    timeout : int
        Seconds one cell may take.

    Returns
    -------
    pathlib.Path
        The copy written.

    Raises
    ------
    nbclient.exceptions.CellExecutionError
        If a cell raises; no copy is written then.
    """
    import nbformat
    from nbclient import NotebookClient

    nb = _read(path)
    os.environ["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + [p for p in [os.environ.get("PYTHONPATH")] if p])
    os.environ.pop("MPLBACKEND", None)
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as figures:
        os.environ["NONHOLO_FIGURE_DIR"] = figures
        NotebookClient(nb, timeout=timeout, kernel_name="python3",
                       extra_arguments=["--InteractiveShellApp.matplotlib=inline"],
                       resources={"metadata": {"path": str(path.parent)}}).execute()
    seconds = time.perf_counter() - start
    today = datetime.date.today().isoformat()
    note = nbformat.v4.new_markdown_cell(
        f"*Executed on {today} at commit {_commit()} from `notebooks/{path.name}` "
        f"({seconds:.0f} s); run it yourself with "
        f"`jupyter lab notebooks/{path.name}`.*")
    note.metadata["tags"] = [NOTE_TAG]
    first_is_title = nb.cells and nb.cells[0].cell_type == "markdown" and nb.cells[0].source.startswith("#")
    nb.cells.insert(1 if first_is_title else 0, note)
    gallery.mkdir(parents=True, exist_ok=True)
    out = gallery / path.name
    nbformat.write(nb, out)
    return out


def main(argv=None) -> int:
    """Refresh (or ``--check``) the gallery; exit status 1 if a problem is left.

    Parameters
    ----------
    argv : list of str, optional
        The command line's arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        0 if the gallery is current afterwards, 1 otherwise.
    """
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("names", nargs="*", help="notebooks to execute (file names in notebooks/)")
    parser.add_argument("--all", action="store_true", help="execute every notebook")
    parser.add_argument("--check", action="store_true", help="only report what is not current")
    args = parser.parse_args(argv)
    if not args.check:
        if args.all:
            todo = sorted(NOTEBOOKS.glob("*.ipynb"))
        elif args.names:
            todo = [NOTEBOOKS / n for n in args.names]
            missing = [str(p) for p in todo if not p.is_file()]
            if missing:
                parser.error(f"no such notebook: {', '.join(missing)}")
        else:
            todo = [p for p in sorted(NOTEBOOKS.glob("*.ipynb"))
                    if any(p.name in m for m in problems())]
        for path in todo:
            print(f"executing {path.name} ...", flush=True)
            print(f"  wrote {execute(path).relative_to(ROOT)}", flush=True)
        for name in {p.name for p in GALLERY.glob("*.ipynb")} - {p.name for p in NOTEBOOKS.glob("*.ipynb")}:
            (GALLERY / name).unlink()
            print(f"removed docs/gallery/{name} (its notebook is gone)")
    left = problems()
    for message in left:
        print(message)
    return 1 if left else 0


def setup(app):
    """Sphinx extension: every gallery problem is a build warning.

    Parameters
    ----------
    app : sphinx.application.Sphinx
        The application.

    Returns
    -------
    dict
        The extension's metadata.
    """
    from sphinx.util import logging

    logger = logging.getLogger(__name__)

    def check(app):
        for message in problems():
            logger.warning(message, type="gallery", subtype="stale")

    app.connect("builder-inited", check)
    return {"parallel_read_safe": True, "parallel_write_safe": True}


if __name__ == "__main__":
    sys.exit(main())
