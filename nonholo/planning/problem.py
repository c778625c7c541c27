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
import time
from dataclasses import asdict, dataclass

import numpy as np

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
from ..motion.simulation import DEFAULT_STEPS
from ..motion.time_change import check_horizon
from ..numerics import effort
from ..numerics.checks import check_count, check_time
from ..model.bounds import InputBounds, StateBounds, of_mechanism
from ..model.limits import Limits
from .constraint_objects import KINDS, Clearance, LegSpeed, LegStroke, check_all, one_of
from .core import Evaluator, Options, Strategy
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


@dataclass(frozen=True, eq=False)
class Problem:
    """One planning problem, checked (see the module; build it with :meth:`build`).

    Parameters
    ----------
    mechanism : Mechanism
        The mechanism.
    R0, q0, Rd, qd : numpy.ndarray
        Start and goal as states ``(R, q)`` (:mod:`nonholo.spaces.groups`).
    T : float
        The horizon (s).
    method, harmonics, grid : str, int, int
        The parametrisation of the planned control.
    controls : Controls
        Its physical initial guess.
    u0_given, gamma_given : bool
        Whether the initial guess, and ``options.gamma``, are the caller's (not the
        strategy's defaults).
    strategy_class : type
        The :class:`~nonholo.planning.core.Strategy` subclass.
    options : Options
        The solver's settings.
    steps : int
        CF4 steps on ``[0, T]``.
    constraints : tuple
        What the motion keeps (:mod:`nonholo.planning.constraint_objects`).
    objective : {None, "energy", "auto"}
        What is lowered once the plan is found.
    route : {"auto", "local", "global"}
        The route (see :func:`nonholo.plan`).
    least_time : bool
        ``T`` is the planning horizon of a plan re-timed in the least time.
    started, started_effort : float
        When the problem was built (for the result's ``seconds`` and the global route's
        budget of effort, :mod:`nonholo.numerics.effort`).
    """

    mechanism: Mechanism
    R0: np.ndarray
    q0: np.ndarray
    Rd: np.ndarray
    qd: np.ndarray
    T: float
    method: str
    harmonics: int
    grid: int
    controls: Controls
    u0_given: bool
    gamma_given: bool
    strategy_class: type[Strategy]
    options: Options
    steps: int
    constraints: tuple = ()
    objective: str | None = "auto"
    route: str = "auto"
    least_time: bool = False
    started: float = dataclasses.field(default_factory=time.perf_counter)
    started_effort: float = dataclasses.field(default_factory=effort.seconds)

    @classmethod
    def build(cls, R0, Rd, *, T: float | None = 1.0, method: str = "parametric", harmonics: int = 2,
              grid: int = 100, u0=None, gamma: float | None = None, step: float = 1.0, tol: float = 1e-10,
              max_iter: int = 200, strategy="robust", mechanism="platform", delta_min: float = 1e-2,
              steps: int | None = None, newton_below: float = 1e-3, min_step: float = 1e-6,
              route: str = "auto", leg_length=None, leg_speed=None, objective: str | None = "auto",
              constraints=(), allow_imports: bool = False) -> "Problem":
        """The problem of :func:`nonholo.plan`'s keywords, checked.

        Parameters
        ----------
        R0, Rd, T, method, harmonics, grid, u0, gamma, step, tol, max_iter, strategy
            As for :func:`nonholo.plan`.
        mechanism, delta_min, steps, newton_below, min_step, route, leg_length
            As for :func:`nonholo.plan`.
        leg_speed, objective, allow_imports
            As for :func:`nonholo.plan`.
        constraints : sequence or None
            Further constraint objects (:mod:`nonholo.planning.constraint_objects`), besides those
            of ``delta_min``, ``leg_length`` and ``leg_speed``; ``None``: none. With
            ``T=None`` the mechanism's own bounds (:func:`~nonholo.model.bounds.of_mechanism`)
            join them, each kind (:class:`~nonholo.model.bounds.InputBounds`,
            :class:`~nonholo.model.bounds.StateBounds`) unless given here.

        Returns
        -------
        Problem
            The problem, every argument checked.

        Raises
        ------
        ValueError
            For bad input, naming the argument; ``R0``/``Rd`` outside the
            :class:`~nonholo.model.bounds.StateBounds`, naming the coordinate.
        TypeError
            For ``constraints`` that are not constraint objects, or an ``allow_imports``
            that is not a bool.
        """
        started, started_effort = time.perf_counter(), effort.seconds()
        mech = catalog.get(mechanism)
        speed = LegSpeed.of(leg_speed, mech)
        given = check_all(constraints, mech)
        if T is None and speed is None:
            given = given + least_time_bounds(given, mech)
            if not any(isinstance(c, InputBounds) and not c.free for c in given):
                raise ValueError(f"T=None asks for the least time, which needs a leg_speed (a platform's) or "
                                 f"InputBounds in constraints to re-time the path under; mechanism "
                                 f"{mech.name!r} has no input bounds of its own")
        if speed is not None and any(isinstance(c, InputBounds) and not c.free for c in given):
            raise ValueError("leg_speed and InputBounds cannot be kept together yet (each re-times the path "
                             "on its own): give one of them")
        if not one_of_choices(objective, OBJECTIVES):
            raise ValueError(f"unknown objective {objective!r}; known: None, 'energy', 'auto'")
        if not one_of_choices(route, ROUTES):
            raise ValueError(f"unknown route {route!r}; known: {', '.join(ROUTES)}")
        stroke = LegStroke.of(leg_length, mech)
        if not one_of_choices(method, METHODS):
            raise ValueError(f"unknown method {method!r}; known: {', '.join(METHODS)}")
        solver = check_strategy(strategy, allow_imports)
        least_time = T is None
        T = check_horizon(PLANNING_TIME if least_time else T)
        harmonics = check_count(harmonics, "harmonics")
        grid = check_count(grid, "grid", maximum=MAX_PLAN_STEPS)     # at most the steps (below)
        R0, q0 = mech.parse_state(R0, "R0")
        Rd, qd = mech.parse_state(Rd, "Rd")
        for c in given:
            if isinstance(c, StateBounds):
                for name, state, what in (("R0", (R0, q0), "the start"), ("Rd", (Rd, qd), "the goal")):
                    outside = c.violation(mech, state, what)
                    if outside is not None:
                        raise ValueError(f"{name}: {outside}")
        options = Options(gamma=solver.default_gamma if gamma is None else gamma, step=step, tol=tol,
                          max_iter=max_iter, newton_below=newton_below, min_step=min_step,
                          delta_min=delta_min)
        if mech.singular.value(R0, q0) == 0.0:
            raise ValueError(mech.singular.refusal)
        # the certificate replays on twice the steps: at most half its finest replay
        steps = check_count(default_steps(method, grid) if steps is None else steps, "steps",
                            maximum=MAX_PLAN_STEPS)
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
        # the keywords' constraints are checked as they are built, the caller's above: at most
        # one of each kind
        listed = (Clearance(options.delta_min), stroke, speed)
        checked = tuple(c for c in listed if c is not None) + given
        for kind in KINDS:
            one_of(checked, kind)
        return cls(mechanism=mech, R0=R0, q0=q0, Rd=Rd, qd=qd, T=T, method=method, harmonics=harmonics,
                   grid=grid, controls=controls, u0_given=u0 is not None, gamma_given=gamma is not None,
                   strategy_class=solver,
                   options=options, steps=steps, constraints=checked, objective=objective, route=route,
                   least_time=least_time, started=started, started_effort=started_effort)

    def part(self, start, goal, T: float, delta_min: float, strategy) -> "Problem":
        """A part of the global route, ``start → goal`` (states ``(R, q)``) in ``T``, planned
        locally with ``strategy`` and the clearance ``delta_min``, under this problem's other
        constraints but the legs' speed (kept by the whole plan's re-timing), with no
        objective: the same settings, its own clock.

        Parameters
        ----------
        start, goal : tuple
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
        solver = strategy_class(strategy)
        options = dataclasses.replace(self.options, delta_min=delta_min,
                                      gamma=self.options.gamma if self.gamma_given else solver.default_gamma)
        controls = initial_controls(self.method, T, mech.n_inputs, self.harmonics, self.grid)
        kept = tuple(c for c in self.constraints if not isinstance(c, (Clearance, LegSpeed, InputBounds)))
        return dataclasses.replace(
            self, R0=np.asarray(start[0], dtype=float), q0=np.asarray(start[1], dtype=float),
            Rd=np.asarray(goal[0], dtype=float), qd=np.asarray(goal[1], dtype=float), T=check_time(T),
            controls=controls, u0_given=False, strategy_class=solver, options=options,
            constraints=(Clearance(options.delta_min),) + kept, objective=None, route="local",
            least_time=False, started=time.perf_counter(), started_effort=effort.seconds())

    # -- what the planner reads ---------------------------------------------------------

    def evaluator(self, frame: bool = False, method: str | None = None, steps: int | None = None,
                  delta_min: float | None = None) -> Evaluator:
        """The :class:`~nonholo.planning.core.Evaluator` of this problem: its start, goal,
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
        Evaluator
            The evaluator.
        """
        return Evaluator(self.R0, self.Rd, self.T, self.mechanism, method or self.method,
                         self.steps if steps is None else steps,
                         self.options.delta_min if delta_min is None else max(delta_min, self.options.delta_min),
                         frame=frame,
                         limits=self.limits, q0=self.q0, qd=self.qd)

    @property
    def strategy(self) -> str:
        """The strategy's name."""
        return self.strategy_class.name

    @property
    def start(self) -> tuple[np.ndarray, np.ndarray]:
        """The start ``(R0, q0)``."""
        return self.R0, self.q0

    @property
    def goal(self) -> tuple[np.ndarray, np.ndarray]:
        """The goal ``(Rd, qd)``."""
        return self.Rd, self.qd

    @property
    def delta_min(self) -> float:
        """The clearance from ``Δ = 0`` the motion keeps."""
        return self.options.delta_min

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
