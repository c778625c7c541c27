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
"""
# ruff: noqa: TRY004 (bad input is refused by a ValueError naming the argument, as across the package)
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

#: The actuation modes of :attr:`Contact.actuators`.
ACTUATORS = ("prescribed", "servo")

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
        The simulation step (s).
    solref : tuple of float, optional
        MuJoCo's ``solref`` of every contact: ``(time constant (s), damping ratio)``; a time
        constant below twice ``timestep`` is raised to it by MuJoCo.
    solimp : tuple of float, optional
        MuJoCo's ``solimp`` of every contact (five numbers).
    friction : float, optional
        The sliding friction coefficient of the rolling contacts.
    noslip_iterations : int, optional
        Iterations of MuJoCo's post-solver no-slip pass, which removes the creep of
        regularised friction (0: none).
    impratio : float, optional
        Frictional over normal impedance of the elliptic friction cones (≥ 1).
    preload : float, optional
        Force (N) pressing the rolling body on: the ball's top plate down on it, a
        vehicle's chassis down on its wheels, the platform's disk on its sphere, in
        addition to gravity.
    radius_compensation : bool, optional
        Measure the effective rolling radius ``ρ − δ/2`` of each driven rolling contact
        once the mechanism has settled and scale the commanded motion by it.
    actuators : {"prescribed", "servo"}, optional
        Stiff tracking of the planned joint motion with its velocity fed forward, or a
        softer position servo that lags.
    settle : float, optional
        Time (s) the mechanism is left at rest before a motion and after it, before its
        state is measured.

    Raises
    ------
    ValueError
        Naming the field that is out of range.
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
        def positive(name, value, finite=True):
            if value is None:
                return
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
                    or not (value > 0) or (finite and not math.isfinite(value)):
                raise ValueError(f"{name} must be a positive finite number, got {value!r}")
            object.__setattr__(self, name, float(value))

        positive("timestep", self.timestep)
        positive("friction", self.friction)
        positive("settle", self.settle)
        for name, size in (("solref", 2), ("solimp", 5)):
            if getattr(self, name) is None:
                continue
            try:
                values = tuple(float(x) for x in getattr(self, name))
            except (TypeError, ValueError):
                raise ValueError(f"{name} must be {size} numbers, got {getattr(self, name)!r}") from None
            if len(values) != size or not all(math.isfinite(x) for x in values):
                raise ValueError(f"{name} must be {size} finite numbers, got {getattr(self, name)!r}")
            object.__setattr__(self, name, values)
        if self.solref is not None and not (self.solref[0] > 0 and self.solref[1] > 0):
            raise ValueError(f"solref must be (time constant > 0, damping ratio > 0), got {self.solref}")
        if self.solimp is not None and not (0 < self.solimp[0] < 1 and 0 < self.solimp[1] < 1
                                            and self.solimp[2] > 0):
            raise ValueError(f"solimp must have impedances in (0, 1) and a width > 0, got {self.solimp}")
        n = self.noslip_iterations
        if n is not None:
            if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 0:
                raise ValueError(f"noslip_iterations must be a whole number >= 0, got {n!r}")
            object.__setattr__(self, "noslip_iterations", int(n))
        positive("impratio", self.impratio)
        if self.impratio is not None and self.impratio < 1:
            raise ValueError(f"impratio must be >= 1, got {self.impratio!r}")
        p = self.preload
        if p is not None:
            if isinstance(p, bool) or not isinstance(p, (int, float, np.integer, np.floating)) \
                    or not math.isfinite(p) or p < 0:
                raise ValueError(f"preload must be a finite force >= 0, got {p!r}")
            object.__setattr__(self, "preload", float(p))
        if self.radius_compensation is not None:
            if not isinstance(self.radius_compensation, (bool, np.bool_)):
                raise ValueError(f"radius_compensation must be True or False, got {self.radius_compensation!r}")
            object.__setattr__(self, "radius_compensation", bool(self.radius_compensation))
        if self.actuators is not None and self.actuators not in ACTUATORS:
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
