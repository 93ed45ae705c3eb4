"""The 3-6 Stewart platform of Li 2017: IK, analytic Jacobians, Newton FK, the certified all-solutions
FK (degree-16 polynomial), mirror symmetry, bad leg lengths."""

import numpy as np
import pytest

from parakin.errors import UnreachableError
from parakin.mechanisms.base import _central_difference
from parakin.mechanisms.stewart36 import TABLE3_ROW1, Stewart36, pose_from_paper
from parakin.solvers import solve_fk


@pytest.fixture(params=[0.5, 1.0, 3.0])
def mech(request) -> Stewart36:
    return Stewart36(b=request.param)


def random_poses(mech, n, seed=0, spread=0.4):
    g = np.random.default_rng(seed)
    x = mech.home() + g.uniform(-1, 1, (n, 6)) * np.array([spread, spread, spread, 0.3, 0.3, 0.3])
    x[:, 5] = np.abs(x[:, 5]) + 0.2
    return x


def wrap(d):
    d = np.array(d, dtype=float)
    d[..., :3] = (d[..., :3] + np.pi) % (2 * np.pi) - np.pi
    return d


def test_reconstructed_inputs_match_notes():
    # docs/li2017_stewart36.md#s3.2: L = IK(Table 3 row 1, b)
    assert np.allclose(
        Stewart36(b=1.0).ik(pose_from_paper(TABLE3_ROW1)),
        [2.201919, 1.889476, 2.025009, 1.901896, 1.871540, 1.573125],
        atol=1e-6,
    )
    assert np.allclose(
        Stewart36(b=3.0).ik(pose_from_paper(TABLE3_ROW1)),
        [3.534129, 2.941952, 3.494753, 3.280693, 3.642136, 3.190821],
        atol=1e-6,
    )


def test_geometry_and_residual(mech):
    assert np.allclose(
        np.linalg.norm(np.diff(mech.top_points[[0, 1, 2, 0]], axis=0), axis=1), mech.a
    )
    assert np.allclose(np.linalg.norm(mech.base_points, axis=1), mech.b)
    assert np.allclose(mech.base_points[0], [0, mech.b, 0]) and np.allclose(
        mech.base_points[3], [0, -mech.b, 0]
    )
    x = random_poses(mech, 50)
    q = mech.ik(x)
    assert np.max(np.abs(mech.residual(x, q))) < 1e-12
    assert np.max(mech.objective(x, q)) < 1e-25
    assert np.min(np.abs(mech.residual(x, q * 1.01))) > 1e-4


def test_analytic_jacobians(mech):
    x = random_poses(mech, 20, seed=1)
    q = mech.ik(x)
    jn = _central_difference(lambda xx: mech.residual(xx, q), x)
    assert np.allclose(mech.jacobian_pose(x, q), jn, atol=1e-6)
    jq = _central_difference(lambda qq: mech.residual(x, qq), q)
    assert np.allclose(mech.jacobian_joints(x, q), jq, atol=1e-6)


def test_newton_fk_from_nearby_random_starts():
    m = Stewart36()
    x = random_poses(m, 2000, seed=2)
    q = m.ik(x)
    x0 = x + np.random.default_rng(3).normal(0, 0.02, x.shape)
    res = solve_fk(m, q, x0=x0, method="newton", tol=1e-12, maxiter=30)
    assert res.success.mean() > 0.99
    assert np.max(np.abs(m.ik(res.x[res.success]) - q[res.success])) < 1e-9
    # near singular poses some starts land on a neighbouring assembly; most return to the true pose
    ok = res.success & (np.max(np.abs(wrap(res.x - x)), axis=-1) < 1e-8)
    assert ok.mean() > 0.95


def test_mirror_has_same_legs(mech):
    x = random_poses(mech, 200, seed=4)
    assert np.array_equal(mech.ik(x), mech.ik(mech.mirror(x)))


def test_fk_all_certified_roots_and_true_pose():
    """>= 500 random poses per b: every root verified by IK to 1e-9, the true pose among the roots,
    roots in mirror pairs, polynomial of degree 16."""
    for b in (1.0, 3.0):
        m = Stewart36(b=b)
        x = random_poses(m, 500, seed=5)
        q = m.ik(x)
        sols, info = m.fk_all(q, return_info=True)
        assert np.all(info["n_complex"] == 16)
        assert np.max(info["tail"]) < 1e-9
        fin = np.isfinite(sols[..., 0])
        err = np.abs(m.ik(np.nan_to_num(sols)) - q[:, None, :]).max(-1)
        assert np.all(err[fin] <= 1e-9)
        d = np.max(np.abs(wrap(np.nan_to_num(sols, nan=1e9) - x[:, None, :])), axis=-1).min(-1)
        assert np.all(d < 1e-7), f"true pose missing for {np.sum(d >= 1e-7)} inputs (b = {b})"
        # mirror pairs: even counts, and each solution's mirror is a solution
        assert np.all(info["n_real"] % 2 == 0)
        mir = m.mirror(np.nan_to_num(sols))
        dm = np.max(
            np.abs(wrap(mir[:, :, None, :] - np.nan_to_num(sols, nan=1e9)[:, None, :, :])), -1
        ).min(-1)
        assert np.all(dm[fin] < 1e-7)
        assert np.all(info["n_above"] * 2 == info["n_real"])


def test_fk_all_reconstructed_input_counts():
    # docs/li2017_stewart36.md#s4.3: 4 real (2 above) for b = 1, 2; 8 real (4 above) for b = 3; row 1 among them
    for b, n in ((1.0, 4), (2.0, 4), (3.0, 8)):
        m = Stewart36(b=b)
        sols = m.fk_all(m.ik(m.home()))
        real = sols[np.isfinite(sols[:, 0])]
        assert len(real) == n
        assert np.min(np.max(np.abs(real - m.home()), axis=-1)) < 1e-10


def test_bad_leg_lengths_raise():
    m = Stewart36(b=3.0)
    q = m.ik(m.home())
    m.check_joints(q)
    bad = q.copy()
    bad[1] = bad[0] + 3.5  # |L1 - L2| > b
    with pytest.raises(UnreachableError, match=r"\|L1 - L2\| = 3\.5 exceeds the base edge b = 3"):
        m.check_joints(bad)
    bad = q.copy()
    bad[2:4] = 1.0  # L3 + L4 < b
    with pytest.raises(UnreachableError, match="L3 \\+ L4 = 2 is shorter than the base edge b = 3"):
        m.check_joints(bad)
    bad = q.copy()
    bad[5] = -1.0
    with pytest.raises(UnreachableError, match="L6 = -1 must be > 0"):
        m.check_joints(bad)
    sols = m.fk_all(np.array([q, bad]))
    assert np.all(np.isnan(sols[1]))
    with pytest.raises(ValueError):
        Stewart36(b=0.0)


def test_skeleton():
    m = Stewart36()
    sk = m.skeleton(m.home())
    assert len(sk.segments) == 6
    lengths = [np.linalg.norm(seg[1] - seg[0]) for _, seg in sk.segments]
    assert np.allclose(lengths, m.ik(m.home()))


def test_fk_all_near_triple_cluster_keeps_mirror_pairs():
    """b = 3 input (random sample 325 of the counts artefact) whose degree-16 polynomial has three real
    t1 roots within 0.008 (~0.2477, 0.2487, 0.2550): complex Newton used to send two of them to the
    same solution, giving 10 real solutions (5 mirror pairs). The truth is 12 (6 pairs)."""
    m = Stewart36(b=3.0)
    q = np.array(
        [
            3.9211831668661516,
            3.3199299404926013,
            3.389189195533072,
            3.0564559700375993,
            3.4826360889603336,
            3.6066525832391036,
        ]
    )
    sols, info = m.fk_all(q, return_info=True)
    real = sols[np.isfinite(sols[:, 0])]
    assert info["n_real"] == 12 and info["n_above"] == 6
    assert np.max(np.abs(m.ik(real) - q)) < 1e-9
    up, down = real[real[:, 5] > 0], real[real[:, 5] < 0]
    mirror = down * np.array([1, -1, -1, 1, 1, -1])
    for s in up:  # each above-base solution has its mirror (alpha, -beta, -gamma, X, Y, -Z)
        assert np.min(np.max(np.abs(mirror - s), axis=-1)) < 1e-8
    # all distinct
    d = np.max(np.abs(real[:, None] - real[None]), axis=-1) + np.eye(len(real))
    assert d.min() > 1e-6


def test_fk_returns_the_assembly_nearest_the_reference():
    m = Stewart36()
    rng = np.random.default_rng(11)
    poses = m.home() + rng.normal(scale=[0.03, 0.03, 0.03, 0.02, 0.02, 0.02], size=(50, 6))
    assert np.max(np.abs(m.fk(m.ik(poses)) - poses)) < 1e-9
    # from a reference at the mirror-free alternative, another assembly of the same legs comes back
    sols = m.fk_all(m.ik(m.home()))
    up = sols[np.isfinite(sols[:, 0]) & (np.nan_to_num(sols[:, 5]) > 0)]
    other = up[np.argmax(np.linalg.norm(up - m.home(), axis=-1))]
    assert np.allclose(m.fk(m.ik(m.home()), near=other), other, atol=1e-9)
