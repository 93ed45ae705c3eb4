"""Li, Quan & Wu 2017, 3-6 Stewart platform (Computer Applications and Software 34(12)): the paper's
experiments. Mechanism: :class:`parakin.mechanisms.stewart36.Stewart36`; PSO: :mod:`parakin.solvers.pso`.
One module per section; each has ``ARTEFACTS``, ``claims(figdir, ref)`` and ``summary(figdir, ref)``.
Configuration: ``config["li2017_stewart36"]``. The FK input (Table 2) is lost and reconstructed as
``L = IK(Table 3 row 1, b)`` (docs/li2017_stewart36.md#g1, ASSUMED).
"""

from __future__ import annotations

import importlib

from parakin.papers.li2017_stewart36.common import KEY, TITLE

#: the sections of the reproduction, in the paper's order
SECTION_NAMES = (
    "chaos",
    "solutions",
)

__all__ = ["KEY", "TITLE", "ARTEFACTS", "SECTIONS", "claims", "summary"]


def __getattr__(name: str):
    """``SECTIONS`` (the section modules), ``ARTEFACTS`` (artefact name -> function(config,
    outdir)), ``claims`` and ``summary``, on first use: a pipeline job imports the one section
    its artefact lives in, not the others (and not what they import)."""
    if name not in ("SECTIONS", "ARTEFACTS", "claims", "summary"):
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from parakin.papers.sections import combine

    sections = [importlib.import_module(f"{__name__}.{s}") for s in SECTION_NAMES]
    artefacts, claims, summary = combine(sections)
    globals().update(SECTIONS=sections, ARTEFACTS=artefacts, claims=claims, summary=summary)
    return globals()[name]
