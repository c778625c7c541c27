"""MuJoCo models of the rolling mechanisms: the ball between two plates, a tricycle for the
car and a differential-drive robot for the unicycle.

Each model drives joints whose motion follows from the planned state: it turns the plan
into position and velocity targets of those joints on the simulation's time grid
(:meth:`~nonholo.physics.rolling_model.RollingModel.follow`, the frame the models share),
relative to where the actuators were last commanded, and the actuators track them
(:mod:`nonholo.physics.contact`). None of them is told where the
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
from __future__ import annotations

import numpy as np
from scipy.integrate import cumulative_trapezoid

from ..io.csv_export import states_at
from .rolling_model import RollingModel


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
