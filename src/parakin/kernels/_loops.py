# Template of the compiled solver loops: parakin.kernels.build() writes this file, with the
# two placeholders below filled in, into the kernel cache and imports it. Not imported itself.
# The kernel module provides residual(p, x, q, out), jacobian(p, x, q, out), ik(p, x, out) -> bool,
# in_domain(p, x) -> bool and on_assembly(p, x, q) -> bool, all numba.njit for one pose.
import math

import numpy as np
from __KERNEL_MODULE__ import ik as IK
from __KERNEL_MODULE__ import in_domain as DOM  # noqa: F401
from __KERNEL_MODULE__ import jacobian as JAC
from __KERNEL_MODULE__ import on_assembly as ASM
from __KERNEL_MODULE__ import residual as RES
from numba import njit, prange  # noqa: F401  (prange: the generated parallel drivers)

M = int("__M__")  # residual equations (filled in by build())
N = int("__N__")  # pose coordinates
_O = dict(cache=True, error_model="numpy", nogil=True)

CONVERGED, SMALL_STEP, SMALL_GRADIENT = 0, 1, 2
MAXITER, NONFINITE, STALLED = -1, -2, -3
RUNNING = 127
# options vector: tol, maxiter, xtol, gtol, tau, c1, shrink, maxls, reg
TOL, MAXIT, XTOL, GTOL, TAU, C1, SHRINK, MAXLS, REG = 0, 1, 2, 3, 4, 5, 6, 7, 8


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
def _finite(v):
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


@njit(**_O)
def _eval(p, x, q, r):
    """Residual at ``x`` (NaN, not counted, where ``x`` is not finite); returns 1 if evaluated."""
    if _finite(x):
        RES(p, x, q, r)
        return 1
    r[:] = math.nan
    return 0


@njit(**_O)
def _checked(x, r):
    """``(|r|_inf, x and r finite)``: what the stopping rule (:func:`_code`) is given."""
    res = _infnorm(r)
    return res, _finite(x) and math.isfinite(res)


@njit(**_O)
def _max_diag(a):
    """``max_i a[i, i]``, NaN propagating."""
    big = -math.inf
    for i in range(N):
        if not a[i, i] <= big:
            big = a[i, i]
    return big


@njit(**_O)
def _solve(a, b, out, w):
    """``a out = b`` for square ``a`` (n, n): LU with partial pivoting; minimum-norm least squares
    ``pinv(a) b`` where ``a`` is exactly singular; NaN where ``a`` or ``b`` is not finite."""
    n = b.shape[0]
    for i in range(n):
        if not math.isfinite(b[i]):
            out[:] = math.nan
            return
        for j in range(n):
            if not math.isfinite(a[i, j]):
                out[:] = math.nan
                return
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
            out[:] = np.linalg.pinv(a) @ b
            return
        if piv != k:
            for j in range(k, n + 1):
                t = w[k, j]
                w[k, j] = w[piv, j]
                w[piv, j] = t
        for i in range(k + 1, n):
            f = w[i, k] / w[k, k]
            for j in range(k + 1, n + 1):
                w[i, j] -= f * w[k, j]
    for i in range(n - 1, -1, -1):
        s = w[i, n]
        for j in range(i + 1, n):
            s -= w[i, j] * out[j]
        out[i] = s / w[i, i]


@njit(**_O)
def _gram(jac, r, a, g):
    """``a = J^T J``, ``g = J^T r``."""
    for i in range(N):
        s = 0.0
        for k in range(M):
            s += jac[k, i] * r[k]
        g[i] = s
        for j in range(i, N):
            s = 0.0
            for k in range(M):
                s += jac[k, i] * jac[k, j]
            a[i, j] = s
            a[j, i] = s


@njit(**_O)
def _direction(jac, r, out, w, a, g):
    """``J^-1 r`` (square, :func:`_solve`) or, for ``m > n``, the least-squares step from the normal
    equations ``J^T J out = J^T r`` (``pinv(J) r`` where ``J^T J`` is singular)."""
    if M == N:
        _solve(jac, r, out, w)
        return
    if not _finite(r):
        out[:] = math.nan
        return
    for k in range(M):
        for i in range(N):
            if not math.isfinite(jac[k, i]):
                out[:] = math.nan
                return
    _gram(jac, r, a, g)
    if not _solve_or_flag(a, g, out, w):
        out[:] = np.linalg.pinv(jac) @ r


@njit(**_O)
def _solve_or_flag(a, b, out, w):
    """LU solve of a finite square system; False (``out`` untouched) where it is singular."""
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
        for i in range(k + 1, n):
            f = w[i, k] / w[k, k]
            for j in range(k + 1, n + 1):
                w[i, j] -= f * w[k, j]
    for i in range(n - 1, -1, -1):
        s = w[i, n]
        for j in range(i + 1, n):
            s -= w[i, j] * out[j]
        out[i] = s / w[i, i]
    return True


@njit(**_O)
def _start(p, q, x0, x, r, opts, info):
    """Residual at the start; returns the status (CONVERGED, NONFINITE or RUNNING) and its norm."""
    x[:] = x0
    info[2] += _eval(p, x, q, r)
    res = _infnorm(r)
    if res <= opts[TOL]:
        return CONVERGED, res
    if not math.isfinite(res):
        return NONFINITE, res
    return RUNNING, res


@njit(**_O)
def _code(opts, step, grad, stalled, new_res, finite):
    code = RUNNING
    if opts[XTOL] > 0 and step <= opts[XTOL]:
        code = SMALL_STEP
    if opts[GTOL] > 0 and grad <= opts[GTOL]:
        code = SMALL_GRADIENT
    if stalled:
        code = STALLED
    if new_res <= opts[TOL]:
        code = CONVERGED
    if not finite:
        code = NONFINITE
    return code


# ---------------------------------------------------------------------------- Newton
@njit(**_O)
def newton_row(p, q, x0, opts, x, info):
    """Newton-Raphson on one pose (see parakin.solvers.newton); info = status, nit, nfev, njev."""
    r = np.empty(M)
    rt = np.empty(M)
    xt = np.empty(N)
    w = np.empty((N, N + 1))
    a = np.empty((N, N))
    g = np.empty(N)
    jac = np.empty((M, N))
    dx = np.empty(N)
    status, res = _start(p, q, x0, x, r, opts, info)
    for _ in range(int(opts[MAXIT])):
        if status != RUNNING:
            break
        JAC(p, x, q, jac)
        info[3] += 1
        _direction(jac, r, dx, w, a, g)
        for i in range(N):
            xt[i] = x[i] - dx[i]
        info[2] += _eval(p, xt, q, rt)
        info[1] += 1
        new_res, finite = _checked(xt, rt)
        status = _code(opts, _infnorm(dx), math.nan, False, new_res, finite)
        if finite:
            x[:] = xt
            r[:] = rt
            res = new_res
    info[0] = MAXITER if status == RUNNING else status
    return res


# ---------------------------------------------------------------------------- Levenberg-Marquardt
@njit(**_O)
def lm_row(p, q, x0, opts, x, info):
    """Levenberg-Marquardt with Nielsen's damping on one pose (see parakin.solvers.lm)."""
    r = np.empty(M)
    rt = np.empty(M)
    xt = np.empty(N)
    w = np.empty((N, N + 1))
    a = np.empty((N, N))
    g = np.empty(N)
    jac = np.empty((M, N))
    h = np.empty(N)
    mg = np.empty(N)
    damped = np.empty((N, N))
    status, res = _start(p, q, x0, x, r, opts, info)
    mu = 0.0
    nu = 2.0
    if status == RUNNING:
        JAC(p, x, q, jac)
        info[3] += 1
        _gram(jac, r, a, g)
        mu = opts[TAU] * _max_diag(a)
        if mu < 2.2250738585072014e-308:
            mu = 2.2250738585072014e-308
    for _ in range(int(opts[MAXIT])):
        if status != RUNNING:
            break
        for i in range(N):
            for j in range(N):
                damped[i, j] = a[i, j]
            damped[i, i] += mu
            mg[i] = -g[i]
        _solve(damped, mg, h, w)
        for i in range(N):
            xt[i] = x[i] + h[i]
        info[2] += _eval(p, xt, q, rt)
        info[1] += 1
        predicted = 0.0
        for i in range(N):
            predicted += h[i] * (mu * h[i] - g[i])
        predicted *= 0.5
        rho = (0.5 * _dot(r, r) - 0.5 * _dot(rt, rt)) / predicted
        ok = rho > 0
        if ok:
            x[:] = xt
            r[:] = rt
            JAC(p, x, q, jac)
            info[3] += 1
            _gram(jac, r, a, g)
            t = 2.0 * rho - 1.0
            mu = mu * max(1.0 / 3.0, 1.0 - t * t * t)
            nu = 2.0
        else:
            mu = mu * nu
            nu = 2.0 * nu
        new_res, finite = _checked(x, r)
        status = _code(opts, _infnorm(h), _infnorm(g), False, new_res, finite)
        if finite:
            res = new_res
    info[0] = MAXITER if status == RUNNING else status
    return res


# ---------------------------------------------------------------------------- Broyden
@njit(**_O)
def broyden_row(p, q, x0, opts, x, info):
    """Broyden's good method on one pose (see parakin.solvers.quasi_newton.broyden)."""
    r = np.empty(M)
    rt = np.empty(M)
    xt = np.empty(N)
    w = np.empty((N, N + 1))
    a = np.empty((N, N))
    g = np.empty(N)
    b = np.empty((M, N))
    d = np.empty(N)
    u = np.empty(M)
    status, res = _start(p, q, x0, x, r, opts, info)
    if status == RUNNING:
        JAC(p, x, q, b)
        info[3] += 1
    for _ in range(int(opts[MAXIT])):
        if status != RUNNING:
            break
        _direction(b, r, d, w, a, g)
        for i in range(N):
            d[i] = -d[i]
            xt[i] = x[i] + d[i]
        info[2] += _eval(p, xt, q, rt)
        info[1] += 1
        dd = _dot(d, d)
        gain = 1.0 / dd if dd > 0 else 0.0
        for k in range(M):
            s = 0.0
            for i in range(N):
                s += b[k, i] * d[i]
            u[k] = (rt[k] - r[k] - s) * gain
        new_res, finite = _checked(xt, rt)
        status = _code(opts, _infnorm(d), math.nan, False, new_res, finite)
        if finite:
            for k in range(M):
                for i in range(N):
                    b[k, i] += u[k] * d[i]
            x[:] = xt
            r[:] = rt
            res = new_res
    info[0] = MAXITER if status == RUNNING else status
    return res


# ---------------------------------------------------------------------------- BFGS
@njit(**_O)
def bfgs_row(p, q, x0, opts, x, info):
    """BFGS with Armijo backtracking on |r|^2 / 2 for one pose (see parakin.solvers.quasi_newton.bfgs)."""
    r = np.empty(M)
    rt = np.empty(M)
    xt = np.empty(N)
    w = np.empty((N, N + 1))
    a = np.empty((N, N))
    g = np.empty(N)
    jac = np.empty((M, N))
    hh = np.empty((N, N))
    gn = np.empty(N)
    pp = np.empty(N)
    y = np.empty(N)
    d = np.empty(N)
    hy = np.empty(N)
    e = np.empty(N)
    col = np.empty(N)
    status, res = _start(p, q, x0, x, r, opts, info)
    if status == RUNNING:
        JAC(p, x, q, jac)
        info[3] += 1
        _gram(jac, r, a, g)
        big = _max_diag(a)
        if big < 1.0e-300:
            big = 1.0e-300
        lam = opts[REG] * big
        for i in range(N):
            a[i, i] += lam
        for j in range(N):
            e[:] = 0.0
            e[j] = 1.0
            _solve(a, e, col, w)
            hh[:, j] = col
    c1, shrink, maxls = opts[C1], opts[SHRINK], int(opts[MAXLS])
    sqeps = math.sqrt(2.220446049250313e-16)
    for _ in range(int(opts[MAXIT])):
        if status != RUNNING:
            break
        for i in range(N):
            s = 0.0
            for j in range(N):
                s += hh[i, j] * g[j]
            pp[i] = -s
        slope = _dot(g, pp)
        if not slope < 0:
            for i in range(N):
                pp[i] = -g[i]
            slope = -_dot(g, g)
        f0 = 0.5 * _dot(r, r)
        alpha = 1.0
        found = False
        for _ls in range(maxls):
            for i in range(N):
                xt[i] = x[i] + alpha * pp[i]
            info[2] += _eval(p, xt, q, rt)
            if 0.5 * _dot(rt, rt) <= f0 + c1 * alpha * slope:
                found = True
                break
            alpha *= shrink
        gn[:] = g
        if found:
            JAC(p, xt, q, jac)
            info[3] += 1
            for i in range(N):
                s = 0.0
                for k in range(M):
                    s += jac[k, i] * rt[k]
                gn[i] = s
        for i in range(N):
            d[i] = alpha * pp[i] if found else 0.0
            y[i] = gn[i] - g[i]
        yd = _dot(y, d)
        size = math.sqrt(_dot(y, y)) * math.sqrt(_dot(d, d))
        rho = 1.0 / yd if yd > sqeps * size else 0.0
        for i in range(N):
            s = 0.0
            for j in range(N):
                s += hh[i, j] * y[j]
            hy[i] = s
        coef = rho * rho * _dot(y, hy) + rho
        for i in range(N):
            for j in range(N):
                hh[i, j] = hh[i, j] - rho * (d[i] * hy[j] + hy[i] * d[j]) + coef * d[i] * d[j]
        g[:] = gn
        if found:
            x[:] = xt
            r[:] = rt
        info[1] += 1
        step = 0.0
        for i in range(N):
            v = abs(alpha * pp[i])
            if v != v or v > step:
                step = v
        new_res, finite = _checked(x, r)
        status = _code(opts, step, _infnorm(g), not found, new_res, finite)
        if finite:
            res = new_res
    info[0] = MAXITER if status == RUNNING else status
    return res


# ---------------------------------------------------------------------------- verification
@njit(**_O)
def verify_row(p, q, x, flags):
    """flags[0] = in domain, flags[1] = on assembly; returns max |ik(x) - q| (inf outside)."""
    flags[0] = 0
    flags[1] = 0
    if not (_finite(x) and DOM(p, x)):
        return math.inf
    flags[0] = 1
    flags[1] = 1 if ASM(p, x, q) else 0
    out = np.empty(M)
    if not IK(p, x, out):
        return math.inf
    err = 0.0
    for k in range(M):
        v = abs(out[k] - q[k])
        if v != v:
            return math.inf
        if v > err:
            err = v
    return err


# ---------------------------------------------------------------------------- particle swarm
@njit(**_O)
def _pso_fitness(p, x, q, r):
    """Li 2020's eq. (20), ``sum |f_j|`` (inf where not finite), as ``parakin.solvers.pso``."""
    if not _finite(x):
        return math.inf
    RES(p, x, q, r)
    s = 0.0
    for k in range(M):
        s += abs(r[k])
    return s if math.isfinite(s) else math.inf


@njit(**_O)
def pso_row(p, q, x, v, pb, pf, gb, gf, rnd, w, k0, lo, hi, vmax, coef, state, hist):
    """Up to ``len(w)`` iterations (``k0, k0 + 1, ...``) of one run of ``parakin.solvers.pso`` with
    the random block ``rnd (B, 2, P, N)`` and inertia weights ``w``: the same updates in the same
    order as the numpy loop. ``coef = (c1, c2, ftol, clamp)``; ``state = (running, nfev, nit)``;
    ``gf`` (1,) the best fitness; ``hist[k]`` the best fitness after iteration k."""
    c1, c2, ftol, clamp = coef[0], coef[1], coef[2], coef[3] != 0
    P = x.shape[0]
    r = np.empty(M)
    for s in range(w.shape[0]):
        k = k0 + s
        if state[0] == 0:
            hist[k] = gf[0]
            continue
        wk = w[s]
        for i in range(P):
            for j in range(N):
                vv = wk * v[i, j] + c1 * rnd[s, 0, i, j] * (pb[i, j] - x[i, j])
                vv = vv + c2 * rnd[s, 1, i, j] * (gb[j] - x[i, j])
                if clamp:
                    vv = min(max(vv, -vmax[j]), vmax[j])
                v[i, j] = vv
                x[i, j] = min(max(x[i, j] + vv, lo[j]), hi[j])
            f = _pso_fitness(p, x[i], q, r)
            if f < pf[i]:
                pf[i] = f
                for j in range(N):
                    pb[i, j] = x[i, j]
        gi = 0
        for i in range(1, P):  # first minimum, as argmin
            if pf[i] < pf[gi]:
                gi = i
        for j in range(N):
            gb[j] = pb[gi, j]
        gf[0] = pf[gi]
        state[1] += P
        state[2] += 1
        hist[k] = gf[0]
        if not (gf[0] > ftol):
            state[0] = 0


# ---------------------------------------------------------------------------- batches
# __BATCH__ (build() appends a serial and a prange-parallel driver per solver, for verify_row and
# for pso_row (pso_serial, pso_parallel: rows independent, own random numbers and weights) here)
