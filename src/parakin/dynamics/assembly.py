"""A mechanism's bodies at given poses, as plain values: what a physics-engine model is built from.

:func:`assemble` evaluates :meth:`Mechanism.bodies` and flattens its groups into one list of bodies
(name, kind, parent, joint to the parent, frame origin and rotation in the world, joint axis,
rigid body) and of loop closures, batched over poses. :func:`joint_coordinates` turns two such
assemblies (a reference and a current one) into each joint's coordinate in the convention of
MuJoCo and pinocchio: a free joint's position and orientation in the world, a ball joint's
rotation relative to its reference, a slide joint's travel and a hinge joint's angle.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

import parakin.dynamics.jet as jet
from parakin.dynamics.model import MassModel, RigidBody, motion
from parakin.geometry import quaternion
from parakin.mechanisms.base import Array, Mechanism, as_batch

__all__ = [
    "Assembly",
    "EngineModel",
    "assemble",
    "joint_coordinates",
    "quaternion",
    "rotation_angle",
]


@dataclass(frozen=True, eq=False)
class Assembly:
    """Every body and loop closure of a mechanism at a batch of poses (batch shape ``(...)``).

    Per body k (lists): ``names``, ``kinds``, ``parents`` (a name or ``"world"``), ``joints``,
    ``spin_free`` (declared by its axis: no spin about it), ``rigid`` (its :class:`RigidBody`); arrays ``origin`` (..., nb, 3), ``rotation``
    (..., nb, 3, 3), ``axis`` (..., nb, 3) (slide and hinge joints; NaN for the others),
    ``centre`` (..., nb, 3) its centre of mass. Closures: ``closures`` ``(first, second)`` names
    and ``points`` (..., nc, 3). ``actuators``: the actuated bodies in joint order; ``platform``.
    """

    names: tuple[str, ...]
    kinds: tuple[str, ...]
    parents: tuple[str, ...]
    joints: tuple[str, ...]
    spin_free: tuple[bool, ...]
    rigid: tuple[RigidBody, ...]
    origin: Array
    rotation: Array
    axis: Array
    centre: Array
    closures: tuple[tuple[str, str], ...]
    points: Array
    actuators: tuple[str, ...]
    platform: str
    gravity: tuple[float, float, float]

    def index(self, name: str) -> int:
        return self.names.index(name)

    def frame(self, name: str) -> tuple[Array, Array]:
        """Origin (..., 3) and rotation (..., 3, 3) of body ``name`` (the world: zero, identity)."""
        if name == "world":
            return np.zeros(self.origin.shape[:-2] + (3,)), np.broadcast_to(
                np.eye(3), self.origin.shape[:-2] + (3, 3)
            )
        k = self.index(name)
        return self.origin[..., k, :], self.rotation[..., k, :, :]

    def relative(self, name: str) -> tuple[Array, Array]:
        """Origin and rotation of body ``name`` in its parent's frame."""
        k = self.index(name)
        po, pr = self.frame(self.parents[k])
        prt = np.swapaxes(pr, -1, -2)
        return jet.vmatvec(prt, self.origin[..., k, :] - po), prt @ self.rotation[..., k, :, :]


@dataclass(frozen=True, eq=False)
class EngineModel:
    """What an independent engine's model of ``mech`` (MuJoCo, pinocchio) is built from: the mass
    model and the reference assembly (:func:`assemble`) it was written at; each engine's model
    adds its own objects and index maps."""

    mech: Mechanism
    mass: MassModel
    reference: Assembly = field(repr=False)


def assemble(mech: Mechanism, pose: ArrayLike, mass: MassModel | None = None) -> Assembly:
    """The mechanism's bodies at poses (..., n) (at rest: only positions are used)."""
    mass = mech.mass_model() if mass is None else mass
    x = as_batch(pose, mech.n_pose, "pose")
    bodies = mech.bodies(jet.variable(x, np.zeros_like(x)))
    names, kinds, parents, joints, rigid, spin_free = [], [], [], [], [], []
    origin, rotation, axis, centre = [], [], [], []
    for g in bodies.groups:
        body = mass.body(g.kind)
        m = motion(g, body)
        count = len(g.names)
        names += g.names
        parents += g.parents
        kinds += [g.kind] * count
        joints += [g.joint] * count
        spin_free += [g.axis is not None] * count
        rigid += [body] * count
        origin.append(g.origin.value)
        rotation.append(m.rotation)
        centre.append(m.centre.value)
        ax = np.full(g.origin.shape, np.nan) if g.joint_axis is None else g.joint_axis
        axis.append(np.broadcast_to(ax, g.origin.shape))
    first = tuple(n for c in bodies.closures for n in c.first)
    second = tuple(n for c in bodies.closures for n in c.second)
    points = np.concatenate(
        [np.broadcast_to(c.points, x.shape[:-1] + (len(c.first), 3)) for c in bodies.closures],
        axis=-2,
    )
    return Assembly(
        tuple(names),
        tuple(kinds),
        tuple(parents),
        tuple(joints),
        tuple(spin_free),
        tuple(rigid),
        np.concatenate(origin, axis=-2),
        np.concatenate(rotation, axis=-3),
        np.concatenate(axis, axis=-2),
        np.concatenate(centre, axis=-2),
        tuple(zip(first, second)),
        points,
        bodies.actuators,
        bodies.platform,
        mass.gravity,
    )


def rotation_angle(r: ArrayLike, axis: ArrayLike) -> Array:
    """Angle (rad) of rotations ``r`` (..., 3, 3) about the unit ``axis`` (..., 3)."""
    r = np.asarray(r, dtype=float)
    sin = 0.5 * jet.vdot(
        np.stack(
            [r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0], r[..., 1, 0] - r[..., 0, 1]],
            -1,
        ),
        np.asarray(axis, dtype=float),
    )
    cos = 0.5 * (r[..., 0, 0] + r[..., 1, 1] + r[..., 2, 2] - 1)
    return np.arctan2(sin, cos)


def joint_coordinates(reference: Assembly, current: Assembly, name: str) -> Array:
    """Coordinates (..., k) of body ``name``'s joint at ``current`` relative to ``reference``
    (one pose): free -> world position and quaternion (w, x, y, z) (7); ball -> quaternion of the
    rotation relative to the reference (4); slide -> travel along the axis (1); hinge -> angle (1)."""
    k = current.index(name)
    joint = current.joints[k]
    if joint == "free":
        return np.concatenate(
            [current.origin[..., k, :], quaternion(current.rotation[..., k, :, :])], -1
        )
    p0, r0 = reference.relative(name)
    p, r = current.relative(name)
    turn = np.swapaxes(r0, -1, -2) @ r
    if joint == "ball":
        return quaternion(turn)
    axis_local = jet.vmatvec(
        np.swapaxes(reference.rotation[..., k, :, :], -1, -2), reference.axis[..., k, :]
    )
    if joint == "slide":
        return jet.vdot(p - p0, jet.vmatvec(r0, axis_local))[..., None]
    return rotation_angle(turn, axis_local)[..., None]
