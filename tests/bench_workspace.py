"""pytest-benchmark suite of the workspace classifier (issue 44: >= 10^6 poses classified per second
on 2 cores). Not part of the default run (the file name does not match ``test_*.py``):
``pytest tests/bench_workspace.py -o addopts="" -p no:cacheprovider``.

Every registered mechanism, 10^6 uniform points of its fitted box, classified three ways in the
same run: the compiled loop on every core (``compiled``), the same without the condition number
(``compiled_ik``: IK and joint limits, the constant-orientation test), and numpy (``numpy``, the
baseline). ``extra_info`` records poses per second of wall time and of CPU time (all threads), so
a busy machine shows in the ratio of the two.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from parakin.mechanisms import REGISTRY
from parakin.workspace import classify, fit_box, make_region

N = 1_000_000


@pytest.fixture(scope="module", params=list(REGISTRY))
def problem(request):
    region, _ = fit_box(make_region(REGISTRY[request.param]()))
    pts = np.random.default_rng(44).uniform(region.lo, region.hi, size=(N, region.dim))
    classify(region, pts[:30_000], compiled=True)  # load (or compile) the loop first
    return region, pts


@pytest.mark.parametrize("how", ["compiled", "compiled_ik", "numpy"])
def test_classify(benchmark, problem, how):
    region, pts = problem
    kwargs = {"compiled": how != "numpy", "cond": how != "compiled_ik"}
    n = N if how != "numpy" else N // 10  # numpy: a tenth (its rate does not depend on the size)
    cpu = []

    def run():
        t = time.process_time()
        out = classify(region, pts[:n], **kwargs)
        cpu.append(time.process_time() - t)
        return out

    res = benchmark.pedantic(run, rounds=3, iterations=1)
    benchmark.extra_info["poses"] = n
    benchmark.extra_info["poses_per_cpu_s"] = n / min(cpu)
    if benchmark.stats is not None:  # None under --benchmark-disable
        benchmark.extra_info["poses_per_s"] = n / benchmark.stats.stats.min
    assert res.member.any()
