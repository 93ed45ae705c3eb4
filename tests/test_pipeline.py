"""The Snakemake pipeline end to end on the quick config: it runs, and two runs give
byte-identical tables and figures (seeds from config, deterministic output): the first with every
job in a process of its own, the second with the single-threaded jobs run by the job server (the
pipeline's default, parakin.launch), so the server is shown to change no output."""

import contextlib
import filecmp
import json
import os
import re
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from parakin import launch
from parakin.io import is_timing_column
from parakin.pipeline import artefacts

ROOT = Path(__file__).resolve().parents[1]


def run_pipeline(workdir: Path, server: str = "") -> Path:
    """The quick pipeline in a copy of the workflow in ``workdir``; ``server``: the job server's
    socket (``PARAKIN_SERVER``), empty for none."""
    for item in ("Snakefile", "workflow", "config"):
        src = ROOT / item
        (shutil.copytree if src.is_dir() else shutil.copy)(src, workdir / item)
    shutil.copytree(ROOT / "data" / "reference", workdir / "data" / "reference")
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "snakemake",
            "--cores",
            "2",
            "--configfile",
            "config/quick.yaml",
            "-q",
        ],
        cwd=workdir,
        env={**os.environ, launch.ENV: server},
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    return workdir / "build" / "quick" / "figures"


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    """The job server's socket for the second run; afterwards its log (one line per job)."""
    socket = tmp_path_factory.mktemp("server") / "s.sock"
    yield socket
    log = socket.with_suffix(".log")
    if log.exists() and (m := re.search(r"parakin server (\d+):", log.read_text())):
        with contextlib.suppress(ProcessLookupError):
            os.kill(int(m.group(1)), signal.SIGTERM)


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory, served):
    alone = run_pipeline(tmp_path_factory.mktemp("run1"))
    return alone, run_pipeline(tmp_path_factory.mktemp("run2"), server=str(served))


def test_pipeline_writes_table1_and_report(two_runs):
    figures, _ = two_runs
    for name in (
        "zhao2017_3p4s/table1.csv",
        "zhao2017_3p4s/table1.md",
        "zhao2017_3p4s/table2.md",
        "zhao2017_3p4s/fk_benchmark.md",
        "REPORT.md",
    ):
        assert (figures / name).stat().st_size > 0
    assert "Table 1 (IK)" in (figures / "REPORT.md").read_text()
    assert not list(figures.rglob(".*.tmp*")), "temporary files left behind"


#: outputs of the artefacts whose tolerance declares them timings (registry): machine-dependent
TIMED_FILES = {
    name for a in artefacts().values() if a.tolerance.kind == "timing" for name in a.outputs
}


def _same(a: Path, b: Path) -> bool:
    if a.name in ("REPORT.md", "report.csv", "benchmarks.md") or a.name in TIMED_FILES:
        return True  # timings, or quotes of them; every other number comes from the files compared here
    if a.suffix == ".json":
        ja, jb = (json.loads(p.read_text()) for p in (a, b))
        return {k: v for k, v in ja.items() if "time" not in k} == {
            k: v for k, v in jb.items() if "time" not in k
        }
    if a.suffix == ".csv":
        da, db = pd.read_csv(a), pd.read_csv(b)
        keep = [c for c in da.columns if not is_timing_column(c)]
        return list(da.columns) == list(db.columns) and da[keep].equals(db[keep])
    timed_csv = a.with_suffix(".csv")
    if (
        a.suffix == ".md"
        and timed_csv.exists()
        and any(is_timing_column(c) for c in pd.read_csv(timed_csv).columns)
    ):
        return True  # the Markdown view of a timed table: its CSV is compared above
    return filecmp.cmp(a, b, shallow=False)


def test_two_runs_are_byte_identical(two_runs):
    """Same config, same seeds -> the same bytes (timing columns aside), network weights included."""
    a, b = two_runs
    files = sorted(p.relative_to(a) for p in a.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(b) for p in b.rglob("*") if p.is_file())
    different = [str(f) for f in files if not _same(a / f, b / f)]
    assert not different
    gen_a, gen_b = a.parent / "generated", b.parent / "generated"
    for f in sorted(p.relative_to(gen_a) for p in gen_a.rglob("*") if p.is_file()):
        assert _same(gen_a / f, gen_b / f), f


@pytest.mark.skipif(not launch.supported(), reason="no fork/pidfd on this platform")
def test_second_run_went_through_the_job_server(two_runs, served):
    """The byte-identity above compares served jobs with jobs run alone: the second run's
    single-threaded artefact jobs went through the server (one line each in its log), but for
    those that came before it listened, and none failed; the multi-threaded ones ran alone."""
    log = served.with_suffix(".log").read_text()
    done = dict(
        ((s, n), code)
        for s, n, code in re.findall(r"parakin reproduce (\S+) (\S+): exit (-?\d+)", log)
    )
    logs = two_runs[1].parent / "logs"
    ran = [a for a in artefacts().values() if (logs / a.study / f"{a.name}.log").exists()]
    single = {(a.study, a.name) for a in ran if a.threads == 1}
    assert set(done) <= single
    assert len(done) >= 0.8 * len(single), f"{len(done)} of {len(single)} jobs served"
    assert set(done.values()) == {"0"}


def test_quick_table1_agrees_with_committed(two_runs):
    """Table 1 does not depend on the quick sizes: the committed full-config table agrees."""
    quick = pd.read_csv(two_runs[0] / "zhao2017_3p4s" / "table1.csv", dtype={"paper": str})
    full = pd.read_csv(ROOT / "figures" / "zhao2017_3p4s" / "table1.csv", dtype={"paper": str})
    assert (quick["paper"] == full["paper"]).all()
    assert np.allclose(quick["stated"], full["stated"], atol=1e-15)
    assert np.allclose(quick["fit"], full["fit"], atol=1e-6)  # the fit's seed grid differs


def test_snakemake_lint_is_clean():
    """`snakemake --lint` passes: log per rule, software env, no hard-coded path params (issue 18)."""
    res = subprocess.run(
        [sys.executable, "-m", "snakemake", "--lint"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]


def test_report_has_every_figure_with_its_caption(two_runs):
    """`snakemake --report` on the finished quick run: every figure and table marked, captioned."""
    workdir = two_runs[0].parents[2]
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "snakemake",
            "--configfile",
            "config/quick.yaml",
            "--report",
            "report.html",
        ],
        cwd=workdir,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    html = (workdir / "report.html").read_text(errors="replace")
    assert "fig03_convergence.png" in html and "table1.csv" in html and "REPORT.md" in html
    assert "Fig. 3" in html  # a caption from the registry (the artefact's docstring)


def test_long_jobs_declare_resources_and_report_progress():
    """The long jobs reserve cores/time for a cluster (profiles/slurm), and print progress."""
    from parakin.pipeline import artefacts

    found = artefacts()
    for key in (
        "zhao2017_3p4s:train",
        "zhao2017_3p4s:ga_runs",
        "zhao2017_3p4s:pareto",
        "zhao2017_3p4s:ga_paper_box",
        "extra:solver_atlas",
        "li2017_stewart36:fig03",
        "li2020_2ups:table2",
    ):
        assert dict(found[key].resources)["runtime"] >= 30, key
    assert all(a.description for a in found.values())
    assert (ROOT / "profiles" / "slurm" / "config.yaml").exists() and (
        ROOT / "docs" / "cluster.md"
    ).exists()


def test_progress_lines(capsys):
    from parakin.progress import Progress, counting

    p = Progress("GA", 20, "generations")
    f = counting(lambda x: x, p)
    for k in range(20):
        f(k)
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 10 and lines[-1].startswith("  GA: 100% (20/20 generations")
