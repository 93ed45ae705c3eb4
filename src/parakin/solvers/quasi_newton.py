"""Quasi-Newton forward kinematics: Broyden's method on the residual, BFGS on its squared norm.

BFGS is the "quasi-Newton" with which Zhao et al. 2017 refine a network's guess (their stopping
rule, "iteration error eps = 1e-7", is the ``xtol`` option below).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from parakin.kernels.methods import DEFAULTS
from parakin.mechanisms.base import Array
from parakin.solvers.gauss_newton import jacobian_init, secant_step
from parakin.solvers.newton import newton_direction, solve_linear
from parakin.solvers.result import Evaluator, Plan, State, StepInfo, inf_norm, iterative

__all__ = ["BROYDEN_UPDATES", "bfgs", "bfgs_step", "broyden", "gradient_jtr"]


def _dot(a: Array, b: Array) -> Array:
    return np.einsum("...i,...i->...", a, b)


def _matvec(a: Array, b: Array) -> Array:
    return np.einsum("...ij,...j->...i", a, b)


def _outer(a: Array, b: Array) -> Array:
    return a[..., :, None] * b[..., None, :]


# ---------------------------------------------------------------------------- Broyden
#: the two forms of Broyden's rank-one secant update (``broyden(..., update=...)``)
BROYDEN_UPDATES = ("direct", "inverse")


def _pinv(a: Array) -> Array:
    """Batched Moore-Penrose pseudo-inverse (SVD); NaN for a row with a non-finite matrix."""
    out = np.full(a.shape[:-2] + (a.shape[-1], a.shape[-2]), np.nan)
    ok = np.all(np.isfinite(a), axis=(-2, -1))
    if ok.any():
        try:
            out[ok] = np.linalg.pinv(a[ok])
        except np.linalg.LinAlgError:  # SVD did not converge somewhere in the batch: row by row
            for i in np.flatnonzero(ok):
                try:
                    out[i] = np.linalg.pinv(a[i])
                except np.linalg.LinAlgError:
                    pass
    return out


def _broyden_inverse_init(ev: Evaluator, rows: NDArray[np.intp], s: State) -> State:
    return {"H": _pinv(ev.jacobian(s["x"], rows))}


def _broyden_inverse_step(
    ev: Evaluator, rows: NDArray[np.intp], s: State
) -> tuple[State, StepInfo]:
    """``x+ = x - H r``, then ``H+ = H + (d - H y) d^T H / (d^T H y)`` with ``y = r+ - r``."""
    h = s["H"]
    d = -_matvec(h, s["r"])
    x = s["x"] + d
    r = ev.residual(x, rows)
    hy = _matvec(h, r - s["r"])
    dh = np.einsum("...i,...ij->...j", d, h)  # d^T H
    den = _dot(d, hy)
    ok = np.isfinite(den) & (den != 0)  # the update's condition d^T H y != 0; else H is kept
    gain = np.where(ok, 1.0 / np.where(ok, den, 1.0), 0.0)
    h = h + _outer((d - hy) * gain[:, None], dh)
    return {"x": x, "r": r, "H": h}, StepInfo(step=inf_norm(d))


@iterative("broyden")
def broyden(*, xtol: float = DEFAULTS["xtol"], update: str = "direct") -> Plan:
    """Broyden's "good" method on ``residual(x, q) = 0``.

    Broyden 1965; Dennis & Schnabel 1996, ch. 8.

    The Jacobian approximation ``B`` starts as the analytic ``jacobian_pose`` at ``x0`` (one
    Jacobian evaluation per pose that does not start converged) and is then corrected by the
    rank-one secant update ``B += (y - B d) d^T / (d^T d)`` after each full step
    ``d = -B^-1 r``. One iteration = one step = one residual evaluation, no Jacobian.
    Superlinear near a solution, no line search. For ``m > n`` the step is the least-squares one,
    ``-pinv(B) r`` (then identical to ``"broyden-ls"``).

    ``update="inverse"``: the good update written for an approximation ``H`` of the *inverse*
    Jacobian (Broyden 1965's inverse form, obtained from the update above by Sherman-Morrison;
    not his "second", or "bad", method): ``H0 = pinv(J(x0))``, step ``d = -H r``, then
    ``H += (d - H y) d^T H / (d^T H y)`` with ``y = r+ - r`` (skipped where ``d^T H y = 0``), so
    that the secant condition ``H+ y = d`` holds. ``H`` is ``n x m``, so it also runs on
    over-determined systems (``m > n``), where it is a different algorithm from the direct update
    with least-squares steps (their iterates part after the first step). For square regular
    systems the two take the same steps to rounding. ``update="direct"`` (default) is the update
    of ``B`` described above.

    Options: ``xtol`` (stop with success when the step inf-norm is ``<= xtol``; 0 = off),
    ``update`` (``"direct"`` | ``"inverse"``), ``callback(k, x, residual_norm)``.
    """
    if update not in BROYDEN_UPDATES:
        raise ValueError(f"update = {update!r} must be one of {BROYDEN_UPDATES}")
    if update == "inverse":
        return Plan(_broyden_inverse_step, init=_broyden_inverse_init)
    return Plan(secant_step(newton_direction), init=jacobian_init)


# ---------------------------------------------------------------------------- BFGS
def _gauss_newton_inverse(jac: Array, reg: float) -> Array:
    """``(J^T J + lambda I)^-1`` with ``lambda = reg * max(diag(J^T J))`` (lambda > 0)."""
    a = np.swapaxes(jac, -1, -2) @ jac
    n = a.shape[-1]
    lam = reg * np.maximum(np.max(np.diagonal(a, axis1=-2, axis2=-1), axis=-1), 1.0e-300)
    return solve_linear(a + lam[:, None, None] * np.eye(n), np.broadcast_to(np.eye(n), a.shape))


def _bfgs_init(reg: float) -> Callable[[Evaluator, NDArray[np.intp], State], State]:
    def init(ev: Evaluator, rows: NDArray[np.intp], s: State) -> State:
        jac = ev.jacobian(s["x"], rows)
        return {
            "g": _matvec(np.swapaxes(jac, -1, -2), s["r"]),
            "H": _gauss_newton_inverse(jac, reg),
        }

    return init


def _backtrack(
    ev: Evaluator,
    rows: NDArray[np.intp],
    s: State,
    p: Array,
    slope: Array,
    c1: float,
    shrink: float,
    maxls: int,
) -> tuple[Array, Array, Array, NDArray[np.bool_]]:
    """Armijo backtracking (Nocedal & Wright 2006, Alg. 3.1), batched: ``alpha = 1, shrink, ...``
    until ``f(x + alpha p) <= f(x) + c1 alpha slope`` with ``f = |r|^2 / 2``.

    Returns the step lengths, the accepted points and residuals (unchanged where none was found)
    and the mask of poses where one was found. Each trial is one residual evaluation.
    """
    f0 = 0.5 * _dot(s["r"], s["r"])
    alpha = np.ones(len(rows))
    x, r = s["x"].copy(), s["r"].copy()
    found = np.zeros(len(rows), dtype=bool)
    todo = np.arange(len(rows))
    for _ in range(maxls):
        xt = s["x"][todo] + alpha[todo, None] * p[todo]
        rt = ev.residual(xt, rows[todo])
        ok = 0.5 * _dot(rt, rt) <= f0[todo] + c1 * alpha[todo] * slope[todo]  # NaN -> False
        x[todo[ok]], r[todo[ok]], found[todo[ok]] = xt[ok], rt[ok], True
        todo = todo[~ok]
        if todo.size == 0:
            break
        alpha[todo] *= shrink
    return alpha, x, r, found


def gradient_jtr(ev: Evaluator, x: Array, rows: NDArray[np.intp], r: Array) -> Array:
    """The gradient ``J^T r`` of ``|r|^2 / 2`` at ``x`` (one Jacobian evaluation)."""
    return _matvec(np.swapaxes(ev.jacobian(x, rows), -1, -2), r)


def bfgs_step(
    c1: float, shrink: float, maxls: int, gradient: Callable[..., Array] = gradient_jtr
) -> Callable[..., tuple[State, StepInfo]]:
    """One batched BFGS iteration (direction ``-H g``, steepest descent where that is not
    downhill, Armijo backtracking, the inverse update), the new gradient by
    ``gradient(ev, x, rows, r)`` (the library's: :func:`gradient_jtr`; the paper's variants in
    :mod:`parakin.papers.zhao2017_3p4s.bfgs_variants` also take finite differences)."""

    def step(ev: Evaluator, rows: NDArray[np.intp], s: State) -> tuple[State, StepInfo]:
        g, h = s["g"], s["H"]
        p = -_matvec(h, g)
        slope = _dot(g, p)
        uphill = ~(slope < 0)  # H lost positive definiteness to rounding: steepest descent
        p[uphill] = -g[uphill]
        slope[uphill] = -_dot(g[uphill], g[uphill])
        alpha, x, r, found = _backtrack(ev, rows, s, p, slope, c1, shrink, maxls)
        d = np.where(found[:, None], alpha[:, None] * p, 0.0)
        # gradient at the new iterate (where a step was taken)
        g_new = g.copy()
        if found.any():
            g_new[found] = gradient(ev, x[found], rows[found], r[found])
        # inverse update, N&W eq. (6.17), skipped unless y^T d > sqrt(eps) |y| |d| (curvature)
        y = g_new - g
        yd = _dot(y, d)
        size = np.linalg.norm(y, axis=-1) * np.linalg.norm(d, axis=-1)
        update = yd > np.sqrt(np.finfo(float).eps) * size
        rho = np.where(update, 1.0 / np.where(update, yd, 1.0), 0.0)
        hy = _matvec(h, y)
        h_new = (
            h
            - rho[:, None, None] * (_outer(d, hy) + _outer(hy, d))
            + (rho**2 * _dot(y, hy) + rho)[:, None, None] * _outer(d, d)
        )
        return (
            {"x": x, "r": r, "g": g_new, "H": h_new},
            StepInfo(step=inf_norm(alpha[:, None] * p), grad=inf_norm(g_new), stalled=~found),
        )

    return step


@iterative("bfgs")
def bfgs(
    *,
    xtol: float = DEFAULTS["xtol"],
    gtol: float = DEFAULTS["gtol"],
    c1: float = DEFAULTS["c1"],
    shrink: float = DEFAULTS["shrink"],
    maxls: int = int(DEFAULTS["maxls"]),
    reg: float = DEFAULTS["reg"],
) -> Plan:
    """BFGS minimising ``f(x) = |residual(x, q)|^2 / 2`` (Nocedal & Wright 2006, Alg. 6.1).

    Gradient ``g = J^T r`` from the analytic ``jacobian_pose``. Search direction ``p = -H g``,
    step length by batched Armijo backtracking (``alpha = 1, shrink, ...``, at most ``maxls``
    trials, sufficient-decrease constant ``c1``), inverse-Hessian update N&W eq. (6.17), skipped
    where the curvature ``y^T s`` is not safely positive (Dennis & Schnabel 1996, ch. 9), which
    keeps ``H`` positive definite without a Wolfe line search.

    Initial inverse Hessian: the Gauss-Newton one, ``H0 = (J0^T J0 + lambda I)^-1`` at ``x0``
    with ``lambda = reg * max diag(J0^T J0)``. The FK residual vanishes at the solution, so
    ``J^T J`` *is* the Hessian there: the first step is a Gauss-Newton (= Newton) step, the
    iteration does not depend on the units of the pose coordinates, and ``lambda`` only guards
    a singular ``J0``. (The identity would make the first step steepest descent, badly scaled
    for mixed m/rad poses.)

    One iteration = one line search (one residual evaluation per trial) plus one Jacobian
    evaluation at the accepted point. A pose whose line search finds no decrease stops as
    failed (``Status.STALLED``): at a non-zero local minimum of ``|r|^2`` (unreachable joints)
    or where ``tol`` is below the rounding floor of the residual.

    Stopping: residual inf-norm ``<= tol``; optionally step inf-norm ``<= xtol`` (Zhao 2017's
    "iteration error") or gradient inf-norm ``<= gtol`` (both off at 0). ``xtol``/``gtol``
    accept a stationary point as success, as scipy does: check ``residual`` where it matters.
    """
    return Plan(bfgs_step(c1, shrink, maxls), init=_bfgs_init(reg))
