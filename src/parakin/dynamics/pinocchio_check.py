"""pinocchio's constrained dynamics as a second independent check, on a model built from the same
description as :mod:`parakin.dynamics.mujoco_check` (optional: ``pip install pin``, the extra
``parakin[pin]``).

:func:`build` makes a ``pinocchio.Model`` from :meth:`Mechanism.bodies` at a reference pose: one
joint per body (free flyer, spherical, unaligned prismatic or revolute), its placement in its
parent's frame, its inertia; one ``RigidConstraintModel`` (``CONTACT_3D``) per loop closure.

:func:`check` then runs pinocchio's constrained forward dynamics (``constraintDynamics``: the
KKT system of the tree's dynamics with the loop constraints, solved exactly) at each trajectory
sample, and answers two questions:

* driven by *our* actuator forces, does the platform get the acceleration the trajectory asks for?
  (``platform_error``: the largest relative difference of the platform's classical acceleration);
* which actuator forces does pinocchio itself need for that acceleration? The platform's
  acceleration is affine in the forces, ``a(u) = a(0) + D u``; ``m + 1`` forward solves give
  ``D`` and ``a(0)``, and ``u`` is the minimum-norm solution of ``D u = a_target - a(0)``.

The state (``q``, ``v``) is assembled as for MuJoCo: ``q`` from the bodies' placements, ``v`` the
minimum-norm joint velocity that gives the platform its twist and holds every loop
(pinocchio's frame Jacobians).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from parakin.dynamics.assembly import Assembly, EngineModel, assemble, joint_coordinates
from parakin.dynamics.inverse import State, state
from parakin.dynamics.model import MassModel
from parakin.errors import ShapeError
from parakin.mechanisms.base import Array, Mechanism, as_batch

__all__ = ["PinocchioModel", "PinocchioResult", "available", "import_pinocchio", "build", "check"]


def import_pinocchio():
    """The ``pinocchio`` module, or an ImportError saying how to get it."""
    try:
        import pinocchio
    except ImportError as exc:
        raise ImportError(
            "the pinocchio check needs the optional package 'pin' (pip install 'parakin[pin]' or pin==4.1.0)"
        ) from exc
    return pinocchio


def available() -> bool:
    """True when pinocchio imports."""
    try:
        import_pinocchio()
    except ImportError:
        return False
    return True


@dataclass(frozen=True, eq=False)
class PinocchioModel(EngineModel):
    """A pinocchio model of a mechanism, its loop constraints and index maps."""

    model: Any = field(repr=False)
    constraints: Any = field(repr=False)
    joint_ids: dict = field(repr=False)
    loop_frames: tuple = field(repr=False)  # (frame id or None for the world) pairs per closure
    platform_frame: int = 0

    def q(self, current: Assembly) -> Array:
        """Configurations (..., nq) of assemblies ``current`` (quaternions as x, y, z, w)."""
        out = np.zeros(current.origin.shape[:-2] + (self.model.nq,))
        for name in current.names:
            jid = self.joint_ids[name]
            adr = self.model.joints[jid].idx_q
            c = joint_coordinates(self.reference, current, name)
            if current.joints[current.index(name)] == "free":
                c = np.concatenate([c[..., :3], c[..., 4:], c[..., 3:4]], -1)
            elif current.joints[current.index(name)] == "ball":
                c = np.concatenate([c[..., 1:], c[..., :1]], -1)
            out[..., adr : adr + c.shape[-1]] = c
        return out

    def drives(self) -> Array:
        """Velocity index of each actuated joint, in joint order."""
        return np.array(
            [self.model.joints[self.joint_ids[n]].idx_v for n in self.reference.actuators]
        )


def _joint_model(pin, joint: str, axis_local: Array):
    if joint == "free":
        return pin.JointModelFreeFlyer()
    if joint == "ball":
        return pin.JointModelSpherical()
    if joint == "slide":
        return pin.JointModelPrismaticUnaligned(axis_local)
    return pin.JointModelRevoluteUnaligned(axis_local)


def _add_frame(pin, model, name: str, joint_id: int, point_local: Array) -> int:
    return model.addFrame(
        pin.Frame(name, joint_id, pin.SE3(np.eye(3), point_local), pin.FrameType.OP_FRAME)
    )


def _depth_first(ref: Assembly) -> list[int]:
    """Body indices in depth-first order: pinocchio's constrained algorithms (its sparse KKT
    factorisation) need every subtree's joints contiguous."""
    order: list[int] = []

    def visit(parent: str) -> None:
        for k, p in enumerate(ref.parents):
            if p == parent:
                order.append(k)
                visit(ref.names[k])

    visit("world")
    return order


def build(
    mech: Mechanism, reference_pose: ArrayLike | None = None, mass: MassModel | None = None
) -> PinocchioModel:
    """The pinocchio model of ``mech`` assembled at ``reference_pose`` (default :meth:`home`)."""
    pin = import_pinocchio()
    mass = mech.mass_model() if mass is None else mass
    ref = assemble(mech, mech.home() if reference_pose is None else reference_pose, mass)
    if ref.origin.ndim != 2:
        raise ShapeError(f"reference_pose must be one pose ({mech.n_pose},)")
    model = pin.Model()
    model.gravity = pin.Motion(np.concatenate([ref.gravity, np.zeros(3)]))
    ids: dict[str, int] = {"world": 0}
    for k in _depth_first(ref):
        name = ref.names[k]
        pos, rot = ref.relative(name)
        if ref.joints[k] == "free":  # a free flyer's configuration is its placement in the world
            pos, rot = np.zeros(3), np.eye(3)
        axis_local = (
            ref.rotation[k].T @ ref.axis[k] if ref.joints[k] in ("slide", "hinge") else None
        )
        jid = model.addJoint(
            ids[ref.parents[k]],
            _joint_model(pin, ref.joints[k], axis_local),
            pin.SE3(rot, pos),
            name,
        )
        body = ref.rigid[k]
        model.appendBodyToJoint(
            jid,
            pin.Inertia(body.mass, np.asarray(body.com), body.inertia_matrix),
            pin.SE3.Identity(),
        )
        ids[name] = jid
    constraints, frames = [], []
    for c, (first, second) in enumerate(ref.closures):
        local = []
        for owner in (first, second):
            o, r = ref.frame(owner)
            local.append((ids[owner], r.T @ (ref.points[c] - o)))
        (j1, p1), (j2, p2) = local
        constraints.append(
            pin.RigidConstraintModel(
                pin.ContactType.CONTACT_3D,
                model,
                j1,
                pin.SE3(np.eye(3), p1),
                j2,
                pin.SE3(np.eye(3), p2),
                pin.ReferenceFrame.LOCAL,
            )
        )
        frames.append(
            tuple(
                None if j == 0 else _add_frame(pin, model, f"loop{c}{s}", j, p)
                for (j, p), s in zip(local, "ab")
            )
        )
    k = ref.index(ref.platform)
    platform = _add_frame(
        pin, model, "platform_com", ids[ref.platform], np.asarray(ref.rigid[k].com)
    )
    return PinocchioModel(mech, mass, ref, model, constraints, ids, tuple(frames), platform)


@dataclass(frozen=True)
class PinocchioResult:
    """pinocchio's answers along a trajectory (batch shape ``(...)``)."""

    force: Array  #: (..., m) minimum-norm actuator forces pinocchio needs for the platform's motion
    platform_error: Array  #: (...) max |a_pin(our forces) - a_target| / max |a_target|
    kinematic_residual: Array  #: (...) relative residual of the velocity solve
    loop_error: Array  #: (...) largest distance between the two points of a closure (m)


def _jacobians(pm: PinocchioModel, data, q: Array, v: Array | None) -> tuple[Array, Array]:
    """Loop-closure rows (point a - point b, 3 each) and platform rows (6), and, with ``v``,
    their bias (classical acceleration at zero joint acceleration)."""
    pin = import_pinocchio()
    model = pm.model
    ref = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    zero = np.zeros(model.nv)
    pin.computeJointJacobians(model, data, q)
    pin.forwardKinematics(model, data, q, zero if v is None else v, zero)
    pin.updateFramePlacements(model, data)
    rows, bias = [], []

    def point(fid, six: bool = False):
        if fid is None:
            return np.zeros((6 if six else 3, model.nv)), np.zeros(6 if six else 3)
        jac = pin.getFrameJacobian(model, data, fid, ref)
        acc = pin.getFrameClassicalAcceleration(model, data, fid, ref).vector
        return (jac, acc) if six else (jac[:3], acc[:3])

    for fa, fb in pm.loop_frames:
        (ja, aa), (jb, ab) = point(fa), point(fb)
        rows.append(ja - jb)
        bias.append(aa - ab)
    jp, ap = point(pm.platform_frame, True)
    return np.vstack(rows + [jp]), np.concatenate(bias + [ap])


def _platform_acceleration(
    pm: PinocchioModel, data, cdatas, q: Array, v: Array, tau: Array
) -> Array:
    pin = import_pinocchio()
    ddq = pin.constraintDynamics(pm.model, data, q, v, tau, pm.constraints, cdatas)
    pin.forwardKinematics(pm.model, data, q, v, ddq)
    pin.updateFramePlacements(pm.model, data)
    return pin.getFrameClassicalAcceleration(
        pm.model, data, pm.platform_frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    ).vector.copy()


def check(
    pm: PinocchioModel, pose: ArrayLike, rate: ArrayLike, acceleration: ArrayLike, force: ArrayLike
) -> PinocchioResult:
    """Run pinocchio's constrained dynamics along trajectory samples (each (..., n)) with our
    actuator ``force`` (..., m) (module docstring)."""
    pin = import_pinocchio()
    mech = pm.mech
    x, v, a = (
        as_batch(arr, mech.n_pose, w)
        for arr, w in ((pose, "pose"), (rate, "rate"), (acceleration, "acceleration"))
    )
    f = as_batch(force, len(pm.reference.actuators), "force")
    batch = x.shape[:-1]
    x, v, a, f = (arr.reshape(-1, arr.shape[-1]) for arr in (x, v, a, f))
    st: State = state(mech, x, v, pm.mass)
    plat = st.platform()
    target_v = np.concatenate([plat.centre.rate[:, 0], plat.spin.rate[:, 0]], -1)
    target_a = np.concatenate(
        [plat.centre.acceleration(a)[:, 0], plat.spin.acceleration(a)[:, 0]], -1
    )
    qs = pm.q(assemble(mech, x, pm.mass))
    data = pm.model.createData()
    cdatas = [c.createData() for c in pm.constraints]
    pin.initConstraintDynamics(pm.model, data, pm.constraints, cdatas)
    drives = pm.drives()
    nc = 3 * len(pm.loop_frames)
    out = np.empty((len(x), len(drives)))
    err, resid, loop = np.empty(len(x)), np.empty(len(x)), np.empty(len(x))
    for k in range(len(x)):
        rows, _ = _jacobians(pm, data, qs[k], None)
        loop[k] = _loop_error(pm, data)
        qdot, *_ = np.linalg.lstsq(rows, np.concatenate([np.zeros(nc), target_v[k]]), rcond=None)
        resid[k] = np.linalg.norm(rows @ qdot - np.concatenate([np.zeros(nc), target_v[k]])) / max(
            np.linalg.norm(target_v[k]), 1e-300
        )
        out[k], err[k] = _forces(pm, data, cdatas, qs[k], qdot, drives, f[k], target_a[k])
    shape = batch + (len(drives),)
    return PinocchioResult(
        out.reshape(shape), err.reshape(batch), resid.reshape(batch), loop.reshape(batch)
    )


def _forces(pm, data, cdatas, q, qdot, drives, ours, target) -> tuple[Array, float]:
    """pinocchio's minimum-norm actuator forces for ``target``, and the relative platform
    acceleration error with ``ours``."""
    tau = np.zeros(pm.model.nv)
    base = _platform_acceleration(pm, data, cdatas, q, qdot, tau)
    cols = []
    for i in drives:
        tau[:] = 0.0
        tau[i] = 1.0
        cols.append(_platform_acceleration(pm, data, cdatas, q, qdot, tau) - base)
    d = np.column_stack(cols)
    tau[:] = 0.0
    tau[drives] = ours
    with_ours = _platform_acceleration(pm, data, cdatas, q, qdot, tau)
    scale = max(np.max(np.abs(target)), 1e-300)
    u = np.linalg.lstsq(d, target - base, rcond=1e-10)[0]
    return u, float(np.max(np.abs(with_ours - target)) / scale)


def _loop_error(pm: PinocchioModel, data) -> float:
    worst = 0.0
    for c, (fa, fb) in enumerate(pm.loop_frames):
        pa = pm.reference.points[c] if fa is None else data.oMf[fa].translation
        pb = pm.reference.points[c] if fb is None else data.oMf[fb].translation
        worst = max(worst, float(np.linalg.norm(pa - pb)))
    return worst
