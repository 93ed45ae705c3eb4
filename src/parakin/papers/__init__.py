"""One module per paper: the set-up of each table and figure, and the claims for the report."""

from types import ModuleType

from parakin.papers import li2017_stewart36, li2020_2ups, ye_stewart12, zhao2017_3p4s

#: paper key -> module with TITLE, ARTEFACTS, claims(figdir, ref), summary(figdir, ref)
PAPERS: dict[str, ModuleType] = {
    zhao2017_3p4s.KEY: zhao2017_3p4s,
    li2020_2ups.KEY: li2020_2ups,
    ye_stewart12.KEY: ye_stewart12,
    li2017_stewart36.KEY: li2017_stewart36,
}

__all__ = ["PAPERS"]
