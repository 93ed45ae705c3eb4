"""The 12-leg Stewart-derived cube mechanism of Ye, You, Shen, Wu, Ru (paper key ``ye_stewart12``).

Geometry (paper §1; ``docs/ye_stewart12.md#s1``): a moving cube of side ``2n`` inside a static
cube of side ``2(n+L)``; six double compound spherical joints ``B_i = M + R p_i`` at the midpoints
of the moving cube's edges, each carrying two prismatic legs to ``b_k`` on the static cube, normal
to one of the two faces adjacent to the edge; all legs have length ``L`` at home.

* joint offsets (docs/ye_stewart12.md#s1.2): ``p1 = (0, n, -n)``, ``p2 = (-n, n, 0)``, ``p3 = (n, 0, -n)``,
  ``p_{i+3} = -p_i``; b1, b3, b5 VERIFIED from eqs (12)-(14); the others ASSUMED
  (``b_{k+6} = -b_k``, legs normal to the adjacent faces);
* pose ``(x0, y0, z0, lambda1, lambda2, lambda3)`` (m, m, m, 1, 1, 1); the paper never defines
  lambda (docs/ye_stewart12.md#s1.3): ``convention`` = ``"euler_parameters"`` (default: vector part of a unit
  quaternion, lambda0 = +sqrt(1 - |lambda|^2)), ``"cayley"`` (Gibbs vector) or ``"euler_xyz"``
  (R = Rx Ry Rz, radians);
* joints: the 12 absolute leg lengths ``l1..l12`` (m).

Closed-form FK from all 12 lengths (paper eqs 6-11, lost in extraction; docs/ye_stewart12.md#s1.5): with
``q = l^2`` the same-joint differences give ``M`` linearly, and three opposite-leg sums plus three
differences give ``u1 = B1 - M``, ``u2 = B2 - M`` by one constant 6x6 solve (``u3 = u1 - u2``,
eq. 4). Both constant matrices are inverted once per mechanism; the FK is a few matrix products.

Compatibility equations (21)-(26): substituting the FK into the constraints (12)-(20) and
simplifying (f = (12)-(15), g = (13)-(16), v = (14)-(17), u = -[(12)+(13)-(18)],
w = -[(13)+(14)-(19)], h = -[(12)+(14)-(20)], the printed signs) gives six functions ``F(l)`` of the
12 lengths that vanish exactly on assemblable lengths. :class:`DriveMode` poses them as a
"mechanism" whose unknowns are the passive leg lengths, so that the generic solvers of
:mod:`parakin.solvers` (newton, broyden, lm) solve the paper's N-R / Broyden problem.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from types import ModuleType
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

import parakin.dynamics.jet as dj
from parakin.dynamics.jet import Jet
from parakin.dynamics.model import Bodies, MassModel, RigidBody, hexapod, hexapod_masses
from parakin.geometry import quaternion, skew
from parakin.kernels import Kernel, evaluate
from parakin.kernels import stewart12 as kernels
from parakin.mechanisms.base import (
    Array,
    Mechanism,
    Skeleton,
    as_batch,
    raise_first,
)

__all__ = [
    "Stewart12",
    "DriveMode",
    "ActiveLegs",
    "CONVENTIONS",
    "NESTED_PASSIVE",
    "rotation_matrix",
]

CONVENTIONS = ("euler_parameters", "cayley", "euler_xyz")

#: the nested passive-leg sets per redundancy R (Fig. 9 lost; ASSUMED, docs/ye_stewart12.md#s2.3)
NESTED_PASSIVE: dict[int, tuple[int, ...]] = {
    0: (7, 8, 9, 10, 11, 12),
    1: (8, 9, 10, 11, 12),
    2: (9, 10, 11, 12),
    3: (10, 11, 12),
    4: (11, 12),
    5: (12,),
}

_H = 1e-30  # complex-step size: derivatives exact to rounding


def rotation_matrix(lam: Array, convention: str) -> Array:
    """Rotation ``(..., 3, 3)`` of the orientation parameters ``lam (..., 3)``; complex-safe
    (used with complex steps), no domain check (see :meth:`Stewart12.ik`)."""
    if convention == "euler_parameters":
        l0sq = 1.0 - np.einsum("...i,...i->...", lam, lam)
        l0 = np.sqrt(l0sq)
        eye = np.broadcast_to(np.eye(3), lam.shape[:-1] + (3, 3))
        return (2 * l0sq - 1)[..., None, None] * eye + 2 * (
            lam[..., :, None] * lam[..., None, :] + l0[..., None, None] * skew(lam)
        )
    if convention == "cayley":
        s = skew(lam)
        k = 2.0 / (1.0 + np.einsum("...i,...i->...", lam, lam))
        return np.eye(3) + k[..., None, None] * (s + s @ s)
    if convention == "euler_xyz":
        c, s = np.cos(lam), np.sin(lam)
        one, zero = np.ones_like(c[..., 0]), np.zeros_like(c[..., 0])
        rx = np.stack(
            [
                np.stack([one, zero, zero], -1),
                np.stack([zero, c[..., 0], -s[..., 0]], -1),
                np.stack([zero, s[..., 0], c[..., 0]], -1),
            ],
            -2,
        )
        ry = np.stack(
            [
                np.stack([c[..., 1], zero, s[..., 1]], -1),
                np.stack([zero, one, zero], -1),
                np.stack([-s[..., 1], zero, c[..., 1]], -1),
            ],
            -2,
        )
        rz = np.stack(
            [
                np.stack([c[..., 2], -s[..., 2], zero], -1),
                np.stack([s[..., 2], c[..., 2], zero], -1),
                np.stack([zero, zero, one], -1),
            ],
            -2,
        )
        return rx @ ry @ rz
    raise ValueError(f"convention = {convention!r} must be one of {CONVENTIONS}")


def _orientation_from_matrix(r: Array, convention: str) -> Array:
    """Inverse of :func:`rotation_matrix` (principal branch: lambda0 >= 0; |angles| < pi/2)."""
    if convention == "euler_xyz":
        b = np.arcsin(np.clip(r[..., 0, 2], -1.0, 1.0))
        a = np.arctan2(-r[..., 1, 2], r[..., 2, 2])
        c = np.arctan2(-r[..., 0, 1], r[..., 0, 0])
        return np.stack([a, b, c], -1)
    quat = quaternion(r)
    if convention == "euler_parameters":
        return quat[..., 1:]
    if convention == "cayley":
        return quat[..., 1:] / quat[..., :1]
    raise ValueError(f"convention = {convention!r} must be one of {CONVENTIONS}")


@dataclass(frozen=True)
class Stewart12(Mechanism):
    """12-leg cube mechanism. Lengths in metres.

    ``n``: half edge of the moving cube (paper: 15 mm); ``L``: initial leg length (25 mm);
    ``convention``: meaning of lambda (paper undefined; docs/ye_stewart12.md#s1.3, default Euler parameters);
    ``compat_tol``: relative tolerance (of ``(n+L)^2``) on the compatibility functions above
    which :meth:`check_joints` declares lengths non-assemblable.
    """

    n: float = 0.015
    L: float = 0.025
    convention: str = "euler_parameters"
    compat_tol: float = 1e-9

    name: ClassVar[str] = "stewart12"
    kernels: ClassVar[ModuleType] = kernels
    pose_names: ClassVar[tuple[str, ...]] = ("x0", "y0", "z0", "lambda1", "lambda2", "lambda3")
    joint_names: ClassVar[tuple[str, ...]] = tuple(f"l{k}" for k in range(1, 13))
    pose_units: ClassVar[tuple[str, ...]] = ("m", "m", "m", "1", "1", "1")
    joint_units: ClassVar[tuple[str, ...]] = ("m",) * 12
    paper_pose_units: ClassVar[tuple[str, ...]] = ("mm", "mm", "mm", "1", "1", "1")
    paper_joint_units: ClassVar[tuple[str, ...]] = ("mm",) * 12
    #: joint (0-based) of each leg
    leg_joint: ClassVar[tuple[int, ...]] = (0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5)

    def __post_init__(self) -> None:
        for key in ("n", "L"):
            v = getattr(self, key)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"{key} = {v!r} m must be a positive length")
        if self.convention not in CONVENTIONS:
            raise ValueError(f"convention = {self.convention!r} must be one of {CONVENTIONS}")
        if not (self.compat_tol > 0):
            raise ValueError(f"compat_tol = {self.compat_tol!r} must be > 0")

    # ------------------------------------------------------------------ geometry
    @cached_property
    def platform_points_local(self) -> Array:
        """p1..p6 (6, 3): edge midpoints of the moving cube (docs/ye_stewart12.md#s1.2)."""
        n = self.n
        p = np.array([[0.0, n, -n], [-n, n, 0.0], [n, 0.0, -n]])
        return np.concatenate([p, -p])

    @cached_property
    def base_points(self) -> Array:
        """b1..b12 (12, 3) on the static cube (b1, b3, b5 from eqs 12-14; the rest ASSUMED)."""
        n, a = self.n, self.n + self.L
        b = np.array(
            [[0, a, -n], [0, n, -a], [-n, a, 0], [-a, n, 0], [n, 0, -a], [a, 0, -n]], dtype=float
        )
        return np.concatenate([b, -b])

    @cached_property
    def _fk_matrices(self) -> dict[str, Array]:
        """Constant matrices of the linear FK (docs/ye_stewart12.md#s1.5), inverted once."""
        n, b = self.n, self.base_points
        c = float(b[0] @ b[0])
        d = np.array([b[2 * i] - b[2 * i + 1] for i in range(3)])  # d_i = b_{2i-1} - b_{2i}
        # M . d_i = [-(q_{2i-1} - q_{2i}) + (q_{2i+5} - q_{2i+6})] / 4
        rm = np.zeros((3, 12))
        for i in range(3):
            rm[i, 2 * i], rm[i, 2 * i + 1], rm[i, 2 * i + 6], rm[i, 2 * i + 7] = (
                -0.25,
                0.25,
                0.25,
                -0.25,
            )
        am = np.linalg.solve(d, rm)  # M = am @ q
        # unknowns U = (u1, u2); u3 = u1 - u2 (eq. 4: p3 = p1 - p2)
        sel = [
            np.hstack([np.eye(3), np.zeros((3, 3))]),
            np.hstack([np.zeros((3, 3)), np.eye(3)]),
            np.hstack([np.eye(3), -np.eye(3)]),
        ]
        a = np.zeros((6, 6))
        qm = np.zeros((6, 12))
        s_coef = np.zeros(6)
        const = np.zeros(6)
        for i in range(3):
            # u_i . b_{2i-1} = (2S + 2|p|^2 + 2c - q_{2i-1} - q_{2i+5}) / 4  (opposite-leg sum)
            a[2 * i] = b[2 * i] @ sel[i]
            qm[2 * i, 2 * i], qm[2 * i, 2 * i + 6] = -0.25, -0.25
            s_coef[2 * i] = 0.5
            const[2 * i] = 0.5 * (2 * n * n) + 0.5 * c
            # u_i . d_i = -[(q_{2i-1} - q_{2i}) + (q_{2i+5} - q_{2i+6})] / 4  (same-joint differences)
            a[2 * i + 1] = d[i] @ sel[i]
            qm[2 * i + 1, [2 * i, 2 * i + 1, 2 * i + 6, 2 * i + 7]] = [-0.25, 0.25, -0.25, 0.25]
        ainv = np.linalg.inv(a)
        p = self.platform_points_local
        pm = np.column_stack([p[0], p[1], np.cross(p[0], p[1])])
        return {
            "am": am,
            "uq": ainv @ qm,
            "us": ainv @ s_coef,
            "u0": ainv @ const,
            "pinv": np.linalg.inv(pm),
            "c": np.array(c),
        }

    def home(self) -> Array:
        """Both cubes concentric and parallel: all legs of length L."""
        return np.zeros(6)

    def pose_bounds(self) -> tuple[Array, Array]:
        """|x0|, |y0|, |z0| <= 3 mm, |lambda_i| <= 0.15 (our test box, docs/ye_stewart12.md#s1.5; the paper gives none)."""
        hi = np.array([0.003, 0.003, 0.003, 0.15, 0.15, 0.15])
        return -hi, hi

    # ------------------------------------------------------------------ kinematics
    def rotation(self, pose: ArrayLike) -> Array:
        x = as_batch(pose, 6, "pose")
        self._check_orientation(x)
        return rotation_matrix(x[..., 3:], self.convention)

    def _check_orientation(self, x: Array) -> None:
        if self.convention == "euler_parameters":
            s = np.einsum("...i,...i->...", x[..., 3:], x[..., 3:])
            raise_first(
                s >= 1.0,
                x.shape[:-1],
                lambda idx: (
                    f"|lambda|^2 = {s[idx]:.6g} must be < 1 for Euler parameters "
                    f"(lambda0 = sqrt(1 - |lambda|^2))"
                ),
            )

    def joint_centres(self, pose: ArrayLike) -> Array:
        """B1..B6 (..., 6, 3) in the inertial frame."""
        x = as_batch(pose, 6, "pose")
        r = self.rotation(x)
        return x[..., None, :3] + self.platform_points_local @ np.swapaxes(r, -1, -2)

    def leg_vectors(self, pose: ArrayLike) -> Array:
        """``B_{j(k)} - b_k`` (..., 12, 3)."""
        b = self.joint_centres(pose)
        return b[..., list(self.leg_joint), :] - self.base_points

    # ik, residual, jacobian_pose and in_domain of the default Euler-parameter convention are the
    # kernels of parakin.kernels.stewart12 (one source for numpy, numba and torch; docs/kernels.md)
    def ik(self, pose: ArrayLike) -> Array:
        """Leg lengths ``l_k = |M + R p_{j(k)} - b_k|`` (eq. 2), shape (..., 12), metres."""
        if self.convention == "euler_parameters":
            x = as_batch(pose, 6, "pose")
            self._check_orientation(x)
            return evaluate(self._declared_kernel, "ik", x)[0]
        v = self.leg_vectors(pose)
        return np.sqrt(np.einsum("...ij,...ij->...i", v, v))

    def in_domain(self, pose: ArrayLike) -> np.ndarray:
        """Finite, and ``|lambda|^2 < 1`` for Euler parameters (lambda0 real)."""
        x = np.asarray(pose, dtype=float)
        fin = np.all(np.isfinite(x), axis=-1)
        if self.convention == "euler_parameters":
            return fin & evaluate(self._declared_kernel, "in_domain", x)
        return fin & ~self._outside(x)

    def _outside(self, x: Array) -> np.ndarray:
        """True where lambda leaves the convention's domain (Euler parameters: |lambda| >= 1)."""
        if self.convention != "euler_parameters":
            return np.zeros(x.shape[:-1], dtype=bool)
        with np.errstate(all="ignore"):
            return ~(np.einsum("...i,...i->...", x[..., 3:], x[..., 3:]) < 1.0)

    def residual(self, pose: ArrayLike, joints: ArrayLike) -> Array:
        """``l(pose) - joints`` (12 equations in 6 unknowns: least squares for numeric FK); NaN rows
        outside the lambda domain (a solver iterate may leave it, which must not raise mid-solve)."""
        q = as_batch(joints, 12, "joints")
        x = as_batch(pose, 6, "pose")
        if self.convention == "euler_parameters":
            return evaluate(self._declared_kernel, "residual", x, q)
        bad = self._outside(x)
        r = self.ik(np.where(bad[..., None], 0.0, x)) - q
        return np.where(bad[..., None], np.nan, r)

    def jacobian_pose(self, pose: ArrayLike, joints: ArrayLike | None = None) -> Array:
        """Analytic ``d l / d pose`` (..., 12, 6): ``e_k . dB_j`` (see :meth:`leg_jacobian`); NaN
        rows outside the lambda domain."""
        x = as_batch(pose, 6, "pose")
        if self.convention == "euler_parameters":
            return evaluate(self._declared_kernel, "jacobian", x, np.zeros(12))  # reads no joints
        bad = self._outside(x)
        j = self.leg_jacobian(np.where(bad[..., None], 0.0, x), range(12))
        return np.where(bad[..., None, None], np.nan, j)

    def leg_jacobian(self, pose: ArrayLike, legs) -> Array:
        """Rows ``legs`` (0-based) of ``d l / d pose`` (..., len(legs), 6): ``e_k . dB_j`` with
        ``e_k`` the unit leg vector; ``dR/dlambda`` analytic for Euler parameters, by complex step
        (exact to rounding) for the other conventions."""
        x = as_batch(pose, 6, "pose")
        self._check_orientation(x)
        legs = list(legs)
        joint = [self.leg_joint[k] for k in legs]
        lam = x[..., 3:]
        r = rotation_matrix(lam, self.convention)
        p = self.platform_points_local[joint]  # (k, 3)
        w = p @ np.swapaxes(r, -1, -2)  # R p, (..., k, 3) (matmul: 4x einsum's speed)
        v = x[..., None, :3] + w - self.base_points[legs]
        e = v / np.sqrt(np.einsum("...ij,...ij->...i", v, v))[..., None]
        if self.convention == "euler_parameters":
            # d(R p)/d lambda_i = omega_i x (R p), omega = 2 (l0 I + lam lam^T / l0 + [lam]x) d lambda (the
            # angular velocity of the unit quaternion (l0, lam)), so e . d(R p)/d lambda_i = omega_i . (R p x e)
            l0 = np.sqrt(1.0 - np.einsum("...i,...i->...", lam, lam))[..., None, None]
            omega = 2 * (l0 * np.eye(3) + lam[..., :, None] * lam[..., None, :] / l0 + skew(lam))
            c = np.stack(
                [
                    w[..., 1] * e[..., 2] - w[..., 2] * e[..., 1],
                    w[..., 2] * e[..., 0] - w[..., 0] * e[..., 2],
                    w[..., 0] * e[..., 1] - w[..., 1] * e[..., 0],
                ],
                -1,
            )
            return np.concatenate([e, c @ omega], -1)
        cols = [e[..., :, 0], e[..., :, 1], e[..., :, 2]]
        dr = self._rotation_derivatives(lam)  # (..., 3, 3, 3): d R / d lambda_i
        for i in range(3):
            cols.append(
                np.einsum("...kc,...kc->...k", e, np.einsum("...cj,kj->...kc", dr[..., i, :, :], p))
            )
        return np.stack(cols, -1)

    def _rotation_derivatives(self, lam: Array) -> Array:
        """``d R / d lambda_i`` (..., 3 (i), 3, 3)."""
        if self.convention != "euler_parameters":
            out = []
            for i in range(3):
                lc = lam.astype(complex)
                lc[..., i] += 1j * _H
                out.append(rotation_matrix(lc, self.convention).imag / _H)
            return np.stack(out, -3)
        # R = (2 l0^2 - 1) I + 2 (lam lam^T + l0 [lam]x), l0 = sqrt(1 - |lam|^2), d l0 / d lam_i = -lam_i / l0:
        # dR/dlam_i = -4 lam_i I + 2 (e_i lam^T + lam e_i^T) - 2 (lam_i / l0) [lam]x + 2 l0 [e_i]x
        l0 = np.sqrt(1.0 - np.einsum("...i,...i->...", lam, lam))
        eye = np.eye(3)
        sk = skew(lam)
        out = []
        for i in range(3):
            outer = eye[i][:, None] * lam[..., None, :] + lam[..., :, None] * eye[i][None, :]
            out.append(
                -4 * lam[..., i, None, None] * eye
                + 2 * outer
                - 2 * (lam[..., i] / l0)[..., None, None] * sk
                + 2 * l0[..., None, None] * skew(eye[i])
            )
        return np.stack(out, -3)

    def jacobian_joints(self, pose: ArrayLike, joints: ArrayLike | None = None) -> Array:
        x = as_batch(pose, 6, "pose")
        return np.broadcast_to(-np.eye(12), x.shape[:-1] + (12, 12)).copy()

    # ------------------------------------------------------------------ closed-form FK
    def fk_points(self, joints: ArrayLike) -> tuple[Array, Array]:
        """``M`` (..., 3) and ``u1, u2`` (..., 2, 3) of the linear FK from all 12 lengths (no
        check: off the constraint manifold the result is the FK's linear extrapolation).
        Complex-safe (complex-step Jacobians of :meth:`compatibility`)."""
        lengths = np.asarray(joints)
        q = lengths * lengths
        f = self._fk_matrices
        m = q @ f["am"].T
        s = np.einsum("...i,...i->...", m, m)
        u = q @ f["uq"].T + s[..., None] * f["us"] + f["u0"]
        return m, u.reshape(*u.shape[:-1], 2, 3)

    def kernel(self) -> Kernel | None:
        """The kernels (:mod:`parakin.kernels.stewart12`) of the default Euler-parameter
        convention; None for the other conventions."""
        return super().kernel() if self.convention == "euler_parameters" else None

    def kernel_params(self, legs: tuple[int, ...] = tuple(range(12))) -> Array:
        """Platform point (local frame) of each of ``legs`` (0-based), then their base points."""
        p = self.platform_points_local[[self.leg_joint[k] for k in legs]]
        return np.concatenate([p.ravel(), self.base_points[list(legs)].ravel()])

    def fk(self, joints: ArrayLike, check: bool = True) -> Array:
        """Closed-form FK: the pose (..., 6) from all 12 leg lengths (m), batched.

        ``check=True`` first runs :meth:`check_joints` (UnreachableError where the lengths do not
        assemble). The orientation is ``[u1, u2, u1 x u2] [p1, p2, p1 x p2]^-1`` converted to the
        configured lambda convention.
        """
        q = as_batch(joints, 12, "joints")
        if check:
            self.check_joints(q)
        m, u = self.fk_points(q)
        u1, u2 = u[..., 0, :], u[..., 1, :]
        r = np.stack([u1, u2, np.cross(u1, u2)], -1) @ self._fk_matrices["pinv"]
        return np.concatenate([m, _orientation_from_matrix(r, self.convention)], -1)

    # ------------------------------------------------------------------ compatibility (21)-(26)
    def constraints(self, joints: ArrayLike) -> Array:
        """The nine constraints (12)-(20) as ``lhs - rhs`` (..., 9) after substituting the FK."""
        lengths = np.asarray(joints)
        m, u = self.fk_points(lengths)
        b1, b2 = m + u[..., 0, :], m + u[..., 1, :]
        b3 = b1 - u[..., 1, :]
        bp = self.base_points
        p = self.platform_points_local
        q = lengths * lengths

        def sq(v: Array) -> Array:
            return np.einsum("...i,...i->...", v, v)

        return np.stack(
            [
                sq(b1 - bp[0]) - q[..., 0],
                sq(b2 - bp[2]) - q[..., 2],
                sq(b3 - bp[4]) - q[..., 4],
                sq(b1 - m) - p[0] @ p[0],
                sq(b2 - m) - p[1] @ p[1],
                sq(b3 - m) - p[2] @ p[2],
                sq(b1 - b2) - sq(p[0] - p[1]),
                sq(b2 - b3) - sq(p[1] - p[2]),
                sq(b1 - b3) - sq(p[0] - p[2]),
            ],
            -1,
        )

    def compatibility(self, joints: ArrayLike) -> Array:
        """``F = (f, g, v, u, w, h)`` of eqs (21)-(26) (..., 6), m^2; zero on assemblable lengths."""
        e = self.constraints(joints)
        return np.stack(
            [
                e[..., 0] - e[..., 3],
                e[..., 1] - e[..., 4],
                e[..., 2] - e[..., 5],
                -(e[..., 0] + e[..., 1] - e[..., 6]),
                -(e[..., 1] + e[..., 2] - e[..., 7]),
                -(e[..., 0] + e[..., 2] - e[..., 8]),
            ],
            -1,
        )

    def compatibility_jacobian(self, joints: ArrayLike, columns: ArrayLike | None = None) -> Array:
        """``dF / dl`` (..., 6, k) for the leg indices ``columns`` (0-based, default all 12), by
        complex step: F is a polynomial in l, so this is exact to rounding."""
        lengths = as_batch(joints, 12, "joints")
        cols = np.arange(12) if columns is None else np.asarray(columns, dtype=int)
        out = []
        for k in cols:
            z = lengths.astype(complex)
            z[..., k] += 1j * _H
            out.append(self.compatibility(z).imag / _H)
        return np.stack(out, -1)

    def check_joints(self, joints: ArrayLike) -> None:
        """UnreachableError where a length is not positive or the 12 lengths do not assemble
        (``max |F| > compat_tol (n+L)^2``), naming the value and the limit."""
        q = as_batch(joints, 12, "joints")
        raise_first(
            q <= 0,
            q.shape[:-1],
            lambda idx: f"leg length l{idx[-1] + 1} = {q[idx]:.6g} m must be > 0",
        )
        f = np.max(np.abs(self.compatibility(q)), axis=-1)
        limit = self.compat_tol * (self.n + self.L) ** 2
        raise_first(
            ~(f <= limit),
            q.shape[:-1],
            lambda idx: (
                f"leg lengths do not assemble: max |F| of the compatibility equations "
                f"(21)-(26) = {f[idx]:.6g} m^2 exceeds the limit {limit:.3g} m^2 (compat_tol = "
                f"{self.compat_tol:g} of (n+L)^2)"
            ),
        )

    # ------------------------------------------------------------------ drawing
    def skeleton(self, pose: ArrayLike, passive: tuple[int, ...] = ()) -> Skeleton:
        """Static cube (edges), moving cube (edges), 12 legs (``passive`` legs, 1-based, dashed),
        joints B1..B6, base points b1..b12; frames O-XYZ and M-UVW."""
        x = as_batch(pose, 6, "pose")
        if x.ndim != 1:
            raise ValueError(f"skeleton() draws one pose, got a batch of shape {x.shape[:-1]}")
        r = self.rotation(x)
        bj = self.joint_centres(x)
        pts = {f"B_{i + 1}": bj[i] for i in range(6)}
        pts.update({f"b_{k + 1}": self.base_points[k] for k in range(12)})
        segments = [
            (
                "passive" if (k + 1) in passive else "actuator",
                np.stack([self.base_points[k], bj[self.leg_joint[k]]]),
            )
            for k in range(12)
        ]
        a, n = self.n + self.L, self.n
        corners = np.array(
            [[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], dtype=float
        )
        edges = [
            (i, j)
            for i in range(8)
            for j in range(i + 1, 8)
            if np.sum(corners[i] != corners[j]) == 1
        ]
        for i, j in edges:
            segments.append(("base", a * np.stack([corners[i], corners[j]])))
            moving = x[:3] + n * np.stack([corners[i], corners[j]]) @ r.T
            segments.append(("platform", moving))
        return Skeleton(
            points=pts,
            segments=segments,
            polygons=[],
            frames={"O": (np.zeros(3), np.eye(3)), "M": (x[:3].copy(), r)},
        )

    # ------------------------------------------------------------------ dynamics (issue 27)
    def mass_model(self) -> MassModel:
        """Illustrative defaults (the paper has no dynamics): the moving cube a solid 0.2 kg cube
        of side ``2n`` (``I = m (2n)^2 / 6``, centred), legs of a 20 g cylinder and a 10 g piston
        shaped by :func:`parakin.dynamics.model.hexapod_masses` to the leg length ``L``."""
        side, m = 2 * self.n, 0.2
        masses = hexapod_masses(
            self.platform_points_local,
            self.L,
            m,
            0.02,
            0.01,
            note="stewart12 illustrative defaults",
        )
        return masses.replace(platform=RigidBody(m, (m * side**2 / 6,) * 3))

    def bodies(self, pose: Jet) -> Bodies:
        """The moving cube (origin ``M``, rotation of :attr:`convention`) and twelve S-P-S legs,
        leg k from ``b_k`` to ``B_j(k)`` (:func:`parakin.dynamics.model.hexapod`); joints: the
        twelve lengths (six more than the pose: a redundant drive)."""
        lam = pose[..., 3:]
        if self.convention == "euler_parameters":
            l0sq = 1.0 - dj.dot(lam, lam)
            outer = lam[..., :, None] * lam[..., None, :]
            rotation = (2.0 * l0sq - 1.0)[..., None, None] * np.eye(3) + 2.0 * (
                outer + dj.sqrt(l0sq)[..., None, None] * dj.skew(lam)
            )
        elif self.convention == "cayley":
            s = dj.skew(lam)
            k = 2.0 / (1.0 + dj.dot(lam, lam))
            rotation = k[..., None, None] * (s + dj.matmul(s, s)) + np.eye(3)
        else:
            rotation = dj.rotations([lam[..., 0], lam[..., 1], lam[..., 2]], "xyz")
        top = self.platform_points_local[list(self.leg_joint)]
        return hexapod(pose[..., :3], rotation, self.base_points, top)


@dataclass(frozen=True)
class DriveMode(Mechanism, register=False):
    """The compatibility equations of one drive mode as a solvable "mechanism" (paper eq. 28).

    Unknowns ("pose"): the ``6 - R`` passive leg lengths ``X`` (m); inputs ("joints"): the
    ``6 + R`` active lengths, in leg order. ``residual`` is ``F`` of (21)-(26) padded with ``R``
    identically zero rows, so that it has one entry per input as the solver protocol expects;
    the zero rows do not change a (Gauss-)Newton, Broyden or LM step. For ``R > 0`` the system is
    over-determined (6 equations, 6 - R unknowns): ``newton`` then takes the least-squares
    (Gauss-Newton, pseudo-inverse) step, ``broyden`` the pseudo-inverse of its secant matrix.
    """

    mech: Stewart12 = field(default_factory=Stewart12)
    passive: tuple[int, ...] = NESTED_PASSIVE[0]  #: 1-based passive legs

    name: ClassVar[str] = "stewart12-drive"
    pose_names: ClassVar[tuple[str, ...]] = ()
    joint_names: ClassVar[tuple[str, ...]] = ()
    pose_units: ClassVar[tuple[str, ...]] = ()
    joint_units: ClassVar[tuple[str, ...]] = ()
    paper_pose_units: ClassVar[tuple[str, ...]] = ()
    paper_joint_units: ClassVar[tuple[str, ...]] = ()

    def __post_init__(self) -> None:
        p = tuple(int(k) for k in self.passive)
        if len(set(p)) != len(p) or not (1 <= len(p) <= 6) or not all(1 <= k <= 12 for k in p):
            raise ValueError(
                f"passive = {self.passive!r} must be 1..6 distinct leg numbers in 1..12"
            )
        object.__setattr__(self, "passive", tuple(sorted(p)))

    @property
    def redundancy(self) -> int:
        return 6 - len(self.passive)

    @property
    def active(self) -> tuple[int, ...]:
        return tuple(k for k in range(1, 13) if k not in self.passive)

    @property
    def n_pose(self) -> int:  # type: ignore[override]
        return len(self.passive)

    @property
    def n_joints(self) -> int:  # type: ignore[override]
        return 12 - len(self.passive)

    def assemble(self, passive_lengths: ArrayLike, active_lengths: ArrayLike) -> Array:
        """All 12 lengths (..., 12) from the passive and active ones (complex-safe)."""
        xp, qa = np.asarray(passive_lengths), np.asarray(active_lengths)
        shape = np.broadcast_shapes(xp.shape[:-1], qa.shape[:-1])
        out = np.zeros((*shape, 12), dtype=np.result_type(xp, qa))
        out[..., [k - 1 for k in self.passive]] = xp
        out[..., [k - 1 for k in self.active]] = qa
        return out

    def split(self, lengths: ArrayLike) -> tuple[Array, Array]:
        """(passive, active) parts of 12 lengths."""
        q = np.asarray(lengths, dtype=float)
        return q[..., [k - 1 for k in self.passive]], q[..., [k - 1 for k in self.active]]

    def home(self) -> Array:
        return np.full(len(self.passive), self.mech.L)

    def pose_bounds(self) -> tuple[Array, Array]:
        return np.zeros(len(self.passive)), np.full(len(self.passive), 3 * self.mech.L)

    def ik(self, pose: ArrayLike) -> Array:
        raise NotImplementedError("a drive mode maps active to passive lengths only (use solve_fk)")

    def in_domain(self, pose: ArrayLike) -> np.ndarray:
        """Finite, positive passive lengths."""
        x = np.asarray(pose, dtype=float)
        return np.all(np.isfinite(x) & (x > 0), axis=-1)

    def joint_error(self, pose: ArrayLike, joints: ArrayLike) -> Array:
        """``max_k |l_k(fk(l)) - l_k|`` over all 12 legs ``l = (X, active)``: the pose of the linear
        FK (eqs 6-11) must reproduce every length, passive and active, through the IK (eq. 2)."""
        lengths = self.assemble(pose, joints)
        with np.errstate(all="ignore"):
            x = self.mech.fk(lengths, check=False)
        bad = ~self.mech.in_domain(x)
        legs = self.mech.ik(np.where(bad[..., None], 0.0, x))
        return np.where(bad, np.inf, np.max(np.abs(legs - lengths), axis=-1))

    def _pad(self, f: Array) -> Array:
        r = self.redundancy
        return (
            f if r == 0 else np.concatenate([f, np.zeros(f.shape[:-1] + (r,), dtype=f.dtype)], -1)
        )

    def residual(self, pose: ArrayLike, joints: ArrayLike) -> Array:
        """``F(X, l_active)`` (..., 6 + R): the six compatibility functions, then R zeros."""
        f = self.mech.compatibility(self.assemble(pose, joints))
        return self._pad(f)

    def jacobian_pose(self, pose: ArrayLike, joints: ArrayLike) -> Array:
        """``dF/dX`` (..., 6 + R, 6 - R), exact (complex step), zero padding rows."""
        lengths = self.assemble(pose, joints)
        jac = self.mech.compatibility_jacobian(lengths, [k - 1 for k in self.passive])
        r = self.redundancy
        if r == 0:
            return jac
        return np.concatenate([jac, np.zeros(jac.shape[:-2] + (r, jac.shape[-1]))], -2)


@dataclass(frozen=True)
class ActiveLegs(Mechanism, register=False):
    """Pose-space FK from any ``N >= 6`` active legs: residual ``l_k(pose) - l_k`` over the active
    legs only (beyond the paper, docs/ye_stewart12.md#s7.1); solve with ``lm`` (least squares for N > 6) or
    ``newton``. The passive lengths then follow by :meth:`Stewart12.ik`."""

    mech: Stewart12 = field(default_factory=Stewart12)
    active: tuple[int, ...] = (1, 2, 3, 4, 5, 6)  #: 1-based active legs

    name: ClassVar[str] = "stewart12-active"
    kernels: ClassVar[ModuleType] = kernels
    pose_names: ClassVar[tuple[str, ...]] = Stewart12.pose_names
    joint_names: ClassVar[tuple[str, ...]] = ()
    pose_units: ClassVar[tuple[str, ...]] = Stewart12.pose_units
    joint_units: ClassVar[tuple[str, ...]] = ()
    paper_pose_units: ClassVar[tuple[str, ...]] = Stewart12.paper_pose_units
    paper_joint_units: ClassVar[tuple[str, ...]] = ()

    def __post_init__(self) -> None:
        a = tuple(sorted(int(k) for k in self.active))
        if len(set(a)) != len(a) or len(a) < 6 or not all(1 <= k <= 12 for k in a):
            raise ValueError(f"active = {self.active!r} must be >= 6 distinct leg numbers in 1..12")
        object.__setattr__(self, "active", a)

    @property
    def n_joints(self) -> int:  # type: ignore[override]
        return len(self.active)

    def home(self) -> Array:
        return self.mech.home()

    def pose_bounds(self) -> tuple[Array, Array]:
        return self.mech.pose_bounds()

    def ik(self, pose: ArrayLike) -> Array:
        return self.mech.ik(pose)[..., [k - 1 for k in self.active]]

    def in_domain(self, pose: ArrayLike) -> np.ndarray:
        return self.mech.in_domain(pose)

    def kernel(self) -> Kernel | None:
        """The kernels of :mod:`parakin.kernels.stewart12` over the active legs (the default
        Euler-parameter convention), compiled like any mechanism's; None for the other
        conventions and a subclass of Stewart12 as ``mech``."""
        return super().kernel() if self._by_kernel else None

    @property
    def _by_kernel(self) -> bool:
        """Whether residual and jacobian_pose run the kernels (the Stewart12 itself, not a
        subclass of it, in the Euler-parameter convention)."""
        return type(self.mech) is Stewart12 and self.mech.convention == "euler_parameters"

    def kernel_params(self) -> Array:
        """The active legs' platform and base points (:meth:`Stewart12.kernel_params`)."""
        return self.mech.kernel_params(tuple(k - 1 for k in self.active))

    def _inside(self, pose: ArrayLike) -> tuple[Array, Array]:
        """Pose with out-of-domain rows (|lambda| >= 1 for Euler parameters) replaced by home, and
        their mask: a solver iterate may leave the domain, which must not raise mid-solve."""
        x = as_batch(pose, 6, "pose")
        bad = np.zeros(x.shape[:-1], dtype=bool)
        if self.mech.convention == "euler_parameters":
            bad = np.einsum("...i,...i->...", x[..., 3:], x[..., 3:]) >= 1.0
        return np.where(bad[..., None], 0.0, x), bad

    def residual(self, pose: ArrayLike, joints: ArrayLike) -> Array:
        """``l_k(pose) - l_k`` over the active legs; NaN rows outside the lambda domain."""
        if self._by_kernel:
            q = np.asarray(joints, dtype=float)
            return evaluate(self._declared_kernel, "residual", as_batch(pose, 6, "pose"), q)
        x, bad = self._inside(pose)
        r = self.ik(x) - np.asarray(joints, dtype=float)
        return np.where(bad[..., None], np.nan, r)

    def jacobian_pose(self, pose: ArrayLike, joints: ArrayLike | None = None) -> Array:
        if self._by_kernel:
            x = as_batch(pose, 6, "pose")
            return evaluate(self._declared_kernel, "jacobian", x, np.zeros(self.n_joints))
        x, bad = self._inside(pose)
        j = self.mech.leg_jacobian(x, [k - 1 for k in self.active])
        return np.where(bad[..., None, None], np.nan, j)
