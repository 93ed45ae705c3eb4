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

    if args.mechanism_file is not None:  # a described mechanism: the solver atlas on it alone
        if args.name or args.peers is not None or args.outdir is not None:
            raise ValueError("--mechanism FILE runs the solver atlas on that mechanism alone: "
                             "it takes no benchmark NAME, --peers or --outdir")  # fmt: skip
        table = _atlas_of_file(args.mechanism_file, quick=args.quick)
        if args.json:
            print(table.to_json(orient="records"))
        else:
            from parakin.io import markdown_table

            print(markdown_table(table[_ATLAS_COLUMNS], floatfmt=".3g"))
        return 0
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


#: the columns of the solver atlas that ``bench --mechanism FILE`` prints as text
_ATLAS_COLUMNS = [
    "scenario",
    "solver",
    "success_rate",
    "wrong_assembly_rate",
    "median_err",
    "median_nit",
    "median_latency_us",
    "throughput_per_s",
    "speedup_single",
]


def _atlas_of_file(path: str, *, quick: bool):
    """The solver atlas (:func:`parakin.atlas.run_atlas`, every standard solver, its scenarios
    and seeds) on the mechanism described in ``path``: ``quick`` 50 inputs per scenario, else 200."""
    import zlib

    import numpy as np

    from parakin.atlas import AtlasCase, run_atlas, standard_solvers
    from parakin.mechanisms import from_file

    mech = from_file(path)
    rows = 10 if quick else 40
    case = AtlasCase(mech.name, mech, mech.pose_bounds(), standard_solvers(mech, pso_rows=rows))
    return run_atlas(
        [case],
        lambda stream: np.random.default_rng(zlib.crc32(stream.encode())),  # one seed per stream
        n=50 if quick else 200,
        n_single=10 if quick else 30,
        n_batch=1_000 if quick else 10_000,
        repeats=1 if quick else 3,
        progress=lambda s: print(f"parakin bench: {s} ...", file=sys.stderr),
    )


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
    _text_option(
        p,
        "--mechanism",
        dest="mechanism_file",
        metavar="FILE",
        help="the solver atlas (every solver, the atlas's scenarios) on the mechanism described "
        "in FILE alone (YAML/JSON, docs/mechanism_file.md); --quick: 50 inputs per scenario",
    )
    p.add_argument(
        "--peers",
        nargs="?",
        const="",
        default=None,
        metavar="FKSGP_DIR",
        help="the 6-6 all-solutions FK against Bertini 2 (if installed) and, given a local copy "
        "of martyushev/fkSGP, its elimination-template solver: same inputs, one run",
    )
