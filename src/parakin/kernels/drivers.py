"""The compiled solver loops, written once for every mechanism: Newton, Levenberg-Marquardt,
Broyden, BFGS, Powell's dog leg, the verification of an answer and particle-swarm iterations, each for **one**
pose, taking the mechanism's kernels (:mod:`parakin.kernels`) as their first arguments, in the
manner of QuantEcon's ``optimize.root_finding`` (``newton(res, jac, p, q, x0, opts, x, info, ws)``,
``ws`` the work arrays of :func:`work`, made once per batch).

The kernels (``numba.njit`` functions of one pose, see :func:`parakin.kernels.compiled`):
``res(p, x, q, out)`` the residual, ``jac(p, x, q, out)`` its Jacobian, ``ik(p, x, out) -> ok``,
``dom(p, x) -> ok``, ``asm(p, x, q) -> ok`` and ``per(p, k)``, the period of joint ``k`` (2 pi for
an angle, whose errors are taken modulo a turn; :func:`no_period` for a kernel without angles). ``p`` is the mechanism's parameter vector, ``q``
the joints (``m`` values), ``x`` the pose (``n``); ``m`` and ``n`` are read from the arrays.

Numba specialises a loop on the kernels it is given (they are compiled into it, as if written
there), which is what makes it fast; it cannot cache such a specialisation on disk (the kernels'
identity is not stable across processes). The cached units are therefore the small entry points
of :mod:`parakin.kernels.entries`, one set per kernel, which call these loops; they carry the
cache, keyed on everything that produced them (:mod:`parakin.kernels.store`). Nothing here is
compiled before a solve asks for it.

Options come in one vector, positions as :data:`parakin.kernels.methods.VECTOR` declares them.
Status codes as :class:`parakin.solvers.result.Status`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from parakin.kernels.methods import VECTOR

__all__ = [
    "bfgs",
    "broyden",
    "dogleg",
    "lm",
    "newton",
    "no_period",
    "pso_iterations",
    "verify",
]

_O = dict(error_model="numpy", nogil=True)
#: the loops that take kernels: inlined into their callers (numba's IR inlining), so that a
#: kernel passed as an argument becomes a direct call and nothing of it is left as a run-time
#: value (a compiled function that holds one cannot be cached on disk)
_TAKES_KERNELS = dict(_O, inline="always")

CONVERGED, SMALL_STEP, SMALL_GRADIENT = 0, 1, 2
MAXITER, NONFINITE, STALLED = -1, -2, -3
RUNNING = 127
#: positions in the options vector (parakin.kernels.methods.VECTOR, read at compile time)
TOL, MAXIT, XTOL, GTOL = (VECTOR.index(k) for k in ("tol", "maxiter", "xtol", "gtol"))
TAU, C1, SHRINK, MAXLS, REG = (VECTOR.index(k) for k in ("tau", "c1", "shrink", "maxls", "reg"))
FACTOR, ETA = (VECTOR.index(k) for k in ("factor", "eta"))
_TINY = 2.2250738585072014e-308  # smallest normal double: LM's damping never reaches 0


@njit(**_O)
def _infnorm(v):
    m = 0.0
    for i in range(v.shape[0]):
        a = abs(v[i])
        if a != a:
            return math.nan
        if a > m:
            m = a
    return m


@njit(**_O)
def _copy(dst, src):
    """``dst[:] = src`` element by element. numba compiles a slice assignment from an array with
    its shape-mismatch error message (string formatting: about 2 CPU-s in every process that
    compiles one, and that code linked into every caller); a loop compiles to the same copy."""
    for i in range(dst.shape[0]):
        dst[i] = src[i]


@njit(**_O)
def finite(v):
    """Every entry of ``v`` finite."""
    for i in range(v.shape[0]):
        if not math.isfinite(v[i]):
            return False
    return True


@njit(**_O)
def _dot(a, b):
    s = 0.0
    for i in range(a.shape[0]):
        s += a[i] * b[i]
    return s


@njit(**_TAKES_KERNELS)
def _eval(res, p, x, q, r):
    """Residual at ``x`` (NaN, not counted, where ``x`` is not finite); returns 1 if evaluated."""
    if finite(x):
        res(p, x, q, r)
        return 1
    r[:] = math.nan
    return 0


@njit(**_O)
def _checked(x, r):
    """``(|r|_inf, x and r finite)``: what the stopping rule (:func:`_code`) is given."""
    res = _infnorm(r)
    return res, finite(x) and math.isfinite(res)


@njit(**_O)
def _max_diag(a):
    """``max_i a[i, i]``, NaN propagating."""
    big = -math.inf
    for i in range(a.shape[0]):
        if not a[i, i] <= big:
            big = a[i, i]
    return big


@njit(**_O)
def _lu_solve(a, b, out, w):
    """``a out = b`` for a finite square ``a`` (n, n) by LU with partial pivoting (``w`` (n, n + 1)
    scratch); False (``out`` untouched) where ``a`` is exactly singular."""
    n = b.shape[0]
    for i in range(n):
        for j in range(n):
            w[i, j] = a[i, j]
        w[i, n] = b[i]
    for k in range(n):
        piv = k
        big = abs(w[k, k])
        for i in range(k + 1, n):
            if abs(w[i, k]) > big:
                big = abs(w[i, k])
                piv = i
        if big == 0.0:
            return False
        if piv != k:
            for j in range(k, n + 1):
                t = w[k, j]
                w[k, j] = w[piv, j]
                w[piv, j] = t
        # two rows at a time: the same operations on each entry in the same order (the same
        # bits), their chains overlapped (a 6 x 6 solve 150-170 -> 130-140 ns)
        d = w[k, k]
        i = k + 1
        while i + 1 < n:
            f0 = w[i, k] / d
            f1 = w[i + 1, k] / d
            for j in range(k + 1, n + 1):
                wkj = w[k, j]
                w[i, j] -= f0 * wkj
                w[i + 1, j] -= f1 * wkj
            i += 2
        if i < n:
            f0 = w[i, k] / d
            for j in range(k + 1, n + 1):
                w[i, j] -= f0 * w[k, j]
    for i in range(n - 1, -1, -1):
        s = w[i, n]
        for j in range(i + 1, n):
            s -= w[i, j] * out[j]
        out[i] = s / w[i, i]
    return True


@njit(**_O)
def _all_finite(a):
    for i in range(a.shape[0]):
        for j in range(a.shape[1]):
            if not math.isfinite(a[i, j]):
                return False
    return True


@njit(**_O)
def _solve(a, b, out, w):
    """``a out = b`` for square ``a``: LU with partial pivoting; minimum-norm least squares
    ``pinv(a) b`` where ``a`` is exactly singular; NaN where ``a`` or ``b`` is not finite."""
    if not (finite(b) and _all_finite(a)):
        out[:] = math.nan
    elif not _lu_solve(a, b, out, w):
        _copy(out, np.linalg.pinv(a) @ b)


@njit(**_O)
def _gram(jac, r, a, g):
    """``a = J^T J``, ``g = J^T r``. Two sums of a row of ``a`` at a time: each is still summed over
    ``k`` in order (the same bits as one after the other), but their chains of ``m`` additions
    overlap (one chain at a time, the processor waits on each addition's result: a 12 x 6 Gram
    matrix took 175 ns, two at a time 95)."""
    m, n = jac.shape
    for i in range(n):
        s = 0.0
        for k in range(m):
            s += jac[k, i] * r[k]
        g[i] = s
        j = i
        while j + 1 < n:
            s0 = 0.0
            s1 = 0.0
            for k in range(m):
                jki = jac[k, i]
                s0 += jki * jac[k, j]
                s1 += jki * jac[k, j + 1]
            a[i, j] = a[j, i] = s0
            a[i, j + 1] = a[j + 1, i] = s1
            j += 2
        if j < n:
            s = 0.0
            for k in range(m):
                s += jac[k, i] * jac[k, j]
            a[i, j] = a[j, i] = s


@njit(**_O)
def _direction(jac, r, out, w, a, g):
    """``J^-1 r`` (square, :func:`_solve`) or, for ``m > n``, the least-squares step from the normal
    equations ``J^T J out = J^T r`` (``pinv(J) r`` where ``J^T J`` is singular)."""
    if jac.shape[0] == jac.shape[1]:
        _solve(jac, r, out, w)
    elif not (finite(r) and _all_finite(jac)):
        out[:] = math.nan
    else:
        _gram(jac, r, a, g)
        if not _lu_solve(a, g, out, w):
            _copy(out, np.linalg.pinv(jac) @ r)


#: n-vectors among the work arrays (:func:`work`): as many as BFGS uses at once
_VECTORS = 8


@njit(**_O)
def work(m, n):
    """The work arrays of one pose's solve, ``m`` joints and ``n`` pose coordinates, made once per
    batch: every row's loop reuses them and writes each before it reads it, so a row's result
    does not depend on the rows before it. ``(r, rt, xt, w, a, jm, nn, u, v)``: the residual at
    the iterate and at the trial point (m), the trial point (n), the LU's scratch (n, n + 1),
    ``J^T J`` (n, n), the Jacobian (m, n), a second (n, n) matrix, an m-vector and
    :data:`_VECTORS` n-vectors (the rows of ``v``). (Made per row, these eight to ten small arrays
    cost 120 ns of the 12-leg cube's batched Newton solve, 2,350 ns.)"""
    return (
        np.empty(m),
        np.empty(m),
        np.empty(n),
        np.empty((n, n + 1)),
        np.empty((n, n)),
        np.empty((m, n)),
        np.empty((n, n)),
        np.empty(m),
        np.empty((_VECTORS, n)),
    )


@njit(**_TAKES_KERNELS)
def _start(res, p, q, x0, x, r, opts, info):
    """Residual at the start; returns the status (CONVERGED, NONFINITE or RUNNING) and its norm."""
    _copy(x, x0)
    info[2] += _eval(res, p, x, q, r)
    norm = _infnorm(r)
    if norm <= opts[TOL]:
        return CONVERGED, norm
    if not math.isfinite(norm):
        return NONFINITE, norm
    return RUNNING, norm


@njit(**_O)
def _code(opts, step, grad, stalled, new_res, ok):
    code = RUNNING
    if opts[XTOL] > 0 and step <= opts[XTOL]:
        code = SMALL_STEP
    if opts[GTOL] > 0 and grad <= opts[GTOL]:
        code = SMALL_GRADIENT
    if stalled:
        code = STALLED
    if new_res <= opts[TOL]:
        code = CONVERGED
    if not ok:
        code = NONFINITE
    return code


# ---------------------------------------------------------------------------- Newton
@njit(**_TAKES_KERNELS)
def newton(res, jac, p, q, x0, opts, x, info, ws):
    """Newton-Raphson on one pose (see parakin.solvers.newton); info = status, nit, nfev, njev;
    ``ws`` the work arrays (:func:`work`). Returns the residual's inf-norm at ``x``."""
    n = x0.shape[0]
    r, rt, xt, w, a, jm, _, _, v = ws
    g, dx = v[0], v[1]
    status, norm = _start(res, p, q, x0, x, r, opts, info)
    for _ in range(int(opts[MAXIT])):
        if status != RUNNING:
            break
        jac(p, x, q, jm)
        info[3] += 1
        _direction(jm, r, dx, w, a, g)
        for i in range(n):
            xt[i] = x[i] - dx[i]
        info[2] += _eval(res, p, xt, q, rt)
        info[1] += 1
        new_res, ok = _checked(xt, rt)
        status = _code(opts, _infnorm(dx), math.nan, False, new_res, ok)
        if ok:
            _copy(x, xt)
            _copy(r, rt)
            norm = new_res
    info[0] = MAXITER if status == RUNNING else status
    return norm


# ---------------------------------------------------------------------------- Levenberg-Marquardt
@njit(**_O)
def _lm_trial(a, g, mu, h, damped, mg, w):
    """The step ``h`` of ``(J^T J + mu I) h = -J^T r``."""
    n = g.shape[0]
    for i in range(n):
        for j in range(n):
            damped[i, j] = a[i, j]
        damped[i, i] += mu
        mg[i] = -g[i]
    _solve(damped, mg, h, w)


@njit(**_TAKES_KERNELS)
def lm(res, jac, p, q, x0, opts, x, info, ws):
    """Levenberg-Marquardt with Nielsen's damping on one pose (see parakin.solvers.lm)."""
    n = x0.shape[0]
    r, rt, xt, w, a, jm, damped, _, v = ws
    g, h, mg = v[0], v[1], v[2]
    status, norm = _start(res, p, q, x0, x, r, opts, info)
    mu, nu = 0.0, 2.0
    if status == RUNNING:
        jac(p, x, q, jm)
        info[3] += 1
        _gram(jm, r, a, g)
        mu = opts[TAU] * _max_diag(a)
        if mu < _TINY:
            mu = _TINY
    for _ in range(int(opts[MAXIT])):
        if status != RUNNING:
            break
        _lm_trial(a, g, mu, h, damped, mg, w)
        for i in range(n):
            xt[i] = x[i] + h[i]
        info[2] += _eval(res, p, xt, q, rt)
        info[1] += 1
        predicted = 0.0
        for i in range(n):
            predicted += h[i] * (mu * h[i] - g[i])
        rho = (0.5 * _dot(r, r) - 0.5 * _dot(rt, rt)) / (0.5 * predicted)
        if rho > 0:
            _copy(x, xt)
            _copy(r, rt)
            jac(p, x, q, jm)
            info[3] += 1
            _gram(jm, r, a, g)
            t = 2.0 * rho - 1.0
            mu = mu * max(1.0 / 3.0, 1.0 - t * t * t)
            nu = 2.0
        else:
            mu = mu * nu
            nu = 2.0 * nu
        new_res, ok = _checked(x, r)
        status = _code(opts, _infnorm(h), _infnorm(g), False, new_res, ok)
        if ok:
            norm = new_res
    info[0] = MAXITER if status == RUNNING else status
    return norm


# ---------------------------------------------------------------------------- Broyden
@njit(**_TAKES_KERNELS)
def broyden(res, jac, p, q, x0, opts, x, info, ws):
    """Broyden's good method on one pose (see parakin.solvers.quasi_newton.broyden)."""
    m, n = q.shape[0], x0.shape[0]
    r, rt, xt, w, a, b, _, u, v = ws
    g, d = v[0], v[1]
    status, norm = _start(res, p, q, x0, x, r, opts, info)
    if status == RUNNING:
        jac(p, x, q, b)
        info[3] += 1
    for _ in range(int(opts[MAXIT])):
        if status != RUNNING:
            break
        _direction(b, r, d, w, a, g)
        for i in range(n):
            d[i] = -d[i]
            xt[i] = x[i] + d[i]
        info[2] += _eval(res, p, xt, q, rt)
        info[1] += 1
        dd = _dot(d, d)
        gain = 1.0 / dd if dd > 0 else 0.0
        for k in range(m):
            s = 0.0
            for i in range(n):
                s += b[k, i] * d[i]
            u[k] = (rt[k] - r[k] - s) * gain
        new_res, ok = _checked(xt, rt)
        status = _code(opts, _infnorm(d), math.nan, False, new_res, ok)
        if ok:
            for k in range(m):
                for i in range(n):
                    b[k, i] += u[k] * d[i]
            _copy(x, xt)
            _copy(r, rt)
            norm = new_res
    info[0] = MAXITER if status == RUNNING else status
    return norm


# ---------------------------------------------------------------------------- BFGS
@njit(**_TAKES_KERNELS)
def _bfgs_start(jac, p, x, q, r, opts, info, jm, a, g, hh, w, e, col):
    """``g = J^T r`` and the Gauss-Newton inverse Hessian ``(J^T J + reg max diag I)^-1``."""
    n = x.shape[0]
    jac(p, x, q, jm)
    info[3] += 1
    _gram(jm, r, a, g)
    big = _max_diag(a)
    if big < 1.0e-300:
        big = 1.0e-300
    lam = opts[REG] * big
    for i in range(n):
        a[i, i] += lam
    for j in range(n):
        e[:] = 0.0
        e[j] = 1.0
        _solve(a, e, col, w)
        for i in range(n):
            hh[i, j] = col[i]


@njit(**_TAKES_KERNELS)
def _armijo(res, p, x, q, r, pp, slope, opts, info, xt, rt):
    """Backtracking from ``alpha = 1`` along ``pp``: ``(alpha, found)``; ``xt``, ``rt`` at it."""
    f0 = 0.5 * _dot(r, r)
    alpha = 1.0
    for _ls in range(int(opts[MAXLS])):
        for i in range(x.shape[0]):
            xt[i] = x[i] + alpha * pp[i]
        info[2] += _eval(res, p, xt, q, rt)
        if 0.5 * _dot(rt, rt) <= f0 + opts[C1] * alpha * slope:
            return alpha, True
        alpha *= opts[SHRINK]
    return alpha, False


@njit(**_O)
def _bfgs_update(hh, d, y, hy):
    """N&W eq. (6.17), skipped where the curvature ``y^T d`` is not safely positive (``hy``:
    scratch, n)."""
    n = d.shape[0]
    yd = _dot(y, d)
    size = math.sqrt(_dot(y, y)) * math.sqrt(_dot(d, d))
    rho = 1.0 / yd if yd > math.sqrt(2.220446049250313e-16) * size else 0.0
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += hh[i, j] * y[j]
        hy[i] = s
    coef = rho * rho * _dot(y, hy) + rho
    for i in range(n):
        for j in range(n):
            hh[i, j] = hh[i, j] - rho * (d[i] * hy[j] + hy[i] * d[j]) + coef * d[i] * d[j]


@njit(**_TAKES_KERNELS)
def bfgs(res, jac, p, q, x0, opts, x, info, ws):
    """BFGS with Armijo backtracking on |r|^2 / 2 for one pose (see parakin.solvers.quasi_newton.bfgs)."""
    m, n = q.shape[0], x0.shape[0]
    r, rt, xt, w, a, jm, hh, _, v = ws
    g, gn, pp, y, d, e, col, hy = v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]
    status, norm = _start(res, p, q, x0, x, r, opts, info)
    if status == RUNNING:
        _bfgs_start(jac, p, x, q, r, opts, info, jm, a, g, hh, w, e, col)
    for _ in range(int(opts[MAXIT])):
        if status != RUNNING:
            break
        for i in range(n):
            s = 0.0
            for j in range(n):
                s += hh[i, j] * g[j]
            pp[i] = -s
        slope = _dot(g, pp)
        if not slope < 0:
            for i in range(n):
                pp[i] = -g[i]
            slope = -_dot(g, g)
        alpha, found = _armijo(res, p, x, q, r, pp, slope, opts, info, xt, rt)
        _copy(gn, g)
        if found:
            jac(p, xt, q, jm)
            info[3] += 1
            for i in range(n):
                s = 0.0
                for k in range(m):
                    s += jm[k, i] * rt[k]
                gn[i] = s
        for i in range(n):
            d[i] = alpha * pp[i] if found else 0.0
            y[i] = gn[i] - g[i]
        _bfgs_update(hh, d, y, hy)
        _copy(g, gn)
        if found:
            _copy(x, xt)
            _copy(r, rt)
        info[1] += 1
        step = 0.0
        for i in range(n):
            v = abs(alpha * pp[i])
            if v != v or v > step:
                step = v
        new_res, ok = _checked(x, r)
        status = _code(opts, step, _infnorm(g), not found, new_res, ok)
        if ok:
            norm = new_res
    info[0] = MAXITER if status == RUNNING else status
    return norm


# ---------------------------------------------------------------------------- dog leg
_EPS = 2.220446049250313e-16


@njit(**_O)
def _scaled_norm(d, v):
    """``|D v|_2`` for the diagonal scaling ``d``."""
    s = 0.0
    for i in range(v.shape[0]):
        s += (d[i] * v[i]) * (d[i] * v[i])
    return math.sqrt(s)


@njit(**_O)
def _dogleg_model(jm, r, d, g, pn, w, a, gg, first):
    """At a new iterate: ``g = J^T r``, the Gauss-Newton step ``pn = -J^-1 r`` (:func:`_direction`)
    and MINPACK's scaling ``d_i = max(d_i, |J e_i|)`` (``first``: ``|J e_i|``, 1 where 0)."""
    m, n = jm.shape
    _direction(jm, r, pn, w, a, gg)
    for i in range(n):
        pn[i] = -pn[i]
        s, c = 0.0, 0.0
        for k in range(m):
            s += jm[k, i] * r[k]
            c += jm[k, i] * jm[k, i]
        g[i] = s
        c = math.sqrt(c)
        if first:
            d[i] = c if c != 0.0 else 1.0
        elif c > d[i]:
            d[i] = c


@njit(**_O)
def _dogleg_step(jm, g, pn, d, delta, st):
    """Powell's dog-leg step ``st`` in the scaled variables ``y = D st`` with ``|y| <= delta``
    (Nocedal & Wright, sec. 4.1): the Gauss-Newton step where it fits, else the path from the
    Cauchy point towards it, cut at the boundary. Returns True where ``st`` ends on the boundary."""
    m, n = jm.shape
    if _scaled_norm(d, pn) <= delta:
        _copy(st, pn)
        return False
    gs2, jv2 = 0.0, 0.0
    for i in range(n):
        gs2 += (g[i] / d[i]) * (g[i] / d[i])
    for k in range(m):
        s = 0.0
        for i in range(n):
            s += jm[k, i] * (g[i] / (d[i] * d[i]))
        jv2 += s * s
    gnorm = math.sqrt(gs2)
    t = gs2 / jv2 if jv2 > 0.0 else math.inf  # the Cauchy point is -t D^-1 g in y
    if t * gnorm >= delta:  # steepest descent, cut at the boundary
        for i in range(n):
            st[i] = -delta * (g[i] / d[i]) / gnorm / d[i]
        return True
    a, b = 0.0, 0.0
    c = (t * gnorm) * (t * gnorm) - delta * delta
    for i in range(n):
        yu = -t * g[i] / d[i]
        dy = d[i] * pn[i] - yu
        a += dy * dy
        b += 2.0 * yu * dy
    root = math.sqrt(b * b - 4.0 * a * c)
    tau = -2.0 * c / (b + root) if b >= 0.0 else (root - b) / (2.0 * a)
    for i in range(n):
        yu = -t * g[i] / d[i]
        st[i] = (yu + tau * (d[i] * pn[i] - yu)) / d[i]
    return True


@njit(**_O)
def _gain_ratio(jm, r, rt, st):
    """Actual over predicted reduction of ``|r|^2 / 2`` for the step ``st`` (-1 where either is
    not a positive finite number: the step is rejected)."""
    m, n = jm.shape
    pred = 0.0
    for k in range(m):
        s = r[k]
        for i in range(n):
            s += jm[k, i] * st[i]
        pred += r[k] * r[k] - s * s
    rho = (_dot(r, r) - _dot(rt, rt)) / pred
    return rho if pred > 0.0 and math.isfinite(rho) else -1.0


@njit(**_O)
def _new_radius(delta, rho, snorm, boundary):
    """Nocedal & Wright's Alg. 4.1: shrink to a quarter of the step below rho = 1/4, double on the
    boundary above 3/4."""
    if rho < 0.25:
        return 0.25 * (snorm if math.isfinite(snorm) else delta)
    if rho > 0.75 and boundary:
        return 2.0 * delta
    return delta


@njit(**_TAKES_KERNELS)
def dogleg(res, jac, p, q, x0, opts, x, info, ws):
    """Powell's dog-leg trust region on one pose (see parakin.solvers.dogleg)."""
    n = x0.shape[0]
    r, rt, xt, w, a, jm, _, _, v = ws
    gg, g, pn, d, st = v[0], v[1], v[2], v[3], v[4]
    status, norm = _start(res, p, q, x0, x, r, opts, info)
    delta = 0.0
    if status == RUNNING:
        jac(p, x, q, jm)
        info[3] += 1
        _dogleg_model(jm, r, d, g, pn, w, a, gg, True)
        size = _scaled_norm(d, x)
        delta = opts[FACTOR] * size if size > 0.0 else opts[FACTOR]
    for _ in range(int(opts[MAXIT])):
        if status != RUNNING:
            break
        boundary = _dogleg_step(jm, g, pn, d, delta, st)
        for i in range(n):
            xt[i] = x[i] + st[i]
        info[2] += _eval(res, p, xt, q, rt)
        info[1] += 1
        rho = _gain_ratio(jm, r, rt, st)
        delta = _new_radius(delta, rho, _scaled_norm(d, st), boundary)
        if rho > opts[ETA]:
            _copy(x, xt)
            _copy(r, rt)
            jac(p, x, q, jm)
            info[3] += 1
            _dogleg_model(jm, r, d, g, pn, w, a, gg, False)
        stalled = not delta > _EPS * _scaled_norm(d, x)
        new_res, ok = _checked(x, r)
        status = _code(opts, _infnorm(st), math.nan, stalled, new_res, ok)
        if ok:
            norm = new_res
    info[0] = MAXITER if status == RUNNING else status
    return norm


# ---------------------------------------------------------------------------- verification
@njit(**_O)
def no_period(p, k):
    """The joint period of a kernel that declares none: 0, no joint is an angle."""
    return 0.0


@njit(**_O)
def _joint_gap(d, period):
    """``|d|``, or for a joint of ``period`` > 0 (an angle: 2 pi) the distance to the nearest
    multiple of the period: 3.56 rad and -2.72 rad are the same crank angle."""
    if period > 0.0:
        d = d - period * math.floor(d / period + 0.5)
    return abs(d)


@njit(**_TAKES_KERNELS)
def verify(ik, dom, asm, per, p, q, x, flags, out):
    """flags[0] = in domain, flags[1] = on assembly; returns max |ik(x) - q| (inf outside), each
    joint's difference taken modulo its period ``per(p, k)`` (0: none); ``out``: scratch (m) for
    the joints of ``x``."""
    flags[0] = 0
    flags[1] = 0
    if not (finite(x) and dom(p, x)):
        return math.inf
    flags[0] = 1
    flags[1] = 1 if asm(p, x, q) else 0
    m = q.shape[0]
    if not ik(p, x, out):
        return math.inf
    err = 0.0
    for k in range(m):
        v = _joint_gap(out[k] - q[k], per(p, k))
        if v != v:
            return math.inf
        if v > err:
            err = v
    return err


# ---------------------------------------------------------------------------- particle swarm
@njit(**_TAKES_KERNELS)
def _pso_fitness(res, p, x, q, r):
    """Li 2020's eq. (20), ``sum |f_j|`` (inf where not finite), as ``parakin.solvers.pso``."""
    if not finite(x):
        return math.inf
    res(p, x, q, r)
    s = 0.0
    for k in range(r.shape[0]):
        s += abs(r[k])
    return s if math.isfinite(s) else math.inf


@njit(**_O)
def _pso_move(i, wk, rnd_s, x, v, pb, gb, lo, hi, vmax, c1, c2, clamp):
    """Velocity and position update of particle ``i`` (clamped to ``vmax`` and to the box)."""
    for j in range(x.shape[1]):
        vv = wk * v[i, j] + c1 * rnd_s[0, i, j] * (pb[i, j] - x[i, j])
        vv = vv + c2 * rnd_s[1, i, j] * (gb[j] - x[i, j])
        if clamp:
            vv = min(max(vv, -vmax[j]), vmax[j])
        v[i, j] = vv
        x[i, j] = min(max(x[i, j] + vv, lo[j]), hi[j])


@njit(**_TAKES_KERNELS)
def pso_iterations(res, p, q, x, v, pb, pf, gb, gf, rnd, w, k0, lo, hi, vmax, coef, state, hist):
    """Up to ``len(w)`` iterations (``k0, k0 + 1, ...``) of one run of ``parakin.solvers.pso`` with
    the random block ``rnd (B, 2, P, N)`` and inertia weights ``w``: the same updates in the same
    order as the numpy loop. ``coef = (c1, c2, ftol, clamp)``; ``state = (running, nfev, nit)``;
    ``gf`` (1,) the best fitness; ``hist[k]`` the best fitness after iteration k."""
    c1, c2, ftol, clamp = coef[0], coef[1], coef[2], coef[3] != 0
    n_particles = x.shape[0]
    r = np.empty(q.shape[0])
    for s in range(w.shape[0]):
        k = k0 + s
        if state[0] == 0:
            hist[k] = gf[0]
            continue
        for i in range(n_particles):
            _pso_move(i, w[s], rnd[s], x, v, pb, gb, lo, hi, vmax, c1, c2, clamp)
            f = _pso_fitness(res, p, x[i], q, r)
            if f < pf[i]:
                pf[i] = f
                _copy(pb[i], x[i])
        gi = 0
        for i in range(1, n_particles):  # first minimum, as argmin
            if pf[i] < pf[gi]:
                gi = i
        _copy(gb, pb[gi])
        gf[0] = pf[gi]
        state[1] += n_particles
        state[2] += 1
        hist[k] = gf[0]
        if not (gf[0] > ftol):
            state[0] = 0


#: the linear algebra every loop shares, which calls no kernel: cached in numba's part of the
#: kernel cache (:func:`parakin.kernels.store.share_compiled`), so that one compiled copy serves
#: every entry. An entry compiled after them links their cached code instead of compiling them
#: again, LAPACK's pseudo-inverse included (about 3 of the 8.6 CPU-s that a fresh process spent on
#: a toy kernel's first Newton solve). Their cache is keyed by this file, which holds all they call
SHARED = (finite, _all_finite, _lu_solve, _solve, _gram, _direction)
