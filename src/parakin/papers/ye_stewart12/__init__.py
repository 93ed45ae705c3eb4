"""Ye, You, Shen, Wu, Ru: the Stewart-derived 12-leg cube mechanism — closed-form FK, the six
compatibility equations, N-R vs Broyden, drive modes with redundancy 0..5. Mechanism:
:class:`parakin.mechanisms.stewart12.Stewart12` (and its :class:`DriveMode`); solvers: the generic
``gauss-newton`` (= ``newton`` on square systems), ``broyden`` with ``update="inverse"`` (the
paper's inverse rank-one update, every mode), ``broyden-ls`` (the direct update of a rectangular
``B``, beyond the paper) and ``lm`` (``common.METHODS_USED``).
One module per section; each has ``ARTEFACTS``, ``claims(figdir, ref)`` and ``summary(figdir, ref)``.
Configuration: ``config["ye_stewart12"]``. The paper in our own words: ``docs/ye_stewart12.md``.
"""

from __future__ import annotations

from parakin.papers import lazy_sections
from parakin.papers.ye_stewart12.common import KEY, TITLE

#: the sections of the reproduction, in the paper's order
SECTION_NAMES = (
    "fk",
    "symbolic",
    "solvers",
    "modes",
)

__all__ = ["KEY", "TITLE", "ARTEFACTS", "SECTIONS", "claims", "summary"]


#: SECTIONS, ARTEFACTS, claims, summary: built on first use (parakin.papers.lazy_sections)
__getattr__ = lazy_sections(__name__, SECTION_NAMES)
