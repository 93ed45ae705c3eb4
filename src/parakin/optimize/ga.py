"""A real-coded genetic algorithm with MATLAB ``ga`` semantics (Zhao 2017 §3.4) and the normalised
weighted sum of eqs (38)-(40).

The paper sets (§3.4): population 50, 100 generations, arithmetic crossover, 2 elites, crossover
fraction 0.8, roulette-wheel selection, adaptive mutation -- the options ``PopulationSize``,
``MaxGenerations``, ``CrossoverFcn = @crossoverarithmetic``, ``EliteCount``,
``CrossoverFraction``, ``SelectionFcn = @selectionroulette``, ``MutationFcn =
@mutationadaptfeasible`` of MATLAB's ``ga``. One generation here does what ``ga`` does:

1. scores -> expectations by rank scaling (``@fitscalingrank``, ga's default: expectation
   proportional to ``1/sqrt(rank)``, summing to the number of parents);
2. the ``elite`` best pass unchanged; of the remaining ``P - elite`` children
   ``round(crossover_fraction * (P - elite))`` come from crossover, the rest from mutation;
3. parents by roulette on the expectations (``@selectionroulette``);
4. arithmetic crossover: ``child = r p1 + (1 - r) p2`` with one ``r ~ U(0, 1)`` per child;
5. adaptive feasible mutation: a random unit direction times a step ``s (hi - lo)``; ``s``
   starts at 1 and is doubled (capped at 1) after a generation that improved the best score and
   halved otherwise (ga grows / shrinks its step the same way); the step is cut back so the child
   stays inside the bounds.

Everything is vectorised over the population: ``objective(X)`` gets the whole ``(P, n)`` array
and returns ``(P,)`` scores (``inf`` = infeasible). Randomness comes only from the generator
passed in, so a seed reproduces a run bit for bit.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

__all__ = ["GAOptions", "GAResult", "ga", "rank_expectation", "normalised_sum"]


@dataclass(frozen=True)
class GAOptions:
    """The paper's settings (§3.4) as defaults."""

    population: int = 50
    generations: int = 100
    elite: int = 2
    crossover_fraction: float = 0.8

    def __post_init__(self) -> None:
        if not (isinstance(self.population, int) and self.population >= 4):
            raise ValueError(f"population = {self.population!r} must be an integer >= 4")
        if not (isinstance(self.generations, int) and self.generations >= 1):
            raise ValueError(f"generations = {self.generations!r} must be an integer >= 1")
        if not (isinstance(self.elite, int) and 0 <= self.elite < self.population):
            raise ValueError(f"elite = {self.elite!r} must be an integer in [0, population)")
        if not 0.0 <= self.crossover_fraction <= 1.0:
            raise ValueError(f"crossover_fraction = {self.crossover_fraction!r} must lie in [0, 1]")


@dataclass
class GAResult:
    """Best point, its score, and the per-generation history (generation 0 = initial population)."""

    x: np.ndarray
    fun: float
    best: np.ndarray  #: best score per generation (G + 1,)
    mean: np.ndarray  #: mean finite score per generation (G + 1,)
    best_x: np.ndarray  #: best point per generation (G + 1, n)
    nfev: int
    wall_time: float
    population: np.ndarray = field(repr=False)  #: final population (P, n)
    scores: np.ndarray = field(repr=False)  #: its scores (P,)


def rank_expectation(scores: np.ndarray, n_parents: int) -> np.ndarray:
    """MATLAB ``fitscalingrank``: expectation ``1/sqrt(rank)`` (rank 1 = best, ties by order),
    scaled to sum to ``n_parents``. Infeasible (non-finite) scores get the worst ranks."""
    order = np.argsort(np.where(np.isfinite(scores), scores, np.inf), kind="stable")
    rank = np.empty(len(scores))
    rank[order] = np.arange(1, len(scores) + 1)
    e = 1.0 / np.sqrt(rank)
    return e * (n_parents / e.sum())


def _roulette(expectation: np.ndarray, k: int, rng: np.random.Generator) -> np.ndarray:
    """MATLAB ``selectionroulette``: ``k`` indices drawn with probability proportional to expectation."""
    wheel = np.cumsum(expectation) / np.sum(expectation)
    return np.minimum(np.searchsorted(wheel, rng.random(k), side="right"), len(expectation) - 1)


def ga(
    objective: Callable[[np.ndarray], np.ndarray],
    lower: np.ndarray,
    upper: np.ndarray,
    rng: np.random.Generator,
    options: GAOptions = GAOptions(),
) -> GAResult:
    """Minimise ``objective`` over the box ``[lower, upper]`` with the GA described in the module.

    ``objective`` maps ``(P, n)`` -> ``(P,)``; non-finite values mean infeasible.
    """
    t0 = time.perf_counter()
    lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    if lo.shape != hi.shape or lo.ndim != 1 or not np.all(lo <= hi):
        raise ValueError(
            f"bounds must be 1-D arrays of equal length with lower <= upper: {lo} / {hi}"
        )
    P, n = options.population, len(lo)
    span = hi - lo

    def evaluate(X):
        f = np.asarray(objective(X), dtype=float)
        if f.shape != (len(X),):
            raise ValueError(f"objective returned shape {f.shape}, expected ({len(X)},)")
        return np.where(np.isnan(f), np.inf, f)

    X = lo + span * rng.random((P, n))  # gacreationuniform
    f = evaluate(X)
    nfev = P
    n_x = int(round(options.crossover_fraction * (P - options.elite)))
    n_m = P - options.elite - n_x
    step = 1.0
    hist_best, hist_mean, hist_x = [], [], []

    def record():
        i = int(np.argmin(f))
        hist_best.append(f[i])
        fin = f[np.isfinite(f)]
        hist_mean.append(fin.mean() if len(fin) else np.inf)
        hist_x.append(X[i].copy())

    record()
    for _ in range(options.generations):
        exp = rank_expectation(f, 2 * n_x + n_m)
        parents = _roulette(exp, 2 * n_x + n_m, rng)
        elite = np.argsort(f, kind="stable")[: options.elite]
        p1, p2 = X[parents[:n_x]], X[parents[n_x : 2 * n_x]]
        r = rng.random((n_x, 1))
        kids_x = r * p1 + (1 - r) * p2  # crossoverarithmetic
        base = X[parents[2 * n_x :]]
        d = rng.standard_normal((n_m, n))
        d *= span > 0  # fixed variables (lower == upper) do not move
        d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)
        move = step * span * d
        # largest t in (0, 1] keeping base + t move inside the box (mutationadaptfeasible)
        with np.errstate(divide="ignore", invalid="ignore"):
            room = np.where(
                move > 0, (hi - base) / move, np.where(move < 0, (lo - base) / move, np.inf)
            )
        t = np.clip(np.min(room, axis=1, keepdims=True), 0.0, 1.0) * rng.random((n_m, 1))
        kids_m = np.clip(base + t * move, lo, hi)
        X_new = np.concatenate([X[elite], kids_x, kids_m])
        f_new = np.concatenate([f[elite], evaluate(np.concatenate([kids_x, kids_m]))])
        nfev += n_x + n_m
        step = min(1.0, 2 * step) if f_new.min() < f.min() else max(step / 2, 1e-6)
        X, f = X_new, f_new
        record()
    i = int(np.argmin(f))
    return GAResult(
        x=X[i].copy(),
        fun=float(f[i]),
        best=np.array(hist_best),
        mean=np.array(hist_mean),
        best_x=np.array(hist_x),
        nfev=nfev,
        wall_time=time.perf_counter() - t0,
        population=X,
        scores=f,
    )


def normalised_sum(
    values: np.ndarray, vmin: np.ndarray, vmax: np.ndarray, maximise: np.ndarray
) -> np.ndarray:
    """Eqs (38)-(40): ``f = sum_i f_i`` with ``f_i = (sigma_i - min_i)/(max_i - min_i)`` for an index
    to minimise and ``(max_i - sigma_i)/(max_i - min_i)`` for one to maximise.

    Eq (38) prints the first form for all three indices, which for the stiffness index (larger is
    better) would *minimise* stiffness; we flip it (docs/zhao2017_3p4s.md#g18). ``values`` (P, 3) -> (P,).
    """
    values = np.asarray(values, dtype=float)
    vmin, vmax = np.asarray(vmin, dtype=float), np.asarray(vmax, dtype=float)
    if np.any(vmax <= vmin):
        raise ValueError(f"normalisation needs max > min for every index: min {vmin}, max {vmax}")
    f = (values - vmin) / (vmax - vmin)
    f = np.where(np.asarray(maximise, dtype=bool), 1.0 - f, f)
    return f.sum(axis=-1)
