"""Tables of planning problems: the JSON Lines format :func:`nonholo.batch.sweep.sweep` runs.

One problem per line, a JSON object::

    {"start": [[...], [...], [...]], "goal": [[...], [...], [...]],
     "mechanism": "platform", "options": {"T": 1.0, "strategy": "paper"}}
    {"start": [0, 0, 0, 0], "goal": [0, 1, 0, 0], "mechanism": "car"}
    {"start": [[[...], [...], [...]], [0, 0]], "goal": [[[...], [...], [...]], [0, 0]],
     "mechanism": "rolling_ball"}

``start`` and ``goal`` are the states :func:`nonholo.plan` takes as ``R0`` and ``Rd``, in
the JSON form of the row's mechanism's space (:meth:`nonholo.spaces.product.Product.to_json`):
a 3×3 rotation matrix (nested lists) on SO(3), the ``k`` coordinates on ``Rᵏ``, the pair
``[R, q]`` on ``SO(3) × Rᵏ``. ``mechanism`` (a name, :func:`nonholo.model.catalog.names`;
a mechanism file, a path ending in ``.toml`` relative to the table's own directory; or a
mechanism's definition as an object, as a file holds it; default ``"platform"``) and
``options`` (keyword arguments of :func:`nonholo.plan` that JSON can hold, :data:`OPTIONS`)
are optional; so is ``label``, free text carried
into the results (e.g. a goal's name). A table may mix mechanisms: each row's states are
checked against its own. In Python the same rows are dicts (``start`` and ``goal`` may
be arrays, and a pair a tuple ``(R, q)``).

:func:`check` validates a whole table before anything runs and names the row (from 0, the
line of the file) and the column of the first problem it finds; :func:`fingerprint`
identifies a table, so that a sweep resumed with another one is refused.

A table is data: ``options.strategy`` names a strategy (``"paper"``, ``"robust"``); one
given by its import path ``"package.module:Class"`` would import that module (and run its
top-level code), so it is refused, naming the row, unless the caller opts in
(``allow_imports=True``; ``nonholo sweep --allow-imports``). Nothing is imported here.
"""
from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

from ..model import catalog, definition_forms
from ..model.mechanism import Mechanism
from ..numerics.checks import is_number
from . import safe_write

#: The columns a problem may have; ``start`` and ``goal`` are required.
COLUMNS = ("start", "goal", "mechanism", "options", "label")
#: The keyword arguments of :func:`nonholo.plan` a problem's ``options`` may set (those
#: JSON can hold; ``u0`` and ``callback`` cannot).
OPTIONS = ("T", "method", "harmonics", "grid", "gamma", "step", "tol", "max_iter", "strategy",
           "delta_min", "steps", "newton_below", "min_step", "route", "leg_length", "leg_speed",
           "objective")
#: The option :func:`check_row` adds for a strategy named by its import path the caller
#: allowed (``plan(allow_imports=True)``); a table cannot set it (it is not in :data:`OPTIONS`).
IMPORTS = "allow_imports"


def _fail(row: int, column: str | None, message: str):
    where = f"row {row}" + ("" if column is None else f", column {column!r}")
    raise ValueError(f"problem {where}: {message}")


def _state(space, value, row: int, column: str, mechanism: str):
    """The state ``value`` of the column ``column`` in the caller's form of ``space``."""
    try:
        R, q = space.from_json(value, column)
    except (TypeError, ValueError, OverflowError) as exc:
        want = space.describe()
        detail = str(exc)
        if detail.startswith(f"{column} must be {want}"):
            detail = detail[len(f"{column} must be {want}"):].lstrip(":, ")
        _fail(row, column, f"mechanism {mechanism!r} expects {want}; {detail}")
    return space.public((R, q))


def row_mechanism(value, row: int, base=None) -> Mechanism:
    """The mechanism of a row's ``mechanism`` column (see the module).

    Parameters
    ----------
    value : str, dict or Mechanism
        A name, a mechanism file's path (``.toml``), a definition, or (in Python) a
        :class:`~nonholo.model.mechanism.Mechanism` of the catalog or with a definition.
    row : int
        The row's number, for messages.
    base : str or os.PathLike, optional
        The directory a relative file path is relative to (the table's).

    Returns
    -------
    Mechanism
        The mechanism (one object per file or definition: :func:`nonholo.model.catalog.resolve`).

    Raises
    ------
    ValueError
        Naming the row and the column (and, for a file, the file, its line and field).
    """
    if isinstance(value, Mechanism):
        if value.definition is None and not _in_catalog(value):
            _fail(row, "mechanism", f"mechanism {value.name!r} is not the catalog's and has no definition as "
                                    "data to rebuild it from in a worker: give its file (.toml)")
        return value
    if isinstance(value, str) and not value.lower().endswith(".toml") and value not in catalog.names():
        _fail(row, "mechanism", f"unknown mechanism {value!r} (known: {', '.join(catalog.names())}; or a "
                                "mechanism file, .toml)")
    if not isinstance(value, (str, dict)):
        _fail(row, "mechanism", f"must be a mechanism's name, a mechanism file (.toml) or a definition, got "
                                f"{value!r}")
    try:
        return catalog.resolve(value, base, where="mechanism")
    except ValueError as exc:
        _fail(row, "mechanism", str(exc))


def _in_catalog(mechanism: Mechanism) -> bool:
    return mechanism.name in catalog.names() and catalog.get(mechanism.name) is mechanism


def check_row(d, row: int, allow_imports: bool = False, base=None) -> dict:
    """One problem, checked.

    Parameters
    ----------
    d : dict
        The row, with the columns of :data:`COLUMNS`.
    row : int
        Its number (from 0), for messages.
    allow_imports : bool
        Accept a strategy named by its import path (see the module); refused otherwise.
    base : str or os.PathLike, optional
        The directory a mechanism file's relative path is relative to (the table's;
        default: the working directory).

    Returns
    -------
    dict
        ``{"start", "goal", "mechanism", "kinematics", "options", "label"}`` with the
        states in the form :func:`nonholo.plan` takes (arrays; a pair ``(R, q)`` as a
        tuple), the mechanism's name, the :class:`~nonholo.model.mechanism.Mechanism`
        itself and a dict of keywords of :func:`nonholo.plan`: the row's options, and
        ``allow_imports=True`` with an import path allowed.

    Raises
    ------
    ValueError
        Naming the row and the column, for a row that is not a problem.
    """
    if not isinstance(d, dict):
        _fail(row, None, f"must be an object with columns {', '.join(COLUMNS)}, got {type(d).__name__}")
    unknown = [k for k in d if k not in COLUMNS]
    if unknown:
        _fail(row, str(unknown[0]), f"is not a column (known: {', '.join(COLUMNS)})")
    for key in ("start", "goal"):
        if key not in d:
            _fail(row, key, "is missing")
    mechanism = row_mechanism(d.get("mechanism", "platform"), row, base)
    name = mechanism.name
    space = mechanism.space
    start = _state(space, d["start"], row, "start", name)
    goal = _state(space, d["goal"], row, "goal", name)
    options = d.get("options", {})
    if not isinstance(options, dict):
        _fail(row, "options", f"must be an object of plan() options, got {type(options).__name__}")
    for key, value in options.items():
        if key not in OPTIONS:
            _fail(row, f"options.{key}", f"is not an option of plan() (known: {', '.join(OPTIONS)})")
        why = _json_value(value)
        if why:
            _fail(row, f"options.{key}", why)
    options = dict(options)
    strategy = options.get("strategy")
    if isinstance(strategy, str) and ":" in strategy:
        if not allow_imports:
            _fail(row, "options.strategy",
                  f"names a strategy by its import path {strategy!r}, which would import the module "
                  f"{strategy.partition(':')[0]!r} and run its code; a problem table is data: allow it with "
                  "allow_imports=True (nonholo sweep --allow-imports) if you trust the table")
        options[IMPORTS] = True              # the caller's opt-in, passed on to plan()
    label = d.get("label")
    if label is not None and not isinstance(label, str):
        _fail(row, "label", f"must be text, got {label!r}")
    return {"start": start, "goal": goal, "mechanism": name, "kinematics": mechanism, "options": options,
            "label": label}


def _json_value(x) -> str | None:
    """Why ``x`` is not an option's value JSON can hold (``None``: it is one)."""
    if x is None or isinstance(x, (bool, str)):
        return None
    if is_number(x):
        try:
            finite = math.isfinite(x)
        except OverflowError:                 # an integer beyond the floats' range
            return f"is an integer too large for a number of plan() ({_digits(x)} digits)"
        return None if finite else f"must be a finite number, got {x!r}"
    if isinstance(x, (list, tuple)):
        return next((why for why in map(_json_value, x) if why), None)
    return f"must be a number, string, boolean, null or list, got {x!r}"


def _digits(n: int) -> int:
    """The decimal digits of a (huge) integer, without converting it to text."""
    return int(abs(n).bit_length() * math.log10(2)) + 1


def check(rows, allow_imports: bool = False, base=None) -> list[dict]:
    """Every row checked (:func:`check_row`).

    Parameters
    ----------
    rows : iterable of dict
        The problems.
    allow_imports : bool
        See :func:`check_row`.
    base : str or os.PathLike, optional
        See :func:`check_row`.

    Returns
    -------
    list of dict
        The checked problems, in order.

    Raises
    ------
    ValueError
        Naming the first bad row, or if there are no rows.
    TypeError
        If ``rows`` is not a list (an iterable) of rows.
    """
    if rows is None or isinstance(rows, (str, bytes, dict)):
        raise TypeError(f"problems must be a list of problems (dicts) or a JSON Lines file's path, "
                        f"got {type(rows).__name__}")
    try:
        rows = list(rows)
    except TypeError:
        raise TypeError(f"problems must be a list of problems (dicts) or a JSON Lines file's path, "
                        f"got {type(rows).__name__}") from None
    if not rows:
        raise ValueError("the problem table is empty")
    return [check_row(d, i, allow_imports, base) for i, d in enumerate(rows)]


def read(path, allow_imports: bool = False) -> list[dict]:
    """The problems of a JSON Lines file, checked.

    Parameters
    ----------
    path : str or pathlib.Path
        The file: one JSON object per line (blank lines are not allowed: every line is a
        row, numbered from 0).
    allow_imports : bool
        See :func:`check_row`.

    Returns
    -------
    list of dict
        The checked problems (:func:`check`; a mechanism file's path relative to the
        file's directory).

    Raises
    ------
    ValueError
        Naming the row, for a line that is blank, not JSON or not a problem; for an empty
        file.
    """
    rows = []
    with open(path, encoding="utf-8-sig") as f:
        for i, line in enumerate(f):
            if not line.strip():
                _fail(i, None, "is blank (one JSON object per line)")
            try:
                rows.append(json.loads(line))
            except json.JSONDecodeError as exc:
                _fail(i, None, f"is not JSON: {exc.msg} at character {exc.pos}")
    if not rows:
        raise ValueError(f"{path}: no problems (an empty file)")
    return check(rows, allow_imports, Path(path).parent)


def as_json(problem: dict) -> dict:
    """A checked problem as a JSON-able row (the inverse of :func:`check_row`).

    Parameters
    ----------
    problem : dict
        A problem as :func:`check_row` returns it.

    Returns
    -------
    dict
        The row, the states in the JSON form of the mechanism's space; the mechanism by
        its definition if it has one (data a worker rebuilds it from), else by its name.
    """
    mechanism = problem.get("kinematics") or catalog.resolve(problem["mechanism"])
    space = mechanism.space
    out = {"start": space.to_json(space.parse(problem["start"], "start")),
           "goal": space.to_json(space.parse(problem["goal"], "goal")),
           "mechanism": (mechanism.name if mechanism.definition is None
                         else definition_forms.json_data(mechanism.definition)),
           "options": {k: v for k, v in problem["options"].items() if k != IMPORTS}}
    if problem.get("label") is not None:
        out["label"] = problem["label"]
    return out


def write(path, rows) -> Path:
    """Write problems as JSON Lines, checked first.

    Parameters
    ----------
    path : str or pathlib.Path
        The file, written by :func:`nonholo.io.safe_write.write_text` (atomically).
    rows : iterable of dict
        The problems, as :func:`check_row` takes them.

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    ValueError
        Naming ``path`` if it is a directory; naming the row for a bad problem
        (:func:`check`).
    """
    safe_write.check_target(path, "path")
    lines = [json.dumps(as_json(p), separators=(",", ":")) for p in check(rows, allow_imports=True)]
    return safe_write.write_text(path, "\n".join(lines) + "\n", "path")


def fingerprint(problems: list[dict]) -> str:
    """A SHA-256 of the checked problems' canonical JSON: the identity of a table.

    Parameters
    ----------
    problems : list of dict
        Checked problems (:func:`check`).

    Returns
    -------
    str
        The hex digest.
    """
    h = hashlib.sha256()
    for p in problems:
        h.update(json.dumps(as_json(p), sort_keys=True, separators=(",", ":")).encode())
        h.update(b"\n")
    return h.hexdigest()
