"""The results files of the benchmark scripts (``benchmarks/results/*.md``).

Every results file starts with the same header, written here and nowhere else: the date
(UTC, ISO 8601), the code measured (git commit, short hash, with ``+ uncommitted changes``
when the code differs from it — the output folders do not count), the
machine (CPU model, cores, platform; Python, NumPy, SciPy and numba versions, and any
other package a script names) and the exact command.

:class:`Report` collects a script's output as markdown — paragraphs and tables — echoes
it to standard output as it comes, and writes the file at the end.
"""
from __future__ import annotations

import datetime as _dt
import os
import platform
import shlex
import sys
from pathlib import Path

from nonholo.io import provenance

RESULTS_DIR = Path(__file__).resolve().parent / "results"


def utc_now() -> str:
    """The current time, UTC, ISO 8601 to the second (``2026-11-22T05:17:57+00:00``)."""
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")


def git_revision() -> str | None:
    """``"<short hash>"`` of HEAD, plus ``" + uncommitted changes"`` if the code differs from
    it (:func:`nonholo.io.provenance.git_revision`); ``None`` outside a git checkout."""
    return provenance.git_revision(short=True)


def cpu_model() -> str | None:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or None


def _version(package: str) -> str | None:
    try:
        module = __import__(package)
    except ImportError:
        return None
    if hasattr(module, "__version__"):
        return module.__version__
    try:
        from importlib.metadata import version
        return version(package)
    except Exception:  # not installed as a distribution of that name
        return "?"


def machine_info(extra_packages: tuple[str, ...] = ()) -> dict:
    """Processor, cores, platform and the versions of Python, NumPy, SciPy, numba and
    ``extra_packages`` (``None`` where not installed), and the git revision (``"git"``)."""
    info = {"processor": cpu_model(), "cores": os.cpu_count(), "platform": platform.platform(),
            "python": platform.python_version()}
    for pkg in ("numpy", "scipy", "numba", *extra_packages):
        info[pkg] = _version(pkg)
    info["git"] = git_revision()
    return info


_LABELS = {"numpy": "NumPy", "scipy": "SciPy", "casadi": "CasADi"}


def machine_line(info: dict) -> str:
    """The machine of :func:`machine_info` in one line."""
    versions = ", ".join(f"{_LABELS.get(k, k)} {info[k]}" for k in info
                         if k not in ("processor", "cores", "platform", "python", "git"))
    return (f"{info.get('processor') or 'unknown CPU'}, {info['cores']} cores, {info['platform']}; "
            f"Python {info['python']}, {versions}")


def command(module: str, argv=None) -> str:
    """The command line that ran ``python -m module`` with ``argv`` (default: ``sys.argv[1:]``)."""
    args = list(sys.argv[1:] if argv is None else argv)
    return " ".join(["python -m", module, *(shlex.quote(str(a)) for a in args)])


def header_lines(title: str, command_line: str, date: str, machine: dict) -> list[str]:
    """The markdown header of a results file (see the module docstring)."""
    return [f"# {title}", "",
            f"- Date: {date}",
            f"- Code: git {machine.get('git') or 'revision unknown'}",
            f"- Machine: {machine_line(machine)}",
            f"- Command: `{command_line}`",
            ""]


def _cell(x) -> str:
    return str(x).replace("|", "\\|").replace("\n", " ")


def table_lines(headers, rows, align=None) -> list[str]:
    """A markdown table; ``align``: one of ``"l"``, ``"r"`` per column (default: right
    but the first)."""
    align = align or ["l"] + ["r"] * (len(headers) - 1)
    rule = ["---:" if a == "r" else "---" for a in align]
    out = ["| " + " | ".join(_cell(h) for h in headers) + " |", "|" + "|".join(rule) + "|"]
    out += ["| " + " | ".join(_cell(c) for c in row) + " |" for row in rows]
    return out


class Report:
    """A results file in the making: the header (date taken now), then paragraphs and
    tables, each echoed to standard output as it is added; :meth:`write` saves it."""

    def __init__(self, name: str, title: str, module: str, argv=None, extra_packages=(),
                 echo: bool = True, results_dir: Path = RESULTS_DIR):
        self.path = Path(results_dir) / name
        self.command = command(module, argv)
        self.date = utc_now()
        self.machine = machine_info(tuple(extra_packages))
        self.echo = echo
        self.lines = header_lines(title, self.command, self.date, self.machine)
        self._emit(self.lines)

    def _emit(self, lines) -> None:
        if self.echo:
            print("\n".join(lines), flush=True)

    def add(self, *lines: str) -> None:
        """Markdown lines (one paragraph, or several lines of one)."""
        self.lines += list(lines)
        self._emit(lines)

    def paragraph(self, *lines: str) -> None:
        """Lines followed by a blank line."""
        self.add(*lines, "")

    def heading(self, text: str, level: int = 2) -> None:
        self.paragraph("#" * level + " " + text)

    def table(self, headers, rows, align=None) -> None:
        self.paragraph(*table_lines(headers, rows, align))

    def write(self) -> Path:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.path.write_text("\n".join(self.lines).rstrip("\n") + "\n")
        if self.echo:
            print(f"(wrote {self.path})", flush=True)
        return self.path
