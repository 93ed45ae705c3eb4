"""Kernels of the 3-6 Stewart platform (:class:`parakin.mechanisms.Stewart36`), written once.

``residual`` / ``jacobian`` / ``ik`` / ``in_domain`` / ``on_assembly`` of ``Stewart36``,
elementwise and branch-free (:mod:`parakin.kernels._math`): one pose under numba, a batch on the
trailing axis under numpy (what the ``Stewart36`` methods call) and torch. ``p`` (:data:`PARAMS`,
by name) holds the platform point of each leg in the moving frame (``platform``, 6 x 3) and the
base points (``base``, 6 x 3).
"""

from __future__ import annotations

from parakin.kernels._math import Layout, cos, kernel, sin, sqrt
from parakin.kernels.frames import leg_vector, rotation_zyx

#: the parameter vector, by name (``Stewart36.kernel_params`` packs it; its length is checked once)
PARAMS = Layout(platform=(6, 3), base=(6, 3))
_PLATFORM, _BASE = PARAMS.platform, PARAMS.base


@kernel
def _rotation(x):
    """The nine entries of ``T = Rz(alpha) Ry(beta) Rx(gamma)`` (eq 1), row by row."""
    return rotation_zyx(x[0], x[1], x[2])


@kernel
def _leg(p, x, t, i):
    """``w = T a_i`` and the leg vector ``v = O_A + w - B_i`` of leg ``i`` (six scalars)."""
    a, b = _PLATFORM + 3 * i, _BASE + 3 * i
    return leg_vector(t, p[a], p[a + 1], p[a + 2], x[3], x[4], x[5], p[b], p[b + 1], p[b + 2])


@kernel
def residual(p, x, q, out):
    """``f_i = |T A_p(i) + O_A - B_i|^2 - L_i^2`` (eq 2)."""
    t = _rotation(x)
    for i in range(6):
        w0, w1, w2, v0, v1, v2 = _leg(p, x, t, i)
        out[i] = v0 * v0 + v1 * v1 + v2 * v2 - q[i] * q[i]


@kernel
def jacobian(p, x, q, out):
    """``d f / d pose`` (6, 6): ``2 u_q . (w_i x v_i)`` for the angles (``u_alpha = z``,
    ``u_beta = Rz(alpha) y``, ``u_gamma = T x``) and ``2 v_i`` for X, Y, Z."""
    t = _rotation(x)
    ca, sa = cos(x[0]), sin(x[0])
    for i in range(6):
        w0, w1, w2, v0, v1, v2 = _leg(p, x, t, i)
        c0 = w1 * v2 - w2 * v1
        c1 = w2 * v0 - w0 * v2
        c2 = w0 * v1 - w1 * v0
        out[i, 0] = 2 * c2
        out[i, 1] = 2 * (ca * c1 - sa * c0)
        out[i, 2] = 2 * (t[0] * c0 + t[3] * c1 + t[6] * c2)
        out[i, 3] = 2 * v0
        out[i, 4] = 2 * v1
        out[i, 5] = 2 * v2


@kernel
def ik(p, x, out):
    """Leg lengths; every pose has one (returns True)."""
    t = _rotation(x)
    for i in range(6):
        w0, w1, w2, v0, v1, v2 = _leg(p, x, t, i)
        out[i] = sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    return x[0] == x[0]


@kernel
def in_domain(p, x):
    """Every finite pose (the caller checks finiteness)."""
    return x[0] == x[0]


@kernel
def on_assembly(p, x, q):
    """Above the base, ``Z > 0``."""
    return x[5] > 0
