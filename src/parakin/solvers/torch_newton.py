"""Batched Newton forward kinematics in torch: the same code on CPU or CUDA.

:func:`newton_torch` is the numpy solver :func:`parakin.solvers.newton.newton` (pure Newton,
``x <- x - J(x)^-1 r(x)``, no line search, converged where ``max |r| <= tol``) with every
iteration on a torch device. It takes and returns numpy (an :class:`FKResult` with the fields,
status codes and counters of the numpy solvers) so a benchmark can put it beside ``solve_fk``.

The residual and the analytic Jacobian are the mechanism's own kernels
(:meth:`~parakin.mechanisms.base.Mechanism.kernel`, :func:`parakin.kernels.torch_kernel`): the
very functions the numpy methods and the compiled loops run, written once beside the mechanism in
``parakin/kernels/<mechanism>.py`` and evaluated here on torch tensors (this module imports no
concrete mechanism). A mechanism without a kernel may give a torch residual of its own
(:meth:`~parakin.mechanisms.base.Mechanism.torch_residual`); its Jacobian then comes from
``torch.func`` (exact to rounding: one vjp of the batched residual vmapped over the output
directions, or ``vmap(jacrev)`` / ``vmap(jacfwd)`` per row), as it may for a kernel too
(``jacobian=``). The step comes from ``torch.linalg.solve_ex``. Kernels today: P3P4S, UPS2
(either ``branch``), Stewart36, Stewart12 and its ActiveLegs in the default
``"euler_parameters"`` convention. A mechanism with neither raises NotImplementedError.

Device behaviour: one device-to-host sync per iteration, two integers (how many rows take an LU
step and how many a pinv step: the stop test and the sizes of the gather); the rows still running
are gathered (a stable argsort of their group on the device), stepped and scattered back with
index tensors, never row by row. A row whose Jacobian is exactly singular (LU
fails) takes the minimum-norm step ``pinv(J) r`` in the next pass instead (numpy's
:func:`~parakin.solvers.newton.solve_linear` falls back for the whole batch; the step is the same).
A row whose iterate or residual becomes non-finite stops with :attr:`Status.NONFINITE` and keeps
its last finite iterate.

torch is an optional dependency (``pip install parakin[nn]``): without it this module still
imports, :func:`gpu_available` is False and the solver raises ImportError.

Why torch beside numba (:mod:`parakin.kernels`): torch runs the kernels on a GPU (the GPU column of
the solver atlas); numba's CUDA target needs a CUDA toolkit and kernels written for it. On the
CPU the compiled loops are faster (issue 17: about 2 us per Stewart36 Newton solve, 5-25 us on
the batched numpy/torch paths). The torch path is checked against the numpy methods and the
numba kernels by ``tests/test_torch_newton.py`` and ``tests/test_kernels.py``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from parakin.errors import ShapeError
from parakin.kernels import torch_kernel
from parakin.mechanisms.base import Mechanism
from parakin.solvers.result import FKResult, Status, summarize

try:  # optional dependency
    import torch
except ImportError:  # pragma: no cover - exercised only without torch
    torch = None  # type: ignore[assignment]

if TYPE_CHECKING:  # pragma: no cover
    from torch import Tensor

__all__ = ["default_device", "gpu_available", "newton_torch", "torch_jacobian", "torch_residual"]

ResidualFn = Callable[["Tensor", "Tensor"], "Tensor"]

_RUNNING = 127  # internal status of a row still iterating (as in parakin.solvers.result)


def _need_torch() -> None:
    if torch is None:
        raise ImportError("parakin.solvers.torch_newton needs torch (pip install 'parakin[nn]')")


def gpu_available() -> bool:
    """True where torch is installed and sees a CUDA device."""
    return torch is not None and bool(torch.cuda.is_available())


def default_device() -> str:
    """``"cuda"`` where a GPU is available, else ``"cpu"``."""
    return "cuda" if gpu_available() else "cpu"


# ============================================================================ residual, Jacobian
def torch_residual(mech: Mechanism) -> ResidualFn:
    """``mech.residual`` on torch tensors: ``f(pose (..., n), joints (..., m)) -> (..., m)``.

    The mechanism's kernel (:meth:`Mechanism.kernel`, run by :func:`parakin.kernels.torch_kernel`)
    where it has one, else its own :meth:`Mechanism.torch_residual`. It works in the dtype and on
    the device of ``pose`` (float64 matches numpy to rounding), is batched over any leading axes
    and composes with ``torch.func`` (vmap, jacfwd, jacrev). Raises NotImplementedError where the
    mechanism has neither (``kernel()`` returns ``None`` for a subclass of a mechanism with
    kernels: a subclass may change the kinematics).
    """
    _need_torch()
    k = mech.kernel()
    if k is not None:
        return torch_kernel(k)[0]
    fun = mech.torch_residual()
    if fun is None:
        raise NotImplementedError(
            f"no torch residual for mechanism type {type(mech).__name__} "
            "(its Mechanism.kernel() and Mechanism.torch_residual() return None)"
        )
    return fun


def torch_jacobian(mech: Mechanism) -> Callable[[Tensor, Tensor], Tensor] | None:
    """The analytic ``mech.jacobian_pose`` on torch tensors, ``(..., m, n)``, from the
    mechanism's kernel; ``None`` without one."""
    _need_torch()
    k = mech.kernel()
    return torch_kernel(k)[1] if k is not None else None


# ============================================================================ the solver
def newton_torch(
    mech: Mechanism,
    joints: ArrayLike,
    x0: ArrayLike | None,
    *,
    tol: float = 1e-10,
    maxiter: int = 50,
    device: str | Any | None = None,
    dtype: Any = None,
    jacobian: str | None = None,
) -> FKResult:
    """Newton-Raphson forward kinematics on a torch device; numpy in, numpy out.

    ``joints (..., m)`` and ``x0 (..., n)`` (``None``: ``mech.home()``) broadcast to one batch, as
    in :func:`parakin.solvers.solve_fk`; the result has that batch shape. ``device`` defaults to
    :func:`default_device`, ``dtype`` to ``torch.float64``. A row converges when the inf-norm of its
    residual is ``<= tol``; ``maxiter`` bounds the iterations (Newton steps) per row. Needs a
    square system (``m == n``) and a mechanism with a kernel or a torch residual
    (:func:`torch_residual`).

    ``jacobian`` picks the Jacobian (all exact to rounding): ``"analytic"`` (the default for a
    mechanism with a kernel) the kernel's ``jacobian``, the one ``jacobian_pose`` computes; or
    ``torch.func`` on the residual: ``"vjp"`` (the default without a kernel) one reverse pass of
    the whole batch, vmapped over the ``m`` output directions (what ``jacrev`` does per row, done
    for all rows at once: every residual computes each row from that row alone), ``"jacrev"``
    ``vmap(jacrev(residual))`` and ``"jacfwd"`` ``vmap(jacfwd(residual))`` per row.

    Counters as the numpy solvers: ``nit`` steps per row, ``nfev`` residual evaluations (one at
    ``x0``, one per finite step), ``njev`` Jacobian evaluations (one per step; a row whose LU
    failed is evaluated once more for its ``pinv`` step). ``method="newton-torch"``.
    """
    _need_torch()
    start = time.perf_counter()
    from parakin.solvers import flatten_problem

    batch, q_np, x_np = flatten_problem(mech, joints, x0, tol, maxiter)
    maxiter = int(maxiter)
    if jacobian is not None and jacobian not in ("analytic", *_JACOBIANS):
        raise ValueError(
            f"jacobian = {jacobian!r} must be one of analytic, {', '.join(_JACOBIANS)}"
        )
    fun = torch_residual(mech)
    analytic = torch_jacobian(mech)
    if jacobian is None:
        jacobian = "vjp" if analytic is None else "analytic"
    if jacobian == "analytic":
        if analytic is None:
            raise ValueError(
                f"jacobian='analytic' needs a kernel; {type(mech).__name__} has none "
                "(use 'vjp', 'jacrev' or 'jacfwd')"
            )
        jac = analytic
    else:
        jac = _JACOBIANS[jacobian](fun)
    if mech.n_pose != mech.n_joints:
        raise ShapeError(
            f"newton_torch needs as many equations as unknowns; {type(mech).__name__} has "
            f"{mech.n_joints} joints and {mech.n_pose} pose coordinates"
        )

    dev = torch.device(default_device() if device is None else device)
    dt = torch.float64 if dtype is None else dtype
    x, nit, nfev, njev, res, status = _solve(fun, jac, q_np, x_np, dev, dt, tol, maxiter)

    status = np.where(status == _RUNNING, Status.MAXITER, status).astype(np.int64)
    result = FKResult(
        x=x.astype(float),
        success=status >= 0,
        status=status,
        nit=nit,
        nfev=nfev,
        njev=njev,
        residual=res.astype(float),
        wall_time=time.perf_counter() - start,
        method="newton-torch",
        message=summarize(status, maxiter),
    )
    return result.reshape(batch)


def _solve(
    fun: ResidualFn,
    jac: Callable[[Tensor, Tensor], Tensor],
    q_np: np.ndarray,
    x_np: np.ndarray,
    dev: Any,
    dt: Any,
    tol: float,
    maxiter: int,
) -> tuple[np.ndarray, ...]:
    """The iteration on flat ``(N, m)`` / ``(N, n)`` arrays; returns numpy arrays."""
    n_rows = len(q_np)
    with torch.no_grad():
        q = torch.as_tensor(q_np, device=dev, dtype=dt)
        x = torch.as_tensor(x_np, device=dev, dtype=dt).clone()
        r = fun(x, q)
        res = _inf_norm(r)
        long = dict(device=dev, dtype=torch.long)
        nit = torch.zeros(n_rows, **long)
        nfev = torch.ones(n_rows, **long)  # the residual at x0 (as_batch made x0 finite)
        njev = torch.zeros(n_rows, **long)
        status = torch.full((n_rows,), _RUNNING, **long)
        status = torch.where(res <= tol, Status.CONVERGED, status)
        status = torch.where(torch.isfinite(res), status, Status.NONFINITE)
        if maxiter == 0:
            status = torch.where(status == _RUNNING, Status.MAXITER, status)
        needs_pinv = torch.zeros(n_rows, device=dev, dtype=torch.bool)

        while True:
            # group of each row: 0 LU step, 1 pinv step (its LU failed last pass), 2 stopped
            group = torch.where(status == _RUNNING, needs_pinv.long(), 2)
            # the one device -> host sync of the pass (two integers): the stop test and the sizes
            n_lu, n_pinv = torch.stack([(group == 0).sum(), (group == 1).sum()]).tolist()
            n_active = n_lu + n_pinv
            if n_active == 0:
                break
            if n_lu == n_rows:
                idx: Any = slice(None)  # every row runs: no gather / scatter
            else:  # running rows, LU group first, gathered on the device (sizes known: no sync)
                idx = torch.argsort(group, stable=True)[:n_active]
            xa, qa, ra = x[idx], q[idx], r[idx]

            jm = jac(xa, qa)  # (k, m, n)
            njev[idx] += 1
            dx = torch.zeros_like(xa)
            stepped = torch.ones(n_active, device=dev, dtype=torch.bool)
            if n_lu:
                j_lu, r_lu = jm[:n_lu], ra[:n_lu]
                sol, info = torch.linalg.solve_ex(j_lu, r_lu.unsqueeze(-1))
                # LU failed on a finite system: exactly singular, pinv step in the next pass.
                # A non-finite J or r gives a non-finite step: the row stops as NONFINITE.
                singular = (
                    (info != 0) & torch.isfinite(j_lu).all((-2, -1)) & torch.isfinite(r_lu).all(-1)
                )
                dx[:n_lu] = torch.where(singular[:, None], 0.0, sol[..., 0])
                stepped[:n_lu] = ~singular
            if n_active > n_lu:
                dx[n_lu:] = (torch.linalg.pinv(jm[n_lu:]) @ ra[n_lu:].unsqueeze(-1))[..., 0]
            needs_pinv[idx] = ~stepped

            x_new = xa - dx
            x_fin = torch.isfinite(x_new).all(-1)
            r_new = fun(
                torch.where(x_fin[:, None], x_new, xa), qa
            )  # never evaluate non-finite poses
            nfev[idx] += (stepped & x_fin).long()
            nit[idx] += stepped.long()
            res_new = _inf_norm(r_new)
            finite = x_fin & torch.isfinite(res_new)

            code = torch.where(res_new <= tol, Status.CONVERGED, _RUNNING)
            code = torch.where(finite, code, Status.NONFINITE)
            code = torch.where(stepped, code, _RUNNING)
            code = torch.where((code == _RUNNING) & (nit[idx] >= maxiter), Status.MAXITER, code)
            status[idx] = code
            keep = (stepped & finite)[:, None]
            x[idx] = torch.where(keep, x_new, xa)
            r[idx] = torch.where(keep, r_new, ra)
            res[idx] = torch.where(keep[:, 0], res_new, res[idx])

        out = [t.cpu().numpy() for t in (x, nit, nfev, njev, res, status)]
    return tuple(np.asarray(o, dtype=np.float64 if o.dtype.kind == "f" else np.int64) for o in out)


def _batched_vjp(fun: ResidualFn) -> Callable[[Tensor, Tensor], Tensor]:
    """``d fun / d pose`` (N, m, n) from one vjp of the batched residual, vmapped over the m
    output directions: valid because every residual computes each row from that row alone."""

    def jac(x: Tensor, q: Tensor) -> Tensor:
        _, pull = torch.func.vjp(lambda xx: fun(xx, q), x)
        m = q.shape[-1]
        basis = torch.eye(m, dtype=x.dtype, device=x.device)[:, None, :].expand(m, *q.shape)
        return torch.func.vmap(pull)(basis)[0].permute(1, 0, 2)

    return jac


#: ways to get the batched Jacobian ``(N, m, n)`` of a torch residual (``jacobian=`` option)
_JACOBIANS: dict[str, Callable[[ResidualFn], Callable[[Tensor, Tensor], Tensor]]] = {
    "jacrev": lambda fun: torch.func.vmap(torch.func.jacrev(fun, argnums=0)),
    "jacfwd": lambda fun: torch.func.vmap(torch.func.jacfwd(fun, argnums=0)),
    "vjp": _batched_vjp,
}


def _inf_norm(r: Tensor) -> Tensor:
    """Inf-norm over the last axis, NaN where any entry is NaN (as :func:`parakin.solvers.result.inf_norm`)."""
    if r.shape[-1] == 0:
        return torch.zeros(r.shape[:-1], dtype=r.dtype, device=r.device)
    return r.abs().amax(-1)
