"""3-P(4S) velocity/acceleration maps and inverse dynamics (Zhao 2017 eqs 8-23).

Every map is checked against finite differences of the IK / of the geometry along trajectories;
the forces against an energy balance computed independently of the Newton-Euler code and against
a static load from the gradient of the potential energy; the paper's three printed slips are
quantified; the section's artefacts run on a small grid.
"""

import dataclasses
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from parakin.claims import resolve
from parakin.errors import ConfigError, ShapeError, SingularityError, UnreachableError
from parakin.mechanisms import P3P4S
from parakin.mechanisms import p3p4s_dynamics as dyn
from parakin.registry import of_module
from parakin.report import load_reference, printed_value

MECH = P3P4S.zhao2017()
PARAMS = dyn.InertialParams.zhao2017()

# 6th-order central stencils, offsets -3..3
D1 = np.array([-1.0, 9.0, -45.0, 0.0, 45.0, -9.0, 1.0]) / 60.0
D2 = np.array([2.0, -27.0, 270.0, -490.0, 270.0, -27.0, 2.0]) / 180.0


@dataclasses.dataclass(frozen=True)
class Lissajous:
    """A demanding test trajectory: every axis moves, 2 cm amplitudes, so that the velocity-squared
    terms (H, omega x I omega) matter. Same interface as dyn.SineMotion."""

    centre: tuple = (0.005, -0.01, 0.565)
    amp: tuple = (0.02, 0.015, 0.012)
    omega: float = 2 * np.pi * 5.0
    ratio: tuple = (1.0, 2.0, 3.0)
    phase: tuple = (0.3, 1.1, -0.4)

    def _w(self):
        return self.omega * np.asarray(self.ratio)

    def pose(self, t):
        t = np.asarray(t, dtype=float)[..., None]
        return np.asarray(self.centre) + np.asarray(self.amp) * np.sin(
            self._w() * t + np.asarray(self.phase)
        )

    def velocity(self, t):
        t = np.asarray(t, dtype=float)[..., None]
        return np.asarray(self.amp) * self._w() * np.cos(self._w() * t + np.asarray(self.phase))

    def acceleration(self, t):
        t = np.asarray(t, dtype=float)[..., None]
        return (
            -np.asarray(self.amp) * self._w() ** 2 * np.sin(self._w() * t + np.asarray(self.phase))
        )

    def state(self, t):
        return self.pose(t), self.velocity(t), self.acceleration(t)


def stencil(f, t, h, weights):
    return sum(w * f(t + k * h) for k, w in zip(range(-3, 4), weights) if w)


def rod_geometry(p):
    """Rod directions and centroids (eq 10) straight from the IK: no maps involved."""
    q = MECH.ik(p)
    n = MECH.rod_directions(p, q)
    return n, MECH.r_b * MECH.e + q[..., None] * MECH.m + 0.5 * MECH.L * n


def rel(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


# ---------------------------------------------------------------------------------------- inputs
def test_parameters_are_the_transcribed_ones():
    ref = load_reference("zhao2017_3p4s")
    val = lambda a, q: float(printed_value(ref, a, q))  # noqa: E731
    assert PARAMS.m_platform == val("text_s2.4", "m_platform")
    assert PARAMS.m_slider == val("text_s2.4", "m_slider")
    assert PARAMS.m_rod == val("text_s2.4", "m_rod")
    assert PARAMS.I_rod == (
        val("text_s2.4", "i_xx"),
        val("text_s2.4", "i_yy"),
        val("text_s2.4", "i_zz"),
    )
    assert PARAMS.rods_per_limb == int(val("text_s2.1", "rods_per_limb"))
    motion = dyn.SineMotion()
    assert motion.amplitude == val("text_s2.4", "motion.amplitude")
    assert motion.omega == pytest.approx(val("text_s2.4", "motion.omega"), rel=1e-15)
    assert motion.z0 == val("text_s2.4", "motion.z_p")
    assert PARAMS.total_mass == pytest.approx(21.41)


def test_motion_law_derivatives_are_exact():
    motion, t, h = dyn.SineMotion(), np.linspace(0, 0.1, 201), 2e-4
    assert rel(stencil(motion.pose, t, h, D1) / h, motion.velocity(t)) < 1e-9
    assert rel(stencil(motion.velocity, t, h, D1) / h, motion.acceleration(t)) < 1e-9
    p = motion.pose(t)
    assert np.all(p[:, 0] == p[:, 1]) and np.all(p[:, 2] == 0.57)
    assert np.max(np.abs(p[:, 0])) == pytest.approx(1e-3, rel=1e-6)
    assert motion.period == pytest.approx(0.05)


@pytest.mark.parametrize(
    "bad",
    [
        dict(m_platform=-1.0),
        dict(m_rod=float("nan")),
        dict(I_rod=(0.02, 0.03, 1e-4)),
        dict(I_rod=(0.02, 0.02)),
        dict(rods_per_limb=0),
        dict(g=(0.0, 9.81)),
    ],
)
def test_inertial_params_reject_bad_values(bad):
    with pytest.raises(ValueError):
        dyn.InertialParams(**bad)


@pytest.mark.parametrize("bad", [dict(amplitude=-1e-3), dict(omega=0.0), dict(z0=float("inf"))])
def test_motion_rejects_bad_values(bad):
    with pytest.raises(ValueError):
        dyn.SineMotion(**bad)


# ---------------------------------------------------------------------------------------- maps vs FD
@pytest.fixture(scope="module")
def lissajous():
    motion = Lissajous()
    t = np.linspace(0.0, 0.2, 121)
    p, v, a = motion.state(t)
    return motion, t, p, v, a, dyn.limb_kinematics(MECH, p, v, a)


def test_drive_rates_match_ik_finite_differences(lissajous):
    motion, t, p, v, a, kin = lissajous
    _, qdot, qddot = dyn.ik_finite_differences(MECH, motion, t, 2e-4)
    assert rel(kin.qdot, qdot) < 1e-8  # eq 8
    assert rel(kin.qddot, qddot) < 1e-6  # eq 13 with 1/l
    assert np.allclose(kin.J, MECH.velocity_jacobian(p), rtol=1e-13, atol=0)
    # the printed H (no 1/l) misses the finite differences by a visible amount here
    printed = dyn.drive_accelerations(MECH, p, v, a, h_form="paper")
    assert rel(printed, qddot) > 1e-2


def test_rod_maps_match_geometry_finite_differences(lissajous):
    motion, t, p, v, a, kin = lissajous
    h = 2e-4
    n = lambda tt: rod_geometry(motion.pose(tt))[0]  # noqa: E731
    r = lambda tt: rod_geometry(motion.pose(tt))[1]  # noqa: E731
    ndot, nddot = stencil(n, t, h, D1) / h, stencil(n, t, h, D2) / h**2
    rdot, rddot = stencil(r, t, h, D1) / h, stencil(r, t, h, D2) / h**2
    assert rel(kin.r_rod, r(t)) < 1e-15
    assert rel(kin.omega, np.cross(n(t), ndot)) < 1e-8  # eq 9: omega = n x dn/dt (no spin)
    assert rel(kin.v_rod, rdot) < 1e-8  # eq 11
    assert rel(kin.a_rod, rddot) < 1e-6  # eq 14
    assert rel(kin.alpha, np.cross(n(t), nddot)) < 1e-6  # eq 15: alpha = n x d2n/dt2
    # omega from eq 9 differentiated in time is alpha of eq 15
    omega = lambda tt: dyn.limb_kinematics(MECH, *motion.state(tt)).omega  # noqa: E731
    assert rel(kin.alpha, stencil(omega, t, h, D1) / h) < 1e-8
    # the paper's H makes eqs 14 and 15 wrong as well
    paper = dyn.limb_kinematics(MECH, p, v, a, h_form="paper")
    assert rel(paper.a_rod, rddot) > 1e-3 and rel(paper.alpha, np.cross(n(t), nddot)) > 1e-3


def test_map_functions_agree_with_limb_kinematics(lissajous):
    _, _, p, v, a, kin = lissajous
    assert np.allclose(dyn.drive_jacobian(MECH, p), kin.J, rtol=0, atol=1e-14)
    assert np.allclose(dyn.omega_jacobians(MECH, p), kin.J_omega, rtol=0, atol=1e-14)
    assert np.allclose(dyn.rod_velocity_jacobians(MECH, p), kin.J_v, rtol=0, atol=1e-14)
    assert np.allclose(dyn.acceleration_hessians(MECH, p), kin.H, rtol=0, atol=1e-12)
    # printed H = l * corrected H: the missing factor is exactly 1/l
    assert np.allclose(
        dyn.acceleration_hessians(MECH, p, h_form="paper"), MECH.L * kin.H, rtol=1e-14, atol=0
    )
    assert np.allclose(dyn.drive_accelerations(MECH, p, v, a), kin.qddot, rtol=0, atol=1e-13)
    assert np.allclose(dyn.rod_accelerations(MECH, p, v, a), kin.a_rod, rtol=0, atol=1e-13)
    assert np.allclose(dyn.rod_angular_accelerations(MECH, p, v, a), kin.alpha, rtol=0, atol=1e-12)
    # P_i v = l dn_i/dt and H_i v.v = |P_i v|^2 / (l^2 n_i.m_i) * l
    n_dot = (v[:, None, :] - kin.qdot[..., None] * MECH.m) / MECH.L
    assert np.allclose(kin.vHv, MECH.L * np.sum(n_dot**2, -1) / kin.nm, rtol=1e-12, atol=1e-14)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.floats(-0.05, 0.05),
    st.floats(-0.05, 0.05),
    st.floats(0.53, 0.59),
    st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6),
)
def test_any_state_matches_a_parabola_through_it(x, y, z, va):
    """For arbitrary (p, v, a): q(t) = ik(p + v t + a t^2/2) has qdot(0) = J v, qddot(0) = J a + v^T H v."""
    p0, v, a = np.array([x, y, z]), np.array(va[:3]), 10.0 * np.array(va[3:])
    h = 1e-4
    q = lambda tt: MECH.ik(p0 + v * tt + 0.5 * a * tt**2)  # noqa: E731
    kin = dyn.limb_kinematics(MECH, p0, v, a)
    qdot = sum(w * q(k * h) for k, w in zip(range(-3, 4), D1)) / h
    qddot = sum(w * q(k * h) for k, w in zip(range(-3, 4), D2)) / h**2
    scale = 1.0 + np.max(np.abs(kin.qddot))
    assert np.max(np.abs(kin.qdot - qdot)) < 1e-8 * (1 + np.max(np.abs(qdot)))
    assert np.max(np.abs(kin.qddot - qddot)) < 1e-5 * scale


# ---------------------------------------------------------------------------------------- dynamics
def test_static_load_at_the_centre():
    f = dyn.inverse_dynamics(MECH, PARAMS, [0.0, 0.0, 0.57], np.zeros(3), np.zeros(3))
    assert f == pytest.approx(
        [40.6308] * 3, abs=1e-4
    )  # docs/zhao2017_3p4s.md#s3.4: 40.63 N per motor


@pytest.mark.parametrize("pose", [[0.0, 0.0, 0.57], [0.02, -0.01, 0.57], [-0.04, 0.03, 0.55]])
def test_static_load_is_the_gradient_of_potential_energy(pose):
    """Virtual work at rest: f . dq = dV, i.e. f = J^-T dV/dp with V from dyn.energy (independent)."""
    pose = np.asarray(pose)
    h = 1e-5
    grad = np.array(
        [
            (
                dyn.energy(MECH, PARAMS, pose + h * e, np.zeros(3)).potential
                - dyn.energy(MECH, PARAMS, pose - h * e, np.zeros(3)).potential
            )
            / (2 * h)
            for e in np.eye(3)
        ]
    )
    expected = np.linalg.solve(MECH.velocity_jacobian(pose).T, grad)
    assert dyn.inverse_dynamics(MECH, PARAMS, pose, np.zeros(3), np.zeros(3)) == pytest.approx(
        expected, abs=1e-6
    )


def test_power_balance_paper_motion():
    motion = dyn.SineMotion()
    t = np.linspace(0.0, 0.05, 401)
    ours = dyn.power_balance(MECH, PARAMS, motion, t)
    assert ours.relative_error < 1e-6
    assert np.max(np.abs(ours.dEdt)) == pytest.approx(16.74, abs=0.01)
    # each printed slip breaks the balance
    for opts, at_least in (
        (dict(h_form="paper"), 1e-4),
        (dict(gravity_moment=True), 1e-3),
        (dict(rod_inertia_factor=1.0), 0.1),
        (dyn.PAPER_PRINTED, 0.1),
    ):
        assert dyn.power_balance(MECH, PARAMS, motion, t, **opts).relative_error > at_least, opts


def test_power_balance_demanding_trajectory(lissajous):
    motion, t, *_ = lissajous
    ours = dyn.power_balance(MECH, PARAMS, motion, t, step=2e-4)
    assert ours.relative_error < 1e-6
    assert (
        dyn.power_balance(MECH, PARAMS, motion, t, step=2e-4, h_form="paper").relative_error > 1e-2
    )


def test_power_balance_other_geometry_and_masses():
    mech = P3P4S.zhao2017_optimised()
    params = dyn.InertialParams(
        m_platform=3.0,
        m_slider=1.0,
        m_rod=0.5,
        I_rod=(0.01, 0.01, 1e-3),
        rods_per_limb=3,
        g=(0.5, -0.2, -9.0),
    )
    motion = Lissajous(centre=(0.0, 0.0, 0.6))
    t = np.linspace(0.0, 0.2, 81)
    assert dyn.power_balance(mech, params, motion, t, step=2e-4).relative_error < 1e-6


def test_gravity_moment_term_of_eq21():
    """The spurious eq 21 term: 20.68 N per actuator at the centre (it lowers the static motor
    force from 40.63 to 19.95 N); 17.3 / 24.3 / 20.7 N at (0.02, -0.01, 0.57) (docs/zhao2017_3p4s.md#s4.4)."""
    zero = np.zeros(3)
    terms = dyn.force_terms(MECH, PARAMS, [0.0, 0.0, 0.57], zero, zero, gravity_moment=True)
    assert terms["gravity_moment"] == pytest.approx([-20.681] * 3, abs=1e-3)
    assert sum(terms.values()) == pytest.approx([19.950] * 3, abs=1e-3)
    off = dyn.force_terms(MECH, PARAMS, [0.02, -0.01, 0.57], zero, zero, gravity_moment=True)[
        "gravity_moment"
    ]
    assert -off == pytest.approx([17.318, 24.273, 20.727], abs=1e-3)


def test_rod_inertia_factor_of_eq23():
    motion = dyn.SineMotion()
    p, v, a = motion.state(np.linspace(0, 0.05, 1001))
    terms = dyn.force_terms(MECH, PARAMS, p, v, a)
    once = dyn.inverse_dynamics(MECH, PARAMS, p, v, a, rod_inertia_factor=1.0)
    rods = terms["rods_translation"] + terms["rods_rotation"]
    assert np.allclose(once, sum(terms.values()) - rods / 2, rtol=0, atol=1e-10)
    assert np.max(np.abs(rods / 2)) == pytest.approx(
        87.50, abs=0.01
    )  # how much the slip changes Fig. 9


def test_paper_example_forces():
    """Fig. 9's numbers (docs/zhao2017_3p4s.md#s3.4): min/max per drive over 0..0.1 s."""
    motion = dyn.SineMotion()
    f = dyn.inverse_dynamics(MECH, PARAMS, *motion.state(np.linspace(0, 0.1, 2001)))
    assert f.min(0) == pytest.approx([-237.6, -60.8, -340.2], abs=0.1)
    assert f.max(0) == pytest.approx([316.9, 142.2, 417.2], abs=0.1)


def test_gyroscopic_term_vanishes_for_axisymmetric_rods(lissajous):
    _, _, p, v, a, kin = lissajous
    inertia = PARAMS.rod_inertia_world(kin.n)
    w = kin.omega
    assert np.max(np.abs(np.cross(w, np.einsum("...kij,...kj->...ki", inertia, w)))) < 1e-12
    assert np.max(np.abs(np.einsum("...ki,...ki->...k", w, kin.n))) < 1e-12  # no spin


def test_batched_equals_one_by_one(lissajous):
    _, _, p, v, a, _ = lissajous
    batch = dyn.inverse_dynamics(
        MECH, PARAMS, p[:24].reshape(2, 12, 3), v[:24].reshape(2, 12, 3), a[:24].reshape(2, 12, 3)
    )
    assert batch.shape == (2, 12, 3)
    loop = np.array([dyn.inverse_dynamics(MECH, PARAMS, p[k], v[k], a[k]) for k in range(24)])
    assert np.allclose(batch.reshape(24, 3), loop, rtol=0, atol=1e-11)
    # one pose, many accelerations: broadcasting
    f = dyn.inverse_dynamics(MECH, PARAMS, p[0], v[0], a[:5])
    assert f.shape == (5, 3)
    assert np.allclose(
        f[3], dyn.inverse_dynamics(MECH, PARAMS, p[0], v[0], a[3]), rtol=0, atol=1e-11
    )


def test_fig9_curve_is_fast():
    """Issue 5: one full Fig. 9 curve (>= 2000 samples) in <= 50 ms; best of 5."""
    p, v, a = dyn.SineMotion().state(np.linspace(0, 0.1, 2001))
    best = np.inf
    for _ in range(5):
        t0 = time.perf_counter()
        dyn.inverse_dynamics(MECH, PARAMS, p, v, a)
        best = min(best, time.perf_counter() - t0)
    assert best < 0.05


# ---------------------------------------------------------------------------------------- bad input
def test_bad_input_raises_clear_errors():
    zero = np.zeros(3)
    with pytest.raises(ShapeError, match="broadcast"):
        dyn.inverse_dynamics(MECH, PARAMS, np.zeros((4, 3)) + [0, 0, 0.57], np.zeros((5, 3)), zero)
    with pytest.raises(ShapeError):
        dyn.inverse_dynamics(MECH, PARAMS, [0.0, 0.57], zero, zero)
    with pytest.raises(ValueError, match="non-finite"):
        dyn.inverse_dynamics(MECH, PARAMS, [0.0, np.nan, 0.57], zero, zero)
    with pytest.raises(UnreachableError):
        dyn.inverse_dynamics(MECH, PARAMS, [0.0, 0.0, 0.9], zero, zero)
    with pytest.raises(ValueError, match="h_form"):
        dyn.drive_accelerations(MECH, [0, 0, 0.57], zero, zero, h_form="printed")
    with pytest.raises(ValueError, match="rod_inertia_factor"):
        dyn.inverse_dynamics(MECH, PARAMS, [0, 0, 0.57], zero, zero, rod_inertia_factor=-1)
    with pytest.raises(TypeError):
        dyn.inverse_dynamics(P3P4S, PARAMS, [0, 0, 0.57], zero, zero)
    with pytest.raises(ValueError, match="step"):
        dyn.ik_finite_differences(MECH, dyn.SineMotion(), [0.0], 0.0)


def test_singular_configuration_raises():
    # at the centre the rods stand vertical when z = L + delta tan(phi): J's rows are all e_z / sin(phi)
    z = MECH.L + MECH.delta * np.tan(MECH.phi)
    with pytest.raises(SingularityError, match="coplanar"):
        dyn.inverse_dynamics(MECH, PARAMS, [0.0, 0.0, z], np.zeros(3), np.zeros(3))
    with pytest.raises(SingularityError):
        dyn.limb_kinematics(MECH, [[0.0, 0.0, 0.57], [0.0, 0.0, z]], np.zeros(3), np.zeros(3))


# ---------------------------------------------------------------------------------------- artefacts
SMALL_DYN = {"z0": 0.57, "t_end": 0.05, "samples_per_period": 40, "fd_step": 1e-3}
SMALL = {"zhao2017_3p4s": {"dynamics": SMALL_DYN}}


@pytest.fixture(scope="module")
def section_outputs(tmp_path_factory):
    from parakin.papers.zhao2017_3p4s import dynamics as section

    out = tmp_path_factory.mktemp("zhao2017_dynamics")
    written = {name: fn(SMALL, out) for name, fn in of_module(section).items()}
    return section, out, written


def test_artefacts_write_their_files(section_outputs):
    import pandas as pd

    section, out, written = section_outputs
    expected = {
        "fig05": ["fig05_drive_velocities.csv", "fig05_drive_velocities.png"],
        "fig06": ["fig06_drive_accelerations.csv", "fig06_drive_accelerations.png"],
        "fig07": ["fig07_velocity_check.csv", "fig07_velocity_check.png"],
        "fig08": ["fig08_acceleration_check.csv", "fig08_acceleration_check.png"],
        "fig09": ["fig09_driving_forces.csv", "fig09_driving_forces.png"],
        "fig10": ["fig10_mujoco_forces.csv", "fig10_mujoco_forces.png"],
        "power_balance": ["extra_power_balance.csv", "extra_power_balance.png"],
        "dynamics_slips": ["extra_dynamics_slips.csv", "extra_dynamics_slips.md"],
        "dynamics_printed": ["extra_dynamics_printed.csv", "extra_dynamics_printed.png"],
        "mujoco_tracking": ["extra_mujoco_tracking.csv", "extra_mujoco_tracking.png"],
    }
    assert {k: sorted(p.name for p in v) for k, v in written.items()} == {
        k: sorted(v) for k, v in expected.items()
    }
    for paths in written.values():
        for path in paths:
            assert path.stat().st_size > 0
    f9 = pd.read_csv(out / "fig09_driving_forces.csv")
    assert len(f9) == 41 and f9["z_m"].eq(0.57).all()
    assert f9["static_centre_N"].iloc[0] == pytest.approx(40.6308, abs=1e-4)
    slips = pd.read_csv(out / "extra_dynamics_slips.csv").set_index("variant")
    assert slips.loc["corrected (ours)", "verdict"] == "passes all checks"
    for label in ("H without 1/l", "spurious gravity moment", "rod inertia without factor 2"):
        assert slips.loc[label, "verdict"] == "slip confirmed"
    assert slips.loc["spurious gravity moment", "static_centre_change_N"] == pytest.approx(
        -20.681, abs=1e-3
    )
    assert (
        slips.loc["corrected (ours)", "tracking_rel"]
        < 1e-3
        < slips.loc["all three (as printed)", "tracking_rel"]
    )
    tracking = pd.read_csv(out / "extra_mujoco_tracking.csv")
    assert tracking["error_ours_parallelogram_m"].max() < 1e-6
    pb = pd.read_csv(out / "extra_power_balance.csv")
    assert np.max(np.abs(pb["residual_W"])) / np.max(np.abs(pb["dEdt_W"])) < 1e-6


def test_claims_and_summary(section_outputs):
    section, out, _ = section_outputs
    ref = load_reference("zhao2017_3p4s")
    claims = section.claims(out, ref)
    assert len(claims) == 8
    for c in claims:
        printed = "printed" in c.variant
        c = resolve(c, ref)  # judged with the tolerance data/reference declares
        # the agreement needs our corrected equations: consistent after assuming them (issue 28)
        want = "consistent after fitting or assuming" if c.basis else "reproduced"
        assert c.verdict == ("differs — cause shown" if printed else want), (c.variant, c.ours)
        assert printed or c.outcome == "reproduced", (c.variant, c.ours)
    text = section.summary(out, ref)
    assert "40.63 N per motor" in text and "slip confirmed" in text and "Power balance" in text
    assert "open loop" in text


@pytest.mark.parametrize(
    "cfg, match",
    [
        ({}, "no 'zhao2017_3p4s.dynamics'"),
        (
            {"zhao2017_3p4s": {"dynamics": {"z0": 0.57, "t_end": 0.05, "samples_per_period": 40}}},
            "fd_step is missing",
        ),
        (
            {"zhao2017_3p4s": {"dynamics": {**SMALL_DYN, "samples_per_period": 4}}},
            "samples_per_period",
        ),
        ({"zhao2017_3p4s": {"dynamics": {**SMALL_DYN, "z0": "0.57"}}}, "z0"),
        ({"zhao2017_3p4s": {"dynamics": {**SMALL_DYN, "t_end": True}}}, "t_end"),
    ],
)
def test_section_rejects_bad_config(cfg, match):
    from parakin.papers.zhao2017_3p4s import dynamics as section

    with pytest.raises(ConfigError, match=match):
        section.settings(cfg)
