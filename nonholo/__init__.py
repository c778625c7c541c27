"""nonholo: motion planning of non-holonomic systems on SO(3).

The numeric kinematics come from generated modules (``nonholo.generated``, written by
``nonholo derive`` from the SymPy derivations in ``derivations/``). Entry points:

- ``nonholo.plan(start, goal, mechanism=..., T=..., constraints=[...], settings=...)`` →
  :class:`~nonholo.io.result.PlanResult` (:mod:`nonholo.planning.api`); ``nonholo.solve``
  plans a :class:`~nonholo.planning.problem.Problem` built beforehand, and
  :class:`~nonholo.planning.settings.Settings` holds the numerical settings;
- :class:`~nonholo.spaces.state.State`: a state ``(R, q)``, always complete;
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
from .planning.api import plan, solve  # noqa: E402
from .planning.retime import retime  # noqa: E402

from .planning.problem import Problem  # noqa: E402
from .planning.settings import Settings  # noqa: E402
from .spaces.state import State  # noqa: E402
from . import constraints  # noqa: E402

__all__ = ["plan", "solve", "simulate", "retime", "PlanResult", "Mechanism", "mechanism_named", "Problem",
           "Settings", "State"]
