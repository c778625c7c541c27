"""Effort: how much integrating this process has done, counted in the kernels' steps.

A clock for budgets that must not make a result depend on the machine or its load: the
global route's (:mod:`nonholo.planning.route`) and the least-energy stage's stop trying
after a budget of effort, not of wall time, so a plan is the same whether it runs alone, beside other work, or on a
slower machine — only the wall time it takes differs. Every call of a compiled kernel
(:func:`nonholo.integrate.system_kernels.compile_system`) adds its steps: a variational step counts 1, a
forward step :data:`FORWARD_WEIGHT` (its share of the work), a step of a normal extremal
:data:`EXTREMAL_WEIGHT`, a partial step of
:func:`nonholo.integrate.motion_kernels.frame_inputs` as much; the least-energy stage
(:mod:`nonholo.planning.energy_optimiser`) adds its iterations' linear algebra. :func:`seconds` converts the count with
:data:`STEPS_PER_SECOND`, the variational steps a second of planning on the reference
machine (the benchmarks' 2-core AMD EPYC), so that budgets keep their meaning in seconds
there (a plan's wall time there is within about 20 % of its effort for nine in ten).

The count is exact, so that where a budget ends does not depend on what the process
counted before: it is a whole number of :data:`UNITS_PER_STEP`-ths of a variational step,
read as that number times a power of two (:data:`SECONDS_PER_UNIT`), so a reading, and
a deadline a dyadic budget after it, carry no rounding (a count in floating point made a
budget's last comparison a tie broken by the count's rounding: the same plan came out
differently after other plans).

The count is per process (threads planning at once share it: their budgets then depend
on each other; a sweep's workers are processes).
"""
from __future__ import annotations

#: The count's unit: this many per variational step (a forward step is a whole number of them).
UNITS_PER_STEP = 5
#: The reading is the count times this power of two (``2⁻²²`` s per unit).
SECONDS_PER_UNIT = 2.0 ** -22
#: Variational CF4 steps a second of planning on the reference machine, everything around
#: the kernels included (fitted to the wall times of 300 random far pairs' plans, rounded to
#: ``2²²/5`` so that a reading is exact: the variational kernel alone runs 2.0e6 steps a
#: second there).
STEPS_PER_SECOND = 1.0 / (UNITS_PER_STEP * SECONDS_PER_UNIT)
#: A forward step's effort, in variational steps (forward replays run about 2.5× faster).
FORWARD_WEIGHT = 0.4
#: A step of a normal extremal (state and costate, :mod:`nonholo.integrate.extremal_kernels`),
#: in variational steps (a whole number of units, like :data:`FORWARD_WEIGHT`).
EXTREMAL_WEIGHT = 0.6

_count = [0]


def add(steps: float) -> None:
    """Count effort.

    Parameters
    ----------
    steps : float
        The effort, in variational steps (rounded to the count's unit).
    """
    _count[0] += round(steps * UNITS_PER_STEP)


def seconds() -> float:
    """The effort so far, in seconds of the reference machine.

    Returns
    -------
    float
        The count in seconds (``count · 2⁻²²``: exact below ``2³¹`` s).
    """
    return _count[0] * SECONDS_PER_UNIT
