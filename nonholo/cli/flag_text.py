"""Messages of the Python API in the command line's words: the arguments of
:func:`nonholo.plan` named by the flags that set them (``leg_speed`` → ``--leg-speed``,
``T=None`` → ``--T min``, ``R0`` → ``--from``), so that an error printed by a sub-command
names what its user typed.

The Python messages stay the reference (they name the Python arguments); :func:`in_flags`
rewrites them at the command line's boundary. Names with an underscore are unambiguous
and always rewritten; a one-word name (``T``, ``steps``, ``harmonics`` …) only where it is
the argument — before ``must``, ``is``, ``=``, ``>=``, ``<=`` or ``:``, or after
``raise``/``lower``; the names of constraint classes become words.
"""
from __future__ import annotations

import re

#: ``plan()``'s arguments with an underscore (or a digit), by the flags that set them.
FLAGS = {"leg_speed": "--leg-speed", "leg_length": "--leg-length", "delta_min": "--delta-min",
         "max_iter": "--max-iter", "allow_imports": "--allow-imports", "csv_rate": "--csv-rate",
         "R0": "--from", "Rd": "--to"}
#: One-word arguments whose flag is the word itself.
WORDS = ("T", "harmonics", "grid", "steps", "gamma", "tol", "method", "strategy", "route", "objective")
#: One-word arguments whose flag is another word.
RENAMED = {"start": "--from", "goal": "--to"}
#: Phrases of the Python API with no counterpart on the command line, and what stands there.
PHRASES = {"T=None": "--T min",
           "InputBounds in constraints": "a mechanism's own input bounds (nonholo mechanisms lists them)",
           " (or pass a nonholo.Mechanism)": "", " (or pass a Strategy subclass)": "",
           ", or pass a Strategy subclass": "",
           "allow_imports=True (nonholo plan --allow-imports)": "--allow-imports",
           "InputBounds": "input bounds", "StateBounds": "coordinate bounds", "LegSpeed": "--leg-speed"}

_NAMED = re.compile(r"(?<![\w/-])(" + "|".join(map(re.escape, FLAGS)) + r")(?![\w])")
_WORD = re.compile(r"(?<![\w/-])(" + "|".join(WORDS) + r")(?= must\b| is\b| ?=| ?>=| ?<=|:)")
_RENAMED = re.compile(r"(?<![\w/-])(" + "|".join(RENAMED) + r")(?= must\b| is\b| ?=| ?>=| ?<=|:)")
_AFTER = re.compile(r"\b(raise|lower) (" + "|".join(WORDS) + r")\b")


def in_flags(text: str) -> str:
    """``text`` with the Python arguments of :func:`nonholo.plan` named by their flags.

    Parameters
    ----------
    text : str
        A message of the Python API (an exception's, a plan's reason).

    Returns
    -------
    str
        The message in the command line's words.
    """
    for phrase, flag in PHRASES.items():
        text = text.replace(phrase, flag)
    text = _NAMED.sub(lambda m: FLAGS[m.group(1)], text)
    text = _WORD.sub(lambda m: "--" + m.group(1), text)
    text = _RENAMED.sub(lambda m: RENAMED[m.group(1)], text)
    return _AFTER.sub(lambda m: f"{m.group(1)} --{m.group(2)}", text)
