"""FK methods that call the mechanism's own closed form: ``"closed-form"`` (``fk``) and
``"all-solutions"`` (``fk_all``, then the solution nearest the start)."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from parakin.mechanisms.base import Array, Mechanism
from parakin.solvers.registry import METHODS
from parakin.solvers.result import ROW_ERRORS, FKResult, Status, inf_norm, rowwise, summarize

__all__ = ["all_solutions", "closed_form"]


def _result(
    mech: Mechanism, joints: Array, x: Array, ok: Array, tol: float, start: float, method: str
) -> FKResult:
    """Success where the closed form gave a pose (``ok``) whose residual inf-norm is ``<= tol``."""
    with np.errstate(all="ignore"):
        res = rowwise(mech.residual, x, joints, tail=(joints.shape[-1],))
    res = inf_norm(res)
    status = np.where(ok & (res <= tol), Status.CONVERGED, Status.NO_SOLUTION).astype(np.int64)
    zeros = np.zeros(len(joints), dtype=np.int64)
    return FKResult(
        x=x,
        success=status >= 0,
        status=status,
        nit=zeros,
        nfev=zeros.copy(),
        njev=zeros.copy(),
        residual=res,
        wall_time=time.perf_counter() - start,
        method=method,
        message=summarize(status),
    )


def _others(name: str) -> str:
    return ", ".join(sorted(set(METHODS) - {name}))


def closed_form(
    mech: Mechanism, joints: Array, x0: Array, *, tol: float, maxiter: int = 0, **options: Any
) -> FKResult:
    """The mechanism's own closed-form ``fk`` (``options`` are passed to it, e.g. ``branch``).

    ``nit = nfev = njev = 0``; ``success`` where ``fk`` has a solution whose residual inf-norm
    is ``<= tol``; elsewhere (``fk`` raises for that row, or gives no finite pose) ``x = x0`` and
    ``Status.NO_SOLUTION``. A row for which ``fk`` raises never costs the others (the batch is
    bisected around it). ``x0`` and ``maxiter`` are otherwise unused.
    """
    if getattr(mech, "fk", None) is None:
        raise ValueError(
            f"{type(mech).__name__} has no closed-form fk; use one of {_others('closed-form')}"
        )
    start = time.perf_counter()
    x = rowwise(lambda q: mech.fk(q, **options), joints, tail=(mech.n_pose,))
    ok = np.all(np.isfinite(x), axis=-1)
    return _result(mech, joints, np.where(ok[:, None], x, x0), ok, tol, start, "closed-form")


def _fk_all(mech: Mechanism, joints: Array, options: dict[str, Any]) -> Array:
    """``fk_all`` as ``(N, k, n)``; rows for which it raises get no solution (all NaN)."""
    n, n_pose = len(joints), mech.n_pose
    try:
        with np.errstate(all="ignore"):
            return np.asarray(mech.fk_all(joints, **options), dtype=float).reshape(n, -1, n_pose)
    except ROW_ERRORS:
        rows = []
        for q in joints:  # rare path: isolate the rows that raise
            try:
                with np.errstate(all="ignore"):
                    rows.append(
                        np.asarray(mech.fk_all(q[None], **options), dtype=float).reshape(-1, n_pose)
                    )
            except ROW_ERRORS:
                rows.append(np.full((1, n_pose), np.nan))
        k = max(len(r) for r in rows)
        return np.stack([np.concatenate([r, np.full((k - len(r), n_pose), np.nan)]) for r in rows])


def _on_assembly(mech: Mechanism, sols: Array, joints: Array) -> Array:
    """``mech.on_assembly`` of every finite solution ``(N, k, n)`` (False for the NaN padding)."""
    fin = np.all(np.isfinite(sols), axis=-1)
    out = np.zeros(fin.shape, dtype=bool)
    if fin.any():
        q = np.broadcast_to(joints[:, None, :], (*sols.shape[:2], joints.shape[-1]))
        out[fin] = rowwise(mech.on_assembly, sols[fin], q[fin], tail=(), fill=0.0) > 0.5
    return out


def all_solutions(
    mech: Mechanism, joints: Array, x0: Array, *, tol: float, maxiter: int = 0, **options: Any
) -> FKResult:
    """Every real solution from the mechanism's ``fk_all`` (``(N, k, n)``, NaN-padded), then the one
    nearest ``x0``: what a controller that knows its last pose does with an all-solutions FK.

    Only solutions on the assembly the mechanism asks for (``mech.on_assembly``: above the base
    for the 3-6 Stewart, ``|beta|, |gamma| < 90 deg`` for the 2-UPS) are candidates. Distances are
    taken per coordinate in units of the ``pose_bounds()`` box width, angle coordinates (unit
    ``rad``) modulo 2 pi. ``success`` where a solution exists whose residual
    inf-norm is ``<= tol``; elsewhere ``x = x0`` and ``Status.NO_SOLUTION``. ``options`` go to
    ``fk_all``; ``maxiter`` is unused (``nit = nfev = njev = 0``).
    """
    if not hasattr(mech, "fk_all"):
        raise ValueError(
            f"{type(mech).__name__} has no all-solutions fk_all; use one of {_others('all-solutions')}"
        )
    start = time.perf_counter()
    n = len(joints)
    sols = _fk_all(mech, joints, options)
    lo, hi = mech.pose_bounds()
    with np.errstate(all="ignore"):
        d = mech.pose_difference(sols, x0[:, None, :])
        dist = np.sqrt(np.sum((d / (np.asarray(hi) - np.asarray(lo))) ** 2, axis=-1))
    dist = np.where(np.isfinite(dist) & _on_assembly(mech, sols, joints), dist, np.inf)
    best = np.argmin(dist, axis=-1) if sols.shape[1] else np.zeros(n, dtype=np.intp)
    ok = np.isfinite(dist[np.arange(n), best]) if sols.shape[1] else np.zeros(n, dtype=bool)
    x = np.where(ok[:, None], sols[np.arange(n), best], x0) if sols.shape[1] else x0.copy()
    return _result(mech, joints, x, ok, tol, start, "all-solutions")
