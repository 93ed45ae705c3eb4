"""The compiled dynamics (issue 27): recorded programs and the compiled solves equal the numpy
computations they replace.

A program (:mod:`parakin.dynamics.program`) performs the operations of the numpy function it was
recorded from, in the same order: the two differ by rounding only (sums over an axis may associate
differently, compiled ``sin``/``cos``/``pow`` may differ in the last bit). Tolerance, fixed before
comparing: 1e-12 relative to the largest value (ten thousand roundings). The compiled solves
differ from numpy's LAPACK calls by rounding amplified by the condition number (< 1e3 here):
1e-12 relative as well.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from parakin import dynamics as D
from parakin.dynamics import forward, inverse
from parakin.dynamics.forward import computed_torque, equations, simulate
from parakin.dynamics.program import NotRecordable, Program, record
from parakin.dynamics.trajectory import Harmonic
from parakin.mechanisms import REGISTRY, Stewart36

MECHS = [cls() for cls in REGISTRY.values() if cls().mass_model() is not None]
IDS = [m.name for m in MECHS]
TOL = 1e-12
#: what each recorded function takes
TERMS = [
    (inverse._inverse_terms, ("pose", "rate", "acceleration", "wrench")),
    (forward._motion_terms, ("pose", "rate")),
]


def rel(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a) - b)) / np.max(np.abs(b)))


def random_states(mech, rng, count=5) -> dict:
    """Poses near home, rates, accelerations (scaled to the pose box) and wrenches."""
    lo, hi = mech.pose_bounds()
    span = 0.5 * (hi - lo)
    return {
        "pose": mech.home() + 0.02 * span * rng.uniform(-1, 1, (count, mech.n_pose)),
        "rate": 0.1 * span * rng.normal(size=(count, mech.n_pose)),
        "acceleration": span * rng.normal(size=(count, mech.n_pose)),
        "wrench": rng.normal(size=(count, 6)),
    }


@pytest.mark.parametrize("mech", MECHS, ids=IDS)
def test_every_mechanism_is_recorded_and_its_program_is_its_numpy_function(mech, rng):
    mass = mech.mass_model()
    states = random_states(mech, rng)
    for build, names in TERMS:
        program = inverse.compiled(build, mech, mass, names)
        assert isinstance(program, Program), (build.__name__, type(program))
        arrays = [states[k] for k in names]
        got, want = program(*arrays), build(mech, mass)(*arrays)
        assert got.keys() == want.keys()
        for key, value in want.items():
            assert got[key].shape == np.shape(value)
            assert rel(got[key], value) < TOL, (build.__name__, key)
        # one sample at a time gives the batch's numbers (a chunk of one)
        one = program(*(a[2] for a in arrays))
        for key in want:
            assert np.array_equal(one[key], got[key][2]), key


@pytest.mark.parametrize("mech", MECHS, ids=IDS)
def test_equations_are_the_bodies_mass_matrix_load_and_energy(mech, rng):
    """The compiled equations of motion against the jet-level definitions: mass matrix, load
    with a wrench, joint accelerations, and the kinetic energy 1/2 xdot^T M xdot of every body."""
    s = random_states(mech, rng)
    x, v, a, w = s["pose"], s["rate"], s["acceleration"], s["wrench"]
    eq, st = equations(mech, x, v), D.state(mech, x, v)
    assert rel(eq.mass_matrix, D.mass_matrix(st)) < TOL
    assert np.array_equal(eq.mass_matrix, np.swapaxes(eq.mass_matrix, -1, -2))
    assert rel(eq.load(a, w), D.generalized_forces(st, a, w)) < TOL
    assert rel(eq.joint_acceleration(a), st.joints.acceleration(a)) < TOL
    assert rel(eq.joints, mech.ik(x)) < TOL
    kinetic = 0.5 * np.einsum("...i,...ij,...j->...", v, eq.mass_matrix, v)
    assert rel(kinetic, D.energy(st)[0]) < TOL


@dataclass(frozen=True)
class BranchingStewart36(Stewart36):
    """The 3-6 platform whose bodies() looks at a value (a program cannot record that)."""

    def bodies(self, pose):
        if np.any(pose.value[..., 5] <= 0):
            raise ValueError("the platform must stand above the base")
        return super().bodies(pose)


def test_bodies_that_branch_on_values_run_in_numpy_with_the_same_numbers(rng):
    mech, plain = BranchingStewart36(), Stewart36()
    assert not isinstance(
        inverse.compiled(inverse._inverse_terms, mech, mech.mass_model(), TERMS[0][1]), Program
    )
    s = random_states(mech, rng)
    x, v, a = s["pose"], s["rate"], s["acceleration"]
    assert (
        rel(D.inverse_dynamics(mech, x, v, a).force, D.inverse_dynamics(plain, x, v, a).force) < TOL
    )
    assert (
        rel(
            forward.forward_dynamics(mech, x, v, np.ones(6)),
            forward.forward_dynamics(plain, x, v, np.ones(6)),
        )
        < TOL
    )


def every_operation(x, y):
    """Each operation a program has, on positive ``x`` (..., 2) and any ``y`` (..., 2): every
    fused form once (each product read by nothing else), then the plain ones and the folds."""
    a, b, c, d = x[..., 0], x[..., 1], y[..., 0], y[..., 1]
    fused = [a * c + b, b * d - a, a - c * c, a * a + b * b, d * d - b * c]
    fused += [a * 3.5 + c, b * 4.5 - c, d - c * 5.5]
    plain = [a * b, a * 2.5, a + b, a - b, a / b, a + 1.5, a - 1.5, 1.5 - a, a / 3.0, 3.0 / a]
    plain += [np.sqrt(a), np.sin(a), np.cos(b), a**b, a**1.5, -a, b**0.5, b**-1]
    folded = [-(0.0 - a), a + 0.0, a * 1.0, 0.0 / a, a * 0.0 + b, b * a - a * b]
    values = np.stack(fused + plain + folded, -1)
    return {"values": values, "constant": np.full(x.shape[:-1] + (2,), 2.0)}


def test_a_program_replays_every_operation(rng):
    x, y = rng.uniform(0.5, 2.0, (7, 2)), rng.normal(size=(7, 2))
    program = record(every_operation, [x[0], y[0]])
    assert isinstance(program, Program)
    got, want = program(x, y), every_operation(x, y)
    assert np.max(np.abs(got["values"] - want["values"])) <= 1e-15 * np.max(np.abs(want["values"]))
    assert np.array_equal(got["constant"], want["constant"])
    # every fused form and every opcode of the interpreter ran
    assert set(program.code[:, 0].tolist()) == set(range(27))


def test_what_a_program_cannot_record():
    assert record(lambda x: {"y": np.where(x > 0, x, -x)}, [np.ones(2)]) is None
    assert record(lambda x: {"y": np.abs(x)}, [np.ones(2)]) is None
    assert record(lambda x: {"y": x.astype(float)}, [np.ones(2)]) is None
    assert record(lambda x: {"y": x.sum()}, [np.ones(2)]) is None  # the batch axis lost
    program = record(lambda x: {"y": 2.0 * x}, [np.ones(2)])
    with pytest.raises(ValueError, match="takes 1 arrays"):
        program(np.ones(2), np.ones(2))
    with pytest.raises(NotRecordable):
        float(_symbol())
    with pytest.raises(NotRecordable):
        bool(_symbol() > 0)


def _symbol():
    """A lone symbol of a fresh recording."""
    from parakin.dynamics.program import INPUT, _Tape

    return _Tape().add(INPUT, 0)


@pytest.mark.parametrize("shape", [(6, 6), (12, 6), (3, 6)], ids=["square", "redundant", "short"])
def test_compiled_force_solve_is_numpys(shape, rng):
    """solve_forces (compiled, sample by sample) against its numpy form; a sample with a zero
    pivot takes the pseudo-inverse (condition inf)."""
    m, n = shape
    j = rng.normal(size=(50, m, n))
    q = rng.normal(size=(50, n))
    j[7] = 0.0
    f, cond, res = inverse.solve_forces(j, q)
    ok = np.arange(50) != 7
    f_np, cond_np, res_np = inverse._solve_numpy(j[ok], q[ok])
    assert np.max(np.abs(f[ok] - f_np) / np.max(np.abs(f_np), axis=-1, keepdims=True)) < 1e-10
    assert np.allclose(cond[ok], cond_np, rtol=1e-10, atol=0)
    assert np.allclose(res[ok], res_np, rtol=0, atol=1e-12)
    # the singular sample: numpy's pseudo-inverse, whatever else the batch holds
    singular = inverse._solve_numpy(j[7:8], q[7:8])
    assert np.isinf(cond[7]) and np.array_equal(f[7], singular[0][0]) and res[7] == singular[2][0]


def test_a_batch_of_simulations_is_each_simulation(rng):
    mech = REGISTRY["2ups"]()
    tr = Harmonic.around(mech, 0.02, 0.25)
    x0, v0, _ = tr.state(0.0)
    lo, hi = mech.pose_bounds()
    starts = x0 + 0.01 * 0.5 * (hi - lo) * rng.uniform(-1, 1, (2, 3))
    law = computed_torque(tr, 2.0)
    both = simulate(mech, starts, np.stack([v0, v0]), law, 0.02, 1e-3)
    for k in range(2):
        alone = simulate(mech, starts[k], v0, law, 0.02, 1e-3)
        assert np.array_equal(both.pose[:, k], alone.pose)
        assert np.array_equal(both.drift[:, k], alone.drift)


@pytest.mark.parametrize("mech", MECHS, ids=IDS)
def test_without_numba_the_same_numbers(mech, rng, monkeypatch):
    """``PARAKIN_KERNELS=0`` (or numba missing): the numpy functions and numpy's solves."""
    s = random_states(mech, rng)
    x, v, a, w = s["pose"], s["rate"], s["acceleration"], s["wrench"]
    f = rng.normal(size=(len(x), mech.n_joints))

    def run():
        return (
            D.inverse_dynamics(mech, x, v, a, wrench=w).force,
            forward.forward_dynamics(mech, x, v, f, wrench=w),
            equations(mech, x, v).mass_matrix,
        )

    compiled = run()
    monkeypatch.setenv("PARAKIN_KERNELS", "0")
    assert not isinstance(
        inverse.compiled(inverse._inverse_terms, mech, None, TERMS[0][1]), Program
    )
    for got, want in zip(run(), compiled):
        assert rel(got, want) < TOL
