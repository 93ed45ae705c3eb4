"""Kernels of the 3-P(4S) mechanism (:class:`parakin.mechanisms.P3P4S`), written once.

``residual`` / ``jacobian`` / ``ik`` / ``in_domain`` / ``on_assembly`` of ``P3P4S``, elementwise
and branch-free (:mod:`parakin.kernels._math`): one pose under numba, a batch on the trailing
axis under numpy (what the ``P3P4S`` methods call) and torch. ``p`` (:data:`PARAMS`, by name):
``delta``, ``L``, the radial unit vectors ``e_i`` (``e``, 3 x 3) and the rail unit vectors
``m_i`` (``m``, 3 x 3).
"""

from __future__ import annotations

from parakin.kernels._math import Layout, kernel, nan, sqrt, where

#: the parameter vector, by name (``P3P4S.kernel_params`` packs it; its length is checked once)
PARAMS = Layout(delta=1, L=1, e=(3, 3), m=(3, 3))
_DELTA, _L, _E, _M = PARAMS.delta, PARAMS.L, PARAMS.e, PARAMS.m


@kernel
def _rod(p, x, q, i, c):
    """Coordinate ``c`` of rod ``i``: ``d_i - c_i = w_i - l_i m_i``, ``w_i = p - delta e_i`` (eq 3)."""
    return x[c] - p[_DELTA] * p[_E + 3 * i + c] - q[i] * p[_M + 3 * i + c]


@kernel
def _discriminant(p, x, i):
    """``b_i = w_i . m_i`` and eq (5)'s ``L^2 - |w_i - b_i m_i|^2`` of limb ``i``."""
    w0 = x[0] - p[_DELTA] * p[_E + 3 * i]
    w1 = x[1] - p[_DELTA] * p[_E + 1 + 3 * i]
    w2 = x[2] - p[_DELTA] * p[_E + 2 + 3 * i]
    b = w0 * p[_M + 3 * i] + w1 * p[_M + 1 + 3 * i] + w2 * p[_M + 2 + 3 * i]
    return b, p[_L] * p[_L] - ((w0 * w0 + w1 * w1 + w2 * w2) - b * b)


@kernel
def residual(p, x, q, out):
    """``(|d_i - c_i|^2 - L^2) / 2L`` (eq 4): metres to first order, polynomial everywhere."""
    ll = p[_L]
    for i in range(3):
        r0, r1, r2 = _rod(p, x, q, i, 0), _rod(p, x, q, i, 1), _rod(p, x, q, i, 2)
        out[i] = (r0 * r0 + r1 * r1 + r2 * r2 - ll * ll) / (2 * ll)


@kernel
def jacobian(p, x, q, out):
    """``d residual / d p``: row i is ``(d_i - c_i) / L`` (= n_i on the constraint manifold)."""
    for i in range(3):
        for c in range(3):
            out[i, c] = _rod(p, x, q, i, c) / p[_L]


@kernel
def ik(p, x, out):
    """Strokes ``l_i = b_i - sqrt(L^2 - |w_i - b_i m_i|^2)`` (eqs 2-5, the minus root: the
    working mode); False (and NaN) where a square root is imaginary."""
    ok = True
    for i in range(3):
        b, disc = _discriminant(p, x, i)
        good = disc >= 0
        ok = ok & good
        out[i] = where(good, b - sqrt(where(good, disc, 0.0)), nan)
    return ok


@kernel
def in_domain(p, x):
    """Every limb's eq. (5) discriminant ``>= 0`` (the caller checks finiteness)."""
    ok = True
    for i in range(3):
        ok = ok & (_discriminant(p, x, i)[1] >= 0)
    return ok


@kernel
def on_assembly(p, x, q):
    """The working mode of :func:`ik`: every rod leans along its rail, ``n_i . m_i >= -1e-6``."""
    ok = True
    for i in range(3):
        nm = 0.0
        for c in range(3):
            nm = nm + _rod(p, x, q, i, c) * p[_M + 3 * i + c]
        ok = ok & (nm / p[_L] >= -1e-6)
    return ok
