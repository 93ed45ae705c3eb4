"""Ye et al. §1-§2 and §3.1: the mechanism (Figs 1, 2, 6 redrawn from our model), the closed-form
linear FK from all 12 lengths (Table 1), the compatibility errors (Table 3) and the FK throughput."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pandas as pd

from parakin.claims import Claim
from parakin.config import rng
from parakin.io import write_csv, write_table
from parakin.papers.drawing import draw_skeleton_table
from parakin.papers.sections import table_claims, table_text
from parakin.papers.ye_stewart12.common import (
    KEY,
    artefact,
    mech,
    passive_sets,
    table,
    table_and_figure,
    test_pose,
)
from parakin.registry import DESCRIPTIVE, EXACT, TIMING

EQS = ("f (21)", "g (22)", "v (23)", "u (24)", "w (25)", "h (26)")


def _states(config: dict) -> dict[str, np.ndarray]:
    m = mech(config)
    return {"initial": m.home(), "arbitrary (§3.3 test pose)": test_pose(config)}


@table("table1", "table1", "table1_random.csv", config=[KEY], tolerance=EXACT)
def table1(config: dict, outdir: Path) -> list[Path]:
    """Table 1 (lost): FK check — pose and joint centres from the 12 IK lengths vs the exact ones,
    at the initial state and at the §3.3 test pose (the paper's arbitrary state is unknown)."""
    m = mech(config)
    rows = []
    for state, pose in _states(config).items():
        lengths = m.ik(pose)
        got = m.fk(lengths)
        bj_true, bj_got = m.joint_centres(pose), m.joint_centres(got)
        names = ["x0 (mm)", "y0 (mm)", "z0 (mm)", "lambda1", "lambda2", "lambda3"]
        scale = np.array([1e3, 1e3, 1e3, 1, 1, 1])
        for i, nm in enumerate(names):
            rows.append(
                {
                    "state": state,
                    "quantity": nm,
                    "exact": pose[i] * scale[i],
                    "computed": got[i] * scale[i],
                    "abs_error": abs(got[i] - pose[i]) * scale[i],
                }
            )
        for j in range(6):
            for c, ax in enumerate("xyz"):
                rows.append(
                    {
                        "state": state,
                        "quantity": f"B{j + 1}.{ax} (mm)",
                        "exact": bj_true[j, c] * 1e3,
                        "computed": bj_got[j, c] * 1e3,
                        "abs_error": abs(bj_got[j, c] - bj_true[j, c]) * 1e3,
                    }
                )
    df = pd.DataFrame(rows)
    g = rng(config, f"{KEY}.table1")
    lo, hi = m.pose_bounds()
    poses = g.uniform(lo, hi, (int(config[KEY]["fk_poses"]), 6))
    err = np.abs(m.fk(m.ik(poses)) - poses)
    notes = (
        f"Closed-form linear FK (docs/ye_stewart12.md#s1.5) from the 12 IK lengths; lambda = {m.convention}. "
        f"Over {len(poses)} random poses of the box |x|,|y|,|z| <= 3 mm, |lambda_i| <= 0.15: max error "
        f"{err[:, :3].max() * 1e3:.3g} mm in position, {err[:, 3:].max():.3g} in lambda."
    )
    paths = write_table(
        df, outdir / "table1", title="Table 1: FK computed vs exact", notes=notes, floatfmt=".9g"
    )
    summ = pd.DataFrame(
        [
            {
                "poses": len(poses),
                "max_position_error_mm": err[:, :3].max() * 1e3,
                "max_lambda_error": err[:, 3:].max(),
            }
        ]
    )
    return paths + [write_csv(summ, outdir / "table1_random.csv")]


@artefact("table3", outputs=["table3.csv", "table3.md"], config=[KEY], tolerance=EXACT)
def table3(config: dict, outdir: Path) -> list[Path]:
    """Table 3 (lost): |F| of (21)-(26) at consistent lengths, initial and test state, composite =
    mean of the six (eq. 27 read as delta = |F(X*)|, X* the exact lengths)."""
    m = mech(config)
    rows = []
    for state, pose in _states(config).items():
        f = np.abs(m.compatibility(m.ik(pose))) * 1e6  # m^2 -> mm^2
        rows.append(
            {"state": state, **{e: v for e, v in zip(EQS, f)}, "composite": float(f.mean())}
        )
    df = pd.DataFrame(rows)
    return write_table(
        df,
        outdir / "table3",
        title="Table 3: compatibility-equation errors |F| (mm^2)",
        notes=(
            "Double precision. F is evaluated exactly (no series truncation): the nonzero "
            "values at the test state are rounding only."
        ),
        floatfmt=".3g",
    )


#: length (m) of the frame arrows in the mechanism drawings
FRAME_LENGTH = 0.012
FIG01_TITLE = "12-leg cube mechanism, §3.3 test pose (R = 0; passive legs thin black)"
FIG06_TITLE = "Virtual prototype, R = 3 (passive legs thin black)"
#: the pose of Fig. 6 (m, lambda): a larger tilt than the test pose, for visibility
FIG06_POSE = np.array([2e-3, -1.5e-3, 1e-3, 0.12, -0.08, 0.15])


def _skeleton_frame(
    config: dict, pose: np.ndarray, passive: tuple[int, ...], **extra
) -> pd.DataFrame:
    """The drawing's points and segments (:func:`skeleton_table`), plus constant columns ``extra``."""
    from parakin.plot import skeleton_table

    sk = mech(config).skeleton(pose, passive=passive)
    return skeleton_table(sk, frame_length=FRAME_LENGTH).assign(**extra)


def _draw_skeleton(frame: pd.DataFrame, path: Path, title: str, labels: bool) -> Path:
    skeleton = frame[["element", "kind", "name", "index", "x", "y", "z"]]
    return draw_skeleton_table(
        skeleton, path, frame_length=FRAME_LENGTH, title=title, labels=labels
    )


def draw_fig01(frame: pd.DataFrame, path: Path) -> Path:
    """Fig. 1 from its CSV (the skeleton table): passive legs thin black, no labels."""
    return _draw_skeleton(frame, path, FIG01_TITLE, labels=False)


def draw_fig02(frame: pd.DataFrame, path: Path) -> Path:
    """Fig. 2 from its CSV (the skeleton table with the geometry ``n_mm``, ``L_mm``), labelled."""
    title = f"Topology at home: n = {frame['n_mm'].iloc[0]:g} mm, L = {frame['L_mm'].iloc[0]:g} mm"
    return _draw_skeleton(frame, path, title, labels=True)


def draw_fig06(frame: pd.DataFrame, path: Path) -> Path:
    """Fig. 6 from its CSV (the skeleton table)."""
    return _draw_skeleton(frame, path, FIG06_TITLE, labels=False)


@table_and_figure("fig01", "fig01_mechanism", draw_fig01, config=[KEY], tolerance=DESCRIPTIVE)
def fig01(config: dict) -> pd.DataFrame:
    """Fig. 1: the mechanism at the §3.3 test pose, mode R=0 (passive legs dashed)."""
    return _skeleton_frame(config, test_pose(config), passive_sets(config)[0])


@table_and_figure("fig02", "fig02_topology", draw_fig02, config=[KEY], tolerance=DESCRIPTIVE)
def fig02(config: dict) -> pd.DataFrame:
    """Fig. 2: topology at home — static cube 2(n+L), moving cube 2n, b_k and B_i labelled."""
    c = config[KEY]
    return _skeleton_frame(
        config, mech(config).home(), (), n_mm=float(c["n_mm"]), L_mm=float(c["L_mm"])
    )


@table_and_figure("fig06", "fig06_prototype", draw_fig06, config=[KEY], tolerance=DESCRIPTIVE)
def fig06(config: dict) -> pd.DataFrame:
    """Fig. 6 (the paper's Mathematica prototype): our model at a larger tilt for visibility."""
    return _skeleton_frame(config, FIG06_POSE, passive_sets(config)[3])


@artefact(
    "fk_speed", outputs=["extra_fk_speed.csv", "extra_fk_speed.md"], config=[KEY], tolerance=TIMING
)
def fk_speed(config: dict, outdir: Path) -> list[Path]:
    """Extra: batched closed-form FK throughput (poses/s), unchecked and with the assembly check."""
    m = mech(config)
    g = rng(config, f"{KEY}.fk_speed")
    lo, hi = m.pose_bounds()
    poses = g.uniform(lo, hi, (int(config[KEY]["fk_bench_poses"]), 6))
    lengths = m.ik(poses)
    rows = []
    m.fk(lengths[:1000], check=True)  # warm-up (allocations, cached matrices)
    for check in (False, True):
        best = np.inf
        for _ in range(3):
            t = time.perf_counter()
            m.fk(lengths, check=check)
            best = min(best, time.perf_counter() - t)
        rows.append(
            {
                "variant": "with assembly check" if check else "closed form only",
                "poses": len(poses),
                "wall_s": best,
                "throughput_poses_per_s": len(poses) / best,
            }
        )
    return write_table(
        pd.DataFrame(rows),
        outdir / "extra_fk_speed",
        title="Closed-form FK throughput (1 core)",
        floatfmt=".4g",
    )


def _table1_claims(t: pd.DataFrame) -> list[Claim]:
    """C1: the closed-form FK against the exact pose over random poses."""
    t = t.iloc[0]
    return [
        Claim(
            KEY,
            "table1",
            "fk.max_position_error",
            "0",
            float(t["max_position_error_mm"]),
            "mm",
            variant=f"{int(t['poses'])} random poses",
            reason="C1: the paper: computed pose 'fully consistent' with the exact one",
        )
    ]


def _table3_claims(t: pd.DataFrame) -> list[Claim]:
    """C3: the composite compatibility error at the initial and at an arbitrary state."""
    return [
        Claim(
            KEY,
            "table3",
            "composite.initial",
            "0",
            float(t["composite"].iloc[0]),
            "mm^2",
            reason="C3: zero error (ours: rounding of the FK products) at the initial state",
        ),
        Claim(
            KEY,
            "table3",
            "composite.arbitrary",
            "1e-6",
            float(t["composite"].iloc[1]),
            "mm^2",
            reason=(
                "C3: 'negligible' at an arbitrary state (bound 1e-6 mm^2 is ours; the "
                "values are lost). Rounding only, not the paper's 'Taylor truncation'"
            ),
        ),
    ]


def claims(figdir: Path, ref: pd.DataFrame) -> list[Claim]:
    return table_claims(figdir, {"table1_random.csv": _table1_claims, "table3.csv": _table3_claims})


def summary(figdir: Path, ref: pd.DataFrame) -> str:
    return table_text(
        figdir,
        {
            "table1_random.csv": lambda t: (
                f"Closed-form FK (Table 1): max error {t['max_position_error_mm'].iloc[0]:.2g} mm / "
                f"{t['max_lambda_error'].iloc[0]:.2g} over {int(t['poses'].iloc[0])} random poses."
            ),
            "extra_fk_speed.csv": lambda t: (
                f"Batched FK throughput {t['throughput_poses_per_s'].iloc[0]:.3g} poses/s."
            ),
            "table3.csv": lambda t: (
                f"Compatibility errors (Table 3): composite {t['composite'].iloc[0]:.2g} mm^2 at the initial "
                f"state, {t['composite'].iloc[1]:.2g} mm^2 at the test pose (rounding)."
            ),
        },
        sep=" ",
    )
