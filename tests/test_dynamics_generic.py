"""Generic dynamics of every mechanism (issue 27): jets, mass models, inverse and forward dynamics.

Every check compares with something computed another way: finite differences of the IK and of
the jets' own values along parabolas in pose space, the energy of the bodies differentiated in
time (power balance), the gradient of the potential energy (statics), Zhao's Newton-Euler
(the 3-P(4S)), the forward dynamics run back through the inverse, a simulator that must conserve
energy. The physics engines are tests/test_dynamics_engines.py.
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

import parakin.dynamics.jet as jet
from parakin import dynamics as D
from parakin.dynamics.forward import feedforward, forward_dynamics, simulate
from parakin.dynamics.model import MassModel, RigidBody
from parakin.dynamics.trajectory import Harmonic, power_balance, read_trajectory
from parakin.errors import ShapeError, SingularityError, UnreachableError
from parakin.mechanisms import P3P4S, REGISTRY, Stewart12
from parakin.mechanisms import p3p4s_dynamics as zhao
from parakin.mechanisms.rpr3 import RPR3

#: every registered mechanism that declares its dynamics
MECHS = [cls() for cls in REGISTRY.values() if cls().mass_model() is not None]
IDS = [m.name for m in MECHS]
#: central stencils, offsets -3..3 (6th order)
D1 = np.array([-1.0, 9.0, -45.0, 0.0, 45.0, -9.0, 1.0]) / 60.0
D2 = np.array([2.0, -27.0, 270.0, -490.0, 270.0, -27.0, 2.0]) / 180.0


def rel(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a) - b)) / np.max(np.abs(b)))


def trajectory(mech) -> Harmonic:
    """The test trajectory: every coordinate moving by 5 % of its half range about home, 0.5-3 Hz."""
    return Harmonic.around(mech, 0.05, 0.5)


def parabola_states(mech, rng, count=4):
    """Random states near home: pose x0, rate v, acceleration a (per coordinate, scaled to the
    pose box)."""
    lo, hi = mech.pose_bounds()
    span = 0.5 * (hi - lo)
    x0 = mech.home() + 0.02 * span * rng.uniform(-1, 1, (count, mech.n_pose))
    return x0, 0.1 * span * rng.normal(size=x0.shape), span * rng.normal(size=x0.shape)


def test_every_mechanism_of_the_registry_has_dynamics():
    assert sorted(IDS) == sorted(REGISTRY)


# ---------------------------------------------------------------------------------------- jets
def test_jet_rules_match_finite_differences(rng):
    """Value, tangents and bias of a composition of every jet operation, against 6th-order
    differences along x(t) = x0 + v t + a t^2 / 2 (d/dt = J v, d2/dt2 = J a + bias)."""
    x0, v, a = rng.normal(size=(3, 5, 4))

    def compose(x):
        r = jet.euler_zyx(x[..., 0], x[..., 1], x[..., 2])
        u = jet.stack([x[..., 3], jet.sin(x[..., 0]) * x[..., 1], 1.0 + x[..., 2] * x[..., 2]])
        n, length = jet.normalize(jet.cross(jet.matvec(r, u), u + 2.0))
        w = jet.matmul(jet.skew(n), r) - jet.transpose(r) * jet.cos(x[..., 3])[..., None, None]
        return jet.stack(
            [jet.dot(n, u) / length, jet.sqrt(length), 3.0 / (2.0 + x[..., 1] * x[..., 1])]
        ), w

    def values(t):
        xs = x0 + v * t + 0.5 * a * t * t
        return [j.value for j in compose(jet.variable(xs, np.zeros_like(xs)))]

    h = 1e-3
    samples = [values(k * h) for k in range(-3, 4)]
    for i, j in enumerate(compose(jet.variable(x0, v))):
        rate = sum(w * s[i] for w, s in zip(D1, samples)) / h
        acc = sum(w * s[i] for w, s in zip(D2, samples)) / h**2
        assert np.allclose(j.value, samples[3][i], rtol=0, atol=1e-15)
        assert rel(j.rate, rate) < 1e-9
        assert rel(j.acceleration(a), acc) < 1e-6
        vb = v.reshape(v.shape[:1] + (1,) * (j.value.ndim - 1) + v.shape[1:])
        assert np.allclose(np.sum(j.jacobian * vb, -1), j.rate, rtol=0, atol=1e-12)


def test_spin_of_a_rotation_is_its_angular_velocity(rng):
    """omega from vee(Rdot R^T) and alpha from the bias equal finite differences of R."""
    x0, v, a = rng.normal(size=(3, 6, 3))

    def rotation(t: float) -> jet.Jet:
        x = jet.variable(x0 + v * t + 0.5 * a * t * t, v + a * t)
        return jet.euler_zyx(x[..., 0], x[..., 1], x[..., 2])

    spin = jet.spin_of_rotation(rotation(0.0))
    h = 1e-4
    r0 = rotation(0.0).value
    omega = (rotation(h).value - rotation(-h).value) / (2 * h) @ np.swapaxes(r0, -1, -2)
    assert np.allclose(omega, -np.swapaxes(omega, -1, -2), atol=1e-7)
    assert (
        rel(spin.rate, np.stack([omega[..., 2, 1], omega[..., 0, 2], omega[..., 1, 0]], -1)) < 1e-7
    )
    alpha = (jet.spin_of_rotation(rotation(h)).rate - jet.spin_of_rotation(rotation(-h)).rate) / (
        2 * h
    )
    assert rel(spin.acceleration(a), alpha) < 1e-6


# ---------------------------------------------------------------------------------------- kinematics
@pytest.mark.parametrize("mech", MECHS, ids=IDS)
def test_joint_jets_are_the_ik_and_its_derivatives(mech, rng):
    x0, v, a = parabola_states(mech, rng)
    st = D.state(mech, x0, v)
    assert np.allclose(st.joints.value, mech.ik(x0), rtol=0, atol=1e-14)
    assert rel(st.jacobian, mech.velocity_jacobian(x0)) < 1e-10
    h = 1e-3
    q = [mech.ik(x0 + v * k * h + 0.5 * a * (k * h) ** 2) for k in range(-3, 4)]
    qdd = sum(w * qk for w, qk in zip(D2, q)) / h**2
    assert rel(st.joints.acceleration(a), qdd) < 1e-5


@pytest.mark.parametrize("mech", MECHS, ids=IDS)
def test_power_balance_closes(mech):
    """f . qdot = d(T + V)/dt along the test trajectory, to <= 1e-9 of max |dE/dt| (issue goal)."""
    tr = trajectory(mech)
    t = np.linspace(0.0, tr.period, 41)
    balance = power_balance(mech, tr, t, step=1e-4 * tr.period)
    assert balance.relative_error < 1e-9
    # with an external wrench on the platform (its power enters the balance)
    wrench = np.array([3.0, -2.0, 5.0, 0.4, -0.3, 0.2]) * mech.mass_model().body("platform").mass
    assert power_balance(mech, tr, t, 1e-4 * tr.period, wrench=wrench).relative_error < 1e-9


@pytest.mark.parametrize("mech", MECHS, ids=IDS)
def test_static_forces_are_the_gradient_of_the_potential(mech, rng):
    """At rest, J^T f = dV/dx: virtual work against the potential energy alone."""
    x0, _, _ = parabola_states(mech, rng, 3)
    zero = np.zeros_like(x0)
    res = D.inverse_dynamics(mech, x0, zero, zero)
    h = 1e-6 * np.maximum(1.0, np.abs(x0))
    grad = np.stack(
        [
            (
                D.energy(D.state(mech, x0 + h * e, zero))[1]
                - D.energy(D.state(mech, x0 - h * e, zero))[1]
            )
            / (2 * h[:, k])
            for k, e in enumerate(np.eye(mech.n_pose))
        ],
        -1,
    )
    assert rel(np.einsum("...ij,...i->...j", res.jacobian, res.force), grad) < 1e-6


@pytest.mark.parametrize("mech", MECHS, ids=IDS)
def test_forward_dynamics_inverts_the_inverse(mech, rng):
    x0, v, a = parabola_states(mech, rng)
    f = D.inverse_dynamics(mech, x0, v, a).force
    assert rel(forward_dynamics(mech, x0, v, f), a) < 1e-9


@pytest.mark.parametrize("mech", MECHS, ids=IDS)
def test_batched_equals_one_by_one(mech, rng):
    x0, v, a = parabola_states(mech, rng, 6)
    batch = D.inverse_dynamics(mech, x0.reshape(2, 3, -1), v.reshape(2, 3, -1), a.reshape(2, 3, -1))
    loop = np.array([D.inverse_dynamics(mech, x0[k], v[k], a[k]).force for k in range(6)])
    assert batch.force.shape == (2, 3, mech.n_joints)
    assert np.allclose(
        batch.force.reshape(6, -1), loop, rtol=1e-12, atol=1e-12 * np.max(np.abs(loop))
    )


def test_benchmark_batches_on_threads_give_one_calls_forces():
    """The benchmark's batch (parakin.dynamics.bench: chunks, as contiguous blocks on two
    threads, the last chunk of each block shorter) gives one call's forces, in order."""
    from parakin.dynamics.bench import batched_forces

    mech = Stewart12()
    tr = Harmonic.around(mech, 0.05, 0.5)
    x, v, a = tr.state(np.linspace(0.0, tr.period, 300))
    one = D.inverse_dynamics(mech, x, v, a).force
    got = batched_forces(mech, x, v, a, chunk=64, workers=2)
    assert got.shape == one.shape
    assert np.allclose(got, one, rtol=1e-12, atol=1e-12 * np.max(np.abs(one)))


# ---------------------------------------------------------------------------------------- Zhao
class Lissajous:
    """Every axis moving by centimetres at 5, 10 and 15 Hz (velocity-squared terms matter)."""

    def state(self, t):
        t = np.asarray(t, dtype=float)[..., None]
        w = 2 * np.pi * 5.0 * np.array([1.0, 2.0, 3.0])
        amp, phase = np.array([0.02, 0.015, 0.012]), np.array([0.3, 1.1, -0.4])
        s, c = np.sin(w * t + phase), np.cos(w * t + phase)
        return np.array([0.005, -0.01, 0.565]) + amp * s, amp * w * c, -amp * w**2 * s


@pytest.mark.parametrize(
    "mech, params, motion",
    [
        (P3P4S.zhao2017(), zhao.InertialParams.zhao2017(), zhao.SineMotion()),
        (P3P4S.zhao2017(), zhao.InertialParams.zhao2017(), Lissajous()),
        (
            P3P4S.zhao2017_optimised(),
            zhao.InertialParams(3.0, 1.0, 0.5, (0.01, 0.01, 1e-3), (0.5, -0.2, -9.0)),
            Lissajous(),
        ),
    ],
    ids=["paper_motion", "lissajous", "other_geometry_masses_gravity"],
)
def test_generic_path_reproduces_zhaos_newton_euler(mech, params, motion):
    """The issue's check: the 3-P(4S)'s Newton-Euler (eqs 8-23, corrected) to <= 1e-9 relative."""
    p, v, a = motion.state(np.linspace(0.0, 0.1, 401))
    ours = D.inverse_dynamics(mech, p, v, a, mass=params.mass_model(mech))
    assert rel(ours.force, zhao.inverse_dynamics(mech, params, p, v, a)) < 1e-9
    assert rel(ours.joint_acceleration, zhao.drive_accelerations(mech, p, v, a)) < 1e-9


def test_zhao_masses_are_declared_once():
    params, model = zhao.InertialParams.zhao2017(), P3P4S.zhao2017().mass_model()
    assert model.body("rod").mass == params.m_rod and model.body("slider").mass == params.m_slider
    assert model.body("platform").mass == params.m_platform
    assert np.allclose(np.diag(model.body("rod").inertia_matrix), params.I_rod, rtol=0, atol=0)
    with pytest.raises(ValueError, match="rods_per_limb"):
        zhao.InertialParams(rods_per_limb=3).mass_model(P3P4S.zhao2017())


# ---------------------------------------------------------------------------------------- redundancy
def test_redundant_drive_minimum_norm_and_null_space(rng):
    """The 12-leg cube: J^T f = Q holds, f is orthogonal to the 6 internal-force patterns, and
    adding any of them balances the same load; six active legs give the unique solution."""
    mech = Stewart12()
    x0, v, a = parabola_states(mech, rng, 3)
    res = D.inverse_dynamics(mech, x0, v, a)
    assert res.redundancy == 6
    jt = np.swapaxes(res.jacobian, -1, -2)
    assert rel(np.einsum("...ij,...j->...i", jt, res.force), res.generalized) < 1e-12
    null = res.null_space()
    assert null.shape == (3, 12, 6)
    assert np.max(np.abs(np.einsum("...ij,...jk->...ik", jt, null))) < 1e-12
    assert np.max(np.abs(np.einsum("...i,...ik->...k", res.force, null))) < 1e-9 * np.max(
        np.abs(res.force)
    )
    internal = res.force + 100.0 * null[..., 0]
    assert rel(np.einsum("...ij,...j->...i", jt, internal), res.generalized) < 1e-10
    six = D.inverse_dynamics(mech, x0, v, a, active=[0, 2, 4, 6, 8, 10])
    assert np.all(six.force[..., 1::2] == 0)
    assert rel(np.einsum("...ij,...j->...i", jt, six.force), res.generalized) < 1e-10
    assert np.all(np.linalg.norm(six.force, axis=-1) >= np.linalg.norm(res.force, axis=-1))


def test_too_few_drives_cannot_balance():
    mech = Stewart12()
    x, zero = mech.home(), np.zeros(6)
    with pytest.raises(SingularityError, match="cannot balance"):
        D.inverse_dynamics(mech, x, zero, zero, active=[0, 1, 2, 3, 4])
    flagged = D.inverse_dynamics(mech, x, zero, zero, active=[0, 1, 2, 3, 4], on_singular="flag")
    assert flagged.unbalanced and np.all(np.isnan(flagged.force)) and flagged.balance > 1e-3


# ---------------------------------------------------------------------------------------- bad input
def test_trajectory_through_a_singularity_is_named_or_flagged():
    """The 3-P(4S)'s rods stand vertical at z = L + delta tan(phi): cond(J) -> infinity."""
    mech = P3P4S.zhao2017()
    z_sing = mech.L + mech.delta * np.tan(mech.phi)
    z = np.linspace(0.57, z_sing, 5)
    pose = np.stack([np.zeros(5), np.zeros(5), z], -1)
    zero = np.zeros_like(pose)
    with pytest.raises(SingularityError, match=r"cond\(J\) = .* at batch index \(4,\)"):
        D.inverse_dynamics(mech, pose, zero, zero)
    res = D.inverse_dynamics(mech, pose, zero, zero, on_singular="flag")
    assert res.singular.tolist() == [False] * 4 + [True]
    assert np.all(np.isnan(res.force[-1])) and np.all(np.isfinite(res.force[:-1]))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(mass=-1.0), "mass"),
        (dict(mass=1.0, inertia=(1.0, 1.0, -0.1)), "positive definite"),
        (dict(mass=1.0, inertia=(0.1, 0.1, 0.5)), "triangle"),
        (dict(mass=1.0, inertia=[[1.0, 0.2, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), "symmetric"),
        (dict(mass=1.0, inertia=(1.0, 1.0, np.nan)), "finite"),
        (dict(mass=1.0, inertia=(1.0, 1.0, 1.0), com=(0.0, 1.0)), "com"),
    ],
)
def test_non_physical_inertia_is_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        RigidBody(**kwargs)


def test_mass_model_errors():
    model = P3P4S.zhao2017().mass_model()
    with pytest.raises(KeyError, match="no body 'piston'"):
        model.body("piston")
    with pytest.raises(KeyError, match="unknown body kind"):
        model.replace(piston=RigidBody(1.0, (1.0, 1.0, 1.0)))
    with pytest.raises(ValueError, match="gravity"):
        MassModel(model.bodies, gravity=(0.0, 9.81))
    with pytest.raises(TypeError, match="RigidBody"):
        MassModel({"platform": 1.0})
    # a spin-free rod whose inertia is not axisymmetric about it: its spin would matter
    lopsided = model.replace(rod=RigidBody(1.0, (0.02, 0.03, 0.01), (0.0, 0.0, 0.2)))
    with pytest.raises(ValueError, match="axisymmetric"):
        D.inverse_dynamics(
            P3P4S.zhao2017(), [0.0, 0.0, 0.57], np.zeros(3), np.zeros(3), mass=lopsided
        )


def test_bad_states():
    mech = P3P4S.zhao2017()
    zero = np.zeros(3)
    with pytest.raises(UnreachableError, match="outside 3p4s's domain"):
        D.inverse_dynamics(mech, [0.0, 0.0, 0.95], zero, zero)
    with pytest.raises(ShapeError):
        D.inverse_dynamics(mech, np.zeros((4, 3)) + [0, 0, 0.57], np.zeros((5, 3)), zero)
    with pytest.raises(ValueError, match="non-finite"):
        D.inverse_dynamics(mech, [0.0, np.nan, 0.57], zero, zero)
    with pytest.raises(ValueError, match="on_singular"):
        D.inverse_dynamics(mech, [0.0, 0.0, 0.57], zero, zero, on_singular="ignore")
    with pytest.raises(ValueError, match="active"):
        D.inverse_dynamics(mech, [0.0, 0.0, 0.57], zero, zero, active=[3])
    with pytest.raises(NotImplementedError, match="no mass model"):
        from parakin.mechanisms.stewart12 import DriveMode

        D.state(DriveMode(), np.zeros(0), np.zeros(0))


def test_trajectory_files(tmp_path):
    mech = P3P4S.zhao2017()
    tr = Harmonic.around(mech, 0.2, 2.0)
    t = np.linspace(0.0, 0.5, 201)
    x, v, a = tr.state(t)
    path = tmp_path / "traj.csv"
    import pandas as pd

    pd.DataFrame({"t": t, "x": x[:, 0], "y": x[:, 1], "z": x[:, 2]}).to_csv(path, index=False)
    sampled = read_trajectory(path, mech)
    xs, vs, as_ = sampled.state(t[20:-20])
    assert rel(xs, x[20:-20]) < 1e-12 and rel(vs, v[20:-20]) < 1e-5 and rel(as_, a[20:-20]) < 1e-3
    pd.DataFrame({"t": t, "x": x[:, 0]}).to_csv(path, index=False)
    with pytest.raises(ValueError, match=r"missing column\(s\) \['y', 'z'\]"):
        read_trajectory(path, mech)


# ---------------------------------------------------------------------------------------- simulation
def test_simulation_conserves_energy_and_holds_the_loops():
    """No gravity, no drive force: a free motion keeps its kinetic energy; the joints integrated
    beside the pose stay on the loop closures (projection each step), and without the projection
    they drift, by a measured but small amount."""
    mech = Stewart12()
    mass = mech.mass_model().replace(gravity=(0.0, 0.0, 0.0))
    x0, v0 = mech.home(), np.array([1e-3, -5e-4, 2e-4, 0.02, -0.01, 0.015])
    zero = lambda t, st: np.zeros(12)  # noqa: E731
    sim = simulate(mech, x0, v0, zero, 0.05, 1e-3, mass=mass)
    kinetic = [D.energy(D.state(mech, x, v, mass))[0] for x, v in zip(sim.pose, sim.rate)]
    assert np.max(np.abs(np.array(kinetic) / kinetic[0] - 1)) < 1e-9
    assert sim.max_drift < 1e-12 and sim.pose.shape == (51, 6) and sim.joints.shape == (51, 12)
    free = simulate(mech, x0, v0, zero, 0.05, 1e-3, mass=mass, stabilise=False)
    assert np.allclose(free.pose, sim.pose, rtol=0, atol=1e-15)
    assert free.max_drift < 1e-9


def test_simulation_follows_the_feedforward_forces():
    mech = P3P4S.zhao2017()
    tr = Harmonic.around(mech, 0.3, 2.0)
    sim = simulate(mech, *tr.state(0.0)[:2], feedforward(mech, tr, 0.1, 1e-3), 0.1, 1e-3)
    assert np.max(np.abs(sim.pose - tr.state(sim.t)[0])) < 1e-9
    assert sim.max_drift < 1e-9
    with pytest.raises(ValueError, match="dt"):
        simulate(mech, *tr.state(0.0)[:2], feedforward(mech, tr, 0.1, 1e-3), 0.1, 0.0)


def test_planar_3rpr_in_its_plane_and_under_its_forces():
    """The 3-RPR (docs/dynamics.md §7): every body stays in the plane z = 0 (values and
    derivatives); gravity normal to the plane does no work, so the joints carry it and the forces
    are those of zero gravity (to rounding), while the default in-plane gravity changes them; under
    the feedforward forces of a trajectory the simulator follows it, the loops held."""
    mech = RPR3()
    tr = Harmonic.around(mech, 0.5, 1.0)
    x, v, a = tr.state(np.linspace(0.0, tr.period, 9))
    origins = [g.origin for g in mech.bodies(jet.variable(x, v)).groups]
    assert all(np.all(o.value[..., 2] == 0) and np.all(o.tangents[..., 2] == 0) for o in origins)
    model = mech.mass_model()
    free = D.inverse_dynamics(mech, x, v, a, mass=model.replace(gravity=(0.0, 0.0, 0.0))).force
    flat = D.inverse_dynamics(mech, x, v, a, mass=model.replace(gravity=(0.0, 0.0, -9.81))).force
    assert rel(flat, free) < 1e-12
    assert rel(D.inverse_dynamics(mech, x, v, a).force, free) > 0.1
    sim = simulate(mech, *tr.state(0.0)[:2], feedforward(mech, tr, 0.1, 1e-3), 0.1, 1e-3)
    assert np.max(np.abs(sim.pose - tr.state(sim.t)[0])) < 1e-9
    assert sim.max_drift < 1e-9


# ---------------------------------------------------------------------------------------- layering
def test_dynamics_modules_name_no_mechanism():
    """parakin.dynamics is generic: it reaches mechanisms only through the protocol (base); the
    mechanisms reach it only through jet and model (which import no mechanism)."""
    src = Path(__file__).resolve().parents[1] / "src" / "parakin"
    for path in (src / "dynamics").glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith(
                "parakin.mechanisms"
            ):
                assert node.module == "parakin.mechanisms.base", (path.name, node.module)
    core = {cls.__module__.rpartition(".")[2] for cls in REGISTRY.values()}
    for path in (src / "mechanisms").glob("*.py"):
        allowed = {"parakin.dynamics.jet", "parakin.dynamics.model"}
        if path.stem not in core:  # a paper's own dynamics module checks the generic path
            allowed |= {"parakin.dynamics.trajectory", "parakin.dynamics.mujoco_check"}
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                names = [node.module or ""]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            else:
                continue
            bad = [n for n in names if n.startswith("parakin.dynamics") and n not in allowed]
            assert not bad, (path.name, bad)


# ---------------------------------------------------------------------------------------- CLI, study
def test_cli_dynamics(tmp_path, capsys):
    """`parakin dynamics MECH --trajectory FILE`: forces per sample; a singular sample is one
    line of error (status 2), or NaN forces with --flag-singular."""
    import pandas as pd

    from parakin.cli import main

    mech = P3P4S.zhao2017()
    t = np.linspace(0.0, 1.0, 11)
    z_sing = mech.L + mech.delta * np.tan(mech.phi)
    zero = 0.0 * t
    frame = {"t": t, "x": zero, "y": zero, "z": np.linspace(0.57, z_sing, 11)}
    frame.update({f"{p}_{c}": zero for p in ("d", "dd") for c in "xyz"})
    path = tmp_path / "traj.csv"
    pd.DataFrame(frame).to_csv(path, index=False)
    assert main(["dynamics", "3p4s", "--trajectory", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cond(J)" in err and "(10,)" in err
    out = tmp_path / "forces.csv"
    assert (
        main(
            ["dynamics", "3p4s", "--trajectory", str(path), "--flag-singular", "--output", str(out)]
        )
        == 0
    )
    table = pd.read_csv(out)
    assert (
        table["singular"].tolist() == [False] * 10 + [True] and table["l1 [N]"].isna().tolist()[-1]
    )
    at_rest = D.inverse_dynamics(mech, [0.0, 0.0, 0.57], np.zeros(3), np.zeros(3)).force
    assert np.allclose(table.iloc[0, 1:4].to_numpy(float), at_rest, rtol=1e-12)
    assert main(["dynamics", "stewart66", "--trajectory", str(path)]) == 2
    assert "missing column" in capsys.readouterr().err


def test_study_on_the_quick_config(quick_config, tmp_path):
    """The study's data: forces of every mechanism (one figure drawn) and a short simulation
    (the pipeline's quick run, tests/test_pipeline.py, runs every artefact whole)."""
    from parakin.studies import dynamics as study

    for name in IDS:
        table = study.forces_data(quick_config, name)
        assert set(table["mechanism"]) == {name} and table["force"].notna().all()
    assert study.draw_forces(table, tmp_path / "f.png", IDS[-1]).stat().st_size > 0
    config = {**quick_config, "dynamics": {**quick_config["dynamics"]}}
    config["dynamics"]["simulation"] = {**config["dynamics"]["simulation"], "t_end": 0.02}
    sim = study.simulation_data(config, "2ups")
    assert sim["step_drift"].max() < 1e-9 and sim["error_vs_analytic"].max() < 1e-6
