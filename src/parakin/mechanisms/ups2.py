"""The 2-UPS/(S+SPR)R 2R1T parallel mechanism of Li et al. 2020 (Packaging Engineering 41(7)).

Base: equilateral triangle A0 A2 A3 of side ``a`` (A0 a vertex, the origin), A1 the midpoint of
A2A3. Platform: isosceles right triangle B1 B2 B3 with legs ``b`` (right angle at B1). Limbs: two
UPS legs A2B2, A3B3 (actuated lengths l2, l3); a rigid SR link A0B1 of length ``c``; an SPR leg
from A1 to B0 = (2/3) B1 on that link (actuated length l1). Paper §1, eqs (1)-(14); see
``docs/li2020_2ups.md#s1``.

Kinematics (all VERIFIED, docs/li2020_2ups.md#s4.1; re-checked by ``tests/test_ups2.py``):

* orientation ``R = Rz(alpha) Ry(beta) Rx(gamma)`` (eq 1) with ``alpha = 0`` (eqs 6-8: the first
  constraint ``B2B3 . e_y = 0`` gives ``sin(alpha) cos(beta) = 0``);
* position of B1 ``P = (rho sin(beta), Y, rho cos(beta))``, ``rho = +sqrt(c^2 - Y^2)`` (eq 14);
* pose ``(beta, gamma, Y)`` in (rad, rad, m); leg vectors from the vector form (9)-(11) (the
  printed scalar IK (15)-(17) has typos, docs/li2020_2ups.md#s1.7, and is not used);
* joints: **stroke changes** ``q_j = l_j - l_j(home)`` (m), the home pose being the paper's
  initial pose beta = gamma = Y = 0 (docs/li2020_2ups.md#g2, ASSUMED: Table 2's inputs are signed).

The paper gives no values for a, b, c (docs/li2020_2ups.md#g1): the defaults 150, 100, 300 mm are our choice
(ASSUMED), under which every Table 2 input has exactly one FK solution inside the Table 1 box and
that box is free of singularities.

Beyond the paper (docs/li2020_2ups.md#s7.1): ``l1`` depends on ``Y`` only, so ``Y`` is closed form; ``beta`` and
``gamma`` then solve one degree-8 polynomial in ``t = tan(gamma/2)`` (:meth:`UPS2.fk_all`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import cached_property
from types import ModuleType
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

import parakin.dynamics.jet as dj
from parakin.dynamics.jet import Jet
from parakin.dynamics.model import Bodies, BodyGroup, Closure, MassModel, RigidBody, strut
from parakin.geometry import rot_x, rot_y
from parakin.kernels import evaluate
from parakin.kernels import ups2 as kernels
from parakin.mechanisms.base import Array, Mechanism, Skeleton, as_batch, raise_first

__all__ = ["UPS2"]

_SQ3 = float(np.sqrt(3.0))


@dataclass(frozen=True)
class UPS2(Mechanism):
    """2-UPS/(S+SPR)R mechanism. Lengths in metres.

    ``a``, ``b``, ``c``: ASSUMED 0.150, 0.100, 0.300 m (the paper gives none, docs/li2020_2ups.md#g1, #s5).
    ``stroke_limits``: eq (19), |q1| <= 23 mm, |q2|, |q3| <= 32 mm.
    """

    a: float = 0.150  #: base triangle side |A0A2| (m) -- not in the paper, ASSUMED (docs/li2020_2ups.md#g1)
    b: float = 0.100  #: platform leg |B1B2| = |B1B3| (m) -- not in the paper, ASSUMED
    c: float = 0.300  #: SR link length |A0B1| (m) -- not in the paper, ASSUMED
    stroke_limits: tuple[float, float, float] = (0.023, 0.032, 0.032)  #: eq (19), m
    #: assembly branch of eq (14): +1 the paper's (rho = +sqrt(c^2 - Y^2), platform above the base),
    #: -1 the mirror assembly (rho < 0); strokes are always measured from the +1 home pose
    branch: int = 1

    name: ClassVar[str] = "2ups"
    kernels: ClassVar[ModuleType] = kernels
    pose_names: ClassVar[tuple[str, ...]] = ("beta", "gamma", "Y")
    joint_names: ClassVar[tuple[str, ...]] = ("l1", "l2", "l3")
    pose_units: ClassVar[tuple[str, ...]] = ("rad", "rad", "m")
    joint_units: ClassVar[tuple[str, ...]] = ("m", "m", "m")
    paper_pose_units: ClassVar[tuple[str, ...]] = ("deg", "deg", "mm")
    paper_joint_units: ClassVar[tuple[str, ...]] = ("mm", "mm", "mm")
    #: A0B0 / A0B1 (paper §1.1)
    link_ratio: ClassVar[float] = 2.0 / 3.0

    def __post_init__(self) -> None:
        for key in ("a", "b", "c"):
            value = getattr(self, key)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{key} = {value!r} m must be a positive length")
        lim = tuple(float(v) for v in self.stroke_limits)
        if len(lim) != 3 or not all(np.isfinite(v) and v > 0 for v in lim):
            raise ValueError(
                f"stroke_limits = {self.stroke_limits!r} must be three positive lengths (m)"
            )
        object.__setattr__(self, "stroke_limits", lim)
        if self.branch not in (1, -1):
            raise ValueError(
                f"branch = {self.branch!r} must be +1 (the paper's, rho > 0) or -1 (rho < 0)"
            )

    # ------------------------------------------------------------------ constructors
    @classmethod
    def li2020(cls) -> UPS2:
        """The nominal geometry of the reproduction (a, b, c = 150, 100, 300 mm, ASSUMED)."""
        return cls()

    # ------------------------------------------------------------------ derived geometry
    @property
    def k(self) -> float:
        """``(sqrt 2 / 2) b``: the platform points' offsets along u and v (eq 4)."""
        return float(np.sqrt(0.5) * self.b)

    @property
    def h(self) -> float:
        """``(sqrt 3 / 2) a``: distance A0 -> A1 (base height)."""
        return 0.5 * _SQ3 * self.a

    @cached_property
    def base_points(self) -> Array:
        """A0, A1, A2, A3 (eq 2) as rows of a (4, 3) array."""
        a, h = self.a, self.h
        return np.array([[0.0, 0.0, 0.0], [0.0, h, 0.0], [a / 2, h, 0.0], [-a / 2, h, 0.0]])

    @cached_property
    def platform_points_local(self) -> Array:
        """B1', B2', B3' in the moving frame (eq 4), rows of a (3, 3) array."""
        k = self.k
        return np.array([[0.0, 0.0, 0.0], [k, k, 0.0], [-k, k, 0.0]])

    @cached_property
    def home_lengths(self) -> Array:
        """Leg lengths (l1, l2, l3) at the initial pose beta = gamma = Y = 0 of the paper's branch:
        the stroke reference (the same physical strokes on both branches)."""
        if self.branch != 1:
            return dataclasses.replace(self, branch=1).home_lengths
        return self.lengths(np.zeros(3))

    def home(self) -> Array:
        """The paper's initial pose: platforms parallel, B1 above A0 (beta = gamma = Y = 0)."""
        return np.zeros(3)

    def pose_bounds(self) -> tuple[Array, Array]:
        """Table 1's PSO search box: beta in [-30, 30] deg, gamma in [-60, 60] deg, Y in [-20, 110] mm."""
        return (
            np.array([np.deg2rad(-30.0), np.deg2rad(-60.0), -0.020]),
            np.array([np.deg2rad(30.0), np.deg2rad(60.0), 0.110]),
        )

    # ------------------------------------------------------------------ kinematics
    def rotation(self, pose: ArrayLike) -> Array:
        """``R = Ry(beta) Rx(gamma)`` (eq 1 with alpha = 0), shape (..., 3, 3)."""
        x = as_batch(pose, 3, "pose")
        return rot_y(x[..., 0]) @ rot_x(x[..., 1])

    def position(self, pose: ArrayLike) -> Array:
        """``P = B1 = (rho sin beta, Y, rho cos beta)``, ``rho = sqrt(c^2 - Y^2)`` (eq 14)."""
        x = as_batch(pose, 3, "pose")
        rho = self._rho(x[..., 2])
        return np.stack([rho * np.sin(x[..., 0]), x[..., 2], rho * np.cos(x[..., 0])], axis=-1)

    def _rho(self, y: Array) -> Array:
        # clamped so that residual() stays finite for any Y; ik() rejects |Y| >= c explicitly
        return self.branch * np.sqrt(np.maximum(self.c**2 - y**2, 0.0))

    def points(self, pose: ArrayLike) -> dict[str, Array]:
        """A0..A3 (each (3,)), and B0, B1, B2, B3 (each (..., 3)) at ``pose`` (eqs 2-5, 14)."""
        x = as_batch(pose, 3, "pose")
        p = self.position(x)
        r = self.rotation(x)
        b = p[..., None, :] + np.einsum("...ij,kj->...ki", r, self.platform_points_local)
        out = {f"A{i}": self.base_points[i] for i in range(4)}
        out.update(
            {"B0": self.link_ratio * p, "B1": b[..., 0, :], "B2": b[..., 1, :], "B3": b[..., 2, :]}
        )
        return out

    def leg_vectors(self, pose: ArrayLike) -> Array:
        """Vectors l1 = B0 - A1, l2 = B2 - A2, l3 = B3 - A3 (eqs 9-11), shape (..., 3, 3)."""
        pts = self.points(pose)
        return np.stack(
            [pts["B0"] - pts["A1"], pts["B2"] - pts["A2"], pts["B3"] - pts["A3"]], axis=-2
        )

    def lengths(self, pose: ArrayLike) -> Array:
        """Absolute leg lengths |l_j| (m), shape (..., 3); no reachability check."""
        v = self.leg_vectors(pose)
        return np.sqrt(np.einsum("...ij,...ij->...i", v, v))

    def lengths_closed_form(self, pose: ArrayLike) -> Array:
        """|l_j| from the scalar closed forms (docs/li2020_2ups.md#s1.7; equal to the vector form (9)-(11)):
        ``l1^2 = 4c^2/9 + 3a^2/4 - (2/sqrt3) a Y``, ``l2,3^2 = Q -/+ a (rho + k sin g) sin b`` with
        ``Q = (rho + k sin g)^2 + k^2 + a^2/4 + (k cos g + Y - h)^2 - a k cos b``. Cheaper: the
        forms :meth:`residual`, :meth:`ik` and :meth:`jacobian_pose` evaluate (in the kernels of
        :mod:`parakin.kernels.ups2`)."""
        x = as_batch(pose, 3, "pose")
        beta, gamma, y = x[..., 0], x[..., 1], x[..., 2]
        a, k = self.a, self.k
        rho = self._rho(y)
        u = rho + k * np.sin(gamma)
        q = (
            u * u
            + (k * k + a * a / 4)
            + (k * np.cos(gamma) + y - self.h) ** 2
            - a * k * np.cos(beta)
        )
        s = a * u * np.sin(beta)
        l1 = 4 * self.c**2 / 9 + 0.75 * a * a - (2 / _SQ3) * a * y
        return np.sqrt(np.maximum(np.stack([l1, q - s, q + s], axis=-1), 0.0))

    # residual (eq 18 with strokes as inputs), jacobian_pose (differentiated from the closed forms
    # of lengths_closed_form), in_domain (|Y| < c) and on_assembly (the working assembly of fk,
    # |beta|, |gamma| < 90 deg on this instance's branch) are the kernels of parakin.kernels.ups2
    # (Mechanism's defaults; one source for numpy, numba and torch, docs/kernels.md)
    def ik(self, pose: ArrayLike, check_limits: bool = False) -> Array:
        """Strokes ``q = l(pose) - l(home)`` (m) of ``pose`` = (beta, gamma, Y) (rad, rad, m), from
        the closed forms of :meth:`lengths_closed_form`.

        Raises UnreachableError where ``|Y| >= c`` (eq 14 has no real rho), and, with
        ``check_limits=True``, where a stroke exceeds eq (19)'s limits.
        """
        x = as_batch(pose, 3, "pose")
        q, ok = evaluate(self._declared_kernel, "ik", x)
        raise_first(
            ~ok,
            x.shape[:-1],
            lambda idx: (
                f"pose Y = {x[idx][2]:.6g} m is unreachable: |Y| must be < c = {self.c} m "
                f"(eq. 14, rho = sqrt(c^2 - Y^2))"
            ),
        )
        if check_limits:
            self._check_limits(q)
        return q

    def _check_limits(self, q: Array) -> None:
        lim = np.asarray(self.stroke_limits)
        raise_first(
            np.abs(q) > lim * (1 + 1e-12),
            q.shape[:-1],
            lambda idx: (
                f"stroke l{idx[-1] + 1} = {q[idx] * 1e3:.6g} mm exceeds the limit "
                f"+/-{lim[idx[-1]] * 1e3:.6g} mm (eq. 19)"
            ),
        )

    def jacobian_joints(self, pose: ArrayLike, joints: ArrayLike | None = None) -> Array:
        """``d residual / d q = -I``."""
        x = as_batch(pose, 3, "pose")
        return np.broadcast_to(-np.eye(3), x.shape[:-1] + (3, 3)).copy()

    # ------------------------------------------------------------------ drawing
    def skeleton(self, pose: ArrayLike) -> Skeleton:
        """Fig. 1 redrawn from the model: base triangle, platform triangle, the SR link A0B1,
        the SPR leg A1B0 and the UPS legs A2B2, A3B3; frames A0-xyz and B1-uvw."""
        x = as_batch(pose, 3, "pose")
        if x.ndim != 1:
            raise ValueError(f"skeleton() draws one pose, got a batch of shape {x.shape[:-1]}")
        self.ik(x)
        pts = self.points(x)
        seg = lambda p, q: np.stack([pts[p], pts[q]])  # noqa: E731
        segments = [
            ("passive", seg("A0", "B1")),  # SR link (S at A0, R at B1)
            ("actuator", seg("A1", "B0")),  # SPR leg
            ("actuator", seg("A2", "B2")),  # UPS leg 2
            ("actuator", seg("A3", "B3")),  # UPS leg 3
        ]
        return Skeleton(
            points={name: np.asarray(p, dtype=float) for name, p in pts.items()},
            segments=segments,
            polygons=[
                ("base", np.stack([pts["A0"], pts["A2"], pts["A3"]])),
                ("platform", np.stack([pts["B1"], pts["B2"], pts["B3"]])),
            ],
            frames={"A_0": (np.zeros(3), np.eye(3)), "B_1": (pts["B1"], self.rotation(x))},
        )

    # ------------------------------------------------------------------ forward kinematics
    def y_from_l1(self, l1: ArrayLike) -> Array:
        """Closed-form ``Y`` from the absolute SPR length: ``l1^2 = 4c^2/9 + 3a^2/4 - (2/sqrt3) a Y``."""
        l1 = np.asarray(l1, dtype=float)
        return _SQ3 / (2 * self.a) * (4 * self.c**2 / 9 + 0.75 * self.a**2 - l1**2)

    def fk_all(self, joints: ArrayLike, polish: int = 2) -> Array:
        """Every real FK solution on this mechanism's branch of eq (14) (``branch``: +1 the paper's
        rho > 0, -1 the mirror assembly; :meth:`fk_all_branches` gives both), shape (..., 8, 3).

        ``Y`` from l1 in closed form; then, with ``D = (l3^2 - l2^2)/(2a)`` and
        ``E = (l2^2 + l3^2)/2 - rho^2 - 2k^2 - a^2/4 - (Y - h)^2``, ``sin(beta) = D/(rho + k sin(gamma))``
        and ``a cos(beta) = 2 rho sin(gamma) + 2 (Y - h) cos(gamma) - E/k``; ``sin^2 + cos^2 = 1``
        is a degree-8 polynomial in ``t = tan(gamma/2)`` (docs/li2020_2ups.md#s7.1). Each real root gives one
        ``(beta, gamma)`` with beta in (-pi, pi]; ``polish`` Newton steps on the 2x2 system refine
        it. Rows are sorted by ``|beta| + |gamma|`` with unused rows NaN (2, 4, 6 or 8 are real).
        """
        q = as_batch(joints, 3, "joints")
        batch = q.shape[:-1]
        qf = q.reshape(-1, 3)
        l2 = qf + self.home_lengths
        sq = l2**2
        a, k, h = self.a, self.k, self.h
        y = self.y_from_l1(l2[:, 0])
        n = len(qf)
        out = np.full((n, 8, 3), np.nan)
        ok = np.abs(y) < self.c
        if not np.any(ok):
            return out.reshape(*batch, 8, 3)
        yy = y[ok]
        rho = self.branch * np.sqrt(
            self.c**2 - yy**2
        )  # the polynomial holds for either sign (docs/li2020_2ups.md#s7.1)
        d = (sq[ok, 2] - sq[ok, 1]) / (2 * a)
        e = 0.5 * (sq[ok, 1] + sq[ok, 2]) - rho**2 - 2 * k**2 - a**2 / 4 - (yy - h) ** 2
        m = len(yy)
        one_t2 = np.broadcast_to(np.array([1.0, 0.0, 1.0]), (m, 3))  # 1 + t^2 (ascending powers)
        at = rho[:, None] * one_t2 + np.array([0.0, 2 * k, 0.0])
        bt = (
            4 * rho[:, None] * np.array([0.0, 1.0, 0.0])
            + 2 * (yy - h)[:, None] * np.array([1.0, 0.0, -1.0])
            - (e / k)[:, None] * one_t2
        )
        s2 = _polymul(one_t2, one_t2)
        at2 = _polymul(at, at)
        coeffs = (
            a**2 * d[:, None] ** 2 * _polymul(s2, s2)
            + _polymul(_polymul(bt, bt), at2)
            - a**2 * _polymul(at2, s2)
        )
        roots = _poly_roots(coeffs)  # (m, 8) complex
        real = np.abs(roots.imag) <= 1e-6 * (1 + np.abs(roots.real))
        t = np.where(real, roots.real, np.nan)
        gamma = 2 * np.arctan(t)
        sg, cg = np.sin(gamma), np.cos(gamma)
        with np.errstate(all="ignore"):
            sb = d[:, None] / (rho[:, None] + k * sg)
            cb = (2 * rho[:, None] * sg + 2 * (yy[:, None] - h) * cg - (e / k)[:, None]) / a
            beta = np.arctan2(sb, cb)
        poses = np.stack([beta, gamma, np.broadcast_to(yy[:, None], beta.shape)], axis=-1)
        target = qf[ok][:, None, :]
        with np.errstate(all="ignore"):
            for _ in range(polish):  # Newton on (l2, l3) in (beta, gamma), Y exact
                fin = np.all(np.isfinite(poses), axis=-1)
                pz = np.where(fin[..., None], poses, 0.0)
                r = self.residual(pz, np.broadcast_to(target, pz.shape))[..., 1:]
                jac = self.jacobian_pose(pz)[..., 1:, :2]
                det = jac[..., 0, 0] * jac[..., 1, 1] - jac[..., 0, 1] * jac[..., 1, 0]
                step0 = (jac[..., 1, 1] * r[..., 0] - jac[..., 0, 1] * r[..., 1]) / det
                step1 = (-jac[..., 1, 0] * r[..., 0] + jac[..., 0, 0] * r[..., 1]) / det
                good = fin & np.isfinite(step0) & np.isfinite(step1)
                poses[..., 0] -= np.where(good, step0, 0.0)
                poses[..., 1] -= np.where(good, step1, 0.0)
            poses[..., :2] = np.angle(np.exp(1j * poses[..., :2]))  # wrap to (-pi, pi]
            fin = np.all(np.isfinite(poses), axis=-1)
            res = np.abs(
                self.residual(
                    np.where(fin[..., None], poses, 0.0), np.broadcast_to(target, poses.shape)
                )
            )
            keep = fin & (np.max(res, axis=-1) <= 1e-7 * max(1.0, self.c))
        poses[~keep] = np.nan
        # drop duplicates (a double root reported twice)
        order_key = np.where(keep, np.abs(poses[..., 0]) + np.abs(poses[..., 1]), np.inf)
        idx = np.argsort(order_key, axis=-1)
        poses = np.take_along_axis(poses, idx[..., None], axis=1)
        for j in range(1, 8):
            same = np.all(np.abs(poses[:, j] - poses[:, j - 1]) < 1e-9, axis=-1)
            poses[same, j] = np.nan
        key = np.where(
            np.all(np.isfinite(poses), -1), np.abs(poses[..., 0]) + np.abs(poses[..., 1]), np.inf
        )
        poses = np.take_along_axis(poses, np.argsort(key, axis=-1)[..., None], axis=1)
        out[ok] = poses
        return out.reshape(*batch, 8, 3)

    def fk_all_branches(self, joints: ArrayLike) -> dict[int, Array]:
        """:meth:`fk_all` on both assembly branches of eq (14): ``{+1: (..., 8, 3), -1: (..., 8, 3)}``.
        A pose of branch -1 is interpreted by ``UPS2(..., branch=-1)``."""
        return {b: dataclasses.replace(self, branch=b).fk_all(joints) for b in (1, -1)}

    def real_solutions(self, joints: ArrayLike) -> tuple[Array, None]:
        """Every real solution on both branches of eq (14) (:meth:`fk_all_branches`), (N, 16, 3);
        no completeness guarantee (the degree-8 polynomial's roots are judged real by a threshold)."""
        both = self.fk_all_branches(joints)
        return np.concatenate([both[1], both[-1]], axis=-2), None

    def solution_labels(self, solutions: Array, joints: Array) -> list[list[str]]:
        """The branch of eq (14) each solution of :meth:`real_solutions` belongs to: its first 8
        rows are branch +1's (rho > 0, the paper's), the last 8 branch -1's (rho < 0, the mirror
        assembly, ``UPS2(branch=-1)``); a pose may belong to both (at Y = 0 the two coincide)."""
        names = {1: "branch +1 (rho > 0, the paper)", -1: "branch -1 (rho < 0, mirror)"}
        return [
            [
                names[1 if j < 8 else -1] if np.all(np.isfinite(x)) else ""
                for j, x in enumerate(rows)
            ]
            for rows in solutions
        ]

    def kernel_params(self) -> Array:
        """``a, k, c, h, branch`` and the home lengths ``l_j(home)``."""
        return kernels.PARAMS.pack(
            a=self.a, k=self.k, c=self.c, h=self.h, branch=float(self.branch),
            l_home=self.home_lengths,
        )  # fmt: skip

    def fk(self, joints: ArrayLike) -> Array:
        """The working-branch FK solution: the real solution with |beta|, |gamma| < 90 deg closest
        to the home pose (in units of the Table 1 box). Raises UnreachableError if there is none."""
        q = as_batch(joints, 3, "joints")
        sols = self.fk_all(q)
        lo, hi = self.pose_bounds()
        with np.errstate(invalid="ignore"):
            inside = (
                np.all(np.isfinite(sols), -1)
                & (np.abs(sols[..., 0]) < np.pi / 2)
                & (np.abs(sols[..., 1]) < np.pi / 2)
            )
            dist = np.where(
                inside,
                np.linalg.norm(np.nan_to_num(sols - self.home()) / (hi - lo), axis=-1),
                np.inf,
            )
        raise_first(
            ~np.any(inside, axis=-1),
            q.shape[:-1],
            lambda idx: (
                f"strokes (l1, l2, l3) = {tuple(np.round(q[idx] * 1e3, 6).tolist())} mm cannot "
                f"be assembled with |beta|, |gamma| < 90 deg (Y = "
                f"{float(self.y_from_l1(q[idx][0] + self.home_lengths[0])):.6g} m, c = {self.c} m)"
            ),
        )
        best = np.argmin(dist, axis=-1)
        return np.take_along_axis(sols, best[..., None, None], axis=-2)[..., 0, :]

    def check_joints(self, joints: ArrayLike) -> None:
        """Raise UnreachableError beyond eq (19)'s stroke limits, or where the strokes do not assemble."""
        q = as_batch(joints, 3, "joints")
        self._check_limits(q)
        self.fk(q)

    def within_limits(self, joints: ArrayLike) -> np.ndarray:
        """Boolean mask: strokes inside eq (19)'s limits."""
        q = as_batch(joints, 3, "joints")
        return np.all(np.abs(q) <= np.asarray(self.stroke_limits) * (1 + 1e-12), axis=-1)

    # ------------------------------------------------------------------ dynamics (issue 27)
    def mass_model(self) -> MassModel:
        """Illustrative defaults (the paper has no dynamics): a 1 kg platform (a thin disc of
        radius ``b / 2`` at the triangle's centroid), the SR link a 0.5 kg rod of length ``c``, and
        each leg a 0.3 kg cylinder and a 0.2 kg piston (10 cm rods of 1 cm radius, centres 5 cm
        from their joints)."""
        centroid = self.platform_points_local.mean(axis=0)
        cylinder, piston = RigidBody.rod(0.3, 0.1, 0.01, 0.05), RigidBody.rod(0.2, 0.1, 0.01, -0.05)
        return MassModel(
            {
                "platform": RigidBody.disc(1.0, 0.5 * self.b, centroid),
                "link": RigidBody.rod(0.5, self.c, 0.01, 0.5 * self.c),
                "spr_cylinder": cylinder,
                "spr_piston": piston,
                "cylinder": cylinder,
                "piston": piston,
            },
            note="2ups illustrative defaults",
        )

    def bodies(self, pose: Jet) -> Bodies:
        """The SR link (ball at A0, its frame ``[r, z x r, z]`` with ``z`` along A0B1 and ``r =
        Ry(beta) x`` the axis of both R joints), the platform hinged to it at B1 about ``r``, the SPR
        leg (piston hinged to the link at B0 about ``r``, cylinder sliding in it, ball-jointed to
        the base at A1: a loop closure) and the two UPS legs A2B2, A3B3, modelled as S-P-S
        (axisymmetric legs: the universal joint's hold on their spin is left out). Joints: the
        strokes from :attr:`home_lengths`."""
        beta, y = pose[..., 0], pose[..., 2]
        rho = self.branch * dj.sqrt(self.c**2 - y * y)
        sb, cb = dj.sin(beta), dj.cos(beta)
        b1 = dj.stack([rho * sb, y, rho * cb])  # eq 14
        rotation = dj.rotations([beta, pose[..., 1]], "yx")  # eq 1, alpha = 0
        r = dj.stack([cb, 0.0 * cb, -sb])  # Ry(beta) x: the R joints' axis
        z = b1 / self.c
        b0 = self.link_ratio * b1
        n, l1 = dj.normalize(b0 - self.base_points[1])
        frame = lambda axis: dj.stack([r, dj.cross(axis, r), axis], axis=-1)[..., None, :, :]  # noqa: E731
        tops = b1[..., None, :] + dj.matvec(
            rotation[..., None, :, :], self.platform_points_local[1:]
        )
        (cylinders, pistons), closure, lengths = strut(
            self.base_points[2:], tops, ("platform", "platform"), labels=("2", "3")
        )
        batch = y.shape

        def fixed(k: int) -> Jet:
            return dj.constant_like(np.broadcast_to(self.base_points[k], (*batch, 1, 3)), pose)

        axis = r.value[..., None, :]
        groups = (
            BodyGroup("link", ("link",), ("world",), "ball", fixed(0), rotation=frame(z)),
            BodyGroup(
                "platform",
                ("platform",),
                ("link",),
                "hinge",
                b1[..., None, :],
                rotation=rotation[..., None, :, :],
                joint_axis=axis,
            ),
            BodyGroup(
                "spr_piston",
                ("spr_piston",),
                ("link",),
                "hinge",
                b0[..., None, :],
                rotation=frame(n),
                joint_axis=axis,
            ),
            BodyGroup(
                "spr_cylinder",
                ("spr_cylinder",),
                ("spr_piston",),
                "slide",
                fixed(1),
                rotation=frame(n),
                joint_axis=-n.value[..., None, :],
            ),
            cylinders,
            pistons,
        )
        joints = dj.stack([l1, lengths[..., 0], lengths[..., 1]]) - self.home_lengths
        spr = Closure(
            ("spr_cylinder",), ("world",), np.broadcast_to(self.base_points[1], (*y.shape, 1, 3))
        )
        return Bodies(groups, joints, ("spr_cylinder", *pistons.names), (spr, closure))


def _polymul(p: Array, q: Array) -> Array:
    """Row-wise product of polynomials (ascending coefficients): (m, i) x (m, j) -> (m, i + j - 1)."""
    out = np.zeros((len(p), p.shape[1] + q.shape[1] - 1))
    for i in range(p.shape[1]):
        out[:, i : i + q.shape[1]] += p[:, i : i + 1] * q
    return out


def _poly_roots(coeffs: Array) -> Array:
    """Roots of many polynomials (ascending coefficients, rows of (m, d+1)) by batched companion
    eigenvalues; a vanishing leading coefficient gives roots at infinity (NaN)."""
    m, d1 = coeffs.shape
    d = d1 - 1
    lead = coeffs[:, -1]
    scale = np.max(np.abs(coeffs), axis=1)
    degenerate = np.abs(lead) < 1e-14 * scale
    lead = np.where(degenerate, 1.0, lead)
    comp = np.zeros((m, d, d))
    comp[:, 1:, :-1] = np.eye(d - 1)
    comp[:, :, -1] = -coeffs[:, :-1] / lead[:, None]
    roots = np.linalg.eigvals(comp).astype(complex)
    roots[degenerate] = np.nan
    return roots
