"""Playing planned motions on MuJoCo models of the mechanisms (needs the ``physics`` extra,
``pip install nonholo[physics]``).

- :func:`execute` plays a plan from rest to rest on its mechanism's model, lets it settle,
  measures where it ended, and re-plans from there to the goal for each touch-up, played
  only when predicted to end nearer the goal (:mod:`nonholo.physics.execution`),
  recording each stage in an :class:`Execution`, saved as JSON and read back
  (:mod:`nonholo.physics.execution_record`);
- :class:`Contact` holds every contact and actuation setting, each in a bounded range
  (:mod:`nonholo.physics.contact`);
- :func:`model_for` gives a mechanism's model, chosen by its kinematics, not its name;
  :func:`write_mjcf` writes its MJCF file (:mod:`nonholo.physics.models`; the rolling
  mechanisms' models: :mod:`nonholo.physics.vehicle_models`, on the frame they share,
  :mod:`nonholo.physics.rolling_model`).

Bad settings, durations and counts are refused before anything is played; a stage in which
MuJoCo goes unstable is recorded as such and ends the execution.

MuJoCo is imported only when a model is simulated.
"""
from .contact import Contact
from .execution import execute
from .execution_record import Execution
from .models import model_for, write_mjcf

__all__ = ["Contact", "Execution", "execute", "model_for", "write_mjcf"]
