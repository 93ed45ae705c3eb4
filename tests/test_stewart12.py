"""The 12-leg cube mechanism: IK, closed-form FK, compatibility equations, drive modes, solvers."""

import numpy as np
import pytest

from parakin.errors import UnreachableError
from parakin.mechanisms.stewart12 import (
    CONVENTIONS,
    NESTED_PASSIVE,
    ActiveLegs,
    DriveMode,
    Stewart12,
)
from parakin.papers.ye_stewart12.common import run_mode, steps  # registers gauss-newton, broyden-ls
from parakin.solvers import solve_fk

TEST_POSE = np.array([0.5e-3, 0.0, 0.0, -0.05, 0.05, 0.05])
#: docs/ye_stewart12.md#s1.3: leg lengths (mm) at the §3.3 pose, Euler-parameter and Cayley readings
NOTES_EP = [
    26.865024,
    23.922647,
    26.585689,
    24.132186,
    23.605347,
    26.108406,
    26.976044,
    24.047256,
    26.639024,
    23.134415,
    23.671737,
    27.106966,
]
NOTES_CAYLEY = [
    26.856652,
    23.924807,
    26.579426,
    24.136746,
    23.610032,
    26.102050,
    26.967297,
    24.048945,
    26.632587,
    23.138956,
    23.676152,
    27.100619,
]


def random_poses(m, k, seed=0):
    lo, hi = m.pose_bounds()
    return np.random.default_rng(seed).uniform(lo, hi, (k, 6))


def test_home_and_test_pose_lengths():
    m = Stewart12()
    assert np.allclose(m.ik(m.home()), 0.025, atol=1e-15)
    assert np.allclose(m.ik(TEST_POSE) * 1e3, NOTES_EP, atol=1e-6)
    assert np.allclose(Stewart12(convention="cayley").ik(TEST_POSE) * 1e3, NOTES_CAYLEY, atol=1e-6)
    r = m.rotation(TEST_POSE)
    assert r[0, 1] == pytest.approx(-0.104624, abs=1e-6) and r[0, 0] == pytest.approx(
        0.99, abs=1e-12
    )


@pytest.mark.parametrize("convention", CONVENTIONS)
def test_fk_inverts_ik_on_1000_poses(convention):
    m = Stewart12(convention=convention)
    x = random_poses(m, 1000)
    got = m.fk(m.ik(x))
    assert got.shape == (1000, 6)
    assert np.max(np.abs(got[:, :3] - x[:, :3])) * 1e3 < 1e-10  # mm
    assert np.max(np.abs(got[:, 3:] - x[:, 3:])) < 1e-12
    assert np.allclose(m.fk(m.ik(x[7])), x[7], atol=1e-14)  # unbatched


def test_linear_fk_matches_notes_closed_forms_off_manifold():
    """docs/ye_stewart12.md#s1.5's explicit formulas (x0, u1y, u2z) hold for ANY lengths, not only consistent ones."""
    m = Stewart12()
    n, L = m.n, m.L
    q = np.random.default_rng(1).uniform(0.02, 0.03, (50, 12)) ** 2
    mm, u = m.fk_points(np.sqrt(q))
    x0 = (
        q[:, 0]
        - q[:, 1]
        - q[:, 2]
        + q[:, 3]
        + q[:, 4]
        - q[:, 5]
        - q[:, 6]
        + q[:, 7]
        + q[:, 8]
        - q[:, 9]
        - q[:, 10]
        + q[:, 11]
    ) / (8 * L)
    s = np.sum(mm**2, -1)
    k = L * (s + L**2 + 2 * n * L + 4 * n * n)
    u1y = (2 * k - (L + n) * (q[:, 0] + q[:, 6]) + n * (q[:, 1] + q[:, 7])) / (4 * L * (L + 2 * n))
    assert np.allclose(mm[:, 0], x0, atol=1e-16) and np.allclose(u[:, 0, 1], u1y, atol=1e-16)


def test_jacobian_pose_matches_finite_differences():
    for conv in CONVENTIONS:
        m = Stewart12(convention=conv)
        x = random_poses(m, 5, seed=2)
        jac = m.jacobian_pose(x, m.ik(x))
        h = 1e-7
        fd = np.stack([(m.ik(x + h * e) - m.ik(x - h * e)) / (2 * h) for e in np.eye(6)], -1)
        assert jac.shape == (5, 12, 6)
        assert np.max(np.abs(jac - fd)) < 1e-7


def test_compatibility_vanishes_on_consistent_lengths_only():
    m = Stewart12()
    lengths = m.ik(random_poses(m, 500, seed=3))
    assert np.max(np.abs(m.compatibility(lengths))) < 1e-16  # m^2 (~1e-10 mm^2)
    assert np.max(np.abs(m.compatibility(np.full(12, m.L)))) < 1e-17
    bad = lengths.copy()
    bad[:, 7] += 1e-4
    assert np.all(np.max(np.abs(m.compatibility(bad)), -1) > 1e-9)


def test_compatibility_jacobian_matches_finite_differences_and_has_rank_6():
    m = Stewart12()
    lengths = m.ik(TEST_POSE)
    jac = m.compatibility_jacobian(lengths)
    h = 1e-8
    fd = np.stack(
        [
            (m.compatibility(lengths + h * e) - m.compatibility(lengths - h * e)) / (2 * h)
            for e in np.eye(12)
        ],
        -1,
    )
    assert np.max(np.abs(jac - fd)) < 1e-8 * np.max(np.abs(jac))
    assert np.linalg.matrix_rank(jac) == 6


def test_bad_lengths_raise_documented_error():
    m = Stewart12()
    lengths = m.ik(TEST_POSE)
    bad = lengths.copy()
    bad[3] += 2e-3
    with pytest.raises(UnreachableError, match=r"do not assemble: max \|F\|.*exceeds the limit"):
        m.fk(bad)
    neg = lengths.copy()
    neg[4] = -0.01
    with pytest.raises(UnreachableError, match=r"l5 = -0.01 m must be > 0"):
        m.check_joints(neg)
    with pytest.raises(UnreachableError, match=r"\|lambda\|\^2 = 1.08 must be < 1"):
        m.ik([0, 0, 0, 0.6, 0.6, 0.6])
    m.check_joints(lengths)  # fine
    assert np.all(np.isfinite(m.fk(bad, check=False)))  # unchecked: the linear extrapolation


def test_drive_mode_solvers_are_the_generic_ones():
    """R = 0 (square): gauss-newton == newton, broyden-ls == broyden, iterate for iterate."""
    m = Stewart12()
    dm = DriveMode(m, NESTED_PASSIVE[0])
    xs, act = dm.split(m.ik(TEST_POSE))
    x0 = 1.2 * xs
    for a, b in (("newton", "gauss-newton"), ("broyden", "broyden-ls")):
        ra = solve_fk(dm, act, x0=x0, method=a, tol=0.0, xtol=1e-12)
        rb = solve_fk(dm, act, x0=x0, method=b, tol=0.0, xtol=1e-12)
        assert int(ra.nit) == int(rb.nit) and np.allclose(ra.x, rb.x, atol=1e-15)
        assert np.allclose(rb.x, xs, atol=1e-10)


@pytest.mark.parametrize("r", range(6))
def test_every_drive_mode_converges_from_10_percent(r):
    m = Stewart12()
    run_ = run_mode(m, NESTED_PASSIVE[r], TEST_POSE, np.array([0.1, -0.1]), "gauss-newton", 40)
    assert np.allclose(run_["x"], run_["xstar"], atol=1e-12)
    dm = DriveMode(m, NESTED_PASSIVE[r])
    assert dm.residual(*dm.split(m.ik(TEST_POSE))).shape == (6 + r,)


def test_table5_step_counts_within_one_of_the_paper():
    m = Stewart12()
    d = np.arange(20, 26) / 100
    nr = steps(run_mode(m, NESTED_PASSIVE[0], TEST_POSE, d, "gauss-newton", 60)["traj"], 1e-9)
    br = steps(run_mode(m, NESTED_PASSIVE[0], TEST_POSE, d, "broyden-ls", 60)["traj"], 1e-9)
    assert nr.tolist() == [5, 5, 5, 5, 6, 6]  # the paper's N-R column exactly
    assert np.all(np.abs(br - [10, 10, 11, 11, 11, 12]) <= 1) and br.mean() == pytest.approx(65 / 6)


def test_pose_space_lm_and_least_squares_fk():
    m = Stewart12()
    lengths = m.ik(TEST_POSE)
    al = ActiveLegs(m, (1, 2, 3, 4, 5, 6, 9))
    res = solve_fk(
        al, lengths[[0, 1, 2, 3, 4, 5, 8]], x0=np.zeros(6), method="lm", tol=1e-14, maxiter=50
    )
    assert bool(res.success) and np.allclose(res.x, TEST_POSE, atol=1e-12)
    res = solve_fk(m, lengths, x0=np.zeros(6), method="gauss-newton", tol=1e-14, maxiter=50)
    assert bool(res.success) and np.allclose(res.x, TEST_POSE, atol=1e-12)
    # out-of-domain iterates fail cleanly instead of raising
    assert np.isnan(al.residual([0, 0, 0, 0.9, 0.9, 0], lengths[:7])).all()


def test_skeleton_has_all_legs_and_cube_edges():
    m = Stewart12()
    sk = m.skeleton(TEST_POSE, passive=(7, 8))
    kinds = [k for k, _ in sk.segments]
    assert kinds.count("actuator") == 10 and kinds.count("passive") == 2
    assert kinds.count("base") == 12 and kinds.count("platform") == 12
    assert np.allclose(sk.points["B_1"], m.joint_centres(TEST_POSE)[0])
