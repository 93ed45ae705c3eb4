"""Shared pieces of the mechanisms' torch residual ports (``<mechanism>_torch.py``).

Each port module (:mod:`parakin.mechanisms.p3p4s_torch`, ...) holds one mechanism's hand-written
torch translation of its ``residual``; the mechanism class returns it from
:meth:`parakin.mechanisms.base.Mechanism.torch_residual` and the torch solver
(:mod:`parakin.solvers.torch_newton`) only calls that hook. These modules import torch at the top,
so they are imported lazily (inside the hook): the package itself imports without torch.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import torch
from torch import Tensor

#: a torch residual ``f(pose (..., n), joints (..., m)) -> (..., m)``
ResidualFn = Callable[[Tensor, Tensor], Tensor]


class TorchConstants:
    """Numpy constants of a mechanism, converted once per (device, dtype) on first use."""

    def __init__(self, **arrays: Any) -> None:
        self._np = {k: np.asarray(v) for k, v in arrays.items()}
        self._cache: dict[tuple[Any, Any], dict[str, Tensor]] = {}

    def on(self, like: Tensor) -> dict[str, Tensor]:
        key = (like.device, like.dtype)
        out = self._cache.get(key)
        if out is None:
            out = {
                k: torch.as_tensor(
                    v, device=like.device, dtype=torch.long if v.dtype.kind in "iu" else like.dtype
                )
                for k, v in self._np.items()
            }
            self._cache[key] = out
        return out
