"""Drawings the papers share: a mechanism redrawn from the skeleton table saved beside its figure."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd


def draw_skeleton_table(frame: pd.DataFrame, path: Path, **options: Any) -> Path:
    """The mechanism a skeleton table lists (:func:`parakin.plot.skeleton_table`, read back from
    the CSV beside its figure), drawn by :func:`parakin.plot.draw_mechanism` with ``options``
    (title, labels, frame length, ...) and saved to ``path``: a figure redrawn from its CSV alone."""
    from parakin.plot import draw_mechanism, save_figure, skeleton_from_table

    ax = draw_mechanism(skeleton_from_table(frame), **options)
    return save_figure(ax.figure, path)
