"""Effort: how much integrating this process has done, counted in the kernels' steps.

A clock for budgets that must not make a result depend on the machine or its load: the
global route's (:mod:`nonholo.planning.route`) and the least-energy stage's stop trying
after a budget of effort, not of wall time, so a plan is the same whether it runs alone, beside other work, or on a
slower machine — only the wall time it takes differs. Every call of a compiled kernel
(:func:`nonholo.integrate.cf4.compile_system`) adds its steps: a variational step counts 1, a
forward step :data:`FORWARD_WEIGHT` (its share of the work), a partial step of
:func:`nonholo.integrate.cf4.frame_inputs` as much; the least-energy stage
(:mod:`nonholo.planning.energy`) adds its iterations' linear algebra. :func:`seconds` converts the count with
:data:`STEPS_PER_SECOND`, the variational steps a second of planning on the reference
machine (the benchmarks' 2-core AMD EPYC), so that budgets keep their meaning in seconds
there (a plan's wall time there is within about 20 % of its effort for nine in ten).

The count is per process (threads planning at once share it: their budgets then depend
on each other; a sweep's workers are processes).
"""
from __future__ import annotations

#: Variational CF4 steps a second of planning on the reference machine, everything around
#: the kernels included (fitted to the wall times of 300 random far pairs' plans: the
#: variational kernel alone runs 2.0e6 steps a second there).
STEPS_PER_SECOND = 8.0e5
#: A forward step's effort, in variational steps (forward replays run about 2.5× faster).
FORWARD_WEIGHT = 0.4

_count = [0.0]


def add(steps: float) -> None:
    """Count effort.

    Parameters
    ----------
    steps : float
        The effort, in variational steps.
    """
    _count[0] += steps


def seconds() -> float:
    """The effort so far, in seconds of the reference machine.

    Returns
    -------
    float
        The count divided by :data:`STEPS_PER_SECOND`.
    """
    return _count[0] / STEPS_PER_SECOND
