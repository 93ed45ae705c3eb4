"""Compiled path tracker of the 6-6 general parameter homotopy: a geometry's own start system.

:func:`parakin.mechanisms.stewart66_homotopy.track` on a
:class:`~parakin.mechanisms.stewart66_homotopy.GeneralHomotopy`, path by path in compiled code: the
same predictor (cubic Hermite through the last two points and their tangents, Euler on the first
step), the same corrector (three chord-Newton updates with the Jacobian at the predicted point,
accepted when they contract), the same step-size rule and the same failure tests, so that it
follows the same paths; its arithmetic differs from numpy's only in rounding. Each path costs a few
microseconds per step here, against tens in the batched numpy tracker, whose per-step overhead
does not shrink for the 40 paths of one geometry (:attr:`parakin.mechanisms.Stewart66.fk_start`).

``H(x, t) = (x^T Q_m(t) x, a . x - 1)`` with ``Q_m(t) = Q0_m + t Q1_m + t^2 Q2_m`` (m = 0..6),
``Q(t)`` formed once per step.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["track"]

_O = dict(cache=True, error_model="numpy", nogil=True)


@njit(**_O)
def _quadrics_at(q0, q1, q2, t, out):
    """``out = Q0 + t Q1 + t^2 Q2`` (7, 8, 8)."""
    tt = t * t
    for m in range(7):
        for i in range(8):
            for j in range(8):
                out[m, i, j] = q0[m, i, j] + t * q1[m, i, j] + tt * q2[m, i, j]


@njit(**_O)
def _residual(q, patch, x, out):
    """``H`` at ``x`` for the quadrics ``q`` (7, 8, 8): ``out[m] = x^T q_m x``, ``out[7] = a.x - 1``."""
    for m in range(7):
        s = 0j
        for i in range(8):
            y = 0j
            for j in range(8):
                y += q[m, i, j] * x[j]
            s += y * x[i]
        out[m] = s
    s = 0j
    for j in range(8):
        s += patch[j] * x[j]
    out[7] = s - 1.0


@njit(**_O)
def _jacobian(q, patch, x, out):
    """``dH/dx`` (8, 8): ``2 q_m x`` (the quadrics are symmetric) and the chart."""
    for m in range(7):
        for i in range(8):
            y = 0j
            for j in range(8):
                y += q[m, i, j] * x[j]
            out[m, i] = 2.0 * y
    for j in range(8):
        out[7, j] = patch[j]


@njit(**_O)
def _dt(q1, q2, t, x, out):
    """``dH/dt``: ``x^T (Q1 + 2 t Q2) x``, 0 for the chart."""
    for m in range(7):
        s = 0j
        for i in range(8):
            y = 0j
            for j in range(8):
                y += (q1[m, i, j] + 2.0 * t * q2[m, i, j]) * x[j]
            s += y * x[i]
        out[m] = s
    out[7] = 0j


@njit(**_O)
def _lu(a, perm):
    """LU with partial pivoting in place; False where a pivot is zero or not finite."""
    n = a.shape[0]
    for i in range(n):
        perm[i] = i
    for k in range(n):
        p, best = k, abs(a[k, k])
        for i in range(k + 1, n):
            v = abs(a[i, k])
            if v > best:
                p, best = i, v
        if not (best > 0.0) or not math.isfinite(best):
            return False
        if p != k:
            for j in range(n):
                a[k, j], a[p, j] = a[p, j], a[k, j]
            perm[k], perm[p] = perm[p], perm[k]
        for i in range(k + 1, n):
            f = a[i, k] / a[k, k]
            a[i, k] = f
            for j in range(k + 1, n):
                a[i, j] -= f * a[k, j]
    return True


@njit(**_O)
def _solve(lu, perm, b, out):
    """``out = A^{-1} b`` from :func:`_lu`'s factors."""
    n = lu.shape[0]
    for i in range(n):
        s = b[perm[i]]
        for j in range(i):
            s -= lu[i, j] * out[j]
        out[i] = s
    for i in range(n - 1, -1, -1):
        s = out[i]
        for j in range(i + 1, n):
            s -= lu[i, j] * out[j]
        out[i] = s / lu[i, i]


@njit(**_O)
def _norm(v):
    s = 0.0
    for i in range(v.shape[0]):
        s += v[i].real * v[i].real + v[i].imag * v[i].imag
    return math.sqrt(s)


@njit(**_O)
def _track_path(q0, q1, q2, patch, x0, h0, hmax, hmin, max_steps, tau, blowup, floor):
    """One path from ``t = 0`` to ``1``: ``(x, reached, steps)``."""
    q = np.empty((7, 8, 8), dtype=np.complex128)
    jac = np.empty((8, 8), dtype=np.complex128)
    perm = np.empty(8, dtype=np.int64)
    r = np.empty(8, dtype=np.complex128)
    d = np.empty(8, dtype=np.complex128)
    x = x0.copy()
    v = np.empty(8, dtype=np.complex128)
    xp = np.empty(8, dtype=np.complex128)
    vp = np.empty(8, dtype=np.complex128)
    pred = np.empty(8, dtype=np.complex128)
    x1 = np.empty(8, dtype=np.complex128)
    t, h, tp, steps, have_prev = 0.0, h0, 0.0, 0, False
    # the first tangent: J(x0, 0) v = -H_t
    _quadrics_at(q0, q1, q2, 0.0, q)
    _jacobian(q, patch, x, jac)
    if not _lu(jac, perm):
        return x, False, steps
    _dt(q1, q2, 0.0, x, r)
    _solve(jac, perm, r, v)
    for i in range(8):
        v[i] = -v[i]
    while True:
        ha = min(h, 1.0 - t)
        t1 = t + ha
        if have_prev:  # cubic Hermite through (tp, xp, vp) and (t, x, v), extrapolated to t1
            dt = t - tp
            s = ha / dt
            for i in range(8):
                a_ = xp[i] - x[i] + dt * v[i]
                b_ = dt * (vp[i] - v[i])
                c3 = b_ + 2.0 * a_
                c2 = 3.0 * a_ + b_
                pred[i] = x[i] + dt * v[i] * s + c2 * s * s + c3 * s * s * s
        else:
            for i in range(8):
                pred[i] = x[i] + ha * v[i]
        _quadrics_at(q0, q1, q2, t1, q)
        _jacobian(q, patch, pred, jac)
        ok = _lu(jac, perm)
        scale = 1.0 + _norm(pred)
        n1 = n2 = n3 = math.nan
        if ok:
            for i in range(8):
                x1[i] = pred[i]
            for k in range(3):
                _residual(q, patch, x1, r)
                _solve(jac, perm, r, d)
                for i in range(8):
                    x1[i] -= d[i]
                nk = _norm(d)
                if k == 0:
                    n1 = nk
                elif k == 1:
                    n2 = nk
                else:
                    n3 = nk
        good = (
            ok
            and math.isfinite(n3)
            and n1 < 0.1 * scale
            and n2 <= 0.2 * n1 + floor * scale
            and n3 <= 0.2 * n2 + floor * scale
        )
        steps += 1
        if good:
            for i in range(8):
                xp[i] = x[i]
                vp[i] = v[i]
                x[i] = x1[i]
            tp, t, have_prev = t, t1, True
            _dt(q1, q2, t1, x, r)  # the new tangent, with the Jacobian at the predicted point
            _solve(jac, perm, r, v)
            for i in range(8):
                v[i] = -v[i]
            fac = 0.9 * (tau / max(n1, 1e-300)) ** (1.0 / 3.0)
            fac = min(max(fac, 0.5), 3.0)
            h = min(ha * fac, hmax)
        else:
            h = ha * 0.5
        if t >= 1.0:
            return x, True, steps
        if h < hmin or steps >= max_steps or not (_norm(x) < blowup):
            return x, False, steps


@njit(**_O)
def _track_all(q0, q1, q2, patch, x0, h0, hmax, hmin, max_steps, tau, blowup, floor):
    k = x0.shape[0]
    x = np.empty((k, 8), dtype=np.complex128)
    reached = np.zeros(k, dtype=np.bool_)
    steps = np.zeros(k, dtype=np.int64)
    for p in range(k):
        xe, ok, n = _track_path(
            q0, q1, q2, patch, x0[p], h0, hmax, hmin, max_steps, tau, blowup, floor
        )
        x[p] = xe
        reached[p] = ok
        steps[p] = n
    return x, reached, steps


def track(
    hom,
    x0: np.ndarray,
    *,
    h0: float = 0.05,
    hmax: float = 0.5,
    hmin: float = 1e-7,
    max_steps: int = 400,
    tau: float = 2e-3,
    blowup: float = 1e7,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`parakin.mechanisms.stewart66_homotopy.track` of a ``GeneralHomotopy`` ``hom``,
    compiled: the same arguments and returns (``(x (K, 8), reached (K,), steps (K,))``)."""
    q0, q1, q2 = (
        np.ascontiguousarray(c.reshape(8, 7, 8).transpose(1, 2, 0), dtype=np.complex128)
        for c in hom.coef
    )
    floor = 100 * np.finfo(np.complex128).eps
    return _track_all(
        q0,
        q1,
        q2,
        np.ascontiguousarray(hom.patch, dtype=np.complex128),
        np.ascontiguousarray(x0, dtype=np.complex128),
        float(h0),
        float(hmax),
        float(hmin),
        int(max_steps),
        float(tau),
        float(blowup),
        float(floor),
    )
