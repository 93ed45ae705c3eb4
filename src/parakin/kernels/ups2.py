"""Kernels of the 2-UPS/(S+SPR)R mechanism (:class:`parakin.mechanisms.UPS2`), written once.

``residual`` (the scalar closed forms of ``UPS2.lengths_closed_form``), ``jacobian``
(differentiated from the same closed forms), ``ik`` (strokes, no stroke-limit check),
``in_domain`` and ``on_assembly``, elementwise and branch-free (:mod:`parakin.kernels._math`):
one pose under numba, a batch on the trailing axis under numpy (what the ``UPS2`` methods call)
and torch. ``p`` (:data:`PARAMS`, by name): ``a, k, c, h, branch`` and the home lengths
``l_home`` (3).
"""

from __future__ import annotations

import math

from parakin.kernels._math import Layout, cos, kernel, maximum, nan, pi, sin, sqrt, where

#: the parameter vector, by name (``UPS2.kernel_params`` packs it; its length is checked once)
PARAMS = Layout(a=1, k=1, c=1, h=1, branch=1, l_home=3)
_A, _K, _C, _H, _BRANCH, _HOME = (
    PARAMS.a,
    PARAMS.k,
    PARAMS.c,
    PARAMS.h,
    PARAMS.branch,
    PARAMS.l_home,
)
_SQ3 = math.sqrt(3.0)


@kernel
def _squares(p, x):
    """``l1^2``, ``Q``, ``s``, ``u``, ``rho``, ``t`` of the closed forms (docs/li2020_2ups.md#s1.7):
    ``l1^2 = 4c^2/9 + 3a^2/4 - (2/sqrt3) a Y``, ``l2,3^2 = Q -/+ s``, ``s = a u sin(beta)``,
    ``Q = u^2 + k^2 + a^2/4 + t^2 - a k cos(beta)``, ``u = rho + k sin(gamma)``,
    ``t = k cos(gamma) + Y - h``, ``rho = branch sqrt(c^2 - Y^2)`` (eq 14, clamped at 0)."""
    a, k, c, h, branch = p[_A], p[_K], p[_C], p[_H], p[_BRANCH]
    beta, gamma, y = x[0], x[1], x[2]
    rho = branch * sqrt(maximum(c * c - y * y, 0.0))
    u = rho + k * sin(gamma)
    t = k * cos(gamma) + y - h
    qq = u * u + (k * k + a * a / 4) + t * t - a * k * cos(beta)
    s = a * u * sin(beta)
    l1 = 4 * c * c / 9 + 0.75 * a * a - (2 / _SQ3) * a * y
    return l1, qq, s, u, rho, t


@kernel
def residual(p, x, q, out):
    """``f_j = l_j(pose) - l_j(home) - q_j`` (m): eq (18) with strokes as inputs."""
    l1, qq, s, u, rho, t = _squares(p, x)
    out[0] = sqrt(maximum(l1, 0.0)) - p[_HOME] - q[0]
    out[1] = sqrt(maximum(qq - s, 0.0)) - p[_HOME + 1] - q[1]
    out[2] = sqrt(maximum(qq + s, 0.0)) - p[_HOME + 2] - q[2]


@kernel
def jacobian(p, x, q, out):
    """``d l_j / d (beta, gamma, Y)`` = ``d(l_j^2) / (2 l_j)``."""
    a, k = p[_A], p[_K]
    beta, gamma, y = x[0], x[1], x[2]
    l1, qq, s, u, rho, t = _squares(p, x)
    drho = -y / rho
    sb, cb, sg, cg = sin(beta), cos(beta), sin(gamma), cos(gamma)
    dq0, dq1, dq2 = a * k * sb, 2 * u * k * cg - 2 * t * k * sg, 2 * u * drho + 2 * t
    ds0, ds1, ds2 = a * u * cb, a * k * cg * sb, a * drho * sb
    n1 = sqrt(l1)
    out[0, 0] = 0.0
    out[0, 1] = 0.0
    out[0, 2] = -(2 / _SQ3) * a / (2 * n1)
    n2 = sqrt(qq - s)
    n3 = sqrt(qq + s)
    out[1, 0] = (dq0 - ds0) / (2 * n2)
    out[1, 1] = (dq1 - ds1) / (2 * n2)
    out[1, 2] = (dq2 - ds2) / (2 * n2)
    out[2, 0] = (dq0 + ds0) / (2 * n3)
    out[2, 1] = (dq1 + ds1) / (2 * n3)
    out[2, 2] = (dq2 + ds2) / (2 * n3)


@kernel
def ik(p, x, out):
    """Strokes ``l(pose) - l(home)``; False (and NaN) where ``|Y| >= c`` (eq 14: no real rho)."""
    ok = abs(x[2]) < p[_C]
    l1, qq, s, u, rho, t = _squares(p, x)
    out[0] = where(ok, sqrt(maximum(l1, 0.0)) - p[_HOME], nan)
    out[1] = where(ok, sqrt(maximum(qq - s, 0.0)) - p[_HOME + 1], nan)
    out[2] = where(ok, sqrt(maximum(qq + s, 0.0)) - p[_HOME + 2], nan)
    return ok


@kernel
def in_domain(p, x):
    """``|Y| < c`` (eq. 14 has a real rho; the caller checks finiteness)."""
    return abs(x[2]) < p[_C]


@kernel
def on_assembly(p, x, q):
    """The working assembly of ``UPS2.fk``: ``|beta|, |gamma| < 90 deg`` modulo 2 pi."""
    ok = True
    for j in range(2):
        wrapped = (x[j] + pi) % (2 * pi) - pi
        ok = ok & (abs(wrapped) < pi / 2)
    return ok
