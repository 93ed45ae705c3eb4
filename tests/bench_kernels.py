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
    if benchmark.stats is not None:  # None under --benchmark-disable (one plain call)
        benchmark.extra_info["solves_per_s"] = len(q) / benchmark.stats.stats.min
    benchmark.extra_info["success_rate"] = float(np.mean(res.success))  # beside the speed
    # a success is a right answer: the pose's IK gives the joints back (from the whole pose box,
    # the 3-6's and the 6-6's plain Newton from home fail often; that is measured, not asserted)
    x = res.x[res.success]
    assert np.abs(mech.ik(x) - q[res.success]).max(initial=0.0) <= 1e-6


def test_stewart36_all_solutions(benchmark):
    mech = MECHS["stewart36"]
    _, q = _sample(mech, 500, seed=19)
    benchmark.pedantic(
        solve_fk, args=(mech, q), kwargs={"method": "all-solutions"}, rounds=1, iterations=1
    )


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "numpy"])
def test_stewart66_start_on_a_new_geometry(benchmark, compiled):
    """``Stewart66.fk_start`` on a geometry not seen before: what a geometry's start system costs
    (built where it takes more than one input), its paths tracked compiled (the lane tracker) or in
    numpy. The detour a retry takes is tracked once per process, before the timing."""
    from parakin.mechanisms.stewart66 import random_platform

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


def test_stewart66_new_geometry_per_call(benchmark):
    """One input on a new geometry, everything timed: the mechanism built from its anchors
    (validated), then its first ``fk_all``, which takes the new-geometry path (the stored generic
    start moved to the input's anchors and leg lengths in one homotopy). One numba thread."""
    from parakin.mechanisms.stewart66 import Stewart66, random_platform, random_pose
    from parakin.timing import one_thread

    rng = np.random.default_rng(4)

    def setup():
        m = random_platform(rng)
        return (m.base_points, m.platform_points, m.ik(random_pose(rng, 1, m))[0]), {}

    def call(base, platform, legs):
        return Stewart66(base=base, platform=platform).fk_all(legs, return_info=True)

    call(*setup()[0])  # compiles
    with one_thread():
        res = benchmark.pedantic(call, setup=setup, rounds=20, iterations=1)
    assert res.complete and res.n_found == 40


@pytest.mark.parametrize("batch", [1, 100], ids=["one-input-per-call", "batch-of-100"])
def test_stewart66_same_geometry(benchmark, batch):
    """Inputs on a known geometry (its start system built before the clock: a platform reused),
    one per call or 100 in one call, each along its fibre; random poses on one random platform.
    One numba thread. ``extra_info``: milliseconds per input."""
    from parakin.mechanisms.stewart66 import random_platform, random_pose
    from parakin.timing import one_thread

    rng = np.random.default_rng(5)
    mech = random_platform(rng)
    q = mech.ik(random_pose(rng, 2000, mech))
    mech.fk_all(q[:2])  # the start system, and compiles
    rows = iter(range(0, len(q), batch))

    def setup():
        i = next(rows)
        return (q[i] if batch == 1 else q[i : i + batch],), {}

    with one_thread():
        res = benchmark.pedantic(
            lambda legs: mech.fk_all(legs, return_info=True), setup=setup, rounds=19, iterations=1
        )
    if benchmark.stats is not None:
        benchmark.extra_info["ms_per_input"] = 1e3 * benchmark.stats.stats.median / batch
    assert np.all(res.complete)


def _iteration_parts():
    """Compiled loops that call one part of a Newton iteration ``reps`` times on one pose (the
    pose moves by a rounding-size amount each time, so that no call can be hoisted out)."""
    import numba

    from parakin.kernels import drivers

    @numba.njit
    def kernel_part(f, p, x, q, out, reps):
        for i in range(reps):
            x[0] += 1e-15 * (i & 1)
            f(p, x, q, out)

    @numba.njit
    def direction(jm, r, dx, w, a, g, reps):
        for i in range(reps):
            r[0] += 1e-15 * (i & 1)
            drivers._direction(jm, r, dx, w, a, g)

    return kernel_part, direction


@pytest.mark.parametrize("part", ["residual", "jacobian", "direction", "solve"])
@pytest.mark.parametrize("name", ["stewart12", "stewart36"])
def test_newton_iteration_parts(benchmark, name, part):
    """The profile of one batched Newton iteration (issue 29): the kernel's residual, its Jacobian
    and the step (``drivers._direction``: the normal equations J^T J and their LU for the 12 legs
    of the cube, the LU of J for the 3-6), each 1 000 times in a compiled loop on one core, and
    the whole solve (``solve``: 1 000 of ``test_batched``'s inputs from home, the serial entry, one
    core); ``extra_info['ns_per_call']``, for ``solve`` also the mean iterations per solve."""
    mech = MECHS[name]
    kernel = kernels.kernel_of(mech)
    x, q = _sample(mech, 1, seed=18)
    x, q = np.ascontiguousarray(x[0]), np.ascontiguousarray(q[0])
    m, n, p, reps = len(q), len(x), kernel.params, 1000
    compiled = kernels.compiled(kernel.module)
    kernel_part, direction = _iteration_parts()
    jm, r = np.empty((m, n)), np.empty(m)
    compiled.jacobian(p, x, q, jm)
    compiled.residual(p, x, q, r)
    if part == "solve":
        _, qs = _sample(mech, reps, seed=18)
        x0 = np.ascontiguousarray(np.broadcast_to(kernel.home, (reps, n)))
        opts = kernels.methods.pack("newton", 1e-10, 100, {})
        xs, info, out = np.empty((reps, n)), np.zeros((reps, 4), np.int64), np.empty((reps, 1))
        serial = kernels.entries_of(kernel.module, "newton").serial
        run = lambda: (info.fill(0), serial(p, qs, x0, opts, xs, info, out))  # noqa: E731
    elif part == "direction":
        out, scratch = np.empty(n), (np.empty((n, n + 1)), np.empty((n, n)), np.empty(n))
        run = lambda: direction(jm, r, out, *scratch, reps)  # noqa: E731
    else:
        f, out = getattr(compiled, part), (jm if part == "jacobian" else r)
        run = lambda: kernel_part(f, p, x.copy(), q, out, reps)  # noqa: E731
    run()  # compiles
    assert np.isfinite(out).all()  # what the part writes
    benchmark.pedantic(run, rounds=50, iterations=1)
    if benchmark.stats is not None:  # None under --benchmark-disable (one plain call)
        benchmark.extra_info["ns_per_call"] = 1e9 * benchmark.stats.stats.min / reps
    if part == "solve":
        benchmark.extra_info["iterations_per_solve"] = float(info[:, 1].mean())
