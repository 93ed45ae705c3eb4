"""Inertia as data, and the moving bodies of a mechanism as functions of its pose.

A mechanism that has dynamics declares two things beside its kinematics (both optional methods of
:class:`parakin.mechanisms.base.Mechanism`):

* :meth:`mass_model` -> :class:`MassModel`: the mass, centre of mass and inertia of each kind of
  body (``"platform"``, ``"cylinder"``, ``"piston"``, ...) and gravity, with documented defaults;
* :meth:`bodies` (pose jet) -> :class:`Bodies`: where every moving body is, as a function of the
  pose written with the operations of :mod:`parakin.dynamics.jet` (so velocities and accelerations
  follow exactly), how the bodies hang together (each body's parent and joint, and the points
  where loops close), and which joint each actuator drives.

Body frames: each body's frame has its origin at the joint that carries it (a leg cylinder at its
base joint, a piston at its platform joint, a rod at its lower ball joint, the platform at the
pose's reference point); the mass model gives the centre of mass and the inertia in that frame.
A body that turns freely about its own axis between two ball joints (the cylinder and piston of an
S-P-S leg, an S-S rod) is declared by its unit axis alone (its frame's z axis): it is taken not to
spin about that axis, which is exact when its inertia is axisymmetric about the axis and its centre
of mass lies on it (the spin is then an idle freedom that no force excites), and :func:`axis_motion`
enforces that. Every other body is declared by its rotation.

Builders for the common legs: :func:`strut` (a prismatic S-P-S leg: cylinder and piston),
:func:`rods` (rigid S-S links).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

import parakin.dynamics.jet as jet
from parakin.dynamics.jet import Array, Jet, Spin

__all__ = [
    "RigidBody",
    "MassModel",
    "BodyGroup",
    "Closure",
    "Bodies",
    "BodyMotion",
    "JOINTS",
    "strut",
    "rods",
    "axis_motion",
    "rigid_motion",
    "frame_with_z",
]

#: joint kinds between a body and its parent (MJCF / pinocchio names: free, ball, slide, hinge)
JOINTS = ("free", "ball", "slide", "hinge")

#: relative tolerance of the symmetry and triangle-inequality checks of an inertia matrix
_INERTIA_RTOL = 1e-12


# ---------------------------------------------------------------------------------------- inertia
@dataclass(frozen=True)
class RigidBody:
    """Mass (kg), centre of mass ``com`` (m, in the body frame) and inertia (kg m^2, about the
    centre of mass, body axes) of one rigid body.

    ``inertia`` is a 3x3 matrix or its three diagonal entries. Validated: finite positive mass;
    symmetric, positive-definite inertia whose principal moments satisfy the triangle inequality
    ``I_1 + I_2 >= I_3`` (every real mass distribution does).
    """

    mass: float
    inertia: Sequence = (0.0, 0.0, 0.0)
    com: Sequence = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        m = float(self.mass)
        if not (np.isfinite(m) and m > 0):
            raise ValueError(f"mass = {self.mass!r} kg must be finite and > 0")
        com = np.asarray(self.com, dtype=float)
        if com.shape != (3,) or not np.all(np.isfinite(com)):
            raise ValueError(f"com = {self.com!r} must be a finite 3-vector (m)")
        inertia = _inertia_matrix(self.inertia)
        object.__setattr__(self, "mass", m)
        object.__setattr__(self, "com", tuple(float(c) for c in com))
        object.__setattr__(self, "inertia", tuple(tuple(float(v) for v in row) for row in inertia))

    @property
    def inertia_matrix(self) -> Array:
        """The inertia about the centre of mass in body axes (3, 3)."""
        return np.array(self.inertia)

    @property
    def is_axisymmetric(self) -> bool:
        """True when the inertia is symmetric about the body's z axis and the centre of mass on it."""
        i = self.inertia_matrix
        scale = np.trace(i)
        off = max(abs(i[0, 1]), abs(i[0, 2]), abs(i[1, 2]))
        return (
            abs(i[0, 0] - i[1, 1]) <= _INERTIA_RTOL * scale
            and off <= _INERTIA_RTOL * scale
            and self.com[0] == 0.0
            and self.com[1] == 0.0
        )

    @classmethod
    def rod(cls, mass: float, length: float, radius: float, com: float) -> RigidBody:
        """A solid cylinder of ``length`` and ``radius`` along z, its centre of mass at ``z = com``:
        ``I_xx = I_yy = m (3 r^2 + l^2) / 12``, ``I_zz = m r^2 / 2``."""
        it = mass * (3 * radius**2 + length**2) / 12
        return cls(mass, (it, it, 0.5 * mass * radius**2), (0.0, 0.0, com))

    @classmethod
    def disc(cls, mass: float, radius: float, com: Sequence = (0.0, 0.0, 0.0)) -> RigidBody:
        """A thin disc of ``radius`` in the body's xy plane: ``I_xx = I_yy = m r^2 / 4``,
        ``I_zz = m r^2 / 2``."""
        return cls(
            mass, (0.25 * mass * radius**2, 0.25 * mass * radius**2, 0.5 * mass * radius**2), com
        )


def _inertia_matrix(value) -> Array:
    i = np.asarray(value, dtype=float)
    if i.shape == (3,):
        i = np.diag(i)
    if i.shape != (3, 3) or not np.all(np.isfinite(i)):
        raise ValueError(
            f"inertia = {value!r} must be three finite moments or a 3x3 matrix (kg m^2)"
        )
    scale = max(np.trace(i), 1e-300)
    if np.max(np.abs(i - i.T)) > _INERTIA_RTOL * scale:
        raise ValueError(f"inertia = {i.tolist()} is not symmetric")
    moments = np.linalg.eigvalsh(i)
    if moments[0] <= 0:
        raise ValueError(
            f"inertia has a principal moment {moments[0]:.6g} kg m^2 <= 0: it must be positive definite"
        )
    if moments[0] + moments[1] < moments[2] * (1 - _INERTIA_RTOL):
        raise ValueError(
            f"inertia's principal moments {moments.round(12).tolist()} kg m^2 break the triangle "
            f"inequality I1 + I2 >= I3: no mass distribution has them"
        )
    return i


@dataclass(frozen=True)
class MassModel:
    """The rigid body of each kind of moving body of a mechanism, and gravity (m/s^2).

    ``bodies`` maps a kind (``"platform"``, ``"cylinder"``, ...) to its :class:`RigidBody`; every
    body of that kind in :meth:`Mechanism.bodies` has it.
    """

    bodies: Mapping[str, RigidBody]
    gravity: Sequence = (0.0, 0.0, -9.81)
    note: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        bodies = dict(self.bodies)
        for kind, body in bodies.items():
            if not isinstance(body, RigidBody):
                raise TypeError(
                    f"mass model body {kind!r} must be a RigidBody, got {type(body).__name__}"
                )
        g = np.asarray(self.gravity, dtype=float)
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise ValueError(f"gravity = {self.gravity!r} must be a finite 3-vector (m/s^2)")
        object.__setattr__(self, "bodies", bodies)
        object.__setattr__(self, "gravity", tuple(float(v) for v in g))

    def body(self, kind: str) -> RigidBody:
        """The rigid body of ``kind``, or a one-line KeyError naming the kinds declared."""
        try:
            return self.bodies[kind]
        except KeyError:
            raise KeyError(
                f"the mass model has no body {kind!r}; it declares {', '.join(self.bodies)}"
            ) from None

    def replace(self, gravity: Sequence | None = None, **bodies: RigidBody) -> MassModel:
        """A copy with some bodies (by kind) and/or gravity changed."""
        unknown = set(bodies) - set(self.bodies)
        if unknown:
            raise KeyError(
                f"unknown body kind(s) {sorted(unknown)}; known: {', '.join(self.bodies)}"
            )
        return MassModel(
            {**self.bodies, **bodies}, self.gravity if gravity is None else gravity, self.note
        )


# ---------------------------------------------------------------------------------------- bodies
@dataclass(frozen=True, eq=False)
class BodyGroup:
    """Bodies of one kind that move alike (e.g. the six cylinders of a hexapod), batched.

    ``origin`` (..., c, 3): each frame's origin, at its joint; exactly one of ``axis``
    (..., c, 3: unit z axis of a body that does not spin about it) and ``rotation``
    (..., c, 3, 3) is given. ``names``, ``parents`` (a body name or ``"world"``) and ``joint``
    (one of :data:`JOINTS`, to the parent) describe the tree for the physics engines;
    ``joint_axis`` (..., c, 3) is the world axis of a slide or hinge joint.
    """

    kind: str
    names: tuple[str, ...]
    parents: tuple[str, ...]
    joint: str
    origin: Jet
    axis: Jet | None = None
    rotation: Jet | None = None
    joint_axis: Array | None = None

    def __post_init__(self) -> None:
        if self.joint not in JOINTS:
            raise ValueError(f"joint = {self.joint!r} must be one of {JOINTS}")
        if (self.axis is None) == (self.rotation is None):
            raise ValueError(f"body group {self.kind!r}: give exactly one of axis and rotation")
        if len(self.names) != len(self.parents) or len(self.names) != self.origin.shape[-2]:
            raise ValueError(f"body group {self.kind!r}: one name and one parent per body")
        if self.joint in ("slide", "hinge") and self.joint_axis is None:
            raise ValueError(f"body group {self.kind!r}: a {self.joint} joint needs joint_axis")


@dataclass(frozen=True, eq=False)
class Closure:
    """Loop closures: point ``points[..., k, :]`` (world) of body ``first[k]`` coincides with the
    same point of body ``second[k]`` (a ball joint that closes a loop)."""

    first: tuple[str, ...]
    second: tuple[str, ...]
    points: Array


@dataclass(frozen=True, eq=False)
class Bodies:
    """Every moving body of a mechanism at a batch of poses (what :meth:`Mechanism.bodies` returns).

    ``joints``: the mechanism's joint coordinates as a jet (..., m) (their Jacobian is the velocity
    Jacobian ``J``, ``qdot = J xdot``); ``actuators[i]``: the body whose joint (to its parent) joint
    ``i`` drives, a slide joint moving by ``dq_i`` when joint ``i`` does; ``platform``: the body
    whose motion a trajectory prescribes (and an external wrench loads).
    """

    groups: tuple[BodyGroup, ...]
    joints: Jet
    actuators: tuple[str, ...]
    closures: tuple[Closure, ...] = ()
    platform: str = "platform"

    def group(self, kind: str) -> BodyGroup:
        for g in self.groups:
            if g.kind == kind:
                return g
        raise KeyError(f"no body group {kind!r}; groups: {', '.join(g.kind for g in self.groups)}")

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(n for g in self.groups for n in g.names)


@dataclass(frozen=True, eq=False)
class BodyMotion:
    """The motion of one group's centres of mass: ``centre`` jet (..., c, 3) and the angular
    velocity ``spin`` of the body frames, which are either rotations ``frame`` (..., c, 3, 3) or,
    for spin-free axisymmetric bodies, given by their unit ``axis`` (..., c, 3)."""

    centre: Jet
    spin: Spin
    frame: Array | None = None
    axis: Array | None = None

    @property
    def rotation(self) -> Array:
        """The body frames (..., c, 3, 3) (an arbitrary turn about the axis of spin-free bodies)."""
        return self.frame if self.frame is not None else frame_with_z(self.axis)

    def inertia_times(self, body: RigidBody, w: Array) -> Array:
        """``I w`` with the inertia in world axes, for vectors ``w`` (..., c, 3) (a leading axis
        of directions allowed): ``I_t w + (I_a - I_t)(n . w) n`` for an axisymmetric body on
        ``n``, ``R I R^T w`` otherwise."""
        i = body.inertia_matrix
        if self.axis is not None:
            n = self.axis
            return i[0, 0] * w + (i[2, 2] - i[0, 0]) * jet.vdot(n, w)[..., None] * n
        r = self.frame
        local = jet.vmatvec(np.swapaxes(r, -1, -2), w)
        return jet.vmatvec(r, jet.vmatvec(i, local))


def free_platform(origin: Jet, rotation: Jet) -> BodyGroup:
    """The moving platform: one free body hung from the world, its frame at ``origin``
    (..., 1, 3) with ``rotation`` (..., 1, 3, 3) (a group of one)."""
    return BodyGroup("platform", ("platform",), ("world",), "free", origin, rotation=rotation)


def frame_with_z(axis: Array) -> Array:
    """A rotation (..., 3, 3) whose third column is the unit ``axis`` (..., 3) (its turn about the
    axis is arbitrary: for bodies whose spin is idle)."""
    n = np.asarray(axis, dtype=float)
    helper = np.where(np.abs(n[..., :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    x = helper - np.sum(helper * n, axis=-1, keepdims=True) * n
    x = x / np.linalg.norm(x, axis=-1, keepdims=True)
    return np.stack([x, np.cross(n, x), n], axis=-1)


def axis_motion(group: BodyGroup, body: RigidBody) -> BodyMotion:
    """Motion of spin-free bodies on their axis: centre ``origin + com_z n``, ``omega = n x ndot``."""
    if not body.is_axisymmetric:
        raise ValueError(
            f"the {group.kind!r} bodies turn freely about their own axis: their inertia must be "
            f"axisymmetric about the body z axis and the centre of mass on it (com = {body.com}, "
            f"inertia = {body.inertia})"
        )
    n = group.axis
    return BodyMotion(group.origin + n * body.com[2], jet.spin_of_axis(n), axis=n.value)


def rigid_motion(group: BodyGroup, body: RigidBody) -> BodyMotion:
    """Motion of bodies with a declared rotation: centre ``origin + R com``."""
    r = group.rotation
    return BodyMotion(
        group.origin + jet.matvec(r, np.asarray(body.com)), jet.spin_of_rotation(r), frame=r.value
    )


def motion(group: BodyGroup, body: RigidBody) -> BodyMotion:
    """:func:`axis_motion` or :func:`rigid_motion`, whichever the group declares."""
    return axis_motion(group, body) if group.axis is not None else rigid_motion(group, body)


# ---------------------------------------------------------------------------------------- builders
def strut(
    base: Jet | ArrayLike,
    top: Jet,
    top_bodies: Sequence[str],
    *,
    kinds: tuple[str, str] = ("cylinder", "piston"),
    base_bodies: Sequence[str] | None = None,
    labels: Sequence[str] | None = None,
) -> tuple[tuple[BodyGroup, BodyGroup], Closure, Jet]:
    """Prismatic S-P-S legs from ``base`` (..., c, 3) to ``top`` (..., c, 3): a cylinder on a ball
    joint at the base end and a piston sliding in it, whose top end is ball-jointed to
    ``top_bodies`` (a loop closure). Returns the two groups, the closure and the leg lengths
    (..., c) as a jet (the piston's slide joint moves by the change of length)."""
    top = top if isinstance(top, Jet) else jet.constant_like(top, base)
    if not isinstance(base, Jet):
        base = jet.constant_like(np.broadcast_to(base, top.shape), top)
    n, length = jet.normalize(top - base)
    count = top.shape[-2]
    labels = [str(k + 1) for k in range(count)] if labels is None else list(labels)
    cyl = tuple(f"{kinds[0]}{k}" for k in labels)
    pis = tuple(f"{kinds[1]}{k}" for k in labels)
    parents = tuple(base_bodies) if base_bodies is not None else ("world",) * count
    groups = (
        BodyGroup(kinds[0], cyl, parents, "ball", base, axis=n),
        BodyGroup(kinds[1], pis, cyl, "slide", top, axis=n, joint_axis=n.value),
    )
    return groups, Closure(pis, tuple(top_bodies), top.value), length


def rods(
    kind: str,
    bottom: Jet,
    top: Jet,
    bottom_bodies: Sequence[str],
    top_bodies: Sequence[str],
    labels: Sequence[str],
) -> tuple[BodyGroup, Closure]:
    """Rigid S-S links from ``bottom`` (..., c, 3) (a ball joint on ``bottom_bodies``) to ``top``
    (ball-jointed to ``top_bodies``, closing a loop)."""
    n, _ = jet.normalize(top - bottom)
    names = tuple(f"{kind}{k}" for k in labels)
    return BodyGroup(kind, names, tuple(bottom_bodies), "ball", bottom, axis=n), Closure(
        names, tuple(top_bodies), top.value
    )


def hexapod(origin: Jet, rotation: Jet, base: ArrayLike, top_local: ArrayLike) -> Bodies:
    """The bodies of a Gough-Stewart platform: the platform (a free body with frame origin
    ``origin`` (..., 3) and rotation ``rotation`` (..., 3, 3)) and one S-P-S leg (cylinder and
    piston, :func:`strut`) from each fixed ``base`` point (k, 3) to each platform point
    ``top_local`` (k, 3, in the platform frame); the joints are the leg lengths."""
    top = origin[..., None, :] + jet.matvec(
        rotation[..., None, :, :], np.asarray(top_local, dtype=float)
    )
    count = top.shape[-2]
    (cylinders, pistons), closure, lengths = strut(base, top, ("platform",) * count)
    platform = free_platform(origin[..., None, :], rotation[..., None, :, :])
    return Bodies((platform, cylinders, pistons), lengths, pistons.names, (closure,))


def hexapod_masses(
    top_local: ArrayLike,
    leg_length: float,
    platform_mass: float,
    cylinder_mass: float,
    piston_mass: float,
    gravity: Sequence = (0.0, 0.0, -9.81),
    note: str = "",
) -> MassModel:
    """A mass model for :func:`hexapod` scaled to the geometry: the platform a thin disc of radius
    the RMS distance of its anchors from their centroid, centred there; cylinder and piston solid
    rods of length ``leg_length / 2`` and radius ``leg_length / 20``, each with its centre of mass a
    quarter of ``leg_length`` from its joint (the piston's towards the base: ``z = -leg_length / 4``)."""
    p = np.asarray(top_local, dtype=float)
    centroid = p.mean(axis=0)
    radius = float(np.sqrt(np.mean(np.sum((p - centroid) ** 2, axis=-1))))
    half, r = 0.5 * leg_length, 0.05 * leg_length
    return MassModel(
        {
            "platform": RigidBody.disc(platform_mass, radius, centroid),
            "cylinder": RigidBody.rod(cylinder_mass, half, r, 0.25 * leg_length),
            "piston": RigidBody.rod(piston_mass, half, r, -0.25 * leg_length),
        },
        gravity,
        note,
    )
