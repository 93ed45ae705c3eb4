"""Compiled single-pose kernels of the 3-P(4S) mechanism (:class:`parakin.mechanisms.P3P4S`).

The same equations as ``P3P4S.residual`` / ``jacobian_pose`` / ``ik`` / ``in_domain`` /
``on_assembly``, one pose at a time. ``p`` (see ``P3P4S.kernel``): ``delta, L``, the radial unit
vectors ``e_i`` (``p[2:11]``, 3 x 3) and the rail unit vectors ``m_i`` (``p[11:20]``).
"""

from __future__ import annotations

import math

from numba import njit

_OPTS = dict(cache=True, error_model="numpy", nogil=True)


@njit(**_OPTS)
def residual(p, x, q, out):
    """``(|d_i - c_i|^2 - L^2) / 2L`` with rod ``w_i - l_i m_i``, ``w_i = p - delta e_i``."""
    delta, ll = p[0], p[1]
    for i in range(3):
        s = 0.0
        for c in range(3):
            rod = x[c] - delta * p[2 + 3 * i + c] - q[i] * p[11 + 3 * i + c]
            s += rod * rod
        out[i] = (s - ll * ll) / (2 * ll)


@njit(**_OPTS)
def jacobian(p, x, q, out):
    """Row i: ``(d_i - c_i) / L``."""
    delta, ll = p[0], p[1]
    for i in range(3):
        for c in range(3):
            out[i, c] = (x[c] - delta * p[2 + 3 * i + c] - q[i] * p[11 + 3 * i + c]) / ll


@njit(**_OPTS)
def ik(p, x, out):
    """Strokes ``b_i - sqrt(L^2 - |w_i - b_i m_i|^2)``; False where a square root is imaginary."""
    delta, ll = p[0], p[1]
    ok = True
    for i in range(3):
        b = 0.0
        ww = 0.0
        for c in range(3):
            w = x[c] - delta * p[2 + 3 * i + c]
            b += w * p[11 + 3 * i + c]
            ww += w * w
        disc = ll * ll - (ww - b * b)
        if not disc >= 0:
            ok = False
        out[i] = b - math.sqrt(disc) if disc >= 0 else math.nan
    return ok


@njit(**_OPTS)
def in_domain(p, x):
    """Every limb's eq. (5) discriminant ``>= 0``."""
    delta, ll = p[0], p[1]
    for i in range(3):
        b = 0.0
        ww = 0.0
        for c in range(3):
            w = x[c] - delta * p[2 + 3 * i + c]
            b += w * p[11 + 3 * i + c]
            ww += w * w
        if not ll * ll - (ww - b * b) >= 0:
            return False
    return True


@njit(**_OPTS)
def on_assembly(p, x, q):
    """Every rod leans along its rail: ``n_i . m_i >= -1e-6``."""
    delta, ll = p[0], p[1]
    for i in range(3):
        nm = 0.0
        for c in range(3):
            rod = x[c] - delta * p[2 + 3 * i + c] - q[i] * p[11 + 3 * i + c]
            nm += rod * p[11 + 3 * i + c]
        if not nm / ll >= -1e-6:
            return False
    return True
