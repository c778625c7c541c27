"""MuJoCo models of the rolling mechanisms: the ball between two plates, a tricycle for the
car and a differential-drive robot for the unicycle.

Each model drives joints whose motion follows from the planned state: it turns the plan
into position and velocity targets of those joints on the simulation's time grid
(:meth:`RollingModel.follow`), relative to where the actuators were last commanded, and the
actuators track them (:mod:`nonholo.physics.contact`). None of them is told where the
mechanism should be: the rolling contacts alone carry the motion to the state measured.

- :class:`BallModel` (``rolling_ball``): the ball of radius ``ρ = 1`` lies on the floor
  under a horizontal top plate pressed down on it. The plate slides at ``(r_f + r_p)/ρ``
  times the centre's planned velocity (twice it for rigid contacts), ``r_f, r_p`` the
  rolling radii at the floor and at the plate: rolling without slipping on both, the
  ball then turns at the planned ``ω = e₃ × v / ρ`` with no spin about the vertical, which
  contacts at its poles cannot excite.
- :class:`CarModel` (``car``): a tricycle. Two free rear wheels on the axle, whose midpoint
  is the state's ``(x, y)``, and a front wheel one wheelbase ahead, steered to ``φ(t)``
  about the vertical through its contact and spun so that its contact moves at
  ``v / cos φ``, which makes the rear axle move at ``v``. The rear wheels turn
  independently, so turning scrubs nothing (a driven rear axle would slip in turns).
- :class:`UnicycleModel` (``unicycle``): two driven wheels at ``±b`` from the midpoint,
  spun at ``(v ∓ ω b)/r``, and frictionless casters fore and aft.

The wheels are spheres on hinges: each touches the floor at one point below its centre,
so its rolling radius is that of a ball, ``r − δ/2`` on a soft contact.
"""
# ruff: noqa: TRY004 (bad input is refused by a ValueError naming the argument, as across the package)
from __future__ import annotations

import abc

import numpy as np
from scipy.integrate import cumulative_trapezoid

from ..io.csv_export import states_at
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


def quaternion(R) -> np.ndarray:
    """The unit quaternion ``(w, x, y, z)`` of a rotation matrix (MuJoCo's order).

    Parameters
    ----------
    R : array_like
        A rotation matrix.

    Returns
    -------
    numpy.ndarray
        Shape ``(4,)``, ``w ≥ 0``.
    """
    import mujoco

    out = np.zeros(4)
    mujoco.mju_mat2Quat(out, np.ascontiguousarray(R, dtype=float).reshape(9))
    return out / np.linalg.norm(out)


def yaw_quaternion(theta: float) -> np.ndarray:
    """The quaternion ``(w, x, y, z)`` of a turn by ``theta`` about the vertical.

    Parameters
    ----------
    theta : float
        The heading (rad).

    Returns
    -------
    numpy.ndarray
        Shape ``(4,)``.
    """
    return np.array([np.cos(theta / 2), 0.0, 0.0, np.sin(theta / 2)])


def wrap(angle):
    """An angle wrapped into ``[−π, π)``.

    Parameters
    ----------
    angle : float or array_like
        Angles (rad).

    Returns
    -------
    numpy.ndarray
        The wrapped angles.
    """
    return (np.asarray(angle) + np.pi) % (2 * np.pi) - np.pi


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


def _documented(cls):
    """``cls`` with the docstrings of its base classes' methods on its overrides that have none."""
    for name, member in vars(cls).items():
        if callable(member) and not member.__doc__:
            for base in cls.__mro__[1:]:
                doc = getattr(getattr(base, name, None), "__doc__", None)
                if doc:
                    member.__doc__ = doc
                    break
    return cls


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


def planned(played, t) -> tuple[np.ndarray, np.ndarray]:
    """The planned states of ``played`` at times ``t`` (:func:`nonholo.io.csv_export.states_at`).

    Parameters
    ----------
    played : PlanResult
        The motion.
    t : numpy.ndarray
        Sorted times in ``[0, T]``.

    Returns
    -------
    tuple of numpy.ndarray
        ``R (n, 3, 3)`` and ``q (n, k)``.
    """
    return states_at(played, np.minimum(np.asarray(t, dtype=float), float(played.t[-1])))


@_documented
class BallModel(RollingModel):
    """The rolling ball between the floor and a top plate (see the module).

    Parameters
    ----------
    mechanism : Mechanism
        The ``rolling_ball`` mechanism (radius 1).
    contact : Contact, optional
        The settings.
    """

    name = "rolling_ball"
    RADIUS = 1.0
    BALL_MASS = 1.0
    PLATE_MASS = 1.0
    #: Half-width of the top plate (the ball stays under it).
    PLATE = 50.0
    driven = (("plate_x", PLATE_MASS + BALL_MASS), ("plate_y", PLATE_MASS + BALL_MASS))
    rolling = (("floor", "ball", "floor", RADIUS), ("plate", "ball", "plate", RADIUS))

    def bodies(self) -> str:
        r, w = float(self.RADIUS), float(self.PLATE)
        return "\n".join([
            f'    <body name="ball" pos="0 0 {r!r}">',
            '      <freejoint name="ball"/>',
            (f'      <geom name="ball" type="sphere" size="{r!r}" mass="{float(self.BALL_MASS)!r}" '
             'rgba="0.2 0.4 0.8 1"/>'),
            "    </body>",
            f'    <body name="plate" pos="0 0 {2 * r!r}">',
            '      <joint name="plate_x" type="slide" axis="1 0 0"/>',
            '      <joint name="plate_y" type="slide" axis="0 1 0"/>',
            '      <joint name="plate_z" type="slide" axis="0 0 1"/>',
            (f'      <geom name="plate" type="box" size="{w!r} {w!r} 0.05" pos="0 0 0.05" '
             f'mass="{float(self.PLATE_MASS)!r}" rgba="0.6 0.6 0.6 0.4"/>'),
            "    </body>"])

    def extra_actuators(self) -> str:
        return '    <motor name="press" joint="plate_z" gear="1"/>'

    def place(self, model, data, R, q) -> None:
        data.qpos[0:3] = [q[0], q[1], self.RADIUS]
        data.qpos[3:7] = quaternion(R)
        data.qpos[7:10] = [q[0], q[1], 0.0]

    def pressing(self, model, data) -> None:
        import mujoco

        data.ctrl[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, "press")] = -self.contact.preload

    def displacements(self, played, t, R, q):
        _, qp = planned(played, t)
        v = played.controls(t)
        k = (self.radii["floor"] + self.radii["plate"]) / self.RADIUS
        return k * qp, k * v

    def state(self, model, data):
        import mujoco

        b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "ball")
        R = np.array(data.xmat[b]).reshape(3, 3)
        return R, np.array(data.xpos[b][:2])


@_documented
class WheeledModel(RollingModel):
    """A chassis on a free joint carrying sphere wheels on hinges; its origin at wheel-centre
    height above the point the state's ``(x, y)`` names, its ``x`` axis the heading.

    Parameters
    ----------
    mechanism : Mechanism
        The numeric mechanism.
    contact : Contact, optional
        The settings (default: ``Contact()``), resolved for the mechanism.
    """

    WHEEL = 0.15
    CHASSIS_MASS = 2.0
    WHEEL_MASS = 0.1

    def pressing(self, model, data) -> None:
        import mujoco

        b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "chassis")
        data.xfrc_applied[b] = [0.0, 0.0, -self.contact.preload, 0.0, 0.0, 0.0]

    def wheel(self, name: str, pos, axis="0 1 0", driven=False) -> str:
        """The MJCF of one sphere wheel on a hinge.

        Parameters
        ----------
        name : str
            The wheel's body, joint and geom name.
        pos : str
            Its position in the chassis frame (MJCF numbers).
        axis : str
            The hinge's axis in the chassis frame.
        driven : bool
            Whether an actuator drives it (its rotor inertia is then the tracking's).

        Returns
        -------
        str
            The ``<body>`` element.
        """
        r = float(self.WHEEL)
        # a driven wheel's rotor: the tracking's inertia, whatever the contact transmits
        rotor = f' armature="{float(dict(self.driven)[name])!r}"' if driven else ""
        return "\n".join([
            f'      <body name="{name}" pos="{pos}">',
            f'        <joint name="{name}" type="hinge" axis="{axis}"{rotor}/>',
            (f'        <geom name="{name}" type="sphere" size="{r!r}" mass="{float(self.WHEEL_MASS)!r}" '
             f'rgba="{"0.8 0.3 0.2 1" if driven else "0.2 0.2 0.2 1"}"/>'),
            "      </body>"])

    def heading(self, model, data) -> float:
        """The chassis's heading, continued from the last one read (no jump of 2π).

        Parameters
        ----------
        model, data : mujoco.MjModel, mujoco.MjData
            The model and its data.

        Returns
        -------
        float
            The heading (rad).
        """
        import mujoco

        b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "chassis")
        m = np.array(data.xmat[b]).reshape(3, 3)
        theta = float(np.arctan2(m[1, 0], m[0, 0]))
        ref = getattr(self, "_heading", theta)
        theta = ref + float(wrap(theta - ref))
        self._heading = theta
        return theta

    def chassis_xy(self, model, data) -> np.ndarray:
        """The chassis origin's ``(x, y)``.

        Parameters
        ----------
        model, data : mujoco.MjModel, mujoco.MjData
            The model and its data.

        Returns
        -------
        numpy.ndarray
            Shape ``(2,)``.
        """
        import mujoco

        b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "chassis")
        return np.array(data.xpos[b][:2])

    def place_chassis(self, data, x, y, theta) -> None:
        """Put the chassis at ``(x, y)`` with heading ``theta``, its wheels on the floor.

        Parameters
        ----------
        data : mujoco.MjData
            The model's data.
        x, y : float
            The position.
        theta : float
            The heading (rad).
        """
        data.qpos[0:3] = [x, y, self.WHEEL]
        data.qpos[3:7] = yaw_quaternion(theta)
        self._heading = float(theta)


@_documented
class CarModel(WheeledModel):
    """The car as a tricycle (see the module).

    Parameters
    ----------
    mechanism : Mechanism
        The ``car`` mechanism (wheelbase 1).
    contact : Contact, optional
        The settings.
    """

    name = "car"
    WHEELBASE = 1.0
    TRACK = 0.6
    driven = (("steer", 0.02), ("front", 0.05))
    rolling = (("front", "front", "floor", WheeledModel.WHEEL),)

    def bodies(self) -> str:
        L, w = float(self.WHEELBASE), float(self.TRACK)
        return "\n".join([
            f'    <body name="chassis" pos="0 0 {float(self.WHEEL)!r}">',
            '      <freejoint name="chassis"/>',
            (f'      <geom name="frame" type="box" size="{L / 2 + 0.1!r} {w / 2 - 0.05!r} 0.03" '
             f'pos="{L / 2!r} 0 0.12" mass="{float(self.CHASSIS_MASS)!r}" contype="0" conaffinity="0" '
             'rgba="0.3 0.6 0.3 1"/>'),
            self.wheel("rear_left", f"0 {w / 2!r} 0"),
            self.wheel("rear_right", f"0 {-w / 2!r} 0"),
            f'      <body name="steering" pos="{L!r} 0 0">',
            f'        <joint name="steer" type="hinge" axis="0 0 1" armature="{float(dict(self.driven)["steer"])!r}"/>',
            ('        <geom name="fork" type="cylinder" size="0.02 0.1" pos="0 0 0.1" mass="0.05" '
             'contype="0" conaffinity="0"/>'),
            "\n".join("  " + line for line in self.wheel("front", "0 0 0", driven=True).split("\n")),
            "      </body>",
            "    </body>"])

    def place(self, model, data, R, q) -> None:
        self.place_chassis(data, q[0], q[1], q[2])
        import mujoco

        j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "steer")
        data.qpos[model.jnt_qposadr[j]] = q[3]

    def displacements(self, played, t, R, q):
        _, qp = planned(played, t)
        u = played.controls(t)
        rate = u[:, 0] / np.cos(qp[:, 3]) / self.radii["front"]
        spin = cumulative_trapezoid(rate, t, initial=0.0)
        return np.column_stack([qp[:, 3], spin]), np.column_stack([u[:, 1], rate])

    def state(self, model, data):
        import mujoco

        j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "steer")
        x, y = self.chassis_xy(model, data)
        return np.eye(3), np.array([x, y, self.heading(model, data), float(data.qpos[model.jnt_qposadr[j]])])


@_documented
class UnicycleModel(WheeledModel):
    """The unicycle as a differential-drive robot (see the module).

    Parameters
    ----------
    mechanism : Mechanism
        The ``unicycle`` mechanism.
    contact : Contact, optional
        The settings.
    """

    name = "unicycle"
    HALF_TRACK = 0.3
    CASTER = 0.05
    driven = (("left", 0.05), ("right", 0.05))
    rolling = (("left", "left", "floor", WheeledModel.WHEEL), ("right", "right", "floor", WheeledModel.WHEEL))

    def bodies(self) -> str:
        b, r, c = float(self.HALF_TRACK), float(self.WHEEL), float(self.CASTER)
        caster = (f'type="sphere" size="{c!r}" condim="1" priority="1" mass="0.01" '
                  'rgba="0.5 0.5 0.5 1"')
        return "\n".join([
            f'    <body name="chassis" pos="0 0 {r!r}">',
            '      <freejoint name="chassis"/>',
            (f'      <geom name="frame" type="box" size="0.45 {b - 0.05!r} 0.03" pos="0 0 0.12" '
             f'mass="{float(self.CHASSIS_MASS)!r}" contype="0" conaffinity="0" rgba="0.3 0.3 0.6 1"/>'),
            f'      <geom name="caster_front" pos="0.4 0 {c - r!r}" {caster}/>',
            f'      <geom name="caster_back" pos="-0.4 0 {c - r!r}" {caster}/>',
            self.wheel("left", f"0 {b!r} 0", driven=True),
            self.wheel("right", f"0 {-b!r} 0", driven=True),
            "    </body>"])

    def place(self, model, data, R, q) -> None:
        self.place_chassis(data, q[0], q[1], q[2])

    def displacements(self, played, t, R, q):
        _, qp = planned(played, t)
        u = played.controls(t)
        b = self.HALF_TRACK
        s = cumulative_trapezoid(u[:, 0], t, initial=0.0)
        turn = qp[:, 2] - qp[0, 2]
        pos = np.column_stack([(s - b * turn) / self.radii["left"], (s + b * turn) / self.radii["right"]])
        vel = np.column_stack([(u[:, 0] - b * u[:, 1]) / self.radii["left"],
                               (u[:, 0] + b * u[:, 1]) / self.radii["right"]])
        return pos, vel

    def state(self, model, data):
        x, y = self.chassis_xy(model, data)
        return np.eye(3), np.array([x, y, self.heading(model, data)])
