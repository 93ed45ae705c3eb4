"""``parakin dynamics``: actuator forces along a trajectory."""

from __future__ import annotations

import sys

import numpy as np

from parakin.cli.common import (
    _compiled_if_worth_it,
    _dumps,
    _fmt_vector,
    _mechanism_options,
    _text_option,
    finite_float,
    mechanism_of,
    nonempty,
)
from parakin.io import write_rows


def add_dynamics(sub) -> None:
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

    mech = mechanism_of(args)
    if mech.mass_model() is None:
        raise ValueError(f"{mech.name} declares no masses (mass_model()): no dynamics")
    traj = read_trajectory(args.trajectory, mech)
    _compiled_if_worth_it(len(traj.t))
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
