"""The frame the MuJoCo models of the rolling mechanisms share (:class:`RollingModel`): the
MJCF file around their bodies, actuators tracking targets of the driven joints, settling,
and slip and contact-force measurements.

A model turns the plan into position and velocity targets of its driven joints on the
simulation's time grid (:class:`Targets`, :meth:`RollingModel.follow`), relative to where
the actuators were last commanded, and the actuators track them with gains of a critically
damped natural frequency (:data:`STIFF`, :data:`SERVO`, at most :data:`STIFF_STEP` per time
step). The models themselves: :mod:`nonholo.physics.vehicle_models`.
"""
# ruff: noqa: TRY004 (bad input is refused by a ValueError naming the argument, as across the package)
from __future__ import annotations

import abc

import numpy as np

from . import contact as contacts
from .contact import Contact

#: Natural frequency (rad/s) of the tracking of a driven joint, "prescribed" actuators, at
#: most :data:`STIFF_STEP` over the time step.
STIFF = 2 * np.pi * 25.0
#: ... and "servo" actuators.
SERVO = 2 * np.pi * 2.0
#: Largest product of the tracking frequency and the time step (the stiffness is explicit).
STIFF_STEP = 0.5
#: Gravity's acceleration (m/s²), as :meth:`Contact.option_xml` writes it.
GRAVITY = 9.81


class Targets:
    """Positions and velocities of the driven joints on a uniform time grid.

    Parameters
    ----------
    step : float
        The grid's spacing (s).
    positions, velocities : numpy.ndarray
        Shape ``(n + 1, a)``: the targets at ``t_k = k · step`` (the last at the motion's end).
    duration : float
        The motion's end ``T``; after it the last positions hold, at zero velocity.
    """

    def __init__(self, step: float, positions, velocities, duration: float):
        self.step = float(step)
        self.positions = np.asarray(positions, dtype=float)
        self.velocities = np.asarray(velocities, dtype=float)
        self.duration = float(duration)

    @classmethod
    def hold(cls, positions) -> Targets:
        """Targets that hold ``positions`` at rest.

        Parameters
        ----------
        positions : array_like
            Shape ``(a,)``.

        Returns
        -------
        Targets
            The targets.
        """
        p = np.asarray(positions, dtype=float)[None]
        return cls(1.0, p, np.zeros_like(p), 0.0)

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """The targets at time ``t`` (linear between grid points).

        Parameters
        ----------
        t : float
            Time since the motion's start (s).

        Returns
        -------
        tuple of numpy.ndarray
            Positions and velocities, shape ``(a,)`` each.
        """
        last = len(self.positions) - 1
        if t >= self.duration or last == 0:
            return self.positions[-1], np.zeros(self.positions.shape[1])
        x = max(t, 0.0) / self.step
        i = min(int(x), last - 1)
        f = x - i
        if f <= 1e-9:
            return self.positions[i], self.velocities[i]
        return ((1 - f) * self.positions[i] + f * self.positions[i + 1],
                (1 - f) * self.velocities[i] + f * self.velocities[i + 1])


def steps_of(T: float, h: float, name: str) -> int:
    """The time steps ``h`` a motion of ``T`` seconds takes (at least one), at most
    :data:`~nonholo.physics.contact.MAX_STAGE_STEPS`.

    Parameters
    ----------
    T, h : float
        The motion's duration and the time step (s).
    name : str
        The motion's name, for the message.

    Returns
    -------
    int
        The number of steps.

    Raises
    ------
    ValueError
        Naming ``name``, for a motion of more steps (checked before anything is allocated).
    """
    steps = T / h
    if not steps <= contacts.MAX_STAGE_STEPS:
        raise ValueError(f"{name}: a motion of {T:g} s takes {steps:.3g} time steps of {h:g} s, more than "
                         f"MAX_STAGE_STEPS = {contacts.MAX_STAGE_STEPS:.3g}")
    return max(int(np.ceil(steps - 1e-9)), 1)


class RollingModel(abc.ABC):
    """What the rolling models share: the MJCF frame, actuators tracking targets, settling,
    slip and force measurements (the model protocol of :mod:`nonholo.physics.models`).

    Subclasses set :attr:`name`, :attr:`driven` (``(joint, effective inertia)`` of each
    driven joint), :attr:`rolling` (``(label, geom, geom it rolls on, nominal radius)`` of
    each rolling contact whose radius scales the motion) and write :meth:`bodies`, :meth:`place`, :meth:`state` and
    :meth:`displacements`.

    Parameters
    ----------
    mechanism : Mechanism
        The numeric mechanism.
    contact : Contact, optional
        The settings (default: ``Contact()``), resolved for the mechanism.
    """

    name = ""
    driven: tuple = ()
    rolling: tuple = ()
    #: Half-size of the floor as drawn (it is infinite for contacts).
    floor = 20.0

    def __init__(self, mechanism, contact: Contact | None = None):
        self.mechanism = mechanism
        contact = Contact() if contact is None else contact
        if not isinstance(contact, Contact):
            raise ValueError(f"contact must be a Contact, got {type(contact).__name__}")
        self.contact = contact.resolved(self.name)
        self.radii = {label: r for label, _, _, r in self.rolling}
        self._targets = None
        self._hold = np.zeros(len(self.driven))

    # -- the model file ---------------------------------------------------------------------
    @abc.abstractmethod
    def bodies(self) -> str:
        """The mechanism's bodies.

        Returns
        -------
        str
            MJCF elements inside ``<worldbody>``.
        """

    def extra_actuators(self) -> str:
        """Actuators besides the driven joints'.

        Returns
        -------
        str
            MJCF elements inside ``<actuator>`` (none by default).
        """
        return ""

    def gains(self) -> list[tuple[float, float]]:
        """The tracking gains: a critically damped natural frequency on each driven joint's
        inertia, :data:`STIFF` or :data:`SERVO`, at most :data:`STIFF_STEP` per time step.

        Returns
        -------
        list of tuple of float
            ``(kp, kv)`` per driven joint.
        """
        wn = min(STIFF if self.contact.actuators == "prescribed" else SERVO,
                 STIFF_STEP / self.contact.timestep)
        return [(inertia * wn * wn, 2.0 * inertia * wn) for _, inertia in self.driven]

    def mjcf(self) -> str:
        """The complete MJCF text of the model.

        Returns
        -------
        str
            Loads with ``mujoco.MjModel.from_xml_string``.
        """
        acts = []
        for (joint, _), (kp, kv) in zip(self.driven, self.gains()):
            acts.append(f'    <position name="{joint}_position" joint="{joint}" kp="{float(kp)!r}"/>')
            acts.append(f'    <velocity name="{joint}_velocity" joint="{joint}" kv="{float(kv)!r}"/>')
        f = float(self.floor)
        return "\n".join([
            f'<mujoco model="{self.name}">',
            '  <compiler angle="radian" autolimits="true"/>',
            f"  {self.contact.option_xml()}",
            "  <default>",
            f"    <geom {self.contact.geom_attributes()}/>",
            "  </default>",
            "  <worldbody>",
            '    <light pos="0 0 10" dir="0 0 -1" directional="true"/>',
            f'    <geom name="floor" type="plane" size="{f!r} {f!r} 0.1" rgba="0.8 0.8 0.8 1"/>',
            self.bodies(),
            "  </worldbody>",
            "  <actuator>",
            *acts,
            *[line for line in [self.extra_actuators()] if line],
            "  </actuator>",
            "</mujoco>",
            ""])

    # -- ids ----------------------------------------------------------------------------------
    def _ids(self, model) -> dict:
        import mujoco

        def ident(kind, name):
            i = mujoco.mj_name2id(model, kind, name)
            if i < 0:
                raise ValueError(f"the model has no {kind.name[6:].lower()} named {name!r}: "
                                 f"not one written by {type(self).__name__}.mjcf()")
            return i

        J, A, G = mujoco.mjtObj.mjOBJ_JOINT, mujoco.mjtObj.mjOBJ_ACTUATOR, mujoco.mjtObj.mjOBJ_GEOM
        return {
            "qpos": np.array([model.jnt_qposadr[ident(J, j)] for j, _ in self.driven], dtype=int),
            "position": np.array([ident(A, f"{j}_position") for j, _ in self.driven], dtype=int),
            "velocity": np.array([ident(A, f"{j}_velocity") for j, _ in self.driven], dtype=int),
            "rolling": [(ident(G, g), ident(G, other)) for _, g, other, _ in self.rolling],
        }

    # -- the protocol -------------------------------------------------------------------------
    @abc.abstractmethod
    def place(self, model, data, R, q) -> None:
        """Put the mechanism at ``(R, q)``, just touching the floor.

        Parameters
        ----------
        model, data : mujoco.MjModel, mujoco.MjData
            The simulation (``data.qpos`` is set).
        R, q : numpy.ndarray
            The state.
        """

    def reset(self, model, data, R, q) -> None:
        """Place the mechanism at ``(R, q)`` at rest and let it settle for
        :attr:`Contact.settle` with the actuators holding; then measure the rolling radii
        (with :attr:`Contact.radius_compensation`).

        Parameters
        ----------
        model, data : mujoco.MjModel, mujoco.MjData
            The simulation (``data`` is reset).
        R, q : numpy.ndarray
            The state.
        """
        import mujoco

        mujoco.mj_resetData(model, data)
        self.place(model, data, np.asarray(R, dtype=float), np.asarray(q, dtype=float))
        mujoco.mj_forward(model, data)
        ids = self._ids(model)
        self._hold = data.qpos[ids["qpos"]].copy()
        self._targets = Targets.hold(self._hold)
        self.pressing(model, data)
        for _ in range(round(self.contact.settle / model.opt.timestep)):
            self.drive(model, data, 0.0)
            mujoco.mj_step(model, data)
        mujoco.mj_forward(model, data)
        self.radii = {label: r for label, _, _, r in self.rolling}
        if self.contact.radius_compensation:
            for (label, _, _, r), (gid, oid) in zip(self.rolling, ids["rolling"]):
                self.radii[label] = r - 0.5 * contacts.penetration(model, data, gid, oid)

    def pressing(self, model, data) -> None:
        """Apply :attr:`Contact.preload` (through ``data.ctrl`` or ``data.xfrc_applied``).

        Parameters
        ----------
        model, data : mujoco.MjModel, mujoco.MjData
            The simulation.
        """

    def drive(self, model, data, t: float) -> None:
        """Set the actuators' targets for time ``t`` of the motion being followed.

        Parameters
        ----------
        model, data : mujoco.MjModel, mujoco.MjData
            The simulation.
        t : float
            Time since the motion's start (s); past its end the final targets hold.
        """
        ids = self._ids_cache(model)
        pos, vel = self._targets.at(t)
        data.ctrl[ids["position"]] = pos
        data.ctrl[ids["velocity"]] = vel if self.contact.actuators == "prescribed" else 0.0

    def _ids_cache(self, model) -> dict:
        cached = getattr(self, "_cached", None)
        if cached is None or cached[0] is not model:
            cached = (model, self._ids(model))
            self._cached = cached
        return cached[1]

    @abc.abstractmethod
    def displacements(self, played, t, R, q) -> tuple[np.ndarray, np.ndarray]:
        """The driven joints' positions (up to a constant) and velocities along ``played``.

        Parameters
        ----------
        played : PlanResult
            The motion.
        t : numpy.ndarray
            The time grid, ``(n,)``.
        R, q : numpy.ndarray
            The measured state it starts from.

        Returns
        -------
        tuple of numpy.ndarray
            Positions and velocities, ``(n, a)`` each.
        """

    def follow(self, played, R, q) -> None:
        """Precompute the actuators' targets for playing ``played`` from the measured state
        ``(R, q)``, on the time grid of :attr:`Contact.timestep`: the joints' planned
        displacements added to where they were last commanded.

        Parameters
        ----------
        played : PlanResult
            The motion to play, from rest to rest.
        R, q : numpy.ndarray
            The state it starts from.

        Raises
        ------
        ValueError
            Naming ``played``, if its motion takes more than
            :data:`~nonholo.physics.contact.MAX_STAGE_STEPS` time steps.
        """
        h = self.contact.timestep
        T = float(played.T)
        n = steps_of(T, h, "played")
        t = np.minimum(np.arange(n + 1) * h, T)
        disp, vel = self.displacements(played, t, np.asarray(R, dtype=float), np.asarray(q, dtype=float))
        pos = self._hold[None] + disp - disp[0]
        self._targets = Targets(h, pos, vel, T)
        self._hold = pos[-1].copy()

    def slip(self, model, data) -> float:
        """The largest tangential speed at a rolling contact now (frictional contacts).

        Parameters
        ----------
        model, data : mujoco.MjModel, mujoco.MjData
            The simulation.

        Returns
        -------
        float
            The speed (model units per second).
        """
        return contacts.max_slip(model, data)

    def contact_force(self, model, data) -> float:
        """The largest normal contact force now.

        Parameters
        ----------
        model, data : mujoco.MjModel, mujoco.MjData
            The simulation.

        Returns
        -------
        float
            The force (N).
        """
        return contacts.max_normal_force(model, data)

    @abc.abstractmethod
    def state(self, model, data) -> tuple[np.ndarray, np.ndarray]:
        """The measured state in the mechanism's convention.

        Parameters
        ----------
        model, data : mujoco.MjModel, mujoco.MjData
            The simulation.

        Returns
        -------
        tuple of numpy.ndarray
            ``R`` (3, 3), the identity without an orientation, and ``q`` (k,).
        """
