"""The baseline a user would write: ``scipy.optimize.root`` called once per pose in a loop.

It is registered as ``"scipy-root"`` so that benchmarks measure every solver against it in the
same run (DESIGN: speed claims are ratios against a baseline). ``method="hybr"`` (MINPACK's
Powell hybrid, scipy's default) with the mechanism's analytic Jacobian.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from parakin.mechanisms.base import Array, Mechanism
from parakin.solvers.result import FKResult, Status, inf_norm, rowwise, summarize

__all__ = ["scipy_root"]


def scipy_root(
    mech: Mechanism,
    joints: Array,
    x0: Array,
    *,
    tol: float,
    maxiter: int,
    root_method: str | None = None,
    **options: Any,
) -> FKResult:
    """``scipy.optimize.root(residual, x0, jac=jacobian_pose)`` pose by pose (a Python loop).

    ``tol`` is passed to scipy as its own ``tol`` (for ``hybr``: relative error between two
    iterates) and success is then judged like every other method: residual inf-norm ``<= tol``
    with a floor of 1e-12 (hybr stops on the step, not the residual). ``maxiter`` bounds the
    function evaluations (``maxfev = 20 * maxiter``). ``nit`` reports scipy's ``nfev``
    (MINPACK counts evaluations, not iterations). ``root_method`` defaults to ``"hybr"`` for a
    square system and to ``"lm"`` (MINPACK's Levenberg-Marquardt, least squares) where the mechanism
    has more equations than unknowns (``hybr`` needs ``m == n``).
    """
    from scipy.optimize import root  # imported here: scipy.optimize costs 0.35 s of a cold CLI call

    start = time.perf_counter()
    n = len(joints)
    x = np.array(x0, dtype=float)
    nfev = np.zeros(n, dtype=np.int64)
    njev = np.zeros(n, dtype=np.int64)
    nonfinite = np.zeros(n, dtype=bool)
    square = joints.shape[-1] == x0.shape[-1]
    kind = root_method or ("hybr" if square else "lm")
    budget = {"maxfev" if kind == "hybr" else "maxiter": 20 * max(maxiter, 1)}
    for i in range(n):
        q = joints[i]
        try:
            with np.errstate(all="ignore"):
                sol = root(
                    lambda p, q=q: mech.residual(p, q),
                    x0[i],
                    jac=lambda p, q=q: mech.jacobian_pose(p, q),
                    method=kind,
                    tol=tol,
                    options={**budget, **options},
                )
        except (ValueError, ArithmeticError):  # MINPACK stepped to a pose the mechanism refused
            nonfinite[i] = True
            continue
        nonfinite[i] = not np.all(np.isfinite(sol.x))
        if not nonfinite[i]:
            x[i] = sol.x
        nfev[i] = sol.get("nfev", 0)
        njev[i] = sol.get("njev", 0)
    res = inf_norm(rowwise(mech.residual, x, joints, tail=(joints.shape[-1],)))
    ok = np.isfinite(res) & (res <= max(tol, 1e-12)) & ~nonfinite
    status = np.where(
        ok, Status.CONVERGED, np.where(nonfinite, Status.NONFINITE, Status.MAXITER)
    ).astype(np.int64)
    return FKResult(
        x=x,
        success=ok,
        status=status,
        nit=nfev.copy(),
        nfev=nfev,
        njev=njev,
        residual=res,
        wall_time=time.perf_counter() - start,
        method="scipy-root",
        message=summarize(status, maxiter),
    )
