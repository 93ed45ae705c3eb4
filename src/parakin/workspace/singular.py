"""Singularity loci over a workspace: where det A or det B changes sign (Gosselin & Angeles 1990).

With the closure equations ``F(pose, q) = 0``, ``A = dF/dpose`` and ``B = dF/dq``: the *direct*
kinematic (type II) singularities are where ``det A = 0`` (the platform gains freedom with the
actuators locked), the *inverse* kinematic (type I) ones where ``det B = 0`` (a leg loses a
freedom; on a closed-form IK branch that is the edge of the IK's domain, where the branch meets
another). Along the lines of a grid over a plane of the workspace each sign change of a
determinant between two neighbouring points, both with an IK, is bracketed and bisected: to
1e-9 in every coordinate (the stated tolerance) and on until the bracket stops shrinking
(floating-point resolution), so that the located point is singular to working precision. The
edges of the IK's domain are located the same way on the IK's existence. Each point is then
*verified*: the matrix's smallest singular value relative to its largest at the bracketing grid
points is at most 1e-8 (for a domain edge, where ``sigma_min(B)`` vanishes like the square root
of the distance, its square is held to that bound). Sign changes through a pole (an entry that
blows up) fail that test and are reported as not verified.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from parakin.workspace.classify import jacobian_dets, joints_of
from parakin.workspace.region import Region

__all__ = ["LOCATE_TOL", "VERIFY_REL", "Loci", "locate", "plane_grid"]

#: every coordinate of a located point is bracketed to within this (its unit)
LOCATE_TOL = 1e-9
#: a located point is singular when sigma_min <= this x sigma_max (relative)
VERIFY_REL = 1e-8
#: bisection steps at most (a bracket of a box's width reaches the resolution of doubles in ~60)
_STEPS = 80


@dataclasses.dataclass(frozen=True)
class Loci:
    """Located singular points: ``points`` ``(K, dim)`` over the region's axes, ``kind`` (K,)
    ``"direct"`` (det A), ``"inverse"`` (det B) or ``"domain edge"`` (where the IK stops existing),
    ``width`` the final bracket's largest coordinate width, ``sigma_rel`` sigma_min / sigma_max
    of the matrix concerned (A for direct, B otherwise), ``verified`` the test of the module's
    docstring, ``member`` whether the point lies in the constant-orientation workspace."""

    points: np.ndarray
    kind: np.ndarray
    width: np.ndarray
    sigma_rel: np.ndarray
    verified: np.ndarray
    member: np.ndarray

    def __len__(self) -> int:
        return len(self.points)

    @staticmethod
    def concat(parts: list[Loci], dim: int) -> Loci:
        if not parts:
            return Loci(np.zeros((0, dim)), np.zeros(0, dtype="<U11"), *(np.zeros(0),) * 2,
                        np.zeros(0, dtype=bool), np.zeros(0, dtype=bool))  # fmt: skip
        return Loci(*(np.concatenate([getattr(p, f.name) for p in parts])
                      for f in dataclasses.fields(Loci)))  # fmt: skip


def plane_grid(region: Region, i: int, j: int, n: int, at: np.ndarray | None = None):
    """An ``n x n`` grid over axes ``i`` and ``j`` of the region (indices into its axes), the other
    axes at ``at`` (default: the box's middle): ``(U, V, points (n, n, dim))``."""
    mid = 0.5 * (region.lo + region.hi) if at is None else np.asarray(at, dtype=float)
    u = np.linspace(region.lo[i], region.hi[i], n)
    v = np.linspace(region.lo[j], region.hi[j], n)
    U, V = np.meshgrid(u, v, indexing="ij")
    pts = np.empty((n, n, region.dim))
    pts[...] = mid
    pts[..., i], pts[..., j] = U, V
    return U, V, pts


def _evaluate(region: Region, pts: np.ndarray) -> dict[str, np.ndarray]:
    """IK existence and both Jacobians' determinants and singular values at ``pts`` (M, dim)."""
    x = region.poses(pts)
    q, ok = joints_of(region.mech, x)
    out = {"ok": ok}
    keys = ("det_A", "det_B", "smin_A", "smin_B", "smax_A", "smax_B")
    for k in keys:
        out[k] = np.full(len(pts), np.nan)
    if np.any(ok):
        vals = jacobian_dets(region.mech, x[ok], q[ok])
        for k in keys:
            out[k][ok] = vals[k]
    return out


def _pairs(shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Flat indices of every pair of neighbours along both lines of an ``shape`` grid."""
    idx = np.arange(shape[0] * shape[1]).reshape(shape)
    a = np.concatenate([idx[:-1, :].ravel(), idx[:, :-1].ravel()])
    b = np.concatenate([idx[1:, :].ravel(), idx[:, 1:].ravel()])
    return a, b


def _bisect(region: Region, p0: np.ndarray, p1: np.ndarray, test) -> tuple[np.ndarray, ...]:
    """Bisect the segments ``p0 -> p1`` ``(K, dim)`` on ``test(values, rows) -> (side, defined)``
    (the values at the midpoints of brackets ``rows``; ``side`` True on p0's side; a bracket whose
    midpoint is not ``defined`` is dropped). Returns both ends of the final brackets and whether
    each stayed well defined."""
    a, b = p0.copy(), p1.copy()
    alive = np.ones(len(a), dtype=bool)
    for _ in range(_STEPS):
        mid = 0.5 * (a + b)
        moving = alive & np.any((mid != a) & (mid != b), axis=-1)
        if not np.any(moving):
            break
        rows = np.flatnonzero(moving)
        side, defined = test(_evaluate(region, mid[rows]), rows)
        alive[rows[~defined]] = False
        keep = rows[defined]
        s = side[defined]
        a[keep[s]] = mid[keep[s]]
        b[keep[~s]] = mid[keep[~s]]
    return a, b, alive


def _located(region, kind, a, b, alive, scale, matrix, squared=False) -> Loci:
    """Loci of the brackets ``[a, b]``: the point is the end inside the IK's domain (``a``)."""
    a, b, scale = a[alive], b[alive], scale[alive]
    ev = _evaluate(region, a)
    smin = ev[f"smin_{matrix}"]
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = smin / scale
        verified = (rel**2 if squared else rel) <= VERIFY_REL
    from parakin.workspace.classify import classify

    member = classify(region, a, cond=False).member if len(a) else np.zeros(0, dtype=bool)
    width = np.max(np.abs(b - a), axis=-1) if len(a) else np.zeros(0)
    return Loci(a, np.full(len(a), kind, dtype="<U11"), width, rel, verified & np.isfinite(rel),
                member)  # fmt: skip


def locate(region: Region, pts: np.ndarray, values: dict[str, np.ndarray] | None = None) -> Loci:
    """The singular points on the lines of a 2-D grid ``pts`` ``(n_u, n_v, dim)`` of workspace
    points (:func:`plane_grid`): sign changes of det A (direct) and det B (inverse) between IK
    neighbours, and the IK domain's edges, each bisected and verified (module docstring).
    ``values``: :func:`_evaluate` of the grid, if already computed."""
    shape = pts.shape[:2]
    flat = pts.reshape(-1, region.dim)
    ev = _evaluate(region, flat) if values is None else values
    ia, ib = _pairs(shape)
    ok = ev["ok"]
    parts = []
    for kind, m in (("direct", "A"), ("inverse", "B")):
        det = ev[f"det_{m}"]
        if np.all(np.isnan(det[ok])):  # not square (a redundant mechanism): no determinant
            continue
        both = ok[ia] & ok[ib] & np.isfinite(det[ia]) & np.isfinite(det[ib])
        change = both & (np.sign(det[ia]) * np.sign(det[ib]) < 0)
        a0, b0 = ia[change], ib[change]
        zero = np.flatnonzero(ok & (det == 0))  # a grid point exactly on the locus
        if len(zero):
            scale = ev[f"smax_{m}"][zero]
            keep = np.ones(len(zero), dtype=bool)
            parts.append(_located(region, kind, flat[zero], flat[zero], keep, scale, m))
        if not len(a0):
            continue
        s0 = np.sign(det[a0])
        scale = np.fmax(ev[f"smax_{m}"][a0], ev[f"smax_{m}"][b0])
        a, b, alive = _bisect_det(region, flat[a0], flat[b0], m, s0)
        parts.append(_located(region, kind, a, b, alive, scale, m))
    # the IK domain's edges: one neighbour with an IK, the other without
    edge = ok[ia] != ok[ib]
    if np.any(edge):
        inside = np.where(ok[ia[edge]], ia[edge], ib[edge])
        outside = np.where(ok[ia[edge]], ib[edge], ia[edge])

        def test(e, rows):
            return e["ok"], np.ones(len(e["ok"]), dtype=bool)

        a, b, alive = _bisect(region, flat[inside], flat[outside], test)
        scale = ev["smax_B"][inside]
        parts.append(_located(region, "domain edge", a, b, alive, scale, "B", squared=True))
    return Loci.concat(parts, region.dim)


def _bisect_det(region: Region, p0, p1, m: str, s0: np.ndarray):
    """:func:`_bisect` on the sign of det ``m`` (``s0`` its sign at ``p0``), keeping both ends in
    the IK's domain (a midpoint without an IK drops the bracket)."""

    def test(e, rows):
        d = e[f"det_{m}"]
        return np.sign(d) == s0[rows], e["ok"] & np.isfinite(d)  # det 0 exactly: on b's side

    return _bisect(region, p0, p1, test)
