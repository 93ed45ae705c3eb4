"""Wall-clock timing of repeated calls, for the benchmarks: :mod:`timeit`'s repeat loop (garbage
collection off while a call is timed, as timeit does), the shortest of the calls kept."""

from __future__ import annotations

import contextlib
import timeit
from collections.abc import Callable, Iterator
from typing import Any

__all__ = ["best_of", "best_time", "one_thread"]


def best_of(f: Callable[[], Any], repeats: int) -> tuple[float, Any]:
    """The shortest of ``repeats`` (at least one) timed calls of ``f`` (seconds) and the last
    call's result."""
    out: list[Any] = [None]

    def call() -> None:
        out[0] = f()

    return min(timeit.repeat(call, number=1, repeat=max(repeats, 1))), out[0]


def best_time(f: Callable[[], Any], repeats: int) -> float:
    """The shortest of ``repeats`` (at least one) timed calls of ``f``, in seconds."""
    return best_of(f, repeats)[0]


@contextlib.contextmanager
def one_thread() -> Iterator[None]:
    """numba's thread count set to 1 inside the block (what "single-threaded" means for the
    compiled code), the caller's count restored after; without numba, nothing to set."""
    try:
        import numba
    except ImportError:  # the numpy path: one thread anyway
        yield
        return
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(threads)
