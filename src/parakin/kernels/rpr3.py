"""Kernels of the planar 3-RPR parallel mechanism (:class:`parakin.mechanisms.rpr3.RPR3`).

Three legs in the base plane, each a revolute joint at a base pivot ``B_i``, an actuated prismatic
joint of length ``rho_i`` and a revolute joint at a platform pivot ``P_i``. Pose ``(x, y, phi)``:
the platform origin and its rotation. With ``a_i`` the platform pivot in the platform frame and
``R(phi)`` the planar rotation, the leg vector is ``v_i = (x, y) + R(phi) a_i - B_i`` and
``rho_i = |v_i|``.

``p`` (:data:`PARAMS`, by name): the base pivots ``B_i`` (``base``, 3 x 2), the platform pivots
``a_i`` (``platform``, 3 x 2) and the sign of ``det(d rho / d pose)`` at the home pose
(``home_sign``), which names the working assembly mode (see :func:`on_assembly`).
"""

from __future__ import annotations

from parakin.kernels._math import Layout, cos, kernel, nan, sin, sqrt, where

#: the parameter vector, by name (``RPR3.kernel_params`` packs it; its length is checked once)
PARAMS = Layout(base=(3, 2), platform=(3, 2), home_sign=1)
_BASE, _PLATFORM, _SIGN = PARAMS.base, PARAMS.platform, PARAMS.home_sign


@kernel
def _leg(p, x, i):
    """``R(phi) a_i`` and the leg vector ``v_i`` (four scalars)."""
    c, s = cos(x[2]), sin(x[2])
    ax, ay = p[_PLATFORM + 2 * i], p[_PLATFORM + 2 * i + 1]
    wx = c * ax - s * ay
    wy = s * ax + c * ay
    return wx, wy, x[0] + wx - p[_BASE + 2 * i], x[1] + wy - p[_BASE + 2 * i + 1]


@kernel
def residual(p, x, q, out):
    """``rho_i(pose) - q_i`` (m)."""
    for i in range(3):
        wx, wy, vx, vy = _leg(p, x, i)
        out[i] = sqrt(vx * vx + vy * vy) - q[i]


@kernel
def _row(p, x, i):
    """Row ``i`` of ``d rho / d (x, y, phi)``: ``v_i / rho_i`` and ``(v_i x R(phi) a_i) / rho_i``
    (``d R a / d phi = (-w_y, w_x)``)."""
    wx, wy, vx, vy = _leg(p, x, i)
    n = sqrt(vx * vx + vy * vy)
    return vx / n, vy / n, (vy * wx - vx * wy) / n


@kernel
def jacobian(p, x, q, out):
    """``d residual / d pose`` (3, 3): the legs' unit vectors and their moments about the origin."""
    for i in range(3):
        out[i, 0], out[i, 1], out[i, 2] = _row(p, x, i)


@kernel
def ik(p, x, out):
    """The leg lengths ``rho_i = |v_i|``; False (and NaN) where a leg has zero length."""
    ok = x[0] == x[0]
    for i in range(3):
        wx, wy, vx, vy = _leg(p, x, i)
        n2 = vx * vx + vy * vy
        ok = ok & (n2 > 0)
        out[i] = where(n2 > 0, sqrt(n2), nan)
    return ok


@kernel
def in_domain(p, x):
    """Every leg of non-zero length (the caller checks finiteness)."""
    ok = x[0] == x[0]
    for i in range(3):
        wx, wy, vx, vy = _leg(p, x, i)
        ok = ok & (vx * vx + vy * vy > 0)
    return ok


@kernel
def on_assembly(p, x, q):
    """The working assembly: ``det(d rho / d pose)`` has the sign it has at home, i.e. the pose lies
    on home's side of the singularity locus ``det = 0`` (the assembly modes of the 3-RPR are
    separated by it; up to six poses share one set of leg lengths)."""
    a0, a1, a2 = _row(p, x, 0)
    b0, b1, b2 = _row(p, x, 1)
    c0, c1, c2 = _row(p, x, 2)
    det = a0 * (b1 * c2 - b2 * c1) - a1 * (b0 * c2 - b2 * c0) + a2 * (b0 * c1 - b1 * c0)
    return det * p[_SIGN] > 0
