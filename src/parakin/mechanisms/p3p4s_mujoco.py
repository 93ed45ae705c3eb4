"""An independent inverse-dynamics check of the 3-P(4S) in MuJoCo (stands in for the paper's ADAMS).

The MJCF is generated from a :class:`~parakin.mechanisms.P3P4S` and
:class:`~parakin.mechanisms.p3p4s_dynamics.InertialParams` (no hand-written model):

* three sliders on inclined prismatic joints along ``m_i`` (joint value = stroke ``q_i``);
* on each slider, rods hanging from ball joints, their tops tied to the platform by site-based
  ``<equality><connect site1=... site2=...>`` (the loop closures). Two models:
  ``rods="equivalent"`` -- one equivalent rod per limb from ``c_i`` to ``d_i`` (mass ``k m_d``,
  inertia ``k I_dio``, ``k`` rods per limb: the paper's model, eq 20), the platform on three slide
  joints (three SS rods alone do not hold its orientation); ``rods="parallelogram"`` -- the
  full model, two side rods per limb at ``c_i +- (d/2) t_i`` to ``d_i +- (d/2) t_i``, each
  ``m_d``, ``I_dio``, and the platform on a free joint (the parallelograms keep it from turning);
* gravity ``params.g``; a motor (gear 1) on each slider joint.

Actuator forces follow the recipe of docs/zhao2017_3p4s.md#mujoco (MuJoCo does not infer actuator forces
of a closed loop; ``mj_inverse`` with the loops on lets the soft constraints absorb the load):

1. ``qpos`` from the IK (sliders, ball quaternions turning each rod onto ``n_i``);
2. ``qvel`` and ``qacc`` from MuJoCo's own kinematics: with the platform rates prescribed, solve
   ``J_c qvel = 0`` and ``J_c qacc = -Jdot_c qvel`` (minimum norm: no spin of the rods), where
   ``J_c`` and ``Jdot_c`` are MuJoCo's site Jacobians (``mj_jacSite``, ``mj_jacDot``) of the
   connect constraints -- so the drive rates are independent of our eqs 8 and 13;
3. constraints disabled, ``mj_inverse`` gives the tree's generalised forces ``tau``;
4. ``[S^T  J_c^T] [u; lambda] = tau`` in least squares: ``u`` = motor forces along ``+m_i``.

This module keeps what is particular to Zhao's paper: the "equivalent" model (one rod per limb,
the paper's eq 20) and the layout of its results for the paper's figures. The generic pieces (the
MuJoCo import, MJCF vectors, the site Jacobians of the loop closures, the open-loop stepping) are
:mod:`parakin.dynamics.mujoco_check`, which also builds the MJCF of *any* mechanism from its
bodies; for the 3-P(4S) that generic model is this module's "parallelogram" model, and the tests
check that both give the same forces.

MuJoCo is imported lazily; the rest of parakin does not need it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from parakin.dynamics.mujoco_check import Tracking, open_loop, open_tree_forces, site_jacobians
from parakin.dynamics.mujoco_check import import_mujoco as _mujoco
from parakin.dynamics.mujoco_check import vector as _vec
from parakin.errors import ShapeError
from parakin.mechanisms.base import Array, as_batch
from parakin.mechanisms.p3p4s import P3P4S
from parakin.mechanisms.p3p4s_dynamics import InertialParams

__all__ = [
    "RodModel",
    "MujocoMechanism",
    "MujocoResult",
    "TrackingResult",
    "mjcf",
    "build",
    "inverse_dynamics",
    "track",
]

RodModel = Literal["equivalent", "parallelogram"]

_EZ = np.array([0.0, 0.0, 1.0])


def _quat_z_to(u: Array) -> Array:
    """Unit quaternion (w, x, y, z) of the smallest rotation taking e_z onto unit ``u`` (..., 3)."""
    u = np.asarray(u, dtype=float)
    if np.any(u[..., 2] <= -1 + 1e-12):
        raise ValueError(
            "a rod points straight down (n = -e_z): its reference rotation is ambiguous"
        )
    q = np.stack([1.0 + u[..., 2], -u[..., 1], u[..., 0], np.zeros_like(u[..., 0])], axis=-1)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def _quat_to_matrix(q: Array) -> Array:
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def _rod_layout(mech: P3P4S, params: InertialParams, rods: str) -> list[tuple[int, float, float]]:
    """``(limb, offset along t_i, mass multiplier)`` of every rod body of the model."""
    if rods == "equivalent":
        return [(i, 0.0, float(params.rods_per_limb)) for i in range(3)]
    if rods == "parallelogram":
        k = params.rods_per_limb
        offsets = np.linspace(-0.5 * mech.d, 0.5 * mech.d, k) if k > 1 else np.zeros(1)
        return [(i, float(s), 1.0) for i in range(3) for s in offsets]
    raise ValueError(
        f"rods = {rods!r}: use 'equivalent' (one rod per limb) or 'parallelogram' (all side rods)"
    )


def mjcf(
    mech: P3P4S,
    params: InertialParams,
    rods: RodModel = "equivalent",
    reference_pose: ArrayLike | None = None,
    timestep: float = 1e-4,
) -> str:
    """The MJCF text of the model (see the module docstring), assembled at ``reference_pose``
    (default: the mechanism's home pose; also the ``home`` keyframe).

    The platform's rotational inertia is not given in the paper; it does not enter (the platform
    only translates), so a thin disc of radius ``r_a`` is used. For forward simulation
    (:func:`track`) the loops are made stiff (``solref`` time constant ``2 timestep``, the least
    MuJoCo allows; ``solimp`` 0.9999) and the integrator is RK4; the inverse dynamics does not
    depend on either.
    """
    if not (np.isfinite(timestep) and 0 < timestep <= 1e-2):
        raise ValueError(f"timestep = {timestep!r} s must lie in (0, 0.01]")
    if not isinstance(mech, P3P4S):
        raise TypeError(f"expected a P3P4S mechanism, got {type(mech).__name__}")
    layout = _rod_layout(mech, params, rods)
    p0 = as_batch(mech.home() if reference_pose is None else reference_pose, 3, "reference_pose")
    if p0.ndim != 1:
        raise ShapeError(f"reference_pose must be one pose (3,), got shape {p0.shape}")
    q0 = mech.ik(p0)
    n0 = mech.rod_directions(p0, q0)
    t = np.cross(_EZ, mech.e)
    L = mech.L
    i_t, _, i_a = params.I_rod
    m_p = params.m_platform
    disc = (0.25 * m_p * mech.r_a**2, 0.25 * m_p * mech.r_a**2, 0.5 * m_p * mech.r_a**2)
    lines = [
        f'<mujoco model="3p4s_{rods}">',
        '  <compiler angle="radian" inertiafromgeom="false" autolimits="true"/>',
        f'  <option gravity="{_vec(params.g)}" timestep="{timestep!r}" integrator="RK4" jacobian="dense"/>',
        "  <default>",
        '    <geom contype="0" conaffinity="0"/>',
        f'    <equality solref="{2 * timestep!r} 1" solimp="0.9999 0.9999 0.0001 0.5 2"/>',
        "  </default>",
        "  <worldbody>",
    ]
    if rods == "equivalent":
        lines += [
            '    <body name="platform" pos="0 0 0">',
            '      <joint name="px" type="slide" axis="1 0 0"/>',
            '      <joint name="py" type="slide" axis="0 1 0"/>',
            '      <joint name="pz" type="slide" axis="0 0 1"/>',
        ]
    else:
        lines += [
            f'    <body name="platform" pos="{_vec(p0)}">',
            '      <freejoint name="platform"/>',
        ]
    lines.append(f'      <inertial pos="0 0 0" mass="{m_p!r}" diaginertia="{_vec(disc)}"/>')
    lines.append(
        f'      <geom type="cylinder" size="{mech.r_a!r} 0.005" rgba="0.96 0.76 0.55 0.6"/>'
    )
    for r, (i, s, _) in enumerate(layout):
        lines.append(
            f'      <site name="top{r}" pos="{_vec(mech.a * mech.e[i] + s * t[i])}" size="0.008"/>'
        )
    lines.append("    </body>")
    for i in range(3):
        lines += [
            f'    <body name="slider{i + 1}" pos="{_vec(mech.r_b * mech.e[i])}">',
            f'      <joint name="q{i + 1}" type="slide" axis="{_vec(mech.m[i])}"/>',
            f'      <inertial pos="0 0 0" mass="{params.m_slider!r}" diaginertia="1e-3 1e-3 1e-3"/>',
            '      <geom type="box" size="0.03 0.03 0.015" rgba="0.9 0.62 0 1"/>',
        ]
        for r, (limb, s, mult) in enumerate(layout):
            if limb != i:
                continue
            quat = _quat_z_to(n0[i])
            inertia = (mult * i_t, mult * i_t, mult * i_a)
            lines += [
                f'      <body name="rod{r}" pos="{_vec(s * t[i])}" quat="{_vec(quat)}">',
                f'        <joint name="ball{r}" type="ball"/>',
                f'        <inertial pos="0 0 {0.5 * L!r}" mass="{mult * params.m_rod!r}" '
                f'diaginertia="{_vec(inertia)}"/>',
                f'        <geom type="capsule" fromto="0 0 0 0 0 {L!r}" size="0.0125" rgba="0.2 0.2 0.2 1"/>',
                f'        <site name="end{r}" pos="0 0 {L!r}" size="0.008"/>',
                "      </body>",
            ]
        lines.append("    </body>")
    lines.append("  </worldbody>")
    lines.append("  <equality>")
    for r in range(len(layout)):
        lines.append(f'    <connect name="loop{r}" site1="end{r}" site2="top{r}"/>')
    lines.append("  </equality>")
    lines.append("  <actuator>")
    for i in range(3):
        lines.append(f'    <motor name="motor{i + 1}" joint="q{i + 1}" gear="1"/>')
    lines.append("  </actuator>")
    key = list(p0) if rods == "equivalent" else [*p0, 1.0, 0.0, 0.0, 0.0]
    for i in range(3):  # qpos order follows the body tree: slider i, then its rods' ball joints
        key += [q0[i]] + [1.0, 0.0, 0.0, 0.0] * sum(1 for limb, _, _ in layout if limb == i)
    lines.append(f'  <keyframe><key name="home" qpos="{_vec(key)}"/></keyframe>')
    lines.append("</mujoco>")
    return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class MujocoMechanism:
    """A compiled MuJoCo model of a 3-P(4S) plus the index maps the check needs."""

    mech: P3P4S
    params: InertialParams
    rods: str
    xml: str = field(repr=False)
    model: Any = field(repr=False, compare=False)
    platform_dofs: tuple[int, ...]
    slider_dofs: tuple[int, int, int]
    slider_qpos: tuple[int, int, int]
    platform_qpos: tuple[int, ...]
    rod_limb: tuple[int, ...]
    rod_ball_qpos: tuple[int, ...]
    rod_ball_dofs: tuple[int, ...]
    rod_ref_rot: Array = field(repr=False, compare=False)  # (n_rods, 3, 3) reference body rotations
    site_pairs: tuple[tuple[int, int], ...]  # (rod end site, platform site) per connect

    def qpos(self, pose: Array, joints: Array) -> Array:
        """Assembled ``qpos`` for one platform position and its strokes."""
        mech = self.mech
        qpos = np.array(self.model.qpos0, dtype=float)
        if self.rods == "equivalent":
            qpos[list(self.platform_qpos)] = pose
        else:
            qpos[list(self.platform_qpos)] = np.concatenate([pose, [1.0, 0.0, 0.0, 0.0]])
        qpos[list(self.slider_qpos)] = joints
        n = mech.rod_directions(pose, joints)
        for r, (limb, adr) in enumerate(zip(self.rod_limb, self.rod_ball_qpos)):
            local = self.rod_ref_rot[r].T @ n[limb]
            qpos[adr : adr + 4] = _quat_z_to(local)
        return qpos


def build(
    mech: P3P4S,
    params: InertialParams,
    rods: RodModel = "equivalent",
    reference_pose: ArrayLike | None = None,
    timestep: float = 1e-4,
) -> MujocoMechanism:
    """Generate the MJCF (:func:`mjcf`) and compile it."""
    mujoco = _mujoco()
    xml = mjcf(mech, params, rods, reference_pose, timestep)
    model = mujoco.MjModel.from_xml_string(xml)
    jid = lambda name: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)  # noqa: E731
    bid = lambda name: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)  # noqa: E731
    sid = lambda name: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, name)  # noqa: E731
    if rods == "equivalent":
        pj = [jid(n) for n in ("px", "py", "pz")]
        platform_dofs = tuple(int(model.jnt_dofadr[j]) for j in pj)
        platform_qpos = tuple(int(model.jnt_qposadr[j]) for j in pj)
    else:
        j = jid("platform")
        platform_dofs = tuple(range(int(model.jnt_dofadr[j]), int(model.jnt_dofadr[j]) + 6))
        platform_qpos = tuple(range(int(model.jnt_qposadr[j]), int(model.jnt_qposadr[j]) + 7))
    sj = [jid(f"q{i + 1}") for i in range(3)]
    layout = _rod_layout(mech, params, rods)
    ref = np.stack([_quat_to_matrix(model.body_quat[bid(f"rod{r}")]) for r in range(len(layout))])
    return MujocoMechanism(
        mech=mech,
        params=params,
        rods=rods,
        xml=xml,
        model=model,
        platform_dofs=platform_dofs,
        slider_dofs=tuple(int(model.jnt_dofadr[j]) for j in sj),
        slider_qpos=tuple(int(model.jnt_qposadr[j]) for j in sj),
        platform_qpos=platform_qpos,
        rod_limb=tuple(limb for limb, _, _ in layout),
        rod_ball_qpos=tuple(int(model.jnt_qposadr[jid(f"ball{r}")]) for r in range(len(layout))),
        rod_ball_dofs=tuple(int(model.jnt_dofadr[jid(f"ball{r}")]) for r in range(len(layout))),
        rod_ref_rot=ref,
        site_pairs=tuple((sid(f"end{r}"), sid(f"top{r}")) for r in range(len(layout))),
    )


@dataclass(frozen=True)
class MujocoResult:
    """Drive rates and motor forces from MuJoCo, per sample (batch shape ``(...)``)."""

    force: Array  #: motor forces along +m_i (..., 3), N
    qdot: Array  #: slider joint velocities (..., 3), m/s
    qddot: Array  #: slider joint accelerations (..., 3), m/s^2
    loop_error: Array  #: max |efc_pos| of the loop closures (...), m (the IK assembles the loops)
    lstsq_residual: Array  #: |[S^T J_c^T][u; lambda] - tau| / |tau| (...)
    rod_spin: Array  #: max |spin rate| of any rod about its own axis (...), rad/s (should be 0)


def _constraint_jacobians(mm: MujocoMechanism, data, with_dot: bool) -> tuple[Array, Array | None]:
    return site_jacobians(mm.model, data, mm.site_pairs, with_dot)


def _assemble(
    mm: MujocoMechanism, data, pose: Array, joints: Array, v: Array
) -> tuple[Array, Array]:
    """Set ``qpos`` (IK) and ``qvel`` (``J_c qvel = 0`` with the platform velocity ``v``), run the
    forward pass; return ``qvel`` and the loop Jacobian ``J_c``."""
    mujoco = _mujoco()
    model = mm.model
    plat = np.array(mm.platform_dofs)
    free = np.setdiff1d(np.arange(model.nv), plat)
    data.qpos[:] = mm.qpos(pose, joints)
    data.qvel[:] = 0.0
    mujoco.mj_forward(model, data)
    jc, _ = _constraint_jacobians(mm, data, with_dot=False)
    v_plat = np.zeros(len(plat))
    v_plat[:3] = v
    qvel = np.zeros(model.nv)
    qvel[plat] = v_plat
    qvel[free] = np.linalg.lstsq(jc[:, free], -jc[:, plat] @ v_plat, rcond=None)[0]
    data.qvel[:] = qvel
    mujoco.mj_forward(model, data)
    return qvel, jc


def inverse_dynamics(
    mm: MujocoMechanism, pose: ArrayLike, velocity: ArrayLike, acceleration: ArrayLike
) -> MujocoResult:
    """Motor forces for prescribed platform motion, from MuJoCo (module docstring, steps 1-4).

    ``pose``, ``velocity``, ``acceleration`` are ``(..., 3)`` arrays of the same shape; MuJoCo
    works one sample at a time (about 0.3 ms each).
    """
    mujoco = _mujoco()
    x = as_batch(pose, 3, "pose")
    v = as_batch(velocity, 3, "velocity")
    a = as_batch(acceleration, 3, "acceleration")
    if not (x.shape == v.shape == a.shape):
        raise ShapeError(
            f"pose {x.shape}, velocity {v.shape} and acceleration {a.shape} must have one shape"
        )
    batch = x.shape[:-1]
    x, v, a = x.reshape(-1, 3), v.reshape(-1, 3), a.reshape(-1, 3)
    q = mm.mech.ik(x)
    model = mm.model
    data = mujoco.MjData(model)
    nv = model.nv
    plat = np.array(mm.platform_dofs)
    free = np.setdiff1d(np.arange(nv), plat)
    sliders = np.array(mm.slider_dofs)
    sel = np.zeros((nv, 3))
    sel[sliders, np.arange(3)] = 1.0
    n_loop_rows = 3 * len(mm.site_pairs)
    ns = len(x)
    force, qdot, qddot = np.empty((ns, 3)), np.empty((ns, 3)), np.empty((ns, 3))
    loop_error, residual, spin = np.empty(ns), np.empty(ns), np.empty(ns)
    for k in range(ns):
        # 1-2: assembled state; velocity from J_c qvel = 0, acceleration from J_c qacc = -Jdot_c qvel
        qvel, _ = _assemble(mm, data, x[k], q[k], v[k])
        loop_error[k] = float(np.max(np.abs(data.efc_pos[:n_loop_rows]))) if data.nefc else 0.0
        jc, jdot = _constraint_jacobians(mm, data, with_dot=True)
        a_plat = np.zeros(len(plat))
        a_plat[:3] = a[k]
        qacc = np.zeros(nv)
        qacc[plat] = a_plat
        qacc[free] = np.linalg.lstsq(jc[:, free], -jdot @ qvel - jc[:, plat] @ a_plat, rcond=None)[
            0
        ]
        tau = open_tree_forces(model, data, qacc)  # 3: the open tree, constraints off
        # 4: tau = S^T u + J_c^T lambda
        lhs = np.hstack([sel, jc.T])
        sol = np.linalg.lstsq(lhs, tau, rcond=None)[0]
        force[k] = sol[:3]
        residual[k] = np.linalg.norm(lhs @ sol - tau) / max(np.linalg.norm(tau), 1e-300)
        qdot[k] = qvel[sliders]
        qddot[k] = qacc[sliders]
        spin[k] = _max_spin(mm, qvel)
    shape = batch + (3,)
    return MujocoResult(
        force.reshape(shape),
        qdot.reshape(shape),
        qddot.reshape(shape),
        loop_error.reshape(batch),
        residual.reshape(batch),
        spin.reshape(batch),
    )


@dataclass(frozen=True)
class TrackingResult(Tracking):
    """An open-loop forward simulation: the platform's path against the target motion (the
    generic :class:`~parakin.dynamics.mujoco_check.Tracking`; the platform only translates, so its
    ``centre`` is its position, also ``pose``; ``loop_error`` max |efc_pos| of the loop closures)."""

    @property
    def pose(self) -> Array:
        """Simulated platform position (n, 3), m."""
        return self.centre


def track(
    mm: MujocoMechanism, motion, t_end: float, force: Callable[[float], ArrayLike]
) -> TrackingResult:
    """Drive the MuJoCo model open loop with motor forces ``force(t)`` (N, along +m_i) and record
    where the platform goes: a forward-dynamics check through MuJoCo's constraint solver.

    Starts from the exact state of ``motion`` at t = 0 (``motion.pose/velocity``); each step of
    ``model.opt.timestep`` (RK4) holds the force evaluated at the step's midpoint. With the right
    forces the platform follows ``motion``; a wrong force model makes it drift away.
    """
    model = mm.model  # open_loop checks t_end
    data = _mujoco().MjData(model)
    p0 = np.asarray(motion.pose(0.0), dtype=float)
    _assemble(mm, data, p0, mm.mech.ik(p0), np.asarray(motion.velocity(0.0), dtype=float))
    plat = list(mm.platform_qpos)[:3]
    n_loop_rows = 3 * len(mm.site_pairs)

    def record(d) -> tuple:
        loop = float(np.max(np.abs(d.efc_pos[:n_loop_rows]))) if d.nefc else 0.0
        return d.time, d.qpos[plat].copy(), loop

    rec = open_loop(model, data, force, t_end, record)
    ts, poses, loops = (list(col) for col in zip(*rec))
    t = np.asarray(ts)
    return TrackingResult(
        t, np.asarray(poses), np.asarray(motion.pose(t), dtype=float), np.asarray(loops)
    )


def _max_spin(mm: MujocoMechanism, qvel: Array) -> float:
    """Largest rod angular velocity component about the rod's own axis (rad/s); the ball joint's
    velocity is in the rod's body frame, whose z is the rod axis."""
    return max(abs(float(qvel[adr + 2])) for adr in mm.rod_ball_dofs)
