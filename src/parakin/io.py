"""Atomic, deterministic output, and bounded input: a pipeline interrupted mid-write never leaves a
half file behind, and no input file makes a command read, parse or walk without end.

Every file parakin writes (the pipeline's tables and figures, the CLI's ``--output``, the record)
goes through :func:`atomic_writer`: the content is written to a fresh temporary file in the
destination folder (a random name created exclusively, ``O_EXCL | O_NOFOLLOW``: a planted name or
symlink is never followed and concurrent writers never share one), flushed to disk, then
``os.replace``-d over the target. The rename is atomic on POSIX: readers see either the old file
or the complete new one, and of several concurrent writers of one file each succeeds and the last
rename wins. A target that is a symlink is replaced by the new file; what it pointed to is left
alone. The new file has the mode of the file it replaces, else the mode the umask gives a new
file (``0666 & ~umask``): a private file stays private. Errors name the user's path, never the
temporary one.

:func:`read_text` is the matching reader: UTF-8 text of a regular file, at most a given size, or
a one-line error naming the file. :func:`load_data` and :func:`parse_data` read YAML or JSON
(configs, ``--param`` and ``--geometry`` values, mechanism description files) within one set of
bounds, all checked on the parser's events before anything is built: at most
:data:`MAX_DATA_BYTES`, nested at most :data:`MAX_DATA_DEPTH` deep, at most
:data:`MAX_DATA_ALIASES` aliases, and at most :data:`MAX_DATA_VALUES` values once every alias is
expanded (counted, never expanded); a file that breaks one is one line, at once (a 1 MiB file is
read, checked and built in about a second).
"""

from __future__ import annotations

import csv
import errno
import io
import json
import math
import os
import re
import shutil
import stat
import uuid
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # pandas is imported where a table is read (a cold `parakin fk` needs none)
    import pandas as pd

__all__ = [
    "is_timing_column",
    "atomic_copy",
    "atomic_write_bytes",
    "atomic_write_text",
    "atomic_writer",
    "check_data",
    "load_data",
    "parse_data",
    "read_rows",
    "read_text",
    "row_format",
    "write_rows",
    "write_csv",
    "write_table",
    "markdown_table",
]


#: words that mark a table column as a wall-clock measurement (it differs run to run; the
#: determinism and figure-regression tests compare tables without such columns)
TIMING_WORDS = frozenset({"time", "timed", "latency", "throughput", "speedup", "wall", "ratio"})


def is_timing_column(name: str) -> bool:
    """True for a column that holds a timing: one of its ``_``-separated words is in
    :data:`TIMING_WORDS` (``time_ms``, ``median_latency_us``, ``batched_s``), or a rate per second (``inputs_per_s``;
    not ``iteration``)."""
    name = name.lower()
    rate = name.endswith("_per_s")  # a rate per second of wall time (inputs_per_s)
    return (
        bool(TIMING_WORDS & set(name.split("_")))
        or rate
        or name.startswith(("batched_s", "loop_s"))
    )


def atomic_writer(path: str | os.PathLike, write: Callable[[Path], None]) -> Path:
    """Call ``write(tmp_path)`` for a fresh temporary path beside ``path``, then rename it onto ``path``.

    The temporary file keeps ``path``'s suffix (matplotlib and pandas pick the format from it).
    The result has the permission bits of the regular file it replaces, else those the umask
    gives a new file. On any exception the temporary file is removed and ``path`` is left
    untouched; an OSError of the write names ``path`` (not the temporary file).
    """
    path = Path(path)
    try:
        if path.parent.exists() and not path.parent.is_dir():
            raise NotADirectoryError(errno.ENOTDIR, os.strerror(errno.ENOTDIR), str(path.parent))
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = _fresh(path)
    except OSError as exc:
        raise _naming(exc, path) from None
    try:
        write(tmp)
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
            mode = _kept_mode(path)
            if mode is not None:
                os.fchmod(fh.fileno(), mode)
        os.replace(tmp, path)
    except BaseException as exc:
        tmp.unlink(missing_ok=True)
        if isinstance(exc, OSError) and exc.filename in (None, str(tmp), tmp):
            raise _naming(exc, path) from None
        raise
    return path


def _fresh(path: Path) -> Path:
    """A new empty file beside ``path`` (``.<stem>.<random>.tmp<suffix>``), created exclusively
    and never through a symlink, with mode ``0666`` less the umask (the kernel applies it)."""
    for _ in range(100):
        tmp = path.parent / f".{path.stem}.{uuid.uuid4().hex[:12]}.tmp{path.suffix}"
        try:
            flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0)
            os.close(os.open(tmp, flags, 0o666))
        except FileExistsError:  # 48 random bits taken: try another
            continue
        return tmp
    raise FileExistsError(errno.EEXIST, "no free temporary name", str(path.parent))


def _kept_mode(path: Path) -> int | None:
    """The permission bits of the regular file at ``path`` (not followed: a symlink there is
    replaced, and what it points to says nothing), or None where there is none."""
    try:
        st = os.lstat(path)
    except OSError:
        return None
    return stat.S_IMODE(st.st_mode) & 0o777 if stat.S_ISREG(st.st_mode) else None


def _naming(exc: OSError, path: Path) -> OSError:
    """``exc`` (same errno, hence same class) about ``path``, the file the user asked for; a folder
    on the way that caused it (a file where a folder should be) is named too, the temporary file
    never."""
    reason = exc.strerror or str(exc)
    culprit = exc.filename
    if culprit is not None and Path(culprit) != path:
        if not Path(culprit).name.startswith(f".{path.stem}."):
            reason += f" ({culprit})"
    return OSError(exc.errno, reason, str(path)) if exc.errno else OSError(f"{reason}: {path}")


def atomic_copy(source: str | os.PathLike, path: str | os.PathLike) -> Path:
    """Copy the file ``source`` to ``path`` atomically (contents only, see :func:`atomic_writer`)."""
    return atomic_writer(path, lambda tmp: shutil.copyfile(source, tmp))


#: largest text file :func:`read_text` reads unless told otherwise (a CSV of 10^7 rows)
MAX_TEXT_BYTES = 1 << 30


def read_bytes(
    path: str | os.PathLike, where: str, limit: int, error: type[Exception] = ValueError
) -> bytes:
    """The bytes of the regular file ``path``, at most ``limit`` of them; else ``error`` naming
    ``where``: a missing file, a device, FIFO or directory (``/dev/zero`` would never end, a FIFO
    never open), a file too large. Opened without blocking, so a FIFO is refused, not waited on."""
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise error(f"{where} does not exist") from None
    except OSError as exc:
        raise error(f"{where} cannot be read ({exc.strerror or type(exc).__name__})") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):  # checked on what is open: no race with a rename
            kind = "a directory" if stat.S_ISDIR(st.st_mode) else "a device, FIFO or socket"
            raise error(f"{where} is not a regular file ({kind})")
        if st.st_size > limit:
            raise error(f"{where} is {st.st_size} bytes, more than the limit {limit}")
    except BaseException:
        os.close(fd)
        raise
    with os.fdopen(fd, "rb") as fh:
        data = fh.read(limit + 1)
    if len(data) > limit:  # grew while being read
        raise error(f"{where} is more than {limit} bytes, the limit")
    return data


def read_text(path: str | os.PathLike, what: str = "", limit: int = MAX_TEXT_BYTES) -> str:
    """The UTF-8 text of the regular file ``path`` (a leading byte-order mark dropped, at most
    ``limit`` bytes), or a one-line ValueError that names the file: missing, not a regular file,
    too large, or the first byte that is not UTF-8 (a binary or UTF-16 file)."""
    where = f"{what} {path}" if what else str(path)
    data = read_bytes(path, where, limit)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ValueError(
            f"{where}: not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start}; "
            "a binary file, or text in another encoding such as UTF-16?)"
        ) from None


# ------------------------------------------------------------------ bounded YAML / JSON
#: largest YAML/JSON input (the full config is about 15 kB)
MAX_DATA_BYTES = 1 << 20
#: most values an input may expand to (the full config holds about 300): YAML aliases repeat a
#: node wherever they point, so 700 bytes of nested aliases expand to ~10^11 values
MAX_DATA_VALUES = 100_000
#: deepest nesting (the full config nests 5 deep; numpy takes at most 32 axes)
MAX_DATA_DEPTH = 64
#: most aliases in one input (configs and mechanism files use none or a few)
MAX_DATA_ALIASES = 1000


def load_data(
    path: str | os.PathLike, what: str = "", *, error: type[Exception] | None = None
) -> Any:
    """The YAML or JSON document in file ``path``, read and parsed within the bounds of
    :func:`parse_data` (the file at most :data:`MAX_DATA_BYTES`, a regular file, UTF-8).

    ``what`` names the input in every message (default: the path), e.g. ``"--geometry g.yaml"``
    or ``"config file 'c.yaml'"``; ``error`` is the exception raised (default
    :class:`parakin.errors.InputError`, a ValueError), always one line."""
    from parakin.errors import InputError

    error = error or InputError
    where = what or str(path)
    data = read_bytes(path, where, MAX_DATA_BYTES, error)
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise error(
            f"{where}: not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start})"
        ) from None
    return parse_data(text, where, error=error)


def parse_data(text: str, what: str, *, error: type[Exception] | None = None) -> Any:
    """The YAML (or JSON) document ``text``, checked before anything is built: at most
    :data:`MAX_DATA_BYTES` (UTF-8), nested at most :data:`MAX_DATA_DEPTH` deep, at most
    :data:`MAX_DATA_ALIASES` aliases and :data:`MAX_DATA_VALUES` values with every alias expanded
    (counted on libyaml's events, nothing expanded), no alias to a node that contains it. Only
    plain data is built (``yaml.safe_load``: no Python objects). Anything else is one ``error``
    line (default :class:`parakin.errors.InputError`) naming ``what`` and the limit or the line
    and column of a syntax error."""
    from parakin.errors import InputError

    error = error or InputError
    if len(text) > MAX_DATA_BYTES and len(text.encode("utf-8")) > MAX_DATA_BYTES:
        raise error(
            f"{what} is {len(text.encode('utf-8'))} bytes, more than the limit {MAX_DATA_BYTES}"
        )
    import yaml

    if text.lstrip()[:1] in ("{", "["):  # JSON first: it allows tabs YAML refuses
        try:
            data = json.loads(text)
        except (ValueError, RecursionError):
            pass  # not JSON (or deeper than json's recursion): YAML's flow style, or an error
        else:
            check_data(data, what, error=error)
            return data
    try:
        _scan(text, what, error)
        return yaml.load(text, Loader=_loader())
    except error:
        raise
    except yaml.YAMLError as exc:  # e.g. a tab in the indentation: where, in one line
        mark = getattr(exc, "problem_mark", None)
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark is not None else ""
        problem = getattr(exc, "problem", None) or "not valid YAML"
        raise error(f"{what} is not valid YAML{where}: {_short(problem)}") from None
    except (ValueError, OverflowError) as exc:  # e.g. an integer of 10^5 digits
        raise error(f"{what}: {_short(_one_line(exc))}") from None


def _short(text: str, limit: int = 80) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _loader() -> Any:
    import yaml

    return getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml: 5-10x faster, same result


def _scan(text: str, what: str, error: type[Exception]) -> None:
    """Depth, aliases and expanded size of YAML ``text`` from the parser's events, one pass,
    nothing built: each anchored node's expanded size and depth are kept, and an alias adds them
    where it stands. libyaml's parser keeps its own stack (no recursion), so a file nested 10^5
    deep is measured, not overflowed (its composer would crash the process)."""
    import yaml
    from yaml import events as ev

    stack: list[list] = []  # per open collection: [expanded size, depth below, anchor]
    anchors: dict[str, tuple[int, int] | None] = {}  # None: still open
    total, aliases = 0, 0

    def at(event: Any) -> str:
        m = event.start_mark
        return f" (line {m.line + 1}, column {m.column + 1})" if m is not None else ""

    def add(size: int, depth: int) -> None:
        nonlocal total
        if stack:
            stack[-1][0] += size
            stack[-1][1] = max(stack[-1][1], depth)
        else:
            total += size

    for event in yaml.parse(text, Loader=_loader()):
        if isinstance(event, ev.CollectionStartEvent):
            if len(stack) >= MAX_DATA_DEPTH:
                raise error(f"{what} nests deeper than the limit {MAX_DATA_DEPTH}{at(event)}")
            if event.anchor is not None:
                anchors[event.anchor] = None
            stack.append([1, 0, event.anchor])
        elif isinstance(event, ev.CollectionEndEvent):
            size, depth, anchor = stack.pop()
            if anchor is not None:
                anchors[anchor] = (size, depth + 1)
            add(size, depth + 1)
        elif isinstance(event, ev.ScalarEvent):
            if event.anchor is not None:
                anchors[event.anchor] = (1, 0)
            add(1, 0)
        elif isinstance(event, ev.AliasEvent):
            aliases += 1
            if aliases > MAX_DATA_ALIASES:
                raise error(f"{what} holds more than {MAX_DATA_ALIASES} YAML aliases, the limit")
            if event.anchor in anchors and anchors[event.anchor] is None:
                raise error(f"{what} refers to itself (a recursive YAML alias){at(event)}")
            size, depth = anchors.get(event.anchor) or (1, 0)  # undefined: the loader says so
            if len(stack) + depth > MAX_DATA_DEPTH:
                raise error(f"{what} nests deeper than the limit {MAX_DATA_DEPTH}{at(event)}")
            add(size, depth)
    if total > MAX_DATA_VALUES:
        raise error(
            f"{what} expands to {total:.3g} values, more than the limit {MAX_DATA_VALUES} "
            "(YAML aliases that repeat aliases?)"
        )


def check_data(data: Any, what: str, *, error: type[Exception] | None = None) -> None:
    """Raise ``error`` (default :class:`parakin.errors.InputError`) where the loaded ``data``
    expands to more than :data:`MAX_DATA_VALUES` values, nests deeper than
    :data:`MAX_DATA_DEPTH` or refers to itself: the bounds of :func:`parse_data` on data that came
    another way (JSON on the command line, a config Snakemake loaded). Each shared node is counted
    once and multiplied, so a bomb is measured without being expanded."""
    from parakin.errors import InputError

    error = error or InputError
    size = _expanded_size(data, {}, set(), 0, what, error)
    if size > MAX_DATA_VALUES:
        raise error(
            f"{what} expands to {size:.3g} values, more than the limit {MAX_DATA_VALUES} "
            "(YAML aliases that repeat aliases?)"
        )


def _expanded_size(
    node: Any, memo: dict[int, int], active: set[int], depth: int, what: str, error: type
) -> int:
    if not isinstance(node, (dict, list)):
        return 1
    key = id(node)
    if key in memo:
        return memo[key]
    if key in active:
        raise error(f"{what} refers to itself (a recursive YAML alias)")
    if depth >= MAX_DATA_DEPTH:
        raise error(f"{what} nests deeper than the limit {MAX_DATA_DEPTH}")
    active.add(key)
    children = node.values() if isinstance(node, dict) else node
    memo[key] = 1 + sum(_expanded_size(c, memo, active, depth + 1, what, error) for c in children)
    active.discard(key)
    return memo[key]


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically."""
    return atomic_writer(path, lambda tmp: tmp.write_bytes(data))


def atomic_write_text(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` (UTF-8, ``\\n`` line ends) to ``path`` atomically."""
    return atomic_write_bytes(path, text.encode("utf-8"))


def markdown_table(df: pd.DataFrame, floatfmt: str | dict[str, str] = ".6g") -> str:
    """A GitHub-flavoured Markdown table of ``df`` (index dropped), floats formatted by ``floatfmt``.

    ``floatfmt`` is a format spec for every float column, or a dict column -> spec. Written here
    rather than ``DataFrame.to_markdown``: that needs ``tabulate``, whose padding and float
    formats changed between releases, and the record's tables must be the same bytes everywhere.
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
    import pandas as pd

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


# ------------------------------------------------------------------ rows of poses or joint vectors
#: file formats of the CLI's --input and --output (one pose or joint vector per row)
ROW_FORMATS = (".csv", ".npy")
#: most rows one input file may hold
MAX_ROWS = 10_000_000
_NPY_MAGIC = b"\x93NUMPY"


def row_format(path: str | os.PathLike, option: str) -> str:
    """``".csv"`` or ``".npy"`` from ``path``'s suffix, or a ValueError naming ``option``."""
    suffix = Path(path).suffix.lower()
    if suffix not in ROW_FORMATS:
        raise ValueError(f"{option} {path}: the file name must end in {' or '.join(ROW_FORMATS)}")
    return suffix


def read_rows(
    path: str, names: Sequence[str], units: Sequence[str], option: str = "--input"
) -> np.ndarray:
    """The ``(N, n)`` finite values of a CSV or .npy file, one pose or joint vector per row.

    A CSV may start with a header; where it names every one of ``names`` (``x [m]`` or ``x``, any
    order, other columns ignored: every CSV that ``parakin ik``/``fk --output`` writes reads back)
    those columns are read by name, and a unit in brackets must be the one ``units`` gives.
    Without such a header the file has exactly ``n`` columns in the order of ``names``. Lines
    starting with ``#`` are comments. A .npy holds an array of shape ``(..., n)``; rows that are
    entirely NaN in an array of 3 or more axes are padding (``fk --all`` pads inputs with fewer
    solutions) and are skipped. Anything else (empty, truncated, not numeric, not finite, not
    UTF-8) is a one-line ValueError naming the file.
    """
    where = f"{option} {path}"
    if row_format(path, option) == ".npy":
        a = _read_npy(path, where, len(names), names)
    else:
        a = _read_csv(path, where, names, units)
    if len(a) == 0:
        raise ValueError(f"{where}: the file holds no rows")
    bad = ~np.all(np.isfinite(a), axis=-1)
    if np.any(bad):
        row = int(np.argmax(bad))
        raise ValueError(
            f"{where}: row {row + 1} is not finite ({np.array2string(a[row], precision=6)})"
        )
    return a


def _read_npy(path: str, where: str, n: int, names: Sequence[str]) -> np.ndarray:
    data = read_bytes(path, where, MAX_TEXT_BYTES)  # a regular file of bounded size, no FIFO
    magic = data[: len(_NPY_MAGIC)]
    if magic != _NPY_MAGIC:
        raise ValueError(
            f"{where}: not a .npy file ({'empty' if not magic else 'no .npy header'}; "
            "np.save writes one, or give a .csv)"
        )
    try:
        a = np.load(io.BytesIO(data), allow_pickle=False)
    except (ValueError, EOFError) as exc:  # truncated, pickled objects, a corrupt header
        raise ValueError(f"{where}: not a readable numeric .npy array ({_one_line(exc)})") from None
    if a.dtype.kind not in "iuf" or a.ndim == 0 or a.shape[-1] != n:
        raise ValueError(
            f"{where}: a .npy file must hold a numeric array of shape (N, {n}) "
            f"({', '.join(names)}), got {a.dtype} {a.shape}"
        )
    if a.size > MAX_ROWS * n:
        raise ValueError(f"{where}: more than {MAX_ROWS} rows")
    rows = a.reshape(-1, n).astype(float)
    if a.ndim >= 3:  # fk --all: inputs with fewer real solutions are padded with NaN rows
        rows = rows[~np.all(np.isnan(rows), axis=-1)]
    return rows


def _header_name(token: str) -> tuple[str, str | None]:
    """``"x [mm]"`` -> ``("x", "mm")``; ``"x"`` -> ``("x", None)``."""
    m = re.fullmatch(r"\s*([^\[\]]*?)\s*(?:\[\s*([^\]]*?)\s*\])?\s*", token)
    return (m.group(1), m.group(2)) if m else (token.strip(), None)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _csv_lines(path: str, where: str) -> list[tuple[int, list[str]]]:
    """``(line number, stripped cells)`` of each data line (blank and ``#`` lines skipped)."""
    text = read_text(path, where.split(" ", 1)[0])
    lines = [
        (k + 1, line)
        for k, line in enumerate(text.splitlines())
        if line.strip() and not line.lstrip().startswith("#")
    ]
    if len(lines) > MAX_ROWS + 1:
        raise ValueError(f"{where}: more than {MAX_ROWS} rows")
    try:
        return [(k, [c.strip() for c in next(csv.reader([line]))]) for k, line in lines]
    except csv.Error as exc:  # e.g. a NUL byte
        raise ValueError(f"{where}: not a CSV file ({exc})") from None


def _columns(
    header: list[str], where: str, names: Sequence[str], units: Sequence[str]
) -> list[int] | None:
    """The column of each of ``names`` in ``header`` (None: read by position), units checked."""
    found = {}
    for i, cell in enumerate(header):
        found.setdefault(_header_name(cell)[0], (i, _header_name(cell)[1]))
    if not all(name in found for name in names):
        if len(header) != len(names):
            raise ValueError(
                f"{where}: the header {header} names neither the columns {list(names)} nor "
                f"{len(names)} columns"
            )
        return None
    for name, want in zip(names, units):
        unit = found[name][1]
        if unit not in (None, "", want) and not (unit == "-" and want == "1"):
            raise ValueError(
                f"{where}: column {name!r} is in {unit} but these --units read {name} in {want}"
            )
    return [found[name][0] for name in names]


def _read_csv(path: str, where: str, names: Sequence[str], units: Sequence[str]) -> np.ndarray:
    n = len(names)
    cells = _csv_lines(path, where)
    if not cells:
        raise ValueError(f"{where}: the file holds no rows")
    columns, width = None, n
    if not any(_is_number(c) for c in cells[0][1]):  # a header: no cell of it is a number
        header = cells.pop(0)[1]
        columns, width = _columns(header, where, names, units), len(header)
        if not cells:
            raise ValueError(f"{where}: the file holds a header and no rows")
    rows = []
    for k, row in cells:
        if len(row) != width:
            expected = f"{width} (the header's)" if columns else f"{n} ({', '.join(names)})"
            raise ValueError(f"{where}, line {k}: {len(row)} values, expected {expected}")
        picked = [row[c] for c in columns] if columns else row
        try:
            rows.append([float(c) for c in picked])
        except ValueError:
            raise ValueError(f"{where}, line {k}: {picked} are not all numbers") from None
    return np.asarray(rows, dtype=float).reshape(-1, n)


def write_rows(
    path: str,
    names: Sequence[str],
    units: Sequence[str],
    values: np.ndarray,
    extra: dict[str, Sequence] | None = None,
    lead: dict[str, Sequence] | None = None,
) -> Path:
    """Write ``values (N, n)`` atomically to a CSV (header ``name [unit]``, ``lead`` columns first,
    ``extra`` columns last; what :func:`read_rows` reads back by name) or a ``.npy`` (the values
    only, any shape)."""
    if row_format(path, "--output") == ".npy":

        def write(tmp: Path) -> None:
            with open(tmp, "wb") as fh:
                np.save(fh, np.asarray(values, dtype=float))

        return atomic_writer(path, write)
    lead, extra = lead or {}, extra or {}
    header = [*lead, *(f"{n} [{u}]" if u != "1" else n for n, u in zip(names, units)), *extra]
    v = np.atleast_2d(values)
    buf = io.StringIO()
    out = csv.writer(buf, lineterminator="\n")
    out.writerow(header)
    for i in range(len(v)):
        out.writerow(
            [_cell(c[i]) for c in lead.values()]
            + [_cell(x) for x in v[i]]
            + [_cell(c[i]) for c in extra.values()]
        )
    return atomic_write_text(path, buf.getvalue())


def _cell(value) -> str:
    """A CSV cell: ``true``/``false``, a float that reads back exactly, empty where not finite."""
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (float, np.floating)):
        return repr(float(value)) if math.isfinite(value) else ""
    return str(value)


def _one_line(exc: BaseException) -> str:
    return " ".join((str(exc) or type(exc).__name__).split())
