"""Beyond the papers: every forward solution of the general 6-6 Gough-Stewart platform.

A study registered like a paper (:mod:`parakin.registry`; config section ``stewart66``; the
method: ``docs/stewart66.md``). Three ``data(config) -> DataFrame`` / ``draw(frame, path)`` pairs,
each declared as a figure artefact at the end of this module:

* :func:`assemblies_data` / :func:`assemblies_draw`: the 40 real assemblies of Dietmaier's platform
  (certified, checked by the IK), one small 3-D drawing each;
* :func:`real_counts_data` / :func:`real_counts_draw`: over random platforms and poses, how many of
  the 40 complex solutions were found (certified), how many are real (histogram);
* :func:`timing_data` / :func:`timing_draw`: all 40 solutions per input, single call and batched,
  against a batched Newton from 40 random starts (the project's fastest local solver).

``config`` keys (all optional): ``seed`` (int), ``n_platforms`` (random geometries, one pose each),
``n_poses`` (random poses on Dietmaier's platform), ``n_timing`` (inputs of the batched timing).
Timing columns end in ``_s`` / ``_per_s`` and never decide anything.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from parakin.mechanisms.stewart66 import (
    DIETMAIER_LENGTHS,
    Stewart66,
    random_platform,
    random_pose,
)
from parakin.timing import one_thread

__all__ = [
    "assemblies_data",
    "assemblies_draw",
    "real_counts_data",
    "real_counts_draw",
    "timing_data",
    "timing_draw",
    "random_platform",
    "random_pose",
]

DEFAULTS: dict[str, Any] = {"seed": 66, "n_platforms": 50, "n_poses": 200, "n_timing": 200}


def _cfg(config: dict | None) -> dict[str, Any]:
    return {**DEFAULTS, **(config or {})}


# ------------------------------------------------------------------------------------ assemblies
def assemblies_data(config: dict | None = None) -> pd.DataFrame:
    """Dietmaier's 40 real assemblies: one row each (solution index, pose, alpha, IK error)."""
    m = Stewart66()
    r = m.fk_all(DIETMAIER_LENGTHS, return_info=True)
    rows = []
    k = 0
    for j in range(r.poses.shape[0]):
        p = r.poses[j]
        if not np.all(np.isfinite(p)):
            continue
        k += 1
        err = float(np.max(np.abs(m.ik(p) - np.asarray(DIETMAIER_LENGTHS))))
        rows.append({"solution": k, **dict(zip(m.pose_names, p.tolist())), "ik_error": err})
    df = pd.DataFrame(rows)
    df.attrs.update(
        n_found=int(r.n_found),
        n_real=int(r.n_real),
        complete=bool(r.complete),
        alpha_max=float(np.nanmax(r.alpha)),
    )
    return df


def assemblies_draw(frame: pd.DataFrame, path: str | Path) -> Path:
    """All real assemblies side by side, 8 a row, in one common 3-D view (orthographic, the same
    elevation, azimuth and scale in every panel, a metre as long on every axis): base and platform
    outlines, the six legs and the world axes (0.5 m arrows at the base origin)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from parakin.plot import DPI, save_figure, use_style

    m = Stewart66()
    poses = frame[list(m.pose_names)].to_numpy(dtype=float)
    tops = m.platform_world(poses).reshape(len(frame), 6, 3)
    b = m.base_points
    pts = np.concatenate([tops.reshape(-1, 3), b, np.zeros((1, 3)), np.eye(3) * AXIS_M])
    lo, hi = pts.min(0), pts.max(0)
    cols, cell = 8, 1.55
    rows = max(1, int(np.ceil(len(frame) / cols)))
    head, foot = 0.55, 0.35  # inches: title, legend
    with use_style():
        fig = Figure(figsize=(cols * cell, rows * cell + head + foot), dpi=DPI)
        FigureCanvasAgg(fig)
        w, h = 1 / cols, cell / fig.get_figheight()
        for i, (top, sol) in enumerate(zip(tops, frame["solution"])):
            r, c = divmod(i, cols)
            y0 = 1 - head / fig.get_figheight() - (r + 1) * h
            ax = fig.add_axes((c * w, y0, w, h), projection="3d", proj_type="ortho")
            ax.view_init(elev=VIEW[0], azim=VIEW[1])
            for k in range(6):
                ax.plot(*np.stack([b[k], top[k]]).T, color="0.1", lw=0.9)
            for poly, colour in ((b, "0.35"), (top, "tab:red")):
                ax.add_collection3d(
                    Poly3DCollection([poly], facecolor=colour, edgecolor=colour, alpha=0.25, lw=0.8)
                )
            for axis, colour in zip(np.eye(3) * AXIS_M, ("#D55E00", "#009E73", "#0072B2")):
                ax.quiver(0, 0, 0, *axis, color=colour, lw=0.8, arrow_length_ratio=0.25)
            ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]))
            ax.set_box_aspect(hi - lo, zoom=1.35)
            ax.set_axis_off()
            ax.text2D(0.04, 0.9, f"{int(sol)}", transform=ax.transAxes, fontsize=8)
        fig.suptitle(
            f"Beyond the papers: Dietmaier's 6-6 platform, all {len(frame)} real assemblies of one "
            "set of leg lengths (certified, IK-checked)\n"
            f"one view for all: orthographic, elevation {VIEW[0]:g}°, azimuth {VIEW[1]:g}°, "
            f"the same scale in every panel (box {hi[0] - lo[0]:.2f} x {hi[1] - lo[1]:.2f} x "
            f"{hi[2] - lo[2]:.2f} m)",
            fontsize=10,
            y=1 - 0.05 / fig.get_figheight(),
            va="top",
        )
        handles = [
            Line2D([], [], color="0.35", lw=4, alpha=0.5, label="base"),
            Line2D([], [], color="tab:red", lw=4, alpha=0.5, label="platform"),
            Line2D([], [], color="0.1", lw=1, label="legs"),
            *[
                Line2D([], [], color=colour, lw=1, label=f"world {name} ({AXIS_M:g} m)")
                for name, colour in zip("xyz", ("#D55E00", "#009E73", "#0072B2"))
            ],
        ]
        fig.legend(handles=handles, loc="lower center", ncols=6, fontsize=8, frameon=False)
    return save_figure(fig, path, tag=False)


#: the common view of :func:`assemblies_draw`: (elevation, azimuth) in degrees
VIEW = (18.0, -58.0)
#: length of the world axes drawn in every panel (m)
AXIS_M = 0.5


# ------------------------------------------------------------------------------------ real counts
def real_counts_data(config: dict | None = None) -> pd.DataFrame:
    """Random platforms (one random pose each) and random poses of Dietmaier's platform: per input
    the geometry's root count, solutions found (certified, distinct), completeness, real count,
    IK error, tracking steps, retries. Column ``set`` is ``random platform`` or ``Dietmaier``."""
    c = _cfg(config)
    rng = np.random.default_rng(c["seed"])
    rows = []
    Stewart66().fk_all(DIETMAIER_LENGTHS)  # warm-up: the compiled kernel loaded outside wall_s
    for i in range(int(c["n_platforms"])):
        m = random_platform(rng)
        pose = random_pose(rng, 1, m)
        t0 = time.perf_counter()
        r = m.fk_all(m.ik(pose), return_info=True)
        wall = time.perf_counter() - t0
        rows.append(
            {
                "set": "random platform",
                "index": i,
                "root_count": m.root_count,
                "n_found": int(r.n_found[0]),
                "complete": bool(r.complete[0]),
                "n_real": int(r.n_real[0]),
                "ik_error": float(r.ik_error[0]),
                "steps": int(r.steps[0]),
                "retries": int(r.retries[0]),
                "wall_s": wall,
            }
        )
    m = Stewart66()
    poses = random_pose(rng, int(c["n_poses"]), m)
    r = m.fk_all(m.ik(poses), return_info=True)
    for i in range(len(poses)):
        rows.append(
            {
                "set": "Dietmaier",
                "index": i,
                "root_count": m.root_count,
                "n_found": int(r.n_found[i]),
                "complete": bool(r.complete[i]),
                "n_real": int(r.n_real[i]),
                "ik_error": float(r.ik_error[i]),
                "steps": int(r.steps[i]),
                "retries": int(r.retries[i]),
                "wall_s": np.nan,
            }
        )
    return pd.DataFrame(rows)


def real_counts_draw(frame: pd.DataFrame, path: str | Path) -> Path:
    """Histogram of real-solution counts (even numbers 0..40), one bar series per set."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.4, 3.6), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    bins = np.arange(0, 42, 2)
    sets = list(dict.fromkeys(frame["set"]))
    width = 1.8 / max(1, len(sets))
    for k, s in enumerate(sets):
        counts = np.array([(frame.loc[frame["set"] == s, "n_real"] == b).sum() for b in bins])
        ax.bar(
            bins - 0.9 + width * (k + 0.5),
            counts,
            width=width,
            label=f"{s} (n = {(frame['set'] == s).sum()})",
        )
    comp = frame["complete"].mean() * 100
    ax.set_xlabel("real forward solutions (of 40 complex)")
    ax.set_ylabel("inputs")
    ax.set_xticks(bins[::2])
    ax.set_title(
        f"Beyond the papers: 6-6 Gough-Stewart, real solutions per input\n({comp:.1f} % of inputs complete)"
    )
    ax.legend(fontsize=8)
    path = Path(path)
    fig.savefig(path)
    return path


# ------------------------------------------------------------------------------------ timing
def timing_data(config: dict | None = None) -> pd.DataFrame:
    """Wall time of all solutions per input: ``fk_all`` one input per call on one thread (median of
    up to 20), ``fk_all`` on a batch of ``n_timing`` inputs (the compiled kernel's threads), and
    batched Newton (``solve_fk``) from 40 random starts per input (starts uniform in
    :meth:`Stewart66.pose_bounds`), with the distinct real solutions each finds."""
    from parakin.solvers import solve_fk

    c = _cfg(config)
    rng = np.random.default_rng(c["seed"] + 1)
    m = Stewart66()
    _ = m.root_count  # build the geometry's start system outside the timings
    n = int(c["n_timing"])
    q = m.ik(random_pose(rng, n, m))
    rows = []
    single = []
    m.fk_all(q[0])  # warm-up: the compiled kernel loaded
    with one_thread():
        for i in range(min(n, 20)):
            t0 = time.perf_counter()
            r1 = m.fk_all(q[i], return_info=True)
            single.append(time.perf_counter() - t0)
    rows.append(
        {
            "method": "fk_all, one input per call (1 thread)",
            "inputs": 1,
            "per_input_s": float(np.median(single)),
            "inputs_per_s": 1 / float(np.median(single)),
            "complete_rate": 1.0 * bool(r1.complete),
            "mean_real_found": float(r1.n_real),
        }
    )
    t0 = time.perf_counter()
    r = m.fk_all(q, return_info=True)
    wall = time.perf_counter() - t0
    rows.append(
        {
            "method": "fk_all, batched",
            "inputs": n,
            "per_input_s": wall / n,
            "inputs_per_s": n / wall,
            "complete_rate": float(r.complete.mean()),
            "mean_real_found": float(r.n_real.mean()),
        }
    )
    lo, hi = m.pose_bounds()
    starts = rng.uniform(lo, hi, (n, 40, 6))
    t0 = time.perf_counter()
    res = solve_fk(
        m,
        np.broadcast_to(q[:, None], (n, 40, 6)),
        x0=starts,
        method="newton",
        tol=1e-10,
        maxiter=50,
    )
    wall_n = time.perf_counter() - t0
    found = []
    for i in range(n):
        x = res.x[i][res.success[i]]
        found.append(_count_distinct(m, x))
    rows.append(
        {
            "method": "Newton from 40 random starts, batched",
            "inputs": n,
            "per_input_s": wall_n / n,
            "inputs_per_s": n / wall_n,
            "complete_rate": np.nan,
            "mean_real_found": float(np.mean(found)),
        }
    )
    df = pd.DataFrame(rows)
    df["x_newton_time"] = df["per_input_s"] / (wall_n / n)
    return df


def _count_distinct(m: Stewart66, x: np.ndarray) -> int:
    if not len(x):
        return 0
    rot = m.rotation(x).reshape(len(x), 9)
    key = np.concatenate([rot, x[:, 3:]], -1)
    d = np.max(np.abs(key[:, None] - key[None]), -1)
    keep = [0]
    for i in range(1, len(x)):
        if np.all(d[i, keep] > 1e-6):
            keep.append(i)
    return len(keep)


def timing_draw(frame: pd.DataFrame, path: str | Path) -> Path:
    """Bar chart: inputs per second of each method, annotated with the real solutions found."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.ticker import NullFormatter

    fig = Figure(figsize=(6.4, 3.2), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    y = np.arange(len(frame))
    ax.barh(y, frame["inputs_per_s"])
    ax.set_yticks(y, frame["method"], fontsize=8)
    ax.set_xscale("log")
    ax.xaxis.set_minor_formatter(NullFormatter())  # under a decade, minor labels would collide
    ax.set_xlim(right=3 * float(frame["inputs_per_s"].max()))  # room for the bars' notes
    ax.set_xlabel("inputs per second (all solutions of each input)")
    fig.suptitle(
        "Beyond the papers: 6-6 Gough-Stewart, all solutions per input\n(timings of one machine)",
        fontsize=10,
    )
    for yi, (_, r) in zip(y, frame.iterrows()):
        ax.text(
            r["inputs_per_s"],
            yi,
            f"  {r['mean_real_found']:.1f} real found",
            va="center",
            fontsize=8,
        )
    path = Path(path)
    fig.savefig(path)
    return path


# ------------------------------------------------------------------------------------ artefacts
KEY = "stewart66"


def _section(config: dict) -> dict[str, Any]:
    """The study's config section with its seed (derived from the master seed)."""
    from parakin.config import seed_for

    return {**config[KEY], "seed": seed_for(config, KEY) % 2**32}


def assemblies(config: dict) -> pd.DataFrame:
    """Dietmaier's 40 real assemblies (certified, IK-checked)."""
    return assemblies_data(_section(config))


def real_counts(config: dict) -> pd.DataFrame:
    """Found, complete and real solution counts over random platforms and poses."""
    return real_counts_data(_section(config))


def timing(config: dict) -> pd.DataFrame:
    """All 40 solutions per input against batched Newton from 40 random starts."""
    return timing_data(_section(config))


def _declare():
    from parakin.registry import ROUNDING, TIMING, Tolerance, figure

    #: path tracking: the root count, the solutions found and the real ones are properties of the
    #: input (stable), the steps and retries of a path tracker move with rounding (not compared)
    counts = Tolerance.statistical(
        "all-solutions counts per input are properties of the input: compared exactly; "
        "tracking steps and retries move with rounding (not compared); IK error to 1e-9",
        columns={
            **Tolerance.exactly("index", "root_count", "n_found", "n_real"),
            "ik_error": (0.0, 1e-9),
        },
    )
    common = {"config": [KEY], "reference": False}
    figure(
        KEY,
        "assemblies",
        "extra_dietmaier_assemblies",
        assemblies,
        assemblies_draw,
        tolerance=ROUNDING.but("certified roots refined by Newton to machine precision"),
        **common,
    )
    figure(
        KEY,
        "real_counts",
        "extra_real_counts",
        real_counts,
        real_counts_draw,
        tolerance=counts,
        **common,
    )
    figure(KEY, "timing", "extra_fk_all_timing", timing, timing_draw, tolerance=TIMING, **common)


_declare()
