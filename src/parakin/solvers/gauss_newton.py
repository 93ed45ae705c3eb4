"""Least-squares Newton (Gauss-Newton) and least-squares Broyden for ``m >= n`` residuals.

``newton`` and ``broyden`` need a square Jacobian; these two take the minimum-norm least-squares
step ``dx = -pinv(J) r`` instead, so that they also solve over-determined systems (e.g. the
compatibility equations of a redundantly driven mechanism: 6 equations, fewer unknowns). On a
square regular system they take exactly the steps of ``newton`` / ``broyden``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from parakin.mechanisms.base import Array
from parakin.solvers.result import Evaluator, Plan, State, Step, StepInfo, inf_norm, iterative

__all__ = ["gauss_newton", "broyden_ls", "lstsq_step", "full_step", "jacobian_init", "secant_step"]


def lstsq_step(a: Array, r: Array) -> Array:
    """Least-squares ``x`` with ``a x ~ r`` per row (``a (k, m, n)``, ``r (k, m)``, ``m >= n``).

    Square ``a``: LU solve. ``m > n``: the normal equations ``a^T a x = a^T r`` (LU; accurate
    while cond(a) << 1e8, which the kinematic systems here satisfy). Where a matrix is singular
    the batch falls back to ``pinv(a) r`` (SVD). NaN rows where ``a`` or ``r`` is not finite.
    """
    out = np.full(a.shape[:-2] + (a.shape[-1],), np.nan)
    ok = np.all(np.isfinite(a), axis=(-2, -1)) & np.all(np.isfinite(r), axis=-1)
    if not ok.any():
        return out
    aa, rr = a[ok], r[ok]
    try:
        if aa.shape[-2] == aa.shape[-1]:
            out[ok] = np.linalg.solve(aa, rr[..., None])[..., 0]
        else:
            at = np.swapaxes(aa, -1, -2)
            out[ok] = np.linalg.solve(at @ aa, np.einsum("...ij,...j->...i", at, rr)[..., None])[
                ..., 0
            ]
    except np.linalg.LinAlgError:
        try:
            out[ok] = np.einsum("...ij,...j->...i", np.linalg.pinv(aa), rr)
        except np.linalg.LinAlgError:  # SVD did not converge somewhere: row by row
            for i, row in zip(np.flatnonzero(ok), range(len(aa))):
                try:
                    out[i] = np.linalg.pinv(aa[row]) @ rr[row]
                except np.linalg.LinAlgError:
                    pass
    return out


def full_step(direction: Callable[[Array, Array], Array]) -> Step:
    """The step ``x <- x - direction(J(x), r)`` (one Jacobian and one residual evaluation): Newton's
    with :func:`~parakin.solvers.newton.newton_direction`, Gauss-Newton's with :func:`lstsq_step`."""

    def step(ev: Evaluator, rows: NDArray[np.intp], s: State) -> tuple[State, StepInfo]:
        dx = direction(ev.jacobian(s["x"], rows), s["r"])
        x = s["x"] - dx
        return {"x": x, "r": ev.residual(x, rows)}, StepInfo(step=inf_norm(dx))

    return step


@iterative("gauss-newton")
def gauss_newton(*, xtol: float = 0.0) -> Plan:
    """Gauss-Newton: ``x <- x - pinv(J) r`` (full step, no line search; Dennis & Schnabel 1996,
    §10.2). One Jacobian and one residual evaluation per iteration; ``m >= n`` allowed. Options
    ``xtol`` (step inf-norm stop, 0 = off) and ``callback`` as for ``newton``."""
    return Plan(full_step(lstsq_step))


def jacobian_init(ev: Evaluator, rows: NDArray[np.intp], s: State) -> State:
    """The secant methods' start: ``B`` = the analytic Jacobian at ``x0``."""
    return {"B": ev.jacobian(s["x"], rows)}


def secant_step(direction: Callable[[Array, Array], Array]) -> Step:
    """``x+ = x + d`` with ``d = -direction(B, r)``, then Broyden's good update
    ``B+ = B + (y - B d) d^T / d^T d`` with ``y = r+ - r`` (one residual evaluation): ``broyden``'s
    with :func:`~parakin.solvers.newton.newton_direction`, ``broyden_ls``'s with
    :func:`lstsq_step`."""

    def step(ev: Evaluator, rows: NDArray[np.intp], s: State) -> tuple[State, StepInfo]:
        d = -direction(s["B"], s["r"])
        x = s["x"] + d
        r = ev.residual(x, rows)
        dd = np.einsum("...i,...i->...", d, d)
        gain = np.where(dd > 0, 1.0 / np.where(dd > 0, dd, 1.0), 0.0)  # no update for a zero step
        y = r - s["r"] - np.einsum("...ij,...j->...i", s["B"], d)
        b = s["B"] + (y * gain[:, None])[:, :, None] * d[:, None, :]
        return {"x": x, "r": r, "B": b}, StepInfo(step=inf_norm(d))

    return step


@iterative("broyden-ls")
def broyden_ls(*, xtol: float = 0.0) -> Plan:
    """Broyden's good rank-one secant update of a rectangular ``B`` (``m x n``; Broyden 1965),
    started at the analytic Jacobian at ``x0``, with the least-squares step ``d = -pinv(B) r``.
    One residual evaluation per iteration; for square regular ``B`` identical to ``broyden``."""
    return Plan(secant_step(lstsq_step), init=jacobian_init)
