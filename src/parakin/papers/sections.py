"""A paper's reproduction is a list of section modules; this joins them into one.

Each section module has ``ARTEFACTS`` (name -> function(config, outdir) -> list of paths),
``claims(figdir, ref) -> list[Claim]`` and ``summary(figdir, ref) -> str``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from types import ModuleType

import pandas as pd

from parakin.report import Claim


def combine(sections: Sequence[ModuleType]) -> tuple[dict[str, Callable], Callable, Callable]:
    """``(ARTEFACTS, claims, summary)`` of a paper made of ``sections`` (in the paper's order)."""
    artefacts: dict[str, Callable] = {}
    for section in sections:
        clash = set(artefacts) & set(section.ARTEFACTS)
        if clash:
            raise ValueError(f"artefact name(s) {sorted(clash)} defined twice (in {section.__name__})")
        artefacts.update(section.ARTEFACTS)

    def claims(figdir: Path, ref: pd.DataFrame) -> list[Claim]:
        """Claims of the paper that the pipeline outputs in ``figdir`` cover so far."""
        return [c for section in sections for c in section.claims(figdir, ref)]

    def summary(figdir: Path, ref: pd.DataFrame) -> str:
        """The report's paragraphs for the paper, built from the pipeline outputs."""
        return "\n\n".join(p for section in sections if (p := section.summary(figdir, ref).strip()))

    return artefacts, claims, summary
