"""The workspace's boundary along rays from a point inside, located by bisection.

From a centre in the constant-orientation workspace, each ray is marched in ``march`` equal steps
to the box and the first step that leaves the workspace is bisected until every coordinate is
bracketed to 1e-9 (and on to floating-point resolution). Each boundary point is labelled with the
constraint that stops it just outside: ``domain`` (no IK), ``<joint> min`` / ``<joint> max`` (a
joint limit), ``legs`` (the clearance) or ``box`` (none within the box). The rays give the
boundary as a surface (a grid of directions) and, where the workspace is star-shaped about the
centre, a second estimate of its volume, ``|S^{d-1}| / d x mean(r^d)`` over directions uniform on
the sphere (exact quadrature on the circle for d = 2).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from parakin.workspace.classify import classify
from parakin.workspace.region import Region
from parakin.workspace.singular import LOCATE_TOL

__all__ = ["Rays", "boundary_rays", "fibonacci_directions", "ray_volume", "sphere_grid"]


@dataclasses.dataclass(frozen=True)
class Rays:
    """``centre`` (dim,), unit ``directions`` (R, dim), ``radius`` (R,), boundary ``points`` (R, dim)
    and the ``reason`` (R,) each ray stops (module docstring)."""

    centre: np.ndarray
    directions: np.ndarray
    radius: np.ndarray
    points: np.ndarray
    reason: np.ndarray


def fibonacci_directions(n: int, dim: int) -> np.ndarray:
    """``n`` unit vectors spread evenly: equal angles on the circle (dim 2), the Fibonacci lattice
    on the sphere (dim 3)."""
    k = np.arange(n)
    if dim == 2:
        t = 2 * np.pi * k / n
        return np.stack([np.cos(t), np.sin(t)], axis=-1)
    if dim == 3:
        z = 1 - (2 * k + 1) / n
        r = np.sqrt(1 - z * z)
        phi = k * np.pi * (3 - math.sqrt(5))
        return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)
    raise ValueError(f"rays span 2-D and 3-D workspaces, not {dim}-D")


def sphere_grid(n_theta: int, n_phi: int) -> np.ndarray:
    """Directions on a (polar, azimuth) grid ``(n_theta, n_phi, 3)``, poles and the seam included
    (a closed surface for ``plot_surface``)."""
    th = np.linspace(0, np.pi, n_theta)[:, None]
    ph = np.linspace(0, 2 * np.pi, n_phi)[None, :]
    return np.stack(
        np.broadcast_arrays(np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)), axis=-1
    )


def _reasons(region: Region, pts: np.ndarray) -> np.ndarray:
    """Why each point (outside the workspace) is out."""
    cls = classify(region, pts, cond=False)
    out = np.full(len(pts), "legs", dtype=object)
    out[~cls.domain] = "domain"
    lim = cls.domain & ~cls.limits
    if np.any(lim):
        q = cls.joints[lim]
        below = region.joint_lo - q
        above = q - region.joint_hi
        worst = np.maximum(below, above)
        k = np.argmax(worst, axis=-1)
        low = below[np.arange(len(k)), k] >= above[np.arange(len(k)), k]
        names = np.asarray(region.mech.joint_names, dtype=object)
        out[lim] = names[k] + np.where(low, " min", " max")
    out[cls.member] = "box"
    return out.astype(str)


def boundary_rays(
    region: Region,
    directions: np.ndarray,
    centre: np.ndarray | None = None,
    *,
    march: int = 48,
    tol: float = LOCATE_TOL,
) -> Rays:
    """The first boundary crossing along each ray ``centre + t d`` (``directions`` ``(..., dim)``,
    made unit; ``centre`` default: the box's middle, which must be in the workspace)."""
    shape = np.shape(directions)[:-1]
    d = np.asarray(directions, dtype=float).reshape(-1, region.dim)
    d = d / np.linalg.norm(d, axis=-1, keepdims=True)
    c = 0.5 * (region.lo + region.hi) if centre is None else np.asarray(centre, dtype=float)
    if not classify(region, c[None], cond=False).member[0]:
        raise ValueError(
            f"the rays' centre {c.tolist()} is not in the workspace of {region.mech.name}"
        )
    with np.errstate(divide="ignore", invalid="ignore"):
        to_hi = np.where(d > 0, (region.hi - c) / d, np.inf)
        to_lo = np.where(d < 0, (region.lo - c) / d, np.inf)
    t_box = np.min(np.minimum(to_hi, to_lo), axis=-1)
    ts = t_box[:, None] * np.arange(1, march + 1) / march  # (R, march)
    pts = c + ts[..., None] * d[:, None, :]
    member = classify(region, pts.reshape(-1, region.dim), cond=False).member.reshape(ts.shape)
    out = ~member
    first = np.where(np.any(out, axis=-1), np.argmax(out, axis=-1), -1)
    hit = first >= 0
    rows = np.arange(len(d))
    lo_t = np.where(hit & (first > 0), ts[rows, np.maximum(first - 1, 0)], 0.0)
    hi_t = np.where(hit, ts[rows, np.maximum(first, 0)], t_box)
    step = np.max(np.abs(d), axis=-1)
    for _ in range(200):
        active = (
            hit
            & ((hi_t - lo_t) * step > 0)
            & (0.5 * (lo_t + hi_t) != lo_t)
            & (0.5 * (lo_t + hi_t) != hi_t)
        )
        if not np.any(active):
            break
        mid = 0.5 * (lo_t[active] + hi_t[active])
        inside = classify(region, c + mid[:, None] * d[active], cond=False).member
        idx = np.flatnonzero(active)
        lo_t[idx[inside]] = mid[inside]
        hi_t[idx[~inside]] = mid[~inside]
    if np.any(hit & ((hi_t - lo_t) * step > tol)):
        raise ArithmeticError("a ray's boundary could not be bracketed to the tolerance")
    reason = np.full(len(d), "box", dtype="<U24")
    if np.any(hit):
        reason[hit] = _reasons(region, c + hi_t[hit, None] * d[hit])
    radius = np.where(hit, lo_t, t_box)
    points = c + radius[:, None] * d
    return Rays(c, d.reshape(shape + (region.dim,)), radius.reshape(shape),
                points.reshape(shape + (region.dim,)), reason.reshape(shape))  # fmt: skip


def ray_volume(rays: Rays) -> float:
    """``|S^{d-1}| / d x mean(r^d)``: the volume of the star-shaped set the rays bound (directions
    from :func:`fibonacci_directions`)."""
    dim = rays.directions.shape[-1]
    sphere = {2: 2 * np.pi, 3: 4 * np.pi}[dim]
    return float(sphere / dim * np.mean(rays.radius.ravel() ** dim))
