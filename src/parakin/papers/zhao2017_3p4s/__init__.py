"""Zhao et al. 2017, 3-P(4S) parallel mechanism (Trans. CSAM 48(10)): the paper's experiments.

One function per table or figure: configuration and published inputs in, files out (written
atomically into the paper's figures folder). No kinematics lives here, only the set-up of each
experiment; the mechanism is :class:`parakin.mechanisms.P3P4S`. One module per section of the
paper; each has ``ARTEFACTS``, ``claims(figdir, ref)`` and ``summary(figdir, ref)``.
"""

from __future__ import annotations

from parakin.papers import lazy_sections
from parakin.papers.zhao2017_3p4s.common import KEY, TITLE

#: the sections of the reproduction, in the paper's order
SECTION_NAMES = (
    "kinematics",
    "fk",
    "dynamics",
    "optimization",
)

__all__ = ["KEY", "TITLE", "ARTEFACTS", "SECTIONS", "claims", "summary"]


#: SECTIONS, ARTEFACTS, claims, summary: built on first use (parakin.papers.lazy_sections)
__getattr__ = lazy_sections(__name__, SECTION_NAMES)
