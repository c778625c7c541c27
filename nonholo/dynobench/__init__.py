"""Dynobench's instances and trajectories: read, planned, written and checked.

Dynobench is the benchmark of iDb-A* (instances, models and checker in the public
repository ``quimortiz/dynobench``, MIT licence).

- :func:`load`: an env file and the model file it names, as an :class:`Instance`
  (:mod:`nonholo.dynobench.instance`);
- :func:`to_dynobench`: a plan as Dynobench's trajectory (``states`` and ``actions`` at the
  model's ``dt``), :func:`write` and :func:`read` its file
  (:mod:`nonholo.dynobench.trajectory`);
- :func:`check`: the project's own check of a trajectory, by Dynobench's rules and
  thresholds (:mod:`nonholo.dynobench.checker`);
- :func:`~nonholo.dynobench.solve.solve`: an instance planned in the least time under its
  model's bounds, exported and checked (:mod:`nonholo.dynobench.solve`), a short trajectory
  then brought to fewer Euler steps of the model (:mod:`nonholo.dynobench.euler_steps`).
"""
from .checker import Report, check
from .instance import Box, Instance, load
from .trajectory import read, to_dynobench, write

__all__ = ["Box", "Instance", "Report", "check", "load", "read", "to_dynobench", "write"]
