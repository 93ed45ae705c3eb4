"""Li, Quan & Wu 2017, 3-6 Stewart platform (Computer Applications and Software 34(12)): the paper's
experiments. Mechanism: :class:`parakin.mechanisms.stewart36.Stewart36`; PSO: :mod:`parakin.solvers.pso`.
One module per section; each has ``ARTEFACTS``, ``claims(figdir, ref)`` and ``summary(figdir, ref)``.
Configuration: ``config["li2017_stewart36"]``. The FK input (Table 2) is lost and reconstructed as
``L = IK(Table 3 row 1, b)`` (docs/li2017_stewart36.md#g1, ASSUMED).
"""

from __future__ import annotations

from parakin.papers import lazy_sections
from parakin.papers.li2017_stewart36.common import KEY, TITLE

#: the sections of the reproduction, in the paper's order
SECTION_NAMES = (
    "chaos",
    "solutions",
)

__all__ = ["KEY", "TITLE", "ARTEFACTS", "SECTIONS", "claims", "summary"]


#: SECTIONS, ARTEFACTS, claims, summary: built on first use (parakin.papers.lazy_sections)
__getattr__ = lazy_sections(__name__, SECTION_NAMES)
