"""parakin.workspace (issue 44): volumes against closed forms, Monte Carlo between the certified
interval bounds, singular points verified by the smallest singular value, the compiled classifier
against numpy, finite differences, Zhao's recorded atlas reproduced, the Delta against a
closed-form test, interference, the CLI and the study at small sizes."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from parakin import workspace as W
from parakin.mechanisms import REGISTRY
from parakin.mechanisms.described import from_dict
from parakin.workspace.interval import _NAMES, Interval, Node, _Context, classify_boxes

ROOT = Path(__file__).resolve().parents[1]


# ---------------------------------------------------------------------------------------- fixtures
def lens_mechanism(r1: float = 1.0, r2: float = 1.0):
    """A point platform on three length legs: legs 1 and 2 from (0,0,0) and (1,0,0) of length at most
    ``r1``, ``r2``, leg 3 from far above with room to spare. Its workspace is the lens where the
    two balls meet (closed form), cut by the direct singular plane y = 0 (the three base points'
    plane: there the leg directions are coplanar)."""
    legs = [
        {"type": "length", "base": [0.0, 0.0, 0.0], "platform": [0, 0, 0], "limits": [1e-3, r1]},
        {"type": "length", "base": [1.0, 0.0, 0.0], "platform": [0, 0, 0], "limits": [1e-3, r2]},
        {"type": "length", "base": [0.5, 0.0, 5.0], "platform": [0, 0, 0], "limits": [1e-3, 20.0]},
    ]
    return from_dict(
        {
            "name": "lens",
            "platform": "translational",
            "home": [0.5, 0.3, 0.2],
            "bounds": {"lower": [-0.5, -0.5, -0.5], "upper": [1.5, 0.5, 0.5]},
            "legs": legs,
        }
    )


def lens_volume(r: float, d: float) -> float:
    """Two balls of radius ``r`` whose centres are ``d`` apart: their intersection's volume."""
    return math.pi * (4 * r + d) * (2 * r - d) ** 2 / 12


def lens_area(r: float, d: float) -> float:
    """Two discs of radius ``r`` whose centres are ``d`` apart: their intersection's area."""
    return 2 * r * r * math.acos(d / (2 * r)) - 0.5 * d * math.sqrt(4 * r * r - d * d)


@pytest.fixture(scope="module")
def lens():
    return lens_mechanism()


# ---------------------------------------------------------------------------------------- closed forms
def test_lens_volume_closed_form_within_bounds_and_error_bar(lens):
    region = W.make_region(lens)
    assert region.limits_source == "declared by the mechanism"
    region, touching = W.fit_box(region)
    assert touching == []
    exact = lens_volume(1.0, 1.0)
    est = W.volumes(region, 200_000, np.random.default_rng(3), compiled=False)["constant"]
    assert abs(est.volume - exact) <= 4 * est.se, (est.volume, est.se, exact)
    bounds = W.certify(region, levels=5)
    assert bounds.inner <= exact <= bounds.outer
    assert bounds.inner - 4 * est.se <= est.volume <= bounds.outer + 4 * est.se
    assert bounds.outer - bounds.inner < 0.5 * exact  # the bounds mean something


@pytest.mark.parametrize(
    "name, axes, unit",
    [("3p4s", None, "m^3"), ("rpr3", None, "m^2"), ("rpr3", ["x", "y", "phi"], "m^2 rad")],
)
def test_monte_carlo_between_the_certified_bounds(name, axes, unit):
    """A translational and a planar mechanism (the latter also with its angle as an axis)."""
    region, _ = W.fit_box(W.make_region(REGISTRY[name](), axes=axes))
    assert region.unit == unit
    est = W.volumes(region, 100_000, np.random.default_rng(13), cond=False, compiled=False)
    bounds = W.certify(region, levels=5)
    v, se = est["constant"].volume, est["constant"].se
    assert bounds.inner - 4 * se <= v <= bounds.outer + 4 * se
    assert 0 < bounds.inner < bounds.outer


def test_long_runs_print_a_progress_line(capsys):
    region = W.make_region(REGISTRY["rpr3"]())
    W.volumes(region, 2000, np.random.default_rng(0), cond=False, compiled=False, progress=True)
    err = capsys.readouterr().err
    assert "workspace of rpr3: 100%" in err and "2000/2000 poses" in err


def test_lens_slice_area_closed_form(lens):
    """The 2-D workspace over (x, y) at z = 0.2: two discs of radius sqrt(1 - 0.04)."""
    region, _ = W.fit_box(W.make_region(lens, axes=["x", "y"]))
    assert region.unit == "m^2" and region.others == (2,)
    exact = lens_area(math.sqrt(1 - 0.2**2), 1.0)
    est = W.volumes(region, 100_000, np.random.default_rng(4), compiled=False)["constant"]
    assert abs(est.volume - exact) <= 4 * est.se
    bounds = W.certify(region, levels=7)
    assert bounds.inner <= exact <= bounds.outer


def test_rays_find_the_lens_boundary(lens):
    region, _ = W.fit_box(W.make_region(lens))
    rays = W.boundary_rays(region, W.fibonacci_directions(200, 3), np.array([0.5, 0.05, 0.0]))
    p = rays.points
    # on the boundary one of the two spheres of radius 1 holds the point (to the bisection's 1e-9)
    d1 = np.linalg.norm(p, axis=-1)
    d2 = np.linalg.norm(p - [1.0, 0, 0], axis=-1)
    assert np.all(np.minimum(abs(d1 - 1), abs(d2 - 1)) < 1e-8)
    # a described mechanism's kernel refuses joints beyond their limits: its IK's domain ends there
    assert set(rays.reason) <= {"l1 max", "l2 max", "domain"}
    # the lens is convex: the rays' volume is the closed form (to the quadrature's error)
    assert W.ray_volume(rays) == pytest.approx(lens_volume(1.0, 1.0), rel=0.02)


# ---------------------------------------------------------------------------------------- singular points
@pytest.mark.parametrize("n", [30, 31])  # 31: a grid line on the locus itself (det exactly 0)
def test_singular_points_of_the_lens_lie_on_its_singular_plane(lens, n):
    """det A = 0 where the legs' directions are coplanar: the plane y = 0 of the base points."""
    region, _ = W.fit_box(W.make_region(lens))
    _, _, pts = W.plane_grid(region, 0, 1, n, at=np.array([0.5, 0.0, 0.1]))
    loci = W.locate(region, pts)
    direct = loci.kind == "direct"
    assert direct.sum() >= 10
    assert np.all(np.abs(loci.points[direct, 1]) <= W.LOCATE_TOL)
    assert np.all(loci.width[direct] <= W.LOCATE_TOL)
    assert np.all(loci.verified[direct]) and np.all(loci.sigma_rel[direct] <= W.VERIFY_REL)


@pytest.mark.parametrize("name", ["stewart66", "3p4s", "2ups"])
def test_registered_singular_points_verified_by_sigma_min(name):
    region, _ = W.fit_box(W.make_region(REGISTRY[name]()))
    _, _, pts = W.plane_grid(region, 0, 1, 31)
    loci = W.locate(region, pts)
    direct = loci.kind == "direct"
    if direct.any():
        assert np.all(loci.sigma_rel[direct & loci.verified] <= W.VERIFY_REL)
        assert loci.verified[direct].mean() > 0.9
    edge = loci.kind == "domain edge"
    # the 3-P(4S)'s IK domain edge: a rod at right angles to its rail, B singular (square-root law)
    if name == "3p4s":
        assert edge.sum() > 0 and np.all(loci.verified[edge])
        assert np.all(loci.sigma_rel[edge] ** 2 <= W.VERIFY_REL)
    # every located point sits where det changes sign: independent check by sigma_min of A
    x = region.poses(loci.points[direct])
    q, ok = W.joints_of(region.mech, x)
    s = np.linalg.svd(region.mech.jacobian_pose(x[ok], q[ok]), compute_uv=False)
    assert np.all(s[:, -1] / s[:, 0] <= 1e-8)


# ---------------------------------------------------------------------------------------- classification
def test_compiled_classifier_matches_numpy():
    mech = REGISTRY["rpr3"]()
    region, _ = W.fit_box(W.make_region(mech))
    pts = np.random.default_rng(5).uniform(region.lo, region.hi, size=(4000, region.dim))
    fast = W.classify(region, pts, compiled=True)
    slow = W.classify(region, pts, compiled=False)
    assert np.array_equal(fast.domain, slow.domain)
    assert np.array_equal(fast.member, slow.member)
    both = np.isfinite(slow.cond)
    assert np.array_equal(both, np.isfinite(fast.cond))
    assert np.max(np.abs(fast.cond[both] / slow.cond[both] - 1)) < 1e-8


def test_condition_number_against_finite_differences_of_the_ik():
    mech = REGISTRY["3p4s"]()
    region = W.make_region(mech, stroke=0.0)
    x = W.sample_reachable(mech, 50, np.random.default_rng(6))
    cls = W.classify(region, x[:, list(region.axes)], compiled=False)
    h = 1e-6
    jac = np.stack(
        [(mech.ik(x + h * e) - mech.ik(x - h * e)) / (2 * h) for e in np.eye(3)], axis=-1
    )
    s = np.linalg.svd(jac, compute_uv=False)
    np.testing.assert_allclose(cls.cond, s[:, 0] / s[:, -1], rtol=1e-5)


def test_zhao_recorded_atlas_reproduced():
    """The committed speed atlases (Figs 23, 25) on their grid over W: every point in the
    workspace, cond(J) equal to the recorded speed index to rounding."""
    from parakin.mechanisms import P3P4S

    for fig, mech in (("fig23_speed_before_atlas", P3P4S.zhao2017()),
                      ("fig25_speed_after_atlas", P3P4S.zhao2017_optimised())):  # fmt: skip
        df = pd.read_csv(ROOT / "figures" / "zhao2017_3p4s" / f"{fig}.csv")
        pts = df[["x_m", "y_m", "z_m"]].to_numpy()
        region = W.make_region(mech, stroke=0.0)
        cls = W.classify(region, pts, compiled=False)
        assert cls.member.all()
        np.testing.assert_allclose(cls.cond, df["speed"].to_numpy(), rtol=1e-12)


def test_delta_against_the_closed_form_torus_test():
    from parakin.mechanisms import from_file
    from parakin.studies.workspace_atlas import delta_torus_test

    mech = from_file(ROOT / "examples" / "delta.yaml")
    region, touching = W.fit_box(W.make_region(mech))
    assert touching == [] and region.unit == "m^3"
    assert region.limits_source.startswith("none")
    pts = np.random.default_rng(7).uniform(region.lo, region.hi, size=(20_000, 3))
    ours = W.classify(region, pts, cond=False, compiled=False).member
    assert np.mean(ours == delta_torus_test(mech, pts)) > 0.9999
    est = region.box_volume * ours.mean()
    bounds = W.certify(region, levels=4)
    assert bounds.inner <= est <= bounds.outer


def test_reachable_contains_constant_and_dexterous_inside_constant():
    region, _ = W.fit_box(W.make_region(REGISTRY["stewart66"](), orientation_fraction=0.25))
    v = W.volumes(region, 20_000, np.random.default_rng(8), orientations=3, compiled=False)
    assert v["dexterous"].hits <= v["constant"].hits <= v["reachable"].hits
    assert v["reachable"].hits > v["constant"].hits  # tilting the platform reaches further


def test_fit_box_grows_a_small_box_and_keeps_angles_within_a_turn():
    mech = REGISTRY["rpr3"]()
    small = W.make_region(mech, box=([-0.01, -0.01], [0.01, 0.01]))
    grown, touching = W.fit_box(small)
    assert touching == [] and np.all(grown.hi - grown.lo > 0.2)
    ups = W.make_region(REGISTRY["2ups"]())
    fitted, _ = W.fit_box(ups)
    rad = [k for k, u in enumerate(fitted.axis_units) if u == "rad"]
    assert np.all(fitted.hi[rad] - fitted.lo[rad] <= 2 * np.pi + 1e-12)


def test_region_bad_input_names_the_value():
    mech = REGISTRY["3p4s"]()
    with pytest.raises(ValueError, match="cond_max"):
        W.make_region(mech, cond_max=0.5)
    with pytest.raises(ValueError, match="low < high"):
        W.make_region(mech, box=([0, 0, 0.6], [0.1, 0.1, 0.5]))
    with pytest.raises(ValueError, match="not a pose coordinate"):
        W.make_region(mech, axes=["x", "q"])
    with pytest.raises(ValueError, match="must be an integer >= 1"):
        W.volumes(W.make_region(mech), 0, np.random.default_rng(0))


# ---------------------------------------------------------------------------------------- intervals
@pytest.mark.parametrize("name", ["sqrt", "sin", "cos", "atan2", "where", "maximum", "mul", "div"])
def test_interval_functions_enclose_every_sample(name):
    """Each interval operation over random boxes holds the values at random points inside them."""
    g = np.random.default_rng(9)
    n = 400
    lo = g.uniform(-4, 4, (2, n))
    hi = lo + g.uniform(0, 3, (2, n)) ** 2
    t = g.uniform(0, 1, (50, 2, n))
    pts = lo + t * (hi - lo)
    ctx = _Context([])
    a = Node(Interval(lo[0], hi[0]), Interval(lo[0]), None, ctx)
    b = Node(Interval(lo[1], hi[1]), Interval(lo[1]), None, ctx)
    ops = {
        "sqrt": (lambda: _NAMES["sqrt"](a), lambda x, y: np.sqrt(np.where(x >= 0, x, np.nan))),
        "sin": (lambda: _NAMES["sin"](a), lambda x, y: np.sin(x)),
        "cos": (lambda: _NAMES["cos"](a), lambda x, y: np.cos(x)),
        "atan2": (lambda: _NAMES["atan2"](a, b), lambda x, y: np.arctan2(x, y)),
        "where": (
            lambda: _NAMES["where"](a > 0.5, a * b, b),
            lambda x, y: np.where(x > 0.5, x * y, y),
        ),
        "maximum": (lambda: _NAMES["maximum"](a, b), np.maximum),
        "mul": (lambda: a * b - a * a, lambda x, y: x * y - x * x),
        "div": (lambda: a / (b * b + 1.0), lambda x, y: x / (y * y + 1)),
    }
    make, f = ops[name]
    enc = make().val
    vals = f(pts[:, 0], pts[:, 1])
    ok = np.isnan(vals) | ((vals >= enc.lo) & (vals <= enc.hi))
    assert ok.all()


def test_interval_boxes_agree_with_points():
    """A box certified in has every sampled point in; a box certified out has none."""
    mech = REGISTRY["3p4s"]()
    region, _ = W.fit_box(W.make_region(mech))
    g = np.random.default_rng(10)
    lo = g.uniform(region.lo, region.hi, (300, 3))
    hi = np.minimum(lo + g.uniform(0, 0.03, (300, 3)), region.hi)
    inside, outside = classify_boxes(region, lo, hi)
    assert inside.any() and outside.any()
    pts = lo[:, None] + g.uniform(0, 1, (300, 40, 3)) * (hi - lo)[:, None]
    member = W.classify(region, pts.reshape(-1, 3), cond=False, compiled=False).member.reshape(
        300, 40
    )
    assert np.all(member[inside]) and not np.any(member[outside])


# ---------------------------------------------------------------------------------------- legs
def test_segment_distance_against_brute_force():
    g = np.random.default_rng(11)
    p0, p1, q0, q1 = (g.normal(size=(200, 3)) for _ in range(4))
    p1[:20] = p0[:20]  # degenerate: a point
    q1[20:40] = q0[20:40] + 2 * (p1[20:40] - p0[20:40])  # parallel
    d = W.segment_distance(p0, p1, q0, q1)
    s = np.linspace(0, 1, 101)
    a = p0[:, None] + s[None, :, None] * (p1 - p0)[:, None]
    b = q0[:, None] + s[None, :, None] * (q1 - q0)[:, None]
    brute = np.min(np.linalg.norm(a[:, :, None] - b[:, None, :], axis=-1), axis=(1, 2))
    assert np.all(d <= brute + 1e-12)
    assert np.all(brute - d <= 0.05 * np.max(np.linalg.norm(p1 - p0, axis=-1)))


def test_clearance_only_removes_poses():
    mech = REGISTRY["stewart66"]()
    region, _ = W.fit_box(W.make_region(mech))
    pts = np.random.default_rng(12).uniform(region.lo, region.hi, (3000, 3))
    free = W.classify(region, pts, cond=False, compiled=False)
    d = W.min_leg_distance(mech, region.poses(pts[free.member]))
    clearance = float(np.quantile(d, 0.3))
    tight = W.classify(region.replace(clearance=clearance), pts, cond=False, compiled=False)
    assert np.all(tight.member <= free.member)
    assert tight.member.sum() == np.sum(d >= clearance)


# ---------------------------------------------------------------------------------------- generic code
def test_workspace_package_imports_no_concrete_mechanism():
    from test_architecture import _concrete_imports, _module_name

    for path in sorted((ROOT / "src" / "parakin" / "workspace").glob("*.py")):
        bad = _concrete_imports(path.read_text(), _module_name(path)[1])
        assert not bad, f"{path.name} imports concrete mechanisms: {bad}"


def test_sample_reachable_still_importable_and_seeded():
    from parakin.workspace import sample_reachable

    mech = REGISTRY["3p4s"]()
    a = sample_reachable(mech, 10, np.random.default_rng(1))
    b = sample_reachable(mech, 10, np.random.default_rng(1))
    assert np.array_equal(a, b) and mech.is_reachable(a).all()


# ---------------------------------------------------------------------------------------- CLI
SMALL = [
    "--samples",
    "3000",
    "--levels",
    "2",
    "--grid",
    "11",
    "--rays",
    "16",
    "--orientations",
    "1",
]


def _run(capsys, *argv):
    from parakin.cli import main

    rc = main(["workspace", *argv])
    return rc, capsys.readouterr()


def test_cli_json_3p4s_and_delta(capsys):
    rc, out = _run(capsys, "3p4s", "--json", *SMALL)
    assert rc == 0
    d = json.loads(out.out)
    assert d["unit"] == "m^3" and d["volume"] > 0 and d["volume_se"] > 0
    assert d["certified"]["inner"] <= d["certified"]["outer"]
    rc, out = _run(capsys, "--mechanism", str(ROOT / "examples" / "delta.yaml"), "--json", *SMALL)
    assert rc == 0 and json.loads(out.out)["unit"] == "m^3"
    rc, out = _run(capsys, "rpr3", "--json", *SMALL)
    assert rc == 0 and json.loads(out.out)["unit"] == "m^2"


def test_cli_text_output_and_files(capsys, tmp_path):
    rc, out = _run(capsys, "rpr3", *SMALL, "--output", str(tmp_path / "a.csv"),
                   "--figure", str(tmp_path / "a.png"))  # fmt: skip
    assert rc == 0 and "m^2" in out.out and (tmp_path / "a.png").stat().st_size > 0
    assert set(pd.read_csv(tmp_path / "a.csv")["part"]) >= {"meta", "volume", "cell", "ray"}


@pytest.mark.parametrize(
    "argv, words",
    [
        (["3p4s", "--box", "x=1:0"], "LO < HI"),
        (["3p4s", "--axes", "x,q"], "not a pose coordinate"),
        (["3p4s", "--cond-max", "0.5"], "cond_max"),
        (["3p4s", "--joint-limit", "l9=0:1"], "not a joint"),
        (["3p4s", "--samples", "0"], "integer in"),
        (["--mechanism", "/nonexistent.yaml"], "nonexistent"),
        (["rpr3", "--at", "phi=1e308"], "at most 1000 rad"),
        (["rpr3", "--box", "x=-1e308:1e308"], "at most 1e+06 m"),
        (["rpr3", "--at", "x=0.1"], "not a held coordinate"),
        (["rpr3", "--at", "phi=nan"], "must be finite"),
    ],
)
def test_cli_bad_input_one_line_exit_2(capsys, argv, words):
    from parakin.cli import main

    try:
        rc = main(["workspace", *argv])
    except SystemExit as exc:  # argparse's own errors
        rc = exc.code
    err = capsys.readouterr().err.strip()
    assert rc == 2 and words in err and len(err.splitlines()) == 1


# ---------------------------------------------------------------------------------------- study
def test_study_atlas_and_table_at_small_sizes(tmp_path):
    from parakin.studies import workspace_atlas as S

    config = {
        "seed": 1,
        "workspace": dict(
            samples=3000,
            orientations=1,
            orientation_fraction=0.25,
            stroke=0.25,
            cond_max=100.0,
            levels=2,
            grid=11,
            rays=16,
            fit_grid=9,
            delta_samples=2000,
            delta_levels=2,
        ),  # fmt: skip
    }
    df = S.atlas_data(config, "rpr3")
    assert set(df.part) >= {"meta", "volume", "cell", "ray"}
    png = W.atlas.draw(df, tmp_path / "extra_workspace_rpr3.png")
    assert png.stat().st_size > 0
    again = S.atlas_data(config, "rpr3")  # seeded from the config: the same table
    pd.testing.assert_frame_equal(df, again)
