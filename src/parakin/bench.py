"""Benchmarks: every FK solver on the same inputs, in one run, with ratios against a baseline.

Speed claims live here, not in timed tests. :func:`bench_fk` measures, per solver, on the same
seeded sets of reachable inputs (true poses known): success rate (converged *and* within
``success_tol`` of the true pose), median / max pose error, iterations, the median latency of a
single solve (one joint vector per call, as a controller would call it) and the throughput of
one batched call. Ratios are taken against ``scipy.optimize.root`` measured in the same run.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from parakin.mechanisms.base import Array, Mechanism
from parakin.solvers import solve_fk

__all__ = ["SolverSpec", "bench_fk", "BASELINE"]

BASELINE = "scipy-root"


@dataclass(frozen=True)
class SolverSpec:
    """One benchmarked configuration: a label, a registered method, its options and start."""

    label: str
    method: str
    options: dict[str, Any] = field(default_factory=dict)
    start: str = "home"  #: "home" (the mechanism's home pose) or "network" (hybrid: ignored)
    batched: bool = True  #: False for per-pose loops (the scipy baseline): throughput on the single set


def _errors(x: Array, truth: Array) -> Array:
    return np.max(np.abs(x - truth), axis=-1)


def bench_fk(
    mech: Mechanism,
    specs: list[SolverSpec],
    single: tuple[Array, Array],
    batch: tuple[Array, Array],
    *,
    tol: float = 1e-10,
    maxiter: int = 100,
    success_tol: float = 1e-8,
    repeats: int = 3,
    progress: Callable[[str], None] | None = None,
) -> pd.DataFrame:
    """Benchmark ``specs`` on ``single = (joints (N1, m), poses (N1, n))`` one call per input and
    on ``batch = (joints (N2, m), poses (N2, n))`` in one call (best of ``repeats``).

    Returns one row per spec. Accuracy columns come from the batched run (from the single run for
    non-batched specs); latency from the single run. ``speedup_single`` / ``speedup_per_solve``:
    the baseline's median latency over this solver's median latency / per-solve batched time.
    """
    rows = []
    q1, x1 = single
    q2, x2 = batch
    home = mech.home()
    for spec in specs:
        if progress:
            progress(spec.label)
        kwargs = dict(method=spec.method, tol=tol, maxiter=maxiter, **spec.options)
        solve_fk(mech, q1[0], x0=home, **kwargs)  # warm-up (imports, caches)
        latencies = np.empty(len(q1))
        xs = np.empty_like(x1)
        nits = np.empty(len(q1), dtype=np.int64)
        oks = np.empty(len(q1), dtype=bool)
        for i in range(len(q1)):
            t0 = time.perf_counter()
            r = solve_fk(mech, q1[i], x0=home, **kwargs)
            latencies[i] = time.perf_counter() - t0
            xs[i], nits[i], oks[i] = r.x, r.nit, r.success
        if spec.batched:
            best = np.inf
            for _ in range(max(repeats, 1)):
                t0 = time.perf_counter()
                rb = solve_fk(mech, q2, x0=home, **kwargs)
                best = min(best, time.perf_counter() - t0)
            err, nit, ok, n_acc = _errors(rb.x, x2), rb.nit, rb.success, len(q2)
            throughput = len(q2) / best
        else:
            err, nit, ok, n_acc = _errors(xs, x1), nits, oks, len(q1)
            throughput = len(q1) / latencies.sum()
        rows.append({
            "solver": spec.label,
            "method": spec.method,
            "start": spec.start,
            "n_accuracy": n_acc,
            "success_rate": float(np.mean(ok & (err <= success_tol))),
            "median_err_m": float(np.median(err)),
            "max_err_m": float(np.max(err)),
            "median_nit": float(np.median(nit)),
            "max_nit": int(np.max(nit)),
            "median_latency_us": float(np.median(latencies) * 1e6),
            "p95_latency_us": float(np.percentile(latencies, 95) * 1e6),
            "throughput_per_s": float(throughput),
            "batched": spec.batched,
        })
    df = pd.DataFrame(rows)
    base = df[df["method"] == BASELINE]
    if len(base):
        b = base.iloc[0]
        df["speedup_single"] = b["median_latency_us"] / df["median_latency_us"]
        df["speedup_per_solve"] = df["throughput_per_s"] / b["throughput_per_s"]
    return df
