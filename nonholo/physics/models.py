"""Which physics model plays which mechanism: :func:`model_for`, and :func:`write_mjcf`.

A model is any object with this protocol (duck-typed):

- ``__init__(mechanism, contact)``; attributes ``mechanism`` and ``contact``;
- ``mjcf() -> str``: the complete MJCF text;
- ``reset(model, data, R, q)``: place the mechanism at the state at rest (and settle);
- ``follow(played, R, q)``: prepare to play ``played`` (a rest-to-rest
  :class:`~nonholo.io.result.PlanResult`) from the measured state, precomputing the
  actuators' targets;
- ``drive(model, data, t)``: set ``data.ctrl`` for time ``t`` of that motion;
- ``state(model, data) -> (R, q)``: the measured state in the mechanism's convention
  (the identity ``R`` or an empty ``q`` where the state has none);
- ``slip(model, data)``, ``contact_force(model, data)``: the largest tangential speed at a
  rolling contact and the largest normal contact force now.

The rolling ball, the car and the unicycle have the models of
:mod:`nonholo.physics.vehicle_models`; a two-leg platform (a mechanism with a
``geometry``) has ``PlatformModel`` of this package's module ``platform_model``, imported
when asked for.

A model is chosen by the mechanism's kinematics, never by its name alone
(:func:`matching_model`): a mechanism of one's own called ``"car"`` with a wheelbase of 2
is not the catalog's car, and its plans played on the catalog car's model would end a
wheelbase off without a word. A mechanism (other than the catalog's own object) plays on a
vehicle's model only if its state space, coordinates and inputs have the catalog vehicle's
shape and its velocity field ``G(R, q)`` equals the catalog vehicle's at
:data:`SAMPLES` seeded sample states (to :data:`FIELD_RTOL`); on the platforms' model only
if it has a geometry and every velocity it allows, ``L(R) u``, lies in the plane the disk
of that geometry allows, ``ω · (contact × axle) = 0``, with rank 2, at those sample
orientations — the model is written from the geometry and plays the plan's orientations,
so that is all it needs. Otherwise :func:`model_for` refuses it with a ``ValueError``
naming it.
"""
# ruff: noqa: TRY004 (bad input is refused by a ValueError naming the argument, as across the package)
from __future__ import annotations

import numpy as np

from ..io import safe_write
from ..io.result import PlanResult
from ..model import catalog
from ..model.mechanism import Mechanism
from .contact import Contact
from .vehicle_models import BallModel, CarModel, UnicycleModel

#: The calibration (:data:`~nonholo.physics.contact.CALIBRATED`) of every two-leg platform's model.
PLATFORM_CALIBRATION = "platform"
#: The rolling mechanisms' models, by the name of the catalog mechanism whose kinematics they play.
VEHICLES = {"rolling_ball": BallModel, "car": CarModel, "unicycle": UnicycleModel}
#: Sample states at which a mechanism's velocity field is compared with a model's (seeded:
#: the choice of a model never depends on anything but the mechanism).
SAMPLES = 12
#: Relative tolerance of that comparison (entries of ``G``, relative to the largest).
FIELD_RTOL = 1e-9
#: Coordinates of the sample states are drawn in ``[-SPREAD, SPREAD]`` (away from the car's
#: singular steering ``|φ| = π/2``).
SPREAD = 1.0


def model_for(mechanism, contact: Contact | None = None):
    """The physics model of a mechanism.

    Parameters
    ----------
    mechanism : str or Mechanism
        A mechanism or its name.
    contact : Contact, optional
        The contact and actuation settings (default: ``Contact()``); the model gets them
        resolved for the mechanism (:meth:`Contact.resolved`).

    Returns
    -------
    object
        The model (see the module for its protocol).

    Raises
    ------
    ValueError
        Naming ``mechanism`` for one without a physics model (or unknown) or whose
        kinematics no model plays (:func:`matching_model`), naming ``contact`` for settings
        that are not a :class:`Contact`.
    """
    if not isinstance(mechanism, (str, Mechanism)):
        raise ValueError(f"mechanism must be a mechanism's name or a Mechanism, got {type(mechanism).__name__}")
    try:
        mech = catalog.get(mechanism)
    except ValueError as exc:
        raise ValueError(f"mechanism: {exc}") from None
    if contact is None:
        contact = Contact()
    if not isinstance(contact, Contact):
        raise ValueError(f"contact must be a Contact, got {type(contact).__name__}")
    kind = matching_model(mech)
    if kind in VEHICLES:
        return VEHICLES[kind](mech, contact.resolved(kind))
    from .platform_model import PlatformModel

    # every two-leg platform, one of one's own geometry too, takes the platforms' calibration
    return PlatformModel(mech, contact.resolved(PLATFORM_CALIBRATION))


def matching_model(mechanism: Mechanism) -> str:
    """Which physics model plays a mechanism, by its kinematics (see the module).

    Parameters
    ----------
    mechanism : Mechanism
        The numeric mechanism.

    Returns
    -------
    str
        A key of :data:`VEHICLES` (the catalog vehicle whose kinematics it has), or
        :data:`PLATFORM_CALIBRATION` (a two-leg platform whose field its geometry's disk allows).

    Raises
    ------
    ValueError
        Naming the mechanism, when no physics model matches its kinematics (saying why).
    """
    name = mechanism.name
    if getattr(mechanism, "geometry", None) is not None:
        why = _platform_mismatch(mechanism)
        if why is None:
            return PLATFORM_CALIBRATION
        raise ValueError(f"mechanism {name!r}: no physics model matches its kinematics: {why}")
    whys = {}
    for vehicle in VEHICLES:
        why = _vehicle_mismatch(mechanism, catalog.get(vehicle))
        if why is None:
            return vehicle
        whys[vehicle] = why
    known = sorted(VEHICLES) + ["a two-leg platform (a mechanism with a geometry)"]
    if name in whys:                          # named as a catalog vehicle, but not its kinematics
        raise ValueError(f"mechanism {name!r}: no physics model matches its kinematics: it is not the "
                         f"catalog's {name!r} ({whys[name]}); there are models for {', '.join(known)}")
    raise ValueError(f"mechanism {name!r} has no physics model: no physics model matches its kinematics; "
                     f"there are models for {', '.join(known)}")


def _samples(space) -> list[tuple[np.ndarray, np.ndarray]]:
    """:data:`SAMPLES` seeded states ``(R, q)`` of ``space``: the identity moved by random
    variations, rotations by up to ``π/√3`` per row and coordinates in ``[-SPREAD, SPREAD]``."""
    rng = np.random.default_rng(20240611)
    half = np.full(space.dim, SPREAD)
    half[space.rows("rotation")] = np.pi / np.sqrt(3)
    return [tuple(space.retract(space.identity(), rng.uniform(-half, half))) for _ in range(SAMPLES)]


def _field(mechanism, R, q) -> np.ndarray | None:
    """``G(R, q)`` of a mechanism as floats, ``None`` where it cannot be evaluated (a singular state)."""
    try:
        with np.errstate(all="ignore"):
            G = mechanism.G(R, q)
        G = np.asarray(G, dtype=float)
    except (ArithmeticError, ValueError, TypeError):
        return None
    return G if np.all(np.isfinite(G)) else None


def _vehicle_mismatch(mechanism, vehicle) -> str | None:
    """Why ``mechanism`` does not have the kinematics of the catalog ``vehicle`` (``None`` if it does)."""
    if mechanism is vehicle:
        return None
    if mechanism.state_space != vehicle.state_space or len(mechanism.coordinates) != len(vehicle.coordinates):
        return (f"its state space is {mechanism.state_space}, that of the catalog's {vehicle.name!r} "
                f"{vehicle.state_space}")
    if len(mechanism.inputs) != len(vehicle.inputs):
        return f"it has {len(mechanism.inputs)} inputs, the catalog's {vehicle.name!r} {len(vehicle.inputs)}"
    compared = 0
    for R, q in _samples(vehicle.space):
        G, ref = _field(mechanism, R, q), _field(vehicle, R, q)
        if ref is None:
            continue
        if G is None or G.shape != ref.shape:
            return (f"its velocity field differs from that of the catalog's {vehicle.name!r} at "
                    f"q = {np.round(q, 3).tolist()}")
        scale = max(1.0, float(np.max(np.abs(ref))))
        gap = float(np.max(np.abs(G - ref)))
        if gap > FIELD_RTOL * scale:
            return (f"its velocity field differs from that of the catalog's {vehicle.name!r} by {gap:.3g} at "
                    f"q = {np.round(q, 3).tolist()}")
        compared += 1
    return None if compared else f"no sample state where the field of the catalog's {vehicle.name!r} is regular"


def _platform_mismatch(mechanism) -> str | None:
    """Why the field of a mechanism with a geometry is not one its disk allows (``None`` if it is)."""
    g = mechanism.geometry
    if mechanism.state_space != "SO(3)" or len(mechanism.inputs) != 2:
        return (f"a two-leg platform's model plays an orientation on SO(3) with 2 inputs, it has "
                f"{mechanism.state_space} with {len(mechanism.inputs)}")
    normal = np.cross(np.asarray(g.contact, dtype=float), np.asarray(g.axle, dtype=float))
    size = float(np.linalg.norm(normal))
    if not size > 0:
        return "its geometry's axle is along the contact normal: the disk constrains nothing"
    normal /= size
    compared = 0
    for R, q in _samples(mechanism.space):
        L = _field(mechanism, R, q)
        if L is None:
            continue
        if L.shape != (3, 2):
            return f"its field L(R) has shape {L.shape}, not (3, 2)"
        scale = float(np.max(np.abs(L)))
        sigma = np.linalg.svd(L, compute_uv=False)
        if not scale > 0 or sigma[-1] <= 1e-9 * sigma[0]:
            return "its field L(R) does not have rank 2"
        side = float(np.max(np.abs(normal @ L)))
        if side > FIELD_RTOL * 10 * scale:
            return (f"its field turns the sphere with a side slip of the disk its geometry gives "
                    f"(|(contact × axle)·L(R)| = {side:.3g} of {scale:.3g})")
        compared += 1
    return None if compared else "no sample orientation where its field is regular"


def write_mjcf(result_or_mechanism, path, contact: Contact | None = None):
    """Write the MJCF file of a plan's or a mechanism's physics model.

    Parameters
    ----------
    result_or_mechanism : PlanResult, Mechanism or str
        A plan (its mechanism's model) or a mechanism or its name.
    path : str or pathlib.Path
        Where to write (atomically, :mod:`nonholo.io.safe_write`).
    contact : Contact, optional
        The settings written into the file.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    ValueError
        For a mechanism without a physics model, or a ``path`` that cannot be replaced.
    """
    safe_write.check_target(path, "path")
    if isinstance(result_or_mechanism, PlanResult):
        mech = result_or_mechanism.kinematics
    elif isinstance(result_or_mechanism, (str, Mechanism)):
        mech = result_or_mechanism
    else:
        raise ValueError("result_or_mechanism must be a PlanResult, a Mechanism or a mechanism's name, "
                         f"got {type(result_or_mechanism).__name__}")
    return safe_write.write_text(path, model_for(mech, contact).mjcf(), "path")
