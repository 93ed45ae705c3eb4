"""The ``parakin`` command line (``parakin --help`` lists every command; ``parakin CMD --help``
its options).

Bad input (a wrong number of values, an unreachable pose, an unknown solver, a malformed config or
file) exits with status 2 and one line on stderr, never a traceback. SI units by default;
``--units paper`` reads and prints the units the paper uses. ``ik`` and ``fk`` take many poses or
joint vectors from a file (``--input``, CSV or .npy, one per row) and write them to one
(``--output``, atomically: :func:`parakin.io.atomic_writer`); each reads what the other writes.
An ``fk`` answer near a singularity (another solution close by) gets a one-line warning.
"""

from __future__ import annotations

import argparse
import contextvars
import dataclasses
import json
import math
import os
import re
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from parakin import kernels, mechanisms
from parakin.errors import ParakinError
from parakin.io import read_rows, read_text, write_rows
from parakin.units import TO_SI, from_si, parse_quantity, to_si

EXIT_BAD_INPUT = 2
EXIT_NOT_CONVERGED = 1


#: largest --maxiter (a bound on the work one command may ask for)
MAXITER_LIMIT = 100_000
#: largest magnitude of a --param value in SI units (m, rad): far beyond any real mechanism
PARAM_LIMIT = 1e6
#: largest |angle| of a pose, a start or a joint (rad, about 159 turns). The spacing of doubles
#: at 1e3 is 1.1e-13 rad, below every accuracy the solvers promise; near 4.5e3 rad it reaches
#: 1e-12 rad and at 1e308 it is larger than a turn: such an angle names no orientation at all.
ANGLE_LIMIT = 1e3
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


def nonempty(text: str) -> str:
    """A non-empty string (``--output ''`` is a mistake, not a request for the default)."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f"{text!r} is empty")
    return text


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


def _default(field: dataclasses.Field):
    if field.default is not dataclasses.MISSING:
        return field.default
    if field.default_factory is not dataclasses.MISSING:
        return field.default_factory()
    return None


def _numeric_shape(value) -> tuple[int, ...] | None:
    """The shape of ``value`` if it is a real number or an array of them (not a bool), else None."""
    if isinstance(value, (bool, np.bool_, str)) or value is None:
        return None
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return None
    return a.shape


def parameters_of(cls) -> dict[str, object]:
    """The parameters ``--param`` and ``--geometry`` may set, name -> default: every field of the
    mechanism's dataclass whose default is a real number or an array of them, by the names of the
    Python API (switches such as a convention name or a flag are not parameters)."""
    out = {}
    for f in dataclasses.fields(cls):
        default = _default(f)
        if _numeric_shape(default) is not None:
            out[f.name] = default
    return out


def _parameter(where: str, value, default):
    """``value`` (a number, a quantity such as ``35deg``, or a nested list of them) checked against
    the parameter's default: the same shape, finite, at most :data:`PARAM_LIMIT` in magnitude (SI)
    and whole where the default is an integer; arrays as nested tuples (mechanisms are hashable)."""
    shape = _numeric_shape(default)
    try:
        a = np.vectorize(lambda v: parse_quantity(v) if isinstance(v, str) else float(v))(
            np.asarray(value, dtype=object)
        ).astype(float)
    except (TypeError, ValueError) as exc:
        raise ValueError(
            f"{where}: {value!r:.60} is not a number or an array of numbers ({exc})"
        ) from None
    if a.shape != shape:
        want = "one number" if not shape else f"an array of shape {shape}"
        raise ValueError(f"{where}: expected {want}, got shape {a.shape}")
    if not np.all(np.isfinite(a) & (np.abs(a) <= PARAM_LIMIT)):
        raise ValueError(
            f"{where}: values must be finite numbers <= {PARAM_LIMIT:g} in magnitude (SI units)"
        )
    if isinstance(default, (int, np.integer)):
        if not float(a).is_integer():
            raise ValueError(f"{where}: {float(a)!r} must be a whole number")
        return int(a)
    return float(a) if not shape else _nested_tuple(a)


def _nested_tuple(a: np.ndarray):
    return tuple(_nested_tuple(v) for v in a) if a.ndim else float(a)


def _param_text(text: str, default):
    """The value of ``--param NAME=TEXT``: a number or quantity, or for an array parameter a
    YAML/JSON list (``[[0, 0, 0], [1, 0, 0], ...]``)."""
    if not _numeric_shape(default):
        return text
    import yaml  # here, not at the top: a solve on the command line does not need it

    try:
        return yaml.safe_load(text)
    except yaml.YAMLError:
        raise ValueError(f"{text!r:.60} is not a YAML/JSON list") from None


def _geometry(path: str) -> dict:
    """The parameters in ``--geometry FILE`` (YAML or JSON, the names of the Python API)."""
    import yaml

    from parakin.config import check_bounds

    try:
        data = yaml.safe_load(read_text(path, "--geometry"))
    except yaml.YAMLError as exc:
        raise ValueError(
            f"--geometry {path}: not YAML or JSON ({' '.join(str(exc).split())})"
        ) from None
    if not isinstance(data, dict):
        raise ValueError(f"--geometry {path}: expected a mapping of parameter names to values")
    check_bounds(data, f"--geometry {path}")
    return data


def _mechanism(name: str, params: Sequence[str], geometry: str | None = None):
    """The mechanism ``name`` with the parameters of ``--geometry FILE``, then of each ``--param
    NAME=VALUE`` (the declared parameters, :func:`parameters_of`)."""
    cls = mechanisms.get(name)
    known = parameters_of(cls)
    given = {}
    if geometry is not None:
        given = {k: (f"--geometry {geometry}: {k}", v) for k, v in _geometry(geometry).items()}
    for item in params:
        key, sep, value = item.partition("=")
        if not sep:
            raise ValueError(f"--param {item!r} must look like NAME=VALUE (e.g. phi=35deg)")
        key = key.strip()
        given[key] = (f"--param {item}", _param_text(value, known.get(key)))
    unknown = sorted(set(given) - set(known))
    if unknown:
        raise ValueError(f"unknown parameter(s) {unknown} of {name}; known: {sorted(known)}")
    values = {k: _parameter(where, v, known[k]) for k, (where, v) in given.items()}
    try:
        return cls(**values)
    except TypeError as exc:
        raise ValueError(f"{name}: {exc}") from None


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


def _angles(values: np.ndarray, names, units, option: str) -> np.ndarray:
    """``values`` if every angle among them (unit ``rad`` or ``deg``) is within
    :data:`ANGLE_LIMIT`; else a ValueError naming the value and the limit in its unit."""
    for k, unit in enumerate(units):
        if unit in ("rad", "deg"):
            limit = ANGLE_LIMIT / TO_SI[unit]
            worst = float(np.max(np.abs(np.atleast_2d(values)[..., k])))
            if not worst <= limit:
                raise ValueError(
                    f"{option}: {names[k]} = {worst:.6g} {unit} is beyond the limit |angle| <= "
                    f"{limit:.6g} {unit} ({ANGLE_LIMIT:g} rad; a pose angle is a few turns at most)"
                )
    return values


def _dumps(obj) -> str:
    """Strict JSON (no NaN or Infinity)."""
    return json.dumps(obj, allow_nan=False)


def _print_json(mech, fields: dict) -> None:
    """One JSON object on stdout: the mechanism, its parameters, then ``fields``."""
    print(_dumps({"mechanism": mech.name, "parameters": mech.parameters(), **fields}))


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


def _inputs(args, mech, what: str, paper: bool) -> tuple[np.ndarray, np.ndarray]:
    """The values of ``--pose``/``--joints`` (one vector or a batch) or of ``--input FILE``, as
    given (in ``--units``) and in SI, every one finite and every angle within :data:`ANGLE_LIMIT`."""
    kind = "pose" if what == "pose" else "joint"
    names, units = getattr(mech, f"{kind}_names"), _units(mech, kind, paper)
    values = getattr(args, what)
    if args.input is not None:
        if values is not None:
            raise ValueError(f"give --{what} or --input, not both")
        given = read_rows(args.input, names, units)
    elif values is None:
        raise ValueError(f"give --{what} VALUES or --input FILE (CSV or .npy, one row each)")
    else:
        given = _batch(values, len(names), f"--{what}", names)
    option = f"--{what}" if args.input is None else f"--input {args.input}"
    _angles(given, names, units, option)
    _compiled_if_worth_it(len(given))
    return given, _finite(to_si(given, units), f"{option} in SI units", given)


#: a command with fewer inputs runs the kernels on numpy: loading compiled code costs 0.5-1 s per
#: process (minutes on an empty cache), more than numpy takes for a few hundred inputs
#: (``PARAKIN_KERNELS=1`` compiles anyway, ``=0`` never)
COMPILED_MIN_INPUTS = 256


def _compiled_if_worth_it(n_inputs: int) -> None:
    """For the rest of this command: the numpy path below :data:`COMPILED_MIN_INPUTS` inputs."""
    if n_inputs < COMPILED_MIN_INPUTS and os.environ.get("PARAKIN_KERNELS") != "1":
        kernels.use_interpreted()


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


def cmd_kernels(args) -> int:
    """``parakin kernels``: where compiled code is cached, what is there; ``--clear`` empties it."""
    from parakin.kernels import store

    root = store.root()
    if args.clear:
        freed = store.clear()
        print(f"parakin kernels: removed {freed / 1e6:.1f} MB of compiled code from {root}")
        return 0
    status = store.status()
    on = "on" if kernels.enabled() else "off (the numpy path)"
    print(f"cache: {status['root'] or 'none writable'}; compiled path {on}")
    for b in status["builds"]:
        what = f"{b['name']} ({b['hash']})" if b["hash"] else b["name"]
        print(f"  {what:<50} {b['files']:>4} files {b['bytes'] / 1e6:8.1f} MB")
    return 0


def _add_kernels(sub) -> None:
    p = sub.add_parser(
        "kernels",
        help="the cache of compiled kernels: status (default) or --clear",
        func=cmd_kernels,
    )
    p.add_argument("--status", action="store_true", help="list the cached builds (default)")
    p.add_argument("--clear", action="store_true", help="remove every cached build")


def cmd_readme(args) -> int:
    """Copy the "at a glance" block of ``figures/benchmarks.md`` into README (``--check``: only compare)."""
    from parakin.config import ROOT
    from parakin.glance import GLANCE_BEGIN, GLANCE_END
    from parakin.report import STATUS_BEGIN, STATUS_END, readme_blocks_match, sync_status
    from parakin.studies.solver_atlas import BEGIN, END, readme_block, sync_readme

    readme = Path(args.readme) if args.readme is not None else ROOT / "README.md"
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


def _default_config() -> dict:
    from parakin.config import load_run_config

    return load_run_config()


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


class _VersionAction(argparse.Action):
    """``--version``: argparse's version action, with the version looked up only when asked
    (importlib.metadata is about 10 ms of every command's start otherwise)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, **kwargs):
        kwargs.setdefault("help", "show the program's version number and exit")
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"parakin {_version()}")
        parser.exit()


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


class _Commands:
    """The subcommands as the ``_add_*`` functions declare them (``add_parser(name, help=...)``),
    each help kept here for ``parakin --help``'s command list rather than handed to argparse,
    whose help formatter measures subcommands one indent short and would push a long name's
    help onto the next line."""

    def __init__(self, action: argparse.Action) -> None:
        self.action = action
        self.helps: dict[str, str] = {}

    def add_parser(
        self, name: str, *, func: Callable[..., int], help: str = "", **kwargs
    ) -> argparse.ArgumentParser:
        """The parser of command ``name``, which ``func(args)`` runs."""
        self.helps[name] = help
        parser = self.action.add_parser(name, **kwargs)
        parser.set_defaults(func=func)
        return parser

    def listing(self) -> str:
        """``commands:`` and one line per command: its name and its help."""
        width = max(map(len, self.helps), default=0) + 2
        lines = [f"  {name:<{width}} {text}" for name, text in self.helps.items()]
        return "\n".join(["commands:", *lines])


def build_parser() -> argparse.ArgumentParser:
    """The ``parakin`` parser: one subcommand per ``_add_*`` function below; ``parakin --help``
    lists them, one line each, from the parser itself."""
    parser = _Parser(
        prog="parakin",
        formatter_class=argparse.RawTextHelpFormatter,
        description="parakin: parallel-mechanism kinematics (IK/FK, solvers, benchmarks) and the "
        "reproduction of four papers.",
    )
    parser.add_argument("--version", action=_VersionAction)
    action = parser.add_subparsers(
        title="commands", dest="command", required=True, metavar="COMMAND", parser_class=_Parser
    )
    sub = _Commands(action)
    for add in (
        _add_ik,
        _add_fk,
        _add_bench,
        _add_readme,
        _add_reproduce,
        _add_check,
        _add_which,
        _add_record,
        _add_report,
        _add_dynamics,
        _add_kernels,
    ):
        add(sub)
    # the usage as argparse writes it; then the command list is ours, in the epilog
    parser.usage = parser.format_usage().removeprefix("usage: ").rstrip("\n")
    action.help = argparse.SUPPRESS
    parser.epilog = (
        sub.listing() + "\n\nparakin COMMAND --help shows a command's options. Bad input: exit "
        "status 2 and one line on stderr."
    )
    return parser


def _text_option(p, flag: str, **kwargs) -> None:
    """An option that takes a non-empty text (a file, a folder, a name); None when not given."""
    p.add_argument(flag, type=nonempty, default=None, **kwargs)


def _mechanism_options(p) -> None:
    """The mechanism and its geometry: ``MECH [--param NAME=VALUE]... [--geometry FILE]``."""
    p.add_argument("mechanism", choices=sorted(mechanisms.REGISTRY), help="mechanism name")
    p.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="set a mechanism parameter, by its name in the Python API: a number (SI, or with "
        "a unit: phi=35deg, d=120mm) or an array as a YAML/JSON list (base=[[0,0,0],...])",
    )
    _text_option(
        p,
        "--geometry",
        metavar="FILE",
        help="the mechanism's parameters from a YAML or JSON file (names of the Python API, "
        "arrays as lists); --param values override them",
    )


def _mechanism_args(p) -> None:
    _mechanism_options(p)
    p.add_argument(
        "--units", choices=["si", "paper"], default="si", help="units of input and output"
    )
    p.add_argument("--json", action="store_true", help="print a JSON object")


def _file_args(p, what: str) -> None:
    _text_option(
        p,
        "--input",
        metavar="FILE",
        help=f"read many {what}s from FILE (.csv, optional header 'name [unit]', or .npy), one per row",
    )
    _text_option(
        p,
        "--output",
        metavar="FILE",
        help="write the results to FILE (.csv with a header, or .npy) instead of printing them",
    )


def _config_args(p) -> None:
    p.add_argument(
        "--config",
        action="append",
        type=nonempty,
        default=None,
        metavar="YAML",
        help="config overlay(s) merged onto config/config.yaml in order, as snakemake "
        "--configfile (e.g. config/quick.yaml)",
    )
    _text_option(
        p,
        "--config-json",
        help="the whole config as JSON (what Snakemake passes)",
    )
    p.add_argument(
        "--validated",
        action="store_true",
        help="the --config-json sections were validated by the pipeline (workflow/rules/common.smk "
        "validates the whole config once); skip validating them again",
    )


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


def _add_ik(sub) -> None:
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


def _add_fk(sub) -> None:
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


def _add_bench(sub) -> None:
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


def _add_readme(sub) -> None:
    p = sub.add_parser(
        "readme",
        help="copy the benchmark summary block of figures/benchmarks.md into README.md",
        func=cmd_readme,
    )
    _text_option(p, "--readme", help="README file (default: the project's)")
    _text_option(
        p,
        "--benchmarks",
        help="benchmarks.md (default: figures/benchmarks.md)",
    )
    p.add_argument("--check", action="store_true", help="only compare; exit 1 if they differ")


def _add_reproduce(sub) -> None:
    p = sub.add_parser(
        "reproduce",
        help="compute one artefact (table or figure) of a paper or study",
        func=cmd_reproduce,
    )
    p.add_argument(
        "paper",
        help="study key, e.g. zhao2017_3p4s, or 'extra' (beyond the papers: solver atlas, benchmarks)",
    )
    p.add_argument("artefact", help="artefact name, e.g. table1, or 'all'")
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


def _add_check(sub) -> None:
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
    p.add_argument(
        "--config",
        action="append",
        type=nonempty,
        default=None,
        metavar="YAML",
        help="config overlay(s) merged onto config/config.yaml (e.g. config/quick.yaml)",
    )
    p.add_argument("--strict", action="store_true", help="exit 1 if anything differs or is missing")


def _add_which(sub) -> None:
    p = sub.add_parser(
        "which", help="which function and rule make a committed figure or table", func=cmd_which
    )
    p.add_argument("path", nargs="*", help="file(s), e.g. figures/zhao2017_3p4s/table1.csv")
    p.add_argument(
        "--list", action="store_true", help="list every registered output file and its artefact"
    )


def _add_record(sub) -> None:
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
        help="do not copy the benchmark block into README",
    )


def _add_report(sub) -> None:
    p = sub.add_parser("report", help="write the claim-by-claim REPORT.md", func=cmd_report)
    _text_option(
        p,
        "--figures",
        help="figures folder (default: figures_dir of the config)",
    )
    _text_option(p, "--out", help="output file (default: <figures>/REPORT.md)")
    _config_args(p)


# ---------------------------------------------------------------------------------------- dynamics
def _add_dynamics(sub) -> None:
    """``parakin dynamics MECH --trajectory FILE``: actuator forces along a trajectory."""
    p = sub.add_parser(
        "dynamics",
        help="actuator forces along a trajectory (inverse dynamics, docs/dynamics.md)",
        description="Actuator forces of a mechanism along a trajectory, by virtual work over its "
        "declared bodies and masses (mass_model() defaults). The trajectory FILE is a CSV with a "
        "column t (s) and one column per pose coordinate (SI), optionally d_<name> rates and "
        "dd_<name> accelerations (else a cubic spline through the poses gives them).",
        func=cmd_dynamics,
    )
    p.add_argument(
        "--trajectory",
        required=True,
        type=nonempty,
        metavar="FILE",
        help="trajectory CSV (SI units)",
    )
    _mechanism_options(p)
    p.add_argument(
        "--wrench",
        type=finite_float,
        nargs=6,
        default=None,
        metavar="W",
        help="external force (N) and moment (N m) on the platform",
    )
    p.add_argument(
        "--flag-singular",
        action="store_true",
        help="report singular or unbalanced samples (NaN forces) instead of stopping",
    )
    _text_option(
        p,
        "--output",
        metavar="FILE",
        help="write the forces to FILE (.csv or .npy)",
    )
    p.add_argument("--json", action="store_true", help="print a JSON object")


def cmd_dynamics(args) -> int:
    from parakin import dynamics
    from parakin.dynamics.trajectory import read_trajectory

    mech = _mechanism(args.mechanism, args.param, args.geometry)
    if mech.mass_model() is None:
        raise ValueError(f"{mech.name} declares no masses (mass_model()): no dynamics")
    traj = read_trajectory(args.trajectory, mech)
    res = dynamics.inverse_dynamics(
        mech,
        *traj.state(traj.t),
        wrench=args.wrench,
        on_singular="flag" if args.flag_singular else "raise",
    )
    units = ["N" if u == "m" else "N m" if u == "rad" else "N" for u in mech.joint_units]
    flags = {"condition": res.condition, "singular": res.singular, "unbalanced": res.unbalanced}
    if args.output:
        write_rows(
            args.output, mech.joint_names, units, res.force, extra=flags, lead={"t [s]": traj.t}
        )
        print(
            f"parakin dynamics: {len(traj.t)} sample(s) written to {args.output}", file=sys.stderr
        )
    if args.json:
        print(
            _dumps(
                {
                    "mechanism": mech.name,
                    "joints": list(mech.joint_names),
                    "force_units": units,
                    "t": traj.t.tolist(),
                    "force": res.force.tolist(),
                    **{k: v.tolist() for k, v in flags.items()},
                }
            )
        )
    elif not args.output:
        for t, f in zip(traj.t, res.force):
            print(f"t = {t:.6g} s  " + _fmt_vector(mech.joint_names, f, units))
    bad = int(np.sum(res.singular | res.unbalanced))
    if bad:
        print(
            f"parakin dynamics: {bad} sample(s) singular or unbalanced (forces NaN)",
            file=sys.stderr,
        )
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        with np.errstate(all="ignore"):  # non-finite results are checked, not warned about
            return contextvars.copy_context().run(args.func, args)  # settings stay in the command
    except (
        ParakinError,
        ValueError,
        KeyError,
        ArithmeticError,
        OSError,
        MemoryError,
        RecursionError,  # e.g. --config-json nested thousands deep
    ) as exc:
        print(f"parakin {args.command}: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_BAD_INPUT


def _one_line(exc: BaseException) -> str:
    """The error's message on one line (a KeyError's without quotes; an OSError's with its path)."""
    if isinstance(exc, KeyError) and exc.args:
        message = str(exc.args[0])
    elif isinstance(exc, MemoryError):
        message = f"out of memory ({exc or 'the request is too large'})"
    elif isinstance(exc, RecursionError):
        message = f"input nested too deeply ({exc})"
    elif isinstance(exc, OSError) and exc.filename is not None:
        message = f"{exc.strerror or exc}: {exc.filename}"
    else:
        message = str(exc) or type(exc).__name__
    return " ".join(message.split())


if __name__ == "__main__":
    sys.exit(main())
