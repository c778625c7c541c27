"""The rotation factors of a state space: :class:`SO3` and :class:`FixedRotation`, its trivial
stand-in for a mechanism without an orientation (the conventions of a factor:
:mod:`nonholo.spaces.axes`).

A rotation's command-line numbers are its RPY angles (:data:`RPY`, rad), its JSON the rows of
its matrix, its table columns its unit quaternion ``(qx, qy, qz, qw)``.
"""
from __future__ import annotations

import numpy as np

from ..numerics import kernels
from . import so3
from .axes import Axis
from .state import IDENTITY

#: The RPY angles of ``R = R(Z, φ) R(Y, ϑ) R(X, ψ)``, a rotation's command-line numbers: the
#: symbol, the angle's name, the axis it turns about, its ASCII name and its range (rad).
RPY = (("φ", "yaw", "z", "phi", (-np.pi, np.pi)), ("ϑ", "pitch", "y", "theta", (-np.pi / 2, np.pi / 2)),
       ("ψ", "roll", "x", "psi", (-np.pi, np.pi)))


class SO3:
    """The rotation group: states ``R`` (3×3), errors ``log(R R_dᵀ)`` (rad)."""

    dim = 3
    #: the state's part it owns
    part = "rotation"
    cli_names = ("φ", "ϑ", "ψ")
    name = "SO(3)"
    #: the unit of each row of a variation ``s_R`` (and of the RPY angles)
    units = ("rad", "rad", "rad")

    def describe(self) -> str:
        """What a state of this factor is, for messages.

        Returns
        -------
        str
            ``"a rotation matrix (3×3)"``.
        """
        return "a rotation matrix (3×3)"

    def parse(self, value, name: str) -> np.ndarray:
        """``value`` as a rotation matrix.

        Parameters
        ----------
        value : array_like
            The caller's rotation matrix.
        name : str
            The argument's name, for messages.

        Returns
        -------
        numpy.ndarray
            The 3×3 rotation.

        Raises
        ------
        ValueError
            Naming ``name``, if ``value`` is not a rotation matrix (a pair, say).
        """
        if isinstance(value, tuple):
            raise ValueError(f"{name} must be {self.describe()}, got a pair")
        return so3.check_rotation(value, name)

    def identity(self) -> np.ndarray:
        """The identity rotation.

        Returns
        -------
        numpy.ndarray
            ``I`` (3×3), a copy.
        """
        return IDENTITY.copy()

    def difference(self, R, Rd) -> np.ndarray:
        """``l`` with ``[l] = log(R R_dᵀ)`` (rad).

        Parameters
        ----------
        R, Rd : array_like
            Rotation matrices.

        Returns
        -------
        numpy.ndarray
            The 3-vector ``l``.
        """
        return kernels.log_error(np.ascontiguousarray(R, dtype=float), np.ascontiguousarray(Rd, dtype=float))[0]

    def error(self, R, Rd) -> tuple[np.ndarray, float]:
        """``(l, |l|)`` of :meth:`difference`.

        Parameters
        ----------
        R, Rd : array_like
            Rotation matrices.

        Returns
        -------
        tuple of (numpy.ndarray, float)
            ``l`` and its norm (rad).
        """
        l, err = kernels.log_error(np.ascontiguousarray(R, dtype=float), np.ascontiguousarray(Rd, dtype=float))
        return l, float(err)

    def distance(self, R1, R2) -> float:
        """The geodesic distance ``|log(R1 R2ᵀ)|``.

        Parameters
        ----------
        R1, R2 : array_like
            Rotation matrices.

        Returns
        -------
        float
            The distance (rad).
        """
        return self.error(R1, R2)[1]

    def interpolate(self, Ra, Rb, s) -> np.ndarray:
        """The geodesic ``exp(s·log(R_b R_aᵀ)) R_a`` at the fractions ``s``.

        Parameters
        ----------
        Ra, Rb : array_like
            The ends, rotation matrices.
        s : array_like
            Fractions of the way, shape ``(n,)``.

        Returns
        -------
        numpy.ndarray
            The rotations, shape ``(n, 3, 3)``.
        """
        return so3.geodesic(Ra, Rb, s)

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` rotations, uniform (Haar).

        Parameters
        ----------
        rng : numpy.random.Generator
            The random numbers.
        n : int
            How many.

        Returns
        -------
        numpy.ndarray
            The rotations, shape ``(n, 3, 3)``.
        """
        from scipy.spatial.transform import Rotation  # loaded when first needed

        return Rotation.random(n, random_state=rng).as_matrix().reshape(n, 3, 3)

    def retract(self, R, s) -> np.ndarray:
        """``exp([s]) R``: ``R`` moved by the variation ``s`` (rad), in the spatial frame.

        Parameters
        ----------
        R : array_like
            A rotation matrix.
        s : array_like
            The variation, shape ``(3,)``.

        Returns
        -------
        numpy.ndarray
            The moved rotation.
        """
        return so3.exp(np.asarray(s, dtype=float)) @ np.asarray(R, dtype=float)

    def to_json(self, R) -> list:
        """A rotation as JSON.

        Parameters
        ----------
        R : array_like
            A rotation matrix.

        Returns
        -------
        list
            Its rows, nested lists of floats.
        """
        return np.asarray(R, dtype=float).tolist()

    def from_json(self, value, name: str) -> np.ndarray:
        """The rotation of :meth:`to_json`'s form.

        Parameters
        ----------
        value : list
            Nested lists, 3×3.
        name : str
            The field's name, for messages.

        Returns
        -------
        numpy.ndarray
            The 3×3 rotation.
        """
        return self.parse(value if not isinstance(value, tuple) else list(value), name)

    def from_cli(self, numbers) -> np.ndarray:
        """RPY angles ``(φ, ϑ, ψ)`` (rad) as a rotation.

        Parameters
        ----------
        numbers : array_like
            The three angles.

        Returns
        -------
        numpy.ndarray
            The 3×3 rotation.
        """
        return so3.from_rpy(*np.asarray(numbers, dtype=float))

    def to_cli(self, R) -> np.ndarray:
        """A rotation's RPY angles ``(φ, ϑ, ψ)`` (rad), inverse of :meth:`from_cli`.

        Parameters
        ----------
        R : array_like
            A rotation matrix.

        Returns
        -------
        numpy.ndarray
            The three angles.
        """
        return so3.as_rpy(R)

    def axes(self) -> tuple[Axis, ...]:
        """The RPY angles as axes (:data:`RPY`).

        Returns
        -------
        tuple of Axis
            ``φ``, ``ϑ``, ``ψ``: angles in rad over their RPY ranges.
        """
        return tuple(Axis(symbol, (ascii,), bounds, True, "rad", f"{symbol} ({name}, about {axis})")
                     for symbol, name, axis, ascii, bounds in RPY)

    def from_cli_many(self, numbers) -> np.ndarray:
        """Rotations of RPY angles, vectorised (SciPy's ``"ZYX"`` Euler angles).

        Parameters
        ----------
        numbers : array_like
            ``(φ, ϑ, ψ)`` rows (rad), shape ``(n, 3)``.

        Returns
        -------
        numpy.ndarray
            The rotations, shape ``(n, 3, 3)``.
        """
        from scipy.spatial.transform import Rotation  # loaded when first needed

        return Rotation.from_euler("ZYX", np.asarray(numbers, dtype=float)).as_matrix().reshape(-1, 3, 3)

    def describe_numbers(self, numbers) -> str:
        """RPY angles in words, for messages.

        Parameters
        ----------
        numbers : array_like
            ``(φ, ϑ, ψ)`` (rad).

        Returns
        -------
        str
            ``"RPY(0.5, 1.2, -0.5)"`` (rounded to 3 decimals).
        """
        return f"RPY{tuple(round(float(a), 3) for a in numbers)}"

    #: the columns of a table of rotations (:meth:`columns`)
    column_names = ("qx", "qy", "qz", "qw")

    def columns(self, R) -> dict:
        """Rotations as table columns: their unit quaternions ``(x, y, z, w)``, signs kept
        continuous (:func:`~nonholo.spaces.so3.continuous_quaternions`).

        Parameters
        ----------
        R : numpy.ndarray
            Rotations, shape ``(n, 3, 3)``.

        Returns
        -------
        dict
            ``{"qx": …, "qy": …, "qz": …, "qw": …}``, arrays ``(n,)``.
        """
        quaternion = so3.continuous_quaternions(R)
        return {name: quaternion[:, i] for i, name in enumerate(self.column_names)}

    def difference_text(self, a: str, b: str) -> str:
        """:meth:`difference` of rotations named ``a`` and ``b``, for messages.

        Parameters
        ----------
        a, b : str
            The rotations' names.

        Returns
        -------
        str
            ``"log(a bᵀ)"``.
        """
        return f"log({a} {b}ᵀ)"

    def __repr__(self) -> str:
        return "SO3()"

    def __eq__(self, other) -> bool:
        return isinstance(other, SO3)

    def __hash__(self) -> int:
        return hash("SO3")


class FixedRotation:
    """The rotation factor of a mechanism without an orientation: the identity alone
    (``dim = 0``; no variation, no error, left out of the caller's forms). Its methods take
    and give what :class:`SO3`'s do."""

    dim = 0
    #: the state's part it owns
    part = "rotation"
    cli_names = ()
    name = ""
    units = ()

    def describe(self) -> str:
        """What a state of this factor is, for messages.

        Returns
        -------
        str
            ``""``: the caller never gives this part.
        """
        return ""

    def identity(self) -> np.ndarray:
        """The one state.

        Returns
        -------
        numpy.ndarray
            ``I`` (3×3), a copy.
        """
        return IDENTITY.copy()

    def parse(self, value, name: str) -> np.ndarray:
        """The one state, whatever the caller's form holds (it has no rotation).

        Parameters
        ----------
        value : object
            Unused.
        name : str
            Unused.

        Returns
        -------
        numpy.ndarray
            ``I`` (3×3).
        """
        return IDENTITY.copy()

    def difference(self, R, Rd) -> np.ndarray:
        """The empty variation.

        Parameters
        ----------
        R, Rd : array_like
            Unused.

        Returns
        -------
        numpy.ndarray
            Shape ``(0,)``.
        """
        return np.zeros(0)

    def error(self, R, Rd) -> tuple[np.ndarray, float]:
        """No error.

        Parameters
        ----------
        R, Rd : array_like
            Unused.

        Returns
        -------
        tuple of (numpy.ndarray, float)
            ``(∅, 0)``.
        """
        return np.zeros(0), 0.0

    def distance(self, R1, R2) -> float:
        """No distance.

        Parameters
        ----------
        R1, R2 : array_like
            Unused.

        Returns
        -------
        float
            ``0``.
        """
        return 0.0

    def interpolate(self, Ra, Rb, s) -> np.ndarray:
        """The one state at each fraction.

        Parameters
        ----------
        Ra, Rb : array_like
            Unused.
        s : array_like
            Fractions of the way, shape ``(n,)``.

        Returns
        -------
        numpy.ndarray
            ``I``, shape ``(n, 3, 3)``.
        """
        return np.broadcast_to(IDENTITY, (np.size(s), 3, 3))

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` copies of the one state (no random numbers drawn).

        Parameters
        ----------
        rng : numpy.random.Generator
            Unused.
        n : int
            How many.

        Returns
        -------
        numpy.ndarray
            ``I``, shape ``(n, 3, 3)``.
        """
        return np.broadcast_to(IDENTITY, (n, 3, 3))

    def retract(self, R, s) -> np.ndarray:
        """``R`` unmoved (the variation is empty).

        Parameters
        ----------
        R : array_like
            The state (the identity), or a stack of them.
        s : array_like
            The empty variation.

        Returns
        -------
        numpy.ndarray
            ``R``.
        """
        return np.asarray(R, dtype=float)

    def to_json(self, R) -> list:
        """No JSON: the part is left out.

        Parameters
        ----------
        R : array_like
            Unused.

        Returns
        -------
        list
            ``[]``.
        """
        return []

    def from_json(self, value, name: str) -> np.ndarray:
        """The one state.

        Parameters
        ----------
        value : object
            Unused.
        name : str
            Unused.

        Returns
        -------
        numpy.ndarray
            ``I`` (3×3).
        """
        return IDENTITY.copy()

    def from_cli(self, numbers) -> np.ndarray:
        """The one state (it takes no numbers).

        Parameters
        ----------
        numbers : array_like
            Empty.

        Returns
        -------
        numpy.ndarray
            ``I`` (3×3).
        """
        return IDENTITY.copy()

    def to_cli(self, R) -> np.ndarray:
        """No numbers.

        Parameters
        ----------
        R : array_like
            Unused.

        Returns
        -------
        numpy.ndarray
            Shape ``(0,)``.
        """
        return np.zeros(0)

    def axes(self) -> tuple:
        """No axes.

        Returns
        -------
        tuple
            ``()``.
        """
        return ()

    def from_cli_many(self, numbers) -> np.ndarray:
        """The identity for each row of ``numbers``.

        Parameters
        ----------
        numbers : array_like
            Shape ``(n, 0)``.

        Returns
        -------
        numpy.ndarray
            ``I`` ``n`` times, shape ``(n, 3, 3)`` (read-only).
        """
        return np.broadcast_to(IDENTITY, (np.shape(numbers)[0], 3, 3))

    def describe_numbers(self, numbers) -> str:
        """No numbers to describe.

        Parameters
        ----------
        numbers : array_like
            Unused.

        Returns
        -------
        str
            ``""``.
        """
        return ""

    column_names = ()

    def columns(self, R) -> dict:
        """No columns.

        Parameters
        ----------
        R : numpy.ndarray
            Unused.

        Returns
        -------
        dict
            ``{}``.
        """
        return {}

    def difference_text(self, a: str, b: str) -> str:
        """No difference.

        Parameters
        ----------
        a, b : str
            Unused.

        Returns
        -------
        str
            ``""``.
        """
        return ""

    def __repr__(self) -> str:
        return "FixedRotation()"

    def __eq__(self, other) -> bool:
        return isinstance(other, FixedRotation)

    def __hash__(self) -> int:
        return hash("FixedRotation")
