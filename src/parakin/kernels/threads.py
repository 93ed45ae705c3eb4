"""A batch split into contiguous blocks of rows that run side by side on threads.

Every compiled loop of parakin is a serial loop over rows that releases the GIL (``nogil=True``);
a large batch runs on every core by handing contiguous blocks of its rows to Python threads. Each
row runs the same compiled code as in one serial call and no value crosses rows, so the result is
the same, bit for bit, whatever the thread count. This replaced numba's ``prange`` variants
(``parallel=True``), which compiled every solver a second time (41 % of a method's compile time on
an empty cache) and, on numba's fork-safe ``workqueue`` layer, could be entered from one thread at a
time only.

The thread count is numba's (``NUMBA_NUM_THREADS``, or ``numba.set_num_threads`` in the calling
thread: :func:`parakin.timing.one_thread` makes every batch serial). A batch started from inside a
block runs in that block's thread (a block never waits on the pool that runs it).
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np

__all__ = ["MIN_ROWS", "count", "rows", "side_by_side"]

#: batches of fewer rows run in the calling thread unless asked otherwise (a block's start costs
#: tens of microseconds)
MIN_ROWS = 64

_POOL: list[Any] = [None, None]  # [executor, pid]: recreated after a fork (threads do not follow)
_LOCK = threading.Lock()
_STATE = threading.local()  # .in_block: this thread runs a block


def count() -> int:
    """The threads a batch runs on: numba's thread count for the calling thread (1 without
    numba)."""
    try:
        import numba
    except ImportError:
        return 1
    return int(numba.get_num_threads())


def _pool(workers: int) -> ThreadPoolExecutor:
    with _LOCK:
        pool, pid = _POOL
        if pool is None or pid != os.getpid() or pool._max_workers < workers:
            # a narrower pool is left to idle, not shut down: another thread may be submitting
            pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="parakin")
            _POOL[:] = [pool, os.getpid()]
        return pool


def side_by_side(
    n: int, run: Callable[[int, int], Any], *, threads: int | None = None, min_block: int = 1
) -> None:
    """``run(lo, hi)`` over ``n`` items split into at most ``threads`` (default :func:`count`)
    contiguous blocks of at least ``min_block`` items, run side by side; the first exception of a
    block is raised once every block has ended."""
    threads = count() if threads is None else max(1, int(threads))
    nb = max(1, min(threads, n // max(1, int(min_block))))
    if nb == 1 or getattr(_STATE, "in_block", False):
        run(0, n)
        return
    bounds = (n * np.arange(nb + 1)) // nb

    def block(b: int) -> None:
        _STATE.in_block = True
        try:
            run(int(bounds[b]), int(bounds[b + 1]))
        finally:
            _STATE.in_block = False

    futures = [_pool(nb).submit(block, b) for b in range(nb)]
    errors = [f.exception() for f in futures]
    for err in errors:
        if err is not None:
            raise err


def rows(
    fn: Callable[..., Any],
    args: Sequence[Any],
    batched: Sequence[int],
    *,
    parallel: bool | None = None,
) -> None:
    """``fn(*args)``, a serial compiled loop over the rows of the arrays ``args[i]``, ``i`` in
    ``batched`` (one batch: the same number of rows in each), as blocks of rows side by side.
    ``parallel``: True on every thread, False in the calling thread, None by size (at least
    :data:`MIN_ROWS` rows). A compiled entry not yet loaded runs the first row alone, in the
    calling thread, before the blocks start: it loads there, once (its cache lock and its
    known-answer check)."""
    args = list(args)
    n = len(args[batched[0]])
    if parallel is None:
        parallel = n >= MIN_ROWS
    if not parallel or n < 2:
        fn(*args)
        return
    first = 0
    if getattr(fn, "ready", True) is False:  # parakin.kernels._Entry: it loads on row 0, here
        fn(*_sliced(args, batched, 0, 1))
        first = 1  # each row once: a row may update state in place (a swarm's run)

    def run(lo: int, hi: int) -> None:
        fn(*_sliced(args, batched, first + lo, first + hi))

    side_by_side(n - first, run)


def _sliced(args: list[Any], batched: Sequence[int], lo: int, hi: int) -> list[Any]:
    out = list(args)
    for i in batched:
        out[i] = args[i][lo:hi]
    return out
