"""Compiled all-solutions FK of the 3-6 Stewart platform (parakin.kernels.stewart36_all) against
the numpy path of ``Stewart36.fk_all`` (``PARAKIN_KERNELS=0``).

On well-conditioned inputs (random poses near Table 3 row 1, the counts artefact's sampling) the two
give the same solutions in the same order and the same info. On a whole-box sample the degree-16
polynomial is often badly conditioned (clusters of roots near singular configurations): there the
two root finders (Aberth-Ehrlich on the even polynomial in t1^2 here, companion eigenvalues there)
each lost real solutions on a few per cent of inputs (issue 29: 6 and 11 of 300, against the
certified 6-6 homotopy). Both paths now detect those inputs (refined roots not 16 distinct
converged solutions) and complete them with the certified homotopy
(``Stewart36.as_stewart66``): the same real solutions, the true ones, on every input.
Speed: ``tests/bench_kernels.py``, ``parakin bench kernels``.
"""

from __future__ import annotations

import numpy as np
import pytest

from parakin.mechanisms import Stewart36
from parakin.mechanisms import stewart36 as s36

pytest.importorskip("numba")

from parakin.kernels import stewart36_all  # noqa: E402


def _numpy(mech, q, monkeypatch):
    with monkeypatch.context() as mp:
        mp.setenv("PARAKIN_KERNELS", "0")
        return mech.fk_all(q, return_info=True)


def _near_home(m: Stewart36, n: int, seed: int) -> np.ndarray:
    """As the counts artefact (li2017_stewart36.solutions.counts_artefact)."""
    g = np.random.default_rng(seed)
    pose = m.home() + g.uniform(-1, 1, (n, 6)) * np.array([0.5, 0.5, 0.5, 0.3, 0.3, 0.3])
    return m.ik(pose) * g.uniform(0.85, 1.15, (n, 6))


def _same(a, ia, b, ib):
    assert np.array_equal(np.isfinite(a), np.isfinite(b))
    assert np.nanmax(np.abs(a - b), initial=0.0) < 1e-9
    for k in ("n_complex", "n_real", "n_above"):
        assert np.array_equal(ia[k], ib[k]), k
    for k in ("ik_error", "tail"):
        assert np.array_equal(np.isnan(ia[k]), np.isnan(ib[k])), k
    assert np.nanmax(np.abs(ia["ik_error"] - ib["ik_error"]), initial=0.0) < 1e-12
    assert np.nanmax(ib["tail"], initial=0.0) < 1e-10


@pytest.mark.parametrize("b", [0.5, 1.0, 2.0, 3.0])
def test_same_as_numpy_near_home_and_on_the_paper_input(b, monkeypatch):
    m = Stewart36(b=b)
    q = np.concatenate([m.ik(m.home())[None], _near_home(m, 150, seed=int(10 * b))])
    q[5, 2:4] = 0.3 * b  # L3 + L4 < b: no circle, no solution (NaN rows, zero counts)
    q[6, 1] = q[6, 0] + 1.5 * b  # |L1 - L2| > b: no circle
    ref, iref = _numpy(m, q, monkeypatch)
    got, info = m.fk_all(q, return_info=True)
    _same(ref, iref, got, info)
    assert info["n_real"][5] == 0 and np.all(np.isnan(got[5]))


def test_whole_box_certified_mirror_paired_and_mostly_equal(monkeypatch):
    m = Stewart36()
    rng = np.random.default_rng(19)
    lo, hi = m.pose_bounds()
    q = m.ik(rng.uniform(lo, hi, size=(300, 6)))
    ref, iref = _numpy(m, q, monkeypatch)
    got, info = m.fk_all(q, return_info=True)
    fin = np.isfinite(got[..., 0])
    err = np.abs(m.ik(np.nan_to_num(got)) - q[:, None]).max(-1)
    assert np.all(err[fin] <= 1e-9)
    assert np.all(info["n_real"] % 2 == 0)  # mirror pairs, exactly
    assert np.all(info["n_above"] * 2 == info["n_real"])
    with np.errstate(invalid="ignore"):
        close = np.abs(ref - got) < 1e-9
    same = np.all(close | (np.isnan(ref) & np.isnan(got)), axis=(1, 2))
    assert same.all()  # 96 % before the homotopy completed the near-singular inputs (docstring)
    assert 0 < info["homotopy"].sum() < 0.15 * len(q)


#: whole-box inputs (poses uniform in the box, seed 19) on which the compiled and the numpy paths
#: disagreed on the number of real solutions before issue 29: indices in the draw of 300, and the
#: true real counts (the certified 6-6 homotopy, complete on each)
DISAGREED = [10, 23, 29, 100, 191, 195, 201, 216, 236, 286]
TRUE_REAL = [8, 8, 4, 4, 4, 4, 8, 8, 4, 4]


def test_near_singular_inputs_where_the_paths_disagreed(monkeypatch):
    """Both paths find every real solution the certified homotopy finds, and nothing else."""
    m = Stewart36()
    rng = np.random.default_rng(19)
    lo, hi = m.pose_bounds()
    q = m.ik(rng.uniform(lo, hi, size=(300, 6)))[DISAGREED]
    truth = m.as_stewart66.fk_all(q, return_info=True)
    assert np.all(truth.complete) and np.array_equal(truth.n_real, TRUE_REAL)
    ref, iref = _numpy(m, q, monkeypatch)
    got, info = m.fk_all(q, return_info=True)
    for sols, inf in ((ref, iref), (got, info)):
        assert np.array_equal(inf["n_real"], TRUE_REAL)
        for i in range(len(q)):
            a = sols[i][np.isfinite(sols[i, :, 0])]
            b = truth.poses[i][np.isfinite(truth.poses[i, :, 0])]
            d = np.abs(a[:, None] - b[None])
            d[..., :3] = np.minimum(d[..., :3], 2 * np.pi - d[..., :3])  # angles modulo 2 pi
            d = d.max(-1)
            assert np.all(d.min(0) < 1e-9) and np.all(d.min(1) < 1e-9)
    assert np.array_equal(np.isnan(ref), np.isnan(got)) and np.nanmax(np.abs(ref - got)) < 1e-9


def test_batch_shapes_single_serial_parallel():
    m = Stewart36()
    q = _near_home(m, 70, seed=3)
    a, ia = m.fk_all(q, return_info=True)
    b, ib = m.fk_all(q.reshape(2, 35, 6), return_info=True)
    assert b.shape == (2, 35, 16, 6) and ib["n_real"].shape == (2, 35)
    assert np.array_equal(a.reshape(b.shape), b, equal_nan=True)
    one, i1 = m.fk_all(q[7], return_info=True)
    assert one.shape == (16, 6) and np.ndim(i1["n_real"]) == 0
    assert np.array_equal(one, a[7], equal_nan=True)
    p = stewart36_all.params(m.top_points[s36.LEG_TOP], m.base_points, m.a, m.home())
    s, _ = stewart36_all.fk_all(p, q, parallel=False)
    par, _ = stewart36_all.fk_all(p, q, parallel=True)
    assert np.array_equal(s, par, equal_nan=True)  # identical, not just close


def test_numpy_path_when_kernels_are_off(monkeypatch):
    m = Stewart36()
    called = []
    monkeypatch.setattr(stewart36_all, "fk_all", lambda *a, **k: called.append(1))
    monkeypatch.setenv("PARAKIN_KERNELS", "0")
    sols = m.fk_all(m.ik(m.home()))
    assert not called and np.isfinite(sols[:, 0]).sum() == 8


def test_constants_follow_the_numpy_path():
    assert (stewart36_all.RECOVER_WIDTH, stewart36_all.RECOVER_POINTS) == (
        s36.RECOVER_WIDTH,
        s36.RECOVER_POINTS,
    )
    assert (stewart36_all.CONVERGED, stewart36_all.DISTINCT) == (s36.CONVERGED, s36.DISTINCT)


def test_without_numba_every_compiled_path_falls_back():
    """numba stays optional: with it unimportable, the 3-6 and 6-6 all-solutions FK and PSO run
    their numpy paths (a fresh interpreter: this one has numba loaded)."""
    import subprocess
    import sys

    code = (
        "import sys; sys.modules['numba'] = None\n"
        "import numpy as np\n"
        "from parakin import kernels\n"
        "from parakin.mechanisms import Stewart36, Stewart66\n"
        "from parakin.solvers import solve_fk\n"
        "assert not kernels.enabled()\n"
        "m = Stewart36(); s = m.fk_all(m.ik(m.home()))\n"
        "assert np.isfinite(s[:, 0]).sum() == 8\n"
        "r = solve_fk(m, m.ik(m.home()), method='pso', maxiter=20, seed=1)\n"
        "m6 = Stewart66(); a = m6.fk_all(m6.ik(m6.home()), return_info=True)\n"
        "assert a.complete and a.n_found == 40\n"
        "assert not any(k.startswith('numba') and sys.modules[k] is not None for k in sys.modules)\n"
        "assert 'parakin.kernels.stewart36_all' not in sys.modules\n"
        "assert 'parakin.kernels.stewart66_track' not in sys.modules\n"
        "print('ok')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr[-2000:]
