"""Benchmarks: every FK solver on the same inputs, in one run, with ratios against a baseline.

Speed claims live here, not in timed tests. :func:`bench_fk` measures, per solver, on the same
seeded sets of reachable inputs (true poses known): success rate (converged *and* within
``success_tol`` of the true pose), median / max pose error, iterations, the median latency of a
single solve (one joint vector per call, as a controller would call it) and the throughput of
one batched call. Ratios are taken against ``scipy.optimize.root`` measured in the same run.
"""

from __future__ import annotations

import contextlib
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from parakin.kernels import methods
from parakin.mechanisms.base import REGISTRY, Array, Mechanism
from parakin.solvers import solve_fk
from parakin.timing import best_of, best_time, one_thread

__all__ = ["SolverSpec", "bench_fk", "BASELINE"]

BASELINE = "scipy-root"


@dataclass(frozen=True)
class SolverSpec:
    """One benchmarked configuration: a label, a registered method, its options and start."""

    label: str
    method: str
    options: dict[str, Any] = field(default_factory=dict)
    start: str = "home"  #: "home" (the mechanism's home pose) or "network" (hybrid: ignored)
    batched: bool = (
        True  #: False for per-pose loops (the scipy baseline): throughput on the single set
    )


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
            best, rb = best_of(lambda: solve_fk(mech, q2, x0=home, **kwargs), repeats)  # noqa: B023
            err, nit, ok, n_acc = _errors(rb.x, x2), rb.nit, rb.success, len(q2)
            throughput = len(q2) / best
        else:
            err, nit, ok, n_acc = _errors(xs, x1), nits, oks, len(q1)
            throughput = len(q1) / latencies.sum()
        rows.append(
            {
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
            }
        )
    df = pd.DataFrame(rows)
    base = df[df["method"] == BASELINE]
    if len(base):
        b = base.iloc[0]
        df["speedup_single"] = b["median_latency_us"] / df["median_latency_us"]
        df["speedup_per_solve"] = df["throughput_per_s"] / b["throughput_per_s"]
    return df


# ---------------------------------------------------------------------------- compiled-path goals
#: the goals of the compiled path (issue 17), checked by :func:`kernel_goals`
GOALS = {
    "single_vs_scipy": 30.0,
    "newton_per_s": 1e6,
    "lm_per_s": 5e5,
    "stewart36_all_per_s": 2e4,
    "li2017_pso_s": 2.0,
    "stewart66_all_ms": 1.0,  # issue 19: <= 1 ms per input, >= 2000 inputs/s
    "stewart66_all_per_s": 2000.0,
}


def _sample(mech: Mechanism, n: int, seed: int) -> tuple[Array, Array]:
    """``n`` poses uniform in ``mech.pose_bounds()`` inside the domain, and their joints."""
    rng = np.random.default_rng(seed)
    lo, hi = mech.pose_bounds()
    x = rng.uniform(lo, hi, size=(3 * n, mech.n_pose))
    x = x[mech.in_domain(x)][:n]
    return x, mech.ik(x)


@contextlib.contextmanager
def _kernels_off():
    """``PARAKIN_KERNELS=0`` inside the block (the numpy path), restored after."""
    old = os.environ.get("PARAKIN_KERNELS")
    os.environ["PARAKIN_KERNELS"] = "0"
    try:
        yield
    finally:
        if old is None:
            del os.environ["PARAKIN_KERNELS"]
        else:
            os.environ["PARAKIN_KERNELS"] = old


def _compiled_mechanisms() -> list[Mechanism]:
    """Every registered mechanism with compiled kernels (default parameters), in registry order."""
    mechs = [cls() for cls in REGISTRY.values()]
    return [m for m in mechs if m.kernel() is not None]


def kernel_goals(
    n_single: int = 200,
    n_batch: int = 100_000,
    n_all: int = 2000,
    n_all_66: int = 50,
    repeats: int = 3,
    pso: bool = True,
    progress: Callable[[str], None] | None = None,
) -> pd.DataFrame:
    """The compiled path's goals measured in one run (ratios against ``scipy.optimize.root`` in the
    same run): per mechanism, the median single-call latency of ``solve_fk`` (Newton, LM, Broyden,
    BFGS; one joint vector per call, start = home) over ``scipy-root``'s, and the batched Newton
    and LM throughput (``n_batch`` inputs, one call); the 3-6 Stewart's all-solutions FK (inputs/s,
    ``n_all`` inputs) and the 6-6's (``n_all_66`` inputs, 0 skips it: one input per call on one
    thread, median ms; a batch on every core, inputs/s), each batch also against its numpy path
    (``PARAKIN_KERNELS=0``) in the same run; and Li 2017's PSO experiment as published (50 runs x
    50 particles x 1000 iterations, seconds).
    One row per measurement: ``mechanism, what, value, unit, goal, met``. The mechanisms are the
    registered ones with kernels (:data:`parakin.mechanisms.base.REGISTRY`)."""
    rows: list[dict[str, Any]] = []
    # the 6-6 first, its rows last: on an empty kernel cache its tracker is the longest compile
    # (~70 CPU-s, one process), and the solver atlas, which runs beside this in the pipeline,
    # needs it too. Started last, it was the chain that both jobs waited on (a cold quick run:
    # this job idle 57 s on the atlas's compile); first, the other job compiles the solver
    # entries meanwhile
    rows_66 = []
    if n_all_66:
        if progress:
            progress("stewart66 all-solutions")
        rows_66 = _stewart66_all_goals(n_all_66, repeats)
    for mech in _compiled_mechanisms():
        if progress:
            progress(mech.name)
        rows += _solver_goals(mech, n_single, n_batch, repeats)
    mech = REGISTRY["stewart36"]()  # the goals of issue 17 name the 3-6 and the 6-6
    rows += _stewart36_all_goals(mech, n_all, repeats)
    rows += rows_66
    if pso:
        if progress:
            progress("Li 2017 PSO")
        rows += _pso_goals(mech)
    from parakin.dynamics.bench import dynamics_goals  # issue 27: the dynamics rows

    dyn = dynamics_goals(
        [c() for c in REGISTRY.values()], n_batch, max(10, min(200, n_batch // 500)), repeats
    )
    return pd.DataFrame(rows + dyn.to_dict("records"))


def _goal_row(
    mech: str,
    what: str,
    value: float,
    unit: str,
    goal: float,
    higher: bool = True,
    success: float = np.nan,
) -> dict[str, Any]:
    """One row of :func:`kernel_goals`; ``met`` when ``value`` is at least (``higher``) or at most
    ``goal``; ``success``: the success rate of the solves timed (NaN where not a solve), beside the
    speed, since a solver that fails fast is not fast."""
    return {
        "mechanism": mech,
        "what": what,
        "value": value,
        "unit": unit,
        "success_rate": success,
        "goal": goal,
        "met": bool(value >= goal if higher else value <= goal),
    }


def _solver_goals(mech: Mechanism, n_single: int, n_batch: int, repeats: int) -> list[dict]:
    """Single-call latency of each compiled method against ``scipy.optimize.root``, and batched
    Newton and LM throughput, for one mechanism."""
    rows: list[dict[str, Any]] = []
    _, q1 = _sample(mech, n_single, seed=17)
    _, q2 = _sample(mech, n_batch, seed=18)

    def latency(method: str) -> tuple[float, float]:
        """Median seconds of one call, and the success rate of those calls."""
        solve_fk(mech, q1[0], method=method, maxiter=100)  # warm-up: load the cached kernels
        lat = np.empty(len(q1))
        ok = np.empty(len(q1), dtype=bool)
        for i in range(len(q1)):
            t0 = time.perf_counter()
            r = solve_fk(mech, q1[i], method=method, maxiter=100)
            lat[i] = time.perf_counter() - t0
            ok[i] = r.success
        return float(np.median(lat)), float(ok.mean())

    base, base_ok = latency(BASELINE)
    name = mech.name
    rows.append(_goal_row(name, "scipy.optimize.root single call", base * 1e6, "us", np.nan, success=base_ok))  # fmt: skip
    for method in methods.COMPILED:
        t, ok = latency(method)
        rows.append(_goal_row(name, f"{method} single call", t * 1e6, "us", np.nan, success=ok))
        goal = GOALS["single_vs_scipy"]
        rows.append(_goal_row(name, f"{method} single call vs scipy", base / t, "x", goal, success=ok))  # fmt: skip
    for method, goal in (("newton", GOALS["newton_per_s"]), ("lm", GOALS["lm_per_s"])):
        solve_fk(mech, q2[:1000], method=method, maxiter=100)
        t, r = best_of(lambda: solve_fk(mech, q2, method=method, maxiter=100), repeats)  # noqa: B023
        ok = float(np.mean(r.success))
        rows.append(_goal_row(name, f"{method} batched", len(q2) / t, "solves/s", goal, success=ok))
    return rows


def _stewart36_all_goals(mech: Mechanism, n_all: int, repeats: int) -> list[dict]:
    """The 3-6 Stewart's all-solutions FK throughput, compiled and numpy path."""
    _, qa = _sample(mech, n_all, seed=19)
    solve_fk(mech, qa[:10], method="all-solutions")
    t = best_time(lambda: solve_fk(mech, qa, method="all-solutions"), repeats)
    with _kernels_off():  # the numpy path, the baseline of the same run
        t_np = best_time(lambda: solve_fk(mech, qa, method="all-solutions"), 1)
    return [
        _goal_row(mech.name, "all-solutions FK", len(qa) / t, "inputs/s", GOALS["stewart36_all_per_s"]),
        _goal_row(mech.name, "all-solutions FK, numpy path", len(qa) / t_np, "inputs/s", np.nan),
        _goal_row(mech.name, "all-solutions FK vs numpy path", t_np / t, "x", np.nan),
    ]  # fmt: skip


def _stewart66_all_goals(n_all_66: int, repeats: int) -> list[dict]:
    """The 6-6 Stewart's all-solutions FK as issue 29 states its goals: one input per call on one
    thread (median ms, ``<= 1 ms``) and a batch on every core (inputs/s, ``>= 2000``); the batch
    also on the numpy path. A batch's time per input is not a single call's: a call of one input
    waits for its longest path (docs/peers.md, "What is left")."""
    m66 = REGISTRY["stewart66"]()
    _, q66 = _sample(m66, n_all_66, seed=20)
    m66.fk_all(q66[:2])  # warm-up: the geometry's start system, the cached kernels
    single = _one_thread_median(m66.fk_all, q66, repeats)
    t = best_time(lambda: m66.fk_all(q66), repeats)
    with _kernels_off():
        t_np = best_time(lambda: m66.fk_all(q66), 1)
    per = GOALS["stewart66_all_ms"]
    return [
        _goal_row(m66.name, "all-solutions FK, one input per call, 1 thread", 1e3 * single, "ms/input", per, higher=False),
        _goal_row(m66.name, "all-solutions FK batched, time per input", 1e3 * t / len(q66), "ms/input", np.nan),
        _goal_row(m66.name, "all-solutions FK batched", len(q66) / t, "inputs/s", GOALS["stewart66_all_per_s"]),
        _goal_row(m66.name, "all-solutions FK batched, numpy path", 1e3 * t_np / len(q66), "ms/input", np.nan),
        _goal_row(m66.name, "all-solutions FK batched vs numpy path", t_np / t, "x", np.nan),
    ]  # fmt: skip


def _one_thread_median(f: Callable[[Any], Any], items: Any, repeats: int) -> float:
    """Median seconds of ``f(item)`` over ``items`` (each ``repeats`` times) with numba's thread
    pool at one thread (restored after)."""
    lat = []
    with one_thread():
        for _ in range(repeats):
            for item in items:
                t0 = time.perf_counter()
                f(item)
                lat.append(time.perf_counter() - t0)
    return float(np.median(lat))


def _pso_goals(mech: Mechanism) -> list[dict]:
    """Li 2017's PSO experiment as published (50 runs x 50 particles x 1000 iterations, seconds),
    and single PSO solves of the compiled loop against the numpy loop."""
    q = np.broadcast_to(mech.ik(mech.home()), (50, 6))
    fit = lambda x, joints: mech.objective(x, joints[:, None, :])  # noqa: E731  (as chaos.run_pso)
    kw = dict(method="pso", seed=np.arange(50), tol=0.0, maxiter=1000, swarm=50, inertia="linear")
    t = best_time(lambda: solve_fk(mech, q, vclamp=0.2, fitness=fit, **kw), 1)
    what = "Li 2017 PSO experiment (50 x 50 x 1000)"
    rows = [_goal_row(mech.name, what, t, "s", GOALS["li2017_pso_s"], higher=False)]
    # one run per call as the atlas's PSO rows (40 particles, 300 iterations, eq. 20 fitness):
    # the compiled loop (parakin.kernels: pso_row) against the numpy loop, same results
    _, qp = _sample(mech, 10, seed=21)
    kw = dict(method="pso", tol=1e-9, maxiter=300, swarm=40, vclamp=0.2, inertia="linear")

    def rate() -> float:
        solve_fk(mech, qp[0], seed=0, **kw)
        t0 = time.perf_counter()
        for i in range(len(qp)):
            solve_fk(mech, qp[i], seed=i, **kw)
        return len(qp) / (time.perf_counter() - t0)

    r = rate()
    with _kernels_off():
        r_np = rate()
    return rows + [
        _goal_row(mech.name, "PSO single solve (40 x 300)", r, "solves/s", np.nan),
        _goal_row(mech.name, "PSO single solve (40 x 300), numpy loop", r_np, "solves/s", np.nan),
        _goal_row(mech.name, "PSO single solve vs numpy loop", r / r_np, "x", np.nan),
    ]


def format_goals(df: pd.DataFrame) -> str:
    """The rows of :func:`kernel_goals` as a Markdown table."""
    lines = [
        "| mechanism | measurement | value | success | goal | met |",
        "|---|---|---|---|---|---|",
    ]
    for r in df.itertuples():
        goal = (
            ""
            if not np.isfinite(r.goal)
            else f"{'<=' if r.unit in ('s', 'ms/input') else '>='} {r.goal:.3g} {r.unit}"
        )
        met = "" if not np.isfinite(r.goal) else ("yes" if r.met else "no")
        rate = getattr(r, "success_rate", np.nan)
        success = f"{rate:.1%}" if np.isfinite(rate) else ""
        lines.append(
            f"| {r.mechanism} | {r.what} | {r.value:.3g} {r.unit} | {success} | {goal} | {met} |"
        )
    return "\n".join(lines)


if __name__ == "__main__":  # python -m parakin.bench [--quick]
    import sys

    quick = "--quick" in sys.argv
    table = kernel_goals(
        n_single=50 if quick else 200,
        n_batch=10_000 if quick else 100_000,
        n_all=200 if quick else 2000,
        n_all_66=10 if quick else 50,
        pso=not quick,
        progress=lambda s: print(f"parakin.bench: {s} ...", file=sys.stderr),
    )
    print(format_goals(table))
