"""The reproduction check compares each number by what it is (issue 28): condition numbers by class
near a singularity, statistics of chaotic runs by their confidence intervals."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from parakin import registry
from parakin.check import compare_file

COND = registry.Tolerance(
    "statistical", 0.0, 0.0, "conditioning", columns={"cond": registry.Tolerance.condition(6)}
)


def _pair(tmp_path, record: dict, run: dict):
    rec, new = tmp_path / "rec.csv", tmp_path / "new.csv"
    pd.DataFrame(record).to_csv(rec, index=False)
    pd.DataFrame(run).to_csv(new, index=False)
    return rec, new


def _singular_cond(perturb: float) -> float:
    """cond of a rank-deficient 6 x 6 matrix whose round-off is changed by ``perturb``."""
    g = np.random.default_rng(0)
    a = g.standard_normal((6, 5))
    J = np.column_stack([a, a[:, 0] + a[:, 1]])  # exactly dependent columns
    J[0, 0] += perturb
    return float(np.linalg.cond(J))


def test_condition_numbers_of_singular_matrices_compare_by_class(tmp_path):
    # the case: Ye's singular home pose, 2.84005e17 in the record, 2.82996e17 on another CPU
    rec, new = _pair(tmp_path, {"cond": [2.84005e17, 9.936]}, {"cond": [2.82996e17, 9.936]})
    assert compare_file(rec, new, COND)[0] == "within tolerance"
    # two round-off levels of one singular matrix: both singular to working precision
    a, b = _singular_cond(0.0), _singular_cond(1e-16)
    rec, new = _pair(tmp_path, {"cond": [a]}, {"cond": [b]})
    assert compare_file(rec, new, COND)[0] == "within tolerance"
    # singular against regular, and a regular matrix moved beyond its round-off: differs
    rec, new = _pair(tmp_path, {"cond": [2.8e17]}, {"cond": [1e6]})
    assert compare_file(rec, new, COND)[:2] == ("differs", "cond")
    rec, new = _pair(tmp_path, {"cond": [792.46472802]}, {"cond": [792.4648]})
    assert compare_file(rec, new, COND)[:2] == ("differs", "cond")
    # ... but not within its round-off: k kappa = (6 + sqrt 6) eps 792 ~ 1.5e-12 relative
    rec, new = _pair(tmp_path, {"cond": [792.4647280251125]}, {"cond": [792.4647280250655]})
    assert compare_file(rec, new, COND)[0] == "within tolerance"


@pytest.mark.parametrize("kappa", [1.0, 1e3, 1e8, 1e13])
def test_condition_rule_covers_the_round_off_it_derives(kappa):
    """The bound holds for matrices of known conditioning perturbed at the rounding level."""
    rule = registry.ConditionNumber(6)
    g = np.random.default_rng(1)
    u, _ = np.linalg.qr(g.standard_normal((6, 6)))
    v, _ = np.linalg.qr(g.standard_normal((6, 6)))
    J = u @ np.diag(np.geomspace(1.0, 1.0 / kappa, 6)) @ v.T
    base = np.linalg.cond(J)
    moved = [np.linalg.cond(J * (1 + 2.2e-16 * g.standard_normal((6, 6)))) for _ in range(20)]
    assert rule.agree(np.full(20, base), np.array(moved)).all()


def test_statistics_of_chaotic_runs_compare_by_interval_overlap(tmp_path):
    tol = registry.Tolerance(
        "statistical",
        0.0,
        0.0,
        "medians of independent runs",
        columns={"runs": (0.0, 0.0)},
        intervals=(("ci_low", "ci_high"),),
    )
    record = {
        "quantity": ["g"],
        "runs": [30],
        "median": [70.0],
        "ci_low": [60.0],
        "ci_high": [80.0],
    }
    rec, new = _pair(
        tmp_path, record, {**record, "median": [64.0], "ci_low": [55.0], "ci_high": [75.0]}
    )
    assert compare_file(rec, new, tol)[0] == "within tolerance"
    rec, new = _pair(
        tmp_path, record, {**record, "median": [90.0], "ci_low": [85.0], "ci_high": [95.0]}
    )
    status, column, _, detail = compare_file(rec, new, tol)
    assert status == "differs" and column == "ci_low..ci_high" and "overlap" in detail
    rec, new = _pair(tmp_path, record, {**record, "runs": [10]})
    assert compare_file(rec, new, tol)[:2] == ("differs", "runs")


def test_condition_rule_rejects_a_bad_dimension():
    with pytest.raises(ValueError, match="n = 0"):
        registry.ConditionNumber(0)


BASIN = registry.Tolerance(
    "iterative",
    0.0,
    0.0,
    "medians over the converged starts",
    columns={"p_converge": (0.0, 0.05), "median_iterations": (0.0, 1.0)},
    over_successes={"median_iterations": ("p_converge", "trials")},
)


def test_a_median_over_successes_is_compared_only_over_enough_successes(tmp_path):
    """200 starts, p_converge within 0.05: 10 starts may differ, so a median over the converged
    starts is compared only where both runs have more than 20."""
    record = {
        "trials": [200] * 3,
        "p_converge": [0.0, 0.5, 0.105],
        "median_iterations": [np.nan, 7.0, 9.0],
    }
    # the cell: one start of 200 converged on another BLAS kernel (57 iterations), none in
    # the record; and 20 against 21 converged: too few to fix a median either way
    run = {**record, "p_converge": [0.005, 0.5, 0.1], "median_iterations": [57.0, 7.0, 30.0]}
    rec, new = _pair(tmp_path, record, run)
    assert compare_file(rec, new, BASIN)[0] == "within tolerance"
    # with 100 converged starts on each side the median is compared, within its atol of one
    rec, new = _pair(tmp_path, record, {**run, "median_iterations": [57.0, 8.0, 30.0]})
    assert compare_file(rec, new, BASIN)[0] == "within tolerance"
    rec, new = _pair(tmp_path, record, {**run, "median_iterations": [57.0, 9.5, 30.0]})
    assert compare_file(rec, new, BASIN)[:2] == ("differs", "median_iterations")
    # ... and the fraction itself is still compared in every row
    rec, new = _pair(tmp_path, record, {**run, "p_converge": [0.06, 0.5, 0.1]})
    assert compare_file(rec, new, BASIN)[:2] == ("differs", "p_converge")


def test_a_value_against_none_differs_without_bound(tmp_path):
    """A number where the record has NaN (or the reverse) is an infinite excess, not zero."""
    tol = registry.Tolerance("iterative", 0.0, 1.0, "counts")
    rec, new = _pair(tmp_path, {"n": [1.0, np.nan]}, {"n": [1.0, 57.0]})
    status, column, excess, detail = compare_file(rec, new, tol)
    assert (status, column, excess) == ("differs", "n", np.inf) and "57 vs record nan" in detail
