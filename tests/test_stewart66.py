"""The general 6-6 Gough-Stewart platform: geometry checks, IK, Jacobians, generic solvers and the
certified all-40-solutions FK (parameter homotopy in Study coordinates)."""

from __future__ import annotations

import numpy as np
import pytest

from parakin.atlas import evaluate, make_scenario, standard_solvers
from parakin.errors import UnreachableError
from parakin.geometry import euler_zyx
from parakin.indices import kinematic_indices
from parakin.mechanisms import REGISTRY, Stewart36
from parakin.mechanisms import stewart66_homotopy as hc
from parakin.mechanisms.base import _central_difference
from parakin.mechanisms.stewart36 import LEG_TOP
from parakin.mechanisms.stewart66 import DIETMAIER_LENGTHS, Stewart66, load_start
from parakin.solvers import solve_fk
from parakin.studies import stewart66 as study


@pytest.fixture(scope="module")
def mech() -> Stewart66:
    return Stewart66()


@pytest.fixture(scope="module")
def random_mechs() -> list[Stewart66]:
    rng = np.random.default_rng(7)
    return [study.random_platform(rng) for _ in range(3)]


def _wrap(d):
    d = np.array(d, dtype=float)
    d[..., :3] = (d[..., :3] + np.pi) % (2 * np.pi) - np.pi
    return d


# ------------------------------------------------------------------------------------ the model
def test_registered_and_default_is_dietmaier(mech):
    assert REGISTRY["stewart66"] is Stewart66
    assert mech.base_points.shape == (6, 3) and mech.platform_points.shape == (6, 3)
    assert hash(mech) == hash(Stewart66())  # frozen, hashable parameters


def test_validation_messages():
    b, p = np.random.default_rng(0).normal(size=(2, 6, 3))
    with pytest.raises(ValueError, match=r"shape \(6, 3\)"):
        Stewart66(base=b[:5], platform=p)
    bad = p.copy()
    bad[2, 1] = np.nan
    with pytest.raises(ValueError, match=r"platform\[2\].*non-finite"):
        Stewart66(base=b, platform=bad)
    s = Stewart36()
    with pytest.raises(ValueError, match="3-6 layout.*Stewart36"):
        Stewart66(base=s.base_points, platform=s.top_points[LEG_TOP])
    dup = b.copy()
    dup[4] = dup[1]
    with pytest.raises(ValueError, match="base points 2=5"):
        Stewart66(base=dup, platform=p)
    line = np.outer(np.arange(6.0), [1.0, 2.0, 0.5])
    with pytest.raises(ValueError, match="architecturally singular"):
        Stewart66(base=line, platform=line * 0.3)


def test_ik_residual_and_jacobians(mech):
    rng = np.random.default_rng(1)
    x = study.random_pose(rng, 20, mech)
    q = mech.ik(x)
    v = mech.platform_points @ euler_zyx(*x[0, :3]).T + x[0, 3:] - mech.base_points
    assert np.allclose(q[0], np.linalg.norm(v, axis=-1), atol=1e-14)
    assert np.max(np.abs(mech.residual(x, q))) < 1e-13
    ja = mech.jacobian_pose(x, q)
    jn = _central_difference(lambda xx: mech.residual(xx, q), x)
    assert np.allclose(ja, jn, atol=1e-6, rtol=1e-6)
    jq = _central_difference(lambda qq: mech.residual(x, qq), q)
    assert np.allclose(mech.jacobian_joints(x, q), jq, atol=1e-6)
    assert mech.velocity_jacobian(x).shape == (20, 6, 6)
    ind = kinematic_indices(mech, x)
    assert np.all(np.isfinite(ind["speed"])) and np.all(ind["speed"] >= 1)


def test_study_formulation_vanishes_at_real_poses():
    rng = np.random.default_rng(2)
    b, p = rng.normal(size=(2, 6, 3))
    r = euler_zyx(*rng.normal(size=3))
    t = rng.normal(size=3)
    lengths = np.linalg.norm(p @ r.T + t - b, axis=-1)
    x = hc.pose_to_study(r, t) * (0.3 - 1.1j)  # any projective scale
    q = hc.quadrics(b, p, np.sum(p * p, -1) + np.sum(b * b, -1) - lengths**2)
    assert np.max(np.abs(np.einsum("mij,i,j->m", q, x, x))) < 1e-13
    r2, t2 = hc.study_to_rt(x)
    assert np.allclose(r2, r, atol=1e-14) and np.allclose(t2, t, atol=1e-14)


def test_stored_start_system_regenerates():
    """The stored 40 start solutions are what monodromy finds again from the same seed; each is a
    certified, distinct, nonsingular solution of the stored start system."""
    stored = load_start()
    assert stored["solutions"].shape == (40, 8)
    fresh = hc.generate_start(int(stored["seed"]))
    assert len(fresh["solutions"]) == 40
    for key in ("base", "platform", "c", "patch"):
        assert np.allclose(fresh[key], stored[key], atol=1e-12)
    d = np.linalg.norm(fresh["solutions"][:, None] - stored["solutions"][None], axis=-1)
    assert np.all(d.min(axis=1) < 1e-8) and len(set(d.argmin(axis=1))) == 40
    q = np.broadcast_to(hc.quadrics(stored["base"], stored["platform"], stored["c"]), (40, 7, 8, 8))
    x, beta, jn = hc.newton_refine(q, stored["patch"], stored["solutions"], iters=1)
    alpha = hc.certify(q, beta, jn)
    assert np.all(alpha < hc.ALPHA0)
    assert hc.distinct(x[None], beta[None], (alpha < hc.ALPHA0)[None], alpha[None]).all()


# ------------------------------------------------------------------------------------ all solutions
def test_dietmaier_has_40_real_certified_solutions(mech):
    r = mech.fk_all(DIETMAIER_LENGTHS, return_info=True)
    assert mech.root_count == 40
    assert r.n_found == 40 and r.complete and r.n_real == 40
    assert np.all(r.is_real[:40]) and np.nanmax(r.alpha) < hc.ALPHA0
    assert r.ik_error < 1e-12
    poses = r.poses[:40]
    assert np.max(np.abs(mech.ik(poses) - np.asarray(DIETMAIER_LENGTHS))) < 1e-12
    d = np.max(np.abs(_wrap(poses[:, None] - poses[None])), -1) + np.eye(40)
    assert d.min() > 1e-6  # 40 different assemblies
    assert np.all(np.diff(poses[:, 5]) <= 0)  # sorted by Z descending
    # the array form the generic all-solutions solver uses
    assert mech.fk_all(DIETMAIER_LENGTHS).shape == (40, 6)


def test_random_platforms_give_40_complex_and_recover_the_pose(random_mechs):
    rng = np.random.default_rng(3)
    for m in random_mechs:
        assert m.root_count == 40
        x = study.random_pose(rng, 30, m)
        r = m.fk_all(m.ik(x), return_info=True)
        assert np.all(r.complete) and np.all(r.n_found == 40)
        assert np.nanmax(r.alpha) < hc.ALPHA0 and np.nanmax(r.ik_error) < 1e-9
        assert np.all(r.n_real % 2 == 0) and np.all(
            r.n_real >= 2
        )  # non-real ones come in conjugate pairs
        d = np.max(np.abs(_wrap(r.poses - x[:, None])), -1)
        assert np.all(np.nanmin(d, axis=1) < 1e-9)  # the pose the legs came from is among them
        # complex solutions: rotation matrices with R^T R = I (no conjugation) and the leg equations
        rot, o = r.rotation[:, :40], r.translation[:, :40]
        assert np.allclose(np.swapaxes(rot, -1, -2) @ rot, np.eye(3), atol=1e-8)
        v = np.einsum("...ij,kj->...ki", rot, m.platform_points) + o[..., None, :] - m.base_points
        assert np.allclose(np.sum(v * v, -1), m.ik(x)[:, None, :] ** 2, atol=1e-7)


def test_batch_shapes_and_single_input(mech):
    rng = np.random.default_rng(4)
    x = study.random_pose(rng, 6, mech).reshape(2, 3, 6)
    q = mech.ik(x)
    sols = mech.fk_all(q)
    assert sols.shape == (2, 3, 40, 6)
    r = mech.fk_all(q, return_info=True)
    assert r.n_found.shape == (2, 3) and r.study.shape == (2, 3, 40, 8)
    one = mech.fk_all(q[1, 2])
    assert np.allclose(np.nan_to_num(one), np.nan_to_num(sols[1, 2]), atol=1e-10)
    with pytest.raises(UnreachableError, match="L3"):
        mech.fk_all([1, 1, -1, 1, 1, 1])


def test_three_six_special_case_agrees_with_stewart36():
    s = Stewart36()
    m = Stewart66(base=s.base_points, platform=s.top_points[LEG_TOP], allow_coincident=True)
    assert m.root_count == 16  # the 3-6 has 16 complex solutions, not 40
    rng = np.random.default_rng(5)
    x = np.concatenate(
        [
            rng.uniform(-0.5, 0.5, (5, 3)),
            rng.uniform(-0.3, 0.3, (5, 2)),
            rng.uniform(1.0, 2.0, (5, 1)),
        ],
        -1,
    )
    q = s.ik(x)
    r = m.fk_all(q, return_info=True)
    ref = s.fk_all(q)
    assert np.all(r.complete)
    for i in range(len(q)):
        a = r.poses[i][np.isfinite(r.poses[i, :, 0])]
        b = ref[i][np.isfinite(ref[i, :, 0])]
        assert len(a) == len(b)
        d = np.max(np.abs(_wrap(a[:, None] - b[None])), -1)
        assert np.all(d.min(1) < 1e-9) and np.all(d.min(0) < 1e-9)


# ------------------------------------------------------------------------------------ generic solvers
LOCAL = ["newton", "broyden", "bfgs", "lm", "gauss-newton", "broyden-ls", "scipy-root"]


@pytest.mark.parametrize("method", LOCAL)
def test_generic_solvers_converge_from_nearby_starts(mech, method):
    rng = np.random.default_rng(6)
    x = study.random_pose(rng, 40 if method != "scipy-root" else 10, mech)
    q = mech.ik(x)
    x0 = x + rng.normal(0, 0.01, x.shape)
    res = solve_fk(mech, q, x0=x0, method=method, tol=1e-10, maxiter=200)
    ok = res.success & (np.max(np.abs(_wrap(res.x - x)), -1) < 1e-6)
    assert ok.mean() >= 0.95, (method, ok.mean())


def test_all_solutions_closed_form_and_pso(mech):
    rng = np.random.default_rng(8)
    x = study.random_pose(rng, 5, mech)
    q = mech.ik(x)
    res = solve_fk(mech, q, x0=x + 0.01, method="all-solutions", tol=1e-10)
    assert np.all(res.success) and np.max(np.abs(_wrap(res.x - x))) < 1e-9
    res = solve_fk(mech, q, method="closed-form", tol=1e-10)  # fk: the real solution nearest home
    assert np.all(res.success) and np.max(np.abs(mech.residual(res.x, q))) < 1e-10
    assert np.allclose(res.x, mech.fk(q, near=mech.home()))
    lo, hi = mech.pose_bounds()
    res = solve_fk(
        mech,
        q[:2],
        x0=x[:2],
        method="pso",
        tol=1e-6,
        maxiter=300,
        swarm=30,
        bounds=(np.maximum(lo, x[:2].min(0) - 0.05), np.minimum(hi, x[:2].max(0) + 0.05)),
        seed=0,
    )
    # the swarm runs on the 6-6 through the protocol; it does not reach 1e-6 in 300 iterations (a
    # global search in 6-D, as on the 3-6), so only its finiteness and improvement are checked
    assert np.all(np.isfinite(res.x)) and np.max(np.abs(mech.residual(res.x, q[:2]))) < 0.5


def test_atlas_row(mech):
    rng = np.random.default_rng(9)
    sc = make_scenario(mech, "nominal", 20, rng)
    solvers = {s.method: s for s in standard_solvers(mech)}
    assert "all-solutions" in solvers
    assert np.all(mech.fk_all(sc.joints, return_info=True).complete)
    # "nearest the start" may pick a neighbouring assembly when the start (10 % of the box away) is closer to it
    row = evaluate(mech, solvers["all-solutions"], sc)
    assert row["success_rate"] >= 0.85
    assert (
        0 < evaluate(mech, solvers["newton"], sc)["success_rate"] <= 1
    )  # local: starts 10 % of the box away


# ------------------------------------------------------------------------------------ studies
def test_study_functions_write_figures(tmp_path):
    df = study.assemblies_data({})
    assert len(df) == 40 and df["ik_error"].max() < 1e-12
    assert study.assemblies_draw(df, tmp_path / "a.png").stat().st_size > 10_000
    counts = study.real_counts_data({"n_platforms": 2, "n_poses": 5})
    assert counts["complete"].all() and set(counts["set"]) == {"random platform", "Dietmaier"}
    assert study.real_counts_draw(counts, tmp_path / "h.png").exists()
    t = study.timing_data({"n_timing": 10})
    assert len(t) == 3 and (t["inputs_per_s"] > 0).all()
    assert study.timing_draw(t, tmp_path / "t.png").exists()


@pytest.mark.slow
def test_slow_validation_random_platforms():
    """>= 1000 random platforms (one pose each) and 2000 random poses of Dietmaier's platform:
    every input complete (40 certified solutions), real ones IK-checked."""
    df = study.real_counts_data({"n_platforms": 1000, "n_poses": 2000, "seed": 2026})
    assert df["complete"].mean() >= 0.999
    assert (df["root_count"] == 40).all()
    assert np.nanmax(df["ik_error"]) < 1e-8


def test_independent_check_by_bertini2(mech):
    """Bertini 2 (the ``bertini2`` wheel, import name ``bertini``), total-degree homotopy on the same
    Study system of Dietmaier's input (dehomogenised by e0 = 1): the same 40 solutions, all real."""
    b = pytest.importorskip("bertini")
    b.recording(False)  # bertini2 records every solve in ./bertini_output unless told not to
    bs, ps, *_ = mech._scaled
    q = hc.quadrics(bs, ps, mech._target_c(np.asarray(DIETMAIER_LENGTHS)[None])[0]).real
    names = ["e1", "e2", "e3", "g0", "g1", "g2", "g3"]
    v = [b.Variable(n) for n in names]
    x = [1] + v
    system = b.System()
    system.add_variable_group(v)
    for k in range(7):
        f = None
        for i in range(8):
            for j in range(8):
                if q[k, i, j] != 0:
                    c = b.coefficient(repr(float(q[k, i, j])))
                    term = c * x[i] * x[j] if (i or j) else c
                    f = term if f is None else f + term
        system.add_function(f)
    res = b.solve(system, seed=1, show_progress=False)
    theirs = np.array([[1] + [complex(z) for z in p] for p in res.solutions])
    r = mech.fk_all(DIETMAIER_LENGTHS, return_info=True)
    ours = r.study[:40] / r.study[:40, :1]
    d = np.abs(theirs[:, None] - ours[None]).max(-1)
    assert len(theirs) == 40 and np.all(d.min(0) < 1e-6) and np.all(d.min(1) < 1e-6)


# ------------------------------------------------------------------------- compiled fk_all
def _solution_sets_agree(a, b, i, tol=1e-9):
    """Input ``i``'s certified solutions in ``a`` and ``b`` (FKAll) are the same set."""
    sa = a.study[i][np.isfinite(a.study[i, :, 0])]
    sb = b.study[i][np.isfinite(b.study[i, :, 0])]
    if len(sa) != len(sb):
        return False
    # e.e = 1 fixes the projective scale up to sign
    d = np.minimum(np.abs(sa[:, None] - sb[None]).max(-1), np.abs(sa[:, None] + sb[None]).max(-1))
    return bool(np.all(d.min(0) < tol) and np.all(d.min(1) < tol))


def test_compiled_fk_all_same_solutions_as_numpy(mech, random_mechs, monkeypatch):
    """parakin.kernels.stewart66_track (the whole fk_all compiled: Taylor/Padé tracker in lanes,
    certificates, poses) finds the same certified solution sets, real poses and counts as the
    numpy path."""
    pytest.importorskip("numba")
    from parakin import kernels

    if not kernels.enabled():
        pytest.skip("compiled kernels switched off")
    rng = np.random.default_rng(12)
    for m in (mech, random_mechs[0]):
        q = m.ik(study.random_pose(rng, 4, m))
        got = m.fk_all(q, return_info=True)
        with monkeypatch.context() as mp:
            mp.setenv("PARAKIN_KERNELS", "0")
            ref = m.fk_all(q, return_info=True)
        for k in ("n_found", "n_real", "n_undecided", "complete"):
            assert np.array_equal(getattr(got, k), getattr(ref, k)), k
        assert np.array_equal(np.isnan(got.poses), np.isnan(ref.poses))
        assert np.nanmax(np.abs(_wrap(got.poses - ref.poses))) < 1e-9
        assert all(_solution_sets_agree(got, ref, i) for i in range(len(q)))
        assert np.nanmax(got.alpha) < hc.ALPHA0 and np.nanmax(got.ik_error) < 1e-12
        # the complex solutions as rotations (R^T R = I, no conjugation) and origins satisfy the legs
        rot, o = got.rotation[:, :40], got.translation[:, :40]
        v = np.einsum("...ij,kj->...ki", rot, m.platform_points) + o[..., None, :] - m.base_points
        ok = np.isfinite(v[..., 0, 0])
        legs = np.broadcast_to(q[:, None, :], ok.shape + (6,))
        assert np.allclose(np.sum(v * v, -1)[ok], legs[ok] ** 2, atol=1e-7)


def test_compiled_fk_all_is_deterministic(mech):
    """The same bits whatever the batch around an input and the number of threads: each path's
    arithmetic does not depend on its lane, block or thread."""
    pytest.importorskip("numba")
    from parakin import kernels

    if not kernels.enabled():
        pytest.skip("compiled kernels switched off")
    from parakin.kernels import stewart66_track as tk

    rng = np.random.default_rng(13)
    q = mech.ik(study.random_pose(rng, 7, mech))
    kernel, prepared = mech._kernel
    c1 = mech._target_c(q)
    one = tk.fk_all(prepared, c1, q, alpha0=hc.ALPHA0, threads=1)
    two = tk.fk_all(prepared, c1, q, alpha0=hc.ALPHA0, threads=2)
    alone = tk.fk_all(prepared, c1[3:4], q[3:4], alpha0=hc.ALPHA0, threads=2)
    for k in one:
        assert np.array_equal(one[k], two[k], equal_nan=True), k
        assert np.array_equal(one[k][3:4], alone[k], equal_nan=True), k
    with pytest.raises(ValueError, match="unknown tracking option"):
        tk.options_vector({"tau": 1.0})


def test_numpy_path_when_kernels_are_off(mech, monkeypatch):
    from parakin.mechanisms import stewart66 as s66

    monkeypatch.setenv("PARAKIN_KERNELS", "0")
    assert s66._compiled_kernel(mech.fk_start["q0"]) is None
    monkeypatch.setenv("PARAKIN_KERNELS", "1")
    q0 = mech.fk_start["q0"].astype(complex) * (1 + 1e-3j)  # a complex geometry: numpy
    assert s66._compiled_kernel(q0) is None


def _projective_sets_agree(a, b, tol=1e-9):
    """Two sets of Study points (rows, any chart) are the same projective points."""
    if len(a) != len(b):
        return False
    a = a / np.linalg.norm(a, axis=1, keepdims=True)
    b = b / np.linalg.norm(b, axis=1, keepdims=True)
    # |<a, b>| = 1 exactly for the same projective point (unit representatives)
    return bool(np.all(np.abs(np.abs(a.conj() @ b.T) - 1).min(1) < tol))


def test_compiled_start_system_is_the_numpy_one(random_mechs):
    """A geometry's start system by the lane tracker (parakin.kernels.stewart66_lanes, the general
    parameter homotopy from the stored start) and by the numpy tracker: the same 40 certified
    points of P^7; and the lane tracker's endpoints of the 40 paths are the numpy tracker's
    wherever both reach t = 1 (the same paths, apart by the corrector's accuracy)."""
    pytest.importorskip("numba")
    from parakin import kernels
    from parakin.mechanisms import stewart66 as s66

    if not kernels.enabled():
        pytest.skip("compiled kernels switched off")
    st = load_start()
    m = random_mechs[1]
    source = (st["base"], st["platform"], st["c"])
    target = (*m._scaled[:2], m.fk_start["c"])
    xc, okc, _ = s66._start_track(st["patch"], source, target, st["solutions"])
    with kernels.interpreted():
        xn, okn, _ = s66._start_track(st["patch"], source, target, st["solutions"])
    both = okc & okn
    assert both.sum() >= 30
    d = np.abs(xc[both] - xn[both]).max(1) / np.abs(xn[both]).max(1)
    assert np.median(d) < 1e-8
    compiled = Stewart66(base=m.base_points, platform=m.platform_points)
    with kernels.interpreted():
        numpy_start = Stewart66(base=m.base_points, platform=m.platform_points).fk_start
    assert len(compiled.fk_start["solutions"]) == len(numpy_start["solutions"]) == 40
    assert _projective_sets_agree(compiled.fk_start["solutions"], numpy_start["solutions"])


def test_new_geometry_path_finds_what_the_fibre_finds(random_mechs):
    """A geometry's first single input takes the new-geometry path (one homotopy from the stored
    generic start, no start system built); with the start system built, the same input takes the
    fibre: the same certified solutions, real poses and counts either way."""
    pytest.importorskip("numba")
    from parakin import kernels

    if not kernels.enabled():
        pytest.skip("compiled kernels switched off")
    rng = np.random.default_rng(14)
    for m in random_mechs:
        for q in m.ik(study.random_pose(rng, 3, m)):
            fresh = Stewart66(base=m.base_points, platform=m.platform_points)
            new = fresh.fk_all(q, return_info=True)
            assert "fk_start" not in fresh.__dict__  # no start system was built
            assert m.root_count == 40
            fibre = m.fk_all(q, return_info=True)
            for k in ("n_found", "n_real", "n_undecided", "complete"):
                assert np.array_equal(getattr(new, k), getattr(fibre, k)), k
            assert new.complete and new.n_found == 40
            assert np.nanmax(np.abs(_wrap(new.poses - fibre.poses))) < 1e-9
            a = new.study[np.isfinite(new.study[:, 0])]
            b = fibre.study[np.isfinite(fibre.study[:, 0])]
            assert _projective_sets_agree(a, b)


def test_a_geometry_called_again_builds_its_start_system(random_mechs):
    """The first single input on a geometry takes the new-geometry path; the second call on the
    same instance builds the geometry's start system and takes the fibre, as every later call:
    the same certified counts and real poses as the first call's path."""
    pytest.importorskip("numba")
    from parakin import kernels

    if not kernels.enabled():
        pytest.skip("compiled kernels switched off")
    rng = np.random.default_rng(16)
    m = random_mechs[0]
    q = m.ik(study.random_pose(rng, 2, m))
    fresh = Stewart66(base=m.base_points, platform=m.platform_points)
    first = fresh.fk_all(q[0], return_info=True)
    assert "fk_start" not in fresh.__dict__
    again = fresh.fk_all(q[0], return_info=True)
    assert "fk_start" in fresh.__dict__  # built on the second call
    later = fresh.fk_all(q[1], return_info=True)
    reference = Stewart66(base=m.base_points, platform=m.platform_points).fk_all(
        q, return_info=True
    )  # two inputs at once: the fibre
    for k in ("n_found", "n_real", "n_undecided", "complete"):
        assert np.array_equal(getattr(first, k), getattr(again, k)), k
        assert np.array_equal(getattr(later, k), getattr(reference, k)[1]), k
    assert np.nanmax(np.abs(_wrap(first.poses - again.poses))) < 1e-9
    np.testing.assert_array_equal(later.poses, reference.poses[1])  # the fibre: the same bits


def test_far_from_real_decides_only_what_the_full_reality_test_decides(
    mech, random_mechs, monkeypatch
):
    """The reality test's shortcut (a solution farther from every real point than its certified
    radius is not real, with no Newton in a real chart) changes no result: every array of the
    answer is the same bits with the shortcut switched off (every solution through the full test),
    on Dietmaier's platform (40 real: it marks none) and on random ones (where it marks most of the
    solutions the full test calls not real)."""
    pytest.importorskip("numba")
    from parakin import kernels
    from parakin.kernels import stewart66_track as track

    if not kernels.enabled():
        pytest.skip("compiled kernels switched off")
    rng = np.random.default_rng(17)
    cases = [(mech, np.asarray(DIETMAIER_LENGTHS)[None])]
    cases += [(m, m.ik(study.random_pose(rng, 3, m))) for m in random_mechs[:3]]
    shortcut = track._far_from_real
    marked = []

    def counted(x, beta, alpha, idx, far):
        shortcut(x, beta, alpha, idx, far)
        marked.append(int(far.sum()))

    def off(x, beta, alpha, idx, far):
        far[:] = False

    for m, q in cases:
        m.fk_all(q[0])
        m.fk_all(q[0])  # a geometry's first single call takes another path (the fibre after)
        marked.clear()
        monkeypatch.setattr(track, "_far_from_real", counted)
        fast = m.fk_all(q, return_info=True)
        monkeypatch.setattr(track, "_far_from_real", off)
        full = m.fk_all(q, return_info=True)
        for k, v in vars(fast).items():
            if isinstance(v, np.ndarray):
                assert v.tobytes() == getattr(full, k).tobytes(), k
        not_real = int((fast.n_found - fast.n_real - fast.n_undecided).sum())
        assert sum(marked) <= not_real  # it never marks a real or an undecided solution ...
        if m is mech:
            assert sum(marked) == 0 and fast.n_real == 40
        else:
            assert sum(marked) >= 0.9 * not_real > 0  # ... and it marks most of the others


def test_many_geometries_in_one_batch_are_deterministic():
    """fk_all_geometries: every input its own geometry, all paths side by side; the same bits as
    one call per geometry and whatever the thread count."""
    pytest.importorskip("numba")
    import numba

    from parakin.mechanisms.stewart66 import fk_all_geometries, random_platform

    rng = np.random.default_rng(15)
    ms = [random_platform(rng) for _ in range(5)]
    b = np.stack([m.base_points for m in ms])
    p = np.stack([m.platform_points for m in ms])
    q = np.stack([m.ik(study.random_pose(rng, 1, m))[0] for m in ms])
    r = fk_all_geometries(b, p, q)
    assert r.poses.shape == (5, 40, 6) and np.all(r.complete)
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        one = fk_all_geometries(b, p, q)
    finally:
        numba.set_num_threads(threads)
    alone = Stewart66(base=b[3], platform=p[3]).fk_all(q[3], return_info=True)
    for k in ("poses", "study", "alpha", "n_real"):
        assert np.array_equal(getattr(r, k), getattr(one, k), equal_nan=True), k
        assert np.array_equal(getattr(r, k)[3], getattr(alone, k), equal_nan=True), k
    with pytest.raises(ValueError, match=r"\(n, 6, 3\)"):
        fk_all_geometries(b[:, :5], p, q)


def test_a_fibre_step_moves_only_the_leg_constants():
    """On a fibre (a known geometry: only the leg constants move), a step evaluates the leg
    constants' coefficients alone (``theta_c``); the others, written once per path
    (``_lane_constants``), are the same bits as :func:`theta` gives at any ``t`` in [0, 1]
    (their higher terms are signed zeros), and ``theta_c`` is ``theta``'s leg constants."""
    numba = pytest.importorskip("numba")
    from parakin.kernels import stewart66_lanes as lanes

    @numba.njit
    def fibre_theta(POLY, tt, TH, n):
        lanes.theta_c(POLY, tt, TH, n)
        for ln in range(n):
            lanes._lane_constants(POLY, TH, ln)

    W = lanes.LANES
    rng = np.random.default_rng(18)
    par = np.zeros((W, 3, 6, 7), complex)  # a fibre: anchors at rest, leg constants on a segment
    par[:, 0] = rng.normal(size=(W, 6, 7)) + 1j * rng.normal(size=(W, 6, 7))
    par[:, 1:, :, 6] = rng.normal(size=(W, 2, 6)) + 1j * rng.normal(size=(W, 2, 6))
    par[: W // 2, 0, :, :6] *= -1  # signed zeros of both signs in the products
    POLY = np.zeros((3, 2, 6, lanes.NTH, W))
    for ln in range(W):
        lanes.path_coefficients(par, ln, POLY, ln)
    tt = np.concatenate([[0.0, 1.0], rng.uniform(size=W - 2)])
    full, fibre = np.zeros((2, 3, 2, 6, lanes.NTH, W))
    lanes.theta(POLY, tt, full, W)
    fibre_theta(POLY, tt, fibre, W)
    assert full[0].tobytes() == fibre[0].tobytes()  # every coefficient, at every lane's t
    assert full[1:, :, :, 0].tobytes() == fibre[1:, :, :, 0].tobytes()  # the leg constants' series


def test_lane_kernels_give_the_same_bits_in_both_loop_orders():
    """Each function of the lane tracker runs with the lanes innermost (vectorised) for many lanes
    and one lane at a time for a few: the same operations in the same order in a lane, so the same
    bits (what makes a path's result independent of the batch around it)."""
    pytest.importorskip("numba")
    from parakin.kernels import stewart66_lanes as lanes

    W = lanes.LANES
    few = lanes.VECTOR_LANES - 1
    rng = np.random.default_rng(16)
    par = rng.normal(size=(W, 3, 6, 7)) + 1j * rng.normal(size=(W, 3, 6, 7))
    POLY = np.zeros((3, 2, 6, lanes.NTH, W))
    for ln in range(W):
        lanes.path_coefficients(par, ln, POLY, ln)
    tt = rng.uniform(size=W)

    def both(run):
        many, one = run(W), run(few)
        for a, b in zip(many, one):
            assert np.array_equal(a[..., :few], b[..., :few])

    def theta(n):
        TH = np.zeros((3, 2, 6, lanes.NTH, W))
        lanes.theta(POLY, tt, TH, n)
        return (TH,)

    both(theta)
    TH = theta(W)[0]
    X, U, CH, R = rng.normal(size=(4, 2, 8, W))

    def feats(n):
        F = np.zeros((2, lanes.NF, W))
        lanes.features(X, U, F, 2.0, n)
        out0, out1 = np.zeros((2, 8, W)), R.copy()
        lanes.const_rows(F, out0, n)  # the tracker's level 0 (its constant parts first) ...
        lanes.combine(TH[0], F, out0, n)
        lanes.combine(TH[1], F, out1, n)  # ... and level 1 (added to what is there)
        return F, out0, out1

    both(feats)

    def linear(n):
        A = np.zeros((2, 8, 8, W))
        lanes.jacobian(TH, X, CH, A, n)
        Lm, D, Wk, out = (
            np.zeros((2, 8, 8, W)),
            np.zeros((2, 8, W)),
            np.zeros((2, 8, W)),
            np.zeros((2, 8, W)),
        )
        piv = np.zeros((8, W), np.int64)
        J = A.copy()
        lanes.lu(A, Lm, piv, D, Wk, n)
        lanes.solve(A, Lm, piv, D, U, out, Wk, n)
        return J, A, Lm, D, out

    both(linear)


# ------------------------------------------------------------------------- peers
def test_peer_bench_with_bertini():
    """``parakin bench --peers``: Bertini 2 (optional wheel) tracks the same parameter homotopy to
    the same 40 solutions on Dietmaier's input, timed input by input against ours."""
    pytest.importorskip("bertini")
    pytest.importorskip("numba")
    from parakin.mechanisms import stewart66_peers as peers

    df = peers.bench_peers(n_inputs=2, n_bertini=1, double=False)
    row = df[df["peer"].str.contains("Bertini")].iloc[0]
    assert row["inputs"] == 1 and row["agree"] == 1 and "40 (1x)" in row["note"]
    assert row["case"] == "same geometry, one input per call" and row["ratio_median"] > 1
    assert "Bertini 2 parameter homotopy, adaptive precision" in peers.format_peers(df)


def test_peer_elimination_template_needs_its_repository(tmp_path):
    from parakin.mechanisms import stewart66_peers as peers

    with pytest.raises(FileNotFoundError, match="martyushev/fkSGP"):
        peers.martyushev_solver(tmp_path)


#: a stand-in for the elimination template's repository (python/solver66.py, python/genSGP.py):
#: its solver returns our own real postures as rotations and translations, its generator draws
#: anchors and a pose from numpy's global generator as the real one does
_STAND_IN = {
    "solver66.py": """
import numpy as np
from parakin.geometry import euler_zyx
from parakin.mechanisms.stewart66 import Stewart66

def solver66(X, x, L, realOnly):
    poses = Stewart66(base=X, platform=x).fk_all(np.sqrt(L))
    poses = poses[np.isfinite(poses[:, 0])]
    r = euler_zyx(poses[:, 0], poses[:, 1], poses[:, 2])
    return np.concatenate([r, poses[:, 3:, None]], -1), np.zeros(len(poses))
""",
    "genSGP.py": """
import numpy as np

def genSGP(sgpType, motionType):
    X = np.vstack([np.zeros((1, 3)), 4 * np.random.rand(5, 3) - 2])
    x = np.vstack([np.zeros((1, 3)), 4 * np.random.rand(5, 3) - 2])
    t = np.random.randn(3)
    L = np.sum((x + t - X) ** 2, axis=1)
    return {"X": X, "x": x, "L": L, "solver": "solver66"}
""",
}


def test_peer_bench_times_input_by_input_and_compares_the_solutions(tmp_path):
    """The per-input comparison with a stand-in elimination template (our own real poses): every
    case and origin of inputs has its row, every input agrees, the ratios are medians and
    quartiles of per-input ratios, and the order of the two sides alternates."""
    pytest.importorskip("numba")
    from parakin.mechanisms import stewart66_peers as peers

    (tmp_path / "python").mkdir()
    for name, text in _STAND_IN.items():
        (tmp_path / "python" / name).write_text(text)
    df = peers.bench_peers(n_inputs=3, n_bertini=0, fksgp=tmp_path)
    rows = df[df["peer"].str.startswith("Martyushev")]
    assert sorted(zip(rows["case"], rows["inputs_from"])) == sorted(
        [
            ("same geometry, one input per call", "parakin: Dietmaier's platform"),
            ("same geometry, one input per call", "fkSGP genSGP"),
            ("new geometry per call (everything timed)", "parakin: random platforms"),
            ("new geometry per call (everything timed)", "fkSGP genSGP"),
        ]
    )
    assert (rows["agree"] == rows["inputs"]).all()
    assert (rows["ratio_q1"] <= rows["ratio_median"]).all()
    assert (rows["ratio_median"] <= rows["ratio_q3"]).all()
    batch = df[df["case"].str.startswith("batched")]
    assert len(batch) == 3 and (batch["agree"] == batch["inputs"]).all()
    text = peers.format_peers(df)
    assert "peer / parakin, per input: median [IQR]" in text and "machine:" in text
    order = []
    peers.interleaved(lambda i: order.append(("A", i)), lambda i: order.append(("B", i)), 3)
    assert order == [("A", 0), ("B", 0), ("B", 1), ("A", 1), ("A", 2), ("B", 2)]
