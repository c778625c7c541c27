"""A mechanism in one file: its equations as text in a TOML file, read as data, never run.

A mechanism file (``docs/guide/car_trailer.toml``)::

    name = "car_trailer"
    coordinates = ["x", "y", "theta", "phi", "theta1"]
    inputs = ["v", "w"]
    angles = ["theta", "phi", "theta1"]
    [parameters]
    L = 1.0
    [rates]
    x = "v*cos(theta)"
    theta = "v*tan(phi)/L"
    ...

Its keys and what is checked of them: :mod:`nonholo.model.definition_check`.

:func:`read_file` reads and checks a file: every refusal is a ``ValueError`` naming the
file, the line and the field (``trailer.toml, line 12, rates.theta: …``; the places from
:mod:`nonholo.model.field_places`). The checked data, the *definition*
(:attr:`nonholo.model.mechanism.Mechanism.definition`), is written back by :func:`write`,
as the text :func:`toml_text` gives; its other forms are in
:mod:`nonholo.model.definition_forms`.
"""
from __future__ import annotations

import os
import stat
from collections.abc import Mapping
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:          # Python 3.10
    import tomli as tomllib

from .definition_check import KEYS, check
from .field_places import Where, located_in, syntax_message

#: The largest mechanism file read (bytes).
MAX_BYTES = 1_000_000


def read_bytes(path) -> bytes:
    """A mechanism file's bytes, if it is a regular file of at most :data:`MAX_BYTES`.

    Parameters
    ----------
    path : str or os.PathLike
        The file.

    Returns
    -------
    bytes
        Its content.

    Raises
    ------
    ValueError
        Naming ``path``, if it does not exist, is not a regular file (a directory, a FIFO,
        a device), is larger than :data:`MAX_BYTES` or cannot be read.
    """
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(path, flags)          # not blocking on a FIFO; its kind checked below
    except FileNotFoundError:
        raise ValueError(f"{path}: no such mechanism file") from None
    except OSError as exc:
        raise ValueError(f"{path}: cannot read the mechanism file ({exc.strerror or exc})") from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            kind = "a directory" if stat.S_ISDIR(info.st_mode) else "not a regular file"
            raise ValueError(f"{path}: is {kind}, not a mechanism file")
        if info.st_size > MAX_BYTES:
            raise ValueError(f"{path}: the mechanism file has {info.st_size:,} bytes, more than "
                             f"{MAX_BYTES:,}")
        chunks, size = [], 0
        while size <= MAX_BYTES:
            chunk = os.read(fd, MAX_BYTES + 1 - size)
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
        if size > MAX_BYTES:                  # grew while read
            raise ValueError(f"{path}: the mechanism file has more than {MAX_BYTES:,} bytes")
        return b"".join(chunks)
    except OSError as exc:
        raise ValueError(f"{path}: cannot read the mechanism file ({exc.strerror or exc})") from None
    finally:
        os.close(fd)


def parse_bytes(raw: bytes, name: str) -> tuple[dict, Where]:
    """The definition in a mechanism file's bytes, checked
    (:func:`~nonholo.model.definition_check.check`).

    Parameters
    ----------
    raw : bytes
        The file's content (UTF-8 TOML).
    name : str
        The file's name, for messages.

    Returns
    -------
    definition : dict
        The checked definition.
    where : callable
        ``where(field)``: ``"<name>, line <n>, <field>"``, the place of a field in the file.

    Raises
    ------
    ValueError
        Naming the file, the line and the field.
    """
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw[:exc.start].count(b"\n") + 1
        raise ValueError(f"{name}, line {line}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(syntax_message(name, text, str(exc))) from None
    except RecursionError:
        raise ValueError(f"{name}, line 1: the TOML is nested too deeply") from None
    where = located_in(name, text)
    return check(data, where), where


def read_file(path) -> tuple[dict, Where]:
    """The definition in a mechanism file, checked.

    Parameters
    ----------
    path : str or os.PathLike
        The file (TOML, at most :data:`MAX_BYTES`).

    Returns
    -------
    definition : dict
        The checked definition (:mod:`nonholo.model.definition_check`).
    where : callable
        ``where(field)``: the field's place in the file, for messages.

    Raises
    ------
    ValueError
        Naming the file (and, for its content, the line and the field).
    """
    return parse_bytes(read_bytes(path), str(path))


def read(path) -> dict:
    """The definition in a mechanism file, checked (:func:`read_file`).

    Parameters
    ----------
    path : str or os.PathLike
        The file.

    Returns
    -------
    dict
        The definition.

    Raises
    ------
    ValueError
        Naming the file, the line and the field.
    """
    return read_file(path)[0]


def toml_text(definition: Mapping) -> str:
    """A mechanism file's text for a definition, checked: it reads back
    (:func:`~nonholo.model.definition_check.check`) to the same definition.

    Parameters
    ----------
    definition : mapping
        A checked definition.

    Returns
    -------
    str
        The TOML text.

    Raises
    ------
    ValueError
        If the text would not read back to ``definition``.
    """
    import tomli_w

    head = f"# the mechanism {definition['name']!r}: nonholo.Mechanism.from_file reads this file\n"
    text = head + tomli_w.dumps({k: definition[k] for k in KEYS if k in definition})
    back = check(tomllib.loads(text))
    if back != dict(definition):
        raise ValueError(f"the mechanism file of {definition['name']!r} would not read back to its definition")
    return text


def write(definition: Mapping, path) -> Path:
    """Write a mechanism file (:func:`toml_text`), atomically: a complete new file replaces
    ``path``.

    Parameters
    ----------
    definition : mapping
        A checked definition.
    path : str or os.PathLike
        The file.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    ValueError
        Naming ``path`` if it exists and is not a regular file.
    OSError
        If writing fails (an existing file is then untouched).
    """
    path = Path(path)
    if path.exists() and not path.is_file():
        raise ValueError(f"{path}: is not a regular file; not written")
    text = toml_text(definition)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path
