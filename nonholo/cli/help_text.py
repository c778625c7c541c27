"""Plain text for ``--help`` from a module docstring written in reST: the docstrings stay
the reference (with cross-references for the documentation), the terminal gets text.

Roles (``:mod:`x```, ``:func:`~a.b``, ``:attr:`text <target>```) become their text (the
last dotted part with ``~``), inline literals their content, ``::`` ending a paragraph a
single colon.
"""
from __future__ import annotations

import re

_ROLE = re.compile(r":[a-z]+(?::[a-z]+)?:`([^`]+)`")
_LITERAL = re.compile(r"``(.+?)``", re.DOTALL)
_LITERAL_BLOCK = re.compile(r"(\S)::$", re.MULTILINE)


def _role_text(match: re.Match) -> str:
    text = match.group(1)
    titled = re.fullmatch(r"(.+?)\s*<[^>]+>", text, re.DOTALL)
    if titled:
        return titled.group(1)
    if text.startswith("~"):
        return text[1:].rsplit(".", 1)[-1]
    return text


def plain(doc: str) -> str:
    """``doc`` (reST) as plain text for ``argparse`` (see the module)."""
    text = _ROLE.sub(_role_text, doc)
    text = _LITERAL.sub(r"\1", text)
    return _LITERAL_BLOCK.sub(r"\1:", text)
