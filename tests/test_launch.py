"""The job server (parakin.launch): a ``parakin reproduce`` job run by a fork of a warm process
writes the same files, prints the same and exits with the same status as the job run on its own;
a server refuses to run jobs on sources other than its own; no server, no change."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from parakin import launch

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ["--config", "config/config.yaml", "--config", "config/quick.yaml"]

pytestmark = pytest.mark.skipif(not launch.supported(), reason="no fork/pidfd on this platform")


def _env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k != launch.ENV}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), env.get("PYTHONPATH", "")])
    env.update(OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")  # as in a one-thread pipeline job
    env.update(extra)
    return env


def _parakin(*args: str, env: dict[str, str]) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "parakin.launch", *args],
        cwd=ROOT,
        env=env,
        capture_output=True,
        timeout=600,
    )


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    path = tmp_path_factory.mktemp("server") / "s.sock"
    env = _env(PARAKIN_SERVER_IDLE="120")
    proc = subprocess.Popen(
        [sys.executable, "-m", "parakin.launch", "--serve", str(path)],
        cwd=ROOT,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    for _ in range(1200):  # the warm-up imports every study (seconds, more on a loaded machine)
        if path.exists() or proc.poll() is not None:
            break
        time.sleep(0.1)
    assert path.exists(), proc.stderr.read().decode() if proc.poll() is not None else "no socket"
    yield path
    proc.terminate()  # stops as when idle: exit status 0, socket removed
    assert proc.wait(timeout=30) == 0 and not path.exists()


def test_a_job_through_the_server_is_the_job_on_its_own(server, tmp_path):
    job = ["reproduce", "ye_stewart12", "table1", *CONFIG]
    alone = _parakin(*job, "--outdir", str(tmp_path / "alone"), env=_env())
    served = _parakin(
        *job, "--outdir", str(tmp_path / "served"), env=_env(PARAKIN_SERVER=str(server))
    )
    assert alone.returncode == served.returncode == 0, served.stdout + served.stderr
    files = sorted(p.name for p in (tmp_path / "alone").iterdir())
    assert files and files == sorted(p.name for p in (tmp_path / "served").iterdir())
    for name in files:
        assert (tmp_path / "alone" / name).read_bytes() == (tmp_path / "served" / name).read_bytes()
    # the job's output comes back on stdout (its stderr merged in, as the pipeline logs it);
    # its CPU line (parakin.pipeline.cpu_line) differs by design: a served job starts warm
    lines = (alone.stdout + alone.stderr).decode().splitlines()
    back = served.stdout.decode().replace("served", "alone").splitlines()
    cpu = [[x for x in out if x.startswith("cpu: table1: start-up ")] for out in (lines, back)]
    assert [len(c) for c in cpu] == [1, 1], (lines, back)
    assert sorted(x for x in back if x not in cpu[1]) == sorted(x for x in lines if x not in cpu[0])


def test_a_failing_job_gives_its_status_and_one_line(server):
    served = _parakin(
        "reproduce", "ye_stewart12", "nope", *CONFIG, env=_env(PARAKIN_SERVER=str(server))
    )
    assert served.returncode == 2
    lines = served.stdout.decode().strip().splitlines()
    assert len(lines) == 1 and "unknown artefact" in lines[0] and "Traceback" not in lines[0]


def test_other_sources_are_refused_and_the_server_stops(tmp_path):
    """A request made from other sources (another stamp) gets "stale"; the server then exits, and
    the command runs on its own."""
    path = tmp_path / "s.sock"
    proc = subprocess.Popen(
        [sys.executable, "-m", "parakin.launch", "--serve", str(path)],
        cwd=ROOT,
        env=_env(),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    for _ in range(1200):
        if path.exists():
            break
        time.sleep(0.1)
    conn = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    conn.connect(str(path))
    request = {"argv": ["reproduce"], "cwd": str(ROOT), "env": {}, "stamp": "other sources"}
    conn.sendall(json.dumps(request).encode() + b"\n")
    assert conn.recv(16) == b"stale\n"
    conn.close()
    assert proc.wait(timeout=60) == 0 and not path.exists()


def test_without_a_server_the_job_runs_itself_and_starts_one(tmp_path):
    sock = tmp_path / "auto.sock"
    job = ["reproduce", "ye_stewart12", "table1", *CONFIG, "--outdir", str(tmp_path / "out")]
    env = _env(PARAKIN_SERVER=str(sock), PARAKIN_SERVER_IDLE="5")
    first = _parakin(*job, env=env)
    assert first.returncode == 0, first.stderr
    assert (tmp_path / "out" / "table1.csv").exists()
    assert sock.with_suffix(".log").exists()  # a server was started for the jobs to come


def test_only_single_threaded_jobs_are_served():
    """A served job's BLAS has one thread (its pool is made before the fork): a job that asks
    for more, or does not say, runs alone; an empty PARAKIN_SERVER turns the server off."""
    one = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    assert launch.servable({launch.ENV: "auto", **one})
    assert not launch.servable({launch.ENV: "", **one})
    assert not launch.servable(one)
    assert not launch.servable({launch.ENV: "auto", **one, "OMP_NUM_THREADS": "2"})
    assert not launch.servable({launch.ENV: "auto", "OPENBLAS_NUM_THREADS": "1"})


def test_one_server_per_slurm_job(monkeypatch, tmp_path):
    """A job never hands its work to a server in another SLURM job's allocation (SLURM would
    count it there and stop it with that job); a path in PARAKIN_SERVER is used as it is."""
    monkeypatch.setenv(launch.ENV, "auto")
    monkeypatch.delenv("SLURM_JOB_ID", raising=False)
    here = launch.socket_path()
    monkeypatch.setenv("SLURM_JOB_ID", "101")
    first = launch.socket_path()
    monkeypatch.setenv("SLURM_JOB_ID", "102")
    assert len({here, first, launch.socket_path()}) == 3
    monkeypatch.setenv(launch.ENV, str(tmp_path / "s.sock"))
    assert launch.socket_path() == tmp_path / "s.sock"


def _other_kernel_family() -> str:
    return "Haswell" if os.environ.get("OPENBLAS_CORETYPE") == "Sandybridge" else "Sandybridge"


def test_another_start_up_environment_gets_another_server(monkeypatch):
    """A forked job keeps its server's BLAS kernels, threads, numba and Python settings: a job
    that asks for others must not share a server with jobs that do not."""
    monkeypatch.setenv(launch.ENV, "auto")
    here = launch.socket_path()
    monkeypatch.setenv("OPENBLAS_CORETYPE", _other_kernel_family())
    assert launch.socket_path() != here
    monkeypatch.setenv("SNAKEMAKE_SOMETHING_PER_JOB", "1")  # what jobs do not read as they start
    monkeypatch.setenv("PATH", os.environ.get("PATH", "") + os.pathsep + "/nowhere")
    other = launch.socket_path()
    monkeypatch.undo()
    monkeypatch.setenv(launch.ENV, "auto")
    monkeypatch.setenv("OPENBLAS_CORETYPE", _other_kernel_family())
    assert launch.socket_path() == other


def test_a_server_refuses_a_job_of_another_start_up_environment(server):
    """Given by path (no key in it), a server answers "other" to a job whose start-up environment
    differs from its own (the job then runs on its own), and goes on serving."""
    env = _env(OPENBLAS_CORETYPE=_other_kernel_family())
    request = {"argv": ["reproduce"], "cwd": str(ROOT), "env": env, "stamp": launch.source_stamp()}
    for _ in range(2):  # still listening after the first refusal
        conn = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        conn.connect(str(server))
        conn.sendall(json.dumps(request).encode() + b"\n")
        assert conn.recv(16) == b"other\n"
        conn.close()


def test_source_stamp_follows_the_sources(tmp_path):
    (tmp_path / "a.py").write_text("x = 1\n")
    before = launch.source_stamp(tmp_path)
    time.sleep(0.01)
    (tmp_path / "a.py").write_text("x = 22\n")
    assert launch.source_stamp(tmp_path) != before
