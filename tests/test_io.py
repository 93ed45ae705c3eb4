"""Atomic writes: an interrupted write leaves the previous file intact and no debris."""

import pandas as pd
import pytest

from parakin.io import atomic_write_text, atomic_writer, markdown_table, write_table


def test_interrupted_write_keeps_old_file(tmp_path):
    target = tmp_path / "table.csv"
    atomic_write_text(target, "old\n")

    def half_then_crash(tmp):
        tmp.write_text("half a ta")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic_writer(target, half_then_crash)
    assert target.read_text() == "old\n"
    assert [p.name for p in tmp_path.iterdir()] == ["table.csv"]


def test_write_table_is_deterministic(tmp_path):
    df = pd.DataFrame({"a": [0.1 + 0.2, 1e-17], "b": ["x", "y"]})
    p1 = write_table(df, tmp_path / "one", title="T", notes="n")
    p2 = write_table(df, tmp_path / "two", title="T", notes="n")
    for a, b in zip(p1, p2):
        assert a.read_bytes() == b.read_bytes()
    assert pd.read_csv(p1[0])["a"].iloc[0] == 0.1 + 0.2  # full precision round trip


def test_markdown_table_format():
    md = markdown_table(pd.DataFrame({"x": [1.23456789], "n": ["a"]}), floatfmt={"x": ".3f"})
    assert md.splitlines() == ["| x | n |", "|---|---|", "| 1.235 | a |"]


@pytest.mark.parametrize(
    "name, timed",
    [
        ("time_ms", True),
        ("median_latency_us", True),
        ("batched_s", True),
        ("speedup_single", True),
        ("inputs_per_s", True),
        ("iteration", False),
        ("per_step", False),
        ("t_s", False),
        ("mujoco_loop_error_m", False),
        ("e3", False),
    ],
)
def test_timing_columns_are_recognised(name, timed):
    from parakin.io import is_timing_column

    assert is_timing_column(name) is timed


def test_parse_quantity_units():
    from parakin.units import parse_quantity

    assert parse_quantity("0.21") == 0.21  # a trailing digit is not the unit "1"
    assert parse_quantity("120mm") == pytest.approx(0.12)
    assert parse_quantity("35deg") == pytest.approx(0.6108652381980153)
    with pytest.raises(ValueError, match="cannot read 'abc'"):
        parse_quantity("abc")


# --------------------------------------------------------- hostile targets (issue 26, finding 1)
def test_a_symlinked_target_is_replaced_not_followed(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("keep\n")
    (tmp_path / "out.csv").symlink_to(victim)
    (tmp_path / ".out.csv.tmp").symlink_to(victim)  # the old fixed temporary name
    atomic_write_text(tmp_path / "out.csv", "ours\n")
    assert victim.read_text() == "keep\n"
    assert (
        not (tmp_path / "out.csv").is_symlink() and (tmp_path / "out.csv").read_text() == "ours\n"
    )


def test_concurrent_writers_each_succeed(tmp_path):
    """Eight threads write one file at once: each succeeds, the file is one whole version."""
    from concurrent.futures import ThreadPoolExecutor

    target = tmp_path / "same.csv"
    texts = [f"writer {k}\n" * 2000 for k in range(8)]
    with ThreadPoolExecutor(8) as pool:
        done = list(pool.map(lambda t: atomic_write_text(target, t), texts))
    assert done == [target] * 8
    assert target.read_text() in texts
    assert [p.name for p in tmp_path.iterdir()] == ["same.csv"]


@pytest.mark.parametrize("case", ["directory", "file-as-folder", "disk-full"])
def test_write_errors_name_the_target_never_the_temporary_file(tmp_path, case):
    import errno

    target = tmp_path / "out.csv"
    write = lambda tmp: tmp.write_text("x")  # noqa: E731
    if case == "directory":
        target.mkdir()
    elif case == "file-as-folder":
        (tmp_path / "f").write_text("")
        target = tmp_path / "f" / "out.csv"
    else:

        def write(tmp):
            raise OSError(errno.ENOSPC, "No space left on device")

    with pytest.raises(OSError) as err:
        atomic_writer(target, write)
    assert err.value.filename == str(target) and ".tmp" not in str(err.value)
    assert [p.name for p in tmp_path.iterdir() if ".tmp" in p.name] == []


def test_read_text_names_a_file_that_is_not_utf8(tmp_path):
    from parakin.io import read_text

    path = tmp_path / "cfg.yaml"
    path.write_bytes("seed: 1\n".encode("utf-16"))
    with pytest.raises(ValueError, match=r"cfg.yaml: not UTF-8 text \(byte 0xff at offset 0"):
        read_text(path)
    path.write_bytes(b"\xef\xbb\xbfseed: 1\n")  # a UTF-8 byte-order mark is dropped
    assert read_text(path) == "seed: 1\n"


def test_rows_round_trip_by_name(tmp_path):
    """What write_rows writes (lead and extra columns, quoted labels) read_rows reads by name."""
    import numpy as np

    from parakin.io import read_rows, write_rows

    values = np.array([[0.1, -2.5e-17, 3.0], [4.0, 5.0, 6.0]])
    path = tmp_path / "rows.csv"
    write_rows(
        path,
        ("x", "y", "z"),
        ("m", "m", "rad"),
        values,
        lead={"input": [1, 2]},
        extra={"ok": [True, False], "label": ["a, b", 'say "c"']},
    )
    np.testing.assert_array_equal(
        read_rows(path, ("z", "x", "y"), ("rad", "m", "m")), values[:, [2, 0, 1]]
    )
    with pytest.raises(ValueError, match="column 'z' is in rad but these --units read z in deg"):
        read_rows(path, ("x", "y", "z"), ("m", "m", "deg"))


def _finished_run(results, studies: list[str]) -> list:
    """A fake finished run in ``results``: every output of ``studies`` and the report, each file
    holding ``new <its path>``; returns their paths relative to ``results``."""
    from pathlib import Path

    from parakin.pipeline import artefacts

    found = artefacts(studies)
    files = [Path(a.study_folder) / f for a in found.values() for f in a.outputs]
    files += [Path("REPORT.md"), Path("report.csv")]
    for name in files:
        (results / name).parent.mkdir(parents=True, exist_ok=True)
        (results / name).write_text(f"new {name}\n")
    return files


def test_record_copies_atomically_and_follows_no_symlink(tmp_path, monkeypatch):
    """`parakin record` (pipeline.record) writes the record through the same atomic writer."""
    from pathlib import Path

    from parakin.pipeline import record

    monkeypatch.syspath_prepend(str(Path(__file__).parent / "data"))
    results, committed = tmp_path / "results", tmp_path / "record"
    files = _finished_run(results, ["toy_study"])
    victim = tmp_path / "victim.txt"
    victim.write_text("keep\n")
    (committed / files[0]).parent.mkdir(parents=True)
    (committed / files[0]).symlink_to(victim)
    copied = record(results, committed, ["toy_study"])
    assert len(copied) == len(files) and victim.read_text() == "keep\n"
    assert (committed / files[0]).read_text() == f"new {files[0]}\n"
    assert not list(committed.rglob("*.tmp*"))


def test_cli_record_takes_a_config_overlay(tmp_path, capsys):
    """`parakin record --config config/cluster.yaml` records the cluster census alone (the
    config's one study), not every study of the default config."""
    from pathlib import Path

    from parakin.cli import main

    root = Path(__file__).resolve().parents[1]
    results, committed = tmp_path / "results", tmp_path / "record"
    files = _finished_run(results, ["parakin.studies.stewart66_census"])
    args = ["record", "--no-readme", "--config", str(root / "config" / "cluster.yaml")]
    assert main([*args, "--results", str(results), "--record", str(committed)]) == 0
    assert sorted(p.relative_to(committed) for p in committed.rglob("*") if p.is_file()) == sorted(
        files
    )
    assert f"{len(files)} files copied" in capsys.readouterr().err


# ------------------------------------------------------------ bounded reading (issue 46)
def test_read_text_refuses_what_is_not_a_regular_file_and_what_is_too_large(tmp_path):
    import os

    from parakin.io import read_text

    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    for path, needle in [("/dev/zero", "not a regular file"), (fifo, "not a regular file")]:
        with pytest.raises(ValueError, match=needle):
            read_text(path, "--input")
    with pytest.raises(ValueError, match="not a regular file \\(a directory\\)"):
        read_text(tmp_path)
    (tmp_path / "big").write_bytes(b"x" * 101)
    with pytest.raises(ValueError, match="101 bytes, more than the limit 100"):
        read_text(tmp_path / "big", limit=100)
    with pytest.raises(ValueError, match="does not exist"):
        read_text(tmp_path / "missing")


@pytest.mark.parametrize(
    "text, needle",
    [
        ("a: &a [1, 1]\n" + "".join(f"a{i}: &a{i} [*a, *a]\n" for i in range(3)), None),
        ("x: " + "[" * 63 + "]" * 63, None),  # 64 levels with the mapping
        ("x: " + "[" * 64 + "]" * 64, "nests deeper than the limit 64 (line 1, column 67)"),
        ("x: &a [1]\ny: [" + ", ".join(["*a"] * 1001) + "]", "more than 1000 YAML aliases"),
        ("a: &x [*x]", "refers to itself"),
        ("[" + ", ".join(["1"] * 100_001) + "]", "expands to 1e+05 values"),
        ("a:\n\tb: 1", "is not valid YAML (line 2, column 1)"),
        ("a: !!python/object/apply:os.getpid []", "is not valid YAML"),
        ('{"a":\t[1, 2]}', None),  # JSON with a tab (YAML refuses it)
    ],
    ids=[
        "aliases",
        "64-levels",
        "65-levels",
        "1001-aliases",
        "recursive",
        "100001",
        "tab",
        "tag",
        "json",
    ],
)
def test_parse_data_bounds(text, needle):
    import re

    from parakin.errors import InputError
    from parakin.io import parse_data

    if needle is None:
        assert parse_data(text, "T") is not None
    else:
        with pytest.raises(InputError, match=re.escape(needle)):
            parse_data(text, "T")


def test_load_data_is_fast_at_its_size_limit(tmp_path):
    """The largest accepted file, the most values: read, checked and built in about a second."""
    import time

    from parakin.io import MAX_DATA_BYTES, load_data

    rows = "\n".join(f"- {i}.5" for i in range(99_000))
    path = tmp_path / "big.yaml"
    path.write_text(rows)
    assert path.stat().st_size < MAX_DATA_BYTES
    start = time.perf_counter()
    assert len(load_data(path, "big")) == 99_000
    assert time.perf_counter() - start < 10  # ~1 s on a loaded 2-core machine
