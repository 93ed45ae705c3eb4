"""Multi-objective optimisation by NSGA-II (pymoo), beyond the paper (Zhao 2017 §3.4 uses a weighted
sum, eqs 38-40): the whole Pareto front of the three global indices, so that what a weighted sum
picks can be seen against what it hides.

``objectives(X)`` maps a population ``(P, n)`` to ``(P, m)`` values to *minimise* (negate an index
to maximise); rows with a non-finite value are infeasible and are passed to pymoo as a violated
constraint, so NSGA-II's constrained domination ranks them behind every feasible design.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = ["ParetoResult", "nsga2", "non_dominated"]


@dataclass
class ParetoResult:
    """The final non-dominated feasible set: design points ``X (K, n)`` and objectives ``F (K, m)``."""

    X: np.ndarray
    F: np.ndarray
    n_gen: int
    nfev: int
    wall_time: float


def non_dominated(F: np.ndarray) -> np.ndarray:
    """Boolean mask of the rows of ``F (K, m)`` (minimised) that no other row dominates.

    pymoo's non-dominated sorting (moocore) on each column's rank: the ranks keep every order and
    every tie, so the mask is the same, and moocore gets the finite values it requires (it
    mis-sorts +inf and crashes on -inf). A row with a NaN neither dominates nor is dominated."""
    from pymoo.util.nds.non_dominated_sorting import NonDominatedSorting

    F = np.asarray(F, dtype=float)
    if F.ndim != 2:
        raise ValueError(f"F must be a 2-D array (K, m), got shape {F.shape}")
    keep = np.isnan(F).any(axis=1)
    rows = np.flatnonzero(~keep)
    if F.shape[1] == 0:
        return np.ones(len(F), dtype=bool)
    if rows.size:
        ranks = np.empty((rows.size, F.shape[1]))
        for j in range(F.shape[1]):
            ranks[:, j] = np.unique(F[rows, j], return_inverse=True)[1]
        keep[rows[NonDominatedSorting().do(ranks, only_non_dominated_front=True)]] = True
    return keep


def nsga2(
    objectives: Callable[[np.ndarray], np.ndarray],
    lower: np.ndarray,
    upper: np.ndarray,
    n_obj: int,
    *,
    population: int = 100,
    generations: int = 100,
    seed: int = 0,
) -> ParetoResult:
    """NSGA-II (pymoo 0.6: SBX crossover, polynomial mutation, its defaults) over the box."""
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.core.problem import Problem
    from pymoo.optimize import minimize
    from pymoo.termination import get_termination

    lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    if lo.shape != hi.shape or lo.ndim != 1 or not np.all(lo < hi):
        raise ValueError(
            f"bounds must be 1-D arrays of equal length with lower < upper: {lo} / {hi}"
        )
    counter = {"nfev": 0}

    class _Problem(Problem):
        def __init__(self):
            super().__init__(n_var=len(lo), n_obj=n_obj, n_ieq_constr=1, xl=lo, xu=hi)

        def _evaluate(self, X, out, *args, **kwargs):
            F = np.asarray(objectives(X), dtype=float)
            counter["nfev"] += len(X)
            bad = ~np.all(np.isfinite(F), axis=1)
            out["F"] = np.where(bad[:, None], 1e9, F)
            out["G"] = np.where(bad, 1.0, -1.0)[:, None]

    t0 = time.perf_counter()
    res = minimize(
        _Problem(),
        NSGA2(pop_size=population),
        get_termination("n_gen", generations),
        seed=seed,
        verbose=False,
    )
    X = np.atleast_2d(res.X) if res.X is not None else np.empty((0, len(lo)))
    F = np.atleast_2d(res.F) if res.F is not None else np.empty((0, n_obj))
    keep = np.all(F < 1e8, axis=1)
    X, F = X[keep], F[keep]
    mask = non_dominated(F)
    return ParetoResult(
        X=X[mask],
        F=F[mask],
        n_gen=generations,
        nfev=counter["nfev"],
        wall_time=time.perf_counter() - t0,
    )
