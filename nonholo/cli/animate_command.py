"""``nonholo animate``: an animation of a saved plan, for any mechanism.

Example::

    nonholo plan --mechanism car --from 0 0 0 0 --to 0 1 0 0 --out parking.json
    nonholo animate parking.json --out parking.gif --frames 80 --fps 20

What is drawn depends on the mechanism (:mod:`nonholo.viz.animation`): the platform in 3-D,
the rolling ball on the plane, a vehicle's bodies and wheels, or any other state's path and
coordinates against time. ``--out`` is a ``.gif`` or an ``.mp4`` (the latter needs ffmpeg:
``python -m pip install imageio-ffmpeg``), written as ``nonholo plan`` writes its files
(:mod:`nonholo.io.safe_write`). ``--mechanism NAME`` (a catalog name, or a mechanism file
where mechanism files are known) is the mechanism of a plan whose file does not carry
it. A progress bar is shown on stderr (``--quiet``: none).

Exit status: 0 written, 1 if the animation could not be made or written, 2 on bad input
(naming the flag: ``--frames``, ``--fps``, ``--dpi``, ``--out``, ``--mechanism``, or the
plan file).
"""
from __future__ import annotations

import argparse
import sys

from ..io import safe_write
from ..io.result import PlanResult
from ..model import catalog
from ..numerics.checks import check_count
from .help_text import plain

#: exit status of ``nonholo animate`` (see the module docstring)
EXIT_WRITTEN, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2
#: the suffixes ``--out`` may have
SUFFIXES = (".gif", ".mp4")


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Add ``nonholo animate``.

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

    p = subparsers.add_parser("animate", help=COMMANDS["animate"].help)
    arguments(p)
    return p


def arguments(p: argparse.ArgumentParser) -> None:
    """Give the ``animate`` sub-command's parser ``p`` its description, its arguments and the
    function that runs it (:func:`run`).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The sub-command's parser.
    """
    p.description = plain(__doc__)
    p.formatter_class = argparse.RawDescriptionHelpFormatter
    p.add_argument("plan", help="a plan file written by `nonholo plan --out`")
    p.add_argument("--out", required=True, metavar="FILE", help="the animation: FILE.gif or FILE.mp4")
    p.add_argument("--frames", default="60", metavar="N", help="the number of frames (default 60)")
    p.add_argument("--fps", default="20", metavar="N", help="frames per second (default 20)")
    p.add_argument("--dpi", default="80", metavar="N", help="the frames' resolution (default 80)")
    p.add_argument("--mechanism", metavar="NAME",
                   help="the plan's mechanism, for a plan whose file does not carry it (a catalog name)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def _count(text: str, flag: str, maximum: int) -> int:
    """``text`` as a count in ``[1, maximum]``; ``ValueError`` naming ``flag``."""
    try:
        value = int(text)
    except (TypeError, ValueError):
        raise ValueError(f"{flag} must be an integer >= 1, got {text!r}") from None
    return check_count(value, flag, 1, maximum)


def _mechanism(value):
    """The mechanism ``--mechanism`` names: a catalog name or a mechanism file
    (:func:`nonholo.model.catalog.resolve`); ``ValueError`` naming the flag."""
    try:
        return catalog.resolve(value)
    except (OSError, ValueError) as exc:
        raise ValueError(f"--mechanism: {exc}") from None


def run(args) -> int:
    """Run ``nonholo animate`` for parsed ``args``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments.

    Returns
    -------
    int
        The exit status.
    """
    from ..viz import animation

    try:                                   # everything checked before the plan is read
        frames = _count(args.frames, "--frames", animation.MAX_FRAMES)
        fps = _count(args.fps, "--fps", animation.MAX_FPS)
        dpi = _count(args.dpi, "--dpi", animation.MAX_DPI)
        fmt = animation.output_format(args.out, "--out")
        safe_write.check_target(args.out, "--out")
        mechanism = _mechanism(args.mechanism) if args.mechanism is not None else None
    except ValueError as exc:
        _error(str(exc))
        return EXIT_BAD_INPUT
    if fmt == "mp4":
        try:
            animation.ffmpeg_executable()
        except RuntimeError as exc:
            _error(f"--out: {exc}")
            return EXIT_BAD_INPUT
    try:
        result = PlanResult.load(args.plan, mechanism=mechanism)
    except OSError as exc:
        _error(f"cannot read the plan {args.plan}: {exc.strerror or exc}")
        return EXIT_BAD_INPUT
    except ValueError as exc:
        given = mechanism is not None and "mechanism given" in str(exc)
        _error(f"--mechanism: {exc}" if given else str(exc))
        return EXIT_BAD_INPUT
    try:
        written = animation.animate(result, args.out, frames=frames, fps=fps, dpi=dpi, progress=not args.quiet)
    except ValueError as exc:
        _error(str(exc))
        return EXIT_BAD_INPUT
    except (OSError, RuntimeError) as exc:
        _error(f"cannot write {args.out}: {exc.strerror if isinstance(exc, OSError) and exc.strerror else exc}")
        return EXIT_FAILED
    print(f"wrote {written}", file=sys.stderr)
    return EXIT_WRITTEN


def _error(message: str) -> None:
    print(f"nonholo animate: error: {' '.join(message.split())}", file=sys.stderr, flush=True)
