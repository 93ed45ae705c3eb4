"""A paper's reproduction is a list of section modules; this joins them into one.

Each section module declares its artefacts with ``@artefact`` (:mod:`parakin.registry`) and has
``claims(figdir, ref) -> list[Claim]`` and ``summary(figdir, ref) -> str``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from types import ModuleType

import pandas as pd

from parakin.claims import Claim
from parakin.registry import of_module


def combine(sections: Sequence[ModuleType]) -> tuple[dict[str, Callable], Callable, Callable]:
    """``(ARTEFACTS, claims, summary)`` of a paper made of ``sections`` (in the paper's order)."""
    artefacts: dict[str, Callable] = {
        name: make for s in sections for name, make in of_module(s).items()
    }

    def claims(figdir: Path, ref: pd.DataFrame) -> list[Claim]:
        """Claims of the paper that the pipeline outputs in ``figdir`` cover so far."""
        return [c for section in sections for c in section.claims(figdir, ref)]

    def summary(figdir: Path, ref: pd.DataFrame) -> str:
        """The report's paragraphs for the paper, built from the pipeline outputs."""
        return "\n\n".join(p for section in sections if (p := section.summary(figdir, ref).strip()))

    return artefacts, claims, summary
