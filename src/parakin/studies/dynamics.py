"""Beyond the papers: inverse and forward dynamics of every mechanism, checked by two physics engines.

A study registered like a paper (:mod:`parakin.registry`; config section ``dynamics``; the method:
``docs/dynamics.md``). Every mechanism of the registry that declares its bodies and masses
(:meth:`Mechanism.mass_model`, :meth:`Mechanism.bodies`; the defaults are documented beside each)
moves along one documented trajectory, :meth:`parakin.dynamics.trajectory.Harmonic.around`: pose
coordinate k about :meth:`Mechanism.home` by ``fraction`` of half its :meth:`pose_bounds` width at
``frequency (k + 1)`` Hz, phase k rad, over one period. Artefacts:

* ``forces_<mechanism>``: the actuator forces along it (``extra_forces_<mechanism>.{csv,png}``:
  each figure is drawn from the table beside it);
* ``checks``: per mechanism, the agreement of the generic inverse dynamics with MuJoCo (the
  ``mj_inverse`` recipe) and pinocchio (constrained dynamics), the power balance, and Zhao's Newton-Euler for the 3-P(4S)
  (``extra_dynamics_checks.{csv,md}``);
* ``simulation_<mechanism>``: a computed-torque simulation (RK4, ``dt``, ``t_end`` s) started off
  the trajectory: the pose error against its analytic decay ``e0 (1 + w t) exp(-w t)`` and the
  joint-space drift of each step (``extra_simulation_<mechanism>.{csv,png}``).
"""

from __future__ import annotations

import dataclasses
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from parakin import dynamics as D
from parakin.dynamics.forward import computed_torque, simulate
from parakin.dynamics.trajectory import Harmonic, power_balance
from parakin.io import write_and_draw, write_table
from parakin.mechanisms import P3P4S, REGISTRY
from parakin.mechanisms.base import Mechanism
from parakin.registry import Tolerance, artefact, drawn_figure

__all__ = [
    "KEY",
    "mechanisms",
    "trajectory",
    "forces_data",
    "draw_forces",
    "checks_data",
    "simulation_data",
    "draw_simulation",
]

KEY = "dynamics"


def mechanisms() -> list[Mechanism]:
    """Every registered mechanism (default parameters) that declares its dynamics."""
    return [m for m in (cls() for cls in REGISTRY.values()) if m.mass_model() is not None]


def trajectory(mech: Mechanism, config: dict) -> Harmonic:
    """The study's trajectory of ``mech`` (config ``dynamics.trajectory``): about its home pose, or
    about the centre ``centres[mech.name]`` where the config names one (a mechanism whose home
    lies near a singularity: a test trajectory should check the dynamics, not a singularity)."""
    c = config[KEY]["trajectory"]
    tr = Harmonic.around(mech, c["fraction"], c["frequency"])
    centre = c.get("centres", {}).get(mech.name)
    return tr if centre is None else dataclasses.replace(tr, centre=tuple(map(float, centre)))


def samples(tr: Harmonic, config: dict) -> np.ndarray:
    """The study's sample times over one period of ``tr`` (the forces, their figure and the checks
    use the same ones)."""
    return np.linspace(0.0, tr.period, config[KEY]["trajectory"]["samples"])


def _unit(mech: Mechanism, k: int) -> str:
    """The force unit of joint k: N for a length in metres, N m for an angle, else N per unit."""
    return {"m": "N", "rad": "N m"}.get(mech.joint_units[k], f"N (x {mech.joint_units[k]} length)")


# ---------------------------------------------------------------------------------------- forces
def forces_data(config: dict, name: str) -> pd.DataFrame:
    """The actuator forces of mechanism ``name`` along its trajectory: one row per sample and joint."""
    mech = REGISTRY[name]()
    tr = trajectory(mech, config)
    t = samples(tr, config)
    res = D.inverse_dynamics(mech, *tr.state(t))
    frames = [
        pd.DataFrame(
            {
                "mechanism": mech.name,
                "t_s": t,
                "joint": joint,
                "force": res.force[:, k],
                "unit": _unit(mech, k),
                "joint_rate": res.joint_rate[:, k],
                "joint_acceleration": res.joint_acceleration[:, k],
                "condition": res.condition,
            }
        )
        for k, joint in enumerate(mech.joint_names)
    ]
    return pd.concat(frames, ignore_index=True)


def draw_forces(frame: pd.DataFrame, path: str | Path, mechanism: str) -> Path:
    """One mechanism's actuator forces against time (one line per joint) over the condition
    number of its actuator Jacobian (forces grow with it near a singularity)."""
    from parakin.plot import new_figure, save_figure

    rows = frame[frame["mechanism"] == mechanism]
    fig, ax = new_figure("double_tall")
    fig.delaxes(ax)
    top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=[3, 1])
    joints = list(dict.fromkeys(rows["joint"]))
    for k, joint in enumerate(joints):
        r = rows[rows["joint"] == joint]
        top.plot(r["t_s"], r["force"], label=joint, linestyle="-" if k < 7 else "--")
    top.set_ylabel(f"actuator force ({rows['unit'].iloc[0]})")
    # beside the axes, not over them: a legend inside would hide the curves it names
    top.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=6, borderaxespad=0.0)
    first = rows[rows["joint"] == joints[0]]
    cond = first["condition"]
    bottom.plot(first["t_s"], cond, color="0.3")
    if cond.max() > 10 * cond.min():  # a log scale only when it spans a decade
        bottom.set_yscale("log")
    bottom.set_ylabel("cond(J), 1-norm")
    bottom.set_xlabel("time t (s)")
    fig.suptitle(f"Beyond the papers: actuator forces of {mechanism} along its test trajectory")
    return save_figure(fig, path)


# ---------------------------------------------------------------------------------------- checks
def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def _engines(mech: Mechanism, x, v, a, force) -> dict[str, float]:
    from parakin.dynamics import mujoco_check, pinocchio_check

    mj = mujoco_check.inverse_dynamics(mujoco_check.build(mech), x, v, a)
    pin = pinocchio_check.check(pinocchio_check.build(mech), x, v, a, force)
    return {
        "mujoco_force_rel": _rel(mj.force, force),
        "mujoco_rate_rel": _rel(mj.joint_rate, D.inverse_dynamics(mech, x, v, a).joint_rate),
        "pinocchio_force_rel": _rel(pin.force, force),
        "pinocchio_acceleration_rel": float(np.max(pin.platform_error)),
    }


def checks_data(config: dict) -> pd.DataFrame:
    """Per mechanism: size, largest force and condition, and every check's relative difference."""
    from parakin.mechanisms import p3p4s_dynamics as zhao

    rows = []
    for mech in mechanisms():
        tr = trajectory(mech, config)
        x, v, a = tr.state(samples(tr, config))
        res = D.inverse_dynamics(mech, x, v, a)
        balance = power_balance(mech, tr, np.linspace(0.0, tr.period, 41), 1e-4 * tr.period)
        row: dict[str, Any] = {
            "mechanism": mech.name,
            "pose_coordinates": mech.n_pose,
            "actuators": mech.n_joints,
            "redundancy": res.redundancy,
            "max_abs_force": float(np.max(np.abs(res.force))),
            "max_condition": float(np.max(res.condition)),
            "power_balance_rel": balance.relative_error,
            **_engines(mech, x, v, a, res.force),
            "zhao_newton_euler_rel": np.nan,
        }
        if isinstance(mech, P3P4S):
            params = zhao.InertialParams.zhao2017()
            row["zhao_newton_euler_rel"] = _rel(
                res.force, zhao.inverse_dynamics(mech, params, x, v, a)
            )
        rows.append(row)
    return pd.DataFrame(rows)


# ---------------------------------------------------------------------------------------- simulation
def simulation_data(config: dict, name: str) -> pd.DataFrame:
    """Computed-torque simulation of mechanism ``name`` from a pose ``offset`` (fraction of half
    the pose box) off its trajectory: rows every ``record_every`` steps."""
    c = config[KEY]["simulation"]
    mech = REGISTRY[name]()
    tr = trajectory(mech, config)
    x0, v0, _ = tr.state(0.0)
    lo, hi = mech.pose_bounds()
    e0 = c["offset"] * 0.5 * (hi - lo)
    sim = simulate(mech, x0 + e0, v0, computed_torque(tr, c["bandwidth"]), c["t_end"], c["dt"])
    w = 2 * np.pi * c["bandwidth"]
    error = sim.pose - tr.state(sim.t)[0]
    analytic = e0 * ((1 + w * sim.t) * np.exp(-w * sim.t))[:, None]
    keep = slice(None, None, int(c["record_every"]))
    return pd.DataFrame(
        {
            "t_s": sim.t[keep],
            "pose_error": np.max(np.abs(error / e0), axis=-1)[keep],
            "analytic_error": ((1 + w * sim.t) * np.exp(-w * sim.t))[keep],
            "error_vs_analytic": np.max(np.abs(error - analytic) / np.abs(e0), axis=-1)[keep],
            "step_drift": _window_max(sim.drift, int(c["record_every"])),
            "step_rate_drift": _window_max(sim.rate_drift, int(c["record_every"])),
            "joint_units": mech.joint_units[0],
        }
    )


def _window_max(a: np.ndarray, every: int) -> np.ndarray:
    """The largest value over the ``every`` steps up to each recorded one (the first: itself)."""
    out = np.empty(len(a[::every]))
    out[0] = a[0]
    for i in range(1, len(out)):
        out[i] = np.max(a[(i - 1) * every + 1 : i * every + 1])
    return out


def draw_simulation(frame: pd.DataFrame, path: str | Path, mechanism: str) -> Path:
    """Two panels: the pose error (simulated and analytic), and the joint-space drift per step
    (values below 1e-17 drawn at 1e-17)."""
    from parakin.plot import new_figure, save_figure

    floor = 1e-17
    t = frame["t_s"]
    fig, ax = new_figure("double_tall")
    fig.delaxes(ax)
    top, bottom = fig.subplots(2, 1, sharex=True)
    top.semilogy(
        t, np.maximum(frame["pose_error"], floor), label="simulated (max over coordinates)"
    )
    top.semilogy(
        t, np.maximum(frame["analytic_error"], floor), "--", label="analytic (1 + wt) exp(-wt)"
    )
    top.semilogy(
        t, np.maximum(frame["error_vs_analytic"], floor), ":", label="|simulated - analytic|"
    )
    top.set_ylim(floor / 2, 3.0)
    top.set_ylabel("pose error / initial error")
    top.legend(loc="upper right")
    unit = frame["joint_units"].iloc[0]
    bottom.semilogy(t, np.maximum(frame["step_drift"], floor), label=f"joints ({unit})")
    bottom.semilogy(t, np.maximum(frame["step_rate_drift"], floor), label=f"joint rates ({unit}/s)")
    bottom.axhline(1e-9, color="0.4", linewidth=0.8, linestyle="--", label="goal: 1e-9 m")
    bottom.set_ylim(floor / 2, 1e-7)
    bottom.set_ylabel("joint-space drift of a step")
    bottom.set_xlabel("time t (s)")
    bottom.legend(loc="upper right")
    fig.suptitle(
        f"Beyond the papers: {mechanism}, computed-torque simulation (RK4, loops projected)"
    )
    return save_figure(fig, path)


# ---------------------------------------------------------------------------------------- artefacts
#: forces of closed-form trajectories through linear algebra of fixed size: rounding only (the
#: absolute floor covers samples where a force crosses zero)
FORCES = Tolerance(
    "exact", 1e-9, 1e-6, "closed-form trajectory, one linear solve per sample: rounding only"
)
#: differences between three exact computations are rounding noise: compared against an absolute
#: floor only
CHECKS = Tolerance(
    "rounding",
    1e-9,
    1e-9,
    "forces and conditions to rounding; the relative differences between exact computations are "
    "rounding noise, compared with an absolute floor of 1e-9 (the tests' bound)",
)
#: a contracting closed loop integrated the same way everywhere: rounding, floors for the drifts
SIMULATION = Tolerance(
    "rounding",
    1e-6,
    1e-12,
    "deterministic fixed-step integration of a contracting closed loop; drifts are rounding noise "
    "compared with an absolute floor of 1e-12",
    columns={
        "step_drift": (0.0, 1e-9),
        "step_rate_drift": (0.0, 1e-9),
        "error_vs_analytic": (0.0, 1e-6),
    },
)


NAMES = [m.name for m in mechanisms()]


def _per_mechanism(kind: str, data, draw, tolerance: Tolerance, config_keys, **options) -> None:
    """Declare ``<kind>_<name>`` for every mechanism: one job each (they run in parallel), its
    table ``extra_<kind>_<name>.csv`` and the figure drawn from it beside it."""
    for name in NAMES:
        stem = f"extra_{kind}_{name}"
        plot = partial(draw, mechanism=name)

        def make(config: dict, outdir: Path, name=name, stem=stem, plot=plot) -> list[Path]:
            outdir = Path(outdir)
            return write_and_draw(
                data(config, name), outdir / f"{stem}.csv", plot, outdir / f"{stem}.png"
            )

        make.__name__ = make.__qualname__ = f"{kind}_{name}"
        make.__doc__ = f"{kind.capitalize()} of {name}: the table and the figure drawn from it."
        drawn_figure(
            KEY,
            f"{kind}_{name}",
            stem,
            plot,
            config=[f"{KEY}.{k}" for k in config_keys],
            tolerance=tolerance,
            reference=False,
            **options,
        )(make)


_per_mechanism(
    "forces",
    forces_data,
    draw_forces,
    FORCES,
    ["trajectory"],
    caption="Actuator forces of a mechanism along its documented trajectory.",
)


@artefact(
    KEY,
    "checks",
    outputs=["extra_dynamics_checks.csv", "extra_dynamics_checks.md"],
    config=[f"{KEY}.trajectory"],
    tolerance=CHECKS,
    reference=False,
)
def checks(config: dict, outdir: Path) -> list[Path]:
    """Generic inverse dynamics against MuJoCo, pinocchio, the power balance and Zhao's Newton-Euler."""
    return write_table(
        checks_data(config),
        Path(outdir) / "extra_dynamics_checks",
        title="Beyond the papers: the generic dynamics of every mechanism, checked",
        notes=CHECK_NOTES,
        floatfmt=".3g",
    )


# a computed-torque simulation: error decay against the analytic one, joint-space drift
_per_mechanism(
    "simulation",
    simulation_data,
    draw_simulation,
    SIMULATION,
    ["trajectory", "simulation"],
    resources={"runtime": 30},
)


CHECK_NOTES = """
Each mechanism moves along its documented trajectory (config `dynamics.trajectory`), every sample
of it checked (the samples of its forces figure); the columns are relative differences, max over
the samples, to the largest value: `mujoco_*` the recipe around
`mj_inverse` (constraints off, loop null space) on the MJCF generated from the mechanism's bodies;
`pinocchio_*` pinocchio's constrained forward dynamics on a model built from the same description
(forces: the minimum-norm forces it needs; acceleration: the platform's acceleration under ours); `power_balance_rel`: actuator power against the
time derivative of the bodies' energy; `zhao_newton_euler_rel`: Zhao 2017's eqs 8-23 (corrected).
Tests (tests/test_dynamics_*.py) hold every one to 1e-9. Method: docs/dynamics.md.
"""
