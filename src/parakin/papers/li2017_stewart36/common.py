"""Constants and helpers shared by the sections of the Li 2017 (3-6 Stewart) reproduction.

The FK input of the paper (Table 2: b and the six leg lengths) is LOST in the extraction; it is
**reconstructed** everywhere as ``L = IK(Table 3 row 1, b)`` with ``b`` from the config (docs/li2017_stewart36.md#g1,
ASSUMED), so Table 3 row 1 is an exact solution by construction.
"""

from __future__ import annotations

from functools import partial

import numpy as np
import pandas as pd

from parakin import registry
from parakin.claims import load_reference
from parakin.mechanisms.stewart36 import Stewart36, pose_from_paper

KEY = "li2017_stewart36"

#: the registry's declarations with this paper's key filled in (:func:`registry.declarations`):
#: ``@artefact(name, outputs=...)``, ``@table(name, stem)``, ``@table_and_figure(name, stem, draw)``,
#: ``@drawn_figure(name, stem, draw)``; ``@drawn_figures(name, [(png, csv, draw), ...])``
artefact, table, table_and_figure, drawn_figure = registry.declarations(KEY)
drawn_figures = partial(registry.drawn_figures, KEY)
TITLE = "Li, Quan & Wu 2017 — 3-6 Stewart platform, chaotic-inertia-weight PSO (Comp. Appl. Softw. 34(12))"
POSE_COLS = ("alpha", "beta", "gamma", "X", "Y", "Z")
#: note printed beside every use of the reconstructed input
INPUT_NOTE = "FK input reconstructed as L = IK(Table 3 row 1, b) (Table 2 lost; docs/li2017_stewart36.md#g1, ASSUMED)"


def cfg(config: dict) -> dict:
    return config[KEY]


def mech(config: dict, b: float | None = None) -> Stewart36:
    """The mechanism with the configured base side ``b`` (Table 2 lost: ASSUMED, docs/li2017_stewart36.md#g1)."""
    return Stewart36(b=float(cfg(config)["b"] if b is None else b))


def table3(ref: pd.DataFrame | None = None) -> pd.DataFrame:
    """Table 3's 19 rows (deg, deg, deg, -, -, -) from the reference CSV, with the note column."""
    ref = load_reference(KEY) if ref is None else ref
    t = ref[ref["artefact"] == "table3"]
    rows = []
    for k in range(1, 20):
        sub = t[t["quantity"].str.startswith(f"row{k}.")].set_index("quantity")
        rows.append(
            {
                "row": k,
                **{c: float(sub.loc[f"row{k}.{c}", "value"]) for c in POSE_COLS},
                "note": sub.loc[f"row{k}.alpha", "note"],
            }
        )
    return pd.DataFrame(rows)


def fk_input(config: dict, b: float | None = None) -> np.ndarray:
    """The reconstructed FK input: leg lengths of Table 3 row 1 under geometry ``b``."""
    m = mech(config, b)
    row1 = table3().iloc[0][list(POSE_COLS)].to_numpy(float)
    return m.ik(pose_from_paper(row1))
