"""The solver atlas (src/parakin/atlas.py, src/parakin/studies/solver_atlas.py) and the benchmark summary."""

from __future__ import annotations

import json
import subprocess
import sys
import zlib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib.testing.compare import compare_images

from parakin import mechanisms
from parakin.atlas import (
    AtlasCase,
    AtlasSolver,
    Scenario,
    evaluate,
    make_scenario,
    pose_error,
    run_atlas,
)
from parakin.io import is_timing_column
from parakin.mechanisms import P3P4S, UPS2, Stewart36
from parakin.solvers import Status, solve_fk
from parakin.studies import solver_atlas as extras
from parakin.workspace import sample_reachable

ROOT = Path(__file__).resolve().parents[1]


def _stewart36_box(m: Stewart36, fraction: float = 0.15):
    return extras._box(m, fraction)


# ------------------------------------------------------------------------------ success = right assembly
def test_converged_on_the_mirror_assembly_is_a_failure():
    """Constructed case: Newton started at the mirror image (below the base) of the true pose
    converges there with zero residual; solve_fk and the atlas count it as a wrong assembly, not a
    success."""
    m = Stewart36()
    truth = sample_reachable(m, 5, np.random.default_rng(1), bounds=_stewart36_box(m))
    q = m.ik(truth)
    mirror = m.mirror(truth)
    sc = Scenario("constructed", q, mirror, truth, np.ones(5))
    res = solve_fk(m, q, x0=mirror, method="newton", tol=1e-12)
    assert np.all(res.residual <= 1e-12) and np.all(res.joint_error <= 1e-9)  # Newton converged ...
    assert np.all(pose_error(m, res.x, mirror) < 1e-9)  # ... on the mirror assembly
    assert not res.success.any() and np.all(res.status == Status.WRONG_ASSEMBLY)
    assert res.message.endswith("5 converged on another assembly")
    row = evaluate(m, AtlasSolver("Newton", "newton"), sc, tol=1e-10, success_tol=1e-6)
    assert row["success_rate"] == 0.0
    assert (
        row["wrong_assembly_rate"] == 1.0
        and row["n_wrong_assembly"] == 5
        and row["n_wrong_answer"] == 0
    )
    # and from the truth itself the same rows are successes
    ok = evaluate(m, AtlasSolver("Newton", "newton"), Scenario("c", q, truth, truth, np.ones(5)))
    assert ok["success_rate"] == 1.0 and ok["wrong_assembly_rate"] == 0.0


def test_other_branch_of_the_closed_form_is_a_wrong_assembly():
    m = P3P4S()
    truth = sample_reachable(m, 20, np.random.default_rng(2))
    q = m.ik(truth)
    sc = Scenario("c", q, truth, truth, np.ones(20))
    upper = evaluate(m, AtlasSolver("closed", "closed-form"), sc)
    lower = evaluate(m, AtlasSolver("closed, lower", "closed-form", {"branch": "lower"}), sc)
    assert upper["success_rate"] == 1.0
    assert lower["success_rate"] == 0.0 and lower["wrong_assembly_rate"] == 1.0
    assert np.all(
        solve_fk(m, q, method="closed-form", branch="lower").status == Status.WRONG_ASSEMBLY
    )


def test_pose_error_compares_angles_modulo_2pi():
    m = Stewart36()
    x = m.home()
    y = x.copy()
    y[0] += 2 * np.pi
    y[3] += 1e-3  # a position coordinate: no wrapping
    assert pose_error(m, y, x) == pytest.approx(1e-3)


def test_all_solutions_method_returns_the_solution_nearest_the_start():
    m = Stewart36()
    truth = sample_reachable(m, 20, np.random.default_rng(3), bounds=_stewart36_box(m))
    q = m.ik(truth)
    near = solve_fk(m, q, x0=truth, method="all-solutions")
    assert np.all(near.success) and np.max(pose_error(m, near.x, truth)) < 1e-9
    # from the mirror image (below the base): the nearest solution *above* the base, the assembly asked for
    far = solve_fk(m, q, x0=m.mirror(truth), method="all-solutions")
    assert np.all(far.success) and np.all(far.x[:, 5] > 0)
    sols = m.fk_all(q)
    above = np.where(np.nan_to_num(sols[..., 5]) > 0, 0.0, np.inf)
    lo, hi = m.pose_bounds()
    dist = (
        np.sqrt(np.sum((m.pose_difference(sols, m.mirror(truth)[:, None]) / (hi - lo)) ** 2, -1))
        + above
    )
    nearest = sols[np.arange(len(q)), np.nanargmin(dist, -1)]
    assert np.max(pose_error(m, far.x, nearest)) < 1e-9
    with pytest.raises(ValueError, match="no all-solutions"):
        solve_fk(P3P4S(), P3P4S().ik(P3P4S().home()), method="all-solutions")


# ------------------------------------------------------------------------------ scenarios
def test_scenarios_are_seeded_and_have_exact_references():
    m = UPS2()
    a = make_scenario(m, "noisy", 30, np.random.default_rng(5), joint_noise=1e-4)
    b = make_scenario(m, "noisy", 30, np.random.default_rng(5), joint_noise=1e-4)
    for f in ("joints", "start", "reference", "cond"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
    # the reference solves the noisy joints exactly (and they differ from the exact IK)
    assert np.max(np.abs(m.residual(a.reference, a.joints))) < 1e-12
    assert np.max(np.abs(m.ik(a.reference) - a.joints)) < 1e-12
    nominal = make_scenario(m, "nominal", 30, np.random.default_rng(6))
    assert np.max(np.abs(m.ik(nominal.reference) - nominal.joints)) < 1e-15
    singular = make_scenario(m, "near-singular", 30, np.random.default_rng(6), pool_factor=20)
    assert np.min(singular.cond) > np.median(nominal.cond)
    cold = make_scenario(m, "cold", 10, np.random.default_rng(7))
    np.testing.assert_array_equal(cold.start, np.broadcast_to(m.home(), cold.start.shape))
    with pytest.raises(ValueError, match="unknown scenario 'warm'"):
        make_scenario(m, "warm", 3, np.random.default_rng(0))


def _small_atlas() -> pd.DataFrame:
    m = P3P4S()
    solvers = (
        AtlasSolver("Newton", "newton"),
        AtlasSolver("PSO", "pso", {"swarm": 10}, maxiter=20, seed=3, max_rows=4, single_calls=2),
        AtlasSolver("closed form", "closed-form"),
        AtlasSolver("scipy", "scipy-root", batched=False),
    )
    case = AtlasCase("3p4s", m, m.pose_bounds(), solvers)
    return run_atlas(
        [case],
        lambda s: np.random.default_rng(zlib.crc32(s.encode())),
        n=12,
        n_single=2,
        n_batch=50,
        repeats=1,
        pool_factor=3,
    )


def test_atlas_reproduces_from_seed_and_reports_ratios():
    a, b = _small_atlas(), _small_atlas()
    cols = [c for c in a.columns if not is_timing_column(c)]
    pd.testing.assert_frame_equal(a[cols], b[cols])
    assert set(a["scenario"]) == {"nominal", "cold", "noisy", "near-singular"}
    nominal = a[a["scenario"] == "nominal"].set_index("solver")
    assert nominal.loc["scipy", "speedup_per_solve"] == pytest.approx(1.0)
    assert (
        nominal.loc["Newton", "success_rate"] == 1.0
        and nominal.loc["closed form", "success_rate"] == 1.0
    )
    assert nominal.loc["PSO", "n"] == 4  # row cap
    assert (
        np.isfinite(nominal["median_latency_us"]).all()
        and np.isfinite(nominal["throughput_per_s"]).all()
    )
    assert a[a["scenario"] != "nominal"]["median_latency_us"].isna().all()


# ------------------------------------------------------------------------------ committed outputs
def test_committed_atlas_figure_is_what_the_committed_table_draws(tmp_path):
    df = pd.read_csv(ROOT / "figures" / "extra_solver_atlas.csv")
    path = extras.atlas_figure(df, tmp_path / "extra_solver_atlas.png")
    assert (
        compare_images(str(ROOT / "figures" / "extra_solver_atlas.png"), str(path), tol=2.0) is None
    )


def test_committed_atlas_covers_every_solver_and_mechanism():
    df = pd.read_csv(ROOT / "figures" / "extra_solver_atlas.csv")
    assert set(df["mechanism"]) == set(mechanisms.REGISTRY)  # every registered mechanism
    for mech, g in df.groupby("mechanism"):
        methods = set(g["method"])
        assert {"newton", "broyden", "bfgs", "lm", "pso", "scipy-root"} <= methods, mech
        assert len(set(g[g["method"] == "pso"]["solver"])) == 2, mech  # standard and chaotic
    assert "hybrid" in set(df[df["mechanism"] == "3p4s"]["method"])
    assert {"closed-form", "all-solutions"} & set(df[df["mechanism"] == "2ups"]["method"])
    # Newton from near starts: every 3-P(4S) input (one assembly near the workspace), nearly every 2-UPS one
    nom = df[(df["scenario"] == "nominal") & (df["method"] == "newton")].set_index("mechanism")
    assert nom.loc["3p4s", "success_rate"] == 1.0 and nom.loc["2ups", "success_rate"] >= 0.99
    # the closed form is exact wherever it applies; the cube's home is singular for its 6-leg drive mode
    closed = df[df["method"] == "closed-form"]
    assert (closed["success_rate"] == 1.0).all() and len(closed) == 4
    assert df[df["mechanism"] == "stewart12"]["home_cond"].iloc[0] > 1e12


def test_results_page_quotes_the_generated_benchmark_block():
    readme = (ROOT / "docs" / "results.md").read_text()
    bench = (ROOT / "figures" / "benchmarks.md").read_text()
    assert extras.readme_block(readme) == extras.readme_block(bench)
    res = subprocess.run(
        [sys.executable, "-m", "parakin.cli", "readme", "--check"], capture_output=True, text=True
    )
    assert res.returncode == 0, res.stdout + res.stderr


def test_sync_readme_replaces_only_the_block(tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text(f"intro\n{extras.BEGIN}\nold\n{extras.END}\noutro\n")
    bench = tmp_path / "benchmarks.md"
    bench.write_text(f"# B\n{extras.BEGIN}\n| new |\n{extras.END}\n")
    extras.sync_readme(readme, bench)
    assert readme.read_text() == f"intro\n{extras.BEGIN}\n| new |\n{extras.END}\noutro\n"
    with pytest.raises(ValueError, match="no <!-- benchmarks:begin"):
        extras.readme_block("nothing here")


def test_bench_cli_quick_json(tmp_path):
    """``parakin bench NAME --quick --json``: the benchmark's rows as JSON records, its files in
    ``--outdir``. (The atlas itself runs in the quick pipeline, tests/test_pipeline.py: every
    registered mechanism in it.)"""
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "parakin.cli",
            "bench",
            "fk-3p4s",
            "--quick",
            "--json",
            "--outdir",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert res.returncode == 0, res.stderr[-2000:]
    rows = json.loads(res.stdout)["fk-3p4s"]
    assert {"solver", "method", "success_rate"} <= set(rows[0])
    assert any(r["method"] == "scipy-root" for r in rows)  # the baseline of every ratio
    assert (tmp_path / "zhao2017_3p4s" / "fk_benchmark.csv").exists()
    bad = subprocess.run(
        [sys.executable, "-m", "parakin.cli", "bench", "nonsense"], capture_output=True, text=True
    )
    assert bad.returncode == 2 and "unknown benchmark 'nonsense'" in bad.stderr


def test_report_section_is_computed_from_the_atlas_table(tmp_path):
    """extras.summary reads every number from the CSV: change the table, the text follows."""
    df = pd.read_csv(ROOT / "figures" / "extra_solver_atlas.csv")
    text = extras.summary(ROOT / "figures")
    newton = df[
        (df["scenario"] == "nominal") & (df["method"] == "newton") & (df["mechanism"] == "3p4s")
    ].iloc[0]
    assert f"3p4s {newton['throughput_per_s']:.3g} solves/s" in text
    df.loc[(df["method"] == "newton") & (df["mechanism"] == "3p4s"), "throughput_per_s"] = 12345.0
    df.to_csv(tmp_path / "extra_solver_atlas.csv", index=False)
    assert "3p4s 1.23e+04 solves/s" in extras.summary(tmp_path)
    assert extras.summary(tmp_path / "missing") == ""
    assert extras.TITLE in (ROOT / "figures" / "REPORT.md").read_text()


def test_recommendation_prefers_the_fastest_of_the_most_reliable():
    rows = []
    for solver, success, speed in [
        ("slow exact", 1.0, 10.0),
        ("fast almost", 0.997, 1000.0),
        ("fastest bad", 0.9, 1e6),
    ]:
        for scenario in ("nominal", "cold"):
            rows.append(
                {
                    "mechanism": "m",
                    "solver": solver,
                    "scenario": scenario,
                    "success_rate": success
                    if scenario == "nominal"
                    else 1.0 - (solver == "slow exact") * 0.5,
                    "throughput_per_s": speed,
                }
            )
    rec = extras.recommend(pd.DataFrame(rows)).set_index("mechanism")
    assert rec.loc["m", "nominal"].startswith(
        "fast almost"
    )  # within 0.5 points of the best, faster
    assert rec.loc["m", "cold"].startswith("fastest bad")  # here it is (one of) the most reliable
