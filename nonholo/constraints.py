"""The constraint objects ``nonholo.plan(..., constraints=[...])`` takes, as python-control's
``trajectory_constraints``: bounds on the inputs and on the coordinates, the clearance from
the singular set, the legs' stroke and speed, obstacles a planar vehicle's bodies keep clear
of; :func:`of_mechanism` gives a mechanism's own
bounds as objects. They are defined in :mod:`nonholo.model.bounds` and
:mod:`nonholo.planning.constraint_objects`, which say how each is kept.
"""
from .model.bounds import InputBounds, StateBounds, as_data, of_mechanism
from .model.obstacles import Body, Obstacles
from .planning.constraint_objects import KINDS, Clearance, LegSpeed, LegStroke

__all__ = ["InputBounds", "StateBounds", "Clearance", "LegStroke", "LegSpeed", "Obstacles", "Body", "KINDS",
           "of_mechanism", "as_data"]
