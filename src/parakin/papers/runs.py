"""Independent runs of a chaotic computation, side by side on the job's cores.

A genetic algorithm, a particle swarm or a network's training follows another trajectory once one
product rounds differently (another BLAS kernel, another thread count), so the papers' numbers
they produce are judged on the distribution of many independent runs
(:meth:`parakin.claims.Claim.from_runs`), never on one. Each run is a pure function of its own
seed, computed on one thread, so the runs, their order and their results do not depend on how many
processes share them: ``threads`` (the job's cores, Snakemake's ``threads``) only decides how many
run at once.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from typing import Any

from parakin.progress import Progress

__all__ = ["job_threads", "map_runs"]

#: the variables that set the thread count of BLAS, OpenMP (torch) and MKL in a new process
_THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def job_threads(default: int = 1) -> int:
    """The cores this job may use: what its rule gave it (``OMP_NUM_THREADS``, set by every rule
    from its ``threads``), else ``default``."""
    value = os.environ.get("OMP_NUM_THREADS", "")
    return int(value) if value.isdigit() and int(value) >= 1 else default


def map_runs(
    run: Callable[..., Any],
    tasks: Sequence[tuple],
    threads: int | None = None,
    label: str = "runs",
) -> list[Any]:
    """``[run(*task) for task in tasks]``, computed by up to ``threads`` processes at once
    (default: :func:`job_threads`), with a progress line per ~10 % of the runs (``label``).

    ``run`` must be a module-level function (it is sent to fresh processes); each process gets
    one BLAS/OpenMP thread, so a run computes the same in a worker as in this process when the
    job has a single core (where the runs are done here, one after another). The results come
    back in the order of ``tasks``."""
    threads = job_threads() if threads is None else int(threads)
    if threads < 1:
        raise ValueError(f"threads = {threads} must be >= 1")
    ticker = Progress(f"{label} ({min(threads, len(tasks))} at once)", len(tasks), "runs")
    if threads == 1 or len(tasks) <= 1:
        out = []
        for task in tasks:
            out.append(run(*task))
            ticker.tick()
        return out
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    saved = {k: os.environ.get(k) for k in _THREAD_VARIABLES}
    os.environ.update({k: "1" for k in _THREAD_VARIABLES})  # read by each new process at start
    try:
        context = multiprocessing.get_context("spawn")  # no fork of BLAS/OpenMP thread pools
        with ProcessPoolExecutor(min(threads, len(tasks)), mp_context=context) as pool:
            futures = {pool.submit(run, *task): i for i, task in enumerate(tasks)}
            out: list[Any] = [None] * len(tasks)
            for done in as_completed(futures):
                out[futures[done]] = done.result()
                ticker.tick()
            return out
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
