"""A plan runs with BLAS on one thread, and the caller's setting comes back after it."""
import numpy as np
from threadpoolctl import threadpool_info, threadpool_limits

import nonholo
from nonholo.numerics.blas import one_thread


def blas_threads():
    return [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]


def test_one_thread_holds_blas_to_one_thread_and_restores_the_setting():
    with threadpool_limits(limits=2, user_api="blas"):
        assert blas_threads() and all(n == 2 for n in blas_threads())
        with one_thread():
            assert all(n == 1 for n in blas_threads())
        assert all(n == 2 for n in blas_threads())


def test_a_plan_runs_on_one_blas_thread():
    seen = []

    def callback(record):
        seen.append(blas_threads())

    with threadpool_limits(limits=2, user_api="blas"):
        result = nonholo.plan(np.eye(3), nonholo.spaces.so3.exp(np.array([0.2, -0.1, 0.3])),
                              mechanism="attitude", callback=callback, route="local")
        after = blas_threads()
    assert result.success and seen
    assert all(n == 1 for threads in seen for n in threads)
    assert all(n == 2 for n in after)
