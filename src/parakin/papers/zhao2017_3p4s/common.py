"""Constants shared by the sections of the Zhao 2017 reproduction."""

KEY = "zhao2017_3p4s"
TITLE = "Zhao et al. 2017 — 3-P(4S) parallel mechanism (Trans. CSAM 48(10))"
