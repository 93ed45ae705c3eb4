"""Trained networks shipped with parakin, so that the hybrid solver works on a fresh clone and from
an installed wheel without running the pipeline first.

``data/zhao2017_3p4s_bp.npz`` is the 3-10-3 BP network of Zhao et al. 2017 (§1.1) exactly as the
pipeline trains it on the full config (``parakin reproduce zhao2017_3p4s samples`` then ``train``;
the training facts are in its ``meta``). To refresh it after a change of the training, run those
two artefacts with the full config and copy ``<generated_dir>/zhao2017_3p4s/bp_network.npz`` here.
"""

from __future__ import annotations

import os
from pathlib import Path

from parakin.nn.bp import BPNetwork

__all__ = ["DATA_DIR", "PACKAGED", "packaged_network_path", "load_network"]

DATA_DIR = Path(__file__).resolve().parent / "data"
#: paper key -> file in :data:`DATA_DIR`
PACKAGED = {"zhao2017_3p4s": "zhao2017_3p4s_bp.npz"}


def packaged_network_path(key: str = "zhao2017_3p4s") -> Path:
    """Path of the shipped network of paper ``key``."""
    if key not in PACKAGED:
        raise ValueError(f"no trained network ships for {key!r}; shipped: {', '.join(PACKAGED)}")
    return DATA_DIR / PACKAGED[key]


def load_network(
    path: str | os.PathLike | None = None, key: str = "zhao2017_3p4s", *, fallback: bool = False
) -> BPNetwork:
    """The network at ``path``; with no ``path`` (or, with ``fallback``, a ``path`` that does not
    exist, e.g. the pipeline's output before it has run) the shipped network of paper ``key``."""
    if path is None or (fallback and not Path(path).exists()):
        return BPNetwork.load(packaged_network_path(key))
    return BPNetwork.load(path)
