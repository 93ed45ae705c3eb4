"""The torch Newton FK solver (parakin.solvers.torch_newton) against the numpy mechanisms and solver.

CPU only: every solve passes ``device="cpu"``, so these tests never need (nor use) a GPU.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from parakin import mechanisms  # noqa: E402
from parakin.errors import ShapeError  # noqa: E402
from parakin.mechanisms import P3P4S, UPS2, Stewart12, Stewart36  # noqa: E402
from parakin.mechanisms.stewart12 import ActiveLegs, DriveMode  # noqa: E402
from parakin.solvers import Status, solve_fk  # noqa: E402
from parakin.solvers.torch_newton import (  # noqa: E402
    default_device,
    gpu_available,
    newton_torch,
    torch_residual,
)
from parakin.workspace import sample_reachable  # noqa: E402

#: every registered mechanism whose kernel is square (Newton: as many equations as unknowns),
#: and variants
MECHS = {
    **{
        name: cls()
        for name, cls in mechanisms.REGISTRY.items()
        if cls().kernel() is not None and cls().n_pose == cls().n_joints
    },
    "ups2-mirror": UPS2(branch=-1),
    "active-legs": ActiveLegs(active=(1, 2, 3, 4, 5, 6)),
}
IDS = list(MECHS)


def _poses(mech, n=100, seed=0):
    """Reachable poses (ActiveLegs samples its Stewart12 box through its own pose_bounds)."""
    return sample_reachable(mech, n, np.random.default_rng(seed))


def _t(a):
    return torch.as_tensor(np.asarray(a, dtype=float))


# ---------------------------------------------------------------------------- residual (the kernels)
@pytest.mark.parametrize("key", IDS)
def test_residual_matches_numpy(key):
    mech = MECHS[key]
    x = _poses(mech)
    rng = np.random.default_rng(1)
    q = mech.ik(x)
    q_off = q + 1e-3 * np.abs(q).max() * rng.standard_normal(q.shape)  # off the manifold too
    f = torch_residual(mech)
    for joints in (q, q_off):
        got = f(_t(x), _t(joints))
        assert got.dtype == torch.float64 and got.shape == joints.shape
        np.testing.assert_allclose(got.numpy(), mech.residual(x, joints), rtol=0, atol=1e-12)
    # any leading batch axes, and a single row
    np.testing.assert_allclose(
        f(_t(x[:6].reshape(2, 3, -1)), _t(q_off[:6].reshape(2, 3, -1))).numpy(),
        mech.residual(x[:6], q_off[:6]).reshape(2, 3, -1),
        rtol=0,
        atol=1e-12,
    )
    np.testing.assert_allclose(
        f(_t(x[0]), _t(q_off[0])).numpy(), mech.residual(x[0], q_off[0]), rtol=0, atol=1e-12
    )


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # torch's forward-AD set-up, first jacfwd
@pytest.mark.parametrize("key", IDS)
def test_torch_jacobian_matches_analytic(key):
    mech = MECHS[key]
    x = _poses(mech, n=20)
    q = mech.ik(x)
    f = torch_residual(mech)
    want = mech.jacobian_pose(x, q)
    scale = np.abs(want).max()
    for jac in (torch.func.vmap(torch.func.jacrev(f)), torch.func.vmap(torch.func.jacfwd(f))):
        np.testing.assert_allclose(jac(_t(x), _t(q)).numpy(), want, rtol=0, atol=1e-10 * scale)


def test_residual_reads_the_parameters():
    """Non-default geometry goes through: the port reads the dataclass, not the defaults."""
    for mech in (
        P3P4S.zhao2017_optimised(),
        UPS2(a=0.17, b=0.09, c=0.31),
        Stewart36(b=2.0, a=1.3),
        ActiveLegs(mech=Stewart12(n=0.02, L=0.03), active=(2, 4, 6, 8, 10, 12)),
    ):
        x = _poses(mech, n=30, seed=2)
        q = mech.ik(x) * 1.001
        np.testing.assert_allclose(
            torch_residual(mech)(_t(x), _t(q)).numpy(), mech.residual(x, q), rtol=0, atol=1e-12
        )


def test_active_legs_outside_lambda_domain_is_nan_like_numpy():
    mech = MECHS["active-legs"]
    x = np.array([[0.0, 0.0, 0.0, 0.6, 0.6, 0.6], [0.001, 0.0, 0.0, 0.1, 0.0, 0.0]])
    q = mech.ik(np.zeros((2, 6)))
    got = torch_residual(mech)(_t(x), _t(q)).numpy()
    want = mech.residual(x, q)
    assert np.all(np.isnan(got[0])) and np.all(np.isnan(want[0]))
    np.testing.assert_allclose(got[1], want[1], rtol=0, atol=1e-12)


def test_mechanisms_without_kernel_raise_not_implemented():
    @dataclasses.dataclass(frozen=True)
    class Sub(P3P4S):  # a subclass that changes the kinematics: refused, not solved as its parent
        def residual(self, pose, joints):
            return 2 * super().residual(pose, joints)

    for mech in (DriveMode(), Sub(), ActiveLegs(mech=Stewart12(convention="cayley"))):
        with pytest.raises(NotImplementedError, match=type(mech).__name__):
            torch_residual(mech)

    @dataclasses.dataclass(frozen=True)
    class Extended(P3P4S):  # a subclass that only adds a method keeps its parent's kernels
        def mass(self):
            return 1.0

    assert torch_residual(Extended()) is not None
    with pytest.raises(NotImplementedError, match="DriveMode"):
        newton_torch(DriveMode(), np.full(6, 0.025), np.zeros(6), device="cpu")
    # the 12-leg cube has a kernel (12 equations, 6 unknowns): a residual, but no square Newton
    r = torch_residual(Stewart12())(_t(np.zeros(6)), _t(np.full(12, 0.025)))
    assert r.shape == (12,)
    with pytest.raises(ShapeError, match="12 joints"):
        newton_torch(Stewart12(), np.full(12, 0.025), np.zeros(6), device="cpu")


def test_own_torch_residual_without_kernel_is_solved():
    """A mechanism with no kernel but its own torch residual: torch.func gives the Jacobian."""

    @dataclasses.dataclass(frozen=True)
    class Own(P3P4S):
        def residual(self, pose, joints):  # its own numpy residual: no kernel
            return super().residual(pose, joints)

        def torch_residual(self):
            e, m = _t(self.e), _t(self.m)

            def f(pose, joints):
                rod = pose[..., None, :] - self.delta * e - joints[..., :, None] * m
                return ((rod * rod).sum(-1) - self.L**2) / (2 * self.L)

            return f

    mech = Own()
    truth = _poses(mech, n=20)
    res = newton_torch(mech, mech.ik(truth), None, device="cpu")
    assert res.success.all()
    np.testing.assert_allclose(res.x, truth, atol=1e-9)
    with pytest.raises(ValueError, match="analytic"):
        newton_torch(mech, mech.ik(truth), None, device="cpu", jacobian="analytic")


# ---------------------------------------------------------------------------- the solver
# the 6-6 is sampled over every orientation, where two of its 40 assemblies may lie within a
# start's 1e-3 of the box: its round trips are tested from near starts in tests/test_kernels.py
@pytest.mark.parametrize("key", [k for k in IDS if k != "stewart66"])
def test_newton_round_trip_matches_numpy(key):
    mech = MECHS[key]
    truth = _poses(mech)
    lo, hi = mech.pose_bounds()
    x0 = truth + 1e-3 * (hi - lo) * np.random.default_rng(100).uniform(-1, 1, truth.shape)
    joints = mech.ik(truth)
    got = newton_torch(mech, joints, x0, tol=1e-12, device="cpu")
    ref = solve_fk(mech, joints, x0, method="newton", tol=1e-12)
    assert got.method == "newton-torch" and got.message == "converged"
    assert got.success.all() and (got.status == Status.CONVERGED).all()
    assert np.abs(got.x - truth).max() < 1e-9
    assert np.all(got.residual <= 1e-12)
    assert got.x.dtype == np.float64 and got.nit.dtype == np.int64 and got.shape == (len(truth),)
    same = np.abs(got.nit - ref.nit) <= 1
    assert same.mean() >= 0.95, f"nit differs by more than 1 on {np.sum(~same)} rows"
    equal = got.nit == ref.nit  # same iteration path: same counters
    np.testing.assert_array_equal(got.nfev[equal], ref.nfev[equal])
    np.testing.assert_array_equal(got.njev[equal], ref.njev[equal])


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
@pytest.mark.parametrize("jacobian", ["vjp", "jacrev", "jacfwd"])
def test_jacobian_options_agree(jacobian):
    mech = MECHS["stewart36"]
    truth = _poses(mech, n=40)
    x0 = truth + 1e-3
    got = newton_torch(mech, mech.ik(truth), x0, tol=1e-12, device="cpu", jacobian=jacobian)
    ref = newton_torch(mech, mech.ik(truth), x0, tol=1e-12, device="cpu")
    np.testing.assert_allclose(got.x, ref.x, rtol=0, atol=1e-10)
    assert got.success.all()
    with pytest.raises(ValueError, match="jacobian"):
        newton_torch(mech, mech.ik(truth), x0, device="cpu", jacobian="nope")


@pytest.mark.parametrize("key", IDS)
def test_unreachable_joints_fail_cleanly(key):
    mech = MECHS[key]
    q = mech.ik(mech.home())
    s = np.abs(q).max() + 0.1
    joints = np.stack([q + 3 * s, q + 10 * s, q - 10 * s, q])  # three unreachable rows, one fine
    got = newton_torch(mech, joints, mech.home(), device="cpu")
    ref = solve_fk(mech, joints, mech.home(), method="newton")
    assert not got.success[:3].any() and got.success[3]
    np.testing.assert_array_equal(got.success, ref.success)
    assert np.all(np.isfinite(got.x)) and np.all(np.isfinite(got.residual))
    # UPS2 beyond |Y| = c: numpy's analytic d rho / dY is infinite there (NONFINITE), the autodiff
    # derivative of the clamped rho is 0 (MAXITER); both fail
    assert set(got.status[:3].tolist()) <= {Status.MAXITER, Status.NONFINITE}
    assert np.all(got.nit <= 50)
    assert got.message.startswith("3 of 4 poses did not converge")


def test_nonfinite_rows_keep_their_last_finite_iterate():
    mech = MECHS["active-legs"]  # an iterate leaving |lambda| < 1 has a NaN residual
    joints = mech.ik(mech.home())[None] + 1.0
    got = newton_torch(mech, joints, mech.home(), device="cpu")
    ref = solve_fk(mech, joints, mech.home(), method="newton")
    assert got.status[0] == Status.NONFINITE == ref.status[0]
    np.testing.assert_allclose(got.x, ref.x, rtol=0, atol=1e-12)
    assert np.all(np.isfinite(got.x)) and got.nit[0] == ref.nit[0]


def test_exactly_singular_jacobian_takes_the_pinv_step():
    """P3P4S with stroke l1 = 0 at x0 = delta e1: rod 1 is exactly zero, so row 1 of J vanishes.
    The LU fails; the row takes numpy's fallback step pinv(J) r (one more Jacobian evaluation),
    the regular row beside it is not affected."""
    mech = MECHS["3p4s"]
    joints = np.array([[0.0, 0.3, 0.3], mech.ik([0.01, -0.02, 0.58])])
    x0 = np.array([[mech.delta, 0.0, 0.0], [0.0, 0.0, 0.59]])
    got = newton_torch(mech, joints, x0, maxiter=1, device="cpu")
    ref = solve_fk(mech, joints, x0, method="newton", maxiter=1)  # numpy: pinv for the batch
    np.testing.assert_allclose(got.x, ref.x, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(got.nit, [1, 1])
    np.testing.assert_array_equal(got.njev, [2, 1])
    full = newton_torch(mech, joints, x0, device="cpu")
    assert np.all(np.isfinite(full.x)) and full.success[1]
    np.testing.assert_allclose(full.x[1], [0.01, -0.02, 0.58], atol=1e-9)


def test_batch_shapes_defaults_and_validation():
    mech = MECHS["3p4s"]
    pose = np.array([0.01, -0.02, 0.58])
    one = newton_torch(mech, mech.ik(pose), None, device="cpu")  # x0 = home, 0-d batch
    assert one.shape == () and bool(one.success) and one.x.shape == (3,)
    np.testing.assert_allclose(one.x, pose, atol=1e-9)
    grid = newton_torch(mech, mech.ik(pose), np.tile(mech.home(), (2, 3, 1)), device="cpu")
    assert grid.shape == (2, 3) and grid.x.shape == (2, 3, 3) and grid.success.all()
    start = newton_torch(mech, mech.ik(mech.home()), mech.home(), device="cpu")
    assert int(start.nit) == 0 and int(start.njev) == 0 and int(start.nfev) == 1
    zero = newton_torch(mech, mech.ik(pose), mech.home(), maxiter=0, device="cpu")
    assert int(zero.status) == Status.MAXITER and int(zero.nit) == 0
    empty = newton_torch(mech, np.zeros((0, 3)), np.zeros((0, 3)), device="cpu")
    assert empty.shape == (0,) and empty.message == "converged"
    with pytest.raises(ShapeError):
        newton_torch(mech, np.zeros((2, 4)), mech.home(), device="cpu")
    with pytest.raises(ShapeError):
        newton_torch(mech, np.zeros((2, 3)), np.zeros((3, 3)), device="cpu")
    with pytest.raises(ShapeError, match="as many equations"):
        newton_torch(
            ActiveLegs(active=tuple(range(1, 13))), np.full(12, 0.025), np.zeros(6), device="cpu"
        )
    with pytest.raises(ValueError, match="tol"):
        newton_torch(mech, mech.ik(pose), None, tol=-1.0, device="cpu")


def test_float32_runs():
    mech = MECHS["2ups"]
    truth = _poses(mech, n=20)
    got = newton_torch(
        mech, mech.ik(truth), truth + 1e-3, tol=1e-5, device="cpu", dtype=torch.float32
    )
    assert got.success.all() and got.x.dtype == np.float64
    assert np.abs(got.x - truth).max() < 1e-3


def test_device_helpers():
    assert gpu_available() == torch.cuda.is_available()
    assert default_device() == ("cuda" if torch.cuda.is_available() else "cpu")
