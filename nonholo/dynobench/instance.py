"""A Dynobench instance read: its env file and the model file it names.

:func:`load` reads them.

An env file (``envs/<robot>/<instance>.yaml``) holds the workspace (``environment.min``,
``max``), box obstacles by centre and size, and one robot's type, start and goal; the
model file (``models/<type>.yaml``) its dynamics, bounds, body sizes, distance weights and
step ``dt``. The files are read by ``yaml.safe_load`` — data only, nothing is constructed
or run — and every field is checked: a missing, malformed or unknown one raises
``ValueError`` naming the file and the field.

The models are those of Dynobench's C++ (``src/unicycle1.cpp``, ``src/unicycle2.cpp``,
``src/car.cpp``): a body is a box centred on the state's position ``(x, y)`` and turned by its
heading; a car's trailer a box centred a hitch length behind the car along the trailer's
heading.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: The dynamics read, and the catalog mechanism each is planned as.
MECHANISMS = {"unicycle1": "unicycle", "unicycle2": "unicycle2", "car_with_trailers": "car_with_trailer"}
#: The state's size of each dynamics.
STATE_SIZES = {"unicycle1": 3, "unicycle2": 5, "car_with_trailers": 4}
#: The largest file read (bytes).
MAX_BYTES = 1 << 20


@dataclass(frozen=True)
class Box:
    """An axis-aligned box obstacle.

    Parameters
    ----------
    center : tuple of float
        Its centre ``(x, y)``.
    size : tuple of float
        Its sides ``(length along x, width along y)``.
    """

    center: tuple
    size: tuple


@dataclass(frozen=True)
class Instance:
    """A Dynobench instance (see the module).

    Parameters
    ----------
    name : str
        The instance's name (its file's stem).
    path : Path
        The env file.
    robot : str
        The robot type (the model file's stem, e.g. ``unicycle1_v0``).
    dynamics : str
        The model's dynamics (a key of :data:`MECHANISMS`).
    start, goal : numpy.ndarray
        The start and the goal, in Dynobench's state.
    low, high : numpy.ndarray
        The workspace's corners.
    obstacles : tuple of Box
        The obstacles.
    dt : float
        The model's step (s): a trajectory's cost is its steps times ``dt``.
    input_low, input_high : numpy.ndarray
        The actions' bounds.
    state_low, state_high : numpy.ndarray
        The state's bounds (``±inf`` where free; the position's are the workspace's).
    bodies : tuple of tuple
        The boxes' ``(length, width)``: the vehicle's, then a trailer's.
    weights : numpy.ndarray
        The weights of the model's distance.
    hitch : float
        A trailer's hitch length (0 without).
    wheelbase : float
        A car's wheelbase (0 for a unicycle).
    """

    name: str
    path: Path
    robot: str
    dynamics: str
    start: np.ndarray
    goal: np.ndarray
    low: np.ndarray
    high: np.ndarray
    obstacles: tuple
    dt: float
    input_low: np.ndarray
    input_high: np.ndarray
    state_low: np.ndarray
    state_high: np.ndarray
    bodies: tuple
    weights: np.ndarray
    hitch: float = 0.0
    wheelbase: float = 0.0

    @property
    def mechanism(self) -> str:
        """The catalog mechanism the instance is planned as."""
        return MECHANISMS[self.dynamics]


def read_yaml(path: Path, what: str) -> dict:
    """A YAML file's top-level mapping (``yaml.safe_load``: data only).

    Parameters
    ----------
    path : Path
        The file.
    what : str
        What it should be, for messages.

    Returns
    -------
    dict
        Its mapping.

    Raises
    ------
    ValueError
        Naming the file: missing, too large, not text, not YAML, not a mapping.
    """
    import yaml

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: no such {what} file")
    if path.stat().st_size > MAX_BYTES:
        raise ValueError(f"{path}: more than {MAX_BYTES} bytes: not a {what} file")
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f", line {mark.line + 1}" if mark is not None else ""
        raise ValueError(f"{path}{where}: not YAML: {getattr(exc, 'problem', exc)}") from None
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not text") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path}: a {what} file holds a mapping of fields, got {type(data).__name__}")
    return data


def _field(data: dict, key: str, path: Path, where: str = ""):
    if key not in data:
        raise ValueError(f"{path}: {where}{key} is missing")
    return data[key]


def _numbers(value, key: str, path: Path, size: int | None = None) -> np.ndarray:
    """A list of finite numbers (``size`` of them)."""
    if not isinstance(value, (list, tuple)) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        raise ValueError(f"{path}: {key} must be a list of numbers, got {value!r}")
    out = np.array(value, dtype=float)
    if not np.all(np.isfinite(out)):
        raise ValueError(f"{path}: {key} must be finite, got {value!r}")
    if size is not None and out.size != size:
        raise ValueError(f"{path}: {key} must hold {size} numbers, got {out.size}")
    return out


def _number(value, key: str, path: Path, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{path}: {key} must be a finite number, got {value!r}")
    if positive and value <= 0:
        raise ValueError(f"{path}: {key} must be positive, got {value!r}")
    return float(value)


def model_path(env: Path, robot: str, models: Path | None = None) -> Path:
    """The model file of ``robot`` for the env file ``env``: in ``models`` if given, else in
    ``../../models/`` from the env file (a checkout's layout, and that of the copies under
    ``benchmarks/dynobench/``).

    Parameters
    ----------
    env : Path
        The env file.
    robot : str
        The robot type.
    models : Path, optional
        The folder of model files.

    Returns
    -------
    Path
        The model file (which may not exist).
    """
    folder = Path(models) if models is not None else Path(env).resolve().parent.parent.parent / "models"
    return folder / f"{robot}.yaml"


def load(path, models=None) -> Instance:
    """The Dynobench instance of an env file (see the module).

    Parameters
    ----------
    path : str or os.PathLike
        The env file, ``envs/<robot>/<instance>.yaml`` in a Dynobench checkout or under
        ``benchmarks/dynobench/``.
    models : str or os.PathLike, optional
        The folder of model files (default: :func:`model_path`'s).

    Returns
    -------
    Instance
        The instance.

    Raises
    ------
    ValueError
        Naming the file and the field: a file that is missing, not YAML or too large; a
        field missing or malformed; an unknown robot type or dynamics; more than one robot;
        an obstacle that is not a box; a start or goal of the wrong size, outside the
        workspace or the state's bounds, or whose body overlaps an obstacle.
    """
    path = Path(path)
    env = read_yaml(path, "Dynobench env")
    unknown = set(env) - {"name", "environment", "robots"}
    if unknown:
        raise ValueError(f"{path}: {sorted(unknown)[0]} is not a field of a Dynobench env file "
                         "(name, environment, robots)")
    world = _field(env, "environment", path)
    if not isinstance(world, dict):
        raise ValueError(f"{path}: environment must be a mapping, got {type(world).__name__}")
    low = _numbers(_field(world, "min", path, "environment."), "environment.min", path, 2)
    high = _numbers(_field(world, "max", path, "environment."), "environment.max", path, 2)
    if np.any(low >= high):
        raise ValueError(f"{path}: environment.min must be below environment.max, got {low.tolist()} and "
                         f"{high.tolist()}")
    obstacles = []
    for i, obstacle in enumerate(world.get("obstacles") or []):
        key = f"environment.obstacles[{i}]"
        if not isinstance(obstacle, dict):
            raise ValueError(f"{path}: {key} must be a mapping, got {obstacle!r}")
        if obstacle.get("type") != "box":
            raise ValueError(f"{path}: {key}.type must be 'box', got {obstacle.get('type')!r}")
        center = _numbers(_field(obstacle, "center", path, key + "."), key + ".center", path, 2)
        size = _numbers(_field(obstacle, "size", path, key + "."), key + ".size", path, 2)
        if np.any(size <= 0):
            raise ValueError(f"{path}: {key}.size must be positive, got {size.tolist()}")
        obstacles.append(Box(tuple(center), tuple(size)))
    robots = _field(env, "robots", path)
    if not isinstance(robots, list) or len(robots) != 1 or not isinstance(robots[0], dict):
        raise ValueError(f"{path}: robots must be a list of one robot (a mapping), got {robots!r}")
    robot = robots[0]
    kind = _field(robot, "type", path, "robots[0].")
    if not isinstance(kind, str) or not kind.replace("_", "").isalnum():
        raise ValueError(f"{path}: robots[0].type must be a robot's name, got {kind!r}")
    model_file = model_path(path, kind, models)
    if not model_file.is_file():
        raise ValueError(f"{path}: robots[0].type: unknown robot type {kind!r} (no model file {model_file})")
    model = read_yaml(model_file, "Dynobench model")
    dynamics = _field(model, "dynamics", model_file)
    if dynamics not in MECHANISMS:
        raise ValueError(f"{model_file}: dynamics: {dynamics!r} is not one of {', '.join(MECHANISMS)}")
    n = STATE_SIZES[dynamics]
    start = _numbers(_field(robot, "start", path, "robots[0]."), "robots[0].start", path, n)
    goal = _numbers(_field(robot, "goal", path, "robots[0]."), "robots[0].goal", path, n)
    dt = _number(_field(model, "dt", model_file), "dt", model_file, positive=True)
    number = lambda key: _number(_field(model, key, model_file), key, model_file)
    size = _numbers(_field(model, "size", model_file), "size", model_file, 2)
    bodies = [tuple(size)]
    hitch = wheelbase = 0.0
    state_low, state_high = np.full(n, -np.inf), np.full(n, np.inf)
    state_low[:2], state_high[:2] = low, high
    if dynamics == "unicycle1":
        input_low = np.array([number("min_vel"), number("min_angular_vel")])
        input_high = np.array([number("max_vel"), number("max_angular_vel")])
        weights = _numbers(_field(model, "distance_weights", model_file), "distance_weights", model_file, 2)
    elif dynamics == "unicycle2":
        input_high = np.array([number("max_acc_abs"), number("max_angular_acc")])
        input_low = -input_high
        state_low[3:] = number("min_vel"), number("min_angular_vel")
        state_high[3:] = number("max_vel"), number("max_angular_vel")
        weights = _numbers(_field(model, "distance_weights", model_file), "distance_weights", model_file, 4)
    else:
        if _field(model, "num_trailers", model_file) != 1:
            raise ValueError(f"{model_file}: num_trailers: only one trailer is read, got "
                             f"{model.get('num_trailers')!r}")
        steer = number("max_steering_abs")
        input_low = np.array([number("min_vel"), -steer])
        input_high = np.array([number("max_vel"), steer])
        hitch = float(_numbers(_field(model, "hitch_lengths", model_file), "hitch_lengths", model_file, 1)[0])
        wheelbase = _number(_field(model, "l", model_file), "l", model_file, positive=True)
        bodies.append(tuple(_numbers(_field(model, "size_trailer", model_file), "size_trailer", model_file, 2)))
        weights = _numbers(_field(model, "distance_weights", model_file), "distance_weights", model_file, 3)
    if np.any(input_low > input_high):
        raise ValueError(f"{model_file}: the input bounds have low > high: {input_low.tolist()} > "
                         f"{input_high.tolist()}")
    instance = Instance(name=path.stem, path=path, robot=kind, dynamics=dynamics, start=start, goal=goal,
                        low=low, high=high, obstacles=tuple(obstacles), dt=dt, input_low=input_low,
                        input_high=input_high, state_low=state_low, state_high=state_high,
                        bodies=tuple(bodies), weights=weights, hitch=hitch, wheelbase=wheelbase)
    from .checker import state_clearance

    for key, state in (("start", start), ("goal", goal)):
        if np.any(state < state_low) or np.any(state > state_high):
            raise ValueError(f"{path}: robots[0].{key} {state.tolist()} is outside the workspace or the "
                             f"state's bounds")
        clearance, which = state_clearance(instance, state)
        if clearance < 0.0:
            raise ValueError(f"{path}: robots[0].{key}: the robot's body overlaps obstacle {which} "
                             f"(by {-clearance:.3g})")
    return instance
