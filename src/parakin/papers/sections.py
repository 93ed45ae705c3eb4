"""A paper's reproduction is a list of section modules; this joins them into one.

Each section module declares its artefacts with ``@artefact`` (:mod:`parakin.registry`) and has
``claims(figdir, ref) -> list[Claim]`` and ``summary(figdir, ref) -> str``; both say what the
tables in ``figdir`` show so far (:func:`table_claims`, :func:`table_text`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, Sequence
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


def _from_tables(figdir: Path, makers: Mapping[str | tuple[str, ...], Callable]) -> Iterator:
    """What each function of ``makers`` makes of its CSVs in ``figdir`` (a name or a tuple of
    names, read in the order named), in order; an entry whose CSVs are not all there yet is left out."""
    for names, make in makers.items():
        names = (names,) if isinstance(names, str) else names
        if all((figdir / name).exists() for name in names):
            yield make(*(pd.read_csv(figdir / name) for name in names))


def table_text(
    figdir: Path,
    sentences: Mapping[str | tuple[str, ...], Callable[..., str | None]],
    sep: str = "\n\n",
) -> str:
    """The report text the tables in ``figdir`` support so far.

    ``sentences`` maps a CSV name (or a tuple of names) to a function of that table (those tables,
    in the order named) returning its text, or None where the tables do not say enough yet; an entry
    whose tables are not all there yet is left out. The texts are joined by ``sep`` in order."""
    return sep.join(text for text in _from_tables(figdir, sentences) if text is not None)


def table_claims(
    figdir: Path, judges: Mapping[str | tuple[str, ...], Callable[..., list[Claim]]]
) -> list[Claim]:
    """The claims the tables in ``figdir`` support so far: ``judges`` maps a CSV name (or a tuple
    of names) to a function of that table (those tables, in the order named) returning its claims;
    an entry whose tables are not all there yet is left out. The claims keep the entries' order."""
    return [claim for claims in _from_tables(figdir, judges) for claim in claims]
