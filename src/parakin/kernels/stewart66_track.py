"""Compiled path tracker of the 6-6 Gough-Stewart all-solutions FK, paths side by side in lanes.

The fibre homotopy of :class:`parakin.mechanisms.stewart66_homotopy.FiberHomotopy`: only the six
leg constants move, ``c(t) = c0 + t dc + t (1 - t) bend`` (``bend`` 0 for a straight segment), the
quadrics ``Q_m(c) = Q0_m + c_{m-1} E`` (``E`` the identity on the ``e`` block, legs only) and
``H(x, t) = (x^T Q_m(c(t)) x, a . x - 1)`` in an affine chart ``a``.

Layout: every array holds one path per *lane*, the last axis; the arithmetic loops run over the
lanes innermost, on separate real and imaginary parts, so the compiler turns them into SIMD
instructions (8 paths per instruction with AVX-512). Paths of a block share the lanes through a
queue: a lane whose path ends takes the next one, and when the queue is empty the last lane moves
into the freed one (the active lanes stay ``0 .. n-1``). Lanes never mix: a path's arithmetic is
the same whichever lane, block or thread runs it, so results do not depend on the batch or the
number of threads (no fast-math, so no fused operations in one lane and not another).

One step of a path (Timme 2021, "Mixed precision path tracking for polynomial homotopy
continuation", Adv. Comput. Math. 47: the predictor and step-size rule of HomotopyContinuation.jl):

* **Taylor coefficients** ``x_1 .. x_4`` of the path at the current point, from one LU of the
  Jacobian: the system is quadratic in ``x`` and quadratic in ``t``, so order ``k`` solves
  ``J x_k = -r_k`` with ``r_k`` from lower orders (:func:`taylor`); the LU is the corrector's,
  at the point predicted a step before (its error is the corrector's first update, a high-order
  effect on the coefficients);
* **Padé (2, 1) predictor** per coordinate, ``x + s x_1 + s^2 x_2 / (1 - s x_3 / x_2)`` (the
  cubic Taylor polynomial where ``x_2`` vanishes), its local error ``|x_4 - x_3^2 / x_2| s^4``
  and a trust region ``min |x_2 / x_3|`` (the distance to the nearest pole, Trefethen's robust
  Padé), the step ``s = min(beta_tau * trust, (a / (omega * err))^(1/4), 1 - t)``;
* **moving orthogonal chart**: each prediction is rescaled into the chart ``a = conj(x)/|x|``
  of the current point (projective tracking as in HomotopyContinuation.jl: the affine
  representative stays of norm ~1 and the chart adds no poles of its own);
* **corrector**: two chord-Newton updates with the Jacobian at the predicted point (three on the
  step reaching ``t = 1``, whose last update must be below ``end_tol |x|``); accepted when the
  first is below ``kappa |x|`` and each contracts by ``theta`` (or is below the accuracy limit
  ``noise |x|``); ``omega = 2 |d_2| / |d_1|^2`` estimates the Newton constant; a rejected step
  halves.

:func:`track_block` runs a queue of paths; :func:`refine_block` refines every endpoint by Newton and
computes Smale's alpha (:func:`parakin.mechanisms.stewart66_homotopy.certify`) in lanes as well.
"""

from __future__ import annotations

import cmath
import math
import os
from concurrent.futures import ThreadPoolExecutor
from functools import lru_cache

import numba
import numpy as np
from numba import njit

if "NUMBA_THREADING_LAYER" not in os.environ:  # fork-safe, as parakin.kernels.build: the thread
    numba.config.THREADING_LAYER = "workqueue"  # count read below launches numba's thread pool

__all__ = [
    "geometry",
    "track_block",
    "refine_block",
    "fk_all",
    "OPTIONS",
    "options_vector",
    "LANES",
]

_O = dict(cache=True, error_model="numpy", nogil=True)
#: paths side by side in one block (the lanes of the SIMD loops)
LANES = 32
#: the smallest block of paths worth a thread of its own
MIN_BLOCK = 16
#: from this many active lanes on, LU and solves run vectorised over the lanes (below, one lane at
#: a time: a vector loop's set-up costs more than a few lanes' work)
VECTOR_LANES = 12

#: tracking options, in the order of the compiled options vector (:func:`options_vector`)
OPTIONS: dict[str, float] = {
    "a": 0.005,  # predictor error target, in units of the Newton radius 1/omega
    "beta_tau": 0.75,  # fraction of the Padé trust region (pole distance) a step may use
    "kappa": 0.25,  # first corrector update at most kappa |x|
    "theta": 0.25,  # each corrector update at most theta times the previous one
    "omega0": 1.0,  # Newton constant before the first step's estimate
    "hmin": 1e-12,  # a path whose step falls below hmin fails
    "max_steps": 2000.0,  # ... or that takes more predictor-corrector steps
    "end_tol": 1e-9,  # the step reaching t = 1: its last corrector update at most end_tol |x|
    "noise": 1e-11,  # updates below noise |x| pass the contraction test (the accuracy limit)
}

# rows of a block's lane state ``S`` (one column per lane; the Taylor coefficients are in ``T``)
_PR, _PI = 0, 8  # the chart a of the last prediction
_DR, _DI = 16, 22  # dc
_BR, _BI = 28, 34  # bend
_T, _DT, _OM, _STEPS, _REJ, _ITEM, _FRESH = 40, 41, 42, 43, 44, 45, 46
_NS = 47


def options_vector(options: dict | None = None) -> np.ndarray:
    """The options as the compiled code reads them (unknown names are an error)."""
    opts = {**OPTIONS, **(options or {})}
    unknown = set(opts) - set(OPTIONS)
    if unknown:
        raise ValueError(f"unknown tracking option(s) {sorted(unknown)}; known: {list(OPTIONS)}")
    return np.array([float(opts[k]) for k in OPTIONS])


# ------------------------------------------------------------------------------ lane arithmetic
# The loops run over lanes innermost; the sums over the 8 coordinates are written out (a loop there
# would keep the lane loop from being vectorised), so that each lane loop is one long SIMD body.
@njit(inline="always", **_O)
def _row(Q, m, i, v, ln):
    """``sum_j Q[m, i, j] v[j, ln]`` (``Q`` real)."""
    return (
        Q[m, i, 0] * v[0, ln]
        + Q[m, i, 1] * v[1, ln]
        + Q[m, i, 2] * v[2, ln]
        + Q[m, i, 3] * v[3, ln]
        + Q[m, i, 4] * v[4, ln]
        + Q[m, i, 5] * v[5, ln]
        + Q[m, i, 6] * v[6, ln]
        + Q[m, i, 7] * v[7, ln]
    )


@njit(inline="always", **_O)
def _cdot(ar, ai, m, br, bi, ln):
    """``sum_j a[m, j, ln] b[j, ln]`` (complex, no conjugation): ``(re, im)``."""
    re = (
        (ar[m, 0, ln] * br[0, ln] - ai[m, 0, ln] * bi[0, ln])
        + (ar[m, 1, ln] * br[1, ln] - ai[m, 1, ln] * bi[1, ln])
        + (ar[m, 2, ln] * br[2, ln] - ai[m, 2, ln] * bi[2, ln])
        + (ar[m, 3, ln] * br[3, ln] - ai[m, 3, ln] * bi[3, ln])
        + (ar[m, 4, ln] * br[4, ln] - ai[m, 4, ln] * bi[4, ln])
        + (ar[m, 5, ln] * br[5, ln] - ai[m, 5, ln] * bi[5, ln])
        + (ar[m, 6, ln] * br[6, ln] - ai[m, 6, ln] * bi[6, ln])
        + (ar[m, 7, ln] * br[7, ln] - ai[m, 7, ln] * bi[7, ln])
    )
    im = (
        (ar[m, 0, ln] * bi[0, ln] + ai[m, 0, ln] * br[0, ln])
        + (ar[m, 1, ln] * bi[1, ln] + ai[m, 1, ln] * br[1, ln])
        + (ar[m, 2, ln] * bi[2, ln] + ai[m, 2, ln] * br[2, ln])
        + (ar[m, 3, ln] * bi[3, ln] + ai[m, 3, ln] * br[3, ln])
        + (ar[m, 4, ln] * bi[4, ln] + ai[m, 4, ln] * br[4, ln])
        + (ar[m, 5, ln] * bi[5, ln] + ai[m, 5, ln] * br[5, ln])
        + (ar[m, 6, ln] * bi[6, ln] + ai[m, 6, ln] * br[6, ln])
        + (ar[m, 7, ln] * bi[7, ln] + ai[m, 7, ln] * br[7, ln])
    )
    return re, im


@njit(inline="always", **_O)
def _cdot2(ar, ai, br, bi, ln):
    """``sum_j a[j, ln] b[j, ln]`` (complex, no conjugation): ``(re, im)``."""
    re = (
        (ar[0, ln] * br[0, ln] - ai[0, ln] * bi[0, ln])
        + (ar[1, ln] * br[1, ln] - ai[1, ln] * bi[1, ln])
        + (ar[2, ln] * br[2, ln] - ai[2, ln] * bi[2, ln])
        + (ar[3, ln] * br[3, ln] - ai[3, ln] * bi[3, ln])
        + (ar[4, ln] * br[4, ln] - ai[4, ln] * bi[4, ln])
        + (ar[5, ln] * br[5, ln] - ai[5, ln] * bi[5, ln])
        + (ar[6, ln] * br[6, ln] - ai[6, ln] * bi[6, ln])
        + (ar[7, ln] * br[7, ln] - ai[7, ln] * bi[7, ln])
    )
    im = (
        (ar[0, ln] * bi[0, ln] + ai[0, ln] * br[0, ln])
        + (ar[1, ln] * bi[1, ln] + ai[1, ln] * br[1, ln])
        + (ar[2, ln] * bi[2, ln] + ai[2, ln] * br[2, ln])
        + (ar[3, ln] * bi[3, ln] + ai[3, ln] * br[3, ln])
        + (ar[4, ln] * bi[4, ln] + ai[4, ln] * br[4, ln])
        + (ar[5, ln] * bi[5, ln] + ai[5, ln] * br[5, ln])
        + (ar[6, ln] * bi[6, ln] + ai[6, ln] * br[6, ln])
        + (ar[7, ln] * bi[7, ln] + ai[7, ln] * br[7, ln])
    )
    return re, im


@njit(inline="always", **_O)
def _qdot_term(Q, cr, ci, ur, ui, vr, vi, hr, hi, scale, m, i, ln):
    """``h[m, ln] += scale u[i] (Q_m(c) v)[i]`` in lane ``ln``: one term of :func:`qdot`."""
    sr = _row(Q, m, i, vr, ln)
    si = _row(Q, m, i, vi, ln)
    if m >= 1 and i < 4:
        a, b = cr[m - 1, ln], ci[m - 1, ln]
        sr += a * vr[i, ln] - b * vi[i, ln]
        si += a * vi[i, ln] + b * vr[i, ln]
    hr[m, ln] += scale * (ur[i, ln] * sr - ui[i, ln] * si)
    hi[m, ln] += scale * (ur[i, ln] * si + ui[i, ln] * sr)


@njit(inline="always", **_O)
def _row_dot(yr, yi, ur, ui, outr, outi, scale, add, m, ln):
    """``out[m, ln] (+)= scale u . y[m]`` in lane ``ln``: one entry of :func:`rows_dot`."""
    re, im = _cdot(yr, yi, m, ur, ui, ln)
    if add:
        outr[m, ln] += scale * re
        outi[m, ln] += scale * im
    else:
        outr[m, ln] = scale * re
        outi[m, ln] = scale * im


@njit(**_O)
def qtimes(Q, cr, ci, vr, vi, yr, yi, scale, n):
    """``y[m, :, ln] = scale Q_m(c_ln) v_ln`` for lanes ``ln < n``: ``Q`` (7, 8, 8) the real
    quadrics without leg constants, ``c`` (6, L) each lane's leg constants (on the ``e`` block's
    diagonal of quadrics 1..6)."""
    if n < VECTOR_LANES:
        _qtimes_each(Q, cr, ci, vr, vi, yr, yi, scale, n)
        return
    for m in range(7):
        for i in range(8):
            if m >= 1 and i < 4:
                for ln in range(n):
                    a, b = cr[m - 1, ln], ci[m - 1, ln]
                    yr[m, i, ln] = scale * (_row(Q, m, i, vr, ln) + a * vr[i, ln] - b * vi[i, ln])
                    yi[m, i, ln] = scale * (_row(Q, m, i, vi, ln) + a * vi[i, ln] + b * vr[i, ln])
            else:
                for ln in range(n):
                    yr[m, i, ln] = scale * _row(Q, m, i, vr, ln)
                    yi[m, i, ln] = scale * _row(Q, m, i, vi, ln)


@njit(**_O)
def _qtimes_each(Q, cr, ci, vr, vi, yr, yi, scale, n):
    """:func:`qtimes` one lane at a time (few lanes; the same arithmetic)."""
    for ln in range(n):
        for m in range(7):
            for i in range(8):
                if m >= 1 and i < 4:
                    a, b = cr[m - 1, ln], ci[m - 1, ln]
                    yr[m, i, ln] = scale * (_row(Q, m, i, vr, ln) + a * vr[i, ln] - b * vi[i, ln])
                    yi[m, i, ln] = scale * (_row(Q, m, i, vi, ln) + a * vi[i, ln] + b * vr[i, ln])
                else:
                    yr[m, i, ln] = scale * _row(Q, m, i, vr, ln)
                    yi[m, i, ln] = scale * _row(Q, m, i, vi, ln)


@njit(**_O)
def qdot(Q, cr, ci, ur, ui, vr, vi, hr, hi, scale, add, n):
    """``h[m] (+)= scale u^T Q_m(c) v`` (m < 7): the quadrics' bilinear forms."""
    if n < VECTOR_LANES:
        _qdot_each(Q, cr, ci, ur, ui, vr, vi, hr, hi, scale, add, n)
        return
    for m in range(7):
        if not add:
            for ln in range(n):
                hr[m, ln] = 0.0
                hi[m, ln] = 0.0
        for i in range(8):
            leg = m >= 1 and i < 4
            for ln in range(n):  # written out, not a helper: the lane loop must vectorise
                sr = _row(Q, m, i, vr, ln)
                si = _row(Q, m, i, vi, ln)
                if leg:
                    a, b = cr[m - 1, ln], ci[m - 1, ln]
                    sr += a * vr[i, ln] - b * vi[i, ln]
                    si += a * vi[i, ln] + b * vr[i, ln]
                hr[m, ln] += scale * (ur[i, ln] * sr - ui[i, ln] * si)
                hi[m, ln] += scale * (ur[i, ln] * si + ui[i, ln] * sr)


@njit(**_O)
def rows_dot(yr, yi, ur, ui, outr, outi, scale, add, n):
    """``out[m] (+)= scale u . y[m]`` for m < 7 (``y`` (7 or 8, 8, L))."""
    if n < VECTOR_LANES:
        _rows_dot_each(yr, yi, ur, ui, outr, outi, scale, add, n)
        return
    for m in range(7):
        for ln in range(n):  # written out, not a helper: the lane loop must vectorise
            re, im = _cdot(yr, yi, m, ur, ui, ln)
            if add:
                outr[m, ln] += scale * re
                outi[m, ln] += scale * im
            else:
                outr[m, ln] = scale * re
                outi[m, ln] = scale * im


@njit(**_O)
def _qdot_each(Q, cr, ci, ur, ui, vr, vi, hr, hi, scale, add, n):
    """:func:`qdot` one lane at a time (few lanes; the same arithmetic)."""
    for ln in range(n):
        for m in range(7):
            if not add:
                hr[m, ln] = 0.0
                hi[m, ln] = 0.0
            for i in range(8):
                _qdot_term(Q, cr, ci, ur, ui, vr, vi, hr, hi, scale, m, i, ln)


@njit(**_O)
def _rows_dot_each(yr, yi, ur, ui, outr, outi, scale, add, n):
    """:func:`rows_dot` one lane at a time (few lanes; the same arithmetic)."""
    for ln in range(n):
        for m in range(7):
            _row_dot(yr, yi, ur, ui, outr, outi, scale, add, m, ln)


@njit(**_O)
def lu(F, n):
    """LU with partial pivoting of the 8x8 matrices ``F = (ar, ai, lr, li, piv, dr, di, wr, wi)`` of
    lanes ``ln < n`` (:func:`_lu_lanes` for many lanes, :func:`_lu_each` for a few): ``a``
    becomes the strictly upper part of U (zeros elsewhere), ``l`` the multipliers (strictly
    lower; its other entries stay 0 from :func:`lu_scratch`), ``d`` the reciprocals of U's
    diagonal (non-finite where a pivot is exactly 0: that lane's solves give non-finite values,
    which its step rejects), ``piv[k]`` the row swapped with row ``k`` at step ``k``; ``w``
    scratch. Both give the same bits (the same operations in the same order per lane)."""
    if n >= VECTOR_LANES:
        _lu_lanes(F, n)
    else:
        _lu_each(F, n)


@njit(**_O)
def _lu_each(F, n):
    """:func:`lu` one lane at a time (the lane loop outermost, short unrolled loops inside)."""
    ar, ai, lr, li, piv, dr, di = F[:7]
    for ln in range(n):
        for k in range(8):
            p = k
            best = ar[k, k, ln] * ar[k, k, ln] + ai[k, k, ln] * ai[k, k, ln]
            for i in range(k + 1, 8):
                v = ar[i, k, ln] * ar[i, k, ln] + ai[i, k, ln] * ai[i, k, ln]
                if v > best:
                    best = v
                    p = i
            piv[k, ln] = p
            if p != k:
                for j in range(k, 8):  # both rows are 0 left of column k
                    ar[k, j, ln], ar[p, j, ln] = ar[p, j, ln], ar[k, j, ln]
                    ai[k, j, ln], ai[p, j, ln] = ai[p, j, ln], ai[k, j, ln]
                for j in range(k):  # the multipliers so far
                    lr[k, j, ln], lr[p, j, ln] = lr[p, j, ln], lr[k, j, ln]
                    li[k, j, ln], li[p, j, ln] = li[p, j, ln], li[k, j, ln]
            s = ar[k, k, ln] * ar[k, k, ln] + ai[k, k, ln] * ai[k, k, ln]
            rr = ar[k, k, ln] / s
            ri = -ai[k, k, ln] / s
            dr[k, ln] = rr
            di[k, ln] = ri
            ar[k, k, ln] = 0.0
            ai[k, k, ln] = 0.0
            for i in range(k + 1, 8):
                fr = ar[i, k, ln] * rr - ai[i, k, ln] * ri
                fi = ar[i, k, ln] * ri + ai[i, k, ln] * rr
                lr[i, k, ln] = fr
                li[i, k, ln] = fi
                ar[i, k, ln] = 0.0
                ai[i, k, ln] = 0.0
                for j in range(k + 1, 8):
                    ar[i, j, ln] -= fr * ar[k, j, ln] - fi * ai[k, j, ln]
                    ai[i, j, ln] -= fr * ai[k, j, ln] + fi * ar[k, j, ln]


@njit(**_O)
def solve(F, br, bi, outr, outi, n):
    """``out = A^-1 b`` per lane from :func:`lu`'s factors ``F`` (``out`` not ``b``); as
    :func:`lu`, vectorised over many lanes, one lane at a time for a few (the same bits)."""
    if n >= VECTOR_LANES:
        _solve_lanes(F, br, bi, outr, outi, n)
    else:
        _solve_each(F, br, bi, outr, outi, n)


@njit(**_O)
def _solve_each(F, br, bi, outr, outi, n):
    """:func:`solve` one lane at a time."""
    ar, ai, lr, li, piv, dr, di = F[:7]
    for ln in range(n):
        for i in range(8):
            outr[i, ln] = br[i, ln]
            outi[i, ln] = bi[i, ln]
        for k in range(7):
            p = piv[k, ln]
            if p != k:
                outr[k, ln], outr[p, ln] = outr[p, ln], outr[k, ln]
                outi[k, ln], outi[p, ln] = outi[p, ln], outi[k, ln]
        for i in range(1, 8):
            sr = outr[i, ln]
            si = outi[i, ln]
            for j in range(i):
                sr -= lr[i, j, ln] * outr[j, ln] - li[i, j, ln] * outi[j, ln]
                si -= lr[i, j, ln] * outi[j, ln] + li[i, j, ln] * outr[j, ln]
            outr[i, ln] = sr
            outi[i, ln] = si
        for i in range(7, -1, -1):
            sr = outr[i, ln]
            si = outi[i, ln]
            for j in range(i + 1, 8):
                sr -= ar[i, j, ln] * outr[j, ln] - ai[i, j, ln] * outi[j, ln]
                si -= ar[i, j, ln] * outi[j, ln] + ai[i, j, ln] * outr[j, ln]
            outr[i, ln] = sr * dr[i, ln] - si * di[i, ln]
            outi[i, ln] = sr * di[i, ln] + si * dr[i, ln]


@njit(**_O)
def _lu_lanes(F, n):
    """:func:`lu` with the lanes innermost. The compiler vectorises a lane loop only where it can
    tell that its stores do not overlap its loads: each loop here writes one row of one array and
    reads other arrays (the pivot row is copied into ``w`` first) or the same element it writes."""
    ar, ai, lr, li, piv, dr, di, wr, wi = F
    for k in range(8):
        for ln in range(n):
            piv[k, ln] = k
            dr[k, ln] = ar[k, k, ln] * ar[k, k, ln] + ai[k, k, ln] * ai[k, k, ln]  # best |a|^2
        for i in range(k + 1, 8):
            for ln in range(n):
                v = ar[i, k, ln] * ar[i, k, ln] + ai[i, k, ln] * ai[i, k, ln]
                if v > dr[k, ln]:
                    dr[k, ln] = v
                    piv[k, ln] = i
        for ln in range(n):
            p = piv[k, ln]
            if p != k:
                for j in range(k, 8):  # both rows are 0 left of column k
                    ar[k, j, ln], ar[p, j, ln] = ar[p, j, ln], ar[k, j, ln]
                    ai[k, j, ln], ai[p, j, ln] = ai[p, j, ln], ai[k, j, ln]
                for j in range(k):  # the multipliers so far
                    lr[k, j, ln], lr[p, j, ln] = lr[p, j, ln], lr[k, j, ln]
                    li[k, j, ln], li[p, j, ln] = li[p, j, ln], li[k, j, ln]
        for ln in range(n):
            s = ar[k, k, ln] * ar[k, k, ln] + ai[k, k, ln] * ai[k, k, ln]
            dr[k, ln] = ar[k, k, ln] / s
            di[k, ln] = -ai[k, k, ln] / s
            ar[k, k, ln] = 0.0
            ai[k, k, ln] = 0.0
        for j in range(k + 1, 8):
            for ln in range(n):
                wr[j, ln] = ar[k, j, ln]
                wi[j, ln] = ai[k, j, ln]
        for i in range(k + 1, 8):
            for ln in range(n):
                fr = ar[i, k, ln] * dr[k, ln] - ai[i, k, ln] * di[k, ln]
                fi = ar[i, k, ln] * di[k, ln] + ai[i, k, ln] * dr[k, ln]
                lr[i, k, ln] = fr
                li[i, k, ln] = fi
                ar[i, k, ln] = 0.0
                ai[i, k, ln] = 0.0
            for j in range(k + 1, 8):
                for ln in range(n):
                    fr, fi = lr[i, k, ln], li[i, k, ln]
                    ar[i, j, ln] -= fr * wr[j, ln] - fi * wi[j, ln]
                    ai[i, j, ln] -= fr * wi[j, ln] + fi * wr[j, ln]


@njit(**_O)
def _solve_lanes(F, br, bi, outr, outi, n):
    """:func:`solve` with the lanes innermost; finished rows are copied into ``w`` and read from
    there (see :func:`_lu_lanes`)."""
    ar, ai, lr, li, piv, dr, di, wr, wi = F
    for i in range(8):
        for ln in range(n):
            outr[i, ln] = br[i, ln]
            outi[i, ln] = bi[i, ln]
    for k in range(7):
        for ln in range(n):
            p = piv[k, ln]
            if p != k:
                outr[k, ln], outr[p, ln] = outr[p, ln], outr[k, ln]
                outi[k, ln], outi[p, ln] = outi[p, ln], outi[k, ln]
    for i in range(8):
        for j in range(i):
            for ln in range(n):
                outr[i, ln] -= lr[i, j, ln] * wr[j, ln] - li[i, j, ln] * wi[j, ln]
                outi[i, ln] -= lr[i, j, ln] * wi[j, ln] + li[i, j, ln] * wr[j, ln]
        for ln in range(n):
            wr[i, ln] = outr[i, ln]
            wi[i, ln] = outi[i, ln]
    for i in range(7, -1, -1):
        for j in range(i + 1, 8):
            for ln in range(n):
                outr[i, ln] -= ar[i, j, ln] * wr[j, ln] - ai[i, j, ln] * wi[j, ln]
                outi[i, ln] -= ar[i, j, ln] * wi[j, ln] + ai[i, j, ln] * wr[j, ln]
        for ln in range(n):
            r, v = outr[i, ln], outi[i, ln]
            outr[i, ln] = r * dr[i, ln] - v * di[i, ln]
            outi[i, ln] = r * di[i, ln] + v * dr[i, ln]
            wr[i, ln] = outr[i, ln]
            wi[i, ln] = outi[i, ln]


@njit(inline="always", **_O)
def _sumsq(vr, vi, ln):
    """``|v_ln|^2`` (8 coordinates)."""
    return (
        vr[0, ln] * vr[0, ln]
        + vi[0, ln] * vi[0, ln]
        + vr[1, ln] * vr[1, ln]
        + vi[1, ln] * vi[1, ln]
        + vr[2, ln] * vr[2, ln]
        + vi[2, ln] * vi[2, ln]
        + vr[3, ln] * vr[3, ln]
        + vi[3, ln] * vi[3, ln]
        + vr[4, ln] * vr[4, ln]
        + vi[4, ln] * vi[4, ln]
        + vr[5, ln] * vr[5, ln]
        + vi[5, ln] * vi[5, ln]
        + vr[6, ln] * vr[6, ln]
        + vi[6, ln] * vi[6, ln]
        + vr[7, ln] * vr[7, ln]
        + vi[7, ln] * vi[7, ln]
    )


@njit(**_O)
def norms(vr, vi, out, n):
    """``out[ln] = |v_ln|`` (2-norm of 8 coordinates)."""
    for ln in range(n):
        out[ln] = math.sqrt(_sumsq(vr, vi, ln))


@njit(**_O)
def legc(S, c0r, c0i, tt, cr, ci, cpr, cpi, n):
    """Leg constants ``c(t)`` and ``c'(t)`` of each lane at its ``tt[ln]``."""
    for k in range(6):
        for ln in range(n):
            t = tt[ln]
            dr, di, br, bi = S[_DR + k, ln], S[_DI + k, ln], S[_BR + k, ln], S[_BI + k, ln]
            cr[k, ln] = c0r[k] + t * dr + t * (1.0 - t) * br
            ci[k, ln] = c0i[k] + t * di + t * (1.0 - t) * bi
            cpr[k, ln] = dr + (1.0 - 2.0 * t) * br
            cpi[k, ln] = di + (1.0 - 2.0 * t) * bi


# ------------------------------------------------------------------------------ Taylor predictor
@njit(inline="always", **_O)
def _ed(Tr, Ti, a, b, ln):
    """``e_a . e_b`` of lane ``ln``'s Taylor coefficients (complex, no conjugation)."""
    sr = 0.0
    si = 0.0
    for i in range(4):
        sr += Tr[a, i, ln] * Tr[b, i, ln] - Ti[a, i, ln] * Ti[b, i, ln]
        si += Tr[a, i, ln] * Ti[b, i, ln] + Ti[a, i, ln] * Tr[b, i, ln]
    return sr, si


@njit(**_O)
def _e_sums(T, k, E, n):
    """``E[0:2] = sum_{i+j=k-1} e_i.e_j`` and ``E[2:4] = sum_{i+j=k-2} e_i.e_j`` (ordered pairs:
    ``e_0.e_1`` counts twice)."""
    Tr, Ti = T[0], T[1]
    for ln in range(n):
        s1r = s1i = s2r = s2i = 0.0
        for i in range(k):  # i + j = k - 1
            r, m = _ed(Tr, Ti, i, k - 1 - i, ln)
            s1r += r
            s1i += m
        for i in range(k - 1):  # i + j = k - 2
            r, m = _ed(Tr, Ti, i, k - 2 - i, ln)
            s2r += r
            s2i += m
        E[0, ln], E[1, ln], E[2, ln], E[3, ln] = s1r, s1i, s2r, s2i


@njit(**_O)
def _taylor_rhs(rr, ri, E, k, cpr, cpi, S, n):
    """``-r_k``: the bilinear part in ``rr, ri`` plus, on the leg rows, ``c' E1 + (c''/2) E2``
    with ``c''/2 = -bend``; the chart row 0."""
    for m in range(1, 7):
        for ln in range(n):
            rr[m, ln] += cpr[m - 1, ln] * E[0, ln] - cpi[m - 1, ln] * E[1, ln]
            ri[m, ln] += cpr[m - 1, ln] * E[1, ln] + cpi[m - 1, ln] * E[0, ln]
            if k >= 2:
                br, bi = -S[_BR + m - 1, ln], -S[_BI + m - 1, ln]
                rr[m, ln] += br * E[2, ln] - bi * E[3, ln]
                ri[m, ln] += br * E[3, ln] + bi * E[2, ln]
    for m in range(7):
        for ln in range(n):
            rr[m, ln] = -rr[m, ln]
            ri[m, ln] = -ri[m, ln]
    for ln in range(n):
        rr[7, ln] = 0.0
        ri[7, ln] = 0.0


@njit(**_O)
def taylor(Q, T, S, cr, ci, cpr, cpi, F, W, Y, n):
    """Taylor coefficients ``T[:, 1..4]`` of the path through ``T[:, 0]`` at each lane's ``t``
    (``c, c'`` there), with the LU ``F`` (:func:`lu`) of the Jacobian. Order ``k``:
    ``J x_k = -r_k``, ``r_k = sum_{i+j=k; i,j>=1} x_i^T Q x_j + c' sum_{i+j=k-1} e_i.e_j
    + c''/2 sum_{i+j=k-2} e_i.e_j`` (the coefficient of ``s^k`` in ``H(x(t+s), t+s)``)."""
    Tr, Ti = T[0], T[1]
    rr, ri, E = W[0], W[1], W[2]
    for k in range(1, 5):
        if k == 1:
            for m in range(8):
                for ln in range(n):
                    rr[m, ln] = 0.0
                    ri[m, ln] = 0.0
        elif k == 2:
            qtimes(Q, cr, ci, Tr[1], Ti[1], Y[0], Y[1], 1.0, n)  # Q x_1, kept for k = 3, 4
            rows_dot(Y[0], Y[1], Tr[1], Ti[1], rr, ri, 1.0, False, n)
        elif k == 3:
            rows_dot(Y[0], Y[1], Tr[2], Ti[2], rr, ri, 2.0, False, n)
        else:
            rows_dot(Y[0], Y[1], Tr[3], Ti[3], rr, ri, 2.0, False, n)
            qdot(Q, cr, ci, Tr[2], Ti[2], Tr[2], Ti[2], rr, ri, 1.0, True, n)
        _e_sums(T, k, E, n)
        _taylor_rhs(rr, ri, E, k, cpr, cpi, S, n)
        solve(F, rr, ri, Tr[k], Ti[k], n)


@njit(**_O)
def pade(T, flag, tau, err, n):
    """Per lane: the Padé trust region ``tau = min_i |x_2i / x_3i|`` and the norm ``err`` of the
    local error coefficient (``x_4 - x_3^2 / x_2``); ``flag[i, ln]`` 1 where coordinate ``i``
    uses Padé, 0 the cubic Taylor polynomial (error ``x_4``) where ``x_2`` is negligible against
    ``x_1, x_3`` scaled by ``lambda = max(2^-18, |x_1|)``. Squared moduli throughout."""
    Tr, Ti = T[0], T[1]
    for ln in range(n):
        tau[ln] = math.inf
        err[ln] = 0.0
    for i in range(8):
        for ln in range(n):
            x2r, x2i, x3r, x3i = Tr[2, i, ln], Ti[2, i, ln], Tr[3, i, ln], Ti[3, i, ln]
            a1 = Tr[1, i, ln] * Tr[1, i, ln] + Ti[1, i, ln] * Ti[1, i, ln]
            a2 = x2r * x2r + x2i * x2i
            a3 = x3r * x3r + x3i * x3i
            lam = max(1.4551915228366852e-11, a1)  # lambda^2, 2^-36
            c1, c2, c3 = a1 / lam, a2 / (lam * lam), a3 / (lam * lam * lam)
            taylor = c2 <= 1e-28 * max(c1, c2, c3)
            pr = x3r * x3r - x3i * x3i  # x3^2 / x2 = x3^2 conj(x2) / |x2|^2
            pi = 2.0 * x3r * x3i
            er = Tr[4, i, ln] - (0.0 if taylor else (pr * x2r + pi * x2i) / a2)
            ei = Ti[4, i, ln] - (0.0 if taylor else (pi * x2r - pr * x2i) / a2)
            flag[i, ln] = 0.0 if taylor else 1.0
            r = math.inf if taylor else a2 / a3
            tau[ln] = min(tau[ln], r)
            err[ln] += er * er + ei * ei
    for ln in range(n):
        tau[ln] = math.sqrt(tau[ln])
        err[ln] = math.sqrt(err[ln])


@njit(**_O)
def predict(T, S, flag, out_r, out_i, n):
    """The prediction at ``t + dt`` of each lane, ``x_0 + s (x_1 + s g)`` with
    ``g = x_2^2 / (x_2 - s x_3)`` (Padé) or ``x_2 + s x_3`` (Taylor), rescaled into the chart
    ``a = conj(x_0)/|x_0|`` (stored in ``S``) so that ``a . x = 1``."""
    Tr, Ti = T[0], T[1]
    for i in range(8):
        for ln in range(n):
            s = S[_DT, ln]
            x2r, x2i, x3r, x3i = Tr[2, i, ln], Ti[2, i, ln], Tr[3, i, ln], Ti[3, i, ln]
            dr, di = x2r - s * x3r, x2i - s * x3i
            nr, ni = x2r * x2r - x2i * x2i, 2.0 * x2r * x2i
            d = dr * dr + di * di
            pade_ = flag[i, ln] != 0.0
            gr = (nr * dr + ni * di) / d if pade_ else x2r + s * x3r
            gi = (ni * dr - nr * di) / d if pade_ else x2i + s * x3i
            out_r[i, ln] = Tr[0, i, ln] + s * (Tr[1, i, ln] + s * gr)
            out_i[i, ln] = Ti[0, i, ln] + s * (Ti[1, i, ln] + s * gi)
    for ln in range(n):
        nx = 0.0
        for i in range(8):
            nx += Tr[0, i, ln] * Tr[0, i, ln] + Ti[0, i, ln] * Ti[0, i, ln]
        nx = 1.0 / math.sqrt(nx)
        sr = 0.0
        si = 0.0
        for i in range(8):
            ar, ai = Tr[0, i, ln] * nx, -Ti[0, i, ln] * nx
            S[_PR + i, ln] = ar
            S[_PI + i, ln] = ai
            sr += ar * out_r[i, ln] - ai * out_i[i, ln]
            si += ar * out_i[i, ln] + ai * out_r[i, ln]
        d = 1.0 / (sr * sr + si * si)
        for i in range(8):
            r, v = out_r[i, ln], out_i[i, ln]
            out_r[i, ln] = (r * sr + v * si) * d
            out_i[i, ln] = (v * sr - r * si) * d


# ------------------------------------------------------------------------------ corrector
@njit(**_O)
def correct(Q, S, xr, xi, cr, ci, F, W, nrm, t1, n):
    """Two chord-Newton updates of ``x`` (8, L) with the Jacobian at the predicted ``x`` (its LU
    left in ``F``), a third for the lanes whose step reaches ``t1 = 1`` (their endpoint must be
    accurate; the others keep two, whichever lanes they share the loop with); ``nrm[k, ln]`` the
    norm of update ``k`` (0 for a third not made). ``W`` scratch."""
    ar, ai = F[0], F[1]
    hr, hi, sr, si = W[0], W[1], W[2], W[3]
    jacobian(Q, cr, ci, xr, xi, S[_PR : _PR + 8], S[_PI : _PI + 8], ar, ai, n)
    rows_dot(ar, ai, xr, xi, hr, hi, 0.5, False, n)  # H = x . Q x = x . J / 2
    lu(F, n)
    final = False
    for ln in range(n):
        final |= t1[ln] >= 1.0
    for it in range(3 if final else 2):
        if it:
            qdot(Q, cr, ci, xr, xi, xr, xi, hr, hi, 1.0, False, n)
        chart_residual(S[_PR : _PR + 8], S[_PI : _PI + 8], xr, xi, hr, hi, n)
        solve(F, hr, hi, sr, si, n)
        for ln in range(n):
            if it == 2 and t1[ln] < 1.0:
                sr[:, ln] = 0.0
                si[:, ln] = 0.0
        for i in range(8):
            for ln in range(n):
                xr[i, ln] -= sr[i, ln]
                xi[i, ln] -= si[i, ln]
        norms(sr, si, nrm[it], n)
    if not final:
        for ln in range(n):
            nrm[2, ln] = 0.0


@njit(**_O)
def jacobian(Q, cr, ci, xr, xi, par, pai, ar, ai, n):
    """``J = (2 Q_m(c) x, a)``: the quadrics' gradients and the chart ``a`` (``par, pai``)."""
    qtimes(Q, cr, ci, xr, xi, ar, ai, 2.0, n)
    for i in range(8):
        for ln in range(n):
            ar[7, i, ln] = par[i, ln]
            ai[7, i, ln] = pai[i, ln]


@njit(**_O)
def chart_residual(par, pai, xr, xi, hr, hi, n):
    """``h[7] = a . x - 1`` (the chart's equation)."""
    for ln in range(n):
        re, im = _cdot2(par, pai, xr, xi, ln)
        hr[7, ln] = re - 1.0
        hi[7, ln] = im


# ------------------------------------------------------------------------------ step control
@njit(**_O)
def control(S, T, xr, xi, nrm, t1, acc, opts, n):
    """Accept or reject each lane's step (``S[_DT]`` from ``S[_T]``): ``acc[ln]`` 1 or 0. An
    accepted step moves the lane to the corrected point and updates ``omega``; a rejected one
    halves the step and doubles ``omega``."""
    kappa, theta, omega0, end_tol, noise = opts[2], opts[3], opts[4], opts[7], opts[8]
    Tr, Ti = T[0], T[1]
    for ln in range(n):
        n1, n2, n3 = nrm[0, ln], nrm[1, ln], nrm[2, ln]
        last = n3 if t1[ln] >= 1.0 else n2
        scale = 0.0
        for i in range(8):
            scale += xr[i, ln] ** 2 + xi[i, ln] ** 2
        scale = math.sqrt(scale)
        floor = noise * scale
        fresh = S[_FRESH, ln] == 1.0
        if fresh:  # a start solution: no prediction, the corrector only checks it
            good = math.isfinite(last) and n1 <= 1e-8 * scale
        else:
            good = (
                math.isfinite(last)
                and n1 <= kappa * scale
                and n2 <= theta * n1 + floor
                and n3 <= theta * n2 + floor
                and (t1[ln] < 1.0 or last <= end_tol * scale)
            )
            S[_STEPS, ln] += 1.0
        if good:
            for i in range(8):
                Tr[0, i, ln] = xr[i, ln]
                Ti[0, i, ln] = xi[i, ln]
            S[_T, ln] = min(S[_T, ln] + S[_DT, ln], 1.0)
            if fresh:
                S[_OM, ln] = omega0
            elif n1 > floor and n2 > 0:
                S[_OM, ln] = max(2.0 * n2 / (n1 * n1), 0.25 * S[_OM, ln])
            S[_FRESH, ln] = 0.0
            acc[ln] = 1.0
        else:
            S[_REJ, ln] += 1.0
            S[_DT, ln] *= 0.5
            S[_OM, ln] *= 2.0
            acc[ln] = 0.0


@njit(**_O)
def next_step(S, tau, err, acc, opts, n):
    """The next step of each accepted lane (``acc[ln]`` 1): the smallest of the trust region
    share, the step whose predicted error is ``a / omega`` and what is left to ``t = 1``."""
    a, beta_tau = opts[0], opts[1]
    for ln in range(n):
        if acc[ln] == 0.0:
            continue
        s = min(1.0 - S[_T, ln], beta_tau * tau[ln])
        e = err[ln]
        if e > 0:
            s = min(s, (a / (S[_OM, ln] * e)) ** 0.25)
        S[_DT, ln] = s


# ------------------------------------------------------------------------------ a block of paths
@njit(**_O)
def _move(S, T, flag, src, dst):
    """Lane ``src``'s whole state into lane ``dst``."""
    for r in range(_NS):
        S[r, dst] = S[r, src]
    for a in range(2):
        for k in range(5):
            for i in range(8):
                T[a, k, i, dst] = T[a, k, i, src]
    for i in range(8):
        flag[i, dst] = flag[i, src]


@njit(**_O)
def _load(S, T, flag, ln, p, item_k, item_j, starts, dc, bend, opts):
    """Lane ``ln`` takes queue entry ``p``: start solution ``item_j[p]`` (scaled to norm 1) of
    input ``item_k[p]`` (its ``dc``, ``bend``), at ``t = 0`` with a zero first step."""
    k, j = item_k[p], item_j[p]
    nx = 0.0
    for i in range(8):
        nx += abs(starts[j, i]) ** 2
    nx = math.sqrt(nx)
    for i in range(8):
        T[0, 0, i, ln] = starts[j, i].real / nx
        T[1, 0, i, ln] = starts[j, i].imag / nx
        flag[i, ln] = 0.0
        for o in range(1, 5):
            T[0, o, i, ln] = 0.0
            T[1, o, i, ln] = 0.0
    for i in range(6):
        S[_DR + i, ln], S[_DI + i, ln] = dc[k, i].real, dc[k, i].imag
        S[_BR + i, ln], S[_BI + i, ln] = bend[k, i].real, bend[k, i].imag
    S[_T, ln] = 0.0
    S[_DT, ln] = 0.0
    S[_OM, ln] = opts[4]
    S[_STEPS, ln] = 0.0
    S[_REJ, ln] = 0.0
    S[_ITEM, ln] = p
    S[_FRESH, ln] = 1.0


@njit(**_O)
def _finish(S, T, ln, ok, patch, out_x, out_ok, out_steps):
    """Write lane ``ln``'s path: its point in the common ``patch`` (``patch . x = 1``)."""
    p = int(S[_ITEM, ln])
    s = 0j
    for i in range(8):
        s += patch[i] * complex(T[0, 0, i, ln], T[1, 0, i, ln])
    for i in range(8):
        out_x[p, i] = complex(T[0, 0, i, ln], T[1, 0, i, ln]) / s
    out_ok[p] = ok
    out_steps[p] = int(S[_STEPS, ln])


@njit(**_O)
def _retire(S, T, flag, acc, opts, n, nxt, P, item_k, item_j, starts, dc, bend, patch, out):
    """Lanes whose path reached ``t = 1`` or failed write their result and take the next queue
    entry (or the last active lane moves in); returns ``(n, nxt)``."""
    hmin, max_steps = opts[5], opts[6]
    for ln in range(n - 1, -1, -1):
        done = acc[ln] == 1.0 and S[_T, ln] >= 1.0
        failed = not done and (not S[_DT, ln] >= hmin or S[_STEPS, ln] >= max_steps)
        if not (done or failed):
            continue
        _finish(S, T, ln, done, patch, out[0], out[1], out[2])
        if nxt < P:
            _load(S, T, flag, ln, nxt, item_k, item_j, starts, dc, bend, opts)
            nxt += 1
        else:
            n -= 1
            if ln != n:
                _move(S, T, flag, n, ln)
    return n, nxt


@njit(**_O)
def lu_scratch(L):
    """Arrays of :func:`lu`'s factors for ``L`` lanes (and its scratch rows)."""
    return (
        np.zeros((8, 8, L)),
        np.zeros((8, 8, L)),
        np.zeros((8, 8, L)),
        np.zeros((8, 8, L)),
        np.zeros((8, L), np.int64),
        np.zeros((8, L)),
        np.zeros((8, L)),
        np.zeros((8, L)),
        np.zeros((8, L)),
    )


@njit(**_O)
def _scratch(L):
    return (
        np.zeros((_NS, L)),  # S
        np.zeros((2, 5, 8, L)),  # T: Taylor coefficients
        np.zeros((2, 5, 8, L)),  # T2: new ones, copied where accepted
        np.zeros((8, L)),  # flag: Padé (1) or Taylor (0) per coordinate
        np.zeros((2, 8, L)),  # X: predicted / corrected point
        np.zeros((4, 6, L)),  # C: c, c'
        lu_scratch(L),  # F
        np.zeros((2, 7, 8, L)),  # Y: Q x_1
        np.zeros((8, 8, L)),  # W: rhs and small per-lane vectors
        np.zeros((3, L)),  # nrm
        np.zeros((4, L)),  # per lane: t1, acc, tau, err
    )


@njit(**_O)
def track_block(
    Q, c0, starts, dc, bend, item_k, item_j, opts, lanes, patch, out_x, out_ok, out_steps
):
    """Track the paths ``item_j[p]`` (start solution) of inputs ``item_k[p]`` (rows of ``dc``,
    ``bend`` (K, 6) complex) for every queue entry ``p``, ``lanes`` at a time; writes
    ``out_x[p]`` (the endpoint, in the common ``patch``), ``out_ok[p]`` (reached ``t = 1``) and
    ``out_steps[p]``."""
    P = len(item_k)
    L = max(1, min(lanes, P))
    S, T, T2, flag, X, C, F, Y, W, nrm, lane = _scratch(L)
    c0r, c0i = c0.real.copy(), c0.imag.copy()
    out = (out_x, out_ok, out_steps)
    n = 0
    for ln in range(L):
        _load(S, T, flag, ln, ln, item_k, item_j, starts, dc, bend, opts)
        n += 1
    nxt = L
    while n > 0:
        predict(T, S, flag, X[0], X[1], n)
        for ln in range(n):
            lane[0, ln] = min(S[_T, ln] + S[_DT, ln], 1.0)
        legc(S, c0r, c0i, lane[0], C[0], C[1], C[2], C[3], n)
        correct(Q, S, X[0], X[1], C[0], C[1], F, W, nrm, lane[0], n)
        control(S, T, X[0], X[1], nrm, lane[0], lane[1], opts, n)
        # Taylor coefficients at the new points (the accepted lanes keep them)
        legc(S, c0r, c0i, S[_T], C[0], C[1], C[2], C[3], n)
        for a in range(2):
            for i in range(8):
                for ln in range(n):
                    T2[a, 0, i, ln] = T[a, 0, i, ln]
        taylor(Q, T2, S, C[0], C[1], C[2], C[3], F, W, Y, n)
        for ln in range(n):
            if lane[1, ln] == 1.0:
                for a in range(2):
                    for k in range(1, 5):
                        for i in range(8):
                            T[a, k, i, ln] = T2[a, k, i, ln]
        pade(T, flag, lane[2], lane[3], n)
        next_step(S, lane[2], lane[3], lane[1], opts, n)
        n, nxt = _retire(
            S, T, flag, lane[1], opts, n, nxt, P, item_k, item_j, starts, dc, bend, patch, out
        )


# ------------------------------------------------------------------------------ certificates
@njit(**_O)
def qnorm(Q, c):
    """``sqrt(sum_m |Q_m(c)|_F^2)`` (the bound of Smale's gamma of a quadratic system, with
    :func:`refine_block`'s ``|J^-1|_F``), ``c`` (6,) complex."""
    s = 0.0
    for m in range(7):
        for i in range(8):
            for j in range(8):
                v = Q[m, i, j] + (c[m - 1] if (m >= 1 and i == j and i < 4) else 0.0j)
                s += v.real * v.real + v.imag * v.imag
    return math.sqrt(s)


@njit(**_O)
def _newton_lanes(Q, C, A, X, F, W, nrm, jn, ok, iters, n):
    """Newton's method on ``x^T Q_m(c) x = 0, a . x = 1`` in lanes ``ln < n`` (``X`` (2, 8, L) the
    points, ``C`` (2, 6, L) the leg constants, ``A`` (2, 8, L) the charts): ``iters`` updates (none
    in a lane whose Jacobian is singular), then at the last iterate ``nrm = |J^-1 F|`` (beta),
    ``jn = |J^-1|_F`` and ``ok`` 1 where the Jacobian is nonsingular."""
    for it in range(iters + 1):
        jacobian(Q, C[0], C[1], X[0], X[1], A[0], A[1], F[0], F[1], n)
        rows_dot(F[0], F[1], X[0], X[1], W[0], W[1], 0.5, False, n)
        chart_residual(A[0], A[1], X[0], X[1], W[0], W[1], n)
        lu(F, n)
        _nonsingular(F[5], F[6], ok, n)
        solve(F, W[0], W[1], W[2], W[3], n)
        if it < iters:
            for i in range(8):
                for ln in range(n):
                    if ok[ln] == 1.0:
                        X[0, i, ln] -= W[2, i, ln]
                        X[1, i, ln] -= W[3, i, ln]
    norms(W[2], W[3], nrm, n)
    _inverse_norm(F, W, jn, n)


@njit(**_O)
def _lane_scratch(P, lanes):
    """Lanes ``L`` and the scratch of :func:`_newton_lanes` for ``P`` points."""
    L = max(1, min(lanes, P))
    X, C, A = np.zeros((2, 8, L)), np.zeros((2, 6, L)), np.zeros((2, 8, L))
    return L, X, C, A, lu_scratch(L), np.zeros((4, 8, L)), np.zeros(L), np.zeros(L), np.zeros(L)


@njit(**_O)
def refine_block(Q, patch, c1, qn, item_k, x, iters, lanes, out_x, beta, alpha):
    """Newton's method on ``x^T Q_m(c1) x = 0, patch . x = 1`` for every endpoint ``x[p]``
    (input ``item_k[p]``): ``iters`` updates (none where the Jacobian is singular), then
    ``beta = |J^-1 F|`` and Smale's ``alpha = beta |J^-1|_F qn`` (``qn[k]``: :func:`qnorm`) at
    the last iterate (inf where singular), as
    :func:`parakin.mechanisms.stewart66_homotopy.newton_refine` and ``certify``."""
    P = len(item_k)
    L, X, C, A, F, W, nrm, jn, ok = _lane_scratch(P, lanes)
    for s0 in range(0, P, L):
        n = min(L, P - s0)
        for ln in range(n):
            k = item_k[s0 + ln]
            for i in range(8):
                X[0, i, ln], X[1, i, ln] = x[s0 + ln, i].real, x[s0 + ln, i].imag
                A[0, i, ln], A[1, i, ln] = patch[i].real, patch[i].imag
            for i in range(6):
                C[0, i, ln], C[1, i, ln] = c1[k, i], 0.0
        _newton_lanes(Q, C, A, X, F, W, nrm, jn, ok, iters, n)
        for ln in range(n):
            p = s0 + ln
            for i in range(8):
                out_x[p, i] = complex(X[0, i, ln], X[1, i, ln])
            b = nrm[ln] if ok[ln] == 1.0 else math.inf
            beta[p] = b
            alpha[p] = b * (jn[ln] if ok[ln] == 1.0 else math.inf) * qn[item_k[p]]


#: :data:`parakin.mechanisms.stewart66_homotopy.ALPHA_ROBUST` and ``EVAL_ULPS`` (the same rule)
ALPHA_ROBUST = 0.03
EVAL_ULPS = 16 * np.finfo(np.float64).eps


@njit(**_O)
def real_block(Q, c1, qn, item_k, x, iters, lanes, out_y, decision):
    """Certified reality of the approximate zeros ``x[p]`` (input ``item_k[p]``), as
    :func:`parakin.mechanisms.stewart66_homotopy.real_decision` (see there for the criterion, from
    Hauenstein & Sottile 2012's alphaCertified): each point moved to the real chart ``y_k = 1`` of
    its largest coordinate, ``iters`` Newton updates there, then ``decision[p]`` -1 (not real) where
    ``|Im y| > 2 beta``, +1 (real) where ``alpha <= 0.03`` and ``|Im y| <= 1/(20 gamma)``, else 0
    (undecided); ``out_y[p]`` the refined point."""
    P = len(item_k)
    L, X, C, A, F, W, nrm, jn, ok = _lane_scratch(P, lanes)
    for s0 in range(0, P, L):
        n = min(L, P - s0)
        for ln in range(n):
            xp = x[s0 + ln]
            piv = 0
            for i in range(8):
                if abs(xp[i]) > abs(xp[piv]):
                    piv = i
            for i in range(8):
                y = xp[i] / xp[piv]
                X[0, i, ln], X[1, i, ln] = y.real, y.imag
                A[0, i, ln], A[1, i, ln] = (1.0 if i == piv else 0.0), 0.0
            for i in range(6):
                C[0, i, ln], C[1, i, ln] = c1[item_k[s0 + ln], i], 0.0
        _newton_lanes(Q, C, A, X, F, W, nrm, jn, ok, iters, n)
        for ln in range(n):
            p = s0 + ln
            im = 0.0
            yy = 0.0
            for i in range(8):
                out_y[p, i] = complex(X[0, i, ln], X[1, i, ln])
                im += X[1, i, ln] ** 2
                yy += X[0, i, ln] ** 2 + X[1, i, ln] ** 2
            im = math.sqrt(im)
            gamma = jn[ln] * qn[item_k[p]]
            beta = nrm[ln] + EVAL_ULPS * gamma * yy
            if not (ok[ln] == 1.0 and math.isfinite(beta) and math.isfinite(gamma)):
                decision[p] = 0
            elif im > 2 * beta:
                decision[p] = -1
            elif beta * gamma <= ALPHA_ROBUST and 20 * gamma * im <= 1:
                decision[p] = 1
            else:
                decision[p] = 0


@njit(**_O)
def _nonsingular(dr, di, ok, n):
    """``ok[ln]`` 1 where every pivot reciprocal of lane ``ln`` is finite."""
    for ln in range(n):
        ok[ln] = 1.0
    for k in range(8):
        for ln in range(n):
            if not (math.isfinite(dr[k, ln]) and math.isfinite(di[k, ln])):
                ok[ln] = 0.0


@njit(**_O)
def _inverse_norm(F, W, out, n):
    """``out[ln] = |J_ln^-1|_F``, column by column from the LU ``F`` (``W`` (4, 8, L) scratch)."""
    for ln in range(n):
        out[ln] = 0.0
    for k in range(8):
        for i in range(8):
            for ln in range(n):
                W[0, i, ln] = 1.0 if i == k else 0.0
                W[1, i, ln] = 0.0
        solve(F, W[0], W[1], W[2], W[3], n)
        for ln in range(n):
            out[ln] += _sumsq(W[2], W[3], ln)
    for ln in range(n):
        out[ln] = math.sqrt(out[ln])


# ------------------------------------------------------------------------------ a pass
@njit(**_O)
def track_refine(G, c1, qn, dc, bend, item_k, item_j, opts, iters, out):
    """Track and refine queue entries ``p`` (start solution ``item_j[p]`` of input ``item_k[p]``,
    the rows of ``c1, qn, dc, bend``): ``out = (x, ok, steps, refined x, beta, alpha)`` per entry.
    ``G = (q, c0, starts, patch)``. Releases the GIL: threads run blocks side by side."""
    q, c0, starts, patch = G
    x, ok, steps, xr, beta, alpha = out
    if len(item_k) == 0:
        return
    track_block(q, c0, starts, dc, bend, item_k, item_j, opts, LANES, patch, x, ok, steps)
    refine_block(q, patch, c1, qn, item_k, x, iters, LANES, xr, beta, alpha)


# ------------------------------------------------------------------------------ certificates
@njit(**_O)
def keep_distinct(x, beta, alpha, alpha0, keep):
    """``keep[i]``: ``x[i]`` is certified (``alpha < alpha0``), an assembly (``e . e`` not
    numerically 0) and its ``2 beta`` ball meets no earlier kept one's (as
    :func:`parakin.mechanisms.stewart66_homotopy.distinct`)."""
    m = len(x)
    for i in range(m):
        ee = 0j
        nn = 0.0
        for a in range(4):
            ee += x[i, a] * x[i, a]
            nn += x[i, a].real ** 2 + x[i, a].imag ** 2
        keep[i] = abs(ee) > 1e-10 * nn and alpha[i] < alpha0
    for i in range(1, m):
        if not keep[i]:
            continue
        for j in range(i):
            if keep[j]:
                r = 2 * (beta[i] + beta[j]) + 1e-12
                d = 0.0
                for a in range(8):
                    z = x[i, a] - x[j, a]
                    d += z.real * z.real + z.imag * z.imag
                if d <= r * r:
                    keep[i] = False
                    break


@njit(**_O)
def _merge(x, beta, alpha, keep, x2, b2, a2, alpha0):
    """The kept solutions of ``x`` then the new ones of ``x2`` not among them, kept ones first
    (the numpy path's merge after a retry), in place."""
    m = len(x)
    xx = np.full((2 * m, 8), np.nan + 0j)
    bb = np.full(2 * m, np.inf)
    aa = np.full(2 * m, np.inf)
    for i in range(m):
        if keep[i]:
            xx[i], bb[i], aa[i] = x[i], beta[i], alpha[i]
        xx[m + i], bb[m + i], aa[m + i] = x2[i], b2[i], a2[i]
    kk = np.zeros(2 * m, np.bool_)
    keep_distinct(xx, bb, aa, alpha0, kk)
    slot = 0
    for want in (True, False):
        for i in range(2 * m):
            if kk[i] == want and slot < m:
                x[slot], beta[slot], alpha[slot], keep[slot] = xx[i], bb[i], aa[i], kk[i]
                slot += 1


@njit(**_O)
def certify_all(x, beta, alpha, alpha0, keep):
    """:func:`keep_distinct` of every input (rows of ``x`` (n, M, 8))."""
    for i in range(len(x)):
        keep_distinct(x[i], beta[i], alpha[i], alpha0, keep[i])


@njit(**_O)
def merge_all(x, beta, alpha, keep, bad, x2, b2, a2, alpha0):
    """:func:`_merge` of inputs ``bad`` with their retracked solutions (rows of ``x2``...)."""
    for a in range(len(bad)):
        i = bad[a]
        _merge(x[i], beta[i], alpha[i], keep[i], x2[a], b2[a], a2[a], alpha0)


# ------------------------------------------------------------------------------ poses
@njit(**_O)
def study_rt(x, rot, trn):
    """Rotation ``R(e)/(e.e)`` and translation ``vec(g e')/(e.e)`` of Study parameters ``x``
    (real or complex, no conjugation), as :func:`parakin.mechanisms.stewart66_homotopy.study_to_rt`."""
    w, a, b, c = x[0], x[1], x[2], x[3]
    n = w * w + a * a + b * b + c * c
    rot[0, 0] = (w * w + a * a - b * b - c * c) / n
    rot[0, 1] = 2 * (a * b - w * c) / n
    rot[0, 2] = 2 * (a * c + w * b) / n
    rot[1, 0] = 2 * (a * b + w * c) / n
    rot[1, 1] = (w * w - a * a + b * b - c * c) / n
    rot[1, 2] = 2 * (b * c - w * a) / n
    rot[2, 0] = 2 * (a * c - w * b) / n
    rot[2, 1] = 2 * (b * c + w * a) / n
    rot[2, 2] = (w * w - a * a - b * b + c * c) / n
    g0, g1, g2, g3 = x[4], x[5], x[6], x[7]
    trn[0] = (w * g1 - g0 * a + (b * g3 - c * g2)) / n
    trn[1] = (w * g2 - g0 * b + (c * g1 - a * g3)) / n
    trn[2] = (w * g3 - g0 * c + (a * g2 - b * g1)) / n


@njit(**_O)
def _origin(rot, trn, bc, pc, s, out):
    """Moving-frame origin ``O = t s + Bc - R Pc`` (metres) of a centred, scaled translation."""
    for r in range(3):
        out[r] = trn[r] * s + bc[r] - (rot[r, 0] * pc[0] + rot[r, 1] * pc[1] + rot[r, 2] * pc[2])


@njit(**_O)
def _real_pose(y, geo, joints, pose):
    """The pose of a solution certified real (:func:`real_block`; ``y`` its refined point in a
    real chart, whose real part is used) and its IK error."""
    bc, pc, s, base, plat = geo
    yr = np.empty(8)
    for a in range(8):
        yr[a] = y[a].real
    rot, trn = np.empty((3, 3)), np.empty(3)
    study_rt(yr, rot, trn)
    pose[0] = math.atan2(rot[1, 0], rot[0, 0])
    pose[1] = math.asin(min(max(-rot[2, 0], -1.0), 1.0))
    pose[2] = math.atan2(rot[2, 1], rot[2, 2])
    _origin(rot, trn, bc, pc, s, pose[3:])
    return _ik_error(pose, base, plat, joints)


@njit(**_O)
def _ik_error(pose, base, plat, joints):
    """``max_i | |T P_i + O - B_i| - L_i |`` with ``T = Rz Ry Rx`` of the pose's angles."""
    ca, sa = math.cos(pose[0]), math.sin(pose[0])
    cb, sb = math.cos(pose[1]), math.sin(pose[1])
    cc, sc = math.cos(pose[2]), math.sin(pose[2])
    r = (
        (ca * cb, ca * sb * sc - sa * cc, ca * sb * cc + sa * sc),
        (sa * cb, sa * sb * sc + ca * cc, sa * sb * cc - ca * sc),
        (-sb, cb * sc, cb * cc),
    )
    err = 0.0
    for i in range(6):
        d2 = 0.0
        for a in range(3):
            v = r[a][0] * plat[i, 0] + r[a][1] * plat[i, 1] + r[a][2] * plat[i, 2]
            v += pose[3 + a] - base[i, a]
            d2 += v * v
        err = max(err, abs(math.sqrt(d2) - joints[i]))
    return err


@njit(**_O)
def _package(i, x, alpha, keep, y, decision, joints, geo, out):
    """Input ``i``'s certified solutions as Study parameters (``e . e = 1``), rotations, origins;
    its real ones (``decision`` +1, :func:`real_block`) as poses (IK error at most
    ``1e-8 max(1, size)``), sorted by Z descending; undecided ones (``decision`` 0, or real with a
    pose that misses the IK tolerance) counted apart."""
    poses, study, rot, trn, is_real, al, counts, ik_err = out
    bc, pc, s = geo[0], geo[1], geo[2]
    M = x.shape[1]
    tol = 1e-8 * max(1.0, s)
    cand = np.full((M, 6), np.nan)
    z = np.full(M, np.inf)
    worst = -math.inf
    undecided = 0
    for j in range(M):
        if not keep[i, j]:
            continue
        ee = 0j
        for a in range(4):
            ee += x[i, j, a] * x[i, j, a]
        xs = x[i, j] / cmath.sqrt(ee)
        study[i, j] = xs
        al[i, j] = alpha[i, j]
        study_rt(xs, rot[i, j], trn[i, j])
        _origin(rot[i, j], trn[i, j].copy(), bc + 0j, pc + 0j, s, trn[i, j])
        if decision[i, j] == 0:
            undecided += 1
        elif decision[i, j] == 1:
            err = _real_pose(y[i, j], geo, joints[i], cand[j])
            if err <= tol:
                is_real[i, j] = True
                z[j] = -cand[j, 5]
                worst = max(worst, err)
            else:
                undecided += 1
    nr = 0
    for j in range(M):  # stable insertion by Z descending (few solutions)
        if z[j] < np.inf:
            slot = nr
            while slot > 0 and -poses[i, slot - 1, 5] > z[j]:
                poses[i, slot] = poses[i, slot - 1]
                slot -= 1
            poses[i, slot] = cand[j]
            nr += 1
    counts[i, 0] = keep[i].sum()
    counts[i, 1] = nr
    counts[i, 2] = undecided
    ik_err[i] = worst if nr else np.nan


@njit(**_O)
def package_all(x, alpha, keep, y, decision, joints, geo, out):
    """:func:`_package` of every input."""
    for i in range(len(x)):
        _package(i, x, alpha, keep, y, decision, joints, geo, out)


# ------------------------------------------------------------------------------ geometry
# ------------------------------------------------------------------------------ the batch
_POOL: list = [None, None]  # [executor, pid]: the block threads, recreated after a fork


def _threads_pool(workers: int) -> ThreadPoolExecutor:
    pool, pid = _POOL
    if pool is None or pid != os.getpid() or pool._max_workers < workers:
        pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="stewart66")
        _POOL[:] = [pool, os.getpid()]
    return pool


def _side_by_side(P: int, threads: int, run) -> None:
    """``run(lo, hi)`` over ``P`` items split into at most ``threads`` contiguous blocks of at
    least :data:`MIN_BLOCK`, run side by side (the compiled code releases the GIL)."""
    nb = max(1, min(threads, P // MIN_BLOCK))
    bounds = (P * np.arange(nb + 1)) // nb
    if nb == 1:
        run(0, P)
    else:
        list(_threads_pool(nb).map(lambda b: run(bounds[b], bounds[b + 1]), range(nb)))


def _run_pass(G, c1, qn, dc, bend, opts, iters: int, threads: int):
    """Every start solution of every input (rows of ``c1, qn, dc, bend``) tracked and refined, in
    ``threads`` blocks run side by side (the compiled code releases the GIL):
    ``(x (K, M, 8), beta, alpha (K, M), steps (K,))``."""
    K, M = len(c1), len(G[2])
    P = K * M
    item_k = np.repeat(np.arange(K), M)
    item_j = np.tile(np.arange(M), K)
    out = (
        np.empty((P, 8), np.complex128),
        np.zeros(P, np.bool_),
        np.zeros(P, np.int64),
        np.empty((P, 8), np.complex128),
        np.empty(P),
        np.empty(P),
    )

    def run(lo: int, hi: int) -> None:
        part = tuple(o[lo:hi] for o in out)
        track_refine(G, c1, qn, dc, bend, item_k[lo:hi], item_j[lo:hi], opts, iters, part)

    _side_by_side(P, threads, run)
    steps = out[2].reshape(K, M).sum(-1)
    return out[3].reshape(K, M, 8), out[4].reshape(K, M), out[5].reshape(K, M), steps


def geometry(q0, c0, starts, patch, bc, pc, size, base, platform) -> tuple:
    """A geometry as :func:`fk_all` takes it: ``q0`` (7, 8, 8) real quadrics without leg
    constants, the start system ``c0`` (6,) and ``starts`` (M, 8), the common ``patch`` (8,),
    the anchors' centroids ``bc, pc`` (3,), ``size``, ``base`` and ``platform`` (6, 3)."""
    f8, c16 = np.float64, np.complex128
    G = (
        np.ascontiguousarray(np.real(q0), dtype=f8),
        np.ascontiguousarray(c0, dtype=c16),
        np.ascontiguousarray(starts, dtype=c16),
        np.ascontiguousarray(patch, dtype=c16),
    )
    geo = (
        np.ascontiguousarray(bc, dtype=f8),
        np.ascontiguousarray(pc, dtype=f8),
        float(size),
        np.ascontiguousarray(base, dtype=f8),
        np.ascontiguousarray(platform, dtype=f8),
    )
    return G, geo


def _reality(G, c1, qn, x, keep, iters: int, threads: int):
    """:func:`real_block` of every kept solution, in ``threads`` blocks side by side:
    ``(y (n, M, 8), decision (n, M))`` (decision 0 where not kept)."""
    n, M = keep.shape
    flat = np.flatnonzero(keep.ravel())
    P = len(flat)
    xk = np.ascontiguousarray(x.reshape(-1, 8)[flat])
    item_k = flat // M
    yk = np.empty((P, 8), np.complex128)
    dk = np.zeros(P, np.int64)

    def run(lo: int, hi: int) -> None:
        real_block(G[0], c1, qn, item_k[lo:hi], xk[lo:hi], iters, LANES, yk[lo:hi], dk[lo:hi])

    _side_by_side(P, threads, run)
    y = np.full((n * M, 8), complex(np.nan, np.nan))
    decision = np.zeros(n * M, np.int64)
    y[flat], decision[flat] = yk, dk
    return y.reshape(n, M, 8), decision.reshape(n, M)


def fk_all(
    prepared: tuple,
    c1,
    joints,
    *,
    alpha0: float,
    retries: int = 3,
    options: dict | None = None,
    iters: int = 3,
    threads: int | None = None,
) -> dict:
    """All forward solutions of a batch, compiled. ``prepared``: :func:`geometry`'s tuple;
    ``c1`` (n, 6) the inputs' leg constants (centred, scaled anchors), ``joints`` (n, 6) their
    leg lengths; ``alpha0`` the certificate's threshold. Inputs with fewer certified distinct
    solutions than start solutions are retracked along bent paths (up to ``retries`` times).
    ``threads``: blocks run side by side (default ``numba.get_num_threads()``).

    Returns the arrays of :class:`parakin.mechanisms.stewart66.FKAll` (40 slots per input):
    ``poses, study, rotation, translation, is_real, alpha, n_found, n_real, n_undecided, ik_error,
    steps, retries``."""
    G, geo = prepared
    _loaded()
    c1 = np.ascontiguousarray(c1, dtype=np.float64)
    joints = np.ascontiguousarray(joints, dtype=np.float64)
    threads = numba.get_num_threads() if threads is None else max(1, int(threads))
    opts = options_vector(options)
    n, M = len(c1), len(G[2])
    qn = _qnorms(G[0], c1)
    dc = c1 - G[1]
    x, beta, alpha, steps = _run_pass(G, c1, qn, dc, np.zeros_like(dc), opts, iters, threads)
    keep = np.zeros((n, M), np.bool_)
    certify_all(x, beta, alpha, alpha0, keep)
    retried = np.zeros(n, np.int64)
    bends = _bends(retries)
    for r in range(retries):
        bad = np.flatnonzero(keep.sum(-1) < M)
        if not bad.size:
            break
        d = dc[bad]
        x2, b2, a2, s2 = _run_pass(
            G, c1[bad], qn[bad], d, bends[r] * (1 + np.abs(d)), opts, iters, threads
        )
        merge_all(x, beta, alpha, keep, bad, x2, b2, a2, alpha0)
        steps[bad] += s2
        retried[bad] += 1
    y, decision = _reality(G, c1, qn, x, keep, iters, threads)
    cnan = complex(np.nan, np.nan)
    out = (
        np.full((n, 40, 6), np.nan),
        np.full((n, 40, 8), cnan),
        np.full((n, 40, 3, 3), cnan),
        np.full((n, 40, 3), cnan),
        np.zeros((n, 40), np.bool_),
        np.full((n, 40), np.nan),
        np.zeros((n, 3), np.int64),
        np.full(n, np.nan),
    )
    package_all(x, alpha, keep, y, decision, joints, geo, out)
    names = ("poses", "study", "rotation", "translation", "is_real", "alpha")
    res = dict(zip(names, out[:6]))
    res.update(
        n_found=out[6][:, 0],
        n_real=out[6][:, 1],
        n_undecided=out[6][:, 2],
        ik_error=out[7],
        steps=steps,
        retries=retried,
    )
    return res


@lru_cache(maxsize=1)
def _loaded() -> None:
    """Load (or compile) the rarely used retry merge once, on the first call, so that no later
    call pays for it."""
    z = np.zeros((1, 1, 8), np.complex128)
    r = np.zeros((1, 1))
    merge_all(z, r, r, np.ones((1, 1), np.bool_), np.zeros(1, np.int64), z, r, r, 0.0)


@lru_cache(maxsize=8)
def _bends(retries: int) -> np.ndarray:
    """One fixed random complex direction per retry (the same for every input and batch)."""
    rng = np.random.default_rng(1000)
    return rng.normal(size=(retries, 6)) + 1j * rng.normal(size=(retries, 6))


@njit(**_O)
def _qnorms(q, c1):
    """:func:`qnorm` of each input's target quadrics."""
    out = np.empty(len(c1))
    for i in range(len(c1)):
        out[i] = qnorm(q, c1[i] + 0j)
    return out
