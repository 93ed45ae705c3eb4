"""Powell's dog-leg trust region on ``|residual|^2 / 2``: Newton's method made global."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from parakin.kernels.methods import BOUNDS, DEFAULTS
from parakin.mechanisms.base import Array
from parakin.solvers.newton import newton_direction
from parakin.solvers.result import Evaluator, Plan, State, StepInfo, inf_norm, iterative

__all__ = ["dogleg"]

_EPS = np.finfo(float).eps


def _scaled_norm(d: Array, v: Array) -> Array:
    return np.sqrt(np.sum((d * v) * (d * v), axis=-1))


def _model(jac: Array, r: Array, d: Array | None) -> dict[str, Array]:
    """At new iterates: ``J``, ``g = J^T r``, the Gauss-Newton step ``pn = -J^-1 r`` and MINPACK's
    scaling ``d_i = max(d_i, |J e_i|)`` (no ``d`` yet: ``|J e_i|``, 1 where 0)."""
    cols = np.sqrt(np.sum(jac * jac, axis=-2))
    d = np.where(cols != 0.0, cols, 1.0) if d is None else np.maximum(d, cols)
    g = np.einsum("...ki,...k->...i", jac, r)
    return {"J": jac, "g": g, "pn": -newton_direction(jac, r), "d": d}


def _step(jac: Array, g: Array, pn: Array, d: Array, delta: Array) -> tuple[Array, Array]:
    """Powell's dog-leg step of every row in the scaled variables ``y = D p``, ``|y| <= delta``
    (Nocedal & Wright, sec. 4.1), and whether it ends on the boundary."""
    gs = g / d
    gs2 = np.sum(gs * gs, axis=-1)
    jv = np.einsum("...ki,...i->...k", jac, g / (d * d))
    jv2 = np.sum(jv * jv, axis=-1)
    t = np.divide(gs2, jv2, out=np.full_like(gs2, np.inf), where=jv2 > 0.0)
    gnorm = np.sqrt(gs2)
    yu = -t[:, None] * gs
    dy = d * pn - yu
    a = np.sum(dy * dy, axis=-1)
    b = np.sum(2.0 * yu * dy, axis=-1)
    c = (t * gnorm) * (t * gnorm) - delta * delta
    root = np.sqrt(b * b - 4.0 * a * c)
    tau = np.where(b >= 0.0, -2.0 * c / (b + root), (root - b) / (2.0 * a))
    leg = (yu + tau[:, None] * dy) / d
    cut = (-delta[:, None] * gs / gnorm[:, None]) / d
    newton = _scaled_norm(d, pn) <= delta
    steepest = ~newton & (t * gnorm >= delta)
    st = np.where(newton[:, None], pn, np.where(steepest[:, None], cut, leg))
    return st, ~newton


def _gain_ratio(jac: Array, r: Array, rt: Array, st: Array) -> Array:
    """Actual over predicted reduction of ``|r|^2 / 2`` (-1 where not a positive finite number)."""
    lin = r + np.einsum("...ki,...i->...k", jac, st)
    pred = np.sum(r * r - lin * lin, axis=-1)
    rho = (np.sum(r * r, axis=-1) - np.sum(rt * rt, axis=-1)) / pred
    return np.where((pred > 0.0) & np.isfinite(rho), rho, -1.0)


def _new_radius(delta: Array, rho: Array, snorm: Array, boundary: Array) -> Array:
    """Nocedal & Wright's Alg. 4.1: a quarter of the step below rho = 1/4, doubled on the boundary
    above 3/4."""
    shrunk = 0.25 * np.where(np.isfinite(snorm), snorm, delta)
    return np.where(rho < 0.25, shrunk, np.where((rho > 0.75) & boundary, 2.0 * delta, delta))


def _dogleg_init(factor: float) -> Callable[[Evaluator, NDArray[np.intp], State], State]:
    def init(ev: Evaluator, rows: NDArray[np.intp], s: State) -> State:
        model = _model(ev.jacobian(s["x"], rows), s["r"], None)
        size = _scaled_norm(model["d"], s["x"])
        return {**model, "delta": np.where(size > 0.0, factor * size, factor)}

    return init


def _dogleg_iteration(eta: float) -> Callable[..., tuple[State, StepInfo]]:
    def step(ev: Evaluator, rows: NDArray[np.intp], s: State) -> tuple[State, StepInfo]:
        """One trial step; accepted (and a new Jacobian) where the gain ratio exceeds ``eta``."""
        x, r, jac, d = s["x"], s["r"], s["J"], s["d"]
        st, boundary = _step(jac, s["g"], s["pn"], d, s["delta"])
        rt = ev.residual(x + st, rows)
        rho = _gain_ratio(jac, r, rt, st)
        delta = _new_radius(s["delta"], rho, _scaled_norm(d, st), boundary)
        new = {**s, "delta": delta}
        ok = rho > eta
        if ok.any():  # ``iterate`` hands each step its own copy of the rows' state
            x[ok], r[ok] = (x + st)[ok], rt[ok]
            model = _model(ev.jacobian(x[ok], rows[ok]), r[ok], d[ok])
            for k, v in model.items():
                new[k][ok] = v
        stalled = ~(delta > _EPS * _scaled_norm(new["d"], x))
        return new, StepInfo(step=inf_norm(st), stalled=stalled)

    return step


@iterative("dogleg")
def dogleg(
    *,
    xtol: float = DEFAULTS["xtol"],
    factor: float = DEFAULTS["factor"],
    eta: float = DEFAULTS["eta"],
) -> Plan:
    """Powell's dog-leg trust-region method on ``min |residual(x, q)|^2 / 2``, with the exact
    Jacobian at every accepted iterate.

    Powell 1970, "A hybrid method for nonlinear equations" (in Rabinowitz, Numerical Methods for
    Nonlinear Algebraic Equations); Nocedal & Wright 2006, Numerical Optimization, 2nd ed.,
    Alg. 4.1 and sec. 4.1 (the dogleg method); scaled as MINPACK's ``hybrj`` (Moré, Garbow &
    Hillstrom 1980), which ``scipy.optimize.root(method="hybr")`` calls, but with ``J``
    recomputed instead of Broyden-updated.

    The step solves the model ``min |r + J p|^2`` within ``|D p|_2 <= delta``: the Gauss-Newton
    step ``-J^-1 r`` (``pinv`` where singular, least squares for ``m > n``) where it fits, else
    the dog leg from the Cauchy point towards it, cut at the boundary. ``D`` is MINPACK's
    scaling: the largest column norms of ``J`` met so far. The step is accepted when the ratio
    ``rho`` of actual to predicted reduction exceeds ``eta``; the radius becomes a quarter of the
    step's length for ``rho < 1/4`` and doubles for ``rho > 3/4`` with the step on the boundary
    (Alg. 4.1; the quarter of the step rather than of the radius, so that a rejected Newton step
    well inside the region is not tried again). Initial radius ``factor * |D x0|`` (``factor``
    where ``x0 = 0``). A pose whose radius falls below ``eps |D x|`` stops as stalled. Near a
    regular solution every step is Newton's: quadratic convergence.

    One iteration = one trial step (one residual evaluation; one Jacobian evaluation when
    accepted, and one at ``x0``). Options: ``xtol`` (stop with success when the step inf-norm is
    ``<= xtol``; 0 = off), ``factor > 0``, ``0 <= eta < 1/4``, ``callback``.
    """
    for name, value in (("factor", factor), ("eta", eta)):
        lo, hi = BOUNDS[name]
        if not lo <= value < hi:
            raise ValueError(f"{name} = {value!r} must be in [{lo!r}, {hi!r})")
    return Plan(_dogleg_iteration(float(eta)), init=_dogleg_init(float(factor)))
