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
"""
# ruff: noqa: TRY004 (bad input is refused by a ValueError naming the argument, as across the package)
from __future__ import annotations

from ..io import safe_write
from ..io.result import PlanResult
from ..model import catalog
from ..model.mechanism import Mechanism
from .contact import Contact
from .vehicle_models import BallModel, CarModel, UnicycleModel

#: The calibration (:data:`~nonholo.physics.contact.CALIBRATED`) of every two-leg platform's model.
PLATFORM_CALIBRATION = "platform"
#: The rolling mechanisms' models, by mechanism name.
VEHICLES = {"rolling_ball": BallModel, "car": CarModel, "unicycle": UnicycleModel}


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
        Naming ``mechanism`` for one without a physics model (or unknown), naming
        ``contact`` for settings that are not a :class:`Contact`.
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
    if mech.name in VEHICLES:
        return VEHICLES[mech.name](mech, contact.resolved(mech.name))
    if getattr(mech, "geometry", None) is not None:
        from .platform_model import PlatformModel

        # every two-leg platform, one of one's own geometry too, takes the platforms' calibration
        return PlatformModel(mech, contact.resolved(PLATFORM_CALIBRATION))
    known = sorted(VEHICLES) + ["a two-leg platform (a mechanism with a geometry)"]
    raise ValueError(f"mechanism {mech.name!r} has no physics model; there are models for "
                     f"{', '.join(known)}")


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
