"""Torch port of :meth:`parakin.mechanisms.stewart12.ActiveLegs.residual` (for
:mod:`parakin.solvers.torch_newton`), in the default ``"euler_parameters"`` convention.

Imported lazily by :meth:`ActiveLegs.torch_residual`; needs torch. :class:`Stewart12` itself
(12 joints, 6 pose coordinates) and :class:`DriveMode` have no port. Checked against the numpy
residual and Jacobian by ``tests/test_torch_newton.py``.
"""

from __future__ import annotations

import torch
from numpy.typing import ArrayLike
from torch import Tensor

from parakin.mechanisms.base_torch import ResidualFn, TorchConstants


def euler_parameters(lam: Tensor) -> Tensor:
    """:func:`parakin.mechanisms.stewart12.rotation_matrix` for ``"euler_parameters"``:
    ``R = (2 l0^2 - 1) I + 2 (lam lam^T + l0 [lam]x)``, ``l0 = sqrt(1 - |lam|^2)``."""
    l0sq = 1.0 - (lam * lam).sum(-1)
    l0 = torch.sqrt(l0sq)
    x, y, z = lam[..., 0], lam[..., 1], lam[..., 2]
    d = 2 * l0sq - 1
    rows = [
        [d + 2 * x * x, 2 * (x * y - l0 * z), 2 * (x * z + l0 * y)],
        [2 * (y * x + l0 * z), d + 2 * y * y, 2 * (y * z - l0 * x)],
        [2 * (z * x - l0 * y), 2 * (z * y + l0 * x), d + 2 * z * z],
    ]
    return torch.stack([torch.stack(r, dim=-1) for r in rows], dim=-2)


def active_legs_residual(platform: ArrayLike, base: ArrayLike, convention: str) -> ResidualFn:
    """``l_k(pose) - l_k`` over the active legs, NaN where ``|lambda| >= 1`` (see
    :meth:`ActiveLegs.residual`); ``l_k = |M + R p_j(k) - b_k|`` (:meth:`Stewart12.ik`).

    ``platform`` (N, 3) the platform point ``p_j(k)`` of each active leg (local frame), ``base``
    (N, 3) its base point ``b_k``, ``convention`` the Stewart12's (only ``"euler_parameters"``
    is ported: NotImplementedError for the others)."""
    if convention != "euler_parameters":
        raise NotImplementedError(
            f"torch residual of ActiveLegs is ported for the 'euler_parameters' convention only, "
            f"not {convention!r}"
        )
    const = TorchConstants(p=platform, b=base)

    def residual(pose: Tensor, joints: Tensor) -> Tensor:
        c = const.on(pose)
        bad = (pose[..., 3:] * pose[..., 3:]).sum(-1) >= 1.0
        x = torch.where(bad[..., None], torch.zeros_like(pose), pose)
        rot = euler_parameters(x[..., 3:])
        v = x[..., None, :3] + torch.einsum("...ij,kj->...ki", rot, c["p"]) - c["b"]
        r = torch.sqrt((v * v).sum(-1)) - joints
        return torch.where(bad[..., None], torch.full_like(r, float("nan")), r)

    return residual
