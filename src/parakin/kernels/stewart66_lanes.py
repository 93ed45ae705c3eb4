"""Compiled path tracker of the 6-6 Gough-Stewart all-solutions FK in groups of ``W`` lanes, for
any parameter homotopy of the family: every input's anchors and leg constants on a path of their
own, so that one tracker serves a known geometry (only the leg constants move: the *fibre*
homotopy of :class:`parakin.mechanisms.stewart66_homotopy.FiberHomotopy`) and a new geometry
reached from the stored generic start system in one homotopy (anchors and leg constants move).

**The family.** A leg quadric of the Study formulation (``docs/stewart66.md``) is

    x^T Q_i x = g.g + c_i e.e + d_i . D(x) + s_i . X(x) + e^T S'_i e

with ``d = p - b``, ``s = p + b``, ``S' = -2 S(b p^T)`` (``b^T R(e) p = e^T S(b p^T) e``, ``R(e)``
the unnormalised rotation), ``D(x) = 2 (e_0 g_v - g_0 e_v)`` and ``X(x) = 2 g_v x e_v``; the Study
quadric is ``e . g``. A leg quadric is therefore a linear combination, with its 17 coefficients
``theta = (c, d, s, S')``, of *features* of ``x`` that all legs share, and a bilinear form
``u^T Q_i v`` the same combination of the polarised features ``phi(u, v)`` (:func:`features`).
Along a path every input's anchors move linearly, ``b(t) = b_0 + t b_1``, ``p(t) = p_0 + t p_1``,
and its leg constants quadratically, ``c(t) = c_0 + t c_1 + t^2 c_2`` (a bent segment), so
``theta(t)`` is a polynomial of degree 2 in ``t``, and the Taylor coefficients of
``H(x(t + s), t + s)`` are Cauchy products of the coefficients' and the features' series.

**Layout.** A group holds ``W`` paths side by side, one per *lane*, the last axis of every array.
Every loop over lanes runs over all ``W`` (a compile-time constant): each is a few SIMD
instructions with no set-up and no remainder, however many lanes are still busy, so a group's
last path costs what one path costs alone. A lane whose path ends takes the next one from the
group's queue; once the queue is empty it idles (its arithmetic continues on its last state and is
ignored). Lanes never mix: a path's arithmetic does not depend on its lane, its group or the thread
that runs it, so results do not depend on the batch or the number of threads (no fast-math: no
operation is fused in one build and not another).

**One step** (the predictor, corrector and step-size rule of HomotopyContinuation.jl, Timme 2021,
as :mod:`parakin.kernels.stewart66_track` had them): Taylor coefficients ``x_1 .. x_4`` of the path
from one LU of the Jacobian, a Padé (2, 1) predictor per coordinate with its local error and trust
region (the nearest pole), a moving orthogonal chart ``conj(x)/|x|``, two chord-Newton corrector
updates (three on the step that reaches ``t = 1``, whose last must be below ``end_tol |x|``); a
step is accepted when the updates contract; the next step is
``min(beta_tau * trust, (a / (omega * err))^(1/4), 1 - t)``, a rejected one halves.

:func:`newton_queue` runs Newton's method in the same lanes on the target systems (refinement,
Smale's alpha, the certified reality test), any chart per point.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from parakin.kernels import store

__all__ = [
    "LANES",
    "NTH",
    "NF",
    "OPTIONS",
    "options_vector",
    "theta",
    "features",
    "combine",
    "jacobian",
    "residual",
    "lu",
    "solve",
    "track_queue",
    "newton_queue",
]

_O = dict(cache=True, error_model="numpy", nogil=True)
# Compile cost: numba compiles every function called from compiled code on its own, then links
# its optimised code into each caller and optimises the whole again, once per layer of calls.
# The helpers with one call site (the step's parts, the queue's bookkeeping) and the thin
# wrappers (``_higher``, ``_series``) are therefore inlined into their caller (numba IR,
# ``inline="always"``): compiled once, in :func:`track_queue` or :func:`newton_queue`. The
# larger functions (``features``, ``combine``, ``jacobian``, ``lu``, ``solve``, ``theta``,
# ``residual``) stay compiled functions: inlined, they made the queue functions so large that
# LLVM took longer (102 CPU-s). Measured on an empty cache (one process, first 6-6 solve):
# 80-91 -> 72-74 CPU-s; the same operations in the same order, so the same bits.
#: paths side by side: the lanes, the last axis of every array (a single input's 40 paths fill
#: them: no second pass of its queue)
LANES = 40
#: from this many active lanes on, the loops run over the lanes innermost (vectorised); below,
#: one lane at a time (a vector loop's set-up costs more than a few lanes' work)
VECTOR_LANES = 8
#: coefficients per leg: c, d (3), s (3), S' (10: ww, xx, yy, zz, wx, wy, wz, xy, xz, yz)
NTH = 17
#: features of a pair of points: st (the Study quadric), gg, then one per coefficient
NF = 19

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

# rows of a group's lane state ``S``
_T, _DT, _OM, _STEPS, _REJ, _ITEM, _FRESH, _ACT = 0, 1, 2, 3, 4, 5, 6, 7
_NS = 8


def options_vector(options: dict | None = None) -> np.ndarray:
    """The options as the compiled code reads them (unknown names are an error)."""
    opts = {**OPTIONS, **(options or {})}
    unknown = set(opts) - set(OPTIONS)
    if unknown:
        raise ValueError(f"unknown tracking option(s) {sorted(unknown)}; known: {list(OPTIONS)}")
    return np.array([float(opts[k]) for k in OPTIONS])


# ------------------------------------------------------------------------------ complex helpers
@njit(inline="always", **_O)
def _mul(ar, ai, br, bi):
    """``a b`` (complex, split parts)."""
    return ar * br - ai * bi, ar * bi + ai * br


@njit(inline="always", **_O)
def _s_of_m(m00, m01, m02, m10, m11, m12, m20, m21, m22):
    """``S' = -2 S(M)`` (ww, xx, yy, zz, wx, wy, wz, xy, xz, yz) with ``e^T S(M) e =
    sum_jk M_jk R_jk(e)``, ``R(e)`` the unnormalised rotation (``R_00 = w^2 + x^2 - y^2 - z^2``,
    ``R_01 = 2 (x y - w z)``, ...); linear in ``M``, so applied to its real and imaginary parts
    apart."""
    return (
        -2.0 * (m00 + m11 + m22),
        -2.0 * (m00 - m11 - m22),
        -2.0 * (m11 - m00 - m22),
        -2.0 * (m22 - m00 - m11),
        -2.0 * (m21 - m12),
        -2.0 * (m02 - m20),
        -2.0 * (m10 - m01),
        -2.0 * (m01 + m10),
        -2.0 * (m02 + m20),
        -2.0 * (m12 + m21),
    )


@njit(inline="always", **_O)
def _store_s(TH, lev, leg, ln, b, p):
    """``TH[lev, :, leg, 7:17]`` = ``S'`` of ``M = b p^T`` (``b, p`` complex 3-vectors as
    ``(b0r, b0i, b1r, b1i, b2r, b2i)``)."""
    m00r, m00i = _mul(b[0], b[1], p[0], p[1])
    m01r, m01i = _mul(b[0], b[1], p[2], p[3])
    m02r, m02i = _mul(b[0], b[1], p[4], p[5])
    m10r, m10i = _mul(b[2], b[3], p[0], p[1])
    m11r, m11i = _mul(b[2], b[3], p[2], p[3])
    m12r, m12i = _mul(b[2], b[3], p[4], p[5])
    m20r, m20i = _mul(b[4], b[5], p[0], p[1])
    m21r, m21i = _mul(b[4], b[5], p[2], p[3])
    m22r, m22i = _mul(b[4], b[5], p[4], p[5])
    sr = _s_of_m(m00r, m01r, m02r, m10r, m11r, m12r, m20r, m21r, m22r)
    si = _s_of_m(m00i, m01i, m02i, m10i, m11i, m12i, m20i, m21i, m22i)
    TH[lev, 0, leg, 7, ln] = sr[0]
    TH[lev, 0, leg, 8, ln] = sr[1]
    TH[lev, 0, leg, 9, ln] = sr[2]
    TH[lev, 0, leg, 10, ln] = sr[3]
    TH[lev, 0, leg, 11, ln] = sr[4]
    TH[lev, 0, leg, 12, ln] = sr[5]
    TH[lev, 0, leg, 13, ln] = sr[6]
    TH[lev, 0, leg, 14, ln] = sr[7]
    TH[lev, 0, leg, 15, ln] = sr[8]
    TH[lev, 0, leg, 16, ln] = sr[9]
    TH[lev, 1, leg, 7, ln] = si[0]
    TH[lev, 1, leg, 8, ln] = si[1]
    TH[lev, 1, leg, 9, ln] = si[2]
    TH[lev, 1, leg, 10, ln] = si[3]
    TH[lev, 1, leg, 11, ln] = si[4]
    TH[lev, 1, leg, 12, ln] = si[5]
    TH[lev, 1, leg, 13, ln] = si[6]
    TH[lev, 1, leg, 14, ln] = si[7]
    TH[lev, 1, leg, 15, ln] = si[8]
    TH[lev, 1, leg, 16, ln] = si[9]


@njit(inline="always", **_O)
def _vec3(par, k, o, leg, q0):
    """Anchor ``q0 .. q0 + 2`` of a leg, coefficient of ``t^o``: ``(x_r, x_i, y_r, y_i, z_r, z_i)``."""
    return (
        par[k, o, leg, q0].real,
        par[k, o, leg, q0].imag,
        par[k, o, leg, q0 + 1].real,
        par[k, o, leg, q0 + 1].imag,
        par[k, o, leg, q0 + 2].real,
        par[k, o, leg, q0 + 2].imag,
    )


@njit(**_O)
def path_coefficients(par, k, POLY, ln):
    """Lane ``ln``'s leg coefficients as polynomials in ``t`` (``POLY`` (3, 2, 6, 17, L): the
    coefficients of ``t^0, t^1, t^2``, real and imaginary parts) from input ``k``'s parameter path
    ``par[k]`` (3, 6, 7): with ``b(t) = b_0 + t b_1``, ``p(t) = p_0 + t p_1`` and
    ``c(t) = c_0 + t c_1 + t^2 c_2``, ``d = p - b`` and ``s = p + b`` are linear and ``S'(b p^T)``
    is quadratic (``S'`` is linear in ``M = b p^T``: ``S'(b_0 p_0^T) + t (S'(b_1 p_0^T) +
    S'(b_0 p_1^T)) + t^2 S'(b_1 p_1^T)``). Formed once per path, so that a step only evaluates
    polynomials."""
    for leg in range(6):
        b0, p0 = _vec3(par, k, 0, leg, 0), _vec3(par, k, 0, leg, 3)
        b1, p1 = _vec3(par, k, 1, leg, 0), _vec3(par, k, 1, leg, 3)
        for o in range(3):
            POLY[o, 0, leg, 0, ln] = par[k, o, leg, 6].real
            POLY[o, 1, leg, 0, ln] = par[k, o, leg, 6].imag
        for a in range(3):
            for ri in range(2):
                POLY[0, ri, leg, 1 + a, ln] = p0[2 * a + ri] - b0[2 * a + ri]
                POLY[0, ri, leg, 4 + a, ln] = p0[2 * a + ri] + b0[2 * a + ri]
                POLY[1, ri, leg, 1 + a, ln] = p1[2 * a + ri] - b1[2 * a + ri]
                POLY[1, ri, leg, 4 + a, ln] = p1[2 * a + ri] + b1[2 * a + ri]
                POLY[2, ri, leg, 1 + a, ln] = 0.0
                POLY[2, ri, leg, 4 + a, ln] = 0.0
        _store_s(POLY, 0, leg, ln, b0, p0)
        _store_s(POLY, 1, leg, ln, b1, p0)
        _store_s(POLY, 2, leg, ln, b0, p1)  # level 2 as scratch for the second term
        for j in range(7, 17):
            for ri in range(2):
                POLY[1, ri, leg, j, ln] = POLY[1, ri, leg, j, ln] + POLY[2, ri, leg, j, ln]
        _store_s(POLY, 2, leg, ln, b1, p1)


@njit(inline="always", **_O)
def _theta0(POLY, ri, leg, j, ln, t):
    """``theta_j(t)`` of lane ``ln`` (one expression for :func:`theta`, :func:`theta_c` and
    :func:`_lane_constants`: the same bits)."""
    return POLY[0, ri, leg, j, ln] + t * (POLY[1, ri, leg, j, ln] + t * POLY[2, ri, leg, j, ln])


@njit(inline="always", **_O)
def _theta1(POLY, ri, leg, j, ln, t):
    """``theta_j'(t)`` of lane ``ln``."""
    return POLY[1, ri, leg, j, ln] + 2.0 * t * POLY[2, ri, leg, j, ln]


@njit(**_O)
def theta(POLY, tt, TH, n):
    """The leg coefficients ``theta(t)`` of every lane at its ``tt[ln]`` into ``TH[0]`` (3, 2, 6,
    17, L) from their polynomials ``POLY`` (:func:`path_coefficients`), ``theta'(t)`` into
    ``TH[1]`` and ``theta''/2`` into ``TH[2]`` (the Taylor coefficients of ``theta(t + s)``; Newton
    on a target system reads ``TH[0]`` alone, and the two rows it does not need cost less than a
    second compiled form). Where only ``c`` moves, the others' higher coefficients are 0 and they
    keep their values exactly. One short loop over the lanes per coefficient."""
    for ri in range(2):
        for leg in range(6):
            for j in range(NTH):
                for ln in range(n):
                    TH[0, ri, leg, j, ln] = _theta0(POLY, ri, leg, j, ln, tt[ln])
                for ln in range(n):
                    TH[1, ri, leg, j, ln] = _theta1(POLY, ri, leg, j, ln, tt[ln])
                    TH[2, ri, leg, j, ln] = POLY[2, ri, leg, j, ln]


@njit(inline="always", **_O)
def theta_c(POLY, tt, TH, n):
    """:func:`theta` of the leg constants alone (``j = 0``), the only coefficients that move on a
    fibre (a known geometry). The others' values at any ``t >= 0`` are the same bits as at
    ``t = 0`` (their higher terms are signed zeros), written once per path by
    :func:`_lane_constants`; a fibre step reads no other coefficient's ``theta'`` or
    ``theta''``."""
    for ri in range(2):
        for leg in range(6):
            for ln in range(n):
                TH[0, ri, leg, 0, ln] = _theta0(POLY, ri, leg, 0, ln, tt[ln])
                TH[1, ri, leg, 0, ln] = _theta1(POLY, ri, leg, 0, ln, tt[ln])
                TH[2, ri, leg, 0, ln] = POLY[2, ri, leg, 0, ln]


@njit(inline="always", **_O)
def theta_step(POLY, tt, TH, moving, n):
    """A step's coefficients at each lane's ``tt``: :func:`theta` where the anchors move,
    :func:`theta_c` on a fibre."""
    if moving:
        theta(POLY, tt, TH, n)
    else:
        theta_c(POLY, tt, TH, n)


@njit(inline="always", **_O)
def _lane_constants(POLY, TH, ln):
    """Lane ``ln``'s coefficients other than the leg constants at ``t = 0`` (:func:`theta`'s
    expression), for the steps of a fibre (:func:`theta_c`)."""
    for ri in range(2):
        for leg in range(6):
            for j in range(1, NTH):
                TH[0, ri, leg, j, ln] = _theta0(POLY, ri, leg, j, ln, 0.0)


# ------------------------------------------------------------------------------ features
@njit(inline="always", **_O)
def _pp(U, V, a, b, ln):
    """``u_a v_b`` in lane ``ln`` (complex, split parts)."""
    return _mul(U[0, a, ln], U[1, a, ln], V[0, b, ln], V[1, b, ln])


@njit(inline="always", **_O)
def _put(F, f, ln, v, scale, add):
    if add:
        F[0, f, ln] += scale * v[0]
        F[1, f, ln] += scale * v[1]
    else:
        F[0, f, ln] = scale * v[0]
        F[1, f, ln] = scale * v[1]


# One expression per feature, shared by the two loop orders of :func:`features` (the same
# operations in the same order in a lane, so the same bits).
@njit(inline="always", **_O)
def _f_st(U, V, ln):
    a0 = _pp(U, V, 0, 4, ln)
    a1 = _pp(U, V, 1, 5, ln)
    a2 = _pp(U, V, 2, 6, ln)
    a3 = _pp(U, V, 3, 7, ln)
    b0 = _pp(V, U, 0, 4, ln)
    b1 = _pp(V, U, 1, 5, ln)
    b2 = _pp(V, U, 2, 6, ln)
    b3 = _pp(V, U, 3, 7, ln)
    return (
        0.5 * ((a0[0] + a1[0] + a2[0] + a3[0]) + (b0[0] + b1[0] + b2[0] + b3[0])),
        0.5 * ((a0[1] + a1[1] + a2[1] + a3[1]) + (b0[1] + b1[1] + b2[1] + b3[1])),
    )


@njit(inline="always", **_O)
def _f_sum4(U, V, o, ln):
    """``sum_{a<4} u_{o+a} v_{o+a}``: ``gg`` (o = 4) and ``ee`` (o = 0)."""
    p0 = _pp(U, V, o, o, ln)
    p1 = _pp(U, V, o + 1, o + 1, ln)
    p2 = _pp(U, V, o + 2, o + 2, ln)
    p3 = _pp(U, V, o + 3, o + 3, ln)
    return p0[0] + p1[0] + p2[0] + p3[0], p0[1] + p1[1] + p2[1] + p3[1]


@njit(inline="always", **_O)
def _f_d(U, V, a, ln):
    """``D_a = u_e0 v_ga - v_g0 u_ea + v_e0 u_ga - u_g0 v_ea`` (a = 1..3, ``g_a = x_{4+a}``)."""
    t1 = _pp(U, V, 0, 4 + a, ln)
    t2 = _pp(V, U, 4, a, ln)
    t3 = _pp(V, U, 0, 4 + a, ln)
    t4 = _pp(U, V, 4, a, ln)
    return (t1[0] - t2[0]) + (t3[0] - t4[0]), (t1[1] - t2[1]) + (t3[1] - t4[1])


@njit(inline="always", **_O)
def _f_x(U, V, a, ln):
    """``X_a = (v_gv x u_ev)_a + (u_gv x v_ev)_a`` ((a, b, c) cyclic; ``e_v = x_1..3``,
    ``g_v = x_5..7``)."""
    b = (a + 1) % 3
    c = (a + 2) % 3
    t1 = _pp(V, U, 5 + b, 1 + c, ln)
    t2 = _pp(V, U, 5 + c, 1 + b, ln)
    t3 = _pp(U, V, 5 + b, 1 + c, ln)
    t4 = _pp(U, V, 5 + c, 1 + b, ln)
    return (t1[0] - t2[0]) + (t3[0] - t4[0]), (t1[1] - t2[1]) + (t3[1] - t4[1])


@njit(inline="always", **_O)
def _f_e(U, V, a, b, ln):
    """The feature of ``S'_ab``: ``u_a v_a`` on the diagonal, ``u_a v_b + u_b v_a`` off it."""
    t1 = _pp(U, V, a, b, ln)
    if a == b:
        return t1
    t2 = _pp(U, V, b, a, ln)
    return t1[0] + t2[0], t1[1] + t2[1]


#: the entries of S' in the order of theta and the features: ww xx yy zz wx wy wz xy xz yz
_EA = (0, 1, 2, 3, 0, 0, 0, 1, 1, 2)
_EB = (0, 1, 2, 3, 1, 2, 3, 2, 3, 3)


@njit(**_O)
def features(U, V, F, scale, n):
    """``F = scale phi(u, v)`` in lanes ``< n`` (``U, V`` (2, 8, L), ``F`` (2, 19, L)): the
    polarised features of the bilinear forms ``u^T Q v``, in this order: ``st = (u_e.v_g +
    u_g.v_e)/2`` (the Study quadric), ``gg = u_g.v_g``, then the feature of each coefficient:
    ``u_e.v_e`` (of c), ``D`` (of d), ``X`` (of s) and those of the entries of ``S'``.
    Coordinates: ``e = x_0..3``, ``g = x_4..7``. Many lanes: one loop over the lanes per feature
    (vectorised); a few: one lane at a time."""
    if n < VECTOR_LANES:
        for ln in range(n):
            _put(F, 0, ln, _f_st(U, V, ln), scale, False)
            _put(F, 1, ln, _f_sum4(U, V, 4, ln), scale, False)
            _put(F, 2, ln, _f_sum4(U, V, 0, ln), scale, False)
            for a in range(1, 4):
                _put(F, 2 + a, ln, _f_d(U, V, a, ln), scale, False)
            for a in range(3):
                _put(F, 6 + a, ln, _f_x(U, V, a, ln), scale, False)
            for j in range(10):
                _put(F, 9 + j, ln, _f_e(U, V, _EA[j], _EB[j], ln), scale, False)
        return
    for ln in range(n):
        _put(F, 0, ln, _f_st(U, V, ln), scale, False)
    for ln in range(n):
        _put(F, 1, ln, _f_sum4(U, V, 4, ln), scale, False)
    for ln in range(n):
        _put(F, 2, ln, _f_sum4(U, V, 0, ln), scale, False)
    for a in range(1, 4):
        for ln in range(n):
            _put(F, 2 + a, ln, _f_d(U, V, a, ln), scale, False)
    for a in range(3):
        for ln in range(n):
            _put(F, 6 + a, ln, _f_x(U, V, a, ln), scale, False)
    for j in range(10):
        a, b = _EA[j], _EB[j]
        for ln in range(n):
            _put(F, 9 + j, ln, _f_e(U, V, a, b, ln), scale, False)


@njit(inline="always", **_O)
def const_rows(F, out, n):
    """The parts of ``H`` without a coefficient, as the rows' first terms: ``out[0] = st`` (the
    Study quadric), ``out[1 + leg] = gg``; row 7 is not touched. (``0.0 +``: the value
    :func:`combine` always started from, so the same bits, a zero's sign included.)"""
    for ln in range(n):
        out[0, 0, ln] = 0.0 + F[0, 0, ln]
        out[1, 0, ln] = 0.0 + F[1, 0, ln]
    for m in range(1, 7):
        for ln in range(n):
            out[0, m, ln] = 0.0 + F[0, 1, ln]
            out[1, m, ln] = 0.0 + F[1, 1, ln]


@njit(inline="always", **_O)
def accumulate(F, G, n):
    """``F += G`` over the features (``F, G`` (2, 19, W)): a sum of two features' terms formed
    apart, so that :func:`features` has one form (``F = scale phi``), compiled once."""
    for ri in range(2):
        for f in range(NF):
            for ln in range(n):
                F[ri, f, ln] = F[ri, f, ln] + G[ri, f, ln]


# The flags and levels these functions once took were constants at every call site, and numba
# compiles a function called from compiled code once per *literal* argument: features twice,
# combine three times, theta twice. One form each, with the level's slice of ``TH`` passed in,
# compiles each once (docs/kernels.md, "One compiled form per tracker function").
@njit(**_O)
def combine(THl, F, out, n):
    """``out[1 + leg] += theta_leg . phi`` (``THl`` (2, 6, 17, L) one level of the coefficients,
    the features ``F`` (2, 19, L)); rows 0 and 7 are not touched. ``out`` (2, 8, L). The terms are
    added in the order of the coefficients, whichever loop order runs (the same bits)."""
    if n < VECTOR_LANES:
        for ln in range(n):
            for leg in range(6):
                m = 1 + leg
                sr, si = out[0, m, ln] + 0.0, out[1, m, ln] + 0.0
                for j in range(NTH):
                    a, b = THl[0, leg, j, ln], THl[1, leg, j, ln]
                    fr, fi = F[0, 2 + j, ln], F[1, 2 + j, ln]
                    sr = sr + (a * fr - b * fi)
                    si = si + (a * fi + b * fr)
                out[0, m, ln] = sr
                out[1, m, ln] = si
        return
    for leg in range(6):
        m = 1 + leg
        for ln in range(n):
            out[0, m, ln] = out[0, m, ln] + 0.0
            out[1, m, ln] = out[1, m, ln] + 0.0
        for j in range(NTH):
            for ln in range(n):
                a, b = THl[0, leg, j, ln], THl[1, leg, j, ln]
                fr, fi = F[0, 2 + j, ln], F[1, 2 + j, ln]
                out[0, m, ln] = out[0, m, ln] + (a * fr - b * fi)
                out[1, m, ln] = out[1, m, ln] + (a * fi + b * fr)


@njit(**_O)
def combine_c(THl, F, out, n):
    """``out[1 + leg] += c_leg e.e``: :func:`combine` of a level whose only non-zero coefficient
    is the leg constant (the fibre homotopy: only ``c`` moves)."""
    for leg in range(6):
        for ln in range(n):
            a, b = THl[0, leg, 0, ln], THl[1, leg, 0, ln]
            out[0, 1 + leg, ln] += a * F[0, 2, ln] - b * F[1, 2, ln]
            out[1, 1 + leg, ln] += a * F[1, 2, ln] + b * F[0, 2, ln]


# ------------------------------------------------------------------------------ Jacobian, residual
# One expression per entry of a leg's gradient row ``2 Q_leg x`` (shared by both loop orders of
# :func:`jacobian`: the same bits). ``Q x`` by blocks: ``e``: ``c e + S' e + (d . g_v,
# -d g_0 + s x g_v)``; ``g``: ``g + (-d . e_v, e_0 d + e_v x s)``. theta's entries: c 0,
# d 1..3, s 4..6, S' 7..16 (ww xx yy zz wx wy wz xy xz yz).
@njit(inline="always", **_O)
def _tx(TH, leg, j, X, i, ln):
    """``theta_j x_i`` (complex) of lane ``ln``."""
    return _mul(TH[0, 0, leg, j, ln], TH[0, 1, leg, j, ln], X[0, i, ln], X[1, i, ln])


@njit(inline="always", **_O)
def _cx(TH, leg, j, X, i, ln):
    """``(c + S'_jj) x_i``: the diagonal of the e block."""
    return _mul(
        TH[0, 0, leg, 0, ln] + TH[0, 0, leg, j, ln],
        TH[0, 1, leg, 0, ln] + TH[0, 1, leg, j, ln],
        X[0, i, ln],
        X[1, i, ln],
    )


@njit(inline="always", **_O)
def _j_e(t0, t1, t2, t3, u, v, h):
    """``2 ((t0 + t1 + t2 + t3) + (u - v - h))``: an e row."""
    return (
        2.0 * ((t0[0] + t1[0] + t2[0] + t3[0]) + (u[0] - v[0] - h[0])),
        2.0 * ((t0[1] + t1[1] + t2[1] + t3[1]) + (u[1] - v[1] - h[1])),
    )


@njit(inline="always", **_O)
def _j0(TH, leg, X, ln):
    q0 = _tx(TH, leg, 1, X, 5, ln)
    q1 = _tx(TH, leg, 2, X, 6, ln)
    q2 = _tx(TH, leg, 3, X, 7, ln)
    c0 = _cx(TH, leg, 7, X, 0, ln)
    w1 = _tx(TH, leg, 11, X, 1, ln)
    w2 = _tx(TH, leg, 12, X, 2, ln)
    w3 = _tx(TH, leg, 13, X, 3, ln)
    return (
        2.0 * ((c0[0] + w1[0] + w2[0] + w3[0]) + (q0[0] + q1[0] + q2[0])),
        2.0 * ((c0[1] + w1[1] + w2[1] + w3[1]) + (q0[1] + q1[1] + q2[1])),
    )


@njit(inline="always", **_O)
def _j1(TH, leg, X, ln):
    return _j_e(
        _tx(TH, leg, 11, X, 0, ln),
        _cx(TH, leg, 8, X, 1, ln),
        _tx(TH, leg, 14, X, 2, ln),
        _tx(TH, leg, 15, X, 3, ln),
        _tx(TH, leg, 5, X, 7, ln),
        _tx(TH, leg, 6, X, 6, ln),
        _tx(TH, leg, 1, X, 4, ln),
    )


@njit(inline="always", **_O)
def _j2(TH, leg, X, ln):
    return _j_e(
        _tx(TH, leg, 12, X, 0, ln),
        _tx(TH, leg, 14, X, 1, ln),
        _cx(TH, leg, 9, X, 2, ln),
        _tx(TH, leg, 16, X, 3, ln),
        _tx(TH, leg, 6, X, 5, ln),
        _tx(TH, leg, 4, X, 7, ln),
        _tx(TH, leg, 2, X, 4, ln),
    )


@njit(inline="always", **_O)
def _j3(TH, leg, X, ln):
    return _j_e(
        _tx(TH, leg, 13, X, 0, ln),
        _tx(TH, leg, 15, X, 1, ln),
        _tx(TH, leg, 16, X, 2, ln),
        _cx(TH, leg, 10, X, 3, ln),
        _tx(TH, leg, 4, X, 6, ln),
        _tx(TH, leg, 5, X, 5, ln),
        _tx(TH, leg, 3, X, 4, ln),
    )


@njit(inline="always", **_O)
def _j4(TH, leg, X, ln):
    k1 = _tx(TH, leg, 1, X, 1, ln)
    k2 = _tx(TH, leg, 2, X, 2, ln)
    k3 = _tx(TH, leg, 3, X, 3, ln)
    return (
        2.0 * (X[0, 4, ln] - (k1[0] + k2[0] + k3[0])),
        2.0 * (X[1, 4, ln] - (k1[1] + k2[1] + k3[1])),
    )


@njit(inline="always", **_O)
def _j_g(TH, leg, X, a, ln):
    """Row ``5 + a`` (a = 0..2): ``2 (g_a + e_0 d_a + (e_v x s)_a)``."""
    b = (a + 1) % 3
    c = (a + 2) % 3
    e = _tx(TH, leg, 1 + a, X, 0, ln)
    v = _tx(TH, leg, 4 + c, X, 1 + b, ln)
    w = _tx(TH, leg, 4 + b, X, 1 + c, ln)
    return (
        2.0 * (X[0, 5 + a, ln] + e[0] + (v[0] - w[0])),
        2.0 * (X[1, 5 + a, ln] + e[1] + (v[1] - w[1])),
    )


@njit(inline="always", **_O)
def _jset(A, m, i, ln, v):
    A[0, m, i, ln] = v[0]
    A[1, m, i, ln] = v[1]


@njit(**_O)
def jacobian(TH, X, CH, A, n):
    """``A`` (2, 8, 8, L) = ``dH/dx`` at ``X`` (2, 8, L): row 0 ``(x_g, x_e)`` (the Study
    quadric), rows ``1 + leg`` the gradients ``2 Q_leg x`` and row 7 the chart ``CH`` (2, 8, L).
    Many lanes: one loop over the lanes per entry (vectorised); a few: one lane at a time."""
    for ln in range(n):
        for a in range(4):
            A[0, 0, a, ln] = X[0, 4 + a, ln]
            A[1, 0, a, ln] = X[1, 4 + a, ln]
            A[0, 0, 4 + a, ln] = X[0, a, ln]
            A[1, 0, 4 + a, ln] = X[1, a, ln]
        for i in range(8):
            A[0, 7, i, ln] = CH[0, i, ln]
            A[1, 7, i, ln] = CH[1, i, ln]
    if n < VECTOR_LANES:
        for ln in range(n):
            for leg in range(6):
                m = 1 + leg
                _jset(A, m, 0, ln, _j0(TH, leg, X, ln))
                _jset(A, m, 1, ln, _j1(TH, leg, X, ln))
                _jset(A, m, 2, ln, _j2(TH, leg, X, ln))
                _jset(A, m, 3, ln, _j3(TH, leg, X, ln))
                _jset(A, m, 4, ln, _j4(TH, leg, X, ln))
                for a in range(3):
                    _jset(A, m, 5 + a, ln, _j_g(TH, leg, X, a, ln))
        return
    for leg in range(6):
        m = 1 + leg
        for ln in range(n):
            _jset(A, m, 0, ln, _j0(TH, leg, X, ln))
        for ln in range(n):
            _jset(A, m, 1, ln, _j1(TH, leg, X, ln))
        for ln in range(n):
            _jset(A, m, 2, ln, _j2(TH, leg, X, ln))
        for ln in range(n):
            _jset(A, m, 3, ln, _j3(TH, leg, X, ln))
        for ln in range(n):
            _jset(A, m, 4, ln, _j4(TH, leg, X, ln))
        for a in range(3):
            for ln in range(n):
                _jset(A, m, 5 + a, ln, _j_g(TH, leg, X, a, ln))


@njit(inline="always", **_O)
def rows_half(A, X, out, n):
    """``out[m] = x . A[m] / 2`` for rows ``m < 7``: the quadrics' values ``x^T Q_m x`` from the
    Jacobian's rows ``2 Q_m x`` (Euler's identity for quadratic forms)."""
    for m in range(7):
        for ln in range(n):
            re = 0.0
            im = 0.0
            for i in range(8):
                re += A[0, m, i, ln] * X[0, i, ln] - A[1, m, i, ln] * X[1, i, ln]
                im += A[0, m, i, ln] * X[1, i, ln] + A[1, m, i, ln] * X[0, i, ln]
            out[0, m, ln] = 0.5 * re
            out[1, m, ln] = 0.5 * im


@njit(inline="always", **_O)
def chart_row(CH, X, out, n):
    """``out[7] = a . x - 1`` (the chart's equation)."""
    for ln in range(n):
        re = 0.0
        im = 0.0
        for i in range(8):
            re += CH[0, i, ln] * X[0, i, ln] - CH[1, i, ln] * X[1, i, ln]
            im += CH[0, i, ln] * X[1, i, ln] + CH[1, i, ln] * X[0, i, ln]
        out[0, 7, ln] = re - 1.0
        out[1, 7, ln] = im


@njit(**_O)
def residual(TH, X, CH, F, out, n):
    """``out`` (2, 8, W) = ``H(x)``: the Study quadric, the legs ``x^T Q(theta) x``, the chart;
    ``F`` (2, 19, W) scratch (left holding ``phi(x, x)``)."""
    features(X, X, F, 1.0, n)
    const_rows(F, out, n)
    combine(TH[0], F, out, n)
    chart_row(CH, X, out, n)


# ------------------------------------------------------------------------------ LU and solves
@njit(**_O)
def _lu_each(A, L, piv, D, n):
    """:func:`lu` one lane at a time (a few lanes): the same operations in the same order in a
    lane, so the same bits."""
    for ln in range(n):
        for k in range(8):
            p = k
            best = A[0, k, k, ln] * A[0, k, k, ln] + A[1, k, k, ln] * A[1, k, k, ln]
            for i in range(k + 1, 8):
                v = A[0, i, k, ln] * A[0, i, k, ln] + A[1, i, k, ln] * A[1, i, k, ln]
                if v > best:
                    best = v
                    p = i
            piv[k, ln] = p
            if p != k:
                for j in range(k, 8):
                    A[0, k, j, ln], A[0, p, j, ln] = A[0, p, j, ln], A[0, k, j, ln]
                    A[1, k, j, ln], A[1, p, j, ln] = A[1, p, j, ln], A[1, k, j, ln]
                for j in range(k):
                    L[0, k, j, ln], L[0, p, j, ln] = L[0, p, j, ln], L[0, k, j, ln]
                    L[1, k, j, ln], L[1, p, j, ln] = L[1, p, j, ln], L[1, k, j, ln]
            s = A[0, k, k, ln] * A[0, k, k, ln] + A[1, k, k, ln] * A[1, k, k, ln]
            rr = A[0, k, k, ln] / s
            ri = -A[1, k, k, ln] / s
            D[0, k, ln] = rr
            D[1, k, ln] = ri
            A[0, k, k, ln] = 0.0
            A[1, k, k, ln] = 0.0
            for i in range(k + 1, 8):
                fr = A[0, i, k, ln] * rr - A[1, i, k, ln] * ri
                fi = A[0, i, k, ln] * ri + A[1, i, k, ln] * rr
                L[0, i, k, ln] = fr
                L[1, i, k, ln] = fi
                A[0, i, k, ln] = 0.0
                A[1, i, k, ln] = 0.0
                for j in range(k + 1, 8):
                    A[0, i, j, ln] -= fr * A[0, k, j, ln] - fi * A[1, k, j, ln]
                    A[1, i, j, ln] -= fr * A[1, k, j, ln] + fi * A[0, k, j, ln]


@njit(**_O)
def _solve_each(A, L, piv, D, B, out, n):
    """:func:`solve` one lane at a time (the same bits)."""
    for ln in range(n):
        for i in range(8):
            out[0, i, ln] = B[0, i, ln]
            out[1, i, ln] = B[1, i, ln]
        for k in range(7):
            p = piv[k, ln]
            if p != k:
                out[0, k, ln], out[0, p, ln] = out[0, p, ln], out[0, k, ln]
                out[1, k, ln], out[1, p, ln] = out[1, p, ln], out[1, k, ln]
        for i in range(1, 8):
            sr = out[0, i, ln]
            si = out[1, i, ln]
            for j in range(i):
                sr -= L[0, i, j, ln] * out[0, j, ln] - L[1, i, j, ln] * out[1, j, ln]
                si -= L[0, i, j, ln] * out[1, j, ln] + L[1, i, j, ln] * out[0, j, ln]
            out[0, i, ln] = sr
            out[1, i, ln] = si
        for i in range(7, -1, -1):
            sr = out[0, i, ln]
            si = out[1, i, ln]
            for j in range(i + 1, 8):
                sr -= A[0, i, j, ln] * out[0, j, ln] - A[1, i, j, ln] * out[1, j, ln]
                si -= A[0, i, j, ln] * out[1, j, ln] + A[1, i, j, ln] * out[0, j, ln]
            out[0, i, ln] = sr * D[0, i, ln] - si * D[1, i, ln]
            out[1, i, ln] = sr * D[1, i, ln] + si * D[0, i, ln]


@njit(**_O)
def lu(A, L, piv, D, Wk, n):
    """LU with partial pivoting of every lane's 8x8 complex ``A`` (2, 8, 8, W): ``A`` becomes the
    strictly upper part of U, ``L`` (2, 8, 8, W) the multipliers (strictly lower; its other
    entries must stay 0), ``D`` (2, 8, W) the reciprocals of U's diagonal (non-finite where a pivot
    is exactly 0: that lane's solves give non-finite values, which its step rejects), ``piv[k]``
    the row swapped with row ``k`` at step ``k``; ``Wk`` (2, 8, W) scratch. Each lane loop writes
    one row of one array and reads other arrays or the element it writes (the pivot row is copied
    into ``Wk`` first), so that the compiler can vectorise it; below :data:`VECTOR_LANES` lanes,
    :func:`_lu_each`."""
    if n < VECTOR_LANES:
        _lu_each(A, L, piv, D, n)
        return
    for k in range(8):
        for ln in range(n):
            piv[k, ln] = k
            D[0, k, ln] = A[0, k, k, ln] * A[0, k, k, ln] + A[1, k, k, ln] * A[1, k, k, ln]
        for i in range(k + 1, 8):
            for ln in range(n):
                v = A[0, i, k, ln] * A[0, i, k, ln] + A[1, i, k, ln] * A[1, i, k, ln]
                if v > D[0, k, ln]:
                    D[0, k, ln] = v
                    piv[k, ln] = i
        for ln in range(n):
            p = piv[k, ln]
            if p != k:
                for j in range(k, 8):
                    A[0, k, j, ln], A[0, p, j, ln] = A[0, p, j, ln], A[0, k, j, ln]
                    A[1, k, j, ln], A[1, p, j, ln] = A[1, p, j, ln], A[1, k, j, ln]
                for j in range(k):
                    L[0, k, j, ln], L[0, p, j, ln] = L[0, p, j, ln], L[0, k, j, ln]
                    L[1, k, j, ln], L[1, p, j, ln] = L[1, p, j, ln], L[1, k, j, ln]
        for ln in range(n):
            s = A[0, k, k, ln] * A[0, k, k, ln] + A[1, k, k, ln] * A[1, k, k, ln]
            D[0, k, ln] = A[0, k, k, ln] / s
            D[1, k, ln] = -A[1, k, k, ln] / s
            A[0, k, k, ln] = 0.0
            A[1, k, k, ln] = 0.0
        for j in range(k + 1, 8):
            for ln in range(n):
                Wk[0, j, ln] = A[0, k, j, ln]
                Wk[1, j, ln] = A[1, k, j, ln]
        for i in range(k + 1, 8):
            for ln in range(n):
                fr = A[0, i, k, ln] * D[0, k, ln] - A[1, i, k, ln] * D[1, k, ln]
                fi = A[0, i, k, ln] * D[1, k, ln] + A[1, i, k, ln] * D[0, k, ln]
                L[0, i, k, ln] = fr
                L[1, i, k, ln] = fi
                A[0, i, k, ln] = 0.0
                A[1, i, k, ln] = 0.0
            for j in range(k + 1, 8):
                for ln in range(n):
                    fr, fi = L[0, i, k, ln], L[1, i, k, ln]
                    A[0, i, j, ln] -= fr * Wk[0, j, ln] - fi * Wk[1, j, ln]
                    A[1, i, j, ln] -= fr * Wk[1, j, ln] + fi * Wk[0, j, ln]


@njit(**_O)
def solve(A, L, piv, D, B, out, Wk, n):
    """``out = A^-1 b`` in every lane from :func:`lu`'s factors (``B``, ``out`` (2, 8, W), two
    different arrays; ``Wk`` (2, 8, W) scratch; finished rows are read from ``Wk``, see
    :func:`lu`)."""
    if n < VECTOR_LANES:
        _solve_each(A, L, piv, D, B, out, n)
        return
    for i in range(8):
        for ln in range(n):
            out[0, i, ln] = B[0, i, ln]
            out[1, i, ln] = B[1, i, ln]
    for k in range(7):
        for ln in range(n):
            p = piv[k, ln]
            if p != k:
                out[0, k, ln], out[0, p, ln] = out[0, p, ln], out[0, k, ln]
                out[1, k, ln], out[1, p, ln] = out[1, p, ln], out[1, k, ln]
    for i in range(8):
        for j in range(i):
            for ln in range(n):
                out[0, i, ln] -= L[0, i, j, ln] * Wk[0, j, ln] - L[1, i, j, ln] * Wk[1, j, ln]
                out[1, i, ln] -= L[0, i, j, ln] * Wk[1, j, ln] + L[1, i, j, ln] * Wk[0, j, ln]
        for ln in range(n):
            Wk[0, i, ln] = out[0, i, ln]
            Wk[1, i, ln] = out[1, i, ln]
    for i in range(7, -1, -1):
        for j in range(i + 1, 8):
            for ln in range(n):
                out[0, i, ln] -= A[0, i, j, ln] * Wk[0, j, ln] - A[1, i, j, ln] * Wk[1, j, ln]
                out[1, i, ln] -= A[0, i, j, ln] * Wk[1, j, ln] + A[1, i, j, ln] * Wk[0, j, ln]
        for ln in range(n):
            r, v = out[0, i, ln], out[1, i, ln]
            out[0, i, ln] = r * D[0, i, ln] - v * D[1, i, ln]
            out[1, i, ln] = r * D[1, i, ln] + v * D[0, i, ln]
            Wk[0, i, ln] = out[0, i, ln]
            Wk[1, i, ln] = out[1, i, ln]


@njit(inline="always", **_O)
def norms(V, out, n):
    """``out[ln] = |v_ln|`` (2-norm of 8 complex coordinates)."""
    for ln in range(n):
        s = 0.0
        for i in range(8):
            s += V[0, i, ln] * V[0, i, ln] + V[1, i, ln] * V[1, i, ln]
        out[ln] = math.sqrt(s)


# ------------------------------------------------------------------------------ Taylor predictor
@njit(inline="always", **_O)
def _negate_rhs(R, n):
    """``R = -R`` on rows 0..6, 0 on the chart's row (the chart fixes ``a . x_k = 0``)."""
    for m in range(7):
        for ln in range(n):
            R[0, m, ln] = -R[0, m, ln]
            R[1, m, ln] = -R[1, m, ln]
    for ln in range(n):
        R[0, 7, ln] = 0.0
        R[1, 7, ln] = 0.0


@njit(inline="always", **_O)
def _higher(TH, FS, k, R, moving, n):
    """Add ``theta' . F_{k-1} + theta''/2 . F_{k-2}`` (the parameters' motion) to ``R``; only the
    leg constants where the anchors do not move."""
    if moving:
        combine(TH[1], FS[k - 1], R, n)
        if k >= 2:
            combine(TH[2], FS[k - 2], R, n)
    else:
        combine_c(TH[1], FS[k - 1], R, n)
        if k >= 2:
            combine_c(TH[2], FS[k - 2], R, n)


@njit(inline="always", **_O)
def _series(U, V, F, scale, add, moving, n, G):
    """A term of the features' series that only the parameters' motion reads (a pair with
    ``x_0``): every feature where the anchors move (added through the scratch ``G``), ``e.e``
    alone where only ``c`` does."""
    if moving:
        if add:
            features(U, V, G, scale, n)
            accumulate(F, G, n)
        else:
            features(U, V, F, scale, n)
        return
    for ln in range(n):
        _put(F, 2, ln, _f_sum4(U, V, 0, ln), scale, add)


@njit(inline="always", **_O)
def taylor(TH, T, A, L, piv, D, FS, Fx, Fy, R, Wk, moving, n):
    """Taylor coefficients ``T[1..4]`` of the path through ``T[0]`` (each lane at its ``t``,
    ``TH`` its coefficients' series there) with the LU ``A, L, piv, D`` of the Jacobian. The
    coefficient of ``s^k`` in ``H(x(t+s), t+s)`` is ``J x_k + r_k`` with ``r_k`` the sum over
    ``l = 0, 1, 2`` of ``theta_l . F_{k-l}`` (``F_m = sum_{i+j=m} phi(x_i, x_j)``, the
    features' series, and without the ``x_0, x_k`` terms for ``l = 0``), so ``J x_k = -r_k``.
    ``FS`` (4, 2, 19, W) holds ``F_0 .. F_3``, ``Fx, Fy`` (2, 19, W) and ``R`` (2, 8, W) scratch."""
    # where only the leg constants move, the parameters' terms read only e.e: the features of
    # the pairs with x_0 are needed for that one alone
    _series(T[0], T[0], FS[0], 1.0, False, moving, n, Fy)
    # k = 1: the parameters' motion only
    for m in range(8):
        for ln in range(n):
            R[0, m, ln] = 0.0
            R[1, m, ln] = 0.0
    _higher(TH, FS, 1, R, moving, n)
    _negate_rhs(R, n)
    solve(A, L, piv, D, R, T[1], Wk, n)
    _series(T[0], T[1], FS[1], 2.0, False, moving, n, Fy)
    # k = 2
    features(T[1], T[1], FS[2], 1.0, n)
    const_rows(FS[2], R, n)
    combine(TH[0], FS[2], R, n)
    _higher(TH, FS, 2, R, moving, n)
    _negate_rhs(R, n)
    solve(A, L, piv, D, R, T[2], Wk, n)
    _series(T[0], T[2], FS[2], 2.0, True, moving, n, Fy)
    # k = 3
    features(T[1], T[2], FS[3], 2.0, n)
    const_rows(FS[3], R, n)
    combine(TH[0], FS[3], R, n)
    _higher(TH, FS, 3, R, moving, n)
    _negate_rhs(R, n)
    solve(A, L, piv, D, R, T[3], Wk, n)
    _series(T[0], T[3], FS[3], 2.0, True, moving, n, Fy)
    # k = 4
    features(T[1], T[3], Fx, 2.0, n)
    features(T[2], T[2], Fy, 1.0, n)
    accumulate(Fx, Fy, n)
    const_rows(Fx, R, n)
    combine(TH[0], Fx, R, n)
    _higher(TH, FS, 4, R, moving, n)
    _negate_rhs(R, n)
    solve(A, L, piv, D, R, T[4], Wk, n)


@njit(inline="always", **_O)
def pade(T, flag, tau, err, n):
    """Per lane: the Padé trust region ``tau = min_i |x_2i / x_3i|`` and the norm ``err`` of the
    local error coefficient (``x_4 - x_3^2 / x_2``); ``flag[i, ln]`` 1 where coordinate ``i``
    uses Padé, 0 the cubic Taylor polynomial (error ``x_4``) where ``x_2`` is negligible against
    ``x_1, x_3`` scaled by ``lambda = max(2^-18, |x_1|)``. Squared moduli throughout."""
    for ln in range(n):
        tau[ln] = math.inf
        err[ln] = 0.0
    for i in range(8):
        for ln in range(n):
            x2r, x2i, x3r, x3i = T[2, 0, i, ln], T[2, 1, i, ln], T[3, 0, i, ln], T[3, 1, i, ln]
            a1 = T[1, 0, i, ln] * T[1, 0, i, ln] + T[1, 1, i, ln] * T[1, 1, i, ln]
            a2 = x2r * x2r + x2i * x2i
            a3 = x3r * x3r + x3i * x3i
            lam = max(1.4551915228366852e-11, a1)  # lambda^2, 2^-36
            c1, c2, c3 = a1 / lam, a2 / (lam * lam), a3 / (lam * lam * lam)
            plain = c2 <= 1e-28 * max(c1, c2, c3)
            pr = x3r * x3r - x3i * x3i  # x3^2 / x2 = x3^2 conj(x2) / |x2|^2
            pi = 2.0 * x3r * x3i
            er = T[4, 0, i, ln] - (0.0 if plain else (pr * x2r + pi * x2i) / a2)
            ei = T[4, 1, i, ln] - (0.0 if plain else (pi * x2r - pr * x2i) / a2)
            flag[i, ln] = 0.0 if plain else 1.0
            r = math.inf if plain else a2 / a3
            tau[ln] = min(tau[ln], r)
            err[ln] += er * er + ei * ei
    for ln in range(n):
        tau[ln] = math.sqrt(tau[ln])
        err[ln] = math.sqrt(err[ln])


@njit(inline="always", **_O)
def predict(T, S, flag, X, CH, n):
    """The prediction at ``t + dt`` of each lane, ``x_0 + s (x_1 + s g)`` with
    ``g = x_2^2 / (x_2 - s x_3)`` (Padé) or ``x_2 + s x_3`` (Taylor), rescaled into the chart
    ``a = conj(x_0)/|x_0|`` (written to ``CH``) so that ``a . x = 1``."""
    for i in range(8):
        for ln in range(n):
            s = S[_DT, ln]
            x2r, x2i, x3r, x3i = T[2, 0, i, ln], T[2, 1, i, ln], T[3, 0, i, ln], T[3, 1, i, ln]
            dr, di = x2r - s * x3r, x2i - s * x3i
            nr, ni = x2r * x2r - x2i * x2i, 2.0 * x2r * x2i
            d = dr * dr + di * di
            use = flag[i, ln] != 0.0
            gr = (nr * dr + ni * di) / d if use else x2r + s * x3r
            gi = (ni * dr - nr * di) / d if use else x2i + s * x3i
            X[0, i, ln] = T[0, 0, i, ln] + s * (T[1, 0, i, ln] + s * gr)
            X[1, i, ln] = T[0, 1, i, ln] + s * (T[1, 1, i, ln] + s * gi)
    for ln in range(n):
        nx = 0.0
        for i in range(8):
            nx += T[0, 0, i, ln] * T[0, 0, i, ln] + T[0, 1, i, ln] * T[0, 1, i, ln]
        nx = 1.0 / math.sqrt(nx)
        sr = 0.0
        si = 0.0
        for i in range(8):
            ar, ai = T[0, 0, i, ln] * nx, -T[0, 1, i, ln] * nx
            CH[0, i, ln] = ar
            CH[1, i, ln] = ai
            sr += ar * X[0, i, ln] - ai * X[1, i, ln]
            si += ar * X[1, i, ln] + ai * X[0, i, ln]
        d = 1.0 / (sr * sr + si * si)
        for i in range(8):
            r, v = X[0, i, ln], X[1, i, ln]
            X[0, i, ln] = (r * sr + v * si) * d
            X[1, i, ln] = (v * sr - r * si) * d


# ------------------------------------------------------------------------------ step control
@njit(inline="always", **_O)
def control(S, T, X, nrm, t1, acc, opts, n):
    """Accept or reject each lane's step: ``acc[ln]`` 1 or 0. An accepted step moves the lane to
    the corrected point and updates ``omega``; a rejected one halves the step and doubles
    ``omega``. A fresh lane (a start solution, no prediction) passes where the corrector finds it
    a solution to ``1e-8 |x|``."""
    kappa, theta_, omega0, end_tol, noise = opts[2], opts[3], opts[4], opts[7], opts[8]
    for ln in range(n):
        n1, n2, n3 = nrm[0, ln], nrm[1, ln], nrm[2, ln]
        last = n3 if t1[ln] >= 1.0 else n2
        scale = 0.0
        for i in range(8):
            scale += X[0, i, ln] ** 2 + X[1, i, ln] ** 2
        scale = math.sqrt(scale)
        floor = noise * scale
        fresh = S[_FRESH, ln] == 1.0
        if fresh:
            good = math.isfinite(last) and n1 <= 1e-8 * scale
        else:
            good = (
                math.isfinite(last)
                and n1 <= kappa * scale
                and n2 <= theta_ * n1 + floor
                and n3 <= theta_ * n2 + floor
                and (t1[ln] < 1.0 or last <= end_tol * scale)
            )
            S[_STEPS, ln] += 1.0
        if good:
            for i in range(8):
                T[0, 0, i, ln] = X[0, i, ln]
                T[0, 1, i, ln] = X[1, i, ln]
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


@njit(inline="always", **_O)
def next_step(S, tau, err, acc, opts, n):
    """The next step of each accepted lane: the smallest of the trust region's share, the step
    whose predicted error is ``a / omega`` and what is left to ``t = 1``."""
    a, beta_tau = opts[0], opts[1]
    for ln in range(n):
        if acc[ln] == 0.0:
            continue
        s = min(1.0 - S[_T, ln], beta_tau * tau[ln])
        e = err[ln]
        if e > 0:
            s = min(s, (a / (S[_OM, ln] * e)) ** 0.25)
        S[_DT, ln] = s


# ------------------------------------------------------------------------------ a queue of paths
@njit(inline="always", **_O)
def _leg_constants(par, k, POLY, ln):
    """Lane ``ln``'s leg constants' coefficients from input ``k``'s path (as
    :func:`path_coefficients` sets them)."""
    for o in range(3):
        for leg in range(6):
            POLY[o, 0, leg, 0, ln] = par[k, o, leg, 6].real
            POLY[o, 1, leg, 0, ln] = par[k, o, leg, 6].imag


@njit(inline="always", **_O)
def _same_anchors(par, k, k2):
    """Whether inputs ``k`` and ``k2`` have the same anchors on their paths (bit for bit)."""
    if k == k2:
        return True
    for o in range(3):
        for leg in range(6):
            for c in range(6):
                if par[k, o, leg, c] != par[k2, o, leg, c]:
                    return False
    return True


@njit(inline="always", **_O)
def _load(S, T, flag, POLY, TH, ln, p, item_k, item_j, starts, par, opts):
    """Lane ``ln`` takes queue entry ``p``: start solution ``item_j[p]`` (scaled to norm 1) on
    input ``item_k[p]``'s parameter path ``par[k]`` (3, 6, 7), at ``t = 0`` with a zero step."""
    k, j = item_k[p], item_j[p]
    nx = 0.0
    for i in range(8):
        nx += starts[j, i].real ** 2 + starts[j, i].imag ** 2
    nx = math.sqrt(nx)
    for i in range(8):
        T[0, 0, i, ln] = starts[j, i].real / nx
        T[0, 1, i, ln] = starts[j, i].imag / nx
        flag[i, ln] = 0.0
        for o in range(1, 5):
            T[o, 0, i, ln] = 0.0
            T[o, 1, i, ln] = 0.0
    # A path with the anchors of the lane's last path (a known geometry: every path of the call)
    # has the same coefficients but the leg constants' (the same bits): only those are set.
    if S[_ACT, ln] == 1.0 and _same_anchors(par, k, item_k[int(S[_ITEM, ln])]):
        _leg_constants(par, k, POLY, ln)
    else:
        path_coefficients(par, k, POLY, ln)
        _lane_constants(POLY, TH, ln)
    S[_T, ln] = 0.0
    S[_DT, ln] = 0.0
    S[_OM, ln] = opts[4]
    S[_STEPS, ln] = 0.0
    S[_REJ, ln] = 0.0
    S[_ITEM, ln] = p
    S[_FRESH, ln] = 1.0
    S[_ACT, ln] = 1.0


@njit(inline="always", **_O)
def _finish(S, T, ln, ok, patch, out_x, out_ok, out_steps):
    """Write lane ``ln``'s path: its point in the common ``patch`` (``patch . x = 1``)."""
    p = int(S[_ITEM, ln])
    s = 0j
    for i in range(8):
        s += patch[i] * complex(T[0, 0, i, ln], T[0, 1, i, ln])
    for i in range(8):
        out_x[p, i] = complex(T[0, 0, i, ln], T[0, 1, i, ln]) / s
    out_ok[p] = ok
    out_steps[p] = int(S[_STEPS, ln])


@njit(inline="always", **_O)
def _move(S, T, flag, POLY, TH, src, dst):
    """Lane ``src``'s path (its state, Taylor coefficients, flags and parameters) into lane
    ``dst``: the active lanes stay ``0 .. n - 1``, so that the loops run over them only."""
    for r in range(_NS):
        S[r, dst] = S[r, src]
    for o in range(5):
        for a in range(2):
            for i in range(8):
                T[o, a, i, dst] = T[o, a, i, src]
    for i in range(8):
        flag[i, dst] = flag[i, src]
    for o in range(3):
        for a in range(2):
            for leg in range(6):
                for j in range(NTH):
                    POLY[o, a, leg, j, dst] = POLY[o, a, leg, j, src]
    _lane_constants(POLY, TH, dst)


@njit(**_O)
def track_queue(par, starts, item_k, item_j, opts, moving, patch, out_x, out_ok, out_steps):
    """Track queue entries ``p`` (start solution ``item_j[p]`` on input ``item_k[p]``'s path),
    ``LANES`` at a time: ``par`` (K, 3, 6, 7) complex, per input the coefficients of
    ``t^0, t^1, t^2`` of each leg's ``(b, p, c)`` (anchors linear); ``starts`` (M, 8);
    ``moving``: whether any anchor moves (else only the leg constants' terms of the Taylor
    series are formed). A lane whose path ends takes the next queue entry; once the queue is
    empty the last active lane moves into it, so that the loops run over the busy lanes only.
    Writes ``out_x[p]`` (the endpoint in the common ``patch``), ``out_ok[p]`` (reached ``t = 1``)
    and ``out_steps[p]``. Releases the GIL."""
    P = len(item_k)
    if P == 0:
        return
    hmin, max_steps = opts[5], opts[6]
    W = LANES
    S = np.zeros((_NS, W))
    T = np.zeros((5, 2, 8, W))
    T2 = np.zeros((5, 2, 8, W))
    flag = np.zeros((8, W))
    POLY = np.zeros((3, 2, 6, NTH, W))
    TH = np.zeros((3, 2, 6, NTH, W))
    X = np.zeros((2, 8, W))
    CH = np.zeros((2, 8, W))
    A = np.zeros((2, 8, 8, W))
    Lm = np.zeros((2, 8, 8, W))
    piv = np.zeros((8, W), np.int64)
    D = np.zeros((2, 8, W))
    Wk = np.zeros((2, 8, W))
    H = np.zeros((2, 8, W))
    DX = np.zeros((2, 8, W))
    FS = np.zeros((4, 2, NF, W))
    Fx = np.zeros((2, NF, W))
    Fy = np.zeros((2, NF, W))
    nrm = np.zeros((3, W))
    t1 = np.zeros(W)
    acc = np.zeros(W)
    tau = np.zeros(W)
    err = np.zeros(W)
    n = min(W, P)
    for ln in range(n):
        _load(S, T, flag, POLY, TH, ln, ln, item_k, item_j, starts, par, opts)
    nxt = n
    while n > 0:
        predict(T, S, flag, X, CH, n)
        final = False
        for ln in range(n):
            t1[ln] = min(S[_T, ln] + S[_DT, ln], 1.0)
            final |= t1[ln] >= 1.0
        theta_step(POLY, t1, TH, moving, n)
        jacobian(TH, X, CH, A, n)
        rows_half(A, X, H, n)
        chart_row(CH, X, H, n)
        lu(A, Lm, piv, D, Wk, n)
        for it in range(3 if final else 2):
            if it:
                residual(TH, X, CH, Fx, H, n)
            solve(A, Lm, piv, D, H, DX, Wk, n)
            if it == 2:  # the third update moves only the lanes that reach t = 1
                for ln in range(n):
                    if t1[ln] < 1.0:
                        for i in range(8):
                            DX[0, i, ln] = 0.0
                            DX[1, i, ln] = 0.0
            for i in range(8):
                for ln in range(n):
                    X[0, i, ln] -= DX[0, i, ln]
                    X[1, i, ln] -= DX[1, i, ln]
            norms(DX, nrm[it], n)
        if not final:
            for ln in range(n):
                nrm[2, ln] = 0.0
        control(S, T, X, nrm, t1, acc, opts, n)
        # Taylor coefficients at the new points (for the accepted lanes, whose t is t1)
        for a in range(2):
            for i in range(8):
                for ln in range(n):
                    T2[0, a, i, ln] = T[0, a, i, ln]
        taylor(TH, T2, A, Lm, piv, D, FS, Fx, Fy, H, Wk, moving, n)
        for ln in range(n):
            if acc[ln] == 1.0:
                for o in range(1, 5):
                    for a in range(2):
                        for i in range(8):
                            T[o, a, i, ln] = T2[o, a, i, ln]
        pade(T, flag, tau, err, n)
        next_step(S, tau, err, acc, opts, n)
        for ln in range(n - 1, -1, -1):
            done = acc[ln] == 1.0 and S[_T, ln] >= 1.0
            failed = not done and (not S[_DT, ln] >= hmin or S[_STEPS, ln] >= max_steps)
            if not (done or failed):
                continue
            _finish(S, T, ln, done, patch, out_x, out_ok, out_steps)
            if nxt < P:
                _load(S, T, flag, POLY, TH, ln, nxt, item_k, item_j, starts, par, opts)
                nxt += 1
            else:
                n -= 1
                if ln != n:
                    _move(S, T, flag, POLY, TH, n, ln)


# ------------------------------------------------------------------------------ Newton in lanes
@njit(inline="always", **_O)
def _inverse_norm(A, Lm, piv, D, B, Y, Wk, out, n):
    """``out[ln] = |J_ln^-1|_F``, column by column from the LU (``B, Y`` (2, 8, W) scratch)."""
    for ln in range(n):
        out[ln] = 0.0
    for k in range(8):
        for i in range(8):
            for ln in range(n):
                B[0, i, ln] = 1.0 if i == k else 0.0
                B[1, i, ln] = 0.0
        solve(A, Lm, piv, D, B, Y, Wk, n)
        for ln in range(n):
            s = 0.0
            for i in range(8):
                s += Y[0, i, ln] * Y[0, i, ln] + Y[1, i, ln] * Y[1, i, ln]
            out[ln] += s
    for ln in range(n):
        out[ln] = math.sqrt(out[ln])


@njit(inline="always", **_O)
def qnorm(TH, out, n):
    """``out[ln] = sqrt(sum_m |Q_m|_F^2)`` of each lane's quadrics (``TH[0]``): the bound of
    Smale's gamma of a quadratic system with ``|J^-1|_F``. The Study quadric contributes 2 (eight
    entries 1/2); a leg ``|c I + S'|_F^2 + 4 |d|^2 + 4 |s|^2 + 4`` (the e-g blocks hold ``d`` and
    the skew matrix of ``s`` twice each, the g block is the identity)."""
    for ln in range(n):
        tot = 2.0
        for leg in range(6):
            cr, ci = TH[0, 0, leg, 0, ln], TH[0, 1, leg, 0, ln]
            s = 4.0
            for a in range(4):
                r = cr + TH[0, 0, leg, 7 + a, ln]
                i = ci + TH[0, 1, leg, 7 + a, ln]
                s += r * r + i * i
            for j in range(11, 17):
                s += 2.0 * (TH[0, 0, leg, j, ln] ** 2 + TH[0, 1, leg, j, ln] ** 2)
            for j in range(1, 7):
                s += 4.0 * (TH[0, 0, leg, j, ln] ** 2 + TH[0, 1, leg, j, ln] ** 2)
            tot += s
        out[ln] = math.sqrt(tot)


@njit(**_O)
def newton_queue(par, x, item_k, charts, iters, out_x, out_beta, out_jn, out_qn):
    """Newton's method on ``x^T Q_m x = 0, a . x = 1`` (the quadrics of input ``item_k[p]`` at
    ``t = 0`` of its path ``par``, the chart ``charts[p]``) for every point ``x[p]``, ``W`` at a
    time: ``iters`` updates (none in a lane whose Jacobian is singular), then at the last iterate
    ``out_beta = |J^-1 F|`` (inf where singular), ``out_jn = |J^-1|_F`` and ``out_qn`` the
    quadrics' norm (:func:`qnorm`)."""
    P = len(item_k)
    W = LANES
    POLY = np.zeros((3, 2, 6, NTH, W))
    TH = np.zeros((3, 2, 6, NTH, W))
    X = np.zeros((2, 8, W))
    CH = np.zeros((2, 8, W))
    A = np.zeros((2, 8, 8, W))
    Lm = np.zeros((2, 8, 8, W))
    piv = np.zeros((8, W), np.int64)
    D = np.zeros((2, 8, W))
    Wk = np.zeros((2, 8, W))
    H = np.zeros((2, 8, W))
    DX = np.zeros((2, 8, W))
    B = np.zeros((2, 8, W))
    tt = np.zeros(W)
    nrm = np.zeros(W)
    jn = np.zeros(W)
    qn = np.zeros(W)
    ok = np.zeros(W)
    for s0 in range(0, P, W):
        n = min(W, P - s0)
        for ln in range(n):
            p = s0 + ln
            k = item_k[p]
            for i in range(8):
                X[0, i, ln], X[1, i, ln] = x[p, i].real, x[p, i].imag
                CH[0, i, ln], CH[1, i, ln] = charts[p, i].real, charts[p, i].imag
            path_coefficients(par, k, POLY, ln)  # the target: par[k]'s t^0 (the rest is 0)
        theta(POLY, tt, TH, n)
        for it in range(iters + 1):
            jacobian(TH, X, CH, A, n)
            rows_half(A, X, H, n)
            chart_row(CH, X, H, n)
            lu(A, Lm, piv, D, Wk, n)
            for ln in range(n):
                ok[ln] = 1.0
            for k in range(8):
                for ln in range(n):
                    if not (math.isfinite(D[0, k, ln]) and math.isfinite(D[1, k, ln])):
                        ok[ln] = 0.0
            solve(A, Lm, piv, D, H, DX, Wk, n)
            if it < iters:
                for i in range(8):
                    for ln in range(n):
                        if ok[ln] == 1.0:
                            X[0, i, ln] -= DX[0, i, ln]
                            X[1, i, ln] -= DX[1, i, ln]
        norms(DX, nrm, n)
        _inverse_norm(A, Lm, piv, D, B, H, Wk, jn, n)
        qnorm(TH, qn, n)
        for ln in range(n):
            p = s0 + ln
            for i in range(8):
                out_x[p, i] = complex(X[0, i, ln], X[1, i, ln])
            good = ok[ln] == 1.0
            out_beta[p] = nrm[ln] if good else math.inf
            out_jn[p] = jn[ln] if good else math.inf
            out_qn[p] = qn[ln]


# one process at a time compiles each of these functions; the others wait and load it
# LLVM level 2 (numba's is 3): the tracker's first solve on an empty cache 51-52 against 62-66
# CPU-s, a solve afterwards as fast (0.83-0.86 against 0.87-0.90 ms), the same bits
# (docs/kernels.md)
store.share_compiles(vars(), llvm_level=2)
