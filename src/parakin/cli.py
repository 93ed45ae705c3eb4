"""The ``parakin`` command line: ``ik``, ``fk``, ``bench``, ``reproduce``, ``report`` and ``readme``.

Bad input (a wrong number of values, an unreachable pose, an unknown solver, a malformed config)
exits with status 2 and one line on stderr, never a traceback. SI units by default; ``--units
paper`` reads and prints the units the paper uses. ``ik`` and ``fk`` take many poses or joint
vectors from a file (``--input``, CSV or .npy, one per row) and write them to one (``--output``);
``fk --all`` lists every real solution where the mechanism has an all-solutions method.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import re
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from parakin import mechanisms
from parakin.errors import ParakinError
from parakin.units import from_si, parse_quantity, to_si

EXIT_BAD_INPUT = 2
EXIT_NOT_CONVERGED = 1


#: largest --maxiter (a bound on the work one command may ask for)
MAXITER_LIMIT = 100_000
#: largest magnitude of a --param value in SI units (m, rad): far beyond any real mechanism
PARAM_LIMIT = 1e6
#: what argparse must read as a (negative) number, not an option: -1, -1.5, -.5, -1e-3, -1.5E+02, -inf, -nan
_NEGATIVE_NUMBER = re.compile(
    r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|infinity|nan)$", re.IGNORECASE
)


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        # argparse's own pattern misses scientific notation: "-1e-3" would be taken for an option
        self._negative_number_matcher = _NEGATIVE_NUMBER

    def error(self, message: str):  # one line, status 2 (argparse prints usage too; keep it short)
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}\n")


def finite_float(text: str) -> float:
    """A finite number (decimal or scientific notation, any sign), or a clear argparse error."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return value


def nonnegative_float(text: str) -> float:
    value = finite_float(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r} must be >= 0")
    return value


def iteration_count(text: str) -> int:
    """An integer in [0, MAXITER_LIMIT]; "1e3" is accepted (an integral number)."""
    value = finite_float(text)
    if not value.is_integer() or not 0 <= value <= MAXITER_LIMIT:
        raise argparse.ArgumentTypeError(f"{text!r} must be an integer in [0, {MAXITER_LIMIT}]")
    return int(value)


def parameters_of(cls) -> list[str]:
    """The real parameters ``--param`` may set: the mechanism's float fields (class attributes,
    tuples, switches such as a branch or a convention are not parameters)."""
    return sorted(f.name for f in dataclasses.fields(cls) if f.type in ("float", float))


def _parameter(name: str, key: str, text: str) -> float:
    value = parse_quantity(text)
    if not (math.isfinite(value) and 0 < value <= PARAM_LIMIT):
        raise ValueError(
            f"--param {key}={text} of {name}: {value!r} must be a positive finite number "
            f"<= {PARAM_LIMIT:g} (SI units)"
        )
    return value


def _mechanism(name: str, params: Sequence[str]):
    cls = mechanisms.get(name)
    changes = {}
    for item in params:
        key, sep, value = item.partition("=")
        if not sep:
            raise ValueError(f"--param {item!r} must look like NAME=VALUE (e.g. phi=35deg)")
        changes[key.strip()] = value
    known = parameters_of(cls)
    unknown = sorted(set(changes) - set(known))
    if unknown:
        raise ValueError(f"unknown parameter(s) {unknown} of {name}; known: {known}")
    return cls(**{key: _parameter(name, key, text) for key, text in changes.items()})


def _finite(values: np.ndarray, what: str, inputs: np.ndarray) -> np.ndarray:
    """``values`` if every entry is finite; else a ValueError naming the input (too large?)."""
    bad = ~np.all(np.isfinite(np.atleast_2d(values)), axis=-1)
    if np.any(bad):
        row = np.atleast_2d(inputs)[int(np.argmax(bad))]
        raise ValueError(
            f"{what} of {np.array2string(row, precision=6)} is not finite "
            f"(|values| up to {np.max(np.abs(row)):.3g}: too large for this mechanism?)"
        )
    return values


def _dumps(obj) -> str:
    """Strict JSON (no NaN or Infinity)."""
    return json.dumps(obj, allow_nan=False)


def _batch(values: Sequence[float], n: int, what: str, names: Sequence[str]) -> np.ndarray:
    if len(values) == 0 or len(values) % n:
        raise ValueError(
            f"{what} needs a multiple of {n} values ({', '.join(names)}), got {len(values)}"
        )
    a = np.asarray(values, dtype=float).reshape(-1, n)
    return a[0] if len(a) == 1 else a


def _units(mech, kind: str, paper: bool) -> tuple[str, ...]:
    return getattr(mech, f"paper_{kind}_units" if paper else f"{kind}_units")


def _unit(u: str) -> str:
    """A unit as printed after a value: nothing for a dimensionless one (``"1"``)."""
    return "" if u == "1" else f" {u}"


def _fmt_vector(names, values, units) -> str:
    """``name = value unit`` per entry (no unit where dimensionless); values in a form the options
    read back (``-2.1e-17`` too)."""
    return "  ".join(f"{n} = {v:.10g}{_unit(u)}" for n, v, u in zip(names, values, units))


def _units_note(mech, command: str, paper: bool) -> None:
    """``--units paper`` where the paper prints SI: say so (once, on stderr) instead of silently
    printing the same numbers."""
    if (
        paper
        and mech.paper_pose_units == mech.pose_units
        and mech.paper_joint_units == mech.joint_units
    ):
        units = (
            ", ".join(sorted(set(mech.pose_units + mech.joint_units) - {"1"})) or "dimensionless"
        )
        print(
            f"parakin {command}: note: the paper prints {mech.name} poses and joints in SI units ({units}), "
            "so --units paper is the same as --units si",
            file=sys.stderr,
        )


#: file formats of --input and --output
FILE_FORMATS = (".csv", ".npy")
#: most rows one --input file may hold
MAX_ROWS = 10_000_000


def _format_of(path: str, option: str) -> str:
    suffix = Path(path).suffix.lower()
    if suffix not in FILE_FORMATS:
        raise ValueError(f"{option} {path}: the file name must end in {' or '.join(FILE_FORMATS)}")
    return suffix


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _header_name(token: str) -> tuple[str, str | None]:
    """``"x [mm]"`` -> ``("x", "mm")``; ``"x"`` -> ``("x", None)``."""
    m = re.fullmatch(r"\s*([^\[\]]*?)\s*(?:\[\s*([^\]]*?)\s*\])?\s*", token)
    return (m.group(1), m.group(2)) if m else (token.strip(), None)


def read_rows(
    path: str, names: Sequence[str], units: Sequence[str], option: str = "--input"
) -> np.ndarray:
    """The ``(N, n)`` values of a CSV or .npy file, one pose or joint vector per row.

    A CSV may start with a header; where it names every one of ``names`` (e.g. ``x [m]`` or ``x``,
    in any order, other columns ignored: what ``--output`` writes reads back) those columns are
    taken, and a unit in brackets must be the one ``--units`` reads. Without a header the file
    has exactly ``n`` columns in the order of ``names``. Lines starting with ``#`` are comments.
    """
    n = len(names)
    fmt = _format_of(path, option)
    if fmt == ".npy":
        try:
            a = np.load(path, allow_pickle=False)
        except ValueError as exc:
            raise ValueError(
                f"{option} {path}: not a numeric .npy array ({_one_line(exc)})"
            ) from None
        if a.dtype.kind not in "iuf" or a.ndim not in (1, 2) or a.shape[-1] != n:
            raise ValueError(
                f"{option} {path}: a .npy file must hold a numeric array of shape (N, {n}) "
                f"({', '.join(names)}), got {a.dtype} {a.shape}"
            )
        a = np.atleast_2d(a.astype(float))
    else:
        with open(path, newline="") as fh:
            lines = [
                (k + 1, line.strip())
                for k, line in enumerate(fh)
                if line.strip() and not line.lstrip().startswith("#")
            ]
        if not lines:
            raise ValueError(f"{option} {path}: the file holds no rows")
        if len(lines) > MAX_ROWS + 1:
            raise ValueError(f"{option} {path}: more than {MAX_ROWS} rows")
        cells = [(k, [c.strip() for c in line.split(",")]) for k, line in lines]
        columns = list(range(n))
        if not any(_is_number(c) for c in cells[0][1]):  # a header (no cell of it is a number)
            header = [_header_name(c) for c in cells[0][1]]
            found = {name: (i, unit) for i, (name, unit) in enumerate(header)}
            if all(name in found for name in names):
                columns = [found[name][0] for name in names]
                for name, want in zip(names, units):
                    unit = found[name][1]
                    if unit not in (None, "", want) and not (unit == "-" and want == "1"):
                        raise ValueError(
                            f"{option} {path}: column {name!r} is in {unit} but these --units read "
                            f"{name} in {want}"
                        )
            elif len(header) != n:
                raise ValueError(
                    f"{option} {path}: the header {cells[0][1]} names neither the columns "
                    f"{list(names)} nor {n} columns"
                )
            cells = cells[1:]
            if not cells:
                raise ValueError(f"{option} {path}: the file holds a header and no rows")
        rows = []
        for k, row in cells:
            if len(row) < max(columns) + 1 or (columns == list(range(n)) and len(row) != n):
                raise ValueError(
                    f"{option} {path}, line {k}: {len(row)} values, expected {n} "
                    f"({', '.join(names)})"
                )
            try:
                rows.append([float(row[c]) for c in columns])
            except ValueError:
                raise ValueError(f"{option} {path}, line {k}: {row} are not all numbers") from None
        a = np.asarray(rows, dtype=float).reshape(-1, n)
    if len(a) == 0:
        raise ValueError(f"{option} {path}: the file holds no rows")
    bad = ~np.all(np.isfinite(a), axis=-1)
    if np.any(bad):
        raise ValueError(
            f"{option} {path}: row {int(np.argmax(bad)) + 1} is not finite "
            f"({np.array2string(a[int(np.argmax(bad))], precision=6)})"
        )
    return a


def write_rows(
    path: str,
    names: Sequence[str],
    units: Sequence[str],
    values: np.ndarray,
    extra: dict[str, Sequence] | None = None,
    lead: dict[str, Sequence] | None = None,
) -> None:
    """Write ``values (N, n)`` to a CSV (header ``name [unit]``, then ``extra`` columns; ``lead``
    columns first) or ``.npy`` (the values only, any shape). Written to a temporary file first."""
    fmt = _format_of(path, "--output")
    target = Path(path)
    tmp = target.with_name(f".{target.name}.tmp")
    try:
        if fmt == ".npy":
            with open(tmp, "wb") as fh:
                np.save(fh, np.asarray(values, dtype=float))
        else:
            header = [
                *(lead or {}),
                *(f"{n} [{u}]" if u != "1" else n for n, u in zip(names, units)),
                *(extra or {}),
            ]
            v = np.atleast_2d(values)
            with open(tmp, "w", newline="") as fh:
                fh.write(",".join(header) + "\n")
                for i in range(len(v)):
                    cells = [str(c[i]) for c in (lead or {}).values()]
                    cells += ["" if not math.isfinite(x) else repr(float(x)) for x in v[i]]
                    cells += [_cell(c[i]) for c in (extra or {}).values()]
                    fh.write(",".join(cells) + "\n")
        tmp.replace(target)
    finally:
        tmp.unlink(missing_ok=True)


def _cell(value) -> str:
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (float, np.floating)):
        return "" if not math.isfinite(value) else repr(float(value))
    text = str(value)
    return f'"{text}"' if "," in text else text


def _inputs(args, what: str, names, units, n) -> np.ndarray:
    """The values of ``--pose``/``--joints`` (one vector or a batch) or of ``--input FILE``."""
    given = getattr(args, what)
    if args.input is not None:
        if given is not None:
            raise ValueError(f"give --{what} or --input, not both")
        return read_rows(args.input, names, units)
    if given is None:
        raise ValueError(f"give --{what} VALUES or --input FILE (CSV or .npy, one row each)")
    return _batch(given, n, f"--{what}", names)


def cmd_ik(args) -> int:
    mech = _mechanism(args.mechanism, args.param)
    paper = args.units == "paper"
    pu, ju = _units(mech, "pose", paper), _units(mech, "joint", paper)
    given = _inputs(args, "pose", mech.pose_names, pu, mech.n_pose)
    pose = _finite(to_si(given, pu), "--pose in SI units", given)
    with np.errstate(all="ignore"):
        joints = _finite(from_si(mech.ik(pose), ju), "the inverse kinematics", given)
    if args.output:
        write_rows(args.output, mech.joint_names, ju, np.atleast_2d(joints))
        print(
            f"parakin ik: {len(np.atleast_2d(joints))} joint vector(s) written to {args.output}",
            file=sys.stderr,
        )
    if args.json:
        print(
            _dumps(
                {
                    "mechanism": mech.name,
                    "parameters": mech.parameters(),
                    "pose": given.tolist(),
                    "pose_units": pu,
                    "joints": joints.tolist(),
                    "joint_units": ju,
                }
            )
        )
    elif not args.output:
        for q in np.atleast_2d(joints):
            print(_fmt_vector(mech.joint_names, q, ju))
    _units_note(mech, "ik", paper)
    return 0


def cmd_fk(args) -> int:
    from parakin.solvers import METHODS, solve_fk

    mech = _mechanism(args.mechanism, args.param)
    paper = args.units == "paper"
    pu, ju = _units(mech, "pose", paper), _units(mech, "joint", paper)
    given = _inputs(args, "joints", mech.joint_names, ju, mech.n_joints)
    joints = _finite(to_si(given, ju), "--joints in SI units", given)
    if args.all:
        if args.solver is not None or args.x0 is not None:
            raise ValueError(
                "--all lists every solution of the all-solutions method: it takes no --solver or --x0"
            )
        return _fk_all(args, mech, given, joints, pu, ju)
    with np.errstate(all="ignore"):
        mech.check_joints(
            joints
        )  # unreachable joints: the mechanism's own error, whatever the solver
    method = args.solver or ("closed-form" if mech.fk is not None else "newton")
    if method not in METHODS:
        raise ValueError(f"unknown solver {method!r}; known: {', '.join(sorted(METHODS))}")
    x0 = (
        None
        if args.x0 is None
        else to_si(_batch(args.x0, mech.n_pose, "--x0", mech.pose_names), pu)
    )
    options = {"network": _network(mech, args.network)} if method == "hybrid" else {}
    res = solve_fk(
        mech,
        joints,
        x0=x0,
        method=method,
        tol=args.tol,
        maxiter=args.maxiter,
        joint_tol=args.joint_tol,
        **options,
    )
    with np.errstate(all="ignore"):
        pose = _finite(from_si(res.x, pu), "the solution in --units " + args.units, given)
    if args.output:
        flat = np.atleast_2d(pose)
        extra = {
            "success": np.atleast_1d(res.success),
            "status": [_status_name(v) for v in np.atleast_1d(res.status)],
            "nit": np.atleast_1d(res.nit),
            "residual": np.atleast_1d(res.residual).astype(float),
            "joint_error_m": np.atleast_1d(res.joint_error).astype(float),
        }
        write_rows(args.output, mech.pose_names, pu, flat, extra=extra)
        print(
            f"parakin fk: {len(flat)} pose(s) written to {args.output} ({int(np.sum(res.success))} converged)",
            file=sys.stderr,
        )
    if args.json:
        out = {
            "mechanism": mech.name,
            "parameters": mech.parameters(),
            "joints": given.tolist(),
            "joint_units": ju,
            "pose_units": pu,
            **res.to_dict(),
        }
        out["x"] = pose.tolist()
        print(_dumps(out))
    elif not args.output:
        for x in np.atleast_2d(pose):
            print(_fmt_vector(mech.pose_names, x, pu))
    if not np.all(res.success):
        print(f"parakin fk: error: {res.message} ({_why(res, args.tol)})", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    _units_note(mech, "fk", paper)
    return 0


def all_solutions_of(mech, joints: np.ndarray) -> list[list[tuple[str, np.ndarray, bool]]]:
    """Every real FK solution of each row of ``joints (N, m)`` (SI), with its assembly label and
    whether it is the working one (what ``fk`` returns: the papers' assembly, nearest home).

    2-UPS/(S+SPR)R: both branches of eq (14) (rho > 0 the paper's; a rho < 0 pose belongs to the
    mirror assembly, ``UPS2(branch=-1)``); Stewart platforms: above or below the base (Z > 0)."""
    if hasattr(mech, "fk_all_branches"):
        sets = [(b, sols) for b, sols in mech.fk_all_branches(joints).items()]
    elif hasattr(mech, "fk_all"):
        sets = [(None, mech.fk_all(joints))]
    else:
        raise ValueError(
            f"{mech.name} has no all-solutions method; --all works on "
            f"{', '.join(all_solution_mechanisms())}"
        )
    try:
        with np.errstate(all="ignore"):
            working = np.atleast_2d(mech.fk(joints))
    except ParakinError:  # some row has no working solution: mark none of that batch
        working = np.full((len(joints), mech.n_pose), np.nan)
    z = mech.pose_names.index("Z") if "Z" in mech.pose_names else None
    out = []
    for i in range(len(joints)):
        rows = []
        for branch, sols in sets:
            for x in sols[i]:
                if not np.all(np.isfinite(x)):
                    continue
                parts = []
                if branch is not None:
                    parts.append(
                        f"branch {branch:+d} ({'rho > 0, the paper' if branch > 0 else 'rho < 0, mirror'})"
                    )
                if z is not None:
                    parts.append("above the base" if x[z] > 0 else "below the base")
                own = branch is None or branch == getattr(mech, "branch", branch)
                near = (
                    own
                    and bool(np.all(np.isfinite(working[i])))
                    and float(np.max(np.abs(mech.pose_difference(x, working[i])))) < 1e-7
                )
                if near:
                    parts.append("working (what fk returns)")
                rows.append((", ".join(parts), x, near))
        out.append(rows)
    return out


def all_solution_mechanisms() -> list[str]:
    return sorted(n for n, cls in mechanisms.REGISTRY.items() if hasattr(cls, "fk_all"))


def _fk_all(args, mech, given, joints, pu, ju) -> int:
    with np.errstate(all="ignore"):
        found = all_solutions_of(mech, np.atleast_2d(joints))
    for rows in found:
        for _, x, _ in rows:
            _finite(from_si(x, pu), "a solution in --units " + args.units, given)
    counts = [len(rows) for rows in found]
    if args.output:
        if Path(args.output).suffix.lower() == ".npy":
            k = max(counts + [1])
            a = np.full((len(found), k, mech.n_pose), np.nan)
            for i, rows in enumerate(found):
                for j, (_, x, _) in enumerate(rows):
                    a[i, j] = from_si(x, pu)
            write_rows(args.output, mech.pose_names, pu, a)
        else:
            flat = [
                (i + 1, j + 1, label, work, from_si(x, pu))
                for i, rows in enumerate(found)
                for j, (label, x, work) in enumerate(rows)
            ]
            values = np.array([f[4] for f in flat]).reshape(-1, mech.n_pose)
            write_rows(
                args.output,
                mech.pose_names,
                pu,
                values,
                lead={"input": [f[0] for f in flat], "solution": [f[1] for f in flat]},
                extra={"working": [f[3] for f in flat], "assembly": [f[2] for f in flat]},
            )
        print(
            f"parakin fk: {sum(counts)} real solution(s) of {len(found)} input(s) written to {args.output}",
            file=sys.stderr,
        )
    if args.json:
        print(
            _dumps(
                {
                    "mechanism": mech.name,
                    "parameters": mech.parameters(),
                    "joints": np.atleast_2d(given).tolist(),
                    "joint_units": ju,
                    "pose_units": pu,
                    "n_real": counts,
                    "solutions": [
                        [
                            {"assembly": label, "working": work, "x": from_si(x, pu).tolist()}
                            for label, x, work in rows
                        ]
                        for rows in found
                    ],
                }
            )
        )
    elif not args.output:
        q = np.atleast_2d(given)
        for i, rows in enumerate(found):
            print(f"{_fmt_vector(mech.joint_names, q[i], ju)}: {len(rows)} real solution(s)")
            for j, (label, x, _) in enumerate(rows):
                print(
                    f"  #{j + 1}  {_fmt_vector(mech.pose_names, from_si(x, pu), pu)}  [{label or 'real'}]"
                )
    none = [i for i, c in enumerate(counts) if c == 0]
    if none:
        print(
            f"parakin fk: error: no real solution for {len(none)} input(s), the first: "
            f"{np.array2string(np.atleast_2d(given)[none[0]], precision=6)} (cannot be assembled)",
            file=sys.stderr,
        )
        return EXIT_NOT_CONVERGED
    _units_note(mech, "fk", args.units == "paper")
    return 0


def _status_name(value) -> str:
    from parakin.solvers import Status

    try:
        return Status(int(value)).name
    except ValueError:
        return str(int(value))


def _why(res, tol: float) -> str:
    """The numbers behind a failed solve and what to try."""
    from parakin.solvers import Status

    residual, joint = np.max(res.residual), np.max(res.joint_error)
    hint = (
        "raise --maxiter, or the joints may be unreachable"
        if np.any(res.status == Status.MAXITER)
        else "try another --x0 (the start decides the assembly)"
        if np.any(res.status == Status.WRONG_ASSEMBLY)
        else "tighten --tol, or the joints may be unreachable"
    )
    return f"max residual {residual:.3g} (tol {tol:g}), max joint error {joint:.3g}; {hint}"


#: mechanism name -> (paper key, file name) of the network the pipeline trains for it
NETWORKS = {"3p4s": ("zhao2017_3p4s", "bp_network.npz")}


def _network(mech, path: str | None):
    """The trained network for the hybrid solver: ``--network PATH``, or the one parakin ships (the
    pipeline's, trained on the full config: :mod:`parakin.nn.packaged`)."""
    from parakin.nn import load_network

    if path is not None:
        return load_network(path)
    if mech.name not in NETWORKS:
        raise ValueError(f"no trained network is known for {mech.name}: pass --network PATH")
    return load_network(key=NETWORKS[mech.name][0])


def cmd_bench(args) -> int:
    """Run benchmarks with a config's sizes; no NAME: the solver atlas, every paper's benchmark and
    the summary ``benchmarks.md`` (what the pipeline's ``extra_benchmarks`` rule writes)."""
    import pandas as pd

    from parakin.config import DEFAULT_CONFIG, QUICK_CONFIG, load_config
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
    config = load_config([DEFAULT_CONFIG, QUICK_CONFIG] if args.quick else [DEFAULT_CONFIG])
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


def cmd_readme(args) -> int:
    """Copy the "at a glance" block of ``figures/benchmarks.md`` into README (``--check``: only compare)."""
    from parakin.config import ROOT
    from parakin.studies.solver_atlas import readme_block, sync_readme

    readme = Path(args.readme) if args.readme else ROOT / "README.md"
    bench = Path(args.benchmarks) if args.benchmarks else ROOT / "figures" / "benchmarks.md"
    from parakin.report import readme_blocks_match, sync_status

    report_csv = bench.with_name("report.csv")  # the status table: from report.csv and the registry
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


def _config(args) -> dict:
    from parakin.config import DEFAULT_CONFIG, load_config, validate_sections

    if args.config_json:  # one pipeline rule's sections (registry.prune_config)
        config = json.loads(args.config_json)
        if not isinstance(config, dict):
            raise ValueError(f"--config-json must be a JSON object, got {type(config).__name__}")
        # the pipeline validated the whole config once (workflow/rules/common.smk)
        return config if getattr(args, "validated", False) else validate_sections(config)
    return load_config(args.config or [DEFAULT_CONFIG])


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
    from parakin.config import load_config
    from parakin.pipeline import check

    config = load_config(args.config) if args.config else None
    results = Path(args.results or (config or _default_config())["figures_dir"])
    record = Path(args.record or (config or _default_config())["record_dir"] or "figures")
    out = Path(args.out) if args.out else results.parent / "reproduction_check"
    csv, md, line = check(results, record, out, args.studies or None)
    print(f"{line}; see {md}")
    bad = line.count(" differs") + line.count(" missing")
    return EXIT_NOT_CONVERGED if args.strict and bad else 0


def _default_config() -> dict:
    from parakin.config import DEFAULT_CONFIG, load_config

    return load_config(DEFAULT_CONFIG)


def cmd_which(args) -> int:
    from parakin.pipeline import which

    if not args.path and not args.list:
        raise ValueError("give a file (e.g. figures/zhao2017_3p4s/table1.csv) or --list")
    print(which(args.path, list_all=args.list))
    return 0


def cmd_record(args) -> int:
    from parakin.pipeline import record

    config = _default_config()
    results = Path(args.results or config["figures_dir"])
    target = Path(args.record or config["record_dir"])
    record(results, target)
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


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("parakin")
    except PackageNotFoundError:  # running from a source tree that was never installed
        return "unknown"


#: what each solver is, for ``parakin fk --help`` (others: the first line of their docstring)
SOLVER_HELP = {
    "newton": "Newton-Raphson",
    "broyden": "Broyden's good method (quasi-Newton)",
    "broyden-ls": "Broyden, direct update of a rectangular B with pseudo-inverse steps (redundant systems; the 12-leg drive modes' variant beside the paper's inverse update, broyden update=inverse)",
    "bfgs": "BFGS on |residual|^2 / 2",
    "lm": "Levenberg-Marquardt",
    "gauss-newton": "Gauss-Newton (least squares, redundant systems)",
    "scipy-root": "scipy.optimize.root (hybr), pose by pose",
    "pso": "particle swarm (Li 2020, Li 2017); --maxiter iterations",
    "hybrid": "trained network + quasi-Newton (Zhao 2017; 3p4s, --network)",
    "closed-form": "the mechanism's own fk: closed form (3p4s, stewart12) or its working assembly (2ups, stewart36, stewart66)",
    "all-solutions": "every real solution, then the one nearest --x0 (2ups, stewart36, stewart66; --all lists them)",
}


def _solver_help() -> str:
    from parakin.solvers import METHODS

    width = max(map(len, METHODS))
    lines = ["solvers (--solver NAME):"]
    for name in sorted(METHODS):
        text = SOLVER_HELP.get(name) or " ".join(
            (METHODS[name].__doc__ or "").split(".")[0].replace("`", "").split()
        )
        lines.append(f"  {name:<{width}}  {text}")
    return "\n".join(lines)


def _mechanism_help(what: str) -> str:
    """Names and units of each mechanism's poses and joints (SI; the paper's where they differ)."""
    lines = ["mechanisms (pose | joints, SI units; --units paper: the paper's):"]
    for name in sorted(mechanisms.REGISTRY):
        cls = mechanisms.REGISTRY[name]

        def fmt(names, units, paper):
            if len(names) > 3 and len(set(units)) == 1 and len(set(paper)) == 1:  # l1..l12 [m]
                si = f"{names[0]}..{names[-1]}" + (f" [{units[0]}]" if units[0] != "1" else "")
                return si + (f" (paper: {paper[0]})" if paper[0] != units[0] else "")
            si = " ".join(f"{n}{'[' + u + ']' if u != '1' else ''}" for n, u in zip(names, units))
            if tuple(paper) != tuple(units):
                si += " (paper: " + " ".join(u if u != "1" else "-" for u in paper) + ")"
            return si

        lines.append(
            f"  {name:<10} {fmt(cls.pose_names, cls.pose_units, cls.paper_pose_units)} | "
            f"{fmt(cls.joint_names, cls.joint_units, cls.paper_joint_units)}"
        )
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="parakin", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"parakin {_version()}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    names = sorted(mechanisms.REGISTRY)

    def mech_args(p):
        p.add_argument("mechanism", choices=names, help="mechanism name")
        p.add_argument(
            "--param",
            action="append",
            default=[],
            metavar="NAME=VALUE",
            help="override a mechanism parameter (SI, or with a unit: phi=35deg, d=120mm)",
        )
        p.add_argument(
            "--units", choices=["si", "paper"], default="si", help="units of input and output"
        )
        p.add_argument("--json", action="store_true", help="print a JSON object")

    def file_args(p, what):
        p.add_argument(
            "--input",
            default=None,
            metavar="FILE",
            help=f"read many {what}s from FILE (.csv, optional header 'name [unit]', or .npy), one per row",
        )
        p.add_argument(
            "--output",
            default=None,
            metavar="FILE",
            help="write the results to FILE (.csv with a header, or .npy) instead of printing them",
        )

    p = sub.add_parser(
        "ik",
        help="inverse kinematics: joints of a pose",
        epilog=_mechanism_help("pose"),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    mech_args(p)
    p.add_argument(
        "--pose",
        type=finite_float,
        nargs="+",
        default=None,
        help="pose value(s), n per pose (several poses: n values each, one after the other)",
    )
    file_args(p, "pose")
    p.set_defaults(func=cmd_ik)

    p = sub.add_parser(
        "fk",
        help="forward kinematics: pose of joint values",
        epilog=_solver_help() + "\n\n" + _mechanism_help("joints"),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    mech_args(p)
    p.add_argument(
        "--joints",
        type=finite_float,
        nargs="+",
        default=None,
        help="joint value(s), m per pose (several inputs: m values each, one after the other)",
    )
    file_args(p, "joint vector")
    p.add_argument(
        "--all",
        action="store_true",
        help="list every real solution with its assembly label (mechanisms with an all-solutions "
        f"method: {', '.join(all_solution_mechanisms())})",
    )
    p.add_argument(
        "--solver",
        default=None,
        metavar="NAME",
        help="solver (default: closed-form where one exists, else newton); the list is below",
    )
    p.add_argument(
        "--x0",
        type=finite_float,
        nargs="+",
        default=None,
        help="initial pose (default: the mechanism's home)",
    )
    p.add_argument(
        "--tol", type=nonnegative_float, default=1e-10, help="residual tolerance (default 1e-10)"
    )
    p.add_argument(
        "--joint-tol",
        type=nonnegative_float,
        default=None,
        help="largest |ik(x) - joints| of a success (default: 100 x tol, at least 1e-8)",
    )
    p.add_argument(
        "--maxiter",
        type=iteration_count,
        default=50,
        help=f"iteration limit (default 50, at most {MAXITER_LIMIT})",
    )
    p.add_argument(
        "--network",
        default=None,
        help="trained network for --solver hybrid (default: the pipeline's)",
    )
    p.set_defaults(func=cmd_fk)

    p = sub.add_parser(
        "bench", help="run benchmarks (every solver, same inputs, ratios against scipy in one run)"
    )
    p.add_argument(
        "name",
        nargs="*",
        help=f"benchmark(s): atlas, kernels, {', '.join(BENCHES)} (default: all, and the summary)",
    )
    p.add_argument("--quick", action="store_true", help="small sizes (config/quick.yaml)")
    p.add_argument(
        "--outdir", default=None, help="figures folder (default: figures_dir of the config)"
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
    p.set_defaults(func=cmd_bench)

    p = sub.add_parser(
        "readme", help="copy the benchmark summary block of figures/benchmarks.md into README.md"
    )
    p.add_argument("--readme", default=None, help="README file (default: the project's)")
    p.add_argument(
        "--benchmarks", default=None, help="benchmarks.md (default: figures/benchmarks.md)"
    )
    p.add_argument("--check", action="store_true", help="only compare; exit 1 if they differ")
    p.set_defaults(func=cmd_readme)

    def config_args(p):
        p.add_argument(
            "--config",
            action="append",
            default=None,
            metavar="YAML",
            help="config file(s), later ones override earlier ones (default config/config.yaml)",
        )
        p.add_argument(
            "--config-json", default=None, help="the whole config as JSON (what Snakemake passes)"
        )
        p.add_argument(
            "--validated",
            action="store_true",
            help="the --config-json sections were validated by the pipeline (workflow/rules/common.smk "
            "validates the whole config once); skip validating them again",
        )

    p = sub.add_parser(
        "reproduce", help="compute one artefact (table or figure) of a paper or study"
    )
    p.add_argument(
        "paper",
        help="study key, e.g. zhao2017_3p4s, or 'extra' (beyond the papers: solver atlas, benchmarks)",
    )
    p.add_argument("artefact", help="artefact name, e.g. table1, or 'all'")
    p.add_argument("--outdir", default=None, help="output folder (default: <figures_dir>/<paper>)")
    p.add_argument(
        "--module", default=None, help="the study's module (default: those the config lists)"
    )
    config_args(p)
    p.set_defaults(func=cmd_reproduce)

    p = sub.add_parser(
        "check",
        help="check a run's outputs against the committed record, within declared tolerances",
    )
    p.add_argument(
        "--results",
        default=None,
        help="the run's figures folder (default: figures_dir of the config)",
    )
    p.add_argument(
        "--record", default=None, help="the record (default: record_dir of the config, figures/)"
    )
    p.add_argument(
        "--out", default=None, help="output stem (default: <results>/../reproduction_check)"
    )
    p.add_argument(
        "--studies", nargs="*", default=None, help="study modules (default: the config's)"
    )
    p.add_argument("--config", action="append", default=None, metavar="YAML", help="config file(s)")
    p.add_argument("--strict", action="store_true", help="exit 1 if anything differs or is missing")
    p.set_defaults(func=cmd_check)

    p = sub.add_parser("which", help="which function and rule make a committed figure or table")
    p.add_argument("path", nargs="*", help="file(s), e.g. figures/zhao2017_3p4s/table1.csv")
    p.add_argument(
        "--list", action="store_true", help="list every registered output file and its artefact"
    )
    p.set_defaults(func=cmd_which)

    p = sub.add_parser(
        "record", help="copy a finished run (results/) into the committed record (figures/)"
    )
    p.add_argument(
        "--results",
        default=None,
        help="the run's figures folder (default: figures_dir of the config)",
    )
    p.add_argument("--record", default=None, help="the record (default: record_dir of the config)")
    p.add_argument(
        "--no-readme",
        dest="readme",
        action="store_false",
        help="do not copy the benchmark block into README",
    )
    p.set_defaults(func=cmd_record)

    p = sub.add_parser("report", help="write the claim-by-claim REPORT.md")
    p.add_argument(
        "--figures", default=None, help="figures folder (default: figures_dir of the config)"
    )
    p.add_argument("--out", default=None, help="output file (default: <figures>/REPORT.md)")
    config_args(p)
    p.set_defaults(func=cmd_report)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        with np.errstate(all="ignore"):  # non-finite results are checked, not warned about
            return args.func(args)
    except (ParakinError, ValueError, KeyError, ArithmeticError, OSError, MemoryError) as exc:
        print(f"parakin {args.command}: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_BAD_INPUT


def _one_line(exc: BaseException) -> str:
    """The error's message on one line (a KeyError's without quotes; an OSError's with its path)."""
    if isinstance(exc, KeyError) and exc.args:
        message = str(exc.args[0])
    elif isinstance(exc, MemoryError):
        message = f"out of memory ({exc or 'the request is too large'})"
    elif isinstance(exc, OSError) and exc.filename is not None:
        message = f"{exc.strerror or exc}: {exc.filename}"
    else:
        message = str(exc) or type(exc).__name__
    return " ".join(message.split())


if __name__ == "__main__":
    sys.exit(main())
