"""A mechanism is a file (issue 43): the examples/ descriptions, their kinematics, assemblies,
Jacobians, dynamics and drawings, checked against the classes they copy, published closed forms
(R. L. Williams II's Delta), finite differences, brute force and each other.

Tolerances are declared before looking: 1e-12 where a file copies a class (the same arithmetic
to rounding), 1e-12 rad for the Delta's IK against Williams' closed form, 1e-9 m for its FK
(three spheres, conditioning about 10 at worst in the box), 1e-9 for round trips through a
solver, 1e-6 relative for finite differences.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from parakin import kernels
from parakin.cli import main
from parakin.errors import UnreachableError
from parakin.mechanisms import P3P4S, Stewart66, from_file
from parakin.mechanisms.described import DescriptionError, from_dict
from parakin.mechanisms.rpr3 import RPR3

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
#: every described example of this issue
FILES = ["delta", "linear_delta", "rrr3", "rss6", "stewart66", "rpr3", "p3p4s"]
EXACT = ["delta", "linear_delta", "rrr3", "rpr3", "p3p4s"]  # translational or planar
N = 10_000


def load(name: str):
    return from_file(EXAMPLES / f"{name}.yaml")


def poses_in(mech, n: int, seed: int = 0) -> np.ndarray:
    """Uniform poses in the mechanism's box, kept where its IK exists and on its assembly mode."""
    lo, hi = mech.pose_bounds()
    x = np.random.default_rng(seed).uniform(lo, hi, (n, mech.n_pose))
    x = x[mech.in_domain(x)]
    return x[mech.on_assembly(x, mech.ik(x))]


def gap(mech, a, b) -> np.ndarray:
    return np.max(np.abs(mech.pose_difference(a, b)), axis=-1)


# ---------------------------------------------------------------------------- the files
@pytest.mark.parametrize("name", FILES)
def test_every_example_loads_and_reads_back(name):
    mech = load(name)
    assert mech.n_joints == mech.n_pose == len(mech.legs)
    again = from_dict(json.loads(json.dumps(mech.to_dict())))
    assert again == mech  # the description as data is the whole mechanism
    assert mech.in_domain(mech.home())
    assert mech.kernel() is not None and mech.kernel().module is kernels.legs


def test_files_match_their_classes_on_random_poses():
    """The 3-RPR, 3-P(4S) and 6-6 files give their classes' joints to <= 1e-12 on 10^4 random poses
    (the 6-6 file orders its pose x, y, z, alpha, beta, gamma)."""
    rng = np.random.default_rng(1)
    for name, cls, order in (
        ("rpr3", RPR3, [0, 1, 2]),
        ("p3p4s", P3P4S, [0, 1, 2]),
        ("stewart66", Stewart66, [3, 4, 5, 0, 1, 2]),
    ):
        mech, ref = load(name), cls()
        lo, hi = ref.pose_bounds()
        x = rng.uniform(lo, hi, (N, ref.n_pose))
        x = x[ref.in_domain(x)]
        assert len(x) > 0.9 * N
        assert np.max(np.abs(mech.ik(x[:, order]) - ref.ik(x))) <= 1e-12, name
        assert np.array_equal(mech.in_domain(x[:, order]), ref.in_domain(x)), name
    # the 3-RPR's residual, Jacobian and assembly test are the class's too, and so is the 3-P(4S)'s FK
    mech, ref = load("rpr3"), RPR3()
    x = rng.uniform(*ref.pose_bounds(), (N, 3))
    q = ref.ik(x)
    assert np.max(np.abs(mech.jacobian_pose(x, q) - ref.jacobian_pose(x, q))) <= 1e-12
    assert np.array_equal(mech.on_assembly(x, q), ref.on_assembly(x, q))
    mech, ref = load("p3p4s"), P3P4S()
    x = rng.uniform(*ref.pose_bounds(), (N, 3))
    assert np.max(np.abs(mech.fk(ref.ik(x)) - ref.fk(ref.ik(x)))) <= 1e-12


@pytest.mark.parametrize("name", EXACT)
def test_round_trip_through_every_assembly(name):
    """On 10^4 random poses: the pose is one of fk_all(ik(pose)), which is complete, and fk (the
    working assembly nearest home) gives joints that ik maps back."""
    mech = load(name)
    x = poses_in(mech, N)
    assert len(x) > 0.8 * N
    q = mech.ik(x)
    sols, complete = mech.real_solutions(q)
    assert complete.all()
    nearest = np.nanmin(gap(mech, sols, x[:, None]), axis=-1)
    assert np.max(nearest) <= 1e-9
    got = mech.fk(q)
    assert np.max(np.abs(mech.joint_error(got, q))) <= 1e-9
    assert np.mean(gap(mech, got, x) <= 1e-9) > 0.99  # fk: this pose, save rare twins near home


@pytest.mark.parametrize("name", ["stewart66", "rss6"])
def test_spatial_round_trip_by_newton(name):
    """On 10^4 random poses, Newton (numpy path) from 0.1 % of the box away: a success on >= 99.9 %
    (every success's IK gives the joints back), and the pose itself except where another solution
    of the same joints lies close (near-singular: flagged, or cond(d residual / d pose) >= 1e3;
    the 6-6's box holds every orientation). One input's homotopy assemblies include the pose,
    certified complete."""
    from parakin.solvers import solve_fk

    mech = load(name)
    x = poses_in(mech, N)
    lo, hi = mech.pose_bounds()
    start = x + 1e-3 * (hi - lo) * np.random.default_rng(2).uniform(-1, 1, x.shape)
    q = mech.ik(x)
    with kernels.interpreted():
        res = solve_fk(mech, q, x0=start, method="newton", tol=1e-12)
    assert res.success.mean() >= 0.999
    assert np.max(res.joint_error[res.success]) <= 1e-9
    back = gap(mech, res.x, x) <= 1e-8
    close = res.near_singular | (np.linalg.cond(mech.jacobian_pose(x, q)) >= 1e3)
    assert np.all(back | close | ~res.success)
    sols, complete = mech.real_solutions(q[:1])
    assert complete.all() and np.nanmin(gap(mech, sols[0], x[0])) <= 1e-9


def test_a_general_planar_mechanism_has_every_assembly_found():
    """A 3-RPR without symmetry: fk_all's assemblies equal those Newton finds from a grid of 637
    starts, input by input (up to four real ones here)."""
    mech = from_dict(
        {
            "name": "general-3rpr",
            "platform": "planar",
            "home": [0.3, 0.3, 0.1],
            "legs": [
                {"type": "length", "base": [0, 0], "platform": [0, 0]},
                {"type": "length", "base": [1, 0], "platform": [0.5, 0.1]},
                {"type": "length", "base": [0.3, 0.9], "platform": [0.2, 0.4]},
            ],
        }
    )
    rng = np.random.default_rng(3)
    grid = np.stack(
        np.meshgrid(np.linspace(-1, 2, 7), np.linspace(-1, 2, 7), np.linspace(-3, 3, 13)), -1
    ).reshape(-1, 3)
    counts = []
    for q in rng.uniform(0.3, 1.1, (12, 3)):
        sols, complete = mech.real_solutions(q)
        found = sols[0][np.isfinite(sols[0, :, 0])]
        x, qq = grid.copy(), np.broadcast_to(q, grid.shape)
        with np.errstate(all="ignore"):
            for _ in range(40):
                step = np.linalg.solve(
                    mech.jacobian_pose(x, qq) + 1e-14 * np.eye(3),
                    mech.residual(x, qq)[..., None],
                )[..., 0]
                x = x - np.nan_to_num(step)
            ok = np.max(np.abs(mech.residual(x, qq)), -1) < 1e-10
        brute = mech._distinct_rows(np.where(ok[:, None], x, np.nan)[None])[0]
        brute = brute[np.isfinite(brute[:, 0])]
        assert complete[0] and len(found) == len(brute), q
        for y in brute:
            assert np.min(gap(mech, found, y)) < 1e-8
        counts.append(len(found))
    assert max(counts) == 4


# ---------------------------------------------------------------------------- the Delta
WILLIAMS = {"s_B": 0.567, "s_P": 0.076, "L": 0.524, "l": 1.244}


def williams_efg(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Williams' IPK coefficients: leg i closes where ``E_i cos(theta_i) + F_i sin(theta_i) + G_i
    = 0``, each (..., 3)."""
    s_b, s_p, big_l, small_l = WILLIAMS.values()
    w_b, u_p, w_p = np.sqrt(3) / 6 * s_b, np.sqrt(3) / 3 * s_p, np.sqrt(3) / 6 * s_p
    a, b, c = w_b - u_p, s_p / 2 - np.sqrt(3) / 2 * w_b, w_p - w_b / 2
    px, py, pz = x[..., 0], x[..., 1], x[..., 2]
    r2 = px**2 + py**2 + pz**2
    e = [
        2 * big_l * (py + a),
        -big_l * (np.sqrt(3) * (px + b) + py + c),
        big_l * (np.sqrt(3) * (px - b) - py - c),
    ]
    g = [
        r2 + a**2 + big_l**2 + 2 * py * a - small_l**2,
        r2 + b**2 + c**2 + big_l**2 + 2 * (px * b + py * c) - small_l**2,
        r2 + b**2 + c**2 + big_l**2 + 2 * (-px * b + py * c) - small_l**2,
    ]
    return np.stack(e, -1), np.stack([2 * pz * big_l] * 3, -1), np.stack(g, -1)


def williams_ik(x: np.ndarray) -> np.ndarray:
    """Both roots of Williams' IPK, (..., 3, 2): ``theta = 2 atan((-F +- sqrt(E^2 + F^2 - G^2)) /
    (G - E))`` (tangent half-angle substitution)."""
    e, f, g = williams_efg(x)
    d = np.sqrt(e**2 + f**2 - g**2)
    return np.stack([2 * np.arctan((-f + d) / (g - e)), 2 * np.arctan((-f - d) / (g - e))], -1)


def williams_fk(theta: np.ndarray) -> np.ndarray:
    """Williams' FPK: the intersection of three spheres of radius l about the virtual centres
    A_i - (platform offset of leg i), both points (..., 2, 3), by trilateration in the frame of
    the centres (another construction than parakin's)."""
    s_b, s_p, big_l, small_l = WILLIAMS.values()
    w_b, u_p, w_p = np.sqrt(3) / 6 * s_b, np.sqrt(3) / 3 * s_p, np.sqrt(3) / 6 * s_p
    t1, t2, t3 = theta[..., 0], theta[..., 1], theta[..., 2]
    k = np.sqrt(3) / 2
    centres = np.stack(
        [
            np.stack([0 * t1, -w_b - big_l * np.cos(t1) + u_p, -big_l * np.sin(t1)], -1),
            np.stack(
                [
                    k * (w_b + big_l * np.cos(t2)) - s_p / 2,
                    0.5 * (w_b + big_l * np.cos(t2)) - w_p,
                    -big_l * np.sin(t2),
                ],
                -1,
            ),  # fmt: skip
            np.stack(
                [
                    -k * (w_b + big_l * np.cos(t3)) + s_p / 2,
                    0.5 * (w_b + big_l * np.cos(t3)) - w_p,
                    -big_l * np.sin(t3),
                ],
                -1,
            ),  # fmt: skip
        ],
        -2,
    )
    p1, p2, p3 = centres[..., 0, :], centres[..., 1, :], centres[..., 2, :]
    d = np.linalg.norm(p2 - p1, axis=-1)
    ex = (p2 - p1) / d[..., None]
    i = np.sum(ex * (p3 - p1), -1)
    ey = p3 - p1 - i[..., None] * ex
    j = np.linalg.norm(ey, axis=-1)
    ey = ey / j[..., None]
    ez = np.cross(ex, ey)
    px = d / 2  # equal radii
    py = (i**2 + j**2) / (2 * j) - i / j * px
    pz = np.sqrt(small_l**2 - px**2 - py**2)
    base = p1 + px[..., None] * ex + py[..., None] * ey
    return np.stack([base + pz[..., None] * ez, base - pz[..., None] * ez], -2)


def test_delta_ik_is_williams_closed_form():
    """Both crank branches solve Williams' IPK equation to rounding (<= 1e-13 of |E| + |F| + |G|)
    and are his two roots (<= 1e-9 rad modulo a turn: his half-angle formula, evaluated in
    doubles, loses digits where G - E is small, up to 7e-12 rad here) on 10^4 poses; the default
    branch (-1) is the knee out: the crank's tip farther out along the leg's outward direction."""
    mech = load("delta")
    x = poses_in(mech, N)
    other = dataclasses.replace(
        mech, legs=tuple(dataclasses.replace(leg, branch=1) for leg in mech.legs)
    )
    e, f, g = williams_efg(x)
    for m in (mech, other):
        theta = m.ik(x)
        closure = e * np.cos(theta) + f * np.sin(theta) + g
        assert np.max(np.abs(closure) / (np.abs(e) + np.abs(f) + np.abs(g))) <= 1e-13
    roots = williams_ik(x)
    mine = np.stack([mech.ik(x), other.ik(x)], -1)  # (N, 3, 2)
    wrap = lambda d: (d + np.pi) % (2 * np.pi) - np.pi  # noqa: E731
    direct = np.abs(wrap(mine - roots)).max(-1)
    swapped = np.abs(wrap(mine - roots[..., ::-1])).max(-1)
    assert np.max(np.minimum(direct, swapped)) <= 1e-9
    # the knee out: the crank's tip farther out along the leg's outward direction (its zero)
    outward = [np.cos(q) for q in (mech.ik(x), other.ik(x))]  # (tip - centre) . zero / crank
    assert np.all(outward[0] > outward[1])


def test_delta_fk_is_williams_three_spheres_both_points():
    mech = load("delta")
    x = poses_in(mech, N)
    q = mech.ik(x)
    sols, complete = mech.real_solutions(q)
    ref = williams_fk(q)
    assert complete.all() and np.isfinite(sols).all()
    d = np.abs(sols[:, :, None, :] - ref[:, None, :, :]).max(-1)  # (N, 2 mine, 2 his)
    assert np.max(np.minimum(d[:, 0, 0] + d[:, 1, 1], d[:, 0, 1] + d[:, 1, 0])) <= 2e-9
    assert np.max(np.abs(mech.fk(q) - x)) <= 1e-9  # the working point: below the base, knee out


# ---------------------------------------------------------------------------- Jacobians
@pytest.mark.parametrize("name", FILES)
def test_jacobians_match_finite_differences(name):
    mech = load(name)
    x = poses_in(mech, 200, seed=5)[:20]
    q = mech.ik(x)
    h = 1e-6
    eye = np.eye(mech.n_pose) * h
    fd_pose = np.stack(
        [(mech.residual(x + e, q) - mech.residual(x - e, q)) / (2 * h) for e in eye], -1
    )
    scale = np.max(np.abs(fd_pose))
    assert np.max(np.abs(mech.jacobian_pose(x, q) - fd_pose)) <= 1e-6 * scale
    eye = np.eye(mech.n_joints) * h
    fd_joint = np.stack(
        [(mech.residual(x, q + e) - mech.residual(x, q - e)) / (2 * h) for e in eye], -1
    )
    assert np.max(np.abs(mech.jacobian_joints(x, q) - fd_joint)) <= 1e-6 * np.max(np.abs(fd_joint))
    fd_ik = np.stack(
        [(mech.ik(x + e) - mech.ik(x - e)) / (2 * h) for e in np.eye(mech.n_pose) * h], -1
    )
    jv = mech.velocity_jacobian(x)
    assert np.max(np.abs(jv - fd_ik)) <= 1e-6 * np.max(np.abs(fd_ik))


# ---------------------------------------------------------------------------- branches and limits
def test_each_rod_leg_has_two_branches():
    """A slider's two positions and a crank's two angles both close the leg; the branch field picks
    one, the other is the other root."""
    for name in ("linear_delta", "delta"):
        mech = load(name)
        x = poses_in(mech, 200, seed=6)
        flip = dataclasses.replace(  # (no limits: the other branch's sliders are below 0)
            mech,
            legs=tuple(
                dataclasses.replace(leg, branch=-leg.branch, limits=None) for leg in mech.legs
            ),
            home_pose=None if name == "linear_delta" else mech.home_pose,
            bounds=None,
        )
        for m in (mech, flip):
            assert np.max(np.abs(m.residual(x, m.ik(x)))) <= 1e-12
        assert np.min(np.abs(mech.ik(x) - flip.ik(x))) > 1e-3


def test_limits_bound_the_domain_and_the_joints():
    mech = load("linear_delta")
    x = mech.home()
    assert mech.in_domain(x)
    high = x + [0, 0, 0.5]  # the carriages past the rails' tops (0.6 m)
    assert not mech.in_domain(high)
    with pytest.raises(UnreachableError, match="outside the domain"):
        mech.ik(high)
    q = mech.ik(x)
    with pytest.raises(UnreachableError, match=r"s2 = 0.7 m is outside its limits \[0, 0.6\] m"):
        mech.check_joints([q[0], 0.7, q[2]])


def test_joints_that_cannot_assemble_are_refused_with_the_reason():
    with pytest.raises(UnreachableError, match="legs 1 and 2 hold their anchors"):
        load("rpr3").check_joints([0.1, 0.1, 0.1])
    with pytest.raises(UnreachableError, match="must be > 0"):
        RPR3().check_joints([0.0, 0.0, 0.0])
    with pytest.raises(UnreachableError, match="never as this mechanism works"):
        load("delta").check_joints([3.0, 3.0, 3.0])
    RPR3().check_joints(RPR3().ik([[0.01, 0.02, 0.1], [0.0, 0.0, 0.0]]))  # reachable: no error


# ---------------------------------------------------------------------------- malformed files
GOOD = (EXAMPLES / "delta.yaml").read_text()


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("- 1\n- 2\n", "expected a mapping with name, platform and legs"),
        (GOOD.replace("name: delta", "name: ''"), "name: expected a non-empty text"),
        (GOOD.replace("platform: translational", "platform: rotary"), "platform: expected one of"),
        (GOOD.replace("home:", "hom:"), "hom: unknown field"),
        (GOOD.replace("type: crank-rod", "type: cable", 1), r"legs\[0\].type: expected one of"),
        (GOOD.replace("    rod: 1.244\n", "", 1), r"legs\[0\].rod: missing"),
        (GOOD.replace("rod: 1.244", "rod: -1.244", 1), r"legs\[0\].rod: expected a length > 0"),
        (GOOD.replace("crank: 0.524", "crank: abc", 1), r"legs\[0\].crank: expected a number"),
        (
            GOOD.replace("zero: [0.0, -1.0, 0.0]", "zero: [1.0, 0.5, 0.0]", 1),
            r"legs\[0\].zero: must be perpendicular",
        ),
        (GOOD.replace("branch: -1 ", "branch: 2 ", 1), r"legs\[0\].branch: expected \+1 or -1"),
        (
            GOOD.replace("axis: [1.0, 0.0, 0.0]", "axis: [0, 0, 0]", 1),
            r"legs\[0\].axis: a direction must not be zero",
        ),
        (
            GOOD.replace("home: [0.0, 0.0, -0.9]", "home: [0.0, 0.0]"),
            "home: expected a list of 3 numbers",
        ),
        (
            GOOD.replace("home: [0.0, 0.0, -0.9]", "home: [0.0, 0.0, 5.0]"),
            "home: the pose .* is outside",
        ),
        (GOOD.replace("masses:", "masses:\n  slider: 1.0"), "masses.slider: unknown field"),
        ("name: x\nplatform: planar\nlegs: [1, 2, 3]\n", r"legs\[0\]: expected a mapping"),
        ("name: x\nplatform: planar\nlegs: []\n", "needs 3 legs, got 0"),
        (
            "a: &a [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]\n"
            + "".join(
                f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n"
                for p, c in zip("abcdefgh", "bcdefghi")
            ),
            "expands to",
        ),  # fmt: skip
        ("name: [unclosed\n", "not valid YAML or JSON"),
    ],
)
def test_malformed_files_get_one_line_naming_the_field(tmp_path, capsys, text, message):
    path = tmp_path / "m.yaml"
    path.write_text(text)
    with pytest.raises(DescriptionError, match=message) as err:
        from_file(path)
    assert "\n" not in str(err.value) and str(path) in str(err.value)
    assert main(["ik", "--mechanism", str(path), "--pose", "0", "0", "-0.9"]) == 2
    line = capsys.readouterr().err
    assert line.count("\n") == 1 and "Traceback" not in line


def test_a_file_too_large_is_refused_before_it_is_read(tmp_path):
    path = tmp_path / "big.yaml"
    path.write_text("# " + "x" * (1 << 20) + "\n")
    with pytest.raises(DescriptionError, match="more than the limit"):
        from_file(path)


# ---------------------------------------------------------------------------- dynamics, drawings
@pytest.mark.parametrize("name", ["delta", "linear_delta", "rrr3", "rss6"])
def test_dynamics_from_declared_masses_balance_power(name):
    from parakin import dynamics as D
    from parakin.dynamics.trajectory import Harmonic, power_balance

    mech = load(name)
    tr = Harmonic.around(mech, 0.05, 0.5)
    t = np.linspace(0.0, tr.period, 21)
    assert power_balance(mech, tr, t, step=1e-4 * tr.period).relative_error < 1e-9
    x = poses_in(mech, 50, seed=7)[:4]
    st = D.state(mech, x, np.zeros_like(x))
    assert np.max(np.abs(st.joints.value - mech.ik(x))) <= 1e-14
    assert np.max(np.abs(st.jacobian - mech.velocity_jacobian(x))) <= 1e-10 * np.max(
        np.abs(mech.velocity_jacobian(x))
    )


def test_no_masses_no_dynamics():
    assert load("rpr3").mass_model() is None


@pytest.mark.parametrize("name", ["delta", "linear_delta", "rrr3", "rss6"])
def test_the_drawing_of_a_described_mechanism(name):
    pytest.importorskip("matplotlib")
    from parakin.plot import draw_mechanism

    mech = load(name)
    ax = draw_mechanism(mech)
    sk = mech.skeleton(mech.home())
    assert len(ax.lines) >= len(sk.segments) >= mech.n_joints
    import matplotlib.pyplot as plt

    plt.close(ax.figure)


# ---------------------------------------------------------------------------- the command line
def _json(capsys, *argv) -> tuple[int, dict]:
    code = main([*argv, "--json"])
    return code, json.loads(capsys.readouterr().out)


def test_cli_fk_all_of_the_delta_file_gives_both_assemblies(capsys):
    mech = load("delta")
    x = np.array([0.1, -0.05, -1.0])
    q = mech.ik(x)
    code, out = _json(capsys, "fk", "--mechanism", str(EXAMPLES / "delta.yaml"), "--joints",
                      *map(repr, q.tolist()), "--all")  # fmt: skip
    assert code == 0 and out["n_found"] == [2] and out["complete"] == [True]
    sols = out["solutions"][0]
    working = [s for s in sols if s["working"]]
    assert len(working) == 1 and np.allclose(working[0]["x"], x, atol=1e-12)
    assert any(s["x"][2] > 0 for s in sols)  # the mirror point, above the base
    code, out = _json(capsys, "ik", "--mechanism", str(EXAMPLES / "delta.yaml"), "--pose",
                      *map(repr, x.tolist()))  # fmt: skip
    assert code == 0 and np.allclose(out["joints"], q, atol=1e-15)


def test_cli_revolute_joints_modulo_a_turn(capsys):
    """A crank angle given a turn away (3.56 rad for -2.72 rad) is the same joint: a success."""
    mech = load("rrr3")
    x = np.array([0.02, -0.01, 0.1])
    q = mech.ik(x) + [0.0, -2 * np.pi, 2 * np.pi]
    for solver in ("newton", "closed-form"):
        code, out = _json(capsys, "fk", "--mechanism", str(EXAMPLES / "rrr3.yaml"), "--joints",
                          *map(repr, q.tolist()), "--solver", solver)  # fmt: skip
        assert code == 0 and out["success"] and out["joint_error"] <= 1e-9
        assert np.allclose(out["x"], x, atol=1e-9)


def test_cli_refuses_unreachable_joints_before_the_solver(capsys):
    assert main(["fk", "rpr3", "--joints", "0", "0", "0"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and "rho1 = 0 m must be > 0" in captured.err


def test_cli_dynamics_and_bench_take_a_file(tmp_path, capsys):
    mech = load("delta")
    t = np.linspace(0, 1, 5)
    x = mech.home() + 0.02 * np.stack([np.sin(t), np.cos(t) - 1, 0 * t], -1)
    csv = tmp_path / "traj.csv"
    csv.write_text("t,x,y,z\n" + "".join(f"{a},{b},{c},{d}\n" for a, (b, c, d) in zip(t, x)))
    code = main(["dynamics", "--mechanism", str(EXAMPLES / "delta.yaml"), "--trajectory",
                 str(csv), "--json"])  # fmt: skip
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and np.array(out["force"]).shape == (5, 3)
    assert main(["dynamics", "rpr3", "--mechanism", str(EXAMPLES / "delta.yaml"),
                 "--trajectory", str(csv)]) == 2  # fmt: skip
    assert "not both" in capsys.readouterr().err


@pytest.mark.slow
def test_cli_bench_runs_the_atlas_on_a_file(capsys):
    """`parakin bench --mechanism FILE --quick`: every standard solver on the atlas's scenarios
    (compiles the legs kernel's every method on an empty cache: minutes)."""
    assert main(["bench", "--mechanism", str(EXAMPLES / "rrr3.yaml"), "--quick", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    nominal = {r["method"]: r for r in rows if r["scenario"] == "nominal"}
    assert {"newton", "lm", "broyden", "bfgs", "all-solutions", "scipy-root"} <= set(nominal)
    assert nominal["newton"]["success_rate"] == 1.0
    assert nominal["all-solutions"]["success_rate"] == 1.0
