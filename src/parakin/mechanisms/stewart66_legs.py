"""What every Gough-Stewart platform of six S-P-S legs shares: the general 6-6
(:class:`parakin.mechanisms.stewart66.Stewart66`) and the 3-6 of Li 2017
(:class:`parakin.mechanisms.stewart36.Stewart36`, a 6-6 whose platform points meet in pairs).

Pose ``(alpha, beta, gamma, X, Y, Z)``: the platform point ``p`` sits at ``T p + O`` in the fixed
frame, ``T = Rz(alpha) Ry(beta) Rx(gamma)`` (Z-Y-X Euler), ``O = (X, Y, Z)``; joints: the six leg
lengths ``L_i``; residual ``f_i = |T P_i + O - B_i|^2 - L_i^2``.
"""

from __future__ import annotations

from abc import abstractmethod
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

import parakin.dynamics.jet as dj
from parakin.dynamics.jet import Jet
from parakin.dynamics.model import Bodies, hexapod
from parakin.geometry import euler_zyx
from parakin.mechanisms.base import Array, Mechanism, Skeleton, as_batch, raise_first

__all__ = ["SixLegs"]


class SixLegs(Mechanism, register=False):
    """The shared part of a six-legged platform. A subclass declares ``base_points`` B (6, 3),
    ``platform_points`` (k, 3) in the moving frame (k = 6, or 3 for the 3-6) and
    ``platform_world(pose)``, them in the fixed frame; :attr:`leg_top` (the platform point of each
    leg) and :attr:`top_label` (how drawings name the platform points) if not the 6-6's."""

    pose_names: ClassVar[tuple[str, ...]] = ("alpha", "beta", "gamma", "X", "Y", "Z")
    joint_names: ClassVar[tuple[str, ...]] = ("L1", "L2", "L3", "L4", "L5", "L6")
    #: index into ``platform_points`` of each leg's platform point
    leg_top: ClassVar[Array] = np.arange(6)
    #: label of the platform points in drawings (``"P_1"``, ...)
    top_label: ClassVar[str] = "P"

    base_points: Array
    platform_points: Array

    @abstractmethod
    def platform_world(self, pose: ArrayLike) -> Array:
        """The platform points in the fixed frame (..., k, 3)."""

    def rotation(self, pose: ArrayLike) -> Array:
        """``T = Rz(alpha) Ry(beta) Rx(gamma)`` (..., 3, 3)."""
        x = as_batch(pose, 6, "pose")
        return euler_zyx(x[..., 0], x[..., 1], x[..., 2])

    def assembly_label(self, pose: ArrayLike, joints: ArrayLike) -> str:
        """Above or below the base (``Z > 0``: the papers' assembly, the mirror image below)."""
        return "above the base" if float(as_batch(pose, 6, "pose")[5]) > 0 else "below the base"

    def jacobian_joints(self, pose: ArrayLike, joints: ArrayLike) -> Array:
        """``d f / d L = -2 diag(L)``."""
        q = as_batch(joints, 6, "joints")
        return -2 * q[..., :, None] * np.eye(6)

    def _check_positive(self, q: Array) -> None:
        """UnreachableError where a leg length is not > 0."""
        raise_first(
            q <= 0,
            q.shape[:-1],
            lambda idx: f"leg length L{idx[-1] + 1} = {float(q[idx]):g} must be > 0",
        )

    def skeleton(self, pose: ArrayLike) -> Skeleton:
        """Base and platform outlines, the six legs and both frames, from the model."""
        x = as_batch(pose, 6, "pose")
        if x.ndim != 1:
            raise ValueError(f"skeleton() draws one pose, got a batch of shape {x.shape[:-1]}")
        top = self.platform_world(x)
        pts = {f"B_{k + 1}": self.base_points[k] for k in range(6)}
        pts.update({f"{self.top_label}_{k + 1}": top[k] for k in range(len(top))})
        segs = [
            ("actuator", np.stack([top[self.leg_top[i]], self.base_points[i]])) for i in range(6)
        ]
        return Skeleton(
            points=pts,
            segments=segs,
            polygons=[("base", self.base_points.copy()), ("platform", top.copy())],
            frames={"O": (np.zeros(3), np.eye(3)), "o": (x[3:].copy(), self.rotation(x))},
        )

    def bodies(self, pose: Jet) -> Bodies:
        """The platform (``T``, origin ``O``) and six S-P-S legs, leg i from ``B_i`` to its
        platform point (:func:`parakin.dynamics.model.hexapod`); joints: the leg lengths."""
        rotation = dj.euler_zyx(pose[..., 0], pose[..., 1], pose[..., 2])
        return hexapod(
            pose[..., 3:], rotation, self.base_points, self.platform_points[self.leg_top]
        )
