"""Inverse dynamics of any mechanism that declares its bodies and masses, by virtual work.

For a trajectory sample (pose ``x``, rate ``xdot``, acceleration ``xddot``) every moving body b has
its centre-of-mass acceleration ``a_b = J_b xddot + b_b`` and angular acceleration
``alpha_b = W_b xddot + c_b`` (:mod:`parakin.dynamics.jet`). D'Alembert's inertial and gravity load
of body b is the wrench ``F_b = m_b (a_b - g)``, ``T_b = I_b alpha_b + omega_b x I_b omega_b``
(Euler's equation about the centre of mass, ``I_b`` in world axes). The principle of virtual work
over the virtual displacements the kinematics allows, ``dq = J dx`` for the actuated joints and
``J_b dx``, ``W_b dx`` for the bodies, gives for every ``dx``::

    J^T f = Q,    Q = sum_b J_b^T F_b + W_b^T T_b - J_p^T F_ext - W_p^T T_ext

(Tsai, "Solving the inverse dynamics of a Stewart-Gough manipulator by the principle of virtual
work", J. Mech. Des. 122(1), 2000; ``F_ext``, ``T_ext`` an external wrench on the platform p). With
as many actuators as pose coordinates ``f = J^-T Q``; with more (redundant drive, ``m > n``) the
minimum-norm solution ``f = J (J^T J)^-1 Q`` plus any element of the null space of ``J^T``
(internal forces that move nothing); with fewer, or at a singular ``J``, the load may not be
balanced at all, which the result reports (``balance``).

The same quantities give the mass matrix ``M = sum_b m_b J_b^T J_b + W_b^T I_b W_b`` and the
velocity-product and gravity terms ``h = Q(xddot = 0)``, so ``M xddot + h = J^T f`` is also the
forward dynamics (:mod:`parakin.dynamics.forward`).
"""

from __future__ import annotations

import pickle
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

import parakin.dynamics.jet as jet
from parakin.dynamics.model import Bodies, BodyGroup, BodyMotion, MassModel, RigidBody, motion
from parakin.dynamics.program import available, record
from parakin.errors import ShapeError, SingularityError
from parakin.mechanisms.base import Array, Mechanism, as_batch, describe_first, raise_first

__all__ = [
    "SINGULAR_CONDITION",
    "BALANCE_TOL",
    "State",
    "InverseDynamics",
    "state",
    "inverse_dynamics",
    "generalized_forces",
    "mass_matrix",
    "energy",
    "solve_forces",
]

#: condition number of the actuator Jacobian J above which a sample is singular: the forces grow
#: with cond(J) and their rounding error (~ cond(J) x 1e-16) would pass 1e-8 relative
SINGULAR_CONDITION = 1e8
#: relative residual |J^T f - Q| / |Q| above which the drives cannot balance the load
BALANCE_TOL = 1e-9


@dataclass(frozen=True, eq=False)
class State:
    """Every body's motion at a batch of states (``pose``, ``rate``, each (..., n)): the
    mechanism's :class:`Bodies`, and per group its rigid body (mass model) and
    :class:`BodyMotion`."""

    pose: Array
    rate: Array
    bodies: Bodies
    mass: MassModel
    groups: tuple[tuple[BodyGroup, RigidBody, BodyMotion], ...]

    @property
    def joints(self) -> jet.Jet:
        return self.bodies.joints

    @property
    def jacobian(self) -> Array:
        """Actuator Jacobian ``J = dq/dx`` (..., m, n)."""
        return self.bodies.joints.jacobian

    def platform(self) -> BodyMotion:
        """The motion of the platform (the body a trajectory prescribes), shape (..., 1, 3)."""
        name = self.bodies.platform
        for g, _, m in self.groups:
            if name in g.names:
                k = slice(g.names.index(name), g.names.index(name) + 1)
                spin = jet.Spin(m.spin.tangents[..., k, :], m.spin.bias[..., k, :])
                frame = None if m.frame is None else m.frame[..., k, :, :]
                axis = None if m.axis is None else m.axis[..., k, :]
                return BodyMotion(m.centre[..., k, :], spin, frame, axis)
        raise KeyError(f"no body named {name!r} (the platform)")


def _mass_model(mech: Mechanism, mass: MassModel | None) -> MassModel:
    if mass is None:
        mass = mech.mass_model()
        if mass is None:
            raise NotImplementedError(f"{type(mech).__name__} declares no mass model (no dynamics)")
    if not isinstance(mass, MassModel):
        raise TypeError(f"mass must be a MassModel, got {type(mass).__name__}")
    return mass


def state(
    mech: Mechanism, pose: ArrayLike, rate: ArrayLike, mass: MassModel | None = None
) -> State:
    """Evaluate the mechanism's bodies (:meth:`Mechanism.bodies`) at poses (..., n) moving at
    ``rate`` (..., n); raises UnreachableError outside the mechanism's domain."""
    mass = _mass_model(mech, mass)
    x, v = _checked(mech, pose, rate)
    return _state(mech, x, v, mass)


def _checked(mech: Mechanism, pose: ArrayLike, rate: ArrayLike, *more: ArrayLike) -> tuple:
    """Poses and rates (and more arrays of pose size) broadcast together, poses in the domain."""
    x = as_batch(pose, mech.n_pose, "pose")
    arrays = [as_batch(a, mech.n_pose, what) for a, what in zip((rate, *more), _NAMES)]
    try:
        out = np.broadcast_arrays(x, *arrays)
    except ValueError:
        shapes = ", ".join(f"{w} {a.shape}" for w, a in zip(("pose", *_NAMES), (x, *arrays)))
        raise ShapeError(f"{shapes} do not broadcast") from None
    raise_first(
        ~mech.in_domain(out[0]),
        out[0].shape[:-1],
        lambda idx: (
            f"pose {np.round(out[0][idx], 6).tolist()} is outside {mech.name}'s domain (no IK)"
        ),
    )
    return tuple(out)


_NAMES = ("rate", "acceleration")


def _state(mech: Mechanism, x: Array, v: Array, mass: MassModel) -> State:
    """:func:`state` without the checks (also on the symbols of a recorded program)."""
    bodies = mech.bodies(jet.variable(x, v))
    groups = tuple((g, mass.body(g.kind), motion(g, mass.body(g.kind))) for g in bodies.groups)
    return State(x, v, bodies, mass, groups)


def _loads(st: State, xddot: Array) -> list[tuple[jet.Jet, jet.Spin, Array, Array]]:
    """Per group: centre jet, spin, and the inertial-minus-gravity force and moment (..., c, 3)."""
    g = np.asarray(st.mass.gravity)
    out = []
    for _, body, m in st.groups:
        acc = m.centre.acceleration(xddot)
        alpha = m.spin.acceleration(xddot)
        omega = m.spin.rate
        moment = m.inertia_times(body, alpha) + jet.vcross(omega, m.inertia_times(body, omega))
        out.append((m.centre, m.spin, body.mass * (acc - g), moment))
    return out


def generalized_forces(st: State, xddot: ArrayLike, wrench: ArrayLike | None = None) -> Array:
    """``Q`` (..., n): the load of every body (inertia and gravity, minus an external ``wrench``
    (..., 6) = force and moment about the platform's centre of mass, world axes) as a
    generalised force on the pose coordinates."""
    w = None if wrench is None else as_batch(wrench, 6, "wrench")
    return _generalized(st, jet.numeric(xddot), w)


def _generalized(st: State, xdd: Array, w: Array | None) -> Array:
    n = st.joints.n
    q = 0.0
    for centre, spin, force, moment in _loads(st, xdd):
        q = q + _project(centre.tangents[:n], force) + _project(spin.tangents[:n], moment)
    if w is not None:
        p = st.platform()
        q = (
            q
            - _project(p.centre.tangents[:n], w[..., None, :3])
            - _project(p.spin.tangents[:n], w[..., None, 3:])
        )
    return np.moveaxis(q, 0, -1)


def _project(tangents: Array, load: Array) -> Array:
    """``sum over bodies and axes of tangents[k] . load`` -> (n, ...)."""
    return np.sum(jet.vdot(tangents, load), axis=-1)


def mass_matrix(st: State) -> Array:
    """``M = sum_b m_b J_b^T J_b + W_b^T I_b W_b`` (..., n, n) in pose coordinates (symmetric: the
    upper triangle computed, the lower one its mirror)."""
    n = st.joints.n
    rows: list = [0.0] * n  # rows[k]: M[k, k:] (n - k, ...)
    for _, body, m in st.groups:
        jc, jw = m.centre.tangents[:n], m.spin.tangents[:n]  # (n, ..., c, 3)
        i_jw = m.inertia_times(body, jw)
        for k in range(n):
            upper = body.mass * jet.vdot(jc[k], jc[k:]) + jet.vdot(jw[k], i_jw[k:])
            rows[k] = rows[k] + np.sum(upper, axis=-1)
    full = np.stack([np.stack([rows[min(k, j)][abs(j - k)] for j in range(n)]) for k in range(n)])
    return np.moveaxis(full, (0, 1), (-2, -1))  # (n, n, ...) -> (..., n, n)


def energy(st: State) -> tuple[Array, Array]:
    """Kinetic and potential energy (J) of all moving bodies, each of the batch shape."""
    g = np.asarray(st.mass.gravity)
    kinetic, potential = 0.0, 0.0
    for _, body, m in st.groups:
        v, omega = m.centre.rate, m.spin.rate
        rot = jet.vdot(omega, m.inertia_times(body, omega))
        kinetic = kinetic + 0.5 * np.sum(body.mass * jet.vdot(v, v) + rot, axis=-1)
        potential = potential - body.mass * np.sum(jet.vdot(m.centre.value, g), axis=-1)
    return kinetic, potential


# ---------------------------------------------------------------------------------------- forces
@dataclass(frozen=True)
class InverseDynamics:
    """Actuator forces along a trajectory and what they rest on (batch shape ``(...)``).

    ``force`` (..., m): along each joint (N for a length, N m for an angle), the minimum-norm
    solution when the drive is redundant; ``joint_rate``, ``joint_acceleration`` (..., m);
    ``generalized`` ``Q`` (..., n); ``jacobian`` ``J`` (..., m, n); ``condition`` cond(J) (1-norm
    estimate); ``balance`` ``|J^T f - Q| / |Q|``; ``singular`` and ``unbalanced`` flag samples
    (their forces are NaN: never a silent number).
    """

    force: Array
    joint_rate: Array
    joint_acceleration: Array
    generalized: Array
    jacobian: Array
    condition: Array
    balance: Array
    singular: Array
    unbalanced: Array

    @property
    def power(self) -> Array:
        """Actuator power ``f . qdot`` (W)."""
        return np.sum(self.force * self.joint_rate, axis=-1)

    @property
    def redundancy(self) -> int:
        """``m - n``: how many independent internal force patterns the drives can add."""
        return max(self.jacobian.shape[-2] - self.jacobian.shape[-1], 0)

    def null_space(self) -> Array:
        """Orthonormal basis (..., m, m - rank) of the internal forces ``J^T f = 0``: adding any
        combination to :attr:`force` balances the same load (empty for a non-redundant drive)."""
        u, s, _ = np.linalg.svd(self.jacobian, full_matrices=True)
        rank = self.jacobian.shape[-1]
        return u[..., rank:]


def _inverse(g: Array) -> tuple[Array, Array]:
    """Batched inverse and 1-norm condition number; a numerically singular matrix gets a
    pseudo-inverse and condition inf (no exception mid-batch)."""
    try:
        inv = np.linalg.inv(g)
    except np.linalg.LinAlgError:
        inv = np.linalg.pinv(g)
        s = np.linalg.svd(g, compute_uv=False)
        cond = np.where(
            s[..., -1] > 0, s[..., 0] / np.where(s[..., -1] > 0, s[..., -1], 1.0), np.inf
        )
        return inv, cond
    norm1 = lambda a: np.max(np.sum(np.abs(a), axis=-2), axis=-1)  # noqa: E731
    with np.errstate(all="ignore"):
        cond = norm1(g) * norm1(inv)
    return inv, np.where(np.isfinite(cond), cond, np.inf)


def solve_forces(jacobian: ArrayLike, load: ArrayLike) -> tuple[Array, Array, Array]:
    """``f`` with ``J^T f = Q`` (minimum norm when ``m > n``, least squares when ``m < n``), the
    condition number of ``J`` and the relative residual ``|J^T f - Q| / |Q|``: compiled, sample
    by sample (:func:`parakin.dynamics._kernels.forces`); samples where an elimination meets a
    zero pivot go through numpy's pseudo-inverse (all of them without numba)."""
    j = np.asarray(jacobian, dtype=float)
    q = np.asarray(load, dtype=float)
    if not available():
        return _solve_numpy(j, q)
    from parakin.dynamics._kernels import forces

    m, n = j.shape[-2:]
    batch = j.shape[:-2]
    if q.shape[:-1] != batch:
        batch = np.broadcast_shapes(batch, q.shape[:-1])
        j, q = np.broadcast_to(j, batch + (m, n)), np.broadcast_to(q, batch + (n,))
    jf = np.ascontiguousarray(j.reshape(-1, m, n))
    qf = np.ascontiguousarray(q.reshape(-1, n))
    f, cond, residual = np.empty((len(jf), m)), np.empty(len(jf)), np.empty(len(jf))
    ok = np.empty(len(jf), dtype=bool)
    forces(jf, qf, f, cond, residual, ok)
    if not ok.all():
        f[~ok], cond[~ok], residual[~ok] = _solve_numpy(jf[~ok], qf[~ok])
    return f.reshape(batch + (m,)), cond.reshape(batch), residual.reshape(batch)


def _solve_numpy(j: Array, q: Array) -> tuple[Array, Array, Array]:
    """:func:`solve_forces` in numpy (batched inverse or pseudo-inverse)."""
    m, n = j.shape[-2:]
    jt = np.swapaxes(j, -1, -2)
    if m == n:
        inv, cond = _inverse(j)
        f = np.sum(np.swapaxes(inv, -1, -2) * q[..., None, :], axis=-1)
    elif m > n:
        inv, cond = _inverse(jt @ j)
        f = np.sum(j * np.sum(inv * q[..., None, :], axis=-1)[..., None, :], axis=-1)
        cond = np.sqrt(cond)
    else:
        inv, cond = _inverse(j @ jt)
        f = np.sum(inv * np.sum(j * q[..., None, :], axis=-1)[..., None, :], axis=-1)
        cond = np.sqrt(cond)
    residual = np.sum(jt * f[..., None, :], axis=-1) - q
    scale = np.maximum(np.linalg.norm(q, axis=-1), 1e-300)
    return f, cond, np.linalg.norm(residual, axis=-1) / scale


def inverse_dynamics(
    mech: Mechanism,
    pose: ArrayLike,
    rate: ArrayLike,
    acceleration: ArrayLike,
    *,
    mass: MassModel | None = None,
    wrench: ArrayLike | None = None,
    active: ArrayLike | None = None,
    on_singular: str = "raise",
) -> InverseDynamics:
    """Actuator forces (..., m) that move ``mech`` along the trajectory samples ``pose``,
    ``rate``, ``acceleration`` (each (..., n), broadcast), by virtual work (module docstring).

    ``mass``: the mass model (default :meth:`Mechanism.mass_model`); ``wrench`` (..., 6): an
    external force and moment on the platform (about its centre of mass, world axes);
    ``active``: indices of the driven joints (the others are passive: zero force), default all.
    ``on_singular="raise"`` (default): a sample where cond(J) > :data:`SINGULAR_CONDITION`, or
    whose load the drives cannot balance (residual > :data:`BALANCE_TOL`), raises one line
    naming it; ``"flag"``: such samples get NaN forces and their flags set.
    """
    if on_singular not in ("raise", "flag"):
        raise ValueError(f"on_singular = {on_singular!r}: use 'raise' or 'flag'")
    x, v, a = _checked(mech, pose, rate, acceleration)
    w = np.zeros(6) if wrench is None else as_batch(wrench, 6, "wrench")
    terms = compiled(_inverse_terms, mech, mass, ("pose", "rate", "acceleration", "wrench"))
    terms = terms(x, v, a, w)
    jac, load = terms["jacobian"], terms["load"]
    picked = _active(active, jac.shape[-2])
    f_active, cond, balance = solve_forces(jac[..., picked, :], load)
    force = np.zeros(jac.shape[:-1])
    force[..., picked] = f_active
    return _flagged(terms, force, cond, balance, on_singular)


def _inverse_terms(mech: Mechanism, mass: MassModel):
    """The numpy function of (pose, rate, acceleration, wrench) that inverse dynamics needs:
    the load ``Q``, the Jacobian ``J`` and the joint rates and accelerations."""

    def terms(x: Array, v: Array, a: Array, w: Array) -> dict[str, Array]:
        st = _state(mech, x, v, mass)
        joints = st.joints
        return {
            "load": _generalized(st, a, w),
            "jacobian": joints.jacobian,
            "joint_rate": joints.rate,
            "joint_acceleration": joints.acceleration(a),
        }

    return terms


# ---------------------------------------------------------------------------------------- programs
#: recorded programs (or the numpy functions that could not be recorded), by what they compute,
#: the mechanism's class and parameters and the mass model; a few dozen at most
_PROGRAMS: dict[tuple, Callable] = {}
_PROGRAMS_LOCK = threading.Lock()


def compiled(
    build: Callable, mech: Mechanism, mass: MassModel | None, arrays: Sequence[str]
) -> Callable:
    """The numpy function ``build(mech, mass)`` of the ``arrays`` named (of :func:`probe`)
    recorded as a program (:mod:`parakin.dynamics.program`: the same arithmetic, compiled), or
    the function itself where it cannot be recorded. ``mass``: the mass model, ``None`` for the
    mechanism's own (:meth:`Mechanism.mass_model`, a function of its parameters). Cached per
    mechanism class, parameters and mass model."""
    if not available():
        return build(mech, _mass_model(mech, mass))
    try:
        key = (build, type(mech), pickle.dumps(mech.parameters()), pickle.dumps(mass))
    except Exception:  # parameters that do not pickle: no cache, no program
        return build(mech, _mass_model(mech, mass))
    fn = _PROGRAMS.get(key)
    if fn is not None:
        return fn
    with _PROGRAMS_LOCK:
        fn = _PROGRAMS.get(key)
        if fn is None:
            terms = build(mech, _mass_model(mech, mass))
            state = probe(mech)
            fn = record(terms, [state[name] for name in arrays]) or terms
            if len(_PROGRAMS) >= 64:
                _PROGRAMS.pop(next(iter(_PROGRAMS)))
            _PROGRAMS[key] = fn
    return fn


def probe(mech: Mechanism) -> dict[str, Array]:
    """A state that every recording is checked on: :meth:`Mechanism.home`, a rate and an
    acceleration of every coordinate (scaled to :meth:`Mechanism.pose_bounds`), and a wrench."""
    lo, hi = mech.pose_bounds()
    span = 0.5 * (np.asarray(hi, dtype=float) - np.asarray(lo, dtype=float))
    k = np.arange(mech.n_pose)
    return {
        "pose": np.asarray(mech.home(), dtype=float),
        "rate": 0.1 * span * np.cos(k + 1.0),
        "acceleration": span * np.sin(k + 2.0),
        "wrench": np.array([1.0, -2.0, 3.0, 0.1, -0.2, 0.3]),
    }


def _active(active: ArrayLike | None, m: int) -> Array:
    if active is None:
        return np.arange(m)
    idx = np.unique(np.asarray(active, dtype=int).ravel())
    if idx.size == 0 or idx.min() < 0 or idx.max() >= m:
        raise ValueError(
            f"active = {np.asarray(active).tolist()} must list joints among 0..{m - 1}"
        )
    return idx


def _flagged(terms, force, cond, balance, on_singular) -> InverseDynamics:
    singular = ~(cond <= SINGULAR_CONDITION)
    unbalanced = ~(balance <= BALANCE_TOL) & ~singular
    batch = cond.shape
    if on_singular == "raise" and np.any(singular):
        raise SingularityError(
            f"the actuator Jacobian is singular along the trajectory: cond(J) = "
            f"{cond[singular].flat[0]:.3g} > {SINGULAR_CONDITION:g}{describe_first(singular, batch)}"
        )
    if on_singular == "raise" and np.any(unbalanced):
        raise SingularityError(
            f"the drives cannot balance the load: |J^T f - Q| / |Q| = "
            f"{balance[unbalanced].flat[0]:.3g} > {BALANCE_TOL:g}{describe_first(unbalanced, batch)}"
        )
    bad = singular | unbalanced
    return InverseDynamics(
        force=np.where(bad[..., None], np.nan, force),
        joint_rate=terms["joint_rate"],
        joint_acceleration=terms["joint_acceleration"],
        generalized=terms["load"],
        jacobian=terms["jacobian"],
        condition=cond,
        balance=balance,
        singular=singular,
        unbalanced=unbalanced,
    )
