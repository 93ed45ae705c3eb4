"""The 3-6 Stewart platform of Li, Quan & Wu 2017 (Computer Applications and Software 34(12)).

Moving platform: equilateral triangle A1 A2 A3 of side ``a``; base: regular hexagon B1..B6 of side
(= circumradius) ``b``; six S-S legs, leg i joins ``A_ceil(i/2)`` and ``B_i`` (paper eq. 2). All
lengths dimensionless (divided by the top side, paper §3), so ``a = 1`` by default. Notes
``004_stewart36.md`` §1.

Layout (docs/li2017_stewart36.md#s1.2, ASSUMED: the paper's coordinates are lost in the extraction)::

    A1 = (-a/(2 sqrt3),  a/2, 0)   A2 = (-a/(2 sqrt3), -a/2, 0)   A3 = (a/sqrt3, 0, 0)   (moving frame)
    B_k = b (cos phi_k, sin phi_k, 0),  phi_k = 90 deg + 60 deg (k - 1)                   (fixed frame)

Pose ``(alpha, beta, gamma, X, Y, Z)``: ``T = Rz(alpha) Ry(beta) Rx(gamma)`` ("Z-Y-X Euler",
docs/li2017_stewart36.md#s1.3, ASSUMED reading) and the triangle centre ``O_A = (X, Y, Z)``. Joints: absolute leg lengths
``L_1 .. L_6``. Residual (eq. 3, squared form, docs/li2017_stewart36.md#g4 ASSUMED): ``f_i = |T A_p(i) + O_A - B_i|^2 - L_i^2``;
the paper's objective (4) is ``F = sum f_i^2`` (:meth:`Stewart36.objective`).

Beyond the paper: :meth:`Stewart36.fk_all`, every forward solution (16 complex, in mirror pairs about
the base plane) from a degree-16 univariate polynomial (docs/li2017_stewart36.md#s1.5), real roots refined by Newton
and verified by the IK.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from types import ModuleType
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from parakin.dynamics.model import MassModel, hexapod_masses
from parakin.errors import UnreachableError
from parakin.geometry import euler_zyx_from_matrix
from parakin.kernels import stewart36 as kernels
from parakin.mechanisms.base import (
    Array,
    as_batch,
    describe_first,
    raise_first,
)
from parakin.mechanisms.stewart66_legs import SixLegs

__all__ = ["Stewart36", "TABLE3_ROW1"]

_SQ3 = float(np.sqrt(3.0))
#: platform point of each leg (0-based): leg i joins A_ceil(i/2) and B_i (paper eq. 2)
LEG_TOP = np.array([0, 0, 1, 1, 2, 2])
#: Table 3 row 1 (deg, deg, deg, -, -, -): the FK input is reconstructed as its IK (docs/li2017_stewart36.md#g1, ASSUMED)
TABLE3_ROW1 = (79.675, 47.468, 10.064, -0.282, 0.130, 1.571)


@dataclass(frozen=True)
class Stewart36(SixLegs):
    """3-6 Stewart platform, dimensionless lengths (top side ``a`` = 1, docs/li2017_stewart36.md#s1.1).

    ``b``: base hexagon side, LOST with Table 2 (docs/li2017_stewart36.md#g1): default 3 (ASSUMED; sweep 0.5, 1, 2, 3).
    """

    b: float = 3.0  #: base hexagon side = circumradius (Table 2 LOST; ASSUMED 3, docs/li2017_stewart36.md#g1)
    a: float = 1.0  #: top triangle side (dimensionless unit, paper §3)

    name: ClassVar[str] = "stewart36"
    leg_top: ClassVar[Array] = LEG_TOP  # two legs share each top point
    top_label: ClassVar[str] = "A"
    kernels: ClassVar[ModuleType] = kernels
    pose_units: ClassVar[tuple[str, ...]] = ("rad", "rad", "rad", "1", "1", "1")
    joint_units: ClassVar[tuple[str, ...]] = ("1",) * 6
    paper_pose_units: ClassVar[tuple[str, ...]] = ("deg", "deg", "deg", "1", "1", "1")
    paper_joint_units: ClassVar[tuple[str, ...]] = ("1",) * 6

    def __post_init__(self) -> None:
        for key in ("a", "b"):
            value = getattr(self, key)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{key} = {value!r} must be a positive (dimensionless) length")

    # ------------------------------------------------------------------ geometry
    @cached_property
    def top_points(self) -> Array:
        """A1, A2, A3 in the moving frame, rows of (3, 3) (docs/li2017_stewart36.md#s1.2)."""
        a = self.a
        return np.array(
            [[-a / (2 * _SQ3), a / 2, 0.0], [-a / (2 * _SQ3), -a / 2, 0.0], [a / _SQ3, 0.0, 0.0]]
        )

    @property
    def platform_points(self) -> Array:
        """:attr:`top_points`, as :class:`SixLegs` names them."""
        return self.top_points

    @cached_property
    def base_points(self) -> Array:
        """B1..B6 in the fixed frame, rows of (6, 3): B1 on +Y, counter-clockwise every 60 deg."""
        phi = np.deg2rad(90.0 + 60.0 * np.arange(6))
        return self.b * np.stack([np.cos(phi), np.sin(phi), np.zeros(6)], axis=-1)

    def home(self) -> Array:
        """Table 3 row 1 (rad, -): the pose whose IK is the reconstructed FK input (docs/li2017_stewart36.md#g1)."""
        return pose_from_paper(TABLE3_ROW1)

    def pose_bounds(self) -> tuple[Array, Array]:
        """The PSO search box of docs/li2017_stewart36.md#s2.3 (ASSUMED, the paper states none): alpha, gamma in [-pi, pi],
        beta in [-pi/2, pi/2], X, Y in [-2, 2] (scaled by max(1, b/2)), Z in [0, 3 max(1, b/3)]."""
        s = max(1.0, self.b / 2)
        return (
            np.array([-np.pi, -np.pi / 2, -np.pi, -2 * s, -2 * s, 0.0]),
            np.array([np.pi, np.pi / 2, np.pi, 2 * s, 2 * s, 3.0 * max(1.0, self.b / 3)]),
        )

    # ------------------------------------------------------------------ kinematics
    def platform_world(self, pose: ArrayLike) -> Array:
        """A1, A2, A3 in the fixed frame (eq. 1), shape (..., 3, 3)."""
        x = as_batch(pose, 6, "pose")
        return x[..., None, 3:] + np.einsum("...ij,kj->...ki", self.rotation(x), self.top_points)

    def leg_vectors(self, pose: ArrayLike) -> Array:
        """``A_p(i) - B_i`` (..., 6, 3)."""
        return self.platform_world(pose)[..., LEG_TOP, :] - self.base_points

    # ik (eq. 2), residual (eq. 3, squared), jacobian_pose (d f / d pose: 2 u_q . (w_i x v_i) for
    # the angles, u_q the joint axis of angle q in the fixed frame, 2 v_i for X, Y, Z), in_domain
    # (every finite pose) and on_assembly (above the base, Z > 0, as fk and the paper take it: the
    # mirror image below has the same legs) are the kernels of parakin.kernels.stewart36
    # (Mechanism's defaults; one source for numpy, numba and torch, docs/kernels.md)
    def objective(self, pose: ArrayLike, joints: ArrayLike) -> Array:
        """The paper's fitness, eq. (4): ``F = sum_i f_i^2`` (the text's "eq. (5)" is a slip, docs/li2017_stewart36.md#g5)."""
        f = self.residual(pose, joints)
        return np.sum(f * f, axis=-1)

    def check_joints(self, joints: ArrayLike) -> None:
        """Raise UnreachableError where a leg pair cannot reach its base edge: ``L_i > 0`` and
        ``|L_2k-1 - L_2k| <= b <= L_2k-1 + L_2k`` (the circle of A_k must exist, docs/li2017_stewart36.md#s1.5).
        Inputs passing this may still have no real solution (the triangle does not close):
        :meth:`fk_all` then returns no real pose."""
        q = as_batch(joints, 6, "joints")
        self._check_positive(q)
        l1, l2 = q[..., 0::2], q[..., 1::2]
        gap, reach = np.abs(l1 - l2), l1 + l2

        def cannot_meet(what: str, value: Array) -> Callable[[tuple[int, ...]], str]:
            def message(idx: tuple[int, ...]) -> str:
                k = idx[-1]
                return (
                    what.format(i=2 * k + 1, j=2 * k + 2, v=value[idx], b=self.b)
                    + f": legs {2 * k + 1}, {2 * k + 2} cannot meet at A{k + 1}"
                )

            return message

        raise_first(
            gap > self.b,
            q.shape[:-1],
            cannot_meet("|L{i} - L{j}| = {v:.6g} exceeds the base edge b = {b}", gap),
        )
        raise_first(
            reach < self.b,
            q.shape[:-1],
            cannot_meet("L{i} + L{j} = {v:.6g} is shorter than the base edge b = {b}", reach),
        )

    # ------------------------------------------------------------------ all forward solutions
    def circles(self, joints: ArrayLike) -> tuple[Array, Array, Array]:
        """Circle of each A_k (legs 2k-1, 2k about base edge B_2k-1 B_2k): centres C (..., 3, 3),
        radii r (..., 3) (NaN where the circle does not exist) and in-plane unit normals u (3, 3)."""
        q = as_batch(joints, 6, "joints")
        b0, b1 = self.base_points[0::2], self.base_points[1::2]
        d = np.linalg.norm(b1 - b0, axis=-1)  # (3,) = b
        e = (b1 - b0) / d[:, None]
        l1, l2 = q[..., 0::2], q[..., 1::2]
        s = (l1**2 - l2**2 + d**2) / (2 * d)
        with np.errstate(invalid="ignore"):
            r = np.sqrt(l1**2 - s**2)
        c = b0 + s[..., None] * e
        u = np.cross(np.array([0.0, 0.0, 1.0]), e)
        return c, r, u

    def _biquadratics(self, c: Array, r: Array, u: Array) -> Array:
        """Coefficients G[k, p, q] of E_ij (pairs (0,1), (1,2), (0,2)) times (1+ti^2)(1+tj^2) at
        ti^p tj^q, ti = tan(theta_i/2), shape (..., 3, 3, 3)."""
        out = []
        for i, j in ((0, 1), (1, 2), (0, 2)):
            cij = c[..., i, :] - c[..., j, :]
            k0 = np.einsum("...c,...c->...", cij, cij) + r[..., i] ** 2 + r[..., j] ** 2 - self.a**2
            p = 2 * r[..., i] * (cij @ u[i])
            qq = -2 * r[..., j] * (cij @ u[j])
            m = -2 * r[..., i] * r[..., j] * float(u[i] @ u[j])
            n = -2 * r[..., i] * r[..., j]
            g = np.zeros(k0.shape + (3, 3))
            # coefficient of tj^0: (K+Q)(1+ti^2) + (P+M)(1-ti^2); tj^2: (K-Q)(1+ti^2) + (P-M)(1-ti^2)
            g[..., 0, 0] = k0 + qq + p + m
            g[..., 2, 0] = k0 + qq - p - m
            g[..., 0, 2] = k0 - qq + p - m
            g[..., 2, 2] = k0 - qq - p + m
            g[..., 1, 1] = 4 * n
            out.append(g)
        return np.stack(out, axis=-3)

    def fk_poly(self, joints: ArrayLike, samples: int = 32) -> Array:
        """Coefficients (ascending, (..., 17), complex) of the degree-16 polynomial in
        ``t1 = tan(theta_1/2)`` whose roots are the FK solutions: ``Res_t3(Res_t2(E12, E23), E13)``,
        evaluated at ``samples`` points of the unit circle (Sylvester determinants) and interpolated
        by FFT. Coefficients above degree 16 vanish to rounding (checked by :meth:`fk_all`)."""
        c, r, u = self.circles(joints)
        g = self._biquadratics(c, r, u)  # (..., 3, 3, 3)
        t = np.exp(2j * np.pi * np.arange(samples) / samples)  # (S,)
        tp = t[:, None] ** np.arange(3)  # (S, 3)
        a12 = np.einsum(
            "...pq,sp->...sq", g[..., 0, :, :], tp
        )  # E12 as quadratic in t2, (..., S, 3)
        e13 = np.einsum("...pq,sp->...sq", g[..., 2, :, :], tp)  # E13 as quadratic in t3
        cc = g[..., 1, None, :, :]  # E23: row p = power of t2, col q = power of t3 -> c_p(t3)
        a0, a1, a2 = (a12[..., k][..., None] for k in range(3))
        c0, c1, c2 = (cc[..., k, :] for k in range(3))
        pm = _pmul
        res = pm(a2 * c0 - a0 * c2, a2 * c0 - a0 * c2) - pm(
            a2 * c1 - a1 * c2, a1 * c0 - a0 * c1
        )  # deg 4 in t3
        syl = np.zeros(res.shape[:-1] + (6, 6), dtype=complex)
        rr = res[..., ::-1]  # descending
        ee = e13[..., ::-1]
        for row in range(2):
            syl[..., row, row : row + 5] = rr
        for row in range(4):
            syl[..., 2 + row, row : row + 3] = ee
        vals = np.linalg.det(syl)  # (..., S)
        coef = np.fft.fft(vals, axis=-1) / samples
        return coef

    def fk_all(self, joints: ArrayLike, *, newton_steps: int = 8, return_info: bool = False):
        """Every real forward solution, shape (..., 16, 6) NaN-padded, sorted by Z descending.

        Method (docs/li2017_stewart36.md#s1.5): the three A_k move on circles fixed by the leg pairs; the triangle
        closure gives three biquadratics in ``t_k = tan(theta_k / 2)``; two resultants give a
        degree-16 polynomial in t1 (:meth:`fk_poly`), whose 16 complex roots are found as companion
        eigenvalues; t2, t3 are back-substituted, all three refined by complex Newton on the
        biquadratics, the real ones converted to poses, polished by Newton on the pose and kept only
        if ``max |IK(pose) - L| <= 1e-9``. With ``return_info`` also a dict of per-input arrays:
        ``n_complex`` (roots of the polynomial), ``n_real``, ``n_above`` (Z > 0), ``ik_error``
        (max over the real solutions), ``tail`` (relative size of the interpolated coefficients
        above degree 16: the certificate that the degree is 16), ``homotopy`` (see below).

        Completeness: where the refined roots are not 16 distinct converged solutions of the
        biquadratics (:func:`_unresolved`: the polynomial's roots clustered, so that root finding
        lost some; about 7 % of inputs drawn over the whole pose box, rare near home), the input is
        also solved by the certified parameter homotopy of the 6-6 platform
        (:class:`parakin.mechanisms.stewart66.Stewart66` with this platform's anchors, 16 roots)
        and the real solutions of both, each checked by the IK, are merged (``homotopy`` True).

        Where the compiled kernels are on (:func:`parakin.kernels.enabled`), the same steps run
        compiled, in parallel for large batches (:mod:`parakin.kernels.stewart36_all`; the roots
        there come from Aberth-Ehrlich iterations on the polynomial, which is even, in t1^2).
        Results agree to rounding except on badly conditioned inputs near singular configurations
        (see ``tests/test_kernels_all.py``).
        """
        q = as_batch(joints, 6, "joints")
        batch = q.shape[:-1]
        qf = q.reshape(-1, 6)
        from parakin import kernels

        if type(self) is Stewart36 and kernels.enabled():  # compiled: parakin.kernels.stewart36_all
            from parakin.kernels import stewart36_all

            p = stewart36_all.params(
                self.top_points[LEG_TOP], self.base_points, self.a, self.home()
            )
            out, info = stewart36_all.fk_all(p, qf, int(newton_steps))
            unresolved = np.flatnonzero(info.pop("unresolved"))
        else:
            out, info, unresolved = self._fk_all_numpy(qf, newton_steps)
        self._complete_by_homotopy(qf, out, info, unresolved)
        out = out.reshape(*batch, 16, 6)
        if return_info:
            return out, {k: v.reshape(batch) for k, v in info.items()}
        return out

    def _fk_all_numpy(self, qf: Array, newton_steps: int) -> tuple[Array, dict, Array]:
        """:meth:`fk_all` of flat inputs by numpy: ``(poses (n, 16, 6), info, unresolved rows)``."""
        n = len(qf)
        c, r, u = self.circles(qf)
        ok = np.all(np.isfinite(r), axis=-1)
        out = np.full((n, 16, 6), np.nan)
        info = {
            "n_complex": np.zeros(n, int),
            "n_real": np.zeros(n, int),
            "n_above": np.zeros(n, int),
            "ik_error": np.full(n, np.nan),
            "tail": np.full(n, np.nan),
            "homotopy": np.zeros(n, bool),
        }
        idx = np.flatnonzero(ok)
        unresolved = np.zeros(0, dtype=int)
        if idx.size:
            coef = self.fk_poly(qf[idx])
            scale = np.max(np.abs(coef[:, :17]), axis=-1)
            info["tail"][idx] = np.max(np.abs(coef[:, 17:]), axis=-1) / scale
            roots = _poly_roots(coef[:, :17] / scale[:, None])  # (m, 16)
            info["n_complex"][idx] = np.sum(np.isfinite(roots), axis=-1)
            g = self._biquadratics(c[idx], r[idx], u)
            t = _back_substitute(g, roots)  # (m, 16, 3) complex
            t = _newton_t(g, t, newton_steps)
            t = _recover_merged(g, t, newton_steps)
            unresolved = idx[_unresolved(g, t)]
            real = np.all(np.abs(t.imag) <= 1e-6 * (1 + np.abs(t)), axis=-1) & np.all(
                np.isfinite(t), -1
            )
            theta = 2 * np.arctan(t.real)
            pts = c[idx][:, None, :, :] + r[idx][:, None, :, None] * (
                np.cos(theta)[..., None] * u + np.sin(theta)[..., None] * np.array([0.0, 0.0, 1.0])
            )
            poses = self.pose_from_points(pts)
            tgt = np.broadcast_to(qf[idx][:, None, :], poses.shape)
            poses = np.where(real[..., None], poses, self.home())
            for _ in range(3):  # Newton polish on the pose
                with np.errstate(all="ignore"):
                    f = self.residual(poses, tgt)
                    jac = self.jacobian_pose(poses, tgt)
                    step = np.linalg.solve(jac, f[..., None])[..., 0]
                good = np.all(np.isfinite(step), -1) & real
                poses = np.where(
                    good[..., None], poses - np.where(good[..., None], step, 0.0), poses
                )
            poses[..., :3] = (poses[..., :3] + np.pi) % (2 * np.pi) - np.pi
            err = np.max(np.abs(self.ik(poses) - tgt), axis=-1)
            keep = real & (err <= 1e-9)
            poses[~keep] = np.nan
            poses = _dedupe(poses)
            key = np.where(np.isfinite(poses[..., 5]), -poses[..., 5], np.inf)
            order = np.argsort(key, axis=-1, kind="stable")
            poses = np.take_along_axis(poses, order[..., None], axis=1)
            out[idx] = poses
            fin = np.isfinite(poses[..., 0])
            info["n_real"][idx] = fin.sum(-1)
            info["n_above"][idx] = (fin & (np.nan_to_num(poses[..., 5]) > 0)).sum(-1)
            with np.errstate(invalid="ignore"):
                e = np.where(
                    np.isfinite(poses[..., 0]),
                    np.max(np.abs(self.ik(np.nan_to_num(poses)) - qf[idx][:, None]), axis=-1),
                    -np.inf,
                )
            info["ik_error"][idx] = np.where(fin.any(-1), e.max(-1), np.nan)
        return out, info, unresolved

    @cached_property
    def as_stewart66(self):
        """This platform as a general 6-6 (coincident top anchors allowed): its certified
        all-solutions FK (:meth:`parakin.mechanisms.stewart66.Stewart66.fk_all`, 16 roots)."""
        from parakin.mechanisms.stewart66 import Stewart66

        return Stewart66(
            base=self.base_points, platform=self.top_points[LEG_TOP], allow_coincident=True
        )

    def _complete_by_homotopy(self, qf: Array, out: Array, info: dict, rows: Array) -> None:
        """Merge the real solutions of :attr:`as_stewart66`'s certified homotopy into inputs
        ``rows`` of ``out`` (n, 16, 6) and their ``info`` counts, in place (each solution checked by
        the IK, duplicates removed, sorted by Z descending)."""
        info.setdefault("homotopy", np.zeros(len(qf), bool))
        if not len(rows):
            return
        extra = self.as_stewart66.fk_all(qf[rows])  # (k, 40, 6): certified real, IK-checked
        extra[..., :3] = (extra[..., :3] + np.pi) % (2 * np.pi) - np.pi  # as this path wraps
        poses = _dedupe(np.concatenate([out[rows], extra], axis=1))
        key = np.where(np.isfinite(poses[..., 5]), -poses[..., 5], np.inf)
        poses = np.take_along_axis(poses, np.argsort(key, -1, kind="stable")[..., None], 1)
        out[rows] = poses[:, :16]
        fin = np.isfinite(out[rows][..., 0])
        with np.errstate(invalid="ignore"):
            e = np.max(np.abs(self.ik(np.nan_to_num(out[rows])) - qf[rows][:, None]), axis=-1)
        info["n_real"][rows] = fin.sum(-1)
        info["n_above"][rows] = (fin & (np.nan_to_num(out[rows][..., 5]) > 0)).sum(-1)
        info["ik_error"][rows] = np.where(fin.any(-1), np.where(fin, e, -np.inf).max(-1), np.nan)
        info["homotopy"][rows] = True

    def pose_from_points(self, pts: ArrayLike) -> Array:
        """Pose (..., 6) of the platform whose vertices A1, A2, A3 are ``pts`` (..., 3, 3) (docs/li2017_stewart36.md#s1.5):
        ``O_A`` the centroid, ``y = (A1 - A2)/|.|``, ``x`` along ``A3 - (A1 + A2)/2``, ``z = x cross y``."""
        p = np.asarray(pts, dtype=float)
        o = p.mean(axis=-2)
        y = p[..., 0, :] - p[..., 1, :]
        y = y / np.linalg.norm(y, axis=-1, keepdims=True)
        x = p[..., 2, :] - 0.5 * (p[..., 0, :] + p[..., 1, :])
        x = x - np.sum(x * y, -1, keepdims=True) * y
        x = x / np.linalg.norm(x, axis=-1, keepdims=True)
        z = np.cross(x, y)
        t = np.stack([x, y, z], axis=-1)
        return np.concatenate([euler_zyx_from_matrix(t), o], axis=-1)

    def fk(self, joints: ArrayLike, near: ArrayLike | None = None) -> Array:
        """One forward solution: of the certified real solutions above the base (Z > 0), the one
        closest to ``near`` (default :meth:`home`; angles compared modulo 2 pi), shape (..., 6).
        The 3-6 platform has up to 8 such assemblies, so "the" FK needs this choice; a controller
        passes its last pose. Raises UnreachableError where no real solution lies above the base."""
        sols = self.fk_all(joints)  # (..., 16, 6), NaN-padded
        ref = self.home() if near is None else as_batch(near, 6, "near")
        diff = self.pose_difference(sols, ref[..., None, :])
        dist = np.sqrt(np.sum(diff * diff, axis=-1))
        ok = np.isfinite(dist) & (np.nan_to_num(sols[..., 5]) > 0)
        none = ~np.any(ok, axis=-1)
        if np.any(none):
            raise UnreachableError(
                "leg lengths have no real forward solution above the base"
                f"{describe_first(none, none.shape)}"
            )
        best = np.argmin(np.where(ok, dist, np.inf), axis=-1)
        return np.take_along_axis(sols, best[..., None, None], axis=-2)[..., 0, :]

    def kernel_params(self) -> Array:
        """The platform point of each leg in the moving frame (6 x 3), then the base points."""
        return kernels.PARAMS.pack(platform=self.top_points[LEG_TOP], base=self.base_points)

    def mirror(self, pose: ArrayLike) -> Array:
        """Reflection about the base plane: ``(alpha, -beta, -gamma, X, Y, -Z)`` (same leg lengths)."""
        x = as_batch(pose, 6, "pose").copy()
        x[..., [1, 2, 5]] *= -1
        return x

    # ------------------------------------------------------------------ dynamics (issue 27)
    def mass_model(self) -> MassModel:
        """Illustrative defaults (the paper has no dynamics; lengths in units of the top side ``a``
        are read as metres): a 5 kg platform and legs of a 1 kg cylinder and a 0.5 kg piston, shaped
        by :func:`parakin.dynamics.model.hexapod_masses` to the mean leg length at :meth:`home`."""
        leg = float(np.mean(self.ik(self.home())))
        return hexapod_masses(
            self.top_points, leg, 5.0, 1.0, 0.5, note="stewart36 illustrative defaults"
        )


# ---------------------------------------------------------------------------------------- helpers
def pose_from_paper(pose: ArrayLike) -> Array:
    """(deg, deg, deg, -, -, -) -> (rad, rad, rad, -, -, -)."""
    p = np.asarray(pose, dtype=float).copy()
    p[..., :3] = np.deg2rad(p[..., :3])
    return p


def pose_to_paper(pose: ArrayLike) -> Array:
    """(rad, rad, rad, -, -, -) -> (deg, deg, deg, -, -, -)."""
    p = np.asarray(pose, dtype=float).copy()
    p[..., :3] = np.rad2deg(p[..., :3])
    return p


def _pmul(p: Array, q: Array) -> Array:
    """Product of polynomials along the last axis (ascending coefficients), broadcasting."""
    n = p.shape[-1] + q.shape[-1] - 1
    shape = np.broadcast_shapes(p.shape[:-1], q.shape[:-1]) + (n,)
    out = np.zeros(shape, dtype=np.result_type(p, q))
    for i in range(p.shape[-1]):
        out[..., i : i + q.shape[-1]] += p[..., i : i + 1] * q
    return out


def _poly_roots(coeffs: Array) -> Array:
    """Roots of many polynomials (ascending complex coefficients (m, d+1)) by companion eigenvalues;
    trailing near-zero leading coefficients lower the degree (roots at infinity -> NaN)."""
    m, d1 = coeffs.shape
    d = d1 - 1
    out = np.full((m, d), np.nan + 0j)
    lead_ok = np.abs(coeffs) > 1e-13
    deg = np.where(lead_ok.any(-1), d - np.argmax(lead_ok[:, ::-1], axis=-1), 0)
    for k in np.unique(deg):
        rows = np.flatnonzero(deg == k)
        if k < 1:
            continue
        cf = coeffs[rows, : k + 1]
        comp = np.zeros((len(rows), k, k), dtype=complex)
        comp[:, 1:, :-1] = np.eye(k - 1)
        comp[:, :, -1] = -cf[:, :-1] / cf[:, -1:]
        out[rows, :k] = np.linalg.eigvals(comp)
    return out


def _eval_bq(g: Array, ti: Array, tj: Array) -> Array:
    """Biquadratic sum_pq g[p, q] ti^p tj^q, broadcasting g (..., 3, 3) over ti, tj."""
    pi = ti[..., None] ** np.arange(3)
    pj = tj[..., None] ** np.arange(3)
    return np.einsum("...pq,...p,...q->...", g, pi, pj)


def _quad_roots(c: Array) -> Array:
    """Both roots (..., 2) of c0 + c1 t + c2 t^2 (complex; NaN for degenerate)."""
    c0, c1, c2 = c[..., 0], c[..., 1], c[..., 2]
    with np.errstate(all="ignore"):
        disc = np.sqrt(c1 * c1 - 4 * c2 * c0 + 0j)
        sgn = np.where((np.conj(c1) * disc).real >= 0, 1.0, -1.0)
        qq = -0.5 * (c1 + sgn * disc)
        return np.stack([qq / c2, c0 / qq], axis=-1)


def _back_substitute(g: Array, roots: Array) -> Array:
    """(t1, t2, t3) (m, 16, 3) for each t1 root: t2 from E12, t3 from E13, the pair minimising |E23|."""
    gg = g[:, None]  # (m, 1, 3, 3, 3)
    t1 = np.nan_to_num(roots, nan=0.0)
    tp = t1[..., None] ** np.arange(3)
    c12 = np.einsum("...pq,...p->...q", gg[..., 0, :, :], tp)
    c13 = np.einsum("...pq,...p->...q", gg[..., 2, :, :], tp)
    t2 = _quad_roots(c12)  # (m, 16, 2)
    t3 = _quad_roots(c13)
    e23 = np.abs(
        _eval_bq(gg[..., 1, None, None, :, :], t2[..., :, None], t3[..., None, :])
    )  # (m,16,2,2)
    e23 = np.where(np.isfinite(e23), e23, np.inf).reshape(*e23.shape[:-2], 4)
    best = np.argmin(e23, axis=-1)
    i2, i3 = best // 2, best % 2
    out = np.stack(
        [
            t1,
            np.take_along_axis(t2, i2[..., None], -1)[..., 0],
            np.take_along_axis(t3, i3[..., None], -1)[..., 0],
        ],
        axis=-1,
    )
    out[~np.isfinite(roots)] = np.nan
    return out


def _newton_update(g: Array, t: Array) -> tuple[Array, Array]:
    """One complex Newton update on (E12(t1,t2), E23(t2,t3), E13(t1,t3)) = 0, batched over the
    leading axes of ``t`` (..., 3): ``(step, ok)``, ``ok`` False (step 0) where the Jacobian is not
    finite or singular."""
    gg = g[:, None]
    pw = np.arange(3)
    with np.errstate(all="ignore"):
        p = t[..., None] ** pw  # (m, 16, 3, 3): variable, power
        dp = np.concatenate([np.zeros_like(p[..., :1]), p[..., :1], 2 * p[..., 1:2]], axis=-1)
        f = np.zeros(t.shape, dtype=complex)
        jac = np.zeros(t.shape + (3,), dtype=complex)
        for row, (i, j, k) in enumerate(((0, 1, 0), (1, 2, 1), (0, 2, 2))):
            gk = gg[..., k, :, :]
            f[..., row] = np.einsum("...pq,...p,...q->...", gk, p[..., i, :], p[..., j, :])
            jac[..., row, i] = np.einsum("...pq,...p,...q->...", gk, dp[..., i, :], p[..., j, :])
            jac[..., row, j] = np.einsum("...pq,...p,...q->...", gk, p[..., i, :], dp[..., j, :])
        fin = np.all(np.isfinite(jac), axis=(-1, -2)) & np.all(np.isfinite(f), -1)
        ok = fin & (np.abs(np.linalg.det(np.where(fin[..., None, None], jac, np.eye(3)))) > 1e-300)
        jj = np.where(ok[..., None, None], jac, np.eye(3))
        step = np.linalg.solve(jj, np.where(ok[..., None], f, 0)[..., None])[..., 0]
    return step, ok


def _newton_t(g: Array, t: Array, steps: int) -> Array:
    """Complex Newton on (E12(t1,t2), E23(t2,t3), E13(t1,t3)) = 0, batched over (m, 16)."""
    for _ in range(steps):
        step, ok = _newton_update(g, t)
        t = np.where(ok[..., None], t - step, t)
    return t


def _is_real_t(t: Array) -> Array:
    return np.all(np.isfinite(t), axis=-1) & np.all(
        np.abs(t.imag) <= 1e-6 * (1 + np.abs(t)), axis=-1
    )


#: half-width (relative, times 1 + |t1|) and grid size of the 1-D scan that recovers a root lost when two
#: roots of a near-multiple cluster converge to the same solution (a module constant, not a config key)
RECOVER_WIDTH, RECOVER_POINTS = 0.05, 4001


def _recover_merged(g: Array, t: Array, steps: int) -> Array:
    """Recover real roots lost in near-multiple clusters. With clustered roots of the degree-16 polynomial
    (e.g. three t1 roots within 0.008) the companion eigenvalues are off by ~1e-3 and complex Newton can
    send two of them to the same real solution, dropping a third real one (seen at b = 3: 10 real
    solutions, an impossible 5 mirror pairs with a near-triple cluster; the truth is 12). For each such
    duplicate, scan the closure residual E23 along real t1 (both branches of t2 from E12 and of t3 from
    E13) around it, refine each sign change by Newton and take the first real root not yet present."""
    t = t.copy()
    pw = np.arange(3)
    real = _is_real_t(t)
    with np.errstate(all="ignore"):
        d = np.max(np.abs(t[:, :, None] - t[:, None, :]), axis=-1)  # (m, 16, 16)
    close = (
        (d < 1e-7 * (1 + np.max(np.abs(np.nan_to_num(t)), axis=-1))[:, None, :])
        & real[:, :, None]
        & real[:, None, :]
    )
    close &= np.tri(t.shape[1], k=-1, dtype=bool)  # pairs (j, earlier)
    for i in np.flatnonzero(close.any(axis=(-1, -2))):
        ti = t[i]
        real = _is_real_t(ti)
        idx = np.flatnonzero(real)
        dup = [
            ja
            for a, ja in enumerate(idx)
            if any(
                np.max(np.abs(ti[ja] - ti[jb])) < 1e-7 * (1 + np.max(np.abs(ti[jb])))
                for jb in idx[:a]
            )
        ]
        for j in dup:
            c0 = float(ti[j, 0].real)
            w = RECOVER_WIDTH * (1 + abs(c0))
            grid = np.linspace(c0 - w, c0 + w, RECOVER_POINTS)
            tp = grid[:, None].astype(complex) ** pw
            t2 = _quad_roots(tp @ g[i, 0])
            t3 = _quad_roots(tp @ g[i, 2])
            cands = []
            for a in range(2):
                for b in range(2):
                    with np.errstate(all="ignore"):
                        h = _eval_bq(g[i, 1], t2[:, a], t3[:, b])
                    ok = (
                        (np.abs(h.imag) <= 1e-9 * (1 + np.abs(h.real)))
                        & (np.abs(t2[:, a].imag) < 1e-12)
                        & (np.abs(t3[:, b].imag) < 1e-12)
                    )
                    hr = h.real
                    k = np.flatnonzero(ok[:-1] & ok[1:] & (np.sign(hr[:-1]) != np.sign(hr[1:])))
                    for kk in k:
                        f = hr[kk] / (hr[kk] - hr[kk + 1])
                        cands.append(
                            [grid[kk] + f * (grid[kk + 1] - grid[kk]), t2[kk, a], t3[kk, b]]
                        )
            if not cands:
                continue
            cand = _newton_t(g[i : i + 1], np.array(cands, dtype=complex)[None], steps)[0]
            for cnd in cand:
                if _is_real_t(cnd) and not np.any(
                    np.max(np.abs(ti[_is_real_t(ti)] - cnd), axis=-1)
                    < 1e-7 * (1 + np.max(np.abs(cnd)))
                ):
                    ti[j] = cnd
                    break
        t[i] = ti
    return t


#: a refined (t1, t2, t3) is converged when one more Newton step moves it less than CONVERGED, and
#: two are distinct when they differ by at least DISTINCT (both relative, times 1 + |t|)
CONVERGED, DISTINCT = 1e-10, 1e-6


def _unresolved(g: Array, t: Array) -> Array:
    """Inputs (rows of ``t`` (m, 16, 3)) whose finite refined roots are not all converged (one more
    Newton step, with a nonsingular Jacobian, below ``CONVERGED``) and pairwise distinct (by
    ``DISTINCT``) solutions of the biquadratics: where the degree-16 polynomial's roots cluster,
    root finding and Newton lose some (two converge to one, or one stalls at a near-singular
    point), and the real solutions found may be fewer than the real ones there are."""
    step, ok = _newton_update(g, t)
    scale = 1 + np.max(np.abs(np.nan_to_num(t)), axis=-1)  # (m, 16)
    fin = np.all(np.isfinite(t), axis=-1)
    with np.errstate(invalid="ignore"):
        moved = np.max(np.abs(step), axis=-1) / scale
        d = np.max(np.abs(t[:, :, None] - t[:, None, :]), axis=-1)
    converged = np.all(~fin | (ok & (moved < CONVERGED)), axis=-1)
    pair = fin[:, :, None] & fin[:, None, :] & ~np.eye(t.shape[1], dtype=bool)
    far = d >= DISTINCT * np.maximum(scale[:, :, None], scale[:, None, :])
    return ~(converged & np.all(~pair | far, axis=(-1, -2)))


def _dedupe(poses: Array, tol: float = 1e-7) -> Array:
    """NaN out repeated solutions (a double root reported twice), per row of (m, 16, 6)."""
    p = poses.copy()
    for j in range(1, p.shape[1]):
        d = np.max(np.abs(p[:, :j] - p[:, j : j + 1]), axis=-1)
        dup = np.any(d < tol, axis=-1)
        p[dup, j] = np.nan
    return p
