"""pytest-benchmark suite of the compiled FK path (issue 17). Not part of the default run (the file
name does not match ``test_*.py``): ``pytest tests/bench_kernels.py -o addopts=""``.

``parakin.bench.kernel_goals`` (``python -m parakin.bench``) measures the same with the ratios
against ``scipy.optimize.root`` and the goals in one table.
"""

from __future__ import annotations

import numpy as np
import pytest

from parakin import kernels
from parakin.bench import _compiled_mechanisms, _sample
from parakin.solvers import solve_fk

#: every registered mechanism with compiled kernels
MECHS = {m.name: m for m in _compiled_mechanisms()}


@pytest.fixture(scope="module", params=list(MECHS))
def problem(request):
    mech = MECHS[request.param]
    _, q = _sample(mech, 100_000, seed=18)
    return mech, q


@pytest.mark.parametrize("method", ["newton", "lm", "broyden", "bfgs", "scipy-root"])
def test_single_call(benchmark, problem, method):
    mech, q = problem
    solve_fk(mech, q[0], method=method)
    benchmark(solve_fk, mech, q[0], method=method)


@pytest.mark.parametrize("method", ["newton", "lm"])
def test_batched(benchmark, problem, method):
    mech, q = problem
    solve_fk(mech, q[:100], method=method)
    res = benchmark.pedantic(
        solve_fk, args=(mech, q), kwargs={"method": method}, rounds=3, iterations=1
    )
    benchmark.extra_info["solves_per_s"] = len(q) / benchmark.stats.stats.min
    assert np.mean(res.success) > 0.9


def test_stewart36_all_solutions(benchmark):
    mech = MECHS["stewart36"]
    _, q = _sample(mech, 500, seed=19)
    benchmark.pedantic(
        solve_fk, args=(mech, q), kwargs={"method": "all-solutions"}, rounds=1, iterations=1
    )


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "numpy"])
def test_stewart66_start_on_a_new_geometry(benchmark, compiled):
    """``Stewart66.fk_start`` on a geometry not seen before: the cost of the first ``fk_all`` on a
    user's own 6-6, with the start system's paths tracked compiled or in numpy. The detour a retry
    takes is tracked once per process, before the timing."""
    from parakin.studies.stewart66 import random_platform

    rng = np.random.default_rng(3)
    with kernels.interpreted(not compiled):
        assert len(random_platform(rng).fk_start["solutions"]) == 40  # compiles; tracks the detour
        res = benchmark.pedantic(
            lambda mech: mech.fk_start,
            setup=lambda: ((random_platform(rng),), {}),
            rounds=20,
            iterations=1,
        )
    assert len(res["solutions"]) == 40
