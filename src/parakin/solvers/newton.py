"""Newton-Raphson forward kinematics, and the batched linear solve the other solvers share."""

from __future__ import annotations

import numpy as np

from parakin.kernels.methods import DEFAULTS
from parakin.mechanisms.base import Array
from parakin.solvers.gauss_newton import full_step, lstsq_step
from parakin.solvers.result import Plan, iterative

__all__ = ["newton", "solve_linear", "newton_direction"]


def solve_linear(a: Array, b: Array) -> Array:
    """Solve ``a x = b`` for square ``a`` ``(k, n, n)``; ``b`` is ``(k, n)`` or ``(k, n, p)``.

    LU (``numpy.linalg.solve``) where every matrix is regular; if one of them is exactly
    singular the batch falls back to the minimum-norm least-squares solution ``pinv(a) b``,
    so one singular pose never stops the others. Rows with a non-finite ``a`` or ``b`` give NaN.
    """
    vector = b.ndim == a.ndim - 1
    rhs = b[..., None] if vector else b
    ok = np.all(np.isfinite(a), axis=(-2, -1)) & np.all(np.isfinite(rhs), axis=(-2, -1))
    if ok.all():  # the usual case: one LU over the whole batch, no masking
        try:
            out = np.linalg.solve(a, rhs)
            return out[..., 0] if vector else out
        except np.linalg.LinAlgError:
            pass
    out = np.full(rhs.shape, np.nan)
    if ok.any():
        try:
            out[ok] = np.linalg.solve(a[ok], rhs[ok])
        except np.linalg.LinAlgError:
            out[ok] = np.linalg.pinv(a[ok]) @ rhs[ok]
    return out[..., 0] if vector else out


def newton_direction(a: Array, r: Array) -> Array:
    """``a^-1 r`` for square ``a`` (:func:`solve_linear`), the least-squares ``pinv(a) r`` for
    ``m > n`` rows (:func:`~parakin.solvers.gauss_newton.lstsq_step`: e.g. the 12 legs of the cube
    mechanism, or a redundant drive mode's padded compatibility equations)."""
    return solve_linear(a, r) if a.shape[-1] == a.shape[-2] else lstsq_step(a, r)


@iterative("newton")
def newton(*, xtol: float = DEFAULTS["xtol"]) -> Plan:
    """Newton-Raphson on ``residual(x, q) = 0`` (Dennis & Schnabel 1996, ch. 5, Alg. 5.1.1).

    One iteration is one full step ``x <- x - J^-1 r`` with ``J = jacobian_pose`` evaluated at
    the current iterate (one Jacobian and one residual evaluation); no line search, so the
    convergence is quadratic near a regular solution and the basin is that of pure Newton.
    A singular ``J`` falls back to the least-squares step ``pinv(J) r`` (see
    :func:`solve_linear`); a pose that diverges stops as non-finite. For ``m > n`` the step is
    the least-squares (Gauss-Newton) one, ``pinv(J) r``.

    Options: ``xtol`` (stop with success when the step inf-norm is ``<= xtol``; 0 = off),
    ``callback(k, x, residual_norm)`` after every iteration.
    """
    return Plan(full_step(newton_direction))
