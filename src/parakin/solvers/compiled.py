"""The compiled solve behind :func:`parakin.solvers.solve_fk`: the kernels' entries
(:mod:`parakin.kernels`) run on a flat batch or one pose and their results returned as
:class:`~parakin.solvers.result.FKResult`, verified by the same rules as every other solve
(:mod:`parakin.solvers.verify`). Kernels know nothing of solvers; this module joins the two."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from parakin.kernels import entries_of, kernel_of, methods, threads
from parakin.solvers.result import FKResult, summarize
from parakin.solvers.verify import default_joint_tol, judge_one

__all__ = ["solve", "solve_one"]


def _without_callback(options: dict[str, Any]) -> dict[str, Any] | None:
    """``options`` less a ``callback=None``; None where a callback is given (numpy path)."""
    if options.get("callback") is not None:
        return None
    return {k: v for k, v in options.items() if k != "callback"}


def solve(
    mech: Any,
    method: str,
    joints: np.ndarray,
    x0: np.ndarray,
    tol: float,
    maxiter: int,
    options: dict[str, Any],
    *,
    parallel: bool | None = None,
):
    """The compiled solve of the flat batch (``joints (N, m)``, ``x0 (N, n)``) as an
    :class:`~parakin.solvers.result.FKResult` (not yet verified), or ``None`` where the compiled
    path does not apply. ``parallel``: None = by batch size (:data:`parakin.kernels.threads.MIN_ROWS`)."""
    options = _without_callback(options)
    opts = None if options is None else methods.pack(method, tol, maxiter, options)
    kernel = None if opts is None else kernel_of(mech)
    if kernel is None:
        return None
    start = time.perf_counter()
    group = entries_of(kernel.module, method)
    n = len(joints)
    q = np.ascontiguousarray(joints, dtype=float)
    x0 = np.ascontiguousarray(x0, dtype=float)
    x = np.empty_like(x0)
    info = np.zeros((n, 4), dtype=np.int64)  # four columns: solved only (verified after)
    res = np.empty((n, 1))
    args = (kernel.params, q, x0, opts, x, info, res)
    threads.rows(group.serial, args, (1, 2, 4, 5, 6), parallel=parallel)
    status = info[:, 0].copy()
    return FKResult(
        x=x,
        success=status >= 0,
        status=status,
        nit=info[:, 1].copy(),
        nfev=info[:, 2].copy(),
        njev=info[:, 3].copy(),
        residual=res[:, 0],
        wall_time=time.perf_counter() - start,
        method=method,
        message=summarize(status, maxiter),
    )


#: (method, tol, maxiter, options) -> options vector (single-call path)
_OPTS: dict[tuple, np.ndarray] = {}
#: (kernel module, method) -> compiled solve (the batched entry, called with one row), once it
#: has loaded
_ONE: dict[tuple[Any, str], Any] = {}


def _options(method: str, tol: float, maxiter: int, options: dict[str, Any]) -> np.ndarray | None:
    try:
        key = (method, tol, maxiter, *sorted(options.items()))
        return _OPTS[key]
    except TypeError:  # an unhashable option value
        key = None
    except KeyError:
        pass
    opts = methods.pack(method, tol, maxiter, options)
    if opts is not None and key is not None and len(_OPTS) < 1000:
        _OPTS[key] = opts
    return opts


def _single(kernel: Any, method: str) -> Any:
    """The compiled entry of ``kernel`` and ``method`` (the numba function itself once it has
    loaded, which saves the loader's check on every later call)."""
    fn = _ONE.get((kernel.module, method))
    if fn is None:
        fn = entries_of(kernel.module, method).serial
        if fn.ready:
            fn = _ONE[kernel.module, method] = fn.fn
    return fn


def solve_one(
    mech: Any,
    method: str,
    joints: Any,
    x0: Any,
    tol: float,
    maxiter: int,
    options: dict[str, Any],
    joint_tol: float | None,
    start: float,
):
    """The single-call path of :func:`parakin.solvers.solve_fk`: one joint vector (1-D) from one
    start (1-D or None = home), solved and verified in one compiled call, the status then decided
    by :func:`parakin.solvers.verify.judge_one` (the rules of :func:`~parakin.solvers.verify.verify`).
    Returns the 0-d :class:`~parakin.solvers.result.FKResult` or ``None`` where this path does
    not apply (then the general path runs). ``start``: the caller's ``perf_counter`` at entry."""
    if method not in methods.COMPILED or not (isinstance(joints, (np.ndarray, list, tuple))):
        return None
    kernel = kernel_of(mech)
    if kernel is None:
        return None
    opts = _options(method, tol, maxiter, options)
    if opts is None:
        return None
    try:
        # contiguous, as the batched path's: one compiled signature for both
        q = np.ascontiguousarray(joints, dtype=float)
        x0 = kernel.home if x0 is None else np.ascontiguousarray(x0, dtype=float)
    except (TypeError, ValueError, OverflowError):
        return None
    if q.shape != (kernel.n_joints,) or x0.shape != (kernel.n_pose,):
        return None
    # one row whose info has six columns: solved and checked in the same compiled call
    x = np.empty((1, kernel.n_pose))
    info = np.zeros((1, 6), dtype=np.int64)  # status, nit, nfev, njev, in domain, on assembly
    out = np.empty((1, 2))  # residual, joint error
    _single(kernel, method)(kernel.params, q[None], x0[None], opts, x, info, out)
    x, info, out = x[0], info[0], out[0]
    if info[0] == methods.BAD_INPUT:  # joints or start not finite: the general path marks it
        return None
    jtol = default_joint_tol(tol, options) if joint_tol is None else float(joint_tol)
    status = judge_one(int(info[0]), bool(info[4]), bool(info[5]), float(out[1]), jtol)
    message = "converged" if status >= 0 else summarize(np.array([status]), maxiter)
    # 0-d views of this call's own work arrays (nothing else holds them): no copies needed
    return FKResult(
        x=x,
        success=np.array(status >= 0),
        status=np.array(status, dtype=np.int64),
        nit=info[1, ...],
        nfev=info[2, ...],
        njev=info[3, ...],
        residual=out[0, ...],
        wall_time=time.perf_counter() - start,
        method=method,
        message=message,
        joint_error=out[1, ...],
    )
