"""Forward dynamics of any mechanism that declares its bodies, and a simulator.

The equations of motion in pose coordinates come from the same virtual-work terms as the inverse
dynamics (:mod:`parakin.dynamics.inverse`): ``M(x) xddot + h(x, xdot) = J^T f (+ external)``, with
``M`` the mass matrix and ``h = Q(xddot = 0)`` the velocity-product and gravity terms, so
:func:`forward_dynamics` is one batched linear solve per sample.

:func:`simulate` integrates them with the classical fourth-order Runge-Kutta method at a fixed
step. Its state is the pose and its rate, which place every body (so the closed loops hold by
construction), and also the joint coordinates and rates, integrated through their own equation
``qddot = J xddot + b`` as an encoder would read them: the two descriptions of one machine agree
only while the integration is exact. After every step the joints are projected back onto the
loop-closure manifold (``q = ik(x)``, ``qdot = J xdot``: coordinate projection, the dependent
coordinates recomputed from the independent ones; Wehage & Haug, J. Mech. Des. 104(1), 1982), and
the size of the correction, the joint-space drift one step produced, is reported
(``drift``, ``rate_drift``); ``stabilise=False`` skips the projection, so that the drift
accumulates and shows what the projection removes.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from parakin.dynamics.inverse import (
    SINGULAR_CONDITION,
    _checked,
    _generalized,
    _state,
    compiled,
    inverse_dynamics,
    mass_matrix,
    solve_forces,
)
from parakin.dynamics.model import MassModel
from parakin.dynamics.program import Program, available
from parakin.errors import SingularityError, UnreachableError
from parakin.mechanisms.base import Array, Mechanism, as_batch, describe_first

__all__ = [
    "Equations",
    "equations",
    "Force",
    "forward_dynamics",
    "Simulation",
    "simulate",
    "feedforward",
    "computed_torque",
]


@dataclass(frozen=True, eq=False)
class Equations:
    """The equations of motion at a batch of states (``pose``, ``rate``, each (..., n)), in pose
    coordinates: ``M xddot + h = J^T f + P^T w`` for actuator forces ``f`` (..., m) and an
    external wrench ``w`` (..., 6) on the platform.

    ``mass_matrix`` ``M`` (..., n, n); ``bias`` ``h`` (..., n): the load at ``xddot = 0``
    (velocity products and gravity); ``jacobian`` ``J = dq/dx`` (..., m, n); ``platform`` ``P``
    (..., 6, n): the Jacobians of the platform's centre velocity and angular velocity; the joints
    ``joints``, ``joint_rate`` and ``joint_bias`` (..., m): ``qddot = J xddot + joint_bias``.
    """

    pose: Array
    rate: Array
    joints: Array
    joint_rate: Array
    joint_bias: Array
    jacobian: Array
    mass_matrix: Array
    bias: Array
    platform: Array

    def load(self, xddot: ArrayLike, wrench: ArrayLike | None = None) -> Array:
        """``Q = M xddot + h - P^T w`` (..., n): what the drives must balance, ``J^T f = Q``
        (:func:`parakin.dynamics.inverse.generalized_forces` of the same state)."""
        q = _times(self.mass_matrix, np.asarray(xddot, dtype=float)) + self.bias
        return q if wrench is None else q - self._wrench(wrench)

    def joint_acceleration(self, xddot: ArrayLike) -> Array:
        """``qddot = J xddot + joint_bias`` (..., m)."""
        return _times(self.jacobian, np.asarray(xddot, dtype=float)) + self.joint_bias

    def _wrench(self, wrench: ArrayLike) -> Array:
        """``P^T w``: the generalised force of an external wrench on the platform."""
        return _times(np.swapaxes(self.platform, -1, -2), as_batch(wrench, 6, "wrench"))


def _times(matrix: Array, vector: Array) -> Array:
    """Batched matrix times vector."""
    return (matrix @ vector[..., None])[..., 0]


#: a force law ``force(t, equations) -> (..., m)``: the actuator forces at time ``t`` given the
#: :class:`Equations` (pose, rate, joints, Jacobian, mass matrix, ...) of the current state
Force = Callable[[float, Equations], ArrayLike]


def _motion_terms(mech: Mechanism, mass: MassModel):
    """The numpy function of (pose, rate) that gives every array of :class:`Equations`."""

    def terms(x: Array, v: Array) -> dict[str, Array]:
        st = _state(mech, x, v, mass)
        joints, platform = st.joints, st.platform()
        return {
            "joints": joints.value,
            "joint_rate": joints.rate,
            "joint_bias": joints.bias,
            "jacobian": joints.jacobian,
            "mass_matrix": mass_matrix(st),
            "bias": _generalized(st, np.zeros(np.shape(x)), None),
            "platform": np.concatenate(
                [platform.centre.jacobian[..., 0, :, :], platform.spin.jacobian[..., 0, :, :]],
                axis=-2,
            ),
        }

    return terms


def equations(
    mech: Mechanism, pose: ArrayLike, rate: ArrayLike, *, mass: MassModel | None = None
) -> Equations:
    """The :class:`Equations` of ``mech`` at poses (..., n) moving at ``rate`` (..., n), from its
    bodies (:meth:`Mechanism.bodies`, recorded once as a compiled program); raises
    UnreachableError outside the mechanism's domain."""
    x, v = _checked(mech, pose, rate)
    return Equations(x, v, **compiled(_motion_terms, mech, mass, ("pose", "rate"))(x, v))


def _accelerations(eq: Equations, force: ArrayLike, wrench, active) -> Array:
    """Pose accelerations ``M^-1 (J^T f - h + P^T w)`` under actuator ``force`` (compiled, sample
    by sample: :func:`parakin.dynamics._kernels.accelerations`; numpy without numba)."""
    m, n = eq.jacobian.shape[-2:]
    f = as_batch(force, m, "force")
    if active is not None:
        passive = np.setdiff1d(np.arange(m), np.asarray(active, dtype=int))
        f = f.copy()
        f[..., passive] = 0.0
    batch = eq.bias.shape[:-1]
    extra = np.zeros(batch + (n,)) if wrench is None else eq._wrench(wrench)
    if f.shape[:-1] != batch or extra.shape[:-1] != batch:
        batch = np.broadcast_shapes(batch, f.shape[:-1], extra.shape[:-1])
    xdd, cond = np.empty(batch + (n,)), np.empty(batch)
    if available():
        from parakin.dynamics._kernels import accelerations

        accelerations(
            _rows(eq.mass_matrix, batch, (n, n)),
            _rows(eq.jacobian, batch, (m, n)),
            _rows(eq.bias, batch, (n,)),
            _rows(f, batch, (m,)),
            _rows(extra, batch, (n,)),
            xdd.reshape(-1, n),
            cond.reshape(-1),
        )
    else:
        rhs = np.sum(eq.jacobian * f[..., :, None], axis=-2) - eq.bias + extra
        cond[...] = np.linalg.cond(np.broadcast_to(eq.mass_matrix, batch + (n, n)))
        if np.all(cond < SINGULAR_CONDITION):
            xdd[...] = np.linalg.solve(eq.mass_matrix, rhs[..., None])[..., 0]
    bad = ~(cond < SINGULAR_CONDITION)
    if bad.any():
        raise SingularityError(
            f"the mass matrix in pose coordinates is singular (cond {cond[bad].flat[0]:.3g}): the "
            f"pose coordinates degenerate here{describe_first(bad, cond.shape)}"
        )
    return xdd


def _rows(a: Array, batch: tuple[int, ...], core: tuple[int, ...]) -> Array:
    """``a`` broadcast to ``batch + core``, as a contiguous array (samples, *core)."""
    if a.shape != batch + core:
        a = np.broadcast_to(a, batch + core)
    return np.ascontiguousarray(a).reshape((-1, *core))


def forward_dynamics(
    mech: Mechanism,
    pose: ArrayLike,
    rate: ArrayLike,
    force: ArrayLike,
    *,
    mass: MassModel | None = None,
    wrench: ArrayLike | None = None,
    active: ArrayLike | None = None,
) -> Array:
    """Pose accelerations (..., n) of ``mech`` at ``pose``, ``rate`` under actuator ``force``
    (..., m) (and an external ``wrench`` (..., 6) on the platform; joints not in ``active`` exert
    nothing): ``xddot = M^-1 (J^T f + P^T w - h)``."""
    return _accelerations(equations(mech, pose, rate, mass=mass), force, wrench, active)


@dataclass(frozen=True)
class Simulation:
    """A simulated motion at the step times ``t`` (k,): ``pose``, ``rate`` (k, ..., n), the
    joints ``joints``, ``joint_rate`` (k, ..., m) and the largest joint-space drift each step
    produced before the projection, ``drift`` (k, ...) (joint units, m for lengths) and
    ``rate_drift`` (k, ...)."""

    t: Array
    pose: Array
    rate: Array
    joints: Array
    joint_rate: Array
    drift: Array
    rate_drift: Array
    stabilised: bool

    @property
    def max_drift(self) -> float:
        return float(np.max(self.drift))


class _System:
    """The simulated system as one state vector ``y = (x, xdot, q, qdot)`` (..., 2n + 2m) and its
    time derivative (the RK4 right-hand side)."""

    def __init__(self, mech, mass, force, wrench, active) -> None:
        self.mech, self.force, self.wrench, self.active = mech, force, wrench, active
        self.terms = compiled(_motion_terms, mech, mass, ("pose", "rate"))
        self.n = mech.n_pose

    def equations(self, y: Array, domain: bool = False) -> Equations:
        """The equations at ``y``; raises where the joints are not finite (a pose outside the
        domain, where the IK has no real value) or, with ``domain``, where
        :meth:`Mechanism.in_domain` refuses the pose."""
        n = self.n
        x, v = y[..., :n], y[..., n : 2 * n]
        if isinstance(self.terms, Program):  # the state's leading columns are its inputs
            out = self.terms.run(y[..., : 2 * n].reshape(-1, 2 * n))
            eq = Equations(x, v, **self.terms.unpack(out, y.shape[:-1]))
        else:
            eq = Equations(x, v, **self.terms(x, v))
        if not np.isfinite(eq.joints).all() or (domain and not self.mech.in_domain(x).all()):
            _checked(self.mech, x, v)  # raises, naming the pose
            bad = ~np.all(np.isfinite(eq.joints), axis=-1)
            raise UnreachableError(
                f"{self.mech.name}'s joints are not finite at pose "
                f"{np.round(x[bad][0], 6).tolist()}{describe_first(bad, bad.shape)}"
            )
        return eq

    def derivative(self, t: float, y: Array, eq: Equations | None = None) -> Array:
        eq = self.equations(y) if eq is None else eq
        xdd = _accelerations(eq, self.force(t, eq), self.wrench, self.active)
        m = eq.joints.shape[-1]
        return np.concatenate(
            [eq.rate, xdd, y[..., y.shape[-1] - m :], eq.joint_acceleration(xdd)], axis=-1
        )


def _rk4_step(f: Callable, t: float, y: Array, dt: float, eq: Equations) -> Array:
    """One classical Runge-Kutta step; ``eq``: the equations at ``y`` (already evaluated)."""
    k1 = f(t, y, eq)
    k2 = f(t + 0.5 * dt, y + 0.5 * dt * k1)
    k3 = f(t + 0.5 * dt, y + 0.5 * dt * k2)
    k4 = f(t + dt, y + dt * k3)
    return y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


def simulate(
    mech: Mechanism,
    pose: ArrayLike,
    rate: ArrayLike,
    force: Force,
    t_end: float,
    dt: float = 1e-3,
    *,
    mass: MassModel | None = None,
    wrench: ArrayLike | None = None,
    active: ArrayLike | None = None,
    stabilise: bool = True,
) -> Simulation:
    """Integrate ``mech`` from ``pose``, ``rate`` (each (..., n): a batch of motions at once)
    under actuator forces ``force(t, equations) -> (..., m)`` for ``t_end`` seconds in RK4 steps
    of ``dt`` (module docstring). Raises where a pose leaves the domain or the mass matrix
    degenerates."""
    if not (np.isfinite(t_end) and t_end > 0 and np.isfinite(dt) and 0 < dt <= t_end):
        raise ValueError(f"t_end = {t_end!r} s and dt = {dt!r} s must satisfy 0 < dt <= t_end")
    x, v = _checked(mech, pose, rate)
    system = _System(mech, mass, force, wrench, active)
    n = mech.n_pose
    eq = system.equations(np.concatenate([x, v], axis=-1), domain=True)
    y = np.concatenate([x, v, eq.joints, eq.joint_rate], axis=-1)
    steps = int(round(t_end / dt))
    history = np.empty((steps + 1, *y.shape))
    drift, rate_drift = np.zeros((2, steps + 1, *y.shape[:-1]))
    history[0] = y
    m = eq.joints.shape[-1]
    for k in range(steps):
        y = _rk4_step(system.derivative, k * dt, y, dt, eq)
        eq = system.equations(y, domain=True)
        drift[k + 1] = np.max(np.abs(y[..., 2 * n : 2 * n + m] - eq.joints), axis=-1)
        rate_drift[k + 1] = np.max(np.abs(y[..., 2 * n + m :] - eq.joint_rate), axis=-1)
        if stabilise:
            y = np.concatenate([y[..., : 2 * n], eq.joints, eq.joint_rate], axis=-1)
        history[k + 1] = y
    parts = np.split(history, [n, 2 * n, 2 * n + m], axis=-1)
    return Simulation(
        np.arange(steps + 1) * dt, *parts, drift=drift, rate_drift=rate_drift, stabilised=stabilise
    )


def feedforward(
    mech: Mechanism, trajectory, t_end: float, dt: float, *, mass: MassModel | None = None
) -> Force:
    """The inverse-dynamics forces of ``trajectory`` at every time an RK4 run of step ``dt`` asks
    for (the step times and their midpoints), computed in one batch; the returned
    ``force(t, state)`` looks them up by time (open-loop feedforward)."""
    half = 0.5 * dt
    grid = np.arange(int(round(t_end / half)) + 1) * half
    forces = inverse_dynamics(mech, *trajectory.state(grid), mass=mass).force

    def force(t: float, eq: Equations) -> Array:
        k = int(round(t / half))
        if not (0 <= k < len(grid) and abs(grid[k] - t) <= 1e-9 * max(half, abs(t))):
            raise ValueError(
                f"feedforward has no force at t = {t!r} s (step {dt} s, end {t_end} s)"
            )
        return forces[k]

    return force


def computed_torque(
    trajectory, frequency: float, damping: float = 1.0, active: ArrayLike | None = None
) -> Force:
    """A computed-torque controller of the trajectory: the forces that give the pose the
    acceleration ``xddot_d + w^2 (x_d - x) + 2 z w (xdot_d - xdot)`` (``w = 2 pi frequency``,
    ``z = damping``) by the inverse dynamics of the current state, so that with an exact model the
    pose error obeys ``e'' + 2 z w e' + w^2 e = 0`` (Craig, *Introduction to Robotics*, ch. 10)."""
    w = 2 * np.pi * frequency
    if not (np.isfinite(w) and w > 0 and np.isfinite(damping) and damping >= 0):
        raise ValueError(f"frequency = {frequency!r} Hz must be > 0 and damping = {damping!r} >= 0")

    def force(t: float, eq: Equations) -> Array:
        xd, vd, ad = trajectory.state(t)
        command = ad + w * w * (xd - eq.pose) + 2 * damping * w * (vd - eq.rate)
        jac, load = eq.jacobian, eq.load(command)
        if active is None:
            return solve_forces(jac, load)[0]
        picked = np.asarray(active, dtype=int)
        f = np.zeros(jac.shape[:-1])
        f[..., picked] = solve_forces(jac[..., picked, :], load)[0]
        return f

    return force
