"""The documentation's references resolve, and the command line's help is plain text.

Scanned: README.md, the notebooks and the package's sources (docstrings, comments, help
texts; the generated modules aside). A dotted name ``nonholo.x.y`` must import (a module,
or an attribute of one) without a ``DeprecationWarning`` (a moved module's old name is
stale); a repository path (``nonholo/…/x.py``, ``notebooks/x.ipynb``, ``X.md``) must exist.
"""
import argparse
import importlib
import inspect
import re
import warnings
from pathlib import Path

import pytest

from nonholo.cli import entry
from nonholo.cli.help_text import plain

ROOT = Path(__file__).resolve().parents[2]
SOURCES = ([ROOT / "README.md"] + sorted((ROOT / "notebooks").glob("*.ipynb"))
           + sorted(p for p in (ROOT / "nonholo").rglob("*.py") if "generated" not in p.parts))
#: ``nonholo.a.b`` not inside a word, a path, a quoted key or a format name (``nonholo.plan/3``)
DOTTED = re.compile(r"(?<![\w/.\"'])nonholo(?:\.[A-Za-z_]\w*)+(?![\w/])")
PATH = re.compile(r"(?<![\w/.])(?:nonholo|notebooks|derivations|benchmarks|tests|paper_figures)"
                  r"/[\w/.-]*\w\.(?:py|ipynb|md|json|csv|png|gif)\b")
TOP_FILE = re.compile(r"(?<![\w/.])[A-Z][A-Z_]+\.md\b")
#: files a text names as what a step *would* write
HYPOTHETICAL = {"nonholo/generated/platform_turned_disk.py"}
#: reST markup that must not reach a terminal
REST = re.compile(r":[a-z]+(?::[a-z]+)?:`|``")


def resolves(name: str) -> bool:
    parts = name.split(".")
    if parts[:3] == ["nonholo", "generated", "native"] and len(parts) == 4:
        return (ROOT / "nonholo/generated/native" / f"{parts[3]}.c").exists()   # a C extension
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        for i in range(len(parts), 0, -1):
            try:
                obj = importlib.import_module(".".join(parts[:i]))
            except ImportError:
                continue
            except DeprecationWarning:
                return False
            break
        else:
            return False
        for attr in parts[i:]:
            try:
                obj = getattr(obj, attr)
            except (AttributeError, DeprecationWarning):
                return isinstance(obj, type) and instance_attribute(obj, attr)
    return True


def instance_attribute(cls: type, attr: str) -> bool:
    """Whether instances of ``cls`` have ``attr`` (set in a method as ``self.attr``)."""
    return any(re.search(rf"\bself\.{attr}\s*(?::[^=]+)?=", inspect.getsource(k))
               for k in cls.__mro__ if k.__module__.startswith("nonholo"))


def test_the_scanner_sees_stale_names():
    assert resolves("nonholo.planning.strategy_paper") and resolves("nonholo.viz.plan_figure")
    assert resolves("nonholo.spaces.euclidean.Euclidean.box") and not resolves("nonholo.spaces.euclidean.Euclidean.boxes")
    assert not resolves("nonholo.robust") and not resolves("nonholo.verify")
    assert DOTTED.findall("see :mod:`nonholo.robust`.") == ["nonholo.robust"]
    assert not DOTTED.findall('"format": "nonholo.plan/3"') and not DOTTED.findall('b"nonholo.x"')
    assert PATH.findall("(`notebooks/adding_a_mechanism.ipynb`)") == ["notebooks/adding_a_mechanism.ipynb"]
    assert TOP_FILE.findall("the examples of `MODEL.md`") == ["MODEL.md"]


@pytest.mark.parametrize("path", SOURCES, ids=[str(p.relative_to(ROOT)) for p in SOURCES])
def test_references_resolve(path):
    text = path.read_text()
    stale = sorted({n for n in DOTTED.findall(text) if not resolves(n)})
    missing = sorted({p for p in PATH.findall(text) if p not in HYPOTHETICAL and not (ROOT / p).exists()}
                     | {f for f in TOP_FILE.findall(text) if not (ROOT / f).exists()})
    assert not stale, f"names that do not import: {stale}"
    assert not missing, f"files not in the repository: {missing}"


def helps() -> dict[str, str]:
    """Every sub-command's ``--help`` text (and the top level's)."""
    parser = entry.build_parser()
    subs = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return {"nonholo": parser.format_help(), **{name: p.format_help() for name, p in subs.choices.items()}}


def test_help_is_plain_text():
    texts = helps()
    assert {"plan", "sweep", "atlas", "reproduce"} <= set(texts)
    for name, text in texts.items():
        assert not REST.search(text), f"nonholo {name} --help shows reST markup: {REST.search(text)[0]!r}"
        stale = [n for n in DOTTED.findall(text) if not resolves(n)]
        assert not stale, f"nonholo {name} --help names what does not import: {stale}"
    assert "nonholo.planning.strategy_paper" in texts["plan"]     # a reference kept, as text


def test_plain_text_of_rest():
    doc = ("See :mod:`nonholo.io.safe_write` and :func:`~nonholo.io.result.PlanResult.load`, "
           ":attr:`the box <nonholo.spaces.euclidean.Euclidean.box>`; ``--out x``.\n\nExample::\n\n    x\n")
    assert plain(doc) == ("See nonholo.io.safe_write and load, the box; --out x.\n\nExample:\n\n    x\n")
