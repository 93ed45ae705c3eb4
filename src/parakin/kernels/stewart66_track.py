"""Compiled path tracker of the 6-6 Gough-Stewart all-solutions FK (``Stewart66.fk_all``).

The per-input fibre homotopy of :class:`parakin.mechanisms.stewart66_homotopy.FiberHomotopy`
tracked by the algorithm of :func:`parakin.mechanisms.stewart66_homotopy.track` (cubic Hermite
predictor, three chord-Newton corrections, the same acceptance test and step-size rule), then
:func:`~parakin.mechanisms.stewart66_homotopy.newton_refine` and
:func:`~parakin.mechanisms.stewart66_homotopy.certify`, one path at a time and ``prange`` over all
(inputs x start solutions) paths. The batched numpy tracker treats every path independently, so
this is the same computation; only the rounding differs (LU solves instead of explicit inverses,
the quadrics of a real geometry applied in real arithmetic).

``q0`` (7, 8, 8) are the geometry's quadrics without their leg constants (real, passed to the
kernels in compressed rows: :func:`compressed`), ``patch`` (8) the affine patch; a path's leg constants are ``c(t) = c0 + t dc + t (1 - t) bend``.
"""

from __future__ import annotations

import math
import os
from functools import lru_cache

import numba
import numpy as np
from numba import njit, prange

if "NUMBA_THREADING_LAYER" not in os.environ:  # fork-safe, as parakin.kernels.build
    numba.config.THREADING_LAYER = "workqueue"

_O = dict(cache=True, error_model="numpy", nogil=True)
_FLOOR = 100 * np.finfo(np.float64).eps


@njit(**_O)
def _y(q0, c, x, y):
    """``y[m] = Q_m x`` with ``Q_m = q0[m]`` plus ``c[m-1]`` on the e-block diagonal (legs).
    ``q0 = (ptr, col, val)``: the real quadrics in compressed rows (row ``8 m + i``)."""
    ptr, col, val = q0[0], q0[1], q0[2]
    for m in range(7):
        for i in range(8):
            r = 8 * m + i
            are = 0.0
            aim = 0.0
            for k in range(ptr[r], ptr[r + 1]):
                xj = x[col[k]]
                are += val[k] * xj.real
                aim += val[k] * xj.imag
            acc = complex(are, aim)
            if m >= 1 and i < 4:
                acc += c[m - 1] * x[i]
            y[m, i] = acc


@njit(**_O)
def _h(q0, c, patch, x, y, h):
    """``H(x) = (x^T Q_m x, patch . x - 1)``, from the 36 products ``x_i x_j`` (i <= j) shared by
    the seven quadrics and each quadric's upper-triangle nonzeros (``y`` is scratch)."""
    hptr, hidx, hval = q0[3], q0[4], q0[5]
    pr = y.ravel()  # 56 >= 36 slots
    n = 0
    for i in range(8):
        xi = x[i]
        for j in range(i, 8):
            pr[n] = xi * x[j]
            n += 1
    # e.e = x0^2 + x1^2 + x2^2 + x3^2: the products of pairs (0,0), (1,1), (2,2), (3,3)
    ee = pr[0] + pr[8] + pr[15] + pr[21]
    for m in range(7):
        are = 0.0
        aim = 0.0
        for k in range(hptr[m], hptr[m + 1]):
            z = pr[hidx[k]]
            are += hval[k] * z.real
            aim += hval[k] * z.imag
        acc = complex(are, aim)
        if m >= 1:
            acc += c[m - 1] * ee
        h[m] = acc
    s = 0.0j
    for i in range(8):
        s += patch[i] * x[i]
    h[7] = s - 1.0


@njit(**_O)
def _jac(q0, c, patch, x, y, jac):
    """``J = dH/dx = (2 Q_m x, patch)``."""
    _y(q0, c, x, y)
    for m in range(7):
        for i in range(8):
            jac[m, i] = 2 * y[m, i]
    for i in range(8):
        jac[7, i] = patch[i]


@njit(**_O)
def _abs2(z):
    return z.real * z.real + z.imag * z.imag


@njit(**_O)
def _lu(a, piv, dinv):
    """LU with partial pivoting in place (``dinv``: the reciprocals of the pivots); False where a
    pivot is exactly 0 (singular). Pivots are chosen by squared modulus (no hypot)."""
    n = a.shape[0]
    for k in range(n):
        p = k
        best = _abs2(a[k, k])
        for i in range(k + 1, n):
            v = _abs2(a[i, k])
            if v > best:
                best, p = v, i
        piv[k] = p
        if best == 0.0:
            return False
        if p != k:
            for j in range(n):
                a[k, j], a[p, j] = a[p, j], a[k, j]
        r = 1.0 / a[k, k]
        dinv[k] = r
        for i in range(k + 1, n):
            f = a[i, k] * r
            a[i, k] = f
            for j in range(k + 1, n):
                a[i, j] -= f * a[k, j]
    return True


@njit(**_O)
def _solve(lu, piv, dinv, b, out):
    """``out = A^-1 b`` from :func:`_lu`'s factors."""
    n = lu.shape[0]
    for i in range(n):
        out[i] = b[i]
    for k in range(n):
        p = piv[k]
        if p != k:
            out[k], out[p] = out[p], out[k]
    for i in range(n):
        acc = out[i]
        for j in range(i):
            acc -= lu[i, j] * out[j]
        out[i] = acc
    for i in range(n - 1, -1, -1):
        acc = out[i]
        for j in range(i + 1, n):
            acc -= lu[i, j] * out[j]
        out[i] = acc * dinv[i]


@njit(**_O)
def _norm(v):
    s = 0.0
    for i in range(v.shape[0]):
        s += v[i].real * v[i].real + v[i].imag * v[i].imag
    return math.sqrt(s)


@njit(**_O)
def _cc(c0, dc, bend, hasbend, t, c):
    for k in range(6):
        c[k] = c0[k] + t * dc[k]
        if hasbend:
            c[k] += t * (1 - t) * bend[k]


@njit(**_O)
def _ht(dc, bend, hasbend, x, t, out):
    """``dH/dt``: ``(dc + (1 - 2t) bend) e.e`` on the leg rows."""
    ee = 0.0j
    for i in range(4):
        ee += x[i] * x[i]
    out[0] = 0.0
    out[7] = 0.0
    for k in range(6):
        d = dc[k] + (1 - 2 * t) * bend[k] if hasbend else dc[k]
        out[1 + k] = d * ee


@njit(**_O)
def track_path(q0, patch, c0, dc, bend, hasbend, x0, opts, x):
    """Track one path from ``x0`` at t = 0 to t = 1 into ``x``; returns ``(reached, steps)``.
    ``opts = (h0, hmax, hmin, max_steps, tau, blowup)``."""
    h0, hmax, hmin, max_steps, tau, blowup = opts[0], opts[1], opts[2], opts[3], opts[4], opts[5]
    y = np.empty((7, 8), dtype=np.complex128)
    jac = np.empty((8, 8), dtype=np.complex128)
    piv = np.empty(8, dtype=np.int64)
    dinv = np.empty(8, dtype=np.complex128)
    c = np.empty(6, dtype=np.complex128)
    hv = np.empty(8, dtype=np.complex128)
    d = np.empty(8, dtype=np.complex128)
    v = np.empty(8, dtype=np.complex128)
    xp = np.empty(8, dtype=np.complex128)
    vp = np.empty(8, dtype=np.complex128)
    pred = np.empty(8, dtype=np.complex128)
    x1 = np.empty(8, dtype=np.complex128)
    for i in range(8):
        x[i] = x0[i]
    t = 0.0
    h = h0
    steps = 0
    _cc(c0, dc, bend, hasbend, t, c)
    _jac(q0, c, patch, x, y, jac)
    if not _lu(jac, piv, dinv):
        return False, 0
    _ht(dc, bend, hasbend, x, t, hv)
    _solve(jac, piv, dinv, hv, v)
    for i in range(8):
        v[i] = -v[i]
    have_prev = False
    tp = 0.0
    while True:
        ha = min(h, 1.0 - t)
        t1 = t + ha
        if have_prev:  # cubic Hermite through the last two points and tangents
            dt = t - tp
            s = ha / dt
            for i in range(8):
                a_ = xp[i] - x[i] + dt * v[i]
                b_ = dt * (vp[i] - v[i])
                c3 = b_ + 2 * a_
                c2 = 3 * a_ + b_
                pred[i] = x[i] + dt * v[i] * s + c2 * s * s + c3 * s * s * s
        else:
            for i in range(8):
                pred[i] = x[i] + ha * v[i]
        _cc(c0, dc, bend, hasbend, t1, c)
        _jac(q0, c, patch, pred, y, jac)
        okinv = _lu(jac, piv, dinv)
        scale = 1.0 + _norm(pred)
        for i in range(8):
            x1[i] = pred[i]
        n1 = n2 = n3 = math.nan
        if okinv:
            for it in range(3):  # chord Newton with the Jacobian at the predicted point
                _h(q0, c, patch, x1, y, hv)
                _solve(jac, piv, dinv, hv, d)
                for i in range(8):
                    x1[i] -= d[i]
                nd = _norm(d)
                if it == 0:
                    n1 = nd
                elif it == 1:
                    n2 = nd
                else:
                    n3 = nd
        good = (
            okinv
            and math.isfinite(n3)
            and n1 < 0.1 * scale
            and n2 <= 0.2 * n1 + _FLOOR * scale
            and n3 <= 0.2 * n2 + _FLOOR * scale
        )
        steps += 1
        if good:
            for i in range(8):
                xp[i] = x[i]
                vp[i] = v[i]
                x[i] = x1[i]
            tp = t
            have_prev = True
            t = t1
            _ht(dc, bend, hasbend, x, t, hv)
            _solve(jac, piv, dinv, hv, v)
            for i in range(8):
                v[i] = -v[i]
            fac = 0.9 * (tau / max(n1, 1e-300)) ** (1.0 / 3.0)
            fac = min(max(fac, 0.5), 3.0)
            h = min(ha * fac, hmax)
        else:
            h = ha * 0.5
        if t >= 1.0:
            return True, steps
        if h < hmin or steps >= max_steps or not (_norm(x) < blowup):
            return False, steps


@njit(parallel=True, **_O)
def track_parallel(q0, patch, c0, dc, bend, hasbend, x0, opts, x, reached, steps):
    for k in prange(x0.shape[0]):
        r, s = track_path(q0, patch, c0[k], dc[k], bend[k], hasbend, x0[k], opts, x[k])
        reached[k] = r
        steps[k] = s


@njit(**_O)
def track_serial(q0, patch, c0, dc, bend, hasbend, x0, opts, x, reached, steps):
    for k in range(x0.shape[0]):
        r, s = track_path(q0, patch, c0[k], dc[k], bend[k], hasbend, x0[k], opts, x[k])
        reached[k] = r
        steps[k] = s


@njit(**_O)
def refine_path(q0, c, patch, x, iters, out):
    """``newton_refine`` for one path: ``iters`` Newton steps on ``x^T Q_m x = 0, patch . x = 1``,
    then ``(beta, |J^-1|_F)`` at the last iterate (inf where J is singular); Smale's alpha with
    ``gamma <= |J^-1|_F sqrt(sum |Q_m|_F^2)`` is ``beta * jn * qn``."""
    y = np.empty((7, 8), dtype=np.complex128)
    jac = np.empty((8, 8), dtype=np.complex128)
    piv = np.empty(8, dtype=np.int64)
    dinv = np.empty(8, dtype=np.complex128)
    f = np.empty(8, dtype=np.complex128)
    d = np.empty(8, dtype=np.complex128)
    e = np.zeros(8, dtype=np.complex128)
    col = np.empty(8, dtype=np.complex128)
    for i in range(8):
        out[i] = x[i]
    for it in range(iters + 1):
        _h(q0, c, patch, out, y, f)
        _jac(q0, c, patch, out, y, jac)
        ok = _lu(jac, piv, dinv)
        if not ok:
            if it == iters:
                return math.inf, math.inf
            continue
        _solve(jac, piv, dinv, f, d)
        if it == iters:
            jn = 0.0
            for k in range(8):  # |J^-1|_F, column by column
                e[:] = 0.0
                e[k] = 1.0
                _solve(jac, piv, dinv, e, col)
                for i in range(8):
                    jn += col[i].real ** 2 + col[i].imag ** 2
            return _norm(d), math.sqrt(jn)
        for i in range(8):
            out[i] -= d[i]
    return math.inf, math.inf


@njit(**_O)
def _qnorm(q0, c):
    """``sqrt(sum_m |Q_m|_F^2)`` of the target quadrics."""
    ptr, col, val = q0[0], q0[1], q0[2]
    s = 0.0
    for m in range(7):
        for i in range(8):
            r = 8 * m + i
            diag = 0.0
            for k in range(ptr[r], ptr[r + 1]):
                if col[k] == i:
                    diag = val[k]
                else:
                    s += val[k] * val[k]
            v = diag + (c[m - 1] if (m >= 1 and i < 4) else 0.0j)
            s += v.real * v.real + v.imag * v.imag
    return math.sqrt(s)


@njit(parallel=True, **_O)
def refine_parallel(q0, c, patch, x, iters, out, beta, jn, alpha):
    for k in prange(x.shape[0]):
        b, j = refine_path(q0, c[k], patch, x[k], iters, out[k])
        beta[k] = b
        jn[k] = j
        alpha[k] = b * j * _qnorm(q0, c[k])


@njit(**_O)
def refine_serial(q0, c, patch, x, iters, out, beta, jn, alpha):
    for k in range(x.shape[0]):
        b, j = refine_path(q0, c[k], patch, x[k], iters, out[k])
        beta[k] = b
        jn[k] = j
        alpha[k] = b * j * _qnorm(q0, c[k])


def compressed(q0: np.ndarray):
    """:func:`_compressed` of ``q0``, cached by value (a geometry's quadrics are reused by every
    call)."""
    q = np.ascontiguousarray(q0, dtype=np.float64)
    return _compressed_cached(q.tobytes(), q.shape)


@lru_cache(maxsize=32)
def _compressed_cached(data: bytes, shape: tuple):
    return _compressed(np.frombuffer(data, dtype=np.float64).reshape(shape))


def _compressed(q0: np.ndarray):
    """The real quadrics ``q0`` (7, 8, 8) for the kernels: ``(ptr, col, val)``, their nonzeros by
    rows ``8 m + i`` (for ``Q_m x``), and ``(hptr, hidx, hval)``, each quadric's nonzeros on and
    above the diagonal (off-diagonal ones doubled) indexing the 36 products ``x_i x_j``, i <= j
    (for ``x^T Q_m x``)."""
    q = np.asarray(q0, dtype=np.float64)
    rows = q.reshape(56, 8)
    nz = rows != 0
    ptr = np.concatenate([[0], np.cumsum(nz.sum(-1))]).astype(np.int64)
    col = np.nonzero(nz)[1].astype(np.int64)
    pair = {}
    for i in range(8):
        for j in range(i, 8):
            pair[i, j] = len(pair)
    hptr, hidx, hval = [0], [], []
    for m in range(7):
        for i in range(8):
            for j in range(i, 8):
                v = q[m, i, j] if i == j else q[m, i, j] + q[m, j, i]
                if v != 0:
                    hidx.append(pair[i, j])
                    hval.append(v)
        hptr.append(len(hidx))
    return (
        ptr,
        col,
        np.ascontiguousarray(rows[nz]),
        np.array(hptr, dtype=np.int64),
        np.array(hidx, dtype=np.int64),
        np.array(hval, dtype=np.float64),
    )


_OPTS = ("h0", "hmax", "hmin", "max_steps", "tau", "blowup")
_DEFAULTS = {"h0": 0.05, "hmax": 0.5, "hmin": 1e-7, "max_steps": 400, "tau": 2e-3, "blowup": 1e7}


def track(q0, patch, c0, c1, bend, x0, options: dict, parallel: bool = True):
    """``(x (K, 8), reached (K,), steps (K,))``: :func:`~parakin.mechanisms.stewart66_homotopy.track`
    of the fibre homotopy from leg constants ``c0`` (K, 6) to ``c1`` (K, 6) (``bend`` (K, 6) or
    None), compiled. ``q0`` must be real (a real geometry)."""
    k = len(x0)
    opts = np.array([float({**_DEFAULTS, **options}[n]) for n in _OPTS])
    c0 = np.ascontiguousarray(np.broadcast_to(c0, (k, 6)), dtype=np.complex128)
    dc = np.ascontiguousarray(np.broadcast_to(c1, (k, 6)), dtype=np.complex128) - c0
    hasbend = bend is not None
    bend = (
        np.ascontiguousarray(np.broadcast_to(bend, (k, 6)), dtype=np.complex128)
        if hasbend
        else np.zeros((k, 6), dtype=np.complex128)
    )
    x = np.empty((k, 8), dtype=np.complex128)
    reached = np.zeros(k, dtype=np.bool_)
    steps = np.zeros(k, dtype=np.int64)
    fn = track_parallel if parallel else track_serial
    fn(
        compressed(q0),
        np.ascontiguousarray(patch, dtype=np.complex128),
        c0,
        dc,
        bend,
        hasbend,
        np.ascontiguousarray(x0, dtype=np.complex128),
        opts,
        x,
        reached,
        steps,
    )
    return x, reached, steps


def refine(q0, c, patch, x, iters: int = 3, parallel: bool = True):
    """``(x, beta, jinv_norm, alpha)``: ``newton_refine`` and ``certify`` of every path, compiled
    (``c`` (K, 6) the target leg constants of each path)."""
    k = len(x)
    out = np.empty((k, 8), dtype=np.complex128)
    beta, jn, alpha = np.empty(k), np.empty(k), np.empty(k)
    fn = refine_parallel if parallel else refine_serial
    fn(
        compressed(q0),
        np.ascontiguousarray(np.broadcast_to(c, (k, 6)), dtype=np.complex128),
        np.ascontiguousarray(patch, dtype=np.complex128),
        np.ascontiguousarray(x, dtype=np.complex128),
        int(iters),
        out,
        beta,
        jn,
        alpha,
    )
    return out, beta, jn, alpha
