"""The two independent checks of the generic dynamics (issue 27): MuJoCo and pinocchio, each on a
model generated from the mechanism's own description, on every mechanism along a trajectory.

Tolerance, fixed before comparing: 1e-9 relative to the largest force. All three computations are
exact rigid-body dynamics (MuJoCo's soft loop constraints are switched off for ``mj_inverse`` and
enter only through their exact Jacobians; pinocchio solves its constrained KKT system exactly), so
they differ by rounding only: about 1e-16 times the condition numbers of the actuator Jacobian
(< 1e3 on these trajectories) and of the least-squares solves, i.e. ~1e-13; 1e-9 leaves room for
other BLAS kernels. pinocchio (``pin``) is a pinned dependency (environment.txt): never skipped.
"""

from __future__ import annotations

import numpy as np
import pytest

from parakin import dynamics as D
from parakin.dynamics import mujoco_check as mc
from parakin.dynamics.trajectory import Harmonic
from parakin.mechanisms import P3P4S, REGISTRY
from parakin.mechanisms import p3p4s_dynamics as zhao
from parakin.mechanisms import p3p4s_mujoco as zhao_mujoco

MECHS = [cls() for cls in REGISTRY.values() if cls().mass_model() is not None]
IDS = [m.name for m in MECHS]
TOL = 1e-9


def rel(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a) - b)) / np.max(np.abs(b)))


@pytest.fixture(scope="module", params=MECHS, ids=IDS)
def case(request):
    """A mechanism, samples of its test trajectory (5 % of the pose box, 0.5-3 Hz) and our forces."""
    mech = request.param
    tr = Harmonic.around(mech, 0.05, 0.5)
    x, v, a = tr.state(np.linspace(0.0, tr.period, 6))
    return mech, tr, (x, v, a), D.inverse_dynamics(mech, x, v, a)


def test_mujoco_agrees(case):
    mech, _, (x, v, a), ours = case
    res = mc.inverse_dynamics(mc.build(mech), x, v, a)
    assert rel(res.force, ours.force) < TOL
    assert rel(res.joint_rate, ours.joint_rate) < TOL
    assert rel(res.joint_acceleration, ours.joint_acceleration) < TOL
    # the bodies' placements assemble MuJoCo's loops, and its kinematics accepts our platform
    # motion exactly; no idle spin is excited
    assert np.max(res.loop_error) < 1e-12 and np.max(res.kinematic_residual) < 1e-10
    assert np.max(res.spin) < 1e-9


def test_mujoco_model_is_the_description(case):
    mech = case[0]
    mm = mc.build(mech)
    ref, model = mm.reference, mm.model
    assert model.nbody - 1 == len(ref.names) and model.nu == mech.n_joints
    assert model.neq == len(ref.closures) and mm.xml.count("<connect ") == len(ref.closures)
    assert float(model.body_mass.sum()) == pytest.approx(sum(b.mass for b in ref.rigid), rel=1e-14)
    assert np.allclose(model.opt.gravity, mm.mass.gravity, rtol=0, atol=0)
    assert model.opt.disableflags == 0  # the recipe restores the constraint flag


def test_pinocchio_agrees(case):
    from parakin.dynamics import pinocchio_check as pc

    mech, _, (x, v, a), ours = case
    res = pc.check(pc.build(mech), x, v, a, ours.force)
    assert rel(res.force, ours.force) < TOL
    # driven by our forces, pinocchio's constrained dynamics gives the platform the trajectory's
    # acceleration
    assert np.max(res.platform_error) < TOL
    assert np.max(res.loop_error) < 1e-12 and np.max(res.kinematic_residual) < 1e-10


def test_generic_mujoco_model_is_zhaos_parallelogram_model():
    """For the 3-P(4S) the generic MJCF is the full model of p3p4s_mujoco (all side rods)."""
    mech, params = P3P4S.zhao2017(), zhao.InertialParams.zhao2017()
    p, v, a = zhao.SineMotion().state(np.linspace(0.0, 0.05, 5))
    generic = mc.inverse_dynamics(mc.build(mech, mass=params.mass_model(mech)), p, v, a)
    full = zhao_mujoco.inverse_dynamics(zhao_mujoco.build(mech, params, "parallelogram"), p, v, a)
    assert rel(generic.force, full.force) < TOL
    assert mc.build(mech).model.nv == zhao_mujoco.build(mech, params, "parallelogram").model.nv


def test_mujoco_forward_simulation_follows_our_forces():
    """MuJoCo's own forward dynamics (soft loops, RK4) driven by our forces tracks the
    trajectory: to the stiffness of its constraints, not to rounding (tolerance 1e-3 of the
    amplitude, as for Zhao's model; its soft loops open by ~1e-8 m here, bounded at 1 um); the
    same forces halved do not."""
    mech = P3P4S.zhao2017()
    tr = Harmonic.around(mech, 0.2, 5.0)
    mm = mc.build(mech, timestep=1e-4)
    ours = mc.track(mm, tr, 0.05, lambda t: D.inverse_dynamics(mech, *tr.state(t)).force)
    amplitude = np.max(np.abs(np.asarray(tr.amplitude)))
    assert np.max(ours.error) < 1e-3 * amplitude and np.max(ours.loop_error) < 1e-6
    half = mc.track(mm, tr, 0.05, lambda t: 0.5 * D.inverse_dynamics(mech, *tr.state(t)).force)
    assert np.max(half.error) > 0.1 * amplitude


def test_engine_bad_input():
    mech = P3P4S.zhao2017()
    with pytest.raises(ValueError, match="timestep"):
        mc.mjcf(mech, timestep=0.0)
    with pytest.raises(ValueError, match="one pose"):
        mc.mjcf(mech, np.zeros((2, 3)) + mech.home())
    mm = mc.build(mech)
    with pytest.raises(ValueError, match="must have one shape"):
        mc.inverse_dynamics(mm, np.zeros((2, 3)) + mech.home(), np.zeros((3, 3)), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="3 finite actuator forces"):
        mc.track(mm, Harmonic.around(mech, 0.1, 1.0), 0.01, lambda t: [1.0, 2.0])
