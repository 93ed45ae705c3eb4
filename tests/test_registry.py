"""The artefact registry: one declaration per artefact drives the pipeline, the check and `which`."""

import ast
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from parakin import registry
from parakin.check import compare_file
from parakin.cli import main
from parakin.pipeline import artefacts, describe

ROOT = Path(__file__).resolve().parents[1]
ARTEFACTS = artefacts()


#: each committed record (the config that makes it): the default run's, and the cluster census's
RECORDS = {"figures": [], "figures/cluster": ["config/cluster.yaml"]}


def test_every_committed_file_is_made_by_one_artefact():
    from parakin.config import load_run_config

    committed = subprocess.run(
        ["git", "ls-files", "figures"], cwd=ROOT, capture_output=True, text=True
    ).stdout.split()
    assert committed, "no committed record"
    for record, overlays in RECORDS.items():
        config = load_run_config([ROOT / o for o in overlays])
        assert config["record_dir"] == record
        found = artefacts(config["studies"])
        declared = {p for a in found.values() for p in a.output_paths(record, "data/generated")}
        others = [r for r in RECORDS if r != record and r.startswith(record + "/")]
        mine = {
            p
            for p in committed
            if p.startswith(record + "/") and not any(p.startswith(o + "/") for o in others)
        }
        assert sorted(mine - declared - {f"{record}/REPORT.md", f"{record}/report.csv"}) == []
        assert sorted(p for p in declared if not p.startswith("data/") and p not in mine) == []


def test_outputs_are_declared_once_and_every_tolerance_has_a_reason():
    seen = {}
    for a in ARTEFACTS.values():
        for path in a.output_paths("figures", "generated"):
            assert path not in seen, f"{path} declared by {seen.get(path)} and {a.key}"
            seen[path] = a.key
        assert a.tolerance.reason.strip() and a.tolerance.kind in registry.KINDS
        for key in a.needs:
            assert key in ARTEFACTS, f"{a.key} needs undeclared {key}"


def test_which_answers_for_every_committed_file(capsys):
    committed = subprocess.run(
        ["git", "ls-files", "figures"], cwd=ROOT, capture_output=True, text=True
    ).stdout.split()
    for path in committed:
        text = describe(path, ARTEFACTS)
        assert "made by:" in text and ".py:" in text, text
    assert main(["which", "figures/zhao2017_3p4s/fig14_ga_convergence.png"]) == 0
    out = capsys.readouterr().out
    assert (
        "zhao2017_3p4s:fig14" in out
        and "optimization.py:" in out
        and "rule:      zhao2017_3p4s_fig14" in out
    )
    assert main(["which", "figures/nowhere.png"]) == 2


def test_sources_follow_the_imports():
    table1 = ARTEFACTS["zhao2017_3p4s:table1"]
    sources = {Path(p).relative_to(ROOT / "src").as_posix() for p in table1.sources()}
    assert "parakin/papers/zhao2017_3p4s/kinematics.py" in sources
    assert "parakin/mechanisms/p3p4s.py" in sources
    assert "parakin/report.py" not in sources


def test_prune_config_keeps_only_declared_sections():
    from parakin.config import DEFAULT_CONFIG, load_config

    config = load_config(DEFAULT_CONFIG)
    pruned = registry.prune_config(config, ARTEFACTS["zhao2017_3p4s:table1"])
    assert set(pruned) == {"seed", "figures_dir", "generated_dir", "zhao2017_3p4s"}
    assert set(pruned["zhao2017_3p4s"]) == {"table1"}


def _import_graph() -> dict[str, set[str]]:
    src = ROOT / "src"
    graph = {}
    for path in (src / "parakin").rglob("*.py"):
        mod = ".".join(path.relative_to(src).with_suffix("").parts).removesuffix(".__init__")
        package = mod if path.name == "__init__.py" else mod.rpartition(".")[0]
        deps = set()
        for node in ast.walk(ast.parse(path.read_text())):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    parts = package.split(".")[: len(package.split(".")) - node.level + 1]
                    base = ".".join([*parts, base] if base else parts)
                names = [base] + [f"{base}.{a.name}" for a in node.names]
            deps |= {n for n in names if n.startswith("parakin")}
        graph[mod] = deps
    # a dependency on a.b.c is one on the module itself (a name imported from it is not a module)
    return {
        m: {d if d in graph else d.rpartition(".")[0] for d in deps} - {m}
        for m, deps in graph.items()
    }


def test_no_import_cycle():
    """Late imports inside functions count too: the module graph must be acyclic."""
    graph = _import_graph()
    state, cycle = {}, []

    def visit(m, stack):
        state[m] = 1
        for d in sorted(graph.get(m, ())):
            if d not in graph:
                continue
            if state.get(d) == 1:
                cycle.append(stack[stack.index(d) :] + [d])
            elif d not in state:
                visit(d, stack + [d])
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m, [m])
    assert not cycle, cycle[:3]


def test_check_statuses(tmp_path):
    tol = registry.ROUNDING
    rec, new = tmp_path / "rec.csv", tmp_path / "new.csv"
    pd.DataFrame({"a": [1.0, 2.0], "label": ["x", "y"], "time_ms": [1, 2]}).to_csv(rec, index=False)
    pd.DataFrame({"a": [1.0, 2.0 + 1e-9], "label": ["x", "y"], "time_ms": [5, 9]}).to_csv(
        new, index=False
    )
    assert compare_file(rec, new, tol)[0] == "within tolerance"  # timing columns never decide
    pd.DataFrame({"a": [1.0, 2.1], "label": ["x", "y"], "time_ms": [1, 2]}).to_csv(new, index=False)
    status, column, excess, detail = compare_file(rec, new, tol)
    assert (status, column) == ("differs", "a") and excess > 1 and "row 1" in detail
    pd.DataFrame({"a": [1.0, 2.0], "label": ["x", "z"], "time_ms": [1, 2]}).to_csv(new, index=False)
    assert compare_file(rec, new, tol)[:2] == ("differs", "label")
    new.write_bytes(rec.read_bytes())
    assert compare_file(rec, new, tol)[0] == "identical"
    assert compare_file(rec, tmp_path / "absent.csv", tol)[0] == "missing"
    stat = registry.Tolerance(
        "statistical", 0.0, 0.0, "only b is stable", columns={"b": (0.1, 0.0)}
    )
    pd.DataFrame({"a": [1.0], "b": [10.0]}).to_csv(rec, index=False)
    pd.DataFrame({"a": [7.0], "b": [10.5]}).to_csv(new, index=False)
    assert (
        compare_file(rec, new, stat)[0] == "within tolerance"
    )  # statistical: only declared columns
    pd.DataFrame({"a": [1.0], "b": [12.0]}).to_csv(new, index=False)
    assert compare_file(rec, new, stat)[:2] == ("differs", "b")


def _workdir(tmp_path: Path) -> Path:
    for item in ("Snakefile", "workflow", "config", "examples"):
        src = ROOT / item
        (shutil.copytree if src.is_dir() else shutil.copy)(src, tmp_path / item)
    shutil.copytree(ROOT / "data" / "reference", tmp_path / "data" / "reference")
    return tmp_path


@pytest.mark.slow  # snakemake in a fresh process
def test_fresh_clone_schedules_every_artefact(tmp_path):
    """Nothing counts as done because it is committed: a dry run on a fresh tree plans every rule."""
    work = _workdir(tmp_path)
    shutil.copytree(ROOT / "figures", work / "figures")
    res = subprocess.run(
        [sys.executable, "-m", "snakemake", "-n", "--cores", "2", "--quiet", "rules"],
        cwd=work,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert res.returncode == 0, res.stderr[-2000:]
    planned = {
        line.split()[0]
        for line in res.stdout.splitlines()
        if line.strip() and line.split()[-1].isdigit()
    }
    rules = {job.rule for job in registry.jobs(ARTEFACTS)}
    assert rules | {"report", "reproduction_check", "all"} <= planned


def test_every_artefact_is_made_by_one_job_and_small_ones_share_their_module_s():
    """The pipeline's jobs (registry.jobs): each artefact in exactly one; a job of several holds
    only small artefacts (one thread, default resources, nothing upstream or downstream) of one
    module, and every module with several small artefacts has one such job; an artefact with
    threads, resources or links runs alone, under its own rule."""
    jobs = registry.jobs(ARTEFACTS)
    made = [item.key for job in jobs for item in job.items]
    assert sorted(made) == sorted(ARTEFACTS) and len(made) == len(set(made))
    linked = {k for a in ARTEFACTS.values() for k in (a.key, *a.needs) if a.needs}
    for job in jobs:
        if len(job.items) > 1:
            assert job.small and len({a.module for a in job.items}) == 1, job.rule
            assert all(a.threads == 1 and not a.resources for a in job.items), job.rule
            assert not {a.key for a in job.items} & linked, job.rule
        elif not job.small:
            assert job.rule == job.items[0].rule
    assert any(len(job.items) > 1 for job in jobs)
    for module in {a.module for a in ARTEFACTS.values()}:
        shared = [j for j in jobs if j.small and j.items[0].module == module]
        assert len(shared) <= 1, module
    heavy = ARTEFACTS["zhao2017_3p4s:ga_runs"]  # threads and resources: alone
    assert [j.items for j in jobs if heavy in j.items] == [(heavy,)]


@pytest.mark.slow  # a pipeline run: snakemake in a fresh process
def test_a_toy_study_runs_from_one_registration_line(tmp_path):
    """A new mechanism with its own paper: one line in the config's `studies`, nothing else shared."""
    work = _workdir(tmp_path)
    shutil.copy(ROOT / "tests" / "data" / "toy_study.py", work / "toy_study.py")
    # folders with a space: every path reaches the shell quoted
    (work / "toy.yaml").write_text(
        "studies: [toy_study]\nrecord_dir: null\n"
        "figures_dir: 'build/quick run/figures'\ngenerated_dir: 'build/quick run/generated'\n"
    )
    env = {**__import__("os").environ, "PYTHONPATH": str(work)}
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "snakemake",
            "--cores",
            "2",
            "--configfile",
            "config/quick.yaml",
            "toy.yaml",
            "-q",
        ],
        cwd=work,
        capture_output=True,
        text=True,
        timeout=600,
        env=env,
    )
    assert res.returncode == 0, res.stdout[-2000:] + res.stderr[-2000:]
    table = pd.read_csv(work / "build" / "quick run" / "figures" / "toy_study" / "table1.csv")
    assert len(table) == 10 and table["error_m"].max() < 1e-9


def test_a_shared_job_makes_the_same_bytes_as_its_artefacts_alone(tmp_path, capsys):
    """`parakin reproduce STUDY A B` (a job of several small artefacts) writes what each artefact
    writes alone, each given only its own config sections, and logs one CPU line per artefact."""
    import json

    from parakin.config import QUICK_CONFIG, load_run_config, merge

    config = load_run_config([QUICK_CONFIG])
    module = "parakin.papers.zhao2017_3p4s.kinematics"
    names = ["fig01", "fig02"]
    items = [ARTEFACTS[f"zhao2017_3p4s:{n}"] for n in names]
    merged: dict = {}
    for item in items:  # what the pipeline passes a shared job (workflow/rules/common.smk)
        merged = merge(merged, registry.prune_config(config, item))
    common = ["--module", module, "--config-json", json.dumps(merged), "--validated"]
    for name in names:
        assert (
            main(["reproduce", "zhao2017_3p4s", name, "--outdir", str(tmp_path / "alone"), *common])
            == 0
        )
    capsys.readouterr()
    assert (
        main(["reproduce", "zhao2017_3p4s", *names, "--outdir", str(tmp_path / "job"), *common])
        == 0
    )
    cpu = [line for line in capsys.readouterr().err.splitlines() if line.startswith("cpu: ")]
    assert [line.split()[1] for line in cpu] == [f"{n}:" for n in names]
    assert "start-up 0.000 s" in cpu[1] and "start-up 0.000 s" not in cpu[0]
    made = sorted(p.name for p in (tmp_path / "job").iterdir())
    assert made == sorted(f for item in items for f in item.outputs)
    for name in made:
        assert (tmp_path / "job" / name).read_bytes() == (tmp_path / "alone" / name).read_bytes(), (
            name
        )
