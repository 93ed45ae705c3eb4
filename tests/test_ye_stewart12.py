"""Ye et al. reproduction: reference transcription, every artefact on the quick config, claims,
and the notebook."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from parakin.claims import resolve
from parakin.config import DEFAULT_CONFIG, QUICK_CONFIG, load_config
from parakin.papers import ye_stewart12 as Y
from parakin.report import claims_table, load_reference

ROOT = Path(__file__).resolve().parents[1]


def quick_config() -> dict:
    return load_config([DEFAULT_CONFIG, QUICK_CONFIG])


def test_reference_transcription():
    ref = load_reference(Y.KEY)
    assert (ref["paper"] == Y.KEY).all() and not ref.duplicated(["artefact", "quantity"]).any()
    t5 = ref[ref["artefact"] == "table5"].set_index("quantity")["value"]
    assert [t5[f"d{d}.nr_steps"] for d in range(20, 26)] == ["5", "5", "5", "5", "6", "6"]
    assert [t5[f"d{d}.broyden_time"] for d in range(20, 26)] == [
        "156.3",
        "156.3",
        "156.3",
        "156.3",
        "171.9",
        "187.5",
    ]
    # the printed means are the means of the printed rows (docs/ye_stewart12.md#s3)
    nr_t = np.mean([float(t5[f"d{d}.nr_time"]) for d in range(20, 26)])
    assert f"{nr_t:.1f}" == t5["mean.nr_time"]
    t6 = ref[ref["artefact"] == "table6"].set_index("quantity")["value"]
    assert t6["R3.nr"] == "0.60" and t6["R5.broyden"] == "0" and t6["composite.broyden"] == "1.76"
    assert np.mean([float(t6[f"R{r}.nr"]) for r in range(6)]) == pytest.approx(2.23, abs=0.005)


@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    out = tmp_path_factory.mktemp("ye_stewart12")
    cfg = quick_config()
    for fn in Y.ARTEFACTS.values():
        for p in fn(cfg, out):
            assert Path(p).exists()
    return out


def test_table2_and_table5_reproduced(outputs):
    t2 = pd.read_csv(outputs / "table2.csv").set_index("feature")
    assert t2.loc["highest_terms", "before"] == 45 and t2.loc["highest_terms", "after"] == 9
    t5 = pd.read_csv(outputs / "table5.csv")
    assert t5["nr_steps"].iloc[:6].tolist() == [5, 5, 5, 5, 6, 6]
    assert t5["broyden_steps"].iloc[:6].tolist() == [10, 11, 11, 11, 11, 11]


def test_claims_and_summary(outputs):
    ref = load_reference(Y.KEY)
    claims = [resolve(c, ref) for c in Y.claims(outputs, ref)]  # judged as the report judges them
    table = claims_table(claims).set_index("quantity")
    for q in (
        "equations.before",
        "highest_terms.after",
        "fk.max_position_error",
        "composite.initial",
    ):
        assert table.loc[q, "verdict"] == "reproduced", q
    # Table 5's counts rest on the reading of lambda and R = 0's passive legs: never "reproduced"
    for q in ("d20.nr_steps", "d25.nr_steps", "mean.nr_steps"):
        assert table.loc[q, "verdict"] == "consistent after fitting or assuming", q
    assert table.loc["accuracy_factor", "verdict"] == "bound satisfied"  # against a round-off floor
    # C7: the sentence's reading ('first within'), with the assumed 0.01 mm; both readings shown
    assert "first within" in table.loc["broyden.match_step", "variant"]
    readings = pd.read_csv(outputs / "fig08_match_steps.csv").set_index("reading")
    assert readings.loc["first within", "paper_supports"] and set(readings.index) == {
        "first within",
        "stays within",
    }
    assert (readings["broyden"] >= readings.loc["first within", "broyden"]).all()
    # C6 (issue 45): ours is our own measured ratio, and a ratio of clock readings of the paper's
    # machine is not comparable with it; the paper checked against its own Table 5 reproduces
    # nothing, so 164.1 / 210.9 = 77.8 % is only named in the reason
    t5 = pd.read_csv(outputs / "table5.csv").iloc[-1]
    measured = 100 * t5["broyden_time_ms"] / t5["nr_time_ms"]
    assert float(table.loc["time_fraction", "ours"]) == pytest.approx(measured, rel=1e-5)
    assert table.loc["time_fraction", "verdict"] == "not comparable"
    assert "77.8 %" in table.loc["time_fraction", "reason"]
    # what rests on an assumed P or on the assumed passive sets is never more than consistent
    for q in ("best_R.realtime_robust", "odd_even_ratio.nr", "odd_even_ratio.broyden"):
        assert "P = (max - min)/mean" in table.loc[q, "reason"], q
        assert table.loc[q, "verdict"] not in ("reproduced", "bound satisfied"), q
    # a count compared exactly: any N-R drop makes it differ and is named (at the full grid one,
    # R4 near its d_max; the quick grid steps over it)
    drops = float(table.loc["nr.step_drops", "ours"])
    assert table.loc["nr.step_drops", "verdict"].startswith("differs") == (drops > 0)
    assert table.loc["nr.step_drops", "reason"].count(" steps at d = ") == drops
    assert float(table.loc["accuracy_factor", "ours"]) > 1e3
    assert {"composite.nr", "composite_ratio", "width.R2.nr", "bump.R0.L"} <= set(table.index)
    # C9, C10, C11, C15 and the rest of C8 are rows (qualitative statements, encodings in the reasons)
    assert {
        "tol_sensitive.top3_in_R0R1R3",
        "tol_sensitive.nr_most_R",
        "least_initial_dependence_R",
        "broyden.most_initial_dependence_R",
        "nr.step_drops",
        "broyden.step_drops",
        "broyden.drops_near_dmax",
        "broyden.trend_spearman",
        "dmax_vs_n.spearman",
        "dmax_vs_L.spearman",
        "odd_even_ratio.nr",
        "odd_even_ratio.broyden",
    } <= set(table.index)
    # C10: Broyden's steps rise with d, over the assumed passive sets of each drive mode
    trend = next(c for c in claims if c.quantity == "broyden.trend_spearman")
    assert trend.outcome == "bound satisfied"
    assert trend.verdict == "consistent after fitting or assuming" and "passive" in trend.basis
    text = Y.summary(outputs, ref)
    assert "Table 5 steps" in text and "cond(dF/dX)" in text


def test_figures_exist_and_match_their_csv(outputs):
    for png in (
        "fig09_drive_modes.png",
        "fig01_mechanism.png",
        "fig02_topology.png",
        "fig06_prototype.png",
        "fig08_convergence.png",
        "fig10_steps_tol1e-6.png",
        "fig11_steps_tol1e-9.png",
        "fig12_dmax_structures.png",
        "extra_basin.png",
    ):
        assert (outputs / png).stat().st_size > 10_000, png
    f12 = pd.read_csv(outputs / "fig12_dmax_structures.csv")
    assert len(f12) == 9 * 6 * 3  # N-R, the paper's inverse Broyden, the direct Broyden
    assert set(f12["method"]) == {"nr", "broyden", "broyden_direct"}
    nominal = f12[(f12["n_mm"] == 20) & (f12["L_mm"] == 20)]
    assert (nominal["d_max_pct"] > 0).all()
    f8 = pd.read_csv(outputs / "fig08_convergence.csv")
    assert f8["nr_composite_mm"].iloc[0] == pytest.approx(
        32.841346, abs=1e-6
    )  # 1.3 x mean passive length
    f9 = pd.read_csv(outputs / "fig09_drive_modes.csv")
    assert (
        len(f9) == 6 * 12
        and (f9.groupby("R")["active"].sum() == f9.groupby("R")["active_legs"].first()).all()
    )
    assert f9.groupby("R")["active"].sum().to_dict() == {r: 6 + r for r in range(6)}
    home = f9[f9["R"] == 0].set_index("leg")["home_direction"]
    assert [home[k] for k in range(1, 7)] == [
        "+y",
        "-z",
        "+y",
        "-x",
        "-z",
        "+x",
    ]  # docs/ye_stewart12.md#s1.2
    cond = pd.read_csv(outputs / "extra_conditioning.csv").set_index("R")
    assert cond.loc[0, "cond_dF_dX"] == pytest.approx(179.37, abs=0.01)  # docs/ye_stewart12.md#s2.3


def test_the_code_declares_no_tolerance(outputs):
    """One source of tolerances: the reference CSV. Every claim the code makes carries the
    default ``tol``/``kind`` (what resolve replaces), so no tolerance is typed in code."""
    ref = load_reference(Y.KEY)
    claims = Y.claims(outputs, ref)
    assert claims and all(c.tol is None and c.kind == "value" for c in claims)


def test_table6_and_widths_judge_the_papers_inverse_update(outputs):
    """Table 6's Broyden column, the widths and the best-R rules are judged on the inverse update
    (the paper's eqs 31-32); the direct update is shown beside it in the reasons only."""
    ref = load_reference(Y.KEY)
    table = claims_table([resolve(c, ref) for c in Y.claims(outputs, ref)]).set_index("quantity")
    t6 = pd.read_csv(outputs / "table6.csv").set_index("mode")
    assert {"broyden_P", "broyden_direct_P", "broyden_direct_width_pct"} <= set(t6.columns)
    assert float(table.loc["R5.broyden", "ours"]) == pytest.approx(
        t6.loc["I", "broyden_P"], rel=1e-5
    )
    assert "direct update (beyond the paper)" in table.loc["R5.broyden", "reason"]
    assert "direct Broyden (beyond the paper)" in table.loc["best_R.realtime_robust", "reason"]
    assert (
        len(table.loc[["R5.broyden"]]) == 1
    )  # one claim per row: the variant cannot pick the better
    # R = 0: one algorithm (the Sherman-Morrison twins), the same P to rounding
    assert t6.loc["VI", "broyden_P"] == pytest.approx(t6.loc["VI", "broyden_direct_P"], rel=1e-9)


def test_inverse_and_direct_broyden_on_the_drive_modes():
    """R = 0: the paper's inverse update and the direct one take the same iterates to rounding;
    R > 0: different algorithms. d_max at the paper's structure (n = 15, L = 25, full d grid):
    the inverse update gives 100 % (R5) and 235 % (R4), the direct one 2000 % and 355 %
    (docs/ye_stewart12.md#s4.5)."""
    cfg = load_config([DEFAULT_CONFIG])
    s = Y.common.setup(cfg)
    inv, direct = Y.common.METHODS_USED["broyden"], Y.common.METHODS_USED["broyden_direct"]
    d = np.array([0.2, 0.5])
    runs = {
        (r, key): Y.common.run_mode(s.mech, s.sets[r], s.pose, d, m, 8, options=o)["traj"]
        for r in (0, 5)
        for key, (m, o) in (("inv", inv), ("dir", direct))
    }
    assert np.allclose(runs[0, "inv"][:6], runs[0, "dir"][:6], rtol=0, atol=1e-12)
    assert np.max(np.abs(runs[5, "inv"][1:4] - runs[5, "dir"][1:4])) > 1e-6
    dpct = Y.modes.d_grid(cfg)
    dmax = {
        (r, key): Y.modes.scan_case(s.mech, s.sets[r], s.pose, dpct, m, s.maxiter, (s.tol_mm,), o)[
            s.tol_mm
        ][1]
        for r in (5, 4)
        for key, (m, o) in (("inv", inv), ("dir", direct))
    }
    assert dmax == {(5, "inv"): 100.0, (5, "dir"): 2000.0, (4, "inv"): 235.0, (4, "dir"): 355.0}


# the notebook itself is executed by nbmake (pytest --nbmake over notebooks/)
