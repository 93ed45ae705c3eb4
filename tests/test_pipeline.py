"""The Snakemake pipeline end to end on the quick config: it runs once, leaves no process behind,
and a small set of targets run again in a fresh copy gives the same bytes (seeds from config,
deterministic output: the trained network's weights and the GA's runs included)."""

import filecmp
import json
import os
import shutil
import subprocess
import sys
import uuid
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from parakin.io import is_timing_column
from parakin.pipeline import artefacts

ROOT = Path(__file__).resolve().parents[1]
#: what a job of the pipeline inherits, so that any process it leaves behind can be found
MARKER = "PARAKIN_TEST_RUN"
#: the targets run a second time: the network's training (chaotic, seeded), a table that uses
#: the trained network, the 30 GA runs and a closed-form table
AGAIN = (
    "zhao2017_3p4s:train",
    "zhao2017_3p4s:table2",
    "zhao2017_3p4s:ga_runs",
    "zhao2017_3p4s:table1",
)


def _copy_workflow(workdir: Path) -> None:
    for item in ("Snakefile", "workflow", "config", "examples"):
        src = ROOT / item
        (shutil.copytree if src.is_dir() else shutil.copy)(src, workdir / item)
    shutil.copytree(ROOT / "data" / "reference", workdir / "data" / "reference")


def run_pipeline(
    workdir: Path, marker: str, targets: tuple[str, ...] = (), config: tuple[str, ...] = ()
) -> Path:
    """The quick pipeline (or only ``targets``) in a copy of the workflow in ``workdir``; every
    job inherits ``MARKER=marker``; ``config``: ``KEY=VALUE`` settings over the quick config."""
    _copy_workflow(workdir)
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "snakemake",
            *targets,  # first: --configfile and --quiet take several values each
            "--cores",
            "2",
            "--configfile",
            "config/quick.yaml",
            *(("--config", *config) if config else ()),
            "--quiet",
            "rules",
        ],
        cwd=workdir,
        env={**os.environ, MARKER: marker},
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    return workdir / "build" / "quick" / "figures"


def _marked_processes(marker: str) -> list[str]:
    """The command lines of the live processes whose environment holds ``MARKER=marker``."""
    found = []
    needle = f"{MARKER}={marker}".encode()
    for proc in Path("/proc").iterdir():
        if not proc.name.isdigit():
            continue
        try:
            if needle in (proc / "environ").read_bytes().split(b"\0"):
                found.append((proc / "cmdline").read_bytes().replace(b"\0", b" ").decode())
        except OSError:  # gone, or not ours to read
            continue
    return found


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    """The whole quick pipeline once: (figures folder, the marker its jobs inherited)."""
    marker = uuid.uuid4().hex
    return run_pipeline(tmp_path_factory.mktemp("run1"), marker), marker


@pytest.fixture(scope="module")
def two_runs(quick_run, tmp_path_factory):
    """The quick run's figures, and those of :data:`AGAIN` run alone in a fresh copy, on two cores
    a job (``max_threads=2``: the quick config runs every job on one, the GA runs and the
    trainings then run side by side in worker processes)."""
    config = _quick_config()
    found = artefacts(config["studies"])
    targets = tuple(
        path
        for k in AGAIN
        for path in found[k].output_paths(config["figures_dir"], config["generated_dir"])
    )
    again = run_pipeline(
        tmp_path_factory.mktemp("run2"), uuid.uuid4().hex, targets, ("max_threads=2",)
    )
    return quick_run[0], again


def _quick_config() -> dict:
    from parakin.config import QUICK_CONFIG, load_run_config

    return load_run_config([QUICK_CONFIG])


@pytest.mark.slow  # the quick pipeline (about 2-4 min of two cores)
def test_no_process_outlives_the_run(quick_run):
    """No process of the pipeline's jobs is left once snakemake has returned (no server, no
    background worker): none carries the marker the run's jobs inherited."""
    if not Path("/proc/self/environ").exists():
        pytest.skip("no /proc on this platform")
    left = _marked_processes(quick_run[1])
    assert not left, f"processes left behind by the quick run: {left}"


@pytest.mark.slow  # the quick pipeline (about 2-4 min of two cores)
def test_timing_tables_name_their_machine(quick_run):
    """A speed table says which machine it was measured on, by what tells two machines of one
    model name apart (:func:`parakin.timing.machine`): the jobs ran on this one."""
    from parakin.timing import machine

    figures, _ = quick_run
    for name in ("benchmarks.md", "extra_kernel_goals.md"):
        assert machine() in (figures / name).read_text(), name


@pytest.mark.slow  # the quick pipeline (about 2-4 min of two cores)
def test_pipeline_writes_table1_and_report(quick_run):
    figures, _ = quick_run
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


@pytest.mark.slow  # the quick pipeline (about 2-4 min of two cores)
def test_two_runs_are_byte_identical(two_runs):
    """Same config, same seeds -> the same bytes (timing columns aside), whatever the cores a job
    takes: every file the second, smaller run made on two cores a job (its targets and their
    upstream, network weights included) equals the whole run's, made on one."""
    a, b = two_runs
    made = sorted(p.relative_to(b.parent) for p in b.parent.rglob("*") if p.is_file())
    made = [f for f in made if f.parts[0] in ("figures", "generated")]
    assert len(made) >= len(AGAIN)
    different = [str(f) for f in made if not _same(a.parent / f, b.parent / f)]
    assert not different
    # the GA's runs went one at a time in the whole run and two at a time in the second
    for run, cores in ((a, 1), (b, 2)):
        log = (run.parent / "logs" / "zhao2017_3p4s" / "ga_runs.log").read_text()
        assert f"({cores} at once)" in log and f"({3 - cores} at once)" not in log


@pytest.mark.slow  # the quick pipeline (about 2-4 min of two cores)
def test_the_atlas_covers_every_registered_mechanism(quick_run):
    """The solver atlas runs on every registered mechanism (a new one by itself), its figure drawn."""
    from parakin import mechanisms

    figures, _ = quick_run
    atlas = pd.read_csv(figures / "extra_solver_atlas.csv")
    assert set(atlas["mechanism"]) == set(mechanisms.REGISTRY)
    assert (figures / "extra_solver_atlas.png").stat().st_size > 0


@pytest.mark.slow  # the quick pipeline (about 2-4 min of two cores)
def test_quick_table1_agrees_with_committed(quick_run):
    """Table 1 does not depend on the quick sizes: the committed full-config table agrees."""
    quick = pd.read_csv(quick_run[0] / "zhao2017_3p4s" / "table1.csv", dtype={"paper": str})
    full = pd.read_csv(ROOT / "figures" / "zhao2017_3p4s" / "table1.csv", dtype={"paper": str})
    assert (quick["paper"] == full["paper"]).all()
    assert np.allclose(quick["stated"], full["stated"], atol=1e-15)
    assert np.allclose(quick["fit"], full["fit"], atol=1e-6)  # the fit's seed grid differs


@pytest.mark.slow  # parses the whole workflow (~10 s)
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


@pytest.mark.slow  # the quick pipeline (about 2-4 min of two cores)
def test_report_has_every_figure_with_its_caption(quick_run):
    """`snakemake --report` on the finished quick run: every figure and table marked, captioned."""
    workdir = quick_run[0].parents[2]
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
