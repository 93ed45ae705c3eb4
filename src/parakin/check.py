"""The reproduction check: a fresh run's outputs against the committed record, within each
artefact's declared tolerance (:class:`parakin.registry.Tolerance`).

Every output file of every artefact gets one status:

- ``identical``: the same bytes;
- ``within tolerance``: every compared number agrees within the declared tolerance;
- ``differs``: some number does not (the column and the excess are named) or the shape changed;
- ``missing``: the run did not write it, or the record lacks it;
- ``not compared``: declared so (a chaotic trajectory, a timing table), with the reason.

Figures (PNG) and the Markdown views of CSV tables are judged through the data they are drawn
from; timing columns (:func:`parakin.io.is_timing_column`) never decide anything. What a number
is decides how it is compared: closed forms and converged solves within ``(rtol, atol)``;
condition numbers by class near a singularity (:class:`parakin.registry.ConditionNumber`: the
round-off digits of a singular matrix are never compared); the statistics of a chaotic computation
(GA, PSO, network training over independent runs) by the overlap of their confidence intervals; a
statistic over a row's successful trials only (the median iterations of the converged starts)
where both runs have enough successes that the ones allowed to differ cannot be half its sample.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from parakin.io import atomic_write_text, is_timing_column, markdown_table, write_csv
from parakin.registry import Artefact, ConditionNumber

__all__ = ["FileCheck", "compare_file", "check_artefact", "check_all", "write_check", "STATUSES"]

#: from best to worst; an artefact's status is the worst of its files'
STATUSES = ("identical", "within tolerance", "not compared", "differs", "missing")


@dataclass(frozen=True)
class FileCheck:
    study: str
    artefact: str
    file: str
    status: str
    column: str = ""
    excess: float = 0.0
    detail: str = ""


def _numbers(text: str) -> list[str]:
    return re.findall(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?", text)


def _compare_frames(rec: pd.DataFrame, new: pd.DataFrame, tol) -> tuple[str, str, float, str]:
    """(status, column, excess, detail) of two tables under ``tol``."""
    if tol.rows is not None:
        col, keep = tol.rows
        rec = rec[rec[col].isin(keep)].reset_index(drop=True)
        new = new[new[col].isin(keep)].reset_index(drop=True)
    if list(rec.columns) != list(new.columns):
        return "differs", "", math.inf, f"columns {list(new.columns)} != record {list(rec.columns)}"
    if len(rec) != len(new):
        return "differs", "", math.inf, f"{len(new)} rows != record {len(rec)}"
    worst = ("within tolerance", "", 0.0, "")
    stats = [c for c in tol.over_successes if c in rec.columns]
    if stats:
        rec, new = rec.copy(), new.copy()
        for col in stats:
            drop = ~tol.comparable_successes(col, rec, new)
            rec.loc[drop, col] = new.loc[drop, col] = np.nan  # too few successes to compare
    interval_cols = {c for pair in tol.intervals for c in pair}
    for low, high in tol.intervals:
        if low in rec.columns and high in rec.columns:
            found = _compare_intervals(rec[[low, high]], new[[low, high]])
            if found is not None:
                return ("differs", *found)
    for col in rec.columns:
        if is_timing_column(col) or col in tol.skip or col in interval_cols:
            continue
        a, b = rec[col], new[col]
        numeric = pd.api.types.is_numeric_dtype(a) and pd.api.types.is_numeric_dtype(b)
        if numeric and tol.kind == "statistical" and col not in tol.columns:
            continue  # a chaotic computation: only the columns it declares stable are compared
        if numeric:
            found = _compare_numbers(a.to_numpy(float), b.to_numpy(float), tol.limits(col))
            if found is not None and (found[0] > worst[2] or worst[0] != "differs"):
                worst = ("differs", col, *found)
        elif not a.astype(str).equals(b.astype(str)):
            i = int(np.argmax((a.astype(str) != b.astype(str)).to_numpy()))
            return "differs", col, math.inf, f"row {i}: {b.iloc[i]!r} vs record {a.iloc[i]!r}"
    return worst


def _compare_numbers(x: np.ndarray, y: np.ndarray, limit) -> tuple[float, str] | None:
    """``(excess, detail)`` of the worst cell of run ``y`` against record ``x``, or None if all agree."""
    same_nan = np.isnan(x) & np.isnan(y)
    same_inf = np.isinf(x) & (x == y)
    if isinstance(limit, ConditionNumber):
        bad = ~(same_nan | same_inf) & ~limit.agree(x, y)
        if not bad.any():
            return None
        i = int(np.argmax(bad))
        return math.inf, (
            f"row {i}: condition number {y[i]:.6g} vs record {x[i]:.6g} (not the same class "
            f"at n = {limit.n}: singular when k kappa >= 1/2, k = {limit.k:.2g})"
        )
    rtol, atol = limit
    with np.errstate(invalid="ignore"):
        allowed = atol + rtol * np.abs(x)
        gap = np.where(np.isnan(x) != np.isnan(y), np.inf, np.abs(y - x))  # a value against none
        ratio = np.where(np.isinf(gap), np.inf, gap / np.where(allowed > 0, allowed, np.inf))
    bad = ~(same_nan | same_inf) & ~(gap <= allowed)
    if not bad.any():
        return None
    excess = float(np.nanmax(np.where(bad, ratio, 0)))
    i = int(np.argmax(bad))
    excess = excess if math.isfinite(excess) else math.inf
    return excess, f"row {i}: {y[i]:.6g} vs record {x[i]:.6g} (rtol {rtol:g}, atol {atol:g})"


def _compare_intervals(rec: pd.DataFrame, new: pd.DataFrame) -> tuple[str, float, str] | None:
    """``(column, excess, detail)`` of the first row whose interval ``[low, high]`` (the two
    columns) does not overlap the record's, or None."""
    (lo0, hi0), (lo1, hi1) = rec.to_numpy(float).T, new.to_numpy(float).T
    with np.errstate(invalid="ignore"):
        apart = (lo1 > hi0) | (hi1 < lo0)
    apart &= ~(np.isnan(lo0) & np.isnan(lo1))
    if not apart.any():
        return None
    i = int(np.argmax(apart))
    return (
        f"{rec.columns[0]}..{rec.columns[1]}",
        math.inf,
        f"row {i}: interval [{lo1[i]:.6g}, {hi1[i]:.6g}] does not overlap the record's "
        f"[{lo0[i]:.6g}, {hi0[i]:.6g}]",
    )


def compare_file(
    record: Path, ours: Path, tol, siblings: Iterable[str] = ()
) -> tuple[str, str, float, str]:
    """(status, column, excess, detail) of one output file against its record."""
    if not ours.exists():
        return "missing", "", math.inf, "not written by this run"
    if not record.exists():
        return "missing", "", math.inf, "not in the record (new output: update the record)"
    if record.read_bytes() == ours.read_bytes():
        return "identical", "", 0.0, ""
    if record.name in tol.files:
        return "not compared", "", 0.0, tol.reason
    if tol.kind == "timing":
        return "not compared", "", 0.0, "timings: machine-dependent, " + tol.reason
    data = record.with_suffix(".csv").name
    if record.suffix in (".png", ".md") and data in siblings:
        return "within tolerance", "", 0.0, f"drawn from {data}, judged there"
    if record.suffix == ".png":
        return (
            "within tolerance",
            "",
            0.0,
            "figure redrawn from this artefact's tables, judged there",
        )
    if record.suffix == ".csv":
        return _compare_frames(pd.read_csv(record), pd.read_csv(ours), tol)
    if (
        record.suffix == ".md"
    ):  # text with numbers: the words must match, the numbers within tolerance
        a, b = record.read_text(), ours.read_text()
        if re.sub(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?", "#", a) != re.sub(
            r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?", "#", b
        ):
            return "differs", "", math.inf, "text differs beyond its numbers"
        frame = pd.DataFrame({"value": [float(v) for v in _numbers(a)]})
        return _compare_frames(frame, pd.DataFrame({"value": [float(v) for v in _numbers(b)]}), tol)
    return "differs", "", math.inf, "binary file differs"


def check_artefact(item: Artefact, results: Path, record: Path) -> list[FileCheck]:
    """One :class:`FileCheck` per output file of ``item`` (results and record: figures folders)."""
    out = []
    for name in item.outputs:
        rec, new = record / item.study_folder / name, results / item.study_folder / name
        status, col, excess, detail = compare_file(rec, new, item.tolerance, siblings=item.outputs)
        out.append(
            FileCheck(
                item.study,
                item.name,
                f"{item.study_folder}/{name}".lstrip("/"),
                status,
                col,
                excess,
                detail,
            )
        )
    return out


def check_all(artefacts: Iterable[Artefact], results: Path, record: Path) -> pd.DataFrame:
    rows = [c.__dict__ for a in artefacts for c in check_artefact(a, Path(results), Path(record))]
    return pd.DataFrame(rows, columns=list(FileCheck.__dataclass_fields__))


def summarise(files: pd.DataFrame, artefacts: dict[str, Artefact]) -> pd.DataFrame:
    """One row per artefact: its worst file status, the tolerance kind and its reason."""
    rows = []
    for (study, name), group in files.groupby(["study", "artefact"], sort=False):
        worst = max(group["status"], key=STATUSES.index)
        bad = group[group["status"] == worst].iloc[0]
        tol = artefacts[f"{study}:{name}"].tolerance
        rows.append(
            {
                "study": study,
                "artefact": name,
                "status": worst,
                "tolerance": tol.kind,
                "file": bad["file"] if worst != "identical" else "",
                "column": bad["column"],
                "detail": bad["detail"],
                "reason": tol.reason,
            }
        )
    return pd.DataFrame(rows)


def summary_line(per_artefact: pd.DataFrame) -> str:
    counts = per_artefact["status"].value_counts()
    parts = [f"{int(counts[s])} {s}" for s in STATUSES if s in counts]
    return f"reproduction check: {len(per_artefact)} artefacts: " + ", ".join(parts)


def write_check(
    artefacts: dict[str, Artefact], results: Path, record: Path, out: Path
) -> tuple[Path, Path, str]:
    """Write ``out.csv`` (one row per file) and ``out.md`` (per artefact); return them and the summary line."""
    files = check_all(artefacts.values(), results, record)
    per = summarise(files, artefacts)
    line = summary_line(per)
    # what needs a reader's attention first: missing, differs, then the rest in registry order
    per = per.iloc[sorted(range(len(per)), key=lambda i: -STATUSES.index(per["status"].iloc[i]))]
    csv = write_csv(files, Path(out).with_suffix(".csv"))
    text = (
        f"# Reproduction check\n\n{line}.\n\nThis run's outputs (`{results}`) against the committed "
        f"record (`{record}`), each artefact within the tolerance declared beside its code "
        "(`parakin which FILE` names it). Statuses: "
        + ", ".join(f"*{s}*" for s in STATUSES)
        + ". One row per file: `"
        + csv.name
        + "`.\n\n"
        + markdown_table(per)
        + "\n"
    )
    md = atomic_write_text(Path(out).with_suffix(".md"), text)
    return csv, md, line
