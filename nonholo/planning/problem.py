"""The planning problem as one object: mechanism, start, goal, horizon, parametrisation,
constraints, objective and the solver's settings, checked once when it is built.

:func:`nonholo.plan` builds a :class:`Problem` from its keywords (:meth:`Problem.build`)
and hands it to :func:`nonholo.planning.api.solve`; the strategies, the global route and
the least-energy stage read what they need from it, and the route plans its hops as
problems of their own (:meth:`Problem.part`). Constraints are objects in a list
(:mod:`nonholo.planning.constraint_objects`); the numerical settings and the checks of
single arguments are :mod:`nonholo.planning.settings`.
"""
from __future__ import annotations

import dataclasses
from dataclasses import asdict, dataclass


from ..controls import stages
from ..controls.parametrisations import Controls
from ..model import catalog
from ..model.mechanism import Mechanism
from ..spaces.state import State
from ..motion.time_scaling import check_horizon
from ..numerics.checks import check_time
from ..model.bounds import InputBounds, StateBounds, of_mechanism
from ..model.limits import Limits
from .constraint_objects import KINDS, Clearance, LegSpeed, LegStroke, Obstacles, check_all, one_of
from .core import Options, Strategy
from .endpoint_map import EndpointMap
from .settings import (
    DEFAULT_CLEARANCE,
    Settings,
    check_strategy,
    default_steps,
    initial_controls,
    one_of_choices,
    strategy_class,
)

#: The routes :func:`nonholo.plan` takes to a goal.
ROUTES = ("auto", "local", "global")
#: The most numbers the Fourier basis at the integrator's stages (``3·steps × (2·harmonics + 1)``)
#: may hold: 2·10⁷ (160 MB); the planner keeps a few arrays of that size.
MAX_BASIS = 2 * 10**7
#: What :func:`nonholo.plan` optimises once the goal is reached: nothing (the plan as found),
#: the energy ∫|u|² dt, or the plan unless a quick search finds a motion of far less energy
#: (:func:`nonholo.planning.energy.improve`).
OBJECTIVES = (None, "energy", "auto", "time")
#: The planning horizon (s) of a plan asked for in the least time (``T=None``): the path is
#: planned in this time, then re-timed (:mod:`nonholo.planning.retime`).
PLANNING_TIME = 1.0


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
    objective : {None, "energy", "auto", "time"}
        What is lowered once the plan is found (``"time"``: the horizon, under input bounds).
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
        if not one_of_choices(objective, OBJECTIVES):
            raise ValueError(f"unknown objective {objective!r}; known: None, 'energy', 'auto', 'time'")
        if mech.has_drift and T is None:
            raise ValueError(f"T=None asks for the least time by re-timing a path, which a time change keeps "
                             f"only without drift; mechanism {mech.name!r} has drift: give the time T")
        if objective == "time" and speed is None:
            given = given + least_time_bounds(given, mech)
            bounds = one_of(given, InputBounds)
            if bounds is None or bounds.free:
                raise ValueError(f"objective='time' asks for the least time, which needs InputBounds in "
                                 f"constraints (or a platform's LegSpeed); mechanism {mech.name!r} has no input "
                                 f"bounds of its own")
        elif T is None and speed is None:
            given = given + least_time_bounds(given, mech)
            if not any(isinstance(c, InputBounds) and not c.free for c in given):
                raise ValueError(f"T=None asks for the least time, which needs a LegSpeed (a platform's) or "
                                 f"InputBounds in constraints to re-time the path under; mechanism "
                                 f"{mech.name!r} has no input bounds of its own")
        off = next((c.off_zero(mech) for c in given if isinstance(c, InputBounds) and c.off_zero(mech)), None)
        if off is not None and (objective != "time" or mech.has_drift):
            raise ValueError(f"InputBounds: the bound {off} of mechanism {mech.name!r} does not hold 0 inside "
                             f"(low < 0 < high): only the least time (objective='time', without drift) keeps "
                             f"it, scaling the whole motion's time by one factor; a re-timing along the path "
                             f"slows it to rest where it turns, and a mechanism with drift moves at rest")
        if speed is not None and any(isinstance(c, InputBounds) and not c.free for c in given):
            raise ValueError("LegSpeed and InputBounds cannot be kept together yet (each re-times the path "
                             "on its own): give one of them")
        if not one_of_choices(route, ROUTES):
            raise ValueError(f"unknown route {route!r}; known: {', '.join(ROUTES)}")
        solver = check_strategy(strategy, allow_imports)
        least_time = T is None or objective == "time"
        T = check_horizon(PLANNING_TIME if T is None else T)
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
            Fields of :class:`~nonholo.planning.settings.Settings`.

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
        """The :class:`~nonholo.planning.endpoint_map.EndpointMap` of this problem: its start, goal,
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
    def obstacles(self):
        """The obstacles the vehicle's bodies keep clear of, if given
        (:class:`~nonholo.model.obstacles.Obstacles`)."""
        return one_of(self.constraints, Obstacles)

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
