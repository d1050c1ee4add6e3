"""The loop's threads: one BLAS thread (:func:`one_blas_thread`), candidates on parallel threads
(:func:`each`) and the time limit (:class:`TimeLimit`).

The loop alternates the compiled dynamics kernel, parallel over models on numba's OpenMP
threads, with small dense products (the signature's line projections, a few hundred columns;
the least-squares steps' SVDs). After each parallel region the OpenMP threads keep spinning for
a while; a multi-threaded BLAS call made then competes with them for the cores, and on a
shared 2-core machine the line projection of 16 segments takes 0.27 s instead of 3 ms
(``bench/bench_loop.py``: a whole bundle 4-5 times slower). The products are too small to gain
from a second BLAS thread, so the loop runs with one.

Between the kernel calls a candidate's fit is serial work (signatures, the optimiser's steps):
run one candidate at a time, that work leaves all cores but one idle. :func:`each` fits the
candidates on as many threads as numba has, each thread's kernel calls on one numba thread
(the kernel releases the GIL, as does the BLAS product): the cores are busy throughout. Where
the calling thread is free (the calibration, an operating point's wear run), the exploration's
points and the least-squares Jacobian's columns run on the threads instead. Each candidate's
computation is independent of the others' and of the thread that runs it, so the results are
those of the serial order. Numba's workqueue threading layer (a numba without OpenMP or TBB)
cannot run kernels from several threads at once: there the items run in turn.
"""

from __future__ import annotations

import functools
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor, as_completed, wait
from typing import TypeVar

import numba
import numpy as np
from tqdm import tqdm

from physics import blas
from physics.dynamics.model import anti_aliased, anti_aliasing_filter

F = TypeVar("F", bound=Callable)
T = TypeVar("T")
R = TypeVar("R")


#: threads for :func:`each`; None: as many as numba has (``NUMBA_NUM_THREADS``, the cores)
THREADS: int | None = None
_local = threading.local()


def parallel_threads() -> int:
    """Threads :func:`each` uses here: :data:`THREADS` or numba's; 1 within an item that
    already runs on a parallel thread (a candidate's own exploration and Jacobian), and 1
    where numba's threading layer cannot run kernels from several threads at once."""
    if getattr(_local, "in_item", False):
        return 1
    if THREADS is not None:
        return THREADS
    return numba.get_num_threads() if concurrent_kernels() else 1


def concurrent_kernels() -> bool:
    """Whether threads may call numba's parallel kernels at once: the OpenMP and TBB threading
    layers allow it, the workqueue fallback (a numba without either) does not. Numba chooses
    the layer when a parallel kernel first runs: before that, a tiny decimation runs."""
    try:
        layer = numba.threading_layer()
    except ValueError:  # no parallel kernel has run in this process yet
        anti_aliased(np.zeros(len(anti_aliasing_filter(2))), 2, 1)
        layer = numba.threading_layer()
    return layer != "workqueue"


class TimeLimit(Exception):
    """The loop's time limit (``loop.time_limit_s``) passed during a round."""


def one_blas_thread(fn: F) -> F:
    """``fn`` run with the BLAS libraries limited to one thread (restored after)."""
    @functools.wraps(fn)
    def run(*args, **kwargs):
        with blas.one_blas_thread():
            return fn(*args, **kwargs)
    return run  # type: ignore[return-value]


def in_time(items: Iterable, deadline: float | None) -> Iterator:
    """``items`` one by one, until the clock (:func:`time.monotonic`) passes ``deadline``
    (None: no limit); then :class:`TimeLimit`."""
    for x in items:
        if deadline is not None and time.monotonic() > deadline:
            raise TimeLimit
        yield x


def each(fn: Callable[[T], R], items: Sequence[T], desc: str, progress: bool = False,
         deadline: float | None = None) -> list[R]:
    """``[fn(x) for x in items]``, the items on parallel threads (:func:`parallel_threads`,
    each thread's kernel calls on one numba thread), in the items' order. An item not started
    by ``deadline`` raises :class:`TimeLimit`; an error (or an interrupt in the calling
    thread) cancels the items not started and waits for the running ones. A stop
    (:class:`TimeLimit` or KeyboardInterrupt) carries the results of every item that finished,
    those running at the stop included, as its ``finished`` (index, result) pairs: what was
    computed is not lost."""
    workers = min(len(items), parallel_threads())
    bar = tqdm(total=len(items), desc=desc, disable=not progress)
    if workers <= 1:
        out = []
        try:
            for x in in_time(items, deadline):
                out.append(fn(x))
                bar.update()
        except (TimeLimit, KeyboardInterrupt) as stop:
            stop.finished = list(enumerate(out))
            raise
        finally:
            bar.close()
        return out

    def run(x: T) -> R:
        if deadline is not None and time.monotonic() > deadline:
            raise TimeLimit
        _local.in_item = True
        numba.set_num_threads(1)  # this thread's kernel calls
        return fn(x)

    with bar, ThreadPoolExecutor(workers, thread_name_prefix="candidate") as pool:
        futures = [pool.submit(run, x) for x in items]
        try:
            for f in as_completed(futures):
                f.result()
                bar.update()
        except BaseException as err:
            for f in futures:
                f.cancel()
            wait(futures)  # the running ones end: what they computed is kept with the rest
            if isinstance(err, TimeLimit | KeyboardInterrupt):
                err.finished = [(i, f.result()) for i, f in enumerate(futures)
                                if f.done() and not f.cancelled() and f.exception() is None]
            raise
        return [f.result() for f in futures]
