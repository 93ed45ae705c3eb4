"""Progress of the long jobs (training, GA, NSGA-II, PSO, the solver atlas): a line per ~10 % on stderr.

The lines go to stderr (the pipeline's logs keep them: ``results/logs/<study>/<artefact>.log``) and
never change a result: a tick only counts calls.

Hand-written rather than tqdm: a line per ~10 % that a log file keeps readable (no carriage-return
redraws), and no dependency for twenty lines.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import Any

__all__ = ["Progress", "counting"]


class Progress:
    """``tick(n)`` adds ``n`` units of work; a line is printed each time another ``step`` (default
    10 %) of ``total`` is done, and once at the end: ``  <label>: 30 % (3/10 generations, 12.1 s)``."""

    def __init__(
        self, label: str, total: int, unit: str = "steps", *, step: float = 0.1, stream=None
    ) -> None:
        self.label, self.total, self.unit = label, max(int(total), 1), unit
        self.step = step
        self.stream = stream
        self.done = 0
        self._next = step
        self._t0 = time.perf_counter()

    def tick(self, n: int = 1) -> None:
        self.done += int(n)
        frac = self.done / self.total
        if frac + 1e-12 >= self._next or self.done == self.total:
            while self._next <= frac + 1e-12:
                self._next += self.step
            print(
                f"  {self.label}: {min(frac, 1.0):4.0%} ({self.done}/{self.total} {self.unit}, "
                f"{time.perf_counter() - self._t0:.1f} s)",
                file=self.stream or sys.stderr,
                flush=True,
            )

    def callback(self, *_: Any, **__: Any) -> None:
        """``tick(1)`` with any arguments (a solver's per-iteration callback)."""
        self.tick(1)


def counting(fn: Callable, progress: Progress, weight: int = 1) -> Callable:
    """``fn`` that ticks ``progress`` by ``weight`` on every call (an objective evaluated once per
    generation, say)."""

    def wrapped(*args, **kwargs):
        out = fn(*args, **kwargs)
        progress.tick(weight)
        return out

    return wrapped
