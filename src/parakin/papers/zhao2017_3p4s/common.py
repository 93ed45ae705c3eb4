"""Constants shared by the sections of the Zhao 2017 reproduction."""

from functools import partial

from parakin import registry

KEY = "zhao2017_3p4s"

#: ``@artefact(name, outputs=..., ...)`` declares one of this paper's tables or figures
#: (:func:`parakin.registry.artefact` with the paper key filled in)
artefact = partial(registry.artefact, KEY)
TITLE = "Zhao et al. 2017 — 3-P(4S) parallel mechanism (Trans. CSAM 48(10))"
