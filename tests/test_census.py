"""The census of real assemblies of the general 6-6 platform (parakin.studies.stewart66_census):
the chunking does not change the answer, a resumed run reuses what finished chunks wrote, and the
counts obey what every 6-6 input must (an even number of real solutions, at least the pose the
leg lengths came from)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from parakin.studies import stewart66_census as census

SMALL = {"platforms": 3, "inputs_per_platform": 4, "offset": 1.0}


def _config(tmp_path, chunks: int, **section) -> dict:
    return {
        "seed": 20171010,
        "generated_dir": str(tmp_path / "generated"),
        census.KEY: {**SMALL, "chunks": chunks, **section},
    }


def _platforms(config) -> pd.DataFrame:
    return census._gather(config).drop(columns="wall_s")


@pytest.fixture(scope="module")
def two_cuts(tmp_path_factory):
    """The same small census cut into 1 and into 3 chunks."""
    one = _config(tmp_path_factory.mktemp("one"), 1)
    three = _config(tmp_path_factory.mktemp("three"), 3)
    return one, three, _platforms(one), _platforms(three)


def test_chunks_cover_the_platforms_once():
    section = {"platforms": 10, "chunks": 4}
    ranges = [census.chunk_platforms(section, i) for i in range(1, 5)]
    assert [i for r in ranges for i in r] == list(range(10))
    assert {len(r) for r in ranges} <= {2, 3}
    with pytest.raises(ValueError, match="chunk 5 is outside 1..4"):
        census.chunk_platforms(section, 5)


def test_the_census_does_not_depend_on_the_chunking(two_cuts):
    _, _, one, three = two_cuts
    pd.testing.assert_frame_equal(one, three)


def test_counts_are_even_and_include_the_drawn_pose(two_cuts):
    """Real solutions of a real system pair off with their conjugates (40 is even), so a complete
    input has an even real count; its leg lengths are the IK of a real pose, so >= 2."""
    _, _, rows, _ = two_cuts
    counts = rows[census.COUNT_COLUMNS].to_numpy()
    assert counts.sum() + rows["undecided"].sum() == rows["complete"].sum() > 0
    assert counts[:, 1::2].sum() == 0, "an odd number of real solutions"
    assert counts[:, 0].sum() == 0, "no real solution, yet the input came from a real pose"
    assert (rows["root_count"] == 40).all()


def test_resume_reuses_finished_chunks_and_redoes_the_rest(two_cuts, monkeypatch):
    _, three, _, before = two_cuts
    files = census.chunk_files(three)
    Path(files[1]).unlink()  # a chunk that failed: no file
    calls = []
    write = census.write_chunk
    monkeypatch.setattr(
        census, "write_chunk", lambda config, i, path: calls.append(i) or write(config, i, path)
    )
    after = _platforms(three)
    assert calls == [2], "only the missing chunk is computed again"
    pd.testing.assert_frame_equal(before, after)
    stale = pd.read_csv(files[0]).iloc[:0]  # a file that does not hold its platforms
    stale.to_csv(files[0], index=False)
    _platforms(three)
    assert calls == [2, 1]


def test_census_table_and_figure(two_cuts, tmp_path):
    from test_figure_text import check_drawing

    config, _, rows, _ = two_cuts
    table = census.census_data(config)
    assert table["real_solutions"].tolist() == list(range(41))
    assert (
        table["complete_inputs"].sum() + table["undecided_inputs"].sum() == rows["complete"].sum()
    )
    assert table["platforms"].sum() == SMALL["platforms"]
    assert table["platforms_with_max"].sum() == SMALL["platforms"]
    assert np.isclose(table["fraction"].sum(), 1.0)
    assert check_drawing(census.census_draw, table, tmp_path / "census.png") == []


def test_bad_chunking_is_refused_in_one_line(tmp_path):
    with pytest.raises(ValueError, match="chunks = 5 must be <= platforms = 3"):
        census._gather(_config(tmp_path, 5))
    config = _config(tmp_path, 2)
    with pytest.raises(SystemExit, match="not 'I-of-N' with N = stewart66_census.chunks = 2"):
        census.main(["1-of-3", str(tmp_path / "x.csv"), "--config-json", _json(config)])


def test_a_scatter_job_writes_its_chunk(tmp_path, capsys):
    config = _config(tmp_path, 3)
    out = tmp_path / "2-of-3.csv"
    assert census.main(["2-of-3", str(out), "--config-json", _json(config)]) == 0
    assert pd.read_csv(out)["platform"].tolist() == [1]


def _json(config) -> str:
    import json

    return json.dumps(config)


def test_single_input_platforms_share_one_batch_with_the_same_counts(tmp_path):
    """With one input per platform a chunk solves its inputs together on the new-geometry path
    (every input from the stored generic start, no start system per platform); the rows are those
    of each platform's own start system and fibre, timing aside: the counts are properties of the
    inputs, not of the homotopy that found the solutions."""
    section = census._section(_config(tmp_path, 1, platforms=6, inputs_per_platform=1))
    batched = census.chunk_data(section, 1).drop(columns="wall_s")
    rows = []
    for k in range(6):
        mech, legs = census._platform(section["seed"], k, section)
        assert mech.root_count == 40  # its own start system: fk_all then takes the fibre
        rows.append(census._row(k, len(legs), mech.fk_all(legs, return_info=True), 0.0))
    pd.testing.assert_frame_equal(batched, pd.DataFrame(rows).drop(columns="wall_s"))
    assert (batched["complete"] == 1).all() and (batched["root_count"] == 40).all()
