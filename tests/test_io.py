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
        ("iteration", False),
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
