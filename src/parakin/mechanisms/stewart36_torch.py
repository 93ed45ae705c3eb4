"""Torch port of :meth:`parakin.mechanisms.stewart36.Stewart36.residual` (for
:mod:`parakin.solvers.torch_newton`).

Imported lazily by :meth:`Stewart36.torch_residual`; needs torch. Checked against the numpy
residual and Jacobian by ``tests/test_torch_newton.py``.
"""

from __future__ import annotations

import torch
from numpy.typing import ArrayLike
from torch import Tensor

from parakin.mechanisms.base_torch import ResidualFn, TorchConstants


def euler_zyx(a: Tensor, b: Tensor, c: Tensor) -> Tensor:
    """``Rz(a) Ry(b) Rx(c)`` (..., 3, 3), entry by entry as :func:`parakin.geometry.euler_zyx`."""
    ca, sa, cb, sb, cc, sc = (
        torch.cos(a),
        torch.sin(a),
        torch.cos(b),
        torch.sin(b),
        torch.cos(c),
        torch.sin(c),
    )
    rows = [
        [ca * cb, ca * sb * sc - sa * cc, ca * sb * cc + sa * sc],
        [sa * cb, sa * sb * sc + ca * cc, sa * sb * cc - ca * sc],
        [-sb, cb * sc, cb * cc],
    ]
    return torch.stack([torch.stack(r, dim=-1) for r in rows], dim=-2)


def torch_residual(top: ArrayLike, base: ArrayLike) -> ResidualFn:
    """``|T A_p(i) + O_A - B_i|^2 - L_i^2`` (see :meth:`Stewart36.residual`; ``top`` (6, 3) the
    top point of each leg, ``top_points[LEG_TOP]``, ``base`` (6, 3) its ``base_points``)."""
    const = TorchConstants(top=top, base=base)

    def residual(pose: Tensor, joints: Tensor) -> Tensor:
        c = const.on(pose)
        rot = euler_zyx(pose[..., 0], pose[..., 1], pose[..., 2])
        v = pose[..., None, 3:] + torch.einsum("...ij,kj->...ki", rot, c["top"]) - c["base"]
        return (v * v).sum(-1) - joints * joints

    return residual
