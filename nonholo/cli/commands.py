"""The commands of ``nonholo``: each one's line in ``nonholo --help`` and the function that
adds its arguments, so that the top-level parser lists every command without importing the
modules that run them (:mod:`nonholo.cli.entry` imports one only to run its command or to
show that command's help)."""
from __future__ import annotations

from typing import NamedTuple


class Command(NamedTuple):
    """A command: its line in ``nonholo --help``, and where its arguments are added.

    Parameters
    ----------
    help : str
        Its line in ``nonholo --help``.
    module : str
        The module of :mod:`nonholo.cli` whose function adds its arguments.
    arguments : str
        That function, which takes the command's parser.
    """

    help: str
    module: str                 # the module of nonholo.cli whose function adds the arguments
    arguments: str              # that function, which takes the command's parser


#: The commands, in the order ``nonholo --help`` lists them.
COMMANDS = {
    "derive": Command("derive the kinematics symbolically and write nonholo/generated", "entry",
                      "derive_arguments"),
    "audit": Command("hold the appendix formulas against the derivation", "entry", "audit_arguments"),
    "mechanisms": Command("list the mechanisms", "entry", "mechanisms_arguments"),
    "plan": Command("plan a motion R0 -> Rd (Jacobian algorithm of Tchoń & Jakubiak)", "plan_command",
                    "arguments"),
    "execute": Command("play a saved plan on a MuJoCo model of its mechanism", "execute_command", "arguments"),
    "animate": Command("write a GIF or MP4 of a saved plan's motion", "animate_command", "arguments"),
    "reproduce": Command("check the derivation, audit, solve the examples, write paper_figures/",
                         "reproduce_command", "arguments"),
    "sweep": Command("plan every problem of a JSON Lines file, in parallel, into Parquet", "sweep_command",
                     "sweep_arguments"),
    "atlas": Command("write an atlas's problems, or draw the maps of their sweep", "sweep_command",
                     "atlas_arguments"),
    "dynobench": Command("plan a Dynobench instance, write its trajectory in Dynobench's format",
                         "dynobench_command", "arguments"),
}
