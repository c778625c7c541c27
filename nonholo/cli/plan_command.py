"""``nonholo plan``: plan a motion from the command line.

Example::

    nonholo plan --from 0.5 1.2 -0.5 --to 1.0 0.9 -0.5 --T 1 --harmonics 2 --out plan.json --plot plan.png

Orientations are given as RPY angles ``φ ϑ ψ`` in radians, ``RPY(φ, ϑ, ψ) =
R(Z, φ) R(Y, ϑ) R(X, ψ)``. A mechanism whose state goes beyond SO(3) takes its coordinates
(``nonholo plan --mechanism car --from 0 0 0 0 --to 0 1 0 0``: ``x y θ φ``), after the RPY
angles if it has an orientation too (``rolling_ball``: ``φ ϑ ψ p1 p2``); ``nonholo
mechanisms`` lists each one's state; ``--mechanism FILE.toml`` plans a mechanism of one's own
from its file (:mod:`nonholo.model.mechanism_file`; a bad file exits with status 2 naming
the file, the line and the field). The strategy is ``robust``
(:mod:`nonholo.planning.strategy_robust`) unless ``--strategy paper`` asks for the
appendix's algorithm as published (:mod:`nonholo.planning.strategy_paper`). One line is
printed per accepted iteration (iteration, error ``|l_T|``, the step ``γh``, least ``|Δ|``
along the trajectory), then a summary with the errors in the state's units;
then the result is written to ``--out`` and the figure to ``--plot`` (each even if the
other cannot be written). Every file is written by :mod:`nonholo.io.safe_write`: a regular
file is replaced only once the new one is complete; a character device or FIFO
(``--out /dev/stdout``, a named pipe) is written in place, never replaced; a path that is
anything else (a directory) is not written, with an error naming the option.
Output closed early by its reader (``nonholo plan ... | head -1``) is not an error: the
rest is discarded and the files are still written.

``--csv`` writes a successful plan's motion for an actuator controller
(:mod:`nonholo.io.csv_export`), sampled at ``--csv-rate`` Hz.

``--T min`` asks for the least time along the planned path: under ``--leg-speed`` for a
platform, under the vehicle's own bounds for a mechanism that has them (``car``: ``|v| ≤ 1``,
``|φ̇| ≤ 1``, ``|φ| ≤ 0.6``; ``unicycle``: ``|v|, |ω| ≤ 0.5``; ``nonholo plan --mechanism car
--from 0 0 0 0 --to 0 1 0 0 --T min``); the summary prints the time found. Errors name the
flags (``--T``, ``--leg-speed``, ``--from`` …), not the Python arguments behind them
(:mod:`nonholo.cli.flag_text`).

Exit status: 0 on success, 1 if the planner failed, 2 on bad input, 3 if ``--out``,
``--plot`` or ``--csv`` could not be written (whatever the planner's outcome; one line on stderr names
the file and the error).
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path


from ..io import csv_export as export
from ..io import safe_write
from ..model import catalog
from ..planning.api import METHODS, ROUTES, STRATEGIES, plan
from ..planning.settings import arguments_of
from .flag_text import in_flags
from .help_text import plain

#: exit status of ``nonholo plan`` (see the module docstring)
EXIT_SUCCESS, EXIT_FAILED, EXIT_BAD_INPUT, EXIT_WRITE_FAILED = 0, 1, 2, 3


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Add the ``plan`` sub-command to an ``argparse`` sub-parsers object.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        What ``ArgumentParser.add_subparsers`` returned.

    Returns
    -------
    argparse.ArgumentParser
        The sub-command's parser (it runs :func:`run`).
    """
    from .commands import COMMANDS

    p = subparsers.add_parser("plan", help=COMMANDS["plan"].help)
    arguments(p)
    return p


def arguments(p: argparse.ArgumentParser) -> None:
    """Give the ``plan`` sub-command's parser ``p`` its description, its arguments and the
    function that runs it (:func:`run`).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The sub-command's parser.
    """
    p.description = plain(__doc__)
    p.formatter_class = argparse.RawDescriptionHelpFormatter
    p.add_argument("--from", dest="start", nargs="+", type=float, required=True, metavar="X",
                   help="the start: RPY angles φ ϑ ψ (rad) of the orientation, then the coordinates "
                        "of a mechanism whose state has them (see the description)")
    p.add_argument("--to", dest="goal", nargs="+", type=float, required=True, metavar="X",
                   help="the goal, as --from")
    p.add_argument("--T", type=_horizon, default=1.0,
                   help="time horizon in s (default 1), or 'min' for the least time under --leg-speed or, "
                        "for a vehicle with bounds (car, unicycle), under its bounds")
    p.add_argument("--method", choices=METHODS, default="parametric",
                   help="Fourier controls (parametric) or piecewise constant (nonparametric)")
    p.add_argument("--harmonics", type=int, default=2, help="Fourier harmonics K (default 2)")
    p.add_argument("--grid", type=int, default=100, help="intervals of the nonparametric grid (default 100)")
    p.add_argument("--strategy", default="robust",
                   help=f"planning strategy: {', '.join(STRATEGIES)} (default: robust), or an import "
                        "path module:Class with --allow-imports")
    p.add_argument("--allow-imports", action="store_true",
                   help="let --strategy be an import path (module:Class), which imports that module and runs "
                        "its code")
    p.add_argument("--mechanism", default="platform",
                   help=f"mechanism: a name ({', '.join(catalog.names())}; see `nonholo mechanisms`) or a "
                        "mechanism file (.toml)")
    p.add_argument("--gamma", type=float, default=None,
                   help="decay rate γ of the θ-flow (default: the strategy's, 1 robust, 0.5 paper)")
    p.add_argument("--tol", type=float, default=1e-10, help="stop when |l_T| <= tol (rad)")
    p.add_argument("--max-iter", type=int, default=200, help="maximum number of iterations")
    p.add_argument("--delta-min", type=float, default=1e-2, help="keep |Δ| >= this along the motion")
    p.add_argument("--steps", type=int, default=None, help="integrator steps on [0, T]")
    p.add_argument("--route", choices=ROUTES, default="auto",
                   help="auto: one plan from start to goal and, if that fails, hops along a path "
                        "of orientations clear of Δ = 0 (default); local: the one plan only; "
                        "global: only the hops")
    p.add_argument("--leg-length", nargs=2, type=float, default=None, metavar=("LO", "HI"),
                   help="keep every leg's length within [LO, HI] (a platform's geometry units)")
    p.add_argument("--leg-speed", type=float, default=None, metavar="V",
                   help="keep every leg's speed |dl/dt| <= V (geometry units per second): the plan "
                        "is re-timed, in the least time with --T min")
    p.add_argument("--objective", choices=("none", "energy", "auto", "time"), default="auto",
                   help="auto (default): the plan, unless the extremal through it (or, for a wasteful plan, a "
                        "quick search) finds a smooth motion of far less energy; energy: then the least energy "
                        "∫|u|² dt, with the goal and limits kept; time: the path of least time under the input "
                        "bounds (the mechanism's own unless given), played at full use of them; none: the plan "
                        "as found")
    p.add_argument("--out", default=None, help="write the result as JSON to this file")
    p.add_argument("--plot", default=None, help="write a figure of the plan to this file (inputs, orientation, "
                        "coordinates, Δ against t; a vehicle's path on the plane)")
    p.add_argument("--csv", default=None,
                   help="write the motion as CSV for an actuator controller (t, leg lengths and "
                        "speeds, u, quaternion qx qy qz qw, delta; only for a successful plan)")
    p.add_argument("--csv-rate", type=float, default=export.DEFAULT_RATE,
                   help=f"samples per second of --csv (default {export.DEFAULT_RATE:g})")
    p.add_argument("--quiet", action="store_true", help="print the summary only")
    p.set_defaults(func=run)


def _horizon(text: str) -> float | None:
    """``--T``: a number of seconds, or ``min`` (``None``: the least time)."""
    if text.strip().lower() == "min":
        return None
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seconds or 'min', got {text!r}") from None


def _fmt(x, spec: str) -> str:
    return "n/a" if x is None else format(x, spec)


def _error_text(res, spec: str) -> str:
    """The terminal error in words with its units: ``|l_T|`` in rad, or by part beyond SO(3)."""
    space = res.kinematics.space
    if res.errors is None:
        return f"|l_T| = {space.amount(res.terminal_error, spec)}"
    return ", ".join(f"{part} {space.amount(value, spec, part)}" for part, value in res.errors.items())


def _say(text: str) -> None:
    """Print a line of output at once; if the reader has closed stdout (``| head -1``),
    send this and all later output to the null device instead of failing."""
    try:
        print(text, flush=True)
    except BrokenPipeError:
        discard_stdout()


def discard_stdout() -> None:
    """Send all later output to stdout, and what is still buffered, to the null device."""
    # the descriptor itself is redirected: what is still buffered, and the flush at exit,
    # then go to the null device too (no "Exception ignored ... BrokenPipeError")
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):   # no real descriptor behind sys.stdout
        sys.stdout = open(os.devnull, "w")


def _error(text: str) -> None:
    """One line on stderr."""
    print(f"nonholo plan: error: {' '.join(text.split())}", file=sys.stderr, flush=True)


def _cannot_write(path, exc: Exception) -> None:
    why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
    _error(f"cannot write {path}: {why}")


def _print_record(rec: dict) -> None:
    _say(f"iter {rec['iteration']:4d}  |l_T| = {_fmt(rec['error'], '.3e')}  "
         f"step = {rec['step']:<8.4g} min|Δ| = {_fmt(rec['min_delta'], '.4f')}  {rec['phase']}")


def plot_format_error(path) -> str | None:
    """Why matplotlib cannot write a figure to ``path`` (its extension), or ``None``.

    Parameters
    ----------
    path : str or pathlib.Path
        The figure's file.

    Returns
    -------
    str or None
        The reason, naming ``--plot``; ``None`` for a format matplotlib writes.
    """
    suffix = Path(path).suffix[1:].lower()
    if not suffix:
        return None                                  # matplotlib's default format
    from matplotlib.backend_bases import FigureCanvasBase

    known = FigureCanvasBase.get_supported_filetypes()
    if suffix not in known:
        return f"--plot {path}: unknown figure format {suffix!r}; known: {', '.join(sorted(known))}"
    return None


def state_of(mechanism, values, flag: str):
    """The state given on the command line, as :func:`nonholo.plan` takes it (see the module).

    Parameters
    ----------
    mechanism : str or Mechanism
        The mechanism, or its name in the catalog.
    values : sequence of float
        The numbers given to ``flag``.
    flag : str
        The option (``--from``, ``--to``), for the message.

    Returns
    -------
    object
        The state: a rotation matrix, or the mechanism's state beyond SO(3).

    Raises
    ------
    ValueError
        Naming ``flag`` and the numbers it takes, if there are not as many values.
    """
    space = catalog.get(mechanism).space
    names = space.cli_names
    if len(values) != len(names):
        raise ValueError(f"{flag} takes {len(names)} numbers for mechanism {catalog.get(mechanism).name!r} "
                         f"({' '.join(names)}), got {len(values)}")
    return space.public(space.from_cli(values))


def run(args) -> int:
    """Run the ``plan`` sub-command.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        The exit status (see the module).
    """
    why = plot_format_error(args.plot) if args.plot else None
    if why is None and args.csv:
        try:
            export.check_rate(args.csv_rate)
        except ValueError as exc:
            why = f"--csv-rate: {exc}"
    if why:
        _error(why)
        return EXIT_BAD_INPUT
    try:
        mechanism = catalog.resolve(args.mechanism)
        R0 = state_of(mechanism, args.start, "--from")
        Rd = state_of(mechanism, args.goal, "--to")
        flat = dict(method=args.method, harmonics=args.harmonics, grid=args.grid, gamma=args.gamma,
                    tol=args.tol, max_iter=args.max_iter, delta_min=args.delta_min, steps=args.steps,
                    leg_length=args.leg_length, leg_speed=args.leg_speed)
        res = plan(
            R0, Rd, T=args.T, strategy=args.strategy, mechanism=mechanism, route=args.route,
            objective=None if args.objective == "none" else args.objective,
            callback=None if args.quiet else _print_record, allow_imports=args.allow_imports,
            **arguments_of(flat, mechanism))
    except ValueError as exc:
        _error(in_flags(str(exc)))
        return EXIT_BAD_INPUT
    _say(f"{'success' if res.success else 'FAILED'}: {in_flags(res.reason)}")
    _say(f"terminal error {_error_text(res, '.3e')}, min |Δ| = "
         f"{_fmt(res.min_delta, '.4f')}, {res.iterations} iterations, {res.seconds * 1e3:.1f} ms "
         f"({res.mechanism}, {res.method}/{res.strategy}, {res.route} route, T = {res.T:g} s, "
         f"{res.steps} steps)")
    status = EXIT_SUCCESS if res.success else EXIT_FAILED
    if args.out:
        try:
            safe_write.check_target(args.out, "--out")
            res.save(args.out)
        except (OSError, ValueError) as exc:     # ValueError: not a file, or a plan that would not load
            _cannot_write(args.out, exc)
            status = EXIT_WRITE_FAILED
        else:
            _say(f"wrote {args.out}")
    if args.plot:
        try:
            plot(res, args.plot)
        except (OSError, ValueError) as exc:
            _cannot_write(args.plot, exc)
            status = EXIT_WRITE_FAILED
        else:
            _say(f"wrote {args.plot}")
    if args.csv:
        if not res.success:
            _say(f"{args.csv} not written: a failed plan is not a motion to play back")
        else:
            try:
                safe_write.check_target(args.csv, "--csv")
                res.to_csv(args.csv, rate=args.csv_rate)
            except (OSError, ValueError) as exc:
                _cannot_write(args.csv, exc)
                status = EXIT_WRITE_FAILED
            else:
                _say(f"wrote {args.csv}")
    return status


def plot(res, path, argument: str = "--plot") -> None:
    """Write the figure of a :class:`~nonholo.io.result.PlanResult` to a file.

    The figure is :func:`nonholo.viz.plan_summary.plan_figure`'s (inputs, orientation,
    coordinates, ``Δ``, legs against time; a vehicle's path on the plane), written by
    :func:`nonholo.io.safe_write.write_bytes` in the format of the path's extension
    (matplotlib's default format without one; the name is kept as given).

    Parameters
    ----------
    res : PlanResult
        The plan.
    path : str or pathlib.Path
        The file.
    argument : str, default "--plot"
        The option named in messages.

    Raises
    ------
    ValueError
        Naming ``argument``, before the figure is drawn, if ``path`` is not a regular file,
        a character device or a FIFO.
    OSError
        If the file cannot be written.
    """
    safe_write.check_target(path, argument)
    from ..viz.plan_summary import plan_figure

    write_figure(plan_figure(res), path, argument)


def write_figure(fig, path, argument: str = "--plot") -> None:
    """A figure written to ``path`` in the format of its extension (matplotlib's default
    without one), with no date in its metadata, by :func:`nonholo.io.safe_write.write_bytes`.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or pathlib.Path
        The file (a regular file, a character device or a FIFO).
    argument : str
        The option naming ``path``, for messages.

    Raises
    ------
    ValueError
        If ``path`` is not a file that may be written.
    """
    import io

    import matplotlib

    buffer = io.BytesIO()
    fmt = Path(path).suffix[1:].lower() or matplotlib.rcParams["savefig.format"]
    fig.savefig(buffer, dpi=100, format=fmt, metadata=_metadata(fmt))
    safe_write.write_bytes(path, buffer.getvalue(), argument)


def _metadata(fmt: str) -> dict | None:
    """No date in the formats whose metadata would record one (the same plan, the same bytes)."""
    return {"pdf": {"CreationDate": None}, "svg": {"Date": None}}.get(fmt)
