"""Studies beyond the papers, registered like a paper (:mod:`parakin.registry`)."""
