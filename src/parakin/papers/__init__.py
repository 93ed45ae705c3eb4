"""One module per paper: the set-up of each table and figure, and the claims for the report.

``PAPERS`` (paper key -> module with TITLE, ARTEFACTS, claims(figdir, ref), summary(figdir, ref))
is built on first use: importing one paper, or one of its sections (as each pipeline job does),
does not import the other three.
"""

import importlib
import sys
from collections.abc import Callable, Sequence
from types import ModuleType

#: the paper keys, in the report's order
KEYS = ("zhao2017_3p4s", "li2020_2ups", "ye_stewart12", "li2017_stewart36")

__all__ = ["PAPERS", "KEYS", "lazy_sections"]


def __getattr__(name: str) -> dict[str, ModuleType]:
    if name == "PAPERS":
        papers = {key: importlib.import_module(f"parakin.papers.{key}") for key in KEYS}
        globals()["PAPERS"] = papers
        return papers
    raise AttributeError(f"module 'parakin.papers' has no attribute {name!r}")


def lazy_sections(package: str, sections: Sequence[str]) -> Callable[[str], object]:
    """The module ``__getattr__`` of a paper's package ``package`` made of the section modules
    ``sections`` (in the paper's order): ``SECTIONS`` (the modules), ``ARTEFACTS`` (artefact name
    -> function(config, outdir)), ``claims`` and ``summary``, built on first use, so that a
    pipeline job imports the one section its artefact lives in, not the others (nor what they
    import)."""

    def __getattr__(name: str) -> object:
        if name not in ("SECTIONS", "ARTEFACTS", "claims", "summary"):
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        from parakin.papers.sections import combine

        modules = [importlib.import_module(f"{package}.{s}") for s in sections]
        artefacts, claims, summary = combine(modules)
        vars(sys.modules[package]).update(
            SECTIONS=modules, ARTEFACTS=artefacts, claims=claims, summary=summary
        )
        return vars(sys.modules[package])[name]

    return __getattr__
