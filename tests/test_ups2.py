"""The 2-UPS/(S+SPR)R mechanism of Li 2020: IK vector form vs sympy, Jacobians, all-solutions FK,
stroke limits."""

import numpy as np
import pytest

from parakin.errors import UnreachableError
from parakin.mechanisms.base import _central_difference
from parakin.mechanisms.ups2 import UPS2


@pytest.fixture
def mech() -> UPS2:
    return UPS2()


def box_poses(mech, n, seed=0):
    lo, hi = mech.pose_bounds()
    return np.random.default_rng(seed).uniform(lo, hi, (n, 3))


def test_home_lengths_match_notes(mech):
    assert np.allclose(mech.home_lengths * 1e3, [238.4848, 305.8140, 305.8140], atol=1e-4)
    assert np.allclose(mech.ik(mech.home()), 0.0)


def test_sympy_derivation_alpha_zero_and_ik():
    from parakin.papers.li2020_2ups.symbolic import derivation

    d = derivation()
    assert d["eq7_ok"] and d["P_ok"] and all(d["ik_ok"])
    assert d["alpha_solutions"] == pytest.approx([0.0, np.pi])
    assert d["printed16_differs"]


def test_vector_form_equals_closed_form(mech):
    x = box_poses(mech, 500)
    assert np.max(np.abs(mech.lengths(x) - mech.lengths_closed_form(x))) < 1e-14


def test_closed_form_lambdified_from_sympy(mech):
    """Numbers from the symbolic closed forms (lambdified) equal the library's vector-form IK."""
    import sympy as sp

    b, g, Y = sp.symbols("beta gamma Y", real=True)
    a, bb, c = (sp.Float(v) for v in (mech.a, mech.b, mech.c))
    k, h, rho = sp.sqrt(2) / 2 * bb, sp.sqrt(3) / 2 * a, sp.sqrt(c**2 - Y**2)
    P = sp.Matrix([rho * sp.sin(b), Y, rho * sp.cos(b)])
    R = sp.Matrix([[sp.cos(b), 0, sp.sin(b)], [0, 1, 0], [-sp.sin(b), 0, sp.cos(b)]]) * sp.Matrix(
        [[1, 0, 0], [0, sp.cos(g), -sp.sin(g)], [0, sp.sin(g), sp.cos(g)]]
    )
    legs = [
        sp.Rational(2, 3) * P - sp.Matrix([0, h, 0]),
        P + R * sp.Matrix([k, k, 0]) - sp.Matrix([a / 2, h, 0]),
        P + R * sp.Matrix([-k, k, 0]) - sp.Matrix([-a / 2, h, 0]),
    ]
    f = sp.lambdify((b, g, Y), [sp.sqrt(v.dot(v)) for v in legs], "numpy")
    x = box_poses(mech, 200, seed=3)
    ref = np.stack(f(x[:, 0], x[:, 1], x[:, 2]), axis=-1)
    assert np.max(np.abs(mech.lengths(x) - ref)) < 1e-12


def test_jacobian_matches_finite_differences(mech):
    x = box_poses(mech, 200, seed=1)
    q = mech.ik(x)
    num = _central_difference(lambda p: mech.residual(p, q), x)
    assert np.max(np.abs(mech.jacobian_pose(x, q) - num)) < 1e-7
    assert np.allclose(mech.jacobian_joints(x, q), -np.eye(3))


def test_l1_depends_on_y_only_and_y_closed_form(mech):
    x = box_poses(mech, 300, seed=2)
    lengths = mech.lengths(x)
    assert np.allclose(mech.y_from_l1(lengths[:, 0]), x[:, 2], atol=1e-12)


def test_fk_all_recovers_every_pose(mech):
    x = box_poses(mech, 1500, seed=4)
    q = mech.ik(x)
    sols = mech.fk_all(q)
    real = np.all(np.isfinite(sols), axis=-1)
    assert real.sum(-1).min() >= 1
    res = np.abs(mech.residual(np.where(real[..., None], sols, 0.0), q[:, None, :]))
    assert res[real].max() < 1e-9
    dist = np.nanmin(np.linalg.norm(sols - x[:, None, :], axis=-1), axis=1)
    assert dist.max() < 1e-9
    assert np.max(np.abs(mech.fk(q) - x)) < 1e-9


def test_fk_all_table2_matches_notes(mech):
    q = np.array([[0, -24, 26], [-23, -32, -32]]) * 1e-3
    f = mech.fk(q)
    assert np.allclose(np.rad2deg(f[0, :2]), [19.862, 0.817], atol=1e-3) and abs(f[0, 2]) < 1e-12
    assert np.allclose([np.rad2deg(f[1, 1]), f[1, 2] * 1e3], [-16.520, 60.283], atol=1e-3)


@pytest.mark.parametrize("q", [[0.024, 0.0, 0.0], [0.0, -0.033, 0.0], [0.0, 0.0, 0.0321]])
def test_strokes_beyond_eq19_raise(mech, q):
    with pytest.raises(UnreachableError, match="eq. 19"):
        mech.check_joints(q)


def test_unassemblable_strokes_raise(mech):
    with pytest.raises(UnreachableError, match="cannot be assembled"):
        mech.replace(stroke_limits=(1.0, 1.0, 1.0)).check_joints([0.0, 0.3, -0.3])
    with pytest.raises(UnreachableError, match="c ="):
        mech.ik([0.0, 0.0, 0.31])


def test_check_joints_accepts_table2_inputs(mech):
    mech.check_joints(np.array([[0, -24, 26], [2.43, -28.5, 21.5]]) * 1e-3)


def test_skeleton(mech):
    sk = mech.skeleton([0.2, 0.3, 0.03])
    assert len(sk.segments) == 4
    assert np.isclose(np.linalg.norm(sk.points["B1"]), mech.c)
    assert np.isclose(np.linalg.norm(sk.points["B2"] - sk.points["B3"]), np.sqrt(2) * mech.b)


def test_both_assembly_branches():
    """eq (14) has two branches rho = +-sqrt(c^2 - Y^2); fk_all finds the poses of each, and the
    strokes (measured from the paper's home pose) are the same physical inputs on both."""
    m = UPS2()
    mirror = UPS2(branch=-1)
    assert np.allclose(mirror.home_lengths, m.home_lengths)
    assert mirror.position(m.home())[2] < 0 < m.position(m.home())[2]  # platform below vs above
    rng = np.random.default_rng(5)
    lo, hi = m.pose_bounds()
    poses = rng.uniform(lo, hi, size=(300, 3)) * np.array([1.0, 1.0, 0.5])
    for mech in (m, mirror):
        q = mech.ik(poses)
        sols = m.fk_all_branches(q)[mech.branch]
        err = np.nanmin(np.max(np.abs(sols - poses[:, None, :]), axis=-1), axis=-1)
        assert np.all(err < 1e-9)
        fin = np.all(np.isfinite(sols), axis=-1)
        back = mech.ik(np.where(fin[..., None], sols, 0.0))
        assert np.max(np.abs(np.where(fin[..., None], back - q[:, None, :], 0.0))) < 1e-9
    with pytest.raises(ValueError, match="branch = 2"):
        UPS2(branch=2)
