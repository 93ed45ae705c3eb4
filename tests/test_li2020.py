"""Li 2020 reproduction: Table 2 contradictions (geometry-independent), artefacts on a small config,
claims and the notebook."""

from pathlib import Path

import pandas as pd
import pytest

from parakin.config import DEFAULT_CONFIG, QUICK_CONFIG, load_config
from parakin.papers import li2020_2ups as L
from parakin.papers.li2020_2ups.fk import consistency_checks
from parakin.report import load_reference

ROOT = Path(__file__).resolve().parents[1]


def test_reference_transcription():
    ref = load_reference(L.KEY)
    assert (ref["paper"] == L.KEY).all()
    t2 = ref[ref["artefact"] == "table2"]
    assert len(t2) == 30 and t2["value"].tolist()[:6] == ["0", "-24", "26", "-0.680", "1.713", "0.311"]


def test_table2_contradicts_own_ik():
    """If a different reading of the geometry/inputs ever 'fixes' Table 2, these fail loudly."""
    c = consistency_checks()
    assert c["same_l1_Y_spread_mm"] == pytest.approx(1.043)  # cases 1, 2: l_i1 = 0, Y differ
    assert c["order_violations"] >= 1  # Y5 < Y4 though l_i1(5) < l_i1(4)
    assert c["a_max_mm"] < 15 and c["c_max_mm"] < 18  # notes: a <= 14.6, c <= 17.3 mm
    assert c["a_max_with_positive_l1_mm"] == 0.0
    assert c["sign_violations"] == 4


@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    out = tmp_path_factory.mktemp("li2020")
    cfg = load_config([DEFAULT_CONFIG, QUICK_CONFIG])
    for fn in L.ARTEFACTS.values():
        for p in fn(cfg, out):
            assert Path(p).exists()
    return out


def test_artefacts_and_claims(outputs):
    ref = load_reference(L.KEY)
    claims = L.claims(outputs, ref)
    by = {(c.artefact, c.quantity, c.variant): c for c in claims}
    t2 = [c for c in claims if c.artefact == "table2"]
    assert len(t2) == 15 and all(c.verdict == "differs" for c in t2)
    assert next(c for c in claims if c.quantity == "alpha").verdict == "reproduced"
    assert next(c for c in claims if c.quantity == "dof").verdict == "reproduced"
    thr = {c.variant.split(":")[0]: c.verdict for c in claims if c.quantity == "fitness_threshold"}
    assert thr["PSO as_printed"] == "differs"
    assert by  # summary is built from outputs
    text = L.summary(outputs, ref)
    assert "Table 2 cannot satisfy" in text and "α = 0" in text
    df = pd.read_csv(outputs / "table2.csv")
    assert set(df["variant"]) == {"as_printed", "improved", "improved_clamped"}
    fig2 = pd.read_csv(outputs / "fig02_fitness.csv")
    assert set(fig2["case"]) == {1, 2, 3, 4, 5}
    for png in ("fig01_mechanism.png", "fig02_fitness.png", "extra_parasitic.png", "extra_fk_solutions.png"):
        assert (outputs / png).stat().st_size > 10_000


# the notebook itself is executed by nbmake (pytest --nbmake over notebooks/)
