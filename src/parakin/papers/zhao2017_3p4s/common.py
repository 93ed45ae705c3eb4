"""Constants shared by the sections of the Zhao 2017 reproduction."""

from parakin import registry

KEY = "zhao2017_3p4s"

#: the registry's declarations with this paper's key filled in (:func:`registry.declarations`):
#: ``@artefact(name, outputs=...)``, ``@table(name, stem)``, ``@table_and_figure(name, stem, draw)``,
#: ``@drawn_figure(name, stem, draw)``
artefact, table, table_and_figure, drawn_figure = registry.declarations(KEY)
TITLE = "Zhao et al. 2017 — 3-P(4S) parallel mechanism (Trans. CSAM 48(10))"
