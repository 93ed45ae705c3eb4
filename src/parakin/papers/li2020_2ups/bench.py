"""Li 2020, our addition: benchmarks of the forward kinematics (issue targets: one PSO run of Table 1's
size <= 100 ms, 20 seeds x 5 cases batched <= 5 s, all-solutions FK <= 1 ms per input, Newton batched
>= 1e5 solves/s), every ratio measured in the same run.

* PSO as Table 1 sets it up (40 particles x 1500 iterations, as printed and improved): the vectorised
  :func:`parakin.solvers.pso.pso` against :func:`pso_loop`, a per-particle Python loop of the *same*
  algorithm (same seed, same random numbers, asserted bitwise-equal result);
* the all-solutions FK, Newton, LM and ``scipy.optimize.root`` via :func:`parakin.bench.bench_fk`.

Sizes are module constants (not configuration): ``N_SINGLE``, ``N_BATCH``, ``N_NEWTON``, ``REPEATS``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

from parakin.config import rng
from parakin.io import write_table
from parakin.mechanisms.base import Array
from parakin.mechanisms.ups2 import UPS2
from parakin.papers.li2020_2ups.common import KEY, mech, table, table2_inputs
from parakin.papers.li2020_2ups.fk import pso_options, seeds
from parakin.papers.sections import table_text
from parakin.registry import TIMING
from parakin.solvers import solve_fk
from parakin.solvers.pso import _BLOCK, inertia_schedule
from parakin.timing import best_of

N_SINGLE = 200  #: FK inputs solved one per call (latency)
N_BATCH = 20_000  #: FK inputs in one batched call (throughput, accuracy)
N_NEWTON = 100_000  #: Newton's own large batch (the >= 1e5 solves/s target)
REPEATS = 3  #: best of, for batched timings
LOOP_CASE = 0  #: Table 2 case (index) used for the loop PSO (one run per variant)


def pso_loop(
    m: UPS2,
    joints: Array,
    *,
    seed: int,
    swarm: int,
    maxiter: int,
    c1: float,
    c2: float,
    w: float,
    w_end: float,
    inertia: str,
    vclamp: float | None,
    tol: float,
) -> dict:
    """The PSO of :func:`parakin.solvers.pso.pso` for ONE input, one particle at a time in Python
    (the textbook implementation): same generator, same draws, same synchronous global-best update."""
    lo, hi = m.pose_bounds()
    n = lo.size
    vmax = None if vclamp is None else vclamp * (hi - lo)
    schedule = inertia_schedule(inertia, w, w_end)
    q = np.asarray(joints, dtype=float).reshape(1, -1)
    g = np.random.default_rng(int(seed))

    def fitness(p: Array) -> float:
        return float(np.sum(np.abs(m.residual(p[None, :], q)), axis=-1)[0])

    x = g.uniform(lo, hi, size=(swarm, n))
    v = np.zeros_like(x)
    f = np.array([fitness(x[p]) for p in range(swarm)])
    pbest, pf = x.copy(), f.copy()
    gi = int(np.argmin(pf))
    gbest, gf = pbest[gi].copy(), float(pf[gi])
    nit = 0
    rand = None
    for k in range(1, maxiter + 1):
        if gf <= tol:
            break
        slot = (k - 1) % _BLOCK
        if slot == 0:
            rand = g.random((_BLOCK, 2, swarm, n))
        wk = float(schedule(k, maxiter, np.array([0])))
        for p in range(swarm):
            r1, r2 = rand[slot, 0, p], rand[slot, 1, p]
            v[p] = wk * v[p] + c1 * r1 * (pbest[p] - x[p]) + c2 * r2 * (gbest - x[p])
            if vmax is not None:
                v[p] = np.clip(v[p], -vmax, vmax)
            x[p] = np.clip(x[p] + v[p], lo, hi)
            fp = fitness(x[p])
            if fp < pf[p]:
                pbest[p], pf[p] = x[p], fp
        gi = int(np.argmin(pf))
        gbest, gf = pbest[gi].copy(), float(pf[gi])
        nit += 1
    return {"x": gbest, "fitness": gf, "nit": nit}


def pso_rows(config: dict) -> list[dict]:
    """PSO timings: one run (vectorised vs per-particle loop, equality asserted), and all seeds x 5
    cases as one batched call vs one call per run."""
    m = mech(config)
    q = table2_inputs()
    rows = []
    for variant in ("as_printed", "improved"):
        opts = pso_options(config, variant)
        s = seeds(config, variant)
        one = q[LOOP_CASE : LOOP_CASE + 1]
        t_vec, res = best_of(
            lambda one=one, s=s, opts=opts: solve_fk(m, one, method="pso", seed=int(s[0]), **opts),
            REPEATS,
        )
        t0 = time.perf_counter()
        loop = pso_loop(
            m,
            one[0],
            seed=int(s[0]),
            **{
                k: opts[k]
                for k in ("swarm", "maxiter", "c1", "c2", "w", "w_end", "inertia", "vclamp", "tol")
            },
        )
        t_loop = time.perf_counter() - t0
        same = (
            np.array_equal(loop["x"], res.x[0])
            and loop["fitness"] == float(res.fitness[0])
            and loop["nit"] == int(res.nit[0])
        )
        if not same:
            raise AssertionError(
                f"loop PSO differs from the vectorised one ({variant}): {loop} vs {res.x[0]}, "
                f"{res.fitness[0]}, {res.nit[0]}"
            )
        base = {"variant": variant, "swarm": opts["swarm"], "maxiter": opts["maxiter"]}
        rows.append(
            {
                **base,
                "task": f"one run (case {LOOP_CASE + 1}, seed {int(s[0])})",
                "runs": 1,
                "iterations": int(res.nit[0]),
                "vectorised_time_s": t_vec,
                "reference": "per-particle Python loop",
                "reference_time_s": t_loop,
                "speedup": t_loop / t_vec,
                "same_result": same,
            }
        )
        nq, ns = len(q), len(s)
        qq, ss = np.repeat(q, ns, axis=0), np.tile(s, nq)
        t_batch, rb = best_of(
            lambda qq=qq, ss=ss, opts=opts: solve_fk(m, qq, method="pso", seed=ss, **opts),
            repeats=1,
        )
        t0 = time.perf_counter()
        for i in range(len(qq)):
            ri = solve_fk(m, qq[i : i + 1], method="pso", seed=int(ss[i]), **opts)
            if not np.array_equal(ri.x[0], rb.x[i]):
                raise AssertionError(f"PSO run {i} differs alone and in the batch ({variant})")
        t_runs = time.perf_counter() - t0
        rows.append(
            {
                **base,
                "task": f"{ns} seeds x {nq} cases, one batched call",
                "runs": nq * ns,
                "iterations": int(rb.nit.max()),
                "vectorised_time_s": t_batch,
                "reference": "one vectorised call per run",
                "reference_time_s": t_runs,
                "speedup": t_runs / t_batch,
                "same_result": True,
            }
        )
        rows.append(
            {
                **base,
                "task": f"{ns} seeds x {nq} cases, one batched call",
                "runs": nq * ns,
                "iterations": int(rb.nit.max()),
                "vectorised_time_s": t_batch,
                "reference": "per-particle Python loop (one-run time x runs x iterations ratio, extrapolated)",
                "reference_time_s": t_loop / max(int(res.nit[0]), 1) * float(rb.nit.sum()),
                "speedup": t_loop / max(int(res.nit[0]), 1) * float(rb.nit.sum()) / t_batch,
                "same_result": same,
            }
        )
    return rows


def fk_rows(config: dict) -> pd.DataFrame:
    """The FK solvers on random poses of Table 1's box via :func:`parakin.bench.bench_fk`."""
    from parakin.bench import SolverSpec, bench_fk

    m = mech(config)
    lo, hi = m.pose_bounds()
    g = rng(config, f"{KEY}.bench")
    x1 = g.uniform(lo, hi, (N_SINGLE, 3))
    x2 = g.uniform(lo, hi, (N_BATCH, 3))
    specs = [
        SolverSpec(
            "all-solutions FK (closed-form Y + degree-8 polynomial)", "closed-form", start="-"
        ),
        SolverSpec("Newton from home", "newton"),
        SolverSpec("Levenberg-Marquardt from home", "lm"),
        SolverSpec("scipy.optimize.root (hybr), loop", "scipy-root", batched=False),
    ]
    df = bench_fk(
        m,
        specs,
        (m.ik(x1), x1),
        (m.ik(x2), x2),
        tol=1e-12,
        maxiter=50,
        success_tol=1e-8,
        repeats=REPEATS,
        progress=lambda label: print(f"  bench: {label}", file=sys.stderr),
    )
    # fk_all itself (every root, both checks), one input per call
    q1 = m.ik(x1)
    m.fk_all(q1[0])
    lat = []
    for i in range(len(q1)):
        t0 = time.perf_counter()
        m.fk_all(q1[i])
        lat.append(time.perf_counter() - t0)
    # Newton on a large batch
    x3 = g.uniform(lo, hi, (N_NEWTON, 3))
    q3 = m.ik(x3)
    t3, r3 = best_of(
        lambda: solve_fk(m, q3, method="newton", x0=m.home(), tol=1e-12, maxiter=50), REPEATS
    )
    ok = float(np.mean(r3.success & (np.max(np.abs(r3.x - x3), axis=-1) <= 1e-8)))
    base = df[df["method"] == "scipy-root"].iloc[0]
    extra = pd.DataFrame(
        [
            {
                "solver": "fk_all (all real roots), one input per call",
                "method": "fk_all",
                "start": "-",
                "n_accuracy": N_SINGLE,
                "median_latency_us": float(np.median(lat) * 1e6),
                "p95_latency_us": float(np.percentile(lat, 95) * 1e6),
                "throughput_per_s": len(lat) / float(np.sum(lat)),
                "batched": False,
            },
            {
                "solver": f"Newton from home, batch of {N_NEWTON}",
                "method": "newton",
                "start": "home",
                "n_accuracy": N_NEWTON,
                "success_rate": ok,
                "median_nit": float(np.median(r3.nit)),
                "max_nit": int(np.max(r3.nit)),
                "throughput_per_s": N_NEWTON / t3,
                "batched": True,
            },
        ]
    )
    extra["speedup_single"] = base["median_latency_us"] / extra["median_latency_us"]
    extra["speedup_per_solve"] = extra["throughput_per_s"] / base["throughput_per_s"]
    return pd.concat([df, extra], ignore_index=True)


@table("benchmark", "extra_benchmark", config=[KEY], tolerance=TIMING)
def benchmark(config: dict, outdir: Path) -> list[Path]:
    """extra_benchmark.{csv,md}: PSO (vectorised vs loop) and the FK solvers, one table."""
    p = pd.DataFrame(pso_rows(config))
    p.insert(0, "part", "pso")
    f = fk_rows(config)
    f.insert(0, "part", "fk")
    df = pd.concat([p, f], ignore_index=True)
    return write_table(
        df,
        outdir / "extra_benchmark",
        title="FK benchmarks on this machine (ratios in the same run)",
        floatfmt=".4g",
        notes="PSO: Table 1's setup (40 x 1500, F < 1e-6 mm); the loop PSO is the same algorithm "
        "per particle in Python, its result asserted identical (same_result). FK: random poses "
        f"of Table 1's box; {N_SINGLE} single calls (latency), {N_BATCH} batched (throughput, "
        f"best of {REPEATS}); speedup_* against scipy.optimize.root per pose. Wall-clock, "
        "machine-dependent.",
    )


def claims(figdir: Path, ref: pd.DataFrame) -> list:
    return []


def _benchmark_sentences(d: pd.DataFrame) -> str:
    """The vectorised PSO against its reference loop, then the FK solvers' latency and throughput."""
    p = d[d["part"] == "pso"]
    f = d[d["part"] == "fk"].set_index("solver")
    pso = (
        "**Benchmarks (ours, this machine).** PSO as Table 1 sets it up: "
        + "; ".join(
            f"{r.variant}, {r.task}: {r.vectorised_time_s:.3g} s vectorised vs {r.reference_time_s:.3g} s "
            f"{r.reference} (x{r.speedup:.3g})"
            for r in p.itertuples()
        )
        + "."
    )
    fk = (
        "FK: "
        + "; ".join(
            f"{name}: {r.median_latency_us:.3g} µs single, {r.throughput_per_s:.3g} solves/s"
            + (
                f" (x{r.speedup_per_solve:.3g} scipy root per solve)"
                if np.isfinite(r.speedup_per_solve)
                else ""
            )
            for name, r in f.iterrows()
        )
        + "."
    )
    return f"{pso} {fk}"


def summary(figdir: Path, ref: pd.DataFrame) -> str:
    return table_text(figdir, {"extra_benchmark.csv": _benchmark_sentences})
