"""nonholo: motion planning of non-holonomic systems on SO(3).

The numeric kinematics come from generated modules (``nonholo.generated``, written by
``nonholo derive`` from the SymPy derivations in ``derivations/``). Entry points:

- ``nonholo.plan(R0, Rd, ...)`` → :class:`~nonholo.result.PlanResult` (:mod:`nonholo.planner`);
- ``nonholo.simulate(R0, controls, T, ...)`` → :class:`~nonholo.simulation.Trajectory`
  (:mod:`nonholo.simulation`).
"""
__version__ = "0.1.0"

from .planner import plan  # noqa: E402
from .result import PlanResult  # noqa: E402
from .simulation import simulate  # noqa: E402

__all__ = ["plan", "simulate", "PlanResult"]
