"""Wall-clock timing of repeated calls, for the benchmarks: :mod:`timeit`'s repeat loop (garbage
collection off while a call is timed, as timeit does), the shortest of the calls kept."""

from __future__ import annotations

import timeit
from collections.abc import Callable
from typing import Any

__all__ = ["best_of", "best_time"]


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
