"""Classic non-holonomic mechanisms beyond SO(3), derived from their constraints.

- :func:`rolling_ball`: a ball of radius ρ rolling without slipping or spinning on the
  plane z = 0; state ``(R, p) ∈ SO(3) × R²``, inputs ``v = ṗ``.
- :func:`kinematic_car`: the kinematic car with the steering angle as a state,
  ``x = (x, y, θ, φ) ∈ R⁴``, inputs ``(v, φ̇)``; singular where ``cos φ = 0``.
- :func:`car_with_trailer`: the same car towing a trailer hitched at its rear axle,
  ``(x, y, θ, φ, θ₁) ∈ R⁵``, as Dynobench's ``car1`` (wheelbase 0.25, hitch 0.5).
- :func:`unicycle`: the wheel rolling upright on the plane, ``(x, y, θ) ∈ R³``, inputs
  ``(v, ω)``.
- :func:`brockett_integrator`: Brockett's non-holonomic integrator, ``(x, y, z) ∈ R³``,
  ``ẋ = u₁``, ``ẏ = u₂``, ``ż = x u₂ − y u₁``: the textbook system whose least-energy
  motions (circles) are known in closed form.
- :func:`double_integrator`: a planar point mass driven by accelerations,
  ``(x, y, ẋ, ẏ) ∈ R⁴``: the linear system with drift whose least-energy motions are known
  in closed form (the controllability Gramian).
- :func:`second_order_unicycle`: the unicycle driven by its accelerations,
  ``(x, y, θ, v, ω) ∈ R⁵``, as Dynobench's ``unicycle2_v0`` models it.

The last two have drift, ``ẋ = f(x) + G(x) u``: they are written as their equations of
motion (:func:`derivations.equations.field_mechanism`). The others are built as the platform is (:mod:`derivations.mechanisms`): the constraints are
written as linear equations in the unknown rates, solved symbolically, and the
determinant of the constraint matrix gives the singularity function (none vanishes for
the last two).
"""
from __future__ import annotations

import sympy as sp

from . import admission
from .mechanisms import Mechanism, input_map
from .rotations import e3


def rolling_ball(radius=1, name: str = "rolling_ball") -> Mechanism:
    """The ball rolling on the plane z = 0 (radius ``radius``, centre at height ρ).

    ``name``: the mechanism's name (a variant of another radius needs its own).

    Unknown: the spatial angular velocity ``ω``. Constraints, for the input ``v = ṗ``
    (``ṗ = (v₁, v₂, 0)``): the contact point ``p − ρ e₃`` does not slip,
    ``ṗ + ω × (−ρ e₃) = 0`` (its vertical component is ``0 = 0``), and the ball does
    not spin about the vertical, ``ω · e₃ = 0``. Solved: ``ω = (e₃ × ṗ)/ρ``.
    """
    admission.constant(radius, "radius")            # a number (never text: nsimplify would evaluate it)
    rho = sp.Integer(radius) if isinstance(radius, int) else sp.nsimplify(radius)
    p1, p2 = sp.symbols("p1 p2", real=True)
    v = sp.Matrix(sp.symbols("v1:3", real=True))
    w = sp.Matrix(sp.symbols("omega1:4", real=True))
    pdot = sp.Matrix([v[0], v[1], 0])
    slip = pdot + w.cross(-rho * e3)
    equations = [slip[0], slip[1], w.dot(e3)]
    C, rhs = sp.linear_eq_to_matrix(equations, list(w))
    solution = C.LUsolve(rhs)
    Omega = sp.Matrix(solution).jacobian(v).applyfunc(sp.simplify)
    return Mechanism(
        name=name,
        description=f"ball of radius {rho} rolling without slipping or spinning on the plane z = 0",
        inputs=("v1 = dp1/dt", "v2 = dp2/dt"),
        coordinates=(p1, p2), units=("radius", "radius"), angles=(False, False),
        L=Omega, X=sp.eye(2),
        derivation={"constraint_matrix": C, "constraint_rhs": rhs, "radius": rho},
    )


def kinematic_car(wheelbase=1, name: str = "car") -> Mechanism:
    """The kinematic car with steering angle ``φ`` as a state (wheelbase ``ℓ``; ``name``:
    the mechanism's name, which a variant of another wheelbase needs its own of).

    Unknown: ``(ẋ, ẏ, θ̇)`` of the rear axle's midpoint ``(x, y)`` and the heading ``θ``.
    Constraints: the rear wheels roll along the heading at the speed ``v``
    (``ẋ cos θ + ẏ sin θ = v``) without side slip (``−ẋ sin θ + ẏ cos θ = 0``); the front
    wheels, at ``(x, y) + ℓ (cos θ, sin θ)`` and turned by ``φ``, do not slip sideways
    either. The steering angle is driven directly, ``φ̇ = u₂``. The constraint matrix's
    determinant is ``ℓ cos φ``: ``Δ = cos φ``, and ``θ̇ = v tan φ / ℓ`` blows up where it
    vanishes. The desingularised field scales the first column by ``cos φ``
    (``w₁ = v / cos φ``... in physical terms ``v = w₁ cos φ``): finite everywhere and, with
    ``ℓ = 1``, orthonormal.
    """
    admission.constant(wheelbase, "wheelbase")      # a number (never text: nsimplify would evaluate it)
    ell = sp.Integer(wheelbase) if isinstance(wheelbase, int) else sp.nsimplify(wheelbase)
    x, y, th, ph = sp.symbols("x y theta phi", real=True)
    v, u2 = sp.symbols("v u2", real=True)
    xd, yd, thd = sp.symbols("xdot ydot thetadot", real=True)
    front = (xd - ell * sp.sin(th) * thd, yd + ell * sp.cos(th) * thd)
    equations = [xd * sp.cos(th) + yd * sp.sin(th) - v,
                 -xd * sp.sin(th) + yd * sp.cos(th),
                 -front[0] * sp.sin(th + ph) + front[1] * sp.cos(th + ph)]
    C, rhs = sp.linear_eq_to_matrix(equations, [xd, yd, thd])
    det = sp.simplify(sp.trigsimp(sp.expand_trig(C.det())))
    delta = sp.simplify(det / ell)
    rates = C.LUsolve(rhs).applyfunc(lambda e: sp.simplify(sp.trigsimp(sp.expand_trig(e))))
    first = sp.Matrix([*rates, 0]).diff(v).applyfunc(sp.simplify)
    X = sp.Matrix.hstack(first, sp.Matrix([0, 0, 0, 1]))
    frame = sp.Matrix.hstack((first * delta).applyfunc(sp.simplify), sp.Matrix([0, 0, 0, 1]))
    return Mechanism(
        name=name,
        description=f"kinematic car with the steering angle as a state (wheelbase {ell})",
        inputs=("v = rear-axle speed", "u2 = dphi/dt"),
        coordinates=(x, y, th, ph), units=("wheelbase", "wheelbase", "rad", "rad"),
        angles=(False, False, True, True),
        X=X, delta=delta, frame=frame,
        frame_inputs=input_map(X, frame).applyfunc(sp.simplify),
        derivation={"constraint_matrix": C, "constraint_rhs": rhs, "determinant": det,
                    "wheelbase": ell},
    )


def unicycle(name: str = "unicycle") -> Mechanism:
    """The unicycle: a wheel rolling upright on the plane, contact point ``(x, y)``, heading
    ``θ``; inputs the rolling speed ``v`` and the turning rate ``ω``.

    Unknown: ``(ẋ, ẏ, θ̇)``. Constraints: the wheel rolls along its heading at the speed
    ``v`` (``ẋ cos θ + ẏ sin θ = v``) without side slip (``−ẋ sin θ + ẏ cos θ = 0``) and
    turns at ``θ̇ = ω``. The constraint matrix is a rotation (determinant 1): no singular
    set. Solved: ``ẋ = v cos θ``, ``ẏ = v sin θ``, ``θ̇ = ω``.
    """
    x, y, th = sp.symbols("x y theta", real=True)
    v, w = sp.symbols("v omega", real=True)
    xd, yd, thd = sp.symbols("xdot ydot thetadot", real=True)
    equations = [xd * sp.cos(th) + yd * sp.sin(th) - v, -xd * sp.sin(th) + yd * sp.cos(th), thd - w]
    C, rhs = sp.linear_eq_to_matrix(equations, [xd, yd, thd])
    det = sp.simplify(C.det())
    rates = C.LUsolve(rhs).applyfunc(lambda e: sp.simplify(sp.trigsimp(e)))
    X = rates.jacobian([v, w]).applyfunc(sp.simplify)
    return Mechanism(
        name=name,
        description="unicycle: a wheel rolling upright on the plane without side slip",
        inputs=("v = rolling speed", "omega = dtheta/dt"),
        coordinates=(x, y, th), units=("m", "m", "rad"), angles=(False, False, True),
        X=X, derivation={"constraint_matrix": C, "constraint_rhs": rhs, "determinant": det},
    )


def brockett_integrator(name: str = "brockett") -> Mechanism:
    """Brockett's non-holonomic integrator: ``ẋ = u₁``, ``ẏ = u₂``, ``ż = x u₂ − y u₁``.

    Unknown: ``(ẋ, ẏ, ż)``; the equations as linear constraints in them (the third:
    ``z`` grows at twice the rate the area swept by ``(x, y)`` round the origin grows).
    The constraint matrix is the identity: no singular set. The least energy from
    ``(0, 0, 0)`` to ``(0, 0, a)`` in time ``T`` is ``2π|a|`` (one circle of area
    ``|a|/2``), the benchmark of :mod:`benchmarks.optimality`.
    """
    x, y, z = sp.symbols("x y z", real=True)
    u1, u2 = sp.symbols("u1 u2", real=True)
    xd, yd, zd = sp.symbols("xdot ydot zdot", real=True)
    equations = [xd - u1, yd - u2, zd - (x * u2 - y * u1)]
    C, rhs = sp.linear_eq_to_matrix(equations, [xd, yd, zd])
    rates = C.LUsolve(rhs)
    X = rates.jacobian([u1, u2]).applyfunc(sp.expand)
    return Mechanism(
        name=name,
        description="Brockett's non-holonomic integrator (x' = u1, y' = u2, z' = x u2 - y u1)",
        inputs=("u1 = dx/dt", "u2 = dy/dt"),
        coordinates=(x, y, z), units=("", "", ""), angles=(False, False, False),
        X=X, derivation={"constraint_matrix": C, "constraint_rhs": rhs, "determinant": C.det()},
    )


def double_integrator(name: str = "double_integrator") -> Mechanism:
    """A planar point mass of unit mass driven by the force ``(a_x, a_y)``: ``ẋ = v_x``,
    ``ẏ = v_y``, ``v̇_x = a_x``, ``v̇_y = a_y``. The drift ``(v_x, v_y, 0, 0)`` moves it at
    rest; the least energy from rest to rest over a distance ``d`` in time ``T`` is
    ``12 d²/T³``.
    """
    from .equations import field_mechanism

    x, y, vx, vy, ax, ay = sp.symbols("x y vx vy ax ay", real=True)
    return field_mechanism(
        name, coordinates=[x, y, vx, vy], inputs=[ax, ay], rates=[vx, vy, ax, ay],
        units=["m", "m", "m/s", "m/s"],
        description="double integrator: a planar point mass driven by accelerations")


def second_order_unicycle(name: str = "unicycle2") -> Mechanism:
    """The unicycle driven by its accelerations (Dynobench's ``unicycle2``): ``ẋ = v cos θ``,
    ``ẏ = v sin θ``, ``θ̇ = ω``, ``v̇ = a``, ``ω̇ = α``; the speed and the turning rate are
    coordinates (``speed``, ``omega``), the inputs their rates.
    """
    from .equations import field_mechanism

    x, y, th, v, w, a, alpha = sp.symbols("x y theta speed omega a alpha", real=True)
    return field_mechanism(
        name, coordinates=[x, y, th, v, w], inputs=[a, alpha],
        rates=[v * sp.cos(th), v * sp.sin(th), w, a, alpha], angles=[th],
        units=["m", "m", "rad", "m/s", "rad/s"],
        description="second-order unicycle: a wheel rolling upright, driven by its accelerations")


def car_with_trailer(wheelbase=0.25, hitch=0.5, name: str = "car_with_trailer") -> Mechanism:
    """The kinematic car (:func:`kinematic_car`, wheelbase ``ℓ``) towing a trailer hitched at
    the midpoint of its rear axle, the trailer's axle a hitch length ``d`` behind: state
    ``(x, y, θ, φ, θ₁)``, ``θ₁`` the trailer's heading; inputs ``(v, φ̇)``.

    Unknown besides the car's: ``θ̇₁``. Constraint: the trailer's wheels, at
    ``(x, y) − d (cos θ₁, sin θ₁)``, do not slip sideways:
    ``−ẋ₁ sin θ₁ + ẏ₁ cos θ₁ = 0``, whence ``θ̇₁ = (v/d) sin(θ − θ₁)``. Defaults: Dynobench's
    ``car1_v0`` (``ℓ = 0.25``, ``d = 0.5``).
    """
    car = kinematic_car(wheelbase, name)
    admission.constant(hitch, "hitch")
    d = sp.Integer(hitch) if isinstance(hitch, int) else sp.nsimplify(hitch)
    x, y, th, ph = car.coordinates
    th1 = sp.Symbol("theta1", real=True)
    v = sp.Symbol("v", real=True)
    rates = car.X * sp.Matrix(sp.symbols("v u2", real=True))          # (ẋ, ẏ, θ̇, φ̇)
    xd, yd, thd1 = sp.symbols("xdot ydot theta1dot", real=True)
    # the trailer's axle (x − d cos θ₁, y − d sin θ₁) moves along its heading
    trailer = (xd + d * sp.sin(th1) * thd1, yd - d * sp.cos(th1) * thd1)
    constraint = -trailer[0] * sp.sin(th1) + trailer[1] * sp.cos(th1)
    linear = constraint.subs({xd: rates[0], yd: rates[1]})            # a θ̇₁ + b = 0, a = −d
    a = sp.simplify(sp.trigsimp(sp.expand(linear.diff(thd1))))
    solved = sp.simplify(sp.trigsimp(sp.expand_trig(-linear.subs(thd1, 0) / a)))
    row = sp.Matrix([[sp.simplify(solved.diff(v)), 0]])
    X = sp.Matrix.vstack(car.X, row)
    frame = sp.Matrix.vstack(car.frame, (row * sp.diag(car.delta, 1)).applyfunc(sp.simplify))
    return Mechanism(
        name=name,
        description=f"kinematic car with the steering angle as a state (wheelbase {car.derivation['wheelbase']}) "
                    f"towing a trailer (hitch {d})",
        inputs=car.inputs, coordinates=(x, y, th, ph, th1), units=("m", "m", "rad", "rad", "rad"),
        angles=(False, False, True, True, True), X=X, delta=car.delta, frame=frame,
        derivation={**car.derivation, "trailer_constraint": constraint, "hitch": d},
    )
