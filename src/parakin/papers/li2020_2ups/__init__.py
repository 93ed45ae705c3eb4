"""Li et al. 2020, 2-UPS/(S+SPR)R parallel mechanism (Packaging Engineering 41(7)): the paper's
experiments. Mechanism: :class:`parakin.mechanisms.ups2.UPS2`; PSO: :mod:`parakin.solvers.pso`.
One module per section; each has ``ARTEFACTS``, ``claims(figdir, ref)`` and ``summary(figdir, ref)``.
Configuration: ``config["li2020_2ups"]``.
"""

from __future__ import annotations

from parakin.papers import lazy_sections
from parakin.papers.li2020_2ups.common import KEY, TITLE

#: the sections of the reproduction, in the paper's order
SECTION_NAMES = (
    "kinematics",
    "fk",
    "bench",
)

__all__ = ["KEY", "TITLE", "ARTEFACTS", "SECTIONS", "claims", "summary"]


#: SECTIONS, ARTEFACTS, claims, summary: built on first use (parakin.papers.lazy_sections)
__getattr__ = lazy_sections(__name__, SECTION_NAMES)
