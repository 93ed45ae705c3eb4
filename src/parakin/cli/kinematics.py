"""``parakin ik`` and ``parakin fk`` (one solver, or ``--all``: every real assembly)."""

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
    _mechanism,
    _mechanism_args,
    _print_json,
    _text_option,
    _unit,
    _units,
    _units_note,
    finite_float,
    iteration_count,
    nonnegative_float,
)
from parakin.errors import ParakinError
from parakin.io import write_rows
from parakin.units import from_si, to_si


def cmd_ik(args) -> int:
    mech = _mechanism(args.mechanism, args.param, args.geometry)
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
    mech = _mechanism(args.mechanism, args.param, args.geometry)
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
    with np.errstate(all="ignore"):
        pose = _finite(from_si(res.x, pu), "the solution in --units " + args.units, given)
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
        out["x"] = pose.tolist()
        _print_json(mech, out)
    elif args.output is None:
        for x in np.atleast_2d(pose):
            print(_fmt_vector(mech.pose_names, x, pu))
    if not np.all(res.success):
        print(f"parakin fk: error: {res.message} ({_why(res, args.tol)})", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    if np.any(near):
        print(f"parakin fk: warning: {_near_warning(mech, res, near, pu)}", file=sys.stderr)
    _units_note(mech, "fk", paper)
    return 0


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
        "joint_error_m": np.atleast_1d(res.joint_error).astype(float),
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
    if args.output is not None:
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
        _print_json(
            mech,
            {
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
            },
        )
    elif args.output is None:
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
        f"method: {', '.join(all_solution_mechanisms())})",
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
