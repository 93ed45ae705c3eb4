"""The MuJoCo check of the 3-P(4S) dynamics (stands in for the paper's ADAMS, Figs 7, 8, 10).

MuJoCo's model is generated from the mechanism and inertial parameters; its drive rates come
from its own constraint Jacobians and its forces from its own inverse dynamics, so agreement with
parakin.dynamics is a real check. The printed (wrong) equations must disagree with it.
"""

import mujoco
import numpy as np
import pytest

from parakin.errors import ShapeError
from parakin.mechanisms import P3P4S
from parakin.mechanisms import p3p4s_dynamics as dyn
from parakin.mechanisms import p3p4s_mujoco as mc

MECH = P3P4S.zhao2017()
PARAMS = dyn.InertialParams.zhao2017()


@pytest.fixture(scope="module", params=["equivalent", "parallelogram"])
def model(request):
    return mc.build(MECH, PARAMS, request.param)


@pytest.fixture(scope="module")
def paper_motion():
    motion = dyn.SineMotion()
    t = np.linspace(0.0, motion.period, 21)
    return motion, t, *motion.state(t)


def rel(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def test_model_structure(model):
    m = model.model
    equivalent = model.rods == "equivalent"
    assert m.nv == (15 if equivalent else 27)  # platform 3 or 6, sliders 3, 3 or 6 ball joints
    assert m.nu == 3 and m.neq == (3 if equivalent else 6)
    assert float(m.body_mass.sum()) == pytest.approx(PARAMS.total_mass, rel=1e-12)
    assert tuple(m.opt.gravity) == PARAMS.g
    # the home keyframe is assembled: every loop closes
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_forward(m, d)
    assert np.max(np.abs(d.efc_pos[: 3 * m.neq])) < 1e-12


def test_loop_jacobian_is_the_equality_constraint(model, paper_motion):
    """The site Jacobians we use are exactly MuJoCo's equality-constraint rows (efc_J)."""
    _, _, p, _, _ = paper_motion
    m = model.model
    d = mujoco.MjData(m)
    d.qpos[:] = model.qpos(p[5], MECH.ik(p[5]))
    mujoco.mj_forward(m, d)
    jc, _ = mc._constraint_jacobians(model, d, with_dot=False)
    efc = np.asarray(d.efc_J).reshape(d.nefc, m.nv)[: 3 * m.neq]
    assert np.allclose(jc, efc, rtol=0, atol=1e-14)
    assert np.max(np.abs(d.efc_pos[: 3 * m.neq])) < 1e-12  # the IK assembles the model


def test_static_load(model):
    res = mc.inverse_dynamics(model, [0.0, 0.0, 0.57], np.zeros(3), np.zeros(3))
    assert res.force == pytest.approx([40.6308] * 3, abs=1e-4)


def test_paper_motion_agrees_with_newton_euler(model, paper_motion):
    _, _, p, v, a = paper_motion
    ours = dyn.limb_kinematics(MECH, p, v, a)
    f = dyn.inverse_dynamics(MECH, PARAMS, p, v, a)
    res = mc.inverse_dynamics(model, p, v, a)
    assert rel(res.force, f) < 1e-2  # the goal: within 1 % of the peak force
    assert rel(res.force, f) < 1e-9  # what we actually get: rounding
    assert rel(res.qdot, ours.qdot) < 1e-9 and rel(res.qddot, ours.qddot) < 1e-9
    assert np.max(res.loop_error) < 1e-12 and np.max(res.lstsq_residual) < 1e-10
    assert np.max(res.rod_spin) < 1e-12
    assert model.model.opt.disableflags == 0  # the constraint flag is restored


def test_demanding_trajectory_agrees(model):
    """All axes moving by centimetres: the velocity-squared terms matter and still agree."""
    t = np.linspace(0.0, 0.2, 9)[:, None]
    w = 2 * np.pi * 5.0 * np.array([1.0, 2.0, 3.0])
    amp, phase = np.array([0.02, 0.015, 0.012]), np.array([0.3, 1.1, -0.4])
    p = np.array([0.005, -0.01, 0.565]) + amp * np.sin(w * t + phase)
    v = amp * w * np.cos(w * t + phase)
    a = -amp * w**2 * np.sin(w * t + phase)
    res = mc.inverse_dynamics(model, p, v, a)
    assert rel(res.force, dyn.inverse_dynamics(MECH, PARAMS, p, v, a)) < 1e-9
    assert rel(res.qddot, dyn.drive_accelerations(MECH, p, v, a)) < 1e-9
    # the printed H is visibly wrong on this trajectory
    assert rel(res.qddot, dyn.drive_accelerations(MECH, p, v, a, h_form="paper")) > 1e-2


def test_other_geometry_masses_and_gravity():
    mech = P3P4S.zhao2017_optimised()
    params = dyn.InertialParams(
        m_platform=3.0,
        m_slider=1.0,
        m_rod=0.5,
        I_rod=(0.01, 0.01, 1e-3),
        rods_per_limb=3,
        g=(0.5, -0.2, -9.0),
    )
    p = np.array([[0.01, -0.02, 0.6], [-0.03, 0.01, 0.62]])
    v = np.array([[0.3, -0.2, 0.1], [0.0, 0.1, -0.3]])
    a = np.array([[1.0, 2.0, -0.5], [-3.0, 0.5, 2.0]])
    f = dyn.inverse_dynamics(mech, params, p, v, a)
    for rods in ("equivalent", "parallelogram"):
        res = mc.inverse_dynamics(mc.build(mech, params, rods), p, v, a)
        assert rel(res.force, f) < 1e-9, rods


def test_printed_slips_disagree_with_mujoco(paper_motion):
    _, _, p, v, a = paper_motion
    res = mc.inverse_dynamics(mc.build(MECH, PARAMS), p, v, a)
    for opts, at_least in (
        (dict(h_form="paper"), 1e-4),
        (dict(gravity_moment=True), 0.04),
        (dict(rod_inertia_factor=1.0), 0.15),
        (dyn.PAPER_PRINTED, 0.2),
    ):
        assert rel(dyn.inverse_dynamics(MECH, PARAMS, p, v, a, **opts), res.force) > at_least, opts


def test_open_loop_simulation_follows_the_motion():
    """MuJoCo's forward dynamics (constraint solver, RK4) driven by our forces tracks the motion
    law; driven by the printed equations' forces it does not."""
    motion = dyn.SineMotion()
    model = mc.build(MECH, PARAMS, "equivalent")
    ours = mc.track(
        model, motion, 0.025, lambda t: dyn.inverse_dynamics(MECH, PARAMS, *motion.state(t))
    )
    assert len(ours.t) == 251 and ours.t[-1] == pytest.approx(0.025)
    assert np.max(ours.error) < 1e-3 * motion.amplitude
    assert np.max(ours.loop_error) < 1e-8
    printed = mc.track(
        model,
        motion,
        0.025,
        lambda t: dyn.inverse_dynamics(MECH, PARAMS, *motion.state(t), **dyn.PAPER_PRINTED),
    )
    assert np.max(printed.error) > 0.3 * motion.amplitude


def test_mjcf_is_generated_from_the_parameters():
    xml = mc.mjcf(MECH, PARAMS, "parallelogram")
    assert xml.count("<connect ") == 6 and xml.count('type="ball"') == 6 and "<freejoint" in xml
    assert f'mass="{PARAMS.m_rod!r}"' in xml and f'mass="{PARAMS.m_platform!r}"' in xml
    eq = mc.mjcf(MECH, PARAMS, "equivalent")
    assert eq.count("<connect ") == 3 and f'mass="{2 * PARAMS.m_rod!r}"' in eq


def test_bad_input():
    with pytest.raises(ValueError, match="rods"):
        mc.build(MECH, PARAMS, "four-bar")
    with pytest.raises(ValueError, match="timestep"):
        mc.mjcf(MECH, PARAMS, timestep=0.0)
    with pytest.raises(TypeError):
        mc.mjcf(object(), PARAMS)
    model = mc.build(MECH, PARAMS)
    with pytest.raises(ShapeError):
        mc.inverse_dynamics(
            model, np.zeros((2, 3)) + [0, 0, 0.57], np.zeros((3, 3)), np.zeros((2, 3))
        )
    with pytest.raises(ValueError, match="3 finite actuator forces"):
        mc.track(model, dyn.SineMotion(), 0.001, lambda t: [1.0, 2.0])
