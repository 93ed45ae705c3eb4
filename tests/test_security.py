"""Nobody else's code, nobody else's files (issue 46): parakin as another local user would attack it.

The threat model is docs/security.md: another user of the machine, who can create names in shared
directories (``/tmp``) and hand over hostile files, but cannot write the victim's own files. What
is checked here:

* the kernel cache: a directory another user owns, one anyone can write, a symbolic link, a
  directory under one another user can rename are never used (no pickle in them is ever read: a
  planted one would run code); one line says so and the numpy path answers;
* cached code is what it claims: another kernel's compiled entry swapped in by its index or by
  its data file, or re-tagged to pass as this kernel's, is rebuilt with one line, and the answer
  is right;
* outputs: the umask and an existing file's mode are kept; a symlinked target, temporary name or
  lock file is never followed;
* hostile inputs: bombs, deep nesting, devices and FIFOs, through every surface (``--config``,
  ``--param``, ``--geometry``, ``--mechanism``, ``--trajectory``): one line, exit 2, at once;
  Ctrl-C: one line, exit 130; NaN in ``--json``: ``null`` beside the flag that says why.

CI runs as root: the foreign-owned cases ``chown`` to ``nobody``; elsewhere they skip, saying why.
The compiled cases use the small toy kernel of ``tests/data`` (its verification entries compile in
seconds), each victim in a fresh process with its own cache.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import pickle
import shutil
import signal
import stat
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from parakin.cli import main

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"

try:
    import pwd

    NOBODY = pwd.getpwnam("nobody").pw_uid
except (ImportError, KeyError):
    NOBODY = None

as_root = pytest.mark.skipif(
    not hasattr(os, "geteuid") or os.geteuid() != 0 or NOBODY is None,
    reason="making a directory another user owns needs root and a 'nobody' user (CI runs as root)",
)


def run(argv: list[str]) -> tuple[int, str, str]:
    """``main(argv)`` in process: exit status, stdout, stderr."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 2
    return code, out.getvalue(), err.getvalue()


def one_line(code: int, stderr: str, *needles: str) -> str:
    lines = stderr.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "Traceback" not in stderr, (code, stderr[-2000:])
    assert all(n in lines[0] for n in needles), (needles, lines[0])
    return lines[0]


# ------------------------------------------------------------------ the cache directory
def _mode(path: Path) -> int:
    return stat.S_IMODE(os.lstat(path).st_mode)


def test_a_new_cache_directory_is_made_0700(tmp_path):
    from parakin.kernels.store import _unsafe

    assert _unsafe(tmp_path / "a" / "cache") is None
    assert _mode(tmp_path / "a" / "cache") == 0o700


def test_an_own_directory_others_can_read_is_tightened_to_0700(tmp_path):
    from parakin.kernels.store import _unsafe

    path = tmp_path / "cache"
    path.mkdir(mode=0o755)
    path.chmod(0o755)
    assert _unsafe(path) is None and _mode(path) == 0o700


@pytest.mark.parametrize("mode", [0o777, 0o770, 0o1777])
def test_a_directory_others_can_write_is_refused(tmp_path, mode):
    from parakin.kernels.store import _unsafe

    path = tmp_path / "cache"
    path.mkdir()
    path.chmod(mode)
    assert "writable by other users" in _unsafe(path)
    assert _mode(path) == mode  # refused, not repaired: someone else may have planted files


def test_a_symlinked_cache_directory_is_refused(tmp_path):
    from parakin.kernels.store import _unsafe

    real = tmp_path / "real"
    real.mkdir(mode=0o700)
    (tmp_path / "link").symlink_to(real)
    assert "symbolic link" in _unsafe(tmp_path / "link")
    assert list(real.iterdir()) == []  # nothing was made through the link


def test_a_directory_under_one_others_can_write_is_refused(tmp_path):
    """Another user who can write the parent can rename the cache away and put his own in its
    place; a sticky parent (/tmp) forbids that, so it is accepted."""
    from parakin.kernels.store import _unsafe

    parent = tmp_path / "shared"
    parent.mkdir()
    parent.chmod(0o777)
    assert "above it is writable by other users" in _unsafe(parent / "cache")
    parent.chmod(0o1777)
    assert _unsafe(parent / "cache") is None


@as_root
@pytest.mark.parametrize("mode", [0o700, 0o777])
def test_a_directory_another_user_owns_is_refused(tmp_path, mode):
    from parakin.kernels.store import _unsafe

    path = tmp_path / "cache"
    path.mkdir()
    path.chmod(mode)
    os.chown(path, NOBODY, -1)
    why = _unsafe(path)
    assert f"owned by uid {NOBODY} (nobody)" in why, why


@as_root
def test_a_directory_below_one_another_user_owns_is_refused(tmp_path):
    from parakin.kernels.store import _unsafe

    parent = tmp_path / "theirs"
    parent.mkdir(mode=0o755)
    os.chown(parent, NOBODY, -1)
    (parent / "cache").mkdir(mode=0o700)
    assert "above it is owned by uid" in _unsafe(parent / "cache")


def test_no_candidate_is_a_shared_temporary_name(monkeypatch):
    """The cache is $PARAKIN_KERNEL_CACHE or the per-user cache, never a name in /tmp that any
    user could make first; nothing in src/ or workflow/ names a shared temporary directory."""
    from parakin.kernels import store

    monkeypatch.delenv("PARAKIN_KERNEL_CACHE", raising=False)
    assert [label for label, _ in store._candidates()] == ["the per-user cache"]
    offenders = []
    for folder in (ROOT / "src", ROOT / "workflow"):
        for path in folder.rglob("*"):
            if path.is_file() and path.suffix in (".py", ".smk", ".sh", ".yaml", ".cfg"):
                text = path.read_text(errors="replace")
                for needle in ("gettempdir", "import tempfile", "tempfile.", "'/tmp", '"/tmp'):
                    if needle in text:
                        offenders.append(f"{path.relative_to(ROOT)}: {needle}")
    assert not offenders, offenders


def test_an_unusable_cache_is_one_line_then_the_numpy_path(tmp_path, monkeypatch, caplog):
    """PARAKIN_KERNEL_CACHE unset and the per-user cache anyone can write: one line, no disk
    cache, the kernels on numpy (the answer right)."""
    from parakin import kernels
    from parakin.kernels import store
    from parakin.mechanisms import P3P4S

    xdg = tmp_path / "xdg"
    (xdg / "parakin" / "kernels").mkdir(parents=True)
    (xdg / "parakin" / "kernels").chmod(0o777)
    monkeypatch.delenv("PARAKIN_KERNEL_CACHE", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(xdg))
    store.root.cache_clear()
    try:
        with caplog.at_level("WARNING", logger="parakin.kernels"):
            assert store.root() is None and not kernels.enabled()
        notes = [r.getMessage() for r in caplog.records]
        assert len(notes) == 1 and "writable by other users" in notes[0], notes
        assert notes[0].endswith("no disk cache (numpy path)"), notes
        m = P3P4S()
        assert abs(m.fk(m.ik([0.01, 0.0, 0.58]))[0] - 0.01) < 1e-12
    finally:
        store.root.cache_clear()


def test_a_lock_file_planted_as_a_symlink_is_not_followed(tmp_path):
    from parakin.kernels.store import _lock_fd

    victim = tmp_path / "victim"
    victim.write_text("keep")
    (tmp_path / ".locks").mkdir()
    (tmp_path / ".locks" / "k.lock").symlink_to(victim)
    fd = _lock_fd(tmp_path / ".locks" / "k.lock")
    assert fd is None  # refused (the cache then runs unlocked), never opened through the link
    assert victim.read_text() == "keep"


# ------------------------------------------------------------------ compiled code: what it claims
#: a victim: the toy kernel's compiled verification (IK round trip) of two poses, joint 1 of the
#: first moved by 1e-4: prints the path, the flags and the joint errors
VERIFY = textwrap.dedent(
    """
    import dataclasses, json, sys
    import numpy as np
    from parakin import kernels
    import toy_kernels_b
    from toy_mechanism import KernelTwoLeg as Toy

    @dataclasses.dataclass(frozen=True)
    class ToyB(Toy, register=False):
        kernels = toy_kernels_b

    m = Toy() if sys.argv[1] == "a" else ToyB()
    x = np.array([[0.1, 0.9], [0.0, 1.0]])
    q = m.ik(x) + [[1e-4, 0.0], [0.0, 0.0]]
    hooks = kernels.verify_hooks(m, q, x, parallel=False)
    if hooks is None:  # no compiled path: numpy's verification, the same numbers
        out = ["numpy", m.in_domain(x).tolist(), np.abs(m.ik(x) - q).max(-1).tolist()]
    else:
        ok, err, asm = hooks
        out = ["compiled", ok.tolist(), err.tolist()]
    print(json.dumps(out))
    """
)


def _toy_b(folder: Path) -> Path:
    """The toy kernel's sources and a second kernel ``toy_kernels_b`` (pivots twice as far apart:
    same sizes, other numbers) in ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    for name in ("toy_kernels.py", "toy_mechanism.py"):
        shutil.copy(DATA / name, folder / name)
    text = (DATA / "toy_kernels.py").read_text()
    legs = "return x[0] + p[0], x[0] - p[0], x[1]"
    assert legs in text
    (folder / "toy_kernels_b.py").write_text(
        text.replace(legs, "return x[0] + 2 * p[0], x[0] - 2 * p[0], x[1]")
    )
    return folder


def _env(cache: Path | None, sources: Path, **extra: str) -> dict[str, str]:
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ("NUMBA_CACHE_DIR", "PARAKIN_KERNELS", "PARAKIN_KERNEL_CACHE")
    }
    env["PYTHONPATH"] = os.pathsep.join([str(sources), str(ROOT / "src")])
    env["XDG_CACHE_HOME"] = str(sources / "xdg")
    if cache is not None:
        env["PARAKIN_KERNEL_CACHE"] = str(cache)
    env.update(extra)
    return env


def _victim(which: str, env: dict[str, str], cwd: Path) -> tuple[str, list[str]]:
    out = subprocess.run(
        [sys.executable, "-c", VERIFY, which],
        env=env,
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0 and "Traceback" not in out.stderr, out.stderr[-3000:]
    notes = [line for line in out.stderr.splitlines() if line.startswith("parakin:")]
    return out.stdout.strip(), notes


def _right(stdout: str, path: str = "compiled") -> None:
    """Kernel a's answer: both poses in its domain, joint errors 1e-4 (the planted one) and 0."""
    kind, ok, err = json.loads(stdout)
    assert kind == path and ok == [True, True], stdout
    assert abs(err[0] - 1e-4) < 1e-12 and err[1] < 1e-12, stdout


@pytest.fixture(scope="module")
def warm(tmp_path_factory) -> tuple[Path, Path]:
    """``(cache, sources)``: a cache holding the compiled verification of kernels a and b."""
    base = tmp_path_factory.mktemp("warm")
    sources = _toy_b(base / "src")
    cache = base / "cache"
    for which in ("a", "b"):
        stdout, notes = _victim(which, _env(cache, sources, PARAKIN_KERNELS="1"), base)
        assert json.loads(stdout)[0] == "compiled" and not notes, (stdout, notes)
    return cache, sources


def _entry(cache: Path, kernel: str) -> Path:
    """The index file of ``kernel``'s compiled ``verify_serial`` in ``cache``."""
    (index,) = cache.glob(f"{kernel}-*/verify/*/entries.verify_serial__{kernel}__verify-*.nbi")
    return index


@pytest.mark.slow  # three compiles of the toy kernel's verification, ~5 s each
@pytest.mark.parametrize("how", ["index", "data", "retagged"])
def test_another_kernels_entry_is_never_loaded(warm, tmp_path, how, monkeypatch):
    """Kernel b's compiled verification put in kernel a's place, three ways: b's index under a's
    name (it names b's data file, copied beside it), b's data file under a's data file's name
    (a's index kept), and b's files re-tagged as a's own (only the known-answer check can tell).
    Each time: one line saying the build is rebuilt and why, then the right answer; then a
    second process is quiet."""
    cache = tmp_path / "cache"
    shutil.copytree(warm[0], cache)
    mine, theirs = _entry(cache, "toy_kernels"), _entry(cache, "toy_kernels_b")
    if how == "index":
        shutil.copy(theirs, mine)
        for data in theirs.parent.glob(theirs.name[:-4] + ".*.nbc"):
            shutil.copy(data, mine.parent / data.name)
        why = "is not what it claims"
    elif how == "data":
        (ours,) = mine.parent.glob(mine.name[:-4] + ".*.nbc")
        (other,) = theirs.parent.glob(theirs.name[:-4] + ".*.nbc")
        shutil.copy(other, ours)
        why = "is not what it claims"
    else:
        monkeypatch.syspath_prepend(str(warm[1]))  # the data names the toy kernels' modules
        _retag(theirs, mine)
        why = "failed its known-answer check"
    env = _env(cache, warm[1], PARAKIN_KERNELS="1")
    stdout, notes = _victim("a", env, tmp_path)
    assert len(notes) == 1 and why in notes[0] and notes[0].endswith("rebuilt"), notes
    _right(stdout)
    stdout, notes = _victim("a", env, tmp_path)
    assert not notes, notes
    _right(stdout)


def _retag(theirs: Path, mine: Path) -> None:
    """Copy the entry of index ``theirs`` over the entry of index ``mine``, its index keys and
    data labels rewritten to carry ``mine``'s tag: a file that claims to be ours."""
    from numba.core.serialize import dumps

    def index(path: Path):
        with open(path, "rb") as fh:
            version = pickle.load(fh)
            stamp, overloads = pickle.loads(fh.read())
        return version, stamp, overloads

    version, stamp, overloads = index(theirs)
    tag = next(iter(index(mine)[2]))[1]
    forged = {}
    for (key, _), name in overloads.items():
        (_, sig), payload = pickle.loads((theirs.parent / name).read_bytes())
        (mine.parent / name).write_bytes(dumps(((tag, sig), payload)))
        forged[(key, tag)] = name
    with open(mine, "wb") as fh:
        pickle.dump(version, fh, protocol=-1)
        fh.write(dumps((stamp, forged)))


class _Planted:
    """A pickle that, when unpickled, creates the file ``marker``: proof that code ran."""

    def __init__(self, marker: Path) -> None:
        self.marker = str(marker)

    def __reduce__(self):
        return (open, (self.marker, "w"))


@pytest.mark.slow  # the compiled build it plants is made by the module's fixture (~10 s)
@as_root
def test_a_planted_cache_directory_runs_no_code(warm, tmp_path):
    """The issue's attack: PARAKIN_KERNEL_CACHE unset, and the victim's per-user cache is a
    directory another user made first (mode 777) holding a copy of a real build whose every
    index is a pickle that runs code. The victim's compiled solve reads none of it (the marker
    is never made): one line, the numpy path, the right answer; the directory is left as it was."""
    planted = tmp_path / "xdg" / "parakin" / "kernels"
    marker = tmp_path / "code-ran"
    shutil.copytree(warm[0], planted)
    for index in planted.rglob("*.nbi"):
        index.write_bytes(pickle.dumps(_Planted(marker)))
    for path in [planted, *planted.rglob("*")]:
        os.chown(path, NOBODY, -1, follow_symlinks=False)
        if path.is_dir():
            path.chmod(0o777)
    before = sorted(str(p.relative_to(planted)) for p in planted.rglob("*"))
    env = _env(None, warm[1], PARAKIN_KERNELS="1", XDG_CACHE_HOME=str(tmp_path / "xdg"))
    stdout, notes = _victim("a", env, tmp_path)
    assert not marker.exists(), "a planted pickle ran"
    assert len(notes) == 1 and f"owned by uid {NOBODY}" in notes[0], notes
    assert notes[0].endswith("no disk cache (numpy path)"), notes
    _right(stdout, "numpy")
    assert sorted(str(p.relative_to(planted)) for p in planted.rglob("*")) == before


# ------------------------------------------------------------------ outputs
@contextlib.contextmanager
def _umask(mask: int):
    old = os.umask(mask)
    try:
        yield
    finally:
        os.umask(old)


def test_outputs_honour_umask_077(tmp_path):
    from parakin.io import atomic_write_text

    with _umask(0o077):
        atomic_write_text(tmp_path / "a.txt", "x")
        code, _, err = run(
            ["ik", "3p4s", "--pose", "0", "0", "0.592", "--output", str(tmp_path / "q.csv")]
        )
    assert code == 0, err
    assert _mode(tmp_path / "a.txt") == 0o600 and _mode(tmp_path / "q.csv") == 0o600
    with _umask(0o022):
        atomic_write_text(tmp_path / "b.txt", "x")
    assert _mode(tmp_path / "b.txt") == 0o644


@pytest.mark.parametrize("mode", [0o600, 0o640, 0o755])
def test_an_existing_outputs_mode_is_kept(tmp_path, mode):
    from parakin.io import atomic_write_text

    target = tmp_path / "t.csv"
    target.write_text("old")
    target.chmod(mode)
    with _umask(0o022):
        atomic_write_text(target, "new")
    assert target.read_text() == "new" and _mode(target) == mode


def test_a_symlinked_output_is_replaced_never_followed(tmp_path):
    """The link is replaced by our file; what it pointed to (another user's file, a file of the
    victim's that the link was planted to overwrite) keeps its bytes and its mode."""
    victim = tmp_path / "victim"
    victim.write_text("keep")
    victim.chmod(0o600)
    (tmp_path / "out.csv").symlink_to(victim)
    code, _, err = run(
        ["ik", "3p4s", "--pose", "0", "0", "0.592", "--output", str(tmp_path / "out.csv")]
    )
    assert code == 0, err
    assert (
        not (tmp_path / "out.csv").is_symlink() and "l1 [m]" in (tmp_path / "out.csv").read_text()
    )
    assert victim.read_text() == "keep" and _mode(victim) == 0o600


def test_a_symlink_at_the_temporary_name_is_never_followed(tmp_path, monkeypatch):
    """Even a symlink planted at the very temporary name the writer draws first (48 random bits:
    here forced) is not written through: the name is made exclusively, the next one is used."""
    import uuid

    from parakin import io as pio

    victim = tmp_path / "victim"
    victim.write_text("keep")
    fixed = uuid.UUID(int=0x1234)
    draws = iter([fixed, uuid.uuid4(), uuid.uuid4()])
    monkeypatch.setattr(pio.uuid, "uuid4", lambda: next(draws))
    (tmp_path / f".t.{fixed.hex[:12]}.tmp.csv").symlink_to(victim)
    pio.atomic_write_text(tmp_path / "t.csv", "new")
    assert victim.read_text() == "keep" and (tmp_path / "t.csv").read_text() == "new"


# ------------------------------------------------------------------ hostile inputs
def _bomb(levels: int = 9, flow: bool = True) -> str:
    """A YAML alias bomb: ``levels`` anchors, each a list of 9 aliases of the one before."""
    if flow:
        parts = ["&a0 [1, 1, 1, 1, 1, 1, 1, 1, 1]"]
        parts += [f"&a{i} [{', '.join([f'*a{i - 1}'] * 9)}]" for i in range(1, levels)]
        return "[" + ", ".join(parts) + "]"
    rows = ["a0: &a0 [1, 1, 1, 1, 1, 1, 1, 1, 1]"]
    rows += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]" for i in range(1, levels)]
    return "\n".join(rows) + "\n"


DEEP = "[" * 100_000 + "]" * 100_000  # libyaml's composer would overflow the C stack


def _fifo(tmp_path: Path) -> Path:
    path = tmp_path / "fifo.yaml"
    os.mkfifo(path)
    return path


@pytest.mark.parametrize(
    "make, needles",
    [
        (lambda d: (d / "b.yaml").write_text(_bomb(9, False)), ["expands to", "100000"]),
        (lambda d: (d / "b.yaml").write_text("base: " + DEEP), ["nests deeper than the limit 64"]),
        (lambda d: (d / "b.yaml").write_text("r_a: " + "[" * 40 + "1" + "]" * 40), ["nested"]),
        (lambda d: (d / "b.yaml").write_text("r_a: true\n"), ["boolean"]),
        (lambda d: (d / "b.yaml").write_bytes(b"r_a: 1\n" + b"#" * (2 << 20)), ["the limit"]),
        (lambda d: (d / "b.yaml").write_text("a: &x [*x]\n"), ["refers to itself"]),
        (lambda d: (d / "b.yaml").write_text("r_a: !!python/object/apply:os.getpid []"), ["YAML"]),
        (lambda d: "/dev/zero", ["not a regular file"]),
        (lambda d: str(_fifo(d)), ["not a regular file"]),
        (lambda d: str(d), ["not a regular file"]),
    ],
    ids=[
        "bomb",
        "deep",
        "40-deep",
        "true",
        "2MB",
        "recursive",
        "python-tag",
        "devzero",
        "fifo",
        "dir",
    ],
)
def test_hostile_geometry_files_are_one_line_at_once(tmp_path, make, needles):
    path = make(tmp_path)
    path = str(tmp_path / "b.yaml") if path is None or isinstance(path, int) else path
    start = time.perf_counter()
    code, _, stderr = run(["ik", "3p4s", "--pose", "0", "0", "0.592", "--geometry", path])
    one_line(code, stderr, "--geometry", *needles)
    assert time.perf_counter() - start < 10


@pytest.mark.parametrize(
    "value, needles",
    [
        (_bomb(9), ["expands to", "more than the limit 100000"]),
        (
            "[" * 40 + "1" + "]" * 40,
            ["expected an array of shape (6, 3), got a list nested deeper"],
        ),
        (DEEP[:20000], ["nests deeper than the limit 64"]),
        ("[[0,0,true],[1,0,0],[0,1,0],[1,1,0],[2,0,0],[0,2,0]]", ["boolean"]),
        ("[" + ",".join(["1"] * 600_000) + "]", ["bytes, more than the limit"]),
    ],
    ids=["bomb", "40-deep", "deep", "true", "huge"],
)
def test_hostile_param_values_are_one_line_at_once(value, needles):
    start = time.perf_counter()
    code, _, stderr = run(
        ["ik", "stewart66", "--pose", *["0"] * 5, "0.7", "--param", f"base={value}"]
    )
    one_line(code, stderr, "--param", *needles)
    assert time.perf_counter() - start < 10


@pytest.mark.parametrize(
    "make, needles",
    [
        (lambda d: "/dev/zero", ["not a regular file"]),
        (lambda d: str(_fifo(d)), ["not a regular file"]),
        (lambda d: (d / "c.yaml").write_text("a: " + DEEP), ["nests deeper than the limit 64"]),
        (lambda d: (d / "c.yaml").write_text(_bomb(12, False)), ["expands to"]),
    ],
    ids=["devzero", "fifo", "deep", "bomb"],
)
def test_hostile_configs_are_one_line_at_once(tmp_path, make, needles):
    """A config nested 10^5 deep crashed the process (libyaml's composer) before any bound."""
    path = make(tmp_path)
    path = str(tmp_path / "c.yaml") if not isinstance(path, str) else path
    code, _, stderr = run(["reproduce", "zhao2017_3p4s", "table1", "--config", path])
    one_line(code, stderr, "config file", *needles)


@pytest.mark.parametrize(
    "make",
    [
        lambda d: "/dev/zero",
        lambda d: str(_fifo(d)),
        lambda d: (d / "m.yaml").write_text("name: x\nlegs: " + DEEP),
        lambda d: (d / "m.yaml").write_text(_bomb(12, False)),
        lambda d: (d / "m.yaml").write_bytes(b"name: x\n" + b"#" * (2 << 20)),
    ],
    ids=["devzero", "fifo", "deep", "bomb", "2MB"],
)
def test_hostile_mechanism_files_are_one_line_at_once(tmp_path, make):
    if not _takes_mechanism_files():
        pytest.skip("this parakin has no --mechanism option yet (issue 43)")
    path = make(tmp_path)
    path = str(tmp_path / "m.yaml") if not isinstance(path, str) else path
    start = time.perf_counter()
    code, _, stderr = run(["ik", "--mechanism", path, "--pose", "0", "0", "-0.9"])
    line = one_line(code, stderr, path)
    assert "usage" not in line and "unrecognized" not in line, line
    assert time.perf_counter() - start < 10


def _takes_mechanism_files() -> bool:
    """Whether ``parakin ik`` takes ``--mechanism FILE`` (issue 43 adds it)."""
    import argparse

    from parakin.cli import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    return any("--mechanism" in a.option_strings for a in sub.choices["ik"]._actions)


@pytest.mark.parametrize("suffix", [".csv", ".npy"])
def test_an_input_table_that_is_a_fifo_is_refused_at_once(tmp_path, suffix):
    """``--input`` of a FIFO (or a link to /dev/zero) named like a table: refused, not waited on."""
    fifo = tmp_path / f"in{suffix}"
    os.mkfifo(fifo)
    zero = tmp_path / f"zero{suffix}"
    zero.symlink_to("/dev/zero")
    for path in (fifo, zero):
        code, _, stderr = run(["fk", "3p4s", "--input", str(path)])
        one_line(code, stderr, str(path), "not a regular file")


@pytest.mark.parametrize(
    "content, needles",
    [
        (None, ["trajectory /dev/zero", "not a regular file"]),
        (b"\x00\x01\x02\xff", ["not UTF-8"]),
        (b"t,x,y,phi\n0,0,0,0\n1,a,0,0\n2,0,0,0\n3,0,0,0\n", ["line 3", "x = 'a'"]),
        (b"t,x,y,phi\n0,0,0,0\n1,nan,0,0\n2,0,0,0\n3,0,0,0\n", ["line 3", "not a finite number"]),
        (b't,x,y,phi\n0,0,0,0\n1,"1,0,0\n', ["not a CSV table"]),
        (b"t,x\n0,0\n", ["missing column(s)"]),
    ],
    ids=["devzero", "binary", "text", "nan", "quote", "columns"],
)
def test_trajectory_errors_name_the_file(tmp_path, content, needles):
    path = "/dev/zero" if content is None else str(tmp_path / "traj.csv")
    if content is not None:
        Path(path).write_bytes(content)
    code, _, stderr = run(["dynamics", "rpr3", "--trajectory", path])
    one_line(code, stderr, path, *needles)


#: a 3-RPR trajectory through a singular pose (the three legs' lines meet in one point)
SINGULAR = "t,x,y,phi\n0,0,0,0\n0.1,0.1,0.01,-0.5\n0.2,0.29763715,0.03302491,-1.04719755\n0.3,0.2,0.02,-0.8\n0.4,0,0,0\n"


def test_flagged_dynamics_print_strict_json(tmp_path):
    """--flag-singular --json: NaN forces are null, beside the flag that says why (was a failed
    command: NaN met the strict JSON encoder)."""
    path = tmp_path / "traj.csv"
    path.write_text(SINGULAR)
    code, stdout, stderr = run(
        ["dynamics", "rpr3", "--trajectory", str(path), "--flag-singular", "--json"]
    )
    assert code == 0 and "Traceback" not in stderr, stderr
    out = json.loads(stdout, parse_constant=lambda c: pytest.fail(f"non-strict JSON {c}"))
    assert out["singular"] == [False, False, True, False, False]
    for force, singular, unbalanced in zip(out["force"], out["singular"], out["unbalanced"]):
        assert (None in force) == (singular or unbalanced), out
        assert all(f is None for f in force) or all(np.isfinite(f) for f in force)
    assert "1 sample(s) singular" in stderr


def test_ctrl_c_is_one_line_exit_130(monkeypatch):
    """A real SIGINT while a command runs: one line, exit 130, no traceback."""
    from parakin.cli import kinematics

    timer = threading.Timer(0.2, lambda: os.kill(os.getpid(), signal.SIGINT))

    def slow(args):  # the signal comes while the command runs, never after
        timer.start()
        time.sleep(30)
        return 0

    monkeypatch.setattr(kinematics, "cmd_ik", slow)
    # Python's own handler, as under a terminal: a shell starts a background job (``pytest &``)
    # with SIGINT ignored, Python keeps it ignored, and the command would sleep its 30 s out
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        code, stdout, stderr = run(["ik", "3p4s", "--pose", "0", "0", "0.592"])
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)
    assert code == 130 and stderr == "parakin ik: interrupted\n" and not stdout, stderr
