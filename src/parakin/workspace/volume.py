"""Workspace volumes by Monte-Carlo, with an error bar, and the box that holds the workspace.

The constant-orientation, dexterous and reachable workspaces of a :class:`Region` are measured by
the fraction of ``n`` points drawn uniformly in its box that belong to each, times the box's
volume; the error bar is the binomial standard error ``V_box sqrt(p (1 - p) / n)``. The reachable
workspace (some orientation in the region's orientation box) is tested at the given orientation
and at ``orientations`` more drawn uniformly from the orientation box per point: an estimate from
below, which grows towards the true one with ``orientations``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from parakin.progress import Progress
from parakin.workspace.classify import classify
from parakin.workspace.region import Region

__all__ = ["KINDS", "Estimate", "fit_box", "grid_points", "orientation_set", "reachable", "volumes"]

#: the workspaces measured, in the order reported
KINDS = ("constant", "dexterous", "reachable")
#: points per chunk of a Monte-Carlo run (bounds its memory)
CHUNK = 1 << 18
#: runs of at least this many points print a progress line per ~10 % (parakin.progress)
PROGRESS_MIN = 1 << 22


@dataclasses.dataclass(frozen=True)
class Estimate:
    """A Monte-Carlo volume: ``hits`` of ``n`` points in a box of volume ``box``."""

    hits: int
    n: int
    box: float

    @property
    def fraction(self) -> float:
        return self.hits / self.n if self.n else float("nan")

    @property
    def volume(self) -> float:
        return self.fraction * self.box

    @property
    def se(self) -> float:
        """The standard error of :attr:`volume` (binomial)."""
        p = self.fraction
        return self.box * float(np.sqrt(p * (1 - p) / self.n)) if self.n else float("nan")


def volumes(
    region: Region,
    n: int,
    rng: np.random.Generator,
    *,
    orientations: int = 0,
    cond: bool = True,
    compiled: bool | None = None,
    progress: bool | None = None,
) -> dict[str, Estimate]:
    """Monte-Carlo volumes of the constant-orientation, dexterous and reachable workspaces
    (:data:`KINDS`) from ``n`` uniform points of the region's box; ``orientations``: extra
    orientations tried per point for the reachable one (0: it is the constant-orientation one);
    ``cond``: False skips the dexterous test (its estimate is then NaN). The positions come from
    ``rng``, the extra orientations from a stream spawned from it, so the constant-orientation
    estimate does not depend on ``orientations``. ``progress``: a line per ~10 % on stderr (None:
    for runs of at least :data:`PROGRESS_MIN` points)."""
    if not (isinstance(n, (int, np.integer)) and n >= 1):
        raise ValueError(f"n = {n!r} points must be an integer >= 1")
    if not (isinstance(orientations, (int, np.integer)) and orientations >= 0):
        raise ValueError(f"orientations = {orientations!r} must be an integer >= 0")
    orient = orientation_set(region, orientations, rng.spawn(1)[0])
    hits = dict.fromkeys(KINDS, 0)
    show = n >= PROGRESS_MIN if progress is None else progress
    bar = Progress(f"workspace of {region.mech.name}", n, "poses") if show else None
    for start in range(0, n, CHUNK):
        c = min(CHUNK, n - start)
        pts = rng.uniform(region.lo, region.hi, size=(c, region.dim))
        cls = classify(region, pts, cond=cond, compiled=compiled)
        hits["constant"] += int(np.count_nonzero(cls.member))
        hits["dexterous"] += int(np.count_nonzero(cls.dexterous))
        reach = reachable(region, pts, orient, cls.member, compiled=compiled)
        hits["reachable"] += int(np.count_nonzero(reach))
        if bar is not None:
            bar.tick(c)
    out = {k: Estimate(v, n, region.box_volume) for k, v in hits.items()}
    if not cond:
        out["dexterous"] = Estimate(0, 0, region.box_volume)
    return out


def orientation_set(region: Region, k: int, rng: np.random.Generator) -> np.ndarray:
    """``k`` orientations ``(k, n_others)`` spread over the region's orientation box: a scrambled
    Halton sequence seeded from ``rng`` (empty where the region holds no other coordinate)."""
    n = len(region.others)
    if not n or k <= 0:
        return np.zeros((0, n))
    from scipy.stats import qmc

    u = qmc.Halton(d=n, scramble=True, seed=rng).random(k)
    return region.orient_lo + u * (region.orient_hi - region.orient_lo)


def reachable(
    region: Region,
    pts: np.ndarray,
    orientations: np.ndarray,
    member: np.ndarray | None = None,
    *,
    compiled: bool | None = None,
    interference: bool = True,
) -> np.ndarray:
    """Whether each point is in the constant-orientation workspace at its given orientation
    (``member``, computed if not given) or at one of ``orientations`` (:func:`orientation_set`);
    ``interference``: test the legs' clearance (False: IK and joint limits only, a superset)."""
    kw = {"cond": False, "compiled": compiled, "interference": interference}
    inside = (classify(region, pts, **kw).member if member is None else member).copy()
    for o in orientations:
        todo = ~inside
        if not np.any(todo):
            break
        inside[todo] = classify(region, pts[todo], orientation=o[None], **kw).member
    return inside


def grid_points(lo: np.ndarray, hi: np.ndarray, n: int) -> np.ndarray:
    """``n`` points per axis from ``lo`` to ``hi``, ends included: ``(n^d, d)``."""
    axes = [np.linspace(a, b, n) for a, b in zip(lo, hi)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(lo))


def fit_box(
    region: Region,
    *,
    grid: int = 17,
    rounds: int = 8,
    orientations: int = 0,
    rng: np.random.Generator | None = None,
) -> tuple[Region, list[str]]:
    """The region with a box that holds its workspace, found on a ``grid``-point-per-axis grid
    (and a finer grid on each face): where a member lies on a face of the box that side grows by
    half the box's width (at most ``rounds`` times); where none does, the box shrinks to the
    members' bounding box plus a quarter of its extent (at least a grid cell) on each side, and is
    checked again. An angle axis (unit ``rad``) spans at most one turn about its given value.
    Returns the region and the faces the workspace still touches (``"x min"``, ...; empty when it
    fits: a volume of a truncated workspace is of its part in the box). ``orientations``: fit the
    reachable workspace (that many orientations tried per point)."""
    if not (isinstance(grid, (int, np.integer)) and grid >= 3):
        raise ValueError(f"grid = {grid!r} must be an integer >= 3")
    rng = np.random.default_rng(0) if rng is None else rng
    orient = orientation_set(region, orientations, rng)
    lo, hi = region.lo.copy(), region.hi.copy()
    # an angle spans at most one turn about its given value: a workspace that reaches both ends
    # of that turn holds every angle, and its measure along that axis is exact
    turn = np.array([u == "rad" for u in region.axis_units])
    given = region.pose[list(region.axes)]
    cap_lo = np.where(turn, given - np.pi, -np.inf)
    cap_hi = np.where(turn, given + np.pi, np.inf)
    lo, hi = np.maximum(lo, cap_lo), np.minimum(hi, cap_hi)
    names = region.axis_names
    touching: list[str] = []
    shrunk = False
    for step in range(rounds + 1):
        pts = grid_points(lo, hi, grid)
        if np.all((given >= lo) & (given <= hi)):  # a coarse grid may miss a thin workspace
            pts = np.vstack([pts, given])
        # the box holds the workspace without the legs' clearance, a superset: the clearance
        # costs most where legs come from drawings, and takes nothing from the box
        inside = reachable(region, pts, orient, interference=False)
        if not np.any(inside):
            raise ValueError(
                f"no point of the box {lo.tolist()}..{hi.tolist()} ({grid} per axis) is in the "
                f"workspace of {region.mech.name}: give a box around a reachable pose"
            )
        width = hi - lo
        touching = []
        grow_lo = np.zeros(region.dim, dtype=bool)
        grow_hi = np.zeros(region.dim, dtype=bool)
        # the faces on a finer grid of their own: a thin part of the workspace (a sliver along an
        # edge of the IK's domain) can reach a face between the points of the volume grid
        n_face = int(min(4 * grid, max(3, 40_000 ** (1 / max(region.dim - 1, 1)))))
        face = grid_points(lo, hi, n_face) if region.dim == 1 else None
        for k in range(region.dim):
            for side, bound in ((0, lo[k]), (1, hi[k])):
                if face is None:
                    others = [j for j in range(region.dim) if j != k]
                    sub = grid_points(lo[others], hi[others], n_face)
                    fpts = np.empty((len(sub), region.dim))
                    fpts[:, others] = sub
                else:
                    fpts = face.copy()
                fpts[:, k] = bound
                on_face = np.any(reachable(region, fpts, orient, interference=False)) or np.any(
                    inside & (pts[:, k] == bound)
                )
                if side == 0:
                    grow_lo[k] = on_face and lo[k] > cap_lo[k]
                else:
                    grow_hi[k] = on_face and hi[k] < cap_hi[k]
            touching += [f"{names[k]} min"] * bool(grow_lo[k]) + [f"{names[k]} max"] * bool(
                grow_hi[k]
            )
        if not touching:
            if shrunk:
                break
            # a quarter of the members' extent on each side (at least a cell): thin tips of the
            # workspace between the grid's points reach beyond the members' bounding box
            span = pts[inside].max(axis=0) - pts[inside].min(axis=0)
            pad = np.maximum(width / (grid - 1), 0.25 * span)
            new_lo = np.maximum(lo, pts[inside].min(axis=0) - pad)
            new_hi = np.minimum(hi, pts[inside].max(axis=0) + pad)
            shrunk = True
            if np.allclose(new_lo, lo) and np.allclose(new_hi, hi):
                break
            lo, hi = new_lo, new_hi
            continue
        if step == rounds:
            break
        lo = np.maximum(np.where(grow_lo, lo - 0.5 * width, lo), cap_lo)
        hi = np.minimum(np.where(grow_hi, hi + 0.5 * width, hi), cap_hi)
        shrunk = False
    return region.replace(lo=lo, hi=hi), touching
