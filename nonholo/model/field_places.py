"""Where a field is, for messages: in a TOML text, found by scanning it, or in data from
elsewhere.

:func:`key_lines` lists a text's table headers and keys with their lines (the text need not
be valid TOML); :func:`line_of` gives the line of a field (``"rates.theta"``,
``"drawing.bodies[1].x"``), :func:`field_at` the field written at a line, and
:func:`syntax_message` names both in a TOML syntax error. A *locator* ``where(field)``
places a field in a message: :func:`located_in` in a file (``"trailer.toml, line 12,
rates.theta"``), :func:`labelled` in data from elsewhere (``"definition.rates.theta"``).
"""
from __future__ import annotations

import re
from typing import Protocol

#: A locator: ``where(field)`` is the place of a field, for messages.
class Where(Protocol):
    """Where a field is, for messages: called with the field's name, it gives the place
    (``"line 4 of car.toml"``, ``"the definition's"``).

    Parameters
    ----------
    *args, **kwargs
        As a protocol takes them (it is not instantiated).
    """

    def __call__(self, name: str) -> str: ...

_BARE = r"[A-Za-z0-9_-]+|\"(?:[^\"\\]|\\.)*\"|'[^']*'"
_KEY = re.compile(rf"^\s*((?:{_BARE})(?:\s*\.\s*(?:{_BARE}))*)\s*=")
_HEADER = re.compile(rf"^\s*(\[\[?)\s*((?:{_BARE})(?:\s*\.\s*(?:{_BARE}))*)\s*\]\]?")


def _key_parts(text: str) -> tuple[str, ...]:
    parts = re.findall(_BARE, text)
    return tuple(p[1:-1] if p[:1] in "\"'" else p for p in parts)


def key_lines(text: str) -> list[tuple[tuple, int]]:
    """Every table header and key of a TOML text with its line, found by scanning the
    text (it need not be valid TOML).

    Parameters
    ----------
    text : str
        The text.

    Returns
    -------
    list of tuple
        ``(path, line)``: ``path`` the keys from the top (an entry of an array of tables
        as its index, ``("drawing", "bodies", 1, "x")``), ``line`` from 1.
    """
    out, table, counts, quote = [], (), {}, None
    for n, line in enumerate(text.splitlines(), 1):
        if quote is not None:                    # inside a multi-line string
            if line.count(quote) % 2:
                quote = None
            continue
        header = _HEADER.match(line)
        if header:
            path = _key_parts(header.group(2))
            if header.group(1) == "[[":
                counts[path] = counts.get(path, -1) + 1
                path = path + (counts[path],)
            table = path
            out.append((table, n))
            continue
        key = _KEY.match(line)
        if key:
            out.append((table + _key_parts(key.group(1)), n))
            rest = line[key.end():]
            for q in ('"""', "'''"):
                if rest.count(q) % 2:
                    quote = q
    return out


def _path(field: str) -> tuple:
    """``"drawing.bodies[1].x"`` as ``("drawing", "bodies", 1, "x")``."""
    out = []
    for part in field.split("."):
        name, *indices = re.split(r"\[(\d+)\]", part)
        out.append(name)
        out += [int(i) for i in indices if i]
    return tuple(p for p in out if p != "")


def line_of(text: str, field: str) -> int:
    """The line of a field in a TOML text: its key's, else that of the nearest enclosing
    table or key (an inline table), else 1.

    Parameters
    ----------
    text : str
        The file's text.
    field : str
        The field, dotted (``"rates.theta"``, ``"bounds.inputs.v"``, ``"drawing.bodies[1].x"``).

    Returns
    -------
    int
        The line, from 1.
    """
    want = _path(field)
    best, length = 1, 0
    for path, n in key_lines(text):
        if path == want:
            return n
        if len(path) > length and want[:len(path)] == path:
            best, length = n, len(path)
    return best


def field_at(text: str, line: int) -> str:
    """The field written at a line of a TOML text (its key there, else its table).

    Parameters
    ----------
    text : str
        The text.
    line : int
        The line, from 1.

    Returns
    -------
    str
        The dotted field, or ``"(top level)"``.
    """
    lines = text.splitlines()
    table = ()
    for path, n in key_lines(text):
        if n > line:
            break
        if n == line:
            return _dotted(path)
        if _HEADER.match(lines[n - 1]):
            table = path
    return _dotted(table) if table else "(top level)"


def _dotted(path: tuple) -> str:
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else p)
    return out


def located_in(name: str, text: str) -> Where:
    """``where(field)`` for a file: ``"<name>, line <n>, <field>"``.

    Parameters
    ----------
    name : str
        The file's name.
    text : str
        Its text.

    Returns
    -------
    callable
        The locator.
    """
    return lambda field: f"{name}, line {line_of(text, field)}, {field}"


def labelled(label: str) -> Where:
    """``where(field)`` for data from elsewhere: ``"<label>.<field>"``.

    Parameters
    ----------
    label : str
        Names the data (``"definition"``, ``"'mechanism_definition"``).

    Returns
    -------
    callable
        The locator.
    """
    return lambda field: f"{label}.{field}"


def syntax_message(name: str, text: str, message: str) -> str:
    """A TOML syntax error's message naming the file, the line and the field there.

    Parameters
    ----------
    name : str
        The file's name.
    text : str
        Its text.
    message : str
        ``tomllib``'s message (``"Invalid value (at line 3, column 5)"``).

    Returns
    -------
    str
        ``"<name>, line 3, column 5, rates.x: invalid TOML: Invalid value"``.
    """
    match = re.search(r"\s*\(at line (\d+), column (\d+)\)\s*$", message)
    if match:
        line, column = int(match.group(1)), int(match.group(2))
        detail = message[:match.start()]
        place = f"line {line}, column {column}"
    else:
        line = max(1, text.count("\n") + (0 if text.endswith("\n") else 1))
        detail = re.sub(r"\s*\(at end of document\)\s*$", "", message)
        place = f"line {line} (the end)"
    return f"{name}, {place}, {field_at(text, line)}: invalid TOML: {detail}"
