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
(``~/.cache/parakin/kernels`` on Linux); never a name in a shared temporary directory. Numba
unpickles the files of its cache, so loading one runs whatever its writer put there: a directory
is used only where no other user can have written into it (:func:`_unsafe`): made with mode 0700,
then checked with ``lstat`` on an open descriptor: a directory, not a symbolic link, owned by this
user, not writable by anyone else (group or other read bits are taken away, 0700), and every
directory above it owned by this user or root and not writable by others (unless sticky, as
``/tmp``). A directory that fails is not used: the next candidate, then none (the numpy path:
:func:`root` returns ``None``), each step with one line on the ``parakin.kernels`` logger.

What is loaded is what it claims (:func:`first_call`): every cached function of a build records
the build (kernel module and source hash), its group and its own name in its index key and in its
data file, beside the signature numba keys it by; a file of another kernel, group or function
(copied or renamed into place) is refused before any of its code runs. Then a known-answer check
(:func:`_known_answer`) runs each entry once per process on a probe whose answer the kernel's own
source gives on Python floats. Either failure rebuilds the build, with one line. Numba's own cache
directory (``NUMBA_CACHE_DIR``) is pointed at ``<root>/numba`` when this module is imported,
before any parakin module decorates a function, so no cache lands beside the sources.

One process compiles a thing at a time: the first calls of a build's entry group
(:func:`first_call`) and each function of numba's part (:func:`share_compiles`) hold a lock, so a
process that needs what another is compiling waits and loads it, rather than compiling it beside
it (the pipeline's jobs and the test workers start on an empty cache together). A module may
name the LLVM optimisation level its functions compile at (:func:`share_compiles`, the 6-6
tracker's 2), set for their compiles only: every other function keeps numba's. While numba
compiles, Python's cyclic garbage collector is off (:func:`no_gc_while_compiling`).
"""

from __future__ import annotations

import hashlib
import logging
import os
import shutil
import stat
import sys
import threading
import uuid
import weakref
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from functools import cache
from pathlib import Path
from types import ModuleType
from typing import Any

try:
    import fcntl
except ImportError:  # no advisory locks (Windows): builds are made and removed without them
    fcntl = None  # type: ignore[assignment]

__all__ = [
    "clear",
    "digest",
    "first_call",
    "guard",
    "kernel_dir",
    "no_gc_while_compiling",
    "numba_cache",
    "root",
    "share_compiled",
    "share_compiles",
    "status",
]

log = logging.getLogger("parakin.kernels")

#: what a kernel's directory name ends in: ``-`` and this many hex digits of its hash
HASH_DIGITS = 16
#: the layout of a build's files, part of its hash: 2 = every cached function tagged with its
#: build, group and name (:class:`_TaggedCache`); 3 = an entry's compiled name carries its group
#: (format 2's entries of two groups could share a symbol and link each other's loops); builds of
#: an older format are never loaded
FORMAT = 3
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
    """None where a file can be made in directory ``path`` (made exclusively, never through a
    planted name, and removed at once), else why not."""
    probe = path / f".probe-{uuid.uuid4().hex[:12]}"
    try:
        os.close(os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL | _NOFOLLOW, 0o600))
        probe.unlink()
    except OSError as exc:
        return exc.strerror or type(exc).__name__
    return None


#: ``open`` flag that refuses a symbolic link as the last component (0 where the OS has none)
_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)


def _owner(uid: int) -> str:
    """``uid 65534 (nobody)``: a uid with its user name where there is one."""
    try:
        import pwd

        return f"uid {uid} ({pwd.getpwuid(uid).pw_name})"
    except (ImportError, KeyError):
        return f"uid {uid}"


def _unsafe_ancestor(path: Path, me: int) -> str | None:
    """Why a directory above ``path`` lets another user replace what is below it, or None.

    Every directory on the way, as written and as resolved (a symbolic link on the way is judged
    by where it leads, and the directory holding it by itself), must be owned by this user or
    root and not writable by group or others, unless sticky (``/tmp``: there nobody renames or
    removes another user's entry)."""
    seen = set()
    for chain in (path.parent, Path(os.path.realpath(path.parent))):
        for ancestor in [chain, *chain.parents]:
            if ancestor in seen:
                continue
            seen.add(ancestor)
            try:
                st = os.stat(ancestor)
            except OSError as exc:
                return f"{ancestor} cannot be examined ({exc.strerror or type(exc).__name__})"
            if st.st_uid not in (me, 0):
                return f"{ancestor} above it is owned by {_owner(st.st_uid)}"
            if st.st_mode & 0o022 and not st.st_mode & stat.S_ISVTX:
                return (
                    f"{ancestor} above it is writable by other users "
                    f"(mode {stat.S_IMODE(st.st_mode):04o}, not sticky)"
                )
    return None


def _unsafe(path: Path) -> str | None:
    """None where ``path`` is (or is now made) a cache directory no other user can have written
    into, else why it is not used (one clause).

    Made with mode 0700 where it does not exist, then opened without following a symbolic link
    and examined through that descriptor (``fstat``: what was checked is what is open, whatever is
    renamed meanwhile): a directory owned by this user, writable by nobody else. Group and other
    read or search bits of a directory of ours are removed (0700: they let nobody write, but the
    cache is nobody else's business). Where the OS has no user ids (Windows), only writability."""
    path = Path(os.path.abspath(path))
    me = os.geteuid() if hasattr(os, "geteuid") else None
    try:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
        except FileExistsError:  # a file on the way
            return f"{next(p for p in path.parents if p.exists())} is not a directory"
        try:
            os.mkdir(path, 0o700)
        except FileExistsError:
            pass
        if os.path.islink(path):  # lstat: a planted link is never followed
            return f"it is a symbolic link (to {os.readlink(path)})"
        if me is None:
            return _writable(path)
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0) | _NOFOLLOW)
    except OSError as exc:
        return exc.strerror or type(exc).__name__
    try:
        st = os.fstat(fd)
        mode = stat.S_IMODE(st.st_mode)
        if not stat.S_ISDIR(st.st_mode):
            return "it is not a directory"
        if st.st_uid != me:
            return f"it is owned by {_owner(st.st_uid)}, not by this user ({_owner(me)})"
        if mode & 0o022:
            return f"it is writable by other users (mode {mode:04o}; it must be 0700)"
        if mode & 0o077:
            os.fchmod(fd, 0o700)
    except OSError as exc:
        return exc.strerror or type(exc).__name__
    finally:
        os.close(fd)
    return _unsafe_ancestor(path, me) or _writable(path)


def _user_dir() -> Path:
    try:
        import platformdirs
    except ImportError:  # platformdirs is a dependency; XDG as a last resort
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        return Path(base) / "parakin" / "kernels"
    return Path(platformdirs.user_cache_dir("parakin", appauthor=False)) / "kernels"


def _candidates() -> list[tuple[str, Path]]:
    """``(label, path)`` in the order tried: never a shared temporary directory (any user can
    make such a name first)."""
    out = []
    env = os.environ.get("PARAKIN_KERNEL_CACHE")
    if env:
        out.append(("$PARAKIN_KERNEL_CACHE", Path(env)))
    out.append(("the per-user cache", _user_dir()))
    return out


@cache
def root() -> Path | None:
    """The cache directory (created, checked by :func:`_unsafe`), or ``None`` where no candidate
    can be used (then the compiled path is off: no code is loaded from disk). Resolved once per
    process; each candidate refused is one line on the ``parakin.kernels`` logger."""
    candidates = _candidates()
    for i, (label, path) in enumerate(candidates):
        why = _unsafe(path)
        if why is None:
            return Path(os.path.abspath(path))
        nxt = candidates[i + 1][0] if i + 1 < len(candidates) else "no disk cache (numpy path)"
        _notice(f"kernel cache {path} ({label}) is not used: {why}; using {nxt}")
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

    h = hashlib.sha256(f"format {FORMAT}\0".encode())
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
        path.parent.mkdir(mode=0o700, exist_ok=True)
        return os.open(path, os.O_RDWR | os.O_CREAT | _NOFOLLOW, 0o600)
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
            for lock in (base / LOCKS).glob(f"{old.name}.*"):  # its use and its groups' locks
                lock.unlink(missing_ok=True)


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


#: numba functions compiled at an LLVM optimisation level of their own (:func:`share_compiles`)
_LEVELS: weakref.WeakKeyDictionary[Any, int] = weakref.WeakKeyDictionary()


@cache
def _compile_levels() -> None:
    """Compile each function of :data:`_LEVELS` at its LLVM level, every other at numba's own.
    numba reads its level (``numba.config.OPT``) each time it builds LLVM's passes, so a listener
    of its compile events sets the level for the compile of such a function and restores it
    after. A compile runs under numba's compiler lock, one at a time; a function compiled inside
    another's compile (a callee) gets its own level, or numba's."""
    import numba.core.event as ev
    from numba.core import config

    saved: list[Any] = []

    class Level(ev.Listener):
        def on_start(self, event: Any) -> None:
            saved.append(config.OPT)
            try:
                level = _LEVELS.get(event.data.get("dispatcher"))
            except TypeError:  # a compiler of another kind (not weakly referable): not ours
                level = None
            config.OPT = saved[0] if level is None else type(config.OPT)(level)

        def on_end(self, event: Any) -> None:
            config.OPT = saved.pop()

    ev.register("numba:compile", Level())


@cache
def no_gc_while_compiling() -> None:
    """Python's cyclic garbage collector paused while numba compiles, from the first to the last
    event of an outermost compile (its callees' compiles nest inside it), and restored after:
    numba's typing and lowering make millions of short-lived objects, and a full collection
    walks the whole heap each time it grows by a quarter (27 of them in a pipeline job's first 6-6
    solve). The cycles made meanwhile are freed by the first collection after it; the peak memory
    of that solve is about 0.3 GB higher (1.04 against 0.73 GB), its compile 14 % shorter, and
    every result the same. Registered once per process by :func:`share_compiles` (which every
    compiled module of parakin, the solvers' shared drivers included, goes through), for every
    numba compile in it (docs/kernels.md)."""
    import gc

    import numba.core.event as ev

    depth = [0]
    was_on = [False]

    class NoCollection(ev.Listener):
        def on_start(self, event: Any) -> None:  # under numba's compiler lock: one thread
            if depth[0] == 0:
                was_on[0] = gc.isenabled()
                gc.disable()
            depth[0] += 1

        def on_end(self, event: Any) -> None:
            depth[0] -= 1
            if depth[0] == 0 and was_on[0]:
                gc.enable()

    ev.register("numba:compile", NoCollection())


class CacheMismatch(Exception):
    """A cached function's file is not the one asked for: another kernel's, group's or
    function's (copied or renamed into place), or one written without the tags."""


#: every mismatch met in this process (numba may report the failed load of a callee, met while
#: compiling its caller, as an error of its own: :func:`first_call` reads the reason here), and
#: the build that held each (a loop cached in a build of its own, the workspace's, meets the
#: kernel's build through the kernel functions it calls)
_MISMATCHES: list[str] = []
_MISMATCHED_BUILDS: list[Path | None] = []


def _what(key: Any) -> str:
    """The function an index key or data tag names: ``function F of group G of build B``."""
    tag = key[1] if isinstance(key, tuple) and len(key) == 2 else None
    if isinstance(tag, tuple) and len(tag) == 3:
        return f"{tag[2]} ({tag[1]}, build {tag[0]})"
    return "an entry without tags"


@cache
def _tagged_cache() -> type:
    """numba's ``FunctionCache`` that tags what it writes and refuses what is not tagged as its
    own (``_parakin_tag``: build, group, function; set by :func:`guard`)."""
    from numba.core.caching import FunctionCache

    class TaggedCache(FunctionCache):
        _parakin_tag: tuple[str, str, str]

        def _index_key(self, sig: Any, codegen: Any) -> Any:
            # numba's key holds the signature, the target and a hash of the bytecode, which is the
            # same for every kernel's copy of an entry: the tag tells them apart
            return (super()._index_key(sig, codegen), self._parakin_tag)

        def _refuse(self, why: str) -> None:
            _MISMATCHES.append(f"{self._cache_file._index_name} {why}")
            build = self._parakin_tag[0]
            parents = Path(self._cache_path).parents
            _MISMATCHED_BUILDS.append(next((p for p in parents if p.name == build), None))
            raise CacheMismatch(_MISMATCHES[-1])

        def _load_overload(self, sig: Any, target_context: Any) -> Any:
            if not self._enabled:
                return None
            index = self._cache_file._load_index()
            for other in index:
                if not (isinstance(other, tuple) and len(other) == 2) or (
                    other[1] != self._parakin_tag
                ):
                    self._refuse(f"lists {_what(other)}, not {_what((None, self._parakin_tag))}")
            name = index.get(self._index_key(sig, target_context.codegen()))
            if name is None:
                return None
            try:
                data = self._cache_file._load_data(name)
            except OSError:  # removed while the index still named it: compiled again
                return None
            label = (self._parakin_tag, str(sig))
            if not (isinstance(data, tuple) and len(data) == 2 and data[0] == label):
                got = data[0] if isinstance(data, tuple) and len(data) == 2 else None
                sig_text = f" for {got[1]}" if isinstance(got, tuple) and len(got) == 2 else ""
                self._refuse(
                    f"its data file {name} holds {_what((None, got and got[0]))}{sig_text}"
                )
            return self._impl.rebuild(target_context, data[1])

        def _save_overload(self, sig: Any, data: Any) -> None:
            if not self._enabled or not self._impl.check_cachable(data):
                return
            self._impl.locator.ensure_cache_path()
            key = self._index_key(sig, data.codegen)
            label = (self._parakin_tag, str(sig))
            self._cache_file.save(key, (label, self._impl.reduce(data)))

    return TaggedCache


#: id(cache) -> the descriptor of the compile lock this process holds for it (:func:`_shared_cache`)
_COMPILING: dict[int, int] = {}


def _release(cache_: Any) -> None:
    fd = _COMPILING.pop(id(cache_), None)
    if fd is not None:
        os.close(fd)  # releases the lock


@cache
def _shared_cache() -> type:
    """numba's ``FunctionCache`` where a miss is compiled by one process at a time: a process that
    misses takes the function's lock (``<root>/.locks/numba.<index>.lock``) and looks again
    (another process may have written it meanwhile); it holds the lock while it compiles, until
    the function is saved (or its compile failed)."""
    import numba.core.event as ev
    from numba.core.caching import FunctionCache

    class SharedCache(FunctionCache):
        def load_overload(self, sig: Any, target_context: Any) -> Any:
            got = self._readable(sig, target_context)
            base = root()
            if got is not None or not self._enabled or base is None or id(self) in _COMPILING:
                return got
            index = self._cache_file._index_path
            name = hashlib.sha256(index.encode()).hexdigest()[:HASH_DIGITS]
            fd = _lock_fd(base / LOCKS / f"numba.{Path(index).stem}.{name}.lock")
            if fd is None:
                return None
            fcntl.flock(fd, fcntl.LOCK_EX)
            got = self._readable(sig, target_context, mend=True)
            if got is None:
                _COMPILING[id(self)] = fd  # held while this process compiles it
            else:
                os.close(fd)
            return got

        def _readable(self, sig: Any, target_context: Any, mend: bool = False) -> Any:
            """numba's load, where a file that cannot be read (garbage, truncated) is a miss;
            under the function's lock (``mend``) its index is removed with a one-line notice, so
            that the compile that follows writes a fresh one (numba's save reads the old index
            first, and would fail on it)."""
            try:
                return super().load_overload(sig, target_context)
            except Exception as exc:
                if mend:
                    index = Path(self._cache_file._index_path)
                    _notice(
                        f"kernel cache file {index} could not be read ({type(exc).__name__}): "
                        "rebuilt"
                    )
                    index.unlink(missing_ok=True)
                return None

        def save_overload(self, sig: Any, data: Any) -> None:
            try:
                super().save_overload(sig, data)
            finally:
                _release(self)

    class FailedCompile(ev.Listener):
        """Releases the lock of a compile that raised (nothing will be saved)."""

        def on_start(self, event: Any) -> None:
            pass

        def on_end(self, event: Any) -> None:
            disp = event.data["dispatcher"]
            if tuple(event.data["args"]) not in disp.overloads:  # it raised: nothing to save
                _release(disp._cache)

    ev.register("numba:compile", FailedCompile())
    return SharedCache


def share_compiles(namespace: dict[str, Any], *, llvm_level: int | None = None) -> None:
    """Let every ``cache=True`` numba function of ``namespace`` (a module's ``vars()``) that lies
    in numba's part of the cache be compiled by one process at a time (:func:`_shared_cache`):
    the pipeline's jobs and the test workers start on an empty cache together, and the 6-6
    tracker alone takes over a CPU-minute to compile. ``llvm_level``: LLVM's optimisation level
    for the numba functions of ``namespace`` (numba's is 3), unless ``NUMBA_OPT`` says otherwise;
    a level that leaves the same bits and runs as fast but compiles faster (docs/kernels.md)."""
    from numba.core.caching import FunctionCache
    from numba.core.dispatcher import Dispatcher

    shared = _shared_cache()
    no_gc_while_compiling()
    leveled = llvm_level is not None and "NUMBA_OPT" not in os.environ
    if leveled:
        _compile_levels()
    for disp in namespace.values():
        if not isinstance(disp, Dispatcher):
            continue
        if leveled:
            _LEVELS[disp] = llvm_level
        if type(getattr(disp, "_cache", None)) is FunctionCache:
            disp._cache.__class__ = shared  # same fields, same files: only a miss changes


def share_compiled(functions: Iterable[Any]) -> None:
    """Cache the numba ``functions`` (decorated without ``cache``) in numba's part of the cache
    (``<root>/numba``), compiled by one process at a time (:func:`share_compiles`), whatever
    cache directory is in force where their module was imported. Without a cache root nothing is
    cached (the compiled path is off)."""
    where = root()
    if where is None:
        return
    functions = list(functions)
    with numba_cache(where / "numba"):
        for fn in functions:
            fn.enable_caching()
    share_compiles({fn.__name__: fn for fn in functions})


def guard(fn: Any, where: Path) -> list[Any]:
    """Give every cached numba function that ``fn`` reaches through its globals (the entry, the
    entries it calls, the kernel's functions) and whose cache lies in build ``where`` a
    :func:`_tagged_cache` tagged ``(build, group, name)``, before anything is loaded or compiled:
    whichever caller compiles a function first (an entry, or a loop that calls the kernel's
    functions directly, as the workspace's do), what it writes is tagged. Returns them."""
    from numba.core.caching import FunctionCache
    from numba.core.dispatcher import Dispatcher

    tagged = _tagged_cache()
    out, todo, seen = [], [fn], set()
    while todo:
        disp = todo.pop()
        if id(disp) in seen or not isinstance(disp, Dispatcher):
            continue
        seen.add(id(disp))
        store = getattr(disp, "_cache", None)
        if type(store) in (FunctionCache, tagged):
            try:
                group = Path(store._cache_path).relative_to(where).parts[0]
            except (ValueError, IndexError):
                group = None  # cached elsewhere (numba's part of the cache): keyed by its file
            if group is not None:
                store.__class__ = tagged  # same fields, same locator: only the keys change
                store._parakin_tag = (where.name, group, disp.py_func.__qualname__)
                out.append(disp)
        todo.extend(v for v in disp.py_func.__globals__.values() if isinstance(v, Dispatcher))
    return out


#: the entries of :mod:`parakin.kernels.entries` a known answer is asked of (the particle swarm's,
#: random by design, is checked by its tags alone)
_PROBED = ("serial", "verify_serial")


def _known_answer(fn: Any, args: tuple) -> str | None:
    """Ask entry ``fn`` (called with ``args``) a question whose answer the kernel's own source
    gives on Python floats; None where it answers so, or where no question applies (not an entry
    of :data:`_PROBED`, a first pose outside the kernel's domain, or one so far out that the
    source's own answer is not finite), else what differs.

    The probe: ``x`` the first pose of the call (a start, or an answer to verify), ``q`` its IK
    moved by 1e-3 (1 + |q_k|) k / m. A solver entry, run with ``maxiter = 0``, must return
    ``x`` unchanged and the residual's inf-norm at ``(x, q)``; a verification entry the joint
    error ``max |ik(x) - q|``, in domain, and the assembly flag. One call of the compiled code
    with arrays of the call's own types (nothing new is compiled) and a few kernel evaluations
    on Python floats: microseconds, once per entry and process."""
    import numpy as np

    from parakin.kernels._math import rebind, scalar_names
    from parakin.kernels.methods import VECTOR

    py = fn.py_func
    name = py.__name__
    module = sys.modules.get(py.__globals__.get("KERNEL") or "")
    if name not in _PROBED or module is None:
        return None
    ns = rebind(
        module, scalar_names()
    )  # the kernels on Python floats (parakin.kernels._scalar_namespace)
    verifies = name == "verify_serial"
    p = np.asarray(args[0])
    x = np.array(args[2][0], dtype=float)
    like = args[1][0]
    m = like.shape[0]
    pl, xl, ik = p.tolist(), x.tolist(), [0.0] * m
    try:  # the source's answer on Python floats
        with np.errstate(all="ignore"):
            if not (np.all(np.isfinite(x)) and ns.in_domain(pl, xl) and ns.ik(pl, xl, ik)):
                return None
            ik = np.array(ik)
            q = (ik + 1e-3 * (1 + np.abs(ik)) * np.arange(1, m + 1) / m).astype(like.dtype)
            if verifies:
                want = float(np.max(np.abs(ik - q)))
                on = bool(ns.on_assembly(pl, xl, q.tolist()))
            else:
                r = [0.0] * m
                ns.residual(pl, xl, q.tolist(), r)
                want = float(np.max(np.abs(r)))
    except (ArithmeticError, ValueError):
        return None
    if not (np.all(np.isfinite(q)) and np.isfinite(want)):
        return None  # a pose so far out that the source's own answer overflows: nothing to compare
    scale = 1e-10 * (1 + float(np.max(np.abs(q))))
    if verifies:
        flags, err = np.zeros_like(args[3][:1]), np.zeros_like(args[4][:1])
        fn(p, q[None], x[None], flags, err)
        got, flags = float(err[0]), flags[0]
        if flags[0] == 1 and bool(flags[1]) == on and abs(got - want) <= 1e-7 * want + scale:
            return None
        return (
            f"{name} gave joint error {got:.6g}, flags {flags.tolist()} where the kernel's "
            f"source gives {want:.6g}, [1, {int(on)}]"
        )
    opts = np.array(args[3], copy=True)
    opts[VECTOR.index("maxiter")] = 0
    xo, info, out = (np.zeros_like(args[k][:1]) for k in (4, 5, 6))
    fn(p, q[None], x[None], opts, xo, info, out)
    got, xo = float(out[0, 0]), xo[0]
    if np.array_equal(xo, x) and abs(got - want) <= 1e-7 * want + scale:
        return None
    return f"{name} gave residual {got:.6g} where the kernel's source gives {want:.6g}"


def _forget(dispatchers: list[Any]) -> None:
    """Drop what ``dispatchers`` loaded or compiled in this process: they load (or compile) again
    from the rebuilt directory."""
    for disp in dispatchers:
        disp._reset_overloads()


def first_call(fn: Callable[..., Any], where: Path, *args: Any) -> Any:
    """``fn(*args)`` for the first time: numba loads ``fn`` from its cache in build ``where`` (or
    compiles it), the files tagged and checked (:func:`guard`), then its known answer is asked
    (:func:`_known_answer`) before the call itself. Where any of that fails and another process
    rebuilt ``where`` meanwhile (a new directory), it is tried again; where ``where`` is unchanged
    and holds cached files, an entry could not be read (truncated, garbage), is not what it claims
    (another kernel's, group's or function's) or answers wrong: ``where`` is made again
    (:func:`_discard`: a fresh directory of the same name), under the kernel's lock, and the call
    made once more, with a one-line notice. A failure with an empty build (a genuine compile
    error) is raised; so is a failure of the fresh build. A fresh build that answers its probe
    wrong (numba's own error, never seen) is used with a notice.

    One process at a time makes the first call of a group's entries (:func:`_group_lock`): a process
    that finds another compiling them waits and loads what it wrote, rather than compiling the same
    code beside it (the pipeline's jobs and the test workers start on an empty cache together)."""
    with _group_lock(fn, where):
        return _first_call(fn, where, *args)


@contextmanager
def _group_lock(fn: Any, where: Path) -> Iterator[None]:
    """The exclusive lock of the group of build ``where`` whose cache holds entry ``fn``."""
    cached = getattr(getattr(fn, "_cache", None), "_cache_path", None)
    try:
        group = Path(cached).relative_to(where).parts[0]
    except (TypeError, ValueError, IndexError):
        yield  # not cached in the build: nothing to share
        return
    with _locked(where.parent, f"{where.name}.{group}"):
        yield


def _first_call(fn: Callable[..., Any], where: Path, *args: Any) -> Any:
    guarded = guard(fn, where)
    before, seen = _inode(where), len(_MISMATCHES)
    cause: BaseException | None = None
    try:
        wrong = _known_answer(fn, args)
        if wrong is None:
            return fn(*args)
    except Exception as exc:
        cause, wrong = exc, None
    # a mismatch in the build of the kernel a loop calls (the workspace's loops live in a build of
    # their own): that build is made again, not the loop's
    others = [b for b in dict.fromkeys(_MISMATCHED_BUILDS[seen:]) if b not in (None, where)]
    for other in others:
        with _locked(other.parent, other.name.rpartition("-")[0]):
            _notice(f"kernel cache {other} {_fault(None, None, _MISMATCHES[seen:])}; rebuilt")
            _discard(other, remake=True)
        guarded += guard(fn, other)
    with _locked(where.parent, where.name.rpartition("-")[0]):
        # unless another process rebuilt it meanwhile (or the fault lay in another build)
        if not others and _inode(where) == before:
            if cause is not None and (before is None or not any(where.rglob("*.nb*"))):
                raise cause
            _notice(f"kernel cache {where} {_fault(cause, wrong, _MISMATCHES[seen:])}; rebuilt")
            _discard(where, remake=True)
        _forget(guarded)
        wrong = _known_answer(fn, args)
        if wrong is not None:
            _notice(f"kernel cache {where}: the fresh build fails its known-answer check ({wrong})")
        return fn(*args)


def _fault(cause: BaseException | None, wrong: str | None, mismatches: list[str]) -> str:
    """What was wrong with a build, in one clause."""
    if mismatches:
        return f"holds a file that is not what it claims: {' '.join(mismatches[-1].split())[:400]}"
    if wrong is not None:
        return f"failed its known-answer check: {wrong}"
    while cause.__context__ is not None and "numba" in type(cause).__module__:
        cause = cause.__context__  # numba wraps what went wrong while loading a callee
    return f"could not be read ({type(cause).__name__}: {' '.join(str(cause).split())[:80]})"


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
