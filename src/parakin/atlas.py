"""The solver atlas: every forward-kinematics solver on every mechanism, on the same inputs.

No paper compares its FK solver with the others on more than its own mechanism; this module does,
for any set of mechanisms (the four of the papers, or your own). For one mechanism it draws, from a
seeded generator, one set of *scenarios*, each a set of FK problems with a known answer:

* ``nominal``: exact joints of random reachable poses, each solver started from the true pose
  plus a uniform perturbation of ``start_spread`` times the box width per coordinate (a tracking
  controller's situation: the last pose is near the new one);
* ``cold``: the same joints, every solver started from the mechanism's home pose (what the papers
  do: one fixed initial guess);
* ``noisy``: the joints with Gaussian sensor noise of standard deviation ``joint_noise`` (joint
  units); the reference answer is the exact FK of the *noisy* joints on the true pose's assembly
  (Newton continued from the true pose to 1e-13); inputs that no longer assemble are dropped;
* ``near-singular``: the ``n`` poses of largest condition number of ``A = d residual / d pose``
  (a forward, type-II singularity where ``A`` is singular) out of ``pool_factor * n`` random ones.

A solve succeeds when :func:`~parakin.solvers.solve_fk` calls it a success (converged *and* a
valid answer: in the domain, on the mechanism's assembly, its IK within ``joint_tol`` of the joints)
**and** its pose is within ``success_tol`` of the reference pose (angles compared modulo 2 pi).
Failures that look like answers are counted apart: ``wrong_assembly_rate`` / ``n_wrong_assembly``, a
converged solve on another assembly (a mirror image, the other branch: status ``WRONG_ASSEMBLY``,
or a valid answer far from the reference); ``wrong_answer_rate`` / ``n_wrong_answer``, a residual
within ``tol`` whose pose is not an answer (status ``WRONG_ANSWER`` or ``OUT_OF_DOMAIN``).

Every solver of a mechanism sees the same joints and the same starts (PSO searches the box and
ignores the start; the hybrid starts from its network). Columns per (mechanism, scenario, solver):
success rate, wrong-assembly and wrong-answer rates and counts, median / 95th-percentile pose error, median iterations (of the right answers) and
function evaluations, and in the nominal scenario the median latency of one solve per call and the
throughput of one batched call, with ratios against ``scipy.optimize.root`` measured in the same
run. Timing columns carry the words latency / throughput / speedup (see
:func:`parakin.io.is_timing_column`), so reproducibility checks skip them.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from parakin.mechanisms.base import Array, Mechanism
from parakin.solvers import Status, solve_fk
from parakin.workspace import sample_reachable

__all__ = [
    "AtlasSolver",
    "AtlasCase",
    "Scenario",
    "SCENARIOS",
    "BASELINE",
    "make_scenario",
    "pose_error",
    "evaluate",
    "run_atlas",
    "standard_solvers",
]

BASELINE = "scipy-root"
SCENARIOS = ("nominal", "cold", "noisy", "near-singular")


@dataclass(frozen=True)
class AtlasSolver:
    """One solver configuration: a label, a registered FK method and its options."""

    label: str
    method: str
    options: dict[str, Any] = field(default_factory=dict)
    batched: bool = (
        True  #: False: one call per input (the scipy baseline); throughput from that loop
    )
    max_rows: int | None = None  #: solve only the first rows of each scenario (costly solvers: PSO)
    single_calls: int | None = (
        None  #: cap on the single-call latency samples (default: the atlas's)
    )
    maxiter: int | None = None  #: iteration limit of this solver (default: the atlas's)
    seed: int | None = None  #: stochastic solvers: input i is solved with ``seed = seed + i``

    def kwargs(self, tol: float, maxiter: int, rows: slice | int) -> dict[str, Any]:
        """Keyword arguments of :func:`parakin.solvers.solve_fk` for input ``rows`` (a slice or an index)."""
        kw = dict(method=self.method, tol=tol, maxiter=self.maxiter or maxiter, **self.options)
        if self.seed is not None:
            kw["seed"] = self.seed + (
                np.arange(rows.start or 0, rows.stop) if isinstance(rows, slice) else rows
            )
        return kw


@dataclass(frozen=True)
class AtlasCase:
    """One mechanism of the atlas: the mechanism, the pose box its inputs are drawn from, its solvers."""

    key: str
    mech: Mechanism
    box: tuple[Array, Array]
    solvers: tuple[AtlasSolver, ...]


@dataclass(frozen=True)
class Scenario:
    """FK problems with known answers: ``joints`` (N, m), ``start`` (N, n), ``reference`` (N, n),
    and ``cond`` (N,), the condition number of ``A = d residual / d pose`` at the reference."""

    name: str
    joints: Array
    start: Array
    reference: Array
    cond: Array


def _condition(mech: Mechanism, pose: Array, joints: Array) -> Array:
    with np.errstate(all="ignore"):
        c = np.linalg.cond(mech.jacobian_pose(pose, joints))
    return np.where(np.isfinite(c), c, np.inf)


def _starts(truth: Array, box: tuple[Array, Array], spread: float, g: np.random.Generator) -> Array:
    lo, hi = box
    return truth + g.uniform(-1.0, 1.0, truth.shape) * spread * (hi - lo)


def make_scenario(
    mech: Mechanism,
    name: str,
    n: int,
    g: np.random.Generator,
    *,
    box: tuple[Array, Array] | None = None,
    start_spread: float = 0.1,
    joint_noise: float = 1e-4,
    pool_factor: int = 20,
) -> Scenario:
    """Scenario ``name`` (one of :data:`SCENARIOS`) of ``n`` problems drawn from ``box`` (default
    ``mech.pose_bounds()``) with generator ``g`` (see the module docstring)."""
    if name not in SCENARIOS:
        raise ValueError(f"unknown scenario {name!r}; known: {', '.join(SCENARIOS)}")
    box = tuple(np.asarray(b, dtype=float) for b in (box or mech.pose_bounds()))
    if name == "near-singular":
        pool = sample_reachable(mech, pool_factor * n, g, bounds=box)
        cond = _condition(mech, pool, mech.ik(pool))
        truth = pool[np.argsort(-cond, kind="stable")[:n]]
    else:
        truth = sample_reachable(mech, n, g, bounds=box)
    joints = mech.ik(truth)
    start = (
        np.broadcast_to(mech.home(), truth.shape).copy()
        if name == "cold"
        else _starts(truth, box, start_spread, g)
    )
    reference = truth
    if name == "noisy":
        joints = joints + g.normal(0.0, joint_noise, joints.shape)
        res = solve_fk(mech, joints, x0=truth, method="newton", tol=1e-13, maxiter=30)
        keep = res.success & (pose_error(mech, res.x, truth) <= 1e3 * joint_noise)
        joints, start, reference = joints[keep], start[keep], res.x[keep]
    return Scenario(name, joints, start, reference, _condition(mech, reference, joints))


def pose_error(mech: Mechanism, x: Array, reference: Array) -> Array:
    """``max_k |x_k - reference_k|`` per row, angle coordinates (unit ``rad``) compared modulo 2 pi."""
    return np.max(np.abs(mech.pose_difference(x, reference)), axis=-1)


def _solve(
    mech: Mechanism, solver: AtlasSolver, joints: Array, start: Array, tol: float, maxiter: int
):
    """Batched call, or one call per input for a non-batched solver; returns (result fields, seconds)."""
    t0 = time.perf_counter()
    if solver.batched:
        r = solve_fk(mech, joints, x0=start, **solver.kwargs(tol, maxiter, slice(0, len(joints))))
        out = (r.x, r.success, r.status, r.nit, r.nfev)
    else:
        rs = [
            solve_fk(mech, joints[i], x0=start[i], **solver.kwargs(tol, maxiter, i))
            for i in range(len(joints))
        ]
        out = (
            np.array([r.x for r in rs]).reshape(start.shape),
            np.array([bool(r.success) for r in rs]),
            np.array([int(r.status) for r in rs]),
            np.array([int(r.nit) for r in rs]),
            np.array([int(r.nfev) for r in rs]),
        )
    return out, time.perf_counter() - t0


def _median_over(values: np.ndarray, mask: np.ndarray) -> float:
    """Median of ``values[mask]``, NaN for an empty mask."""
    return float(np.median(values[mask])) if np.any(mask) else float("nan")


def evaluate(
    mech: Mechanism,
    solver: AtlasSolver,
    scenario: Scenario,
    *,
    tol: float = 1e-10,
    maxiter: int = 100,
    success_tol: float = 1e-6,
) -> dict[str, Any]:
    """Accuracy of ``solver`` on ``scenario``: one row of the atlas (no latency columns)."""
    rows = slice(None) if solver.max_rows is None else slice(0, solver.max_rows)
    q, x0, ref = scenario.joints[rows], scenario.start[rows], scenario.reference[rows]
    if len(q) == 0:
        raise ValueError(f"scenario {scenario.name!r} has no inputs left for {solver.label}")
    (x, success, status, nit, nfev), seconds = _solve(mech, solver, q, x0, tol, maxiter)
    err = pose_error(mech, x, ref)
    right = err <= success_tol
    wrong_assembly = (status == Status.WRONG_ASSEMBLY) | (success & ~right)
    wrong_answer = np.isin(status, [Status.WRONG_ANSWER, Status.OUT_OF_DOMAIN])
    return {
        "solver": solver.label,
        "method": solver.method,
        "scenario": scenario.name,
        "n": len(q),
        "median_cond": float(np.median(scenario.cond[rows])),
        "success_rate": float(np.mean(success & right)),
        "wrong_assembly_rate": float(np.mean(wrong_assembly)),
        "wrong_answer_rate": float(np.mean(wrong_answer)),
        "n_wrong_assembly": int(np.sum(wrong_assembly)),
        "n_wrong_answer": int(np.sum(wrong_answer)),
        "median_err": float(np.median(err)),
        "p95_err": float(np.percentile(err, 95)),
        # iterations to convergence: over the right answers only (NaN where there are none); the
        # count of a search that never converges is not a property of the solver (it moved by 3
        # between two BLAS kernels for Broyden from the 12-leg cube's singular home pose)
        "median_nit": _median_over(nit, success & right),
        "median_nfev": _median_over(nfev, success & right),
        "_throughput": len(q) / seconds,
    }


def _latency(
    mech: Mechanism, solver: AtlasSolver, scenario: Scenario, n: int, tol: float, maxiter: int
) -> float:
    """Median wall time (s) of one ``solve_fk`` call on one input, over the first ``n`` inputs."""
    solve_fk(
        mech, scenario.joints[0], x0=scenario.start[0], **solver.kwargs(tol, maxiter, 0)
    )  # warm-up
    times = []
    for i in range(min(n, len(scenario.joints))):
        kwargs = solver.kwargs(tol, maxiter, i)
        t0 = time.perf_counter()
        solve_fk(mech, scenario.joints[i], x0=scenario.start[i], **kwargs)
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def _throughput(
    mech: Mechanism, solver: AtlasSolver, scenario: Scenario, repeats: int, tol: float, maxiter: int
) -> float:
    """Solves per second of one batched call on all of ``scenario`` (best of ``repeats``)."""
    best = np.inf
    for _ in range(max(repeats, 1)):
        _, seconds = _solve(mech, solver, scenario.joints, scenario.start, tol, maxiter)
        best = min(best, seconds)
    return len(scenario.joints) / best


def run_atlas(
    cases: Sequence[AtlasCase],
    rng_for: Callable[[str], np.random.Generator],
    *,
    n: int = 500,
    n_single: int = 30,
    n_batch: int = 20_000,
    repeats: int = 3,
    scenarios: Sequence[str] = SCENARIOS,
    start_spread: float = 0.1,
    joint_noise: float = 1e-4,
    pool_factor: int = 20,
    tol: float = 1e-10,
    maxiter: int = 100,
    success_tol: float = 1e-6,
    gpu: Callable[[AtlasCase, Scenario], dict[str, float]] | None = None,
    progress: Callable[[str], None] | None = None,
) -> pd.DataFrame:
    """The atlas: one row per (case, scenario, solver); see the module docstring. ``home_cond``
    and ``median_cond``: condition numbers of ``A = d residual / d pose`` at the home pose (the cold
    start) and over the scenario's reference poses.

    ``rng_for(stream)`` gives the generator of a named stream (e.g. ``parakin.config.rng`` bound to
    a config), so that every case and scenario draws independently and reproducibly. Accuracy on
    ``n`` inputs per scenario; in ``nominal`` also the median latency of ``n_single`` single calls
    and the throughput of one batched call on ``n_batch`` fresh inputs (best of ``repeats``; for a
    non-batched or row-capped solver, the rate of its accuracy run). ``gpu(case, batch)`` (optional)
    returns ``{method: solves/s}`` measured on a GPU for the ``nominal`` throughput batch.
    """
    rows = []
    for case in cases:
        home = case.mech.home()
        home_cond = float(_condition(case.mech, home, case.mech.ik(home)))
        for name in scenarios:
            if progress:
                progress(f"{case.key}: {name}")
            sc = make_scenario(
                case.mech,
                name,
                n,
                rng_for(f"atlas.{case.key}.{name}"),
                box=case.box,
                start_spread=start_spread,
                joint_noise=joint_noise,
                pool_factor=pool_factor,
            )
            big = gpu_rates = None
            if name == "nominal":
                big = make_scenario(
                    case.mech,
                    name,
                    n_batch,
                    rng_for(f"atlas.{case.key}.batch"),
                    box=case.box,
                    start_spread=start_spread,
                )
                gpu_rates = gpu(case, big) if gpu else None
            for solver in case.solvers:
                row = {
                    "mechanism": case.key,
                    "home_cond": home_cond,
                    **evaluate(
                        case.mech, solver, sc, tol=tol, maxiter=maxiter, success_tol=success_tol
                    ),
                }
                rate = row.pop("_throughput")
                row["median_latency_us"] = np.nan
                row["throughput_per_s"] = np.nan
                if big is not None:
                    row["median_latency_us"] = 1e6 * _latency(
                        case.mech, solver, sc, solver.single_calls or n_single, tol, maxiter
                    )
                    row["throughput_per_s"] = (
                        _throughput(case.mech, solver, big, repeats, tol, maxiter)
                        if solver.batched and solver.max_rows is None
                        else rate
                    )
                    if gpu_rates is not None:
                        row["gpu_throughput_per_s"] = gpu_rates.get(solver.method, np.nan)
                rows.append(row)
    df = pd.DataFrame(rows)
    return _with_ratios(df)


def _with_ratios(df: pd.DataFrame) -> pd.DataFrame:
    """Add ``speedup_single`` and ``speedup_per_solve``: the baseline's latency over each solver's,
    and each solver's throughput over the baseline's, within the same mechanism and scenario."""
    base = df[df["method"] == BASELINE].set_index(["mechanism", "scenario"])
    keys = pd.MultiIndex.from_frame(df[["mechanism", "scenario"]])
    lat = base["median_latency_us"].reindex(keys).to_numpy()
    thr = base["throughput_per_s"].reindex(keys).to_numpy()
    df["speedup_single"] = lat / df["median_latency_us"].to_numpy()
    df["speedup_per_solve"] = df["throughput_per_s"].to_numpy() / thr
    return df


def standard_solvers(
    mech: Mechanism,
    *,
    pso_swarm: int = 40,
    pso_maxiter: int = 300,
    pso_rows: int | None = None,
    pso_ftol: float = 1e-9,
    box: tuple[Array, Array] | None = None,
    network: Any = None,
    seed: int = 0,
) -> tuple[AtlasSolver, ...]:
    """Every FK solver of the project that applies to ``mech``: Newton, Broyden, BFGS, LM, standard
    PSO (linearly decreasing inertia 0.9 -> 0.4, Shi & Eberhart), chaotic PSO (logistic-map inertia,
    mu = 4), both stopping at fitness ``sum |residual| <= pso_ftol`` (Li 2020's eq. 20 threshold), the hybrid network + Broyden where ``network`` is given, the closed form (``fk``) or the
    all-solutions FK nearest the start (``fk_all``) where the mechanism has one, and
    ``scipy.optimize.root`` (one call per input) as the baseline."""
    from parakin.solvers.pso import ChaoticLogistic

    box = tuple(np.asarray(b, dtype=float) for b in (box or mech.pose_bounds()))
    # Li 2020's stopping threshold F = sum |f| < 1e-6 mm (eq. 20), its c1 = c2 = 2, our velocity clamp
    pso = dict(swarm=pso_swarm, bounds=box, vclamp=0.2, ftol=pso_ftol)
    common = dict(max_rows=pso_rows, single_calls=3, maxiter=pso_maxiter, seed=seed)
    out = [
        AtlasSolver("Newton", "newton"),
        AtlasSolver("Broyden", "broyden"),
        AtlasSolver("BFGS", "bfgs"),
        AtlasSolver("Levenberg-Marquardt", "lm"),
        AtlasSolver("PSO (standard)", "pso", {**pso, "inertia": "linear"}, **common),
        AtlasSolver("PSO (chaotic)", "pso", {**pso, "inertia": ChaoticLogistic(mu=4.0)}, **common),
    ]
    if network is not None:
        out.append(AtlasSolver("hybrid (network + Broyden)", "hybrid", {"network": network}))
    if hasattr(mech, "fk_all"):
        out.append(AtlasSolver("all-solutions FK, nearest start", "all-solutions"))
    elif getattr(mech, "fk", None) is not None:
        out.append(AtlasSolver("closed form", "closed-form"))
    out.append(AtlasSolver("scipy.optimize.root (hybr), loop", BASELINE, batched=False))
    return tuple(out)
