"""The numeric :class:`Mechanism`: everything the planners, the simulator and the figures
need to know about one mechanism, built from its generated module.

A mechanism on SO(3) is a driftless system ``dR/dt = [L(R) u] R`` (spatial angular
velocity ``ω = L(R) u``, ``u`` its ``m`` inputs). Its generated module
(``nonholo/generated/<name>.py``, written by ``nonholo derive`` from the SymPy derivation
in ``derivations/``) provides

- ``L(R)`` (3×m) and ``Q(R, u)`` (3×3, ``(∂L/∂θ) u = Q s`` for ``∂R/∂θ = [s] R``, eq. (12));
- ``delta(R)``, the singularity function, where ``L`` blows up on ``Δ = 0`` (else none);
- the desingularised frame, when the derivation gives one: ``N(R)`` (3×m, orthonormal
  columns spanning the admissible angular velocities), ``QN(R, w)`` (its ``Q``) and
  ``W(R) = (N(R)ᵀ L(R))^{-1}`` (physical inputs ``u = W(R) w`` of ``ω = N(R) w``);
- ``GEOMETRY``, the joint points of a two-leg platform, for drawings, and its legs'
  lengths ``leg_lengths(R)`` (``l_i = |R tip_i − base_i|``) with their derivative rows
  ``leg_gradients(R)`` (``dl_i = G_i s`` along ``∂R = [s] R``), when ``HAS_LEGS``;

each matrix also as ``NAME_into(..., out)`` for the compiled integrator, which compiles
them (:func:`nonholo.integrate.compiled.compiled_system`): a mechanism is data. Nothing
downstream depends on which mechanism it is; :mod:`nonholo.model.catalog` looks mechanisms
up by name.

Every generated module has one schema, whatever the state: the stacked field
``G(R, q)`` (rows ``(ω, q̇)``; ``q̇`` only without orientation, ``ω`` only on SO(3), where
``G = L``), its variational matrix ``QG(R, q, v)``, ``delta(R, q)`` and the frame
``N(R, q)``, ``QN(R, q, v)``, ``W(R, q)``, with ``q`` of shape ``(0,)`` on SO(3); the kernels
(:mod:`nonholo.integrate.cf4`) take the state as ``(R, q)`` alike. A mechanism whose state
goes beyond SO(3) — ``(R, q) ∈ SO(3) × Rᵏ`` or ``q ∈ Rᵏ`` (:mod:`derivations.state_space`) —
has no ``L`` and ``Q`` (``None``); on SO(3), :attr:`Mechanism.delta` and :attr:`Mechanism.frame`
take ``R`` alone (the paper's ``Δ(R)``, ``N(R)``, ``QN(R, w)``, ``W(R)``).
:attr:`Mechanism.state_space` tells the kinds apart (``"SO(3)"``, ``"SO(3)xR^k"``, ``"R^k"``).
"""
from __future__ import annotations

import dataclasses
import inspect
import types
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Callable

import numpy as np

from ..codegen import mechanism_modules
from ..numerics.checks import real_array
from ..spaces.product import Product
from ..spaces.singular import NoSingularSet, SingularSet
from . import definition_check, definition_forms, field_places, mechanism_file
from .geometry import Geometry


def _on_stack(into, R, shape: tuple) -> np.ndarray:
    """A generated ``NAME_into(R, out)`` (plain arithmetic on the entries of ``R``) filling
    ``shape``: on one ``R`` (3, 3), or on a stack (n, 3, 3) at once, evaluated on ``(3, 3,
    n)`` into ``shape + (n,)``; shape ``shape`` or ``(n,) + shape``."""
    R = real_array(R, "R")
    if R.shape[-2:] != (3, 3) or R.ndim not in (2, 3):
        raise ValueError(f"R must be a rotation matrix (3, 3) or a stack of them (n, 3, 3), got shape {R.shape}")
    if R.ndim == 2:
        out = np.empty(shape)
        into(R, out)
        return out
    out = np.empty((*shape, R.shape[0]))
    into(R.transpose(1, 2, 0), out)
    return np.moveaxis(out, -1, 0)


def on_rotation(function, module) -> Callable:
    """A generated ``function(R, q, ...)`` of a mechanism on SO(3) as ``function(R, ...)``.

    Parameters
    ----------
    function : callable
        A generated function of ``(R, q, ...)``.
    module : module
        Its generated module (``q`` is bound to no coordinates, shape ``(0,)``).

    Returns
    -------
    callable
        ``function(R, ...)``: the paper's ``Δ(R)``, ``N(R)``, ``QN(R, w)``, ``W(R)``.
    """
    none = np.zeros(0)

    def on_R(R, *args):
        return function(R, none, *args)

    on_R.__name__ = on_R.__qualname__ = function.__name__
    on_R.__doc__ = function.__doc__
    on_R.generated = function
    return on_R


def checked_on_R(function) -> Callable:
    """A generated ``function(R, ...)`` (``L``, ``Q``) that checks its ``R``.

    Parameters
    ----------
    function : callable
        A generated function of ``(R, ...)``.

    Returns
    -------
    callable
        ``function(R, ...)`` that refuses, with ``ValueError`` naming ``R``, what is not a
        finite real 3×3 matrix (or a ``(3, 3, n)`` stack).
    """

    def on_R(R, *args):
        R = real_array(R, "R")
        if R.shape[:2] != (3, 3) or R.ndim not in (2, 3):
            raise ValueError(f"R must be a 3×3 matrix (or a (3, 3, n) stack), got shape {R.shape}")
        if not np.all(np.isfinite(R)):
            raise ValueError("R has non-finite entries (NaN or infinity)")
        return function(R, *args)

    on_R.__name__ = on_R.__qualname__ = function.__name__
    on_R.__doc__ = function.__doc__
    on_R.generated = function
    return on_R


@dataclass(frozen=True)
class Frame:
    """The desingularised input frame of a mechanism: ``ω = N(R) w``, ``u = W(R) w``.

    Parameters
    ----------
    N, QN, W : callable
        The generated frame ``N(R)``, its variational matrix ``QN(R, w)`` and the physical
        inputs ``W(R)``.
    """

    N: Callable
    QN: Callable
    W: Callable


@dataclass(frozen=True, eq=False)
class Mechanism:  # signature: __new__'s (*args, **kwargs), the fields below; numpydoc ignore=PR01,PR02
    """Numeric kinematics of one mechanism (see the module docstring).

    Built from a generated module (:meth:`from_module`) or a symbolic mechanism
    (:meth:`from_symbolic`); looked up by name with :func:`nonholo.mechanism_named`.

    Parameters
    ----------
    name, description : str
        The mechanism's name and a phrase describing it.
    inputs : tuple of str
        The inputs' names.
    L, Q : callable
        ``L(R)`` and ``Q(R, u)`` of ``dR/dt = [L(R) u] R`` and eq. (12) (for a state
        beyond SO(3), those of the stacked field).
    delta : callable or None
        ``Δ(R)``; ``None`` without a singular set.
    frame : Frame or None
        The desingularised input frame; ``None`` without one.
    geometry : Geometry or None
        ``None`` for a mechanism that is not a two-leg platform.
    module : module
        The generated module the numbers come from (the integrator compiles its
        ``*_into`` functions).
    state_space : str
        Names the state: ``"SO(3)"`` (an orientation ``R``), ``"SO(3)xR^k"`` or ``"R^k"``.
    coordinates, units, angles : tuple
        Names, units and angle flags of the coordinates ``q`` (a state beyond SO(3)).
    G : callable or None
        The stacked field ``G(R, q)`` (rows ``(ω, q̇)``; ``G(R, q) = L(R)`` on SO(3)).
    definition : dict or None
        The definition as data (mechanism files, plan files).
    drawing : Drawing or None
        How it is drawn (:mod:`nonholo.model.drawing`).
    bounds : dict or None
        Bounds on the inputs and coordinates, as data.
    drift : callable or None
        The rates at rest ``F(R, q)`` of a system with drift, ``(ω, q̇) = F + G u``;
        ``None`` for a driftless one.
    """

    name: str
    description: str
    inputs: tuple[str, ...]
    L: Callable
    Q: Callable
    delta: Callable | None
    frame: Frame | None
    geometry: Geometry | None
    module: types.ModuleType = field(repr=False)
    state_space: str = "SO(3)"
    #: names, units and angle flags of the coordinates ``q`` (a state beyond SO(3))
    coordinates: tuple[str, ...] = ()
    units: tuple[str, ...] = ()
    angles: tuple[bool, ...] = ()
    #: the stacked field ``G(R, q)`` (rows ``(ω, q̇)``; ``G(R, q) = L(R)`` on SO(3))
    G: Callable | None = None
    #: the definition as data (the text form of :meth:`from_equations`), which mechanism
    #: files and plan files carry; ``None`` for a mechanism generated into the package
    definition: dict | None = field(default=None, repr=False)
    #: how the mechanism is drawn (:class:`nonholo.model.drawing.Drawing`); ``None`` without
    drawing: object | None = field(default=None, repr=False)
    #: bounds as data, ``{"inputs": {name: (low, high)}, "coordinates": {name: (low, high)}}``
    #: (``±inf`` where free); ``None`` without
    bounds: dict | None = field(default=None, repr=False)
    #: the rates at rest ``F(R, q)`` of a system with drift (``None``: driftless)
    drift: Callable | None = field(default=None, repr=False)

    def __new__(cls, *args, **kwargs):
        """Arguments that do not fit the fields raise a ``TypeError`` saying how a mechanism
        is built (its fields are a generated module's functions)."""
        try:
            INIT_SIGNATURE.bind(None, *args, **kwargs)
        except TypeError as exc:
            raise TypeError(f"{exc}. A Mechanism holds the functions of a generated module; build one "
                            "with Mechanism.from_equations (a velocity field: coordinates on R^k, an "
                            "orientation on SO(3), or both), Mechanism.from_constraints (Pfaffian "
                            "constraints), Mechanism.from_symbolic (a derivations.mechanisms.Mechanism) "
                            "or Mechanism.from_module") from None
        return super().__new__(cls)

    @cached_property
    def space(self) -> Product:
        """The state space (:mod:`nonholo.spaces.product`): ``SO(3)``, ``SO(3) × Rᵏ`` or ``Rᵏ``."""
        return Product.of(self.state_space.startswith("SO(3)"), self.coordinates, self.units, self.angles)

    @cached_property
    def singular(self) -> SingularSet:
        """The singular set ``Δ = 0`` (:class:`~nonholo.spaces.singular.NoSingularSet` without one)."""
        if self.delta is None:
            return NoSingularSet()
        return SingularSet.on(self.space, self.delta_samples, owner=self.name)

    def parse_state(self, value, name: str):
        """The caller's state as ``(R, q)`` (:meth:`nonholo.spaces.product.Product.parse`).

        Parameters
        ----------
        value
            A state as :func:`nonholo.plan` takes it.
        name : str
            The argument's name, for the error message.

        Returns
        -------
        tuple
            ``(R, q)``.

        Raises
        ------
        ValueError
            If ``value`` is not a state of the mechanism, naming ``name``.
        """
        return self.space.parse(value, name, owner=f" for mechanism {self.name!r}")

    @property
    def orientation(self) -> bool:
        """Whether the state includes an orientation ``R``."""
        return self.state_space.startswith("SO(3)")

    @property
    def n_coordinates(self) -> int:
        """``k``: the number of coordinates ``q``."""
        return len(self.coordinates)

    @property
    def n_rates(self) -> int:
        """``d``: the dimension of a state variation ``s = (s_R, s_q)`` (rows of ``G``)."""
        return self.space.dim

    @property
    def n_inputs(self) -> int:
        """``m``: the number of inputs."""
        return len(self.inputs)

    @property
    def has_drift(self) -> bool:
        """Whether the state moves at rest: ``(ω, q̇) = F(R, q) + G(R, q) u``."""
        return self.drift is not None

    @property
    def has_frame(self) -> bool:
        """Whether the mechanism has a desingularised input frame ``N``."""
        return self.frame is not None

    @property
    def has_legs(self) -> bool:
        """Whether the mechanism has legs whose lengths the derivation gives (a platform)."""
        return bool(getattr(self.module, "HAS_LEGS", False))

    def leg_lengths(self, R) -> np.ndarray:
        """The legs' lengths ``l_i(R) = |R tip_i − base_i|`` (the generated ``leg_lengths``).

        Parameters
        ----------
        R : array_like
            One rotation ``(3, 3)`` or a stack ``(n, 3, 3)``.

        Returns
        -------
        numpy.ndarray
            In the units of :attr:`geometry`: shape ``(k,)`` for one ``R``, ``(n, k)`` for a
            stack.
        """
        return self._legs("leg_lengths_into", R, ())

    def leg_gradients(self, R) -> np.ndarray:
        """Rows ``G_i(R)`` with ``dl_i = G_i s`` along ``∂R = [s] R``.

        Parameters
        ----------
        R : array_like
            One rotation ``(3, 3)`` or a stack ``(n, 3, 3)``.

        Returns
        -------
        numpy.ndarray
            Shape ``(k, 3)`` for one ``R``, ``(n, k, 3)`` for a stack.
        """
        return self._legs("leg_gradients_into", R, (3,))

    def leg_speeds(self, R, u) -> np.ndarray:
        """The legs' speeds ``dl_i/dt = G_i(R) L(R) u`` for inputs ``u`` at ``R``.

        Parameters
        ----------
        R : array_like
            One rotation ``(3, 3)`` or a stack ``(n, 3, 3)``.
        u : array_like
            The inputs, ``(m,)`` or ``(n, m)``.

        Returns
        -------
        numpy.ndarray
            Shape ``(k,)`` for one ``R``, ``(n, k)`` for stacks.
        """
        R = np.asarray(R, dtype=float)
        u = np.asarray(u, dtype=float)
        one = R.ndim == 2
        Rs, us = (R[None], u[None]) if one else (R, u)
        L = _on_stack(self.module.L_into, Rs, (3, self.n_inputs))
        out = np.einsum("nkj,nji,ni->nk", self.leg_gradients(Rs), L, us)
        return out[0] if one else out

    def _legs(self, function: str, R, tail: tuple) -> np.ndarray:
        """The generated leg function ``function`` on one ``R`` or a stack (:func:`_on_stack`)."""
        if not self.has_legs:
            raise ValueError(f"mechanism {self.name!r} has no legs")
        return _on_stack(getattr(self.module, function), R, (len(self.geometry.bases), *tail))

    def delta_samples(self, R, q=None) -> np.ndarray | None:
        """``Δ`` at every state of a stack.

        Parameters
        ----------
        R : array_like
            Rotations, shape ``(n, 3, 3)``.
        q : array_like, optional
            Coordinates, shape ``(n, k)`` (``(n, 0)`` or ``None`` on SO(3)).

        Returns
        -------
        numpy.ndarray or None
            ``Δ(R[n], q[n])``, shape ``(n,)``; ``None`` without a singular set.
        """
        if self.delta is None:
            return None
        R = np.asarray(R, dtype=float)
        q = np.zeros((R.shape[0], 0)) if q is None else np.asarray(q, dtype=float)
        # the generated Δ(R, q) (behind the paper's Δ(R) on SO(3)) is plain arithmetic on
        # entries R[i, j] and q[c]: evaluate it on (3, 3, n) and (k, n)
        generated = getattr(self.delta, "generated", self.delta)
        value = generated(R.transpose(1, 2, 0), q.T)
        return np.broadcast_to(np.asarray(value, dtype=float), (R.shape[0],)).copy()

    def rates(self, R, q, u) -> np.ndarray:
        """The stacked rates ``G(R, q) u`` (``F(R, q) + G(R, q) u`` with drift) of a state
        beyond SO(3).

        Parameters
        ----------
        R : numpy.ndarray
            The orientation (the identity without one).
        q : numpy.ndarray
            The coordinates.
        u : numpy.ndarray
            The inputs.

        Returns
        -------
        numpy.ndarray
            ``(ω, q̇)``, shape ``(d,)``.
        """
        R, q = np.asarray(R, dtype=float), np.asarray(q, dtype=float)
        rates = self.G(R, q) @ np.asarray(u, dtype=float)
        return rates if self.drift is None else rates + self.drift(R, q)

    @classmethod
    def from_module(cls, module: types.ModuleType) -> "Mechanism":
        """The mechanism of a generated module.

        Parameters
        ----------
        module : module
            A module written by the code generator (``nonholo derive`` or
            :mod:`nonholo.codegen.mechanism_modules`).

        Returns
        -------
        Mechanism
            Its numeric kinematics.
        """
        delta = module.delta if module.HAS_SINGULAR_SET else None
        frame = Frame(module.N, module.QN, module.W) if module.HAS_FRAME else None
        drift = module.F if getattr(module, "DRIFT", False) else None
        if module.STATE_SPACE != "SO(3)":
            return cls(name=module.NAME, description=module.DESCRIPTION, inputs=tuple(module.INPUTS),
                       L=None, Q=None, delta=delta, frame=frame, geometry=None, module=module,
                       state_space=module.STATE_SPACE, coordinates=tuple(module.COORDINATES),
                       units=tuple(module.UNITS), angles=tuple(module.ANGLES), G=module.G, drift=drift)
        if frame is not None:
            frame = Frame(*(on_rotation(f, module) for f in (module.N, module.QN, module.W)))
        geometry = getattr(module, "GEOMETRY", None)
        return cls(name=module.NAME, description=module.DESCRIPTION, inputs=tuple(module.INPUTS),
                   L=checked_on_R(module.L), Q=checked_on_R(module.Q), delta=None if delta is None else on_rotation(delta, module),
                   frame=frame, geometry=None if geometry is None else Geometry.from_mapping(geometry),
                   module=module, G=module.G, drift=None if drift is None else on_rotation(drift, module))

    @classmethod
    def from_symbolic(cls, mechanism, cache: bool = True) -> "Mechanism":
        """The numeric mechanism of a symbolic :class:`derivations.mechanisms.Mechanism`, in one
        call: its module is generated (as ``nonholo derive`` would write it) and loaded
        in this process. With ``cache``, the generated source is kept on disk by a digest of
        the definition and of the generator
        (:func:`nonholo.codegen.mechanism_modules.generated_source`), so a later run skips
        the generation; its kernels are compiled once and cached on disk too
        (:mod:`nonholo.codegen.build`).
        To add a mechanism for good, put it in ``derivations/definitions.py`` and run
        ``nonholo derive``. To look it up by name, :func:`nonholo.model.catalog.add` it.

        Parameters
        ----------
        mechanism : derivations.mechanisms.Mechanism
            The symbolic mechanism.
        cache : bool
            Keep the generated source on disk (and read it from there).

        Returns
        -------
        Mechanism
            Its numeric kinematics.

        Raises
        ------
        TypeError
            If ``mechanism`` is not a symbolic mechanism.
        ValueError
            Naming the field, for a name that is not an identifier, text that is not a line
            of printable text, an expression past the size budget or a constant that is
            not a finite real number (:func:`derivations.mechanisms.check_definition`),
            checked before anything is hashed or generated.
        """
        if type(mechanism).__name__ != "Mechanism" or not hasattr(mechanism, "field"):
            raise TypeError(f"mechanism must be a symbolic derivations.mechanisms.Mechanism, not "
                            f"{type(mechanism).__name__}; from equations, use Mechanism.from_equations "
                            "(a velocity field) or Mechanism.from_constraints (Pfaffian constraints)")
        return cls.from_module(mechanism_modules.symbolic_module(mechanism, cache))

    @classmethod
    def from_equations(cls, name: str, *, inputs, coordinates=(), rates=(), omega=None, rotation=None,
                       angles=(), parameters=None, delta=None, units=None, description: str | None = None,
                       cache: bool = True) -> "Mechanism":
        """The mechanism of a driftless field given by its equations (SymPy symbols and
        expressions), e.g. the unicycle towing a trailer::

            Mechanism.from_equations("trailer1", coordinates=[x, y, th0, th1], inputs=[v, w],
                                     rates=[v*cos(th0), v*sin(th0), w, v*sin(th0 - th1)],
                                     angles=[th0, th1])

        ``coordinates`` and ``rates`` (``ẋ = G(x) u``) give a state in ``Rᵏ``; ``omega`` a
        state on SO(3) (or, with coordinates, on SO(3) × Rᵏ). See
        :func:`derivations.equations.field_mechanism`, which checks the equations.
        Generated like :meth:`from_symbolic`; with ``cache``, keyed by the equations as given
        and the generator's version, so a later run neither derives nor generates.

        Parameters
        ----------
        name : str
            The mechanism's name.
        inputs : sequence of sympy.Symbol
            The input symbols ``u``.
        coordinates : sequence of sympy.Symbol
            The coordinates ``x`` of a Euclidean state.
        rates : sequence of sympy.Expr
            Their rates ``ẋ``, one expression each, linear in the inputs.
        omega : sequence of sympy.Expr, optional
            The spatial angular velocity (3 expressions, linear in the inputs) of an
            orientation, in the entries of ``rotation``.
        rotation : sympy.Matrix, optional
            3×3 symbols of the orientation (default ``r11 … r33``).
        angles : sequence of sympy.Symbol
            The coordinates that are angles (errors taken modulo 2π).
        parameters : mapping, optional
            Further symbols and their values (numbers).
        delta : sympy.Expr, optional
            The singularity function ``Δ`` (default: the factors of the field's
            denominators).
        units : sequence or mapping, optional
            A unit per coordinate (default ``"rad"`` for an angle, ``""`` otherwise).
        description : str, optional
            A phrase describing the mechanism.
        cache : bool
            Keep the generated source on disk (and read it from there).

        Returns
        -------
        Mechanism
            Its numeric kinematics.

        Raises
        ------
        ValueError
            Naming it, for an undeclared symbol, a rate that is not linear in the inputs,
            an argument of the wrong class of state, a name that is not an identifier, text
            where a number is due, a constant that is not a finite real number, or an
            expression past the size budget of the symbolic work
            (:func:`derivations.equations.admitted`, checked before anything is derived).

        Notes
        -----
        An expression may also be given as text (``"v*cos(theta0)"``): it is read by
        :func:`derivations.admission.parse` in the declared symbols — numbers,
        arithmetic and a fixed set of functions only, never evaluated as Python.
        """
        arguments = dict(inputs=inputs, coordinates=coordinates, rates=rates, omega=omega, rotation=rotation,
                         angles=angles, parameters=parameters, delta=delta, units=units, description=description)
        mechanism = cls.from_module(mechanism_modules.equations_module("field_mechanism", name, arguments, cache))
        # the definition as data (text), for mechanism files and plan files
        return dataclasses.replace(mechanism, definition=definition_forms.recorded(name, arguments))

    @classmethod
    def from_definition(cls, definition, *, where=None, cache: bool = True) -> "Mechanism":
        """The mechanism of a definition as data — a mechanism file's content
        (:mod:`nonholo.model.mechanism_file`), a plan file's ``mechanism_definition``, a
        :attr:`definition` — checked as a mechanism file is, then built by
        :meth:`from_equations` (and its cache).

        Parameters
        ----------
        definition : mapping
            The definition.
        where : callable or str, optional
            ``where(field)``, the place of a field for messages, or a label (``"definition"``
            by default: ``definition.rates.x``).
        cache : bool
            As for :meth:`from_equations`.

        Returns
        -------
        Mechanism
            The mechanism, with its :attr:`definition`, :attr:`drawing` and :attr:`bounds`.

        Raises
        ------
        ValueError
            Naming the field (``where(field)``) refused.
        """
        if where is None or isinstance(where, str):
            where = field_places.labelled(where or "definition")
        definition = definition_check.check(definition, where)
        try:
            mechanism = cls.from_equations(**definition_forms.arguments(definition), cache=cache)
        except ValueError as exc:
            raise ValueError(definition_check.located(str(exc), definition, where)) from None
        return dataclasses.replace(mechanism, definition=definition,
                                   drawing=definition_check.drawing_of(definition, where),
                                   bounds=definition_forms.bounds_of(definition))

    @classmethod
    def from_file(cls, path, cache: bool = True) -> "Mechanism":
        """The mechanism of a mechanism file (TOML, :mod:`nonholo.model.mechanism_file`):
        its equations as text, read as data — nothing in it is run.

        Parameters
        ----------
        path : str or os.PathLike
            The file (at most :data:`nonholo.model.mechanism_file.MAX_BYTES`).
        cache : bool
            As for :meth:`from_equations`: a later run neither derives nor generates.

        Returns
        -------
        Mechanism
            The mechanism, with its :attr:`definition`, :attr:`drawing` and :attr:`bounds`.

        Raises
        ------
        ValueError
            Naming the file, the line and the field (``trailer.toml, line 12, rates.theta:
            ...``); naming the file for a path that is not a regular file or is too large.
        """
        definition, where = mechanism_file.read_file(path)
        return cls.from_definition(definition, where=where, cache=cache)

    def to_file(self, path) -> Path:
        """Write the mechanism's :attr:`definition` as a mechanism file (TOML), which
        :meth:`from_file` reads back to the same definition; atomically.

        Parameters
        ----------
        path : str or os.PathLike
            The file.

        Returns
        -------
        pathlib.Path
            ``path``.

        Raises
        ------
        ValueError
            For a mechanism without a definition as data (one generated into the package,
            built by :meth:`from_symbolic`, :meth:`from_constraints` or :meth:`from_module`),
            or a ``path`` that is not a regular file.
        OSError
            If writing fails.
        """
        if self.definition is None:
            raise ValueError(f"mechanism {self.name!r} has no definition as data: only a mechanism built by "
                             "Mechanism.from_equations (with equations a mechanism file can hold) or read by "
                             "Mechanism.from_file can be written to a mechanism file")
        return mechanism_file.write(self.definition, path)

    @classmethod
    def from_constraints(cls, name: str, *, coordinates, velocities, constraints, inputs, angles=(),
                         parameters=None, units=None, description: str | None = None,
                         cache: bool = True) -> "Mechanism":
        """The mechanism whose rates obey linear constraints: Pfaffian constraints
        ``A(x) ẋ = 0`` with ``inputs`` chosen among the velocities, and equations defining
        other inputs (a rolling speed).

        The velocities that are not inputs are solved for; ``det A`` is the singularity
        function. See :func:`derivations.equations.constraint_mechanism` (its checks) and
        :meth:`from_equations` (the rest, caching included).

        Parameters
        ----------
        name : str
            The mechanism's name.
        coordinates : sequence of sympy.Symbol
            The coordinates ``x``.
        velocities : sequence of sympy.Symbol
            Their rates ``ẋ``, one symbol per coordinate.
        constraints : sequence of sympy.Expr
            Expressions equal to zero, linear in the velocities and inputs.
        inputs : sequence of sympy.Symbol
            Velocities, or symbols the constraints define.
        angles, parameters, units, description, cache
            As for :meth:`from_equations`.

        Returns
        -------
        Mechanism
            Its numeric kinematics.

        Raises
        ------
        ValueError
            Naming it, for equations :func:`derivations.equations.constraint_mechanism`
            refuses.
        """
        arguments = dict(coordinates=coordinates, velocities=velocities, constraints=constraints, inputs=inputs,
                         angles=angles, parameters=parameters, units=units, description=description)
        return cls.from_module(mechanism_modules.equations_module("constraint_mechanism", name, arguments, cache))

    def __repr__(self) -> str:
        return f"Mechanism({self.name!r}: {self.description})"


#: The signature of :class:`Mechanism`'s fields (checked by ``Mechanism.__new__``).
INIT_SIGNATURE = inspect.signature(Mechanism.__init__)
