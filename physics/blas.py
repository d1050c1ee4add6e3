"""One BLAS thread for a block of small dense products.

The products and solves of the contact models (cells of 64 to 512) gain nothing from a second
BLAS thread and lose up to tenfold when the other core is busy (``physics.tribology.mixed_ehl``).
``threadpoolctl.threadpool_limits`` finds the loaded BLAS libraries again on every call (about 3
ms here, reading the process's memory map); one :class:`threadpoolctl.ThreadpoolController`,
made at the first use, limits them in microseconds.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from functools import cache

from threadpoolctl import ThreadpoolController


@cache
def _controller() -> ThreadpoolController:
    return ThreadpoolController()


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """The block run with the BLAS libraries limited to one thread, restored after.

    The libraries are those loaded at the first call (numpy's and scipy's own, which every
    caller has loaded by then)."""
    with _controller().limit(limits=1, user_api="blas"):
        yield
