"""The planning problem as one object: mechanism, start, goal, horizon, parametrisation,
constraints, objective and the solver's settings, checked once when it is built.

:func:`nonholo.plan` builds a :class:`Problem` from its keywords (:meth:`Problem.build`)
and hands it to :func:`nonholo.planning.api.solve`; the strategies, the global route and
the least-energy stage read what they need from it, and the route plans its hops as
problems of their own (:meth:`Problem.part`). Constraints are objects in a list
(:mod:`nonholo.planning.constraint_objects`).
"""
from __future__ import annotations

import dataclasses
import importlib
from dataclasses import asdict, dataclass


from ..certify.certificate import MAX_REPLAY_STEPS
from ..controls import stages
from ..controls.parametrisations import (
    Controls,
    Fourier,
    PiecewiseConstant,
    paper_initial,
)
from ..model import catalog
from ..model.mechanism import Mechanism
from ..spaces.state import State
from ..motion.simulation import DEFAULT_STEPS
from ..motion.time_scaling import check_horizon
from ..numerics.checks import check_count, check_time
from ..model.bounds import InputBounds, StateBounds, of_mechanism
from ..model.limits import Limits
from .constraint_objects import KINDS, Clearance, LegSpeed, LegStroke, check_all, one_of
from .core import EndpointMap, Options, Strategy
from .strategy_paper import PaperStrategy
from .strategy_robust import RobustStrategy

METHODS = ("parametric", "nonparametric")
#: The routes :func:`nonholo.plan` takes to a goal.
ROUTES = ("auto", "local", "global")
#: The most numbers the Fourier basis at the integrator's stages (``3·steps × (2·harmonics + 1)``)
#: may hold: 2·10⁷ (160 MB); the planner keeps a few arrays of that size.
MAX_BASIS = 2 * 10**7
#: What :func:`nonholo.plan` optimises once the goal is reached: nothing (the plan as found),
#: the energy ∫|u|² dt, or the plan unless a quick search finds a motion of far less energy
#: (:func:`nonholo.planning.energy.improve`).
OBJECTIVES = (None, "energy", "auto")
#: The most ``grid`` intervals and integrator ``steps`` a plan may take: half the finest
#: certified replay (:data:`~nonholo.certify.certificate.MAX_REPLAY_STEPS`), which is on at
#: least twice the planner's steps. A plan on more could never be certified: it would spend
#: its whole ``max_iter``, each step ~``steps`` long, for a certain failure.
MAX_PLAN_STEPS = MAX_REPLAY_STEPS // 2
#: The strategies :func:`nonholo.plan` knows by name.
STRATEGIES: dict[str, type[Strategy]] = {"paper": PaperStrategy, "robust": RobustStrategy}
#: The planning horizon (s) of a plan asked for in the least time (``T=None``): the path is
#: planned in this time, then re-timed (:mod:`nonholo.planning.retime`).
PLANNING_TIME = 1.0


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


def least_time_bounds(given: tuple, mechanism) -> tuple:
    """The mechanism's own bounds a plan in the least time keeps besides ``given``: each kind
    (:class:`~nonholo.model.bounds.InputBounds`, :class:`~nonholo.model.bounds.StateBounds`)
    the caller did not give.

    Parameters
    ----------
    given : tuple
        The caller's constraints, checked.
    mechanism : Mechanism
        The mechanism planned.

    Returns
    -------
    tuple
        The bounds of :func:`~nonholo.model.bounds.of_mechanism` not given already.
    """
    kinds = {type(c) for c in given}
    return tuple(b for b in of_mechanism(mechanism) if type(b) not in kinds)


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


@dataclass(frozen=True, eq=False)
class Problem:
    """One planning problem, checked (see the module; build it with :meth:`build`). A
    problem holds no clock: the budgets of effort start when it is solved.

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.
    start, goal : State
        Start and goal (:class:`~nonholo.spaces.state.State`).
    T : float
        The horizon (s).
    objective : {None, "energy", "auto"}
        What is lowered once the plan is found.
    constraints : tuple
        What the motion keeps (:mod:`nonholo.planning.constraint_objects`), a
        :class:`~nonholo.planning.constraint_objects.Clearance` always among them.
    settings : Settings
        The parametrisation and the solver's numbers, ``steps`` resolved.
    strategy_class : type
        The :class:`~nonholo.planning.core.Strategy` subclass.
    route : {"auto", "local", "global"}
        The route (see :func:`nonholo.plan`).
    controls : Controls
        The physical initial guess.
    u0_given : bool
        Whether the initial guess is the caller's (not the strategy's default).
    least_time : bool
        ``T`` is the planning horizon of a plan re-timed in the least time.
    """

    mechanism: Mechanism
    start: State
    goal: State
    T: float
    objective: str | None
    constraints: tuple
    settings: Settings
    strategy_class: type[Strategy]
    route: str = "auto"
    controls: Controls | None = None
    u0_given: bool = False
    least_time: bool = False

    @classmethod
    def build(cls, start, goal, *, mechanism="platform", T: float | None = 1.0, objective: str | None = "auto",
              constraints=(), strategy="robust", route: str = "auto", settings=None, u0=None,
              allow_imports: bool = False) -> "Problem":
        """The problem of :func:`nonholo.plan`'s arguments, checked.

        Parameters
        ----------
        start, goal, mechanism, T, objective, constraints, strategy, route, settings, u0
            As for :func:`nonholo.plan`.
        allow_imports : bool
            As for :func:`nonholo.plan`.

        Returns
        -------
        Problem
            The problem, every argument checked.

        Raises
        ------
        ValueError
            For bad input, naming the argument; ``start``/``goal`` outside the
            :class:`~nonholo.model.bounds.StateBounds`, naming the coordinate.
        TypeError
            For ``constraints`` that are not constraint objects, ``settings`` of another
            type, or an ``allow_imports`` that is not a bool.
        """
        mech = catalog.get(mechanism)
        settings = Settings.of(settings)
        given = check_all(constraints, mech)
        for kind in KINDS:
            one_of(given, kind)
        if one_of(given, Clearance) is None:
            given = (Clearance(DEFAULT_CLEARANCE),) + given
        speed = one_of(given, LegSpeed)
        if T is None and speed is None:
            given = given + least_time_bounds(given, mech)
            if not any(isinstance(c, InputBounds) and not c.free for c in given):
                raise ValueError(f"T=None asks for the least time, which needs a LegSpeed (a platform's) or "
                                 f"InputBounds in constraints to re-time the path under; mechanism "
                                 f"{mech.name!r} has no input bounds of its own")
        if speed is not None and any(isinstance(c, InputBounds) and not c.free for c in given):
            raise ValueError("LegSpeed and InputBounds cannot be kept together yet (each re-times the path "
                             "on its own): give one of them")
        if not one_of_choices(objective, OBJECTIVES):
            raise ValueError(f"unknown objective {objective!r}; known: None, 'energy', 'auto'")
        if not one_of_choices(route, ROUTES):
            raise ValueError(f"unknown route {route!r}; known: {', '.join(ROUTES)}")
        solver = check_strategy(strategy, allow_imports)
        least_time = T is None
        T = check_horizon(PLANNING_TIME if least_time else T)
        start = mech.parse_state(start, "start")
        goal = mech.parse_state(goal, "goal")
        for c in given:
            if isinstance(c, StateBounds):
                for name, state, what in (("start", start, "the start"), ("goal", goal, "the goal")):
                    outside = c.violation(mech, state, what)
                    if outside is not None:
                        raise ValueError(f"{name}: {outside}")
        if mech.singular.value(*start) == 0.0:
            raise ValueError(mech.singular.refusal)
        # the certificate replays on twice the steps: at most half its finest replay
        method, harmonics, grid = settings.method, settings.harmonics, settings.grid
        steps = default_steps(method, grid) if settings.steps is None else settings.steps
        if method == "parametric" and 2 * harmonics > steps:
            raise ValueError(f"harmonics = {harmonics} is more than the integrator's steps = {steps} "
                             "can resolve (at most steps/2; raise steps or lower harmonics)")
        basis = 3 * steps * (2 * harmonics + 1) if method == "parametric" else 0
        if basis > MAX_BASIS:
            raise ValueError(f"harmonics = {harmonics} on steps = {steps}: the Fourier basis at the "
                             f"integrator's stages would hold {basis:.3g} numbers ({8 * basis / 2**30:.3g} GiB), "
                             f"more than {MAX_BASIS:.0e}; lower harmonics or steps")
        controls = initial_controls(method, T, mech.n_inputs, harmonics, grid, u0)
        stages.check_steps(controls, steps)
        return cls(mechanism=mech, start=start, goal=goal, T=T, objective=objective, constraints=given,
                   settings=dataclasses.replace(settings, steps=steps), strategy_class=solver, route=route,
                   controls=controls, u0_given=u0 is not None, least_time=least_time)

    def part(self, start, goal, T: float, delta_min: float, strategy) -> "Problem":
        """A part of the global route, ``start → goal`` in ``T``, planned locally with
        ``strategy`` and the clearance ``delta_min``, under this problem's other constraints
        but the legs' speed (kept by the whole plan's re-timing), with no objective: the same
        settings.

        Parameters
        ----------
        start, goal : State or tuple
            States ``(R, q)``.
        T : float
            The part's horizon (s).
        delta_min : float
            The part's clearance from ``Δ = 0``.
        strategy : str or type
            The part's strategy.

        Returns
        -------
        Problem
            The part.
        """
        mech = self.mechanism
        s = self.settings
        controls = initial_controls(s.method, T, mech.n_inputs, s.harmonics, s.grid)
        kept = tuple(c for c in self.constraints if not isinstance(c, (Clearance, LegSpeed, InputBounds)))
        return dataclasses.replace(
            self, start=State.of(start), goal=State.of(goal), T=check_time(T),
            controls=controls, u0_given=False, strategy_class=strategy_class(strategy),
            constraints=(Clearance(delta_min),) + kept, objective=None, route="local", least_time=False)

    def with_settings(self, **changes) -> "Problem":
        """The same problem with some settings changed.

        Parameters
        ----------
        **changes
            Fields of :class:`Settings`.

        Returns
        -------
        Problem
            The problem with the new settings.
        """
        return dataclasses.replace(self, settings=dataclasses.replace(self.settings, **changes))

    # -- the settings by name ---------------------------------------------------------------

    @property
    def method(self) -> str:
        """The parametrisation: ``"parametric"`` or ``"nonparametric"``."""
        return self.settings.method

    @property
    def harmonics(self) -> int:
        """Harmonics of the parametric form."""
        return self.settings.harmonics

    @property
    def grid(self) -> int:
        """Intervals of the nonparametric form."""
        return self.settings.grid

    @property
    def steps(self) -> int:
        """CF4 steps on ``[0, T]``."""
        return self.settings.steps

    @property
    def gamma_given(self) -> bool:
        """Whether γ is the caller's (not the strategy's default)."""
        return self.settings.gamma is not None

    @property
    def options(self) -> Options:
        """The solver's :class:`~nonholo.planning.core.Options`: the settings, γ (the
        strategy's default unless given) and the clearance."""
        return self.settings.options(self.strategy_class.default_gamma, self.delta_min)

    # -- what the planner reads ---------------------------------------------------------

    def evaluator(self, frame: bool = False, method: str | None = None, steps: int | None = None,
                  delta_min: float | None = None) -> EndpointMap:
        """The :class:`~nonholo.planning.core.EndpointMap` of this problem: its start, goal,
        horizon, clearance and stroke.

        Parameters
        ----------
        frame : bool
            Controls in the frame coordinates (else the physical inputs).
        method : str, optional
            ``"parametric"`` or ``"nonparametric"`` (default: the problem's).
        steps : int, optional
            Integrator steps on ``[0, T]`` (default: the problem's).
        delta_min : float, optional
            A clearance from ``Δ = 0`` at least the problem's (default: the problem's).

        Returns
        -------
        EndpointMap
            The evaluator.
        """
        return EndpointMap(self.start, self.goal, self.T, self.mechanism, method or self.method,
                         self.steps if steps is None else steps,
                         self.delta_min if delta_min is None else max(delta_min, self.delta_min),
                         frame=frame,
                         limits=self.limits)

    @property
    def strategy(self) -> str:
        """The strategy's name."""
        return self.strategy_class.name

    @property
    def delta_min(self) -> float:
        """The clearance from ``Δ = 0`` the motion keeps."""
        return one_of(self.constraints, Clearance).delta_min

    @property
    def leg_limits(self):
        """The legs' stroke limits (:class:`~nonholo.model.limits.LegLimits`), or ``None``."""
        stroke = one_of(self.constraints, LegStroke)
        return None if stroke is None else stroke.limits

    @property
    def leg_speed(self) -> float | None:
        """The legs' top speed, or ``None``."""
        speed = one_of(self.constraints, LegSpeed)
        return None if speed is None else speed.v

    @property
    def input_bounds(self) -> InputBounds | None:
        """The inputs' bounds (:class:`~nonholo.model.bounds.InputBounds`), or ``None``
        (also for bounds free everywhere)."""
        bounds = one_of(self.constraints, InputBounds)
        return None if bounds is None or bounds.free else bounds

    @property
    def state_bounds(self) -> StateBounds | None:
        """The coordinates' bounds (:class:`~nonholo.model.bounds.StateBounds`), or ``None``
        (also for bounds free everywhere)."""
        bounds = one_of(self.constraints, StateBounds)
        return None if bounds is None or bounds.free else bounds

    @property
    def limits(self) -> Limits | None:
        """The clearances every node keeps (:class:`~nonholo.model.limits.Limits`: the legs'
        stroke, the coordinates' bounds), or ``None``."""
        return Limits.of(self.leg_limits, self.state_bounds)

    def recorded_options(self) -> dict:
        """The options a result records.

        Returns
        -------
        dict
            :class:`~nonholo.planning.core.Options`, ``harmonics``, ``grid`` and, when set,
            ``leg_length``, ``input_bounds`` and ``state_bounds``
            (:meth:`~nonholo.model.bounds.Box.record`).
        """
        limits = self.leg_limits
        extra = {} if limits is None else {"leg_length": list(limits.as_tuple())}
        for key, bounds in (("input_bounds", self.input_bounds), ("state_bounds", self.state_bounds)):
            if bounds is not None:
                extra[key] = bounds.record()
        return {**asdict(self.options), "harmonics": self.harmonics, "grid": self.grid, **extra}
