"""The package's structure by numbers, from its source (run by hand).

    python -m benchmarks.structure

Writes ``benchmarks/results/structure.md`` (headed by the date, the git commit, the machine
and the command, see :mod:`benchmarks.report`): what the state-space redesign measures itself
by, counted with ``ast`` and plain text over ``nonholo/`` (generated code aside):

- lines outside ``nonholo/spaces`` that ask a state space what kind it is (``.k``,
  ``has_orientation``, ``rotation is None``, ``NO_COORDINATES``, ``.exists``, ``beyond_so3``,
  ``.orientation``, ``has_singular_set``);
- calls that look a mechanism up by name (``catalog.get(``) and the files holding them;
- modules longer than :data:`MAX_LINES` lines;
- import aliases kept from old names (``resimulate`` imported as ``verify``, ``api`` as
  ``planner``), in the package, the tests, the benchmarks, the notebooks and the docs;
- the parameters of ``nonholo.plan`` and ``Problem.build`` and the lines of ``plan``'s docstring.
"""
from __future__ import annotations

import argparse
import ast
import inspect
import re
from pathlib import Path

from .report import Report

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "nonholo"
#: A module longer than this is counted as doing more than one job.
MAX_LINES = 700
#: Phrases that ask a state space or a singular set what kind it is.
KIND_QUESTIONS = {
    ".k": re.compile(r"\.k\b(?!\w)"),
    "has_orientation": re.compile(r"\bhas_orientation\b"),
    "rotation is None": re.compile(r"\brotation is None\b"),
    "NO_COORDINATES": re.compile(r"\bNO_COORDINATES\b"),
    ".exists": re.compile(r"\.exists\b(?!\()"),
    "beyond_so3": re.compile(r"\bbeyond_so3\b"),
    ".orientation": re.compile(r"\.orientation\b"),
    "has_singular_set": re.compile(r"\bhas_singular_set\b"),
}
#: Import aliases kept from old names: what is imported under which old name.
ALIASES = {"`resimulate` imported as `verify`": re.compile(r"\bresimulate\s+as\s+verify\b"),
           "`api` imported as `planner`": re.compile(r"\bapi\s+as\s+planner\b")}


def modules() -> list[Path]:
    """The package's hand-written modules."""
    return [p for p in sorted(PACKAGE.rglob("*.py")) if "generated" not in p.relative_to(PACKAGE).parts]


def code_lines(path: Path) -> list[tuple[int, str]]:
    """``(number, text)`` of the lines of ``path`` that are code, not docstrings or comments."""
    text = path.read_text(encoding="utf-8")
    docs = set()
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str):
            docs.update(range(node.lineno, node.end_lineno + 1))
    return [(i, line.split("#", 1)[0]) for i, line in enumerate(text.splitlines(), 1) if i not in docs]


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.parse_args(argv)
    report = Report("structure.md", "The package's structure (structure)", "benchmarks.structure", argv)
    kinds = {name: [0, set()] for name in KIND_QUESTIONS}
    aliases = dict.fromkeys(ALIASES, 0)
    lookups, lookup_files, long_modules = 0, set(), []
    for path in modules():
        rel = path.relative_to(ROOT).as_posix()
        lines = code_lines(path)
        n_lines = len(path.read_text(encoding="utf-8").splitlines())
        if n_lines > MAX_LINES:
            long_modules.append((rel, n_lines))
        for _, line in lines:
            if not rel.startswith("nonholo/spaces/"):
                for name, pattern in KIND_QUESTIONS.items():
                    if pattern.search(line):
                        kinds[name][0] += 1
                        kinds[name][1].add(rel)
            if "catalog.get(" in line:
                lookups += 1
                lookup_files.add(rel)
    for path in [*modules(), *sorted((ROOT / "tests").rglob("*.py")), *sorted((ROOT / "benchmarks").rglob("*.py")),
                 *sorted((ROOT / "notebooks").glob("*.ipynb")), *sorted((ROOT / "docs").rglob("*.md")),
                 *sorted((ROOT / "docs" / "gallery").glob("*.ipynb"))]:
        text = path.read_text(encoding="utf-8")
        for name, pattern in ALIASES.items():
            aliases[name] += len(pattern.findall(text)) if path != Path(__file__).resolve() else 0
    report.heading("Asking the space what kind it is")
    report.paragraph("Code lines outside `nonholo/spaces` (docstrings and comments aside) holding each phrase.")
    report.table(["phrase", "lines", "files"],
                 [[f"`{name}`", count, len(files)] for name, (count, files) in kinds.items()]
                 + [["all", sum(c for c, _ in kinds.values()), len(set().union(*(f for _, f in kinds.values())))]],
                 ["l", "r", "r"])
    report.heading("Looking a mechanism up by name, old aliases, long modules")
    report.table(["what", "count"],
                 [["`catalog.get(` calls", lookups], ["files with them", len(lookup_files)]]
                 + [[f"{name} (package, tests, benchmarks, notebooks, docs)", n] for name, n in aliases.items()]
                 + [[f"modules over {MAX_LINES} lines", len(long_modules)]], ["l", "r"])
    report.table(["module", "lines"], [[f"`{m}`", n] for m, n in sorted(long_modules, key=lambda x: -x[1])],
                 ["l", "r"])
    from nonholo.planning.api import plan
    from nonholo.planning.problem import Problem

    doc_lines = len(inspect.getdoc(plan).splitlines())
    report.heading("The public door")
    report.table(["what", "count"],
                 [["parameters of `nonholo.plan`", len(inspect.signature(plan).parameters)],
                  ["lines of `plan`'s docstring", doc_lines],
                  ["parameters of `Problem.build`", len(inspect.signature(Problem.build).parameters)]],
                 ["l", "r"])
    report.write()


if __name__ == "__main__":
    main()
