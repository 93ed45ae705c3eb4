"""Workspace sampling: seeded, batched, reachable poses of any mechanism."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from parakin.mechanisms.base import Array, Mechanism

__all__ = ["sample_reachable"]


def sample_reachable(
    mech: Mechanism,
    n: int,
    rng: np.random.Generator,
    bounds: tuple[ArrayLike, ArrayLike] | None = None,
    max_rounds: int = 50,
) -> Array:
    """``n`` poses drawn uniformly from the box ``bounds`` (default ``mech.pose_bounds()``),
    keeping only those where the IK exists (rejection sampling; never NaN).

    Raises ValueError when fewer than ``n`` reachable poses turn up in ``max_rounds`` rounds (the
    box barely intersects the workspace).
    """
    if n < 0:
        raise ValueError(f"n = {n} must be >= 0")
    lo, hi = (np.asarray(b, dtype=float) for b in (bounds or mech.pose_bounds()))
    kept: list[Array] = []
    count = 0
    for _ in range(max_rounds):
        if count >= n:
            break
        x = rng.uniform(lo, hi, size=(max(2 * (n - count), 16), len(lo)))
        x = x[mech.is_reachable(x)]
        kept.append(x)
        count += len(x)
    if count < n:
        raise ValueError(
            f"only {count} of {n} poses drawn from the box {lo.tolist()}..{hi.tolist()} are reachable"
        )
    return np.concatenate(kept)[:n]
