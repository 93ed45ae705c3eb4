"""The kernel cache cannot lie (issue 30): every fault planted here ends in a right answer, or a
right answer and a one-line notice, never a traceback and never a stale or edited build.

The faults: a cache directory that cannot be written, a filled cache that is read-only, a corrupt
numba index or data file, a kernel edited on disk, and numba caches beside the sources. Each runs
in a fresh process with its own cache directory (``PARAKIN_KERNEL_CACHE``); the compiled solves
use the toy two-leg kernel of ``tests/data/toy_kernels.py`` (small: it compiles in seconds). No
timing is asserted.
"""

from __future__ import annotations

import os
import shutil
import stat
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

pytest.importorskip("numba")

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"

#: a compiled Newton solve of the toy kernel in a fresh process: prints the answer's error
SOLVE = textwrap.dedent(
    """
    import numpy as np
    from parakin import kernels
    from parakin.solvers import solve_fk
    from toy_mechanism import KernelTwoLeg as Toy

    m = Toy()
    truth = np.array([0.1, 0.9])
    res = solve_fk(m, m.ik(truth), method="newton")
    print("compiled" if kernels.kernel_of(m) is not None else "numpy")
    print(f"error {float(np.abs(res.x - truth).max()):.3g} success {bool(res.success)}")
    """
)


def _env(cache: Path, **extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "PARAKIN_KERNELS")}
    env.update(
        PARAKIN_KERNEL_CACHE=str(cache),
        PYTHONPATH=os.pathsep.join([str(DATA), str(ROOT / "src"), env.get("PYTHONPATH", "")]),
        XDG_CACHE_HOME=str(cache.parent / "xdg"),  # the per-user fallback, inside the test's dir
    )
    env.update(extra)
    return env


def _run(code: str, env: dict[str, str], cwd: Path) -> subprocess.CompletedProcess:
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, cwd=cwd, capture_output=True, text=True, timeout=900
    )
    assert "Traceback" not in out.stderr, out.stderr[-3000:]
    assert out.returncode == 0, out.stderr[-3000:]
    return out


def _notices(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if line.startswith("parakin:")]


def _solved(out: subprocess.CompletedProcess, path: str = "compiled") -> None:
    lines = out.stdout.split("\n")
    assert lines[0] == path, out.stdout
    error = float(lines[1].split()[1])
    assert error < 1e-9 and lines[1].endswith("success True"), out.stdout


@pytest.fixture(scope="module")
def warm(tmp_path_factory) -> Path:
    """A cache filled by one compiled solve of the toy kernel (copied by the tests that break it)."""
    cache = tmp_path_factory.mktemp("warm") / "cache"
    out = _run(SOLVE, _env(cache), cache.parent)
    _solved(out)
    assert not _notices(out.stderr), out.stderr
    return cache


def _copy(warm: Path, tmp_path: Path) -> Path:
    cache = tmp_path / "cache"
    shutil.copytree(warm, cache)
    return cache


def _without_builds(warm: Path, tmp_path: Path) -> Path:
    """A cache with no kernel's build in it, only numba's part of the warm one: the solver loops'
    shared linear algebra, which calls no kernel and which every fresh process here would
    otherwise compile again (about 3.5 of its CPU-s). What these tests build and count, the
    kernels' entries, starts from nothing."""
    cache = tmp_path / "cache"
    shutil.copytree(warm / "numba", cache / "numba")
    return cache


@pytest.mark.slow  # fresh processes that compile (the warm cache)
def test_warm_cache_is_used_and_lives_in_one_directory(warm, tmp_path):
    """The second process solves from the cache; every compiled file is under the cache directory
    (kernel builds named by their hash, numba's own part in numba/), none beside the sources."""
    cache = _copy(warm, tmp_path)
    before = {p: p.stat().st_mtime_ns for p in cache.rglob("*.nb*")}
    out = _run(SOLVE, _env(cache), tmp_path)
    _solved(out)
    assert not _notices(out.stderr)
    assert {p: p.stat().st_mtime_ns for p in cache.rglob("*.nb*")} == before  # loaded, not rebuilt
    builds = [p.name for p in cache.iterdir() if p.is_dir()]
    assert any(b.startswith("toy_kernels-") for b in builds), builds
    assert not list((ROOT / "src").rglob("*.nbi")) and not list((ROOT / "src").rglob("*.nbc"))
    assert not list(DATA.rglob("*.nbi"))


def test_unwritable_cache_directory_falls_back_with_a_notice(tmp_path):
    """PARAKIN_KERNEL_CACHE under a regular file (cannot be created, whoever runs the test): one
    notice line, then the per-user cache."""
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    code = (
        "from parakin.kernels import store\n"
        "print(store.root())\n"
        "from parakin.mechanisms import P3P4S\n"
        "m = P3P4S(); print(abs(m.fk(m.ik([0.01, 0.0, 0.58]))[0] - 0.01) < 1e-12)\n"
    )
    out = _run(code, _env(blocker / "cache", XDG_CACHE_HOME=str(tmp_path / "xdg")), tmp_path)
    notes = _notices(out.stderr)
    assert len(notes) == 1 and "is not a directory" in notes[0] and "per-user cache" in notes[0]
    assert out.stdout.split() == [str(tmp_path / "xdg" / "parakin" / "kernels"), "True"]


def test_no_writable_location_runs_the_numpy_path(tmp_path, monkeypatch, caplog):
    """Every candidate unwritable (as no user can make them writable: paths under a regular file):
    one notice per step, then the compiled path is off and the numpy path answers."""
    import numpy as np

    from parakin import kernels
    from parakin.kernels import store
    from parakin.mechanisms import P3P4S
    from parakin.solvers import solve_fk

    blocker = tmp_path / "file"
    blocker.write_text("")
    paths = [("a", blocker / "a"), ("b", blocker / "b"), ("c", blocker / "c")]
    monkeypatch.setattr(store, "_candidates", lambda: paths)
    store.root.cache_clear()
    try:
        with caplog.at_level("WARNING", logger="parakin.kernels"):
            assert store.root() is None and not kernels.enabled()
        notes = [r.getMessage() for r in caplog.records]
        assert len(notes) == 3 and notes[-1].endswith("no disk cache (numpy path)"), notes
        m = P3P4S()
        truth = np.array([0.01, -0.02, 0.58])
        res = solve_fk(m, m.ik(truth), method="newton")
        assert res.success and np.abs(res.x - truth).max() < 1e-9
    finally:
        store.root.cache_clear()


@pytest.mark.slow  # fresh processes that compile (the warm cache)
def test_read_only_filled_cache_falls_back_with_a_notice(warm, tmp_path):
    cache = _copy(warm, tmp_path)
    for p in [cache, *cache.rglob("*")]:
        p.chmod(p.stat().st_mode & ~(stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))
    try:
        probe = cache / "probe"
        try:
            probe.mkdir()
        except OSError:
            pass
        else:
            pytest.skip("this user writes into read-only directories (root)")
        out = _run(SOLVE, _env(cache), tmp_path)
    finally:
        for p in [cache, *cache.rglob("*")]:
            p.chmod(p.stat().st_mode | stat.S_IWUSR)
    notes = _notices(out.stderr)
    assert len(notes) == 1 and "is not writable" in notes[0], out.stderr
    _solved(out)


@pytest.mark.parametrize("what", ["index", "data"])
@pytest.mark.slow  # fresh processes that compile
def test_corrupt_cache_file_is_rebuilt_with_a_notice(warm, tmp_path, what):
    """A numba index (.nbi) or data file (.nbc) of the build overwritten with garbage: the solve
    rebuilds that entry (one notice line) and answers right; the next process is quiet again.
    The same for the files of numba's part of the cache (the drivers' shared linear algebra):
    each is compiled again, with a notice that names it."""
    cache = _copy(warm, tmp_path)
    files = sorted(cache.rglob("*.nbi" if what == "index" else "*.nbc"))
    assert files and any(f.parts[-3] == "numba" for f in files), files
    for f in files:
        f.write_bytes(b"\x80\x04garbage, not a pickle" * 3)
    out = _run(SOLVE, _env(cache), tmp_path)
    _solved(out)
    notes = _notices(out.stderr)
    assert notes and all("could not be read" in n and "rebuilt" in n for n in notes), out.stderr
    assert any(f"{os.sep}numba{os.sep}" in n for n in notes), notes
    again = _run(SOLVE, _env(cache), tmp_path)
    _solved(again)
    assert not _notices(again.stderr)


@pytest.mark.slow  # fresh processes that compile
def test_a_kernel_edited_on_disk_is_never_served_stale(warm, tmp_path):
    """The kernel module changed after its build was cached (its assembly test now rejects every
    pose below y = 5 m): the edited source gets a build of its own (a new hash), and the answer is
    the edited kernel's (a wrong assembly, not the success a stale build would report)."""
    cache = _copy(warm, tmp_path)
    data = tmp_path / "data"
    shutil.copytree(DATA, data, ignore=shutil.ignore_patterns("__pycache__"))
    kern = data / "toy_kernels.py"
    text = kern.read_text()
    marker = '"""Every pose of the domain is the working assembly."""\n    return x[1] > 0'
    assert marker in text
    kern.write_text(text.replace(marker, marker.replace("x[1] > 0", "x[1] > 5.0")))
    env = _env(cache)
    env["PYTHONPATH"] = env["PYTHONPATH"].replace(str(DATA), str(data))
    out = _run(SOLVE.replace("success {", "status {int(res.status)} success {"), env, tmp_path)
    lines = out.stdout.split("\n")
    assert lines[0] == "compiled", out.stdout
    assert lines[1].split()[2:] == ["status", "-6", "success", "False"], (
        out.stdout
    )  # WRONG_ASSEMBLY
    builds = sorted(p.name for p in cache.iterdir() if p.name.startswith("toy_kernels-"))
    assert len(builds) == 1 and builds[0] not in {p.name for p in warm.iterdir()}


@pytest.mark.slow  # fresh processes that compile (the warm cache)
def test_cli_kernels_status_and_clear(warm, tmp_path):
    cache = _copy(warm, tmp_path)
    env = _env(cache)
    status = subprocess.run(
        [sys.executable, "-m", "parakin.cli", "kernels", "--status"],
        env=env,
        capture_output=True,
        text=True,
    )
    assert status.returncode == 0 and str(cache) in status.stdout, status.stderr
    assert "toy_kernels" in status.stdout
    (cache / "unrelated").mkdir()  # --clear removes parakin's builds only
    clear = subprocess.run(
        [sys.executable, "-m", "parakin.cli", "kernels", "--clear"],
        env=env,
        capture_output=True,
        text=True,
    )
    assert clear.returncode == 0 and "removed" in clear.stdout, clear.stderr
    assert [p.name for p in cache.iterdir()] == ["unrelated"]


#: a worker of the race below: ``rounds`` first calls of the toy kernel's compiled verification
#: (its IK round trip) on random poses, each after the kernel's sources changed (as a re-clone or
#: a checkout does: a new hash, a new build); one output line per round: the flags, the error of
#: the joint error, and whether every build this process has used is still on disk
RACE = textwrap.dedent(
    """
    import os, sys
    import numpy as np
    from parakin import kernels
    from toy_mechanism import KernelTwoLeg as Toy
    import toy_kernels

    m = Toy()
    lo, hi = m.pose_bounds()
    rng = np.random.default_rng(int(sys.argv[1]))
    source = toy_kernels.__file__
    text, used = open(source).read(), []  # the builds this process has used
    for r in range(int(sys.argv[2])):
        with open(source + ".new", "w") as f:  # the same sources in every process at round r
            f.write(text + f"\\n# round {r}\\n")
        os.replace(source + ".new", source)
        # forget the loaded build: the next call looks the kernel directory up and loads (or
        # compiles) its entries again, as a new process would, without a new process's start-up
        for fn in (kernels._build, kernels.compiled, kernels.entries_of):
            fn.cache_clear()
        x = rng.uniform(lo, hi, (6, 2))
        shift = rng.uniform(-1e-3, 1e-3, 6)
        q = m.ik(x)
        q[:, 0] += shift  # the joint error of row i is |shift[i]|
        ok, err, asm = kernels.verify_hooks(m, q, x, parallel=False)
        used.append(kernels._build(toy_kernels)[0])
        kept = all(any(path.rglob("entries.verify_serial*.nbi")) for path in used)
        error = float(np.abs(err - np.abs(shift)).max())
        print(bool(ok.all() and asm.all()), error, kept, flush=True)
    """
)


def _racer(seed: int, rounds: int, cache: Path, tmp_path: Path) -> subprocess.Popen:
    """A :data:`RACE` worker on its own copy of the toy kernel's sources."""
    clone = tmp_path / f"clone{seed}"
    shutil.copytree(DATA, clone, ignore=shutil.ignore_patterns("__pycache__"))
    env = _env(cache)
    env["PYTHONPATH"] = env["PYTHONPATH"].replace(str(DATA), str(clone))
    return subprocess.Popen(
        [sys.executable, "-c", RACE, str(seed), str(rounds)],
        env=env,
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _raced(proc: subprocess.Popen, rounds: int) -> None:
    """Every round of a :data:`RACE` worker answered right, without a traceback or a notice."""
    stdout, stderr = proc.communicate(timeout=900)
    assert proc.returncode == 0 and "Traceback" not in stderr, stderr[-3000:]
    assert not _notices(stderr), stderr
    lines = stdout.split("\n")[:-1]
    assert len(lines) == rounds, stdout
    for line in lines:
        flags, error, kept = line.split()
        assert flags == "True" and float(error) < 1e-12 and kept == "True", stdout


@pytest.mark.slow  # fresh processes that compile
def test_processes_sharing_a_cache_never_pull_a_build_from_under_each_other(tmp_path):
    """Re-clones and checkouts beside running processes (issue 30's CI flake): three processes,
    each with its own copy of the kernel's sources, share a cache; each changes its sources before
    each of several first calls (processes at the same round share a hash and a build, the others'
    builds are of other hashes, older or newer). Every answer is right (the IK round trip gives the
    planted joint error back) and no process sees a build removed while it loads or compiles it
    (no traceback, no rebuild notice). A process started after them, when none is left to use the
    older builds, removes them."""
    cache, rounds = tmp_path / "cache", 4
    for proc in [_racer(seed, rounds, cache, tmp_path) for seed in range(3)]:
        _raced(proc, rounds)
    _raced(_racer(3, 1, cache, tmp_path), 1)  # round 0's sources again, nobody else running
    builds = [p.name for p in cache.iterdir() if p.name.startswith("toy_kernels-")]
    assert len(builds) == 1, builds


#: one method's compiled single solve of the toy kernel, its counters printed (argv: methods)
COUNTERS = textwrap.dedent(
    """
    import sys
    import numpy as np
    from parakin import kernels
    from parakin.solvers import solve_fk
    from toy_mechanism import KernelTwoLeg as Toy

    m = Toy()
    q = m.ik(np.array([0.1, 0.9]))
    for method in sys.argv[1:]:
        assert kernels.kernel_of(m) is not None
        got = solve_fk(m, q, [0.2, 0.7], method=method)
        with kernels.interpreted():
            ref = solve_fk(m, q, [0.2, 0.7], method=method)
        print(method, *(int(getattr(r, f)) for r in (got, ref) for f in ("nit", "nfev", "njev")))
    """
)


@pytest.mark.slow  # fresh processes that compile
def test_entries_built_by_separate_processes_keep_their_own_loops(warm, tmp_path):
    """Every method's entries share their source (``parakin.kernels.entries``) and differ only in
    the loop bound into them. Each built by a fresh process (where numba numbers its functions
    alike), then loaded together by a third: each method still runs its own loop (the counters of
    the numpy path), not the loop of the build that another entry of the same name linked first."""
    cache = _without_builds(warm, tmp_path)
    env = _env(cache)
    env["PYTHONPATH"] = os.pathsep.join([str(DATA), env["PYTHONPATH"]])
    methods = ["newton", "dogleg", "broyden"]
    for method in methods:  # each group compiled first thing in its own process
        _run(COUNTERS.replace("sys.argv[1:]", repr([method])), env, tmp_path)
    out = _run(COUNTERS.replace("sys.argv[1:]", repr(methods)), env, tmp_path)
    rows = [line.split() for line in out.stdout.splitlines()]
    assert [r[0] for r in rows] == methods, out.stdout
    for method, *counts in rows:
        assert counts[:3] == counts[3:], (
            f"{method}: compiled (nit, nfev, njev) {counts[:3]} != numpy {counts[3:]}"
        )


@pytest.mark.slow  # fresh processes that compile
def test_kernel_functions_compiled_outside_an_entry_are_tagged(warm, tmp_path):
    """A loop that calls a kernel's compiled functions directly (the workspace's do) may compile
    them first: what it writes carries the build's tags, so the entries load it after, with no
    notice and no rebuild (untagged, the next solve found "an entry without tags" and rebuilt)."""
    cache = _without_builds(warm, tmp_path)
    env = _env(cache)
    direct = textwrap.dedent(
        """
        import numpy as np
        import toy_kernels
        from parakin import kernels

        nb = kernels.compiled(toy_kernels)
        out = np.empty(2)
        nb.residual(np.array([0.5]), np.array([0.1, 0.9]), np.array([1.0, 1.0]), out)
        print(np.isfinite(out).all())
        """
    )
    first = _run(direct, env, tmp_path)
    assert first.stdout.split() == ["True"] and not _notices(first.stderr), first.stderr
    out = _run(SOLVE, env, tmp_path)
    _solved(out)
    assert not _notices(out.stderr), out.stderr


@pytest.mark.slow  # fresh processes that compile
def test_two_processes_on_an_empty_cache_compile_an_entry_once(warm, tmp_path):
    """Two processes that need the same entries at once: one compiles them, the other waits and
    loads what it wrote (numba's cache statistics of the single-call entry: one miss between the
    two, where both compiled beside each other before the group lock)."""
    cache = _without_builds(warm, tmp_path)
    env = _env(cache)
    code = textwrap.dedent(
        """
        import numpy as np
        from parakin import kernels
        from parakin.solvers import solve_fk
        from toy_mechanism import KernelTwoLeg as Toy

        m = Toy()
        res = solve_fk(m, m.ik(np.array([0.1, 0.9])), method="lm")
        entry = kernels.entries_of(kernels.kernel_of(m).module, "lm").serial.fn
        print(bool(res.success), len(entry.stats.cache_misses), len(entry.stats.cache_hits))
        """
    )
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", code], env=env, cwd=tmp_path, stdout=subprocess.PIPE, text=True
        )
        for _ in range(2)
    ]
    outs = [p.communicate(timeout=900)[0].split() for p in procs]
    assert all(p.returncode == 0 for p in procs), outs
    assert sorted(outs) == [["True", "0", "1"], ["True", "1", "0"]], outs


#: a module of plain ``cache=True`` functions (a caller and its callee), shared as parakin's are
SHARED_MODULE = textwrap.dedent(
    """
    import numpy as np
    from numba import njit

    from parakin.kernels import store

    @njit(cache=True)
    def inner(a):
        s = 0.0
        for i in range(a.shape[0]):
            for j in range(a.shape[1]):
                s += np.sin(a[i, j]) * np.cos(a[j, i]) if i != j else np.sqrt(abs(a[i, j]))
        return s

    @njit(cache=True)
    def outer(a):
        return inner(a) + inner(a.T.copy()) + np.linalg.norm(a)

    store.share_compiles(vars())
    """
)
#: both processes announce themselves, wait for each other, then call (prints misses, hits)
SHARED_CALL = textwrap.dedent(
    """
    import os, sys, time
    from pathlib import Path
    import numpy as np
    import shared_module as m

    Path(f"ready-{os.getpid()}").touch()
    while len(list(Path(".").glob("ready-*"))) < 2:
        time.sleep(0.01)
    m.outer(np.ones((3, 3)))
    print(len(m.outer.stats.cache_misses), len(m.outer.stats.cache_hits))
    """
)


@pytest.mark.slow  # fresh processes that compile
def test_two_processes_compile_a_shared_numba_function_once(tmp_path):
    """A plain ``cache=True`` function (numba's part of the cache, as the 6-6 tracker's) needed by
    two processes at the same moment on an empty cache: one compiles it, the other waits for it
    and loads it (one miss between the two; both compiled it without the lock)."""
    (tmp_path / "shared_module.py").write_text(SHARED_MODULE)
    env = _env(tmp_path / "cache")
    env["PYTHONPATH"] = os.pathsep.join([str(tmp_path), env["PYTHONPATH"]])
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", SHARED_CALL],
            env=env,
            cwd=tmp_path,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )  # fmt: skip
        for _ in range(2)
    ]
    outs = [p.communicate(timeout=900) for p in procs]
    assert all(p.returncode == 0 for p in procs), outs
    assert sorted(o[0].split() for o in outs) == [["0", "1"], ["1", "0"]], outs


def test_a_failed_compile_releases_its_lock(tmp_path, monkeypatch):
    """A shared function whose compile raises (a type error) holds no lock afterwards: another
    process would otherwise wait on it for as long as this one lives."""
    import numba

    from parakin.kernels import store

    monkeypatch.setattr(store, "root", lambda: tmp_path)

    @numba.njit(cache=True)
    def half(x):
        return x / 2

    store.share_compiles({"half": half})
    with pytest.raises(numba.TypingError):
        half("text")
    assert store._COMPILING == {}


#: the workspace's compiled classification of rpr3 against its numpy path (prints: equal?)
CLASSIFY = textwrap.dedent(
    """
    import numpy as np
    from parakin.mechanisms import get
    from parakin.workspace import classify, make_region

    region = make_region(get("rpr3")())
    x = np.random.default_rng(1).uniform(region.lo, region.hi, size=(300, region.dim))
    a = classify(region, x, compiled=True, cond=False)
    b = classify(region, x, compiled=False, cond=False)
    print(type(a).__name__, bool(np.array_equal(a.member, b.member)))
    """
)

#: a kernel function of rpr3 compiled into its build without the tags (as a foreign file would be)
UNTAGGED = textwrap.dedent(
    """
    import numba
    import numpy as np
    import parakin.kernels.rpr3 as mod
    from parakin import kernels
    from parakin.kernels import _math, store
    from parakin.mechanisms import get

    path, _ = kernels._build(mod)
    with store.numba_cache(path / "kernel"):
        ns = _math.rebind(mod, _math.numba_names(numba.njit), numba.njit(cache=True))
    q = np.empty(3)
    print(ns.ik(kernels.kernel_of(get("rpr3")()).params, np.array([0.0, 0.0, 0.0]), q))
    """
)


@pytest.mark.slow  # fresh processes that compile
def test_a_loop_that_meets_a_foreign_kernel_file_rebuilds_the_kernels_build(tmp_path):
    """The workspace's loops live in a build of their own and call the kernel's functions: a
    foreign (untagged) file of a kernel function met through them makes the kernel's build again,
    with one notice, and the classification is right; the next process is quiet (it was refused
    with CacheMismatch on every call, since only the loop's own build was remade)."""
    cache = tmp_path / "cache"
    env = _env(cache)
    _run(UNTAGGED, env, tmp_path)
    out = _run(CLASSIFY, env, tmp_path)
    notes = _notices(out.stderr)
    assert len(notes) == 1 and "without tags" in notes[0] and notes[0].endswith("rebuilt"), notes
    assert "parakin.kernels.rpr3-" in notes[0] and ".workspace-" not in notes[0], notes
    assert out.stdout.split()[-1] == "True", out.stdout
    again = _run(CLASSIFY, env, tmp_path)
    assert not _notices(again.stderr) and again.stdout.split()[-1] == "True", again.stderr
