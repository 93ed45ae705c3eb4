"""Figure regression: the committed record is what the code makes now, on this machine.

Each cheap artefact is regenerated with the full config into a temporary folder and checked
against the committed record (figures/) by the reproduction check (:mod:`parakin.check`), within
the tolerance the artefact declares beside its code: numbers by their declared tolerance, never
bit for bit across BLAS kernels or thread counts. Figures are also compared by image (matplotlib's
RMS compare) unless the artefact declares them a chaotic trajectory. A changed figure fails here;
rerun the pipeline and update the record (``parakin record``) when the change is intended.

``.ci/run`` runs this module under two OpenBLAS kernel families and with 1 and 2 threads.
"""

from pathlib import Path

import pandas as pd
import pytest
from matplotlib.testing.compare import compare_images

from parakin.check import check_artefact
from parakin.config import DEFAULT_CONFIG, load_config
from parakin.pipeline import artefacts

ROOT = Path(__file__).resolve().parents[1]
RECORD = ROOT / "figures"
IMAGE_TOL = 2.0  # RMS over 0-255 grey levels: font hinting may differ between machines, a moved line does not
ARTEFACTS = artefacts()

#: slow too: each regenerates an artefact at full scale (.ci/run runs them again under other BLAS
#: kernels and thread counts)
pytestmark = [pytest.mark.reproduction, pytest.mark.slow]

#: (paper, artefact, prerequisite artefacts) regenerated here; expensive artefacts (training,
#: optimisation) are checked by their own reproduction tests on the quick config instead (Fig. 14
#: and the Pareto front read the 30 GA runs of ``ga_runs``: their figures are redrawn from the
#: committed tables below, the runs are judged at quick scale in test_optimization)
CHEAP = [
    ("zhao2017_3p4s", "fig01", ()),
    ("zhao2017_3p4s", "fig02", ()),
    ("zhao2017_3p4s", "table1_region", ("table1",)),
    *[
        ("zhao2017_3p4s", name, ())
        for name in (
            "fig05",
            "fig06",
            "fig07",
            "fig08",
            "fig09",
            "fig10",
            "power_balance",
            "dynamics_printed",
            "mujoco_tracking",
        )
    ],
    *[
        ("zhao2017_3p4s", name, ())
        for name in (
            "fig11",
            "fig12",
            "fig15",
            "fig17",
            "fig19",
            "fig21",
            "fig23",
            "fig25",
            "index_convergence",
        )
    ],
    *[
        ("li2020_2ups", name, ())
        for name in (
            "fig01",
            "parasitic",
            "fk_solutions",
            "table2",
            "fig02",
            "singularity_workspace",
        )
    ],
    *[
        ("ye_stewart12", name, ())
        for name in ("fig01", "fig02", "fig06", "fig08", "fig09", "fig10", "fig11")
    ],
    *[("li2017_stewart36", name, ()) for name in ("fig01", "fig02", "fig03", "adams")],
]


@pytest.mark.parametrize("paper, artefact, needs", CHEAP, ids=[f"{p}-{a}" for p, a, _ in CHEAP])
def test_committed_figure_is_current(tmp_path, paper, artefact, needs):
    config = load_config(DEFAULT_CONFIG)
    for name in needs:
        ARTEFACTS[f"{paper}:{name}"].make(config, tmp_path / paper)
    item = ARTEFACTS[f"{paper}:{artefact}"]
    produced = item.make(config, tmp_path / paper)
    assert sorted(p.name for p in produced) == sorted(item.outputs), (
        "the artefact writes what it declares"
    )
    checks = check_artefact(item, tmp_path, RECORD)
    bad = [c for c in checks if c.status in ("differs", "missing")]
    assert not bad, "; ".join(f"{c.file}: {c.status} {c.column} {c.detail}" for c in bad)
    for path in produced:
        if path.suffix == ".png" and path.name not in item.tolerance.files:
            result = compare_images(str(RECORD / paper / path.name), str(path), tol=IMAGE_TOL)
            assert result is None, result


#: figures of expensive artefacts, redrawn from the committed numbers they plot:
#: (paper, figure stem, function(data frame, outdir) -> paths)
def _replot_targets():
    from parakin.papers.zhao2017_3p4s import fk

    return [("zhao2017_3p4s", "extra_bp_training", fk._training_figure)]


# Every figure declared with ``registry.figure`` (data apart from drawing) is redrawn from its
# committed CSV and compared with the committed PNG in test_figure_text, with the same drawing
# whose texts it checks (drawing from a committed table does no arithmetic the BLAS kernel or
# the thread count could move, so it is not among the reproduction tests run again under them).


@pytest.mark.parametrize(
    "paper, stem, draw", _replot_targets(), ids=lambda v: v if isinstance(v, str) else ""
)
def test_committed_figure_matches_its_numbers(tmp_path, paper, stem, draw):
    """The committed PNG is what the plotting code draws from the committed CSV beside it."""
    committed = ROOT / "figures" / paper
    data = pd.read_csv(committed / f"{stem}.csv")
    draw(data, tmp_path)
    result = compare_images(
        str(committed / f"{stem}.png"), str(tmp_path / f"{stem}.png"), tol=IMAGE_TOL
    )
    assert result is None, result
