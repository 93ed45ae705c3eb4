"""Chaotic computations are judged on independent runs (issue 28): the summary of the runs, the
verdict rule on their range, a whole that must agree as a whole, and runs that do not depend on
how many cores share them."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import binom

from parakin.claims import (
    BOUND,
    CONSISTENT,
    DIFFERS_SHOWN,
    DIFFERS_UNKNOWN,
    REPRODUCED,
    WITHIN_ROUNDING,
    Claim,
    judge,
    run_summary,
)
from parakin.papers.runs import job_threads, map_runs


def test_run_summary_is_the_order_statistic_interval_of_the_median():
    x = np.arange(1.0, 31.0)[::-1]  # 30 runs, in any order
    s = run_summary(x)
    assert (s["runs"], s["median"], s["min"], s["max"]) == (30, 15.5, 1.0, 30.0)
    # P(Binom(30, 1/2) < j) <= 0.005 for j = 8: the interval is (x_(8), x_(23))
    assert binom.cdf(7, 30, 0.5) <= 0.005 < binom.cdf(8, 30, 0.5)
    assert (s["ci_low"], s["ci_high"]) == (8.0, 23.0)
    ten = run_summary(np.arange(10.0))
    assert (ten["ci_low"], ten["ci_high"]) == (0.0, 9.0)  # 10 runs: 99 % needs the whole range
    assert run_summary([1.0, np.nan, 3.0])["max"] == np.inf  # a failed run sorts above the rest
    with pytest.raises(ValueError, match="at least one run"):
        run_summary([])


def test_values_are_judged_by_the_range_of_the_runs():
    assert judge("70", 64.0, tol=10.0, spread=(40.0, 60.0)) == REPRODUCED  # 70 - 60 <= 10
    assert judge("70", 64.0, tol=5.0, spread=(40.0, 60.0)) == "differs"
    assert judge("0.21", 0.15, spread=(0.1500, 0.2096)) == WITHIN_ROUNDING  # half a printed digit
    assert judge("0.21", 0.15, tol=0.0, spread=(0.1500, 0.2096)) == "differs"  # declared exact
    # an order of magnitude: the runs' range reaches within half a decade of it
    assert judge("1e-4", 8e-4, kind="order", spread=(3e-4, 2e-3)) == REPRODUCED
    assert judge("1e-4", 8e-4, kind="order", spread=(4e-4, 2e-3)) == "differs"
    # a bound: met by the median run
    assert judge("1500", 900.0, kind="upper", spread=(300.0, 1e9)) == BOUND
    assert judge("1500", 1600.0, kind="upper", spread=(300.0, 1e9)) == "differs"


def test_from_runs_names_its_runs_and_keeps_basis_and_evidence():
    c = Claim.from_runs(
        "p", "fig14", "g", "70", [60, 64, 90, 55, 88], "1", what="GA runs", basis="the bounds"
    )
    assert c.ours == 64 and c.spread == (55, 90) and c.verdict == CONSISTENT
    assert c.variant.startswith("median of 5 GA runs 64, 99 % CI [55, 90], range [55, 90]")
    far = Claim.from_runs("p", "fig14", "f", "0.137", [0.007, 0.012], "1", evidence="x.md")
    assert far.verdict == DIFFERS_SHOWN


def test_a_part_of_a_whole_that_does_not_agree_differs():
    alone = Claim("p", "table3", "row2.X", "-0.318", -0.3181, "1")
    assert alone.verdict == WITHIN_ROUNDING  # one coordinate near a solution: a coincidence ...
    part = Claim("p", "table3", "row2.X", "-0.318", -0.3181, "1", whole_agrees=False)
    assert part.verdict == DIFFERS_UNKNOWN  # ... once the row is judged as a whole
    assert Claim("p", "t", "q", "1", 1.0, "1", whole_agrees=True).verdict == WITHIN_ROUNDING


def _seeded(seed: int, n: int) -> float:
    g = np.random.default_rng(seed)
    a = g.standard_normal((n, n))
    return float(np.linalg.cond(a @ a.T))  # BLAS work inside each run


def test_runs_do_not_depend_on_how_many_cores_share_them(monkeypatch):
    tasks = [(s, 40) for s in range(6)]
    one = map_runs(_seeded, tasks, threads=1)
    two = map_runs(_seeded, tasks, threads=2)
    assert one == two  # same numbers, same order
    monkeypatch.setenv("OMP_NUM_THREADS", "3")
    assert job_threads() == 3
    monkeypatch.setenv("OMP_NUM_THREADS", "")
    assert job_threads(2) == 2
    with pytest.raises(ValueError, match="threads = 0"):
        map_runs(_seeded, tasks, threads=0)
