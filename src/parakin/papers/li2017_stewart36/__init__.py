"""Li, Quan & Wu 2017, 3-6 Stewart platform (Computer Applications and Software 34(12)): the paper's
experiments. Mechanism: :class:`parakin.mechanisms.stewart36.Stewart36`; PSO: :mod:`parakin.solvers.pso`.
One module per section; each has ``ARTEFACTS``, ``claims(figdir, ref)`` and ``summary(figdir, ref)``.
Configuration: ``config["li2017_stewart36"]``. The FK input (Table 2) is lost and reconstructed as
``L = IK(Table 3 row 1, b)`` (notes G1, ASSUMED).
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from parakin.papers.li2017_stewart36 import chaos, solutions
from parakin.papers.li2017_stewart36.common import KEY, TITLE
from parakin.report import Claim

SECTIONS = [chaos, solutions]
ARTEFACTS = {name: fn for section in SECTIONS for name, fn in section.ARTEFACTS.items()}

def claims(figdir: Path, ref: pd.DataFrame) -> list[Claim]:
    return [c for section in SECTIONS for c in section.claims(figdir, ref)]


def summary(figdir: Path, ref: pd.DataFrame) -> str:
    return "\n\n".join(p for section in SECTIONS if (p := section.summary(figdir, ref).strip()))


__all__ = ["KEY", "TITLE", "ARTEFACTS", "SECTIONS", "claims", "summary"]
