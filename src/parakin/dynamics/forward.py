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
    State,
    generalized_forces,
    inverse_dynamics,
    mass_matrix,
    solve_forces,
    state,
)
from parakin.dynamics.model import MassModel
from parakin.errors import SingularityError
from parakin.mechanisms.base import Array, Mechanism, as_batch, describe_first

__all__ = ["Force", "forward_dynamics", "Simulation", "simulate", "feedforward", "computed_torque"]

#: a force law ``force(t, state) -> (..., m)``: the actuator forces at time ``t`` given the
#: :class:`~parakin.dynamics.inverse.State` (pose, rate, joints and every body) of the system
Force = Callable[[float, State], ArrayLike]


def _accelerations(mech, st, force, wrench, active) -> tuple[Array, Array]:
    """Pose and joint accelerations of a :class:`State` under actuator ``force``."""
    jac = st.jacobian
    f = as_batch(force, jac.shape[-2], "force")
    if active is not None:
        passive = np.setdiff1d(np.arange(jac.shape[-2]), np.asarray(active, dtype=int))
        f = f.copy()
        f[..., passive] = 0.0
    h = generalized_forces(st, np.zeros(st.joints.value.shape[:-1] + (mech.n_pose,)), wrench)
    m = mass_matrix(st)
    rhs = np.sum(jac * f[..., :, None], axis=-2) - h
    cond = np.linalg.cond(m)
    bad = ~(cond < SINGULAR_CONDITION)
    if np.any(bad):
        raise SingularityError(
            f"the mass matrix in pose coordinates is singular (cond {cond[bad].flat[0]:.3g}): the "
            f"pose coordinates degenerate here{describe_first(bad, cond.shape)}"
        )
    xdd = np.linalg.solve(m, rhs[..., None])[..., 0]
    return xdd, st.joints.acceleration(xdd)


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
    nothing): ``xddot = M^-1 (J^T f - h)``."""
    st = state(mech, pose, rate, mass)
    return _accelerations(mech, st, force, wrench, active)[0]


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


def _derivative(mech, mass, force, wrench, active) -> Callable:
    def f(t: float, y: tuple[Array, Array, Array, Array], st: State | None = None) -> tuple:
        x, v, _, qd = y
        st = state(mech, x, v, mass) if st is None else st
        xdd, qdd = _accelerations(mech, st, force(t, st), wrench, active)
        return v, xdd, qd, qdd

    return f


def _rk4_step(f: Callable, t: float, y: tuple, dt: float, st: State) -> tuple:
    """One classical Runge-Kutta step; ``st``: the state at ``y`` (already evaluated)."""
    k1 = f(t, y, st)
    k2 = f(t + 0.5 * dt, tuple(a + 0.5 * dt * b for a, b in zip(y, k1)))
    k3 = f(t + 0.5 * dt, tuple(a + 0.5 * dt * b for a, b in zip(y, k2)))
    k4 = f(t + dt, tuple(a + dt * b for a, b in zip(y, k3)))
    return tuple(a + dt / 6 * (b + 2 * c + 2 * d + e) for a, b, c, d, e in zip(y, k1, k2, k3, k4))


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
    under actuator forces ``force(t, state) -> (..., m)`` for ``t_end`` seconds in RK4 steps
    of ``dt`` (module docstring). Raises where a pose leaves the domain or the mass matrix
    degenerates."""
    if not (np.isfinite(t_end) and t_end > 0 and np.isfinite(dt) and 0 < dt <= t_end):
        raise ValueError(f"t_end = {t_end!r} s and dt = {dt!r} s must satisfy 0 < dt <= t_end")
    x = as_batch(pose, mech.n_pose, "pose").copy()
    v = np.broadcast_to(as_batch(rate, mech.n_pose, "rate"), x.shape).copy()
    mass = mech.mass_model() if mass is None else mass
    st = state(mech, x, v, mass)
    y = (x, v, st.joints.value, st.joints.rate)
    f = _derivative(mech, mass, force, wrench, active)
    steps = int(round(t_end / dt))
    out = {k: [a] for k, a in zip(("pose", "rate", "joints", "joint_rate"), y)}
    drift, rate_drift = [np.zeros(x.shape[:-1])], [np.zeros(x.shape[:-1])]
    for k in range(steps):
        y = _rk4_step(f, k * dt, y, dt, st)
        st = state(mech, y[0], y[1], mass)
        drift.append(np.max(np.abs(y[2] - st.joints.value), axis=-1))
        rate_drift.append(np.max(np.abs(y[3] - st.joints.rate), axis=-1))
        if stabilise:
            y = (y[0], y[1], st.joints.value, st.joints.rate)
        for key, a in zip(out, y):
            out[key].append(a)
    stacked = {k: np.stack(a) for k, a in out.items()}
    return Simulation(
        np.arange(steps + 1) * dt,
        **stacked,
        drift=np.stack(drift),
        rate_drift=np.stack(rate_drift),
        stabilised=stabilise,
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

    def force(t: float, st: State) -> Array:
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

    def force(t: float, st: State) -> Array:
        xd, vd, ad = trajectory.state(t)
        command = ad + w * w * (xd - st.pose) + 2 * damping * w * (vd - st.rate)
        jac = st.jacobian
        picked = np.arange(jac.shape[-2]) if active is None else np.asarray(active, dtype=int)
        f = np.zeros(jac.shape[:-1])
        f[..., picked] = solve_forces(jac[..., picked, :], generalized_forces(st, command))[0]
        return f

    return force
