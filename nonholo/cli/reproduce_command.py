"""``nonholo reproduce``: the project's main job (see :mod:`nonholo.paper.reproduce`)."""
from __future__ import annotations

import argparse
import os


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Add ``nonholo reproduce``.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The subcommands of the ``nonholo`` parser.

    Returns
    -------
    argparse.ArgumentParser
        The subcommand's parser.
    """
    from .commands import COMMANDS

    p = subparsers.add_parser("reproduce", help=COMMANDS["reproduce"].help)
    arguments(p)
    return p


def arguments(p: argparse.ArgumentParser) -> None:
    """Give the ``reproduce`` sub-command's parser ``p`` its arguments and the function that
    runs it (:func:`run`).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The sub-command's parser.
    """
    p.add_argument("--out", default="paper_figures", help="output directory (default: paper_figures)")
    p.add_argument("--no-audit", action="store_true", help="skip printing the audit")
    p.add_argument("--no-figures", action="store_true", help="skip the figures")
    p.add_argument("--check", action="store_true",
                   help="write nothing: list the outputs that differ from the files there beyond the "
                        "tolerances (numbers 1e-9 of their magnitude), and by how much; exit 1 if any")
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``nonholo reproduce`` (:func:`nonholo.paper.reproduce.run`).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments.

    Returns
    -------
    int
        The exit status.
    """
    os.environ.setdefault("MPLBACKEND", "Agg")
    from ..paper.reproduce import run as _run
    return _run(args.out, audit=not args.no_audit, draw=not args.no_figures, check=args.check)
