"""``parakin workspace``: volumes, boundary and singularity loci of a mechanism's workspace."""

from __future__ import annotations

import argparse
import sys

import numpy as np

from parakin.cli.common import (
    ANGLE_LIMIT,
    PARAM_LIMIT,
    _dumps,
    _mechanism_options,
    _text_option,
    finite_float,
    mechanism_of,
    nonnegative_float,
)
from parakin.units import parse_quantity

#: most Monte-Carlo samples one command may ask for (about 10 min of 2 cores at 10^6 per second)
MAX_SAMPLES = 1_000_000_000


def _int_in(lo: int, hi: int):
    """An argparse type: an integer in ``[lo, hi]`` ("1e6" accepted)."""

    def parse(text: str) -> int:
        value = finite_float(text)
        if not value.is_integer() or not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"{text!r} must be an integer in [{lo}, {hi:g}]")
        return int(value)

    return parse


def add_workspace(sub) -> None:
    """``parakin workspace MECH`` / ``--mechanism FILE``: the workspace atlas of a mechanism."""
    p = sub.add_parser(
        "workspace",
        help="workspace volumes, boundary and singularity loci of a mechanism (docs/workspace.md)",
        description="The constant-orientation workspace of a mechanism (the pose coordinates "
        "--axes, the others held at their given values), its dexterous part (cond(J) <= "
        "--cond-max) and its reachable one (some orientation in the orientation box): Monte-Carlo "
        "volumes with standard errors, interval-analysis inner and outer bounds, singular points "
        "(det A, det B sign changes and the IK domain's edges) located by bisection to 1e-9 and "
        "verified, and the boundary along rays. Joint limits: the mechanism's, else --joint-limit "
        "or --stroke, else assumed (home +- 25 %% of the mean home joint, lengths only), always "
        "reported. SI units throughout; a value may carry a unit (10deg, 5mm).",
        func=cmd_workspace,
    )
    _mechanism_options(p)
    p.add_argument("--axes", type=_names, default=None, metavar="NAME[,NAME...]",
                   help="the pose coordinates that span the workspace (default: the lengths, "
                   "else the coordinates that are not angles)")  # fmt: skip
    p.add_argument("--at", action="append", default=[], metavar="NAME=VALUE",
                   help="a held coordinate's given value (default: the home pose's)")  # fmt: skip
    p.add_argument("--box", action="append", default=[], metavar="NAME=LO:HI",
                   help="the box of an axis (default: the mechanism's pose bounds, then grown or "
                   "shrunk to hold the workspace unless --no-fit)")  # fmt: skip
    p.add_argument("--no-fit", action="store_true", help="keep the box as given")
    p.add_argument("--joint-limit", action="append", default=[], metavar="NAME=LO:HI",
                   help="a joint's limits, replacing the mechanism's (the other joints: none)")  # fmt: skip
    p.add_argument("--stroke", type=nonnegative_float, default=None, metavar="F",
                   help="where the mechanism declares no joint limits: home +- F x the mean |home "
                   "joint| for its length joints (default 0.25; 0: none)")  # fmt: skip
    p.add_argument("--orientation-box", action="append", default=[], metavar="NAME=LO:HI",
                   help="the box of a held coordinate for the reachable workspace")  # fmt: skip
    p.add_argument("--orientation-fraction", type=finite_float, default=0.25, metavar="F",
                   help="default orientation box: given +- F x half the pose bounds' width "
                   "(default 0.25)")  # fmt: skip
    p.add_argument("--orientations", type=_int_in(0, 10_000), default=8, metavar="K",
                   help="orientations tried per point for the reachable workspace (default 8)")  # fmt: skip
    p.add_argument("--cond-max", type=finite_float, default=100.0, metavar="C",
                   help="the dexterous workspace's bound on cond(J) (default 100)")  # fmt: skip
    p.add_argument("--clearance", type=nonnegative_float, default=None, metavar="D",
                   help="least distance between two legs (m; default: not checked)")  # fmt: skip
    p.add_argument("--samples", type=_int_in(1, MAX_SAMPLES), default=200_000, metavar="N",
                   help="Monte-Carlo points (default 200000)")  # fmt: skip
    p.add_argument("--seed", type=_int_in(0, 2**63 - 1), default=0, help="random seed (default 0)")
    p.add_argument("--levels", type=_int_in(0, 16), default=6, metavar="L",
                   help="interval bisection levels of the certified bounds (0: none; default 6)")  # fmt: skip
    p.add_argument("--grid", type=_int_in(5, 1001), default=61, metavar="N",
                   help="points per axis of the slices the singular loci are sought on")  # fmt: skip
    p.add_argument("--rays", type=_int_in(8, 100_000), default=400, metavar="R",
                   help="rays of the boundary (default 400)")  # fmt: skip
    _text_option(p, "--output", metavar="FILE",
                 help="write the atlas table (CSV: slices, singular points, rays, volumes)")  # fmt: skip
    _text_option(p, "--figure", metavar="FILE", help="draw the atlas figure (PNG)")
    p.add_argument("--json", action="store_true", help="print a JSON object")


def _names(text: str) -> list[str]:
    names = [t.strip() for t in text.split(",") if t.strip()]
    if not names:
        raise argparse.ArgumentTypeError(f"{text!r} names no coordinate")
    return names


def _pairs(items: list[str], option: str, known, what: str) -> dict[str, str]:
    out = {}
    for item in items:
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep or not value.strip():
            raise ValueError(f"{option} {item!r} must look like NAME=VALUE")
        if key not in known:
            raise ValueError(
                f"{option} {item!r}: {key!r} is not a {what}; known: {', '.join(known)}"
            )
        out[key] = value
    return out


def _value(text: str, where: str, unit: str) -> float:
    """A number or quantity (``10deg``), finite and within the CLI's bounds: an angle (unit
    ``rad``) within :data:`ANGLE_LIMIT`, anything else within :data:`PARAM_LIMIT` (SI)."""
    v = parse_quantity(text)
    limit = ANGLE_LIMIT if unit == "rad" else PARAM_LIMIT
    if not (np.isfinite(v) and abs(v) <= limit):
        raise ValueError(
            f"{where}: {text!r} must be finite and at most {limit:g} {unit} in magnitude"
        )
    return v


def _range(text: str, where: str, unit: str = "") -> tuple[float, float]:
    lo, sep, hi = text.partition(":")
    if not sep:
        raise ValueError(f"{where}: {text!r} must look like LO:HI")
    a, b = parse_quantity(lo), parse_quantity(hi)
    if not (np.isfinite(a) and np.isfinite(b) and a < b):
        raise ValueError(f"{where}: {text!r} must have finite LO < HI")
    _value(lo, where, unit), _value(hi, where, unit)
    return a, b


def _ranges(mech, values, option: str, lo, hi, axes, not_there: str) -> tuple:
    """Copies of ``lo, hi`` with the ``option KEY=LO:HI`` ranges set, each ``KEY`` one of the
    coordinates ``axes`` (indices of the pose); another coordinate is an error (``not_there``)."""
    names = mech.pose_names
    lo, hi = lo.copy(), hi.copy()
    for key, text in _pairs(values, option, names, "pose coordinate").items():
        k = names.index(key)
        if k not in axes:
            raise ValueError(f"{option} {key}: {not_there}")
        lo[axes.index(k)], hi[axes.index(k)] = _range(text, f"{option} {key}", mech.pose_units[k])
    return lo, hi


def region_of(args, mech):
    """The :class:`parakin.workspace.Region` the options describe."""
    from parakin.workspace import make_region

    names = mech.pose_names
    axes = args.axes
    if axes is not None:
        for a in axes:
            if a not in names:
                raise ValueError(
                    f"--axes: {a!r} is not a pose coordinate; known: {', '.join(names)}"
                )
    pose = np.asarray(mech.home(), dtype=float).copy()
    for key, value in _pairs(args.at, "--at", names, "pose coordinate").items():
        k = names.index(key)
        pose[k] = _value(value, f"--at {key}", mech.pose_units[k])
    region = make_region(mech, axes=axes, pose=pose, stroke=args.stroke,
                         orientation_fraction=args.orientation_fraction, cond_max=args.cond_max,
                         clearance=args.clearance)  # fmt: skip
    for key in _pairs(args.at, "--at", names, "pose coordinate"):
        if names.index(key) in region.axes:
            raise ValueError(
                f"--at {key}: an axis of the workspace ({', '.join(region.axis_names)}), not a "
                "held coordinate; set its range with --box"
            )
    lo, hi = _ranges(
        mech, args.box, "--box", region.lo, region.hi, region.axes,
        f"not an axis of the workspace ({', '.join(region.axis_names)})",
    )  # fmt: skip
    olo, ohi = _ranges(
        mech, args.orientation_box, "--orientation-box", region.orient_lo, region.orient_hi,
        region.others, "an axis of the workspace, not a held coordinate",
    )  # fmt: skip
    joints = _pairs(args.joint_limit, "--joint-limit", mech.joint_names, "joint")
    changes = {"lo": lo, "hi": hi, "orient_lo": olo, "orient_hi": ohi}
    if joints:
        if args.stroke is not None:
            raise ValueError("give --joint-limit or --stroke, not both")
        jlo = np.full(mech.n_joints, -np.inf)
        jhi = np.full(mech.n_joints, np.inf)
        for key, text in joints.items():
            k = mech.joint_names.index(key)
            jlo[k], jhi[k] = _range(text, f"--joint-limit {key}", mech.joint_units[k])
        changes.update(joint_lo=jlo, joint_hi=jhi, limits_source="given")
    return region.replace(**changes), bool(args.box)


def cmd_workspace(args) -> int:
    from parakin import kernels
    from parakin.workspace import atlas as A
    from parakin.workspace.compiled import MIN_ROWS

    if args.samples < MIN_ROWS:  # too little work to pay for loading (or compiling) the loops
        kernels.use_interpreted()
    mech = mechanism_of(args)
    region, boxed = region_of(args, mech)
    sizes = A.Sizes(samples=args.samples, orientations=args.orientations, levels=args.levels,
                    grid=args.grid, rays=args.rays, fit=not (args.no_fit or boxed))  # fmt: skip
    atlas = A.compute(region, sizes, np.random.default_rng(args.seed))
    summary = A.summary(atlas)
    if args.output or args.figure:
        frame = A.frame(atlas)
        if args.output:
            from parakin.io import write_csv

            write_csv(frame, args.output)
            print(f"parakin workspace: the atlas table written to {args.output}", file=sys.stderr)
        if args.figure:
            A.draw(frame, args.figure)
            print(f"parakin workspace: the atlas figure drawn to {args.figure}", file=sys.stderr)
    if atlas.touching:
        print(f"parakin workspace: note: the workspace reaches the box ({', '.join(atlas.touching)}): "
              "its volume is of its part in the box", file=sys.stderr)  # fmt: skip
    if args.json:
        print(_dumps({"mechanism": mech.name, "parameters": mech.parameters(),
                      "samples": args.samples, "seed": args.seed, **summary}))  # fmt: skip
        return 0
    _print_text(mech, summary)
    return 0


def _print_text(mech, s: dict) -> None:
    r = s["region"]
    unit = s["unit"]
    given = ", ".join(f"{k} = {v:.6g}" for k, v in r["given"].items())
    print(
        f"{mech.name}: workspace over ({', '.join(r['axes'])})" + (f" at {given}" if given else "")
    )
    print(f"  joint limits: {r['joint_limits']['source']}")
    box = ", ".join(f"{k} [{a:.6g}, {b:.6g}]" for k, (a, b) in r["box"].items())
    print(f"  box: {box}")
    names = {"constant": "constant orientation", "dexterous": f"dexterous (cond(J) <= {r['cond_max']:g})",
             "reachable": "reachable (some orientation in the box)"}  # fmt: skip
    for kind, e in s["workspaces"].items():
        if kind == "reachable" and not r["given"]:
            continue  # no held coordinate: the reachable workspace is the constant-orientation one
        if e["samples"]:
            print(f"  {names[kind]}: {e['volume']:.6g} +- {e['se']:.2g} {unit} "
                  f"({e['hits']} of {e['samples']} samples)")  # fmt: skip
    c = s["certified"]
    if c is not None:
        print(f"  certified: {c['inner']:.6g} <= volume <= {c['outer']:.6g} {unit} "
              f"({c['levels']} halvings; IK and joint limits)")  # fmt: skip
    for kind, v in s["singular"].items():
        if v["located"]:
            print(f"  singular ({kind}): {v['located']} located, {v['verified']} verified, "
                  f"{v['in_workspace']} in the workspace")  # fmt: skip
