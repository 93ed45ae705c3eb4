"""Wall-clock timing of repeated calls, for the benchmarks: :mod:`timeit`'s repeat loop (garbage
collection off while a call is timed, as timeit does), the shortest of the calls kept."""

from __future__ import annotations

import contextlib
import os
import timeit
from collections.abc import Callable, Iterator
from typing import Any

__all__ = ["best_of", "best_time", "one_thread", "machine"]


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


def machine() -> str:
    """The machine a timing was taken on, in one line: the processor's model name, the
    microarchitecture that numba's compiler targets (LLVM's name for the host, e.g. ``znver3``),
    the widest SIMD extension of the x86 family it has, the CPUs this process may use and the
    memory. Two machines with the same model name ("AMD EPYC") can differ twofold in speed: the
    microarchitecture and the SIMD width are what tell them apart."""
    model, flags, mem_gb = "", set(), None
    with contextlib.suppress(OSError, StopIteration):
        with open("/proc/cpuinfo") as fh:
            lines = fh.read().splitlines()
        model = next((ln.split(":", 1)[1].strip() for ln in lines if ln.startswith("model name")), "")  # fmt: skip
        flags = set(next(ln.split(":", 1)[1] for ln in lines if ln.startswith("flags")).split())
    with contextlib.suppress(OSError, StopIteration, ValueError):
        with open("/proc/meminfo") as fh:
            kb = next(int(ln.split()[1]) for ln in fh if ln.startswith("MemTotal:"))
        mem_gb = kb / 2**20
    arch = ""
    with contextlib.suppress(ImportError):  # llvmlite comes with numba
        import llvmlite.binding as llvm

        arch = llvm.get_host_cpu_name()
    simd = next((name for flag, name in (("avx512f", "AVX-512"), ("avx2", "AVX2"), ("avx", "AVX"), ("sse2", "SSE2")) if flag in flags), "")  # fmt: skip
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    detail = ", ".join(x for x in (arch, simd) if x)
    parts = [f"{model or 'unknown CPU'}" + (f" ({detail})" if detail else ""), f"{cpus} CPUs"]
    if mem_gb is not None:
        parts.append(f"{mem_gb:.0f} GB")
    return ", ".join(parts)
