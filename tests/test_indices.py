"""Performance indices of Zhao 2017 §3 (eqs 24-37): hand values at the centre, invariances, the
delta-only dependence, the batched mass matrix against the dynamics module, quadrature convergence."""

import numpy as np
import pytest

from parakin.errors import UnreachableError
from parakin.mechanisms import P3P4S
from parakin.mechanisms import p3p4s_dynamics as dyn
from parakin.mechanisms import p3p4s_indices as ix

BEFORE = P3P4S.zhao2017()
AFTER = P3P4S.zhao2017_optimised()
PARAMS = dyn.InertialParams.zhao2017()
W = ix.Workspace.square(0.585, 0.05)


def _tilt(mech, z):
    """Rod tilt beta from vertical at (0, 0, z): n_1 = (-sin b, 0, cos b) (inward lean)."""
    n = mech.rod_directions(np.array([0.0, 0.0, z]))[0]
    return np.arctan2(-n[0], n[2])


@pytest.mark.parametrize("mech,z", [(BEFORE, 0.592), (BEFORE, 0.57), (AFTER, 0.64), (AFTER, 0.585)])
def test_centre_line_closed_forms(mech, z):
    b, phi = _tilt(mech, z), mech.phi
    ind = ix.mech_indices(mech, [0.0, 0.0, z])
    assert ind.speed == pytest.approx(np.sqrt(2) / np.tan(b), rel=1e-12)
    smin = np.sqrt(1.5) * np.sin(b) / np.sin(b + phi)
    assert ind.stiffness_sqrt == pytest.approx(smin, rel=1e-12)
    assert ind.stiffness_lambda == pytest.approx(smin**2, rel=1e-12)


def test_home_values_of_the_notes():
    ind = ix.mech_indices(BEFORE, BEFORE.home())
    assert ind.speed == pytest.approx(9.936, abs=5e-4)
    assert ind.dynamic == pytest.approx(28.77, abs=5e-3)
    assert ind.stiffness_lambda == pytest.approx(0.078, abs=5e-4)


def test_mass_matrix_batched_equals_dynamics_module():
    rng = np.random.default_rng(3)
    poses = np.column_stack([rng.uniform(-0.05, 0.05, (20, 2)), rng.uniform(0.55, 0.59, 20)])
    for mech in (BEFORE, AFTER):
        ref = ix.mass_matrix(mech, PARAMS, poses)
        fast = ix.mass_matrix_batched(mech.delta, mech.L, mech.phi, poses)[0]
        np.testing.assert_allclose(fast, ref, rtol=1e-12, atol=1e-12)
    # and the column definition: M e_k is the force for unit acceleration e_k, v = 0, gravity off
    f = dyn.inverse_dynamics(
        BEFORE, dyn.InertialParams(g=(0.0, 0.0, 0.0)), poses[0], np.zeros(3), [0.0, 1.0, 0.0]
    )
    np.testing.assert_allclose(ix.mass_matrix(BEFORE, PARAMS, poses[0])[:, 1], f, rtol=1e-12)


def test_batched_equals_loop():
    x, _ = W.nodes(4)
    loop = ix.local_indices_loop(AFTER, x, k=3.0)
    ind = ix.local_indices(AFTER.delta, AFTER.L, AFTER.phi, x, k=3.0)
    np.testing.assert_allclose(np.stack([ind[k][0] for k in ix.INDEX_NAMES], -1), loop, rtol=1e-10)


def test_speed_index_invariants():
    rng = np.random.default_rng(0)
    x = np.column_stack([rng.uniform(-0.08, 0.08, (500, 2)), rng.uniform(0.53, 0.60, 500)])
    ind = ix.mech_indices(BEFORE, x)
    assert np.all(ind.speed >= 1.0)
    # stiffness scales with k, sqrt form with sqrt(k); dynamic and speed do not depend on k
    ind5 = ix.mech_indices(BEFORE, x, k=5.0)
    np.testing.assert_allclose(ind5.stiffness_lambda, 5 * ind.stiffness_lambda, rtol=1e-12)
    np.testing.assert_allclose(ind5.stiffness_sqrt, np.sqrt(5) * ind.stiffness_sqrt, rtol=1e-12)
    np.testing.assert_array_equal(ind5.speed, ind.speed)


def test_isotropic_design_has_unit_speed_index():
    # cond = sqrt(2) cot(beta) = 1 at the centre when beta = atan(sqrt 2): choose delta for that tilt
    beta = np.arctan(np.sqrt(2.0))
    L, phi, z = 0.38, np.deg2rad(30.0), 0.5
    # rod from c = (delta - q cos phi, 0, q sin phi) to p = (0, 0, z): n = (-sin b, 0, cos b)
    q = (z - L * np.cos(beta)) / np.sin(phi)
    delta = q * np.cos(phi) + L * np.sin(beta)
    ind = ix.local_indices(delta, L, phi, [[0.0, 0.0, z]])
    assert ind.speed[0, 0] == pytest.approx(1.0, abs=1e-12)
    # and a hand-made isotropic J: rows n_i/nm_i orthogonal of equal norm -> singular values equal
    J = np.eye(3) * 2.5
    s = np.linalg.svd(J, compute_uv=False)
    assert s[0] / s[-1] == 1.0


def test_indices_depend_on_delta_only():
    x, _ = W.nodes(5)
    a = P3P4S(r_a=0.25, r_b=0.67, d=0.12)
    b = P3P4S.from_delta(a.delta, a.L, a.phi, r_a=0.20, d=0.08)
    assert b.r_a != a.r_a and b.delta == pytest.approx(a.delta, abs=1e-15)
    ia, ib = ix.mech_indices(a, x), ix.mech_indices(b, x)
    for k in ix.INDEX_NAMES:
        np.testing.assert_allclose(ia[k], ib[k], rtol=1e-12)
    X = np.array([[0.25, 0.67, 0.38, 0.12, a.phi], [0.20, b.r_b, 0.38, 0.08, a.phi]])
    F = ix.design_objectives(X, W, 4)
    np.testing.assert_allclose(F[0], F[1], rtol=1e-12)


def test_quadrature_converges_and_gauss_beats_midpoint():
    g = {
        n: ix.global_indices([BEFORE.delta], [BEFORE.L], [BEFORE.phi], W, n)
        for n in (8, 16, 32, 48)
    }
    ref = g[48]
    for attr in ("sigma1", "sigma2_lambda", "sigma3"):
        # grid doubling 16 -> 32 does not move the 3rd significant digit
        assert abs(getattr(g[32], attr)[0] / getattr(g[16], attr)[0] - 1) < 5e-4
        assert abs(getattr(g[16], attr)[0] / getattr(ref, attr)[0] - 1) < 5e-4
    mid = ix.global_indices([BEFORE.delta], [BEFORE.L], [BEFORE.phi], W, 16, rule="midpoint")
    assert abs(mid.sigma1[0] / ref.sigma1[0] - 1) > abs(g[16].sigma1[0] / ref.sigma1[0] - 1)
    # the weights of a planar workspace sum to 1 and integrate x^2 exactly
    x, w = W.nodes(5)
    assert w.sum() == pytest.approx(1.0, abs=1e-15)
    assert w @ x[:, 0] ** 2 == pytest.approx(0.05**2 / 3, rel=1e-12)
    x3, w3 = ix.Workspace.square(0.57, 0.05, 0.02).nodes(3)
    assert x3.shape == (27, 3) and w3 @ x3[:, 2] == pytest.approx(0.57, rel=1e-12)


def test_before_design_near_the_paper():
    g = ix.global_indices([BEFORE.delta], [BEFORE.L], [BEFORE.phi], W, 16)
    assert abs(g.sigma1[0] / 29.9205 - 1) < 0.05
    assert abs(g.sigma3[0] / 10.0075 - 1) < 0.05


def test_infeasible_designs_are_flagged_not_raised():
    x, _ = W.nodes(3)
    ind = ix.local_indices([BEFORE.delta, 0.2], [0.38, 0.2], [BEFORE.phi, 0.5], x)
    assert ind.feasible[0].all() and not ind.feasible[1].any()
    assert np.isnan(ind.dynamic[1]).all()
    F = ix.design_objectives(
        [[0.25, 0.67, 0.38, 0.12, BEFORE.phi], [0.25, 0.67, 0.38, 0.12, BEFORE.phi]],
        W,
        3,
        max_speed=5.0,
    )
    assert np.isnan(F).all()  # max cond over W is ~12 > 5


def test_bad_input():
    with pytest.raises(UnreachableError):
        ix.mech_indices(BEFORE, [0.0, 0.0, 0.9])
    with pytest.raises(ValueError, match="k ="):
        ix.local_indices(0.4, 0.38, 0.5, [[0, 0, 0.58]], k=-1.0)
    with pytest.raises(ValueError, match="phi"):
        ix.local_indices(0.4, 0.38, 2.0, [[0, 0, 0.58]])
    with pytest.raises(ValueError, match="half_width"):
        ix.Workspace.square(0.58, 0.0)
    with pytest.raises(ValueError, match="rule"):
        W.nodes(4, "simpson")
    with pytest.raises(ValueError, match="d ="):
        ix.design_arrays(0.05, 0.7, 0.38, 0.12, 0.5)
    with pytest.raises(ValueError, match="shape"):
        ix.design_objectives(np.zeros((2, 3)), W, 3)


# ------------------------------------------------------------------------------ any mechanism
def test_kinematic_indices_agree_with_the_3p4s_indices():
    from parakin.indices import kinematic_indices
    from parakin.mechanisms import P3P4S
    from parakin.mechanisms.p3p4s_indices import mech_indices
    from parakin.workspace import sample_reachable

    m = P3P4S()
    x = sample_reachable(m, 50, np.random.default_rng(4))
    gen = kinematic_indices(m, x, k=2.0)
    own = mech_indices(m, x, k=2.0)
    np.testing.assert_allclose(gen["speed"], own.speed, rtol=1e-10)
    np.testing.assert_allclose(gen["stiffness_lambda"], own.stiffness_lambda, rtol=1e-10)
    np.testing.assert_allclose(gen["stiffness_sqrt"], own.stiffness_sqrt, rtol=1e-10)
    np.testing.assert_allclose(
        gen["manipulability"], np.abs(np.linalg.det(m.velocity_jacobian(x))), rtol=1e-10
    )


def test_global_kinematic_indices_match_the_3p4s_global_speed_index():
    from parakin.indices import global_kinematic_indices
    from parakin.mechanisms import P3P4S
    from parakin.mechanisms.p3p4s_indices import Workspace, global_indices

    m = P3P4S()
    ws = Workspace.square(0.585, 0.05)
    lo, hi = np.array([ws.x[0], ws.y[0], ws.z[0]]), np.array([ws.x[1], ws.y[1], ws.z[1]])
    gen = global_kinematic_indices(m, lo, hi, 8)
    own = global_indices(m.delta, m.L, m.phi, ws, 8)
    assert gen["speed"] == pytest.approx(float(np.ravel(own.sigma3)[0]), rel=1e-10)
    assert gen["stiffness_lambda"] == pytest.approx(
        float(np.ravel(own.sigma2_lambda)[0]), rel=1e-10
    )
    with pytest.raises(UnreachableError, match="quadrature node"):
        global_kinematic_indices(m, lo, hi + np.array([0, 0, 0.5]), 4)


def test_box_nodes_integrate_polynomials_exactly():
    from parakin.indices import box_nodes

    x, w = box_nodes([0.0, 1.0, 2.0], [1.0, 3.0, 2.0], 3)  # third axis fixed
    assert x.shape == (9, 3) and np.all(x[:, 2] == 2.0)
    assert w.sum() == pytest.approx(1.0)
    assert w @ (x[:, 0] ** 5 * x[:, 1] ** 3) == pytest.approx(
        (1 / 6) * (3**4 - 1) / 4 / 2, rel=1e-12
    )
    with pytest.raises(ValueError, match="lo <= hi"):
        box_nodes([1.0], [0.0], 3)
