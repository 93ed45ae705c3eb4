"""Shared figure style and a 3-D drawing of any mechanism at a pose.

Three pieces, used by every paper module and notebook:

* :data:`STYLE` and :func:`use_style` -- the rcParams that make every figure look the same and
  render to the same bytes on every machine (Agg, DejaVu Sans, fixed dpi and sizes, no
  timestamps); :func:`new_figure` creates a figure of one of the journal sizes in :data:`FIGSIZE`.
* :func:`save_figure` -- writes a PNG atomically (temporary file in the same folder, then
  ``os.replace``), so an interrupted pipeline never leaves half a figure behind.
* :func:`draw_mechanism` and :func:`skeleton_table` -- draw a
  :class:`~parakin.mechanisms.base.Skeleton` (points, links, closed outlines and frames in world
  coordinates) on a 3-D axes, and list the exact numbers that drawing plots. Nothing here knows
  any particular mechanism: a mechanism describes itself through ``Mechanism.skeleton(pose)``.

Figures are built on :class:`matplotlib.figure.Figure` with an Agg canvas, not through pyplot, so
the library never changes the user's backend and leaks no open figures.
"""

from __future__ import annotations

import contextlib
import os
import re
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

import matplotlib as mpl
import numpy as np
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.legend_handler import HandlerTuple
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.text import Text
from matplotlib.ticker import MaxNLocator
from matplotlib.transforms import Bbox, offset_copy
from mpl_toolkits.mplot3d import Axes3D, proj3d
from mpl_toolkits.mplot3d.art3d import Poly3DCollection
from numpy.typing import ArrayLike

from parakin.io import atomic_writer
from parakin.mechanisms.base import Skeleton

__all__ = [
    "DPI",
    "FIGSIZE",
    "FRAME_AXIS_COLORS",
    "KIND_STYLES",
    "MECHANISM_GRID",
    "PNG_METADATA",
    "STYLE",
    "draw_mechanism",
    "mechanism_axes",
    "new_figure",
    "save_figure",
    "skeleton_from_table",
    "skeleton_table",
    "tex_label",
    "use_style",
]

# ---------------------------------------------------------------------------------------- style
#: Resolution of every saved raster figure (dots per inch).
DPI = 150

#: Figure sizes (width, height) in inches: a journal single column is ~3.5 in, a full page width
#: (double column) ~7 in. ``"mechanism"`` is the full-width size of a 3-D mechanism drawing.
FIGSIZE: dict[str, tuple[float, float]] = {
    "single": (3.5, 2.6),
    "single_tall": (3.5, 3.5),
    "double": (7.0, 3.6),
    "double_tall": (7.0, 5.6),
    "mechanism": (7.0, 5.4),
}

#: PNG metadata of every saved figure: no "Software" entry (it carries the matplotlib version)
#: and no time stamp, so two runs give byte-identical files.
PNG_METADATA: dict[str, str | None] = {"Software": None}

#: rcParams of every parakin figure. Everything that affects the rendered pixels is pinned:
#: the font (DejaVu Sans ships with matplotlib, so no system font is ever picked up), mathtext
#: in the same font, text hinting, sizes, dpi, and the SVG hash salt (stable ids in SVG output).
STYLE: dict[str, Any] = {
    # fonts: the one matplotlib ships, for text and for math
    "font.family": "sans-serif",
    "font.sans-serif": ["DejaVu Sans"],
    "mathtext.fontset": "dejavusans",
    "font.size": 8.0,
    "axes.titlesize": 9.0,
    "axes.labelsize": 8.0,
    "xtick.labelsize": 7.0,
    "ytick.labelsize": 7.0,
    "legend.fontsize": 7.0,
    "figure.titlesize": 9.0,
    # rendering that must not depend on the machine
    "text.hinting": "none",
    "text.usetex": False,
    "path.simplify": True,
    "svg.hashsalt": "parakin",
    "svg.fonttype": "path",
    "pdf.fonttype": 42,
    # sizes
    "figure.figsize": FIGSIZE["single"],
    "figure.dpi": DPI,
    "savefig.dpi": DPI,
    "savefig.format": "png",
    "savefig.bbox": None,  # fixed figure sizes: never crop to the content
    "savefig.facecolor": "white",
    "savefig.edgecolor": "white",
    "savefig.transparent": False,
    "figure.facecolor": "white",
    # axes and lines
    "axes.grid": True,
    "grid.color": "0.85",
    "grid.linewidth": 0.5,
    "grid.linestyle": "-",
    "axes.linewidth": 0.6,
    "axes.edgecolor": "0.2",
    "axes.spines.top": False,
    "axes.spines.right": False,
    "axes.axisbelow": True,
    "axes.prop_cycle": mpl.cycler(
        color=["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000"]
    ),
    "lines.linewidth": 1.2,
    "lines.markersize": 4.0,
    "xtick.major.width": 0.6,
    "ytick.major.width": 0.6,
    "xtick.major.size": 3.0,
    "ytick.major.size": 3.0,
    "xtick.direction": "out",
    "ytick.direction": "out",
    "legend.frameon": False,
    "legend.handlelength": 2.2,
    "image.cmap": "viridis",
}


@contextlib.contextmanager
def use_style(overrides: Mapping[str, Any] | None = None) -> Iterator[dict[str, Any]]:
    """Apply :data:`STYLE` (plus ``overrides``) for the duration of a ``with`` block.

    Also usable as a decorator (``@use_style()``) on a function that builds a figure. The
    rcParams are restored on exit; the pyplot backend is never touched (parakin figures carry
    their own Agg canvas, see :func:`new_figure`). Yields the dict of rcParams in force.
    """
    params = {**STYLE, **(dict(overrides) if overrides else {})}
    with mpl.rc_context(params):
        yield params


def new_figure(
    size: str | tuple[float, float] = "single",
    *,
    projection: str | None = None,
    rect: tuple[float, float, float, float] | None = None,
    style: Mapping[str, Any] | None = None,
) -> tuple[Figure, Any]:
    """A figure of a fixed journal size with one axes, rendered by Agg whatever the backend.

    ``size`` is a key of :data:`FIGSIZE` or a (width, height) in inches. ``projection="3d"``
    gives an :class:`~mpl_toolkits.mplot3d.Axes3D`. ``rect`` places the axes (figure fraction);
    by default 2-D axes get a tight layout and 3-D axes fill the figure. ``style``: rcParams
    over :data:`STYLE` while the axes is made (e.g. :data:`MECHANISM_GRID`). Returns ``(fig, ax)``.
    """
    figsize = FIGSIZE[size] if isinstance(size, str) else tuple(size)
    with use_style(style):
        fig = Figure(figsize=figsize, dpi=DPI)
        FigureCanvasAgg(fig)
        if projection == "3d":
            ax = fig.add_axes(rect or (0.0, 0.0, 1.0, 1.0), projection="3d")
        elif rect is not None:
            ax = fig.add_axes(rect, projection=projection)
        else:
            ax = fig.add_subplot(projection=projection)
            fig.set_layout_engine("constrained")
    return fig, ax


#: the light grid of a mechanism drawing's 3-D axes. mplot3d reads a 3-D axis's grid style from
#: these rcParams when the axes is made and offers no setter afterwards, so the style is applied
#: by making the axes under it (:func:`mechanism_axes`, and ``draw_mechanism``'s own figure).
MECHANISM_GRID: dict[str, Any] = {"grid.color": (0.86, 0.86, 0.86, 1.0), "grid.linewidth": 0.4}


def mechanism_axes(fig: Figure, *args: Any, **kwargs: Any) -> Axes3D:
    """A 3-D axes for :func:`draw_mechanism` in ``fig`` (``fig.add_subplot``'s arguments), with
    the light grid of :data:`MECHANISM_GRID`: a panel of a figure of several mechanisms."""
    with mpl.rc_context(MECHANISM_GRID):
        return fig.add_subplot(*args, projection="3d", **kwargs)


def figure_tag(path: str | os.PathLike[str]) -> str | None:
    """What a figure file is, from its name: ``fig05_...`` -> ``"Fig. 5"`` (the paper's figure
    number), ``extra_...`` -> ``"Beyond the paper"``; None for anything else."""
    stem = Path(path).name.lstrip(".")  # also a temporary file ``.extra_x.tmp123.png`` beside it
    m = re.match(r"fig(\d+)", stem)
    if m:
        return f"Fig. {int(m.group(1))}"
    return "Beyond the paper" if stem.startswith("extra_") else None


def tag_figure(fig: Figure, tag: str | None) -> None:
    """Make sure the figure's title says ``tag`` (its paper figure number, or "Beyond the paper"):
    unless a title already does, prefix the suptitle, else the title of a lone axes, else add a
    suptitle."""
    if not tag:
        return
    if tag.startswith("Fig. "):
        pattern = re.compile(rf"\bFigs?\.?\s*(\d+\s*[-–,]\s*)*{tag[5:]}\b", re.IGNORECASE)
    else:
        pattern = re.compile(r"beyond the paper|not in the paper|our addition", re.IGNORECASE)
    sup = _suptitle(fig)
    titles = [ax.get_title(loc) for ax in fig.axes for loc in ("center", "left", "right")]
    if any(pattern.search(t) for t in [fig.get_suptitle(), *titles]):
        return
    if sup is not None:
        sup.set_text(f"{tag}: {sup.get_text()}")
        return
    with_title = [ax for ax in fig.axes if ax.get_title()]
    if (
        len(with_title) == 1
        and len([ax for ax in fig.axes if ax.get_visible() and ax.get_label() != "<colorbar>"]) == 1
    ):
        ax = with_title[0]
        ax.set_title(f"{tag}: {ax.get_title()}")
        return
    fig.suptitle(tag, fontsize="medium")


def save_figure(
    fig: Figure, path: str | os.PathLike[str], *, close: bool = True, tag: bool = True
) -> Path:
    """Write ``fig`` to ``path`` (PNG unless the suffix says otherwise) atomically; return the path.

    With ``tag``, a figure named after a paper figure (``fig05_*``) or beyond the paper
    (``extra_*``) gets that in its title when no title says it yet (:func:`tag_figure`).

    The figure is rendered under :data:`STYLE` by Agg into a temporary file in the destination
    folder (created if missing), which then replaces ``path`` in one ``os.replace``: readers never
    see a partial file, and a failed save leaves no temporary file behind. PNG metadata carry no
    software version or time stamp (:data:`PNG_METADATA`), so saving the same figure twice gives
    byte-identical files. The figure is closed afterwards unless ``close=False``.
    """
    path = Path(path)
    if tag:
        tag_figure(fig, figure_tag(path))
    fit_titles(fig)
    fmt = path.suffix.lstrip(".").lower() or "png"
    kwargs: dict[str, Any] = {"format": fmt, "dpi": DPI}
    if fmt == "png":
        kwargs["metadata"] = dict(PNG_METADATA)
    elif fmt == "pdf":
        kwargs["metadata"] = {"Creator": None, "CreationDate": None}
    elif fmt == "svg":
        kwargs["metadata"] = {"Date": None}
    if fmt in ("png", "jpg", "jpeg", "tif", "tiff", "webp", "raw", "rgba"):
        kwargs["backend"] = "agg"

    def write(tmp: Path) -> None:
        with use_style():
            fig.savefig(tmp, **kwargs)

    try:
        atomic_writer(path, write)
    finally:
        if close:
            _close(fig)
    return path


def _suptitle(fig: Figure) -> Text | None:
    """The suptitle's :class:`~matplotlib.text.Text` (``Figure.suptitle`` adds it to
    ``fig.texts``), or None without one."""
    title = fig.get_suptitle()
    return next((t for t in fig.texts if t.get_text() == title), None) if title else None


def _words(text: str) -> list[str]:
    """``text`` split at the spaces outside mathtext (``$...$`` stays whole)."""
    words, current, math = [], "", False
    for ch in text:
        if ch == " " and not math:
            words.append(current)
            current = ""
            continue
        math ^= ch == "$"
        current += ch
    return [w for w in [*words, current] if w]


def _leaves_canvas(fig: Figure, text: Text, renderer) -> bool:
    box = text.get_window_extent(renderer)
    return box.x0 < 0.0 or box.x1 > fig.bbox.width


def wrap_to_canvas(fig: Figure, text: Text, renderer, width: float | None = None) -> None:
    """Break ``text`` (a title) at spaces into as few lines as keep it on the canvas.

    Each line is at most ``width`` pixels wide (default: twice the distance from the text's
    centre to the nearer canvas edge, less 4 px); existing line breaks are kept. A single word
    wider than that stays on a line of its own."""
    box = text.get_window_extent(renderer)
    centre = 0.5 * (box.x0 + box.x1)
    room = 2.0 * min(centre, fig.bbox.width - centre) - 8.0
    room = room if width is None else min(room, width)
    lines: list[str] = []
    for paragraph in text.get_text().split("\n"):
        line = ""
        for word in _words(paragraph):
            trial = f"{line} {word}" if line else word
            text.set_text(trial)
            if line and text.get_window_extent(renderer).width > room:
                lines.append(line)
                line = word
            else:
                line = trial
        lines.append(line)
    text.set_text("\n".join(lines))


def fit_titles(fig: Figure) -> None:
    """Wrap every title and the suptitle that leaves the canvas (:func:`wrap_to_canvas`); an
    axes title that does is wrapped to the width of its axes. A title that needs it is first set
    in the body's font size (a long title in the large title size takes four lines).

    Titles are measured where they stand before layout; only a figure with a title past an edge
    there is laid out (one draw) and measured again, so a figure whose titles fit is saved
    exactly as without this step (a layout draw moves constrained-layout axes by a pixel or so)."""
    texts = [(_suptitle(fig), None), *((ax.title, ax) for ax in fig.axes)]
    texts = [(t, ax) for t, ax in texts if t is not None and t.get_visible() and t.get_text()]
    with use_style():
        renderer = fig.canvas.get_renderer()
        near = [(t, ax) for t, ax in texts if _leaves_canvas(fig, t, renderer)]
        if not near:
            return
        fig.draw_without_rendering()  # lays the figure out: title positions are final
        for text, ax in near:
            if _leaves_canvas(fig, text, renderer):  # an axes title: no wider than its axes
                text.set_fontsize(min(text.get_fontsize(), mpl.rcParams["font.size"]))
                wrap_to_canvas(fig, text, renderer, ax and ax.get_window_extent(renderer).width)


def _close(fig: Figure) -> None:
    """Close ``fig`` if pyplot manages it (a no-op for parakin's own pyplot-free figures)."""
    import sys

    plt = sys.modules.get("matplotlib.pyplot")
    if plt is not None:
        plt.close(fig)


# ---------------------------------------------------------------------------------------- labels
_GREEK = {
    "alpha", "beta", "gamma", "delta", "epsilon", "zeta", "eta", "theta", "iota", "kappa",
    "lambda", "mu", "nu", "xi", "pi", "rho", "sigma", "tau", "upsilon", "phi", "chi", "psi",
    "omega", "Gamma", "Delta", "Theta", "Lambda", "Xi", "Pi", "Sigma", "Upsilon", "Phi", "Psi",
    "Omega",
}  # fmt: skip


def tex_label(name: str, *, frame: bool = False) -> str:
    """Mathtext for a point or frame name: ``"u_1"`` -> ``"$u_1$"``, ``"B_12"`` -> ``"$B_{12}$"``.

    Greek names become symbols (``"theta_2"`` -> ``"$\\theta_2$"``); ``frame=True`` wraps the
    name in braces (``"{u_1}"``). A name that already contains ``$`` is returned as it is.
    """
    if "$" in name:
        return name
    base, sep, sub = name.partition("_")
    base = f"\\{base}" if base in _GREEK else base
    body = base
    if sep:
        sub = f"\\{sub}" if sub in _GREEK else sub
        body += f"_{sub}" if len(sub) == 1 else f"_{{{sub}}}"
    if frame:
        body = f"\\{{{body}\\}}"
    return f"${body}$"


# ---------------------------------------------------------------------------------------- drawing
#: How each kind of :class:`Skeleton` element is drawn: line colour, width, style, legend label;
#: polygons also have a translucent face colour. Kinds not listed here fall back to
#: :data:`_FALLBACK_STYLE` with the kind as their legend label.
KIND_STYLES: dict[str, dict[str, Any]] = {
    "rail": {"color": "0.55", "lw": 0.9, "ls": (0, (5, 3)), "label": "rail / guide", "zorder": 2},
    "actuator": {"color": "#E69F00", "lw": 4.0, "ls": "-", "label": "actuator", "zorder": 3,
                 "solid_capstyle": "butt"},
    "passive": {"color": "0.15", "lw": 1.3, "ls": "-", "label": "passive link", "zorder": 4},
    "equivalent": {"color": "#CC79A7", "lw": 1.2, "ls": (0, (1, 1.6)),
                   "label": "equivalent rod", "zorder": 4},
    "base": {"color": "#3A6EA5", "lw": 1.0, "ls": "-", "face": "#9EC1E6", "alpha": 0.30,
             "label": "base", "zorder": 1},
    "platform": {"color": "#B5651D", "lw": 1.2, "ls": "-", "face": "#F6C28B", "alpha": 0.55,
                 "label": "platform", "zorder": 5},
}  # fmt: skip
_FALLBACK_STYLE: dict[str, Any] = {"color": "0.35", "lw": 1.0, "ls": "-", "face": "0.8",
                                   "alpha": 0.3, "zorder": 3}  # fmt: skip

#: Colours of frame axes x, y, z.
FRAME_AXIS_COLORS = ("#D62728", "#2CA02C", "#1F77B4")
_JOINT_KINDS = ("passive",)  # segment kinds whose end points are drawn as joints (open circles)
_POINT_COLOR = "black"
_LABEL_OFFSET_PT = 5.0  # distance of a label from its anchor (points)


def _style(kind: str) -> dict[str, Any]:
    style = dict(_FALLBACK_STYLE)
    style["label"] = kind.replace("_", " ")
    style.update(KIND_STYLES.get(kind, {}))
    return style


def _as_skeleton(skeleton_or_mech: Any, pose: ArrayLike | None) -> Skeleton:
    if isinstance(skeleton_or_mech, Skeleton):
        if pose is not None:
            raise ValueError("pose is only used with a mechanism; a Skeleton already has one pose")
        return skeleton_or_mech
    if not callable(getattr(skeleton_or_mech, "skeleton", None)):
        raise TypeError(
            f"expected a Skeleton or a mechanism with .skeleton(pose), got {type(skeleton_or_mech)!r}"
        )
    if pose is None:
        pose = skeleton_or_mech.home()
    return skeleton_or_mech.skeleton(pose)


def _all_coordinates(sk: Skeleton, frame_length: float) -> np.ndarray:
    chunks = [np.asarray(p, float).reshape(-1, 3) for p in sk.points.values()]
    chunks += [np.asarray(s, float).reshape(-1, 3) for _, s in sk.segments]
    chunks += [np.asarray(v, float).reshape(-1, 3) for _, v in sk.polygons]
    for origin, rot in sk.frames.values():
        o = np.asarray(origin, float)
        chunks.append(o[None, :])
        chunks.append(o + frame_length * np.asarray(rot, float).T)
    return np.concatenate(chunks) if chunks else np.zeros((1, 3))


def draw_mechanism(
    skeleton_or_mech: Any,
    pose: ArrayLike | None = None,
    ax: Axes3D | None = None,
    *,
    labels: bool = True,
    frames: bool = True,
    frame_length: float = 0.08,
    title: str | None = None,
    legend: bool = True,
    view: tuple[float, float] = (22.0, -62.0),
    size: str | tuple[float, float] = "mechanism",
) -> Axes3D:
    """Draw one assembly of a mechanism on a 3-D axes and return the axes.

    ``skeleton_or_mech`` is a :class:`~parakin.mechanisms.base.Skeleton` or a mechanism (then
    ``pose`` defaults to ``mech.home()``). Every segment is exactly one line (so ``ax.lines``
    matches ``skeleton.segments``, each with gid ``"segment:<i>:<kind>"``), styled by its kind
    (:data:`KIND_STYLES`: rails thin grey dashed, actuators thick coloured, passive links solid
    dark, equivalent rods dotted; unknown kinds get a neutral style and their name in the
    legend); polygons (base, platform) are translucent filled outlines; ends of passive links are
    marked as joints; named points are dots labelled in mathtext (``u_1`` -> :math:`u_1`); each
    frame is three arrows of ``frame_length`` metres (x red, y green, z blue) labelled
    ``{name}``. Labels go a few points from their anchor where they cover the fewest lines and
    no other label. The box aspect equals the data ranges (a metre is as long on every axis),
    the projection is orthographic, ``view`` is (elevation, azimuth) in degrees.

    With ``ax=None`` a new figure of size ``size`` (see :data:`FIGSIZE`) is created, the title
    (a ``suptitle``) and a legend strip go on top and the 3-D box is zoomed to fill the rest;
    the figure is ``ax.figure``. With a given ``ax`` the legend goes in its upper left corner and
    the title is the axes title; make it with :func:`mechanism_axes` for the same light grid. Drawing uses :data:`STYLE`; the result is deterministic.
    ``labels=False`` / ``frames=False`` / ``legend=False`` leave those out.
    """
    sk = _as_skeleton(skeleton_or_mech, pose)
    if not (np.isfinite(frame_length) and frame_length > 0):
        raise ValueError(f"frame_length = {frame_length!r} m must be a positive length")
    with use_style():
        own_figure = ax is None
        if ax is None:
            _, ax = new_figure(size, projection="3d", style=MECHANISM_GRID)
        if not isinstance(ax, Axes3D):
            raise TypeError(f"ax must be a 3-D axes (projection='3d'), got {type(ax).__name__}")
        ax.computed_zorder = False  # draw in the order of KIND_STYLES' zorder, not by depth
        handles: dict[str, Any] = {}
        _draw_polygons(ax, sk, handles)
        _draw_segments(ax, sk, handles)
        _draw_joints(ax, sk, handles)
        _draw_points(ax, sk)
        if frames and sk.frames:
            _draw_frames(ax, sk, frame_length, handles)
        _set_limits_and_view(ax, sk, frame_length if frames else 0.0, view)
        _style_panes(ax)
        # title and legend, then (own figure) fit the box below them, then the labels
        handle_list = list(handles.values()) if legend else []
        label_list = [_legend_label(key, h) for key, h in handles.items()] if legend else []
        legend_kw: dict[str, Any] = {
            "handles": handle_list,
            "labels": label_list,
            "handlelength": 2.4,
            "handler_map": {tuple: HandlerTuple(ndivide=None, pad=0.25)},
        }
        if own_figure:
            top = _title_and_legend_on_top(ax, title, legend_kw)
            _fit_axes3d(ax, top=top)
        else:
            if handle_list:
                ax.legend(loc="upper left", **legend_kw)
            if title:
                ax.set_title(title)
        if labels or frames:
            _place_labels(ax, sk, labels=labels, frames=frames, frame_length=frame_length)
    return ax


def _draw_polygons(ax: Axes3D, sk: Skeleton, handles: dict[str, Any]) -> None:
    """Polygons: translucent faces with a solid outline; one legend handle per kind."""
    for i, (kind, verts) in enumerate(sk.polygons):
        st = _style(kind)
        v = np.asarray(verts, float).reshape(-1, 3)
        poly = Poly3DCollection(
            [v], facecolors=mpl.colors.to_rgba(st["face"], st["alpha"]),
            edgecolors=st["color"], linewidths=st["lw"], zorder=st["zorder"],
        )  # fmt: skip
        poly.set_gid(f"polygon:{i}:{kind}")
        ax.add_collection3d(poly)
        handles.setdefault(
            kind,
            Patch(facecolor=mpl.colors.to_rgba(st["face"], st["alpha"]),
                  edgecolor=st["color"], linewidth=st["lw"], label=st["label"]),
        )  # fmt: skip


def _draw_segments(ax: Axes3D, sk: Skeleton, handles: dict[str, Any]) -> None:
    """Segments: exactly one Line3D each (``ax.lines`` has one entry per segment)."""
    for i, (kind, seg) in enumerate(sk.segments):
        st = _style(kind)
        s = np.asarray(seg, float).reshape(2, 3)
        extra = {k: st[k] for k in ("solid_capstyle",) if k in st}
        (line,) = ax.plot(
            s[:, 0], s[:, 1], s[:, 2], color=st["color"], lw=st["lw"], ls=st["ls"],
            zorder=st["zorder"], **extra,
        )  # fmt: skip
        line.set_gid(f"segment:{i}:{kind}")
        if kind not in handles:
            handles[kind] = Line2D([], [], color=st["color"], lw=st["lw"], ls=st["ls"],
                                   label=st["label"], **extra)  # fmt: skip


def _draw_joints(ax: Axes3D, sk: Skeleton, handles: dict[str, Any]) -> None:
    """Joints: open circles at the ends of passive links."""
    joints = _unique_rows(
        [np.asarray(s, float).reshape(2, 3) for k, s in sk.segments if k in _JOINT_KINDS]
    )
    if len(joints):
        sc = ax.scatter(
            joints[:, 0], joints[:, 1], joints[:, 2], s=9, marker="o", facecolors="white",
            edgecolors="0.15", linewidths=0.8, depthshade=False, zorder=6,
        )  # fmt: skip
        sc.set_gid("joints")
        handles["joint"] = Line2D([], [], ls="none", marker="o", ms=3.2, mfc="white",
                                  mec="0.15", mew=0.8, label="joint")  # fmt: skip


def _draw_points(ax: Axes3D, sk: Skeleton) -> None:
    """Named points: small dots."""
    if sk.points:
        pts = np.array([np.asarray(p, float).reshape(3) for p in sk.points.values()])
        sc = ax.scatter(pts[:, 0], pts[:, 1], pts[:, 2], s=7, color=_POINT_COLOR,
                        depthshade=False, zorder=7)  # fmt: skip
        sc.set_gid("points")


def _draw_frames(ax: Axes3D, sk: Skeleton, frame_length: float, handles: dict[str, Any]) -> None:
    """Frames: three arrows each (x red, y green, z blue), ``frame_length`` metres long."""
    origins = np.array([np.asarray(o, float).reshape(3) for o, _ in sk.frames.values()])
    rots = np.array([np.asarray(r, float).reshape(3, 3) for _, r in sk.frames.values()])
    for k, color in enumerate(FRAME_AXIS_COLORS):
        q = ax.quiver(
            origins[:, 0], origins[:, 1], origins[:, 2],
            rots[:, 0, k], rots[:, 1, k], rots[:, 2, k],
            length=frame_length, normalize=True, arrow_length_ratio=0.28,
            color=color, linewidths=1.1, zorder=8,
        )  # fmt: skip
        q.set_gid(f"frame_axes:{'xyz'[k]}")
    handles["frame axes"] = tuple(
        Line2D([], [], color=color, lw=1.4) for color in FRAME_AXIS_COLORS
    )


def _set_limits_and_view(
    ax: Axes3D, sk: Skeleton, frame_length: float, view: tuple[float, float]
) -> None:
    """Limits around everything drawn (frames ``frame_length`` long, 0 = none), equal aspect
    (a metre as long on every axis), orthographic ``view``, axis labels."""
    xyz = _all_coordinates(sk, frame_length)
    lo, hi = xyz.min(axis=0), xyz.max(axis=0)
    span = float(np.max(hi - lo)) or 1.0
    pad = 0.04 * span
    lo, hi = lo - pad, hi + pad
    ranges = np.maximum(hi - lo, 0.05 * span)
    mid = 0.5 * (lo + hi)
    lo, hi = mid - ranges / 2, mid + ranges / 2
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(tuple(ranges), zoom=1.0)
    ax.view_init(elev=view[0], azim=view[1])
    ax.set_proj_type("ortho")  # parallel lines stay parallel, as in a technical drawing
    ax.set_xlabel("$x$ (m)", labelpad=-2)
    ax.set_ylabel("$y$ (m)", labelpad=-2)
    ax.set_zlabel("$z$ (m)", labelpad=-4)


def _title_and_legend_on_top(ax: Axes3D, title: str | None, legend_kw: dict[str, Any]) -> float:
    """Put the title (a suptitle) and the legend (as many columns as fit, at most 5) at the top
    of the axes' own figure; return the pixel height below them."""
    fig = ax.figure
    top = fig.bbox.height
    pt = fig.dpi / 72.0
    if title:
        sup = fig.suptitle(title, y=1.0 - 3 * pt / fig.bbox.height, va="top")
        top = sup.get_window_extent(fig.canvas.get_renderer()).y0 - 2 * pt
    handle_list = legend_kw["handles"]
    if handle_list:
        renderer = fig.canvas.get_renderer()
        for ncols in range(min(len(handle_list), 5), 0, -1):  # widest that fits
            leg = ax.legend(
                loc="upper center", ncols=ncols, bbox_to_anchor=(0.5, top / fig.bbox.height),
                bbox_transform=fig.transFigure, borderaxespad=0.3, columnspacing=1.4,
                frameon=False, **legend_kw,
            )  # fmt: skip
            if leg.get_window_extent(renderer).width <= fig.bbox.width - 4 * pt:
                break
        top = leg.get_window_extent(renderer).y0
    return top


def _legend_label(key: str, handle: Any) -> str:
    if isinstance(handle, tuple):
        return "frame axes $x, y, z$"
    return handle.get_label()


def _style_panes(ax: Axes3D) -> None:
    """Light panes and grid, round-number ticks, small tick labels close to the axes."""
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_pane_color((0.97, 0.97, 0.97, 1.0))
        axis.set_major_locator(MaxNLocator(nbins=5, steps=[1, 2, 2.5, 5, 10]))
    ax.tick_params(axis="both", which="major", pad=-1, labelsize=6.5)
    ax.tick_params(axis="z", pad=0)


def _fit_axes3d(
    ax: Axes3D, *, top: float | None = None, margin_pt: float = 3.0, iterations: int = 4
) -> None:
    """Zoom and move a 3-D axes so its box, ticks and axis labels fill its figure below ``top``.

    A 3-D axes leaves wide empty margins around its box; this measures the drawn extent
    (:func:`_content_bbox`), scales it with ``set_box_aspect(zoom=...)`` to the figure (below
    ``top`` pixels, minus a margin) and centres it there, a few times over (tick labels do not
    scale with the box).
    """
    fig = ax.figure
    renderer = fig.canvas.get_renderer()
    # the box aspect as set_box_aspect stored it (normalised): kept while zooming; reading it back
    # rather than passing the ranges keeps the zoom, hence every figure, bit for bit as before
    aspect = np.asarray(ax.get_box_aspect(), float)
    zoom = 1.0
    m = margin_pt * fig.dpi / 72.0
    x0, y0, x1, y1 = m, m, fig.bbox.width - m, (fig.bbox.height if top is None else top) - m
    fw, fh = fig.bbox.width, fig.bbox.height
    for _ in range(iterations):
        bb = _content_bbox(ax, renderer)
        if bb.width <= 0 or bb.height <= 0:
            return
        s = min((x1 - x0) / bb.width, (y1 - y0) / bb.height)
        zoom *= s
        ax.set_box_aspect(aspect, zoom=zoom)
        pos = ax.get_position()  # figure fraction
        # move the axes so that the scaled content is centred in the target region
        cx, cy = (bb.x0 + bb.x1) / 2 / fw, (bb.y0 + bb.y1) / 2 / fh
        tx, ty = (x0 + x1) / 2 / fw, (y0 + y1) / 2 / fh
        ax_cx, ax_cy = pos.x0 + pos.width / 2, pos.y0 + pos.height / 2
        new_cx, new_cy = tx + (ax_cx - cx) * s, ty + (ax_cy - cy) * s
        ax.set_position([new_cx - pos.width / 2, new_cy - pos.height / 2, pos.width, pos.height])


def _content_bbox(ax: Axes3D, renderer: Any) -> Bbox:
    """Pixel extent of a 3-D axes' box (its 8 projected corners), ticks and axis labels.

    (``Axes3D.get_tightbbox`` reports the whole square axes, because its collections do.)
    """
    ax.figure.draw_without_rendering()  # lays out ticks and labels for the current zoom
    corners = np.array(np.meshgrid(ax.get_xlim3d(), ax.get_ylim3d(), ax.get_zlim3d())).reshape(
        3, -1
    )
    x, y, _ = proj3d.proj_transform(corners[0], corners[1], corners[2], ax.get_proj())
    px = ax.transData.transform(np.stack([x, y], axis=-1))
    boxes = [Bbox.from_extents(*px.min(axis=0), *px.max(axis=0))]
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        bb = axis.get_tightbbox(renderer)
        if bb is not None and np.all(np.isfinite(bb.extents)):
            boxes.append(bb)
    return Bbox.union(boxes)


def _unique_rows(arrays: list[np.ndarray], decimals: int = 9) -> np.ndarray:
    if not arrays:
        return np.zeros((0, 3))
    rows = np.concatenate(arrays)
    _, idx = np.unique(np.round(rows, decimals), axis=0, return_index=True)
    return rows[np.sort(idx)]


def _place_labels(
    ax: Axes3D, sk: Skeleton, *, labels: bool, frames: bool, frame_length: float
) -> None:
    """Label points and frames a few points from their anchors, where they cover the least.

    Works in display pixels: every line of the drawing (segments, polygon edges, frame arrows)
    is projected, and each label is tried in 24 directions at two distances from its anchor.
    A candidate's cost is the length of line its box covers, the area it shares with labels
    already placed (heavily penalised; within 6 px of one, prohibitively), the named points it covers, and whether it leaves the
    axes, minus a small bonus for pointing away from the drawing's centre. Frame labels are placed
    first, then points; the cheapest candidate wins (ties go to the first direction, so the
    result is deterministic).
    """
    fig = ax.figure
    ax.apply_aspect()  # fixes ax.transData for the 3-D projection (done again at draw time)
    to_px = _projector(ax)
    dpi = fig.dpi
    renderer = fig.canvas.get_renderer() if hasattr(fig.canvas, "get_renderer") else None
    seg_px, pts_px = _drawing_in_pixels(sk, frame_length if frames else None, to_px)
    xyz_all = _all_coordinates(sk, frame_length if frames else 0.0)
    centre = to_px(0.5 * (xyz_all.min(axis=0) + xyz_all.max(axis=0)))[0]
    # where labels may go: the axes, as far as it lies inside the figure (x0, y0, x1, y1 pixels)
    axbox = np.array(ax.bbox.extents)
    axbox[:2] = np.maximum(axbox[:2], 0.0)
    axbox[2:] = np.minimum(axbox[2:], [fig.bbox.width, fig.bbox.height])

    todo: list[tuple[np.ndarray, str, bool]] = []
    if frames:
        todo += [(np.asarray(o, float).reshape(3), tex_label(n, frame=True), True)
                 for n, (o, _) in sk.frames.items()]  # fmt: skip
    if labels:
        todo += [(np.asarray(p, float).reshape(3), tex_label(n), False)
                 for n, p in sk.points.items()]  # fmt: skip

    angles = np.deg2rad(np.arange(0.0, 360.0, 15.0))
    dirs = np.stack([np.cos(angles), np.sin(angles)], axis=-1)
    placed: list[np.ndarray] = []  # boxes (x0, y0, x1, y1) of labels already placed
    for pos, text, is_frame in todo:
        size = 8.0 if is_frame else 8.5
        w, h = _text_size(text, size, renderer, dpi)
        anchor = to_px(pos)[0]
        outward = anchor - centre
        n_out = np.linalg.norm(outward)
        outward = outward / n_out if n_out > 1e-9 else np.array([0.0, -1.0])
        obstacles = (seg_px, pts_px, placed, axbox)
        _, k, r_pt, box, ha_k, va_k = _best_label_box(anchor, (w, h), outward, dirs, dpi, obstacles)
        placed.append(box)
        dx, dy = r_pt * dirs[k]
        t = ax.text(
            pos[0], pos[1], pos[2], text,
            transform=offset_copy(ax.transData, fig=fig, x=float(dx), y=float(dy), units="points"),
            ha=("right", "left", "center")[int(ha_k)], va=("top", "bottom", "center")[int(va_k)],
            fontsize=size, color="0.3" if is_frame else "black", zorder=10,
            bbox={"boxstyle": "square,pad=0.05", "facecolor": "white", "edgecolor": "none",
                  "alpha": 0.65},
        )  # fmt: skip
        t.set_gid(("frame_label:" if is_frame else "point_label:") + text)


def _projector(ax: Axes3D) -> Callable[[ArrayLike], np.ndarray]:
    """A function from 3-D points (n, 3) to display pixels (n, 2) in ``ax``'s current view."""
    M = ax.get_proj()

    def to_px(p: ArrayLike) -> np.ndarray:
        p = np.atleast_2d(np.asarray(p, float))
        x, y, _ = proj3d.proj_transform(p[:, 0], p[:, 1], p[:, 2], M)
        return ax.transData.transform(np.stack([x, y], axis=-1))

    return to_px


def _drawing_in_pixels(
    sk: Skeleton, frame_length: float | None, to_px: Callable[[ArrayLike], np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """Every line drawn (segments, polygon edges, frame arrows ``frame_length`` long; None = no
    frames) as pixel segments (n, 2, 2), and the named points as pixels (m, 2)."""
    pieces3: list[np.ndarray] = [np.asarray(s, float).reshape(2, 3) for _, s in sk.segments]
    for _, verts in sk.polygons:
        v = np.asarray(verts, float).reshape(-1, 3)
        pieces3 += [np.stack([v[j], v[(j + 1) % len(v)]]) for j in range(len(v))]
    if frame_length is not None:
        for origin, rot in sk.frames.values():
            o = np.asarray(origin, float).reshape(3)
            r = np.asarray(rot, float).reshape(3, 3)
            pieces3 += [np.stack([o, o + frame_length * r[:, k] / np.linalg.norm(r[:, k])])
                        for k in range(3)]  # fmt: skip
    seg_px = to_px(np.concatenate(pieces3)).reshape(-1, 2, 2) if pieces3 else np.zeros((0, 2, 2))
    pts_px = to_px(np.array([np.asarray(p, float).reshape(3) for p in sk.points.values()])) \
        if sk.points else np.zeros((0, 2))  # fmt: skip
    return seg_px, pts_px


def _best_label_box(
    anchor: np.ndarray,
    size_px: tuple[float, float],
    outward: np.ndarray,
    dirs: np.ndarray,
    dpi: float,
    obstacles: tuple[np.ndarray, np.ndarray, list[np.ndarray], np.ndarray],
) -> tuple[float, int, float, np.ndarray, Any, Any]:
    """The cheapest place for a label of ``size_px`` (w, h pixels) near ``anchor``: tried in each
    direction ``dirs`` at two distances; ``obstacles`` = (pixel segments, pixel points, boxes of
    labels already placed, the area allowed). Returns (cost, direction index, distance in
    points, box, ha code, va code); ties go to the first direction and the nearer ring."""
    w, h = size_px
    seg_px, pts_px, placed, axbox = obstacles
    best = None
    for ring, r_pt in enumerate((_LABEL_OFFSET_PT, 2.0 * _LABEL_OFFSET_PT)):
        off = dirs * (r_pt * dpi / 72.0)  # (C, 2) pixels
        ha, va = _alignment(dirs)
        x0 = anchor[0] + off[:, 0] - np.where(ha == 0, w, np.where(ha == 1, 0.0, w / 2))
        y0 = anchor[1] + off[:, 1] - np.where(va == 0, h, np.where(va == 1, 0.0, h / 2))
        boxes = np.stack([x0, y0, x0 + w, y0 + h], axis=-1)
        pad = 1.5 * dpi / 72.0
        grown = boxes + np.array([-pad, -pad, pad, pad])
        cost = 2.0 * _clipped_length(grown, seg_px).sum(axis=1)
        if placed:
            cost += 0.5 * _overlap_area(grown, np.array(placed)).sum(axis=1)
            # labels that touch read as one: keep 6 px clear of every label placed (the box
            # estimated for a mathtext label runs a few pixels short of the drawn one)
            near = _overlap_area(boxes + np.array([-6.0, -6.0, 6.0, 6.0]), np.array(placed))
            cost += 1e4 * (near.sum(axis=1) > 0)
        if len(pts_px):
            inside = (
                (pts_px[None, :, 0] > grown[:, None, 0])
                & (pts_px[None, :, 0] < grown[:, None, 2])
                & (pts_px[None, :, 1] > grown[:, None, 1])
                & (pts_px[None, :, 1] < grown[:, None, 3])
            )
            cost += 60.0 * inside.sum(axis=1)  # fmt: skip
        outside = (
            np.maximum(axbox[0] - boxes[:, 0], 0)
            + np.maximum(boxes[:, 2] - axbox[2], 0)
            + np.maximum(axbox[1] - boxes[:, 1], 0)
            + np.maximum(boxes[:, 3] - axbox[3], 0)
        )
        cost += 20.0 * outside + 15.0 * ring - 8.0 * (dirs @ outward)  # fmt: skip
        k = int(np.argmin(np.round(cost, 6)))
        if best is None or round(float(cost[k]), 6) < best[0]:
            best = (round(float(cost[k]), 6), k, r_pt, boxes[k], ha[k], va[k])
    assert best is not None
    return best


def _alignment(dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Text alignment codes for label directions: ha 0 right, 1 left, 2 center; va 0 top,
    1 bottom, 2 center (a label to the right of its anchor is left-aligned, and so on)."""
    ha = np.where(dirs[:, 0] > 0.3, 1, np.where(dirs[:, 0] < -0.3, 0, 2))
    va = np.where(dirs[:, 1] > 0.3, 1, np.where(dirs[:, 1] < -0.3, 0, 2))
    return ha, va


def _text_size(text: str, size: float, renderer: Any, dpi: float) -> tuple[float, float]:
    """Width and height (pixels) of ``text`` in the current font at ``size`` points."""
    from matplotlib.font_manager import FontProperties

    if renderer is not None:
        w, h, _ = renderer.get_text_width_height_descent(
            text, FontProperties(size=size), ismath="$" in text
        )
        return float(w), float(h)
    return 0.6 * size * len(text) * dpi / 72.0, 1.2 * size * dpi / 72.0


def _clipped_length(boxes: np.ndarray, segs: np.ndarray) -> np.ndarray:
    """Length (pixels) of each segment (S, 2, 2) inside each box (B, 4): array (B, S)."""
    if len(segs) == 0:
        return np.zeros((len(boxes), 0))
    p0 = segs[None, :, 0, :]
    d = segs[None, :, 1, :] - p0
    b = boxes[:, None, :]
    t0 = np.zeros(np.broadcast_shapes(b.shape[:2], p0.shape[:2]))
    t1 = np.ones_like(t0)
    ok = np.ones_like(t0, dtype=bool)
    for p, q in (
        (-d[..., 0], p0[..., 0] - b[..., 0]),
        (d[..., 0], b[..., 2] - p0[..., 0]),
        (-d[..., 1], p0[..., 1] - b[..., 1]),
        (d[..., 1], b[..., 3] - p0[..., 1]),
    ):
        p = np.broadcast_to(p, t0.shape)
        q = np.broadcast_to(q, t0.shape)
        zero = np.abs(p) < 1e-12
        ok &= ~(zero & (q < 0))
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(zero, 0.0, q / np.where(zero, 1.0, p))
        t0 = np.where(~zero & (p < 0), np.maximum(t0, r), t0)
        t1 = np.where(~zero & (p > 0), np.minimum(t1, r), t1)
    frac = np.where(ok, np.clip(t1 - t0, 0.0, None), 0.0)
    return frac * np.linalg.norm(d, axis=-1)


def _overlap_area(boxes: np.ndarray, others: np.ndarray) -> np.ndarray:
    """Area (pixels^2) each box (B, 4) shares with each other box (O, 4): array (B, O)."""
    wx = np.minimum(boxes[:, None, 2], others[None, :, 2]) - np.maximum(
        boxes[:, None, 0], others[None, :, 0]
    )
    wy = np.minimum(boxes[:, None, 3], others[None, :, 3]) - np.maximum(
        boxes[:, None, 1], others[None, :, 1]
    )
    return np.clip(wx, 0, None) * np.clip(wy, 0, None)


def skeleton_table(skeleton_or_mech: Any, pose: ArrayLike | None = None, *,
                   frame_length: float = 0.08) -> pd.DataFrame:  # fmt: skip
    """The exact numbers :func:`draw_mechanism` plots, one row per drawn point (m).

    Columns ``element, kind, name, index, x, y, z``. Rows, in drawing order:

    * ``point`` -- each named point (``kind="point"``, ``name`` its name, ``index`` 0);
    * ``segment`` -- both ends of each segment (``kind`` its kind, ``name`` its position in
      ``skeleton.segments``, ``index`` 0 = start, 1 = end);
    * ``polygon`` -- each vertex of each closed outline (``name`` its position in
      ``skeleton.polygons``, ``index`` the vertex number);
    * ``frame`` -- each frame origin (``kind="origin"``, ``name`` the frame's name, ``index`` 0)
      followed by its three arrow tips, origin + ``frame_length`` * axis (``kind`` "x", "y", "z",
      ``index`` 1, 2, 3).

    Saved beside each mechanism figure as CSV, so the figure can be checked by numbers.
    """
    sk = _as_skeleton(skeleton_or_mech, pose)
    rows: list[tuple[str, str, str, int, float, float, float]] = []

    def row(element: str, kind: str, name: str, index: int, p: ArrayLike) -> None:
        x, y, z = (float(c) for c in np.asarray(p, float).reshape(3))
        rows.append((element, kind, name, index, x, y, z))

    for name, p in sk.points.items():
        row("point", "point", name, 0, p)
    for i, (kind, seg) in enumerate(sk.segments):
        s = np.asarray(seg, float).reshape(2, 3)
        row("segment", kind, str(i), 0, s[0])
        row("segment", kind, str(i), 1, s[1])
    for i, (kind, verts) in enumerate(sk.polygons):
        for j, v in enumerate(np.asarray(verts, float).reshape(-1, 3)):
            row("polygon", kind, str(i), j, v)
    for name, (origin, rot) in sk.frames.items():
        o = np.asarray(origin, float).reshape(3)
        r = np.asarray(rot, float).reshape(3, 3)
        row("frame", "origin", name, 0, o)
        for k in range(3):
            row(
                "frame", "xyz"[k], name, k + 1, o + frame_length * r[:, k] / np.linalg.norm(r[:, k])
            )
    df = pd.DataFrame(rows, columns=["element", "kind", "name", "index", "x", "y", "z"])
    return df.astype({"index": "int64", "x": "float64", "y": "float64", "z": "float64"})


def skeleton_from_table(table: pd.DataFrame) -> Skeleton:
    """The :class:`~parakin.mechanisms.base.Skeleton` a :func:`skeleton_table` lists (e.g. read
    back from the CSV saved beside a mechanism figure), so the figure can be redrawn from it alone.

    Points, segments and polygons come back in their order; a frame's axes are the unit vectors
    from its origin to its three arrow tips.
    """
    points: dict[str, np.ndarray] = {}
    segments: dict[str, list] = {}
    polygons: dict[str, list] = {}
    frames: dict[str, dict[str, np.ndarray]] = {}
    for r in table.itertuples(index=False):
        p = np.array([r.x, r.y, r.z], dtype=float)
        name = str(r.name)
        if r.element == "point":
            points[name] = p
        elif r.element == "segment":
            segments.setdefault(name, [str(r.kind), {}])[1][int(r.index)] = p
        elif r.element == "polygon":
            polygons.setdefault(name, [str(r.kind), {}])[1][int(r.index)] = p
        elif r.element == "frame":
            frames.setdefault(name, {})[str(r.kind)] = p
        else:
            raise ValueError(f"skeleton table: unknown element {r.element!r}")

    def ordered(vertices: dict[int, np.ndarray]) -> np.ndarray:
        return np.array([vertices[i] for i in sorted(vertices)])

    def axes(f: dict[str, np.ndarray]) -> np.ndarray:
        d = np.stack([f[k] - f["origin"] for k in "xyz"], axis=-1)
        return d / np.linalg.norm(d, axis=0)

    return Skeleton(
        points=points,
        segments=[(kind, ordered(v)) for kind, v in segments.values()],
        polygons=[(kind, ordered(v)) for kind, v in polygons.values()],
        frames={n: (f["origin"], axes(f)) for n, f in frames.items()},
    )
