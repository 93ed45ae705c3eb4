"""Li 2017 §3 Table 3 and the "all forward solutions" claim, against a certified all-solutions FK
(degree-16 polynomial, :meth:`parakin.mechanisms.stewart36.Stewart36.fk_all`); Fig. 1 redrawn; the
real-solution counts over random inputs and over the b sweep (our addition); and a surrogate of the
Adams study of §4 (Figs 5-11; the drive mapping is unknown, docs/li2017_stewart36.md#s5).
"""

from __future__ import annotations

import time
from functools import partial
from pathlib import Path

import numpy as np
import pandas as pd

from parakin.claims import Claim, load_reference, printed_value
from parakin.config import rng
from parakin.io import write_and_draw, write_csv, write_table
from parakin.mechanisms.stewart36 import pose_from_paper, pose_to_paper
from parakin.papers.drawing import draw_skeleton_table
from parakin.papers.li2017_stewart36.common import (
    INPUT_NOTE,
    KEY,
    POSE_COLS,
    artefact,
    cfg,
    drawn_figures,
    fk_input,
    mech,
    table,
    table3,
)
from parakin.papers.sections import table_claims, table_text
from parakin.registry import ROUNDING, table_files
from parakin.solvers import solve_fk

#: Table 3's residuals at the printed poses are closed-form; the certified solution set comes from
#: polynomial roots polished to round-off
ROOTS = ROUNDING.but(
    "roots of a degree-16 polynomial polished by Newton: poses to rounding, residuals at "
    "round-off within 1e-9"
)

RANGES = ("X", "Y", "Z", "angle1", "angle2", "angle3")


def adams_ranges(ref: pd.DataFrame | None = None) -> dict[str, tuple[float, float]]:
    """The CM ranges stated in §4 (from Figs 6-11), keyed by pose column."""
    ref = load_reference(KEY) if ref is None else ref
    cols = {"X": "X", "Y": "Y", "Z": "Z", "angle1": "alpha", "angle2": "beta", "angle3": "gamma"}
    return {
        cols[q]: (
            float(printed_value(ref, "sec4", f"{q}_min")),
            float(printed_value(ref, "sec4", f"{q}_max")),
        )
        for q in RANGES
    }


@artefact("table3", outputs=["table3.csv", "table3.md"], config=[KEY], tolerance=ROOTS)
def table3_artefact(config: dict, outdir: Path) -> list[Path]:
    """Table 3 decoded, each row's fitness and leg error under the reconstructed input (for every b of
    the sweep), and whether it lies inside the §4 ranges."""
    t = table3()
    rngs = adams_ranges()
    poses = pose_from_paper(t[list(POSE_COLS)].to_numpy(float))
    for b in cfg(config)["b_sweep"]:
        m = mech(config, b)
        q = fk_input(config, b)
        t[f"F_b{b:g}"] = m.objective(poses, q)
        t[f"max_leg_err_b{b:g}"] = np.max(np.abs(m.ik(poses) - q), axis=-1)
    inside = np.ones(len(t), bool)
    for col, (lo, hi) in rngs.items():
        inside &= (t[col] >= lo) & (t[col] <= hi)
    t["inside_sec4_ranges"] = inside
    b0 = cfg(config)["b"]
    return write_table(
        t,
        outdir / "table3",
        floatfmt=".4g",
        title=f"Table 3 — the paper's {len(t)} 'forward solutions', decoded, with their residuals",
        notes=f"{INPUT_NOTE}. F = eq. (4) (squared-length residual); max_leg_err = max |IK(row) - L|. "
        f"Row 1 is exact by construction; a real solution would have F ~ 1e-30. Default b = {b0}.",
    )


# ---------------------------------------------------------------------------------- Table 3 as a whole
def _rounding_bound(m, rows: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Per row and leg, how far printing the row's six coordinates (half a unit of each printed
    digit, ``half``, paper units) can move its leg lengths: ``sum_j |dl_i/dp_j| h_j`` by central
    differences (the legs are smooth there; the step is far below the print)."""
    out = np.zeros((len(rows), 6))
    for j in range(6):
        step = np.zeros(6)
        step[j] = 1e-6
        dl = (m.ik(pose_from_paper(rows + step)) - m.ik(pose_from_paper(rows - step))) / 2e-6
        out += np.abs(dl) * half[:, j : j + 1]
    return out


def table3_mismatch(config: dict, bs: np.ndarray) -> dict[str, np.ndarray]:
    """For every base side ``b`` in ``bs`` and every Table 3 row: the largest of the six legs'
    mismatch |l_i(row) - l_i(row 1)| (row 1 defines the input, so nothing is assumed but the
    layout), and by how much it exceeds what printing both rows to their digits allows (``excess``
    <= 0: the row is an assembly of row 1's leg lengths within rounding)."""
    from parakin.claims import half_ulp

    ref = load_reference(KEY)
    t = table3(ref)
    rows = t[list(POSE_COLS)].to_numpy(float)
    half = np.array(
        [
            [half_ulp(printed_value(ref, "table3", f"row{k}.{c}")) for c in POSE_COLS]
            for k in t["row"]
        ]
    )
    mismatch = np.full((len(bs), len(rows)), np.inf)
    excess = np.full((len(bs), len(rows)), np.inf)
    for i, b in enumerate(bs):
        m = mech(config, b)
        with np.errstate(invalid="ignore"):
            legs = m.ik(pose_from_paper(rows))
            bound = _rounding_bound(m, rows, half)
            gap = np.abs(legs - legs[0])
            ok = np.all(np.isfinite(legs), axis=-1)
            mismatch[i] = np.where(ok, gap.max(axis=-1), np.inf)
            excess[i] = np.where(ok, (gap - bound - bound[0]).max(axis=-1), np.inf)
    return {"rows": t["row"].to_numpy(), "mismatch": mismatch, "excess": excess}


def draw_table3_consistency(frame: pd.DataFrame, path: Path) -> Path:
    """extra_table3_consistency from its CSV: per b the largest leg mismatch of each of rows 2-19
    with row 1's leg lengths (thin), their largest and smallest (bold)."""
    from parakin.plot import new_figure, save_figure

    cols = [c for c in frame.columns if c.startswith("mismatch_row")]
    b = frame["b"].to_numpy()
    fig, ax = new_figure((6.4, 3.4))
    ax.semilogy(b, frame[cols].to_numpy(float), color="0.75", lw=0.6)
    ax.semilogy(b, frame["largest_mismatch"], color="C3", lw=1.4, label="largest over rows 2-19")
    ax.semilogy(b, frame["smallest_mismatch"], color="C0", lw=1.4, label="smallest over rows 2-19")
    ax.semilogy(
        b,
        frame["rounding_allowance"],
        color="k",
        ls=":",
        lw=1.0,
        label="what printing allows (largest)",
    )
    ax.set_xlabel("base side b (platform side a = 1)")
    ax.set_ylabel("max |l_i(row) - l_i(row 1)| over the six legs")
    ax.set_title(
        "Table 3: do rows 2-19 assemble with\nrow 1's leg lengths, for any b?", fontsize="small"
    )
    ax.legend(fontsize="x-small")
    return save_figure(fig, path)


#: the base side, as a fraction of the sweep's smallest, at which a mismatch that falls to b -> 0
#: is evaluated as its limit
TINY_B = 1e-3


def _rows_at(per_row: pd.DataFrame, end: str) -> str:
    return ", ".join(str(int(r)) for r in per_row[per_row["minimum_at_sweep_end"] == end]["row"])


@artefact(
    "table3_consistency",
    outputs=[
        "extra_table3_consistency.csv",
        "extra_table3_consistency.png",
        "extra_table3_rows.csv",
        "extra_table3_rows.md",
    ],
    config=[KEY],
    tolerance=ROOTS,
    caption="Table 3 judged row by row as a whole: rows 2-19 against row 1's leg lengths for every b",
    draws=[
        ("extra_table3_consistency.png", "extra_table3_consistency.csv", draw_table3_consistency)
    ],
)
def table3_consistency(config: dict, outdir: Path) -> list[Path]:
    """Table 3 needs no assumed input to be checked against itself: its rows claim to be forward
    solutions of one input, so each must have row 1's six leg lengths. For every base side b of a
    fine sweep: each row's largest leg mismatch with row 1, and whether it is within what printing
    both rows allows (per row: the smallest mismatch over b, where, and its rounding allowance)."""
    lo, hi, n = cfg(config)["consistency"]["b_range"] + [cfg(config)["consistency"]["steps"]]
    bs = np.linspace(lo, hi, int(n))
    r = table3_mismatch(config, bs)
    mis, exc, rows = r["mismatch"], r["excess"], r["rows"]
    allow = mis - exc  # what printing allows, per (b, row)
    per_b = pd.DataFrame({"b": bs})
    for k, row in enumerate(rows[1:], start=1):
        per_b[f"mismatch_row{row}"] = mis[:, k]
    per_b["largest_mismatch"] = mis[:, 1:].max(axis=1)
    per_b["smallest_mismatch"] = mis[:, 1:].min(axis=1)
    per_b["rounding_allowance"] = np.where(np.isfinite(allow[:, 1:]), allow[:, 1:], np.nan).max(
        axis=1
    )
    per_b["rows_within_rounding"] = (exc[:, 1:] <= 0).sum(axis=1)
    best = np.argmin(mis, axis=0)
    # where a row's smallest mismatch lies at an end of the sweep, the sweep does not hold its
    # minimum: at the upper end it must be widened; at the lower one the mismatch may fall all the
    # way to b -> 0 (a base shrunk to a point), whose limit is then the true minimum over b > 0
    # (computed at b = lo * TINY_B; "b -> 0" only where it is no larger than at the sweep's end,
    # else the minimum lies below the sweep's first step: "lower", the sweep must be refined)
    limit = table3_mismatch(config, np.array([lo * TINY_B]))["mismatch"][0]
    first = mis[0]
    end = np.where(
        best == 0,
        np.where(limit <= first, "b -> 0", "lower"),
        np.where(best == len(bs) - 1, "upper", ""),
    )
    per_row = pd.DataFrame(
        {
            "row": rows,
            "min_mismatch": mis[best, np.arange(len(rows))],
            "at_b": bs[best],
            "rounding_allowance_there": allow[best, np.arange(len(rows))],
            "within_rounding_for_some_b": (exc <= 0).any(axis=0),
            "minimum_at_sweep_end": end,
            "limit_b_to_0": np.where(end == "b -> 0", limit, np.nan),
        }
    ).iloc[1:]
    whole = int(np.argmin(per_b["largest_mismatch"]))
    at_end = per_row[per_row["minimum_at_sweep_end"] != ""]
    notes = (
        f"b swept over [{lo:g}, {hi:g}] in {int(n)} steps (platform side a = 1, the layout of docs/li2017_stewart36.md#s1). "
        "Row 1 defines the input (its own leg lengths, no reconstruction needed); a row is an assembly of that "
        "input when all six of its legs match row 1's within what printing both rows to their digits allows "
        "(sum of |dl/dp| times half a printed digit, both rows). Smallest over b of the largest mismatch over "
        f"rows 2-19: {per_b['largest_mismatch'].iloc[whole]:.3g} at b = {bs[whole]:g}. Rows within rounding for "
        f"some b: {int(per_row['within_rounding_for_some_b'].sum())} of {len(per_row)}"
        + (
            "; the table contradicts itself for every b."
            if not per_row["within_rounding_for_some_b"].any()
            else "."
        )
        + (
            f" Rows whose mismatch falls all the way to b -> 0 (a base shrunk to a point, no Stewart "
            f"platform): {_rows_at(at_end, 'b -> 0')}; their minimum over b > 0 is that limit "
            f"(limit_b_to_0, computed at b = {lo * TINY_B:g}), below the value at the sweep's smallest b "
            f"by at most {np.nanmax(at_end['min_mismatch'] - at_end['limit_b_to_0']):.2g}."
            if (end[1:] == "b -> 0").any()
            else ""
        )
        + (
            f" Rows whose minimum lies below the sweep's first step (refine it): {_rows_at(at_end, 'lower')}."
            if (end[1:] == "lower").any()
            else ""
        )
        + (
            f" Rows whose minimum lies at the upper end (widen the sweep): {_rows_at(at_end, 'upper')}."
            if (end[1:] == "upper").any()
            else ""
        )
        + " Per b: extra_table3_consistency.csv."
    )
    return write_and_draw(
        per_b,
        outdir / "extra_table3_consistency.csv",
        draw_table3_consistency,
        outdir / "extra_table3_consistency.png",
    ) + write_table(
        per_row,
        outdir / "extra_table3_rows",
        floatfmt=".4g",
        title="Table 3's rows 2-19 against row 1's leg lengths, over every b",
        notes=notes,
    )


@table(
    "extra_solutions",
    "extra_solutions",
    *table_files("extra_solution_counts_b"),
    config=[KEY],
    tolerance=ROOTS,
)
def solutions_artefact(config: dict, outdir: Path) -> list[Path]:
    """Our table of all real forward solutions of the reconstructed input, for every b of the sweep."""
    rows, counts = [], []
    for b in cfg(config)["b_sweep"]:
        m = mech(config, b)
        q = fk_input(config, b)
        t0 = time.perf_counter()
        sols, info = m.fk_all(q, return_info=True)
        wall = time.perf_counter() - t0
        real = sols[np.isfinite(sols[:, 0])]
        for k, s in enumerate(real):
            p = pose_to_paper(s)
            rows.append(
                {
                    "b": b,
                    "solution": k + 1,
                    **dict(zip(POSE_COLS, p)),
                    "ik_error": float(np.max(np.abs(m.ik(s) - q))),
                    "above_base": bool(s[5] > 0),
                    "is_table3_row1": bool(
                        np.allclose(p, table3().iloc[0][list(POSE_COLS)].to_numpy(float), atol=1e-6)
                    ),
                    "sigma_min_jacobian": float(
                        np.linalg.svd(m.jacobian_pose(s), compute_uv=False)[-1]
                    ),
                }
            )
        counts.append(
            {
                "b": b,
                "complex_roots": int(info["n_complex"]),
                "real": int(info["n_real"]),
                "above_base": int(info["n_above"]),
                "degree_tail": float(info["tail"]),
                "wall_time_ms": wall * 1e3,
            }
        )
    df = pd.DataFrame(rows)
    md = df.copy()
    return write_table(
        df,
        outdir / "extra_solutions",
        floatfmt=".6g",
        markdown=md,
        title="All real forward solutions of the reconstructed input (certified, degree-16 polynomial)",
        notes=f"{INPUT_NOTE}. Angles in degrees. Each solution has its mirror (alpha, -beta, -gamma, X, Y, -Z).",
    ) + write_table(
        pd.DataFrame(counts),
        outdir / "extra_solution_counts_b",
        floatfmt=".4g",
        title="Number of forward solutions per b (paper: "
        f"{printed_value(load_reference(KEY), 'table3', 'n_solutions')}, all above the base)",
        notes="degree_tail = size of the interpolated coefficients above degree 16 (relative): "
        "the polynomial has degree 16, so at most 16 complex and 8 above-base solutions.",
    )


def draw_solution_counts(frame: pd.DataFrame, path: Path) -> Path:
    """Histogram of real-solution counts per b, drawn from ``extra_solution_counts.csv`` alone
    (columns ``b``, ``real_0`` .. ``real_16`` and ``paper_solutions``)."""
    from parakin.plot import new_figure, save_figure

    fig, ax = new_figure((6.4, 2.8))
    width = 0.8 / len(frame)
    ks = np.arange(0, 17, 2)
    for j, (_, r) in enumerate(frame.iterrows()):
        ax.bar(
            ks + (j - (len(frame) - 1) / 2) * width * 2,
            r[[f"real_{k}" for k in ks]].to_numpy(int),
            width=2 * width,
            label=f"b = {r['b']:g}",
        )
    ax.set_xlabel("number of real forward solutions")
    ax.set_ylabel("inputs")
    paper = int(frame["paper_solutions"].iloc[0])
    ax.set_xticks(list(range(0, 17, 2)) + [paper])
    ax.axvline(paper, color="0.3", ls="--", lw=1.0)
    ax.text(
        paper - 0.2,
        ax.get_ylim()[1] * 0.9,
        f"paper: {paper}",
        ha="right",
        va="top",
        fontsize="x-small",
        color="0.3",
    )
    ax.axvline(16.5, color="0.6", ls=":", lw=0.8)
    ax.set_xlim(-1.5, max(20, paper + 1))
    ax.legend(fontsize="x-small")
    return save_figure(fig, path)


@table(
    "extra_solution_counts",
    "extra_solution_counts",
    "extra_solution_counts.png",
    "extra_solution_counts_richest.csv",
    config=[KEY],
    tolerance=ROOTS,
    draws=[("extra_solution_counts.png", "extra_solution_counts.csv", draw_solution_counts)],
)
def counts_artefact(config: dict, outdir: Path) -> list[Path]:
    """Histogram of the number of real FK solutions over random inputs (random pose near Table 3 row 1,
    IK, legs scaled by U[1 - s, 1 + s]), per b of the sweep."""
    c = cfg(config)["counts"]
    n, s = int(c["samples"]), float(c["scale"])
    rows, frames = [], []
    for b in cfg(config)["b_sweep"]:
        g = rng(config, f"{KEY}.counts.b{b:g}")
        m = mech(config, b)
        lo, hi = m.pose_bounds()
        pose = m.home() + g.uniform(-1, 1, (n, 6)) * np.array([0.5, 0.5, 0.5, 0.3, 0.3, 0.3])
        q = m.ik(pose) * g.uniform(1 - s, 1 + s, (n, 6))
        t0 = time.perf_counter()
        _, info = m.fk_all(q, return_info=True)
        wall = time.perf_counter() - t0
        assembl = info["n_complex"] > 0
        best = int(np.argmax(info["n_real"]))
        sb = _[best][np.isfinite(_[best][:, 0])]
        frames.append(
            pd.DataFrame(
                {
                    "b": b,
                    "sample": best,
                    **{f"L{i + 1}": q[best, i] for i in range(6)},
                    "solution": np.arange(1, len(sb) + 1),
                    **{c: pose_to_paper(sb)[:, i] for i, c in enumerate(POSE_COLS)},
                    "ik_error": np.max(np.abs(m.ik(sb) - q[best]), axis=-1),
                }
            )
        )
        hist = np.bincount(info["n_real"][assembl], minlength=17)
        rows.append(
            {
                "b": b,
                "samples": n,
                "no_circles": int(np.sum(~assembl)),
                **{f"real_{k}": int(hist[k]) for k in range(0, 17, 2)},
                "max_real": int(info["n_real"].max()),
                "max_above_base": int(info["n_above"].max()),
                "max_ik_error": float(np.nanmax(info["ik_error"]))
                if np.isfinite(info["ik_error"]).any()
                else 0.0,
                "wall_time_ms_per_input": wall / n * 1e3,
                # the paper's count of Table 3's "solutions" (drawn as a mark; data/reference)
                "paper_solutions": int(printed_value(load_reference(KEY), "table3", "n_solutions")),
            }
        )
    df = pd.DataFrame(rows)
    tables = write_table(
        df,
        outdir / "extra_solution_counts",
        floatfmt=".3g",
        title="Real forward solutions over random inputs (certified all-solutions FK)",
        notes=f"{n} inputs per b: random pose near Table 3 row 1, IK, each leg scaled by U[{1 - s:g}, {1 + s:g}]; "
        "no_circles = a leg pair cannot reach its base edge.",
    )
    png = draw_solution_counts(pd.read_csv(tables[0]), outdir / "extra_solution_counts.png")
    return tables + [
        png,
        write_csv(pd.concat(frames), outdir / "extra_solution_counts_richest.csv"),
    ]


#: length of the frame arrows in Fig. 1 (in units of the top side a)
FIG1_FRAME_LENGTH = 0.4


def draw_fig01(frame: pd.DataFrame, path: Path) -> Path:
    """Fig. 1 drawn from its skeleton table (``fig01_structure.csv``, with the base side ``b``)."""
    return draw_skeleton_table(
        frame,
        path,
        frame_length=FIG1_FRAME_LENGTH,
        title=f"3-6 platform, b = {float(frame['b'].iloc[0]):g}, Table 3 row 1",
    )


def draw_solutions(frame: pd.DataFrame, path: Path) -> Path:
    """Every above-base solution side by side, drawn from ``extra_solutions_skeletons.csv`` alone
    (one skeleton table per ``solution``, with its pose in the paper's units for the title)."""
    from parakin.plot import (
        draw_mechanism,
        mechanism_axes,
        new_figure,
        save_figure,
        skeleton_from_table,
    )

    groups = list(frame.groupby("solution", sort=False))
    k = len(groups)
    fig, _ = new_figure((3.0 * k, 3.2))
    fig.clear()
    fig.set_layout_engine(None)  # placed below: room on the right for the last panel's z label
    for i, (_, sk) in enumerate(groups):
        a = mechanism_axes(fig, 1, k, i + 1)
        pose = sk.iloc[0]
        draw_mechanism(
            skeleton_from_table(sk),
            ax=a,
            labels=False,
            frames=False,
            legend=False,
            title=f"({', '.join(f'{pose[c]:.1f}' for c in ('alpha', 'beta', 'gamma'))})°, "
            f"Z = {pose['Z']:.3f}",
        )
        a.xaxis.labelpad = 3  # the flattest assembly's x ticks come close to the label
    fig.suptitle("every real forward solution above the base, for the reconstructed input")
    fig.subplots_adjust(left=0.01, right=0.95, top=0.84, wspace=0.1)
    return save_figure(fig, path)


@drawn_figures(
    "fig01",
    [
        ("fig01_structure.png", "fig01_structure.csv", draw_fig01),
        ("extra_solutions.png", "extra_solutions_skeletons.csv", draw_solutions),
    ],
    config=[KEY],
    tolerance=ROOTS,
)
def fig01(config: dict, outdir: Path) -> list[Path]:
    """Fig. 1 redrawn from our model at Table 3 row 1, plus every above-base solution of the
    reconstructed input (Fig. 4's role: the model the paper simulated)."""
    from parakin.plot import skeleton_table

    m = mech(config)
    q = fk_input(config)
    sols = m.fk_all(q)
    up = sols[np.isfinite(sols[:, 0]) & (np.nan_to_num(sols[:, 5]) > 0)]
    structure = skeleton_table(m.skeleton(m.home()), frame_length=FIG1_FRAME_LENGTH)
    structure["b"] = m.b  # for the title
    paths = write_and_draw(structure, outdir / "fig01_structure.csv", draw_fig01)
    skeletons = []
    for i, s in enumerate(up):
        p = pose_to_paper(s)
        sk = skeleton_table(m.skeleton(s))
        sk.insert(0, "solution", i + 1)
        for col, v in (("alpha", p[0]), ("beta", p[1]), ("gamma", p[2]), ("Z", s[5])):
            sk.insert(sk.columns.get_loc("element"), col, v)
        skeletons.append(sk)
    return paths + write_and_draw(
        pd.concat(skeletons, ignore_index=True),
        outdir / "extra_solutions_skeletons.csv",
        draw_solutions,
        png=outdir / "extra_solutions.png",
    )


def draw_cm_velocity(frame: pd.DataFrame, path: Path) -> Path:
    """Fig. 5 (surrogate) drawn from ``fig05_cm_velocity.csv`` alone."""
    from parakin.plot import new_figure, save_figure

    fig, ax = new_figure((6.4, 3.0))
    for c in ("VX", "VY", "VZ"):
        ax.plot(frame["t_s"], frame[c], lw=1.0, label=c)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("CM velocity (a/s; a = top side)")
    ax.set_title(
        "Fig. 5, SURROGATE: CM velocity of a trajectory built inside the paper's stated ranges\n"
        "(the Adams drive mapping is not given; recovered by warm-started Newton FK)",
        fontsize=8,
    )
    ax.legend(fontsize="x-small", loc="upper left", bbox_to_anchor=(1.0, 1.0))
    return save_figure(fig, path)


def _draw_ranges(frame: pd.DataFrame, path: Path, cols: tuple[str, ...], unit: str, title: str):
    """Three coordinates over time, each over the band of the range the paper states (the columns
    ``<c>_stated_min``, ``<c>_stated_max`` of ``frame``)."""
    from parakin.plot import new_figure, save_figure, use_style

    fig, _ = new_figure((6.4, 4.6))
    fig.clear()
    with use_style():
        axs = fig.subplots(3, 1, sharex=True)
    for axi, c in zip(axs, cols):
        axi.plot(frame["t_s"], frame[c], lw=1.0, label="recovered by FK")
        lo, hi = float(frame[f"{c}_stated_min"].iloc[0]), float(frame[f"{c}_stated_max"].iloc[0])
        axi.axhspan(lo, hi, color="0.85", zorder=0, label="range the\npaper states")
        axi.set_ylim(lo - 0.2 * (hi - lo), hi + 0.2 * (hi - lo))
        axi.set_ylabel(c + unit)
    axs[0].legend(fontsize="x-small", loc="upper left", bbox_to_anchor=(1.0, 1.0))
    axs[0].set_title(
        f"{title} of a trajectory built inside the paper's stated ranges\n(the Adams drive mapping "
        "is not given; lengths in units of the top side a)",
        fontsize=8,
    )
    axs[-1].set_xlabel("t (s)")
    return save_figure(fig, path)


def draw_cm_position(frame: pd.DataFrame, path: Path) -> Path:
    """Fig. 6 (surrogate) drawn from ``fig06_cm_position.csv`` alone."""
    return _draw_ranges(frame, path, ("X", "Y", "Z"), " (a)", "Fig. 6, SURROGATE: CM position")


def draw_euler_angles(frame: pd.DataFrame, path: Path) -> Path:
    """Fig. 9 (surrogate) drawn from ``fig09_euler_angles.csv`` alone."""
    return _draw_ranges(
        frame, path, ("alpha", "beta", "gamma"), " (°)", "Fig. 9, SURROGATE: Euler angles"
    )


@drawn_figures(
    "adams",
    [
        ("fig05_cm_velocity.png", "fig05_cm_velocity.csv", draw_cm_velocity),
        ("fig06_cm_position.png", "fig06_cm_position.csv", draw_cm_position),
        ("fig09_euler_angles.png", "fig09_euler_angles.csv", draw_euler_angles),
    ],
    "extra_adams_trajectory.csv",
    *table_files("extra_adams_surrogate"),
    config=[KEY],
    tolerance=ROUNDING,
)
def adams_artefact(config: dict, outdir: Path) -> list[Path]:
    """Surrogate of the Adams study (Figs 5-11; drive mapping unknown, docs/li2017_stewart36.md#s5): a pose trajectory whose
    coordinates oscillate inside the stated ranges (periods 10, 6.67, 20 s from eq. 10: X and alpha
    with 10 s, Y and beta 6.67 s, Z and gamma 20 s), IK -> leg lengths -> FK by warm-started Newton ->
    recovered CM position, velocity (central differences) and Euler angles."""
    a = cfg(config)["adams"]
    m = mech(config)
    rngs = adams_ranges()
    t = np.linspace(0, float(a["t_end"]), int(a["samples"]))
    periods = {"X": 10.0, "alpha": 10.0, "Y": 20 / 3, "beta": 20 / 3, "Z": 20.0, "gamma": 20.0}
    traj = np.stack(
        [
            (rngs[c][0] + rngs[c][1]) / 2
            + (rngs[c][1] - rngs[c][0]) / 2 * np.sin(2 * np.pi * t / periods[c])
            for c in POSE_COLS
        ],
        axis=-1,
    )
    truth = pose_from_paper(traj)
    legs = m.ik(truth)
    x = truth[0] + 1e-3
    rec = np.empty_like(truth)
    for k in range(len(t)):
        r = solve_fk(m, legs[k], x0=x, method="newton", tol=1e-13, maxiter=30)
        rec[k] = x = r.x
    err = np.max(np.abs(rec - truth))
    deg = pose_to_paper(rec)
    vel = np.gradient(rec[:, 3:], t, axis=0)
    df = pd.DataFrame(
        {
            "t_s": t,
            **{c: deg[:, i] for i, c in enumerate(POSE_COLS)},
            "VX": vel[:, 0],
            "VY": vel[:, 1],
            "VZ": vel[:, 2],
            **{f"L{i + 1}": legs[:, i] for i in range(6)},
        }
    )
    paths = write_and_draw(
        df[["t_s", "VX", "VY", "VZ"]], outdir / "fig05_cm_velocity.csv", draw_cm_velocity
    )
    for stem, cols, draw in (
        ("fig06_cm_position", ("X", "Y", "Z"), draw_cm_position),
        ("fig09_euler_angles", ("alpha", "beta", "gamma"), draw_euler_angles),
    ):
        fig_df = df[["t_s", *cols]].copy()
        for c in cols:  # the ranges the paper states, drawn as bands
            fig_df[f"{c}_stated_min"], fig_df[f"{c}_stated_max"] = rngs[c]
        paths += write_and_draw(fig_df, outdir / f"{stem}.csv", draw)
    paths.append(write_csv(df, outdir / "extra_adams_trajectory.csv"))
    summ = pd.DataFrame(
        [
            {
                "quantity": c,
                "stated_min": rngs[c][0],
                "stated_max": rngs[c][1],
                "ours_min": df[c].min(),
                "ours_max": df[c].max(),
            }
            for c in POSE_COLS
        ]
        + [{"quantity": "max_roundtrip_error", "ours_max": err}]
    )
    return paths + write_table(
        summ,
        outdir / "extra_adams_surrogate",
        floatfmt=".6g",
        title="Surrogate of the Adams study (drive mapping unknown; docs/li2017_stewart36.md#s5)",
        notes="A pose trajectory inside the stated ranges by construction, recovered by "
        "warm-started Newton FK from its leg lengths; the check is the round trip.",
    )


def _counts_b_claims(c: pd.DataFrame, ref: pd.DataFrame) -> list[Claim]:
    """Table 3's solution count against the certified FK of the reconstructed input, per b."""
    return [
        Claim(
            KEY,
            "table3",
            "n_solutions",
            printed_value(ref, "table3", "n_solutions"),
            float(c["above_base"].max()),
            "1",
            variant="certified FK: max above-base solutions over the b sweep",
            evidence=f"{KEY}/extra_solution_counts_b.md",
            reason=f"the FK is a degree-16 polynomial (16 complex roots in mirror pairs, so <= 8 above the "
            f"base); we find {', '.join(f'{int(r.real)} real / {int(r.above_base)} above (b = {r.b:g})' for r in c.itertuples())}. "
            "Table 3's rows are not solutions of one input (see table3.csv residuals) and 3 are duplicates",
        )
    ]


def _counts_claims(c: pd.DataFrame, ref: pd.DataFrame) -> list[Claim]:
    """Table 3's solution count against the most solutions over random inputs."""
    out: list[Claim] = []
    for col, what in (("max_above_base", "above-base"), ("max_real", "real")):
        r = c.loc[c[col].idxmax()]
        out.append(
            Claim(
                KEY,
                "table3",
                "n_solutions",
                printed_value(ref, "table3", "n_solutions"),
                float(r[col]),
                "1",
                variant=f"certified FK: most {what} solutions over {int(c['samples'].sum())} random inputs "
                f"(b = {', '.join(f'{v:g}' for v in c['b'])})",
                evidence=f"{KEY}/extra_solution_counts.md",
                reason="the polynomial has degree 16, so no input has more than 16 real or 8 above-base "
                f"solutions; the paper's {printed_value(ref, 'table3', 'n_solutions')} (all above the base) "
                "cannot be distinct solutions of one input",
            )
        )
    return out


def _table3_claims(
    t: pd.DataFrame, sols: pd.DataFrame, whole: pd.DataFrame, ref: pd.DataFrame
) -> list[Claim]:
    """Table 3 row by row, and §4's claim that its rows lie inside the centre's ranges."""
    whole = whole.set_index("row")
    sols = sols[sols["above_base"].astype(bool)].reset_index(drop=True)
    outside = int((~t["inside_sec4_ranges"].astype(bool)).sum())
    return _table3_row_claims(t, sols, whole, ref) + [
        Claim(
            KEY,
            "sec4",
            "table3_rows_outside_ranges",
            printed_value(ref, "sec4", "table3_rows_outside_ranges"),
            float(outside),
            "1",
            variant="the paper's Table 3 against its own §4 ranges",
            evidence=f"{KEY}/table3.md",
            reason=f"rows outside: {', '.join(str(r) for r in t.loc[~t['inside_sec4_ranges'].astype(bool), 'row'])} "
            "(alpha > 80 deg or X < -0.30): the paper contradicts itself (paper against paper, "
            "no computation of ours)",
        )
    ]


def claims(figdir: Path, ref: pd.DataFrame) -> list[Claim]:
    """Table 3 row by row against the certified solution set, the solution count, and §4's claim that
    every Table 3 row lies inside the centre's ranges. The Adams surrogate (extra_adams_*) is an
    illustration of the drive law, inside the ranges by construction: it judges nothing, and the
    ranges themselves (Figs 6-11 of an Adams run whose drive mapping is lost) are not comparable."""
    return table_claims(
        figdir,
        {
            "extra_solution_counts_b.csv": lambda c: _counts_b_claims(c, ref),
            "extra_solution_counts.csv": lambda c: _counts_claims(c, ref),
            ("table3.csv", "extra_solutions.csv", "extra_table3_rows.csv"): lambda t, sols, whole: (
                _table3_claims(t, sols, whole, ref)
            ),
        },
    )


def _table3_row_claims(
    t: pd.DataFrame, sols: pd.DataFrame, whole: pd.DataFrame, ref: pd.DataFrame
) -> list[Claim]:
    """Each coordinate of Table 3 against the nearest certified above-base solution; rows 2-19
    judged as wholes (``whole``: extra_table3_rows), row 1 a solution by construction."""
    out: list[Claim] = []
    fcols = [col for col in t.columns if col.startswith("F_b")]
    scale = np.array(
        [np.pi / 180] * 3 + [1.0] * 3
    )  # angles compared in radians, positions as they are
    for _, r in t.iterrows():
        row = int(r["row"])
        p = r[list(POSE_COLS)].to_numpy(float)
        k = int(
            np.argmin(np.sum(((sols[list(POSE_COLS)].to_numpy(float) - p) * scale) ** 2, axis=1))
        )
        near = sols.iloc[k]
        j = int(np.argmin([r[col] for col in fcols]))
        leg = float(r[f"max_leg_err_b{fcols[j][3:]}"])
        note = f"; {r['note']}" if isinstance(r["note"], str) and r["note"] else ""
        for q in POSE_COLS:
            quantity = f"row{row}.{q}"
            unit = "deg" if q in ("alpha", "beta", "gamma") else "1"
            claim = partial(
                Claim,
                KEY,
                "table3",
                quantity,
                printed_value(ref, "table3", quantity),
                float(near[q]),
                unit,
            )
            if row == 1:
                out.append(
                    claim(
                        variant=f"certified FK solution of L = IK(row 1) (b = {near['b']:g})",
                        basis="the lost FK input is reconstructed as IK(row 1) (docs/li2017_stewart36.md#g1), "
                        "so row 1 is a solution by construction",
                    )
                )
                continue
            w = whole.loc[row]
            lowest = (
                f"{w['min_mismatch']:.3g} (at b = {w['at_b']:g}; printing allows "
                f"{w['rounding_allowance_there']:.2g} there)"
                if str(w.get("minimum_at_sweep_end", "")) != "b -> 0"
                else f"{float(w['limit_b_to_0']):.3g} (its mismatch falls all the way to b -> 0, a "
                f"base shrunk to a point: that limit is its minimum over b > 0; "
                f"{w['min_mismatch']:.3g} at the sweep's smallest b = {w['at_b']:g}, where printing "
                f"allows {w['rounding_allowance_there']:.2g})"
            )
            out.append(
                claim(
                    variant=f"nearest certified above-base solution over the b sweep (b = {near['b']:g}, "
                    f"solution {int(near['solution'])}); the row judged as a whole",
                    whole_agrees=bool(w["within_rounding_for_some_b"]),
                    evidence=f"{KEY}/extra_table3_rows.md",
                    reason=f"judged as a whole, row {row} must have row 1's six leg lengths: for every b of "
                    f"the fine sweep a leg is off by at least {lowest}; under the reconstructed "
                    f"input F (eq. 4) >= {float(r[fcols[j]]):.2g}, a leg off by {leg:.3g}; no "
                    "layout/Euler reading tried makes the 19 rows solutions of one input "
                    f"(docs/li2017_stewart36.md#s4.2){note}",
                )
            )
    return out


def _counts_b_sentence(c: pd.DataFrame, ref: pd.DataFrame) -> str:
    """The certified all-solutions FK of the reconstructed input, per base side b."""
    return (
        "Certified all-solutions FK of the reconstructed input: "
        + "; ".join(
            f"b = {r.b:g}: {int(r.complex_roots)} complex, {int(r.real)} real, {int(r.above_base)} above the base "
            f"({r.wall_time_ms:.2g} ms)"
            for r in c.itertuples()
        )
        + f". The paper lists {printed_value(ref, 'table3', 'n_solutions')} 'solutions', all above the base."
    )


def _table3_sentence(t: pd.DataFrame) -> str:
    """Table 3's rows 2-19 under the lengths of row 1."""
    return (
        "Table 3 rows 2-19 under L = IK(row 1): F (eq. 4) from "
        + "; ".join(
            f"{col[2:]}: {t[col].iloc[1:].min():.2g}…{t[col].iloc[1:].max():.2g}"
            for col in t.columns
            if col.startswith("F_b")
        )
        + f" (a solution has F ~ 1e-30); {int((~t['inside_sec4_ranges'].astype(bool)).sum())} of 19 rows lie outside the §4 ranges."
    )


def _counts_sentence(c: pd.DataFrame) -> str:
    """The real solutions over random inputs, per base side b."""
    cols = [col for col in c.columns if col.startswith("real_")]
    return (
        "Real solutions over random inputs: "
        + "; ".join(
            f"b = {r['b']:g}: "
            + ", ".join(f"{col[5:]}: {int(r[col])}" for col in cols if r[col])
            + f" (no circles: {int(r['no_circles'])}; max above base {int(r['max_above_base'])}; "
            f"{r['wall_time_ms_per_input']:.2g} ms/input)"
            for _, r in c.iterrows()
        )
        + "."
    )


def summary(figdir: Path, ref: pd.DataFrame) -> str:
    return table_text(
        figdir,
        {
            "extra_solution_counts_b.csv": lambda c: _counts_b_sentence(c, ref),
            "table3.csv": _table3_sentence,
            "extra_solution_counts.csv": _counts_sentence,
            "extra_adams_surrogate.csv": lambda s: (
                "Adams surrogate: round-trip error of the warm-started Newton FK "
                f"{s.set_index('quantity').loc['max_roundtrip_error', 'ours_max']:.2g}."
            ),
        },
    )
