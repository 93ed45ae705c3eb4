"""Velocity, acceleration and inverse dynamics of the 3-P(4S) (Zhao et al. 2017, §1.2-2.4).

Everything is batched over leading axes: a pose, velocity or acceleration array has shape
``(..., 3)`` (e.g. ``(n_samples, 3)`` along a trajectory), limb quantities get a limb axis
``(..., 3 limbs, ...)``; no Python loop runs over samples.

Notation (paper Fig. 4, eqs 6-15): ``p, v, a`` platform position, velocity, acceleration;
``q_i`` strokes; ``m_i`` rail directions; ``n_i`` unit vector of the equivalent rod ``c_i d_i``
of length ``l = L``; ``nm_i = n_i . m_i``; ``P_i = I - m_i n_i^T / nm_i`` (so ``P_i v = l dn_i/dt``).

* eq (8)  ``qdot = J v``, row i of J = ``n_i^T / nm_i`` (:meth:`P3P4S.velocity_jacobian`);
* eq (9)  ``omega_i = J_omega_i v``, ``J_omega_i = (1/l) [hat(n_i) + (m_i x n_i) n_i^T / nm_i]``;
* eq (11) ``v_di = J_v_i v``, ``J_v_i = (1/2) (I + m_i n_i^T / nm_i)``;
* eq (13) ``qddot_i = J_i a + v^T H_i v`` with ``H_i = P_i^T P_i / (l nm_i)``. The paper prints
  ``H_i = P_i^T P_i / nm_i`` (no ``1/l``; dimensionally wrong, docs/zhao2017_3p4s.md#g8). Both are available
  (``h_form="corrected" | "paper"``);
* eq (14) ``a_di = J_v_i a + (1/2) m_i (v^T H_i v)``;
* eq (15) ``alpha_i = J_omega_i a + (1/l) (m_i x n_i) (v^T H_i v)``.

Inverse dynamics (eqs 16-23, by virtual power), as motor force ``f_i`` along ``+m_i``::

    f = J^-T [ m (a - g) + k sum_i J_v_i^T m_d (a_di - g)
                         + k sum_i J_omega_i^T (I_di alpha_i + omega_i x I_di omega_i) ]
        + m_e (qddot - m_i . g)

with ``k = 2`` rods per parallelogram (eq 20) and ``g = (0, 0, -9.81)``. The paper's printed
slips are options of :func:`force_terms` / :func:`inverse_dynamics`, so that each can be
quantified: ``h_form="paper"`` (eq 13 without ``1/l``), ``gravity_moment=True`` (eq 21's term
``k J_omega_di^T (r_di x m_d g)``), ``rod_inertia_factor=1`` (eq 23 drops eq 20's factor 2).
:data:`PAPER_PRINTED` selects all three.

Independent checks: :func:`energy` (kinetic + potential of every body from positions and
velocities only, no Newton-Euler map) and :func:`power_balance` (``f . qdot = dE/dt``);
:func:`ik_finite_differences` (time derivatives of the IK along a trajectory).

This module is the paper's method, kept to reproduce its equations and their slips. The dynamics
of every mechanism, this one included, is :mod:`parakin.dynamics` (virtual work over the bodies
that :meth:`P3P4S.bodies` declares, the masses of :meth:`InertialParams.mass_model`); Zhao's
Newton-Euler here is its check (tests/test_dynamics_generic.py: equal to 1e-9 relative). The
generic pieces it used to carry (the sixth-order time derivative, the power-balance record) are
:mod:`parakin.dynamics.trajectory`'s.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from parakin.dynamics.model import MassModel, RigidBody
from parakin.dynamics.trajectory import PowerBalance, time_derivative
from parakin.errors import ShapeError, SingularityError
from parakin.geometry import skew
from parakin.mechanisms.base import Array, as_batch, describe_first
from parakin.mechanisms.p3p4s import P3P4S, ZHAO2017_MASSES

__all__ = [
    "HForm",
    "InertialParams",
    "SineMotion",
    "LimbKinematics",
    "Energy",
    "PowerBalance",
    "PAPER_PRINTED",
    "drive_jacobian",
    "omega_jacobians",
    "rod_velocity_jacobians",
    "acceleration_hessians",
    "drive_accelerations",
    "rod_accelerations",
    "rod_angular_accelerations",
    "limb_kinematics",
    "force_terms",
    "inverse_dynamics",
    "energy",
    "power_balance",
    "ik_finite_differences",
    "time_derivative",
]

HForm = Literal["corrected", "paper"]

#: The three slips of the printed dynamics (docs/zhao2017_3p4s.md#g8, #g9, #g10), all at once: eq 13's H without 1/l,
#: eq 21's rod gravity-moment term, eq 23 without eq 20's factor 2 on the rod inertia.
PAPER_PRINTED: dict = {"h_form": "paper", "gravity_moment": True, "rod_inertia_factor": 1.0}

_SINGULAR_DET = 1e-10  # |det(n_1, n_2, n_3)| below this: the rods are coplanar, J is singular


# ---------------------------------------------------------------------------------------- inputs
@dataclass(frozen=True)
class InertialParams:
    """Masses and inertias of the moving bodies (SI units), paper §2.4.

    ``I_rod`` is the inertia of ONE parallelogram side rod about its centroid in its body frame
    with z along the rod (the paper's ``I_dio``); it must be axisymmetric (``I_xx == I_yy``), the
    only case in which the rod's spin about its axis is irrelevant (the paper's definition line of
    ``0R_i`` is empty, docs/zhao2017_3p4s.md#g12). ``rods_per_limb`` is eq (20)'s factor 2. ``g`` is gravity
    (not stated in the paper; docs/zhao2017_3p4s.md#g14).
    """

    m_platform: float = ZHAO2017_MASSES["m_platform"]  #: moving platform mass m (kg)
    m_slider: float = ZHAO2017_MASSES["m_slider"]  #: slider (motor mover) mass m_e per limb (kg)
    m_rod: float = ZHAO2017_MASSES["m_rod"]  #: mass m_d of ONE parallelogram side rod (kg)
    I_rod: tuple[float, float, float] = ZHAO2017_MASSES["I_rod"]  #: I_dio diagonal (kg m^2)
    g: tuple[float, float, float] = (0.0, 0.0, -9.81)  #: gravity (m/s^2)
    rods_per_limb: int = 2  #: side rods per parallelogram (eq 20)

    def __post_init__(self) -> None:
        for key in ("m_platform", "m_slider", "m_rod"):
            value = getattr(self, key)
            if not (np.isfinite(value) and value >= 0):
                raise ValueError(f"{key} = {value!r} kg must be a finite mass >= 0")
        inertia = np.asarray(self.I_rod, dtype=float)
        if inertia.shape != (3,) or not np.all(np.isfinite(inertia)) or np.any(inertia < 0):
            raise ValueError(
                f"I_rod = {self.I_rod!r} must be three finite principal inertias >= 0 (kg m^2)"
            )
        if not np.isclose(inertia[0], inertia[1], rtol=1e-12, atol=0.0):
            raise ValueError(
                f"I_rod = {self.I_rod!r}: the equivalent-rod model needs an axisymmetric rod "
                f"(I_xx == I_yy); got I_xx = {inertia[0]} and I_yy = {inertia[1]} kg m^2"
            )
        gravity = np.asarray(self.g, dtype=float)
        if gravity.shape != (3,) or not np.all(np.isfinite(gravity)):
            raise ValueError(f"g = {self.g!r} must be a finite 3-vector (m/s^2)")
        if not (isinstance(self.rods_per_limb, (int, np.integer)) and self.rods_per_limb >= 1):
            raise ValueError(f"rods_per_limb = {self.rods_per_limb!r} must be a positive integer")
        object.__setattr__(self, "I_rod", tuple(float(x) for x in inertia))
        object.__setattr__(self, "g", tuple(float(x) for x in gravity))

    @classmethod
    def zhao2017(cls) -> InertialParams:
        """The values of the paper's §2.4 (before design) with ``g = (0, 0, -9.81)``."""
        return cls()

    @property
    def gravity(self) -> Array:
        return np.asarray(self.g, dtype=float)

    @property
    def total_mass(self) -> float:
        """Moving mass: platform + 3 sliders + all side rods (kg)."""
        return self.m_platform + 3 * self.m_slider + 3 * self.rods_per_limb * self.m_rod

    def mass_model(self, mech: P3P4S) -> MassModel:
        """The same masses for :mod:`parakin.dynamics` (the bodies of :meth:`P3P4S.bodies`: a
        parallelogram has two side rods, so ``rods_per_limb`` must be 2); the platform's and the
        sliders' inertia, which cannot enter (they only translate), as :meth:`P3P4S.mass_model`."""
        if self.rods_per_limb != 2:
            raise ValueError(
                f"rods_per_limb = {self.rods_per_limb}: the bodies of P3P4S are parallelograms (2 side rods)"
            )
        default = mech.mass_model()
        return MassModel(
            {
                "platform": RigidBody(self.m_platform, default.body("platform").inertia),
                "slider": RigidBody(self.m_slider, default.body("slider").inertia),
                "rod": RigidBody(self.m_rod, self.I_rod, (0.0, 0.0, 0.5 * mech.L)),
            },
            self.g,
            "Zhao 2017 InertialParams",
        )

    def rod_inertia_world(self, n: Array) -> Array:
        """``I_di = 0R_i I_dio 0R_i^T`` for rod directions ``n`` (..., 3) -> (..., 3, 3).

        For an axisymmetric rod this is ``I_xx (I - n n^T) + I_zz n n^T`` whatever the spin of
        ``0R_i`` about ``n`` (eq 19's I_di; its definition line is empty in the paper).
        """
        i_t, _, i_a = self.I_rod
        nn = n[..., :, None] * n[..., None, :]
        return i_t * (np.eye(3) - nn) + i_a * nn


@dataclass(frozen=True)
class SineMotion:
    """The paper's motion law (§1.4, §2.4): ``x = y = A sin(omega t)``, ``z = z0``.

    Defaults: ``A = 0.001 m``, ``omega = 40 pi rad/s`` (20 Hz), ``z0 = 0.57 m`` (§2.4's
    "initial height"; §1.4 gives no z, docs/zhao2017_3p4s.md#g13). Derivatives are exact.
    """

    amplitude: float = 1e-3  #: A (m)
    omega: float = 40 * np.pi  #: angular frequency (rad/s)
    z0: float = 0.57  #: constant height (m)

    def __post_init__(self) -> None:
        if not (np.isfinite(self.amplitude) and self.amplitude >= 0):
            raise ValueError(f"amplitude = {self.amplitude!r} m must be finite and >= 0")
        if not (np.isfinite(self.omega) and self.omega > 0):
            raise ValueError(f"omega = {self.omega!r} rad/s must be finite and > 0")
        if not np.isfinite(self.z0):
            raise ValueError(f"z0 = {self.z0!r} m must be finite")

    @property
    def period(self) -> float:
        """``2 pi / omega`` (s)."""
        return 2 * np.pi / self.omega

    def _t(self, t: ArrayLike) -> Array:
        t = np.asarray(t, dtype=float)
        if not np.all(np.isfinite(t)):
            raise ValueError("time samples t must be finite")
        return t

    def _xy(self, s: Array, t: Array) -> Array:
        return np.stack([s, s, np.zeros_like(t)], axis=-1)

    def pose(self, t: ArrayLike) -> Array:
        """``(x, y, z)`` at times ``t`` (...,) -> (..., 3) in m."""
        t = self._t(t)
        p = self._xy(self.amplitude * np.sin(self.omega * t), t)
        p[..., 2] = self.z0
        return p

    def velocity(self, t: ArrayLike) -> Array:
        """``d(x, y, z)/dt`` (m/s)."""
        t = self._t(t)
        return self._xy(self.amplitude * self.omega * np.cos(self.omega * t), t)

    def acceleration(self, t: ArrayLike) -> Array:
        """``d^2(x, y, z)/dt^2`` (m/s^2)."""
        t = self._t(t)
        return self._xy(-self.amplitude * self.omega**2 * np.sin(self.omega * t), t)

    def state(self, t: ArrayLike) -> tuple[Array, Array, Array]:
        """``(pose, velocity, acceleration)`` at ``t``."""
        return self.pose(t), self.velocity(t), self.acceleration(t)


# ---------------------------------------------------------------------------------------- helpers
def _check(mech: P3P4S) -> None:
    if not isinstance(mech, P3P4S):
        raise TypeError(f"expected a P3P4S mechanism, got {type(mech).__name__}")


def _broadcast(*arrays: Array, names: tuple[str, ...]) -> tuple[Array, ...]:
    try:
        return tuple(np.broadcast_arrays(*arrays))
    except ValueError:
        shapes = ", ".join(f"{n} {a.shape}" for n, a in zip(names, arrays))
        raise ShapeError(f"shapes do not broadcast: {shapes}") from None


def _rods(mech: P3P4S, pose: Array, joints: ArrayLike | None) -> tuple[Array, Array, Array]:
    """``q`` (..., 3), ``n`` (..., 3, 3) and ``nm = n_i . m_i`` (..., 3); raises at singularities."""
    q = mech.ik(pose) if joints is None else as_batch(joints, 3, "joints")
    n = mech.rod_directions(pose, q)
    nm = np.einsum("...ij,ij->...i", n, mech.m)
    bad = np.abs(nm) < 1e-12
    if np.any(bad):
        raise SingularityError(
            "n_i . m_i = 0 (a rod perpendicular to its rail): eq (8)'s J is singular"
            f"{describe_first(np.any(bad, -1), pose.shape[:-1])}"
        )
    det = np.linalg.det(n)
    bad = np.abs(det) < _SINGULAR_DET
    if np.any(bad):
        raise SingularityError(
            f"the three rods are coplanar (|det(n_1, n_2, n_3)| = {np.abs(det[bad]).flat[0]:.3g} < "
            f"{_SINGULAR_DET:g}): J is singular and the platform is not determined by the drives"
            f"{describe_first(bad, pose.shape[:-1])}"
        )
    return q, n, nm


def _projector(mech: P3P4S, n: Array, nm: Array) -> Array:
    """``P_i = I - m_i n_i^T / nm_i`` (..., 3, 3, 3)."""
    return np.eye(3) - mech.m[:, :, None] * n[..., :, None, :] / nm[..., :, None, None]


def _validate_h_form(h_form: str) -> None:
    if h_form not in ("corrected", "paper"):
        raise ValueError(
            f"h_form = {h_form!r}: use 'corrected' (eq 13 with 1/l) or 'paper' (as printed)"
        )


# ---------------------------------------------------------------------------------------- maps
def drive_jacobian(mech: P3P4S, pose: ArrayLike, joints: ArrayLike | None = None) -> Array:
    """Eq (8): ``J`` (..., 3, 3) with ``qdot = J v``; raises SingularityError where J is singular."""
    _check(mech)
    x = as_batch(pose, 3, "pose")
    q, _, _ = _rods(mech, x, joints)
    return mech.velocity_jacobian(x, q)


def omega_jacobians(mech: P3P4S, pose: ArrayLike, joints: ArrayLike | None = None) -> Array:
    """Eq (9): ``J_omega_i = (1/l)[hat(n_i) + (m_i x n_i) n_i^T / (n_i^T m_i)]``, (..., 3, 3, 3).

    ``omega_i = J_omega_i v`` is the rod's angular velocity with no spin about its own axis.
    """
    _check(mech)
    x = as_batch(pose, 3, "pose")
    _, n, nm = _rods(mech, x, joints)
    return _omega_jacobians(mech, n, nm)


def _omega_jacobians(mech: P3P4S, n: Array, nm: Array) -> Array:
    mxn = np.cross(mech.m, n)
    return (skew(n) + mxn[..., :, None] * n[..., None, :] / nm[..., None, None]) / mech.L


def rod_velocity_jacobians(mech: P3P4S, pose: ArrayLike, joints: ArrayLike | None = None) -> Array:
    """Eq (11): ``J_v_i = (1/2)(I + m_i n_i^T / (n_i^T m_i))`` (..., 3, 3, 3); ``v_di = J_v_i v``."""
    _check(mech)
    x = as_batch(pose, 3, "pose")
    _, n, nm = _rods(mech, x, joints)
    return _rod_velocity_jacobians(mech, n, nm)


def _rod_velocity_jacobians(mech: P3P4S, n: Array, nm: Array) -> Array:
    return 0.5 * (np.eye(3) + mech.m[:, :, None] * n[..., :, None, :] / nm[..., :, None, None])


def acceleration_hessians(
    mech: P3P4S, pose: ArrayLike, joints: ArrayLike | None = None, h_form: HForm = "corrected"
) -> Array:
    """Eq (13)'s ``H_i`` (..., 3, 3, 3), ``qddot_i = J_i a + v^T H_i v``.

    ``"corrected"``: ``H_i = P_i^T P_i / (l n_i^T m_i)`` (from ``n . n = 1``: ``n . ddot(n) =
    -|dot(n)|^2`` and ``P_i v = l dot(n_i)``), units 1/m. ``"paper"``: the printed
    ``P_i^T P_i / (n_i^T m_i)``, which lacks the ``1/l`` (docs/zhao2017_3p4s.md#g8).
    """
    _check(mech)
    _validate_h_form(h_form)
    x = as_batch(pose, 3, "pose")
    _, n, nm = _rods(mech, x, joints)
    return _hessians(mech, n, nm, h_form)


def _hessians(mech: P3P4S, n: Array, nm: Array, h_form: str) -> Array:
    proj = _projector(mech, n, nm)
    scale = nm * (mech.L if h_form == "corrected" else 1.0)
    return np.einsum("...kij,...kil->...kjl", proj, proj) / scale[..., None, None]


@dataclass(frozen=True)
class LimbKinematics:
    """Every kinematic quantity of the 3-P(4S) at a batch of states (eqs 6-15), SI units.

    Shapes: ``(...)`` is the batch; limb quantities carry a limb axis of length 3 before the
    vector axis (e.g. ``omega[..., i, :]`` is rod i's angular velocity).
    """

    pose: Array  #: p (..., 3), m
    velocity: Array  #: v (..., 3), m/s
    acceleration: Array  #: a (..., 3), m/s^2
    q: Array  #: strokes (..., 3), m
    n: Array  #: rod unit vectors n_i (..., 3, 3)
    nm: Array  #: n_i . m_i (..., 3)
    J: Array  #: eq 8 (..., 3, 3), qdot = J v
    J_omega: Array  #: eq 9 (..., 3, 3, 3)
    J_v: Array  #: eq 11 (..., 3, 3, 3)
    H: Array  #: eq 13 (..., 3, 3, 3), 1/m when corrected
    vHv: Array  #: v^T H_i v (..., 3), m/s^2 when corrected
    qdot: Array  #: eq 8 (..., 3), m/s
    qddot: Array  #: eq 13 (..., 3), m/s^2
    omega: Array  #: eq 9 (..., 3, 3), rad/s
    alpha: Array  #: eq 15 (..., 3, 3), rad/s^2
    r_rod: Array  #: eq 10 rod centroids r_di (..., 3, 3), m
    v_rod: Array  #: eq 11 (..., 3, 3), m/s
    a_rod: Array  #: eq 14 (..., 3, 3), m/s^2
    h_form: str = field(default="corrected")


def limb_kinematics(
    mech: P3P4S,
    pose: ArrayLike,
    velocity: ArrayLike,
    acceleration: ArrayLike,
    *,
    joints: ArrayLike | None = None,
    h_form: HForm = "corrected",
) -> LimbKinematics:
    """All maps and rates of eqs (8)-(15) at once (one IK, one pass, batched).

    ``pose``, ``velocity``, ``acceleration`` broadcast against each other (``(..., 3)`` each).
    ``joints`` defaults to ``mech.ik(pose)``. Raises UnreachableError / SingularityError.
    """
    _check(mech)
    _validate_h_form(h_form)
    x = as_batch(pose, 3, "pose")
    v = as_batch(velocity, 3, "velocity")
    a = as_batch(acceleration, 3, "acceleration")
    x, v, a = _broadcast(x, v, a, names=("pose", "velocity", "acceleration"))
    q, n, nm = _rods(mech, x, joints if joints is None else np.broadcast_to(joints, x.shape))
    J = n / nm[..., None]  # eq 8, = mech.velocity_jacobian(x, q)
    J_omega = _omega_jacobians(mech, n, nm)
    J_v = _rod_velocity_jacobians(mech, n, nm)
    H = _hessians(mech, n, nm, h_form)
    vHv = np.einsum("...j,...kjl,...l->...k", v, H, v)
    qdot = np.einsum("...ij,...j->...i", J, v)
    qddot = np.einsum("...ij,...j->...i", J, a) + vHv  # eq 13
    omega = np.einsum("...kij,...j->...ki", J_omega, v)  # eq 9
    mxn = np.cross(mech.m, n)
    alpha = np.einsum("...kij,...j->...ki", J_omega, a) + mxn * (vHv / mech.L)[..., None]  # eq 15
    v_rod = np.einsum("...kij,...j->...ki", J_v, v)  # eq 11
    a_rod = np.einsum("...kij,...j->...ki", J_v, a) + 0.5 * mech.m * vHv[..., None]  # eq 14
    r_rod = mech.r_b * mech.e + q[..., None] * mech.m + 0.5 * mech.L * n  # eq 10
    return LimbKinematics(
        x,
        v,
        a,
        q,
        n,
        nm,
        J,
        J_omega,
        J_v,
        H,
        vHv,
        qdot,
        qddot,
        omega,
        alpha,
        r_rod,
        v_rod,
        a_rod,
        h_form,
    )


def _kinematics_field(name: str, field_name: str, doc: str) -> Callable[..., Array]:
    """A function giving one field of :func:`limb_kinematics` (``field_name``), documented ``doc``."""

    def value(
        mech: P3P4S,
        pose: ArrayLike,
        velocity: ArrayLike,
        acceleration: ArrayLike,
        *,
        h_form: HForm = "corrected",
    ) -> Array:
        return getattr(
            limb_kinematics(mech, pose, velocity, acceleration, h_form=h_form), field_name
        )

    value.__name__ = value.__qualname__ = name
    value.__doc__ = doc
    return value


drive_accelerations = _kinematics_field(
    "drive_accelerations", "qddot", "Eq (13): ``qddot = J a + v^T H v`` (..., 3) in m/s^2."
)
rod_accelerations = _kinematics_field(
    "rod_accelerations",
    "a_rod",
    "Eq (14): rod centroid accelerations ``a_di`` (..., 3 limbs, 3) in m/s^2.",
)
rod_angular_accelerations = _kinematics_field(
    "rod_angular_accelerations",
    "alpha",
    "Eq (15): rod angular accelerations ``alpha_i`` (..., 3 limbs, 3) in rad/s^2.",
)


# ---------------------------------------------------------------------------------------- dynamics
def _solve_transpose(J: Array, rhs: Array) -> Array:
    """``J^-T rhs`` batched: solve ``J^T x = rhs``."""
    return np.linalg.solve(np.swapaxes(J, -1, -2), rhs[..., None])[..., 0]


def force_terms(
    mech: P3P4S,
    params: InertialParams,
    pose: ArrayLike,
    velocity: ArrayLike,
    acceleration: ArrayLike,
    *,
    h_form: HForm = "corrected",
    gravity_moment: bool = False,
    rod_inertia_factor: float | None = None,
    kin: LimbKinematics | None = None,
) -> dict[str, Array]:
    """The motor forces of eqs (16)-(23) split into their terms, each (..., 3) in N along +m_i.

    Keys (their sum is :func:`inverse_dynamics`):

    * ``platform``: ``J^-T m a`` (eq 16);
    * ``sliders``: ``m_e qddot`` (eq 17, ``J_ei = m_i e_i^T``);
    * ``rods_translation``: ``k J^-T sum_i J_v_i^T m_d a_di`` (eq 18, ``J_vdi = J_v_i J^-1``);
    * ``rods_rotation``: ``k J^-T sum_i J_omega_i^T (I_di alpha_i + omega_i x I_di omega_i)`` (eq 19);
    * ``gravity``: minus eq (21)'s generalised gravity force without the rod-moment term:
      ``-J^-T (m + k sum_i J_v_i^T m_d) g - m_e (m_i . g)``;
    * ``gravity_moment`` (only with ``gravity_moment=True``): minus eq (21)'s extra term
      ``k J^-T sum_i J_omega_i^T (r_di x m_d g)``, spurious since gravity already acts at the rod
      centroid through ``J_v``, and dependent on the choice of origin of ``r_di`` (docs/zhao2017_3p4s.md#g9).

    ``k`` is ``params.rods_per_limb`` for gravity always and for the rod inertia unless
    ``rod_inertia_factor`` overrides it (``1`` = eq 23 as printed, docs/zhao2017_3p4s.md#g10). ``h_form="paper"``
    uses eq 13's printed H in eqs 13-15 and so in the slider and rod inertia (docs/zhao2017_3p4s.md#g8).
    Sign: this is the force the motor exerts on its slider; the paper's ``tau^A`` of eq 23 is
    written with the opposite sign convention (docs/zhao2017_3p4s.md#g11).
    """
    _check(mech)
    if not isinstance(params, InertialParams):
        raise TypeError(f"expected InertialParams, got {type(params).__name__}")
    if kin is None:
        kin = limb_kinematics(mech, pose, velocity, acceleration, h_form=h_form)
    elif kin.h_form != h_form:
        raise ValueError(f"kin was computed with h_form={kin.h_form!r}, not {h_form!r}")
    k_g = float(params.rods_per_limb)
    k_i = k_g if rod_inertia_factor is None else float(rod_inertia_factor)
    if not (np.isfinite(k_i) and k_i >= 0):
        raise ValueError(f"rod_inertia_factor = {rod_inertia_factor!r} must be finite and >= 0")
    g = params.gravity
    md = params.m_rod
    J = kin.J
    # platform-space generalised forces (N), mapped to the drives by J^-T
    trans = np.einsum("...kji,...kj->...i", kin.J_v, md * kin.a_rod)
    inertia = params.rod_inertia_world(kin.n)
    i_omega = np.einsum("...kij,...kj->...ki", inertia, kin.omega)
    torque = np.einsum("...kij,...kj->...ki", inertia, kin.alpha) + np.cross(kin.omega, i_omega)
    rot = np.einsum("...kji,...kj->...i", kin.J_omega, torque)
    grav_rods = np.einsum("...kji,j->...i", kin.J_v, md * g)
    terms = {
        "platform": _solve_transpose(J, params.m_platform * kin.acceleration),
        "sliders": params.m_slider * kin.qddot,
        "rods_translation": _solve_transpose(J, k_i * trans),
        "rods_rotation": _solve_transpose(J, k_i * rot),
        "gravity": -(
            _solve_transpose(J, params.m_platform * g + k_g * grav_rods)
            + params.m_slider * (mech.m @ g)
        ),
    }
    if gravity_moment:
        moment = np.cross(kin.r_rod, md * g)
        terms["gravity_moment"] = -_solve_transpose(
            J, k_g * np.einsum("...kji,...kj->...i", kin.J_omega, moment)
        )
    return terms


def inverse_dynamics(
    mech: P3P4S,
    params: InertialParams,
    pose: ArrayLike,
    velocity: ArrayLike,
    acceleration: ArrayLike,
    **options: Any,
) -> Array:
    """Motor forces ``f`` (..., 3) in N along ``+m_i`` for the given platform motion (eqs 16-23).

    The sum of :func:`force_terms`, whose keywords ``options`` are (``h_form``,
    ``gravity_moment``, ``rod_inertia_factor``). Defaults implement the correct physics
    (docs/zhao2017_3p4s.md#s1.7); the keyword options reproduce the paper's printed slips one by
    one (see :func:`force_terms`, :data:`PAPER_PRINTED`).
    """
    return sum(force_terms(mech, params, pose, velocity, acceleration, **options).values())


# ---------------------------------------------------------------------------------------- checks
@dataclass(frozen=True)
class Energy:
    """Kinetic and potential energy (J) of each group of bodies, each array of the batch shape."""

    kinetic_platform: Array
    kinetic_sliders: Array
    kinetic_rods: Array
    potential_platform: Array
    potential_sliders: Array
    potential_rods: Array

    @property
    def kinetic(self) -> Array:
        return self.kinetic_platform + self.kinetic_sliders + self.kinetic_rods

    @property
    def potential(self) -> Array:
        return self.potential_platform + self.potential_sliders + self.potential_rods

    @property
    def total(self) -> Array:
        return self.kinetic + self.potential


def energy(mech: P3P4S, params: InertialParams, pose: ArrayLike, velocity: ArrayLike) -> Energy:
    """Kinetic + potential energy of platform, 3 sliders and all side rods, from positions and
    velocities alone: independent of the maps of eqs 9-15 and of the Newton-Euler code.

    Bodies are placed by the IK (eq 5): slider midpoints ``c_i = u_i + q_i m_i``, side rod k of
    limb i from ``c_i + s_k t_i`` to ``d_i + s_k t_i`` (``t_i`` horizontal along the parallelogram
    edges, offsets ``s_k`` spread over ``[-d/2, d/2]``), centroid at mid-length. Rates follow by
    differentiating the definitions: ``|d_i - c_i| = L`` gives
    ``qdot_i = (d_i - c_i) . v / ((d_i - c_i) . m_i)``; ``dn_i/dt = (v - qdot_i m_i)/L``; each side
    rod translates with its parallelogram edge and turns at ``omega_i = n_i x dn_i/dt`` (no spin:
    an axisymmetric rod between two ball joints keeps zero spin). Potential is ``-m g . r``.
    """
    _check(mech)
    x = as_batch(pose, 3, "pose")
    v = as_batch(velocity, 3, "velocity")
    x, v = _broadcast(x, v, names=("pose", "velocity"))
    g = params.gravity
    q = mech.ik(x)
    c = mech.r_b * mech.e + q[..., None] * mech.m  # slider midpoints (..., 3, 3)
    d = x[..., None, :] + mech.a * mech.e  # platform points
    w = d - c
    qdot = np.einsum("...ij,...j->...i", w, v) / np.einsum("...ij,ij->...i", w, mech.m)
    n = w / mech.L
    ndot = (v[..., None, :] - qdot[..., None] * mech.m) / mech.L
    omega = np.cross(n, ndot)
    v_rod = qdot[..., None] * mech.m + 0.5 * mech.L * ndot  # every side rod of limb i
    k = params.rods_per_limb
    t = np.cross([0.0, 0.0, 1.0], mech.e)  # (3, 3) edge directions
    offsets = np.linspace(-0.5 * mech.d, 0.5 * mech.d, k) if k > 1 else np.zeros(1)
    centroids = (c + 0.5 * mech.L * n)[..., None, :, :] + offsets[
        :, None, None
    ] * t  # (..., k, 3, 3)
    inertia = params.rod_inertia_world(n)
    rot = 0.5 * np.einsum("...ki,...kij,...kj->...", omega, inertia, omega)
    return Energy(
        kinetic_platform=0.5 * params.m_platform * np.einsum("...j,...j->...", v, v),
        kinetic_sliders=0.5 * params.m_slider * np.einsum("...i,...i->...", qdot, qdot),
        kinetic_rods=k * (0.5 * params.m_rod * np.einsum("...kj,...kj->...", v_rod, v_rod) + rot),
        potential_platform=-params.m_platform * (x @ g),
        potential_sliders=-params.m_slider * np.einsum("...kj,j->...", c, g),
        potential_rods=-params.m_rod * np.einsum("...skj,j->...", centroids, g),
    )


#: central-difference weights of the first derivative, O(h^6): offsets -3..3
_D1_ORDER6 = np.array([-1.0, 9.0, -45.0, 0.0, 45.0, -9.0, 1.0]) / 60.0


def power_balance(
    mech: P3P4S,
    params: InertialParams,
    motion: SineMotion,
    t: ArrayLike,
    *,
    step: float | None = None,
    **variant,
) -> PowerBalance:
    """The energy check of docs/zhao2017_3p4s.md#s1.7: actuator power of :func:`inverse_dynamics` (with the
    options ``variant``) against ``dE/dt`` of :func:`energy` by :func:`time_derivative`.

    ``step`` defaults to ``0.02 / motion.omega`` (truncation ~ 5e-13, rounding ~ 1e-11 relative).
    With the correct physics the two agree to rounding; each printed slip breaks the balance.
    """
    t = np.asarray(t, dtype=float)
    h = 0.02 / motion.omega if step is None else step
    p, v, a = motion.state(t)
    f = inverse_dynamics(mech, params, p, v, a, **variant)
    qdot = np.einsum("...ij,...j->...i", drive_jacobian(mech, p), v)
    power = np.einsum("...i,...i->...", f, qdot)
    dEdt = time_derivative(
        lambda tt: energy(mech, params, motion.pose(tt), motion.velocity(tt)).total, t, h
    )
    return PowerBalance(t, power, dEdt)


#: central-difference weights of the second derivative, O(h^6): offsets -3..3
_D2_ORDER6 = np.array([2.0, -27.0, 270.0, -490.0, 270.0, -27.0, 2.0]) / 180.0


def ik_finite_differences(
    mech: P3P4S, motion: SineMotion, t: ArrayLike, step: float
) -> tuple[Array, Array, Array]:
    """Strokes and their time derivatives from the IK alone (no Jacobian), along ``motion``.

    Returns ``(q, qdot, qddot)`` (each (..., 3)) from ``q(t + k h) = ik(pose(t + k h))``,
    ``k = -3..3``, by 6th-order central differences: an independent check of eqs (8) and (13).
    Relative errors ``~ (omega h)^6 / 140`` and ``~ (omega h)^6 / 560`` (truncation) and
    ``~ 1e-16 q / (h qdot)``, ``~ 1e-16 q / (h^2 qddot)`` (rounding); ``omega h ~ 0.1`` balances them.
    """
    _check(mech)
    if not (np.isfinite(step) and step > 0):
        raise ValueError(f"step = {step!r} s must be finite and > 0")
    t = np.asarray(t, dtype=float)
    qs = [mech.ik(motion.pose(t + k * step)) for k in range(-3, 4)]
    qdot = sum(w * q for w, q in zip(_D1_ORDER6, qs)) / step
    qddot = sum(w * q for w, q in zip(_D2_ORDER6, qs)) / step**2
    return qs[3], qdot, qddot
