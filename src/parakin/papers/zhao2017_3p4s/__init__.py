"""Zhao et al. 2017, 3-P(4S) parallel mechanism (Trans. CSAM 48(10)): the paper's experiments.

One function per table or figure: configuration and published inputs in, files out (written
atomically into the paper's figures folder). No kinematics lives here, only the set-up of each
experiment; the mechanism is :class:`parakin.mechanisms.P3P4S`. One module per section of the
paper; each has ``ARTEFACTS``, ``claims(figdir, ref)`` and ``summary(figdir, ref)``.
"""

from __future__ import annotations

from parakin.papers.sections import combine
from parakin.papers.zhao2017_3p4s import dynamics, fk, kinematics, optimization
from parakin.papers.zhao2017_3p4s.common import KEY, TITLE

#: the sections of the reproduction, in the paper's order
SECTIONS = [kinematics, fk, dynamics, optimization]

#: artefact name -> function(config, outdir) writing that artefact's files; claims(); summary()
ARTEFACTS, claims, summary = combine(SECTIONS)

__all__ = ["KEY", "TITLE", "ARTEFACTS", "SECTIONS", "claims", "summary"]
