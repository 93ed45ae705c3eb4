"""Compiled single-pose kernels of the 2-UPS/(S+SPR)R mechanism (:class:`parakin.mechanisms.UPS2`).

The same equations as ``UPS2.residual`` (the scalar closed forms of ``lengths_closed_form``),
``jacobian_pose`` (here differentiated from the same closed forms: equal to the numpy vector form
to rounding), ``ik`` (strokes, no stroke-limit check), ``in_domain`` and ``on_assembly``.
``p`` (see ``UPS2.kernel``): ``a, k, c, h, branch, l1_home, l2_home, l3_home``.
"""

from __future__ import annotations

import math

from numba import njit

_OPTS = dict(cache=True, error_model="numpy", nogil=True)
_SQ3 = math.sqrt(3.0)


@njit(**_OPTS)
def _squares(p, x):
    """``l1^2``, ``Q``, ``s``, ``u``, ``rho`` of the closed forms."""
    a, k, c, h, branch = p[0], p[1], p[2], p[3], p[4]
    beta, gamma, y = x[0], x[1], x[2]
    rho = branch * math.sqrt(max(c * c - y * y, 0.0))
    u = rho + k * math.sin(gamma)
    t = k * math.cos(gamma) + y - h
    qq = u * u + (k * k + a * a / 4) + t * t - a * k * math.cos(beta)
    s = a * u * math.sin(beta)
    l1 = 4 * c * c / 9 + 0.75 * a * a - (2 / _SQ3) * a * y
    return l1, qq, s, u, rho, t


@njit(**_OPTS)
def residual(p, x, q, out):
    """``f_j = l_j(pose) - l_j(home) - q_j`` (m)."""
    l1, qq, s, u, rho, t = _squares(p, x)
    out[0] = math.sqrt(max(l1, 0.0)) - p[5] - q[0]
    out[1] = math.sqrt(max(qq - s, 0.0)) - p[6] - q[1]
    out[2] = math.sqrt(max(qq + s, 0.0)) - p[7] - q[2]


@njit(**_OPTS)
def jacobian(p, x, q, out):
    """``d l_j / d (beta, gamma, Y)`` = ``d(l_j^2) / (2 l_j)``."""
    a, k = p[0], p[1]
    beta, gamma, y = x[0], x[1], x[2]
    l1, qq, s, u, rho, t = _squares(p, x)
    drho = -y / rho
    sb, cb, sg, cg = math.sin(beta), math.cos(beta), math.sin(gamma), math.cos(gamma)
    dq = (a * k * sb, 2 * u * k * cg - 2 * t * k * sg, 2 * u * drho + 2 * t)
    ds = (a * u * cb, a * k * cg * sb, a * drho * sb)
    n1 = math.sqrt(l1)
    out[0, 0] = 0.0
    out[0, 1] = 0.0
    out[0, 2] = -(2 / _SQ3) * a / (2 * n1)
    n2 = math.sqrt(qq - s)
    n3 = math.sqrt(qq + s)
    for j in range(3):
        out[1, j] = (dq[j] - ds[j]) / (2 * n2)
        out[2, j] = (dq[j] + ds[j]) / (2 * n3)


@njit(**_OPTS)
def ik(p, x, out):
    """Strokes ``l(pose) - l(home)``; False where ``|Y| >= c``."""
    if not abs(x[2]) < p[2]:
        for j in range(3):
            out[j] = math.nan
        return False
    l1, qq, s, u, rho, t = _squares(p, x)
    out[0] = math.sqrt(max(l1, 0.0)) - p[5]
    out[1] = math.sqrt(max(qq - s, 0.0)) - p[6]
    out[2] = math.sqrt(max(qq + s, 0.0)) - p[7]
    return True


@njit(**_OPTS)
def in_domain(p, x):
    """``|Y| < c``."""
    return abs(x[2]) < p[2]


@njit(**_OPTS)
def on_assembly(p, x, q):
    """``|beta|, |gamma| < 90 deg`` modulo 2 pi."""
    for j in range(2):
        wrapped = (x[j] + math.pi) % (2 * math.pi) - math.pi
        if not abs(wrapped) < math.pi / 2:
            return False
    return True
