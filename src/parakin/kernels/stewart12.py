"""Compiled single-pose kernels of the 12-leg cube mechanism (:class:`parakin.mechanisms.Stewart12`)
in its default Euler-parameter convention.

The same equations as ``Stewart12.residual`` (12 leg lengths minus the joints; NaN outside
``|lambda| < 1``), ``jacobian_pose``, ``ik``, ``in_domain``. ``p`` (see ``Stewart12.kernel``): the
platform point of each leg in the moving frame (``p[0:36]``, 12 x 3) and the base points
(``p[36:72]``, 12 x 3).
"""

from __future__ import annotations

import math

from numba import njit

_OPTS = dict(cache=True, error_model="numpy", nogil=True)


@njit(**_OPTS)
def _rotation(x):
    """``l0`` (NaN outside ``|lambda| < 1``) and the nine entries of
    ``R = (2 l0^2 - 1) I + 2 (lam lam^T + l0 [lam]x)``, row by row."""
    l1, l2, l3 = x[3], x[4], x[5]
    l0sq = 1.0 - (l1 * l1 + l2 * l2 + l3 * l3)
    l0 = math.sqrt(l0sq) if l0sq > 0 else math.nan
    d = 2 * l0sq - 1
    return l0, (
        d + 2 * l1 * l1,
        2 * (l1 * l2 - l0 * l3),
        2 * (l1 * l3 + l0 * l2),
        2 * (l2 * l1 + l0 * l3),
        d + 2 * l2 * l2,
        2 * (l2 * l3 - l0 * l1),
        2 * (l3 * l1 - l0 * l2),
        2 * (l3 * l2 + l0 * l1),
        d + 2 * l3 * l3,
    )


@njit(**_OPTS)
def _leg(p, x, r, k):
    """``w = R p_j(k)`` and the leg vector ``v = M + w - b_k`` (six scalars)."""
    a0, a1, a2 = p[3 * k], p[3 * k + 1], p[3 * k + 2]
    w0 = r[0] * a0 + r[1] * a1 + r[2] * a2
    w1 = r[3] * a0 + r[4] * a1 + r[5] * a2
    w2 = r[6] * a0 + r[7] * a1 + r[8] * a2
    return (
        w0,
        w1,
        w2,
        x[0] + w0 - p[36 + 3 * k],
        x[1] + w1 - p[37 + 3 * k],
        x[2] + w2 - p[38 + 3 * k],
    )


@njit(**_OPTS)
def residual(p, x, q, out):
    """``l_k(pose) - q_k``; NaN where ``|lambda| >= 1``."""
    l0, r = _rotation(x)
    for k in range(12):
        if not l0 > 0:
            out[k] = math.nan
            continue
        w0, w1, w2, v0, v1, v2 = _leg(p, x, r, k)
        out[k] = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2) - q[k]


@njit(**_OPTS)
def jacobian(p, x, q, out):
    """``d l / d pose`` (12, 6): ``[e_k, 2 (R p x e_k) . (l0 I + lam lam^T / l0 + [lam]x)]``; NaN
    where ``|lambda| >= 1``."""
    l0, r = _rotation(x)
    if not l0 > 0:
        out[:, :] = math.nan
        return
    a, b, c = x[3], x[4], x[5]
    # omega / 2 = l0 I + lam lam^T / l0 + [lam]x, entry by entry
    o00, o01, o02 = l0 + a * a / l0, a * b / l0 - c, a * c / l0 + b
    o10, o11, o12 = b * a / l0 + c, l0 + b * b / l0, b * c / l0 - a
    o20, o21, o22 = c * a / l0 - b, c * b / l0 + a, l0 + c * c / l0
    for k in range(12):
        w0, w1, w2, v0, v1, v2 = _leg(p, x, r, k)
        n = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
        e0, e1, e2 = v0 / n, v1 / n, v2 / n
        c0 = w1 * e2 - w2 * e1
        c1 = w2 * e0 - w0 * e2
        c2 = w0 * e1 - w1 * e0
        out[k, 0], out[k, 1], out[k, 2] = e0, e1, e2
        out[k, 3] = 2 * (c0 * o00 + c1 * o10 + c2 * o20)
        out[k, 4] = 2 * (c0 * o01 + c1 * o11 + c2 * o21)
        out[k, 5] = 2 * (c0 * o02 + c1 * o12 + c2 * o22)


@njit(**_OPTS)
def ik(p, x, out):
    """Leg lengths; False where ``|lambda| >= 1``."""
    l0, r = _rotation(x)
    if not l0 > 0:
        out[:] = math.nan
        return False
    for k in range(12):
        w0, w1, w2, v0, v1, v2 = _leg(p, x, r, k)
        out[k] = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    return True


@njit(**_OPTS)
def in_domain(p, x):
    """``|lambda|^2 < 1``."""
    return x[3] * x[3] + x[4] * x[4] + x[5] * x[5] < 1.0


@njit(**_OPTS)
def on_assembly(p, x, q):
    """No assembly modes told apart (the base default)."""
    return True
