"""A toy paper for tests/test_registry.py: a planar two-leg mechanism (a point held by two
telescopic legs from two base pivots) with one table, registered only by naming this module in
the config's ``studies`` list. Nothing in parakin knows about it."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import ClassVar

import numpy as np
import pandas as pd

from parakin.config import rng
from parakin.io import write_table
from parakin.mechanisms.base import Mechanism
from parakin.registry import ROUNDING, artefact
from parakin.solvers import solve_fk

KEY = "toy_study"


@dataclasses.dataclass(frozen=True)
class TwoLeg(Mechanism, register=False):
    """Point (x, y) above two pivots at (-a, 0) and (a, 0); the joints are the two leg lengths."""

    a: float = 0.5
    name: ClassVar[str] = "toy2leg"
    pose_names: ClassVar[tuple[str, ...]] = ("x", "y")
    joint_names: ClassVar[tuple[str, ...]] = ("l1", "l2")
    pose_units: ClassVar[tuple[str, ...]] = ("m", "m")
    joint_units: ClassVar[tuple[str, ...]] = ("m", "m")
    paper_pose_units: ClassVar[tuple[str, ...]] = ("m", "m")
    paper_joint_units: ClassVar[tuple[str, ...]] = ("m", "m")

    def ik(self, pose):
        p = np.asarray(pose, dtype=float)
        return np.stack(
            [np.hypot(p[..., 0] + self.a, p[..., 1]), np.hypot(p[..., 0] - self.a, p[..., 1])],
            axis=-1,
        )

    def residual(self, pose, joints):
        return self.ik(pose) - np.asarray(joints, dtype=float)

    def home(self):
        return np.array([0.0, 1.0])

    def pose_bounds(self):
        return np.array([-0.3, 0.6]), np.array([0.3, 1.2])


@artefact(KEY, "table1", outputs=["table1.csv", "table1.md"], reference=False, tolerance=ROUNDING)
def table1(config: dict, outdir: Path) -> list[Path]:
    """FK of ten random poses by Newton from home: the poses come back."""
    mech = TwoLeg()
    lo, hi = mech.pose_bounds()
    poses = rng(config, f"{KEY}.poses").uniform(lo, hi, size=(10, 2))
    res = solve_fk(mech, mech.ik(poses), method="newton")
    frame = pd.DataFrame(
        {
            "x": poses[:, 0],
            "y": poses[:, 1],
            "x_fk": res.x[:, 0],
            "y_fk": res.x[:, 1],
            "error_m": np.linalg.norm(res.x - poses, axis=1),
        }
    )
    return write_table(frame, Path(outdir) / "table1", title="Toy FK round trip")
