"""Torch port of :meth:`parakin.mechanisms.ups2.UPS2.residual` (for :mod:`parakin.solvers.torch_newton`).

Imported lazily by :meth:`UPS2.torch_residual`; needs torch. Checked against the numpy residual
and Jacobian by ``tests/test_torch_newton.py``.
"""

from __future__ import annotations

import torch
from numpy.typing import ArrayLike
from torch import Tensor

from parakin.mechanisms.base_torch import ResidualFn, TorchConstants


def torch_residual(
    home: ArrayLike, a: float, c: float, h: float, k: float, ratio: float, branch: float
) -> ResidualFn:
    """Strokes of the closed-form leg lengths minus the inputs (see :meth:`UPS2.lengths_closed_form`;
    the arguments are its ``home_lengths``, ``a``, ``c``, ``h``, ``k``, ``link_ratio``, ``branch``).

    ``l1^2 = (r c)^2 + h^2 - 2 r h Y`` with ``r = link_ratio`` (= 4c^2/9 + 3a^2/4 - (2/sqrt3) a Y),
    ``l2,3^2 = Q -/+ a u sin(beta)``, ``u = rho + k sin(gamma)``, ``rho = branch sqrt(c^2 - Y^2)``.
    """
    const = TorchConstants(home=home)
    a, c, h, k = float(a), float(c), float(h), float(k)
    ratio, branch = float(ratio), float(branch)

    def residual(pose: Tensor, joints: Tensor) -> Tensor:
        beta, gamma, y = pose[..., 0], pose[..., 1], pose[..., 2]
        rho = branch * torch.sqrt(torch.clamp(c * c - y * y, min=0.0))
        u = rho + k * torch.sin(gamma)
        q = (
            u * u
            + (k * k + a * a / 4)
            + (k * torch.cos(gamma) + y - h) ** 2
            - a * k * torch.cos(beta)
        )
        s = a * u * torch.sin(beta)
        l1 = (ratio * c) ** 2 + h * h - 2 * ratio * h * y
        sq = torch.stack([l1, q - s, q + s], dim=-1)
        return torch.sqrt(torch.clamp(sq, min=0.0)) - const.on(pose)["home"] - joints

    return residual
