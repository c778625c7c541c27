"""A mechanism's state as one value: :class:`State`, always complete.

A state is the pair ``(R, q)`` of every mechanism: ``R`` the orientation (3×3; the
identity for a mechanism without one) and ``q`` the coordinates (shape ``(k,)``; ``(0,)``
for a mechanism without them). Nothing past the public boundary holds ``None`` for a part
of a state. A :class:`State` unpacks as the pair (``R, q = state``), so the integrator's
kernels, which take the two arrays, are called with ``*state``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: The orientation of a state without one.
IDENTITY = np.eye(3)
#: The coordinates of a state without them.
NO_COORDINATES = np.zeros(0)


@dataclass(frozen=True, eq=False)
class State:
    """One state ``(R, q)``, both parts always present (see the module).

    Parameters
    ----------
    R : array_like
        The orientation, 3×3 (the identity without one).
    q : array_like
        The coordinates, shape ``(k,)`` (``(0,)`` without them).
    """

    R: np.ndarray
    q: np.ndarray

    def __post_init__(self):
        object.__setattr__(self, "R", np.ascontiguousarray(self.R, dtype=float))
        object.__setattr__(self, "q", np.ascontiguousarray(np.reshape(self.q, (-1,)), dtype=float))
        if self.R.shape != (3, 3):
            raise ValueError(f"a state's R must be 3×3, got shape {self.R.shape}")

    @classmethod
    def of(cls, value) -> "State":
        """``value`` as a :class:`State`: a state, or a pair ``(R, q)``.

        Parameters
        ----------
        value : State or tuple
            The state.

        Returns
        -------
        State
            The same state (``value`` itself if it is one).
        """
        if isinstance(value, State):
            return value
        R, q = value
        return cls(R, q)

    def __iter__(self):
        yield self.R
        yield self.q

    def __len__(self) -> int:
        return 2

    def __getitem__(self, i):
        return (self.R, self.q)[i]

    def __eq__(self, other) -> bool:
        if not isinstance(other, State):
            return NotImplemented
        return bool(np.array_equal(self.R, other.R) and np.array_equal(self.q, other.q))

    __hash__ = None

    def __repr__(self) -> str:
        return f"State(R={self.R.tolist()!r}, q={self.q.tolist()!r})"
