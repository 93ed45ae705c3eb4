"""Zhao et al. 2017, 3-P(4S) parallel mechanism (Trans. CSAM 48(10)): the paper's experiments.

One function per table or figure: configuration and published inputs in, files out (written
atomically into the paper's figures folder). No kinematics lives here, only the set-up of each
experiment; the mechanism is :class:`parakin.mechanisms.P3P4S`. One module per section of the
paper; each has ``ARTEFACTS``, ``claims(figdir, ref)`` and ``summary(figdir, ref)``.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from parakin.papers.zhao2017_3p4s import dynamics, fk, kinematics, optimization
from parakin.papers.zhao2017_3p4s.common import KEY, TITLE
from parakin.report import Claim

#: the sections of the reproduction, in the paper's order
SECTIONS = [kinematics, fk, dynamics, optimization]

#: artefact name -> function(config, outdir) writing that artefact's files
ARTEFACTS = {name: fn for section in SECTIONS for name, fn in section.ARTEFACTS.items()}


def claims(figdir: Path, ref: pd.DataFrame) -> list[Claim]:
    """Claims of this paper that our pipeline outputs cover so far."""
    return [c for section in SECTIONS for c in section.claims(figdir, ref)]


def summary(figdir: Path, ref: pd.DataFrame) -> str:
    """The report's paragraphs for this paper, built from the pipeline outputs."""
    return "\n\n".join(p for section in SECTIONS if (p := section.summary(figdir, ref).strip()))


__all__ = ["KEY", "TITLE", "ARTEFACTS", "SECTIONS", "claims", "summary"]
