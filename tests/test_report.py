"""Verdicts of the report: rounding from the printed digits, bounds and orders of magnitude."""

import pandas as pd
import pytest

from parakin.report import Claim, half_ulp, judge, load_reference


@pytest.mark.parametrize(
    "printed, ulp",
    [("0.42", 0.005), ("0.592", 0.0005), ("3", 0.5), ("4.51e-8", 5e-11), ("0.5919999528", 5e-11)],
)
def test_half_ulp_from_printed_digits(printed, ulp):
    assert half_ulp(printed) == pytest.approx(ulp)


def test_value_verdicts():
    assert judge("0.42", 0.4249) == "reproduced within rounding"
    assert judge("0.42", 0.4251) == "differs"
    assert judge("0.42", 0.4251, tol=1e-3) == "differs"
    assert judge("0.42", 0.42005, tol=1e-4) == "reproduced"
    assert judge("0.42", float("nan")) == "differs"
    assert judge("0", 0.19) == "reproduced within rounding"  # a printed 0 read as rounded
    assert judge("0", 0.19, tol=0.0) == "differs"  # declared exact: no rounding reading


def test_bound_and_order_verdicts():
    assert judge("20", 0.4, kind="upper") == "bound satisfied"
    assert judge("20", 25.0, kind="upper") == "differs"
    assert judge("1e-4", 2.9e-4, kind="order") == "reproduced"
    assert judge("1e-4", 4e-4, kind="order") == "differs"
    with pytest.raises(ValueError, match="kind = 'exact'"):
        judge("1", 1.0, kind="exact")


def test_claim_carries_verdict_and_difference():
    c = Claim("p", "table1", "case1.l1", "0.42", 0.4316, "m")
    assert c.verdict == "differs — cause unknown" and c.diff == pytest.approx(0.0116)


def test_reference_csv_is_well_formed():
    ref = load_reference("zhao2017_3p4s")
    assert not ref.duplicated(["artefact", "quantity"]).any()
    assert (ref["paper"] == "zhao2017_3p4s").all()
    for value in ref["value"]:
        float(value)  # every value is a number as printed
    assert (
        len(ref[ref["artefact"] == "table1"]) == 30 and len(ref[ref["artefact"] == "table2"]) == 40
    )


# ------------------------------------------------------------------ issue 15: verdicts that cannot flatter
from pathlib import Path  # noqa: E402

from parakin.claims import (  # noqa: E402
    BOUND,
    CONSISTENT,
    DIFFERS_SHOWN,
    DIFFERS_UNKNOWN,
    INPUT,
    NOT_COMPARABLE,
    NOT_JUDGED,
    ROLES,
    VERDICTS,
    parse_tolerance,
    resolve,
    row_verdicts,
)
from parakin.papers import PAPERS  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def test_verdict_vocabulary():
    assert VERDICTS[:8] == (
        "reproduced",
        "reproduced within rounding",
        "bound satisfied",
        "consistent after fitting or assuming",
        "differs — cause shown",
        "differs — cause unknown",
        "not comparable",
        "input",
    )
    fit = Claim("p", "t", "q", "0.42", 0.4201, "m", basis="geometry fitted to these numbers")
    assert fit.verdict == CONSISTENT  # a fit never counts as reproduced
    assert Claim("p", "t", "q", "0.42", 0.5, "m", basis="fitted").verdict == DIFFERS_UNKNOWN
    assert Claim("p", "t", "q", "0.42", 0.5, "m", evidence="x.md").verdict == DIFFERS_SHOWN
    assert Claim("p", "t", "q", "20", 0.4, "ms", kind="upper").verdict == BOUND
    assert Claim("p", "t", "q", "20", 0.4, "ms", comparable=False).verdict == NOT_COMPARABLE


def test_tolerances_come_from_the_reference():
    assert parse_tolerance("", "0.42") == ("value", None, 1.0)
    assert parse_tolerance("rel:0.05", "20") == ("value", pytest.approx(1.0), 1.0)
    assert parse_tolerance("exact", "3") == ("value", 0.0, 1.0)
    assert parse_tolerance("upper:10", "20") == ("upper", None, 10.0)
    assert judge("20", 3.0, kind="upper", margin=10) == "differs"
    ref = pd.DataFrame(
        [
            {
                "paper": "p",
                "artefact": "t",
                "quantity": "q",
                "value": "0.42",
                "unit": "m",
                "note": "",
                "role": "result",
                "tolerance": "",
            },
            {
                "paper": "p",
                "artefact": "t",
                "quantity": "r",
                "value": "1",
                "unit": "1",
                "note": "",
                "role": "input",
                "tolerance": "",
            },
        ]
    )
    # a tolerance typed in code is replaced by the reference's (none here): the code cannot loosen it
    c = resolve(Claim("p", "t", "q", "0.42", 0.43, "m", tol=0.1), ref)
    assert c.tol is None and c.verdict == DIFFERS_UNKNOWN
    with pytest.raises(ValueError, match="the reference"):
        resolve(Claim("p", "t", "q", "0.5", 0.5, "m"), ref)  # a paper value typed in code
    rows = row_verdicts([c, resolve(Claim("p", "t", "r", "1", 1.0, "1"), ref)], ref)
    assert list(rows["verdict"]) == [DIFFERS_UNKNOWN, INPUT]


@pytest.mark.parametrize("key", list(PAPERS))
def test_every_reference_row_gets_one_verdict(key):
    from parakin.report import paper_claims, report_rows

    ref = load_reference(key)
    assert set(ref["role"]) <= set(ROLES)
    for value in ref["value"]:
        assert value.strip(), "a transcribed number is empty"
    ref_, claims = paper_claims(
        key, ROOT / "figures"
    )  # every claim's paper value is in data/reference
    rows = report_rows(key, ref_, claims, ROOT / "figures" / key)
    assert len(rows) == len(ref)  # the counts add up to the reference
    assert rows["verdict"].isin(VERDICTS).all()
    judged_later = {
        ("abstract", "chaotic_more_precise.p_value")
    }  # made by an artefact newer than the record
    missing = [
        (a, q)
        for a, q, v in zip(rows["artefact"], rows["quantity"], rows["verdict"])
        if v == NOT_JUDGED and (a, q) not in judged_later
    ]
    assert missing == []
    # a fit or an assumption never reads as reproduced
    for c in claims:
        if c.basis:
            assert c.verdict not in ("reproduced", "reproduced within rounding", "bound satisfied")


def test_report_csv_beside_report(tmp_path):
    from parakin.report import REPORT_COLUMNS, write_report

    out = write_report(ROOT / "figures", tmp_path / "REPORT.md")
    table = pd.read_csv(out.with_name("report.csv"), dtype=str, keep_default_na=False)
    assert list(table.columns) == REPORT_COLUMNS
    n = sum(len(load_reference(k)) for k in PAPERS)
    assert len(table) == n
    text = out.read_text()
    assert "consistent after fitting or assuming" in text and "## At a glance" in text


def test_results_page_status_and_glance_blocks_match_report():
    from parakin.report import readme_blocks_match

    report_csv = ROOT / "figures" / "report.csv"
    if not report_csv.exists():
        pytest.skip("figures/report.csv is written by the next recorded run")
    assert readme_blocks_match((ROOT / "docs" / "results.md").read_text(), report_csv)


def test_every_item_of_every_paper_is_drawn_or_says_why_not():
    """items.csv lists each paper's tables and figures; each is judged, drawn, or says why not."""
    from parakin.glance import item_table, load_items

    report_csv = ROOT / "figures" / "report.csv"
    if not report_csv.exists():
        pytest.skip("figures/report.csv is written by the next recorded run")
    report = pd.read_csv(report_csv, dtype=str, keep_default_na=False)
    items = load_items()
    table = item_table(report, ROOT / "figures", items)
    missing = table[table["status"] == "missing"]
    assert missing.empty, f"items no file draws: {missing[['paper', 'item']].values.tolist()}"
    assert (items.loc[items["coverage"] != "", "reason"] != "").all()
    # every table/figure label the report judges is an item of its paper
    known = set(zip(items["paper"], items["item"].str.replace(r"(\D)0+(\d)", r"\1\2", regex=True)))
    labels = report[report["artefact"].str.fullmatch(r"(fig|table)\d+")]
    judged = set(
        zip(labels["paper"], labels["artefact"].str.replace(r"(\D)0+(\d)", r"\1\2", regex=True))
    )
    assert judged <= known, sorted(judged - known)


def test_item_status_comes_from_verdicts():
    from parakin.glance import item_status

    assert item_status(pd.Series(["reproduced", "bound satisfied"])) == "reproduced"
    assert item_status(pd.Series(["reproduced", "differs — cause shown"])) == "partly reproduced"
    assert item_status(pd.Series(["consistent after fitting or assuming"])) == (
        "consistent after fitting or assuming"
    )
    assert (
        item_status(pd.Series(["consistent after fitting or assuming", "differs — cause unknown"]))
        == "differs"
    )
    assert item_status(pd.Series(["not comparable"])) == "not comparable"


def test_no_claim_carries_a_tolerance_typed_in_code():
    """The tolerance of every claim is the reference CSV's (``resolve``); code passes none."""
    import ast

    typed = []
    for path in sorted((ROOT / "src" / "parakin").rglob("*.py")):
        if path.name == "claims.py":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.Call):
                continue
            name = getattr(node.func, "id", getattr(node.func, "attr", ""))
            if name == "Claim":
                typed += [
                    f"{path.relative_to(ROOT)}:{kw.lineno} {kw.arg}="
                    for kw in node.keywords
                    if kw.arg in ("tol", "kind", "margin")
                ]
    assert not typed, typed


@pytest.mark.parametrize("key", list(PAPERS))
def test_no_verdict_rests_on_a_wall_clock_time(key):
    """Issue 28: a claim whose number is a time (ms, s, µs) is never judged; a speed claim is judged on
    iterations or on a ratio of two computations timed in the same run (unit 1)."""
    from parakin.report import paper_claims

    ref, claims = paper_claims(key, ROOT / "figures")
    times = ref[ref["unit"].isin(["ms", "s", "µs", "us"]) & (ref["role"] == "result")]
    assert times.empty, times[["artefact", "quantity"]].values.tolist()
    for c in claims:
        if c.unit in ("ms", "s", "µs", "us"):
            assert c.verdict == NOT_COMPARABLE, (c.artefact, c.quantity, c.verdict)


# ------------------------------------------------------- issue 45: one verdict from several readings
from parakin.claims import WITHIN_ROUNDING, decide, readings_text  # noqa: E402


def _two_readings_ref() -> pd.DataFrame:
    return pd.DataFrame(
        [
            {
                "paper": "p",
                "artefact": "t",
                "quantity": "rate",
                "value": "0.001",
                "unit": "1",
                "note": "encoded: fails on at least 0.1 % of the inputs",
                "role": "result",
                "tolerance": "lower",
            }
        ]
    )


def test_the_weakest_reading_decides_and_every_reading_is_shown(tmp_path):
    """A favourable reading (a wide region) must not hide an unfavourable one (the paper's box):
    with no declared reading the number gets the weakest verdict, whichever order the readings
    come in, and the report row lists both readings with their own verdicts and evidence."""
    from parakin.report import report_rows

    ref = _two_readings_ref()
    wide = Claim("p", "t", "rate", "0.001", 0.2, "1", "wide region", evidence="wide.md")
    box = Claim("p", "t", "rate", "0.001", 0.0, "1", "the paper's box", evidence="box.md")
    wide, box = resolve(wide, ref), resolve(box, ref)
    assert wide.verdict == BOUND and box.verdict == DIFFERS_SHOWN
    for readings in ([wide, box], [box, wide]):
        chosen, how = decide(readings)
        assert chosen is box and how == "weakest reading"
        row = row_verdicts(readings, ref).iloc[0]
        assert row["verdict"] == DIFFERS_SHOWN and row["claim"] is box
        out = report_rows("p", ref, readings, tmp_path).iloc[0]
        assert out["verdict"] == DIFFERS_SHOWN and out["ours"] == "0.0"
        text = out["readings"]
        assert text.startswith("the weakest of 2 readings decides: the paper's box")
        for c in readings:  # every reading, its value, its own verdict and its evidence
            assert f"{c.variant}: {_fmt_(c.ours)} → {c.verdict} (evidence: {c.evidence})" in text
        assert out["evidence"] == "box.md"
        assert out["paper value"] == "0.001"  # as printed: the bound is the tolerance column's


def _fmt_(x):
    from parakin.claims import _fmt

    return _fmt(x)


def test_a_declared_reading_decides_whatever_the_others_say(tmp_path):
    """A reading declared before the comparison (the paper's stated geometry) decides, even where a
    fitted reading of the same number differs or agrees; the row says which and why."""
    from parakin.report import report_rows

    ref = pd.DataFrame(
        [
            {
                "paper": "p",
                "artefact": "table1",
                "quantity": "l1",
                "value": "0.40",
                "unit": "m",
                "note": "",
                "role": "result",
                "tolerance": "",
            }
        ]
    )
    stated = Claim(
        "p",
        "table1",
        "l1",
        "0.40",
        0.4016,
        "m",
        "stated geometry",
        declared="the paper's own inputs",
    )
    fit = Claim("p", "table1", "l1", "0.40", 0.3947, "m", "best fit", basis="fitted to Table 1")
    stated, fit = resolve(stated, ref), resolve(fit, ref)
    assert stated.verdict == WITHIN_ROUNDING and fit.verdict == DIFFERS_UNKNOWN
    chosen, how = decide([fit, stated])
    assert chosen is stated and how == "declared reading"
    out = report_rows("p", ref, [fit, stated], tmp_path).iloc[0]
    assert out["verdict"] == WITHIN_ROUNDING
    assert out["readings"].startswith("declared reading: stated geometry (the paper's own inputs)")
    assert "best fit: 0.3947 → differs — cause unknown" in out["readings"]
    # without the declaration the weakest (the fit) would decide
    plain = resolve(Claim("p", "table1", "l1", "0.40", 0.4016, "m", "stated geometry"), ref)
    assert decide([plain, fit])[0] is fit


def test_a_declared_reading_is_one_and_never_a_fit():
    """At most one declared reading per number, and never one resting on a fit or an assumption
    (a reading chosen because it matches is not chosen before the comparison)."""
    with pytest.raises(ValueError, match="declared reading cannot rest"):
        Claim("p", "t", "q", "0.42", 0.42, "m", basis="fitted", declared="because")
    a = Claim("p", "t", "q", "0.42", 0.42, "m", "a", declared="x")
    b = Claim("p", "t", "q", "0.42", 0.5, "m", "b", declared="y")
    with pytest.raises(ValueError, match="2 readings declare themselves"):
        decide([a, b])
    one = Claim("p", "t", "q", "0.42", 0.42, "m")
    assert (
        decide([one]) == (one, "only reading") and readings_text([one], one, "only reading") == ""
    )


@pytest.mark.parametrize("key", list(PAPERS))
def test_every_number_with_several_readings_says_how_its_verdict_was_chosen(key):
    """In the committed record, each published number judged by several readings gets the declared
    one's verdict or the weakest, and its row lists them all."""
    from parakin.report import report_rows

    ref, claims = paper_claims_(key)
    rows = report_rows(key, ref, claims, ROOT / "figures" / key)
    by = {}
    for c in claims:
        by.setdefault((c.artefact, c.quantity), []).append(c)
    for _, r in rows.iterrows():
        cs = by.get((r["artefact"], r["quantity"]), [])
        if len(cs) < 2 or r["verdict"] == INPUT:
            continue
        declared = [c for c in cs if c.declared]
        want = declared[0] if declared else max(cs, key=lambda c: VERDICTS.index(c.verdict))
        assert r["verdict"] == want.verdict, (r["artefact"], r["quantity"])
        assert r["readings"].count(" → ") == len(cs), (r["artefact"], r["quantity"])


def paper_claims_(key):
    from parakin.report import paper_claims

    return paper_claims(key, ROOT / "figures")
