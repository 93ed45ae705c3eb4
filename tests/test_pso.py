"""The generic PSO solver: reproducible per seed, batched == alone, schedules, convergence."""

import numpy as np
import pytest

import parakin.solvers.pso as pso_mod
from parakin.mechanisms import P3P4S
from parakin.mechanisms.ups2 import UPS2
from parakin.solvers import METHODS, solve_fk

Q = np.array([[0, -24, 26], [-23, -32, -32], [1.62, 23, -27]]) * 1e-3


def test_registered():
    assert METHODS["pso"] is pso_mod.pso


def test_reproducible_per_seed_and_batch_independent():
    m = UPS2()
    kw = dict(method="pso", tol=1e-9, maxiter=150, inertia="linear")
    a = solve_fk(m, Q, seed=[5, 6, 7], **kw)
    b = solve_fk(m, Q, seed=[5, 6, 7], **kw)
    c = solve_fk(m, Q[1], seed=6, **kw)
    assert np.array_equal(a.x, b.x) and np.array_equal(a.history, b.history)
    assert np.array_equal(a.x[1], c.x) and np.array_equal(a.history[1], c.history)
    d = solve_fk(m, Q, seed=[8, 6, 7], **kw)
    assert not np.array_equal(a.x[0], d.x[0])


def test_improved_converges_as_printed_does_not():
    m = UPS2()
    q = np.repeat(Q, 3, axis=0)
    seeds = np.arange(len(q))
    imp = solve_fk(
        m, q, method="pso", tol=1e-9, maxiter=1500, inertia="linear", vclamp=0.2, seed=seeds
    )
    assert imp.success.all() and np.all(imp.fitness <= 1e-9)
    assert np.max(np.abs(imp.x - m.fk(q))) < 1e-5
    lit = solve_fk(m, q, method="pso", tol=1e-9, maxiter=1500, inertia="constant", seed=seeds)
    assert not lit.success.any()
    # history is monotone non-increasing and ends at the best fitness
    assert np.all(np.diff(imp.history, axis=-1) <= 0)
    assert np.allclose(imp.history[:, -1], imp.fitness)


def test_custom_schedule_and_fitness_and_other_mechanism():
    m = P3P4S()
    x = np.array([0.01, -0.02, 0.58])
    calls = []

    def sched(k, maxiter, rows):
        calls.append(k)
        return np.full(len(rows), 0.6)

    res = solve_fk(
        m,
        m.ik(x),
        method="pso",
        tol=1e-9,
        maxiter=800,
        inertia=sched,
        seed=1,
        fitness=lambda xx, q: np.sum(
            m.residual(xx, np.broadcast_to(q[:, None, :], xx.shape)) ** 2, -1
        ),
        ftol=1e-20,
    )
    assert calls[0] == 1 and np.allclose(res.inertia[1 : len(calls) + 1], 0.6)
    assert np.max(np.abs(res.x - x)) < 1e-6


def test_chaotic_schedule():
    s = pso_mod.ChaoticLogistic(z0=0.37)
    w = [s(k, 100, np.arange(2)) for k in range(1, 5)]
    assert all(np.all((v > 0.4 * 0) & (v < 1.0)) for v in w)
    with pytest.raises(ValueError):
        pso_mod.ChaoticLogistic(z0=0.5)


def test_bad_options():
    with pytest.raises(ValueError, match="inertia"):
        solve_fk(UPS2(), Q[0], method="pso", inertia="cubic", maxiter=2)
    with pytest.raises(ValueError, match="seed"):
        solve_fk(UPS2(), Q, method="pso", seed=[1, 2], maxiter=2)


@pytest.mark.parametrize("inertia", ["linear", "constant", "chaotic"])
def test_compiled_loop_same_as_numpy(inertia, monkeypatch):
    """With kernels (parakin.kernels: pso_row) the same random stream, the same updates in the
    same order: the same swarms to the bit, for every schedule whose weights do not depend on
    which runs are still going."""
    pytest.importorskip("numba")
    from parakin import kernels
    from parakin.mechanisms import Stewart36

    if not kernels.enabled():
        pytest.skip("compiled kernels switched off")
    for m, q in ((UPS2(), Q), (Stewart36(), Stewart36().ik(Stewart36().home())[None])):

        def solve(m=m, q=q):
            w = pso_mod.ChaoticLogistic(mu=4.0) if inertia == "chaotic" else inertia
            kw = dict(method="pso", tol=1e-9, maxiter=150, swarm=20, vclamp=0.2, inertia=w)
            return solve_fk(m, np.repeat(q, 3, 0)[:3], seed=[3, 4, 5], **kw)

        got = solve()
        with monkeypatch.context() as mp:
            mp.setenv("PARAKIN_KERNELS", "0")
            ref = solve()
        for k in ("x", "fitness", "history", "nit", "nfev", "status"):
            assert np.array_equal(getattr(got, k), getattr(ref, k)), k
        assert np.allclose(got.inertia, ref.inertia, equal_nan=True)


def test_compiled_loop_not_used_with_callback_or_own_fitness(monkeypatch):
    calls = []
    monkeypatch.setattr(pso_mod, "_compiled_loop", lambda *a, **k: calls.append(1))
    m = UPS2()
    kw = dict(method="pso", tol=1e-9, maxiter=5, seed=1)
    solve_fk(m, Q[0], callback=lambda k, x, f: None, **kw)
    fit = lambda x, q: np.sum(m.residual(x, q[:, None, :]) ** 2, -1)  # noqa: E731
    solve_fk(m, Q[0], fitness=fit, **kw)
    assert not calls
