"""Atomic, deterministic output: a pipeline interrupted mid-write never leaves a half file behind.

Every file the pipeline produces goes through :func:`atomic_write_bytes` (write a temporary file in
the destination folder, flush it to disk, then ``os.replace`` it over the target: the rename is
atomic on POSIX, so readers see either the old file or the complete new one).
"""

from __future__ import annotations

import io
import os
import tempfile
from collections.abc import Callable
from pathlib import Path

import pandas as pd

__all__ = [
    "is_timing_column",
    "atomic_write_bytes",
    "atomic_write_text",
    "atomic_writer",
    "write_csv",
    "write_table",
    "markdown_table",
]


#: words that mark a table column as a wall-clock measurement (it differs run to run; the
#: determinism and figure-regression tests compare tables without such columns)
TIMING_WORDS = frozenset({"time", "timed", "latency", "throughput", "speedup", "wall", "ratio"})


def is_timing_column(name: str) -> bool:
    """True for a column that holds a timing: one of its ``_``-separated words is in
    :data:`TIMING_WORDS` (``time_ms``, ``median_latency_us``, ``batched_s``; not ``iteration``)."""
    name = name.lower()
    return bool(TIMING_WORDS & set(name.split("_"))) or name.startswith(("batched_s", "loop_s"))


def atomic_writer(path: str | os.PathLike, write: Callable[[Path], None]) -> Path:
    """Call ``write(tmp_path)`` for a temporary path beside ``path``, then rename it onto ``path``.

    The temporary file keeps ``path``'s suffix (matplotlib and pandas pick the format from it).
    On any exception the temporary file is removed and ``path`` is left untouched.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(
        prefix=f".{path.stem}.", suffix=f".tmp{path.suffix}", dir=path.parent
    )
    os.close(fd)
    try:
        write(Path(tmp))
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically."""
    return atomic_writer(path, lambda tmp: tmp.write_bytes(data))


def atomic_write_text(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` (UTF-8, ``\\n`` line ends) to ``path`` atomically."""
    return atomic_write_bytes(path, text.encode("utf-8"))


def markdown_table(df: pd.DataFrame, floatfmt: str | dict[str, str] = ".6g") -> str:
    """A GitHub-flavoured Markdown table of ``df`` (index dropped), floats formatted by ``floatfmt``.

    ``floatfmt`` is a format spec for every float column, or a dict column -> spec.
    """

    def fmt(col: str, v) -> str:
        if isinstance(v, float):
            spec = floatfmt.get(col, ".6g") if isinstance(floatfmt, dict) else floatfmt
            return "" if v != v else format(v, spec)
        return str(v)

    header = "| " + " | ".join(map(str, df.columns)) + " |"
    rule = "|" + "|".join("---" for _ in df.columns) + "|"
    rows = [
        "| " + " | ".join(fmt(c, v) for c, v in zip(df.columns, row)) + " |"
        for row in df.itertuples(index=False)
    ]
    return "\n".join([header, rule, *rows]) + "\n"


def write_csv(df: pd.DataFrame, path: str | os.PathLike) -> Path:
    """Write ``df`` as CSV (full precision, no index, ``\n`` line ends) atomically."""
    buf = io.StringIO()
    df.to_csv(buf, index=False, lineterminator="\n")
    return atomic_write_text(path, buf.getvalue())


def write_table(
    df: pd.DataFrame,
    stem: str | os.PathLike,
    *,
    title: str = "",
    notes: str = "",
    floatfmt: str | dict[str, str] = ".6g",
    markdown: pd.DataFrame | None = None,
) -> list[Path]:
    """Write ``stem.csv`` (full precision) and ``stem.md`` (title, table, notes), both atomically.

    ``markdown`` is an optional differently-shaped frame for the Markdown file (e.g. a wide
    layout of a long CSV); by default the Markdown shows ``df``.
    """
    stem = Path(stem)
    csv_path = write_csv(df, stem.with_suffix(".csv"))
    parts = [
        f"# {title}\n" if title else "",
        markdown_table(df if markdown is None else markdown, floatfmt),
    ]
    if notes:
        parts.append("\n" + notes.strip() + "\n")
    md_path = atomic_write_text(stem.with_suffix(".md"), "\n".join(p for p in parts if p))
    return [csv_path, md_path]


def draw_from_csv(
    csv: Path, draw: Callable[[pd.DataFrame, Path], Path], png: Path | None = None
) -> list[Path]:
    """Draw ``png`` (default: beside ``csv``, same stem) with ``draw(frame, path)`` from the CSV as
    written and read back, never from numbers in memory, so the committed figure is what its
    committed CSV draws (an artefact declares the pair with ``draws=[...]``). Returns ``[png, csv]``."""
    csv = Path(csv)
    return [draw(pd.read_csv(csv), Path(png) if png is not None else csv.with_suffix(".png")), csv]


def write_and_draw(
    frame: pd.DataFrame,
    csv: Path,
    draw: Callable[[pd.DataFrame, Path], Path],
    png: Path | None = None,
) -> list[Path]:
    """Write ``frame`` to ``csv`` (atomically), then :func:`draw_from_csv`. Returns ``[png, csv]``."""
    return draw_from_csv(write_csv(frame, csv), draw, png)
