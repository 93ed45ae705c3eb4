"""Blocks of rows side by side on threads (parakin.kernels.threads): every row exactly once, in
order within its block, the errors of a block raised, a batch started inside a block run in its
thread (never a wait on the pool that runs it)."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from parakin.kernels import threads


def test_every_row_once_whatever_the_thread_count():
    for n in (0, 1, 2, 3, 63, 64, 65, 1000):
        for k in (1, 2, 3, 7):
            seen = np.zeros(n, dtype=int)

            def run(lo, hi, seen=seen):
                seen[lo:hi] += 1

            threads.side_by_side(n, run, threads=k)
            assert np.all(seen == 1), (n, k)


def test_blocks_respect_the_smallest_block():
    sizes: list[int] = []
    lock = threading.Lock()

    def run(lo, hi):
        with lock:
            sizes.append(hi - lo)

    threads.side_by_side(40, run, threads=8, min_block=16)
    assert sorted(sizes) == [20, 20]


def test_an_error_in_a_block_is_raised():
    def run(lo, hi):
        if lo > 0:
            raise ValueError(f"block at {lo}")

    with pytest.raises(ValueError, match="block at"):
        threads.side_by_side(100, run, threads=2)


def test_a_batch_inside_a_block_runs_in_that_blocks_thread():
    inner: list[tuple[str, str]] = []

    def run(lo, hi):
        outer = threading.current_thread().name
        threads.side_by_side(10, lambda a, b: inner.append((outer, threading.current_thread().name)), threads=4)  # fmt: skip

    threads.side_by_side(100, run, threads=2)
    assert inner and all(a == b for a, b in inner)


class _Stateful:
    """A loop with state in place (a swarm's run): each row must advance once. ``ready`` False
    until the first call, as a compiled entry that has not loaded yet."""

    def __init__(self):
        self.ready = False
        self.first_rows: int | None = None

    def __call__(self, p, x, out):
        if not self.ready:
            self.first_rows = len(x)
            self.ready = True
        x += p
        out[:] = x[:, 0]


def test_rows_advances_each_row_once_and_loads_an_entry_on_one_row():
    fn = _Stateful()
    x = np.zeros((500, 3))
    out = np.empty(500)
    threads.rows(fn, (1.0, x, out), (1, 2), parallel=True)
    assert fn.first_rows == 1
    assert np.all(x == 1.0) and np.all(out == 1.0)
    threads.rows(fn, (2.0, x, out), (1, 2))  # by size: 500 >= MIN_ROWS
    assert np.all(x == 3.0)
