"""The contact and actuation settings of a physics model: :class:`Contact`, every knob in
one place, and the few MuJoCo measurements every model shares.

A rolling contact in MuJoCo is soft: a body pressed on a surface sinks into it by a small
``δ`` and rolls about the middle of the overlap, with radius ``ρ − δ/2``, and friction is
regularised, so a contact under tangential load creeps. The defaults keep both small — a
stiff ``solref``, ``impratio`` weighting friction above the normal force, post-solver
no-slip iterations — and :attr:`Contact.radius_compensation` measures the rolling radius
after the mechanism has settled and scales the commanded motion to it. Contacts are
``condim`` 3: sliding friction, no torsional or rolling resistance, so a body rolls
without slipping and without being braked.

The actuators follow precomputed targets of the planned motion: ``"prescribed"`` is stiff
proportional–derivative tracking of each driven joint's planned position with its planned
velocity fed forward (the joint moves as planned up to the contact forces over the
stiffness); ``"servo"`` is a softer position servo with velocity damping and no feed-forward,
which lags.

Every setting is bounded (the ``*_RANGE`` constants below): MuJoCo accepts far more — a
preload of 1e300 N, an ``impratio`` of 1e300, a step of a nanosecond or of a gigasecond —
and then either runs without end or goes unstable, resets itself and carries on as if
nothing happened. The ranges hold the calibrated defaults and every test's and every
benchmark's setting with margin (at least a factor 2; MuJoCo's own least ``impratio`` 1 and
least ``solimp`` power 1, and no no-slip pass, are bounds by nature); a setting outside is
refused with a ``ValueError`` naming the field. Inside them a run can still go wrong (the
coarsest step with the strongest press throws the platform's disk off its sphere):
:func:`nonholo.physics.execution.execute` checks MuJoCo's warnings and the contact force
while playing, and marks such a stage ``"unstable"``.
"""
# ruff: noqa: TRY004 (bad input is refused by a ValueError naming the argument, as across the package)
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

#: The actuation modes of :attr:`Contact.actuators`.
ACTUATORS = ("prescribed", "servo")

#: Range (s) of :attr:`Contact.timestep`: below, a stage takes millions of steps; above, a
#: step spans a good part of a motion (the defaults: 1e-3, the platforms' 5e-4; the tests' coarsest 5e-3).
TIMESTEP_RANGE = (1e-5, 1e-2)
#: Range (s) of :attr:`Contact.settle` (the default 0.5).
SETTLE_RANGE = (1e-2, 10.0)
#: Range (N) of :attr:`Contact.preload` (the defaults 10, the platforms' 100).
PRELOAD_RANGE = (0.0, 1e3)
#: Range of :attr:`Contact.impratio` (the default 10; 1 is MuJoCo's own).
IMPRATIO_RANGE = (1.0, 100.0)
#: Range of :attr:`Contact.friction` (the default 1).
FRICTION_RANGE = (1e-2, 10.0)
#: Range of :attr:`Contact.noslip_iterations` (the default 20; 0: no no-slip pass).
NOSLIP_ITERATIONS_RANGE = (0, 200)
#: Range (s) of the time constant of :attr:`Contact.solref` (the defaults 2e-3, the platforms'
#: 1e-3; the tests' 1e-2).
SOLREF_TIME_RANGE = (1e-4, 0.1)
#: Range of the damping ratio of :attr:`Contact.solref` (the default 1; at 0.3 the stiff
#: contacts bounce the ball off the floor).
SOLREF_DAMPING_RANGE = (0.5, 10.0)
#: Range of the width of :attr:`Contact.solimp` (its third number; the defaults 1e-4, the
#: platforms' 1e-3); its impedances lie in ``(0, 1)``, its midpoint in ``(0, 1)``.
SOLIMP_WIDTH_RANGE = (1e-6, 1.0)
#: Range of the power of :attr:`Contact.solimp` (its fifth number; the default 2).
SOLIMP_POWER_RANGE = (1.0, 10.0)

#: Largest number of MuJoCo steps of a stage, its motion and settling: a stage's targets are
#: computed and held in memory beforehand (about 600 bytes a step at their peak: 150 MB here,
#: and seconds of preparation), so the models' ``follow`` and
#: :func:`nonholo.physics.execution.execute` refuse more before allocating anything. The
#: benchmarks' largest stage takes 21 000 (10 s at the platforms' 5e-4 s, and settling).
MAX_STAGE_STEPS = 250_000

#: The calibrated settings: a field of :class:`Contact` left ``None`` takes its value here,
#: the mechanism's own (:data:`CALIBRATED`) before the common one.
DEFAULTS = {
    "timestep": 1e-3,
    "solref": (0.002, 1.0),
    "solimp": (0.99, 0.999, 1e-4, 0.5, 2.0),
    "friction": 1.0,
    "noslip_iterations": 20,
    "impratio": 10.0,
    "preload": 10.0,
    "radius_compensation": True,
    "actuators": "prescribed",
    "settle": 0.5,
}

#: Settings of particular mechanisms that differ from :data:`DEFAULTS`: the two-leg
#: platforms' sphere is turned through one small disk, which needs a finer step, a stiffer
#: contact and a firmer press.
CALIBRATED = {
    name: {"timestep": 5e-4, "solref": (0.001, 1.0), "solimp": (0.99, 0.999, 0.001, 0.5, 2.0),
           "preload": 100.0}
    for name in ("platform", "platform_raised")
}


@dataclass(frozen=True)
class Contact:
    """Contact and actuation settings of a physics model (see the module).

    Every field left ``None`` takes the calibrated value for the mechanism played
    (:meth:`resolved`: :data:`CALIBRATED`, else :data:`DEFAULTS`).

    Parameters
    ----------
    timestep : float, optional
        The simulation step (s), in :data:`TIMESTEP_RANGE`.
    solref : tuple of float, optional
        MuJoCo's ``solref`` of every contact: ``(time constant (s), damping ratio)``, in
        :data:`SOLREF_TIME_RANGE` and :data:`SOLREF_DAMPING_RANGE`; a time constant below
        twice ``timestep`` is raised to it by MuJoCo.
    solimp : tuple of float, optional
        MuJoCo's ``solimp`` of every contact (five numbers: impedances in ``(0, 1)``, width
        in :data:`SOLIMP_WIDTH_RANGE`, midpoint in ``(0, 1)``, power in
        :data:`SOLIMP_POWER_RANGE`).
    friction : float, optional
        The sliding friction coefficient of the rolling contacts, in :data:`FRICTION_RANGE`.
    noslip_iterations : int, optional
        Iterations of MuJoCo's post-solver no-slip pass, which removes the creep of
        regularised friction (0: none), in :data:`NOSLIP_ITERATIONS_RANGE`.
    impratio : float, optional
        Frictional over normal impedance of the elliptic friction cones, in
        :data:`IMPRATIO_RANGE`.
    preload : float, optional
        Force (N) pressing the rolling body on: the ball's top plate down on it, a
        vehicle's chassis down on its wheels, the platform's disk on its sphere, in
        addition to gravity; in :data:`PRELOAD_RANGE`.
    radius_compensation : bool, optional
        Measure the effective rolling radius ``ρ − δ/2`` of each driven rolling contact
        once the mechanism has settled and scale the commanded motion by it.
    actuators : {"prescribed", "servo"}, optional
        Stiff tracking of the planned joint motion with its velocity fed forward, or a
        softer position servo that lags.
    settle : float, optional
        Time (s) the mechanism is left at rest before a motion and after it, before its
        state is measured; in :data:`SETTLE_RANGE`.

    Raises
    ------
    ValueError
        Naming the field that is not a number or is outside its range (the ``*_RANGE``
        constants of the module).
    """

    timestep: float | None = None
    solref: tuple | None = None
    solimp: tuple | None = None
    friction: float | None = None
    noslip_iterations: int | None = None
    impratio: float | None = None
    preload: float | None = None
    radius_compensation: bool | None = None
    actuators: str | None = None
    settle: float | None = None

    def __post_init__(self):
        def number(name, value, bounds, what="a number", unit=""):
            """``value`` as a finite float in the closed range ``bounds``, or a ValueError naming ``name``."""
            lo, hi = bounds
            where = f" in [{lo:g}, {hi:g}]{unit}" if math.isfinite(lo) and math.isfinite(hi) else ""
            bad = ValueError(f"{name} must be {what}{where}, got {shown(value)}")
            if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
                raise bad
            try:
                x = float(value)
            except OverflowError:                 # an int beyond the floats' range
                raise bad from None
            if not math.isfinite(x) or not lo <= x <= hi:
                raise bad
            return x

        def field(name, bounds, what="a number", unit=""):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, number(name, getattr(self, name), bounds, what, unit))

        field("timestep", TIMESTEP_RANGE, "a time step", " s")
        field("friction", FRICTION_RANGE, "a friction coefficient")
        field("settle", SETTLE_RANGE, "a settling time", " s")
        for name, size in (("solref", 2), ("solimp", 5)):
            given = getattr(self, name)
            if given is None:
                continue
            if isinstance(given, (str, bytes, dict)) or not hasattr(given, "__len__") or len(given) != size:
                raise ValueError(f"{name} must be {size} finite numbers, got {given!r}")
            values = tuple(number(f"{name}[{i}]", x, (-math.inf, math.inf), "a finite number")
                           for i, x in enumerate(given))
            object.__setattr__(self, name, values)
        if self.solref is not None:
            (t0, t1), (d0, d1) = SOLREF_TIME_RANGE, SOLREF_DAMPING_RANGE
            if not (t0 <= self.solref[0] <= t1 and d0 <= self.solref[1] <= d1):
                raise ValueError(f"solref must be (time constant in [{t0:g}, {t1:g}] s, damping ratio in "
                                 f"[{d0:g}, {d1:g}]), got {self.solref}")
        if self.solimp is not None:
            (w0, w1), (p0, p1) = SOLIMP_WIDTH_RANGE, SOLIMP_POWER_RANGE
            dmin, dmax, width, mid, power = self.solimp
            if not (0 < dmin < 1 and 0 < dmax < 1 and w0 <= width <= w1 and 0 < mid < 1 and p0 <= power <= p1):
                raise ValueError(f"solimp must have impedances in (0, 1), a width in [{w0:g}, {w1:g}], a "
                                 f"midpoint in (0, 1) and a power in [{p0:g}, {p1:g}], got {self.solimp}")
        n = self.noslip_iterations
        if n is not None:
            lo, hi = NOSLIP_ITERATIONS_RANGE
            if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)) or not lo <= n <= hi:
                raise ValueError(f"noslip_iterations must be a whole number in [{lo}, {hi}], got {n!r}")
            object.__setattr__(self, "noslip_iterations", int(n))
        field("impratio", IMPRATIO_RANGE, "a ratio")
        field("preload", PRELOAD_RANGE, "a force", " N")
        if self.radius_compensation is not None:
            if not isinstance(self.radius_compensation, (bool, np.bool_)):
                raise ValueError(f"radius_compensation must be True or False, got {self.radius_compensation!r}")
            object.__setattr__(self, "radius_compensation", bool(self.radius_compensation))
        if self.actuators is not None and (not isinstance(self.actuators, str) or self.actuators not in ACTUATORS):
            raise ValueError(f"actuators must be one of {ACTUATORS}, got {self.actuators!r}")

    def resolved(self, mechanism: str | None = None) -> Contact:
        """These settings with every ``None`` field at its calibrated value.

        Parameters
        ----------
        mechanism : str, optional
            The mechanism's name (its :data:`CALIBRATED` values before :data:`DEFAULTS`).

        Returns
        -------
        Contact
            Settings without ``None``.
        """
        own = CALIBRATED.get(mechanism, {})
        return dataclasses.replace(self, **{
            f.name: own.get(f.name, DEFAULTS[f.name]) for f in dataclasses.fields(self)
            if getattr(self, f.name) is None})

    def replace(self, **changes) -> Contact:
        """A copy with some fields changed (checked as a new one).

        Parameters
        ----------
        **changes
            Fields and their new values.

        Returns
        -------
        Contact
            The new settings.
        """
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict:
        """The settings as plain JSON values.

        Returns
        -------
        dict
            Field name → value (tuples as lists).
        """
        return {f.name: list(v) if isinstance(v := getattr(self, f.name), tuple) else v
                for f in dataclasses.fields(self)}

    @classmethod
    def from_dict(cls, d: dict) -> Contact:
        """Inverse of :meth:`to_dict`.

        Parameters
        ----------
        d : dict
            Field name → value; missing fields take their defaults.

        Returns
        -------
        Contact
            The settings.

        Raises
        ------
        ValueError
            For an unknown field or a value out of range.
        """
        if not isinstance(d, dict):
            raise ValueError(f"contact must be a mapping of its fields, got {type(d).__name__}")
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(d) - known)
        if unknown:
            raise ValueError(f"contact: unknown fields {unknown}; known: {sorted(known)}")
        return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in d.items()})

    def option_xml(self) -> str:
        """The MJCF ``<option>`` element of these (resolved) settings: implicit-in-velocity
        integrator, elliptic cones, gravity along ``−z``.

        Returns
        -------
        str
            The element.
        """
        return (f'<option timestep="{float(self.timestep)!r}" integrator="implicitfast" cone="elliptic" '
                f'impratio="{float(self.impratio)!r}" noslip_iterations="{int(self.noslip_iterations)}" '
                f'gravity="0 0 -9.81"/>')

    def geom_attributes(self) -> str:
        """The attributes of a rolling contact's geom (resolved settings): ``condim`` 3,
        friction, ``solref``, ``solimp``.

        Returns
        -------
        str
            The attributes, for a ``<geom>`` element or a ``<default>``'s.
        """
        mu = float(self.friction)
        return (f'condim="3" friction="{mu!r} 0 0" solref="{numbers(self.solref)}" '
                f'solimp="{numbers(self.solimp)}"')


def shown(value, width: int = 60) -> str:
    """``repr(value)`` cut to ``width`` characters (a message quotes what it refuses).

    Parameters
    ----------
    value : object
        Anything.
    width : int
        The longest text.

    Returns
    -------
    str
        The text.
    """
    try:
        text = repr(value)
    except ValueError:                    # an int past Python's digits limit
        text = f"<{type(value).__name__} too long to show>"
    return text if len(text) <= width else text[:width - 3] + "..."


def numbers(values) -> str:
    """Numbers as an MJCF attribute's text (each through ``float``, full precision).

    Parameters
    ----------
    values : iterable of float
        The numbers.

    Returns
    -------
    str
        Space-separated.
    """
    return " ".join(repr(float(v)) for v in values)


def _rows(model, data, bodies, friction: bool) -> np.ndarray:
    """The first constraint rows (``efc`` addresses) of the active contacts (with friction,
    ``condim`` 3 or more) touching one of ``bodies``."""
    n = data.ncon
    if n == 0:
        return np.zeros(0, dtype=int)
    adr = np.asarray(data.contact.efc_address[:n])
    keep = adr >= 0
    if friction:
        keep &= np.asarray(data.contact.dim[:n]) >= 3
    if bodies is not None:
        b = np.asarray(sorted(bodies))
        g1, g2 = np.asarray(data.contact.geom1[:n]), np.asarray(data.contact.geom2[:n])
        keep &= np.isin(model.geom_bodyid[g1], b) | np.isin(model.geom_bodyid[g2], b)
    return adr[keep]


def max_slip(model, data, bodies=None) -> float:
    """Largest tangential speed between the two bodies at any active contact with friction
    (``condim`` ≥ 3) touching one of ``bodies``: the contact's tangential constraint
    velocities (elliptic cones), as of the last step's start.

    Parameters
    ----------
    model, data : mujoco.MjModel, mujoco.MjData
        The simulation.
    bodies : collection of int, optional
        Body ids.

    Returns
    -------
    float
        The speed (0 without contacts).
    """
    rows = _rows(model, data, bodies, True)
    if rows.size == 0:
        return 0.0
    return float(np.max(np.hypot(data.efc_vel[rows + 1], data.efc_vel[rows + 2])))


def max_normal_force(model, data, bodies=None) -> float:
    """Largest normal force of any active contact (touching one of ``bodies``), of the last
    step's constraint solution (elliptic cones).

    Parameters
    ----------
    model, data : mujoco.MjModel, mujoco.MjData
        The simulation.
    bodies : collection of int, optional
        Body ids.

    Returns
    -------
    float
        The force (0 without contacts).
    """
    rows = _rows(model, data, bodies, False)
    if rows.size == 0:
        return 0.0
    return float(np.max(data.efc_force[rows]))


def penetration(model, data, geom: int, other: int | None = None) -> float:
    """Depth ``δ ≥ 0`` of the deepest active contact of ``geom`` (with ``other``).

    Parameters
    ----------
    model, data : mujoco.MjModel, mujoco.MjData
        The simulation.
    geom : int
        The geom's id.
    other : int, optional
        The id of the geom it touches (default: any).

    Returns
    -------
    float
        ``δ`` (0 without a contact).
    """
    depth = 0.0
    for i in range(data.ncon):
        c = data.contact[i]
        if c.efc_address >= 0 and geom in (c.geom1, c.geom2) and (other is None or other in (c.geom1, c.geom2)):
            depth = max(depth, -float(c.dist))
    return depth
