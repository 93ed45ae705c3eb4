"""The ``parakin`` command's entry point, and a server that runs pipeline jobs in one warm process.

Every job of the pipeline is one ``parakin reproduce ...`` command (or ``report``, ``check``). On
its own each pays Python's start, the imports (numpy, scipy, pandas, matplotlib, sympy, parakin) and, where it compiles,
numba's start: 0.7-1.1 s of CPU per job, 23 % of the quick pipeline's CPU time on its own against
5 % through the server (measured: docs/kernels.md, "Start-up"). With
``PARAKIN_SERVER=auto`` (or a socket path) in its environment, ``parakin reproduce`` hands its
job to a server that has all of that loaded and **forks a fresh copy of itself for each job**:
the start-up is paid once per server, while every job still runs in a process of its own (nothing
carries over from one job to the next) with its own arguments, working directory and environment;
its output comes back on the command's stdout and its exit status is the command's.

The first job finds no server, starts one in the background and runs itself. The server stops
after ``PARAKIN_SERVER_IDLE`` seconds without a job (default 120) and as soon as parakin's source
files change (a job never runs on other code than its own: it then runs itself, and the next one
starts a new server). What a process reads from its environment as it starts (the BLAS kernel
family and threads, numba, Python, the temporary and cache directories:
:func:`startup_environment`) a forked job takes from its server, so a server serves only jobs
whose values are its own; with ``auto``, jobs of another environment find a server of their own.
Without the variable (or with it empty), or where anything goes wrong on the way, the command runs
in its own process as always. The pipeline sets ``PARAKIN_SERVER=auto`` for
its jobs unless the variable is already set, and not inside a SLURM job, whose steps SLURM stops
with all their processes (workflow/rules/common.smk).

Only single-threaded jobs are served: BLAS runs on one thread in the server's jobs (numpy's thread
pool is made before the fork), so a job that asks for more (``OPENBLAS_NUM_THREADS`` or
``OMP_NUM_THREADS`` other than 1, or unset) runs in its own process, where its BLAS gets the
threads it asks for; numba and torch threads are as in a job of its own. The long jobs are the
multi-threaded ones, so their start-up is a small part of their CPU anyway.

A served job's log counts as start-up its own CPU before the artefact plus the CPU its client
command spent before handing it over (:data:`parakin.pipeline.startup_elsewhere`). The server's
own warm-up, paid once per server, is written to the server's log beside its socket.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import selectors
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

__all__ = ["main", "serve"]

ENV = "PARAKIN_SERVER"
#: the commands a pipeline job runs: these go through the server where there is one
PIPELINE_COMMANDS = ("reproduce", "report", "check")
_ACCEPTED, _STALE, _OTHER = b"ok\n", b"stale\n", b"other\n"
#: what follows a job's output on the socket: this marker and the exit status
_TRAILER = b"\x00parakin-exit "
_SOURCES = Path(__file__).resolve().parent


#: the thread variables a served job's BLAS must ask no more than one thread of
_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")
#: the environment a process reads as it starts, which a forked job inherits from its server
#: whatever its own says: BLAS and OpenMP (the kernel family ``OPENBLAS_CORETYPE``, threads),
#: numba, Python, matplotlib, the loader, the temporary and cache directories and parakin's
#: kernel switches. A server serves only jobs whose values of these are its own.
_STARTUP_PREFIXES = (
    "OPENBLAS_", "GOTOBLAS", "OMP_", "GOMP_", "KMP_", "MKL_", "NUMBA_", "PYTHON", "MPL", "LD_",
    "TMP", "TEMP", "HOME", "XDG_", "PARAKIN_KERNEL",
)  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    """``parakin ...``: a single-threaded pipeline job (:data:`PIPELINE_COMMANDS`) through the
    server where ``PARAKIN_SERVER`` is set, everything else (and any job the server cannot take)
    by :func:`parakin.cli.main`."""
    args = sys.argv[1:] if argv is None else list(argv)
    if args[:1] and args[0] in PIPELINE_COMMANDS and servable(os.environ) and supported():
        code = _delegate(args)
        if code is not None:
            return code
    from parakin.cli import main as cli_main

    return cli_main(args)


def servable(env) -> bool:
    """Whether a job with environment ``env`` goes to the server: ``PARAKIN_SERVER`` is set and
    not empty, and it asks BLAS for one thread (see the module)."""
    return bool(env.get(ENV)) and all(env.get(v) == "1" for v in _THREAD_VARIABLES)


def startup_environment(env) -> dict[str, str]:
    """The variables of ``env`` that take effect when a process starts (:data:`_STARTUP_PREFIXES`):
    a job whose values differ from a server's runs elsewhere (``OPENBLAS_CORETYPE=Sandybridge``
    right after a run on the default kernels must not get the server's kernels)."""
    return {k: env[k] for k in sorted(env) if k.startswith(_STARTUP_PREFIXES)}


def supported() -> bool:
    """Whether this platform can run the server (fork, Unix sockets, Linux's pidfd)."""
    return hasattr(os, "fork") and hasattr(os, "pidfd_open") and hasattr(socket, "AF_UNIX")


def socket_path() -> Path:
    """The server's socket: ``$PARAKIN_SERVER`` if it is a path, else one per user, Python,
    parakin checkout, SLURM job and start-up environment (:func:`startup_environment`) in the
    temporary directory. (Per SLURM job: a server lives in the job that started it, and SLURM
    stops it with that job; a job of its own must not run its work in another job's allocation.)"""
    value = os.environ.get(ENV, "auto")
    if value not in ("auto", "1", "on"):
        return Path(value)
    slurm_job = os.environ.get("SLURM_JOB_ID", "")
    startup = json.dumps(startup_environment(os.environ))
    key = f"{sys.executable}\0{_SOURCES}\0{slurm_job}\0{startup}"
    key = hashlib.sha256(key.encode()).hexdigest()[:12]
    user = os.getuid() if hasattr(os, "getuid") else "user"
    return Path(tempfile.gettempdir()) / f"parakin-{user}" / f"server-{key}.sock"


def source_stamp(root: Path = _SOURCES) -> str:
    """A digest of the names, sizes and modification times of parakin's Python sources."""
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        st = path.stat()
        h.update(f"{path}\0{st.st_size}\0{st.st_mtime_ns}\n".encode())
    return h.hexdigest()


# ---------------------------------------------------------------------------- the client
def _delegate(args: list[str]) -> int | None:
    """The exit status of ``args`` run by the server, or None: no server (one is started for the
    jobs to come), a stale one, or a failure before the job started (run it here)."""
    path = socket_path()
    try:
        conn = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        conn.connect(str(path))
    except OSError:
        _start_server(path)
        return None
    with conn:
        request = {"argv": args, "cwd": os.getcwd(), "env": dict(os.environ)}
        request["stamp"] = source_stamp()
        request["cpu"] = time.process_time()
        try:
            conn.sendall(json.dumps(request).encode() + b"\n")
            if conn.recv(len(_ACCEPTED)) != _ACCEPTED:
                return None  # stale sources (the server is stopping) or another environment
        except OSError:
            return None
        return _relay(conn)


def _relay(conn: socket.socket) -> int:
    """Copy the job's output to stdout until the trailer; its exit status."""
    out = sys.stdout.buffer
    tail = b""
    while True:
        chunk = conn.recv(65536)
        if not chunk:
            break
        data = tail + chunk
        keep = len(_TRAILER) + 8  # the trailer may be split across chunks: hold back its length
        out.write(data[:-keep])
        tail = data[-keep:]
        out.flush()
    head, sep, code = tail.rpartition(_TRAILER)
    if not sep:  # the server went away mid-job
        out.write(tail)
        out.flush()
        print("parakin: error: the job server stopped before the job finished", file=sys.stderr)
        return 1
    out.write(head)
    out.flush()
    return int(code.strip() or 1)


#: seconds a server may take to warm up and listen before another job may start one
_STARTING_S = 60.0


def _start_server(path: Path) -> None:
    """Start a server on ``path`` in the background (its log beside the socket), unless another
    job started one less than :data:`_STARTING_S` ago that is still warming up (its marker
    ``.starting`` beside the socket): the jobs that come meanwhile run on their own rather than
    each paying a server's warm-up."""
    starting = path.with_suffix(".starting")
    try:
        path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        with contextlib.suppress(FileNotFoundError):
            if time.time() - starting.stat().st_mtime < _STARTING_S:
                return
            starting.unlink()
        os.close(os.open(starting, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600))
        if path.exists():
            path.unlink()  # a server that died: nobody listens
        log = open(path.with_suffix(".log"), "ab")
    except OSError:
        return
    with log:
        subprocess.Popen(
            [sys.executable, "-m", "parakin.launch", "--serve", str(path)],
            stdin=subprocess.DEVNULL,
            stdout=log,
            stderr=log,
            start_new_session=True,
        )


# ---------------------------------------------------------------------------- the server
def _warm_up() -> None:
    """Import what the jobs import, and start numba (its registry load), once."""
    os.environ.update(OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    import parakin.cli  # noqa: F401  (numpy, yaml, the mechanisms)
    from parakin import kernels, pipeline

    pipeline.artefacts()  # every study module: scipy, pandas, matplotlib, sympy, ...
    if kernels.enabled():
        from parakin.kernels import store

        store.warm_numba()


def _run_job(conn: socket.socket, request: dict) -> None:
    """In the forked child: the job as its own process would run it, then exit."""
    code = 1
    try:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)  # a cancelled job stops, as on its own
        null = os.open(os.devnull, os.O_RDONLY)
        os.dup2(null, 0)
        os.dup2(conn.fileno(), 1)
        os.dup2(conn.fileno(), 2)
        os.chdir(request["cwd"])
        os.environ.clear()
        os.environ.update(request["env"])
        sys.argv = ["parakin", *request["argv"]]
        from parakin import pipeline
        from parakin.cli import main as cli_main

        pipeline.startup_elsewhere = float(request.get("cpu", 0.0))

        code = cli_main(request["argv"])
    except SystemExit as exc:  # argparse's errors (status 2)
        code = exc.code if isinstance(exc.code, int) else 1
    except BaseException as exc:  # noqa: BLE001  (reported like an uncaught error of a process)
        import traceback

        traceback.print_exception(exc)
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)


def serve(path: Path, idle: float | None = None) -> None:
    """Listen on ``path`` and run each job in a fork of this warm process (see the module)."""
    idle = float(os.environ.get("PARAKIN_SERVER_IDLE", "120")) if idle is None else idle
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))  # stop as when idle: socket removed
    startup = startup_environment(os.environ)  # as inherited, before the warm-up sets threads
    _warm_up()
    print(f"parakin server {os.getpid()}: warm-up {time.process_time():.3f} s of CPU", flush=True)
    stamp = source_stamp()
    path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        listener.bind(str(path))
    except OSError:  # another server is there first
        path.with_suffix(".starting").unlink(missing_ok=True)
        return
    listener.listen(64)
    path.with_suffix(".starting").unlink(missing_ok=True)
    sel = selectors.DefaultSelector()
    sel.register(listener, selectors.EVENT_READ)
    jobs: dict[int, tuple[socket.socket, int, str]] = {}  # pidfd -> (connection, pid, command)
    last = time.monotonic()
    try:
        while jobs or time.monotonic() - last < idle:
            for key, _ in sel.select(timeout=1.0):
                if key.fileobj is listener:
                    if not _accept(listener, stamp, startup, sel, jobs):
                        return  # sources changed: stop (the running jobs finish on their own)
                elif key.data is not None:  # the client of job key.data closed its end
                    _cancel(key.data)
                else:
                    _finish(key.fd, sel, jobs)
                last = time.monotonic()
    finally:
        sel.close()
        listener.close()
        path.unlink(missing_ok=True)
        import resource  # Unix only, as the server is

        cpu = sum(
            getattr(resource.getrusage(who), f)
            for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN)
            for f in ("ru_utime", "ru_stime")
        )
        print(
            f"parakin server {os.getpid()}: stopped, {cpu:.3f} s of CPU with its jobs", flush=True
        )


def _accept(listener, stamp: str, startup: dict, sel, jobs) -> bool:
    """Take one job: fork it; refuse it where the sources changed (returns False: the server
    stops) or where its start-up environment is not the server's (the job runs on its own)."""
    conn, _ = listener.accept()
    conn.settimeout(10.0)
    try:
        line = b""
        while not line.endswith(b"\n"):
            part = conn.recv(1 << 20)
            if not part:
                raise OSError("no request")
            line += part
        request = json.loads(line)
        if request.get("stamp") != stamp:
            conn.sendall(_STALE)
            conn.close()
            return False
        if startup_environment(request.get("env", {})) != startup:
            conn.sendall(_OTHER)
            conn.close()
            return True
        conn.sendall(_ACCEPTED)
    except (OSError, ValueError):
        conn.close()
        return True
    conn.settimeout(None)
    pid = os.fork()
    if pid == 0:
        _run_job(conn, request)
    fd = os.pidfd_open(pid)
    jobs[fd] = (conn, pid, " ".join(request["argv"][:3]))
    sel.register(fd, selectors.EVENT_READ)
    sel.register(conn, selectors.EVENT_READ, pid)  # readable: the client went away
    return True


def _finish(fd: int, sel, jobs) -> None:
    """A job ended: its exit status to its client (and a line to the server's log)."""
    conn, pid, command = jobs.pop(fd)
    sel.unregister(fd)
    sel.unregister(conn)
    os.close(fd)
    _, status = os.waitpid(pid, 0)
    code = os.waitstatus_to_exitcode(status)
    code = code if code >= 0 else 128 - code  # killed by a signal: the shell's convention
    print(f"job {pid}: parakin {command}: exit {code}", flush=True)
    try:
        conn.sendall(_TRAILER + str(code).encode())
    except OSError:
        pass
    conn.close()


def _cancel(pid: int) -> None:
    """Stop a job whose command was stopped (Snakemake cancelled it, or Ctrl-C)."""
    try:
        os.kill(pid, signal.SIGTERM)
    except ProcessLookupError:
        pass


if __name__ == "__main__":
    if sys.argv[1:2] == ["--serve"]:
        serve(Path(sys.argv[2]))
    else:
        sys.exit(main())
