"""The 3-P(4S) translational parallel mechanism of Zhao et al. 2017 (Trans. CSAM 48(10)).

Three linear actuators on rails inclined at ``phi`` to the base plane; each drives a slider that
carries a 4S parallelogram whose upper edge is on the platform. The parallelogram keeps the
platform's orientation fixed, so the pose is the platform centre ``p = (x, y, z)`` only (§1.1),
and each parallelogram acts as one equivalent rod of length ``L`` from the lower-edge midpoint
``c_i`` to the upper-edge midpoint ``d_i``.

Geometry (paper §1.1, eqs 1-3; frames as in Fig. 2):

* base vertices ``u_i = r_b e_i``, ``e_i = (cos g_i, sin g_i, 0)``, ``g = (0, 120, 240) deg``;
* rail direction ``m_i = -cos(phi) e_i + sin(phi) e_z`` (inward and up). The paper writes the rail
  frame as ``R(z, alpha_i) R(x, -phi)``; read as a right-handed rotation that rail points *down*
  and no Table 1 pose is reachable, so the only feasible reading is inward-up (docs/zhao2017_3p4s.md#s1.3, #g1);
* slider midpoint ``c_i = u_i + l_i m_i`` (eq 3), platform point ``d_i = p + a e_i`` with
  ``a = r_a cos(theta) = sqrt(r_a^2 - d^2/4)`` (eq 1, ``theta = arcsin(d / 2 r_a)``).

The kinematics sees the radial dimensions only through ``delta = r_b - a``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from types import ModuleType
from typing import TYPE_CHECKING, ClassVar, Literal

import numpy as np
from numpy.typing import ArrayLike

from parakin.errors import SingularityError
from parakin.kernels import evaluate
from parakin.kernels import p3p4s as kernels
from parakin.mechanisms.base import Array, Mechanism, Skeleton, as_batch, raise_first

if TYPE_CHECKING:  # the dynamics are imported where they are used: a solve does not need them
    from parakin.dynamics.jet import Jet
    from parakin.dynamics.model import Bodies, MassModel

__all__ = ["P3P4S"]

_E_Z = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class P3P4S(Mechanism):
    """3-P(4S) mechanism. Lengths in metres, ``phi`` in radians.

    Defaults are the parameters the paper states in §1.1 (``r_a = 0.25``, ``r_b = 0.67``,
    ``L = 0.38``, ``phi = 30 deg``) with ``d = 0.12`` from Table 3 (§1.1 does not give it).
    """

    r_a: float = 0.25  #: platform circumradius (m)
    r_b: float = 0.67  #: base circumradius, rail end points u_i (m)
    L: float = 0.38  #: parallelogram side = equivalent rod length (m)
    d: float = 0.12  #: parallelogram upper/lower edge length (m)
    phi: float = float(np.deg2rad(30.0))  #: rail inclination to the base plane (rad)

    name: ClassVar[str] = "3p4s"
    pose_names: ClassVar[tuple[str, ...]] = ("x", "y", "z")
    joint_names: ClassVar[tuple[str, ...]] = ("l1", "l2", "l3")
    pose_units: ClassVar[tuple[str, ...]] = ("m", "m", "m")
    joint_units: ClassVar[tuple[str, ...]] = ("m", "m", "m")
    paper_pose_units: ClassVar[tuple[str, ...]] = ("m", "m", "m")  # Table 1 is in metres
    paper_joint_units: ClassVar[tuple[str, ...]] = ("m", "m", "m")
    #: limb azimuths gamma_i of the base vertices u_i (paper §1.1)
    gammas: ClassVar[tuple[float, ...]] = tuple(np.deg2rad([0.0, 120.0, 240.0]))
    #: residual (eq 4), its Jacobian, the IK (eqs 2-5), the domain and the working mode
    kernels: ClassVar[ModuleType] = kernels

    def __post_init__(self) -> None:
        for key in ("r_a", "r_b", "L", "d"):
            value = getattr(self, key)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{key} = {value!r} m must be a positive length")
        if not self.d < 2 * self.r_a:
            raise ValueError(
                f"d = {self.d} m must be < 2 r_a = {2 * self.r_a} m (theta = arcsin(d/2r_a))"
            )
        if not 0 < self.phi < np.pi / 2:
            raise ValueError(f"phi = {self.phi!r} rad must lie in (0, pi/2) (0 to 90 deg)")

    # ------------------------------------------------------------------ constructors
    @classmethod
    def zhao2017(cls) -> P3P4S:
        """The parameters stated in the paper's §1.1 (Table 3, 'before')."""
        return cls()

    @classmethod
    def zhao2017_optimised(cls) -> P3P4S:
        """The optimised design of the paper's Table 3 ('after')."""
        return cls(r_a=0.21, r_b=0.71, L=0.38, d=0.12, phi=float(np.deg2rad(35.0)))

    @classmethod
    def from_delta(
        cls, delta: float, L: float, phi: float, r_a: float = 0.25, d: float = 0.12
    ) -> P3P4S:
        """A mechanism with the given kinematic parameters ``delta = r_b - a``, ``L``, ``phi``."""
        return cls(r_a=r_a, r_b=float(delta + np.sqrt(r_a**2 - d**2 / 4)), L=L, d=d, phi=phi)

    # ------------------------------------------------------------------ derived geometry
    @cached_property
    def theta(self) -> float:
        """Half the angle a short platform edge subtends at the centre, ``arcsin(d / 2 r_a)``."""
        return float(np.arcsin(self.d / (2 * self.r_a)))

    @cached_property
    def a(self) -> float:
        """Distance platform centre -> d_i, ``r_a cos(theta)`` (eq 1)."""
        return float(np.sqrt(self.r_a**2 - self.d**2 / 4))

    @cached_property
    def delta(self) -> float:
        """``r_b - a``: the only radial dimension the kinematics depends on."""
        return self.r_b - self.a

    @cached_property
    def e(self) -> Array:
        """Radial unit vectors e_i, rows of a (3, 3) array."""
        g = np.asarray(self.gammas)
        return np.stack([np.cos(g), np.sin(g), np.zeros(3)], axis=-1)

    @cached_property
    def m(self) -> Array:
        """Rail unit vectors m_i (inward and up), rows of a (3, 3) array."""
        return -np.cos(self.phi) * self.e + np.sin(self.phi) * _E_Z

    def home(self) -> Array:
        """Table 1 case 1, the paper's initial pose (0, 0, 0.592) m."""
        return np.array([0.0, 0.0, 0.592])

    def pose_bounds(self) -> tuple[Array, Array]:
        """Box around the paper's working poses (Table 1 spans |x|,|y| <= 0.07, z 0.537-0.592).

        The top stays at 0.60 m: above it the stated geometry nears the singularity where the rods
        stand parallel (cond(J) ~ 5e1 at z = 0.60, 7e4 at 0.62).
        """
        return np.array([-0.08, -0.08, 0.52]), np.array([0.08, 0.08, 0.60])

    # ------------------------------------------------------------------ kinematics
    def _w(self, pose: Array) -> Array:
        """``w_i = d_i - u_i = p - delta e_i``, shape (..., 3 limbs, 3)."""
        return pose[..., None, :] - self.delta * self.e

    def _discriminant(self, pose: Array) -> tuple[Array, Array]:
        """``b_i = w_i . m_i`` and ``L^2 - |w_i - b_i m_i|^2`` (eq 5's ``L^2 - x^2 - z^2``)."""
        w = self._w(pose)
        b = np.einsum("...ij,ij->...i", w, self.m)
        return b, self.L**2 - (np.einsum("...ij,...ij->...i", w, w) - b**2)

    # residual, jacobian_pose, in_domain and on_assembly (the working mode of ik: every rod leans
    # along its rail) are the kernels of parakin.kernels.p3p4s (Mechanism's defaults; one source
    # for numpy, numba and torch, docs/kernels.md)
    def is_reachable(self, pose: ArrayLike) -> np.ndarray:
        """True where every limb's eq. (5) square root is real."""
        return evaluate(self._declared_kernel, "in_domain", as_batch(pose, 3, "pose"))

    def ik(self, pose: ArrayLike) -> Array:
        """Strokes ``l_i`` (m) of platform position ``pose`` (m), eqs (2)-(5), working branch.

        ``l_i = b_i - sqrt(L^2 - |w_i - b_i m_i|^2)``: the minus root keeps the slider below
        the platform point (the plus root is the other assembly mode, l ~ 0.9 m at home).
        Raises UnreachableError where the square root is imaginary.
        """
        x = as_batch(pose, 3, "pose")
        q, ok = evaluate(self._declared_kernel, "ik", x)
        if not np.all(ok):
            _, disc = self._discriminant(x)
            # a non-finite pose gives NaN strokes (disc < 0 is False): its callers name it
            raise_first(
                disc < 0,
                x.shape[:-1],
                lambda idx: (
                    f"pose (x, y, z) = {tuple(np.round(x[idx[:-1]], 6).tolist())} m is "
                    f"unreachable: limb {idx[-1] + 1} needs L^2 - x_u^2 - z_u^2 = {disc[idx]:.6g} m^2 "
                    f">= 0 (eq. 5, L = {self.L} m)"
                ),
            )
        return q

    def _rod(self, pose: Array, joints: Array) -> Array:
        """Rod vectors ``d_i - c_i = w_i - l_i m_i`` (..., 3, 3)."""
        return self._w(pose) - joints[..., :, None] * self.m

    def jacobian_joints(self, pose: ArrayLike, joints: ArrayLike) -> Array:
        """``d residual / d l``: diagonal, ``-n_i . m_i``."""
        rod = self._rod(as_batch(pose, 3, "pose"), as_batch(joints, 3, "joints"))
        return -np.einsum("...ij,ij->...i", rod, self.m)[..., None] * np.eye(3) / self.L

    def velocity_jacobian(self, pose: ArrayLike, joints: ArrayLike | None = None) -> Array:
        """Eq (8): ``qdot = J v`` with row i of J equal to ``n_i^T / (n_i^T m_i)``."""
        x = as_batch(pose, 3, "pose")
        n = self.rod_directions(x, joints)
        nm = np.einsum("...ij,ij->...i", n, self.m)
        raise_first(
            np.abs(nm) < 1e-12,
            x.shape[:-1],
            lambda idx: "n_i . m_i = 0 (rod perpendicular to its rail): J of eq. (8) is singular",
            SingularityError,
        )
        return n / nm[..., None]

    def rod_directions(self, pose: ArrayLike, joints: ArrayLike | None = None) -> Array:
        """Unit rod vectors ``n_i = (d_i - c_i) / L``, shape (..., 3, 3); joints default to IK."""
        x = as_batch(pose, 3, "pose")
        q = self.ik(x) if joints is None else as_batch(joints, 3, "joints")
        return self._rod(x, q) / self.L

    def points(self, pose: ArrayLike) -> dict[str, Array]:
        """Named points of Fig. 2 at ``pose``: O, p, u_i, c_i, d_i (each (..., 3, 3) or (..., 3))."""
        x = as_batch(pose, 3, "pose")
        q = self.ik(x)
        u = self.r_b * self.e
        return {
            "O": np.zeros(x.shape),
            "p": x,
            "u": np.broadcast_to(u, x.shape[:-1] + (3, 3)).copy(),
            "c": u + q[..., :, None] * self.m,
            "d": x[..., None, :] + self.a * self.e,
        }

    def skeleton(self, pose: ArrayLike) -> Skeleton:
        """Fig. 2's sketch at one pose: rails, sliders, both parallelogram rods, platform hexagon."""
        x = as_batch(pose, 3, "pose")
        if x.ndim != 1:
            raise ValueError(f"skeleton() draws one pose, got a batch of shape {x.shape[:-1]}")
        pts = self.points(x)
        q = self.ik(x)
        t = np.cross(_E_Z, self.e)  # tangential unit vectors, along the parallelogram edges
        half = 0.5 * self.d * t
        rail_end = max(float(q.max()) + 0.08, 0.6)
        segments: list[tuple[str, Array]] = []
        hexagon = []
        for i in range(3):
            u, c, d = pts["u"][i], pts["c"][i], pts["d"][i]
            segments.append(("rail", np.stack([u, u + rail_end * self.m[i]])))
            segments.append(("actuator", np.stack([u, c])))
            segments.append(("passive", np.stack([c - half[i], d - half[i]])))
            segments.append(("passive", np.stack([c + half[i], d + half[i]])))
            segments.append(("passive", np.stack([c - half[i], c + half[i]])))
            segments.append(("equivalent", np.stack([c, d])))
            hexagon += [d - half[i], d + half[i]]
        named = {"O": pts["O"], "p": x}
        for i in range(3):
            named[f"u_{i + 1}"] = pts["u"][i]
            named[f"c_{i + 1}"] = pts["c"][i]
            named[f"d_{i + 1}"] = pts["d"][i]
        frames = {"O": (np.zeros(3), np.eye(3)), "P": (x, np.eye(3))}
        for i in range(3):
            # limb frame {u_i} = R(z, alpha_i) R(x, phi) with alpha_i = gamma_i + 90 deg: x_i
            # horizontal and perpendicular to O u_i, y_i along the rail towards c_i, z_i = x_i x y_i
            y_i = self.m[i]
            x_i = t[i]
            frames[f"u_{i + 1}"] = (pts["u"][i], np.stack([x_i, y_i, np.cross(x_i, y_i)], axis=-1))
        return Skeleton(
            points=named,
            segments=segments,
            polygons=[("base", pts["u"]), ("platform", np.stack(hexagon))],
            frames=frames,
        )

    def _check_edge(self, pose: Array, q: Array) -> None:
        """UnreachableError where the computed pose lies (by rounding) just outside the workspace,
        so that :meth:`ik` would reject it: ``fk`` returns only poses its IK accepts."""
        _, disc = self._discriminant(pose)
        raise_first(
            np.any(disc < 0, axis=-1),
            q.shape[:-1],
            lambda idx: (
                f"strokes (l1, l2, l3) = {tuple(np.round(q[idx], 6).tolist())} m put the "
                f"platform on the workspace edge: at the computed pose L^2 - x_u^2 - z_u^2 = "
                f"{disc[idx].min():.3g} m^2 < 0 (eq. 5), which ik rejects"
            ),
        )

    def check_joints(self, joints: ArrayLike) -> None:
        """Raise UnreachableError unless the strokes assemble in the working mode (via :meth:`fk`)."""
        self.fk(joints)

    # ------------------------------------------------------------------ closed-form FK
    def kernel_params(self) -> Array:
        """``delta, L``, the radial unit vectors ``e_i`` (3 x 3), the rail unit vectors ``m_i``."""
        return kernels.PARAMS.pack(delta=self.delta, L=self.L, e=self.e, m=self.m)

    def fk(self, joints: ArrayLike, branch: Literal["upper", "lower"] = "upper") -> Array:
        """Closed-form forward kinematics: the intersection of three spheres (our addition).

        The platform centre lies on the spheres of radius ``L`` about ``C_i = delta e_i + l_i m_i``
        (= c_i - a e_i). Subtracting sphere 1 from spheres 2 and 3 leaves a line
        ``p = p0 + t u``; sphere 1 then gives a quadratic in ``t``. ``branch="upper"`` (default)
        takes the root with the larger z, the working mode of the paper (the other lies below the
        rails, z ~ -0.17 m for Table 1). Raises UnreachableError where the spheres do not meet, or
        where the upper root has a rod in the other assembly mode (so that ``ik(fk(q)) == q``).
        """
        q = as_batch(joints, 3, "joints")
        c = self.delta * self.e + q[..., :, None] * self.m  # (..., 3, 3) sphere centres
        a = c[..., 1:, :] - c[..., :1, :]  # (..., 2, 3)
        rhs = 0.5 * (
            np.einsum("...ij,...ij->...i", c[..., 1:, :], c[..., 1:, :])
            - np.einsum("...j,...j->...", c[..., 0, :], c[..., 0, :])[..., None]
        )
        u = np.cross(a[..., 0, :], a[..., 1, :])
        uu = np.einsum("...j,...j->...", u, u)
        if np.any(uu < 1e-24):
            raise SingularityError("sphere centres C_i are collinear: closed-form FK is degenerate")
        # minimum-norm point of the line: p0 = A^T (A A^T)^-1 rhs
        p0 = np.einsum(
            "...ij,...i->...j",
            a,
            np.linalg.solve(a @ np.swapaxes(a, -1, -2), rhs[..., None])[..., 0],
        )
        s = p0 - c[..., 0, :]
        half_b = np.einsum("...j,...j->...", u, s)
        disc = half_b**2 - uu * (np.einsum("...j,...j->...", s, s) - self.L**2)
        raise_first(
            disc < 0,
            q.shape[:-1],
            lambda idx: (
                f"strokes (l1, l2, l3) = {tuple(np.round(q[idx], 6).tolist())} m cannot be "
                f"assembled: the three spheres of radius L = {self.L} m do not meet (discriminant "
                f"{disc[idx]:.3g} < 0)"
            ),
        )
        root = np.sqrt(disc)
        t1, t2 = (-half_b + root) / uu, (-half_b - root) / uu
        p1 = p0 + t1[..., None] * u
        p2 = p0 + t2[..., None] * u
        upper_first = p1[..., 2] >= p2[..., 2]
        pick_first = upper_first if branch == "upper" else ~upper_first
        pose = np.where(pick_first[..., None], p1, p2)
        self._check_edge(pose, q)
        if branch == "upper":
            # working mode: every rod leans along its rail (n_i . m_i > 0), i.e. the strokes are
            # the minus root of eq (5); otherwise ik(fk(q)) != q and the pose is another assembly
            nm = np.einsum("...ij,ij->...i", self._rod(pose, q), self.m)

            def other_mode(idx: tuple[int, ...]) -> str:
                limb = int(np.argmax(nm[idx] <= 0)) + 1
                return (
                    f"strokes (l1, l2, l3) = {tuple(np.round(q[idx], 6).tolist())} m assemble only "
                    f"with limb {limb} in the other mode (n_{limb} . m_{limb} = "
                    f"{nm[idx][limb - 1] / self.L:.3g} <= 0, the plus root of eq. 5)"
                )

            raise_first(np.any(nm <= 0, axis=-1), q.shape[:-1], other_mode)
        return pose

    # ------------------------------------------------------------------ dynamics (issue 27)
    def mass_model(self) -> MassModel:
        """Zhao 2017 §2.4's masses (:data:`ZHAO2017_MASSES`, before design) with
        ``g = (0, 0, -9.81)``: platform, sliders and side rods (centroid at mid-length, axisymmetric
        ``I_dio``). Not in the paper, and not entering the dynamics because those bodies only
        translate: the platform's inertia (a thin disc of radius ``r_a``) and the sliders'
        (``1e-3 kg m^2`` about each axis)."""
        from parakin.dynamics.model import MassModel, RigidBody

        z = ZHAO2017_MASSES
        return MassModel(
            {
                "platform": RigidBody.disc(z["m_platform"], self.r_a),
                "slider": RigidBody(z["m_slider"], (1e-3, 1e-3, 1e-3)),
                "rod": RigidBody(z["m_rod"], z["I_rod"], (0.0, 0.0, 0.5 * self.L)),
            },
            note="Zhao 2017 section 2.4",
        )

    def bodies(self, pose: Jet) -> Bodies:
        """The platform (translating: a free body the parallelograms keep level), the three
        sliders on their rails (the actuated slide joints, strokes by eq 5) and the two side rods
        of each parallelogram, from ``c_i +- (d/2) t_i`` on the slider to ``d_i +- (d/2) t_i`` on
        the platform (``t_i`` the horizontal edge direction): S-S links."""
        import parakin.dynamics.jet as dj
        from parakin.dynamics.model import Bodies, BodyGroup, free_platform, rods

        w = pose[..., None, :] - self.delta * self.e
        b = dj.dot(w, self.m)
        strokes = b - dj.sqrt(self.L**2 - (dj.dot(w, w) - b * b))  # eq 5, working branch
        sliders = strokes[..., :, None] * self.m + self.r_b * self.e  # c_i = u_i + l_i m_i
        tops = pose[..., None, :] + self.a * self.e  # d_i
        edge = 0.5 * self.d * np.cross(_E_Z, self.e)  # (d/2) t_i
        batch = pose.shape[:-1]
        bottom = dj.stack([sliders - edge, sliders + edge], axis=-2).reshape((*batch, 6, 3))
        top = dj.stack([tops - edge, tops + edge], axis=-2).reshape((*batch, 6, 3))
        names = ("slider1", "slider2", "slider3")
        labels = tuple(f"{i}{s}" for i in (1, 2, 3) for s in "ab")
        rod_group, closure = rods(
            "rod", bottom, top, [n for n in names for _ in "ab"], ("platform",) * 6, labels
        )
        eye = lambda k: dj.constant_like(np.broadcast_to(np.eye(3), (*batch, k, 3, 3)), pose)  # noqa: E731
        groups = (
            free_platform(pose[..., None, :], eye(1)),
            BodyGroup(
                "slider",
                names,
                ("world",) * 3,
                "slide",
                sliders,
                rotation=eye(3),
                joint_axis=np.broadcast_to(self.m, (*batch, 3, 3)),
            ),
            rod_group,
        )
        return Bodies(groups, strokes, names, (closure,))


#: Zhao 2017 §2.4's masses (kg) and side-rod inertia ``I_dio`` (kg m^2, about the rod's centroid,
#: z along the rod), before design: the defaults of :meth:`P3P4S.mass_model` and of
#: :class:`parakin.mechanisms.p3p4s_dynamics.InertialParams` (tests compare them with
#: data/reference/zhao2017_3p4s.csv)
ZHAO2017_MASSES: dict = {
    "m_platform": 4.16,
    "m_slider": 2.57,
    "m_rod": 1.59,
    "I_rod": (0.0223, 0.0223, 1.276e-4),
}
