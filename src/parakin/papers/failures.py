"""How often a solver started from a fixed pose fails, region by region, and how it fails.

The papers say numerical forward kinematics "depends on the initial value"; whether that shows
depends on where the inputs come from. :func:`failure_table` solves the same sampled poses' joints
with each solver from the same start and counts, per region, the failures with an exact
(Clopper-Pearson) confidence interval, split by kind: *not converged* (the solver gave up: step
limit, stall, divergence) and *another assembly* (converged to a pose that solves the same joints
but is not the sampled one: another branch of the forward kinematics). Works on any mechanism.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
import pandas as pd

from parakin.mechanisms.base import Array, Mechanism
from parakin.solvers import solve_fk

__all__ = ["clopper_pearson", "failure_table"]

#: confidence level of the failure rates' intervals
LEVEL = 0.95


def clopper_pearson(k: int, n: int, level: float = LEVEL) -> tuple[float, float]:
    """The exact two-sided confidence interval of a binomial rate with ``k`` events in ``n``."""
    from scipy.stats import beta

    if not 0 <= k <= n or n < 1:
        raise ValueError(f"need 0 <= k <= n and n >= 1, got k = {k}, n = {n}")
    a = (1 - level) / 2
    low = 0.0 if k == 0 else float(beta.ppf(a, k, n - k + 1))
    high = 1.0 if k == n else float(beta.ppf(1 - a, k + 1, n - k))
    return low, high


def failure_table(
    mech: Mechanism,
    regions: Mapping[str, Array],
    solvers: Mapping[str, dict | Callable],
    *,
    x0: Array,
    success_tol: float,
    tol: float = 1e-10,
    maxiter: int = 100,
    near_tol: float | None = None,
) -> pd.DataFrame:
    """One row per (region, solver): ``poses``, ``failures`` (not within ``success_tol`` of the
    sampled pose), ``failure_rate`` with its :data:`LEVEL` interval, and the kinds
    ``not_converged`` / ``another_assembly``. ``regions``: name -> sampled poses ``(N, n)``;
    ``solvers``: label -> keyword arguments of :func:`parakin.solvers.solve_fk` (``method`` ...)
    or a function ``solve(joints, x0=, tol=, maxiter=) -> FKResult`` (a solver set up outside the
    library), every one started from ``x0``. With ``near_tol``, the column ``short_of_tol`` counts
    the failures within ``near_tol`` of the sampled pose: stopped near it, short of the accuracy
    (a stopping rule or an inexact gradient, not another basin)."""
    rows = []
    for region, poses in regions.items():
        poses = np.asarray(poses, dtype=float)
        joints = mech.ik(poses)
        for label, spec in solvers.items():
            if callable(spec):
                res = spec(joints, x0=x0, tol=tol, maxiter=maxiter)
            else:
                res = solve_fk(mech, joints, x0=x0, tol=tol, maxiter=maxiter, **spec)
            with np.errstate(invalid="ignore"):
                err = np.max(np.abs(res.x - poses), axis=-1)
            right = (err <= success_tol) & res.success
            other = res.success & ~right
            n, k = len(poses), int((~right).sum())
            low, high = clopper_pearson(k, n)
            row = {
                "region": region,
                "solver": label,
                "poses": n,
                "failures": k,
                "failure_rate": k / n,
                "rate_ci_low": low,
                "rate_ci_high": high,
                "not_converged": int((~res.success).sum()),
                "another_assembly": int(other.sum()),
            }
            if near_tol is not None:
                row["short_of_tol"] = int((~right & (err <= near_tol)).sum())
            row["median_nit"] = float(np.median(res.nit[right])) if right.any() else np.nan
            rows.append(row)
    return pd.DataFrame(rows)
