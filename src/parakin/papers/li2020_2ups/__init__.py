"""Li et al. 2020, 2-UPS/(S+SPR)R parallel mechanism (Packaging Engineering 41(7)): the paper's
experiments. Mechanism: :class:`parakin.mechanisms.ups2.UPS2`; PSO: :mod:`parakin.solvers.pso`.
One module per section; each has ``ARTEFACTS``, ``claims(figdir, ref)`` and ``summary(figdir, ref)``.
Configuration: ``config["li2020_2ups"]``.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from parakin.papers.li2020_2ups import bench, fk, kinematics
from parakin.papers.li2020_2ups.common import KEY, TITLE
from parakin.report import Claim

SECTIONS = [kinematics, fk, bench]
ARTEFACTS = {name: fn for section in SECTIONS for name, fn in section.ARTEFACTS.items()}


def claims(figdir: Path, ref: pd.DataFrame) -> list[Claim]:
    return [c for section in SECTIONS for c in section.claims(figdir, ref)]


def summary(figdir: Path, ref: pd.DataFrame) -> str:
    return "\n\n".join(p for section in SECTIONS if (p := section.summary(figdir, ref).strip()))


__all__ = ["KEY", "TITLE", "ARTEFACTS", "SECTIONS", "claims", "summary"]
