"""The pipeline's commands: ``reproduce``, ``check``, ``which``, ``record``, ``report`` and ``readme``."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from parakin.cli.common import (
    EXIT_NOT_CONVERGED,
    _config_args,
    _config_overlays,
    _text_option,
)
from parakin.io import read_text

#: the page whose generated blocks ``parakin readme`` writes (README links to it)
RESULTS_PAGE = "docs/results.md"


def cmd_readme(args) -> int:
    """Write the generated blocks of the results page (``docs/results.md``): the verdict counts
    and the glance block from ``figures/report.csv``, the speed summary from
    ``figures/benchmarks.md`` (``--check``: only compare)."""
    from parakin.config import ROOT
    from parakin.glance import GLANCE_BEGIN, GLANCE_END
    from parakin.report import STATUS_BEGIN, STATUS_END, readme_blocks_match, sync_status
    from parakin.studies.solver_atlas import BEGIN, END, readme_block, sync_readme

    readme = Path(args.readme) if args.readme is not None else ROOT / RESULTS_PAGE
    bench = (
        Path(args.benchmarks) if args.benchmarks is not None else ROOT / "figures" / "benchmarks.md"
    )
    report_csv = bench.with_name("report.csv")  # the status table: from report.csv and the registry
    blocks = [(BEGIN, END)] + (
        [(STATUS_BEGIN, STATUS_END), (GLANCE_BEGIN, GLANCE_END)] if report_csv.exists() else []
    )
    _marked(readme, "--readme", blocks)  # each file blamed for its own missing block
    _marked(bench, "--benchmarks", blocks[:1])
    if args.check:
        same = readme_block(readme.read_text()) == readme_block(bench.read_text())
        print(f"{readme}: benchmark block {'matches' if same else 'differs from'} {bench}")
        if report_csv.exists():
            status = readme_blocks_match(readme.read_text(), report_csv)
            verb = "match" if status else "differ from"
            print(f"{readme}: status and glance blocks {verb} {report_csv}")
            same = same and status
        return 0 if same else EXIT_NOT_CONVERGED
    print(sync_readme(readme, bench))
    if report_csv.exists():
        print(sync_status(readme, report_csv))
    return 0


def _marked(path: Path, option: str, blocks: list[tuple[str, str]]) -> None:
    """Raise a ValueError naming ``path`` unless it holds every ``begin ... end`` block."""
    text = read_text(path, option)
    for begin, end in blocks:
        if not 0 <= text.find(begin) < text.find(end):
            raise ValueError(f"{option} {path} has no {begin} ... {end} block")


def _config(args) -> dict:
    """The config of ``--config-json`` (one rule's sections), or config/config.yaml with the
    ``--config`` overlays merged on top (as the pipeline merges --configfile)."""
    from parakin.config import load_run_config, validate_sections

    if args.config_json:  # one pipeline rule's sections (registry.prune_config)
        config = json.loads(args.config_json)
        if not isinstance(config, dict):
            raise ValueError(f"--config-json must be a JSON object, got {type(config).__name__}")
        # the pipeline validated the whole config once (workflow/rules/common.smk)
        return config if getattr(args, "validated", False) else validate_sections(config)
    return load_run_config(args.config or [])


def cmd_reproduce(args) -> int:
    from parakin.pipeline import reproduce

    config = _config(args)
    for path in reproduce(
        args.paper,
        args.artefact,
        config,
        Path(args.outdir) if args.outdir else None,
        module=args.module,
    ):
        print(path)
    return 0


def cmd_check(args) -> int:
    from parakin.config import load_run_config
    from parakin.pipeline import check

    config = load_run_config(args.config or [])
    results = Path(args.results or config["figures_dir"])
    record = Path(args.record or config["record_dir"] or "figures")
    out = Path(args.out) if args.out else results.parent / "reproduction_check"
    csv, md, line = check(results, record, out, args.studies or config["studies"])
    print(f"{line}; see {md}")
    bad = line.count(" differs") + line.count(" missing")
    return EXIT_NOT_CONVERGED if args.strict and bad else 0


def cmd_which(args) -> int:
    from parakin.pipeline import which

    if not args.path and not args.list:
        raise ValueError("give a file (e.g. figures/zhao2017_3p4s/table1.csv) or --list")
    print(which(args.path, list_all=args.list))
    return 0


def cmd_record(args) -> int:
    from parakin.config import load_run_config
    from parakin.pipeline import record

    config = load_run_config(args.config or [])
    results = Path(args.results or config["figures_dir"])
    target = Path(args.record or config["record_dir"])
    record(results, target, config["studies"])
    if args.readme:
        return cmd_readme(
            argparse.Namespace(readme=None, benchmarks=str(target / "benchmarks.md"), check=False)
        )
    return 0


def cmd_report(args) -> int:
    from parakin.report import write_report

    config = _config(args)
    figures = Path(args.figures or config["figures_dir"])
    print(write_report(figures, Path(args.out) if args.out else figures / "REPORT.md"))
    return 0


def add_readme(sub) -> None:
    p = sub.add_parser(
        "readme",
        help="write the record's verdict counts, glance and speed blocks into docs/results.md",
        func=cmd_readme,
    )
    _text_option(p, "--readme", help=f"the page to write (default: {RESULTS_PAGE})")
    _text_option(
        p,
        "--benchmarks",
        help="benchmarks.md (default: figures/benchmarks.md)",
    )
    p.add_argument("--check", action="store_true", help="only compare; exit 1 if they differ")


def add_reproduce(sub) -> None:
    p = sub.add_parser(
        "reproduce",
        help="compute artefacts (tables or figures) of a paper or study",
        func=cmd_reproduce,
    )
    p.add_argument(
        "paper",
        help="study key, e.g. zhao2017_3p4s, or 'extra' (beyond the papers: solver atlas, benchmarks)",
    )
    p.add_argument(
        "artefact",
        nargs="+",
        help="artefact name, e.g. table1, several (made one after the other, in this process), "
        "or 'all'",
    )
    _text_option(
        p,
        "--outdir",
        help="output folder (default: <figures_dir>/<paper>)",
    )
    _text_option(
        p,
        "--module",
        help="the study's module (default: those the config lists)",
    )
    _config_args(p)


def add_check(sub) -> None:
    p = sub.add_parser(
        "check",
        help="check a run's outputs against the committed record, within declared tolerances",
        func=cmd_check,
    )
    _text_option(
        p,
        "--results",
        help="the run's figures folder (default: figures_dir of the config)",
    )
    _text_option(
        p,
        "--record",
        help="the record (default: record_dir of the config, figures/)",
    )
    _text_option(
        p,
        "--out",
        help="output stem (default: <results>/../reproduction_check)",
    )
    p.add_argument(
        "--studies", nargs="*", default=None, help="study modules (default: the config's)"
    )
    _config_overlays(p)
    p.add_argument("--strict", action="store_true", help="exit 1 if anything differs or is missing")


def add_which(sub) -> None:
    p = sub.add_parser(
        "which", help="which function and rule make a committed figure or table", func=cmd_which
    )
    p.add_argument("path", nargs="*", help="file(s), e.g. figures/zhao2017_3p4s/table1.csv")
    p.add_argument(
        "--list", action="store_true", help="list every registered output file and its artefact"
    )


def add_record(sub) -> None:
    p = sub.add_parser(
        "record",
        help="copy a finished run (results/) into the committed record (figures/)",
        func=cmd_record,
    )
    _text_option(
        p,
        "--results",
        help="the run's figures folder (default: figures_dir of the config)",
    )
    _text_option(
        p,
        "--record",
        help="the record (default: record_dir of the config)",
    )
    p.add_argument(
        "--no-readme",
        dest="readme",
        action="store_false",
        help=f"do not write the generated blocks into {RESULTS_PAGE}",
    )
    _config_overlays(p)


def add_report(sub) -> None:
    p = sub.add_parser("report", help="write the claim-by-claim REPORT.md", func=cmd_report)
    _text_option(
        p,
        "--figures",
        help="figures folder (default: figures_dir of the config)",
    )
    _text_option(p, "--out", help="output file (default: <figures>/REPORT.md)")
    _config_args(p)
