"""Forward-kinematics solvers that work on any mechanism, behind one entry point.

>>> from parakin.mechanisms import P3P4S
>>> from parakin.solvers import solve_fk
>>> mech = P3P4S()
>>> res = solve_fk(mech, mech.ik([0.01, -0.02, 0.58]), method="newton")
>>> bool(res.success), res.x.round(6).tolist()
(True, [0.01, -0.02, 0.58])

Every method sees the mechanism only through ``residual(pose, joints)`` and
``jacobian_pose(pose, joints)`` (``"closed-form"`` through ``fk``), works on a whole batch at once
and returns an :class:`FKResult`. Methods live in :data:`METHODS`; later modules add theirs with
:func:`register`. A registered method is called as
``fn(mech, joints, x0, *, tol, maxiter, **options)`` with flat 2-D ``joints (N, m)`` and
``x0 (N, n)`` and returns an :class:`FKResult` with per-pose fields of shape ``(N,)``;
:func:`solve_fk` does the validation, broadcasting, reshaping and timing around it.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from parakin.errors import ParakinError, ShapeError
from parakin.mechanisms.base import Array, Mechanism, as_batch
from parakin.solvers.lm import levenberg_marquardt
from parakin.solvers.baseline import scipy_root
from parakin.solvers.gauss_newton import broyden_ls, gauss_newton
from parakin.solvers.hybrid import hybrid
from parakin.solvers.newton import newton
from parakin.solvers.quasi_newton import bfgs, broyden
from parakin.solvers.result import FKResult, Status, inf_norm, summarize

__all__ = ["METHODS", "FKResult", "Status", "flatten_problem", "register", "solve_fk"]

Method = Callable[..., FKResult]

#: method name -> solver; extend with :func:`register`.
METHODS: dict[str, Method] = {}


def register(name: str, *, override: bool = False) -> Callable[[Method], Method]:
    """Decorator adding a solver to :data:`METHODS` under ``name`` (see the module docstring).

    Registering a different function under a taken name raises ValueError unless ``override``.
    """

    def add(fn: Method) -> Method:
        if not override and METHODS.get(name, fn) is not fn:
            raise ValueError(
                f"FK method {name!r} is already registered ({METHODS[name].__module__})"
            )
        METHODS[name] = fn
        return fn

    return add


register("newton")(newton)
register("broyden")(broyden)
register("bfgs")(bfgs)
register("lm")(levenberg_marquardt)
register("hybrid")(hybrid)
register("scipy-root")(scipy_root)
register("gauss-newton")(gauss_newton)  # least-squares Newton, m >= n (redundant drive modes)
register("broyden-ls")(broyden_ls)

from parakin.solvers.pso import pso as _pso  # noqa: E402  (pso.py imports register from here)

register("pso")(_pso)


def _fk_by_halves(
    fk: Callable[[Array], Array], joints: Array, n_pose: int
) -> tuple[Array, NDArray[np.bool_]]:
    """``fk`` on the whole batch; where it raises, bisect the batch to isolate the bad rows.

    One vectorised call when every row is fine, ``O(k log N)`` calls for ``k`` bad rows.
    Returns the poses (NaN where there is none) and the mask of rows that have one.
    """
    if len(joints) == 0:
        return np.zeros((0, n_pose)), np.zeros(0, dtype=bool)
    try:
        with np.errstate(all="ignore"):
            x = np.asarray(fk(joints), dtype=float)
        return x, np.all(np.isfinite(x), axis=-1)
    except ParakinError:
        if len(joints) == 1:
            return np.full((1, n_pose), np.nan), np.zeros(1, dtype=bool)
        half = len(joints) // 2
        (xa, oka), (xb, okb) = (
            _fk_by_halves(fk, part, n_pose) for part in np.split(joints, [half])
        )
        return np.concatenate([xa, xb]), np.concatenate([oka, okb])


@register("closed-form")
def closed_form(
    mech: Mechanism, joints: Array, x0: Array, *, tol: float, maxiter: int = 0, **options: Any
) -> FKResult:
    """The mechanism's own closed-form ``fk`` (``options`` are passed to it, e.g. ``branch``).

    ``nit = nfev = njev = 0``; ``success`` where ``fk`` has a solution whose residual inf-norm
    is ``<= tol``; elsewhere ``x = x0`` and ``Status.NO_SOLUTION``. ``x0`` and ``maxiter`` are
    otherwise unused.
    """
    if getattr(mech, "fk", None) is None:
        raise ValueError(
            f"{type(mech).__name__} has no closed-form fk; use one of "
            f"{', '.join(sorted(set(METHODS) - {'closed-form'}))}"
        )
    start = time.perf_counter()
    n = len(joints)
    x, ok = _fk_by_halves(lambda q: mech.fk(q, **options), joints, mech.n_pose)
    x = np.where(ok[:, None], x, x0)
    with np.errstate(all="ignore"):
        res = inf_norm(mech.residual(x, joints))
    status = np.where(ok & (res <= tol), Status.CONVERGED, Status.NO_SOLUTION).astype(np.int64)
    zeros = np.zeros(n, dtype=np.int64)
    return FKResult(
        x=x,
        success=status >= 0,
        status=status,
        nit=zeros,
        nfev=zeros.copy(),
        njev=zeros.copy(),
        residual=res,
        wall_time=time.perf_counter() - start,
        method="closed-form",
        message=summarize(status),
    )


@register("all-solutions")
def all_solutions(
    mech: Mechanism, joints: Array, x0: Array, *, tol: float, maxiter: int = 0, **options: Any
) -> FKResult:
    """Every real solution from the mechanism's ``fk_all`` (``(N, k, n)``, NaN-padded), then the one
    nearest ``x0``: what a controller that knows its last pose does with an all-solutions FK.

    Distances are taken per coordinate in units of the ``pose_bounds()`` box width, angle
    coordinates (unit ``rad``) modulo 2 pi. ``success`` where a solution exists whose residual
    inf-norm is ``<= tol``; elsewhere ``x = x0`` and ``Status.NO_SOLUTION``. ``options`` go to
    ``fk_all``; ``maxiter`` is unused (``nit = nfev = njev = 0``).
    """
    if not hasattr(mech, "fk_all"):
        raise ValueError(f"{type(mech).__name__} has no all-solutions fk_all; use one of "
                         f"{', '.join(sorted(set(METHODS) - {'all-solutions'}))}")
    start = time.perf_counter()
    n = len(joints)
    with np.errstate(all="ignore"):
        sols = np.asarray(mech.fk_all(joints, **options), dtype=float).reshape(n, -1, mech.n_pose)
        lo, hi = mech.pose_bounds()
        d = mech.pose_difference(sols, x0[:, None, :])
        dist = np.sqrt(np.sum((d / (np.asarray(hi) - np.asarray(lo))) ** 2, axis=-1))
    dist = np.where(np.isfinite(dist), dist, np.inf)
    best = np.argmin(dist, axis=-1)
    ok = np.isfinite(dist[np.arange(n), best])
    x = np.where(ok[:, None], sols[np.arange(n), best], x0)
    with np.errstate(all="ignore"):
        res = inf_norm(mech.residual(x, joints))
    status = np.where(ok & (res <= tol), Status.CONVERGED, Status.NO_SOLUTION).astype(np.int64)
    zeros = np.zeros(n, dtype=np.int64)
    return FKResult(x=x, success=status >= 0, status=status, nit=zeros, nfev=zeros.copy(), njev=zeros.copy(),
                    residual=res, wall_time=time.perf_counter() - start, method="all-solutions",
                    message=summarize(status))


def flatten_problem(
    mech: Mechanism, joints: ArrayLike, x0: ArrayLike | None, tol: float, maxiter: int
) -> tuple[tuple[int, ...], Array, Array]:
    """Validate an FK call and flatten it: ``(batch shape, joints (N, m), x0 (N, n))``, owned copies.

    ``x0`` defaults to ``mech.home()``; the batch is the broadcast of both batch shapes. Raises
    ValueError for a negative ``tol`` or ``maxiter`` and ShapeError for shapes that do not fit.
    """
    if not tol >= 0:
        raise ValueError(f"tol = {tol!r} must be >= 0")
    if int(maxiter) != maxiter or maxiter < 0:
        raise ValueError(f"maxiter = {maxiter!r} must be a non-negative integer")
    q = as_batch(joints, mech.n_joints, "joints")
    x = as_batch(mech.home() if x0 is None else x0, mech.n_pose, "x0")
    try:
        batch = np.broadcast_shapes(q.shape[:-1], x.shape[:-1])
    except ValueError:
        raise ShapeError(
            f"joints batch shape {q.shape[:-1]} and x0 batch shape {x.shape[:-1]} do not broadcast"
        ) from None
    flat_q = np.broadcast_to(q, (*batch, q.shape[-1])).reshape(-1, q.shape[-1]).copy()
    flat_x = np.broadcast_to(x, (*batch, x.shape[-1])).reshape(-1, x.shape[-1]).copy()
    return batch, flat_q, flat_x


def solve_fk(
    mech: Mechanism,
    joints: ArrayLike,
    x0: ArrayLike | None = None,
    method: str = "newton",
    tol: float = 1e-10,
    maxiter: int = 50,
    **options: Any,
) -> FKResult:
    """Forward kinematics: the pose(s) ``x`` with ``residual(x, joints) = 0``.

    ``joints``: ``(..., n_joints)``. ``x0``: initial guess ``(..., n_pose)``, default
    ``mech.home()``; the batch is the broadcast of both batch shapes (one joint vector from many
    starts works too). ``method``: a key of :data:`METHODS` (``"newton"``, ``"broyden"``,
    ``"bfgs"``, ``"lm"``, ``"closed-form"``, and whatever later modules register). A pose has
    converged when the inf-norm of its residual is ``<= tol`` (the residual's units: metres for
    the 3-P(4S)). ``maxiter``: iterations per pose. ``options`` go to the method, e.g.
    ``xtol``, ``gtol``, ``callback(k, x, residual_norm)`` (called with batch-shaped arrays).

    Returns an :class:`FKResult` whose per-pose fields have the batch shape (0-d for a single
    joint vector). Never raises for a pose that does not converge: see ``success``/``status``.
    """
    try:
        fn = METHODS[method]
    except KeyError:
        raise ValueError(
            f"unknown FK method {method!r}; known: {', '.join(sorted(METHODS))}"
        ) from None
    start = time.perf_counter()
    batch, flat_q, flat_x = flatten_problem(mech, joints, x0, tol, maxiter)
    callback = options.get("callback")
    if callback is not None:
        options["callback"] = lambda k, xk, rk: callback(
            k, xk.reshape(*batch, xk.shape[-1]), rk.reshape(batch)
        )
    result = fn(mech, flat_q, flat_x, tol=tol, maxiter=int(maxiter), **options)
    return dataclasses.replace(
        result.reshape(batch), wall_time=time.perf_counter() - start, method=method
    )
