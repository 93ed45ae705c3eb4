"""The planar 3-RPR parallel mechanism: a platform held in the plane by three legs, each a revolute
joint on the base, an actuated prismatic joint and a revolute joint on the platform.

Beyond the four papers: the textbook planar parallel mechanism (Gosselin & Angeles 1988; Merlet,
*Parallel Robots*, 2006, ch. 4), added as the worked example of docs/kernels.md. Its geometry is
declared once here, its equations once in :mod:`parakin.kernels.rpr3`; everything else (the
numpy methods, every FK solver, compiled and torch, the CLI, the tests, the solver atlas) follows;
its dynamics (:meth:`RPR3.mass_model`, :meth:`RPR3.bodies`: the worked example of docs/dynamics.md
§7) gives it inverse and forward dynamics and the MuJoCo and pinocchio checks.

Default geometry (ours, symmetric): base pivots on a circle of radius 0.5 m at 90, 210 and 330 deg,
platform pivots on a circle of radius 0.2 m turned 60 deg further, so that at home (the platform
centred, ``phi = 0``) no leg points at the centre and the three leg lines do not meet: home is
well away from a singularity. Forward kinematics is numeric (up to six assemblies share one set of
leg lengths; the working one is home's side of the singularity locus, see ``on_assembly``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from types import ModuleType
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

import parakin.dynamics.jet as dj
from parakin.dynamics.jet import Jet
from parakin.dynamics.model import (
    Bodies,
    BodyGroup,
    Closure,
    MassModel,
    free_platform,
    hexapod_masses,
)
from parakin.kernels import Kernel, evaluate
from parakin.kernels import rpr3 as kernels
from parakin.mechanisms.base import Array, Mechanism, Skeleton, as_batch
from parakin.mechanisms.described import Described, Leg

__all__ = ["RPR3"]

#: the plane's normal: the world z axis, the axis of every revolute joint
_NORMAL = np.array([0.0, 0.0, 1.0])


def _circle(radius: float, degrees: ArrayLike) -> tuple[tuple[float, float], ...]:
    t = np.deg2rad(np.asarray(degrees, dtype=float))
    return tuple(zip((radius * np.cos(t)).tolist(), (radius * np.sin(t)).tolist()))


def _points(values: Any, what: str) -> tuple[tuple[float, float], ...]:
    a = np.asarray(values, dtype=float)
    if a.shape != (3, 2) or not np.all(np.isfinite(a)):
        raise ValueError(f"{what} must be 3 finite points (x, y) in metres, got {values!r:.80}")
    return tuple(map(tuple, a.tolist()))


@dataclass(frozen=True)
class RPR3(Mechanism):
    """Planar 3-RPR: ``base`` pivots ``B_i`` (3, 2) in the fixed frame and ``platform`` pivots
    ``a_i`` (3, 2) in the platform frame, metres. Pose ``(x, y, phi)`` (m, m, rad), joints the leg
    lengths ``rho_1..3`` (m)."""

    base: Any = _circle(0.5, [90.0, 210.0, 330.0])
    platform: Any = _circle(0.2, [150.0, 270.0, 30.0])

    name: ClassVar[str] = "rpr3"
    pose_names: ClassVar[tuple[str, ...]] = ("x", "y", "phi")
    joint_names: ClassVar[tuple[str, ...]] = ("rho1", "rho2", "rho3")
    pose_units: ClassVar[tuple[str, ...]] = ("m", "m", "rad")
    joint_units: ClassVar[tuple[str, ...]] = ("m", "m", "m")
    paper_pose_units: ClassVar[tuple[str, ...]] = ("mm", "mm", "deg")  # no paper: the usual units
    paper_joint_units: ClassVar[tuple[str, ...]] = ("mm", "mm", "mm")
    kernels: ClassVar[ModuleType] = kernels

    def __post_init__(self) -> None:
        object.__setattr__(self, "base", _points(self.base, "base"))
        object.__setattr__(self, "platform", _points(self.platform, "platform"))
        home_det = self._home_det()
        if not abs(home_det) > 1e-9:
            raise ValueError(
                f"the home pose (0, 0, 0) of this geometry is singular (det(d rho / d pose) = "
                f"{home_det:.3g}): the leg lines meet in one point or are parallel"
            )

    def _home_det(self) -> float:
        """``det(d rho / d pose)`` at home, by the kernel (its sign is not a parameter yet)."""
        p = kernels.PARAMS.pack(base=self.base, platform=self.platform, home_sign=1.0)
        jac = evaluate(Kernel(kernels, p, 3, 3), "jacobian", self.home(), np.zeros(3))
        return float(np.linalg.det(jac))

    def kernel_params(self) -> Array:
        """Base pivots, platform pivots, and the sign of the home pose's Jacobian determinant, by
        the names of :data:`parakin.kernels.rpr3.PARAMS`."""
        sign = np.sign(self._home_det())
        return kernels.PARAMS.pack(base=self.base, platform=self.platform, home_sign=sign)

    def home(self) -> Array:
        """The platform centred over the base, not turned."""
        return np.zeros(3)

    @cached_property
    def as_described(self) -> Described:
        """The same mechanism as a description (three length legs on a planar platform,
        :mod:`parakin.mechanisms.described`): its exact assemblies (the planar polynomial) decide
        :meth:`check_joints`."""
        legs = tuple(
            Leg("length", (*b, 0.0), (*a, 0.0), name=name)
            for b, a, name in zip(self.base, self.platform, self.joint_names)
        )
        lo, hi = self.pose_bounds()
        return Described("rpr3", "planar", legs, tuple(self.home()), (tuple(lo), tuple(hi)))

    def real_solutions(self, joints: ArrayLike) -> tuple[Array, Any]:
        """Every real assembly (up to six) of leg lengths (N, 3), exactly (the planar polynomial of
        :attr:`as_described`), and per input whether that is guaranteed complete."""
        return self.as_described.real_solutions(joints)

    def assembly_label(self, pose: ArrayLike, joints: ArrayLike) -> str:
        """Home's side of the singularity locus (the working assembly mode) or the other."""
        return self.as_described.assembly_label(pose, joints).split(", ")[0]

    def check_joints(self, joints: ArrayLike) -> None:
        """Raise UnreachableError where the leg lengths cannot be assembled on home's side of the
        singularity locus (a length not > 0, two legs that cannot hold their pivots at the
        platform's distance, no real assembly, or none in the working mode): what no solver could
        then find. Exact: every assembly is a root of the planar polynomial
        (:meth:`Described.check_joints`)."""
        self.as_described.check_joints(joints)

    def pose_bounds(self) -> tuple[Array, Array]:
        """``|x|, |y| <= 0.1`` m, ``|phi| <= 20`` deg around home: the default geometry's working
        region, on home's side of the singularity locus."""
        return np.array([-0.1, -0.1, -np.deg2rad(20.0)]), np.array([0.1, 0.1, np.deg2rad(20.0)])

    def platform_world(self, pose: ArrayLike) -> Array:
        """The platform pivots in the fixed frame, shape (..., 3, 2)."""
        x = as_batch(pose, 3, "pose")
        c, s = np.cos(x[..., 2])[..., None], np.sin(x[..., 2])[..., None]
        a = np.asarray(self.platform)
        return np.stack(
            [
                x[..., None, 0] + c * a[:, 0] - s * a[:, 1],
                x[..., None, 1] + s * a[:, 0] + c * a[:, 1],
            ],
            axis=-1,
        )

    def skeleton(self, pose: ArrayLike) -> Skeleton:
        """The base and platform triangles and the three legs, in the plane ``z = 0``."""
        x = as_batch(pose, 3, "pose")
        if x.ndim != 1:
            raise ValueError(f"skeleton() draws one pose, got a batch of shape {x.shape[:-1]}")
        self.ik(x)  # an unreachable pose is an error, not a drawing
        flat = np.zeros((3, 1))
        b = np.hstack([np.asarray(self.base), flat])
        p = np.hstack([self.platform_world(x), flat])
        points = {f"B_{i + 1}": b[i] for i in range(3)} | {f"P_{i + 1}": p[i] for i in range(3)}
        c, s = np.cos(x[2]), np.sin(x[2])
        turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        return Skeleton(
            points=points,
            segments=[("actuator", np.stack([b[i], p[i]])) for i in range(3)],
            polygons=[("base", b), ("platform", p)],
            frames={"O": (np.zeros(3), np.eye(3)), "P": (np.array([x[0], x[1], 0.0]), turn)},
        )

    # ------------------------------------------------------------------ dynamics (issue 27)
    def _in_space(self, points: Any) -> Array:
        """Planar points (3, 2) as points (3, 3) of the plane ``z = 0``."""
        return np.hstack([np.asarray(points), np.zeros((3, 1))])

    def mass_model(self) -> MassModel:
        """Illustrative defaults (no paper gives masses): a 1 kg platform, a thin disc in the plane
        of radius the RMS distance of its pivots from their centroid, centred there; each leg a
        0.4 kg cylinder turning about its base pivot and a 0.2 kg piston sliding in it, solid rods
        of half the mean leg length at :meth:`home`, centres a quarter of it from their joints
        (:func:`parakin.dynamics.model.hexapod_masses`).

        Gravity ``(0, -9.81, 0)`` m/s^2 lies *in* the plane of motion: the mechanism stands in a
        vertical plane, ``y`` up, so gravity does work on every body and enters the actuator
        forces. Lying flat (gravity along ``-z``, normal to the plane) it would do no work on a
        planar motion: the joints' reactions carry it, out of the plane, and the actuator forces
        are those of zero gravity (``mass_model().replace(gravity=(0, 0, -9.81))`` shows it)."""
        leg = float(np.mean(self.ik(self.home())))
        return hexapod_masses(
            self._in_space(self.platform),
            leg,
            platform_mass=1.0,
            cylinder_mass=0.4,
            piston_mass=0.2,
            gravity=(0.0, -9.81, 0.0),
            note="rpr3 illustrative defaults, standing in a vertical plane",
        )

    def bodies(self, pose: Jet) -> Bodies:
        """The platform (origin ``(x, y, 0)``, turned by ``phi`` about the plane's normal ``z``)
        and each leg's two bodies in the plane ``z = 0``: the cylinder, hinged to the base at
        ``B_i`` about ``z``, and the piston, sliding in it along the leg (the actuated joint,
        ``rho_i``) and hinged to the platform at ``P_i`` (a loop closure). Both leg bodies turn with
        the leg, frame ``[z, n_i x z, n_i]`` (``n_i`` the unit leg vector: body z along the leg,
        body x the hinge axis). The engines' models are planar too: hinges about ``z``, slides in
        the plane, and three closures at non-collinear points at ``z = 0`` hold the free platform
        in the plane."""
        x, y, phi = pose[..., 0], pose[..., 1], pose[..., 2]
        batch = x.shape
        origin = dj.stack([x, y, 0.0 * x])[..., None, :]  # one platform body
        turn = dj.rotations([phi], "z")[..., None, :, :]
        tops = origin + dj.matvec(turn, self._in_space(self.platform))
        n, lengths = dj.normalize(tops - self._in_space(self.base))
        frame = dj.stack([_NORMAL, dj.cross(n, _NORMAL), n], axis=-1)
        normal = np.broadcast_to(_NORMAL, (*batch, 3, 3))
        cylinders = tuple(f"cylinder{k}" for k in (1, 2, 3))
        pistons = tuple(f"piston{k}" for k in (1, 2, 3))
        base = dj.constant_like(np.broadcast_to(self._in_space(self.base), (*batch, 3, 3)), pose)
        groups = (
            free_platform(origin, turn),
            BodyGroup(
                "cylinder",
                cylinders,
                ("world",) * 3,
                "hinge",
                base,
                rotation=frame,
                joint_axis=normal,
            ),
            BodyGroup(
                "piston", pistons, cylinders, "slide", tops, rotation=frame, joint_axis=n.value
            ),
        )
        closure = Closure(pistons, ("platform",) * 3, tops.value)
        return Bodies(groups, lengths, pistons, (closure,))
