"""nonholo: motion planning of non-holonomic systems on SO(3).

The numeric kinematics come from generated modules (``nonholo.generated``, written by
``nonholo derive`` from the SymPy derivations in ``derivations/``). Entry points:

- ``nonholo.plan(R0, Rd, ..., mechanism=...)`` → :class:`~nonholo.io.result.PlanResult`
  (:mod:`nonholo.planning.api`);
- ``nonholo.simulate(R0, controls, T, ...)`` → :class:`~nonholo.motion.simulation.Trajectory`
  (:mod:`nonholo.motion.simulation`);
- ``nonholo.retime(result, leg_speed, T=None)``: a plan re-timed so that no leg moves
  faster than ``leg_speed``, or no input leaves its bounds (``input_bounds=``)
  (:mod:`nonholo.planning.retime`);
- ``nonholo.constraints``: the constraint objects ``plan(..., constraints=[...])`` takes —
  ``InputBounds``, ``StateBounds``, ``Clearance``, ``LegStroke``, ``LegSpeed`` — and
  ``of_mechanism(m)``, a mechanism's own bounds (:mod:`nonholo.constraints`);
- :class:`~nonholo.model.mechanism.Mechanism`: a mechanism's numeric kinematics
  (``Mechanism.from_equations`` builds one from its velocity field, ``from_constraints``
  from Pfaffian constraints, ``from_symbolic`` from a derivation); ``nonholo.mechanism_named``
  looks one up by name, :func:`nonholo.model.catalog.names` lists them.
"""
__version__ = "0.1.0"

from .io.result import PlanResult  # noqa: E402
from .model.catalog import get as mechanism_named  # noqa: E402
from .model.mechanism import Mechanism  # noqa: E402
from .motion.simulation import simulate  # noqa: E402
from .planning.api import plan  # noqa: E402
from .planning.retime import retime  # noqa: E402

from .planning.problem import Problem  # noqa: E402
from . import constraints  # noqa: E402

__all__ = ["plan", "simulate", "retime", "PlanResult", "Mechanism", "mechanism_named", "Problem"]

#: Modules of the package's former flat layout, reachable as ``from nonholo import so3`` for
#: one release (with a ``DeprecationWarning``): old name → its module now.
MOVED = {"so3": "spaces.so3", "verify": "certify.resimulate", "catalog": "model.catalog",
         "planner": "planning.api", "result": "io.result", "figures": "viz",
         "examples": "paper.examples", "simulation": "motion.simulation",
         "platform": "model.platform", "export": "io.csv_export", "sweep": "batch.sweep",
         "problems": "io.problems", "limits": "model.limits"}


def __getattr__(name):
    if name in MOVED:
        import importlib
        import warnings

        warnings.warn(f"nonholo.{name} is now nonholo.{MOVED[name]}; the old name goes in the next release",
                      DeprecationWarning, stacklevel=2)
        return importlib.import_module(f".{MOVED[name]}", __name__)
    raise AttributeError(f"module 'nonholo' has no attribute {name!r}")
