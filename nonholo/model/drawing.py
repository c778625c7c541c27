"""How a mechanism is drawn: planar bodies and wheels placed by expressions in its
coordinates (a catalog vehicle's, or a mechanism file's ``[drawing]``).

A :class:`Drawing` is data, e.g. the ``[drawing]`` table of a mechanism file::

    [[drawing.bodies]]          # a box; its pose in the plane
    x = "x"                     # expressions (text) in coordinates and parameters
    y = "y"
    heading = "theta"
    length = 1.4                # along the heading
    width = 0.8
    offset = 0.5                # the box's centre ahead of (x, y) along the heading
    [[drawing.wheels]]
    body = 0                    # index of the body it is on
    at = [1.0, 0.35]            # in the body's frame (forward, left) from its (x, y)
    steer = "phi"               # optional: turned by this expression
    diameter = 0.4

An expression is text read once by :class:`Expression`: Python's syntax tree of it
(``ast``, mode ``"eval"``) admits only numbers, the declared names (coordinates,
parameters, ``pi``, ``E``), ``+ - * / **``, unary ``-`` and ``+`` and calls of
:data:`FUNCTIONS`; it becomes a small tree of NumPy closures. Nothing is evaluated as
Python and SymPy is not needed. Every refusal is a ``ValueError`` naming the field
(``drawing.bodies[1].heading: unknown name 'foo'``).
"""
from __future__ import annotations

import ast
import importlib
import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

#: The functions an expression may call, by name, with their arity (those of
#: ``derivations.admission.FUNCTIONS``, on NumPy arrays).
FUNCTIONS: dict[str, int] = {
    "sin": 1, "cos": 1, "tan": 1, "cot": 1, "sec": 1, "csc": 1, "asin": 1, "acos": 1, "atan": 1, "atan2": 2,
    "sinh": 1, "cosh": 1, "tanh": 1, "exp": 1, "log": 1, "sqrt": 1, "cbrt": 1, "abs": 1, "Abs": 1,
}
_NUMPY: dict[str, Callable] = {
    "sin": np.sin, "cos": np.cos, "tan": np.tan, "cot": lambda a: 1.0 / np.tan(a),
    "sec": lambda a: 1.0 / np.cos(a), "csc": lambda a: 1.0 / np.sin(a), "asin": np.arcsin, "acos": np.arccos,
    "atan": np.arctan, "atan2": np.arctan2, "sinh": np.sinh, "cosh": np.cosh, "tanh": np.tanh, "exp": np.exp,
    "log": np.log, "sqrt": np.sqrt, "cbrt": np.cbrt, "abs": np.abs, "Abs": np.abs,
}
#: The named constants an expression may use (a coordinate or parameter of the same name
#: takes precedence).
CONSTANTS = {"pi": math.pi, "E": math.e}
#: The longest expression (characters).
MAX_CHARACTERS = 500
#: The deepest nesting of an expression's syntax tree.
MAX_DEPTH = 32
#: At most this many bodies and wheels in one drawing.
MAX_BODIES, MAX_WHEELS = 32, 64

_BINARY = {ast.Add: np.add, ast.Sub: np.subtract, ast.Mult: np.multiply, ast.Div: np.true_divide,
           ast.Pow: np.power}
_UNARY = {ast.USub: np.negative, ast.UAdd: np.positive}
_BODY_KEYS = ("x", "y", "heading", "length", "width", "offset")
_WHEEL_KEYS = ("body", "at", "steer", "diameter", "width")


def _refuse(where: str, why: str):
    raise ValueError(f"{where}: {why}")


def _number(value, where: str, positive: bool = False) -> float:
    """A finite real number (not a bool, not text); positive if asked."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        _refuse(where, f"must be a number, got {type(value).__name__}")
    value = float(value)
    if not math.isfinite(value):
        _refuse(where, f"must be finite, got {value!r}")
    if positive and value <= 0.0:
        _refuse(where, f"must be positive, got {value!r}")
    return value


@dataclass(frozen=True)
class Expression:
    """An expression of a drawing, read from text once and evaluated on arrays.

    Parameters
    ----------
    text : str
        The expression as written (see the module for what it may hold).
    names : tuple of str
        The names it may use besides ``pi`` and ``E``: the coordinates and the parameters.
    values : tuple of tuple
        ``(name, value)`` of the parameters (their values are constants).
    where : str
        The field it comes from, named by the errors.

    Raises
    ------
    ValueError
        Naming ``where``, for text longer than :data:`MAX_CHARACTERS`, not a Python
        expression, nested deeper than :data:`MAX_DEPTH`, or holding anything but numbers,
        the names, ``+ - * / **``, unary ``-`` and calls of :data:`FUNCTIONS`.
    """

    text: str
    names: tuple[str, ...] = field(repr=False)
    values: tuple[tuple[str, float], ...] = field(default=(), repr=False)
    where: str = field(default="expression", repr=False, compare=False)
    function: Callable = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "function", _compile(self.text, self.names, dict(self.values), self.where))

    def __call__(self, env: Mapping[str, np.ndarray]) -> np.ndarray:
        """The expression's value.

        Parameters
        ----------
        env : mapping
            Each coordinate's values by name (arrays of one shape).

        Returns
        -------
        numpy.ndarray
            The value (a NumPy scalar for an expression without coordinates).
        """
        with np.errstate(all="ignore"):
            return self.function(env)


def _compile(text, names: tuple[str, ...], parameters: dict, where: str) -> Callable:
    """The closure of ``text`` (see :class:`Expression`)."""
    if not isinstance(text, str):
        _refuse(where, f"must be an expression as text, got {type(text).__name__}")
    if len(text) > MAX_CHARACTERS:
        _refuse(where, f"is {len(text)} characters long; at most {MAX_CHARACTERS}")
    if not text.strip():
        _refuse(where, "is empty")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except (SyntaxError, ValueError, MemoryError, RecursionError) as exc:
        _refuse(where, f"is not an expression ({type(exc).__name__}: {getattr(exc, 'msg', exc)})")
    variables = set(names) - set(parameters)
    admitted = "numbers, names, + - * / **, unary - and calls of " + ", ".join(FUNCTIONS)

    def build(node, depth: int) -> Callable:
        if depth > MAX_DEPTH:
            _refuse(where, f"is nested more than {MAX_DEPTH} deep")
        if isinstance(node, ast.Constant):
            if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
                _refuse(where, f"the constant {node.value!r} is not a real number")
            value = np.float64(float(node.value)) if abs(node.value) < 1e308 else np.float64(np.inf)
            if not np.isfinite(value):
                _refuse(where, f"the constant {node.value!r} is not finite")
            return lambda env: value
        if isinstance(node, ast.Name):
            name = node.id
            if name in parameters:
                value = np.float64(parameters[name])
                return lambda env: value
            if name in variables:
                return lambda env: env[name]
            if name in CONSTANTS:
                value = np.float64(CONSTANTS[name])
                return lambda env: value
            if name in FUNCTIONS:
                _refuse(where, f"the function {name!r} must be called")
            _refuse(where, f"unknown name {name!r} (known: {', '.join(sorted(names)) or 'none'}, pi, E)")
        if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
            op = _BINARY[type(node.op)]
            left, right = build(node.left, depth + 1), build(node.right, depth + 1)
            return lambda env: op(left(env), right(env))
        if isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
            op = _UNARY[type(node.op)]
            operand = build(node.operand, depth + 1)
            return lambda env: op(operand(env))
        if isinstance(node, ast.Call):
            if not isinstance(node.func, ast.Name) or node.func.id not in FUNCTIONS or node.func.id in variables:
                shown = repr(node.func.id) if isinstance(node.func, ast.Name) \
                    else f"an expression ({type(node.func).__name__})"
                _refuse(where, f"calls {shown}; only {', '.join(FUNCTIONS)} may be called")
            if node.keywords or any(isinstance(a, ast.Starred) for a in node.args):
                _refuse(where, f"{node.func.id}() takes plain arguments only")
            function, arity = _NUMPY[node.func.id], FUNCTIONS[node.func.id]
            if len(node.args) != arity:
                _refuse(where, f"{node.func.id}() takes {arity} argument{'s' if arity > 1 else ''}, "
                               f"got {len(node.args)}")
            args = [build(a, depth + 1) for a in node.args]
            if arity == 1:
                only = args[0]
                return lambda env: function(only(env))
            first, second = args
            return lambda env: function(first(env), second(env))
        if isinstance(node, (ast.BinOp, ast.UnaryOp)):
            _refuse(where, f"the operator {type(node.op).__name__} is not admitted (only {admitted})")
        _refuse(where, f"{type(node).__name__} is not admitted (only {admitted})")

    return build(tree.body, 1)


@dataclass(frozen=True)
class Body:
    """A box of a drawing, posed in the plane by expressions.

    Parameters
    ----------
    x, y, heading : Expression
        The body's reference point and heading (rad).
    length, width : float
        The box's size along and across the heading.
    offset : float
        The box's centre ahead of ``(x, y)`` along the heading.
    """

    x: Expression
    y: Expression
    heading: Expression
    length: float
    width: float
    offset: float = 0.0


@dataclass(frozen=True)
class Wheel:
    """A wheel of a drawing, on a body.

    Parameters
    ----------
    body : int
        The index of the body it is on.
    at : tuple of float
        Its centre in the body's frame, ``(forward, left)`` from the body's ``(x, y)``.
    steer : Expression or None
        Its steering angle from the body's heading (rad); ``None``: none.
    diameter : float
        Its diameter (drawn along its heading).
    width : float
        Its width (drawn across).
    """

    body: int
    at: tuple[float, float]
    steer: Expression | None
    diameter: float
    width: float


@dataclass(frozen=True)
class Drawing:
    """How a planar mechanism is drawn: boxes (:class:`Body`) and wheels (:class:`Wheel`)
    placed by expressions in its coordinates and parameters (see the module).

    Built from data by :meth:`from_mapping`; :meth:`to_mapping` gives the data back;
    :meth:`poses` and :meth:`outlines` evaluate it along states.

    Parameters
    ----------
    bodies : tuple of Body
        The boxes.
    wheels : tuple of Wheel
        The wheels.
    coordinates : tuple of str
        The mechanism's coordinates, in the order of a state's columns.
    parameters : tuple of tuple
        ``(name, value)`` of the parameters the expressions may use.
    """

    bodies: tuple[Body, ...]
    wheels: tuple[Wheel, ...]
    coordinates: tuple[str, ...]
    parameters: tuple[tuple[str, float], ...] = ()

    @classmethod
    def from_mapping(cls, data, coordinates, parameters=None, where: str = "drawing") -> "Drawing":
        """A drawing from its data (a mechanism file's ``[drawing]`` table), checked.

        Parameters
        ----------
        data : mapping
            ``{"bodies": [...], "wheels": [...]}``: each body with ``x``, ``y`` (and
            ``heading``, default ``0``) as expressions, ``length`` and ``width`` (positive
            numbers) and ``offset`` (default 0); each wheel with ``body`` (an index),
            ``at`` (two numbers, default ``[0, 0]``), ``diameter`` (positive), and
            optionally ``steer`` (an expression) and ``width`` (default a quarter of the
            diameter).
        coordinates : sequence of str
            The mechanism's coordinates, in the order of a state's columns.
        parameters : mapping, optional
            The parameters' values by name (finite real numbers).
        where : str
            The name the errors give ``data``.

        Returns
        -------
        Drawing
            The drawing.

        Raises
        ------
        ValueError
            Naming the field (``drawing.bodies[1].heading: unknown name 'foo'``), for
            data of the wrong shape, an unknown key, a number that is not a finite real
            (or not positive where a size is due), a body index out of range, or an
            expression :class:`Expression` refuses.
        """
        coordinates = _names(coordinates, "coordinates")
        values = _parameters(parameters, coordinates)
        names = coordinates + tuple(name for name, _ in values)
        if not isinstance(data, Mapping):
            _refuse(where, f"must be a table (mapping), got {type(data).__name__}")
        for key in data:
            if key not in ("bodies", "wheels"):
                _refuse(where, f"unknown key {key!r} (known: bodies, wheels)")
        raw_bodies = _table_list(data.get("bodies"), f"{where}.bodies", MAX_BODIES)
        if not raw_bodies:
            _refuse(f"{where}.bodies", "must hold at least one body")
        raw_wheels = _table_list(data.get("wheels", []), f"{where}.wheels", MAX_WHEELS)

        def expression(value, at: str) -> Expression:
            if isinstance(value, numbers.Real) and not isinstance(value, bool):
                value = repr(_number(value, at))
            return Expression(value, names, values, at)

        bodies = []
        for i, body in enumerate(raw_bodies):
            at = f"{where}.bodies[{i}]"
            _keys(body, _BODY_KEYS, at)
            for key in ("x", "y", "length", "width"):
                if key not in body:
                    _refuse(f"{at}.{key}", "is missing")
            bodies.append(Body(x=expression(body["x"], f"{at}.x"), y=expression(body["y"], f"{at}.y"),
                               heading=expression(body.get("heading", "0"), f"{at}.heading"),
                               length=_number(body["length"], f"{at}.length", positive=True),
                               width=_number(body["width"], f"{at}.width", positive=True),
                               offset=_number(body.get("offset", 0.0), f"{at}.offset")))
        wheels = []
        for i, wheel in enumerate(raw_wheels):
            at = f"{where}.wheels[{i}]"
            _keys(wheel, _WHEEL_KEYS, at)
            for key in ("body", "diameter"):
                if key not in wheel:
                    _refuse(f"{at}.{key}", "is missing")
            index = wheel["body"]
            if isinstance(index, bool) or not isinstance(index, numbers.Integral) \
                    or not 0 <= index < len(bodies):
                _refuse(f"{at}.body", f"must be the index of a body (0 to {len(bodies) - 1}), got {index!r}")
            place = wheel.get("at", (0.0, 0.0))
            if isinstance(place, (str, bytes)) or not isinstance(place, Sequence) or len(place) != 2:
                _refuse(f"{at}.at", f"must be two numbers (forward, left), got {place!r}")
            diameter = _number(wheel["diameter"], f"{at}.diameter", positive=True)
            steer = wheel.get("steer")
            wheels.append(Wheel(body=int(index),
                                at=(_number(place[0], f"{at}.at[0]"), _number(place[1], f"{at}.at[1]")),
                                steer=None if steer is None else expression(steer, f"{at}.steer"),
                                diameter=diameter,
                                width=_number(wheel.get("width", diameter / 4), f"{at}.width", positive=True)))
        return cls(bodies=tuple(bodies), wheels=tuple(wheels), coordinates=coordinates, parameters=values)

    def to_mapping(self) -> dict:
        """The drawing as data (:meth:`from_mapping` reads it back to an equal drawing).

        Returns
        -------
        dict
            ``{"bodies": [...], "wheels": [...]}``, expressions as text.
        """
        bodies = [{"x": b.x.text, "y": b.y.text, "heading": b.heading.text, "length": b.length,
                   "width": b.width, "offset": b.offset} for b in self.bodies]
        wheels = []
        for w in self.wheels:
            entry = {"body": w.body, "at": list(w.at), "diameter": w.diameter, "width": w.width}
            if w.steer is not None:
                entry["steer"] = w.steer.text
            wheels.append(entry)
        return {"bodies": bodies, "wheels": wheels}

    def _states(self, X) -> tuple[dict, int]:
        X = np.asarray(X, dtype=float)
        if X.ndim == 1:
            X = X[None]
        k = len(self.coordinates)
        if X.ndim != 2 or X.shape[1] != k:
            raise ValueError(f"X must be states of shape (n, {k}) (coordinates {', '.join(self.coordinates)}), "
                             f"got shape {X.shape}")
        return {name: X[:, i] for i, name in enumerate(self.coordinates)}, X.shape[0]

    def poses(self, X) -> dict:
        """Every body's and wheel's pose along states ``X``.

        Parameters
        ----------
        X : array_like
            States, shape ``(n, k)`` (one state ``(k,)`` is ``n = 1``), the columns in the
            order of ``coordinates``.

        Returns
        -------
        dict
            ``"bodies"``: ``(n, B, 3)``, each body's ``(x, y, heading)``; ``"centres"``:
            ``(n, B, 2)``, its box's centre (``offset`` ahead of ``(x, y)``);
            ``"wheels"``: ``(n, W, 3)``, each wheel's centre and heading (its body's
            heading plus its steering angle).

        Raises
        ------
        ValueError
            If ``X`` is not of shape ``(n, k)``.
        """
        env, n = self._states(X)

        def value(e: Expression) -> np.ndarray:
            return np.broadcast_to(np.asarray(e(env), dtype=float), (n,))

        bodies = np.stack([np.stack([value(b.x), value(b.y), value(b.heading)], axis=-1)
                           for b in self.bodies], axis=1)
        offsets = np.array([b.offset for b in self.bodies])
        heading = bodies[:, :, 2]
        centres = bodies[:, :, :2] + offsets * np.stack([np.cos(heading), np.sin(heading)], axis=-1)
        wheels = np.zeros((n, len(self.wheels), 3))
        for j, w in enumerate(self.wheels):
            x, y, th = bodies[:, w.body].T
            c, s = np.cos(th), np.sin(th)
            wheels[:, j, 0] = x + w.at[0] * c - w.at[1] * s
            wheels[:, j, 1] = y + w.at[0] * s + w.at[1] * c
            wheels[:, j, 2] = th + (0.0 if w.steer is None else value(w.steer))
        return {"bodies": bodies, "centres": centres, "wheels": wheels}

    def outlines(self, X) -> dict:
        """The corners of every body's box and every wheel along states ``X``.

        Parameters
        ----------
        X : array_like
            States, as :meth:`poses` takes them.

        Returns
        -------
        dict
            ``"bodies"``: ``(n, B, 4, 2)``; ``"wheels"``: ``(n, W, 4, 2)`` (a wheel is a
            box of its diameter by its width), counter-clockwise from the rear right.

        Raises
        ------
        ValueError
            If ``X`` is not of shape ``(n, k)``.
        """
        poses = self.poses(X)
        bodies = box_corners(poses["centres"], poses["bodies"][..., 2],
                             np.array([b.length for b in self.bodies]), np.array([b.width for b in self.bodies]))
        wheels = box_corners(poses["wheels"][..., :2], poses["wheels"][..., 2],
                             np.array([w.diameter for w in self.wheels]), np.array([w.width for w in self.wheels]))
        return {"bodies": bodies, "wheels": wheels}


def box_corners(centre, heading, length, width) -> np.ndarray:
    """The corners of boxes in the plane.

    Parameters
    ----------
    centre : array_like
        The boxes' centres, shape ``(..., 2)``.
    heading : array_like
        Their headings (rad), shape ``(...)``.
    length, width : array_like
        Their sizes along and across the heading (broadcast against ``heading``).

    Returns
    -------
    numpy.ndarray
        Shape ``(..., 4, 2)``: rear right, front right, front left, rear left.
    """
    centre = np.asarray(centre, dtype=float)
    heading = np.asarray(heading, dtype=float)
    half_l = 0.5 * np.broadcast_to(length, heading.shape)[..., None]
    half_w = 0.5 * np.broadcast_to(width, heading.shape)[..., None]
    forward = np.stack([np.cos(heading), np.sin(heading)], axis=-1)
    left = np.stack([-np.sin(heading), np.cos(heading)], axis=-1)
    signs = ((-1, -1), (1, -1), (1, 1), (-1, 1))
    return np.stack([centre + a * half_l * forward + b * half_w * left for a, b in signs], axis=-2)


def _names(coordinates, where: str) -> tuple[str, ...]:
    if isinstance(coordinates, str) or not isinstance(coordinates, Sequence):
        _refuse(where, f"must be a sequence of names, got {type(coordinates).__name__}")
    out = tuple(coordinates)
    for name in out:
        if not isinstance(name, str) or not name.isidentifier():
            _refuse(where, f"{name!r} is not a name")
    if len(set(out)) != len(out):
        _refuse(where, "names a coordinate twice")
    return out


def _parameters(parameters, coordinates: tuple[str, ...]) -> tuple[tuple[str, float], ...]:
    if parameters is None:
        return ()
    if not isinstance(parameters, Mapping):
        _refuse("parameters", f"must be a mapping of names to values, got {type(parameters).__name__}")
    out = []
    for name, value in parameters.items():
        name = str(name)              # a SymPy symbol names itself
        if not name.isidentifier():
            _refuse("parameters", f"{name!r} is not a name")
        if name in coordinates:
            _refuse(f"parameters: {name}", "is also a coordinate")
        try:
            value = float(value) if not isinstance(value, (str, bytes, bool)) else value
        except (TypeError, ValueError):
            pass
        out.append((name, _number(value, f"parameters: {name}")))
    return tuple(out)


def _table_list(value, where: str, limit: int) -> list:
    if value is None:
        _refuse(where, "is missing")
    if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, Sequence):
        _refuse(where, f"must be a list of tables, got {type(value).__name__}")
    if len(value) > limit:
        _refuse(where, f"has {len(value)} entries; at most {limit}")
    for i, entry in enumerate(value):
        if not isinstance(entry, Mapping):
            _refuse(f"{where}[{i}]", f"must be a table (mapping), got {type(entry).__name__}")
    return list(value)


def _keys(entry: Mapping, known: tuple[str, ...], where: str) -> None:
    for key in entry:
        if key not in known:
            _refuse(where, f"unknown key {key!r} (known: {', '.join(known)})")


#: The drawings of the catalog's planar vehicles, as data (wheelbase 1 for the car: its
#: ``(x, y)`` is the rear axle's centre; the unicycle's wheel at its ``(x, y)``, in metres).
CATALOG_DRAWINGS = {
    "car": {
        "bodies": [{"x": "x", "y": "y", "heading": "theta", "length": 1.4, "width": 0.8, "offset": 0.5}],
        "wheels": [{"body": 0, "at": [0.0, -0.35], "diameter": 0.4, "width": 0.12},
                   {"body": 0, "at": [0.0, 0.35], "diameter": 0.4, "width": 0.12},
                   {"body": 0, "at": [1.0, -0.35], "steer": "phi", "diameter": 0.4, "width": 0.12},
                   {"body": 0, "at": [1.0, 0.35], "steer": "phi", "diameter": 0.4, "width": 0.12}],
    },
    "unicycle": {
        "bodies": [{"x": "x", "y": "y", "heading": "theta", "length": 0.5, "width": 0.3, "offset": 0.0}],
        "wheels": [{"body": 0, "at": [0.0, 0.0], "diameter": 0.4, "width": 0.06}],
    },
    "car_with_trailer": {    # Dynobench's boxes, 0.5 × 0.25 and 0.3 × 0.25, the trailer's 0.5 behind
        "bodies": [{"x": "x", "y": "y", "heading": "theta", "length": 0.5, "width": 0.25, "offset": 0.0},
                   {"x": "x - 0.5*cos(theta1)", "y": "y - 0.5*sin(theta1)", "heading": "theta1", "length": 0.3,
                    "width": 0.25, "offset": 0.0}],
        "wheels": [{"body": 0, "at": [0.125, -0.1], "steer": "phi", "diameter": 0.12, "width": 0.04},
                   {"body": 0, "at": [0.125, 0.1], "steer": "phi", "diameter": 0.12, "width": 0.04}],
    },
    "unicycle2": {      # Dynobench's box, 0.5 × 0.25
        "bodies": [{"x": "x", "y": "y", "heading": "theta", "length": 0.5, "width": 0.25, "offset": 0.0}],
        "wheels": [{"body": 0, "at": [0.0, 0.0], "diameter": 0.4, "width": 0.06}],
    },
}


def catalog_drawing(name: str):
    """The drawing of the catalog's mechanism ``name``; ``None`` for one without.

    Parameters
    ----------
    name : str
        A catalog name.

    Returns
    -------
    Drawing or None
        Its drawing (:data:`CATALOG_DRAWINGS`, in the coordinates of its generated module).
    """
    if name not in CATALOG_DRAWINGS:
        return None
    module = importlib.import_module(f"nonholo.generated.{name}")
    return Drawing.from_mapping(CATALOG_DRAWINGS[name], tuple(module.COORDINATES), where=f"{name} drawing")
