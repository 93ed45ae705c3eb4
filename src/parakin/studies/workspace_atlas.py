"""Beyond the papers: the workspace and singularity atlas of every registered mechanism (issue 44).

A study registered like a paper (:mod:`parakin.registry`; config section ``workspace``; method,
bounds and cost: ``docs/workspace.md``). For each mechanism of the registry (default parameters)
:mod:`parakin.workspace.atlas` fits the box, measures the constant-orientation, dexterous and
reachable workspaces by Monte Carlo, bounds the first by interval analysis, locates the singular
points on two slices and the boundary along rays. Artefacts:

* ``atlas_<mechanism>``: ``extra_workspace_<mechanism>.{csv,png}``, the figure drawn from the
  table beside it;
* ``table``: one row per mechanism (``extra_workspace.{csv,md}``), read from those tables;
* ``checks``: the module against what is known independently (``extra_workspace_checks.{csv,md}``):
  Zhao 2017's index atlases of the 3-P(4S) (the atlas plane W certified inside the workspace,
  cond(J) against the paper module's speed index) and the Delta robot of ``examples/delta.yaml``
  (its volume against a closed-form torus test of each crank-rod leg on the same points, and
  inside the interval bounds).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from parakin.config import rng
from parakin.io import write_and_draw, write_table
from parakin.mechanisms import REGISTRY
from parakin.mechanisms.base import Mechanism
from parakin.registry import Tolerance, artefact, drawn_figure, table_files
from parakin.workspace import atlas as A
from parakin.workspace import make_region

__all__ = ["KEY", "NAMES", "atlas_data", "checks_data", "delta_torus_test", "table_data"]

KEY = "workspace"
#: the mechanisms of the atlas, in registry order (Fig. W1, W2, ...)
NAMES = list(REGISTRY)
#: the Delta robot of the checks (a described mechanism, issue 43)
DELTA_FILE = Path(__file__).resolve().parents[3] / "examples" / "delta.yaml"


def _sizes(config: dict) -> A.Sizes:
    c = config[KEY]
    return A.Sizes(
        samples=int(c["samples"]),
        orientations=int(c["orientations"]),
        levels=int(c["levels"]),
        grid=int(c["grid"]),
        rays=int(c["rays"]),
        fit_grid=int(c["fit_grid"]),
    )


def _region(mech: Mechanism, config: dict):
    c = config[KEY]
    return make_region(
        mech,
        stroke=float(c["stroke"]),
        orientation_fraction=float(c["orientation_fraction"]),
        cond_max=float(c["cond_max"]),
    )


def atlas_data(config: dict, name: str) -> pd.DataFrame:
    """The atlas table of mechanism ``name`` (:func:`parakin.workspace.atlas.frame`)."""
    mech = REGISTRY[name]()
    result = A.compute(_region(mech, config), _sizes(config), rng(config, f"{KEY}.{name}"))
    return A.frame(result, NAMES.index(name) + 1)


# ---------------------------------------------------------------------------------------- table
def table_data(outdir: Path) -> pd.DataFrame:
    """One row per mechanism from its atlas table in ``outdir``."""
    rows = []
    for name in NAMES:
        df = pd.read_csv(Path(outdir) / f"extra_workspace_{name}.csv")
        meta = json.loads(df[df.part == "meta"]["label"].iloc[0])
        vol = df[df.part == "volume"].set_index("label")
        sing = df[df.part == "singular"]
        row = {
            "figure": f"W{meta['number']}",
            "mechanism": name,
            "axes": " ".join(meta["axes"]),
            "unit": meta["unit"],
            "given": ", ".join(f"{k} = {v:.4g}" for k, v in meta["given"].items()) or "-",
            "joint_limits": meta["limits"],
            "samples": int(vol.loc["constant", "j"]),
        }
        for kind in ("constant", "dexterous", "reachable"):
            row[f"{kind}_volume"] = float(vol.loc[kind, "value"])
            row[f"{kind}_se"] = float(vol.loc[kind, "se"])
        row["certified_inner"] = (
            float(vol.loc["inner", "value"]) if "inner" in vol.index else np.nan
        )
        row["certified_outer"] = (
            float(vol.loc["outer", "value"]) if "outer" in vol.index else np.nan
        )
        row["halvings"] = int(vol.loc["inner", "i"]) if "inner" in vol.index else 0
        row["ray_volume"] = float(vol.loc["rays", "value"]) if "rays" in vol.index else np.nan
        for kind, col in (
            ("direct", "det_A"),
            ("inverse", "det_B"),
            ("domain edge", "domain_edge"),
        ):
            s = sing[sing.label == kind]
            row[f"{col}_points"] = len(s)
            row[f"{col}_verified"] = int(s.flag.astype(bool).sum())
        ok = sing[sing.flag.astype(bool)]
        row["max_sigma_rel_verified"] = float(ok["value"].max()) if len(ok) else np.nan
        row["box_touched"] = ", ".join(meta["touching"]) or "-"
        rows.append(row)
    return pd.DataFrame(rows)


TABLE_NOTES = """
Volumes in `unit` over the pose coordinates `axes`, the others held at `given` (SI: m, rad);
`*_se` the Monte-Carlo standard error; `certified_inner`/`certified_outer` interval-analysis bounds
of the constant-orientation workspace (IK existence and joint limits) after `halvings` bisections;
`ray_volume` the volume of the boundary found along rays from a point inside (equal to the
constant-orientation volume only where the workspace is star-shaped about that point). Reachable:
some orientation in the given values +- a fraction of the mechanism's pose bounds (config
`workspace.orientation_fraction`), tried at a Halton set of `workspace.orientations` of them.
Singular points on two slices (one for a planar workspace): `det_A` direct-kinematic (type II),
`det_B` inverse-kinematic (type I) sign changes and the IK domain's edges (`domain_edge`), each
bisected to 1e-9 and on to floating-point resolution; verified where sigma_min / sigma_max <= 1e-8
(its square for a domain edge, where sigma_min vanishes like the square root of the distance).
Method, bounds and cost: docs/workspace.md.
"""


# ---------------------------------------------------------------------------------------- checks
def delta_torus_test(mech, points: np.ndarray) -> np.ndarray:
    """Whether each position ``(N, 3)`` of a translational platform on crank-rod legs without joint
    limits is reachable, in closed form and apart from the IK: leg i reaches its anchor ``w`` (from
    the crank centre) iff the rod length lies between the least and the greatest distance from
    ``w`` to the crank tip's circle, ``sqrt((rho - r)^2 + h^2) <= L <= sqrt((rho + r)^2 + h^2)``
    (``h`` along the crank axis, ``rho`` the distance from it)."""
    ok = np.ones(len(points), dtype=bool)
    for leg in mech.legs:
        if leg.type != "crank-rod" or leg.limits is not None:
            raise ValueError(f"the torus test takes crank-rod legs without limits, not {leg.type}")
        u = np.asarray(leg.axis, float) / np.linalg.norm(leg.axis)
        w = points + np.asarray(leg.platform, float) - np.asarray(leg.base, float)
        h = w @ u
        rho = np.linalg.norm(w - h[:, None] * u, axis=-1)
        near = np.hypot(rho - leg.crank, h)
        far = np.hypot(rho + leg.crank, h)
        ok &= (near <= leg.rod) & (leg.rod <= far)
    return ok


def _zhao_rows(config: dict) -> list[dict]:
    """The 3-P(4S) against Zhao's index atlases (config ``zhao2017_3p4s.indices``): on each design's
    atlas grid over W, every point in the module's workspace (no joint limits, as the atlases),
    W's square certified inside by interval analysis, and cond(J) against the speed index of
    :func:`parakin.mechanisms.p3p4s_indices.mech_indices` (what Figs 23-26 draw)."""
    from parakin.mechanisms import P3P4S
    from parakin.mechanisms import p3p4s_indices as ix
    from parakin.workspace import classify
    from parakin.workspace.interval import classify_boxes

    c = config["zhao2017_3p4s"]["indices"]
    W = ix.Workspace.square(float(c["z0"]), float(c["half_width"]), float(c["z_half_height"]))
    rows = []
    for design, mech in (("before", P3P4S.zhao2017()), ("after", P3P4S.zhao2017_optimised())):
        _, _, poses = W.grid(int(c["atlas_grid"]))
        flat = poses.reshape(-1, 3)
        region = make_region(mech, stroke=0.0, cond_max=float(config[KEY]["cond_max"]))
        cls = classify(region, flat, compiled=False)
        speed = ix.mech_indices(mech, poses).speed.reshape(-1)
        rel = np.max(np.abs(cls.cond / speed - 1))
        # W's square, split 8 x 8 (a plane: z held by a zero-width side), each box certified in
        edges_x = np.linspace(*W.x, 9)
        edges_y = np.linspace(*W.y, 9)
        lo = np.stack(np.meshgrid(edges_x[:-1], edges_y[:-1], indexing="ij"), -1).reshape(-1, 2)
        hi = np.stack(np.meshgrid(edges_x[1:], edges_y[1:], indexing="ij"), -1).reshape(-1, 2)
        z = np.full((len(lo), 1), W.z[0])
        inside, _ = classify_boxes(region, np.hstack([lo, z]), np.hstack([hi, z]))
        rows.append(
            {
                "check": f"3p4s {design} (Table 3) vs Zhao's atlas grid over W",
                "points": len(flat),
                "in_workspace": int(np.count_nonzero(cls.member)),
                "agree_fraction": float(np.mean(cls.member)),
                "ours": float(np.max(cls.cond)),
                "reference": float(np.max(speed)),
                "max_rel_difference": float(rel),
                "certified_boxes_in": f"{int(np.count_nonzero(inside))} of {len(lo)}",
                "reference_method": "speed index of p3p4s_indices.mech_indices (Figs 23-26)",
            }
        )
    return rows


def _delta_rows(config: dict) -> list[dict]:
    """The Delta robot of ``examples/delta.yaml``: its volume by the module (numpy path) and by the
    closed-form torus test on the same points, and the interval bounds."""
    from parakin.mechanisms import from_file
    from parakin.workspace import certify, classify, fit_box

    c = config[KEY]
    mech = from_file(DELTA_FILE)
    region, touching = fit_box(
        make_region(mech, cond_max=float(c["cond_max"])), grid=int(c["fit_grid"])
    )
    g = rng(config, f"{KEY}.delta")
    n = int(c["delta_samples"])
    pts = g.uniform(region.lo, region.hi, size=(n, 3))
    ours = classify(region, pts, cond=False, compiled=False).member
    ref = delta_torus_test(mech, pts)
    box = region.box_volume
    v_ours, v_ref = box * ours.mean(), box * ref.mean()
    se = box * np.sqrt(ref.mean() * (1 - ref.mean()) / n)
    bounds = certify(region, levels=int(c["delta_levels"]))
    return [
        {
            "check": "delta (examples/delta.yaml) volume vs closed-form torus test, same points",
            "points": n,
            "in_workspace": int(np.count_nonzero(ours)),
            "agree_fraction": float(np.mean(ours == ref)),
            "ours": float(v_ours),
            "reference": float(v_ref),
            "max_rel_difference": float(abs(v_ours / v_ref - 1)),
            "reference_se": float(se),
            "certified_inner": bounds.inner,
            "certified_outer": bounds.outer,
            "box_touched": ", ".join(touching) or "-",
            "reference_method": "min/max distance to each crank circle vs the rod length",
        }
    ]


def checks_data(config: dict) -> pd.DataFrame:
    """The module against independent results (module docstring)."""
    return pd.DataFrame(_zhao_rows(config) + _delta_rows(config))


CHECK_NOTES = """
Zhao rows: Zhao's atlas grid over W (config `zhao2017_3p4s.indices`: plane z0, |x|, |y| <=
half_width, atlas_grid points per axis) without joint limits, as the atlases take it:
`in_workspace` of `points` classified in by this module, `certified_boxes_in` of W's 8 x 8 squares
proved inside by interval analysis, `ours`/`reference` the largest cond(J) over the grid by this
module and by the paper module's speed index (Figs 23-26), `max_rel_difference` their largest
pointwise relative difference. The atlases' own code is unchanged (figures/zhao2017_3p4s/ is not
touched by this study). Delta row: the Delta of examples/delta.yaml (no joint limits: the IK's
domain, below and above the base), `points` uniform in the fitted box, `ours` the module's volume,
`reference` that of the closed-form torus test on the same points, `agree_fraction` the share of
points both classify alike; `reference_se` the Monte-Carlo standard error; the interval bounds must
hold both.
"""


# ---------------------------------------------------------------------------------------- artefacts
#: a rerun agrees to rounding: the classes are exact comparisons of closed-form IK values, the
#: singular points are bisected to floating-point resolution (sigma_rel there is round-off,
#: compared with an absolute floor), cond(J) by class near a singularity; a Monte-Carlo point
#: within rounding of a limit may classify the other way on another machine, moving a volume by
#: one sample (1/samples of the box), hence the relative 1e-3 on the value column
ATLAS = Tolerance(
    "rounding",
    1e-6,
    1e-9,
    "closed-form IK classes and bisections to floating-point resolution; one Monte-Carlo sample "
    "within rounding of a limit may flip (value: rtol 1e-3, atol 1e-7 for round-off sigma ratios); "
    "cond(J) compared by class near a singularity",
    columns={"value": (1e-3, 1e-7), "se": Tolerance.condition(12)},
)
TABLE = Tolerance(
    "rounding",
    1e-3,
    1e-7,
    "Monte-Carlo volumes and interval bounds of closed-form classes: a sample within rounding of "
    "a limit may flip on another machine; singular counts may move by one where a determinant is "
    "within round-off of zero at a grid point",
    columns={
        **{f"{c}_points": (0.0, 1.0) for c in ("det_A", "det_B", "domain_edge")},
        **{f"{c}_verified": (0.0, 1.0) for c in ("det_A", "det_B", "domain_edge")},
    },
)
CHECKS = Tolerance(
    "rounding",
    1e-3,
    1e-9,
    "closed-form classes on seeded points; a point within rounding of the boundary may flip",
    columns={"max_rel_difference": (0.0, 1e-6)},
)


def _declare_atlases() -> None:
    for name in NAMES:
        stem = f"extra_workspace_{name}"

        def make(config: dict, outdir: Path, name=name, stem=stem) -> list[Path]:
            return write_and_draw(atlas_data(config, name), Path(outdir) / f"{stem}.csv", A.draw)

        make.__name__ = make.__qualname__ = f"atlas_{name}"
        make.__doc__ = f"Workspace and singularity atlas of {name}: the table and its figure."
        drawn_figure(
            KEY,
            f"atlas_{name}",
            stem,
            A.draw,
            config=[KEY],
            tolerance=ATLAS,
            reference=False,
            caption=f"Workspace and singularity atlas of {name} (slices, boundary, singular points, "
            "volumes).",
        )(make)


_declare_atlases()


@artefact(
    KEY,
    "table",
    outputs=list(table_files("extra_workspace")),
    needs=[f"{KEY}:atlas_{name}" for name in NAMES],
    config=[KEY],
    tolerance=TABLE,
    reference=False,
)
def table(config: dict, outdir: Path) -> list[Path]:
    """The workspace atlas of every registered mechanism, one row each."""
    return write_table(
        table_data(Path(outdir)),
        Path(outdir) / "extra_workspace",
        title="Beyond the papers: workspace and singularity atlas of every registered mechanism",
        notes=TABLE_NOTES,
        floatfmt=".4g",
    )


@artefact(
    KEY,
    "checks",
    outputs=list(table_files("extra_workspace_checks")),
    config=[KEY, "zhao2017_3p4s.indices"],
    tolerance=CHECKS,
    reference=False,
    files=["examples/delta.yaml"],
)
def checks(config: dict, outdir: Path) -> list[Path]:
    """The workspace module against Zhao's atlases and a closed-form Delta workspace test."""
    return write_table(
        checks_data(config),
        Path(outdir) / "extra_workspace_checks",
        title="Beyond the papers: the workspace module checked against independent results",
        notes=CHECK_NOTES,
        floatfmt=".6g",
    )
