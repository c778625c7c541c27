"""The command line ``nonholo``: argument parsing only (:mod:`nonholo.cli.entry` dispatches
to one module per command)."""
from .entry import main

__all__ = ["main"]
