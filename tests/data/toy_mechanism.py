"""The toy two-leg mechanism of ``toy_study.py`` declared the package's way: its kernel module
(``toy_kernels.py``) and parameter vector, nothing else. Used by tests/test_kernels.py and
tests/test_kernel_cache.py (a mechanism outside parakin; not registered)."""

from __future__ import annotations

import dataclasses
from types import ModuleType
from typing import ClassVar

import numpy as np
import toy_kernels

from parakin.mechanisms.base import Mechanism


@dataclasses.dataclass(frozen=True)
class KernelTwoLeg(Mechanism, register=False):
    """Point (x, y) above two pivots at (-a, 0) and (a, 0); the joints are the two leg lengths."""

    a: float = 0.5
    pose_names: ClassVar[tuple[str, ...]] = ("x", "y")
    joint_names: ClassVar[tuple[str, ...]] = ("l1", "l2")
    pose_units: ClassVar[tuple[str, ...]] = ("m", "m")
    joint_units: ClassVar[tuple[str, ...]] = ("m", "m")
    paper_pose_units: ClassVar[tuple[str, ...]] = ("m", "m")
    paper_joint_units: ClassVar[tuple[str, ...]] = ("m", "m")
    kernels: ClassVar[ModuleType] = toy_kernels

    def kernel_params(self):
        return np.array([self.a])

    def home(self):
        return np.array([0.0, 1.0])

    def pose_bounds(self):
        return np.array([-0.3, 0.6]), np.array([0.3, 1.2])
