"""Compiled all-solutions forward kinematics of the 3-6 Stewart platform (``Stewart36.fk_all``).

The same method as the numpy path (docs/li2017_stewart36.md#s1.5), one input per call and no
numpy temporaries: circles and biquadratics, the degree-16 polynomial in ``t1`` from 32 Sylvester
determinants on the unit circle and a discrete Fourier transform, its roots, ``t2``/``t3`` by
back-substitution, complex Newton on the biquadratics, the recovery scan for roots merged in
near-multiple clusters, poses polished by Newton and kept where ``max |IK - L| <= 1e-9``, then
duplicates removed and the solutions sorted by ``Z`` descending.

One difference of method: the polynomial's roots come from Aberth-Ehrlich iterations (simultaneous
Newton with repulsion) instead of companion-matrix eigenvalues, ten times cheaper here and as
accurate; complex Newton on the biquadratics then refines both to the same solutions. Results
agree with the numpy path to rounding (``tests/test_kernels_all.py``).

Self-contained (no calls into :mod:`parakin.kernels.stewart36`): numba's on-disk cache watches only
the file a function is defined in. ``p`` (see :func:`params`): the platform point of each leg in
the moving frame (``p[0:18]``), the base points (``p[18:36]``), the top side ``a`` (``p[36]``) and
the home pose (``p[37:43]``, the polish's start for non-real roots, unused).
"""

from __future__ import annotations

import cmath
import math
import os

import numba
import numpy as np
from numba import njit

from parakin.kernels import store, threads

if "NUMBA_THREADING_LAYER" not in os.environ:  # fork-safe, as parakin.kernels.build
    numba.config.THREADING_LAYER = "workqueue"

_O = dict(cache=True, error_model="numpy", nogil=True)

#: samples of the resultant on the unit circle (as ``Stewart36.fk_poly``'s default)
SAMPLES = 32
#: as ``parakin.mechanisms.stewart36.RECOVER_WIDTH, RECOVER_POINTS`` (checked by the tests)
RECOVER_WIDTH, RECOVER_POINTS = 0.05, 4001
#: as ``parakin.mechanisms.stewart36.CONVERGED, DISTINCT`` (checked by the tests)
CONVERGED, DISTINCT = 1e-10, 1e-6
#: Aberth-Ehrlich: at most this many sweeps; a root is done when its step is below ABERTH_TOL * (1 + |z|)
ABERTH_MAXIT, ABERTH_TOL = 80, 1e-13
# info columns: ints (n_complex, n_real, n_above, unresolved), floats (ik_error, tail)


def params(top: np.ndarray, base: np.ndarray, a: float, home: np.ndarray) -> np.ndarray:
    """The parameter vector ``p`` from the legs' platform points (6, 3), base points (6, 3), the top
    side and the home pose."""
    return np.concatenate([np.ravel(top), np.ravel(base), [float(a)], np.ravel(home)]).astype(
        np.float64
    )


@njit(**_O)
def _circles(p, q, c, r, u):
    """Centre ``c`` (3, 3), radius ``r`` (3) and in-plane normal ``u`` (3, 3) of each A_k's circle;
    False where a radius is not real (or not finite)."""
    ok = True
    for k in range(3):
        b0 = 18 + 6 * k
        e0 = p[b0 + 3] - p[b0]
        e1 = p[b0 + 4] - p[b0 + 1]
        e2 = p[b0 + 5] - p[b0 + 2]
        d = math.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
        e0 /= d
        e1 /= d
        e2 /= d
        l1, l2 = q[2 * k], q[2 * k + 1]
        s = (l1 * l1 - l2 * l2 + d * d) / (2 * d)
        rr = l1 * l1 - s * s
        if not (rr >= 0 and math.isfinite(rr)):
            ok = False
            rr = math.nan
        r[k] = math.sqrt(rr)
        c[k, 0] = p[b0] + s * e0
        c[k, 1] = p[b0 + 1] + s * e1
        c[k, 2] = p[b0 + 2] + s * e2
        u[k, 0] = -e1  # cross(z, e)
        u[k, 1] = e0
        u[k, 2] = 0.0
    return ok


@njit(**_O)
def _biquadratics(c, r, u, a, g):
    """``g[k, p, q]``: E_ij (pairs (0,1), (1,2), (0,2)) times (1+ti^2)(1+tj^2) at ti^p tj^q."""
    g[:] = 0.0
    for k in range(3):
        i = 1 if k == 1 else 0
        j = 1 if k == 0 else 2
        c0 = c[i, 0] - c[j, 0]
        c1 = c[i, 1] - c[j, 1]
        c2 = c[i, 2] - c[j, 2]
        k0 = c0 * c0 + c1 * c1 + c2 * c2 + r[i] ** 2 + r[j] ** 2 - a * a
        pp = 2 * r[i] * (c0 * u[i, 0] + c1 * u[i, 1] + c2 * u[i, 2])
        qq = -2 * r[j] * (c0 * u[j, 0] + c1 * u[j, 1] + c2 * u[j, 2])
        m = -2 * r[i] * r[j] * (u[i, 0] * u[j, 0] + u[i, 1] * u[j, 1] + u[i, 2] * u[j, 2])
        n = -2 * r[i] * r[j]
        g[k, 0, 0] = k0 + qq + pp + m
        g[k, 2, 0] = k0 + qq - pp - m
        g[k, 0, 2] = k0 - qq + pp - m
        g[k, 2, 2] = k0 - qq - pp + m
        g[k, 1, 1] = 4 * n


@njit(**_O)
def _det(m):
    """Determinant of the square complex ``m`` (destroyed): LU with partial pivoting."""
    n = m.shape[0]
    det = 1.0 + 0.0j
    for k in range(n):
        piv = k
        best = abs(m[k, k])
        for i in range(k + 1, n):
            a = abs(m[i, k])
            if a > best:
                best, piv = a, i
        if best == 0.0:
            return 0.0j
        if piv != k:
            det = -det
            for j in range(k, n):
                m[k, j], m[piv, j] = m[piv, j], m[k, j]
        d = m[k, k]
        det *= d
        for i in range(k + 1, n):
            f = m[i, k] / d
            if f != 0:
                for j in range(k + 1, n):
                    m[i, j] -= f * m[k, j]
    return det


@njit(**_O)
def _fk_poly(g, ts, tw, coef, syl):
    """Coefficients (ascending, ``SAMPLES``) of ``Res_t3(Res_t2(E12, E23), E13)`` in ``t1``, as
    ``Stewart36.fk_poly``: Sylvester determinants at the sample points ``ts``, then a DFT
    (twiddles ``tw[m] = exp(-2 pi i m / SAMPLES)``)."""
    ns = ts.shape[0]
    vals = np.empty(ns, dtype=np.complex128)
    rr = np.empty(5, dtype=np.complex128)
    # g is real and the system even in t1, so vals(conj t) = conj vals(t) and vals(-t) = vals(t):
    # the first quarter of the circle (9 of the 32 samples) gives the others
    for s in range(ns // 4 + 1):
        t = ts[s]
        t2 = t * t
        # E12 as a quadratic in t2 and E13 as a quadratic in t3, at t1 = t
        a0 = g[0, 0, 0] + g[0, 1, 0] * t + g[0, 2, 0] * t2
        a1 = g[0, 0, 1] + g[0, 1, 1] * t + g[0, 2, 1] * t2
        a2 = g[0, 0, 2] + g[0, 1, 2] * t + g[0, 2, 2] * t2
        e0 = g[2, 0, 0] + g[2, 1, 0] * t + g[2, 2, 0] * t2
        e1 = g[2, 0, 1] + g[2, 1, 1] * t + g[2, 2, 1] * t2
        e2 = g[2, 0, 2] + g[2, 1, 2] * t + g[2, 2, 2] * t2
        # Res_t2(E12, E23) = (a2 c0 - a0 c2)^2 - (a2 c1 - a1 c2)(a1 c0 - a0 c1), c_p = g[1, p, :] in t3
        x0 = a2 * g[1, 0, 0] - a0 * g[1, 2, 0]
        x1 = a2 * g[1, 0, 1] - a0 * g[1, 2, 1]
        x2 = a2 * g[1, 0, 2] - a0 * g[1, 2, 2]
        y0 = a2 * g[1, 1, 0] - a1 * g[1, 2, 0]
        y1 = a2 * g[1, 1, 1] - a1 * g[1, 2, 1]
        y2 = a2 * g[1, 1, 2] - a1 * g[1, 2, 2]
        z0 = a1 * g[1, 0, 0] - a0 * g[1, 1, 0]
        z1 = a1 * g[1, 0, 1] - a0 * g[1, 1, 1]
        z2 = a1 * g[1, 0, 2] - a0 * g[1, 1, 2]
        # descending powers of t3
        rr[4] = x0 * x0 - y0 * z0
        rr[3] = (x0 * x1 + x1 * x0) - (y0 * z1 + y1 * z0)
        rr[2] = (x0 * x2 + x1 * x1 + x2 * x0) - (y0 * z2 + y1 * z1 + y2 * z0)
        rr[1] = (x1 * x2 + x2 * x1) - (y1 * z2 + y2 * z1)
        rr[0] = x2 * x2 - y2 * z2
        syl[:] = 0.0
        for row in range(2):
            for j in range(5):
                syl[row, row + j] = rr[j]
        for row in range(4):
            syl[2 + row, row] = e2
            syl[2 + row, row + 1] = e1
            syl[2 + row, row + 2] = e0
        vals[s] = _det(syl)
    half = ns // 2
    for s in range(ns // 4 + 1, half):
        vals[s] = vals[half - s].conjugate()
    for s in range(half, ns):
        vals[s] = vals[s - half]
    for k in range(ns):
        acc = 0.0j
        for s in range(ns):
            acc += vals[s] * tw[(k * s) % ns]
        coef[k] = acc / ns


@njit(**_O)
def _aberth(a, k, z):
    """The ``k`` roots ``z[:k]`` of ``sum_m a[m] t^m`` (``a[k] != 0``) by Aberth-Ehrlich sweeps
    (Gauss-Seidel), started on a circle of the roots' geometric-mean radius."""
    lead = abs(a[k])
    a0 = abs(a[0])
    rad = (a0 / lead) ** (1.0 / k) if a0 > 0 else 1.0
    if not (rad > 0 and math.isfinite(rad)):
        rad = 1.0
    for j in range(k):
        z[j] = rad * cmath.exp(1j * (2 * math.pi * j / k + 0.4))
    done = np.zeros(k, dtype=np.bool_)
    for _ in range(ABERTH_MAXIT):
        alldone = True
        for j in range(k):
            if done[j]:
                continue
            zj = z[j]
            pv = a[k]
            dv = 0.0j
            for m in range(k - 1, -1, -1):
                dv = dv * zj + pv
                pv = pv * zj + a[m]
            if pv == 0:
                done[j] = True
                continue
            ratio = pv / dv
            s = 0.0j
            for m in range(k):
                if m != j:
                    s += 1.0 / (zj - z[m])
            w = ratio / (1.0 - ratio * s)
            if not (math.isfinite(w.real) and math.isfinite(w.imag)):
                done[j] = True
                continue
            z[j] = zj - w
            if abs(w) <= ABERTH_TOL * (1.0 + abs(zj)):
                done[j] = True
            else:
                alldone = False
        if alldone:
            break


@njit(**_O)
def _quad_roots(c0, c1, c2):
    """Both roots of ``c0 + c1 t + c2 t^2`` (the stable pair of formulas of ``_quad_roots``)."""
    disc = cmath.sqrt(c1 * c1 - 4 * c2 * c0)
    v = c1.real * disc.real + c1.imag * disc.imag  # Re(conj(c1) disc)
    sgn = 1.0 if v >= 0 else -1.0
    qq = -0.5 * (c1 + sgn * disc)
    return qq / c2, c0 / qq


@njit(**_O)
def _real_quad_roots(c0, c1, c2):
    """``_quad_roots`` for real coefficients in real arithmetic: ``(r0, r1, ok)``, ``ok`` where
    both roots are finite with imaginary parts below 1e-12 (as the numpy scan's test; a complex
    pair that close to real is taken at its real part)."""
    disc = c1 * c1 - 4 * c2 * c0
    if disc < 0:
        if math.sqrt(-disc) / (2 * abs(c2)) >= 1e-12:
            return math.nan, math.nan, False
        r = -c1 / (2 * c2)
        return r, r, math.isfinite(r)
    sd = math.sqrt(disc)
    qq = -0.5 * (c1 + sd) if c1 * sd >= 0 else -0.5 * (c1 - sd)
    r0 = qq / c2
    r1 = c0 / qq
    return r0, r1, math.isfinite(r0) and math.isfinite(r1)


@njit(**_O)
def _bq(g, k, ti, tj):
    """Biquadratic ``sum_pq g[k, p, q] ti^p tj^q``."""
    ti2 = ti * ti
    tj2 = tj * tj
    return (
        (g[k, 0, 0] + g[k, 0, 1] * tj + g[k, 0, 2] * tj2)
        + (g[k, 1, 0] + g[k, 1, 1] * tj + g[k, 1, 2] * tj2) * ti
        + (g[k, 2, 0] + g[k, 2, 1] * tj + g[k, 2, 2] * tj2) * ti2
    )


@njit(**_O)
def _nmax(a, b):
    """``max`` propagating NaN (as ``np.max``; Python's ``max(0.0, nan)`` is 0.0)."""
    if a != a or b != b:
        return math.nan
    return a if a >= b else b


@njit(**_O)
def _cfinite(z):
    return math.isfinite(z.real) and math.isfinite(z.imag)


@njit(**_O)
def _back_substitute(g, t1, out):
    """``(t1, t2, t3)``: t2 from E12, t3 from E13, the pair of roots minimising ``|E23|``."""
    t1s = t1 * t1
    r2 = _quad_roots(
        g[0, 0, 0] + g[0, 1, 0] * t1 + g[0, 2, 0] * t1s,
        g[0, 0, 1] + g[0, 1, 1] * t1 + g[0, 2, 1] * t1s,
        g[0, 0, 2] + g[0, 1, 2] * t1 + g[0, 2, 2] * t1s,
    )
    r3 = _quad_roots(
        g[2, 0, 0] + g[2, 1, 0] * t1 + g[2, 2, 0] * t1s,
        g[2, 0, 1] + g[2, 1, 1] * t1 + g[2, 2, 1] * t1s,
        g[2, 0, 2] + g[2, 1, 2] * t1 + g[2, 2, 2] * t1s,
    )
    best = math.inf
    ib, jb = 0, 0
    for i in range(2):
        for j in range(2):
            e = abs(_bq(g, 1, r2[i], r3[j]))
            if not math.isfinite(e):
                e = math.inf
            if e < best:
                best, ib, jb = e, i, j
    out[0] = t1
    out[1] = r2[ib]
    out[2] = r3[jb]


@njit(**_O)
def _newton_update(g, t, jac, f):
    """One complex Newton update of triple ``t`` on ``(E12(t1,t2), E23(t2,t3), E13(t1,t3)) = 0``
    into ``f``; False (no update) where the Jacobian is not finite or ``|det| <= 1e-300``."""
    for row in range(3):
        i = 1 if row == 1 else 0
        j = 1 if row == 0 else 2
        ti, tj = t[i], t[j]
        pi1, pi2 = ti, ti * ti
        pj1, pj2 = tj, tj * tj
        fv = 0.0j
        di = 0.0j
        dj = 0.0j
        for a in range(3):
            pa = 1.0 if a == 0 else (pi1 if a == 1 else pi2)
            da = 0.0 if a == 0 else (1.0 if a == 1 else 2 * pi1)
            for b in range(3):
                gab = g[row, a, b]
                pb = 1.0 if b == 0 else (pj1 if b == 1 else pj2)
                db = 0.0 if b == 0 else (1.0 if b == 1 else 2 * pj1)
                fv += gab * pa * pb
                di += gab * da * pb
                dj += gab * pa * db
        f[row] = fv
        for col in range(3):
            jac[row, col] = 0.0
        jac[row, i] = di
        jac[row, j] = dj
    for row in range(3):
        if not _cfinite(f[row]):
            return False
        for col in range(3):
            if not _cfinite(jac[row, col]):
                return False
    # LU with partial pivoting; |det| from the pivots
    det = 1.0
    for k in range(3):
        piv = k
        best = abs(jac[k, k])
        for i in range(k + 1, 3):
            a = abs(jac[i, k])
            if a > best:
                best, piv = a, i
        det *= best
        if best == 0.0:
            break
        if piv != k:
            for col in range(3):
                jac[k, col], jac[piv, col] = jac[piv, col], jac[k, col]
            f[k], f[piv] = f[piv], f[k]
        for i in range(k + 1, 3):
            m = jac[i, k] / jac[k, k]
            for col in range(k + 1, 3):
                jac[i, col] -= m * jac[k, col]
            f[i] -= m * f[k]
    if not (det > 1e-300):
        return False
    for k in range(2, -1, -1):
        acc = f[k]
        for col in range(k + 1, 3):
            acc -= jac[k, col] * f[col]
        f[k] = acc / jac[k, k]
    return True


@njit(**_O)
def _newton_t(g, t, steps, jac, f):
    """Complex Newton (:func:`_newton_update`) on one triple, in place, at most ``steps``
    updates."""
    for _ in range(steps):
        if not _newton_update(g, t, jac, f):
            continue
        small = True
        for k in range(3):
            t[k] -= f[k]
            if not (abs(f[k]) <= 1e-16 * (1 + abs(t[k]))):
                small = False
        if small:  # converged: further steps change t by rounding only
            break


@njit(**_O)
def _unresolved(g, t, nroot, jac, f):
    """As ``parakin.mechanisms.stewart36._unresolved`` for one input: whether the finite refined
    triples are not all converged (one more nonsingular Newton update below ``CONVERGED``) and
    pairwise distinct (by ``DISTINCT``)."""
    one = np.empty(3, dtype=np.complex128)
    scale = np.empty(nroot)
    fin = np.empty(nroot, dtype=np.bool_)
    for j in range(nroot):
        fin[j] = _cfinite(t[j, 0]) and _cfinite(t[j, 1]) and _cfinite(t[j, 2])
        scale[j] = 1.0 + _nmax(_nmax(abs(t[j, 0]), abs(t[j, 1])), abs(t[j, 2]))
    for j in range(nroot):
        if not fin[j]:
            continue
        for k in range(3):
            one[k] = t[j, k]
        if not _newton_update(g, one, jac, f):
            return True
        moved = _nmax(_nmax(abs(f[0]), abs(f[1])), abs(f[2])) / scale[j]
        if not (moved < CONVERGED):
            return True
        for i in range(j):
            if fin[i]:
                d = _nmax(
                    _nmax(abs(t[j, 0] - t[i, 0]), abs(t[j, 1] - t[i, 1])), abs(t[j, 2] - t[i, 2])
                )
                if d < DISTINCT * _nmax(scale[i], scale[j]):
                    return True
    return False


@njit(**_O)
def _is_real(t):
    for k in range(3):
        z = t[k]
        if not _cfinite(z) or abs(z.imag) > 1e-6 * (1 + abs(z)):
            return False
    return True


@njit(**_O)
def _close(t, j, i):
    """Whether triple ``t[j]`` lies within 1e-7 (relative to ``t[i]``) of ``t[i]``."""
    d = 0.0
    mx = 0.0
    for k in range(3):
        d = _nmax(d, abs(t[j, k] - t[i, k]))
        mx = _nmax(mx, abs(t[i, k]))
    return d < 1e-7 * (1 + mx)


@njit(**_O)
def _recover(g, t, nroot, steps, jac, f):
    """``_recover_merged`` for one input: replace each real duplicate (a root lost in a
    near-multiple cluster) by the first new real root found by scanning ``E23`` along real ``t1``
    around it."""
    real = np.zeros(nroot, dtype=np.bool_)
    for j in range(nroot):
        real[j] = _is_real(t[j])
    dup = np.zeros(nroot, dtype=np.bool_)
    anydup = False
    for j in range(nroot):
        if real[j]:
            for i in range(j):
                if real[i] and _close(t, j, i):
                    dup[j] = True
                    anydup = True
                    break
    if not anydup:
        return
    npts = RECOVER_POINTS
    t2s = np.empty((npts, 2))
    t3s = np.empty((npts, 2))
    ok2 = np.empty(npts, dtype=np.bool_)
    ok3 = np.empty(npts, dtype=np.bool_)
    hr = np.empty(npts)
    ok = np.empty(npts, dtype=np.bool_)
    one = np.empty((1, 3), dtype=np.complex128)
    for j in range(nroot):
        if not dup[j]:
            continue
        c0 = t[j, 0].real
        w = RECOVER_WIDTH * (1 + abs(c0))
        grid = np.linspace(c0 - w, c0 + w, npts)
        for k in range(npts):  # real t1: real coefficients, real arithmetic
            x = grid[k]
            x2 = x * x
            t2s[k, 0], t2s[k, 1], ok2[k] = _real_quad_roots(
                g[0, 0, 0] + g[0, 1, 0] * x + g[0, 2, 0] * x2,
                g[0, 0, 1] + g[0, 1, 1] * x + g[0, 2, 1] * x2,
                g[0, 0, 2] + g[0, 1, 2] * x + g[0, 2, 2] * x2,
            )
            t3s[k, 0], t3s[k, 1], ok3[k] = _real_quad_roots(
                g[2, 0, 0] + g[2, 1, 0] * x + g[2, 2, 0] * x2,
                g[2, 0, 1] + g[2, 1, 1] * x + g[2, 2, 1] * x2,
                g[2, 0, 2] + g[2, 1, 2] * x + g[2, 2, 2] * x2,
            )
        # candidates in the numpy path's order (branch a, branch b, grid point), each refined as
        # soon as it is found: the first new real root ends the scan (later ones never count)
        found = False
        for a in range(2):
            for b in range(2):
                for k in range(npts):
                    if ok2[k] and ok3[k]:
                        h = _bq(g, 1, t2s[k, a], t3s[k, b])
                        hr[k] = h
                        ok[k] = math.isfinite(h)
                    else:
                        hr[k] = math.nan
                        ok[k] = False
                for k in range(npts - 1):
                    if ok[k] and ok[k + 1] and np.sign(hr[k]) != np.sign(hr[k + 1]):
                        fr = hr[k] / (hr[k] - hr[k + 1])
                        one[0, 0] = grid[k] + fr * (grid[k + 1] - grid[k])
                        one[0, 1] = t2s[k, a]
                        one[0, 2] = t3s[k, b]
                        _newton_t(g, one[0], steps, jac, f)
                        if _is_real(one[0]) and _is_new(t, nroot, one[0]):
                            for c in range(t.shape[1]):  # no slice from an array (drivers._copy)
                                t[j, c] = one[0, c]
                            found = True
                            break
                if found:
                    break
            if found:
                break


@njit(**_O)
def _is_new(t, nroot, cand):
    """Whether ``cand`` lies farther than 1e-7 (relative) from every real triple of ``t``."""
    for i in range(nroot):
        if _is_real(t[i]):
            d = 0.0
            mx = 0.0
            for kk in range(3):
                d = _nmax(d, abs(t[i, kk] - cand[kk]))
                mx = _nmax(mx, abs(cand[kk]))
            if d < 1e-7 * (1 + mx):
                return False
    return True


@njit(**_O)
def _pose_from_t(c, r, u, t, pose):
    """The pose whose platform vertices sit at angles ``theta_k = 2 atan(Re t_k)`` on the circles
    (``Stewart36.pose_from_points``: O_A the centroid, y along A1 - A2, x towards A3, z = x cross y;
    Z-Y-X Euler angles)."""
    pts = np.empty((3, 3))
    for k in range(3):
        th = 2 * math.atan(t[k].real)
        ct, st = math.cos(th), math.sin(th)
        pts[k, 0] = c[k, 0] + r[k] * (ct * u[k, 0])
        pts[k, 1] = c[k, 1] + r[k] * (ct * u[k, 1])
        pts[k, 2] = c[k, 2] + r[k] * (ct * u[k, 2] + st)
    y0 = pts[0, 0] - pts[1, 0]
    y1 = pts[0, 1] - pts[1, 1]
    y2 = pts[0, 2] - pts[1, 2]
    ny = math.sqrt(y0 * y0 + y1 * y1 + y2 * y2)
    y0, y1, y2 = y0 / ny, y1 / ny, y2 / ny
    x0 = pts[2, 0] - 0.5 * (pts[0, 0] + pts[1, 0])
    x1 = pts[2, 1] - 0.5 * (pts[0, 1] + pts[1, 1])
    x2 = pts[2, 2] - 0.5 * (pts[0, 2] + pts[1, 2])
    dd = x0 * y0 + x1 * y1 + x2 * y2
    x0, x1, x2 = x0 - dd * y0, x1 - dd * y1, x2 - dd * y2
    nx = math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
    x0, x1, x2 = x0 / nx, x1 / nx, x2 / nx
    z2 = x0 * y1 - x1 * y0
    pose[0] = math.atan2(x1, x0)
    pose[1] = math.asin(min(max(-x2, -1.0), 1.0))
    pose[2] = math.atan2(y2, z2)
    for k in range(3):
        pose[3 + k] = (pts[0, k] + pts[1, k] + pts[2, k]) / 3


@njit(**_O)
def _legs(p, x, q, f, jac, lengths):
    """Residual ``f_i = |T a_i + O - B_i|^2 - L_i^2``, its Jacobian (as ``Stewart36.jacobian_pose``)
    and the leg lengths at pose ``x``."""
    ca, sa = math.cos(x[0]), math.sin(x[0])
    cb, sb = math.cos(x[1]), math.sin(x[1])
    cc, sc = math.cos(x[2]), math.sin(x[2])
    t0, t1, t2 = ca * cb, ca * sb * sc - sa * cc, ca * sb * cc + sa * sc
    t3, t4, t5 = sa * cb, sa * sb * sc + ca * cc, sa * sb * cc - ca * sc
    t6, t7, t8 = -sb, cb * sc, cb * cc
    for i in range(6):
        a0, a1, a2 = p[3 * i], p[3 * i + 1], p[3 * i + 2]
        w0 = t0 * a0 + t1 * a1 + t2 * a2
        w1 = t3 * a0 + t4 * a1 + t5 * a2
        w2 = t6 * a0 + t7 * a1 + t8 * a2
        v0 = x[3] + w0 - p[18 + 3 * i]
        v1 = x[4] + w1 - p[19 + 3 * i]
        v2 = x[5] + w2 - p[20 + 3 * i]
        s = v0 * v0 + v1 * v1 + v2 * v2
        f[i] = s - q[i] * q[i]
        lengths[i] = math.sqrt(s)
        c0 = w1 * v2 - w2 * v1
        c1 = w2 * v0 - w0 * v2
        c2 = w0 * v1 - w1 * v0
        jac[i, 0] = 2 * c2
        jac[i, 1] = 2 * (ca * c1 - sa * c0)
        jac[i, 2] = 2 * (t0 * c0 + t3 * c1 + t6 * c2)
        jac[i, 3] = 2 * v0
        jac[i, 4] = 2 * v1
        jac[i, 5] = 2 * v2


@njit(**_O)
def _solve6(a, b):
    """``a^-1 b`` in place in ``b`` (LU with partial pivoting, ``a`` destroyed); False if singular."""
    n = 6
    for k in range(n):
        piv = k
        best = abs(a[k, k])
        for i in range(k + 1, n):
            v = abs(a[i, k])
            if v > best:
                best, piv = v, i
        if not (best > 0):
            return False
        if piv != k:
            for j in range(n):
                a[k, j], a[piv, j] = a[piv, j], a[k, j]
            b[k], b[piv] = b[piv], b[k]
        for i in range(k + 1, n):
            m = a[i, k] / a[k, k]
            for j in range(k + 1, n):
                a[i, j] -= m * a[k, j]
            b[i] -= m * b[k]
    for k in range(n - 1, -1, -1):
        acc = b[k]
        for j in range(k + 1, n):
            acc -= a[k, j] * b[j]
        b[k] = acc / a[k, k]
    return True


@njit(**_O)
def fk_all_row(p, q, ts, tw, steps, out, iinfo, finfo):
    """Every real forward solution of one input ``q`` (6) into ``out`` (16, 6), NaN-padded, sorted
    by Z descending; ``iinfo = (n_complex, n_real, n_above, unresolved)`` (:func:`_unresolved`:
    the caller completes those inputs), ``finfo = (ik_error, tail)``."""
    out[:] = math.nan
    iinfo[:] = 0
    finfo[:] = math.nan
    c = np.empty((3, 3))
    r = np.empty(3)
    u = np.empty((3, 3))
    for k in range(6):
        if not math.isfinite(q[k]):
            return
    if not _circles(p, q, c, r, u):
        return
    g = np.empty((3, 3, 3))
    _biquadratics(c, r, u, p[36], g)
    ns = ts.shape[0]
    coef = np.empty(ns, dtype=np.complex128)
    syl = np.empty((6, 6), dtype=np.complex128)
    _fk_poly(g, ts, tw, coef, syl)
    scale = 0.0
    for k in range(17):
        scale = _nmax(scale, abs(coef[k]))
    tail = 0.0
    for k in range(17, ns):
        tail = _nmax(tail, abs(coef[k]))
    finfo[1] = tail / scale
    # The system is invariant under (t1, t2, t3) -> -(t1, t2, t3) (the mirror about the base plane),
    # so the polynomial is even: its roots are +-sqrt of the roots of the degree-8 polynomial in
    # s = t1^2 (odd coefficients are rounding). Mirror pairs come out exactly paired.
    a = np.empty(9, dtype=np.complex128)
    deg = 0
    for k in range(9):
        a[k] = coef[2 * k] / scale
        if abs(a[k]) > 1e-13:
            deg = k
    iinfo[0] = 2 * deg
    if deg < 1:
        return
    sroots = np.empty(8, dtype=np.complex128)
    _aberth(a, deg, sroots)
    roots = np.empty(16, dtype=np.complex128)
    for j in range(deg):
        w = cmath.sqrt(sroots[j])
        roots[2 * j] = w
        roots[2 * j + 1] = -w
    deg = 2 * deg
    t = np.empty((deg, 3), dtype=np.complex128)
    jac = np.empty((3, 3), dtype=np.complex128)
    f = np.empty(3, dtype=np.complex128)
    for j in range(0, deg, 2):  # the mirror root -t1 gives exactly -(t1, t2, t3)
        _back_substitute(g, roots[j], t[j])
        _newton_t(g, t[j], steps, jac, f)
        for k in range(3):
            t[j + 1, k] = -t[j, k]
    _recover(g, t, deg, steps, jac, f)
    iinfo[3] = _unresolved(g, t, deg, jac, f)
    poses = np.full((16, 6), math.nan)
    fr = np.empty(6)
    jr = np.empty((6, 6))
    lengths = np.empty(6)
    for j in range(deg):
        if not _is_real(t[j]):
            continue
        x = poses[j]
        _pose_from_t(c, r, u, t[j], x)
        for _ in range(3):  # Newton polish on the pose
            _legs(p, x, q, fr, jr, lengths)
            if _solve6(jr, fr):
                fin = True
                for k in range(6):
                    if not math.isfinite(fr[k]):
                        fin = False
                if fin:
                    for k in range(6):
                        x[k] -= fr[k]
        for k in range(3):
            x[k] = (x[k] + math.pi) % (2 * math.pi) - math.pi
        _legs(p, x, q, fr, jr, lengths)
        err = 0.0
        for k in range(6):
            err = _nmax(err, abs(lengths[k] - q[k]))
        if not (err <= 1e-9):
            x[:] = math.nan
    for j in range(1, 16):  # dedupe: NaN out a repeat of an earlier (kept) solution
        if not math.isfinite(poses[j, 0]):
            continue
        for i in range(j):
            d = 0.0
            for k in range(6):
                d = _nmax(d, abs(poses[i, k] - poses[j, k]))
            if d < 1e-7:
                poses[j, :] = math.nan
                break
    _sorted_out(p, q, poses, out, iinfo, finfo, fr, jr, lengths)


@njit(**_O)
def _sorted_out(p, q, poses, out, iinfo, finfo, fr, jr, lengths):
    """The kept ``poses`` (16, 6) into ``out`` sorted by Z descending (stable, NaN last) and their
    counts and IK error into ``iinfo[1:3]``, ``finfo[0]``."""
    # stable sort by -Z (NaN last)
    key = np.empty(16)
    order = np.empty(16, dtype=np.int64)
    for j in range(16):
        key[j] = -poses[j, 5] if math.isfinite(poses[j, 5]) else math.inf
        order[j] = j
    for j in range(1, 16):
        oj = order[j]
        kj = key[oj]
        i = j - 1
        while i >= 0 and key[order[i]] > kj:
            order[i + 1] = order[i]
            i -= 1
        order[i + 1] = oj
    n_real = 0
    n_above = 0
    ik_err = -math.inf
    for j in range(16):
        src = poses[order[j]]
        if not math.isfinite(src[0]):
            continue
        for c in range(out.shape[1]):  # no slice from an array (drivers._copy)
            out[j, c] = src[c]
        n_real += 1
        if src[5] > 0:
            n_above += 1
        _legs(p, src, q, fr, jr, lengths)
        e = 0.0
        for k in range(6):
            e = _nmax(e, abs(lengths[k] - q[k]))
        ik_err = max(ik_err, e)
    iinfo[1] = n_real
    iinfo[2] = n_above
    if n_real:
        finfo[0] = ik_err


@njit(**_O)
def fk_all_serial(p, Q, ts, tw, steps, out, iinfo, finfo):
    for i in range(Q.shape[0]):
        fk_all_row(p, Q[i], ts, tw, steps, out[i], iinfo[i], finfo[i])


_TS = np.exp(2j * np.pi * np.arange(SAMPLES) / SAMPLES)  # as Stewart36.fk_poly
_TW = np.exp(-2j * np.pi * np.arange(SAMPLES) / SAMPLES)


def fk_all(p: np.ndarray, joints: np.ndarray, steps: int = 8, parallel: bool | None = None):
    """``(poses (N, 16, 6), info)`` for the flat batch ``joints (N, 6)``: the compiled
    ``Stewart36.fk_all`` (``info`` as there). ``parallel``: blocks of rows on every core (None: by
    batch size, :func:`parakin.kernels.threads.rows`)."""
    q = np.ascontiguousarray(joints, dtype=np.float64).reshape(-1, 6)
    n = len(q)
    out = np.empty((n, 16, 6))
    iinfo = np.zeros((n, 4), dtype=np.int64)
    finfo = np.empty((n, 2))
    args = (np.ascontiguousarray(p, dtype=np.float64), q, _TS, _TW, int(steps), out, iinfo, finfo)
    threads.rows(fk_all_serial, args, (1, 5, 6, 7), parallel=parallel)
    info = {
        "n_complex": iinfo[:, 0].copy(),
        "n_real": iinfo[:, 1].copy(),
        "n_above": iinfo[:, 2].copy(),
        "ik_error": finfo[:, 0].copy(),
        "tail": finfo[:, 1].copy(),
        "unresolved": iinfo[:, 3] == 1,
    }
    return out, info


# one process at a time compiles each of these functions; the others wait and load it
store.share_compiles(vars())
