"""One module per paper: the set-up of each table and figure, and the claims for the report.

``PAPERS`` (paper key -> module with TITLE, ARTEFACTS, claims(figdir, ref), summary(figdir, ref))
is built on first use: importing one paper, or one of its sections (as each pipeline job does),
does not import the other three.
"""

import importlib
from types import ModuleType

#: the paper keys, in the report's order
KEYS = ("zhao2017_3p4s", "li2020_2ups", "ye_stewart12", "li2017_stewart36")

__all__ = ["PAPERS", "KEYS"]


def __getattr__(name: str) -> dict[str, ModuleType]:
    if name == "PAPERS":
        papers = {key: importlib.import_module(f"parakin.papers.{key}") for key in KEYS}
        globals()["PAPERS"] = papers
        return papers
    raise AttributeError(f"module 'parakin.papers' has no attribute {name!r}")
