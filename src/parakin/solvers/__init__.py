"""Forward-kinematics solvers that work on any mechanism, behind one entry point.

>>> from parakin.mechanisms import P3P4S
>>> from parakin.solvers import solve_fk
>>> mech = P3P4S()
>>> res = solve_fk(mech, mech.ik([0.01, -0.02, 0.58]), method="newton")
>>> bool(res.success), res.x.round(6).tolist()
(True, [0.01, -0.02, 0.58])

Every method sees the mechanism only through ``residual(pose, joints)`` and
``jacobian_pose(pose, joints)`` (``"closed-form"`` through ``fk``), works on a whole batch at once
and returns an :class:`FKResult`. Methods live in :data:`METHODS` (:mod:`parakin.solvers.registry`);
later modules add theirs with :func:`register`. A registered method is called as
``fn(mech, joints, x0, *, tol, maxiter, **options)`` with flat 2-D ``joints (N, m)`` and
``x0 (N, n)`` and returns an :class:`FKResult` with per-pose fields of shape ``(N,)``;
:func:`solve_fk` does the validation, broadcasting, reshaping and timing around it, and decides
what a success is: the method's stopping rule *and* a valid answer (:mod:`parakin.solvers.verify`:
in the mechanism's domain, on its assembly, ``ik(x)`` within ``joint_tol`` of the joints).

Where the mechanism has compiled kernels (``mech.kernel()``), ``"newton"``, ``"lm"``,
``"broyden"``, ``"bfgs"`` and ``"dogleg"`` run as compiled loops (:mod:`parakin.kernels`: the same iterations,
counters and status codes, results equal to the numpy solvers' to rounding), in parallel over the
cores for large batches; a callback, or an option the compiled loop does not take, selects the
numpy solver.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from parakin import kernels
from parakin.errors import ShapeError
from parakin.mechanisms.base import Array, Mechanism
from parakin.solvers import compiled
from parakin.solvers.baseline import scipy_root
from parakin.solvers.closed import all_solutions, closed_form
from parakin.solvers.dogleg import dogleg
from parakin.solvers.gauss_newton import broyden_ls, gauss_newton
from parakin.solvers.hybrid import hybrid
from parakin.solvers.lm import levenberg_marquardt
from parakin.solvers.newton import newton
from parakin.solvers.pso import pso as _pso
from parakin.solvers.quasi_newton import bfgs, broyden
from parakin.solvers.registry import METHODS, Method, register
from parakin.solvers.result import FKResult, Status, summarize
from parakin.solvers.verify import default_joint_tol, verify

__all__ = [
    "MAXITER_LIMIT",
    "METHODS",
    "FKResult",
    "Method",
    "Status",
    "flatten_problem",
    "register",
    "solve_fk",
]

#: largest ``maxiter`` accepted (a bound on the work one call may ask for)
MAXITER_LIMIT = 10_000_000

register("newton")(newton)
register("broyden")(broyden)
register("bfgs")(bfgs)
register("lm")(levenberg_marquardt)
register("dogleg")(dogleg)
register("hybrid")(hybrid)
register("scipy-root")(scipy_root)
register("gauss-newton")(gauss_newton)  # least-squares Newton, m >= n (redundant drive modes)
register("broyden-ls")(broyden_ls)
register("pso")(_pso)
register("closed-form")(closed_form)
register("all-solutions")(all_solutions)

#: methods with a compiled loop (:mod:`parakin.kernels`), used for mechanisms that have kernels
_COMPILED = {
    "newton": newton,
    "lm": levenberg_marquardt,
    "broyden": broyden,
    "bfgs": bfgs,
    "dogleg": dogleg,
}


def _rows(values: ArrayLike, size: int, what: str) -> Array:
    """``values`` as a float array whose last axis has ``size`` entries (non-finite allowed)."""
    try:
        a = np.asarray(values, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{what} must be an array of numbers, got {values!r:.80}") from None
    if a.ndim == 0 or a.shape[-1] != size:
        raise ShapeError(f"{what} must have {size} values along its last axis, got shape {a.shape}")
    return a


def _check_settings(tol: float, maxiter: int, joint_tol: float | None) -> None:
    if not (isinstance(tol, (int, float, np.number)) and math.isfinite(tol) and tol >= 0):
        raise ValueError(f"tol = {tol!r} must be a finite number >= 0")
    if isinstance(maxiter, bool) or int(maxiter) != maxiter or not 0 <= maxiter <= MAXITER_LIMIT:
        raise ValueError(f"maxiter = {maxiter!r} must be an integer in [0, {MAXITER_LIMIT}]")
    if joint_tol is not None and not (np.isfinite(joint_tol) and joint_tol >= 0):
        raise ValueError(f"joint_tol = {joint_tol!r} must be a finite number >= 0")


def flatten_problem(
    mech: Mechanism, joints: ArrayLike, x0: ArrayLike | None, tol: float, maxiter: int
) -> tuple[tuple[int, ...], Array, Array]:
    """Validate an FK call and flatten it: ``(batch shape, joints (N, m), x0 (N, n))``, owned copies.

    ``x0`` defaults to ``mech.home()``; the batch is the broadcast of both batch shapes. Raises
    ValueError for a negative or non-finite ``tol``, a ``maxiter`` outside ``[0, MAXITER_LIMIT]``,
    and ShapeError for shapes that do not fit. Non-finite values are left in place (see
    :func:`solve_fk`: such a row gets :attr:`Status.BAD_INPUT`).
    """
    _check_settings(tol, maxiter, None)
    q = _rows(joints, mech.n_joints, "joints")
    x = _rows(mech.home() if x0 is None else x0, mech.n_pose, "x0")
    try:
        batch = np.broadcast_shapes(q.shape[:-1], x.shape[:-1])
    except ValueError:
        raise ShapeError(
            f"joints batch shape {q.shape[:-1]} and x0 batch shape {x.shape[:-1]} do not broadcast"
        ) from None
    flat_q = np.broadcast_to(q, (*batch, q.shape[-1])).reshape(-1, q.shape[-1]).copy()
    flat_x = np.broadcast_to(x, (*batch, x.shape[-1])).reshape(-1, x.shape[-1]).copy()
    return batch, flat_q, flat_x


def _mark_bad_rows(
    mech: Mechanism, result: FKResult, bad: NDArray[np.bool_], maxiter: int
) -> FKResult:
    """``result`` with the rows ``bad`` (non-finite joints or start) set to :attr:`Status.BAD_INPUT`,
    ``x = home``, no iterations, infinite residual and joint error."""
    fields = {
        f: getattr(result, f).copy()
        for f in ("x", "success", "status", "nit", "nfev", "njev", "residual", "joint_error")
    }
    fields["x"][bad] = mech.home()
    fields["success"][bad] = False
    fields["status"][bad] = Status.BAD_INPUT
    for f in ("nit", "nfev", "njev"):
        fields[f][bad] = 0
    fields["residual"][bad] = np.inf
    fields["joint_error"][bad] = np.inf
    return dataclasses.replace(result, **fields, message=summarize(fields["status"], maxiter))


def solve_fk(
    mech: Mechanism,
    joints: ArrayLike,
    x0: ArrayLike | None = None,
    method: str = "newton",
    tol: float = 1e-10,
    maxiter: int = 50,
    joint_tol: float | None = None,
    **options: Any,
) -> FKResult:
    """Forward kinematics: the pose(s) ``x`` with ``residual(x, joints) = 0``.

    ``joints``: ``(..., n_joints)``. ``x0``: initial guess ``(..., n_pose)``, default
    ``mech.home()``; the batch is the broadcast of both batch shapes (one joint vector from many
    starts works too). ``method``: a key of :data:`METHODS` (``"newton"``, ``"broyden"``,
    ``"bfgs"``, ``"lm"``, ``"closed-form"``, and whatever later modules register). A method stops
    a pose when the inf-norm of its residual is ``<= tol`` (the residual's units: metres for the
    3-P(4S)). ``maxiter``: iterations per pose. ``options`` go to the method, e.g. ``xtol``,
    ``gtol``, ``callback(k, x, residual_norm)`` (called with batch-shaped arrays).

    A pose is a **success** only if its method converged *and* it is a valid answer: inside the
    mechanism's domain, on the assembly the mechanism asks for (the papers' by default), and with
    ``max_k |ik(x)_k - joints_k| <= joint_tol`` (joint units; default 100 x the requested accuracy
    ``tol`` / ``xtol``, at least 1e-8). Otherwise its ``status`` says why
    (:attr:`Status.WRONG_ASSEMBLY`, :attr:`Status.OUT_OF_DOMAIN`, :attr:`Status.WRONG_ANSWER`);
    ``joint_error`` reports that error for every pose.

    Returns an :class:`FKResult` whose per-pose fields have the batch shape (0-d for a single
    joint vector). Never raises for a pose that does not converge, nor for a row with non-finite
    joints or start (:attr:`Status.BAD_INPUT`): see ``success``/``status``.
    """
    try:
        fn = METHODS[method]
    except (KeyError, TypeError):
        raise ValueError(
            f"unknown FK method {method!r}; known: {', '.join(sorted(METHODS))}"
        ) from None
    start = time.perf_counter()
    loading = kernels.load_seconds()
    _check_settings(tol, maxiter, joint_tol)
    if fn is _COMPILED.get(method) and "callback" not in options:  # one pose, compiled: one call
        one = compiled.solve_one(
            mech, method, joints, x0, tol, int(maxiter), options, joint_tol, start
        )
        if one is not None:
            _wrap(one.x, _units(mech))  # the call's own work array: wrapped in place
            if kernels.load_seconds() != loading:  # the first call: it loaded (or compiled)
                one = dataclasses.replace(one, startup=kernels.load_seconds() - loading)
            return one.bind(mech)
    batch, flat_q, flat_x = flatten_problem(mech, joints, x0, tol, maxiter)
    jtol = default_joint_tol(tol, options) if joint_tol is None else float(joint_tol)
    bad = ~(np.all(np.isfinite(flat_q), axis=-1) & np.all(np.isfinite(flat_x), axis=-1))
    if bad.any():  # solved on stand-in values (a good row's joints, the home start), then marked
        fine = np.flatnonzero(~bad)
        flat_q[bad] = flat_q[fine[0]] if fine.size else 0.0
        flat_x[bad] = mech.home()
    callback = options.get("callback")
    if callback is not None:
        options["callback"] = lambda k, xk, rk: callback(
            k, xk.reshape(*batch, xk.shape[-1]), rk.reshape(batch)
        )
    if bad.size and bad.all():
        result = _mark_bad_rows(mech, _nothing(mech, flat_q, flat_x, method), bad, int(maxiter))
    else:
        result = None
        if fn is _COMPILED.get(method):  # the built-in method, not one registered over it
            result = compiled.solve(mech, method, flat_q, flat_x, tol, int(maxiter), options)
        if result is None:  # no kernel, or a callback / option the compiled loop does not take
            result = fn(mech, flat_q, flat_x, tol=tol, maxiter=int(maxiter), **options)
        result = verify(mech, flat_q, result, jtol, int(maxiter))
        if bad.any():
            result = _mark_bad_rows(mech, result, bad, int(maxiter))
    units = _units(mech)
    x = result.x.copy() if _wrap(result.x, units, dry=True) else result.x
    _wrap(x, units)
    return dataclasses.replace(
        result.reshape(batch),
        x=x.reshape(*batch, x.shape[-1]),
        wall_time=time.perf_counter() - start,
        method=method,
        startup=kernels.load_seconds() - loading,
    ).bind(mech)  # FKResult.conditioning: computed when asked


def _units(mech: Mechanism) -> tuple[str, ...]:
    """The mechanism's pose units (none declared: nothing is an angle)."""
    return getattr(mech, "pose_units", ())


def _wrap(x: Array, units: tuple[str, ...], dry: bool = False) -> bool:
    """Wrap the angle coordinates (unit ``rad``) of the poses ``x (..., n)`` into ``(-pi, pi]`` in
    place: a solver may converge a turn or many away (the same pose; the IK is periodic), but an
    answer names the angle once. Entries already there keep their bits. Returns whether any entry
    was (``dry``: would be) outside."""
    rad = [k for k, u in enumerate(units) if u == "rad"]
    if not rad:
        return False
    if x.ndim == 1:  # the single-call path: a few Python comparisons, no array temporaries
        out = [k for k in rad if not -math.pi < x[k] <= math.pi and math.isfinite(x[k])]
        if not dry:
            for k in out:
                x[k] -= 2 * math.pi * math.ceil((x[k] - math.pi) / (2 * math.pi))
        return bool(out)
    v = x[..., rad]
    outside = np.isfinite(v) & ~((v > -math.pi) & (v <= math.pi))
    if not outside.any():
        return False
    if not dry:
        x[..., rad] = np.where(outside, v - 2 * math.pi * np.ceil((v - math.pi) / (2 * math.pi)), v)
    return True


def _nothing(mech: Mechanism, joints: Array, x0: Array, method: str) -> FKResult:
    """A result with no solve at all (every row is bad input): fields to be marked."""
    n = len(joints)
    zeros = np.zeros(n, dtype=np.int64)
    return FKResult(
        x=x0.copy(),
        success=np.zeros(n, dtype=bool),
        status=zeros.copy(),
        nit=zeros,
        nfev=zeros.copy(),
        njev=zeros.copy(),
        residual=np.full(n, np.inf),
        wall_time=0.0,
        method=method,
        message="",
        joint_error=np.full(n, np.inf),
    )
