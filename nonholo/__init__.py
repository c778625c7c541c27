"""nonholo: motion planning of non-holonomic systems on SO(3).

The numeric kinematics come from generated modules (``nonholo.generated``, written by
``nonholo derive`` from the SymPy derivations in ``derivations/``). Entry points:

- ``nonholo.plan(R0, Rd, ..., mechanism=...)`` → :class:`~nonholo.result.PlanResult`
  (:mod:`nonholo.planner`);
- ``nonholo.simulate(R0, controls, T, ...)`` → :class:`~nonholo.simulation.Trajectory`
  (:mod:`nonholo.simulation`);
- ``nonholo.retime(result, leg_speed, T=None)``: a plan re-timed so that no leg moves
  faster than ``leg_speed`` (:mod:`nonholo.retime`);
- :class:`~nonholo.mechanism.Mechanism`: a mechanism's numeric kinematics
  (``Mechanism.from_symbolic`` builds one from a derivation); ``nonholo.mechanism_named``
  looks one up by name, :func:`nonholo.catalog.names` lists them.
"""
__version__ = "0.1.0"

from .catalog import get as mechanism_named  # noqa: E402
from .mechanism import Mechanism  # noqa: E402
from .planner import plan  # noqa: E402
from .result import PlanResult  # noqa: E402
from .retime import retime  # noqa: E402
from .simulation import simulate  # noqa: E402

__all__ = ["plan", "simulate", "retime", "PlanResult", "Mechanism", "mechanism_named"]
