"""Leg-leg interference: the least distance between the legs of a mechanism at a batch of poses.

A leg is a straight segment in space. Where a mechanism declares its legs, they come from (in
order): its ``leg_segments(pose) -> (..., n_legs, 2, 3)`` hook (batched; a proposed addition to
the protocol); else ``base_points`` ``(n, 3)`` and ``leg_vectors(pose)`` ``(..., n, 3)`` of the
same ``n`` (every six-legged platform and the 12-leg cube have them): leg k from ``base_points[k]``
to ``base_points[k] + leg_vectors[k]``; else the ``actuator`` and ``passive`` segments of its
drawing, ``skeleton(pose)``, one pose at a time (slow: 0.1-0.4 ms a pose). Two legs that touch
at the home pose are jointed to each other (a shared platform point, a slider on its
parallelogram's edge) and are not compared.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from parakin.mechanisms.base import Array, Mechanism

__all__ = ["LEG_KINDS", "leg_pairs", "leg_segments", "min_leg_distance", "segment_distance"]

#: the kinds of a drawing's segments that are legs (rails, the base and the platform are not;
#: an ``equivalent`` rod is a virtual one)
LEG_KINDS = ("actuator", "passive")
#: two legs closer than this at home (relative to the longest leg) are taken as jointed
_TOUCH = 1e-9


def _batched_source(mech: Mechanism):
    """A batched ``pose -> (..., n, 2, 3)`` from the mechanism's hooks, or None."""
    hook = getattr(mech, "leg_segments", None)
    if callable(hook):
        return lambda x: np.asarray(hook(x), dtype=float)
    base = getattr(mech, "base_points", None)
    vectors = getattr(mech, "leg_vectors", None)
    if base is None or not callable(vectors):
        return None
    base = np.asarray(base, dtype=float)
    try:
        v0 = np.asarray(vectors(mech.home()), dtype=float)
    except Exception:  # a leg_vectors of another meaning: no legs from it
        return None
    if base.ndim != 2 or base.shape[-1] != 3 or v0.shape != base.shape:
        return None

    def segments(x: Array) -> Array:
        v = np.asarray(vectors(x), dtype=float)
        start = np.broadcast_to(base, v.shape)
        return np.stack([start, start + v], axis=-2)

    return segments


def leg_segments(mech: Mechanism, poses: Array) -> Array | None:
    """The legs ``(N, n_legs, 2, 3)`` at ``poses`` ``(N, n_pose)`` (every pose reachable), or None
    where the mechanism declares no legs (no hook and no drawing)."""
    x = np.asarray(poses, dtype=float)
    batched = _batched_source(mech)
    if batched is not None:
        return batched(x)
    try:
        rows = [_drawn_legs(mech, p) for p in x.reshape(-1, mech.n_pose)]
    except NotImplementedError:
        return None
    if not rows:
        return np.zeros((0, 0, 2, 3))
    return np.stack(rows).reshape(x.shape[:-1] + rows[0].shape)


def _drawn_legs(mech: Mechanism, pose: Array) -> Array:
    sk = mech.skeleton(pose)
    return np.stack([seg for kind, seg in sk.segments if kind in LEG_KINDS])


def leg_pairs(mech: Mechanism) -> tuple[Array, Array] | None:
    """Indices ``(i, j)`` of the leg pairs compared: every pair but those touching at home."""
    try:
        return _pairs_cached(mech)
    except TypeError:  # an unhashable mechanism: computed again
        return _pairs_cached.__wrapped__(mech)


@cache
def _pairs_cached(mech: Mechanism) -> tuple[Array, Array] | None:
    seg = leg_segments(mech, np.asarray(mech.home(), dtype=float)[None])
    if seg is None or seg.shape[1] < 2:
        return None
    seg = seg[0]
    n = len(seg)
    i, j = np.triu_indices(n, 1)
    d = segment_distance(seg[i, 0], seg[i, 1], seg[j, 0], seg[j, 1])
    scale = float(np.max(np.linalg.norm(seg[:, 1] - seg[:, 0], axis=-1)))
    keep = d > _TOUCH * max(scale, 1e-300)
    return i[keep], j[keep]


def min_leg_distance(mech: Mechanism, poses: Array) -> Array | None:
    """The least distance between two legs not jointed to each other, per pose ``(N,)``; None
    where the mechanism declares no legs (or fewer than two)."""
    pairs = leg_pairs(mech)
    if pairs is None:
        return None
    x = np.asarray(poses, dtype=float).reshape(-1, mech.n_pose)
    if len(x) == 0:
        return np.zeros(0)
    seg = leg_segments(mech, x)
    i, j = pairs
    if len(i) == 0:
        return np.full(len(x), np.inf)
    d = segment_distance(seg[:, i, 0], seg[:, i, 1], seg[:, j, 0], seg[:, j, 1])
    return np.min(d, axis=-1)


def segment_distance(p0: Array, p1: Array, q0: Array, q1: Array) -> Array:
    """Least distance between segments ``[p0, p1]`` and ``[q0, q1]`` (``(..., 3)`` each), batched:
    the closest points of the two lines, clamped to the segments (Ericson, *Real-Time Collision
    Detection*, 2005, §5.1.9), with the degenerate cases (a point, parallel segments) branch-free."""
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a = np.einsum("...k,...k->...", d1, d1)
    e = np.einsum("...k,...k->...", d2, d2)
    f = np.einsum("...k,...k->...", d2, r)
    c = np.einsum("...k,...k->...", d1, r)
    b = np.einsum("...k,...k->...", d1, d2)
    tiny = 1e-300
    denom = a * e - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        # s on the first segment: the lines' closest point, or 0 where they are parallel
        s = np.where(denom > 1e-14 * a * e + tiny, np.clip((b * f - c * e) / denom, 0, 1), 0.0)
        t = np.where(e > tiny, (b * s + f) / e, 0.0)
        # t outside [0, 1]: clamp it and recompute s for the clamped t
        t_c = np.clip(t, 0, 1)
        s = np.where(t != t_c, np.where(a > tiny, np.clip((b * t_c - c) / a, 0, 1), 0.0), s)
    gap = (p0 + s[..., None] * d1) - (q0 + t_c[..., None] * d2)
    return np.sqrt(np.einsum("...k,...k->...", gap, gap))
