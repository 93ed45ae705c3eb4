"""The ``parakin`` command line: ``ik``, ``fk``, ``bench``, ``reproduce``, ``report`` and ``readme``.

Bad input (a wrong number of values, an unreachable pose, an unknown solver, a malformed config)
exits with status 2 and one line on stderr, never a traceback. SI units by default; ``--units
paper`` reads and prints the units the paper uses.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Sequence

import numpy as np

from parakin import mechanisms
from parakin.errors import ParakinError
from parakin.units import from_si, parse_quantity, to_si

EXIT_BAD_INPUT = 2
EXIT_NOT_CONVERGED = 1


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # one line, status 2 (argparse prints usage too; keep it short)
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}\n")


def _mechanism(name: str, params: Sequence[str]):
    cls = mechanisms.get(name)
    changes = {}
    for item in params:
        key, sep, value = item.partition("=")
        if not sep:
            raise ValueError(f"--param {item!r} must look like NAME=VALUE (e.g. phi=35deg)")
        changes[key.strip()] = parse_quantity(value)
    fields = cls.__dataclass_fields__
    unknown = sorted(set(changes) - set(fields))
    if unknown:
        raise ValueError(f"unknown parameter(s) {unknown} of {name}; known: {sorted(fields)}")
    return cls(**changes)


def _batch(values: Sequence[float], n: int, what: str, names: Sequence[str]) -> np.ndarray:
    if len(values) == 0 or len(values) % n:
        raise ValueError(f"{what} needs a multiple of {n} values ({', '.join(names)}), got {len(values)}")
    a = np.asarray(values, dtype=float).reshape(-1, n)
    return a[0] if len(a) == 1 else a


def _units(mech, kind: str, paper: bool) -> tuple[str, ...]:
    return getattr(mech, f"paper_{kind}_units" if paper else f"{kind}_units")


def _fmt_vector(names, values, units) -> str:
    return "  ".join(f"{n} = {v:.10g} {u}" for n, v, u in zip(names, values, units))


def cmd_ik(args) -> int:
    mech = _mechanism(args.mechanism, args.param)
    pu, ju = _units(mech, "pose", args.units == "paper"), _units(mech, "joint", args.units == "paper")
    pose = to_si(_batch(args.pose, mech.n_pose, "--pose", mech.pose_names), pu)
    joints = from_si(mech.ik(pose), ju)
    if args.json:
        print(json.dumps({"mechanism": mech.name, "parameters": mech.parameters(), "pose": from_si(pose, pu).tolist(),
                          "pose_units": pu, "joints": joints.tolist(), "joint_units": ju}))
    else:
        for q in np.atleast_2d(joints):
            print(_fmt_vector(mech.joint_names, q, ju))
    return 0


def cmd_fk(args) -> int:
    from parakin.solvers import METHODS, solve_fk

    mech = _mechanism(args.mechanism, args.param)
    pu, ju = _units(mech, "pose", args.units == "paper"), _units(mech, "joint", args.units == "paper")
    joints = to_si(_batch(args.joints, mech.n_joints, "--joints", mech.joint_names), ju)
    mech.check_joints(joints)  # unreachable joints: the mechanism's own error, whatever the solver
    method = args.solver or ("closed-form" if mech.fk is not None else "newton")
    if method not in METHODS:
        raise ValueError(f"unknown solver {method!r}; known: {', '.join(sorted(METHODS))}")
    x0 = None if args.x0 is None else to_si(_batch(args.x0, mech.n_pose, "--x0", mech.pose_names), pu)
    options = {"network": _network(mech, args.network)} if method == "hybrid" else {}
    res = solve_fk(mech, joints, x0=x0, method=method, tol=args.tol, maxiter=args.maxiter, **options)
    pose = from_si(res.x, pu)
    if args.json:
        out = {"mechanism": mech.name, "parameters": mech.parameters(), "joints": from_si(joints, ju).tolist(),
               "joint_units": ju, "pose_units": pu, **res.to_dict()}
        out["x"] = pose.tolist()
        print(json.dumps(out))
    else:
        for x in np.atleast_2d(pose):
            print(_fmt_vector(mech.pose_names, x, pu))
    if not np.all(res.success):
        print(f"parakin fk: error: {res.message} (residual {np.max(res.residual):.3g} > tol {args.tol:g}; "
              "raise --maxiter, or the joints may be unreachable)", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    return 0


#: mechanism name -> (paper key, file name) of the network the pipeline trains for it
NETWORKS = {"3p4s": ("zhao2017_3p4s", "bp_network.npz")}


def _network(mech, path: str | None):
    """The trained network for the hybrid solver: ``--network PATH`` or the pipeline's output."""
    from parakin.config import DEFAULT_CONFIG, load_config
    from parakin.nn import BPNetwork

    if path is None:
        if mech.name not in NETWORKS:
            raise ValueError(f"no trained network is known for {mech.name}: pass --network PATH")
        key, name = NETWORKS[mech.name]
        path = str(Path(load_config(DEFAULT_CONFIG)["generated_dir"]) / key / name)
    return BPNetwork.load(path)


def cmd_bench(args) -> int:
    """Run benchmarks with a config's sizes; no NAME: the solver atlas, every paper's benchmark and
    the summary ``benchmarks.md`` (what the pipeline's ``extra_benchmarks`` rule writes)."""
    import pandas as pd

    from parakin import extras
    from parakin.config import DEFAULT_CONFIG, QUICK_CONFIG, load_config
    from parakin.papers import PAPERS

    config = load_config([DEFAULT_CONFIG, QUICK_CONFIG] if args.quick else [DEFAULT_CONFIG])
    root = Path(args.outdir) if args.outdir else Path(config["figures_dir"])
    names = args.name or ["atlas", *BENCHES]
    tables = []
    for name in names:
        if name not in BENCHES and name != "atlas":
            raise ValueError(f"unknown benchmark {name!r}; known: atlas, {', '.join(BENCHES)}")
        print(f"parakin bench: {name} ...", file=sys.stderr)
        if name == "atlas":
            paths = extras.ARTEFACTS["solver_atlas"](config, root)
        else:
            paper, artefact = BENCHES[name]
            paths = PAPERS[paper].ARTEFACTS[artefact](config, root / paper)
        csv = next(p for p in paths if p.suffix == ".csv")
        tables.append((name, csv))
    if not args.name:
        summary = extras.ARTEFACTS["benchmarks"](config, root)[0]
        print(f"parakin bench: wrote {summary}", file=sys.stderr)
    if args.json:
        print(json.dumps({name: json.loads(pd.read_csv(csv).to_json(orient="records")) for name, csv in tables}))
    elif not args.name:
        print(summary.read_text())
    else:
        for _, csv in tables:
            print(csv.with_suffix(".md").read_text())
    return 0


#: benchmark name -> (paper key, artefact); "atlas" (every solver x every mechanism) is extras'
BENCHES = {"fk-3p4s": ("zhao2017_3p4s", "fk_benchmark"), "indices-3p4s": ("zhao2017_3p4s", "index_benchmark"),
           "2ups": ("li2020_2ups", "benchmark"), "fk-stewart12": ("ye_stewart12", "fk_speed")}


def cmd_readme(args) -> int:
    """Copy the "at a glance" block of ``figures/benchmarks.md`` into README (``--check``: only compare)."""
    from parakin.config import ROOT
    from parakin.extras import readme_block, sync_readme

    readme = Path(args.readme) if args.readme else ROOT / "README.md"
    bench = Path(args.benchmarks) if args.benchmarks else ROOT / "figures" / "benchmarks.md"
    if args.check:
        same = readme_block(readme.read_text()) == readme_block(bench.read_text())
        print(f"{readme}: benchmark block {'matches' if same else 'differs from'} {bench}")
        return 0 if same else EXIT_NOT_CONVERGED
    print(sync_readme(readme, bench))
    return 0


def _config(args) -> dict:
    from parakin.config import DEFAULT_CONFIG, load_config, validate

    if args.config_json:
        return validate(json.loads(args.config_json))
    return load_config(args.config or [DEFAULT_CONFIG])


def cmd_reproduce(args) -> int:
    from parakin import extras
    from parakin.papers import PAPERS

    modules = {**PAPERS, extras.KEY: extras}
    if args.paper not in modules:
        raise ValueError(f"unknown paper {args.paper!r}; known: {', '.join(modules)}")
    artefacts = modules[args.paper].ARTEFACTS
    config = _config(args)
    names = list(artefacts) if args.artefact == "all" else [args.artefact]
    for name in names:
        if name not in artefacts:
            raise ValueError(f"unknown artefact {name!r} of {args.paper}; known: {', '.join(artefacts)}")
        default = Path(config["figures_dir"]) / ("" if args.paper == extras.KEY else args.paper)
        outdir = Path(args.outdir) if args.outdir else default
        for path in artefacts[name](config, outdir):
            print(path)
    return 0


def cmd_report(args) -> int:
    from parakin.report import write_report

    config = _config(args)
    figures = Path(args.figures or config["figures_dir"])
    print(write_report(figures, Path(args.out) if args.out else figures / "REPORT.md"))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="parakin", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    names = sorted(mechanisms.REGISTRY)

    def mech_args(p):
        p.add_argument("mechanism", choices=names, help="mechanism name")
        p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                       help="override a mechanism parameter (SI, or with a unit: phi=35deg, d=120mm)")
        p.add_argument("--units", choices=["si", "paper"], default="si", help="units of input and output")
        p.add_argument("--json", action="store_true", help="print a JSON object")

    p = sub.add_parser("ik", help="inverse kinematics: joints of a pose")
    mech_args(p)
    p.add_argument("--pose", type=float, nargs="+", required=True, help="pose value(s), n per pose")
    p.set_defaults(func=cmd_ik)

    p = sub.add_parser("fk", help="forward kinematics: pose of joint values")
    mech_args(p)
    p.add_argument("--joints", type=float, nargs="+", required=True, help="joint value(s), m per pose")
    p.add_argument("--solver", default=None, help="solver name (default: closed-form where one exists, else newton)")
    p.add_argument("--x0", type=float, nargs="+", default=None, help="initial pose (default: the mechanism's home)")
    p.add_argument("--tol", type=float, default=1e-10, help="residual tolerance (default 1e-10)")
    p.add_argument("--maxiter", type=int, default=50, help="iteration limit (default 50)")
    p.add_argument("--network", default=None, help="trained network for --solver hybrid (default: the pipeline's)")
    p.set_defaults(func=cmd_fk)

    p = sub.add_parser("bench", help="run benchmarks (every solver, same inputs, ratios against scipy in one run)")
    p.add_argument("name", nargs="*", help=f"benchmark(s): atlas, {', '.join(BENCHES)} (default: all, and the summary)")
    p.add_argument("--quick", action="store_true", help="small sizes (config/quick.yaml)")
    p.add_argument("--outdir", default=None, help="figures folder (default: figures_dir of the config)")
    p.add_argument("--json", action="store_true", help="print the tables as JSON records")
    p.set_defaults(func=cmd_bench)

    p = sub.add_parser("readme", help="copy the benchmark summary block of figures/benchmarks.md into README.md")
    p.add_argument("--readme", default=None, help="README file (default: the project's)")
    p.add_argument("--benchmarks", default=None, help="benchmarks.md (default: figures/benchmarks.md)")
    p.add_argument("--check", action="store_true", help="only compare; exit 1 if they differ")
    p.set_defaults(func=cmd_readme)

    def config_args(p):
        p.add_argument("--config", action="append", default=None, metavar="YAML",
                       help="config file(s), later ones override earlier ones (default config/config.yaml)")
        p.add_argument("--config-json", default=None, help="the whole config as JSON (what Snakemake passes)")

    p = sub.add_parser("reproduce", help="compute one artefact (table or figure) of a paper")
    p.add_argument("paper", help="paper key, e.g. zhao2017_3p4s, or 'extra' (beyond the papers: solver atlas, benchmarks)")
    p.add_argument("artefact", help="artefact name, e.g. table1, or 'all'")
    p.add_argument("--outdir", default=None, help="output folder (default: <figures_dir>/<paper>)")
    config_args(p)
    p.set_defaults(func=cmd_reproduce)

    p = sub.add_parser("report", help="write the claim-by-claim REPORT.md")
    p.add_argument("--figures", default=None, help="figures folder (default: figures_dir of the config)")
    p.add_argument("--out", default=None, help="output file (default: <figures>/REPORT.md)")
    config_args(p)
    p.set_defaults(func=cmd_report)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except (ParakinError, ValueError, KeyError, FileNotFoundError) as exc:
        message = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
        print(f"parakin {args.command}: error: {message}", file=sys.stderr)
        return EXIT_BAD_INPUT


if __name__ == "__main__":
    sys.exit(main())
