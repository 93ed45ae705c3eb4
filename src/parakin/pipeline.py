"""The registry-driven commands behind ``parakin reproduce``, ``check``, ``which`` and ``record``.

They only read the registry (:mod:`parakin.registry`) and the config: which studies exist, which
artefact writes which file, and where the results and the committed record live.
"""

from __future__ import annotations

import importlib
import importlib.util
import pkgutil
import re
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from parakin import papers, registry
from parakin import studies as extra_studies
from parakin.config import DEFAULT_CONFIG, ROOT, load_config
from parakin.errors import ConfigError
from parakin.io import atomic_copy

__all__ = [
    "studies",
    "known_studies",
    "check_studies",
    "artefacts",
    "reproduce",
    "check",
    "which",
    "record",
    "describe",
    "cpu_line",
    "startup_share",
]


def studies(config: dict | None = None) -> list[str]:
    """The study modules of ``config`` (default: the packaged full config)."""
    config = load_config(DEFAULT_CONFIG) if config is None else config
    return list(config["studies"])


def known_studies() -> list[str]:
    """The study modules parakin ships: one per paper, and those beyond the papers."""
    return [f"parakin.papers.{key}" for key in papers.KEYS] + [
        f"parakin.studies.{m.name}" for m in pkgutil.iter_modules(extra_studies.__path__)
    ]


def check_studies(names: list[str]) -> None:
    """Raise ConfigError (one line, the known studies listed) unless every one of ``names`` is an
    importable module that declares at least one ``@artefact`` (a study of your own must be on
    the Python path, as ``tests/test_registry.py``'s toy study is)."""
    for name in names:
        problem = _study_problem(name)
        if problem:
            raise ConfigError(
                f"config key 'studies': {name!r} {problem} (parakin's studies: "
                f"{', '.join(known_studies())}; a study of your own must be importable)"
            )


def _study_problem(name: str) -> str:
    try:
        found = importlib.util.find_spec(name) is not None
    except (ImportError, ValueError):  # a parent package is missing
        found = False
    if not found:
        return "is not a module"
    try:
        registry.import_study(name)
    except ImportError as exc:
        return f"cannot be imported ({exc})"
    if not any(
        a.module == name or a.module.startswith(name + ".") for a in registry.REGISTRY.values()
    ):
        return "declares no @artefact"
    return ""


def artefacts(
    names: list[str] | None = None, *, complete: bool = True
) -> dict[str, registry.Artefact]:
    """The registry restricted to the studies ``names`` (default: the full config's), each
    checked (:func:`check_studies`)."""
    names = list(names) if names else studies()
    check_studies(names)
    return registry.load(names, complete=complete)


def reproduce(
    study: str,
    name: str | Sequence[str],
    config: dict,
    outdir: Path | None,
    module: str | None = None,
) -> list[Path]:
    """Run one artefact, or several in the order given (a pipeline job that makes several
    artefacts of one module, :func:`parakin.registry.jobs`), into ``outdir``; ``name == "all"``:
    every artefact of the study, upstream first. Each artefact is given only the config sections
    it declares (:func:`parakin.registry.prune_config`), as if it ran alone."""
    found = artefacts([module] if module else config.get("studies"), complete=not module)
    names = [name] if isinstance(name, str) else list(name)
    if names == ["all"]:
        items = [a for a in found.values() if a.study == study]
        if not items:
            registry.find(found, study, "all")
    else:
        items = [registry.find(found, study, n) for n in names]
    paths = []
    # the process's CPU so far (interpreter, imports, config)
    startup = _cpu()
    for item in items:
        out = Path(outdir) if outdir else Path(config["figures_dir"]) / item.study_folder
        start = _cpu()
        paths += item.make(registry.prune_config(config, item), out)
        print(cpu_line(item.name, startup, _cpu() - start), file=sys.stderr)
        startup = 0.0  # paid once per process
    return paths


def _cpu() -> float:
    """CPU seconds of this process (every thread) and of its finished child processes (the
    workers that run independent runs side by side, :func:`parakin.papers.runs.map_runs`)."""
    import resource

    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + children.ru_utime + children.ru_stime


def cpu_line(name: str, startup: float, work: float) -> str:
    """The line each pipeline job writes to its log: what its process spent on start-up (the
    interpreter, the imports, the config) and on the artefact itself, in CPU seconds (all
    threads, and the worker processes it started), and whether numba was started (its own start, about 0.5-1 s, is then part of the
    artefact's share). :func:`startup_share` adds them up over a run's logs."""
    numba = "numba started" if "numba" in sys.modules else "no numba"
    return f"cpu: {name}: start-up {startup:.3f} s, artefact {work:.3f} s ({numba})"


_CPU_LINE = re.compile(
    r"^cpu: (\S+): start-up ([0-9.]+) s, artefact ([0-9.]+) s \((numba started|no numba)\)$"
)


def startup_share(logs: str | Path) -> dict[str, float]:
    """The :func:`cpu_line` lines of every log under ``logs`` (a run's ``<generated>/../logs``)
    added up: jobs, start-up and artefact CPU seconds, the jobs that started numba, and the
    start-up's share of the jobs' CPU."""
    rows = [
        m.groups()
        for log in sorted(Path(logs).rglob("*.log"))
        for line in log.read_text(errors="replace").splitlines()
        if (m := _CPU_LINE.match(line.strip()))
    ]
    startup = sum(float(r[1]) for r in rows)
    work = sum(float(r[2]) for r in rows)
    return {
        "jobs": len(rows),
        "numba_jobs": sum(r[3] == "numba started" for r in rows),
        "startup_s": startup,
        "artefact_s": work,
        "startup_share": startup / (startup + work) if rows else float("nan"),
    }


def check(
    results: Path, record: Path, out: Path, names: list[str] | None = None
) -> tuple[Path, Path, str]:
    """Write the reproduction check of ``results`` against ``record``; return its files and summary line."""
    from parakin.check import write_check

    return write_check(artefacts(names), Path(results), Path(record), Path(out))


#: files the pipeline writes outside any artefact: (file name, what makes it)
SPECIAL = {
    "REPORT.md": ("parakin.report.build_report", "report"),
    "report.csv": ("parakin.report.write_report", "report"),
    "reproduction_check.md": ("parakin.check.write_check", "reproduction_check"),
    "reproduction_check.csv": ("parakin.check.write_check", "reproduction_check"),
}


def _location(dotted: str) -> str:
    import inspect

    module, _, attr = dotted.rpartition(".")
    fn = getattr(importlib.import_module(module), attr)
    return f"{inspect.getsourcefile(fn)}:{inspect.getsourcelines(fn)[1]}"


def describe(
    path: str | Path,
    found: dict[str, registry.Artefact] | None = None,
    rules: dict[str, str] | None = None,
) -> str:
    """What makes ``path``: the artefact, its function (file:line), its rule and its tolerance.
    ``rules``: each artefact's rule (:func:`rules_of`), computed once by a caller that describes
    several paths."""
    found = artefacts() if found is None else found
    name = Path(path).name
    if name in SPECIAL:
        fn, rule = SPECIAL[name]
        return f"{path}\n  made by:   {fn} ({_relative(_location(fn))})\n  rule:      {rule}"
    item = registry.which(found, path)
    if item is None:
        raise ValueError(
            f"no registered artefact writes {str(path)!r} (`parakin which --list` lists every file)"
        )
    tol = item.tolerance
    rule = (rules_of(found) if rules is None else rules)[item.key]
    lines = [
        f"{path}",
        f"  artefact:  {item.key}",
        f"  made by:   {item.module}.{item.make.__name__} ({_relative(item.location)})",
        f"  rule:      {rule}  (snakemake --cores 2 {rule})",
        f"  config:    {', '.join(['seed', *item.config])}",
        f"  needs:     {', '.join(item.needs) or '-'}",
        f"  writes:    {', '.join(item.outputs + item.generated)}",
        f"  tolerance: {tol.kind}: {tol.reason}",
    ]
    return "\n".join(lines)


def _relative(location: str) -> str:
    try:
        return str(Path(location).relative_to(ROOT))
    except ValueError:
        return location


def which(paths: list[str], list_all: bool = False) -> str:
    found = artefacts()
    if list_all:
        return "\n".join(
            f"{a.study_folder + '/' if a.study_folder else ''}{f}\t{a.key}"
            for a in found.values()
            for f in a.outputs
        )
    rules = rules_of(found)
    return "\n\n".join(describe(p, found, rules) for p in paths)


def rules_of(found: dict[str, registry.Artefact]) -> dict[str, str]:
    """The rule of the pipeline job that makes each artefact, by key (:func:`registry.jobs`)."""
    return {item.key: job.rule for job in registry.jobs(found) for item in job.items}


def record(results: Path, record_dir: Path, names: list[str] | None = None) -> list[Path]:
    """Copy every registered output (and REPORT.md) of a finished run into the record."""
    copied = []
    files = [(a.study_folder, f) for a in artefacts(names).values() for f in a.outputs] + [
        ("", "REPORT.md"),
        ("", "report.csv"),
    ]
    missing = [str(Path(results) / d / f) for d, f in files if not (Path(results) / d / f).exists()]
    if missing:
        raise FileNotFoundError(
            f"the run in {results} is incomplete ({len(missing)} files missing, e.g. "
            f"{missing[0]}): finish it with snakemake before recording"
        )
    for folder, name in files:
        copied.append(atomic_copy(Path(results) / folder / name, Path(record_dir) / folder / name))
    print(
        f"parakin record: {len(copied)} files copied from {results} to {record_dir}",
        file=sys.stderr,
    )
    return copied
