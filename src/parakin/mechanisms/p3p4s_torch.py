"""Torch port of :meth:`parakin.mechanisms.p3p4s.P3P4S.residual` (for :mod:`parakin.solvers.torch_newton`).

Imported lazily by :meth:`P3P4S.torch_residual`; needs torch. Checked against the numpy residual
and Jacobian by ``tests/test_torch_newton.py``.
"""

from __future__ import annotations

from numpy.typing import ArrayLike
from torch import Tensor

from parakin.mechanisms.base_torch import ResidualFn, TorchConstants


def torch_residual(e: ArrayLike, m: ArrayLike, delta: float, length: float) -> ResidualFn:
    """``(|w_i - l_i m_i|^2 - L^2) / 2L`` with ``w_i = p - delta e_i`` (see :meth:`P3P4S.residual`;
    the arguments are its ``e``, ``m``, ``delta`` and ``L``)."""
    const = TorchConstants(e=e, m=m)
    delta, length = float(delta), float(length)

    def residual(pose: Tensor, joints: Tensor) -> Tensor:
        c = const.on(pose)
        rod = pose[..., None, :] - delta * c["e"] - joints[..., :, None] * c["m"]
        return ((rod * rod).sum(-1) - length**2) / (2 * length)

    return residual
