"""Constants and helpers shared by the sections of the Li 2020 reproduction."""

from __future__ import annotations

import numpy as np
import pandas as pd

from parakin import registry
from parakin.claims import load_reference
from parakin.mechanisms.ups2 import UPS2

KEY = "li2020_2ups"

#: the registry's declarations with this paper's key filled in (:func:`registry.declarations`):
#: ``@artefact(name, outputs=...)``, ``@table(name, stem)``, ``@table_and_figure(name, stem, draw)``,
#: ``@drawn_figure(name, stem, draw)``
artefact, table, table_and_figure, drawn_figure = registry.declarations(KEY)
TITLE = "Li et al. 2020 — 2-UPS/(S+SPR)R parallel mechanism (Packaging Engineering 41(7))"
CASES = (1, 2, 3, 4, 5)


def mech(config: dict) -> UPS2:
    """The mechanism with the configured geometry (the paper gives none: docs/li2020_2ups.md#g1, ASSUMED)."""
    g = config[KEY]["geometry_mm"]
    return UPS2(a=g["a"] * 1e-3, b=g["b"] * 1e-3, c=g["c"] * 1e-3)


def table2_inputs(ref: pd.DataFrame | None = None) -> np.ndarray:
    """Table 2's drive inputs (l_i1, l_i2, l_i3) per case, in metres, read from the reference CSV."""
    ref = load_reference(KEY) if ref is None else ref
    t = ref[ref["artefact"] == "table2"].set_index("quantity")["value"]
    return np.array([[float(t[f"case{k}.l_i{j}"]) for j in (1, 2, 3)] for k in CASES]) * 1e-3


def table2_outputs(ref: pd.DataFrame | None = None) -> np.ndarray:
    """Table 2's printed outputs (beta deg, gamma deg, Y mm) per case."""
    ref = load_reference(KEY) if ref is None else ref
    t = ref[ref["artefact"] == "table2"].set_index("quantity")["value"]
    return np.array([[float(t[f"case{k}.{n}"]) for n in ("beta", "gamma", "Y")] for k in CASES])


def to_paper(pose: np.ndarray) -> np.ndarray:
    """(beta, gamma, Y) rad, rad, m -> deg, deg, mm."""
    pose = np.asarray(pose, dtype=float)
    return np.concatenate([np.rad2deg(pose[..., :2]), pose[..., 2:] * 1e3], axis=-1)
