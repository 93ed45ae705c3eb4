"""Beyond the papers: a census of the real assemblies of the general 6-6 Gough-Stewart platform.

Of the 40 complex forward solutions of a general 6-6 platform, how many are real, over many random
platforms and leg lengths? The inputs (config section ``stewart66_census``; method and the
comparison with the literature: ``docs/census.md``):

* ``platforms`` random geometries, the six base and the six platform anchors independent standard
  normal points in 3-D (:func:`parakin.studies.stewart66.random_platform`);
* ``inputs_per_platform`` leg-length sets per geometry, each the IK of a random pose: orientation
  uniform on SO(3) (Haar), origin normal about the platform's home with standard deviation
  ``offset`` x the platform's size (:func:`parakin.studies.stewart66.random_pose` with
  ``offset = 1``). Every input therefore has at least one real assembly (the pose it came from).

Every input is solved by :meth:`Stewart66.fk_all` (all 40 solutions, certified). Platform ``i``
draws from its own stream ``default_rng([seed, i])``, so the census does not depend on how it is
cut: the pipeline splits the platforms into ``chunks`` contiguous ranges, each its own Snakemake
job and file (scatter, ``workflow/rules/census.smk``); :func:`census_data` gathers them, computing
any chunk that is missing (a resumed run loses nothing a finished chunk wrote).
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from parakin.mechanisms.stewart66 import Stewart66, fk_all_geometries

__all__ = [
    "chunk_name",
    "chunk_platforms",
    "chunk_data",
    "write_chunk",
    "census_data",
    "census_draw",
    "chunk_files",
    "main",
    "KEY",
]

KEY = "stewart66_census"
#: the most real solutions an input can have (the complex root count of the general 6-6)
ROOTS = 40
COUNT_COLUMNS = [f"real_{k}" for k in range(ROOTS + 1)]


def chunk_name(i: int, n: int) -> str:
    """File name of chunk ``i`` (1-based) of ``n``: Snakemake's scatter item ``"{i}-of-{n}"``."""
    return f"{i}-of-{n}.csv"


def chunk_platforms(section: dict[str, Any], i: int) -> range:
    """The platform indices of chunk ``i`` (1-based) of ``section['chunks']``: contiguous, sizes
    differing by one at most."""
    n, p = int(section["chunks"]), int(section["platforms"])
    if not 1 <= i <= n:
        raise ValueError(f"census chunk {i} is outside 1..{n} (stewart66_census.chunks)")
    return range((i - 1) * p // n, i * p // n)


def _platform(seed: int, index: int, section: dict[str, Any]) -> tuple[Stewart66, np.ndarray]:
    """Platform ``index`` of the census and the leg lengths of its inputs (its own random stream)."""
    from parakin.mechanisms.stewart66 import random_platform, random_pose

    rng = np.random.default_rng([seed, index])
    mech = random_platform(rng)
    poses = random_pose(rng, int(section["inputs_per_platform"]), mech)
    if float(section["offset"]) != 1.0:  # random_pose draws the origin with sd = size
        home = mech.home()[3:]
        poses[:, 3:] = home + (poses[:, 3:] - home) * float(section["offset"])
    return mech, mech.ik(poses)


def platform_row(seed: int, index: int, section: dict[str, Any]) -> dict[str, Any]:
    """One platform's census: its root count, how many inputs were solved completely, how many
    complete inputs have a solution whose reality the certificate left undecided (``undecided``,
    kept out of the histogram), how many of the other complete inputs have k real solutions
    (``real_k``), plus incomplete inputs by real count found."""
    t0 = time.perf_counter()
    mech, legs = _platform(seed, index, section)
    r = mech.fk_all(legs, return_info=True)
    return _row(index, len(legs), r, time.perf_counter() - t0)


def _row(index: int, inputs: int, r, wall: float) -> dict[str, Any]:
    """A platform's row from its inputs' :class:`parakin.mechanisms.stewart66.FKAll` (batch
    shape ``(inputs,)``); ``root_count`` the count a complete input has (40: the layouts are
    general)."""
    real = np.asarray(r.n_real).reshape(-1)
    undecided = np.asarray(r.n_undecided).reshape(-1) > 0
    done = np.asarray(r.complete).reshape(-1)
    # an input enters the histogram when complete and every solution's reality is decided
    counts = np.bincount(real[done & ~undecided], minlength=ROOTS + 1)
    return {
        "platform": index,
        "root_count": int(r.n_expected),
        "inputs": inputs,
        "complete": int(done.sum()),
        "undecided": int((done & undecided).sum()),
        "incomplete_real_found": int(real[~done].sum()),
        "max_real": int(real.max()),
        **dict(zip(COUNT_COLUMNS, counts.tolist())),
        "wall_s": wall,
    }


#: platforms with at most this many inputs are solved together, every input from the stored
#: generic start in one homotopy (:func:`parakin.mechanisms.stewart66.fk_all_geometries`); a
#: platform with more inputs first moves that start to its own geometry by the same homotopy
#: (its start system, about the cost of one such input) and then takes each input along its
#: fibre, about five times shorter (docs/census.md)
SHARED_START_INPUTS = 1


def chunk_data(section: dict[str, Any], i: int) -> pd.DataFrame:
    """Chunk ``i`` (1-based) of the census: one row per platform (:func:`platform_row`); with at
    most :data:`SHARED_START_INPUTS` inputs per platform, the chunk's inputs in one batch on the
    new-geometry path (each row then carries an equal share of the batch's wall time)."""
    seed = int(section["seed"])
    platforms = chunk_platforms(section, i)
    if int(section["inputs_per_platform"]) > SHARED_START_INPUTS:
        return pd.DataFrame([platform_row(seed, k, section) for k in platforms])
    t0 = time.perf_counter()
    drawn = [_platform(seed, k, section) for k in platforms]
    r = fk_all_geometries(
        np.concatenate([np.broadcast_to(m.base_points, (len(q), 6, 3)) for m, q in drawn]),
        np.concatenate([np.broadcast_to(m.platform_points, (len(q), 6, 3)) for m, q in drawn]),
        np.concatenate([q for _, q in drawn]),
    )
    wall = (time.perf_counter() - t0) / max(1, len(drawn))
    rows, start = [], 0
    for k, (_, q) in zip(platforms, drawn):
        part = slice(start, start + len(q))
        start += len(q)
        sub = {f.name: getattr(r, f.name) for f in dataclasses.fields(r)}
        sub = {f: (v[part] if isinstance(v, np.ndarray) else v) for f, v in sub.items()}
        rows.append(_row(k, len(q), type(r)(**sub), wall))
    return pd.DataFrame(rows)


def write_chunk(config: dict, i: int, path: str | Path) -> Path:
    """Compute chunk ``i`` of the census of ``config`` and write it (atomically) to ``path``."""
    from parakin.io import write_csv

    return write_csv(chunk_data(_section(config), i), Path(path))


def chunk_folder(config: dict) -> Path:
    """Where the chunks of the census live: the generated-data folder of the study."""
    return Path(config["generated_dir"]) / KEY


def chunk_files(config: dict) -> list[str]:
    """Every chunk file of the census (the inputs of the gather step, in order)."""
    n = int(config[KEY]["chunks"])
    return [str(chunk_folder(config) / chunk_name(i, n)) for i in range(1, n + 1)]


def _section(config: dict) -> dict[str, Any]:
    """The study's config section with its seed (derived from the master seed)."""
    from parakin.config import seed_for

    section = config[KEY]
    if int(section["chunks"]) > int(section["platforms"]):
        raise ValueError(
            f"stewart66_census.chunks = {section['chunks']} must be <= platforms = "
            f"{section['platforms']} (a chunk holds at least one platform)"
        )
    return {**section, "seed": seed_for(config, KEY) % 2**32}


# ------------------------------------------------------------------------------------ gather
def _gather(config: dict) -> pd.DataFrame:
    """Every platform row: the chunk files that exist (checked to cover their platforms), the
    missing ones computed and written (resume)."""
    section = _section(config)
    frames = []
    for i, path in enumerate(chunk_files(config), start=1):
        path = Path(path)
        expected = list(chunk_platforms(section, i))
        frame = pd.read_csv(path) if path.exists() else None
        if frame is None or frame["platform"].tolist() != expected:
            path.parent.mkdir(parents=True, exist_ok=True)
            frame = pd.read_csv(write_chunk(config, i, path))
        frames.append(frame)
    return pd.concat(frames, ignore_index=True)


def census_data(config: dict) -> pd.DataFrame:
    """Real forward solutions of the general 6-6 platform over random platforms and leg lengths:
    complete inputs per real count (0..40), their parity, and platforms by their largest count;
    complete inputs with an undecided solution (``undecided_inputs``) are counted apart."""
    rows = _gather(config)
    counts = rows[COUNT_COLUMNS].to_numpy()
    complete = counts.sum(axis=0)
    peak = np.bincount(rows["max_real"], minlength=ROOTS + 1)
    k = np.arange(ROOTS + 1)
    low, high = share_intervals(counts, _section(config)["seed"])
    return pd.DataFrame(
        {
            "real_solutions": k,
            "parity": np.where(k % 2, "odd", "even"),
            "complete_inputs": complete,
            "fraction": complete / max(1, complete.sum()),
            "fraction_low": low,
            "fraction_high": high,
            "platforms_with_max": peak,
            "incomplete_inputs": np.where(
                k == 0, int((rows["inputs"] - rows["complete"]).sum()), 0
            ),
            "undecided_inputs": np.where(k == 0, int(rows["undecided"].sum()), 0),
            "platforms": np.where(k == 0, len(rows), 0),
            "inputs_per_s": np.where(k == 0, rows["inputs"].sum() / rows["wall_s"].sum(), np.nan),
        }
    )


#: bootstrap resamples of the platforms behind each share's interval, and its coverage
RESAMPLES, COVERAGE = 2000, 0.95


def share_intervals(counts: np.ndarray, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The 95 % interval of each real count's share of the complete inputs, by a bootstrap over the
    platforms (``counts``: one row per platform, one column per real count): the inputs of one
    platform are not independent draws (its geometry favours some counts), so the platforms are
    what is resampled; percentile interval of :data:`RESAMPLES` resamples, seeded from the
    study's seed (integer counts: the same bounds on every machine)."""
    rng = np.random.default_rng([seed, RESAMPLES])
    picks = rng.integers(0, len(counts), size=(RESAMPLES, len(counts)))
    totals = np.stack([counts[p].sum(axis=0) for p in picks])  # (RESAMPLES, ROOTS + 1)
    shares = totals / np.maximum(totals.sum(axis=1, keepdims=True), 1)
    tail = (1 - COVERAGE) / 2
    return np.quantile(shares, tail, axis=0), np.quantile(shares, 1 - tail, axis=0)


def census_draw(frame: pd.DataFrame, path: str | Path) -> Path:
    """(a) complete inputs by number of real solutions, even and odd counts apart (log scale);
    (b) platforms by the largest real count among their inputs."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator

    from parakin.plot import DPI, save_figure, use_style

    k = frame["real_solutions"].to_numpy()
    n = frame["complete_inputs"].to_numpy()
    total, incomplete = int(n.sum()), int(frame["incomplete_inputs"].sum())
    undecided = int(frame["undecided_inputs"].sum()) if "undecided_inputs" in frame else 0
    odd = k % 2 == 1
    with use_style():
        fig = Figure(figsize=(7.0, 5.2), dpi=DPI, layout="constrained")
        FigureCanvasAgg(fig)
        ax, bx = fig.subplots(2, 1, sharex=True)
        ax.bar(k[~odd], n[~odd], color="tab:blue", label="even counts")
        ax.bar(k[odd], n[odd], color="tab:red", label=f"odd counts ({int(n[odd].sum())} inputs)")
        if "fraction_low" in frame:  # each share's 95 % interval (bootstrap over the platforms)
            seen = n > 0
            lo, hi = (frame[c].to_numpy() * total for c in ("fraction_low", "fraction_high"))
            ax.errorbar(
                k[seen], n[seen], yerr=[n[seen] - lo[seen], hi[seen] - n[seen]], fmt="none",
                ecolor="0.2", elinewidth=0.8, capsize=2, label="95 % interval (platforms resampled)",
            )  # fmt: skip
        ax.set_yscale("log")
        ax.set_ylim(0.5, max(2.0, float(n.max())) * 5)
        ax.set_ylabel("complete inputs")
        ax.set_title(
            f"(a) {total:,} complete inputs of {int(frame['platforms'].sum()):,} platforms "
            f"({incomplete:,} incomplete, {undecided:,} undecided, left out)",
            fontsize=9,
            loc="left",
        )
        ax.legend(fontsize=8, loc="upper right")
        bx.bar(k, frame["platforms_with_max"], color="0.45")
        bx.set_ylabel("platforms")
        bx.set_xlabel("real forward solutions of an input (of 40 complex)")
        bx.set_title(
            "(b) platforms by the most real solutions among their inputs", fontsize=9, loc="left"
        )
        bx.yaxis.set_major_locator(MaxNLocator(integer=True))
        bx.set_xticks(np.arange(0, ROOTS + 1, 4))
        bx.set_xlim(-1, ROOTS + 1)
        fig.suptitle("Beyond the papers: census of the real assemblies of the general 6-6 platform")
    return save_figure(fig, path, tag=False)


def census(config: dict) -> pd.DataFrame:
    """The census of real assemblies of the general 6-6 platform (gathered from its chunks)."""
    return census_data(config)


def _declare():
    from parakin.registry import Tolerance, figure

    #: real counts of certified solutions are properties of the input; a rerun elsewhere tracks the
    #: same paths up to rounding, so every count is compared exactly (the rate is a timing)
    counts = Tolerance.statistical(
        "real-solution counts of certified solutions are properties of the inputs: compared exactly",
        columns=Tolerance.exactly(
            "complete_inputs",
            "fraction_low",
            "fraction_high",
            "platforms_with_max",
            "incomplete_inputs",
            "undecided_inputs",
            "platforms",
        ),
    )
    figure(
        KEY,
        "census",
        "extra_census_real_roots",
        census,
        census_draw,
        tolerance=counts,
        config=[KEY],
        reference=False,
        caption="Census of the real forward solutions of the general 6-6 platform over random "
        "platforms and leg lengths (histogram by parity).",
    )


_declare()


def main(argv: list[str] | None = None) -> int:
    """One scatter job of the pipeline (``workflow/rules/census.smk``): ``python -m
    parakin.studies.stewart66_census I-of-N OUT.csv --config-json JSON`` writes chunk I of N."""
    import argparse
    import json

    p = argparse.ArgumentParser(prog="python -m parakin.studies.stewart66_census")
    p.add_argument("item", help="the scatter item, 'I-of-N' (1-based)")
    p.add_argument("out", help="the chunk's CSV file")
    p.add_argument("--config-json", required=True, help="the pipeline's config (JSON object)")
    args = p.parse_args(argv)
    config = json.loads(args.config_json)
    i, _, n = args.item.partition("-of-")
    if not (i.isdigit() and n.isdigit()) or int(n) != int(config[KEY]["chunks"]):
        raise SystemExit(
            f"census chunk {args.item!r} is not 'I-of-N' with N = stewart66_census.chunks = "
            f"{config[KEY]['chunks']}"
        )
    print(write_chunk(config, int(i), args.out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
