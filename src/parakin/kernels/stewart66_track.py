"""The compiled all-solutions FK of the 6-6 Gough-Stewart platform: a batch of inputs in, every
certified solution and the real poses out, with no numpy work per input.

The paths are tracked by :mod:`parakin.kernels.stewart66_lanes` (paths side by side in lanes, the
Taylor/Padé predictor of HomotopyContinuation.jl), two homotopies of the same family:

* **a known geometry** (:func:`fk_all`): the geometry's own start system (complex leg constants
  ``c0``, its certified solutions) moved to each input's leg constants, only ``c`` moving (the
  fibre homotopy: 7-9 steps a path);
* **a new geometry per input** (:func:`fk_all_new`): the stored generic start system moved to each
  input's anchors and leg constants at once (a general parameter homotopy: no start system of its
  own, about 40 steps a path).

Then, in lanes as well: Newton's refinement and Smale's alpha of every endpoint, the distinct
certified solutions of each input (:func:`keep_distinct`), retracks of incomplete inputs along
bent segments (merged, :func:`merge_all`), the certified reality test (:func:`_reality`) and the
poses (:func:`package_all`). Blocks of paths run on threads (the compiled code releases the GIL);
a path's arithmetic does not depend on its lane, block or thread, so results do not depend on the
batch or the thread count.
"""

from __future__ import annotations

import cmath
import math
import os
from functools import lru_cache

import numba
import numpy as np
from numba import njit

from parakin.kernels import stewart66_lanes as lanes
from parakin.kernels import store
from parakin.kernels.threads import side_by_side

if "NUMBA_THREADING_LAYER" not in os.environ:  # fork-safe, as parakin.kernels.build: the thread
    numba.config.THREADING_LAYER = "workqueue"  # count read below launches numba's thread pool

__all__ = [
    "geometry",
    "fk_all",
    "fk_all_new",
    "track_solutions",
    "OPTIONS",
    "options_vector",
    "LANES",
]

_O = dict(cache=True, error_model="numpy", nogil=True)
#: paths side by side in a block (the lanes)
LANES = lanes.LANES
#: the smallest block of paths worth a thread of its own
MIN_BLOCK = 16
#: tracking options (:data:`parakin.kernels.stewart66_lanes.OPTIONS`)
OPTIONS = lanes.OPTIONS
options_vector = lanes.options_vector
#: :data:`parakin.mechanisms.stewart66_homotopy.ALPHA_ROBUST` and ``EVAL_ULPS`` (the same rule)
ALPHA_ROBUST = 0.03
EVAL_ULPS = 16 * np.finfo(np.float64).eps


# ------------------------------------------------------------------------------ certificates
@njit(**_O)
def keep_distinct(x, beta, alpha, alpha0, keep):
    """``keep[i]``: ``x[i]`` is certified (``alpha < alpha0``), an assembly (``e . e`` not
    numerically 0) and its ``2 beta`` ball, ``beta`` with its rounding floor, meets no earlier
    kept one's (as :func:`parakin.mechanisms.stewart66_homotopy.distinct`)."""
    m = len(x)
    radius = np.empty(m)
    for i in range(m):
        ee = 0j
        nn = 0.0
        xx = 0.0
        for a in range(8):
            xx += x[i, a].real ** 2 + x[i, a].imag ** 2
        for a in range(4):
            ee += x[i, a] * x[i, a]
            nn += x[i, a].real ** 2 + x[i, a].imag ** 2
        keep[i] = abs(ee) > 1e-10 * nn and alpha[i] < alpha0
        # the computed beta of an ill-conditioned zero is rounding, not a bound on its distance
        # to the zero: the floor gamma EVAL_ULPS |x|^2 (gamma = alpha / beta), as the reality test
        gamma = alpha[i] / beta[i] if beta[i] > 0 else 0.0
        radius[i] = beta[i] + EVAL_ULPS * gamma * xx
    for i in range(1, m):
        if not keep[i]:
            continue
        for j in range(i):
            if keep[j]:
                r = 2 * (radius[i] + radius[j]) + 1e-12
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
    # rows copied element by element: numba compiles an array assigned to a row with its
    # shape-mismatch message (string formatting, about 2 CPU-s per compiling process)
    for i in range(m):
        if keep[i]:
            bb[i], aa[i] = beta[i], alpha[i]
            for c in range(8):
                xx[i, c] = x[i, c]
        bb[m + i], aa[m + i] = b2[i], a2[i]
        for c in range(8):
            xx[m + i, c] = x2[i, c]
    kk = np.zeros(2 * m, np.bool_)
    keep_distinct(xx, bb, aa, alpha0, kk)
    slot = 0
    for want in (True, False):
        for i in range(2 * m):
            if kk[i] == want and slot < m:
                beta[slot], alpha[slot], keep[slot] = bb[i], aa[i], kk[i]
                for c in range(8):
                    x[slot, c] = xx[i, c]
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
    """The pose of a solution certified real (:func:`_reality`; ``y`` its refined point in a
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
    its real ones (``decision`` +1, :func:`_reality`) as poses (IK error at most
    ``1e-8 max(1, size)``), sorted by Z descending; undecided ones (``decision`` 0, or real with a
    pose that misses the IK tolerance) counted apart."""
    poses, study, rot, trn, is_real, al, counts, ik_err = out
    cnan = complex(np.nan, np.nan)
    poses[i] = np.nan  # the empty slots
    study[i] = cnan
    rot[i] = cnan
    trn[i] = cnan
    is_real[i] = False
    al[i] = np.nan
    bc, pc, s = geo[0][i], geo[1][i], geo[2][i]
    geo_i = (bc, pc, s, geo[3][i], geo[4][i])
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
        for a in range(8):  # element by element, as in _merge
            study[i, j, a] = xs[a]
        al[i, j] = alpha[i, j]
        study_rt(xs, rot[i, j], trn[i, j])
        _origin(rot[i, j], trn[i, j].copy(), bc + 0j, pc + 0j, s, trn[i, j])
        if decision[i, j] == 0:
            undecided += 1
        elif decision[i, j] == 1:
            err = _real_pose(y[i, j], geo_i, joints[i], cand[j])
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
                for a in range(6):  # element by element, as in _merge
                    poses[i, slot, a] = poses[i, slot - 1, a]
                slot -= 1
            for a in range(6):
                poses[i, slot, a] = cand[j, a]
            nr += 1
    counts[i, 0] = keep[i].sum()
    counts[i, 1] = nr
    counts[i, 2] = undecided
    ik_err[i] = worst if nr else np.nan


@njit(**_O)
def package_all(x, alpha, keep, y, decision, joints, geo, out):
    """:func:`_package` of every input (``geo``: per input the anchors' centroids ``bc, pc``
    (n, 3), the scale ``size`` (n,), ``base`` and ``platform`` (n, 6, 3))."""
    for i in range(len(x)):
        _package(i, x, alpha, keep, y, decision, joints, geo, out)


# ------------------------------------------------------------------------------ reality
@njit(**_O)
def _far_from_real(x, beta, alpha, idx, far):
    """``far[a]``: the zero of point ``x[idx[a]]`` (``x`` (P, 8) certified approximate zeros in the
    common chart, ``beta, alpha`` (P,) their certificates) is not real, decided without Newton in a
    real chart. The zero ``xi`` lies within ``2 r`` of ``x`` (``r = beta`` with its rounding floor,
    as :func:`keep_distinct`), and a real point of P^7 is ``lambda v`` with ``v`` real, whose
    distance from ``x`` is at least ``min_phi |Im(e^(-i phi) x)|``, the square root of the smaller
    eigenvalue of the Gram matrix of ``Re x, Im x``. Where that distance exceeds ``2 r`` (less a
    bound of its own rounding, ``2 EVAL_ULPS |x|^2`` on the eigenvalue), ``xi`` is not real.
    Elsewhere (a real zero, or one too close to tell) :func:`_reality`'s test decides."""
    for a in range(len(idx)):
        i = idx[a]
        aa, bb, ab = 0.0, 0.0, 0.0
        for k in range(8):
            re, im = x[i, k].real, x[i, k].imag
            aa += re * re
            bb += im * im
            ab += re * im
        xx = aa + bb
        h = 0.5 * (aa - bb)
        low = 0.5 * xx - math.sqrt(h * h + ab * ab)
        gamma = alpha[i] / beta[i] if beta[i] > 0 else 0.0
        r = beta[i] + EVAL_ULPS * gamma * xx
        far[a] = low - 2 * EVAL_ULPS * xx > 4 * r * r


@njit(**_O)
def _real_charts(x, keep_idx, out_y, out_chart):
    """Each kept point moved to the real chart ``y_k = 1`` of its largest coordinate (the same
    point of P^7, a chart that conjugation maps to itself) and that chart."""
    for a in range(len(keep_idx)):
        xp = x[keep_idx[a]]
        piv = 0
        for i in range(8):
            if abs(xp[i]) > abs(xp[piv]):
                piv = i
        for i in range(8):
            out_y[a, i] = xp[i] / xp[piv]
            out_chart[a, i] = 1.0 if i == piv else 0.0


@njit(**_O)
def _decide(y, beta, jn, qn, idx, decision):
    """alphaCertified's local reality test (:func:`parakin.mechanisms.stewart66_homotopy.
    real_decision`) from Newton's refinement in a real chart: ``gamma = |J^-1|_F qn``, ``beta``
    plus a bound of the rounding error of evaluating ``F``; -1 (not real) where
    ``|Im y| > 2 beta``, +1 (real) where ``alpha <= 0.03`` and ``|Im y| <= 1/(20 gamma)``, else 0
    (undecided, also where the Jacobian is singular), into ``decision[idx[p]]``."""
    for p in range(len(y)):
        im = 0.0
        yy = 0.0
        for i in range(8):
            im += y[p, i].imag ** 2
            yy += y[p, i].real ** 2 + y[p, i].imag ** 2
        im = math.sqrt(im)
        gamma = jn[p] * qn[p]
        b = beta[p] + EVAL_ULPS * gamma * yy
        if not (math.isfinite(b) and math.isfinite(gamma)):
            decision[idx[p]] = 0
        elif im > 2 * b:
            decision[idx[p]] = -1
        elif b * gamma <= ALPHA_ROBUST and 20 * gamma * im <= 1:
            decision[idx[p]] = 1
        else:
            decision[idx[p]] = 0


# ------------------------------------------------------------------------------ the batch
def _target(bs, ps, c1) -> np.ndarray:
    """Per input the parameters of its target system as a path at rest (``t^0`` only):
    (n, 3, 6, 7) complex, the anchors ``bs, ps`` (n, 6, 3) and leg constants ``c1`` (n, 6)."""
    n = len(c1)
    par = np.zeros((n, 3, 6, 7), np.complex128)
    par[:, 0, :, :3] = bs
    par[:, 0, :, 3:6] = ps
    par[:, 0, :, 6] = c1
    return par


def _refine(target, x, item_k, patch, iters, threads):
    """Newton's refinement of every endpoint ``x`` (P, 8) on its input's target system in the
    common ``patch``: ``(x, beta, alpha)`` (Smale's ``alpha = beta |J^-1|_F qn``)."""
    charts = np.repeat(patch[None], len(item_k), axis=0)
    xr, beta, jn, qn = _newton(target, x, item_k, charts, iters, threads)
    return xr, beta, beta * jn * qn


def _newton(target, x, item_k, charts, iters, threads):
    """:func:`parakin.kernels.stewart66_lanes.newton_queue` on every point ``x`` (P, 8), its
    input ``item_k`` and chart ``charts``, in blocks side by side: ``(x, beta, |J^-1|_F, qn)``."""
    P = len(item_k)
    xr = np.empty((P, 8), np.complex128)
    beta, jn, qn = np.empty(P), np.empty(P), np.empty(P)

    def run(lo: int, hi: int) -> None:
        lanes.newton_queue(
            target, x[lo:hi], item_k[lo:hi], charts[lo:hi], iters, xr[lo:hi], beta[lo:hi],
            jn[lo:hi], qn[lo:hi],
        )  # fmt: skip

    side_by_side(P, run, threads=threads, min_block=MIN_BLOCK)
    return xr, beta, jn, qn


def track_solutions(par, starts, patch, target, opts, moving, iters, threads):
    """Every start solution ``starts`` (M, 8) on every input's path ``par`` (K, 3, 6, 7) tracked
    (:func:`parakin.kernels.stewart66_lanes.track_queue`), then refined and certified on the
    input's target system ``target`` (K, 3, 6, 7): ``(x (K, M, 8), beta, alpha (K, M), steps
    (K,), reached (K, M))``, ``x`` in the common ``patch``."""
    K, M = len(par), len(starts)
    P = K * M
    item = np.arange(P)
    item_k, item_j = item // M, item % M
    x = np.empty((P, 8), np.complex128)
    ok = np.zeros(P, np.bool_)
    steps = np.zeros(P, np.int64)

    def run(lo: int, hi: int) -> None:
        lanes.track_queue(
            par, starts, item_k[lo:hi], item_j[lo:hi], opts, moving, patch, x[lo:hi], ok[lo:hi],
            steps[lo:hi],
        )  # fmt: skip

    side_by_side(P, run, threads=threads, min_block=MIN_BLOCK)
    xr, beta, alpha = _refine(target, x, item_k, patch, iters, threads)
    return (
        xr.reshape(K, M, 8),
        beta.reshape(K, M),
        alpha.reshape(K, M),
        steps.reshape(K, M).sum(-1),
        ok.reshape(K, M),
    )


def _reality(target, x, beta, alpha, keep, iters: int, threads: int):
    """The certified reality test of every kept solution: ``(y (n, M, 8), decision (n, M))``
    (0 where not kept). A solution far from every real point (:func:`_far_from_real`) is not
    real (-1; its ``y`` is NaN); the others are refined by Newton in the real chart of their
    largest coordinate and decided by :func:`_decide`. (On random platforms most of the 40 are far,
    and the Newton runs on the few near ones.)"""
    n, M = keep.shape
    flat = np.flatnonzero(keep.ravel())
    xf = x.reshape(-1, 8)
    far = np.zeros(len(flat), np.bool_)
    _far_from_real(xf, beta.reshape(-1), alpha.reshape(-1), flat, far)
    near = flat[~far]
    P = len(near)
    y0 = np.empty((P, 8), np.complex128)
    charts = np.empty((P, 8), np.complex128)
    _real_charts(xf, near, y0, charts)
    yk, b, jn, qn = _newton(target, y0, near // M, charts, iters, threads)
    decision = np.zeros(n * M, np.int64)
    decision[flat] = -1  # far ones stay not real; :func:`_decide` decides the near ones
    _decide(yk, b, jn, qn, near, decision)
    y = np.empty((n * M, 8), np.complex128)  # read only where decided real (near)
    y[near] = yk
    return y.reshape(n, M, 8), decision.reshape(n, M)


def geometry(bs, ps, c0, starts, patch, bc, pc, size, base, platform) -> tuple:
    """A known geometry as :func:`fk_all` takes it: the centred, scaled anchors ``bs, ps`` (6, 3),
    its start system's leg constants ``c0`` (6,) and certified solutions ``starts`` (M, 8), the
    common ``patch`` (8,), the anchors' centroids ``bc, pc`` (3,), ``size``, ``base`` and
    ``platform`` (6, 3) (metres)."""
    f8, c16 = np.float64, np.complex128
    bc, pc = np.ascontiguousarray(bc, dtype=f8), np.ascontiguousarray(pc, dtype=f8)
    base = np.ascontiguousarray(base, dtype=f8)
    platform = np.ascontiguousarray(platform, dtype=f8)
    return {
        "bs": np.ascontiguousarray(bs, dtype=f8),
        "ps": np.ascontiguousarray(ps, dtype=f8),
        "c0": np.ascontiguousarray(c0, dtype=c16),
        "starts": np.ascontiguousarray(starts, dtype=c16),
        "patch": np.ascontiguousarray(patch, dtype=c16),
        "bc": bc,
        "pc": pc,
        "size": float(size),
        "base": base,
        "platform": platform,
        # what :func:`package_all` reads per input, for one input (a call of one input, the
        # common case, takes it as it is; a batch repeats it)
        "geo1": tuple(np.array(g, dtype=f8)[None] for g in (bc, pc, size, base, platform)),
    }


def _fibre_paths(G: dict, c1: np.ndarray, bend: np.ndarray) -> np.ndarray:
    """Per input the fibre path ``c(t) = c0 + t (c1 - c0) + t (1 - t) bend`` at the geometry's
    anchors: (n, 3, 6, 7)."""
    par = _target(G["bs"], G["ps"], np.broadcast_to(G["c0"], c1.shape))
    par[:, 1, :, 6] = c1 - G["c0"] + bend
    par[:, 2, :, 6] = -bend
    return par


def fk_all(
    prepared: dict,
    c1,
    joints,
    *,
    alpha0: float,
    retries: int = 3,
    options: dict | None = None,
    iters: int = 3,
    threads: int | None = None,
) -> dict:
    """All forward solutions of a batch on a known geometry, compiled. ``prepared``:
    :func:`geometry`'s dict; ``c1`` (n, 6) the inputs' leg constants (centred, scaled anchors),
    ``joints`` (n, 6) their leg lengths; ``alpha0`` the certificate's threshold. Inputs with fewer
    certified distinct solutions than start solutions are retracked along bent segments (up to
    ``retries`` times). ``threads``: blocks run side by side (default
    ``numba.get_num_threads()``).

    Returns the arrays of :class:`parakin.mechanisms.stewart66.FKAll` (40 slots per input):
    ``poses, study, rotation, translation, is_real, alpha, n_found, n_real, n_undecided, ik_error,
    steps, retries``."""
    G = prepared
    c1 = np.ascontiguousarray(c1, dtype=np.float64)
    n = len(c1)
    target = _target(G["bs"], G["ps"], c1)
    # the geometry repeated per input (np.repeat: a tenth of np.broadcast_to's cost in Python)
    geo = G["geo1"] if n == 1 else tuple(np.repeat(g, n, axis=0) for g in G["geo1"])

    def paths(rows, bend):
        return _fibre_paths(G, c1[rows], bend), target[rows]

    return _solve(paths, G["starts"], G["patch"], False, n, joints, geo, alpha0, retries, options, iters, threads)  # fmt: skip


def fk_all_new(
    start: dict,
    bs,
    ps,
    c1,
    joints,
    geo: tuple,
    *,
    alpha0: float,
    retries: int = 3,
    options: dict | None = None,
    iters: int = 3,
    threads: int | None = None,
) -> dict:
    """All forward solutions of a batch of inputs each on its own geometry, compiled, with no
    start system of its own: the stored generic ``start`` (``base, platform, c, patch,
    solutions``) moved to each input's centred, scaled anchors ``bs, ps`` (n, 6, 3) and leg
    constants ``c1`` (n, 6) in one parameter homotopy (anchors and leg constants on straight
    segments; a retry bends the leg constants' segment). ``geo``: per input the anchors'
    centroids ``bc, pc`` (n, 3), ``size`` (n,), ``base``, ``platform`` (n, 6, 3) (metres).
    Returns what :func:`fk_all` returns."""
    bs = np.ascontiguousarray(bs, dtype=np.float64)
    ps = np.ascontiguousarray(ps, dtype=np.float64)
    c1 = np.ascontiguousarray(c1, dtype=np.float64)
    n = len(c1)
    target = _target(bs, ps, c1)
    b0, p0, c0 = start["base"], start["platform"], start["c"]

    def paths(rows, bend):
        par = _target(np.broadcast_to(b0, (len(rows), 6, 3)), np.broadcast_to(p0, (len(rows), 6, 3)), np.broadcast_to(c0, (len(rows), 6)))  # fmt: skip
        par[:, 1, :, :3] = bs[rows] - b0
        par[:, 1, :, 3:6] = ps[rows] - p0
        par[:, 1, :, 6] = c1[rows] - c0 + bend
        par[:, 2, :, 6] = -bend
        return par, target[rows]

    starts = np.ascontiguousarray(start["solutions"], dtype=np.complex128)
    patch = np.ascontiguousarray(start["patch"], dtype=np.complex128)
    return _solve(paths, starts, patch, True, n, joints, geo, alpha0, retries, options, iters, threads)  # fmt: skip


def _solve(paths, starts, patch, moving, n, joints, geo, alpha0, retries, options, iters, threads):
    """Track, refine, certify, retry the incomplete inputs along bent segments, decide reality
    and package (:func:`fk_all`, :func:`fk_all_new`). ``paths(rows, bend)``: the inputs'
    parameter paths and target systems."""
    _loaded()
    joints = np.ascontiguousarray(joints, dtype=np.float64)
    # writable C arrays: a read-only argument (one input's broadcast view is already contiguous,
    # so ``ascontiguousarray`` kept it read-only) is another type to numba, and
    # :func:`package_all` was compiled twice, once for single inputs and once for batches
    geo = tuple(g if _writable_f8(g) else np.array(g, dtype=np.float64, order="C") for g in geo)
    threads = numba.get_num_threads() if threads is None else max(1, int(threads))
    opts = _default_options() if options is None else options_vector(options)
    M = len(starts)
    rows = np.arange(n)
    par, target = paths(rows, np.zeros((n, 6), np.complex128))
    x, beta, alpha, steps, _ = track_solutions(par, starts, patch, target, opts, moving, iters, threads)  # fmt: skip
    keep = np.zeros((n, M), np.bool_)
    certify_all(x, beta, alpha, alpha0, keep)
    retried = np.zeros(n, np.int64)
    bends = _bends(retries)
    for r in range(retries):
        if keep.all():
            break
        bad = np.flatnonzero(keep.sum(-1) < M)
        par_b, target_b = paths(bad, np.zeros((len(bad), 6), np.complex128))
        dc = par_b[:, 1, :, 6]
        par_b, target_b = paths(bad, bends[r] * (1 + np.abs(dc)))
        x2, b2, a2, s2, _ = track_solutions(par_b, starts, patch, target_b, opts, moving, iters, threads)  # fmt: skip
        merge_all(x, beta, alpha, keep, bad, x2, b2, a2, alpha0)
        steps[bad] += s2
        retried[bad] += 1
    y, decision = _reality(target, x, beta, alpha, keep, iters, threads)
    c16 = np.complex128
    out = (  # every slot written by package_all
        np.empty((n, 40, 6)),
        np.empty((n, 40, 8), c16),
        np.empty((n, 40, 3, 3), c16),
        np.empty((n, 40, 3), c16),
        np.empty((n, 40), np.bool_),
        np.empty((n, 40)),
        np.empty((n, 3), np.int64),
        np.empty(n),
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


def _writable_f8(a: np.ndarray) -> bool:
    """A writable, C-contiguous float64 array (numba's type for :func:`package_all`'s ``geo``)."""
    return a.dtype == np.float64 and a.flags.c_contiguous and a.flags.writeable


@lru_cache(maxsize=1)
def _default_options() -> np.ndarray:
    """:func:`options_vector` of the defaults, made once (the compiled code only reads it)."""
    return options_vector()


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


# one process at a time compiles each of these functions; the others wait and load it
# at LLVM level 2, as the tracker's lanes (parakin.kernels.stewart66_lanes, docs/kernels.md)
store.share_compiles(vars(), llvm_level=2)
