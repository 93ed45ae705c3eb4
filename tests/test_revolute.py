"""Revolute joints first-class (issue 43): joint errors modulo a turn in every verification (the
numpy hooks and the compiled kernel's ``joint_period``), pose angles wrapped into (-pi, pi] by
every solver, and the math table and named parameters of the kernels."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from parakin import kernels
from parakin.kernels import _math
from parakin.mechanisms import UPS2, from_file
from parakin.solvers import solve_fk

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def test_joint_error_of_a_crank_is_taken_modulo_a_turn():
    mech = from_file(EXAMPLES / "rrr3.yaml")
    x = np.array([0.02, -0.01, 0.1])
    q = mech.ik(x)
    turned = q + [2 * np.pi, -4 * np.pi, 0.0]
    assert mech.joint_error(x, turned) <= 1e-12
    assert abs(mech.joint_error(x, q + [0.3, 0, 0]) - 0.3) <= 1e-12
    assert mech.joint_units == ("rad", "rad", "rad")


@pytest.mark.parametrize("method", ["newton", "lm", "closed-form"])
def test_a_solve_of_turned_joints_succeeds_numpy_path(method):
    """`parakin fk rrr3 --joints -0.63 1.35 3.56` used to exit 1 with "max joint error 6.28"."""
    mech = from_file(EXAMPLES / "rrr3.yaml")
    x = np.array([[0.02, -0.01, 0.1], [-0.03, 0.01, -0.2]])
    q = mech.ik(x) + [[2 * np.pi, 0, -2 * np.pi], [0, 4 * np.pi, 0]]
    with kernels.interpreted():
        res = solve_fk(mech, q, method=method)
    assert res.success.all() and np.max(res.joint_error) <= 1e-9
    assert np.max(np.abs(mech.pose_difference(res.x, x))) <= 1e-9


def test_compiled_verification_takes_the_kernels_joint_period():
    """The compiled path (legs kernel): the same joints a turn away succeed, single call and batch,
    and the batch equals the numpy path to rounding."""
    pytest.importorskip("numba")
    if not kernels.enabled():
        pytest.skip("compiled kernels are off")
    mech = from_file(EXAMPLES / "rrr3.yaml")
    rng = np.random.default_rng(4)
    x = rng.uniform(*mech.pose_bounds(), (300, 3))
    q = mech.ik(x) + 2 * np.pi * rng.integers(-2, 3, (300, 3))
    one = solve_fk(mech, q[0], method="newton", tol=1e-12)
    assert bool(one.success) and float(one.joint_error) <= 1e-9
    batch = solve_fk(mech, q, method="newton", tol=1e-12)
    with kernels.interpreted():
        ref = solve_fk(mech, q, method="newton", tol=1e-12)
    assert batch.success.all() and np.array_equal(batch.status, ref.status)
    assert np.max(np.abs(batch.x - ref.x)) <= 1e-12
    assert np.max(np.abs(mech.pose_difference(batch.x, x))) <= 1e-9


def test_pose_angles_come_back_in_the_first_turn():
    """`parakin fk 2ups ... --solver broyden` reported success at -13458 rad."""
    mech = UPS2()
    q = [-0.009495189610500027, -0.006605694583560862, 0.00536619549520756]
    x0 = [0.29078858466325824, -0.41559990848326667, -0.2160431047273716]
    with kernels.interpreted():
        res = solve_fk(mech, q, x0=x0, method="broyden")
    # Where Broyden's iterates end from this start is chaotic: rounding decides it (on a 2-core
    # AMD EPYC with AVX-512 it converged on the asked-for assembly; on a Zen 3 EPYC, OpenBLAS's
    # Haswell kernel, on another assembly, reported as such; with its Sandybridge kernel it ran
    # to maxiter). What must hold on every machine: the reported pose is named in the first turn,
    # and a success reproduces the legs.
    assert np.all(np.abs(res.x[:2]) <= np.pi)
    if res.success:
        assert np.max(np.abs(mech.ik(res.x) - q)) <= 1e-8
    # a start many turns away: the answer is still named in the first turn, the residual unchanged
    x = np.array([0.1, -0.2, 0.01])
    with kernels.interpreted():
        far = solve_fk(mech, mech.ik(x), x0=x + [12 * np.pi, -6 * np.pi, 0], method="newton")
    assert far.success and np.allclose(far.x, x, atol=1e-9)


def test_angles_inside_the_first_turn_keep_their_bits():
    from parakin.solvers import _wrap

    x = np.array([[0.5, -math.pi + 1e-15, math.pi], [1.0, 3.0, -3.0]])
    y = x.copy()
    assert not _wrap(y, ("m", "rad", "rad"))
    assert np.array_equal(x, y)
    z = np.array([0.0, -math.pi, 7.0])
    _wrap(z, ("rad", "rad", "rad"))
    assert z[1] == math.pi and abs(z[2] - (7.0 - 2 * math.pi)) <= 1e-15


# ---------------------------------------------------------------------------- the math table
def test_every_math_name_is_one_row_bound_on_every_backend():
    scalar = _math.scalar_names()
    assert set(scalar) == set(_math.TABLE) >= {"atan2", "acos", "asin", "floor", "sqrt", "where"}
    for name, row in _math.TABLE.items():
        assert getattr(_math, name) is row.numpy
    args = {"atan2": (0.3, -0.7), "acos": (0.4,), "asin": (-0.2,), "floor": (-1.5,)}
    for name, a in args.items():
        # the same function to an ulp (libm's acos and numpy's may round apart)
        assert scalar[name](*a) == pytest.approx(float(_math.TABLE[name].numpy(*a)), rel=3e-16)
    assert math.isnan(scalar["acos"](1.5)) and math.isnan(scalar["sqrt"](-1.0))
    torch = pytest.importorskip("torch")
    bound = _math.torch_names(torch)
    t = torch.tensor([0.4], dtype=torch.float64)
    assert float(bound["acos"](t)) == pytest.approx(math.acos(0.4), abs=1e-15)
    assert float(bound["maximum"](t, 0.5)) == 0.5


def test_named_parameters_are_checked_once():
    layout = _math.Layout(base=(3, 2), platform=(3, 2), home_sign=1)
    assert (layout.base, layout.platform, layout.home_sign, layout.size) == (0, 6, 12, 13)
    p = layout.pack(base=np.zeros((3, 2)), platform=np.ones((3, 2)), home_sign=-1.0)
    assert p.tolist() == [0.0] * 6 + [1.0] * 6 + [-1.0]
    with pytest.raises(ValueError, match=r"missing \['platform'\]"):
        layout.pack(base=np.zeros((3, 2)), home_sign=1.0)
    with pytest.raises(ValueError, match=r"unknown \['sign'\]"):
        layout.pack(base=np.zeros((3, 2)), platform=np.zeros((3, 2)), home_sign=1.0, sign=1)
    with pytest.raises(ValueError, match=r"'base' must have shape \(3, 2\), got \(2, 3\)"):
        layout.pack(base=np.zeros((2, 3)), platform=np.zeros((3, 2)), home_sign=1.0)
    with pytest.raises(ValueError, match="has 12 values, its layout 13"):
        layout.check(np.zeros(12))
    with pytest.raises(AttributeError, match="no kernel parameter 'bse'"):
        _ = layout.bse
    legs = kernels.legs.PARAMS
    legs.check(np.zeros(legs.size + 3 * legs.record.size))
    with pytest.raises(ValueError):
        legs.check(np.zeros(legs.size + 3 * legs.record.size - 1))
