"""Powell's dog leg (parakin.solvers.dogleg): the compiled loop equals its numpy twin on every
registered mechanism, it rejects bad options, and it is a globalised Newton (success from far
starts where pure Newton fails, at least scipy's ``hybr`` on the same starts)."""

from __future__ import annotations

import numpy as np
import pytest

from parakin import mechanisms
from parakin.solvers import solve_fk

pytest.importorskip("numba")

#: every registered mechanism that has compiled kernels
KERNELED = [n for n, cls in mechanisms.REGISTRY.items() if cls().kernel() is not None]


def _far_problem(mech, n: int, seed: int):
    """Poses 30 % of the way from home to a uniform draw from the pose box, and their joints."""
    rng = np.random.default_rng(seed)
    lo, hi = mech.pose_bounds()
    home = mech.home()
    x = home + 0.3 * (rng.uniform(lo, hi, (3 * n, mech.n_pose)) - home)
    return mech.ik(x[mech.in_domain(x)][:n])


@pytest.mark.parametrize("name", KERNELED)
def test_compiled_dogleg_equals_numpy_from_home(name, monkeypatch):
    """From home (far starts: rejected steps, radius changes, the dog leg itself), the compiled
    loop takes the numpy twin's steps: same statuses, counters and poses to 1e-9."""
    mech = mechanisms.REGISTRY[name]()
    joints = _far_problem(mech, 60, seed=11)
    got = solve_fk(mech, joints, method="dogleg", maxiter=100)
    monkeypatch.setenv("PARAKIN_KERNELS", "0")
    ref = solve_fk(mech, joints, method="dogleg", maxiter=100)
    np.testing.assert_array_equal(got.success, ref.success)
    np.testing.assert_array_equal(got.status, ref.status)
    np.testing.assert_array_equal(got.nit, ref.nit)
    np.testing.assert_allclose(got.x[got.success], ref.x[got.success], rtol=0, atol=1e-9)
    assert got.success.mean() > 0.5
    # success promises the asked-for assembly: the joints come back
    assert np.all(np.abs(mech.ik(got.x[got.success]) - joints[got.success]) <= 1e-8)


@pytest.mark.parametrize(
    "option", [{"factor": 0.0}, {"factor": np.inf}, {"eta": 0.25}, {"eta": -1}]
)
def test_dogleg_rejects_bad_options(option):
    mech = mechanisms.REGISTRY["stewart36"]()
    ((key, value),) = option.items()
    with pytest.raises(ValueError, match=f"{key} = {value!r}"):
        solve_fk(mech, mech.ik(mech.home()), method="dogleg", **option)


def test_dogleg_globalises_newton_on_the_6_6():
    """The 6-6 from home across its whole pose box (the bench's inputs): pure Newton succeeds on
    none, the dog leg on at least as many as scipy.optimize.root (hybr) on the same starts."""
    from parakin.bench import _sample

    mech = mechanisms.REGISTRY["stewart66"]()
    _, joints = _sample(mech, 40, seed=17)
    rate = {
        m: solve_fk(mech, joints, method=m, maxiter=100).success.mean()
        for m in ("newton", "dogleg", "scipy-root")
    }
    assert rate["newton"] == 0.0
    assert rate["dogleg"] >= rate["scipy-root"] > 0.3
