"""One BLAS thread for the loop's work (:func:`one_blas_thread`).

The loop alternates the compiled dynamics kernel, parallel over models on numba's OpenMP
threads, with small dense products (the signature's line projections, a few hundred columns;
the least-squares steps' SVDs). After each parallel region the OpenMP threads keep spinning for
a while; a multi-threaded BLAS call made then competes with them for the cores, and on a
shared 2-core machine the line projection of 16 segments took 0.27 s instead of 3 ms
(``bench/bench_loop.py``: a whole bundle 4-5 times slower). The products are too small to gain
from a second BLAS thread, so the loop runs with one.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import TypeVar

from threadpoolctl import threadpool_limits

F = TypeVar("F", bound=Callable)


def one_blas_thread(fn: F) -> F:
    """``fn`` run with the BLAS libraries limited to one thread (restored after)."""
    @functools.wraps(fn)
    def run(*args, **kwargs):
        with threadpool_limits(limits=1, user_api="blas"):
            return fn(*args, **kwargs)
    return run  # type: ignore[return-value]
