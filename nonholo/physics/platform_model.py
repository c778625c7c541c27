"""A MuJoCo model of a two-leg orienting platform, written from its geometry alone.

:class:`PlatformModel` turns a mechanism's :class:`~nonholo.model.geometry.Geometry`
(``base1, tip1, base2, tip2, contact, axle``) into MJCF text and plays a plan on it:

- *Platform*: a sphere of radius ``|contact|`` on a ``ball`` joint at the origin O; sites
  at its joint points ``tip_i`` (platform frame). Its orientation is the quaternion of the
  ball joint, so the measured ``R`` maps platform-frame vectors to the world.
- *Legs* (spherical–prismatic–spherical): a ``ball`` joint at ``base_i`` and a child rod on
  a ``slide`` joint along the leg, whose position is the leg's length (``ref`` is the
  length at ``R = I``). The rod's end is tied to the platform's site by an equality
  ``connect`` (``site1``/``site2``), which closes the loop without tuning the initial
  configuration. The legs are light, so that their weight hardly loads the contact.
- *Disk*: a body just outside the contact point, on a ``slide`` joint along the contact
  normal ``n = contact/|contact|`` and a ``hinge`` about ``axle`` (it spins freely). A
  constant force (an actuator with an affine bias and no gain) presses it on along ``−n``,
  whatever the direction of gravity. Its collision geometry is a small sphere (the rim
  near the contact; sphere–sphere contact is analytic), its drawing a cylinder.
- *Contact*: the one explicit pair sphere–disk, ``condim 3``: no slip in the tangent plane
  (the side slip is the non-holonomic constraint; the slip along the rolling direction is
  taken up by the disk's spin), free spin about the normal. Every other geom collides with
  nothing. Elliptic friction cones; ``impratio`` and ``noslip_iterations`` of the contact
  settings; their ``solref``/``solimp`` for the pair and the two ``connect`` equalities.
- *Drive*: one position actuator per leg slide, on a slide with armature (reflected
  inertia without weight). ``"prescribed"`` is as stiff as the time step allows, with
  feed-forward: the control is ``l + (k_v dl/dt + m_a d²l/dt²)/k_p`` (``m_a`` the armature),
  so the damping and the slide's own inertia act on the tracking error only; ``"servo"``
  has finite gains and is fed the length alone.

:meth:`PlatformModel.follow` samples the played plan's orientations on the model's time
grid — :func:`nonholo.physics.execution.execute` plays plans re-timed rest to rest
(:mod:`nonholo.motion.time_scaling`: the same path, at rest at both ends, so the soft
constraints' lag cancels there) — and turns them into the legs' lengths, offset so that the
legs start where they are commanded now.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from ..io.csv_export import states_at
from ..spaces import so3
from .contact import MAX_STAGE_STEPS

#: The calibrated contact and drive settings used when no ``contact`` is given.
DEFAULTS = {
    "timestep": 5e-4,
    "solref": (0.001, 1.0),
    "solimp": (0.99, 0.999, 0.001, 0.5, 2.0),
    "friction": (1.0, 0.005, 0.0001),
    "noslip_iterations": 20,
    "impratio": 10.0,
    "preload": 100.0,
    "actuators": "prescribed",
}

#: The legs' drives, as the natural frequency (rad/s) of a slide's armature on its position
#: gain, critically damped: ``"prescribed"`` is as stiff as the time step allows (this
#: fraction of ``1/timestep``), ``"servo"`` a finite bandwidth.
DRIVES = {"prescribed": 0.25, "servo": 40.0}

#: Masses: the platform's sphere, one leg (half at its base joint, half in its rod), the disk.
MASSES = {"sphere": 1.0, "leg": 1e-3, "disk": 0.05}

#: Armature (reflected inertia, no weight) of the legs' slides and base joints: it sets the
#: legs' drive frequency ``sqrt(k_p/armature)`` well below ``1/timestep`` without loading
#: the contact with the legs' weight.
ARMATURE = {"slide": 1.0, "base": 0.01}

#: The disk's radius and the legs' drawn thickness, as fractions of the sphere's radius.
DISK_RADIUS = 0.25
LEG_RADIUS = 0.02

#: Settling time (s) of :meth:`PlatformModel.reset`, the platform held at its orientation.
RESET_SETTLE = 0.1


def _fmt(v) -> str:
    """Floats of ``v`` as MJCF text."""
    return " ".join(repr(float(x)) for x in np.atleast_1d(np.asarray(v, dtype=float)))


def _turn(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The quaternion (w, x, y, z) of the least rotation taking unit ``a`` to unit ``b``."""
    c = float(np.dot(a, b))
    if c < -1.0 + 1e-12:                       # opposite: half a turn about any normal
        axis = np.cross(a, [1.0, 0.0, 0.0])
        if np.linalg.norm(axis) < 1e-6:
            axis = np.cross(a, [0.0, 1.0, 0.0])
        axis /= np.linalg.norm(axis)
        return np.array([0.0, *axis])
    q = np.array([1.0 + c, *np.cross(a, b)])
    return q / np.linalg.norm(q)


class PlatformModel:
    """A two-leg orienting platform in MuJoCo, built from ``mechanism.geometry``.

    Parameters
    ----------
    mechanism : Mechanism
        A mechanism with a ``geometry`` (:class:`~nonholo.model.geometry.Geometry`).
    contact : object, optional
        Contact and drive settings: any object with attributes ``timestep, solref, solimp,
        friction, noslip_iterations, impratio, preload, actuators`` (``"prescribed"`` or
        ``"servo"``); an attribute missing or ``None`` takes its value in :data:`DEFAULTS`.
        ``None``: :data:`DEFAULTS`. ``friction`` is ``μ``, ``(μ, torsional, rolling)`` or
        MuJoCo's five values.

    Attributes
    ----------
    mechanism : Mechanism
        The mechanism.
    contact : object
        The ``contact`` given (a namespace of :data:`DEFAULTS` for ``None``).
    geometry : Geometry
        ``mechanism.geometry``.
    settings : dict
        The settings in force: ``contact``'s, completed by :data:`DEFAULTS`.

    Raises
    ------
    ValueError
        If ``mechanism`` has no geometry, or ``contact.actuators`` is not a kind of drive.
    """

    def __init__(self, mechanism, contact=None):
        mech = mechanism
        geometry = getattr(mech, "geometry", None)
        if geometry is None:
            raise ValueError(f"mechanism {getattr(mech, 'name', mech)!r} has no geometry: "
                             "a PlatformModel needs a two-leg platform with a rolling disk")
        self.mechanism = mech
        self.geometry = geometry
        given = {k: getattr(contact, k, None) for k in DEFAULTS}
        given = {k: DEFAULTS[k] if v is None else v for k, v in given.items()}
        if given["actuators"] not in DRIVES:
            raise ValueError(f"contact.actuators must be one of {sorted(DRIVES)}, got {given['actuators']!r}")
        self.contact = contact if contact is not None else SimpleNamespace(**DEFAULTS)
        self.settings = given
        g = geometry
        self.radius = g.radius
        self.normal = g.contact / self.radius
        self.disk_radius = DISK_RADIUS * self.radius
        self.directions = []                   # the legs' directions at R = I
        self.rest_lengths = g.leg_lengths(np.eye(3))
        for base, tip in zip(g.bases, g.tips):
            d = tip - base
            n = np.linalg.norm(d)
            self.directions.append(d / n if n > 1e-9 else np.array([0.0, 0.0, 1.0]))
        self._grid = None                      # follow(): targets on the time grid
        self._hold = None                      # the legs' commands now (their lengths + offset)

    # -- the model ----------------------------------------------------------------------------

    def mjcf(self) -> str:
        """The model as MJCF text.

        Returns
        -------
        str
            A complete ``<mujoco>`` document (angles in radians).
        """
        s, g = self.settings, self.geometry
        kp, kv = self.gains()
        rho, rd = self.radius, self.disk_radius
        mu = np.atleast_1d(np.asarray(s["friction"], dtype=float))
        if mu.size < 5:                        # (sliding, torsional, rolling), defaults after
            mu = np.concatenate([mu, DEFAULTS["friction"][mu.size:]])
            mu = np.array([mu[0], mu[0], mu[1], mu[2], mu[2]])
        friction = _fmt(mu[:5])
        soft = f'solref="{_fmt(s["solref"])}" solimp="{_fmt(s["solimp"])}"'
        legs, connects, drives = [], [], []
        for i, (base, tip, d, l0) in enumerate(zip(g.bases, g.tips, self.directions, self.rest_lengths), 1):
            m = MASSES["leg"] / 2
            legs.append(f"""
    <body name="leg{i}" pos="{_fmt(base)}">
      <joint name="leg{i}_base" type="ball" armature="{_fmt(ARMATURE['base'])}"/>
      <geom type="sphere" size="{_fmt(2 * LEG_RADIUS * rho)}" mass="{_fmt(m)}" rgba=".4 .4 .4 1"/>
      <body name="leg{i}_rod" pos="{_fmt(l0 * d)}">
        <joint name="leg{i}" type="slide" axis="{_fmt(d)}" ref="{_fmt(l0)}" armature="{_fmt(ARMATURE['slide'])}"/>
        <geom type="capsule" fromto="{_fmt(-l0 * d)} 0 0 0" size="{_fmt(LEG_RADIUS * rho)}" mass="{_fmt(m)}" rgba=".8 .5 .2 1"/>
        <site name="leg{i}_end"/>
      </body>
    </body>""")
            connects.append(f'    <connect name="leg{i}" site1="leg{i}_end" site2="tip{i}" {soft}/>')
            drives.append(f'    <position name="leg{i}" joint="leg{i}" kp="{_fmt(kp)}" kv="{_fmt(kv)}"/>')
        tips = "\n".join(f'      <site name="tip{i}" pos="{_fmt(t)}" size="{_fmt(0.03 * rho)}"/>'
                         for i, t in enumerate(g.tips, 1))
        centre = (rho + rd) * self.normal
        half = 0.1 * rd
        return f"""<mujoco model="{self.mechanism.name}">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{_fmt(s['timestep'])}" integrator="implicitfast" cone="elliptic"
          impratio="{_fmt(s['impratio'])}" noslip_iterations="{int(s['noslip_iterations'])}"/>
  <default>
    <geom contype="0" conaffinity="0"/>
  </default>
  <worldbody>
    <light pos="0 0 6" dir="0 0 -1"/>
    <body name="platform">
      <joint name="platform" type="ball"/>
      <geom name="sphere" type="sphere" size="{_fmt(rho)}" mass="{_fmt(MASSES['sphere'])}" rgba=".3 .5 .8 .6"/>
{tips}
    </body>{''.join(legs)}
    <body name="disk" pos="{_fmt(centre)}">
      <joint name="disk_press" type="slide" axis="{_fmt(self.normal)}"/>
      <joint name="disk_spin" type="hinge" axis="{_fmt(g.axle)}"/>
      <geom name="disk" type="sphere" size="{_fmt(rd)}" mass="{_fmt(MASSES['disk'])}" group="3"/>
      <geom type="cylinder" fromto="{_fmt(-half * g.axle)} {_fmt(half * g.axle)}" size="{_fmt(rd)}" mass="0" rgba=".2 .2 .2 1"/>
    </body>
  </worldbody>
  <contact>
    <pair geom1="sphere" geom2="disk" condim="3" friction="{friction}" {soft}/>
  </contact>
  <equality>
{chr(10).join(connects)}
  </equality>
  <actuator>
{chr(10).join(drives)}
    <general name="preload" joint="disk_press" gainprm="0" biastype="affine" biasprm="{_fmt(-float(s['preload']))} 0 0"/>
  </actuator>
</mujoco>
"""

    def gains(self) -> tuple[float, float]:
        """The legs' position and velocity gains (:data:`DRIVES`).

        Returns
        -------
        tuple of float
            ``(k_p, k_v)``.
        """
        kind = self.settings["actuators"]
        omega = DRIVES[kind] / float(self.settings["timestep"]) if kind == "prescribed" else DRIVES[kind]
        mass = ARMATURE["slide"]
        return mass * omega**2, 2.0 * mass * omega

    # -- state --------------------------------------------------------------------------------

    def reset(self, model, data, R, q) -> None:
        """Put the platform at orientation ``R``, the legs at their lengths and the disk on
        the sphere, at rest: the disk and the legs settle for :data:`RESET_SETTLE` seconds
        while the platform is held at ``R``.

        Parameters
        ----------
        model, data : mujoco.MjModel, mujoco.MjData
            The model of :meth:`mjcf` and its data.
        R : array_like
            The platform's orientation (3, 3).
        q : array_like
            The coordinates, shape ``(0,)``.

        Raises
        ------
        ValueError
            If ``R`` is not a rotation or ``q`` is not empty.
        """
        import mujoco

        if np.size(q):
            raise ValueError(f"q must be empty for a platform on SO(3), got shape {np.shape(q)}")
        R = so3.check_rotation(R, "R")
        mujoco.mj_resetData(model, data)
        quat = np.empty(4)
        mujoco.mju_mat2Quat(quat, np.ascontiguousarray(R).ravel())
        lengths = self.geometry.leg_lengths(R)
        adr = {name: model.jnt_qposadr[model.joint(name).id] for name in
               ("platform", "leg1_base", "leg1", "leg2_base", "leg2", "disk_press", "disk_spin")}
        data.qpos[adr["platform"]:adr["platform"] + 4] = quat
        for i, (base, tip, d0) in enumerate(zip(self.geometry.bases, self.geometry.tips, self.directions), 1):
            d = R @ tip - base
            d = d / np.linalg.norm(d)
            a = adr[f"leg{i}_base"]
            data.qpos[a:a + 4] = _turn(d0, d)
            data.qpos[adr[f"leg{i}"]] = lengths[i - 1]
        data.qpos[adr["disk_press"]] = 0.0
        data.qpos[adr["disk_spin"]] = 0.0
        data.qvel[:] = 0.0
        self._hold = lengths.copy()
        self._grid = None
        data.ctrl[:2] = lengths
        mujoco.mj_forward(model, data)
        held = slice(adr["platform"], adr["platform"] + 4)
        vel = model.jnt_dofadr[model.joint("platform").id]
        for _ in range(round(RESET_SETTLE / model.opt.timestep)):
            mujoco.mj_step(model, data)
            data.qpos[held] = quat
            data.qvel[vel:vel + 3] = 0.0
        data.qvel[:] = 0.0
        data.qacc_warmstart[:] = 0.0
        data.time = 0.0
        mujoco.mj_forward(model, data)

    def state(self, model, data) -> tuple[np.ndarray, np.ndarray]:
        """The measured state.

        Parameters
        ----------
        model, data : mujoco.MjModel, mujoco.MjData
            The model and its data.

        Returns
        -------
        tuple of numpy.ndarray
            ``R`` (3, 3), the platform's orientation, and ``q``, shape ``(0,)``.
        """
        import mujoco

        a = model.jnt_qposadr[model.joint("platform").id]
        quat = np.array(data.qpos[a:a + 4])
        R = np.empty(9)
        mujoco.mju_quat2Mat(R, quat / np.linalg.norm(quat))
        return R.reshape(3, 3), np.zeros(0)

    # -- playing ------------------------------------------------------------------------------

    def follow(self, played, R, q) -> None:
        """Prepare to play the plan ``played`` from the measured state ``(R, q)``: its
        orientations on the model's time grid, as the legs' lengths (a plan to be played from
        rest to rest is re-timed so first: ``retime(result, T=…, rest_to_rest=True)``).
        The legs' commands start at their present values (those of :meth:`reset` or of the
        end of the last play), offset from the plan's lengths by the difference at the start.

        Parameters
        ----------
        played : PlanResult
            A successful plan of this mechanism, over ``[0, played.T]``.
        R : array_like
            The measured orientation (3, 3), the plan's start.
        q : array_like
            The measured coordinates, shape ``(0,)``.

        Raises
        ------
        ValueError
            If ``played`` is a plan of another mechanism or did not reach its end, or takes
            more than :data:`~nonholo.physics.contact.MAX_STAGE_STEPS` time steps, ``R`` is
            not a rotation or ``q`` is not empty.
        """
        if np.size(q):
            raise ValueError(f"q must be empty for a platform on SO(3), got shape {np.shape(q)}")
        R = so3.check_rotation(R, "R")
        name = getattr(played.kinematics, "name", None)
        if name != self.mechanism.name:
            raise ValueError(f"played is a plan of mechanism {name!r}, this model is of {self.mechanism.name!r}")
        T = float(played.T)
        dt = float(self.settings["timestep"])
        steps = T / dt
        if not steps <= MAX_STAGE_STEPS:       # checked before anything is allocated
            raise ValueError(f"played: a motion of {T:g} s takes {steps:.3g} time steps of {dt:g} s, more "
                             f"than MAX_STAGE_STEPS = {MAX_STAGE_STEPS:.3g}")
        n = int(np.ceil(steps - 1e-9))
        t = np.arange(n + 1) * dt
        Rs, _ = states_at(played, np.minimum(t, T))
        lengths = self.geometry.leg_lengths(Rs)
        here = self.geometry.leg_lengths(R)
        targets = lengths - here + (here if self._hold is None else self._hold)
        speeds = np.gradient(targets, dt, axis=0) if n > 1 else np.zeros_like(targets)
        accelerations = np.gradient(speeds, dt, axis=0) if n > 1 else np.zeros_like(targets)
        commands = targets
        if self.settings["actuators"] == "prescribed":
            kp, kv = self.gains()
            commands = targets + (kv * speeds + ARMATURE["slide"] * accelerations) / kp
        self._grid = (dt, targets, commands)

    def drive(self, model, data, t: float) -> None:
        """Set the legs' controls for time ``t`` of the play prepared by :meth:`follow` (held
        at its ends outside ``[0, T]``; at the last commands without a play).

        Parameters
        ----------
        model, data : mujoco.MjModel, mujoco.MjData
            The model and its data.
        t : float
            Time since the play's start (s).
        """
        if self._grid is None:
            if self._hold is not None:
                data.ctrl[:2] = self._hold
            return
        dt, targets, commands = self._grid
        last = len(targets) - 1
        k = min(max(float(t) / dt, 0.0), float(last))
        i = min(int(k), max(last - 1, 0))
        f = k - i
        j = min(i + 1, last)
        self._hold = (1 - f) * targets[i] + f * targets[j]
        data.ctrl[:2] = (1 - f) * commands[i] + f * commands[j]

    # -- measurements -------------------------------------------------------------------------

    def _pairs(self, model, data):
        """The contacts between the sphere and the disk now."""
        ids = {model.geom("sphere").id, model.geom("disk").id}
        return [i for i in range(data.ncon) if {data.contact[i].geom1, data.contact[i].geom2} == ids]

    def slip(self, model, data) -> float:
        """The largest tangential speed at the disk's contact now: the sphere's velocity
        relative to the disk's at the contact point, in the tangent plane.

        Parameters
        ----------
        model, data : mujoco.MjModel, mujoco.MjData
            The model and its data.

        Returns
        -------
        float
            The speed (length units per second); 0 without contact.
        """
        import mujoco

        sphere, disk = model.body("platform").id, model.body("disk").id
        jp = np.empty((3, model.nv))
        out = 0.0
        for i in self._pairs(model, data):
            c = data.contact[i]
            p = np.array(c.pos)
            mujoco.mj_jac(model, data, jp, None, p, sphere)
            v = jp @ data.qvel
            mujoco.mj_jac(model, data, jp, None, p, disk)
            v = v - jp @ data.qvel
            n = np.array(c.frame[:3])
            out = max(out, float(np.linalg.norm(v - np.dot(v, n) * n)))
        return out

    def contact_force(self, model, data) -> float:
        """The largest normal force at the disk's contact now.

        Parameters
        ----------
        model, data : mujoco.MjModel, mujoco.MjData
            The model and its data.

        Returns
        -------
        float
            The force (model units); 0 without contact.
        """
        import mujoco

        f = np.empty(6)
        out = 0.0
        for i in self._pairs(model, data):
            mujoco.mj_contactForce(model, data, i, f)
            out = max(out, float(f[0]))
        return out
