"""The numerical settings of a plan and the checks of single arguments of :func:`nonholo.plan`:
:class:`Settings` (the parametrisation and the solver's numbers), the strategies by name
(:data:`STRATEGIES`, :func:`strategy_class`, :func:`check_strategy`), the initial control
(:func:`initial_controls`, :func:`default_steps`), and the flat options of a problem table,
a plan file or the command line turned into :func:`nonholo.plan`'s keywords
(:func:`arguments_of`). The problem they are part of is
:class:`nonholo.planning.problem.Problem`.
"""
from __future__ import annotations

import dataclasses
import importlib
from dataclasses import dataclass

from ..certify.certificate import MAX_REPLAY_STEPS
from ..controls.parametrisations import (
    Controls,
    Fourier,
    PiecewiseConstant,
    paper_initial,
)
from ..model import catalog
from ..motion.simulation import DEFAULT_STEPS
from ..numerics.checks import check_count
from .constraint_objects import Clearance, LegSpeed, LegStroke
from .core import Options, Strategy
from .strategy_paper import PaperStrategy
from .strategy_robust import RobustStrategy

METHODS = ("parametric", "nonparametric")
#: The most ``grid`` intervals and integrator ``steps`` a plan may take: half the finest
#: certified replay (:data:`~nonholo.certify.certificate.MAX_REPLAY_STEPS`), which is on at
#: least twice the planner's steps. A plan on more could never be certified: it would spend
#: its whole ``max_iter``, each step ~``steps`` long, for a certain failure.
MAX_PLAN_STEPS = MAX_REPLAY_STEPS // 2
#: The strategies :func:`nonholo.plan` knows by name.
STRATEGIES: dict[str, type[Strategy]] = {"paper": PaperStrategy, "robust": RobustStrategy}


def one_of_choices(value, choices) -> bool:
    """Whether ``value`` is one of ``choices``, compared only as a string or None.

    Parameters
    ----------
    value : object
        What the caller passed (an array or a dict is simply not a choice: ``==`` would
        compare it elementwise or fail to hash).
    choices : sequence of str or None
        The known names.

    Returns
    -------
    bool
        Whether ``value`` is one of them.
    """
    return (value is None or isinstance(value, str)) and value in choices


def is_import_path(strategy) -> bool:
    """Whether ``strategy`` names a strategy by its import path ``"package.module:Class"``
    (resolving it imports the module and runs its top-level code).

    Parameters
    ----------
    strategy : object
        What the caller passed as ``strategy``.

    Returns
    -------
    bool
        ``True`` for a string with a colon that is not a name of :data:`STRATEGIES`.
    """
    return isinstance(strategy, str) and strategy not in STRATEGIES and ":" in strategy


def check_strategy(strategy, allow_imports: bool) -> type[Strategy]:
    """:func:`strategy_class` of what a caller of :func:`nonholo.plan` passed: an import
    path only with the caller's ``allow_imports=True``. A strategy's name read from a file
    (a plan file's label, a problem table's option) is data: it never imports code unless
    the caller opts in.

    Parameters
    ----------
    strategy : str or type
        As for :func:`strategy_class`.
    allow_imports : bool
        Whether an import path may be imported.

    Returns
    -------
    type
        The :class:`~nonholo.planning.core.Strategy` subclass.

    Raises
    ------
    ValueError
        Naming ``strategy``, for an import path without ``allow_imports`` (nothing is
        imported), or as :func:`strategy_class`.
    TypeError
        If ``allow_imports`` is not ``True`` or ``False``.
    """
    if not isinstance(allow_imports, bool):
        raise TypeError(f"allow_imports must be True or False, got {allow_imports!r}")
    if is_import_path(strategy) and not allow_imports:
        raise ValueError(f"strategy {strategy!r} is an import path, which would import the module "
                         f"{strategy.partition(':')[0]!r} and run its code; known strategies: "
                         f"{', '.join(STRATEGIES)}, or pass a Strategy subclass, or opt in with "
                         "allow_imports=True (nonholo plan --allow-imports) if you trust the name")
    return strategy_class(strategy)


def strategy_class(strategy) -> type[Strategy]:
    """The strategy a name or a class stands for. This resolver imports an import path
    when given one; :func:`nonholo.plan` asks its caller's opt-in first
    (:func:`check_strategy`).

    Parameters
    ----------
    strategy : str or type
        A :class:`~nonholo.planning.core.Strategy` subclass, a name of :data:`STRATEGIES`,
        or an import path ``"package.module:Class"``.

    Returns
    -------
    type
        The :class:`~nonholo.planning.core.Strategy` subclass.

    Raises
    ------
    ValueError
        For an unknown name (listing the known ones), a path that cannot be imported, or
        a class that is not a strategy.
    """
    if isinstance(strategy, type) and issubclass(strategy, Strategy):
        return strategy
    if isinstance(strategy, str) and strategy in STRATEGIES:
        return STRATEGIES[strategy]
    if isinstance(strategy, str) and ":" in strategy:
        module, _, qualname = strategy.partition(":")
        try:
            found = importlib.import_module(module)
            for part in qualname.split("."):
                found = getattr(found, part)
        except (ImportError, AttributeError, ValueError) as exc:
            raise ValueError(f"strategy {strategy!r} cannot be imported: {exc}") from None
        if isinstance(found, type) and issubclass(found, Strategy):
            return found
        raise ValueError(f"strategy {strategy!r} is not a Strategy subclass")
    raise ValueError(f"unknown strategy {strategy!r}; known: {', '.join(STRATEGIES)} "
                     "(or pass a Strategy subclass)")


def initial_controls(method: str, T: float, n_inputs: int, harmonics: int, grid: int, u0=None) -> Controls:
    """The initial control in the parametrisation of ``method``.

    Parameters
    ----------
    method : {"parametric", "nonparametric"}
        The parametrisation: Fourier series or piecewise constant.
    T : float
        The horizon (s).
    n_inputs : int
        The mechanism's inputs.
    harmonics, grid : int
        The size of the parametrisation.
    u0 : optional
        ``None`` (the examples' ``u_1 = 0.3 sin 2πt/T``, ``u_2 = 0.3 cos 2πt/T``), a
        :class:`~nonholo.controls.parametrisations.Controls` of the right kind and size,
        or a vectorised function ``u(t)`` (projected: least squares on the Fourier basis,
        interval means on the grid).

    Returns
    -------
    Controls
        The initial control.

    Raises
    ------
    ValueError
        For a ``u0`` of another kind, size, horizon or number of inputs, or that is
        neither controls nor a function.
    """
    kind, size = (Fourier, harmonics) if method == "parametric" else (PiecewiseConstant, grid)
    if isinstance(u0, Controls):
        if not isinstance(u0, kind):
            raise ValueError(f"u0 is a {type(u0).__name__}, method {method!r} needs a {kind.__name__}")
        if u0.T != T or u0.n_inputs != n_inputs:
            raise ValueError(f"u0 is defined for T = {u0.T:g}, m = {u0.n_inputs}; the problem has "
                             f"T = {T:g}, m = {n_inputs}")
        got = u0.harmonics if kind is Fourier else u0.grid
        if got != size:
            what = "harmonics" if kind is Fourier else "grid"
            raise ValueError(f"u0 has {what} = {got}, the planner was asked for {what} = {size}")
        return u0
    func = paper_initial(T, n_inputs) if u0 is None else u0
    if not callable(func):
        raise ValueError("u0 must be None, a nonholo.controls.parametrisations.Controls or a function u(t)")
    return kind.fit(func, T, size, n_inputs)


def default_steps(method: str, grid: int) -> int:
    """The default CF4 steps of a plan.

    Parameters
    ----------
    method : {"parametric", "nonparametric"}
        The parametrisation.
    grid : int
        Intervals of the nonparametric form.

    Returns
    -------
    int
        :data:`~nonholo.motion.simulation.DEFAULT_STEPS`, rounded up to a multiple of
        ``grid`` for grid controls.
    """
    if method == "nonparametric":
        return -(-DEFAULT_STEPS // grid) * grid
    return DEFAULT_STEPS


#: The clearance from ``Δ = 0`` a plan keeps when ``constraints`` hold no
#: :class:`~nonholo.planning.constraint_objects.Clearance`.
DEFAULT_CLEARANCE = 1e-2


@dataclass(frozen=True)
class Settings:
    """The numerical settings of a plan: its parametrisation and the solver's numbers.

    Parameters
    ----------
    method : {"parametric", "nonparametric"}
        Fourier series with ``harmonics`` = K, or piecewise constant on ``grid`` equal
        intervals (of the physical inputs ``u`` for ``"paper"``, of the frame coordinates
        ``w`` for ``"robust"``).
    harmonics : int
        Harmonics K of the parametric form.
    grid : int
        Intervals of the nonparametric form (at most :data:`MAX_PLAN_STEPS`).
    steps : int, optional
        CF4 steps on ``[0, T]`` (default :func:`default_steps`; at most
        :data:`MAX_PLAN_STEPS`, the most a certificate replays).
    gamma : float, optional
        γ: each flow step asks the error to shrink by ``γh`` (default: the strategy's
        ``default_gamma``).
    step : float
        The initial θ-step h.
    tol : float
        Stop when the terminal error is at most this (the state's units).
    max_iter : int
        Accepted steps at most.
    newton_below : float
        Below this error take full Newton steps (``γh = 1``).
    min_step : float
        Give up when a step halved below this ``γh``.

    Raises
    ------
    ValueError
        For bad settings, naming the one.
    """

    method: str = "parametric"
    harmonics: int = 2
    grid: int = 100
    steps: int | None = None
    gamma: float | None = None
    step: float = 1.0
    tol: float = 1e-10
    max_iter: int = 200
    newton_below: float = 1e-3
    min_step: float = 1e-6

    def __post_init__(self):
        if not one_of_choices(self.method, METHODS):
            raise ValueError(f"unknown method {self.method!r}; known: {', '.join(METHODS)}")
        object.__setattr__(self, "harmonics", check_count(self.harmonics, "harmonics"))
        object.__setattr__(self, "grid", check_count(self.grid, "grid", maximum=MAX_PLAN_STEPS))
        if self.steps is not None:
            object.__setattr__(self, "steps", check_count(self.steps, "steps", maximum=MAX_PLAN_STEPS))
        self.options(1.0 if self.gamma is None else self.gamma, DEFAULT_CLEARANCE)     # the numbers' checks

    def options(self, gamma: float, delta_min: float) -> Options:
        """The solver's :class:`~nonholo.planning.core.Options` of these settings.

        Parameters
        ----------
        gamma : float
            γ, where the settings leave it to the strategy.
        delta_min : float
            The clearance kept.

        Returns
        -------
        Options
            The options, checked.
        """
        return Options(gamma=gamma if self.gamma is None else self.gamma, step=self.step, tol=self.tol,
                       max_iter=self.max_iter, newton_below=self.newton_below, min_step=self.min_step,
                       delta_min=delta_min)

    @classmethod
    def of(cls, value) -> "Settings":
        """``settings`` as :func:`nonholo.plan` takes it: ``None`` (the defaults), a
        :class:`Settings`, or a mapping of its fields.

        Parameters
        ----------
        value : Settings, dict or None
            The caller's settings.

        Returns
        -------
        Settings
            The settings, checked.

        Raises
        ------
        ValueError
            Naming ``settings``, for an unknown field.
        TypeError
            For anything else.
        """
        if value is None:
            return cls()
        if isinstance(value, cls):
            return value
        if isinstance(value, dict):
            known = {f.name for f in dataclasses.fields(cls)}
            unknown = sorted(set(value) - known)
            if unknown:
                raise ValueError(f"settings: unknown setting {unknown[0]!r}; known: {', '.join(sorted(known))}")
            return cls(**value)
        raise TypeError(f"settings must be a nonholo.Settings, a dict of its fields or None, got {value!r}")


#: The names of :class:`Settings`' fields.
SETTINGS_FIELDS = tuple(f.name for f in dataclasses.fields(Settings))


def arguments_of(options: dict, mechanism) -> dict:
    """:func:`nonholo.plan`'s keyword arguments for options in their flat form (a problem
    table's ``options``, a plan file's recorded options, the command line's flags):
    ``delta_min``, ``leg_length`` and ``leg_speed`` become constraint objects, the fields of
    :class:`Settings` one ``settings``; the rest pass as they are.

    Parameters
    ----------
    options : dict
        The flat options.
    mechanism : str or Mechanism
        The mechanism planned (the legs' constraints are checked against it).

    Returns
    -------
    dict
        Keyword arguments of :func:`nonholo.plan`.

    Raises
    ------
    ValueError
        Naming the option, for a bad value.
    """
    mech = catalog.get(mechanism)
    out, settings = {}, {}
    constraints = list(options.get("constraints") or ())
    for key, value in options.items():
        if key in SETTINGS_FIELDS:
            settings[key] = value
        elif key == "delta_min":
            constraints.append(Clearance(value))
        elif key in ("leg_length", "leg_speed"):
            c = (LegStroke if key == "leg_length" else LegSpeed).of(value, mech)
            if c is not None:
                constraints.append(c)
        elif key != "constraints":
            out[key] = value
    if settings:
        out["settings"] = Settings(**settings)
    if constraints:
        out["constraints"] = constraints
    return out
