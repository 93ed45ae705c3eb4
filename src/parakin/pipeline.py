"""The registry-driven commands behind ``parakin reproduce``, ``check``, ``which`` and ``record``.

They only read the registry (:mod:`parakin.registry`) and the config: which studies exist, which
artefact writes which file, and where the results and the committed record live.
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

from parakin import registry
from parakin.config import DEFAULT_CONFIG, ROOT, load_config

__all__ = ["studies", "artefacts", "reproduce", "check", "which", "record", "describe"]


def studies(config: dict | None = None) -> list[str]:
    """The study modules of ``config`` (default: the packaged full config)."""
    config = load_config(DEFAULT_CONFIG) if config is None else config
    return list(config["studies"])


def artefacts(
    names: list[str] | None = None, *, complete: bool = True
) -> dict[str, registry.Artefact]:
    """The registry restricted to the studies ``names`` (default: the full config's)."""
    return registry.load(names or studies(), complete=complete)


def reproduce(
    study: str, name: str, config: dict, outdir: Path | None, module: str | None = None
) -> list[Path]:
    """Run one artefact (``name == "all"``: every artefact of the study, upstream first) into ``outdir``."""
    found = artefacts([module] if module else None, complete=not module)
    if name == "all":
        items = [a for a in found.values() if a.study == study]
        if not items:
            registry.find(found, study, "all")
    else:
        items = [registry.find(found, study, name)]
    paths = []
    for item in items:
        out = Path(outdir) if outdir else Path(config["figures_dir"]) / item.study_folder
        paths += item.make(config, out)
    return paths


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
    import importlib
    import inspect

    module, _, attr = dotted.rpartition(".")
    fn = getattr(importlib.import_module(module), attr)
    return f"{inspect.getsourcefile(fn)}:{inspect.getsourcelines(fn)[1]}"


def describe(path: str | Path, found: dict[str, registry.Artefact] | None = None) -> str:
    """What makes ``path``: the artefact, its function (file:line), its rule and its tolerance."""
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
    lines = [
        f"{path}",
        f"  artefact:  {item.key}",
        f"  made by:   {item.module}.{item.make.__name__} ({_relative(item.location)})",
        f"  rule:      {item.rule}  (snakemake --cores 2 {item.rule})",
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
    return "\n\n".join(describe(p, found) for p in paths)


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
        src, dst = Path(results) / folder / name, Path(record_dir) / folder / name
        dst.parent.mkdir(parents=True, exist_ok=True)
        tmp = dst.with_name(f".{dst.name}.tmp")
        shutil.copyfile(src, tmp)
        tmp.replace(dst)
        copied.append(dst)
    print(
        f"parakin record: {len(copied)} files copied from {results} to {record_dir}",
        file=sys.stderr,
    )
    return copied
