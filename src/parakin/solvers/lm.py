"""Levenberg-Marquardt forward kinematics with Nielsen's damping update."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from parakin.kernels.methods import DEFAULTS
from parakin.mechanisms.base import Array
from parakin.solvers.newton import solve_linear
from parakin.solvers.result import Evaluator, Plan, State, StepInfo, inf_norm, iterative

__all__ = ["levenberg_marquardt"]


def _gram(jac: Array, r: Array) -> tuple[Array, Array]:
    """``J^T J`` and ``g = J^T r``."""
    jt = np.swapaxes(jac, -1, -2)
    return jt @ jac, np.einsum("...ij,...j->...i", jt, r)  # (matmul for J^T J: 2.5x einsum's speed)


def _lm_init(tau: float) -> Callable[[Evaluator, NDArray[np.intp], State], State]:
    def init(ev: Evaluator, rows: NDArray[np.intp], s: State) -> State:
        jac = ev.jacobian(s["x"], rows)
        a, g = _gram(jac, s["r"])
        mu = tau * np.max(np.diagonal(a, axis1=-2, axis2=-1), axis=-1)
        # J itself is not kept: a step needs only J^T J and J^T r (less state to copy per iteration)
        return {
            "A": a,
            "g": g,
            "mu": np.maximum(mu, np.finfo(float).tiny),
            "nu": np.full(len(rows), 2.0),
        }

    return init


def _lm_step(ev: Evaluator, rows: NDArray[np.intp], s: State) -> tuple[State, StepInfo]:
    """One trial step ``(J^T J + mu I) h = -J^T r``; accept it iff the gain ratio is positive."""
    x, r, a, g, mu, nu = s["x"], s["r"], s["A"], s["g"], s["mu"], s["nu"]
    damped = a.copy()
    diag = np.arange(a.shape[-1])
    damped[:, diag, diag] += mu[:, None]
    h = solve_linear(damped, -g)
    x_try = x + h
    r_try = ev.residual(x_try, rows)
    predicted = 0.5 * np.einsum("...i,...i->...", h, mu[:, None] * h - g)
    rho = (
        0.5 * np.einsum("...i,...i->...", r, r) - 0.5 * np.einsum("...i,...i->...", r_try, r_try)
    ) / predicted
    ok = rho > 0  # NaN (zero or non-finite step) -> rejected
    # J^T J and J^T r are kept in the state: computed once per accepted step
    if ok.all():  # the usual case near a solution: no row bookkeeping
        x, r = x_try, r_try
        a, g = _gram(ev.jacobian(x, rows), r)
    elif (
        ok.any()
    ):  # in place: ``iterate`` hands each step its own copy of the rows' state (``_take``)
        x[ok], r[ok] = x_try[ok], r_try[ok]
        a[ok], g[ok] = _gram(ev.jacobian(x[ok], rows[ok]), r[ok])
    # Nielsen (1999): shrink mu smoothly on success, grow it geometrically on failure
    mu = np.where(
        ok, mu * np.maximum(1.0 / 3.0, 1.0 - (2.0 * np.where(ok, rho, 0.0) - 1.0) ** 3), mu * nu
    )
    nu = np.where(ok, 2.0, 2.0 * nu)
    return {"x": x, "r": r, "A": a, "g": g, "mu": mu, "nu": nu}, StepInfo(
        step=inf_norm(h), grad=inf_norm(g)
    )


@iterative("lm")
def levenberg_marquardt(
    *,
    tau: float = DEFAULTS["tau"],
    xtol: float = DEFAULTS["xtol"],
    gtol: float = DEFAULTS["gtol"],
) -> Plan:
    """Levenberg-Marquardt on ``min |residual(x, q)|^2 / 2``.

    Madsen, Nielsen & Tingleff 2004, "Methods for non-linear least squares problems", Alg. 3.16.

    Step ``h`` from ``(J^T J + mu I) h = -J^T r``; it is accepted when the gain ratio
    ``rho = (F(x) - F(x + h)) / (h^T (mu h - g) / 2)`` is positive. The damping follows Nielsen
    (1999, "Damping parameter in Marquardt's method", IMM-REP-1999-05): on acceptance
    ``mu *= max(1/3, 1 - (2 rho - 1)^3)``, ``nu = 2``; on rejection ``mu *= nu``, ``nu *= 2``.
    Start: ``mu0 = tau * max diag(J0^T J0)``, default ``tau = 1e-9``: FK is a square
    zero-residual problem started near its solution, where the undamped step is Newton's, so
    the damping is kept as a safeguard only (it grows x2, x4, x8, ... after rejected steps).
    Madsen et al. suggest ``tau = 1e-6`` for a good ``x0`` and ``1e-3`` otherwise; on 50 000
    reachable 3-P(4S) poses started from home (tol 1e-12, maxiter 50) those left 37 resp. 91
    near-singular poses crawling along a curved valley of ``|r|^2``, ``tau = 1e-9`` none
    (from far random starts ~0.35 % stay unconverged with either).

    One iteration = one trial step, accepted or not: one residual evaluation, plus one
    Jacobian evaluation when accepted (and one at ``x0``). Works for ``m != n`` (least squares):
    converged still means residual inf-norm ``<= tol``.

    Options: ``tau``, ``xtol`` (stop with success when the trial step inf-norm is
    ``<= xtol``), ``gtol`` (... when ``|J^T r|_inf <= gtol``); both off at 0, and both accept
    a stationary point as success: check ``residual`` where it matters. ``callback``.
    """
    return Plan(_lm_step, init=_lm_init(tau))
