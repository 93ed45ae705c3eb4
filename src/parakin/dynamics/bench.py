"""The dynamics rows of the benchmark (issue 27): batched inverse dynamics against MuJoCo.

For each mechanism given: the throughput of :func:`parakin.dynamics.inverse_dynamics` on one
batch of trajectory samples (``n_batch``, in chunks of ``chunk``, on ``workers`` threads: the
compiled program and solves release the GIL), and the same computation through MuJoCo, one sample
at a time (:func:`parakin.dynamics.mujoco_check.inverse_dynamics`: the recipe around
``mj_inverse``, which closes the loops in Python), on ``n_mujoco`` samples of the same trajectory,
in the same run; and MuJoCo's engine call alone, ``mj_inverse`` once per sample at the samples'
joint positions (:func:`mj_inverse_alone`: what the recipe cannot go below); the ratios. Every
side is timed best of the same number of runs (``repeats``). Rows as
:func:`parakin.bench.kernel_goals`: ``mechanism, what, value, unit, goal, met``. Timings depend on
the machine and its load; they never decide a test.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from parakin.dynamics.inverse import inverse_dynamics
from parakin.dynamics.trajectory import Harmonic
from parakin.kernels.threads import side_by_side
from parakin.mechanisms.base import Array, Mechanism
from parakin.timing import best_time

__all__ = ["GOALS", "batched_forces", "dynamics_goals", "mj_inverse_alone"]

#: the issue's goals, for the general 6-6 platform (samples/s on 2 cores; x MuJoCo per sample)
GOALS = {"stewart66": {"per_s": 1e5, "vs_mujoco": 100.0}}


def batched_forces(
    mech: Mechanism,
    pose: Array,
    rate: Array,
    acceleration: Array,
    chunk: int = 1024,
    workers: int = 2,
) -> Array:
    """:func:`inverse_dynamics` forces of samples (k, n) in chunks of ``chunk``, as contiguous
    blocks of samples on ``workers`` threads (:func:`parakin.kernels.threads.side_by_side`: the
    compiled loops inside run serially in their block): the same numbers as one call, since every
    sample is independent."""
    parts: dict[int, Array] = {}

    def run(lo: int, hi: int) -> None:
        for i in range(lo, hi, chunk):
            sl = slice(i, min(i + chunk, hi))
            parts[i] = inverse_dynamics(mech, pose[sl], rate[sl], acceleration[sl]).force

    side_by_side(len(pose), run, threads=workers, min_block=chunk)
    return np.concatenate([parts[i] for i in sorted(parts)])


def mj_inverse_alone(mm, pose: Array) -> Any:
    """A function timing MuJoCo's engine call alone: ``mj_inverse`` of the open tree (constraints
    off, as the recipe's step 3) once per sample, at the samples' joint positions (``pose`` (k, n),
    assembled as the recipe assembles them) with zero velocities and accelerations (the recursive
    Newton-Euler pass costs the same whatever the values). Returns ``run()`` -> the generalised
    forces (k, nv)."""
    from parakin.dynamics import mujoco_check
    from parakin.dynamics.assembly import assemble

    mujoco = mujoco_check.import_mujoco()
    model = mm.model
    qpos = mm.qpos(assemble(mm.mech, pose, mm.mass))
    data = mujoco.MjData(model)
    bit = int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)

    def run() -> Array:
        out = np.empty((len(qpos), model.nv))
        model.opt.disableflags |= bit
        try:
            data.qvel[:] = 0.0
            data.qacc[:] = 0.0
            for k in range(len(qpos)):
                data.qpos[:] = qpos[k]
                mujoco.mj_inverse(model, data)
                out[k] = data.qfrc_inverse
        finally:
            model.opt.disableflags &= ~bit
        return out

    return run


def dynamics_goals(
    mechs: Sequence[Mechanism],
    n_batch: int = 100_000,
    n_mujoco: int = 200,
    repeats: int = 3,
    workers: int = 2,
    chunk: int = 1024,
) -> pd.DataFrame:
    """Per mechanism (with a mass model): batched samples/s, MuJoCo samples/s, and the ratio."""
    from parakin.dynamics import mujoco_check

    rows: list[dict[str, Any]] = []

    def add(mech: str, what: str, value: float, unit: str, goal: float = np.nan) -> None:
        rows.append(
            {
                "mechanism": mech,
                "what": what,
                "value": value,
                "unit": unit,
                "goal": goal,
                "met": bool(value >= goal),
            }
        )

    for mech in mechs:
        if mech.mass_model() is None:
            continue
        tr = Harmonic.around(mech, 0.05, 0.5)
        x, v, a = tr.state(np.linspace(0.0, tr.period, n_batch))
        batched_forces(mech, x[:chunk], v[:chunk], a[:chunk], chunk, workers)  # warm-up
        t_batch = best_time(lambda: batched_forces(mech, x, v, a, chunk, workers), repeats)  # noqa: B023
        mm = mujoco_check.build(mech)
        idx = np.linspace(0, n_batch - 1, n_mujoco).astype(int)
        mujoco_check.inverse_dynamics(mm, x[idx[:2]], v[idx[:2]], a[idx[:2]])  # warm-up
        # every side best of the same number of runs
        t_mj = best_time(lambda: mujoco_check.inverse_dynamics(mm, x[idx], v[idx], a[idx]), repeats)  # noqa: B023
        engine = mj_inverse_alone(mm, x[idx])
        engine()  # warm-up
        t_engine = best_time(engine, repeats)
        goal = GOALS.get(mech.name, {})
        per_s, mj_per_s, engine_per_s = n_batch / t_batch, n_mujoco / t_mj, n_mujoco / t_engine
        add(
            mech.name,
            f"inverse dynamics batched ({workers} threads)",
            per_s,
            "samples/s",
            goal.get("per_s", np.nan),
        )
        add(
            mech.name,
            "inverse dynamics through MuJoCo (mj_inverse recipe), per sample",
            mj_per_s,
            "samples/s",
        )
        add(
            mech.name,
            "mj_inverse alone (open tree, one call per sample; not the loops' forces)",
            engine_per_s,
            "samples/s",
        )
        add(
            mech.name,
            "inverse dynamics batched vs MuJoCo",
            per_s / mj_per_s,
            "x",
            goal.get("vs_mujoco", np.nan),
        )
        add(mech.name, "inverse dynamics batched vs mj_inverse alone", per_s / engine_per_s, "x")
    return pd.DataFrame(rows)
