"""One mechanism's workspace and singularity atlas: the computation, its table and its figure.

:func:`compute` runs everything :mod:`parakin.workspace` offers on one :class:`Region` (the box
fitted, Monte-Carlo volumes, interval bounds, slices with the singular loci, boundary rays);
:func:`frame` writes the result as one long table (every number the figure shows), :func:`draw`
draws the figure from that table alone, and :func:`summary` gives the JSON of ``parakin
workspace`` and the row of the study's table (:mod:`parakin.studies.workspace_atlas`).
"""

from __future__ import annotations

import dataclasses
import json
import time
from pathlib import Path

import numpy as np
import pandas as pd

from parakin.workspace.boundary import (
    Rays,
    boundary_rays,
    fibonacci_directions,
    ray_volume,
    sphere_grid,
)
from parakin.workspace.classify import classify
from parakin.workspace.interval import Bounds, certify
from parakin.workspace.region import Region
from parakin.workspace.singular import Loci, locate, plane_grid
from parakin.workspace.volume import KINDS, Estimate, fit_box, orientation_set, reachable, volumes

__all__ = ["Atlas", "Sizes", "compute", "draw", "frame", "summary"]


@dataclasses.dataclass(frozen=True)
class Sizes:
    """How much work an atlas does: Monte-Carlo ``samples``, extra ``orientations`` per point for
    the reachable workspace, interval ``levels`` (0: none), ``grid`` points per axis of a slice,
    ``rays`` (directions: a circle of that many, or a sphere grid of about that many), the box
    fit's ``fit_grid`` and whether the box is fitted at all (``fit``)."""

    samples: int = 200_000
    orientations: int = 4
    levels: int = 6
    grid: int = 61
    rays: int = 400
    fit_grid: int = 33
    fit: bool = True


@dataclasses.dataclass(frozen=True)
class Slice:
    plane: tuple[int, int]
    at: np.ndarray
    points: np.ndarray  # (n, n, dim)
    member: np.ndarray  # (n, n)
    dexterous: np.ndarray
    reachable: np.ndarray
    cond: np.ndarray
    loci: Loci


@dataclasses.dataclass(frozen=True)
class Atlas:
    region: Region
    touching: list[str]
    estimates: dict[str, Estimate]
    bounds: Bounds | None
    slices: list[Slice]
    rays: Rays | None
    ray_grid: Rays | None
    seconds: dict[str, float]


def _planes(dim: int) -> list[tuple[int, int]]:
    return [(0, 1)] if dim == 2 else [(0, 1), (0, 2)]


def _centre(region: Region, rng: np.random.Generator) -> np.ndarray | None:
    """A point inside the workspace for the rays: the given pose's axes if inside, else the
    member of a small sample nearest the members' mean."""
    given = region.pose[list(region.axes)]
    if np.all((given >= region.lo) & (given <= region.hi)):
        if classify(region, given[None], cond=False).member[0]:
            return given
    pts = rng.uniform(region.lo, region.hi, size=(4096, region.dim))
    inside = pts[classify(region, pts, cond=False).member]
    if not len(inside):
        return None
    mean = inside.mean(axis=0)
    return inside[np.argmin(np.sum(((inside - mean) / (region.hi - region.lo)) ** 2, axis=-1))]


def compute(region: Region, sizes: Sizes, rng: np.random.Generator) -> Atlas:
    """Everything of the atlas of ``region`` (module docstring), random numbers from ``rng``."""
    clock = {}
    t = time.process_time()
    touching: list[str] = []
    if sizes.fit:
        region, touching = fit_box(
            region, grid=sizes.fit_grid, orientations=min(sizes.orientations, 2), rng=rng
        )
    clock["fit"] = time.process_time() - t
    t = time.process_time()
    est = volumes(region, sizes.samples, rng, orientations=sizes.orientations)
    clock["monte_carlo"] = time.process_time() - t
    t = time.process_time()
    bounds = certify(region, levels=sizes.levels) if sizes.levels > 0 else None
    clock["interval"] = time.process_time() - t
    t = time.process_time()
    slices = []
    orient = orientation_set(region, sizes.orientations, rng.spawn(1)[0])
    centre = _centre(region, rng)
    at = 0.5 * (region.lo + region.hi) if centre is None else centre
    for plane in _planes(region.dim):
        _, _, pts = plane_grid(region, *plane, sizes.grid, at)
        flat = pts.reshape(-1, region.dim)
        cls = classify(region, flat)
        reach = reachable(region, flat, orient, cls.member)
        shape = pts.shape[:2]
        slices.append(
            Slice(
                plane,
                at,
                pts,
                cls.member.reshape(shape),
                cls.dexterous.reshape(shape),
                reach.reshape(shape),
                cls.cond.reshape(shape),
                locate(region, pts),
            )  # fmt: skip
        )
    clock["slices_and_loci"] = time.process_time() - t
    t = time.process_time()
    rays = ray_grid = None
    if centre is not None and region.dim in (2, 3):
        rays = boundary_rays(region, fibonacci_directions(sizes.rays, region.dim), centre)
        if region.dim == 3:
            n_t = max(int(np.sqrt(sizes.rays / 2)), 5)
            ray_grid = boundary_rays(region, sphere_grid(n_t, 2 * n_t - 1), centre)
    clock["rays"] = time.process_time() - t
    for r in (rays, ray_grid):  # a ray that meets the box: the grid fit missed a thin part
        if r is not None and np.any(r.reason == "box") and "rays meet the box" not in touching:
            touching = [*touching, "rays meet the box"]
    return Atlas(region, touching, est, bounds, slices, rays, ray_grid, clock)


# ---------------------------------------------------------------------------------------- table
COLUMNS = ["part", "plane", "i", "j", "a", "b", "c", "value", "se", "label", "flag"]


def frame(atlas: Atlas, number: int | None = None) -> pd.DataFrame:
    """The atlas as one long table: a ``meta`` row (JSON in ``label``), ``volume`` rows (value,
    standard error; the interval bounds as ``inner``/``outer``), ``cell`` rows of each slice
    (value 0 out, 1 constant-orientation, 2 dexterous; ``se`` cond(J); ``flag`` reachable),
    ``singular`` rows (value sigma_rel, label kind, flag verified), ``ray`` rows (the boundary on
    the Fibonacci directions; label the active constraint) and ``surface`` rows (on the sphere
    grid, ``i``/``j`` its indices)."""
    r = atlas.region
    parts: list[pd.DataFrame] = []

    def add(part: str, n: int = 1, **cols) -> None:
        parts.append(
            pd.DataFrame(
                {"part": [part] * n, **{k: np.broadcast_to(v, (n,)) for k, v in cols.items()}}
            )
        )

    meta = {
        "mechanism": r.mech.name,
        "number": number,
        "axes": list(r.axis_names),
        "units": list(r.axis_units),
        "unit": r.unit,
        "given": {r.mech.pose_names[k]: float(r.pose[k]) for k in r.others},
        "given_units": {r.mech.pose_names[k]: r.mech.pose_units[k] for k in r.others},
        "limits": r.limits_source,
        "cond_max": r.cond_max,
        "box": [r.lo.tolist(), r.hi.tolist()],
        "touching": atlas.touching,
        "planes": [list(s.plane) for s in atlas.slices],
        "at": atlas.slices[0].at.tolist() if atlas.slices else None,
    }
    add("meta", label=json.dumps(meta, sort_keys=True))
    for kind in KINDS:
        e = atlas.estimates[kind]
        add("volume", value=e.volume, se=e.se, label=kind, i=e.hits, j=e.n)
    if atlas.bounds is not None:
        add("volume", value=atlas.bounds.inner, label="inner", i=atlas.bounds.levels)
        add("volume", value=atlas.bounds.outer, label="outer", i=atlas.bounds.boxes)
    if atlas.rays is not None:
        add("volume", value=ray_volume(atlas.rays), label="rays", i=len(atlas.rays.radius))
    for k, s in enumerate(atlas.slices):
        u, v = s.plane
        n = s.points.shape[0]
        ii, jj = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
        code = s.member.astype(int) + s.dexterous.astype(int)
        add("cell", n * n, plane=k, i=ii.ravel(), j=jj.ravel(), a=s.points[..., u].ravel(),
            b=s.points[..., v].ravel(), value=code.ravel(), se=s.cond.ravel(),
            flag=s.reachable.ravel())  # fmt: skip
        L = s.loci
        if len(L):
            third = L.points[:, 3 - u - v] if r.dim == 3 else np.nan
            add("singular", len(L), plane=k, a=L.points[:, u], b=L.points[:, v], c=third,
                value=L.sigma_rel, label=L.kind.astype(str), flag=L.verified,
                se=L.member.astype(float))  # fmt: skip
    pad = [np.nan] * (3 - r.dim)
    if atlas.rays is not None:
        p = atlas.rays.points
        cols = [p[:, k] for k in range(r.dim)] + pad
        add("ray", len(p), a=cols[0], b=cols[1], c=cols[2], label=atlas.rays.reason.astype(str))
    if atlas.ray_grid is not None:
        g = atlas.ray_grid
        ii, jj = np.meshgrid(*(np.arange(n) for n in g.radius.shape), indexing="ij")
        p = g.points.reshape(-1, 3)
        add("surface", len(p), i=ii.ravel(), j=jj.ravel(), a=p[:, 0], b=p[:, 1], c=p[:, 2],
            label=g.reason.ravel().astype(str))  # fmt: skip
    return pd.concat(parts, ignore_index=True).reindex(columns=COLUMNS)


def summary(atlas: Atlas) -> dict:
    """The JSON of ``parakin workspace``: ``volume`` (the constant-orientation workspace, in
    ``unit``), its standard error, every workspace's estimate, the interval bounds, the singular
    points and the region (SI units)."""
    r = atlas.region
    est = atlas.estimates
    loci = Loci.concat([s.loci for s in atlas.slices], r.dim)
    sing = {}
    for kind in ("direct", "inverse", "domain edge"):
        pick = loci.kind == kind
        sing[kind] = {
            "located": int(np.count_nonzero(pick)),
            "verified": int(np.count_nonzero(pick & loci.verified)),
            "in_workspace": int(np.count_nonzero(pick & loci.member)),
            "max_sigma_rel_verified": (
                float(np.max(loci.sigma_rel[pick & loci.verified]))
                if np.any(pick & loci.verified)
                else None
            ),
        }
    out = {
        "volume": est["constant"].volume,
        "volume_se": est["constant"].se,
        "unit": r.unit,
        "workspaces": {
            k: {"volume": e.volume, "se": e.se, "hits": e.hits, "samples": e.n}
            for k, e in est.items()
        },
        "certified": None
        if atlas.bounds is None
        else {
            "inner": atlas.bounds.inner,
            "outer": atlas.bounds.outer,
            "levels": atlas.bounds.levels,
            "undecided_boxes": atlas.bounds.boxes,
            "covers": "IK existence and joint limits (not the clearance or the cond bound)",
        },
        "ray_volume": None if atlas.rays is None else ray_volume(atlas.rays),
        "singular": sing,
        "box_touches": atlas.touching,
        "region": r.describe(),
        "cpu_seconds": {k: round(v, 3) for k, v in atlas.seconds.items()},
    }
    return out


# ---------------------------------------------------------------------------------------- figure
#: colours of the boundary's active constraints (joint limits share one hue)
_REASON_COLOURS = {"domain": "#D55E00", "legs": "#CC79A7", "box": "0.5"}
_LIMIT_COLOUR = "#0072B2"
_MARKERS = {
    "direct": ("x", "#D55E00"),
    "inverse": ("+", "#009E73"),
    "domain edge": (".", "#000000"),
}


def _unit_suffix(unit: str) -> str:
    return "" if unit == "1" else f" {unit}"


def _label(name: str, unit: str) -> str:
    return f"{name} ({unit})" if unit != "1" else name


def _slice_panel(ax, df: pd.DataFrame, meta: dict, k: int) -> None:
    from matplotlib.colors import ListedColormap
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch
    from matplotlib.ticker import MaxNLocator

    cells = df[(df.part == "cell") & (df.plane == k)]
    n = int(cells["i"].max()) + 1
    A = cells["a"].to_numpy().reshape(n, n)
    B = cells["b"].to_numpy().reshape(n, n)
    code = cells["value"].to_numpy().reshape(n, n)
    reach = cells["flag"].astype(bool).to_numpy().reshape(n, n)
    cmap = ListedColormap(["white", "#9ecae1", "#3182bd"])
    ax.pcolormesh(A, B, code, cmap=cmap, vmin=-0.5, vmax=2.5, shading="nearest")
    handles = [
        Patch(color="#9ecae1", label="constant orientation"),
        Patch(color="#3182bd", label=f"dexterous, cond(J) <= {meta['cond_max']:g}"),
    ]
    if meta["given"] and reach.any() and (reach != (code > 0)).any():
        ax.contour(A, B, reach.astype(float), levels=[0.5], colors="k", linewidths=0.8,
                   linestyles="--")  # fmt: skip
        handles.append(
            Line2D([], [], color="k", ls="--", lw=0.8, label="reachable (some orientation)")
        )
    sing = df[(df.part == "singular") & (df.plane == k)]
    for kind, (marker, colour) in _MARKERS.items():
        s = sing[(sing.label == kind) & sing.flag.astype(bool)]
        if len(s):
            ax.plot(s["a"], s["b"], marker, color=colour, ms=3, ls="none")
            what = {"direct": "det A = 0 (direct)", "inverse": "det B = 0 (inverse)",
                    "domain edge": "IK domain edge (B singular)"}[kind]  # fmt: skip
            handles.append(Line2D([], [], marker=marker, color=colour, ls="none", label=what))
    u, v = meta["planes"][k]
    ax.set_xlabel(_label(meta["axes"][u], meta["units"][u]))
    ax.set_ylabel(_label(meta["axes"][v], meta["units"][v]))
    ax.xaxis.set_major_locator(
        MaxNLocator(5)
    )  # long labels (-0.0075) of a small workspace stay apart
    if len(meta["axes"]) == 3:
        w = 3 - u - v
        at = meta["at"][w]
        ax.set_title(
            f"({'ab'[k]}) slice {meta['axes'][w]} = {at:.4g}{_unit_suffix(meta['units'][w])}",
            fontsize=8,
        )
    else:
        ax.set_title("(a) the workspace plane", fontsize=8)
    ax.legend(handles=handles, fontsize=5.5, loc="best", framealpha=0.8, frameon=True)


def _cond_panel(ax, fig, df: pd.DataFrame, meta: dict) -> None:
    cells = df[(df.part == "cell") & (df.plane == 0)]
    n = int(cells["i"].max()) + 1
    A = cells["a"].to_numpy().reshape(n, n)
    B = cells["b"].to_numpy().reshape(n, n)
    cond = cells["se"].to_numpy().reshape(n, n)
    logc = np.log10(np.where(np.isfinite(cond), cond, np.nan))
    mesh = ax.pcolormesh(A, B, logc, cmap="viridis", shading="nearest")
    cb = fig.colorbar(mesh, ax=ax)
    cb.set_label("log10 cond(J)")
    if np.isfinite(logc).any() and np.nanmax(logc) > np.log10(meta["cond_max"]):
        ax.contour(A, B, np.nan_to_num(logc, nan=-1), levels=[np.log10(meta["cond_max"])],
                   colors="w", linewidths=0.8)  # fmt: skip
    ax.set_xlabel(_label(meta["axes"][0], meta["units"][0]))
    ax.set_ylabel(_label(meta["axes"][1], meta["units"][1]))
    ax.set_title(f"(b) condition number (white: cond = {meta['cond_max']:g})", fontsize=8)


def _reason_colour(reason: str) -> str:
    return _REASON_COLOURS.get(reason, _LIMIT_COLOUR)


def _reason_name(reason: str) -> str:
    if reason in ("domain", "legs", "box"):
        return {"domain": "IK domain edge", "legs": "leg clearance", "box": "box (truncated)"}[
            reason
        ]
    return "joint limit"


def _boundary_panel(ax, df: pd.DataFrame, meta: dict) -> None:
    from matplotlib.lines import Line2D

    rays = df[df.part == "ray"]
    names = meta["axes"]
    units = meta["units"]
    if len(names) == 3:
        surf = df[df.part == "surface"]
        if len(surf):
            ni, nj = int(surf["i"].max()) + 1, int(surf["j"].max()) + 1
            X, Y, Z = (surf[c].to_numpy().reshape(ni, nj) for c in "abc")
            colours = np.array([_reason_colour(s) for s in surf["label"]], dtype=object)
            rgba = _rgba(colours).reshape(ni, nj, 4)
            ax.plot_surface(X, Y, Z, facecolors=rgba, linewidth=0.1, edgecolor="0.3",
                            shade=False, alpha=0.55)  # fmt: skip
        sing = df[(df.part == "singular") & df.flag.astype(bool)]
        for kind, (marker, colour) in _MARKERS.items():
            s = sing[sing.label == kind]
            if not len(s):
                continue
            pts = np.zeros((len(s), 3))
            for row, (p, a, b, c) in enumerate(zip(s["plane"], s["a"], s["b"], s["c"])):
                u, v = meta["planes"][int(p)]
                w = 3 - u - v
                pts[row, u], pts[row, v], pts[row, w] = a, b, c
            ax.scatter(pts[:, 0], pts[:, 1], pts[:, 2], marker=marker, color=colour, s=1)
        ax.set_xlabel(_label(names[0], units[0]), fontsize=6, labelpad=-2)
        ax.set_ylabel(_label(names[1], units[1]), fontsize=6, labelpad=-2)
        ax.set_zlabel(_label(names[2], units[2]), fontsize=6, labelpad=-2)
        ax.tick_params(labelsize=5, pad=-1)
        from matplotlib.ticker import MaxNLocator

        for axis in (ax.xaxis, ax.yaxis, ax.zaxis):  # 3-D tick labels crowd: three per axis
            axis.set_major_locator(MaxNLocator(3))
        ax.set_title("(c) boundary surface (rays), singular points", fontsize=8)
    else:
        for reason in dict.fromkeys(rays["label"]):
            r = rays[rays.label == reason]
            ax.plot(r["a"], r["b"], ".", ms=2, color=_reason_colour(reason))
        ax.set_xlabel(_label(names[0], units[0]))
        ax.set_ylabel(_label(names[1], units[1]))
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title("(c) boundary along rays, by active constraint", fontsize=8)
    seen = dict.fromkeys(_reason_name(s) for s in rays["label"])
    colour_of = {_reason_name(s): _reason_colour(s) for s in rays["label"]}
    ax.legend(
        handles=[Line2D([], [], marker="s", ls="none", color=colour_of[n], label=n) for n in seen],
        fontsize=5.5,
        loc="upper left",
    )


def _rgba(colours: np.ndarray) -> np.ndarray:
    from matplotlib.colors import to_rgba

    table = {c: to_rgba(c) for c in set(colours)}
    return np.array([table[c] for c in colours])


def _volume_panel(ax, df: pd.DataFrame, meta: dict) -> None:
    vol = df[df.part == "volume"].set_index("label")
    kinds = [k for k in KINDS if k in vol.index and vol.loc[k, "j"] > 0]
    names = {
        "constant": "constant\norientation",
        "dexterous": "dexterous",
        "reachable": "reachable",
    }
    x = np.arange(len(kinds))
    ax.bar(x, vol.loc[kinds, "value"], yerr=1.96 * vol.loc[kinds, "se"], color="#9ecae1",
           edgecolor="k", linewidth=0.5, capsize=3, label="Monte Carlo, 95 % interval")  # fmt: skip
    if "inner" in vol.index:
        lo, hi = vol.loc["inner", "value"], vol.loc["outer", "value"]
        ax.errorbar([0.25], [0.5 * (lo + hi)], yerr=[[0.5 * (hi - lo)], [0.5 * (hi - lo)]],
                    fmt="none", ecolor="#D55E00", capsize=4, lw=1.2,
                    label=f"certified [inner, outer], {int(vol.loc['inner', 'i'])} halvings")  # fmt: skip
    if "rays" in vol.index:
        ax.plot([-0.25], [vol.loc["rays", "value"]], "d", color="#009E73", ms=4,
                label="rays (star-shaped estimate)")  # fmt: skip
    ax.set_xticks(x, [names[k] for k in kinds], fontsize=6)
    top = max(float(np.max(vol.loc[kinds, "value"] + 1.96 * vol.loc[kinds, "se"])),
              float(vol["value"].max()))  # fmt: skip
    ax.set_ylim(0, 1.45 * top)  # room for the legend above the bars
    ax.set_ylabel("volume" + ("" if meta["unit"] == "1" else f" ({meta['unit']})"))
    ax.set_title("(d) volumes", fontsize=8)
    ax.legend(fontsize=5.5, loc="upper right")


def draw(df: pd.DataFrame, path: str | Path) -> Path:
    """The atlas figure from its table (:func:`frame`): (a) a slice of the workspace (classes,
    reachable outline, singular points), (b) a second slice (3-D) or cond(J) over the plane
    (2-D), (c) the boundary along rays, (d) the volumes with their error bars and bounds."""
    from parakin.plot import save_figure, use_style

    with use_style():
        fig = _draw(df)
    return save_figure(fig, path)


def _draw(df: pd.DataFrame):
    from parakin.plot import new_figure

    meta = json.loads(df[df.part == "meta"]["label"].iloc[0])
    dim = len(meta["axes"])
    fig, ax0 = new_figure("double_tall")
    fig.delaxes(ax0)
    a = fig.add_subplot(2, 2, 1)
    _slice_panel(a, df, meta, 0)
    b = fig.add_subplot(2, 2, 2)
    if dim == 3:
        _slice_panel(b, df, meta, 1)
    else:
        _cond_panel(b, fig, df, meta)
    c = fig.add_subplot(2, 2, 3, projection="3d" if dim == 3 else None)
    _boundary_panel(c, df, meta)
    d = fig.add_subplot(2, 2, 4)
    _volume_panel(d, df, meta)
    given = ", ".join(
        f"{k} = {v:.4g}{_unit_suffix(meta['given_units'][k])}" for k, v in meta["given"].items()
    )
    number = f"Fig. W{meta['number']}: " if meta.get("number") else ""
    fig.suptitle(
        f"Beyond the papers: {number}workspace and singularity atlas of {meta['mechanism']}"
        + (f" at {given}" if given else "")
        + f"; joint limits {meta['limits']}",
        fontsize=8,
    )
    return fig
