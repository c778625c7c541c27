"""``nonholo sweep`` and ``nonholo atlas``: many plans at once, and maps of them.

Examples::

    nonholo sweep problems.jsonl --out results.parquet --workers 2
    nonholo sweep problems.jsonl --out results.parquet --scheduler tcp://127.0.0.1:8786
    nonholo atlas --problems atlas.jsonl --grid 31
    nonholo sweep atlas.jsonl --out atlas.parquet
    nonholo atlas atlas.parquet --out paper_figures
    nonholo atlas --problems car.jsonl --mechanism car --grid 9 --axes x y --start 0 0 0 0 --extent -1.5 1.5 -1.5 1.5

``sweep`` plans every problem of a JSON Lines file (:mod:`nonholo.io.problems`) and writes one
row per problem to a Parquet file as results arrive (:mod:`nonholo.batch.sweep`); run again with
the same arguments it finishes what an interrupted (even killed) run left, and a second sweep
on the same output while one runs is refused (exit 2). Every row's options are checked as
``plan`` checks them before anything runs; a strategy named by import path
(``"module:Class"``) needs ``--allow-imports``. A row's ``"mechanism"`` may be a mechanism file
(``"trailer.toml"``, relative to the table's directory), and ``atlas --mechanism`` one too
(relative to the working directory). ``atlas --problems`` writes
an atlas's problems (:func:`nonholo.batch.atlas.problems`): goals on a grid over two of the
numbers of a state (``--axes``: the RPY angles phi theta psi with an orientation, then the
coordinates; default phi theta, or the first two coordinates), the others the start's
(``--start``: all of a state's numbers, as ``nonholo plan --from`` takes them), one RPY slice
per ``--psi`` with an orientation; ``atlas RESULTS`` draws the maps of their sweep
(``atlas_success``, ``atlas_iterations``, ``atlas_time``, PNG and PDF).

Exit status: 0 done, 2 bad input (a bad problem file names the row and column; a damaged
results file; another sweep writing the same output).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..io import problems as problem_table
from .help_text import plain


def add_parsers(subparsers) -> None:
    """Add ``nonholo sweep`` and ``nonholo atlas``.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The subcommands of the ``nonholo`` parser.
    """
    from .commands import COMMANDS

    sweep_arguments(subparsers.add_parser("sweep", help=COMMANDS["sweep"].help))
    atlas_arguments(subparsers.add_parser("atlas", help=COMMANDS["atlas"].help))


def sweep_arguments(p: argparse.ArgumentParser) -> None:
    """Give the ``sweep`` sub-command's parser ``p`` its description, its arguments and the
    function that runs it (:func:`run_sweep`).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The sub-command's parser.
    """
    p.description = plain(__doc__)
    p.formatter_class = argparse.RawDescriptionHelpFormatter
    p.add_argument("problems", help="JSON Lines file: one problem per line (start, goal, mechanism, options)")
    p.add_argument("--out", required=True, help="results file (Parquet); resumed if a run was interrupted")
    p.add_argument("--workers", type=int, default=None, help="local worker processes (default: one per core)")
    p.add_argument("--scheduler", default=None,
                   help="run on a Dask distributed cluster: its scheduler's address, e.g. tcp://HOST:8786")
    p.add_argument("--batch", type=int, default=None,
                   help="problems per unit of work, each written as it finishes (default: automatic)")
    p.add_argument("--allow-imports", action="store_true",
                   help="let a row name its strategy by import path (options.strategy = \"module:Class\"), "
                        "which imports that module and runs its code: only for tables you trust")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run_sweep)


def atlas_arguments(p: argparse.ArgumentParser) -> None:
    """Give the ``atlas`` sub-command's parser ``p`` its description, its arguments and the
    function that runs it (:func:`run_atlas`).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The sub-command's parser.
    """
    p.description = plain(__doc__)
    p.formatter_class = argparse.RawDescriptionHelpFormatter
    p.add_argument("results", nargs="?", help="results of a sweep of atlas problems (Parquet)")
    p.add_argument("--out", default="paper_figures", help="directory of the figures (default paper_figures)")
    p.add_argument("--problems", default=None, metavar="FILE",
                   help="instead of drawing: write an atlas's problems to FILE (JSON Lines)")
    p.add_argument("--mechanism", default="platform",
                   help="the mechanism: a name (default platform) or a mechanism file (.toml), whose "
                        "definition the rows then hold")
    p.add_argument("--grid", type=int, default=31, help="goals per side of each slice (default 31)")
    p.add_argument("--axes", nargs=2, default=None, metavar=("A", "B"),
                   help="the goal's two numbers on the grid: phi theta psi (with an orientation) or "
                        "coordinates, e.g. x y (default: phi theta, or the first two coordinates)")
    p.add_argument("--extent", type=float, nargs=4, default=None, metavar=("LO", "HI", "LO", "HI"),
                   help="the axes' ranges (default: φ, ψ [−π, π), ϑ (−π/2, π/2), an angle coordinate "
                        "[−π, π), another [−box, box] of the space)")
    p.add_argument("--psi", type=float, nargs="+", default=None,
                   help="the slices ψ (rad; default: the start's; with an orientation, ψ off the axes)")
    p.add_argument("--start", type=float, nargs="+", default=None, metavar="X",
                   help="the start: a state's numbers, RPY angles (rad) then the coordinates "
                        "(default: Example 1's RPY angles, the coordinates 0)")
    p.set_defaults(func=run_atlas)


#: The flags of :func:`nonholo.batch.atlas.problems`'s arguments named otherwise.
FLAGS = {"n": "grid"}


def _error(message: str) -> int:
    print(f"nonholo: error: {message}", file=sys.stderr)
    return 2


def run_sweep(args) -> int:
    """Run ``nonholo sweep`` (:func:`nonholo.batch.sweep.sweep`).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments.

    Returns
    -------
    int
        The exit status: 0 done, 2 bad input (the error on standard error).
    """
    from ..batch.result_store import SweepBusy
    from ..batch.sweep import sweep

    try:
        table = sweep(args.problems, args.out, workers=args.workers, scheduler=args.scheduler,
                      progress=not args.quiet, batch=args.batch, allow_imports=args.allow_imports)
    except (ValueError, TypeError, OSError, SweepBusy) as exc:
        return _error(str(exc))
    rows = table.select(["success", "error"]).to_pylist()
    solved = sum(r["success"] for r in rows)
    raised = sum(r["error"] is not None for r in rows)
    print(f"{len(rows)} problems: {solved} solved, {len(rows) - solved - raised} not, {raised} raised; "
          f"wrote {args.out}")
    return 0


def run_atlas(args) -> int:
    """Run ``nonholo atlas``: write an atlas's problems, or draw the maps of their sweep.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments.

    Returns
    -------
    int
        The exit status: 0 done, 2 bad input (the error on standard error).
    """
    from ..batch import atlas
    from .. import viz

    if args.problems:
        try:
            rows = atlas.problems(n=args.grid, psi=args.psi, start=args.start, mechanism=args.mechanism,
                                  axes=args.axes, extent=args.extent)
        except atlas.BadArgument as exc:
            return _error(f"--{FLAGS.get(exc.argument, exc.argument)} {exc.detail}")
        try:
            problem_table.write(args.problems, rows)
        except (ValueError, OSError) as exc:
            return _error(str(exc))
        print(f"wrote {len(rows)} problems to {args.problems}")
        return 0
    if not args.results:
        return _error("give the results of a sweep to draw, or --problems FILE to write an atlas's problems")
    from ..batch.result_store import load

    try:
        table = load(args.results)
        for q in atlas.QUANTITIES:
            for path in viz.save_figure(atlas.atlas_figure(table, q), f"atlas_{q}", Path(args.out)):
                print(f"wrote {path}")
    except (ValueError, OSError) as exc:
        return _error(str(exc))
    return 0
