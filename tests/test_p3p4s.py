"""3-P(4S) kinematics (Zhao 2017 eqs 1-8): IK against independent formulations, Jacobians
against finite differences, closed-form FK round trips, reachability errors."""

import math

import numpy as np
import pytest

from parakin.errors import ShapeError, UnreachableError
from parakin.geometry import rot_x, rot_z
from parakin.mechanisms import P3P4S
from parakin.mechanisms.base import Mechanism
from parakin.workspace import sample_reachable as reachable_poses


def ik_paper_frames(mech: P3P4S, pose: np.ndarray) -> np.ndarray:
    """Eqs (1)-(5) literally: d_i expressed in the limb frames {u_i} = R(z, alpha_i) R(x, phi),
    l_i = y - sqrt(L^2 - x^2 - z^2). An independent route to the same strokes (frames and
    homogeneous transforms instead of the coordinate-free rail vector m_i)."""
    out = []
    for gamma, alpha in zip(np.deg2rad([0, 120, 240]), np.deg2rad([90, 210, 330])):
        rot = rot_z(alpha) @ rot_x(mech.phi)  # +phi: the only reading that reaches Table 1
        u = mech.r_b * np.array([math.cos(gamma), math.sin(gamma), 0.0])
        d_platform = (
            mech.r_a * math.cos(mech.theta) * np.array([math.cos(gamma), math.sin(gamma), 0.0])
        )
        x, y, z = rot.T @ (pose + d_platform - u)
        out.append(y - math.sqrt(mech.L**2 - x**2 - z**2))
    return np.array(out)


def test_home_stroke_by_hand():
    # At (0, 0, z) the limb lies in its vertical plane: (l cos phi - delta)^2 + (z - l sin phi)^2 = L^2
    m, z = P3P4S(), 0.592
    delta = 0.67 - math.sqrt(0.25**2 - 0.06**2)
    b = delta * math.cos(math.pi / 6) + z * math.sin(math.pi / 6)
    c = delta**2 + z**2 - 0.38**2
    expected = b - math.sqrt(b * b - c)
    assert expected == pytest.approx(0.4315828, abs=1e-7)
    assert np.allclose(m.ik([0, 0, z]), expected, atol=1e-14, rtol=0)


def test_ik_matches_paper_frame_formulation(p3p4s, rng):
    poses = reachable_poses(p3p4s, 200, rng)
    ours = p3p4s.ik(poses)
    theirs = np.array([ik_paper_frames(p3p4s, p) for p in poses])
    assert np.max(np.abs(ours - theirs)) < 1e-14


def test_ik_residual_vanishes_and_is_batched(p3p4s, rng):
    poses = reachable_poses(p3p4s, 24, rng).reshape(2, 4, 3, 3)[..., 0, :]  # (2, 4, 3)
    q = p3p4s.ik(poses)
    assert q.shape == (2, 4, 3)
    assert np.max(np.abs(p3p4s.residual(poses, q))) < 1e-14
    assert np.allclose(q[1, 2], p3p4s.ik(poses[1, 2]))  # batch == one by one


def test_closed_form_fk_round_trip(p3p4s, rng):
    poses = reachable_poses(p3p4s, 5000, rng)
    back = p3p4s.fk(p3p4s.ik(poses))
    assert np.max(np.abs(back - poses)) < 1e-12
    # the other assembly mode lies below the rails
    lower = p3p4s.fk(p3p4s.ik(poses), branch="lower")
    assert np.all(lower[:, 2] < 0)
    assert np.max(np.abs(p3p4s.residual(lower, p3p4s.ik(poses)))) < 1e-12


def test_velocity_jacobian_eq8_by_finite_differences(p3p4s, rng):
    poses = reachable_poses(p3p4s, 300, rng)
    j = p3p4s.velocity_jacobian(poses)
    h = 1e-6
    fd = np.stack(
        [(p3p4s.ik(poses + h * e) - p3p4s.ik(poses - h * e)) / (2 * h) for e in np.eye(3)], axis=-1
    )
    assert np.max(np.abs(j - fd) / (1 + np.abs(fd))) < 1e-7
    # eq (8) in the paper's form: diag(n_i . m_i)^-1 [n_1; n_2; n_3]
    n = p3p4s.rod_directions(poses)
    nm = np.einsum("kij,ij->ki", n, p3p4s.m)
    assert np.allclose(j, n / nm[..., None], atol=1e-14)
    # the generic protocol route J = -B^-1 A gives the same matrix
    assert np.allclose(Mechanism.velocity_jacobian(p3p4s, poses), j, atol=1e-12)


def test_residual_jacobians_by_finite_differences(p3p4s, rng):
    poses = reachable_poses(p3p4s, 50, rng)
    q = p3p4s.ik(poses) + rng.normal(scale=1e-3, size=(50, 3))  # off the manifold too
    a, b = p3p4s.jacobian_pose(poses, q), p3p4s.jacobian_joints(poses, q)
    a_fd = Mechanism.jacobian_pose(p3p4s, poses, q)
    b_fd = Mechanism.jacobian_joints(p3p4s, poses, q)
    assert np.max(np.abs(a - a_fd)) < 1e-8
    assert np.max(np.abs(b - b_fd)) < 1e-8


def test_limb_frames_are_rz_alpha_rx_phi():
    m = P3P4S()
    sk = m.skeleton(m.home())
    for i, alpha in enumerate(np.deg2rad([90, 210, 330])):
        assert np.allclose(sk.frames[f"u_{i + 1}"][1], rot_z(alpha) @ rot_x(m.phi), atol=1e-15)


def test_unreachable_pose_raises_with_value_and_limit():
    m = P3P4S()
    with pytest.raises(
        UnreachableError, match=r"limb 1 needs L\^2 - x_u\^2 - z_u\^2 = -0.17\d+ m\^2 >= 0"
    ):
        m.ik([0.0, 0.0, 0.9])
    batch = np.array([[0, 0, 0.59], [0, 0, 0.9], [0, 0, 1.0]])
    with pytest.raises(UnreachableError, match=r"batch index \(1,\) \(1 more in this batch\)"):
        m.ik(batch)
    assert m.is_reachable(batch).tolist() == [True, False, False]


def test_unassemblable_strokes_raise_in_closed_form_fk():
    with pytest.raises(UnreachableError, match="spheres of radius L = 0.38 m do not meet"):
        P3P4S().fk([0.0, 1.5, 0.0])
    # these strokes assemble, but only with limb 2 on the plus root of eq (5)
    with pytest.raises(UnreachableError, match=r"limb 2 in the other mode \(n_2 \. m_2 = -"):
        P3P4S().fk([0.0, 0.9, 0.2])


def test_bad_shapes_and_parameters():
    m = P3P4S()
    with pytest.raises(ShapeError, match=r"3 values along its last axis, got shape \(2,\)"):
        m.ik([0.0, 0.5])
    with pytest.raises(ValueError, match="non-finite"):
        m.ik([0.0, np.nan, 0.5])
    with pytest.raises(ValueError, match=r"phi = .* must lie in \(0, pi/2\)"):
        P3P4S(phi=2.0)
    with pytest.raises(ValueError, match="d = 0.6 m must be < 2 r_a"):
        P3P4S(d=0.6)
    with pytest.raises(ValueError, match="L = -1"):
        P3P4S(L=-1)


def test_kinematics_depends_on_delta_only():
    a = P3P4S()
    b = P3P4S.from_delta(a.delta, a.L, a.phi, r_a=0.3, d=0.05)
    assert b.r_b != a.r_b
    assert np.allclose(a.ik(a.home()), b.ik(a.home()), atol=1e-14)
