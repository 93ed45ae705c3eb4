"""Generic FK solvers (parakin.solvers) on the 3-P(4S) and on small synthetic mechanisms.

Tolerances: ``tol`` bounds the residual inf-norm (metres for the 3-P(4S)); the pose error is
then at most about ``tol / sigma_min(J)``. Newton, Broyden and LM converge super-linearly, so
their last step overshoots ``tol`` by orders of magnitude and the pose error stays ~1e-12 m even
at the sampled poses nearest the constraint singularity (cond(J) up to ~5e4 in the pose box).
"""

from __future__ import annotations

import itertools
import json
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from parakin.mechanisms import P3P4S
from parakin.mechanisms.base import Mechanism, as_batch
from parakin.solvers import METHODS, FKResult, Status, register, solve_fk

ITERATIVE = ["newton", "broyden", "bfgs", "lm"]
ALL = [*ITERATIVE, "closed-form"]


def reachable_poses(mech: P3P4S, n: int, seed: int) -> np.ndarray:
    """``n`` poses uniform in ``mech.pose_bounds()``, filtered by ``is_reachable``."""
    rng = np.random.default_rng(seed)
    lo, hi = mech.pose_bounds()
    p = rng.uniform(lo, hi, size=(3 * n, 3))
    p = p[mech.is_reachable(p)]
    assert len(p) >= n
    return p[:n]


@pytest.fixture(scope="module")
def sample() -> tuple[P3P4S, np.ndarray, np.ndarray]:
    mech = P3P4S()
    poses = reachable_poses(mech, 2000, seed=20170)
    return mech, poses, mech.ik(poses)


# ---------------------------------------------------------------------------- IK -> FK round trips
# method: (options, required success rate) at tol = 1e-12 from mech.home(). Pose error: <= 1e-9 m
# where cond(J) <= 1e3, and everywhere within the first-order bound 2 |J^-1|_inf |r|_inf + 1e-13 m
# (a few sampled poses lie near the constraint singularity, cond(J) up to ~5e4, where a residual
# of 1e-12 m allows ~1e-9 m of pose error).
ROUND_TRIP = {
    "newton": ({}, 1.0),
    "broyden": ({}, 1.0),
    "lm": ({}, 1.0),
    "closed-form": ({}, 1.0),
    # BFGS minimises |r|^2 / 2, whose Hessian J^T J has cond(J)^2 up to ~3e9 near the constraint
    # singularity at the top of the pose box (upper and lower assembly modes nearly merge): a
    # narrow curved valley where a secant method needs hundreds of iterations. Hence a larger
    # maxiter, >= 99.9 % success, and every failure must sit at cond(J) > 1e3.
    "bfgs": ({"maxiter": 500}, 0.999),
}


@pytest.fixture(scope="module")
def conditioning(sample):
    """cond(J) and |J^-1|_inf at each sampled pose."""
    mech, poses, joints = sample
    jac = mech.jacobian_pose(poses, joints)
    return np.linalg.cond(jac), np.abs(np.linalg.inv(jac)).sum(axis=-1).max(axis=-1)


@pytest.mark.parametrize("method", ALL)
def test_round_trip_default_geometry(sample, conditioning, method):
    mech, poses, joints = sample
    cond, inv_norm = conditioning
    options, rate = ROUND_TRIP[method]
    res = solve_fk(mech, joints, method=method, tol=1e-12, **options)
    assert res.x.shape == poses.shape and res.success.shape == (len(poses),)
    assert np.all(np.isfinite(res.x))
    assert res.success.mean() >= rate, res.message
    assert np.all(cond[~res.success] > 1e3), cond[~res.success]
    ok = res.success
    assert np.all(res.residual[ok] <= 1e-12)
    err = np.max(np.abs(res.x - poses), axis=-1)
    assert np.all(err[ok & (cond <= 1e3)] <= 1e-9)
    assert np.all(err[ok] <= 2 * inv_norm[ok] * res.residual[ok] + 1e-13)
    if method == "closed-form":
        assert np.all(res.nit == 0) and np.all(res.nfev == 0) and np.all(res.njev == 0)
    else:
        assert np.all(res.nfev >= res.nit + 1)


def test_iteration_counts_match_the_method(sample):
    mech, _, joints = sample
    q = joints[:200]
    newton = solve_fk(mech, q, method="newton", tol=1e-12)
    assert np.array_equal(newton.nfev, newton.nit + 1) and np.array_equal(newton.njev, newton.nit)
    broyden = solve_fk(mech, q, method="broyden", tol=1e-12)
    assert np.array_equal(broyden.nfev, broyden.nit + 1) and np.all(broyden.njev == 1)
    lm = solve_fk(mech, q, method="lm", tol=1e-12)
    assert np.array_equal(lm.nfev, lm.nit + 1) and np.all(lm.njev <= lm.nit + 1)
    bfgs = solve_fk(mech, q, method="bfgs", tol=1e-12, maxiter=500)
    assert np.array_equal(bfgs.njev, bfgs.nit + 1) and np.all(bfgs.nfev >= bfgs.nit + 1)


# ---------------------------------------------------------------------------- shapes and results
@pytest.mark.parametrize("method", ALL)
@pytest.mark.parametrize("batch", [(), (5,), (2, 4)])
def test_batch_shapes(method, batch):
    mech = P3P4S()
    poses = reachable_poses(mech, int(np.prod(batch)), seed=1).reshape(*batch, 3)
    res = solve_fk(mech, mech.ik(poses), method=method)
    assert isinstance(res, FKResult) and res.shape == batch and res.x.shape == (*batch, 3)
    for field in ("success", "status", "nit", "nfev", "njev", "residual"):
        assert isinstance(getattr(res, field), np.ndarray) and getattr(res, field).shape == batch
    assert np.all(res.success) and np.allclose(res.x, poses, atol=1e-9)
    assert isinstance(res.wall_time, float) and res.wall_time > 0 and res.method == method
    d = json.loads(json.dumps(res.to_dict(), allow_nan=False))
    assert (
        np.array(d["x"]).shape == (*batch, 3)
        and d["method"] == method
        and d["message"] == "converged"
    )
    assert method in repr(res)


def test_x0_batch_and_broadcasting():
    mech = P3P4S()
    pose = np.array([0.02, -0.03, 0.57])
    starts = np.stack([pose, mech.home(), mech.home() + [0.01, -0.02, 0.01]])
    res = solve_fk(mech, mech.ik(pose), x0=starts)  # one joint vector, three starts
    assert res.shape == (3,) and np.allclose(res.x, pose, atol=1e-10)
    assert res.nit[0] == 0 and np.all(res.nit[1:] > 0)
    with pytest.raises(ValueError, match="broadcast"):
        solve_fk(mech, mech.ik(np.tile(pose, (4, 1))), x0=starts)


def test_empty_batch():
    mech = P3P4S()
    for method in ALL:
        res = solve_fk(mech, np.zeros((0, 3)), method=method)
        assert res.shape == (0,) and res.x.shape == (0, 3) and res.message == "converged"


# ---------------------------------------------------------------------------- failures
@pytest.mark.parametrize("method", ALL)
def test_unreachable_joints_fail_without_raising(method):
    mech = P3P4S()
    good = mech.ik(np.array([0.01, 0.02, 0.58]))
    # the three spheres of radius L about the C_i do not meet (closed-form discriminant -6e-3 m^2)
    joints = np.array([[0.0, 1.2, 0.2], good])
    res = solve_fk(mech, joints, method=method)
    assert res.success.tolist() == [False, True]
    assert np.all(np.isfinite(res.x)) and np.isfinite(res.residual[0]) and res.residual[0] > 1e-3
    assert res.status[0] < 0 and res.message.startswith("1 of 2 poses did not converge")
    single = solve_fk(mech, joints[0], method=method)
    assert single.shape == () and not single.success and np.all(np.isfinite(single.x))


def test_closed_form_isolates_bad_rows_in_a_batch():
    mech = P3P4S()
    poses = reachable_poses(mech, 9, seed=5)
    joints = mech.ik(poses)
    joints[[2, 7]] = [0.0, 1.2, 0.2]
    res = solve_fk(mech, joints, method="closed-form")
    assert np.flatnonzero(~res.success).tolist() == [2, 7]
    assert np.all(res.status[[2, 7]] == Status.NO_SOLUTION) and np.allclose(res.x[2], mech.home())
    assert np.allclose(np.delete(res.x, [2, 7], 0), np.delete(poses, [2, 7], 0), atol=1e-12)
    assert res.message == "2 of 9 poses did not converge: 2 had no closed-form solution within tol"


def test_maxiter_message():
    mech = P3P4S()
    res = solve_fk(mech, mech.ik(reachable_poses(mech, 10, seed=3)), maxiter=1)
    assert not res.success.any() and np.all(res.status == Status.MAXITER)
    assert res.message == "10 of 10 poses did not converge within maxiter=1"


def test_unknown_method_and_bad_arguments():
    mech = P3P4S()
    with pytest.raises(ValueError, match=r"'gauss-seidel'.*newton"):
        solve_fk(mech, mech.ik(mech.home()), method="gauss-seidel")
    with pytest.raises(ValueError, match="maxiter"):
        solve_fk(mech, mech.ik(mech.home()), maxiter=-1)
    with pytest.raises(ValueError, match="joints"):
        solve_fk(mech, [0.1, 0.2])


def test_register():
    @register("test-home")
    def stay_home(mech, joints, x0, *, tol, maxiter, **options):
        return METHODS["newton"](mech, joints, x0, tol=tol, maxiter=0)

    try:
        res = solve_fk(P3P4S(), P3P4S().ik(P3P4S().home()), method="test-home")
        assert res.success and res.method == "test-home" and res.nit == 0
        with pytest.raises(ValueError, match="already registered"):
            register("newton")(stay_home)
    finally:
        del METHODS["test-home"]


# ---------------------------------------------------------------------------- convergence
@pytest.mark.parametrize("method", ITERATIVE)
def test_poses_at_the_solution_take_zero_iterations(method):
    mech = P3P4S()
    poses = reachable_poses(mech, 6, seed=4)
    x0 = poses.copy()
    x0[::2] = mech.home()  # every other pose starts at its solution
    res = solve_fk(mech, mech.ik(poses), x0=x0, method=method, tol=1e-12)
    assert np.all(res.success)
    assert (
        np.all(res.nit[1::2] == 0) and np.all(res.nfev[1::2] == 1) and np.all(res.njev[1::2] == 0)
    )
    assert np.all(res.nit[::2] > 0) and np.all(res.njev[::2] > 0)


def test_newton_converges_quadratically():
    mech = P3P4S()
    pose = np.array([0.03, -0.04, 0.56])
    direction = np.array([1.0, 2.0, -2.0]) / 3.0
    history: list[float] = []
    res = solve_fk(
        mech,
        mech.ik(pose),
        x0=pose + 0.01 * direction,
        tol=1e-12,
        callback=lambda k, x, r: history.append(float(r)),
    )
    assert res.success and res.nit <= 4 and len(history) == res.nit + 1
    assert history[0] > 1e-3 and history[-1] < 1e-12
    # e_{k+1} <= C e_k^2 while above the rounding floor
    ratios = [b / a**2 for a, b in itertools.pairwise(history) if a > 1e-7]
    assert len(ratios) >= 2 and max(ratios) < 10.0, history


def test_xtol_and_gtol_stop_early():
    mech = P3P4S()
    q = mech.ik(np.array([0.05, 0.02, 0.55]))
    loose = solve_fk(mech, q, method="bfgs", tol=0.0, xtol=1e-7)
    assert loose.success and loose.status == Status.SMALL_STEP and loose.residual > 0
    grad = solve_fk(mech, q, method="lm", tol=0.0, gtol=1e-9)
    assert grad.success and grad.status == Status.SMALL_GRADIENT


# ---------------------------------------------------------------------------- any mechanism
@dataclass(frozen=True)
class Toy(Mechanism):
    """``r = (x^2 - q1, y - q2, x + y - q3)[:m]``: J singular at x = 0; m = 3 is overdetermined."""

    m: int = 2
    name: ClassVar[str] = "toy"
    pose_names: ClassVar[tuple[str, ...]] = ("x", "y")
    pose_units: ClassVar[tuple[str, ...]] = ("m", "m")

    @property
    def n_joints(self) -> int:
        return self.m

    def ik(self, pose):
        x = as_batch(pose, 2, "pose")
        return np.stack([x[..., 0] ** 2, x[..., 1], x[..., 0] + x[..., 1]], axis=-1)[..., : self.m]

    def residual(self, pose, joints):
        return self.ik(pose) - as_batch(joints, self.m, "joints")

    def jacobian_pose(self, pose, joints):
        x = as_batch(pose, 2, "pose")
        one, zero = np.ones(x.shape[:-1]), np.zeros(x.shape[:-1])
        rows = [
            np.stack([2 * x[..., 0], zero], -1),
            np.stack([zero, one], -1),
            np.stack([one, one], -1),
        ]
        return np.stack(rows[: self.m], axis=-2)

    def home(self):
        return np.array([1.0, 0.0])

    def pose_bounds(self):
        return np.array([-2.0, -2.0]), np.array([2.0, 2.0])


@pytest.mark.parametrize("method", ITERATIVE)
def test_singular_jacobian_fails_one_pose_only(method):
    toy = Toy()
    joints = np.array([[4.0, 1.0], [4.0, 1.0]])
    x0 = np.array([[0.0, 0.0], [1.0, 0.0]])  # J = [[0, 0], [0, 1]] at the first start
    res = solve_fk(toy, joints, x0=x0, method=method, tol=1e-12)
    assert not res.success[0] and np.all(np.isfinite(res.x))
    assert res.success[1] and np.allclose(res.x[1], [2.0, 1.0])


def test_lm_least_squares_m_greater_than_n():
    toy = Toy(m=3)
    truth = np.array([[1.5, -0.5], [0.7, 0.2]])
    res = solve_fk(toy, toy.ik(truth), method="lm", tol=1e-12)
    assert np.all(res.success) and np.allclose(res.x, truth, atol=1e-10)


@dataclass(frozen=True)
class Exp(Mechanism):
    """``r = exp(x) - q``: from x0 = -30 Newton's first step lands near 1e13: exp overflows."""

    name: ClassVar[str] = "exp"
    pose_names: ClassVar[tuple[str, ...]] = ("x",)
    joint_names: ClassVar[tuple[str, ...]] = ("q",)

    def ik(self, pose):
        return np.exp(as_batch(pose, 1, "pose"))

    def residual(self, pose, joints):
        return self.ik(pose) - as_batch(joints, 1, "joints")

    def jacobian_pose(self, pose, joints):
        return self.ik(pose)[..., None]

    def home(self):
        return np.array([0.0])

    def pose_bounds(self):
        return np.array([-1.0]), np.array([1.0])


def test_divergence_stops_as_nonfinite_with_last_finite_iterate():
    res = solve_fk(Exp(), [[1.0], [0.5]], x0=[[-30.0], [0.0]], method="newton")
    assert res.status.tolist() == [Status.NONFINITE, Status.CONVERGED]
    assert res.x[0, 0] == -30.0 and res.nit[0] == 1 and np.isfinite(res.residual[0])
    assert res.message == "1 of 2 poses did not converge: 1 became non-finite"
    assert np.isclose(res.x[1, 0], np.log(0.5))


def test_closed_form_requires_an_fk():
    with pytest.raises(ValueError, match="Exp has no closed-form fk"):
        solve_fk(Exp(), [0.3], method="closed-form")


# ---------------------------------------------------------------------------- Broyden's inverse update
def _trajectory(mech, joints, x0, **options):
    traj = []
    res = solve_fk(
        mech, joints, x0=x0, tol=0.0, maxiter=12, callback=lambda k, x, r: traj.append(x), **options
    )
    return res, np.array(traj)


def test_broyden_inverse_update_equals_direct_on_a_square_system():
    """Square regular J: the inverse update is the Sherman-Morrison twin of the direct one, so
    both take the same iterates to rounding (and differ once the system is over-determined)."""
    mech = P3P4S()
    truth = np.array([[0.01, -0.02, 0.58], [-0.03, 0.02, 0.6]])
    x0 = truth * np.array([1.3, 0.7, 1.05])
    direct = _trajectory(mech, mech.ik(truth), x0, method="broyden")[1]
    inverse = _trajectory(mech, mech.ik(truth), x0, method="broyden", update="inverse")[1]
    # the first 6 iterates: down to a residual of ~1e-16, after which both only shuffle round-off
    assert len(direct) > 6 and len(inverse) > 6
    assert np.allclose(inverse[:6], direct[:6], rtol=0, atol=1e-12)
    assert np.abs(inverse[5] - inverse[0]).max() > 1e-3  # it moved
    toy = Toy(m=3)
    q, start = toy.ik([[1.5, -0.5]]), np.array([[2.5, 0.5]])
    d3 = _trajectory(toy, q, start, method="broyden")[1]
    i3 = _trajectory(toy, q, start, method="broyden", update="inverse")[1]
    assert np.max(np.abs(d3[2:4] - i3[2:4])) > 1e-6  # rectangular: two different algorithms


def test_broyden_inverse_update_secant_condition_and_convergence():
    """After each inverse update ``H+ (r+ - r) = d`` (the secant condition), on an over-determined
    (3 x 2) consistent system, and the iteration converges to the known root."""
    from parakin.solvers.quasi_newton import _broyden_inverse_init, _broyden_inverse_step
    from parakin.solvers.result import Evaluator

    toy = Toy(m=3)
    truth = np.array([[1.5, -0.5], [0.7, 0.2]])
    ev = Evaluator(toy, toy.ik(truth))
    rows = np.arange(2)
    x = truth * np.array([1.3, 0.8])
    s = {"x": x, "r": ev.residual(x, rows)}
    s |= _broyden_inverse_init(ev, rows, s)
    assert np.allclose(s["H"], np.linalg.pinv(toy.jacobian_pose(x, None)))  # H0 = J+
    for _ in range(4):
        new, _info = _broyden_inverse_step(ev, rows, s)
        d, y = new["x"] - s["x"], new["r"] - s["r"]
        assert np.allclose(np.einsum("kij,kj->ki", new["H"], y), d, rtol=1e-10, atol=1e-14)
        s = new
    res = solve_fk(
        toy,
        toy.ik(truth),
        x0=truth * np.array([1.3, 0.8]),
        method="broyden",
        update="inverse",
        tol=1e-12,
        maxiter=50,
    )
    assert np.all(res.success) and np.allclose(res.x, truth, atol=1e-10)


def test_broyden_update_option_rejects_unknown_values():
    mech = P3P4S()
    with pytest.raises(ValueError, match=r"update = 'bad' must be one of \('direct', 'inverse'\)"):
        solve_fk(mech, mech.ik([0.01, -0.02, 0.58]), method="broyden", update="bad")


@pytest.mark.parametrize(
    "method", ["newton", "gauss-newton", "broyden", "broyden-ls", "bfgs", "lm", "dogleg"]
)
def test_iterative_methods_keep_the_method_protocol(method):
    """``result.iterative`` builds each method from its options: the public signature is the
    registered-method protocol around them, the method keeps its name in argument errors, and an
    option set away from its default reaches the loop (xtol: a small step stops the pose)."""
    import inspect

    fn = METHODS[method]
    params = list(inspect.signature(fn).parameters.values())
    assert [p.name for p in params[:5]] == ["mech", "joints", "x0", "tol", "maxiter"]
    assert params[-1].name == "callback" and params[-1].default is None
    assert all(p.kind is p.KEYWORD_ONLY for p in params[3:])
    assert "xtol" in inspect.signature(fn).parameters
    import typing

    hints = typing.get_type_hints(fn)  # the annotations resolve (documentation tools read them)
    assert set(hints) == {p.name for p in params} | {"return"}
    with pytest.raises(TypeError, match=rf"^{fn.__name__}\(\) got an unexpected keyword .*'nope'"):
        fn(P3P4S(), np.zeros((1, 3)), np.zeros((1, 3)), tol=1e-10, maxiter=5, nope=1)
    mech = P3P4S()
    q = mech.ik(np.array([[0.01, -0.02, 0.58]]))
    x0 = mech.home()[None, :] + 1e-3
    loose = fn(mech, q, x0, tol=0.0, maxiter=50, xtol=1.0)
    assert loose.method == method and loose.nit.tolist() == [1]
    assert loose.status.tolist() == [Status.SMALL_STEP]
