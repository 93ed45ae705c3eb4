"""Verdicts of the report: rounding from the printed digits, bounds and orders of magnitude."""

import pytest

from parakin.report import Claim, half_ulp, judge, load_reference


@pytest.mark.parametrize("printed, ulp", [("0.42", 0.005), ("0.592", 0.0005), ("3", 0.5), ("4.51e-8", 5e-11), ("0.5919999528", 5e-11)])
def test_half_ulp_from_printed_digits(printed, ulp):
    assert half_ulp(printed) == pytest.approx(ulp)


def test_value_verdicts():
    assert judge("0.42", 0.4249) == "reproduced within rounding"
    assert judge("0.42", 0.4251) == "differs"
    assert judge("0.42", 0.4251, tol=1e-3) == "differs"
    assert judge("0.42", 0.42005, tol=1e-4) == "reproduced"
    assert judge("0.42", float("nan")) == "differs"


def test_bound_and_order_verdicts():
    assert judge("20", 0.4, kind="upper") == "reproduced"
    assert judge("20", 25.0, kind="upper") == "differs"
    assert judge("1e-4", 2.9e-4, kind="order") == "reproduced"
    assert judge("1e-4", 4e-4, kind="order") == "differs"
    with pytest.raises(ValueError, match="kind = 'exact'"):
        judge("1", 1.0, kind="exact")


def test_claim_carries_verdict_and_difference():
    c = Claim("p", "table1", "case1.l1", "0.42", 0.4316, "m")
    assert c.verdict == "differs" and c.diff == pytest.approx(0.0116)


def test_reference_csv_is_well_formed():
    ref = load_reference("zhao2017_3p4s")
    assert not ref.duplicated(["artefact", "quantity"]).any()
    assert (ref["paper"] == "zhao2017_3p4s").all()
    for value in ref["value"]:
        float(value)  # every value is a number as printed
    assert len(ref[ref["artefact"] == "table1"]) == 30 and len(ref[ref["artefact"] == "table2"]) == 40
