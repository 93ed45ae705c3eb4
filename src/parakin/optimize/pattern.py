"""A deterministic box-constrained search for the extremes of a cheap, low-dimensional function:
a grid over the box picks the starts, a pattern search refines each.

Used where a number must be the same from every seed base (the extremes that normalise Zhao
2017's eq. 38: docs/zhao2017_3p4s.md#s4.7): nothing here is random, so the result depends only on
the function, the box and the resolution. It is a local method started from the best grid
points, not a certificate of the global optimum.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


def box_grid(lower: np.ndarray, upper: np.ndarray, n: int) -> np.ndarray:
    """The ``n**d`` points of a regular grid with ``n`` points per axis over ``[lower, upper]``
    (both ends included), as a ``(n**d, d)`` array in C order."""
    lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    if lo.shape != hi.shape or lo.ndim != 1 or not np.all(lo <= hi):
        raise ValueError(
            f"bounds must be 1-D arrays of equal length with lower <= upper: {lo} / {hi}"
        )
    if int(n) < 2:
        raise ValueError(f"n = {n} grid points per axis must be >= 2")
    axes = [np.linspace(a, b, int(n)) for a, b in zip(lo, hi)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(lo))


@dataclass(frozen=True)
class PatternResult:
    """``x``: the best point found, ``fun``: its value, ``nit``: stencil evaluations, ``nfev``:
    function values computed."""

    x: np.ndarray
    fun: float
    nit: int
    nfev: int


def pattern_search(
    objective: Callable[[np.ndarray], np.ndarray],
    x0: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    step: np.ndarray,
    *,
    xtol: float = 1e-5,
    maxiter: int = 1000,
) -> PatternResult:
    """Minimise ``objective`` ((P, d) -> (P,), NaN or inf = infeasible) from a feasible ``x0``
    inside the box.

    Each iteration evaluates the full ``3**d`` stencil ``x + {-1, 0, 1}**d * step`` (clipped to
    the box) in one batched call and moves to its best point if that is strictly better, doubling
    the step (up to ``step``) so that it travels along a valley; when no point is better, the
    step is halved. It stops when every component of the step is below ``xtol``
    times the box's span (or after ``maxiter`` stencils).

    It is a local method with a fixed set of directions: on a curved edge of the feasible set it
    can stop where none of the ``3**d - 1`` directions both improves and stays feasible, short of
    the optimum on that edge (tests/test_optimization.py shows a case)."""
    lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    x = np.clip(np.asarray(x0, dtype=float), lo, hi)
    h0 = np.asarray(step, dtype=float)
    h = h0.copy()
    span = np.where(hi > lo, hi - lo, 1.0)
    d = len(lo)
    stencil = box_grid(-np.ones(d), np.ones(d), 3)

    def evaluate(X):
        f = np.asarray(objective(X), dtype=float)
        if f.shape != (len(X),):
            raise ValueError(f"objective returned shape {f.shape}, expected ({len(X)},)")
        return np.where(np.isnan(f), np.inf, f)

    fun = float(evaluate(x[None])[0])
    if not np.isfinite(fun):
        raise ValueError(f"x0 = {x.tolist()} is infeasible (objective {fun})")
    nit, nfev = 0, 1
    while nit < maxiter and np.any(h / span >= xtol):
        X = np.clip(x + stencil * h, lo, hi)
        f = evaluate(X)
        nit, nfev = nit + 1, nfev + len(X)
        j = int(np.argmin(f))
        if f[j] < fun:
            x, fun = X[j], float(f[j])
            h = np.minimum(2 * h, h0)
        else:
            h = h / 2
    return PatternResult(x=x, fun=fun, nit=nit, nfev=nfev)
