"""BLAS held to one thread while a plan is computed.

A plan's linear algebra is on matrices of a few hundred rows at most (the least-energy
stage's quadratic models, the nonparametric Jacobians): there a threaded BLAS gains
little on an idle machine, and on a busy one its threads wait for each other, many
times slower than one thread. One thread also keeps the rounding of a factorisation
independent of the machine's core count, so the same call gives the same plan
everywhere. Processes that plan in parallel (sweeps) each hold one thread anyway.
"""
from __future__ import annotations

import contextlib

_controller = []


@contextlib.contextmanager
def one_thread():
    """A context in which the BLAS libraries loaded (OpenBLAS, MKL, BLIS) run on one thread.

    Yields
    ------
    None
    """
    if not _controller:
        from threadpoolctl import ThreadpoolController

        _controller.append(ThreadpoolController())
    with _controller[0].limit(limits=1, user_api="blas"):
        yield
