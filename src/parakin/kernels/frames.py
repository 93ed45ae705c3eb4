"""Kernel helpers that the spatial platforms share, written once (:mod:`parakin.kernels._math`'s
rules: elementwise, branch-free): the rotation of the project's Euler convention and a leg's
vector from its two anchors.

A kernel module that calls them imports them, so that :func:`parakin.kernels._math.rebind` puts
them on the module's backend beside its own functions (and its compiled build covers this file).
"""

from __future__ import annotations

from parakin.kernels._math import cos, kernel, sin


@kernel
def rotation_zyx(alpha, beta, gamma):
    """The nine entries of ``R = Rz(alpha) Ry(beta) Rx(gamma)``, row by row: the orientation of
    the project's Stewart platforms and described spatial platforms (docs/li2017_stewart36.md)."""
    ca, sa = cos(alpha), sin(alpha)
    cb, sb = cos(beta), sin(beta)
    cc, sc = cos(gamma), sin(gamma)
    return (
        ca * cb,
        ca * sb * sc - sa * cc,
        ca * sb * cc + sa * sc,
        sa * cb,
        sa * sb * sc + ca * cc,
        sa * sb * cc - ca * sc,
        -sb,
        cb * sc,
        cb * cc,
    )


@kernel
def leg_vector(r, a0, a1, a2, o0, o1, o2, b0, b1, b2):
    """``w = R a`` (``r`` the nine entries of ``R``, ``a`` the platform anchor in the moving frame)
    and the leg vector ``v = o + w - b`` from the base anchor ``b`` to the moved platform anchor
    (``o`` the platform's origin): six scalars ``w0, w1, w2, v0, v1, v2``."""
    w0 = r[0] * a0 + r[1] * a1 + r[2] * a2
    w1 = r[3] * a0 + r[4] * a1 + r[5] * a2
    w2 = r[6] * a0 + r[7] * a1 + r[8] * a2
    return w0, w1, w2, o0 + w0 - b0, o1 + w1 - b1, o2 + w2 - b2
