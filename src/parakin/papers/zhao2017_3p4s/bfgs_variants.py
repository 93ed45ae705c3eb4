"""Which BFGS: the variants behind conclusion (1)'s "quasi-Newton", an experiment set-up of this paper.

The paper's "quasi-Newton method" is not specified (docs/zhao2017_3p4s.md#g7). The library's BFGS
(:func:`parakin.solvers.quasi_newton.bfgs`) starts from the Gauss-Newton inverse Hessian
``(J0^T J0 + lambda I)^-1`` with the analytic gradient ``J^T r``, so its first step is a Newton step.
The textbook BFGS (Nocedal & Wright 2006, Alg. 6.1) starts from the identity, and a library BFGS
given no gradient (``scipy.optimize.minimize(method="BFGS")``, MATLAB's ``fminunc``) also
differentiates numerically. :func:`bfgs_variant` runs those variants batched, with the library's
line search (Armijo backtracking), inverse update (N&W eq. 6.17, skipped where the curvature is
not safely positive), stopping rule and answer check, so that the start and the gradient are the
only differences; ``extra_qn_failures`` shows how often each fails from the home pose.

Declared before the runs (issue 45): the identity start is ``H0 = I`` unscaled (as scipy does); the
numerical gradient is the central difference of ``f = |r|^2 / 2`` with step ``eps^(1/3) max(1, |x_i|)``
(scipy's ``"3-point"`` rule), one residual evaluation per side and coordinate. The forward difference
(scipy's default ``"2-point"``, step ``sqrt(eps) max(1, |x_i|)``) is there to show its accuracy
floor: its error of order the step (~1e-8 m here) stalls the iteration about as far from the pose as
the success criterion allows, which is not a dependence on the start.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from parakin.kernels.methods import DEFAULTS
from parakin.mechanisms.base import Array, Mechanism
from parakin.solvers.quasi_newton import bfgs_step, gradient_jtr
from parakin.solvers.result import Evaluator, FKResult, iterate
from parakin.solvers.verify import default_joint_tol, verify

__all__ = ["FD_STEP", "GRADIENTS", "STARTS", "bfgs_variant", "numerical_gradient"]

#: the initial inverse Hessian: the library's Gauss-Newton one, or the textbook identity
STARTS = ("gauss-newton", "identity")
#: the gradient of |r|^2 / 2: analytic (J^T r), central or forward differences
GRADIENTS = ("analytic", "central", "forward")

#: relative step of the differences: scipy's "3-point" (cube root of the float epsilon) for the
#: central ones, its "2-point" (square root) for the forward ones
FD_STEP = {
    "central": float(np.finfo(float).eps) ** (1.0 / 3.0),
    "forward": float(np.finfo(float).eps) ** 0.5,
}


def _dot(a: Array, b: Array) -> Array:
    return np.einsum("...i,...i->...", a, b)


def numerical_gradient(
    ev: Evaluator, x: Array, rows: NDArray[np.intp], r: Array, kind: str = "central"
) -> Array:
    """Finite differences of ``f = |r|^2 / 2`` at ``x`` (``(len(rows), n)``, ``r`` its residual),
    step :data:`FD_STEP` ``[kind] * max(1, |x_i|)`` per coordinate: central (2 n residual
    evaluations per pose) or forward (n)."""
    g = np.empty_like(x)
    h = FD_STEP[kind] * np.maximum(1.0, np.abs(x))
    f0 = _dot(r, r)
    for i in range(x.shape[-1]):
        up = x.copy()
        up[:, i] += h[:, i]
        ru = ev.residual(up, rows)
        if kind == "forward":
            g[:, i] = (_dot(ru, ru) - f0) / (2.0 * h[:, i])
            continue
        down = x.copy()
        down[:, i] -= h[:, i]
        rd = ev.residual(down, rows)
        g[:, i] = (_dot(ru, ru) - _dot(rd, rd)) / (4.0 * h[:, i])
    return g


def _gradient(gradient: str):
    if gradient == "analytic":
        return gradient_jtr
    return lambda ev, x, rows, r: numerical_gradient(ev, x, rows, r, gradient)


def _init(start: str, grad, reg: float):
    def init(ev: Evaluator, rows: NDArray[np.intp], s: dict) -> dict:
        n = s["x"].shape[-1]
        if start == "identity":
            h = np.broadcast_to(np.eye(n), (len(rows), n, n)).copy()
        else:  # the library's: (J0^T J0 + lambda I)^-1, lambda = reg * max diag
            jac = ev.jacobian(s["x"], rows)
            a = np.swapaxes(jac, -1, -2) @ jac
            lam = reg * np.maximum(np.max(np.diagonal(a, axis1=-2, axis2=-1), axis=-1), 1e-300)
            h = np.linalg.inv(a + lam[:, None, None] * np.eye(n))
        return {"g": grad(ev, s["x"], rows, s["r"]), "H": h}

    return init


def bfgs_variant(
    mech: Mechanism,
    joints: Array,
    x0: Array,
    *,
    start: str,
    gradient: str,
    tol: float,
    maxiter: int,
) -> FKResult:
    """BFGS on ``|r|^2 / 2`` from ``x0`` with the initial inverse Hessian ``start`` (one of
    :data:`STARTS`) and the ``gradient`` (one of :data:`GRADIENTS`); everything else as the
    library's BFGS (its defaults for the line search and the regularisation, stop at residual
    inf-norm ``<= tol``, the answer checked as :func:`parakin.solvers.solve_fk` checks it).
    ``joints (N, m)``; ``x0`` one pose or ``(N, n)``. Returns a flat :class:`FKResult`."""
    if start not in STARTS or gradient not in GRADIENTS:
        raise ValueError(f"start {start!r} / gradient {gradient!r}: one of {STARTS} / {GRADIENTS}")
    q = np.atleast_2d(np.asarray(joints, dtype=float))
    x = np.array(
        np.broadcast_to(np.asarray(x0, dtype=float), (len(q), np.asarray(mech.home()).shape[-1]))
    )
    grad = _gradient(gradient)
    res = iterate(
        mech,
        q,
        x,
        step=bfgs_step(DEFAULTS["c1"], DEFAULTS["shrink"], int(DEFAULTS["maxls"]), gradient=grad),
        init=_init(start, grad, DEFAULTS["reg"]),
        tol=tol,
        maxiter=maxiter,
        method=f"bfgs ({start} start, {gradient} gradient)",
    )
    return verify(mech, q, res, default_joint_tol(tol, {}), maxiter)
