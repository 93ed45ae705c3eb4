"""Kernels of the 12-leg cube mechanism (:class:`parakin.mechanisms.Stewart12`) in its default
Euler-parameter convention, written once.

``residual`` (leg lengths minus the joints; NaN outside ``|lambda| < 1``), ``jacobian``, ``ik``,
``in_domain``, ``on_assembly`` of ``Stewart12`` and of its ``ActiveLegs`` (any subset of the
legs), elementwise and branch-free (:mod:`parakin.kernels._math`): one pose under numba, a batch
on the trailing axis under numpy (what the methods call) and torch. ``p`` (see
``Stewart12.kernel``): for each of the ``n = len(p) // 6`` legs its platform point in the moving
frame (``p[0:3n]``, n x 3), then the base points (``p[3n:6n]``, n x 3).
"""

from __future__ import annotations

from parakin.kernels._math import kernel, nan, sqrt, where
from parakin.kernels.frames import leg_vector


@kernel
def _rotation(x):
    """``l0 = sqrt(1 - |lambda|^2)`` (NaN outside ``|lambda| < 1``) and the nine entries of
    ``R = (2 l0^2 - 1) I + 2 (lam lam^T + l0 [lam]x)``, row by row (docs/ye_stewart12.md#s1.3)."""
    l1, l2, l3 = x[3], x[4], x[5]
    l0sq = 1.0 - (l1 * l1 + l2 * l2 + l3 * l3)
    l0 = sqrt(where(l0sq > 0, l0sq, nan))
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


@kernel
def _leg(p, x, r, k):
    """``w = R p_j(k)`` and the leg vector ``v = M + w - b_k`` (six scalars), eq (2)."""
    a, b = 3 * k, 3 * (len(p) // 6) + 3 * k
    return leg_vector(r, p[a], p[a + 1], p[a + 2], x[0], x[1], x[2], p[b], p[b + 1], p[b + 2])


@kernel
def residual(p, x, q, out):
    """``l_k(pose) - q_k``; NaN where ``|lambda| >= 1`` (a solver iterate may leave the domain:
    there ``l0`` is NaN, so is every off-diagonal entry of ``R`` and with them every ``w``)."""
    l0, r = _rotation(x)
    for k in range(len(p) // 6):
        w0, w1, w2, v0, v1, v2 = _leg(p, x, r, k)
        out[k] = sqrt(v0 * v0 + v1 * v1 + v2 * v2) - q[k]


@kernel
def jacobian(p, x, q, out):
    """``d l / d pose`` (n, 6): ``[e_k, 2 (R p x e_k) . (l0 I + lam lam^T / l0 + [lam]x)]`` (the
    angular velocity of the unit quaternion ``(l0, lam)``); NaN where ``|lambda| >= 1`` (``l0`` NaN,
    as in :func:`residual`)."""
    l0, r = _rotation(x)
    a, b, c = x[3], x[4], x[5]
    # omega / 2 = l0 I + lam lam^T / l0 + [lam]x, entry by entry
    o00, o01, o02 = l0 + a * a / l0, a * b / l0 - c, a * c / l0 + b
    o10, o11, o12 = b * a / l0 + c, l0 + b * b / l0, b * c / l0 - a
    o20, o21, o22 = c * a / l0 - b, c * b / l0 + a, l0 + c * c / l0
    for k in range(len(p) // 6):
        w0, w1, w2, v0, v1, v2 = _leg(p, x, r, k)
        n = sqrt(v0 * v0 + v1 * v1 + v2 * v2)
        e0, e1, e2 = v0 / n, v1 / n, v2 / n
        c0 = w1 * e2 - w2 * e1
        c1 = w2 * e0 - w0 * e2
        c2 = w0 * e1 - w1 * e0
        out[k, 0], out[k, 1], out[k, 2] = e0, e1, e2
        out[k, 3] = 2 * (c0 * o00 + c1 * o10 + c2 * o20)
        out[k, 4] = 2 * (c0 * o01 + c1 * o11 + c2 * o21)
        out[k, 5] = 2 * (c0 * o02 + c1 * o12 + c2 * o22)


@kernel
def ik(p, x, out):
    """Leg lengths ``l_k = |M + R p_j(k) - b_k|`` (eq 2); False (and NaN) where ``|lambda| >= 1``."""
    l0, r = _rotation(x)
    ok = l0 > 0
    for k in range(len(p) // 6):
        w0, w1, w2, v0, v1, v2 = _leg(p, x, r, k)
        out[k] = where(ok, sqrt(v0 * v0 + v1 * v1 + v2 * v2), nan)
    return ok


@kernel
def in_domain(p, x):
    """``|lambda|^2 < 1`` (the caller checks finiteness)."""
    return x[3] * x[3] + x[4] * x[4] + x[5] * x[5] < 1.0


@kernel
def on_assembly(p, x, q):
    """No assembly modes told apart (the base default)."""
    return x[0] == x[0]
