"""Zhao et al. 2017, 3-P(4S) parallel mechanism (Trans. CSAM 48(10)): the paper's experiments.

One function per table or figure: configuration and published inputs in, files out (written
atomically into the paper's figures folder). No kinematics lives here, only the set-up of each
experiment; the mechanism is :class:`parakin.mechanisms.P3P4S`. One module per section of the
paper; each has ``ARTEFACTS``, ``claims(figdir, ref)`` and ``summary(figdir, ref)``.
"""

from __future__ import annotations

import importlib

from parakin.papers.zhao2017_3p4s.common import KEY, TITLE

#: the sections of the reproduction, in the paper's order
SECTION_NAMES = (
    "kinematics",
    "fk",
    "dynamics",
    "optimization",
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
