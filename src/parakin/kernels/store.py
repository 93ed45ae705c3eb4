"""Where compiled code is kept, and why it can be trusted: one directory, checked on every use.

Layout of the cache directory (:func:`root`)::

    <root>/numba/                  numba's cache of parakin's own ``cache=True`` modules
    <root>/<kernel>-<hash>/<what>/ one kernel's compiled functions and the solver entries over it

``<hash>`` is a digest of every source that goes into the machine code (the kernel module,
``_math``, the drivers, the entries, the options table) and of the numba and Python versions:
an edited kernel, driver or library is a new directory, never a stale build (numba itself checks
only the file a function is defined in; a driver compiled over a kernel of another file would be
served after that kernel changed). A build is never removed from under a process that uses it:
several processes share the cache (pytest-xdist workers, pipeline jobs, two clones of the
repository), so each holds a shared lock on the build it uses (``<root>/.locks/<build>.use``) for
its lifetime, and the builds of a kernel are made, removed and rebuilt only under that kernel's
exclusive lock (``<root>/.locks/<kernel>.lock``, ``fcntl.flock``). Older builds of a kernel (another
hash) are removed when no process uses them. A cache entry that cannot be read (a corrupt index or
data file) is rebuilt, with a one-line notice (:func:`first_call`): the build is moved aside in one
rename and made again under the same name, so a process that loads from it meanwhile sees either
the old files or none (numba then compiles), never a half-removed directory. Where no lock can be
taken (a platform without ``fcntl``), the cache works as it would for one process.

The directory is ``$PARAKIN_KERNEL_CACHE``, else the per-user cache of ``platformdirs``
(``~/.cache/parakin/kernels`` on Linux). Where it cannot be written, the per-user cache, then a
temporary directory, then none (the numpy path: :func:`root` returns ``None``), each step with a
one-line notice on the ``parakin.kernels`` logger. Numba's own cache directory
(``NUMBA_CACHE_DIR``) is pointed at ``<root>/numba`` when this module is imported, before any
parakin module decorates a function, so no cache lands beside the sources.
"""

from __future__ import annotations

import hashlib
import logging
import os
import shutil
import sys
import tempfile
import threading
import uuid
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import cache
from pathlib import Path
from types import ModuleType
from typing import Any

try:
    import fcntl
except ImportError:  # no advisory locks (Windows): builds are made and removed without them
    fcntl = None  # type: ignore[assignment]

__all__ = ["clear", "digest", "first_call", "kernel_dir", "numba_cache", "root", "status"]

log = logging.getLogger("parakin.kernels")

#: what a kernel's directory name ends in: ``-`` and this many hex digits of its hash
HASH_DIGITS = 16
_LOCK = threading.RLock()
#: the directory of ``<root>`` that holds the lock files
LOCKS = ".locks"
#: build name -> the descriptor of the shared lock this process holds on it (:func:`_use`)
_USING: dict[str, int] = {}


def _notice(message: str) -> None:
    """One line on the ``parakin.kernels`` logger (stderr unless the application configures
    logging)."""
    log.warning("parakin: %s", message)


def _writable(path: Path) -> str | None:
    """None where ``path`` is (or can be made) a directory we may write, else why not."""
    try:
        path.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=path):
            pass
    except OSError as exc:
        return exc.strerror or type(exc).__name__
    return None


def _user_dir() -> Path:
    try:
        import platformdirs
    except ImportError:  # platformdirs is a dependency; XDG as a last resort
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        return Path(base) / "parakin" / "kernels"
    return Path(platformdirs.user_cache_dir("parakin", appauthor=False)) / "kernels"


def _candidates() -> list[tuple[str, Path]]:
    """``(label, path)`` in the order tried."""
    out = []
    env = os.environ.get("PARAKIN_KERNEL_CACHE")
    if env:
        out.append(("$PARAKIN_KERNEL_CACHE", Path(env)))
    out.append(("the per-user cache", _user_dir()))
    user = f"{os.getuid()}" if hasattr(os, "getuid") else "user"
    out.append(("a temporary directory", Path(tempfile.gettempdir()) / f"parakin-kernels-{user}"))
    return out


@cache
def root() -> Path | None:
    """The cache directory (created), or ``None`` where no candidate can be written (then the
    compiled path is off). Resolved once per process."""
    for i, (label, path) in enumerate(_candidates()):
        why = _writable(path)
        if why is None:
            return path
        nxt = _candidates()[i + 1][0] if i + 1 < len(_candidates()) else "the numpy path"
        _notice(f"kernel cache {path} ({label}) is not writable ({why}); using {nxt}")
    return None


def _numba_default() -> None:
    """Point numba's cache at ``<root>/numba`` (parakin's plain ``cache=True`` modules, e.g.
    :mod:`parakin.kernels.stewart36_all`): through the environment before numba is imported, in
    its config after. Without a writable root numba keeps its own choice."""
    where = root()
    if where is None:
        return
    path = str(where / "numba")
    if "numba" in sys.modules and sys.modules["numba"] is not None:
        sys.modules["numba"].config.CACHE_DIR = path
    else:
        os.environ["NUMBA_CACHE_DIR"] = path


def _source(module: ModuleType) -> bytes:
    path = getattr(module, "__file__", None)
    if path and os.path.exists(path):
        return Path(path).read_bytes()
    import inspect

    return inspect.getsource(module).encode()


def digest(*modules: ModuleType) -> str:
    """Hash of the sources of ``modules`` and of the numba and Python versions (hex, truncated)."""
    import numba

    h = hashlib.sha256()
    for mod in modules:
        h.update(mod.__name__.encode() + b"\0" + _source(mod) + b"\0")
    h.update(f"numba {numba.__version__} python {sys.version}".encode())
    return h.hexdigest()[:HASH_DIGITS]


def kernel_dir(name: str, hash_: str) -> Path:
    """``<root>/<name>-<hash>``, created and marked in use by this process; the builds of ``name``
    that no process uses and that are of other hashes are removed."""
    base = root()
    assert base is not None, "kernel_dir() without a cache root (enabled() is False)"
    path = base / f"{name}-{hash_}"
    with _locked(base, name):
        _use(base, path.name)
        _prune(base, name, keep=path.name)
        path.mkdir(parents=True, exist_ok=True)
    return path


def _lock_fd(path: Path) -> int | None:
    """An open descriptor of lock file ``path`` (created), or ``None`` where locks cannot be
    taken (no ``fcntl``, or a lock file that cannot be written): then the cache runs unlocked."""
    if fcntl is None:
        return None
    try:
        path.parent.mkdir(exist_ok=True)
        return os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    except OSError:
        return None


@contextmanager
def _locked(base: Path, name: str) -> Iterator[None]:
    """The exclusive lock of kernel ``name``'s builds, across processes and threads (each holder
    opens its own descriptor: ``flock`` locks of two descriptors exclude each other)."""
    fd = _lock_fd(base / LOCKS / f"{name}.lock")
    if fd is None:
        yield
        return
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # releases the lock


def _use(base: Path, build: str) -> None:
    """Hold a shared lock on ``build`` for the rest of this process (and of its forked children,
    which share the descriptor): :func:`_prune` leaves a build alone while anyone holds one."""
    if build in _USING:
        return
    fd = _lock_fd(base / LOCKS / f"{build}.use")
    if fd is not None:
        fcntl.flock(fd, fcntl.LOCK_SH)  # only a pruner holds it exclusively, under _locked
        _USING[build] = fd


def _is_build(path: Path, name: str) -> bool:
    """Whether ``path`` is a kernel directory of ``name`` (``name-`` + hex hash)."""
    tail = path.name[len(name) + 1 :]
    return (
        path.name.startswith(name + "-")
        and len(tail) == HASH_DIGITS
        and all(c in "0123456789abcdef" for c in tail)
    )


def _prune(base: Path, name: str, keep: str | None = None) -> None:
    """Remove the builds of ``name`` made from other sources (not ``keep``: another hash) that no
    process uses. Called under :func:`_locked`, so no process starts using one meanwhile."""
    for old in base.glob(f"{name}-*"):
        if _is_build(old, name) and old.name != keep and not _in_use(base, old.name):
            _discard(old)
            (base / LOCKS / f"{old.name}.use").unlink(missing_ok=True)


def _in_use(base: Path, build: str) -> bool:
    """Whether a process holds its shared lock on ``build`` (:func:`_use`); a build whose lock
    file cannot be opened counts as in use."""
    lock = base / LOCKS / f"{build}.use"
    if fcntl is None or not lock.exists():  # every user makes the file before using the build
        return False
    fd = _lock_fd(lock)
    if fd is None:
        return True
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    finally:
        os.close(fd)
    return False


def _discard(path: Path, *, remake: bool = False) -> None:
    """Remove ``path`` by first moving it aside in one rename (a process opening a file of it by
    name meanwhile finds the whole directory or nothing at all); ``remake``: an empty directory of
    the same name is made before the old one is deleted (a new inode: :func:`first_call` tells a
    rebuilt build by it)."""
    aside = path.parent / f".trash-{path.name}-{uuid.uuid4().hex[:8]}"
    try:
        path.rename(aside)
    except OSError:
        aside = None  # gone already
    if remake:
        path.mkdir(parents=True, exist_ok=True)
    if aside is not None:
        shutil.rmtree(aside, ignore_errors=True)


def _inode(path: Path) -> int | None:
    try:
        return path.stat().st_ino
    except OSError:
        return None


@contextmanager
def numba_cache(path: Path) -> Iterator[None]:
    """numba functions decorated inside this block keep their on-disk cache in ``path`` (numba
    reads ``config.CACHE_DIR`` when a function is decorated)."""
    import numba

    with _LOCK:
        old = numba.config.CACHE_DIR
        numba.config.CACHE_DIR = str(path)
        try:
            yield
        finally:
            numba.config.CACHE_DIR = old


def first_call(fn: Callable[..., Any], where: Path, *args: Any) -> Any:
    """``fn(*args)`` for the first time (numba loads it from its cache in build ``where`` or
    compiles it). Where that fails and another process rebuilt ``where`` meanwhile (a new
    directory), it is tried again; where ``where`` is unchanged and holds cached files, a cache
    entry could not be read (truncated, garbage, written by another build): ``where`` is made
    again (:func:`_discard`: a fresh directory of the same name), under the kernel's lock, and the
    call made once more, with a one-line notice. A failure with an empty build (a genuine compile
    error) is raised."""
    before = _inode(where)
    try:
        return fn(*args)
    except Exception as exc:
        cause = exc
    with _locked(where.parent, where.name.rpartition("-")[0]):
        if _inode(where) != before:  # rebuilt by another process while this one read it
            return fn(*args)
        if before is None or not any(where.rglob("*.nb*")):
            raise cause
        while cause.__context__ is not None and "numba" in type(cause).__module__:
            cause = cause.__context__  # numba wraps what went wrong while loading a callee
        _notice(
            f"kernel cache {where} could not be read ({type(cause).__name__}: "
            f"{' '.join(str(cause).split())[:80]}); rebuilt"
        )
        _discard(where, remake=True)
        return fn(*args)


def _size(path: Path) -> int:
    return sum(f.stat().st_size for f in path.rglob("*") if f.is_file())


def _ours(base: Path) -> list[tuple[Path, str, str]]:
    """``(path, name, hash)`` of every directory of ``base`` that parakin made: the kernel builds
    and numba's part (hash ``""``); anything else there is left alone."""
    out = []
    for path in sorted(p for p in base.iterdir() if p.is_dir()):
        name, _, hash_ = path.name.rpartition("-")
        if _is_build(path, name):
            out.append((path, name, hash_))
        elif path.name == "numba":
            out.append((path, "numba", ""))
    return out


def status() -> dict[str, Any]:
    """The cache directory, the builds in it (name, hash, files, bytes) and numba's part."""
    base = root()
    out: dict[str, Any] = {"root": None if base is None else str(base), "builds": []}
    if base is None or not base.exists():
        return out
    for path, name, hash_ in _ours(base):
        files = [f for f in path.rglob("*") if f.is_file()]
        out["builds"].append(
            {"name": name, "hash": hash_, "files": len(files), "bytes": _size(path)}
        )
    return out


def clear() -> int:
    """Remove every build, numba's part of the cache and the lock files (nothing else); returns
    the bytes freed. Builds in use go too: it is the user's command to start afresh."""
    base = root()
    if base is None or not base.exists():
        return 0
    freed = 0
    for path, _, _ in _ours(base):
        freed += _size(path)
        shutil.rmtree(path, ignore_errors=True)
    for path in [base / LOCKS, *base.glob(".trash-*")]:  # locks, and what a crash left aside
        shutil.rmtree(path, ignore_errors=True)
    return freed


_numba_default()
