"""Batched rotations and skew matrices.

Every function accepts arrays with arbitrary leading (batch) axes: an angle array of shape ``(...)``
gives rotation matrices of shape ``(..., 3, 3)``; a vector array ``(..., 3)`` gives ``(..., 3, 3)``.
Angles are in radians. Conventions are those of the papers:

* ``euler_zyx(a, b, c) = Rz(a) @ Ry(b) @ Rx(c)`` (intrinsic z-y'-x'', the usual yaw-pitch-roll);
* ``euler_xyz(a, b, c) = Rx(a) @ Ry(b) @ Rz(c)`` (intrinsic x-y'-z'');
* ``axis_angle(axis, angle)`` by Rodrigues' formula.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "rot_x",
    "rot_y",
    "rot_z",
    "plane_rotation",
    "euler_zyx",
    "euler_xyz",
    "euler_zyx_from_matrix",
    "euler_xyz_from_matrix",
    "axis_angle",
    "skew",
    "unskew",
    "unit",
    "quaternion",
]


def plane_rotation(angle: NDArray, i: int, j: int) -> NDArray:
    """Elementary rotations (..., 3, 3) by ``angle`` (...,) in the (i, j) coordinate plane, in
    ``angle``'s dtype (float, or object for the symbols :mod:`parakin.dynamics.jet` records)."""
    c, s = np.cos(angle), np.sin(angle)
    r = np.zeros(angle.shape + (3, 3), dtype=angle.dtype)
    if angle.dtype == object:
        r[...] = 0.0
    k = 3 - i - j  # the untouched axis
    r[..., k, k] = 1.0
    r[..., i, i] = c
    r[..., j, j] = c
    r[..., i, j] = -s
    r[..., j, i] = s
    return r


def _rot(angle: ArrayLike, i: int, j: int) -> NDArray[np.float64]:
    """Elementary rotation in the (i, j) coordinate plane, batched over ``angle``."""
    return plane_rotation(np.asarray(angle, dtype=float), i, j)


def rot_x(angle: ArrayLike) -> NDArray[np.float64]:
    """Rotation about x by ``angle`` (rad); shape ``angle.shape + (3, 3)``."""
    return _rot(angle, 1, 2)


def rot_y(angle: ArrayLike) -> NDArray[np.float64]:
    """Rotation about y by ``angle`` (rad); shape ``angle.shape + (3, 3)``."""
    return _rot(angle, 2, 0)


def rot_z(angle: ArrayLike) -> NDArray[np.float64]:
    """Rotation about z by ``angle`` (rad); shape ``angle.shape + (3, 3)``."""
    return _rot(angle, 0, 1)


def euler_zyx(a: ArrayLike, b: ArrayLike, c: ArrayLike) -> NDArray[np.float64]:
    """``Rz(a) Ry(b) Rx(c)``: intrinsic z-y'-x'' Euler angles (yaw, pitch, roll).

    Written out entry by entry (no batched 3x3 products): it sits on the FK solvers' hot path.
    """
    a, b, c = np.broadcast_arrays(*(np.asarray(t, dtype=float) for t in (a, b, c)))
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    r = np.empty(a.shape + (3, 3))
    r[..., 0, 0] = ca * cb
    r[..., 0, 1] = ca * sb * sc - sa * cc
    r[..., 0, 2] = ca * sb * cc + sa * sc
    r[..., 1, 0] = sa * cb
    r[..., 1, 1] = sa * sb * sc + ca * cc
    r[..., 1, 2] = sa * sb * cc - ca * sc
    r[..., 2, 0] = -sb
    r[..., 2, 1] = cb * sc
    r[..., 2, 2] = cb * cc
    return r


def euler_xyz(a: ArrayLike, b: ArrayLike, c: ArrayLike) -> NDArray[np.float64]:
    """``Rx(a) Ry(b) Rz(c)``: intrinsic x-y'-z'' Euler angles."""
    return rot_x(a) @ rot_y(b) @ rot_z(c)


def euler_zyx_from_matrix(r: ArrayLike) -> NDArray[np.float64]:
    """Inverse of :func:`euler_zyx`: angles ``(..., 3)`` = (a, b, c) with b in [-pi/2, pi/2]."""
    r = np.asarray(r, dtype=float)
    b = np.arcsin(np.clip(-r[..., 2, 0], -1.0, 1.0))
    a = np.arctan2(r[..., 1, 0], r[..., 0, 0])
    c = np.arctan2(r[..., 2, 1], r[..., 2, 2])
    return np.stack([a, b, c], axis=-1)


def euler_xyz_from_matrix(r: ArrayLike) -> NDArray[np.float64]:
    """Inverse of :func:`euler_xyz`: angles ``(..., 3)`` = (a, b, c) with b in [-pi/2, pi/2]."""
    r = np.asarray(r, dtype=float)
    b = np.arcsin(np.clip(r[..., 0, 2], -1.0, 1.0))
    a = np.arctan2(-r[..., 1, 2], r[..., 2, 2])
    c = np.arctan2(-r[..., 0, 1], r[..., 0, 0])
    return np.stack([a, b, c], axis=-1)


def skew(v: ArrayLike) -> NDArray[np.float64]:
    """Skew-symmetric matrix ``[v]x`` with ``skew(v) @ w == cross(v, w)``; ``(..., 3) -> (..., 3, 3)``.
    A complex ``v`` stays complex (complex-step derivatives, the 6-6's homotopy)."""
    v = np.asarray(v)
    v = v if np.iscomplexobj(v) else v.astype(float, copy=False)
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    o = np.zeros_like(x)
    return np.stack(
        [np.stack([o, -z, y], -1), np.stack([z, o, -x], -1), np.stack([-y, x, o], -1)], axis=-2
    )


def unskew(m: ArrayLike) -> NDArray[np.float64]:
    """Vector of the skew-symmetric part of ``m``: inverse of :func:`skew`."""
    m = np.asarray(m, dtype=float)
    return 0.5 * np.stack(
        [m[..., 2, 1] - m[..., 1, 2], m[..., 0, 2] - m[..., 2, 0], m[..., 1, 0] - m[..., 0, 1]],
        axis=-1,
    )


def unit(v: ArrayLike) -> NDArray[np.float64]:
    """``v / |v|`` along the last axis; raises ``ValueError`` for a zero vector."""
    v = np.asarray(v, dtype=float)
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    if np.any(n == 0):
        raise ValueError("cannot normalise a zero vector (|v| = 0)")
    return v / n


def axis_angle(axis: ArrayLike, angle: ArrayLike) -> NDArray[np.float64]:
    """Rotation by ``angle`` (rad) about ``axis`` (need not be unit length), by Rodrigues' formula.

    ``axis`` has shape ``(..., 3)`` and ``angle`` shape ``(...)``; both broadcast.
    """
    k = skew(unit(axis))
    t = np.asarray(angle, dtype=float)[..., None, None]
    return np.eye(3) + np.sin(t) * k + (1.0 - np.cos(t)) * (k @ k)


def quaternion(r: ArrayLike) -> NDArray[np.float64]:
    """Unit quaternion ``(w, x, y, z)`` (w >= 0) of rotation matrices (..., 3, 3), Shepperd's
    method (the largest of ``4w^2, 4x^2, 4y^2, 4z^2`` picks the stable formula)."""
    r = np.asarray(r, dtype=float)
    t = np.stack(
        [
            1 + r[..., 0, 0] + r[..., 1, 1] + r[..., 2, 2],
            1 + r[..., 0, 0] - r[..., 1, 1] - r[..., 2, 2],
            1 - r[..., 0, 0] + r[..., 1, 1] - r[..., 2, 2],
            1 - r[..., 0, 0] - r[..., 1, 1] + r[..., 2, 2],
        ],
        -1,
    )
    k = np.argmax(t, axis=-1)
    d = 0.5 * np.sqrt(np.maximum(np.take_along_axis(t, k[..., None], -1)[..., 0], 1e-300))
    a, b, c = r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0], r[..., 1, 0] - r[..., 0, 1]
    e, f, g = r[..., 0, 1] + r[..., 1, 0], r[..., 0, 2] + r[..., 2, 0], r[..., 1, 2] + r[..., 2, 1]
    q4 = 4 * d
    cand = np.stack(
        [
            np.stack([d, a / q4, b / q4, c / q4], -1),
            np.stack([a / q4, d, e / q4, f / q4], -1),
            np.stack([b / q4, e / q4, d, g / q4], -1),
            np.stack([c / q4, f / q4, g / q4, d], -1),
        ],
        -2,
    )
    quat = np.take_along_axis(cand, k[..., None, None], -2)[..., 0, :]
    return quat * np.where(quat[..., :1] < 0, -1.0, 1.0)
