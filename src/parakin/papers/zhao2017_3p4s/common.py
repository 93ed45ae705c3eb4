"""Constants shared by the sections of the Zhao 2017 reproduction."""

from functools import partial

from parakin import registry

KEY = "zhao2017_3p4s"

#: ``@artefact(name, outputs=..., ...)`` declares one of this paper's tables or figures
#: (:func:`parakin.registry.artefact` with the paper key filled in)
artefact = partial(registry.artefact, KEY)
#: ``@table(name, stem, *more_outputs, ...)`` declares a table written as ``stem.csv`` and ``stem.md``
table = partial(registry.table, KEY)
#: ``@table_and_figure(name, stem, draw, ...)`` declares a figure drawn from its table
table_and_figure = partial(registry.table_and_figure, KEY)
TITLE = "Zhao et al. 2017 — 3-P(4S) parallel mechanism (Trans. CSAM 48(10))"
