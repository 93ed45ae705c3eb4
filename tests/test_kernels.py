"""Compiled kernels (parakin.kernels): the same equations and the same solves as the numpy path,
for every registered mechanism (its tests appear here by registering) and the variants below.

Compiles once per machine: the entries are cached on disk (:mod:`parakin.kernels.store`), so
only the first run of this file pays numba's compile time. ``PARAKIN_KERNELS=0`` selects the
numpy solvers for the reference runs.
"""

from __future__ import annotations

import subprocess
import sys
from contextlib import contextmanager

import numpy as np
import pandas as pd
import pytest

from parakin import kernels, mechanisms
from parakin.kernels import methods, store
from parakin.mechanisms import P3P4S, UPS2, Stewart12, Stewart36
from parakin.mechanisms.base import Mechanism
from parakin.mechanisms.stewart12 import ActiveLegs, DriveMode
from parakin.solvers import Status, compiled, solve_fk

pytest.importorskip("numba")

#: every registered mechanism with a kernel (default parameters), and variants of some
MECHS = {
    **{name: cls() for name, cls in mechanisms.REGISTRY.items() if cls().kernel() is not None},
    "3p4s-opt": P3P4S.zhao2017_optimised(),
    "2ups-mirror": UPS2(branch=-1),
    "stewart36-b2": Stewart36(b=2.0),
}
#: the mechanisms whose numeric FK from near starts is compared (the 6-6's 40 assemblies make
#: Newton from a start 2 % of the way to home land elsewhere; its own test below)
NEAR = [k for k in MECHS if k != "stewart66"]
#: every method with a compiled loop (a method added to the option table is tested here by itself)
METHODS = list(methods.COMPILED)


def _poses(mech, n: int, seed: int, spread: float = 1.0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    lo, hi = mech.pose_bounds()
    home = mech.home()
    x = home + spread * (rng.uniform(lo, hi, size=(3 * n, mech.n_pose)) - home)
    return x[mech.in_domain(x)][:n]


def _numpy_path(monkeypatch):
    monkeypatch.setenv("PARAKIN_KERNELS", "0")


def _kernel_cases():
    """Every mechanism with a kernel, and two ActiveLegs (6 legs: square; 8: least squares)."""
    return {
        **MECHS,
        "active6": ActiveLegs(active=(1, 3, 5, 7, 9, 11)),
        "active8": ActiveLegs(mech=Stewart12(n=0.02), active=(1, 2, 3, 4, 6, 8, 10, 12)),
    }


def _random_problem(mech, n=300, seed=5):
    """Poses in and around the pose box (also outside the domain), joints near the IK."""
    rng = np.random.default_rng(seed)
    lo, hi = mech.pose_bounds()
    x = rng.uniform(lo - 0.5 * (hi - lo), hi + 0.5 * (hi - lo), size=(n, mech.n_pose))
    inside = mech.in_domain(x)
    q = np.where(inside[:, None], 0.0, 0.1) + rng.uniform(0.0, 1.0, (len(x), mech.n_joints))
    q[inside] = mech.ik(x[inside]) + 1e-3 * rng.standard_normal((inside.sum(), mech.n_joints))
    return x, q, inside


@pytest.mark.parametrize("key", list(_kernel_cases()))
def test_one_source_numpy_numba_torch(key):
    """residual, jacobian_pose, ik, in_domain, on_assembly: the numpy methods (the kernel module
    vectorised over the batch), the numba kernels (one pose) and the torch path (CPU) are the same
    functions, so they agree to rounding; the numpy Jacobian is the residual's derivative."""
    mech = _kernel_cases()[key]
    k = mech.kernel()
    nb = kernels.compiled(k.module)
    x, q, inside = _random_problem(mech)
    res, jac = mech.residual(x[inside], q[inside]), mech.jacobian_pose(x[inside], q[inside])
    ik, asm = mech.ik(x[inside]), mech.on_assembly(x[inside], q[inside])
    np.testing.assert_array_equal(mech.in_domain(x), inside)
    r, j, out = np.empty(k.n_joints), np.empty((k.n_joints, k.n_pose)), np.empty(k.n_joints)
    for row, (xi, qi, ok) in enumerate(zip(x, q, inside)):
        assert bool(nb.in_domain(k.params, xi)) == ok
        if not ok:
            assert not nb.ik(k.params, xi, out) or key.startswith(("stewart36", "stewart66"))
            continue
        i = int(inside[:row].sum())
        nb.residual(k.params, xi, qi, r)
        nb.jacobian(k.params, xi, qi, j)
        assert nb.ik(k.params, xi, out)
        np.testing.assert_allclose(r, res[i], rtol=1e-13, atol=1e-15 * (1 + qi @ qi))
        # rounding of terms of the size of the largest entry (sin, cos: numba's libm and numpy's)
        np.testing.assert_allclose(j, jac[i], rtol=1e-13, atol=1e-15 * (1 + np.abs(jac[i]).max()))
        np.testing.assert_allclose(out, ik[i], rtol=1e-13, atol=1e-15)
        assert bool(nb.on_assembly(k.params, xi, qi)) == asm[i]
    # a few rows go through the scalar path (Python floats): the same numbers
    np.testing.assert_allclose(mech.residual(x[inside][:3], q[inside][:3]), res[:3], rtol=1e-13)
    np.testing.assert_allclose(
        mech.jacobian_pose(x[inside][:3], q[inside][:3]), jac[:3], rtol=1e-13
    )
    # the numpy Jacobian is the derivative of the numpy residual (central differences)
    fd = Mechanism.jacobian_pose(mech, x[inside][:50], q[inside][:50])
    np.testing.assert_allclose(jac[:50], fd, rtol=1e-5, atol=1e-6 * np.abs(jac).max())
    # ik solves residual = 0
    np.testing.assert_allclose(mech.residual(x[inside], ik), 0.0, atol=1e-12)
    torch = pytest.importorskip("torch")
    t_res, t_jac = kernels.torch_kernel(k)
    xt, qt = torch.as_tensor(x[inside]), torch.as_tensor(q[inside])
    scale = 1 + np.max(q[inside] ** 2)  # |v|^2 - L^2 cancels; torch's sin/cos are its own
    np.testing.assert_allclose(t_res(xt, qt).numpy(), res, rtol=1e-12, atol=1e-13 * scale)
    np.testing.assert_allclose(t_jac(xt, qt).numpy(), jac, rtol=1e-12, atol=1e-13 * scale)


def test_kernels_import_and_run_without_numba():
    """numba stays optional: the kernel modules and the numpy methods work where it is missing,
    and the compiled path is off."""
    code = (
        "import sys; sys.modules['numba'] = None\n"
        "import numpy as np\n"
        "from parakin import kernels\n"
        "from parakin.kernels import _math\n"
        "kernels._have_numba.cache_clear(); import importlib.util\n"
        "importlib.util.find_spec = lambda n, *a: None if n == 'numba' else _fs(n, *a)\n"
        "from parakin.mechanisms import Stewart36\n"
        "from parakin.solvers import solve_fk\n"
        "m = Stewart36(); q = m.ik(m.home() + 0.01)\n"
        "assert not kernels.enabled()\n"
        "r = solve_fk(m, q, method='newton')\n"
        "assert r.success and r.method == 'newton', r\n"
        "print('ok')\n"
    )
    code = "import importlib.util as _u; _fs = _u.find_spec\n" + code
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"


def test_build_hash_follows_every_source(monkeypatch):
    """A kernel's build directory is named by the hash of the kernel module (and of the kernel
    modules it takes functions from), _math, the drivers, the entries and the options table: an
    edit to any of them is a new directory, never a stale build."""
    from parakin.kernels import _math, drivers, entries, methods
    from parakin.kernels import stewart36 as k36
    from parakin.kernels import stewart66 as k66

    base = store.digest(k36, _math, drivers, entries, methods)
    real = store._source
    for edited in (k36, _math, drivers, entries, methods):
        monkeypatch.setattr(
            store, "_source", lambda m, e=edited: real(m) + (b"# edit" if m is e else b"")
        )
        assert store.digest(k36, _math, drivers, entries, methods) != base, edited.__name__
    monkeypatch.setattr(store, "_source", real)
    # the 6-6 kernel takes the 3-6's functions: its build hashes both files
    kernels._build.cache_clear()
    path66, _ = kernels._build(k66)
    monkeypatch.setattr(store, "_source", lambda m: real(m) + (b"# edit" if m is k36 else b""))
    kernels._build.cache_clear()
    assert kernels._build(k66)[0] != path66
    monkeypatch.setattr(store, "_source", real)
    kernels._build.cache_clear()


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("key", NEAR)
def test_compiled_solves_equal_numpy(key, method, monkeypatch):
    """Same statuses, counters and verification, poses equal to rounding (near starts: no chaos)."""
    mech = MECHS[key]
    truth = _poses(mech, 150, seed=11)
    joints = mech.ik(truth)
    x0 = truth + 0.02 * (mech.home() - truth) + 1e-3
    x0 = np.where(mech.in_domain(x0)[:, None], x0, truth)
    got = solve_fk(mech, joints, x0, method=method, maxiter=200)
    _numpy_path(monkeypatch)
    ref = solve_fk(mech, joints, x0, method=method, maxiter=200)
    np.testing.assert_array_equal(got.status, ref.status)
    np.testing.assert_array_equal(got.success, ref.success)
    # counters equal, except where a rounding-level difference decides the last iteration (a
    # residual at tol, BFGS's long runs of 40+ iterations): a step or two on at most 2 % of rows
    for f in ("nit", "nfev", "njev"):
        a, b = getattr(got, f), getattr(ref, f)
        differ = a != b
        assert differ.mean() <= 0.02 and np.all(
            np.abs(a - b)[differ] <= 2 * (1 + (method == "bfgs") * 30)
        ), f
        if method != "bfgs":
            assert differ.mean() <= 0.01, f
    # poses equal to rounding where both took the same path (BFGS's slow final approach near a
    # singular pose may stop one iteration apart, or at the same one with a residual of 7e-11
    # where cond(J) ~ 1e5: 1e-8 away, within what tol allows there)
    same = got.success & (got.nit == ref.nit)
    atol = 1e-7 if method == "bfgs" else 1e-9
    np.testing.assert_allclose(got.x[same], ref.x[same], rtol=0, atol=atol)
    assert np.all(got.joint_error <= 1e-8) == np.all(ref.joint_error <= 1e-8)
    assert got.message == ref.message
    assert got.success.mean() > 0.9


def test_exactly_singular_step_takes_the_minimum_norm_step(monkeypatch):
    """P3P4S with stroke l1 = 0 at x0 = delta e1: rod 1 is exactly zero, row 1 of J vanishes, the
    LU fails and the compiled step is ``pinv(J) r``: the numpy path's step, the regular row beside
    it unaffected."""
    mech = MECHS["3p4s"]
    joints = np.array([[0.0, 0.3, 0.3], mech.ik([0.01, -0.02, 0.58])])
    x0 = np.array([[mech.delta, 0.0, 0.0], [0.0, 0.0, 0.59]])
    got = solve_fk(mech, joints, x0, method="newton", maxiter=1)
    _numpy_path(monkeypatch)
    ref = solve_fk(mech, joints, x0, method="newton", maxiter=1)
    assert not np.array_equal(got.x[0], x0[0])  # a step was taken
    np.testing.assert_allclose(got.x, ref.x, rtol=0, atol=1e-12)


@pytest.mark.parametrize("method", METHODS)
def test_serial_and_parallel_identical(method):
    mech = Stewart36()
    truth = _poses(mech, 300, seed=3, spread=0.2)
    joints = mech.ik(truth)
    x0 = np.tile(mech.home(), (len(joints), 1))
    a = compiled.solve(mech, method, joints, x0, 1e-10, 50, {}, parallel=False)
    b = compiled.solve(mech, method, joints, x0, 1e-10, 50, {}, parallel=True)
    for f in ("x", "status", "nit", "nfev", "njev", "residual"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
    ha = kernels.verify_hooks(mech, joints, a.x, parallel=False)
    hb = kernels.verify_hooks(mech, joints, a.x, parallel=True)
    for u, v in zip(ha, hb):
        np.testing.assert_array_equal(u, v)


def test_options_and_verification_apply(monkeypatch):
    """xtol / gtol / tau / maxiter reach the compiled loops; success still needs the IK check."""
    mech = Stewart36()
    truth = _poses(mech, 100, seed=8, spread=0.3)
    joints = mech.ik(truth)
    cases = [
        ("newton", {"xtol": 1e-6}),
        ("lm", {"gtol": 1e-3, "tau": 1e-3}),
        ("bfgs", {"maxls": 5, "c1": 1e-3}),
        ("broyden", {"maxiter": 3}),
        ("dogleg", {"factor": 0.01, "eta": 0.2, "xtol": 1e-6}),
    ]
    x0 = truth + 0.01
    for method, opts in cases:
        got = solve_fk(mech, joints, x0, method=method, tol=1e-12, **opts)
        with monkeypatch.context() as m:
            _numpy_path(m)
            ref = solve_fk(mech, joints, x0, method=method, tol=1e-12, **opts)
        np.testing.assert_array_equal(got.status, ref.status)
        np.testing.assert_array_equal(got.nit, ref.nit)
    # a mirror solution (Z < 0) converges but is on the wrong assembly
    below = mech.mirror(truth[:5])
    res = solve_fk(mech, joints[:5], below, method="newton")
    assert np.all(res.status == Status.WRONG_ASSEMBLY)


def test_generic_path_still_used():
    """No kernel: subclasses, other conventions, a callback, an unknown option, bad rows."""
    assert Stewart12(convention="cayley").kernel() is None
    mode = DriveMode(Stewart12())
    assert mode.kernel() is None
    # ActiveLegs: compiled like any mechanism (the drive modes of the cube); not for a Cayley cube
    assert kernels.kernel_of(ActiveLegs()) is not None
    assert ActiveLegs(mech=Stewart12(convention="cayley")).kernel() is None
    calls = []
    mech = Stewart36()
    q = mech.ik(mech.home() + 0.01)
    res = solve_fk(mech, q, method="newton", callback=lambda k, x, r: calls.append(k))
    assert res.success and calls
    with pytest.raises(TypeError):
        solve_fk(mech, q, method="newton", bogus=1)
    bad = np.array([q, np.full(6, np.nan)])
    res = solve_fk(mech, bad, method="lm")
    assert res.success.tolist() == [True, False] and res.status[1] == Status.BAD_INPUT


def test_entries_are_built_once_in_the_cache_directory():
    k = Stewart36().kernel()
    a = kernels.entries_of(k.module, "newton")
    assert kernels.entries_of(k.module, "newton") is a
    path, hash_ = kernels._build(k.module)
    assert path.parent == store.root() and path.name.endswith(hash_)
    solve_fk(Stewart36(), Stewart36().ik(Stewart36().home()), method="newton")
    assert any((path / "newton").rglob("*.nbi"))  # numba's index of the entries, in our directory


def test_known_answer_probe_asks_the_kernel_the_entry_was_built_for():
    """The 6-6's kernel takes its leg equations from the 3-6's module but has an assembly test of
    its own (every assembly). The first call's probe of its verification must ask the 6-6's
    source: asked the 3-6's (``Z > 0``), a first pose below the base failed the probe, and each
    process that met one threw the whole 6-6 build away and compiled it again."""
    mech = mechanisms.REGISTRY["stewart66"]()
    kernel = kernels.kernel_of(mech)
    entry = kernels.entries_of(kernel.module, "verify").verify_serial
    x = mech.home()[None].copy()
    x[0, 5] = -abs(x[0, 5])  # mirrored through the base: an assembly of the 6-6, not of the 3-6
    q = mech.ik(x)
    # first through the entry's own first call (it loads the entry from the cache, tagged, and
    # asks the probe): the numba function called bare before that would compile untagged files
    # into the shared cache, which every later process refuses
    ok, _, on = kernels.verify_hooks(mech, q, x, parallel=False)
    assert ok[0] and on[0]
    flags, err = np.zeros((1, 2), dtype=np.int64), np.empty(1)
    assert store._known_answer(entry.fn, (kernel.params, q, x, flags, err)) is None


@pytest.mark.parametrize("key", [k for k in mechanisms.REGISTRY if k in MECHS])
def test_known_answer_probe_asks_nothing_of_a_pose_whose_answer_overflows(key):
    """A first pose so far out (finite, 1e300 m) that the source's own joint error is not finite
    has no answer to compare: the probe asks nothing. It compared NaN with the compiled inf, and
    the first verification of such a pose (a fuzzed start, a diverged solve) threw away the
    3-6-6 cube's and the 3-RPR's builds and compiled them again."""
    mech = MECHS[key]
    kernel = kernels.kernel_of(mech)
    entry = kernels.entries_of(kernel.module, "verify").verify_serial
    x = mech.home()[None].copy()
    q = mech.ik(x)
    kernels.verify_hooks(mech, q, x, parallel=False)  # loaded through its first call, tagged
    x[0, 0] = 1e300
    flags, err = np.zeros((1, 2), dtype=np.int64), np.empty(1)
    assert store._known_answer(entry.fn, (kernel.params, q, x, flags, err)) is None


def test_entries_are_tagged_before_their_first_call():
    """Every entry's cache is tagged (build, group, name) as soon as it is made: a bare call of
    the numba function before the entry's first call writes what every process accepts."""
    k = Stewart36().kernel()
    path = kernels._build(k.module)[0]
    for group in ("newton", "verify", "pso"):
        fresh = kernels.entries_of.__wrapped__(k.module, group)  # made now, never called
        for name, entry in vars(fresh).items():
            tag = getattr(entry.fn._cache, "_parakin_tag", None)
            assert tag == (path.name, group, entry.fn.py_func.__qualname__), (group, name, tag)


@pytest.mark.parametrize("method", METHODS)
def test_single_call_path_equals_batched(method, monkeypatch):
    """One joint vector per call (the single-call path: solve and verification in one compiled
    call) gives exactly the batched compiled rows, and the numpy path's statuses. A batch reuses
    one set of work arrays for all its rows (``drivers.work``), a single call has its own: a
    loop that read a work array before writing it would make a row depend on the rows before it."""
    for key in [k for k in mechanisms.REGISTRY if k in MECHS]:
        mech = MECHS[key]
        truth = _poses(mech, 12, seed=4, spread=0.3)
        joints = mech.ik(truth)
        batch = solve_fk(mech, joints, method=method)
        for i in range(len(joints)):
            one = solve_fk(mech, joints[i], method=method)
            assert one.shape == () and one.x.shape == (mech.n_pose,)
            np.testing.assert_array_equal(one.x, batch.x[i])
            for f in ("status", "success", "nit", "nfev", "njev", "residual", "joint_error"):
                assert getattr(one, f) == getattr(batch, f)[i], f
            assert one.message == ("converged" if one.success else one.message)
        with monkeypatch.context() as m:
            _numpy_path(m)
            ref = solve_fk(mech, joints[0], method=method)
        assert ref.status == solve_fk(mech, joints[0], method=method).status


def test_single_call_verification_rules():
    """judge_one is verify's rule for one pose: every combination of the three checks."""
    from parakin.solvers.result import FKResult
    from parakin.solvers.verify import judge_one

    mech = Stewart36()
    combos = [
        (s, d, a, e)
        for s in (0, 1, -1)
        for d in (True, False)
        for a in (True, False)
        for e in (0.0, 1.0)
    ]
    for s, d, a, e in combos:
        got = judge_one(s, d, a, e, 0.5)
        # the batched rule, written out as verify() applies it
        want = s
        if s >= 0:
            want = (
                Status.OUT_OF_DOMAIN
                if not d
                else Status.WRONG_ASSEMBLY
                if not a
                else Status.WRONG_ANSWER
                if e > 0.5
                else s
            )
        assert got == want
    # and the single-call path reports WRONG_ASSEMBLY like the batched one (mirror start converges below the base)
    q = mech.ik(mech.home())
    one = solve_fk(mech, q, mech.mirror(mech.home()), method="newton")
    many = solve_fk(mech, q[None], mech.mirror(mech.home())[None], method="newton")
    assert one.status == many.status[0] == Status.WRONG_ASSEMBLY
    assert isinstance(one, FKResult)


def test_solves_from_several_threads_give_the_same_results():
    """Solves started from several threads at once (each split into blocks on the shared pool)
    give the results of one solve from the main thread."""
    import threading

    mech = P3P4S()
    joints = mech.ik(_poses(mech, 500, seed=9))
    ref = solve_fk(mech, joints, method="lm")
    out: list = []
    threads = [
        threading.Thread(target=lambda: out.append(solve_fk(mech, joints, method="lm")))
        for _ in range(3)
    ]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(out) == 3
    for res in out:
        np.testing.assert_array_equal(res.x, ref.x)
        np.testing.assert_array_equal(res.status, ref.status)


def test_prune_removes_only_older_builds_of_the_same_module(tmp_path):
    old, new, other = "0" * 16, "1" * 16, "2" * 16
    names = (f"pkg.a-{old}", f"pkg.a-{new}", f"pkg.ab-{other}", "pkg.a-notahash", "numba")
    for name in names:
        (tmp_path / name / "x").mkdir(parents=True)
    store._prune(tmp_path, "pkg.a")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(names[2:])


def test_a_mechanism_of_ones_own_declares_its_kernel_module(monkeypatch):
    """A mechanism outside parakin (tests/data/toy_kernels.py: the two-leg toy) declares its kernel
    module and parameter vector and nothing else: it gets the numpy methods, the compiled solves
    and the torch solver from that one module."""
    from pathlib import Path

    monkeypatch.syspath_prepend(str(Path(__file__).parent / "data"))
    from toy_mechanism import KernelTwoLeg
    from toy_study import TwoLeg

    plain, fast = TwoLeg(), KernelTwoLeg()
    lo, hi = plain.pose_bounds()
    x = np.random.default_rng(0).uniform(lo, hi, (40, 2))
    q = plain.ik(x) + 1e-3
    np.testing.assert_allclose(fast.residual(x, q), plain.residual(x, q), rtol=0, atol=1e-14)
    np.testing.assert_allclose(fast.ik(x), plain.ik(x), rtol=1e-15)
    fd = Mechanism.jacobian_pose(plain, x, q)
    np.testing.assert_allclose(fast.jacobian_pose(x, q), fd, rtol=1e-6)
    assert kernels.kernel_of(fast) is not None and kernels.kernel_of(plain) is None
    one = solve_fk(fast, plain.ik(x[0]), method="newton")  # compiled (numba) single call
    ref = solve_fk(plain, plain.ik(x[0]), method="newton")  # generic numpy path
    assert one.success and ref.success
    np.testing.assert_allclose(one.x, x[0], atol=1e-9)
    torch = pytest.importorskip("torch")
    from parakin.solvers.torch_newton import newton_torch

    res = newton_torch(fast, plain.ik(x), None, device="cpu")
    assert res.success.all()
    np.testing.assert_allclose(res.x, x, atol=1e-9)
    assert torch.is_tensor(kernels.torch_kernel(fast.kernel())[0](torch.zeros(2), torch.ones(2)))


def test_the_cube_drive_modes_run_compiled_and_agree_with_numpy(monkeypatch):
    """ActiveLegs (the 12-leg cube driven by a subset of its legs, square or least squares) runs
    the same compiled loops as every mechanism: the statuses and poses of the numpy path."""
    for mech in _kernel_cases()["active6"], _kernel_cases()["active8"]:
        truth = _poses(mech, 100, seed=12, spread=0.3)
        joints = mech.ik(truth)
        got = solve_fk(mech, joints, method="lm", maxiter=100)
        with monkeypatch.context() as m:
            _numpy_path(m)
            ref = solve_fk(mech, joints, method="lm", maxiter=100)
        np.testing.assert_array_equal(got.status, ref.status)
        same = got.success & (got.nit == ref.nit)
        assert same.mean() > 0.95
        np.testing.assert_allclose(got.x[same], ref.x[same], rtol=0, atol=1e-9)


@pytest.mark.parametrize("method", ["newton", "dogleg"])
def test_stewart66_newton_compiled_equals_numpy(method, monkeypatch):
    """The 6-6's kernel (the 3-6's leg equations over six platform points) drives the compiled
    Newton and dog leg: from near starts the numpy path's statuses and poses."""
    mech = MECHS["stewart66"]
    truth = _poses(mech, 100, seed=13, spread=0.05)
    joints = mech.ik(truth)
    x0 = truth + 0.01 * (mech.home() - truth)
    got = solve_fk(mech, joints, x0, method=method)
    _numpy_path(monkeypatch)
    ref = solve_fk(mech, joints, x0, method=method)
    np.testing.assert_array_equal(got.status, ref.status)
    assert got.success.mean() > 0.9
    np.testing.assert_allclose(got.x[got.success], ref.x[got.success], rtol=0, atol=1e-9)


def test_kernel_goals_report_success_beside_speed():
    """Every timed solve of the goals table carries the success rate of the solves it timed (the
    6-6's pure Newton from home on its whole pose box fails there: a fast failure is not speed)."""
    from parakin.bench import _sample, _solver_goals, format_goals

    mech = MECHS["stewart66"]
    rows = pd.DataFrame(_solver_goals(mech, n_single=4, n_batch=30, repeats=1))
    rows = rows.set_index("what")
    _, q1 = _sample(mech, 4, seed=17)
    _, q2 = _sample(mech, 30, seed=18)
    single = np.mean([bool(solve_fk(mech, q, method="newton", maxiter=100).success) for q in q1])
    assert rows.loc["newton single call", "success_rate"] == single
    assert rows.loc["newton single call vs scipy", "success_rate"] == single
    batched = solve_fk(mech, q2, method="newton", maxiter=100).success.mean()
    assert rows.loc["newton batched", "success_rate"] == batched
    assert rows["success_rate"].between(0, 1).all()
    table = format_goals(rows.reset_index())
    assert "| success |" in table.splitlines()[0]
    assert f"| {single:.1%} |" in table


def test_the_machine_line_names_what_tells_two_machines_apart():
    """Timings name their machine (``parakin bench --peers``): the model name alone ("AMD EPYC")
    is the same for processors twice apart in speed, so the line carries the compiler's target,
    the SIMD width and the CPUs, each read here from the source the function must have used."""
    import os
    from pathlib import Path

    import llvmlite.binding as llvm

    from parakin.timing import machine

    line = machine()
    assert f"{len(os.sched_getaffinity(0))} CPUs" in line
    assert llvm.get_host_cpu_name() in line
    if Path("/proc/cpuinfo").exists():
        flags = next(
            ln for ln in Path("/proc/cpuinfo").read_text().splitlines() if ln.startswith("flags")
        )
        widest = "AVX-512" if " avx512f" in flags else "AVX2" if " avx2" in flags else None
        if widest:
            assert f", {widest})" in line
            assert ("AVX-512" in line) == (" avx512f" in flags)


def test_one_input_latency_runs_on_one_thread():
    """The 6-6's ``<= 1 ms`` goal is one input per call on one thread (issue 29): the timed calls
    see numba's pool at one thread, and the caller's setting comes back after."""
    import numba

    from parakin.bench import _one_thread_median

    seen = []
    before = numba.get_num_threads()
    t = _one_thread_median(lambda item: seen.append((item, numba.get_num_threads())), [1, 2, 3], 2)
    assert seen == [(1, 1), (2, 1), (3, 1)] * 2
    assert numba.get_num_threads() == before
    assert 0 <= t < 1


_ONE_PROCESS = """
import numpy as np
from parakin.mechanisms import Stewart36, Stewart66
from parakin.solvers import solve_fk
m36, m66 = Stewart36(), Stewart66()
solve_fk(m66, m66.ik(m66.home()), method="newton")  # the 6-6's entries loaded first
rng = np.random.default_rng(17)
lo, hi = m36.pose_bounds()
x = rng.uniform(lo, hi, (300, 6))
q = m36.ik(x[m36.in_domain(x)][:100])
r = [solve_fk(m36, qq, method="newton", maxiter=100) for qq in q]
ok = np.array([bool(s.success) for s in r])
print(int(ok.sum()), int(m36.on_assembly(np.array([s.x for s in r])[ok], q[ok]).sum()))
"""


@pytest.mark.slow  # fresh processes that compile
def test_kernels_sharing_functions_keep_their_own_entries():
    """The 6-6's kernel takes the 3-6's functions but not its assembly test: a process that loads
    both kernels' cached entries (the second run here) verifies each solve by its own kernel (once,
    the 3-6's single solves were judged by the 6-6's test: a third of their successes on the
    wrong assembly)."""
    for _ in range(2):  # the first run may compile and cache; the second loads both from the cache
        out = subprocess.run(
            [sys.executable, "-c", _ONE_PROCESS], capture_output=True, text=True, check=True
        )
        successes, on_assembly = map(int, out.stdout.split())
        assert successes > 0 and on_assembly == successes


def _fresh_chain():
    """Three numba functions not compiled yet, each calling the next: ``(theirs, ours, outer)``,
    ``outer(x) = 2 (x + 1) - 1``."""
    numba = pytest.importorskip("numba")

    @numba.njit
    def theirs(x):
        return x + 1.0

    @numba.njit
    def ours(x):
        return theirs(x) * 2.0

    @numba.njit
    def outer(x):
        return ours(x) - 1.0

    return theirs, ours, outer


@contextmanager
def _at_compile_start(state):
    """While the block runs, ``(function name, state())`` at the start of every numba compile (a
    listener registered after parakin's: it sees what they set)."""
    from numba.core import event

    seen = []

    class Probe(event.Listener):
        def on_start(self, ev):
            seen.append((ev.data["dispatcher"].py_func.__name__, state()))

        def on_end(self, ev):
            pass

    probe = Probe()
    event.register("numba:compile", probe)
    try:
        yield seen
    finally:
        event.unregister("numba:compile", probe)


def test_the_garbage_collector_pauses_while_numba_compiles_and_comes_back():
    """``store.no_gc_while_compiling``: during a compile (its callees' included) Python's cyclic
    collector is off; after it, on again, also after a compile that raised; a collector the user
    turned off stays off."""
    import gc

    numba = pytest.importorskip("numba")
    store.no_gc_while_compiling()
    outer = _fresh_chain()[-1]

    @numba.njit
    def broken(x):
        return x.no_such_attribute

    @numba.njit
    def later(x):
        return x - 1.0

    was_on = gc.isenabled()
    try:
        with _at_compile_start(gc.isenabled) as seen:
            gc.enable()
            assert outer(1.0) == 3.0
            assert seen == [("outer", False), ("ours", False), ("theirs", False)]
            assert gc.isenabled()
            with pytest.raises(numba.core.errors.TypingError):
                broken(1.0)
            assert gc.isenabled()
            gc.disable()
            assert later(1.0) == 0.0
            assert not gc.isenabled()
    finally:
        (gc.enable if was_on else gc.disable)()


def test_functions_declared_at_an_llvm_level_compile_at_it_and_others_at_numbas(monkeypatch):
    """``store.share_compiles(..., llvm_level=)`` (the 6-6 tracker's modules declare 2): such a
    function compiles at that level, and a function it calls, or that calls it, at numba's own;
    numba's level is restored after."""
    from numba.core import config

    monkeypatch.delenv("NUMBA_OPT", raising=False)
    _, ours, outer = _fresh_chain()
    store.share_compiles({"ours": ours}, llvm_level=1)
    numba_level = int(config.OPT)
    with _at_compile_start(lambda: int(config.OPT)) as seen:
        assert outer(1.0) == 3.0
    assert dict(seen) == {"outer": numba_level, "ours": 1, "theirs": numba_level}
    assert int(config.OPT) == numba_level
