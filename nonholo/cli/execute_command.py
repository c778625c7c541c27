"""``nonholo execute``: play a saved plan on the physics model of its mechanism.

Example::

    nonholo plan --from 0.5 1.2 -0.5 --to 1.0 0.9 -0.5 --out plan.json
    nonholo execute plan.json --touch-ups 3 --json report.json --plot execution.png

The plan is played from rest to rest on a MuJoCo model generated from its mechanism's data
(:mod:`nonholo.physics`; needs the ``physics`` extra), left to settle and measured; each
touch-up re-plans from the measured state to the goal and plays again — only if predicted
to end nearer the goal, and none once within the plan's tolerance
(:func:`nonholo.physics.execution.execute`). One line is printed per stage: the error from
the goal by part, the largest slip and the real-time factor, or why a touch-up was not
played (touching up ends there), or that MuJoCo went unstable in the stage (the execution
ends there). ``--touch-ups`` (at most :data:`~nonholo.physics.execution_record.MAX_TOUCH_UPS`) and
``--duration`` (at most :data:`~nonholo.physics.execution.MAX_DURATION` s) are checked
before the plan is read. ``--json`` writes the record (``{"stages": [{"error":
{"rotation": …, "coordinates": …}, "outcome": "played", "max_slip": …, …}, …]}``, the
open-loop stage first), ``--plot`` its figure
(:func:`nonholo.viz.execution_figures.execution_figure`), ``--mjcf`` the model file, which
loads in plain ``mujoco.MjModel.from_xml_path``. Files are written as ``nonholo plan``
writes them (:mod:`nonholo.io.safe_write`).

Exit status: 0 when every touch-up was played or left out by design (within tolerance, or
predicted to end no nearer), 1 if a touch-up could not be planned or MuJoCo went unstable in
a stage, 2 on bad input (or without MuJoCo), 3 if ``--json``, ``--plot`` or ``--mjcf`` could
not be written.
"""
from __future__ import annotations

import argparse
import sys

from ..io import safe_write
from ..io.result import PlanResult
from . import plan_command
from .help_text import plain

#: exit status of ``nonholo execute`` (see the module docstring; 1 also when MuJoCo went unstable)
EXIT_PLAYED, EXIT_TOUCH_UP_FAILED, EXIT_BAD_INPUT, EXIT_WRITE_FAILED = 0, 1, 2, 3


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Add ``nonholo execute``.

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

    p = subparsers.add_parser("execute", help=COMMANDS["execute"].help)
    arguments(p)
    return p


def arguments(p: argparse.ArgumentParser) -> None:
    """Give the ``execute`` sub-command's parser ``p`` its description, its arguments and the
    function that runs it (:func:`run`).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The sub-command's parser.
    """
    p.description = plain(__doc__)
    p.formatter_class = argparse.RawDescriptionHelpFormatter
    p.add_argument("plan", help="a plan file written by `nonholo plan --out`")
    p.add_argument("--touch-ups", type=int, default=0, metavar="N",
                   help="re-plan from the measured state and play again, at most N times (default 0)")
    p.add_argument("--duration", type=float, default=None, metavar="S",
                   help="seconds each stage's motion takes (default: 10 times the plan's T)")
    p.add_argument("--actuators", choices=("prescribed", "servo"), default=None,
                   help="stiff tracking of the planned joints (the default) or servos with finite gains")
    p.add_argument("--mjcf", metavar="FILE", help="write the model's MJCF file")
    p.add_argument("--json", metavar="FILE", help="write the record of the stages (JSON)")
    p.add_argument("--plot", metavar="FILE", help="write the execution's figure (format by extension)")
    p.add_argument("-q", "--quiet", action="store_true", help="no line per stage")
    p.set_defaults(func=run)


def describe(record: dict, name: str, units: dict) -> str:
    """One stage's line: its error by part, slip and real-time factor, or why it was not played.

    Parameters
    ----------
    record : dict
        The stage's record (:class:`~nonholo.physics.execution_record.Execution`).
    name : str
        The stage's name.
    units : dict
        The unit of each error part.

    Returns
    -------
    str
        The line.
    """
    outcome = record.get("outcome", "played")
    if outcome == "unstable":
        return f"{name}: unstable ({record.get('reason')})"
    if outcome == "not planned":
        return f"{name}: not planned ({record.get('reason')})"
    if outcome != "played":
        return f"{name}: not played, {outcome} ({record.get('reason')})"
    error = ", ".join(f"{part} {value:.2e} {units[part]}".rstrip() for part, value in record["error"].items())
    return (f"{name}: error {error}; max slip {record['max_slip']:.2e}/s; "
            f"real-time factor {record['real_time_factor']:.2f}")


def run(args) -> int:
    """Run ``nonholo execute`` for parsed ``args``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments.

    Returns
    -------
    int
        The exit status.
    """
    try:
        import mujoco  # noqa: F401  (the physics extra)
    except ImportError:
        _error("MuJoCo is not installed: python -m pip install 'nonholo[physics]'")
        return EXIT_BAD_INPUT
    from ..physics import Contact, execute, model_for, write_mjcf
    from ..physics.execution import check_duration, check_steps, check_touch_ups
    from ..viz.execution_figures import execution_figure, stage_names

    try:                                   # bounded before anything is read or allocated
        touch_ups = check_touch_ups(args.touch_ups, "--touch-ups")
        duration = check_duration(args.duration, "--duration")
    except ValueError as exc:
        _error(str(exc))
        return EXIT_BAD_INPUT
    why = plan_command.plot_format_error(args.plot) if args.plot else None
    if why:
        _error(why)
        return EXIT_BAD_INPUT
    try:
        for path, option in ((args.json, "--json"), (args.mjcf, "--mjcf"), (args.plot, "--plot")):
            if path:
                safe_write.check_target(path, option)
        try:
            result = PlanResult.load(args.plan)
        except OSError as exc:
            _error(f"cannot read the plan {args.plan}: {exc.strerror or exc}")
            return EXIT_BAD_INPUT
        contact = Contact(actuators=args.actuators)
        check_steps(result, duration, model_for(result.kinematics, contact).contact, "--duration")
        units = {part: result.kinematics.space.part_unit(part) for part in ("rotation", "coordinates")}
        counter = iter(stage_names(touch_ups + 1))

        def progress(record):
            if not args.quiet:
                print(describe(record, next(counter), units), flush=True)

        status = EXIT_PLAYED
        if args.mjcf:
            try:
                write_mjcf(result, args.mjcf, contact)
            except OSError as exc:
                _cannot_write(args.mjcf, exc)
                status = EXIT_WRITE_FAILED
        run_ = execute(result, touch_ups=touch_ups, duration=duration, contact=contact, progress=progress)
    except ValueError as exc:
        _error(str(exc))
        return EXIT_BAD_INPUT
    if any(s["outcome"] in ("not planned", "unstable") for s in run_.stages):
        status = EXIT_TOUCH_UP_FAILED
    if args.json:
        try:
            run_.save(args.json)
        except (OSError, ValueError) as exc:
            _cannot_write(args.json, exc)
            status = EXIT_WRITE_FAILED
        else:
            print(f"wrote {args.json}", file=sys.stderr)
    if args.plot and run_.traces[0] is None:     # unstable before anything was played: nothing to draw
        _error(f"did not write {args.plot}: the simulation went unstable before the open loop played")
    elif args.plot:
        try:
            plan_command.write_figure(execution_figure(run_), args.plot, "--plot")
        except (OSError, ValueError) as exc:
            _cannot_write(args.plot, exc)
            status = EXIT_WRITE_FAILED
        else:
            print(f"wrote {args.plot}", file=sys.stderr)
    return status


def _error(message: str) -> None:
    print(f"nonholo execute: error: {' '.join(message.split())}", file=sys.stderr, flush=True)


def _cannot_write(path, exc: Exception) -> None:
    _error(f"cannot write {path}: {exc.strerror if isinstance(exc, OSError) and exc.strerror else exc}")
