"""``nonholo dynobench ENV.yaml --out SOLUTION.yaml``: a Dynobench instance planned, its
trajectory written in Dynobench's format (:mod:`nonholo.dynobench`).

Exit status 0 when the trajectory passes every check, 1 (with the reason) when there is
none that does, 2 for bad input (a malformed file, an unknown robot type, a start inside an
obstacle: the message names the file and the field).
"""
from __future__ import annotations

import argparse
import sys


def run(args) -> int:
    """Run the command.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments.

    Returns
    -------
    int
        The exit status.
    """
    from .. import dynobench
    from ..dynobench.solve import SHARE, solve

    try:
        instance = dynobench.load(args.env, models=args.models)
    except ValueError as exc:
        print(f"nonholo dynobench: error: {exc}", file=sys.stderr)
        return 2
    solution = solve(instance, share=0.0 if args.strict else SHARE)
    if solution.trajectory is not None and args.out:
        dynobench.write(args.out, solution.trajectory, solution.report)
    print(f"{instance.robot} {instance.name}: {'solved' if solution.solved else 'not solved'}: {solution.reason} "
          f"({solution.seconds:.2f} s)")
    return 0 if solution.solved else 1


def arguments(p: argparse.ArgumentParser) -> None:
    """Give the ``dynobench`` command's parser ``p`` its arguments and the function that runs it.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser.
    """
    p.add_argument("env", help="a Dynobench env file (envs/<robot>/<instance>.yaml)")
    p.add_argument("--out", help="write the trajectory here (Dynobench's YAML: states, actions)")
    p.add_argument("--models", help="the folder of model files (default: ../../models from the env file)")
    p.add_argument("--strict", action="store_true",
                   help="keep the bounds and the goal exactly (by default the trajectory of fewer "
                        "Euler steps may use 0.9 of Dynobench's thresholds)")
    p.set_defaults(func=run)
