"""MuJoCo as an independent check of the inverse dynamics of any mechanism.

:func:`mjcf` writes the model from the mechanism's own description (:meth:`Mechanism.bodies` at a
reference pose and its :meth:`Mechanism.mass_model`): one MJCF body per moving body, nested as the
description's parents say, each with its joint (free, ball, slide or hinge), its mass, centre of
mass and full inertia; the loops closed by ``<equality><connect site1 site2>`` at the closure
points; a motor of gear 1 on each actuated joint. Nothing is written by hand per mechanism.

Actuator forces (:func:`inverse_dynamics`) follow the recipe of MuJoCo's own advice for closed
loops (its issues #555 and #1547: with the loops on, ``mj_inverse`` lets the soft constraints take
the load), so that no soft constraint enters and the answer is exact to rounding:

1. ``qpos`` from the bodies' placements at the sample (every loop assembled);
2. ``qvel`` and ``qacc`` from MuJoCo's own kinematics: the platform's velocity and acceleration
   prescribed (its centre of mass and angular rates), the loops held (``J_c qvel = 0``,
   ``J_c qacc = -Jdot_c qvel``), minimum norm (the idle spins of S-S legs stay zero); ``J`` and
   ``Jdot`` from ``mj_jac`` and ``mj_jacDot``;
3. constraints disabled, ``mj_inverse`` gives the open tree's generalised forces ``tau``;
4. ``tau = S^T u + J_c^T lambda`` restricted to the loop-consistent motions (the null space ``Z``
   of ``J_c``): ``Z^T S^T u = Z^T tau``, minimum-norm ``u`` (unique unless the drive is
   redundant; then the same minimum-norm choice as :func:`parakin.dynamics.inverse_dynamics`).

MuJoCo is imported lazily (``pip install mujoco``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from parakin.dynamics.assembly import Assembly, EngineModel, assemble, joint_coordinates, quaternion
from parakin.dynamics.inverse import state
from parakin.dynamics.model import MassModel
from parakin.errors import ShapeError
from parakin.mechanisms.base import Array, Mechanism, as_batch

__all__ = [
    "MujocoModel",
    "MujocoResult",
    "Tracking",
    "mjcf",
    "build",
    "inverse_dynamics",
    "import_mujoco",
    "site_jacobians",
    "open_loop",
    "open_tree_forces",
    "track",
    "vector",
]


def import_mujoco():
    """The ``mujoco`` module, or an ImportError saying how to get it."""
    try:
        import mujoco
    except ImportError as exc:  # pragma: no cover - environment.txt installs it
        raise ImportError(
            "the MuJoCo check needs the 'mujoco' package (pip install mujoco)"
        ) from exc
    return mujoco


def vector(v: ArrayLike) -> str:
    """An MJCF vector attribute: every value printed exactly (``repr``)."""
    return " ".join(repr(float(x)) for x in np.asarray(v, dtype=float).ravel())


_vec = vector


def _body_xml(ref: Assembly, k: int, sites: list[tuple[str, int, Array]], indent: str) -> list[str]:
    name = ref.names[k]
    pos, rot = ref.relative(name)
    o, r = ref.frame(name)
    body = ref.rigid[k]
    i = body.inertia_matrix
    lines = [f'{indent}<body name="{name}" pos="{_vec(pos)}" quat="{_vec(quaternion(rot))}">']
    joint = ref.joints[k]
    if joint == "free":
        lines.append(f'{indent}  <freejoint name="{name}"/>')
    elif joint == "ball":
        lines.append(f'{indent}  <joint name="{name}" type="ball"/>')
    else:
        lines.append(
            f'{indent}  <joint name="{name}" type="{joint}" axis="{_vec(r.T @ ref.axis[k])}"/>'
        )
    full = (i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2])
    lines.append(
        f'{indent}  <inertial pos="{_vec(body.com)}" mass="{body.mass!r}" fullinertia="{_vec(full)}"/>'
    )
    for site, owner, point in sites:
        if owner == k:
            lines.append(
                f'{indent}  <site name="{site}" pos="{_vec(r.T @ (point - o))}" size="0.005"/>'
            )
    for child in range(len(ref.names)):
        if ref.parents[child] == name:
            lines += _body_xml(ref, child, sites, indent + "  ")
    lines.append(f"{indent}</body>")
    return lines


def mjcf(
    mech: Mechanism,
    reference_pose: ArrayLike | None = None,
    mass: MassModel | None = None,
    timestep: float = 1e-3,
) -> str:
    """The MJCF text of ``mech`` assembled at ``reference_pose`` (default :meth:`home`), with
    ``mass`` (default :meth:`Mechanism.mass_model`). For a forward simulation the loops are stiff
    (``solref`` time constant ``2 timestep``, the least MuJoCo allows) and the integrator RK4;
    the inverse dynamics depends on neither."""
    if not (np.isfinite(timestep) and 0 < timestep <= 1e-2):
        raise ValueError(f"timestep = {timestep!r} s must lie in (0, 0.01]")
    p0 = as_batch(
        mech.home() if reference_pose is None else reference_pose, mech.n_pose, "reference_pose"
    )
    if p0.ndim != 1:
        raise ShapeError(f"reference_pose must be one pose ({mech.n_pose},), got shape {p0.shape}")
    ref = assemble(mech, p0, mass)
    sites = []  # (site name, body index or -1 for the world, world point)
    for c, (first, second) in enumerate(ref.closures):
        for side, owner in (("a", first), ("b", second)):
            sites.append(
                (f"loop{c}{side}", -1 if owner == "world" else ref.index(owner), ref.points[c])
            )
    lines = [
        f'<mujoco model="{mech.name}">',
        '  <compiler angle="radian" inertiafromgeom="false" autolimits="true"/>',
        f'  <option gravity="{_vec(ref.gravity)}" timestep="{timestep!r}" integrator="RK4" jacobian="dense"/>',
        f'  <default><equality solref="{2 * timestep!r} 1" solimp="0.9999 0.9999 0.0001 0.5 2"/></default>',
        "  <worldbody>",
    ]
    lines += [
        f'    <site name="{s}" pos="{_vec(p)}" size="0.005"/>'
        for s, owner, p in sites
        if owner == -1
    ]
    for k, parent in enumerate(ref.parents):
        if parent == "world":
            lines += _body_xml(ref, k, sites, "    ")
    lines += ["  </worldbody>", "  <equality>"]
    lines += [
        f'    <connect name="loop{c}" site1="loop{c}a" site2="loop{c}b"/>'
        for c in range(len(ref.closures))
    ]
    lines += ["  </equality>", "  <actuator>"]
    lines += [
        f'    <motor name="drive{i + 1}" joint="{a}" gear="1"/>'
        for i, a in enumerate(ref.actuators)
    ]
    lines += ["  </actuator>", "</mujoco>"]
    return "\n".join(lines) + "\n"


@dataclass(frozen=True, eq=False)
class MujocoModel(EngineModel):
    """A compiled MuJoCo model of a mechanism, its reference assembly and index maps."""

    xml: str = field(repr=False)
    model: Any = field(repr=False)

    def qpos(self, current: Assembly) -> Array:
        """``qpos`` (..., nq) of assemblies ``current`` (batched like it)."""
        mujoco = import_mujoco()
        out = np.broadcast_to(
            np.asarray(self.model.qpos0), current.origin.shape[:-2] + (self.model.nq,)
        ).copy()
        for name in current.names:
            j = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_JOINT, name)
            adr = int(self.model.jnt_qposadr[j])
            coords = joint_coordinates(self.reference, current, name)
            out[..., adr : adr + coords.shape[-1]] = coords
        return out

    def dofs(self, names: tuple[str, ...]) -> Array:
        """The velocity index of each named body's one-dof joint."""
        mujoco = import_mujoco()
        ids = [mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_JOINT, n) for n in names]
        return np.array([int(self.model.jnt_dofadr[j]) for j in ids])


def build(
    mech: Mechanism,
    reference_pose: ArrayLike | None = None,
    mass: MassModel | None = None,
    timestep: float = 1e-3,
) -> MujocoModel:
    """Generate the MJCF (:func:`mjcf`) and compile it."""
    mujoco = import_mujoco()
    mass = mech.mass_model() if mass is None else mass
    p0 = mech.home() if reference_pose is None else reference_pose
    xml = mjcf(mech, p0, mass, timestep)
    return MujocoModel(
        mech, mass, assemble(mech, p0, mass), xml, mujoco.MjModel.from_xml_string(xml)
    )


@dataclass(frozen=True)
class MujocoResult:
    """Actuator forces and drive rates from MuJoCo, per sample (batch shape ``(...)``)."""

    force: Array  #: (..., m) along each joint, minimum norm over the internal forces
    joint_rate: Array  #: (..., m) MuJoCo's actuated joint velocities
    joint_acceleration: Array  #: (..., m)
    loop_error: Array  #: (...) largest distance between the two sites of a loop closure (m)
    kinematic_residual: Array  #: (...) relative residual of the velocity and acceleration solves
    spin: Array  #: (...) largest idle spin rate of a ball joint about its body's own axis (rad/s)


def _rows(
    mm: MujocoModel, data, pairs, platform: int, with_dot: bool
) -> tuple[Array, Array | None]:
    """Stacked Jacobians (and their time derivatives) of the loop closures (site1 - site2, 3 rows
    each) and of the platform's centre of mass and angular velocity (6 rows)."""
    mujoco = import_mujoco()
    model, nv = mm.model, mm.model.nv
    loops, loop_dots = site_jacobians(model, data, pairs, with_dot)
    rows, dots = [loops], [loop_dots]
    for dot in [False, True] if with_dot else [False]:
        jp, jr = np.zeros((3, nv)), np.zeros((3, nv))
        fn = mujoco.mj_jacDot if dot else mujoco.mj_jac
        fn(model, data, jp, jr, data.xipos[platform], platform)
        (dots if dot else rows).append(np.vstack([jp, jr]))
    return np.vstack(rows), (np.vstack(dots) if with_dot else None)


def _solve(a: Array, b: Array) -> tuple[Array, float]:
    x = np.linalg.lstsq(a, b, rcond=None)[0]
    return x, float(np.linalg.norm(a @ x - b) / max(np.linalg.norm(b), 1e-300))


def inverse_dynamics(
    mm: MujocoModel, pose: ArrayLike, rate: ArrayLike, acceleration: ArrayLike
) -> MujocoResult:
    """Actuator forces for the trajectory samples (each (..., n)) from MuJoCo (module docstring);
    one sample at a time."""
    mujoco = import_mujoco()
    mech, model = mm.mech, mm.model
    x, v, a = (
        as_batch(arr, mech.n_pose, what)
        for arr, what in ((pose, "pose"), (rate, "rate"), (acceleration, "acceleration"))
    )
    if not (x.shape == v.shape == a.shape):
        raise ShapeError(
            f"pose {x.shape}, rate {v.shape} and acceleration {a.shape} must have one shape"
        )
    batch = x.shape[:-1]
    x, v, a = x.reshape(-1, mech.n_pose), v.reshape(-1, mech.n_pose), a.reshape(-1, mech.n_pose)
    qpos = mm.qpos(assemble(mech, x, mm.mass))
    plat = state(mech, x, v, mm.mass).platform()
    target_v = np.concatenate([plat.centre.rate[:, 0], plat.spin.rate[:, 0]], -1)
    target_a = np.concatenate(
        [plat.centre.acceleration(a)[:, 0], plat.spin.acceleration(a)[:, 0]], -1
    )
    sid = lambda n: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, n)  # noqa: E731
    pairs = [(sid(f"loop{c}a"), sid(f"loop{c}b")) for c in range(len(mm.reference.closures))]
    platform = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, mm.reference.platform)
    drives = mm.dofs(mm.reference.actuators)
    sel = np.zeros((model.nv, len(drives)))
    sel[drives, np.arange(len(drives))] = 1.0
    data = mujoco.MjData(model)
    out = {k: np.empty((len(x), len(drives))) for k in ("force", "rate", "acc")}
    loop, resid, spin = np.empty(len(x)), np.empty(len(x)), np.empty(len(x))
    nc = 3 * len(pairs)
    for k in range(len(x)):
        data.qpos[:] = qpos[k]
        data.qvel[:] = 0.0
        mujoco.mj_forward(model, data)
        loop[k] = max(
            (np.linalg.norm(data.site_xpos[i] - data.site_xpos[j]) for i, j in pairs), default=0.0
        )
        rows, _ = _rows(mm, data, pairs, platform, False)
        qvel, r1 = _solve(rows, np.concatenate([np.zeros(nc), target_v[k]]))
        data.qvel[:] = qvel
        mujoco.mj_forward(model, data)
        rows, dots = _rows(mm, data, pairs, platform, True)
        qacc, r2 = _solve(rows, np.concatenate([np.zeros(nc), target_a[k]]) - dots @ qvel)
        out["force"][k] = _tree_forces(model, data, qacc, rows[:nc], sel)
        out["rate"][k], out["acc"][k] = qvel[drives], qacc[drives]
        resid[k], spin[k] = max(r1, r2), _max_spin(mm, data, qvel)
    shape = batch + (len(drives),)
    return MujocoResult(
        out["force"].reshape(shape),
        out["rate"].reshape(shape),
        out["acc"].reshape(shape),
        loop.reshape(batch),
        resid.reshape(batch),
        spin.reshape(batch),
    )


def _tree_forces(model, data, qacc: Array, jc: Array, sel: Array) -> Array:
    """Steps 3-4: ``mj_inverse`` of the open tree, then the minimum-norm ``u`` with
    ``Z^T S^T u = Z^T tau`` (``Z`` the null space of the loop Jacobian)."""
    tau = open_tree_forces(model, data, qacc)
    _, s, vt = np.linalg.svd(jc)
    rank = int(np.sum(s > s[0] * 1e-12)) if len(s) else 0
    z = vt[rank:].T
    # rank-revealing cut: a redundant drive leaves exact zeros that rounding lifts to ~1e-16
    return np.linalg.lstsq(z.T @ sel, z.T @ tau, rcond=1e-10)[0]


def _max_spin(mm: MujocoModel, data, qvel: Array) -> float:
    """The largest rate of a ball-jointed spin-free body about its own axis (its frame's z; a
    ball joint's velocity is in the body frame)."""
    mujoco = import_mujoco()
    model, spins = mm.model, [0.0]
    for k, joint in enumerate(mm.reference.joints):
        if joint == "ball" and mm.reference.spin_free[k]:
            j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, mm.reference.names[k])
            body = int(model.jnt_bodyid[j])
            axis = data.xmat[body].reshape(3, 3)[:, 2]
            omega = (
                data.xmat[body].reshape(3, 3)
                @ qvel[int(model.jnt_dofadr[j]) : int(model.jnt_dofadr[j]) + 3]
            )
            spins.append(abs(float(axis @ omega)))
    return max(spins)


# ---------------------------------------------------------------------------------------- shared
def open_tree_forces(model, data, qacc: Array) -> Array:
    """Step 3 of the recipe: the generalised forces ``tau`` of the open tree (``mj_inverse`` with
    the constraints disabled) at the state in ``data`` and the accelerations ``qacc``."""
    mujoco = import_mujoco()
    bit = int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    model.opt.disableflags |= bit
    try:
        data.qacc[:] = qacc
        mujoco.mj_inverse(model, data)
        return np.array(data.qfrc_inverse)
    finally:
        model.opt.disableflags &= ~bit


def site_jacobians(model, data, pairs, with_dot: bool) -> tuple[Array, Array | None]:
    """Jacobians (and time derivatives, ``mj_jacDot``) of ``site1 - site2`` for each pair of
    site ids, stacked (3 rows a pair): the rows of ``connect`` loop closures."""
    mujoco = import_mujoco()
    nv = model.nv
    rows, dots = [], []
    for pair in pairs:
        jp = [np.zeros((3, nv)), np.zeros((3, nv))]
        jd = [np.zeros((3, nv)), np.zeros((3, nv))]
        for side, site in enumerate(pair):
            body = int(model.site_bodyid[site])
            if body == 0:
                continue
            mujoco.mj_jac(model, data, jp[side], None, data.site_xpos[site], body)
            if with_dot:
                mujoco.mj_jacDot(model, data, jd[side], None, data.site_xpos[site], body)
        rows.append(jp[0] - jp[1])
        dots.append(jd[0] - jd[1])
    return np.vstack(rows), (np.vstack(dots) if with_dot else None)


def open_loop(
    model, data, force: Callable[[float], ArrayLike], t_end: float, record: Callable
) -> list:
    """Step ``model`` from the state in ``data`` for ``t_end`` seconds, each step holding the
    actuator forces ``force(t)`` of the step's midpoint; ``record(data)`` after every step (and
    before the first) is collected in the returned list."""
    mujoco = import_mujoco()
    if not (np.isfinite(t_end) and t_end > 0):
        raise ValueError(f"t_end = {t_end!r} s must be finite and > 0")
    dt = float(model.opt.timestep)
    out = [record(data)]
    for _ in range(int(round(t_end / dt))):
        f = np.asarray(force(data.time + 0.5 * dt), dtype=float)
        if f.shape != (model.nu,) or not np.all(np.isfinite(f)):
            raise ValueError(f"force(t) must return {model.nu} finite actuator forces, got {f!r}")
        data.ctrl[:] = f
        mujoco.mj_step(model, data)
        out.append(record(data))
    return out


@dataclass(frozen=True)
class Tracking:
    """MuJoCo's forward simulation under given actuator forces: its platform's centre of mass
    against the trajectory's, and its loop closures."""

    t: Array  #: (k,) s
    centre: Array  #: (k, 3) MuJoCo's platform centre of mass, m
    target: Array  #: (k, 3) the trajectory's, m
    loop_error: Array  #: (k,) largest distance between the two sites of a closure, m

    @property
    def error(self) -> Array:
        """``max |centre - target|`` per sample (m)."""
        return np.max(np.abs(self.centre - self.target), axis=-1)


def track(
    mm: MujocoModel, trajectory, t_end: float, force: Callable[[float], ArrayLike]
) -> Tracking:
    """Drive the MuJoCo model of any mechanism open loop with actuator forces ``force(t)`` from the
    trajectory's exact state at t = 0 (positions from the bodies, velocities by the recipe's
    minimum-norm solve) and record where its platform goes; the soft loop constraints and the
    integrator make this a check to the stiffness of the constraints, not to rounding."""
    mujoco = import_mujoco()
    mech, model = mm.mech, mm.model
    x0, v0, _ = (np.asarray(s, dtype=float) for s in trajectory.state(0.0))
    data = mujoco.MjData(model)
    data.qpos[:] = mm.qpos(assemble(mech, x0, mm.mass))
    mujoco.mj_forward(model, data)
    sid = lambda n: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, n)  # noqa: E731
    pairs = [(sid(f"loop{c}a"), sid(f"loop{c}b")) for c in range(len(mm.reference.closures))]
    platform = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, mm.reference.platform)
    plat = state(mech, x0, v0, mm.mass).platform()
    rows, _ = _rows(mm, data, pairs, platform, False)
    target = np.concatenate([np.zeros(3 * len(pairs)), plat.centre.rate[0], plat.spin.rate[0]])
    data.qvel[:] = _solve(rows, target)[0]
    mujoco.mj_forward(model, data)

    def record(d) -> tuple:
        loop = max((np.linalg.norm(d.site_xpos[i] - d.site_xpos[j]) for i, j in pairs), default=0.0)
        return d.time, d.xipos[platform].copy(), loop

    rec = open_loop(model, data, force, t_end, record)
    t = np.array([r[0] for r in rec])
    expected = state(mech, trajectory.state(t)[0], trajectory.state(t)[1], mm.mass).platform()
    return Tracking(
        t, np.array([r[1] for r in rec]), expected.centre.value[:, 0], np.array([r[2] for r in rec])
    )
