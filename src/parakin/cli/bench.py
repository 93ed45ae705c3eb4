"""``parakin bench``: the benchmarks with a config's sizes, and ``--peers`` (docs/peers.md)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from parakin.cli.common import (
    _text_option,
)


def cmd_bench(args) -> int:
    """Run benchmarks with a config's sizes; no NAME: the solver atlas, every paper's benchmark and
    the summary ``benchmarks.md`` (what the pipeline's ``extra_benchmarks`` rule writes)."""
    import pandas as pd

    from parakin.config import QUICK_CONFIG, load_run_config
    from parakin.papers import PAPERS
    from parakin.studies import solver_atlas as extras

    if args.peers is not None:  # the 6-6 all-solutions FK against Bertini 2 / fkSGP (docs/peers.md)
        from parakin.mechanisms import stewart66_peers as peers

        table = peers.bench_peers(
            fksgp=args.peers or None,
            n_inputs=11 if args.quick else 31,
            progress=lambda s: print(f"parakin bench --peers: {s} ...", file=sys.stderr),
        )
        print(table.to_json(orient="records") if args.json else peers.format_peers(table))
        return 0
    config = load_run_config([QUICK_CONFIG] if args.quick else [])
    root = Path(args.outdir) if args.outdir else Path(config["figures_dir"])
    names = args.name or ["atlas", "kernels", *BENCHES]
    tables = []
    for name in names:
        if name not in BENCHES and name not in ("atlas", "kernels"):
            raise ValueError(
                f"unknown benchmark {name!r}; known: atlas, kernels, {', '.join(BENCHES)}"
            )
        print(f"parakin bench: {name} ...", file=sys.stderr)
        if name == "atlas":
            paths = extras.ARTEFACTS["solver_atlas"](config, root)
        elif name == "kernels":  # the compiled kernels' goals: ratios against scipy in this run
            paths = extras.kernel_goals(config, root)
        else:
            paper, artefact = BENCHES[name]
            paths = PAPERS[paper].ARTEFACTS[artefact](config, root / paper)
        csv = next(p for p in paths if p.suffix == ".csv")
        tables.append((name, csv))
    if not args.name:
        summary = extras.ARTEFACTS["benchmarks"](config, root)[0]
        print(f"parakin bench: wrote {summary}", file=sys.stderr)
    if args.json:
        print(
            json.dumps(
                {
                    name: json.loads(pd.read_csv(csv).to_json(orient="records"))
                    for name, csv in tables
                }
            )
        )
    elif not args.name:
        print(summary.read_text())
    else:
        for _, csv in tables:
            print(csv.with_suffix(".md").read_text())
    return 0


#: benchmark name -> (paper key, artefact); "atlas" (every solver x every mechanism) is extras'
BENCHES = {
    "fk-3p4s": ("zhao2017_3p4s", "fk_benchmark"),
    "indices-3p4s": ("zhao2017_3p4s", "index_benchmark"),
    "2ups": ("li2020_2ups", "benchmark"),
    "fk-stewart12": ("ye_stewart12", "fk_speed"),
}


def add_bench(sub) -> None:
    p = sub.add_parser(
        "bench",
        help="run benchmarks (every solver, same inputs, ratios against scipy in one run)",
        func=cmd_bench,
    )
    p.add_argument(
        "name",
        nargs="*",
        help=f"benchmark(s): atlas, kernels, {', '.join(BENCHES)} (default: all, and the summary)",
    )
    p.add_argument("--quick", action="store_true", help="small sizes (config/quick.yaml)")
    _text_option(
        p,
        "--outdir",
        help="figures folder (default: figures_dir of the config)",
    )
    p.add_argument("--json", action="store_true", help="print the tables as JSON records")
    p.add_argument(
        "--peers",
        nargs="?",
        const="",
        default=None,
        metavar="FKSGP_DIR",
        help="the 6-6 all-solutions FK against Bertini 2 (if installed) and, given a local copy "
        "of martyushev/fkSGP, its elimination-template solver: same inputs, one run",
    )
