"""The CPU line every pipeline job writes (``parakin.pipeline.cpu_line``) and its sum over a run's
logs (``startup_share``): what docs/kernels.md's start-up figure is measured with."""

import math

import pytest

from parakin.pipeline import cpu_line, startup_share


def test_startup_share_adds_up_the_lines_of_every_log(tmp_path):
    (tmp_path / "study").mkdir()
    (tmp_path / "study" / "a.log").write_text(
        "  training: 50 % (5/10 epochs, 1.0 s)\n" + cpu_line("fig01", 0.5, 1.5) + "\nbuild/x.png\n"
    )
    (tmp_path / "b.log").write_text(cpu_line("table2", 1.0, 7.0) + "\n")
    (tmp_path / "c.log").write_text("a job that failed before its artefact ran\n")
    got = startup_share(tmp_path)
    assert got["jobs"] == 2
    assert got["startup_s"] == pytest.approx(1.5)
    assert got["artefact_s"] == pytest.approx(8.5)
    assert got["startup_share"] == pytest.approx(1.5 / 10.0)
    assert got["numba_jobs"] in (0, 2)  # both lines were written by this one process


def test_no_logs_no_share(tmp_path):
    got = startup_share(tmp_path)
    assert got["jobs"] == 0 and math.isnan(got["startup_share"])
