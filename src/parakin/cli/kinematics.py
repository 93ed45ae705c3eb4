"""``parakin ik`` and ``parakin fk`` (one solver, or ``--all``: every real assembly), for a
registered mechanism or one described in a file (``--mechanism FILE``)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from parakin import mechanisms
from parakin.cli.common import (
    EXIT_NOT_CONVERGED,
    MAXITER_LIMIT,
    _angles,
    _batch,
    _file_args,
    _finite,
    _fmt_vector,
    _inputs,
    _mechanism_args,
    _print_json,
    _text_option,
    _unit,
    _units,
    _units_note,
    finite_float,
    iteration_count,
    mechanism_of,
    nonnegative_float,
)
from parakin.io import write_rows
from parakin.units import from_si, to_si


def cmd_ik(args) -> int:
    mech = mechanism_of(args)
    paper = args.units == "paper"
    pu, ju = _units(mech, "pose", paper), _units(mech, "joint", paper)
    given, pose = _inputs(args, mech, "pose", paper)
    with np.errstate(all="ignore"):
        joints = _finite(from_si(mech.ik(pose), ju), "the inverse kinematics", given)
    if args.output is not None:
        write_rows(args.output, mech.joint_names, ju, np.atleast_2d(joints))
        print(
            f"parakin ik: {len(np.atleast_2d(joints))} joint vector(s) written to {args.output}",
            file=sys.stderr,
        )
    if args.json:
        _print_json(
            mech,
            {
                "pose": given.tolist(),
                "pose_units": pu,
                "joints": joints.tolist(),
                "joint_units": ju,
            },
        )
    elif args.output is None:
        for q in np.atleast_2d(joints):
            print(_fmt_vector(mech.joint_names, q, ju))
    _units_note(mech, "ik", paper)
    return 0


def cmd_fk(args) -> int:
    mech = mechanism_of(args)
    paper = args.units == "paper"
    pu, ju = _units(mech, "pose", paper), _units(mech, "joint", paper)
    given, joints = _inputs(args, mech, "joints", paper)
    if args.all:
        if args.solver is not None or args.x0 is not None:
            raise ValueError(
                "--all lists every solution of the all-solutions method: it takes no --solver or --x0"
            )
        return _fk_all(args, mech, given, joints, pu, ju)
    res = _solve(args, mech, joints, pu)
    ok = np.atleast_1d(res.success)
    with np.errstate(all="ignore"):
        pose = from_si(res.x, pu)
        _finite(np.atleast_2d(pose)[ok], "the solution in --units " + args.units, given)
    near = res.success & res.near_singular
    if args.output is not None:
        _write_fk(args.output, mech, pu, pose, res, near)
    if args.json:
        out = {
            "joints": given.tolist(),
            "joint_units": ju,
            "pose_units": pu,
            **res.to_dict(),
            **_conditioning_fields(res, pu),
        }
        # a failed row has no pose: its last iterate is kept apart, under its own name
        rows = np.atleast_2d(pose)
        answer = [x.tolist() if good else None for x, good in zip(rows, ok)]
        last = [None if good else x.tolist() for x, good in zip(rows, ok)]
        finite = lambda v: v if v is None else [c if np.isfinite(c) else None for c in v]  # noqa: E731
        out["x"] = answer if np.ndim(res.success) else answer[0]
        out["last_iterate"] = [finite(v) for v in last] if np.ndim(res.success) else finite(last[0])
        out["startup_note"] = _startup_note(res)
        _print_json(mech, out)
    elif args.output is None:
        for x, good, status in zip(np.atleast_2d(pose), ok, np.atleast_1d(res.status)):
            if good:
                print(_fmt_vector(mech.pose_names, x, pu))
            elif ok.size > 1:  # a batch keeps one line per input, marked, without numbers
                print(f"# not solved ({_status_name(status)})")
    if not np.all(res.success):
        print(f"parakin fk: error: {res.message} ({_why(res, args.tol)})", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    if np.any(near):
        print(f"parakin fk: warning: {_near_warning(mech, res, near, pu)}", file=sys.stderr)
    if res.startup > STARTUP_NOTE_S and not args.json:
        print(f"parakin fk: note: {_startup_note(res)}", file=sys.stderr)
    _units_note(mech, "fk", paper)
    return 0


#: a compiled solver's first call that took longer than this (s) says so (``FKResult.startup``)
STARTUP_NOTE_S = 0.5


def _startup_note(res) -> str | None:
    """What of ``wall_time`` was loading or compiling compiled code, or None (none was)."""
    if not res.startup > 0:
        return None
    return (
        f"wall_time {res.wall_time:.3g} s includes {res.startup:.3g} s of loading or compiling "
        "the compiled solver (its first call in this process)"
    )


def _solve(args, mech, joints: np.ndarray, pu):
    """``solve_fk`` with the command's solver, start and tolerances (joints checked first)."""
    from parakin.solvers import METHODS, solve_fk

    with np.errstate(all="ignore"):  # unreachable joints: the mechanism's own error, any solver
        mech.check_joints(joints)
    method = args.solver if args.solver is not None else _default_solver(mech)
    if method not in METHODS:
        raise ValueError(f"unknown solver {method!r}; known: {', '.join(sorted(METHODS))}")
    x0 = None
    if args.x0 is not None:
        x0 = _batch(args.x0, mech.n_pose, "--x0", mech.pose_names)
        x0 = to_si(_angles(x0, mech.pose_names, pu, "--x0"), pu)
    options = {"network": _network(mech, args.network)} if method == "hybrid" else {}
    return solve_fk(
        mech,
        joints,
        x0=x0,
        method=method,
        tol=args.tol,
        maxiter=args.maxiter,
        joint_tol=args.joint_tol,
        **options,
    )


def _default_solver(mech) -> str:
    return "closed-form" if mech.fk is not None else "newton"


def _write_fk(path: str, mech, pu, pose: np.ndarray, res, near: np.ndarray) -> None:
    flat = np.atleast_2d(pose)
    extra = {
        "success": np.atleast_1d(res.success),
        "status": [_status_name(v) for v in np.atleast_1d(res.status)],
        "nit": np.atleast_1d(res.nit),
        "residual": np.atleast_1d(res.residual).astype(float),
        # in the joints' units: metres where every joint is a length (the column's old name)
        ("joint_error_m" if set(mech.joint_units) == {"m"} else "joint_error"): np.atleast_1d(
            res.joint_error
        ).astype(float),
        "near_singular": np.atleast_1d(near),
    }
    write_rows(path, mech.pose_names, pu, flat, extra=extra)
    print(
        f"parakin fk: {len(flat)} pose(s) written to {path} ({int(np.sum(res.success))} converged)",
        file=sys.stderr,
    )


def _conditioning_fields(res, pu) -> dict:
    """The JSON fields of ``res.conditioning`` (offsets in the printed units)."""
    c = res.conditioning
    return {
        "near_singular": (res.success & c.near_singular).tolist(),
        "condition": _finite_or_none(c.condition),
        "nearest_other_solution_offset": _finite_or_none(from_si(c.neighbour, pu)),
    }


def _finite_or_none(a: np.ndarray):
    a = np.asarray(a, dtype=float)
    return np.where(np.isfinite(a), a, None).tolist()


def _near_warning(mech, res, near: np.ndarray, pu) -> str:
    """One line: the (first) answer near a singularity and how far its neighbour is estimated."""
    c = res.conditioning
    flat = np.atleast_1d(near)
    i = int(np.argmax(flat))
    offset = np.abs(from_si(np.reshape(c.neighbour, (-1, mech.n_pose))[i], pu))
    size = ", ".join(
        f"{np.max(offset[[k for k, v in enumerate(pu) if v == unit]]):.2g}{_unit(unit)}"
        for unit in dict.fromkeys(pu)
    )
    which = f"{int(flat.sum())} of {flat.size} poses; row {i + 1} has" if flat.size > 1 else ""
    return (
        f"near a singularity: {which + ' ' if which else ''}another solution of the same joints "
        f"about {size} away (condition number {float(np.reshape(c.condition, -1)[i]):.3g}); "
        "the start decides which one is returned (see --x0)"
    )


def all_solution_mechanisms() -> list[str]:
    """The registered mechanisms that list every real assembly (``--all``)."""
    return sorted(n for n, cls in mechanisms.REGISTRY.items() if cls.lists_assemblies())


def _fk_all(args, mech, given, joints, pu, ju) -> int:
    if not mech.lists_assemblies():
        raise ValueError(
            f"{mech.name} has no all-solutions method; --all works on "
            f"{', '.join(all_solution_mechanisms())} and on described mechanisms (--mechanism FILE)"
        )
    with np.errstate(all="ignore"):
        found = mech.assemblies(np.atleast_2d(joints))
    rows_of = [[(a.label, a.x, a.working) for a in rows] for rows in found.solutions]
    for rows in rows_of:
        for _, x, _ in rows:
            _finite(from_si(x, pu), "a solution in --units " + args.units, given)
    counts = found.n_found
    if args.output is not None:
        if Path(args.output).suffix.lower() == ".npy":
            k = max(counts + [1])
            a = np.full((len(rows_of), k, mech.n_pose), np.nan)
            for i, rows in enumerate(rows_of):
                for j, (_, x, _) in enumerate(rows):
                    a[i, j] = from_si(x, pu)
            write_rows(args.output, mech.pose_names, pu, a)
        else:
            flat = [
                (i + 1, j + 1, label, work, from_si(x, pu))
                for i, rows in enumerate(rows_of)
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
            f"parakin fk: {sum(counts)} real solution(s) of {len(rows_of)} input(s) written to {args.output}",
            file=sys.stderr,
        )
    complete = None if found.complete is None else found.complete.tolist()
    if args.json:
        _print_json(
            mech,
            {
                "joints": np.atleast_2d(given).tolist(),
                "joint_units": ju,
                "pose_units": pu,
                "n_real": counts,
                "n_found": counts,
                # true: the method guarantees no real assembly is missing (a certificate or an
                # exact closed form); false: it may have missed some; null: it says neither
                "complete": complete,
                "solutions": [
                    [
                        {"assembly": label, "working": work, "x": from_si(x, pu).tolist()}
                        for label, x, work in rows
                    ]
                    for rows in rows_of
                ],
            },
        )
    elif args.output is None:
        q = np.atleast_2d(given)
        for i, rows in enumerate(rows_of):
            sure = "" if complete is None else ("" if complete[i] else " (not certified complete)")
            print(f"{_fmt_vector(mech.joint_names, q[i], ju)}: {len(rows)} real solution(s){sure}")
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
    "closed-form": "the mechanism's own fk: closed form (3p4s, stewart12) or its working assembly (2ups, stewart36, stewart66, a --mechanism FILE)",
    "all-solutions": "every real solution, then the one nearest --x0 (2ups, stewart36, stewart66, a --mechanism FILE; --all lists them)",
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
    lines.append(
        "  --mechanism FILE: a mechanism described in YAML/JSON (examples/*.yaml): its pose is "
        "x y z [alpha beta gamma] or x y phi, its joints each leg's length, slider position or "
        "crank angle"
    )
    return "\n".join(lines)


def _kinematics_parser(
    sub, name: str, help: str, epilog: str, values: str, each: str, what: str, func
):
    """The parser of ``ik``/``fk``: the mechanism options, ``--VALUES`` (one vector or a batch,
    ``each`` says how many per input) and ``--input``/``--output`` files of ``what``s."""
    p = sub.add_parser(
        name,
        help=help,
        epilog=epilog,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        func=func,
    )
    _mechanism_args(p)
    p.add_argument("--" + values, type=finite_float, nargs="+", default=None, help=each)
    _file_args(p, what)
    return p


def add_ik(sub) -> None:
    _kinematics_parser(
        sub,
        "ik",
        "inverse kinematics: joints of a pose",
        _mechanism_help("pose"),
        "pose",
        "pose value(s), n per pose (several poses: n values each, one after the other)",
        "pose",
        func=cmd_ik,
    )


def add_fk(sub) -> None:
    p = _kinematics_parser(
        sub,
        "fk",
        "forward kinematics: pose of joint values",
        _solver_help() + "\n\n" + _mechanism_help("joints"),
        "joints",
        "joint value(s), m per pose (several inputs: m values each, one after the other)",
        "joint vector",
        func=cmd_fk,
    )
    p.add_argument(
        "--all",
        action="store_true",
        help="list every real solution with its assembly label (mechanisms with an all-solutions "
        f"method: {', '.join(all_solution_mechanisms())}, and every --mechanism FILE)",
    )
    _text_option(
        p,
        "--solver",
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
    _text_option(
        p,
        "--network",
        help="trained network for --solver hybrid (default: the pipeline's)",
    )
