"""Ye, You, Shen, Wu, Ru: the Stewart-derived 12-leg cube mechanism — closed-form FK, the six
compatibility equations, N-R vs Broyden, drive modes with redundancy 0..5. Mechanism:
:class:`parakin.mechanisms.stewart12.Stewart12` (and its :class:`DriveMode`); solvers: the generic
``gauss-newton`` / ``broyden-ls`` (= ``newton`` / ``broyden`` on square systems) and ``lm``.
One module per section; each has ``ARTEFACTS``, ``claims(figdir, ref)`` and ``summary(figdir, ref)``.
Configuration: ``config["ye_stewart12"]``. Reconstruction notes: ``shared/notes/002_stewart12.md``.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from parakin.papers.ye_stewart12 import fk, modes, solvers, symbolic
from parakin.papers.ye_stewart12.common import KEY, TITLE
from parakin.report import Claim

SECTIONS = [fk, symbolic, solvers, modes]
ARTEFACTS = {name: fn for section in SECTIONS for name, fn in section.ARTEFACTS.items()}


def claims(figdir: Path, ref: pd.DataFrame) -> list[Claim]:
    return [c for section in SECTIONS for c in section.claims(figdir, ref)]


def summary(figdir: Path, ref: pd.DataFrame) -> str:
    return "\n\n".join(p for section in SECTIONS if (p := section.summary(figdir, ref).strip()))


__all__ = ["KEY", "TITLE", "ARTEFACTS", "SECTIONS", "claims", "summary"]
