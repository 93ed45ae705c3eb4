"""Figure regression: the committed figures are what the code makes now.

Each cheap artefact is regenerated with the full config into a temporary folder; every figure
is compared with the committed PNG by image (matplotlib's RMS compare, tolerance below) and
by the numbers it plots (the CSV beside it). A changed figure fails here; regenerate with
``snakemake --cores 2`` and commit the result when the change is intended.
"""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib.testing.compare import compare_images

from parakin.config import DEFAULT_CONFIG, load_config
from parakin.io import is_timing_column
from parakin.papers import PAPERS

ROOT = Path(__file__).resolve().parents[1]
IMAGE_TOL = 2.0  # RMS over 0-255 grey levels: font hinting may differ between machines, a moved line does not

#: (paper, artefact, prerequisite artefacts) regenerated here; expensive artefacts (training,
#: optimisation) are checked by their own reproduction tests on the quick config instead
CHEAP = [
    ("zhao2017_3p4s", "fig01", ()),
    ("zhao2017_3p4s", "fig02", ()),
    ("zhao2017_3p4s", "table1_region", ("table1",)),
    *[("zhao2017_3p4s", name, ()) for name in ("fig05", "fig06", "fig07", "fig08", "fig09", "fig10",
                                               "power_balance", "dynamics_printed", "mujoco_tracking")],
    *[("zhao2017_3p4s", name, ()) for name in ("fig11", "fig12", "fig14", "fig15", "fig17", "fig19", "fig21",
                                               "fig23", "fig25", "index_convergence", "pareto")],
    *[("li2020_2ups", name, ()) for name in ("fig01", "parasitic", "fk_solutions", "table2", "fig02",
                                             "singularity_workspace")],
    *[("ye_stewart12", name, ()) for name in ("fig01", "fig02", "fig06", "fig08", "fig09", "fig10", "fig11")],
    *[("li2017_stewart36", name, ()) for name in ("fig01", "fig02", "fig03", "adams")],
]


@pytest.mark.parametrize("paper, artefact, needs", CHEAP, ids=[f"{p}-{a}" for p, a, _ in CHEAP])
def test_committed_figure_is_current(tmp_path, paper, artefact, needs):
    config = load_config(DEFAULT_CONFIG)
    artefacts = PAPERS[paper].ARTEFACTS
    for name in needs:
        artefacts[name](config, tmp_path)
    produced = artefacts[artefact](config, tmp_path)
    for path in produced:
        committed = ROOT / "figures" / paper / path.name
        assert committed.exists(), f"{committed} is not committed: run snakemake and commit figures/"
        if path.suffix == ".png":
            result = compare_images(str(committed), str(path), tol=IMAGE_TOL)
            assert result is None, result
        elif path.suffix == ".csv":
            new, old = pd.read_csv(path), pd.read_csv(committed)
            assert list(new.columns) == list(old.columns)
            for col in new.columns:
                if is_timing_column(col):
                    continue  # wall-clock measurements differ run to run
                if pd.api.types.is_numeric_dtype(new[col]):
                    # atol: some columns are differences at rounding level (~1e-10 between machines)
                    assert np.allclose(new[col], old[col], rtol=1e-9, atol=1e-8, equal_nan=True), col
                else:
                    assert (new[col].astype(str) == old[col].astype(str)).all(), col


#: figures of expensive artefacts, redrawn from the committed numbers they plot:
#: (paper, figure stem, function(data frame, outdir) -> paths)
def _replot_targets():
    from parakin.papers.zhao2017_3p4s import fk

    return [("zhao2017_3p4s", "extra_bp_training", fk._training_figure)]


@pytest.mark.parametrize("paper, stem, draw", _replot_targets(), ids=lambda v: v if isinstance(v, str) else "")
def test_committed_figure_matches_its_numbers(tmp_path, paper, stem, draw):
    """The committed PNG is what the plotting code draws from the committed CSV beside it."""
    committed = ROOT / "figures" / paper
    data = pd.read_csv(committed / f"{stem}.csv")
    draw(data, tmp_path)
    result = compare_images(str(committed / f"{stem}.png"), str(tmp_path / f"{stem}.png"), tol=IMAGE_TOL)
    assert result is None, result
