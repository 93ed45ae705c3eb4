"""Li et al. 2020, 2-UPS/(S+SPR)R parallel mechanism (Packaging Engineering 41(7)): the paper's
experiments. Mechanism: :class:`parakin.mechanisms.ups2.UPS2`; PSO: :mod:`parakin.solvers.pso`.
One module per section; each has ``ARTEFACTS``, ``claims(figdir, ref)`` and ``summary(figdir, ref)``.
Configuration: ``config["li2020_2ups"]``.
"""

from __future__ import annotations

from parakin.papers.li2020_2ups import bench, fk, kinematics
from parakin.papers.li2020_2ups.common import KEY, TITLE
from parakin.papers.sections import combine

SECTIONS = [kinematics, fk, bench]

#: artefact name -> function(config, outdir) writing that artefact's files; claims(); summary()
ARTEFACTS, claims, summary = combine(SECTIONS)

__all__ = ["KEY", "TITLE", "ARTEFACTS", "SECTIONS", "claims", "summary"]
