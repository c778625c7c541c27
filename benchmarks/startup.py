"""How long ``import nonholo`` and ``nonholo --help`` take, against NumPy and SciPy's linear
algebra, which every use of the package loads (run by hand).

    python -m benchmarks.startup [--runs 21]

Writes ``benchmarks/results/startup.md`` (headed by the date, the git commit, the machine and
the command, see :mod:`benchmarks.report`): each command in a fresh interpreter, the three
interleaved run after run so that a busy machine slows them alike; the median wall time of
each and its ratio to the reference's median; which of the heavy packages
(numba, SymPy, Matplotlib, MuJoCo, SciPy's modules beyond ``linalg``) ``import nonholo``
and ``nonholo --help`` load, and which modules of the commands ``nonholo --help`` loads
(none: :mod:`nonholo.cli.entry` imports a command's module only to run that command).

The interpreters run with Python's bytecode cache on (``PYTHONDONTWRITEBYTECODE`` removed
from their environment), as after any install: NumPy and SciPy come with theirs, and the
warm-up run writes nonholo's, so that both sides load compiled modules.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

from .report import Report

#: The commands timed, each in a fresh interpreter.
COMMANDS = {
    "`python -c \"import numpy, scipy.linalg\"` (the reference)": [sys.executable, "-c", "import numpy, scipy.linalg"],
    "`python -c \"import nonholo\"`": [sys.executable, "-c", "import nonholo"],
    "`nonholo --help`": [sys.executable, "-m", "nonholo.cli", "--help"],
}

#: Packages that load only when used.
HEAVY = ("numba", "sympy", "matplotlib", "mujoco", "pyarrow", "scipy.spatial", "scipy.sparse", "scipy.integrate",
         "scipy.interpolate", "scipy.optimize", "scipy.special")

LOADED = ("import json, sys; import nonholo; "
          f"print(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))")

#: The same for ``nonholo --help``, with the modules of ``nonholo.cli`` it loads besides
#: the parser's own.
HELP_LOADED = ("import contextlib, io, json, sys\n"
               "from nonholo.cli.entry import main\n"
               "with contextlib.redirect_stdout(io.StringIO()):\n"
               "    try:\n"
               "        main(['--help'])\n"
               "    except SystemExit:\n"
               "        pass\n"
               f"print(json.dumps([[m for m in {HEAVY!r} if m in sys.modules],\n"
               "                  sorted(m for m in sys.modules if m.startswith('nonholo.cli.')\n"
               "                         and m not in ('nonholo.cli.entry', 'nonholo.cli.commands'))]))")


def loaded(code: str):
    """What ``code``, run in a fresh interpreter, prints as JSON."""
    return json.loads(subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                                     text=True).stdout)


def listed(names) -> str:
    """``names`` separated by commas, or ``none``."""
    return ", ".join(names) if names else "none"


#: The interpreters' environment: this one's, with the bytecode cache on.
ENV = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


def wall(command: list) -> float:
    """Wall time of one run of ``command`` (its output discarded)."""
    t = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=ENV)
    return time.perf_counter() - t


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=21, help="runs of each command, interleaved")
    args = ap.parse_args(argv)
    report = Report("startup.md", "Start-up (startup)", "benchmarks.startup", argv)
    load = os.getloadavg()[0]
    for command in COMMANDS.values():                       # warm the file and bytecode caches
        wall(command)
    times = {name: [] for name in COMMANDS}
    for _ in range(args.runs):
        for name, command in COMMANDS.items():
            times[name].append(wall(command))
    reference = statistics.median(next(iter(times.values())))
    report.paragraph(
        f"Each command in a fresh interpreter with the bytecode cache on, {args.runs} runs each, "
        "interleaved; wall time, median (min–max), and the median over the reference's median.")
    report.table(["command", "wall [s]", "over the reference"],
                 [[name, f"{statistics.median(ts):.3f} ({min(ts):.3f}–{max(ts):.3f})",
                   f"{statistics.median(ts) / reference:.2f}"] for name, ts in times.items()],
                 ["l", "r", "r"])
    heavy_help, commands_help = loaded(HELP_LOADED)
    report.paragraph(
        f"Of {', '.join(HEAVY)}, `import nonholo` loads: {listed(loaded(LOADED))}; `nonholo --help`: "
        f"{listed(heavy_help)}, and of the commands' modules: {listed(commands_help)}. "
        "numba is imported at the first call of a compiled function, when the native kernels are not "
        "used; SymPy by a derivation or a mechanism of one's own; Matplotlib by a figure; MuJoCo by a "
        "physics run; SciPy's other modules by the functions that use them.")
    report.paragraph(f"Load average (1 min) when the measurements started and ended: {load:.1f} and "
                     f"{os.getloadavg()[0]:.1f}, on {os.cpu_count()} cores.")
    report.write()


if __name__ == "__main__":
    main()
