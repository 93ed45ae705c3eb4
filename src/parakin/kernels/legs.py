"""The one kernel of every described mechanism (:mod:`parakin.mechanisms.described`): a platform on
legs, each leg one of three types, the leg types and their geometry held as data in ``p``.

Every leg holds a platform anchor ``d = t + R a`` (``a`` in the platform frame, ``t`` and ``R`` the
platform's position and rotation) at a fixed distance ``rho`` from a centre ``c`` that its joint
``q`` moves:

* ``length`` (an S-P-S or R-P-R leg): ``c`` the base anchor, ``rho = q`` (the leg's length);
* ``slider-rod`` (a slider on a straight guide, a rod of length ``L`` to the platform):
  ``c = base + q u`` (``u`` the guide's unit direction), ``rho = L``;
* ``crank-rod`` (a crank of radius ``r`` turning about the unit ``axis``, a rod of length ``L``):
  ``c = base + r (cos q z + sin q s)``, ``z`` the crank's zero direction, ``s = axis x z``,
  ``rho = L``; ``q`` is the angle right-handed about ``axis`` from ``z``.

The platform is ``spatial`` (pose ``x, y, z, alpha, beta, gamma``, ``R = Rz(alpha) Ry(beta)
Rx(gamma)``, the convention of the project's Stewart platforms), ``translational`` (``x, y, z``,
``R = I``) or ``planar`` (``x, y, phi``: ``t = (x, y, 0)``, ``R`` a turn by ``phi`` about ``z``).

Closure equations: ``|v| - q`` for a length leg (metres), ``(|v|^2 - L^2) / 2L`` for a rod (metres
to first order), ``v = d - c``. The inverse kinematics of the rod legs has two branches each
(``branch`` +1 or -1 in ``p``): the slider at ``q = b + branch sqrt(L^2 - |w|^2 + b^2)``
(``w = d - base``, ``b = w . u``), the crank at ``q = phi + branch acos(K / rho_w)`` where
``phi`` is the direction of ``w`` in the crank's plane, ``rho_w`` its length there and
``K = (|w|^2 + r^2 - L^2) / 2r`` (written with one ``atan2``, so ``q`` lies in ``(-pi, pi]``).
Optional joint limits (``limited``, ``lower``, ``upper``; modulo 2 pi for a crank) bound the
domain. The working assembly of a translational or planar platform is home's side of the
singularity locus ``det(d residual / d pose) = 0`` (``home_sign``); a spatial one accepts every
assembly (the start decides, as for the 6-6 platform).

The leg type is a parameter, so the branches below are on ``p`` (plain floats on every backend),
never on the pose: the functions stay elementwise on a batch (docs/kernels.md, rules of a kernel).
"""

from __future__ import annotations

from parakin.kernels._math import Layout, atan2, cos, floor, kernel, nan, pi, sin, sqrt, where
from parakin.kernels.frames import rotation_zyx

#: platform types (``p[PARAMS.platform]``) and their pose sizes
SPATIAL, TRANSLATIONAL, PLANAR = 0.0, 1.0, 2.0
#: leg types (``kind`` of a leg record)
LENGTH, SLIDER_ROD, CRANK_ROD = 0.0, 1.0, 2.0

#: one leg: its type, base anchor, guide or crank axis, the crank's zero direction and
#: ``axis x zero``, crank radius, rod length, platform anchor, IK branch, and joint limits
LEG = Layout(
    kind=1,
    base=3,
    axis=3,
    zero=3,
    side=3,
    crank=1,
    rod=1,
    anchor=3,
    branch=1,
    limited=1,
    lower=1,
    upper=1,
)
#: the platform type, the number of legs and the sign of the Jacobian determinant at home, then
#: one :data:`LEG` record per leg
PARAMS = Layout(record=LEG, platform=1, legs=1, home_sign=1)

# offsets as module constants (numba freezes them)
_PLATFORM, _LEGS, _SIGN, _HEAD, _WIDTH = (
    PARAMS.platform,
    PARAMS.legs,
    PARAMS.home_sign,
    PARAMS.size,
    LEG.size,
)
_KIND, _BASE, _AXIS, _ZERO, _SIDE = LEG.kind, LEG.base, LEG.axis, LEG.zero, LEG.side
_CRANK, _ROD, _ANCHOR, _BRANCH = LEG.crank, LEG.rod, LEG.anchor, LEG.branch
_LIMITED, _LOWER, _UPPER = LEG.limited, LEG.lower, LEG.upper
_TWO_PI = 2.0 * pi


@kernel
def _frame(p, x):
    """``t`` (3) and the nine entries of ``R``, row by row, of pose ``x``."""
    kind = p[_PLATFORM]
    if kind == SPATIAL:
        return (x[0], x[1], x[2]) + rotation_zyx(x[3], x[4], x[5])
    if kind == PLANAR:
        c, s = cos(x[2]), sin(x[2])
        return x[0], x[1], 0.0 * x[0], c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0
    return x[0], x[1], x[2], 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0


@kernel
def _anchor(p, o, f):
    """``w = R a`` and the anchor ``d = t + R a`` of the leg whose record starts at ``o``."""
    a0, a1, a2 = p[o + _ANCHOR], p[o + _ANCHOR + 1], p[o + _ANCHOR + 2]
    w0 = f[3] * a0 + f[4] * a1 + f[5] * a2
    w1 = f[6] * a0 + f[7] * a1 + f[8] * a2
    w2 = f[9] * a0 + f[10] * a1 + f[11] * a2
    return w0, w1, w2, f[0] + w0, f[1] + w1, f[2] + w2


@kernel
def _centre(p, o, q):
    """The centre ``c(q)`` (3) of the leg's sphere and its radius ``rho(q)``."""
    kind = p[o + _KIND]
    b0, b1, b2 = p[o + _BASE], p[o + _BASE + 1], p[o + _BASE + 2]
    if kind == LENGTH:
        return b0, b1, b2, q
    if kind == SLIDER_ROD:
        return (
            b0 + q * p[o + _AXIS],
            b1 + q * p[o + _AXIS + 1],
            b2 + q * p[o + _AXIS + 2],
            p[o + _ROD],
        )
    r, c, s = p[o + _CRANK], cos(q), sin(q)
    return (
        b0 + r * (c * p[o + _ZERO] + s * p[o + _SIDE]),
        b1 + r * (c * p[o + _ZERO + 1] + s * p[o + _SIDE + 1]),
        b2 + r * (c * p[o + _ZERO + 2] + s * p[o + _SIDE + 2]),
        p[o + _ROD],
    )


@kernel
def _leg(p, f, q, i):
    """``w = R a``, ``v = d - c(q)`` and the scale of the closure equation (``|v|`` for a length
    leg, the rod length ``L`` for a rod leg) of leg ``i``."""
    o = _HEAD + i * _WIDTH
    w0, w1, w2, d0, d1, d2 = _anchor(p, o, f)
    c0, c1, c2, rho = _centre(p, o, q)
    v0, v1, v2 = d0 - c0, d1 - c1, d2 - c2
    if p[o + _KIND] == LENGTH:
        scale = sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    else:
        scale = rho + 0.0 * v0
    return w0, w1, w2, v0, v1, v2, rho, scale


@kernel
def residual(p, x, q, out):
    """``|v| - q`` (length legs), ``(|v|^2 - L^2) / 2L`` (rod legs), metres."""
    f = _frame(p, x)
    for i in range(int(p[_LEGS])):
        w0, w1, w2, v0, v1, v2, rho, scale = _leg(p, f, q[i], i)
        if p[_HEAD + i * _WIDTH + _KIND] == LENGTH:
            out[i] = scale - q[i]
        else:
            out[i] = (v0 * v0 + v1 * v1 + v2 * v2 - rho * rho) / (2.0 * rho)


@kernel
def _row(p, sa, ca, f, v0, v1, v2, w0, w1, w2, k):
    """``v . d(anchor) / d x_k``: how pose coordinate ``k`` moves the anchor along ``v``. A turn
    about the unit axis ``u`` moves it by ``u x w``, so its rate along ``v`` is ``u . (w x v)``:
    ``u = z`` for alpha (and a planar ``phi``), ``Rz(alpha) y = (-sa, ca, 0)`` for beta and
    ``R x`` for gamma (the z-y'-x'' joint axes)."""
    if p[_PLATFORM] == PLANAR:
        if k == 0:
            return v0
        if k == 1:
            return v1
        return w0 * v1 - w1 * v0
    if k == 0:
        return v0
    if k == 1:
        return v1
    if k == 2:
        return v2
    m0, m1, m2 = w1 * v2 - w2 * v1, w2 * v0 - w0 * v2, w0 * v1 - w1 * v0
    if k == 3:
        return m2
    if k == 4:
        return ca * m1 - sa * m0
    return f[3] * m0 + f[6] * m1 + f[9] * m2


@kernel
def _alpha(p, x):
    """``sin`` and ``cos`` of a spatial pose's alpha (the beta column's axis), else 0 and 1."""
    if p[_PLATFORM] == SPATIAL:
        return sin(x[3]), cos(x[3])
    return 0.0 * x[0], 1.0 + 0.0 * x[0]


@kernel
def jacobian(p, x, q, out):
    """``d residual / d pose``: row ``i`` is ``v_i . d(anchor_i) / d pose`` over the leg's scale."""
    n = 6 if p[_PLATFORM] == SPATIAL else 3
    f = _frame(p, x)
    sa, ca = _alpha(p, x)
    for i in range(int(p[_LEGS])):
        w0, w1, w2, v0, v1, v2, rho, scale = _leg(p, f, q[i], i)
        for k in range(n):
            out[i, k] = _row(p, sa, ca, f, v0, v1, v2, w0, w1, w2, k) / scale


@kernel
def _leg_ik(p, f, i):
    """Joint ``i`` of the pose whose frame is ``f``, and whether it exists (within the limits)."""
    o = _HEAD + i * _WIDTH
    kind = p[o + _KIND]
    w0, w1, w2, d0, d1, d2 = _anchor(p, o, f)
    w0, w1, w2 = d0 - p[o + _BASE], d1 - p[o + _BASE + 1], d2 - p[o + _BASE + 2]
    ww = w0 * w0 + w1 * w1 + w2 * w2
    branch = p[o + _BRANCH]
    if kind == LENGTH:
        ok = ww > 0
        q = sqrt(where(ok, ww, 0.0))
    elif kind == SLIDER_ROD:
        b = w0 * p[o + _AXIS] + w1 * p[o + _AXIS + 1] + w2 * p[o + _AXIS + 2]
        rod = p[o + _ROD]
        disc = rod * rod - (ww - b * b)
        ok = disc >= 0
        q = b + branch * sqrt(where(ok, disc, 0.0))
    else:
        r, rod = p[o + _CRANK], p[o + _ROD]
        wu = w0 * p[o + _ZERO] + w1 * p[o + _ZERO + 1] + w2 * p[o + _ZERO + 2]
        wv = w0 * p[o + _SIDE] + w1 * p[o + _SIDE + 1] + w2 * p[o + _SIDE + 2]
        # with rho_w^2 = wu^2 + wv^2 and K = (|w|^2 + r^2 - L^2) / 2r, the crank's angle is
        # phi + branch acos(K / rho_w); its cosine and sine times rho_w^2 are the two terms below
        big_k = (ww + r * r - rod * rod) / (2.0 * r)
        disc = wu * wu + wv * wv - big_k * big_k
        ok = (disc >= 0) & (wu * wu + wv * wv > 0)
        s = sqrt(where(ok, disc, 0.0))
        q = atan2(wv * big_k + branch * wu * s, wu * big_k - branch * wv * s)
    if p[o + _LIMITED] != 0.0:
        lo, hi = p[o + _LOWER], p[o + _UPPER]
        if kind == CRANK_ROD:  # an angle: within the arc from lo to hi, whatever the turn
            gap = q - lo
            ok = ok & (gap - _TWO_PI * floor(gap / _TWO_PI) <= hi - lo)
        else:
            ok = ok & (q >= lo) & (q <= hi)
    return q, ok


@kernel
def ik(p, x, out):
    """Every joint of pose ``x`` on its leg's branch; False (and NaN) where a leg cannot reach its
    anchor or its joint lies outside its limits."""
    f = _frame(p, x)
    ok = x[0] == x[0]
    for i in range(int(p[_LEGS])):
        q, good = _leg_ik(p, f, i)
        ok = ok & good
        out[i] = where(good, q, nan)
    return ok


@kernel
def in_domain(p, x):
    """Every leg reaches its anchor within its limits (the caller checks finiteness)."""
    f = _frame(p, x)
    ok = x[0] == x[0]
    for i in range(int(p[_LEGS])):
        ok = ok & _leg_ik(p, f, i)[1]
    return ok


@kernel
def on_assembly(p, x, q):
    """Translational and planar platforms: ``det(d residual / d pose)`` has the sign it has at
    home (home's side of the singularity locus, where the assembly modes part); spatial: every
    assembly."""
    if p[_PLATFORM] == SPATIAL:
        return x[0] == x[0]
    f = _frame(p, x)
    z = 0.0 * x[0]
    w0, w1, w2, v0, v1, v2, rho, s = _leg(p, f, q[0], 0)
    a0 = _row(p, z, z, f, v0, v1, v2, w0, w1, w2, 0) / s
    a1 = _row(p, z, z, f, v0, v1, v2, w0, w1, w2, 1) / s
    a2 = _row(p, z, z, f, v0, v1, v2, w0, w1, w2, 2) / s
    w0, w1, w2, v0, v1, v2, rho, s = _leg(p, f, q[1], 1)
    b0 = _row(p, z, z, f, v0, v1, v2, w0, w1, w2, 0) / s
    b1 = _row(p, z, z, f, v0, v1, v2, w0, w1, w2, 1) / s
    b2 = _row(p, z, z, f, v0, v1, v2, w0, w1, w2, 2) / s
    w0, w1, w2, v0, v1, v2, rho, s = _leg(p, f, q[2], 2)
    c0 = _row(p, z, z, f, v0, v1, v2, w0, w1, w2, 0) / s
    c1 = _row(p, z, z, f, v0, v1, v2, w0, w1, w2, 1) / s
    c2 = _row(p, z, z, f, v0, v1, v2, w0, w1, w2, 2) / s
    det = a0 * (b1 * c2 - b2 * c1) - a1 * (b0 * c2 - b2 * c0) + a2 * (b0 * c1 - b1 * c0)
    return det * p[_SIGN] > 0


@kernel
def joint_period(p, k):
    """``2 pi`` for the angle of a crank, 0 for a length or a slider position: joint errors of an
    angle are taken modulo a turn."""
    return _TWO_PI if p[_HEAD + k * _WIDTH + _KIND] == CRANK_ROD else 0.0
