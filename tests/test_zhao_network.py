"""Zhao 2017 §1.1: the BP network trained to convergence per sampling region (the cause of the
network-accuracy gap), Fig. 4 drawn from the model, and one source of tolerances for the claims."""

from __future__ import annotations

import ast
import copy
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from parakin.claims import (
    BOUND,
    DIFFERS_SHOWN,
    DIFFERS_UNKNOWN,
    REPRODUCED,
    decide,
    load_reference,
    resolve,
)
from parakin.errors import ConfigError
from parakin.mechanisms import P3P4S
from parakin.nn import train_lm
from parakin.nn.bp import plateau_epoch
from parakin.papers.zhao2017_3p4s import fk, kinematics

ZHAO = Path(fk.__file__).parent


# ------------------------------------------------------------------------ the convergence rule
def _data(n: int = 300):
    mech = P3P4S.zhao2017()
    lo, hi = mech.pose_bounds()
    poses = lo + (hi - lo) * np.random.default_rng(3).random((n, 3))
    poses = poses[mech.is_reachable(poses)]
    return mech.ik(poses), poses


def test_plateau_rule_stops_where_the_best_validation_error_stalls():
    q, p = _data()
    window, rel = 5, 0.01
    _, log, s = train_lm(q, p, seed=1, max_epochs=400, max_fail=10**6, plateau_window=window)
    assert s["stop_reason"] == "plateau" and s["epochs"] < 400
    assert (s["plateau_window"], s["plateau_improvement"]) == (window, rel)
    best = np.minimum.accumulate(log["val_rms_m"].to_numpy())
    e = s["epochs"]
    assert best[e] > (1 - rel) * best[e - window]  # the rule holds where it stopped ...
    earlier = [k for k in range(window, e) if best[k] > (1 - rel) * best[k - window]]
    assert earlier == []  # ... and nowhere before
    assert plateau_epoch(log["val_rms_m"], window, rel) == e  # the same rule on a finished log
    assert plateau_epoch([1.0, 0.5, 0.25, 0.125], 2) is None


def test_without_the_plateau_rule_training_and_its_meta_are_unchanged():
    q, p = _data()
    net_a, log_a, s_a = train_lm(q, p, seed=1, max_epochs=20)
    net_b, log_b, s_b = train_lm(q, p, seed=1, max_epochs=20, plateau_window=10**6)
    assert "plateau_window" not in s_a and "plateau_window" not in net_a.meta
    np.testing.assert_array_equal(net_a.flat_weights(), net_b.flat_weights())
    assert s_a["stop_reason"] == s_b["stop_reason"] == "max_epochs"
    assert 0 < s_a["test_mean_abs_axis_m"] < s_a["test_rms_m"]  # E_3 below the 3-D RMS
    with pytest.raises(ValueError, match="plateau_window"):
        train_lm(q, p, plateau_window=0)
    with pytest.raises(ValueError, match="plateau_improvement"):
        train_lm(q, p, plateau_window=5, plateau_improvement=1.5)


# ------------------------------------------------------------------------ the artefact
def _tiny(quick_config: dict, tmp: Path) -> dict:
    config = copy.deepcopy(quick_config)
    config["generated_dir"] = str(tmp / "generated")
    config["zhao2017_3p4s"]["network_convergence"].update(
        samples=120, restarts=2, window=4, max_epochs=40
    )
    return config


def test_network_convergence_writes_a_row_per_region_and_draws_from_its_csv(quick_config, tmp_path):
    config = _tiny(quick_config, tmp_path)
    written = {Path(p).name for p in fk.network_convergence(config, tmp_path)}
    assert written == {
        "extra_bp_convergence.csv",
        "extra_bp_convergence.md",
        "extra_bp_convergence_curves.csv",
        "extra_bp_convergence.png",
    }
    tab = pd.read_csv(tmp_path / "extra_bp_convergence.csv")
    boxes = [b["name"] for b in config["zhao2017_3p4s"]["fk"]["accuracy_boxes"]]
    assert list(tab["region"]) == [fk.OURS, *boxes]
    assert (tab["hidden"] == 10).all() and (tab["weights"] == 73).all()  # the paper's size
    assert (tab["restarts"] == 2).all() and (tab["converged_runs"] <= 2).all()
    assert (tab["test_rms_min_m"] <= tab["test_rms_median_m"]).all()
    assert (tab["test_e3_median_m"] < tab["test_rms_median_m"]).all()
    paper = config["zhao2017_3p4s"]["network_convergence"]["paper_region"]
    assert tab.set_index("region").loc[paper, "role"] == "the paper's working poses"
    curves = pd.read_csv(tmp_path / "extra_bp_convergence_curves.csv")
    assert curves.groupby(["region", "restart"])["best"].sum().eq(1).all()
    assert (curves.groupby(["region", "restart"])["epoch"].max() <= 40).all()
    # the declared tolerance compares only columns the table has
    assert set(fk.CONVERGENCE.columns) <= set(tab.columns)


def test_paper_region_must_name_an_accuracy_box(quick_config):
    bad = copy.deepcopy(quick_config)
    bad["zhao2017_3p4s"]["network_convergence"]["paper_region"] = "nowhere"
    with pytest.raises(ConfigError, match="paper_region"):
        fk.convergence_settings(bad)
    del bad["zhao2017_3p4s"]["network_convergence"]
    with pytest.raises(ConfigError, match="network_convergence"):
        fk.convergence_settings(bad)


# ------------------------------------------------------------------------ the verdict's rule
ACC = pd.DataFrame(
    {
        "box": ["workspace (pipeline's network)", "table1_box"],
        "samples": 10000,
        "stop_reason": "max_epochs",
        "best_epoch": 1000,
        "epochs": 1000,
        "test_rms_m": [8e-4, 2e-4],
        "test_e3_m": [3e-4, 8e-5],
    }
)


def _conv(converged=10):
    return pd.DataFrame(
        {
            "region": [fk.OURS, "table1_box", "small_box"],
            "role": ["ours (the pipeline's network)", "the paper's working poses", "a smaller box"],
            "restarts": 10,
            "window": 100,
            "min_improvement": 0.01,
            "converged_runs": [converged, 10, 10],
            "test_e3_median_m": [5e-4, 2e-4, 5e-6],
        }
    )


def _curves(ours, paper):
    """The returned network of each of 10 restarts per region, test errors spread over [lo, hi]."""
    rows = []
    for region, (lo, hi) in ((fk.OURS, ours), ("table1_box", paper), ("small_box", (1e-5, 2e-5))):
        rows += [
            {"region": region, "restart": k, "best": True, "test_rms_m": v}
            for k, v in enumerate(np.geomspace(lo, hi, 10))
        ]
    return pd.DataFrame(rows)


#: a training log whose validation error falls 0.1 % per epoch until epoch 400, then 0.001 %: the
#: rule (1 % over 100 epochs) first fires at epoch 491, where 0.999**9 * 0.99999**91 > 0.99
LOG = pd.DataFrame(
    {"val_rms_m": 1e-3 * np.r_[0.999 ** np.arange(401), 0.999**400 * 0.99999 ** np.arange(1, 601)]}
)


@pytest.mark.parametrize(
    "ours, paper, verdict",
    [
        ((2e-4, 6e-4), (1e-4, 3e-4), REPRODUCED),  # a restart on our box reaches the level
        # only on the assumed region: our box, the declared reading, differs; the assumed region
        # shows the cause (issue 45: it was "consistent", the strongest of the two readings)
        ((8e-4, 2e-3), (2e-4, 6e-4), DIFFERS_SHOWN),
        ((8e-4, 2e-3), (4e-4, 9e-4), DIFFERS_UNKNOWN),  # neither: what was ruled out is said
    ],
)
def test_network_accuracy_is_judged_on_the_range_of_the_restarts(ours, paper, verdict):
    ref = load_reference("zhao2017_3p4s")
    claims = [
        resolve(c, ref)
        for c in fk.network_accuracy_claims(ACC, LOG, _conv(), _curves(ours, paper), ref)
    ]
    assert len(claims) == 2 and all("median of 10 trainings" in c.variant for c in claims)
    best, how = decide(claims)  # as the report decides: the declared reading, our box
    assert how == "declared reading" and "our workspace box" in best.variant
    assert best.verdict == verdict
    if verdict == DIFFERS_UNKNOWN:
        assert (
            "Ruled out: the epoch limit" in best.reason and "converged at epoch 491" in best.reason
        )
        assert "Not shown: the paper's working poses" in best.reason


# ------------------------------------------------------------------------ Fig. 4
def test_fig04_is_the_model_s_limb_and_closes_the_loop_of_eq6(tmp_path):
    mech = P3P4S.zhao2017()
    paths = kinematics.fig04({}, tmp_path)
    frame = pd.read_csv(tmp_path / "fig04_equivalent_limb.csv")
    assert {Path(p).name for p in paths} == {
        "fig04_equivalent_limb.png",
        "fig04_equivalent_limb.csv",
    }
    side = frame[frame["panel"] == "side"].set_index("name")

    def vec(name):
        r = side.loc[name]
        return np.array([r.x1 - r.x0, r.y1 - r.y0, r.z1 - r.z0])

    # eq. (6): r = r_b e_1 + q_1 m_1 + l n_1 + r_a cos(theta) s_1
    loop = vec("r_b e_1") + vec("q_1 m_1") + vec("l n_1") + vec("r_a cos(theta) s_1")
    np.testing.assert_allclose(loop, vec("r"), atol=1e-12)
    np.testing.assert_allclose(vec("r"), mech.home(), atol=1e-12)
    assert np.linalg.norm(vec("l n_1")) == pytest.approx(mech.L, abs=1e-12)
    assert np.linalg.norm(vec("q_1 m_1")) == pytest.approx(mech.ik(mech.home())[0], abs=1e-12)
    assert np.linalg.norm(vec("r_b e_1")) == pytest.approx(mech.r_b, abs=1e-12)
    assert np.linalg.norm(vec("r_a cos(theta) s_1")) == pytest.approx(mech.a, abs=1e-12)
    for u in ("e_1", "m_1", "n_1", "s_1"):
        assert np.linalg.norm(vec(u)) == pytest.approx(kinematics.UNIT_ARROW, abs=1e-12)
    # the panel's 2-D coordinates are a rigid projection: lengths kept (the loop lies in the plane)
    for name in ("r_b e_1", "q_1 m_1", "l n_1", "r"):
        r = side.loc[name]
        assert np.hypot(r.h1 - r.h0, r.v1 - r.v0) == pytest.approx(np.linalg.norm(vec(name)))
    # the parallelogram: two side rods of length l parallel to the equivalent rod, edges of length d
    par = frame[frame["panel"] == "parallelogram"]
    rods = par[par["kind"] == "passive"]
    assert len(rods) == 2
    for r in rods.itertuples():
        assert (r.h1 - r.h0, r.v1 - r.v0) == pytest.approx((0.0, mech.L), abs=1e-12)
    for kind in ("slider edge", "platform edge"):
        r = par[par["kind"] == kind].iloc[0]
        assert abs(r.h1 - r.h0) == pytest.approx(mech.d, abs=1e-12)
    # redrawn from the CSV alone
    kinematics.draw_fig04(frame, tmp_path / "again.png")
    assert (tmp_path / "again.png").stat().st_size > 10_000


# ------------------------------------------------------------------------ one source of tolerances
def test_zhao_claims_take_their_tolerance_from_the_reference_csv_only():
    """No Claim in the Zhao code sets tol, kind or margin: data/reference declares them (the report
    applies them through parakin.claims.resolve)."""
    found = []
    for path in sorted(ZHAO.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "Claim":
                bad = [k.arg for k in node.keywords if k.arg in ("tol", "kind", "margin")]
                if bad:
                    found.append(f"{path.name}:{node.lineno} {bad}")
    assert found == []


# ------------------------------------------- issue 45: which quasi-Newton, and one verdict per number
from parakin.claims import NOT_COMPARABLE  # noqa: E402
from parakin.papers.zhao2017_3p4s import optimization  # noqa: E402
from parakin.papers.zhao2017_3p4s.bfgs_variants import (  # noqa: E402
    bfgs_variant,
    numerical_gradient,
)
from parakin.solvers import solve_fk  # noqa: E402
from parakin.solvers.result import Evaluator  # noqa: E402


@pytest.fixture(scope="module")
def box_poses():
    mech = P3P4S.zhao2017()
    lo, hi = mech.pose_bounds()
    x = np.random.default_rng(45).uniform(lo, hi, size=(200, 3))
    return mech, x[np.isfinite(mech.ik(x)).all(axis=-1)][:100]


def test_bfgs_variants_differ_from_the_library_only_in_start_and_gradient(box_poses):
    """The Gauss-Newton start with the analytic gradient is the library's BFGS, iterate for
    iterate (so the variants beside it differ only in what they are said to differ in); the
    identity start's first step is steepest descent; the central-difference gradient equals the
    analytic one next to the solution to a few per cent, the forward one does not come close."""
    mech, x = box_poses
    q, home = mech.ik(x), mech.home()
    lib = solve_fk(mech, q, x0=home, method="bfgs", tol=1e-10, maxiter=100)
    ours = bfgs_variant(
        mech, q, home, start="gauss-newton", gradient="analytic", tol=1e-10, maxiter=100
    )
    assert np.array_equal(ours.nit, lib.nit) and np.allclose(ours.x, lib.x, atol=1e-12, rtol=0)
    one = bfgs_variant(mech, q, home, start="identity", gradient="analytic", tol=0.0, maxiter=1)
    r = mech.residual(np.broadcast_to(home, x.shape), q)
    g = np.einsum("nji,nj->ni", mech.jacobian_pose(np.broadcast_to(home, x.shape), q), r)
    step = one.x - home  # alpha * (-g): along the gradient, downhill
    cos = (
        -np.einsum("ni,ni->n", step, g) / np.linalg.norm(step, axis=-1) / np.linalg.norm(g, axis=-1)
    )
    assert np.allclose(cos, 1.0, atol=1e-12)
    ev, rows = Evaluator(mech, q), np.arange(len(q))
    near = x + 1e-9  # where the accuracy matters: next to the solution
    rn = ev.residual(near, rows)
    exact = np.einsum("nji,nj->ni", ev.jacobian(near, rows), rn)
    central = numerical_gradient(ev, near, rows, rn, "central")
    forward = numerical_gradient(ev, near, rows, rn, "forward")
    # 1e-9 m from the pose the gradient is ~4e-9: the central differences' O(h^2) error (a fixed
    # ~1.4e-10 here) is a few % of it, the forward ones' O(h) error (~2e-8) several times it
    size = np.max(np.abs(exact))
    assert np.max(np.abs(central - exact)) < 0.1 * size
    assert np.max(np.abs(forward - exact)) > 3 * size


def _qn_table(box_rate: float) -> pd.DataFrame:
    """extra_qn_failures' layout: every solver on every region, Table 1's box at ``box_rate``."""
    rows = []
    regions = {"Table 1's box": box_rate, "benchmark box": 0.0, "whole workspace": 0.2}
    regions["z -0.05 to 0.15 m"] = 0.3
    for region, rate in regions.items():
        for solver in (*fk.QN_READINGS, *fk.BFGS_VARIANTS, "Newton-Raphson from home"):
            k = int(round(rate * 10000))
            rows.append(
                {
                    "region": region,
                    "solver": solver,
                    "poses": 10000,
                    "failures": k,
                    "failure_rate": k / 10000,
                    "rate_ci_low": 0.0,
                    "rate_ci_high": 1.0,
                    "not_converged": k,
                    "another_assembly": 0,
                    "short_of_tol": 0,
                    "median_nit": 5.0,
                }
            )
    return pd.DataFrame(rows).drop_duplicates(["region", "solver"])


def test_quasi_newton_failures_are_judged_by_the_weakest_of_every_variant_and_region():
    """Conclusion (1): no variant or region is given by the paper, so none is declared and the
    weakest of the 4 quasi-Newton variants x 3 regions decides: 0 failures on Table 1's box
    (the library's BFGS first) differs with the cause named, however many fail elsewhere; only
    when every reading fails is the bound satisfied. The forward-difference BFGS (its failures are
    its accuracy floor) and the height bands are no readings."""
    ref = load_reference("zhao2017_3p4s")
    claims = [resolve(c, ref) for c in fk.failure_claims(_qn_table(0.0), ref)]
    assert len(claims) == len(fk.QN_READINGS) * len(fk.QN_REGIONS) == 12
    assert not any("forward" in c.variant or c.variant.endswith(" m") for c in claims)
    chosen, how = decide(claims)
    assert how == "weakest reading" and chosen.variant == f"{fk.BFGS_LIBRARY}, Table 1's box"
    assert chosen.verdict == DIFFERS_SHOWN and "depends on the region and on the variant" in (
        chosen.reason
    )
    assert any(c.verdict == "bound satisfied" for c in claims)  # shown, but not deciding
    every = [resolve(c, ref) for c in fk.failure_claims(_qn_table(0.01), ref)]
    every = [c for c in every if "benchmark box" not in c.variant]
    assert decide(every)[0].verdict == "bound satisfied"


def _speed_table() -> pd.DataFrame:
    return pd.DataFrame(
        {
            "computation": [
                "hybrid (network + Broyden)",
                "Broyden from home",
                fk.GUESS_THEN_BROYDEN,
                "network guess alone",
            ],
            "inputs": 300,
            "median_nit": [2.0, 5.0, 2.0, 0.0],
            "median_nfev": [3.0, 6.0, 3.0, 0.0],
            "median_time_us": [2100.0, 61.0, 74.0, 15.0],
        }
    ).set_index("computation")


def test_hybrid_time_ratio_is_judged_on_both_readings_the_hybrid_as_run_deciding():
    """The hybrid as run (0.029: its reachability check) and like for like (guess + Broyden,
    61 / 74 = 0.82: the guess costs about what it saves) are both readings, both shown by the
    artefact that takes the hybrid apart; of equal verdicts the first given, the hybrid as run,
    decides, and it would decide as well where like for like met the bound (a ratio near 1 whose
    side depends on the machine: the verdict must not)."""
    from parakin.report import report_rows

    ref = load_reference("zhao2017_3p4s")
    claims = [resolve(c, ref) for c in fk.hybrid_speed_claims(_speed_table(), ref)]
    time = [c for c in claims if c.quantity == "hybrid.time_ratio_vs_quasi_newton"]
    assert [round(c.ours, 3) for c in time] == [0.029, 0.824]
    assert [c.verdict for c in time] == [DIFFERS_SHOWN, DIFFERS_SHOWN]
    assert "save about 2 µs" in time[1].reason and "the guess costs 15 µs" in time[1].reason
    chosen, _ = decide(time)
    assert chosen is time[0] and "as run" in chosen.variant
    rows = report_rows("zhao2017_3p4s", ref, claims, Path("/nonexistent"))
    row = rows[rows["quantity"] == "hybrid.time_ratio_vs_quasi_newton"].iloc[0]
    assert row["verdict"] == DIFFERS_SHOWN and row["ours"] == "0.0290476"
    assert row["evidence"] == "zhao2017_3p4s/extra_hybrid_speed.md"
    assert "0.824324 → differs — cause shown" in row["readings"]
    # on a machine where like for like meets the bound, the verdict is the same
    faster = _speed_table()
    faster.loc[fk.GUESS_THEN_BROYDEN, "median_time_us"] = 55.0
    time = [
        resolve(c, ref)
        for c in fk.hybrid_speed_claims(faster, ref)
        if c.quantity == "hybrid.time_ratio_vs_quasi_newton"
    ]
    assert [c.verdict for c in time] == [DIFFERS_SHOWN, BOUND]
    assert decide(time)[0] is time[0]


def test_table3_d_is_not_comparable_and_the_corners_are_compared():
    """Table 3's d enters only through delta and is fixed by the paper's box: not comparable;
    r_a and r_b, pinned at the corners of either box, stay compared."""
    ref = load_reference("zhao2017_3p4s")
    g = np.random.default_rng(0)
    runs = pd.DataFrame(
        {
            "convergence_generation": g.integers(40, 90, 30),
            "f": g.uniform(0.01, 0.05, 30),
            "r_a_m": 0.15,
            "r_b_m": 0.8,
            "L_m": g.uniform(0.3, 0.44, 30),
            "d_m": g.uniform(0.08, 0.16, 30),
            "phi_deg": 45.0,
        }
    )
    claims = {c.quantity: resolve(c, ref) for c in optimization.ga_claims(runs, ref)}
    assert claims["after.d"].verdict == NOT_COMPARABLE
    assert "not identifiable" in claims["after.d"].reason
    assert claims["after.r_a"].verdict == claims["after.r_b"].verdict == DIFFERS_SHOWN


def test_the_zhao_page_quotes_no_time_of_ours():
    """Issue 45: times of ours move from run to run and machine to machine, so the page quotes the
    artefact (extra_hybrid_speed.md, table2.md) and types none (it typed 51 / 1503 µs after the
    record had moved to 61 / 2100 µs); the only times on it are the paper's."""
    import re

    text = (Path(__file__).resolve().parents[1] / "docs" / "zhao2017_3p4s.md").read_text()
    times = re.findall(r"(\d[\d.,\s–-]*)\s?(µs|ms)\b", text)
    assert {value.strip() for value, _ in times} <= {"20"}, times
