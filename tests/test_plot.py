"""Tests of parakin.plot: the shared style, atomic deterministic saving, the mechanism drawing.

The figure-regression test compares against ``tests/baseline/`` with pytest-mpl. Regenerate the
baseline after an intended change of the drawing with::

    python -m pytest tests/test_plot.py --mpl-generate-path=tests/baseline -p no:cacheprovider -o addopts=""

and check it with ``--mpl --mpl-baseline-path=tests/baseline``.
"""

from __future__ import annotations

import os
import struct
from pathlib import Path

import matplotlib as mpl
import numpy as np
import pandas as pd
import pytest
from mpl_toolkits.mplot3d import Axes3D, proj3d

from parakin.mechanisms.base import Skeleton
from parakin.mechanisms.p3p4s import P3P4S
from parakin.plot import (
    DPI,
    FIGSIZE,
    PNG_METADATA,
    STYLE,
    draw_mechanism,
    new_figure,
    save_figure,
    skeleton_table,
    tex_label,
    use_style,
)

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def skeleton() -> Skeleton:
    mech = P3P4S()
    return mech.skeleton(mech.home())


@pytest.fixture(scope="module")
def drawn(skeleton: Skeleton) -> Axes3D:
    return draw_mechanism(skeleton)


def _png_chunks(data: bytes) -> list[tuple[bytes, bytes]]:
    assert data[:8] == PNG_MAGIC
    chunks, i = [], 8
    while i < len(data):
        (n,) = struct.unpack(">I", data[i : i + 4])
        chunks.append((data[i + 4 : i + 8], data[i + 8 : i + 8 + n]))
        i += 12 + n
    return chunks


# ------------------------------------------------------------------------------------- style
def test_style_is_deterministic_and_applies() -> None:
    assert STYLE["font.sans-serif"] == ["DejaVu Sans"]
    assert STYLE["figure.dpi"] == STYLE["savefig.dpi"] == DPI
    assert STYLE["svg.hashsalt"]
    assert STYLE["axes.grid"] is True
    assert FIGSIZE["single"][0] == pytest.approx(3.5) and FIGSIZE["double"][0] == pytest.approx(7.0)
    before = mpl.rcParams["font.size"]
    with use_style({"font.size": 11.0}) as params:
        assert mpl.rcParams["font.size"] == 11.0 == params["font.size"]
        assert mpl.rcParams["svg.hashsalt"] == STYLE["svg.hashsalt"]
    assert mpl.rcParams["font.size"] == before  # restored

    @use_style()
    def font() -> list[str]:
        return list(mpl.rcParams["font.sans-serif"])

    assert font() == font() == ["DejaVu Sans"]  # also a (re-usable) decorator
    backend = mpl.get_backend()
    fig, _ax = new_figure("double")
    assert mpl.get_backend() == backend  # the library never switches the user's backend
    assert tuple(fig.get_size_inches()) == pytest.approx(FIGSIZE["double"])
    assert fig.dpi == DPI
    assert type(fig.canvas).__name__ == "FigureCanvasAgg"


@pytest.mark.parametrize(
    ("name", "frame", "expected"),
    [
        ("u_1", False, "$u_1$"),
        ("O", False, "$O$"),
        ("B_12", False, "$B_{12}$"),
        ("theta_2", False, r"$\theta_2$"),
        ("u_1", True, r"$\{u_1\}$"),
        ("P", True, r"$\{P\}$"),
        ("$q$", False, "$q$"),
    ],
)
def test_tex_label(name: str, frame: bool, expected: str) -> None:
    assert tex_label(name, frame=frame) == expected


# ------------------------------------------------------------------------------------- drawing
def test_draw_mechanism_one_line_per_segment(skeleton: Skeleton, drawn: Axes3D) -> None:
    ax = drawn
    assert isinstance(ax, Axes3D)
    assert len(ax.lines) == len(skeleton.segments)
    kinds = [line.get_gid().split(":")[2] for line in ax.lines]
    assert kinds == [kind for kind, _ in skeleton.segments]
    for line, (_, seg) in zip(ax.lines, skeleton.segments, strict=True):
        xs, ys, zs = line.get_data_3d()
        np.testing.assert_allclose(np.stack([xs, ys, zs], axis=-1), seg)
    # per-kind styles differ: actuators are the thickest, rails dashed, equivalent rods dotted
    by_kind = {line.get_gid().split(":")[2]: line for line in ax.lines}
    assert by_kind["actuator"].get_linewidth() > by_kind["passive"].get_linewidth()
    assert by_kind["actuator"].get_linestyle() == by_kind["passive"].get_linestyle() == "-"
    assert by_kind["rail"].get_linestyle() != "-" and by_kind["equivalent"].get_linestyle() != "-"
    assert mpl.colors.to_hex(by_kind["rail"].get_color()) == "#8c8c8c"  # grey
    # polygons as filled translucent collections
    polys = [c for c in ax.collections if (c.get_gid() or "").startswith("polygon:")]
    assert [p.get_gid().split(":")[2] for p in polys] == [kind for kind, _ in skeleton.polygons]
    assert all(0 < p.get_facecolor()[0][3] < 1 for p in polys)


def test_draw_mechanism_labels_frames_legend(skeleton: Skeleton, drawn: Axes3D) -> None:
    texts = [t.get_text() for t in drawn.texts]
    for name in skeleton.points:
        assert tex_label(name) in texts
    for name in ("O", "P", "u_1", "u_2", "u_3"):
        assert f"$\\{{{name}\\}}$" in texts
    assert len(texts) == len(skeleton.points) + len(skeleton.frames)
    # every frame drawn as three arrows: one quiver per axis colour, one arrow per frame
    quivers = [c for c in drawn.collections if (c.get_gid() or "").startswith("frame_axes:")]
    assert [q.get_gid() for q in quivers] == ["frame_axes:x", "frame_axes:y", "frame_axes:z"]
    legend = [t.get_text() for t in drawn.get_legend().get_texts()]
    for label in ("rail / guide", "actuator", "passive link", "equivalent rod", "base", "platform",
                  "joint", "frame axes $x, y, z$"):  # fmt: skip
        assert label in legend
    assert drawn.get_xlabel() == "$x$ (m)" and drawn.get_zlabel() == "$z$ (m)"


def test_draw_mechanism_labels_inside_figure_and_apart(drawn: Axes3D) -> None:
    """Labels do not leave the figure and no two labels overlap."""
    fig = drawn.figure
    fig.draw_without_rendering()
    renderer = fig.canvas.get_renderer()
    boxes = []
    for t in drawn.texts:  # a Text3D knows its screen position only while drawn: project it
        x3, y3, z3 = t._x, t._y, t._z
        x2, y2, _ = proj3d.proj_transform(x3, y3, z3, drawn.get_proj())
        t._x, t._y = x2, y2
        try:
            boxes.append(t.get_window_extent(renderer))
        finally:
            t._x, t._y = x3, y3
    for b in boxes:
        assert b.x0 >= 0 and b.y0 >= 0 and b.x1 <= fig.bbox.width and b.y1 <= fig.bbox.height
    for i, a in enumerate(boxes):
        for b in boxes[i + 1 :]:
            assert not a.overlaps(b), (a, b)


def test_draw_mechanism_equal_aspect(skeleton: Skeleton, drawn: Axes3D) -> None:
    ranges = np.array(
        [np.ptp(drawn.get_xlim3d()), np.ptp(drawn.get_ylim3d()), np.ptp(drawn.get_zlim3d())]
    )
    aspect = np.asarray(drawn._box_aspect)  # what set_box_aspect stored
    np.testing.assert_allclose(aspect / aspect[0], ranges / ranges[0], rtol=1e-9)
    # every drawn coordinate lies inside the limits
    table = skeleton_table(skeleton)
    lo = np.array([drawn.get_xlim3d()[0], drawn.get_ylim3d()[0], drawn.get_zlim3d()[0]])
    hi = np.array([drawn.get_xlim3d()[1], drawn.get_ylim3d()[1], drawn.get_zlim3d()[1]])
    xyz = table[["x", "y", "z"]].to_numpy()
    assert np.all(xyz >= lo) and np.all(xyz <= hi)


def test_draw_mechanism_accepts_mechanism_and_axes(skeleton: Skeleton) -> None:
    mech = P3P4S()
    ax = draw_mechanism(mech, labels=False, frames=False, legend=False)
    assert len(ax.lines) == len(skeleton.segments)
    assert len(ax.texts) == 0 and ax.get_legend() is None
    _fig, own = new_figure("double_tall", projection="3d")
    out = draw_mechanism(mech, mech.home(), own, title="home pose")
    assert out is own and own.get_title() == "home pose"
    with pytest.raises(ValueError, match="pose"):
        draw_mechanism(skeleton, mech.home())
    with pytest.raises(TypeError, match="3-D"):
        draw_mechanism(skeleton, ax=new_figure()[1])
    with pytest.raises(TypeError, match="skeleton"):
        draw_mechanism(object())
    with pytest.raises(ValueError, match="frame_length"):
        draw_mechanism(skeleton, frame_length=0.0)


def test_draw_mechanism_is_generic() -> None:
    """Any Skeleton draws, including kinds the style table does not know."""
    base = np.array([[0.3, 0.0, 0.0], [-0.15, 0.26, 0.0], [-0.15, -0.26, 0.0]])
    top = base * 0.5 + [0.0, 0.0, 0.4]
    sk = Skeleton(
        points={"A_1": base[0], "alpha": top[0]},
        segments=[("actuator", np.stack([b, t])) for b, t in zip(base, top, strict=True)]
        + [("cable", np.stack([base[0], top[1]]))],
        polygons=[("base", base), ("platform", top)],
        frames={"W": (np.zeros(3), np.eye(3))},
    )
    ax = draw_mechanism(sk)
    assert len(ax.lines) == 4
    assert {"$A_1$", r"$\alpha$", r"$\{W\}$"} <= {t.get_text() for t in ax.texts}
    assert "cable" in [t.get_text() for t in ax.get_legend().get_texts()]


# ------------------------------------------------------------------------------------- table
def test_skeleton_table_rows_and_coordinates(skeleton: Skeleton) -> None:
    df = skeleton_table(skeleton)
    assert list(df.columns) == ["element", "kind", "name", "index", "x", "y", "z"]
    n_vertices = sum(len(v) for _, v in skeleton.polygons)
    assert len(df) == len(skeleton.points) + 2 * len(skeleton.segments) + n_vertices + 4 * len(
        skeleton.frames
    )
    counts = df["element"].value_counts()
    assert counts["point"] == len(skeleton.points)
    assert counts["segment"] == 2 * len(skeleton.segments)
    assert counts["polygon"] == n_vertices
    assert (df.query("element == 'frame' and kind == 'origin'")["name"].tolist()
            == list(skeleton.frames))  # fmt: skip
    assert np.all(np.isfinite(df[["x", "y", "z"]].to_numpy()))
    points = df[df["element"] == "point"].set_index("name")
    for name, p in skeleton.points.items():
        np.testing.assert_array_equal(points.loc[name, ["x", "y", "z"]].to_numpy(float), p)
    seg = df[df["element"] == "segment"]
    for i, (kind, s) in enumerate(skeleton.segments):
        rows = seg[seg["name"] == str(i)].sort_values("index")
        assert (rows["kind"] == kind).all()
        np.testing.assert_array_equal(rows[["x", "y", "z"]].to_numpy(float), s)
    for name, (origin, rot) in skeleton.frames.items():
        rows = df[(df["element"] == "frame") & (df["name"] == name)].sort_values("index")
        xyz = rows[["x", "y", "z"]].to_numpy(float)
        np.testing.assert_array_equal(xyz[0], origin)
        np.testing.assert_allclose(xyz[1:], origin + 0.08 * rot.T, atol=1e-15)
    # a mechanism and its home pose give the same table
    pd.testing.assert_frame_equal(skeleton_table(P3P4S()), df)


# ------------------------------------------------------------------------------------- saving
def test_save_figure_atomic_png(tmp_path: Path, skeleton: Skeleton) -> None:
    target = tmp_path / "nested" / "dir" / "fig01_mechanism.png"
    fig = draw_mechanism(skeleton).figure
    out = save_figure(fig, target, close=False)
    assert out == target
    first = target.read_bytes()
    assert first[:8] == PNG_MAGIC
    assert os.listdir(target.parent) == [target.name]  # no temporary file left behind
    ihdr = _png_chunks(first)[0]
    assert ihdr[0] == b"IHDR"
    width, height = struct.unpack(">II", ihdr[1][:8])
    assert (width, height) == tuple(round(v * DPI) for v in fig.get_size_inches())
    # no software version, no time stamp in the file
    kinds = {kind for kind, _ in _png_chunks(first)}
    assert not kinds & {b"tEXt", b"iTXt", b"zTXt", b"tIME"}
    assert PNG_METADATA == {"Software": None}
    # saving the same figure again, and drawing it afresh, give the same bytes
    save_figure(fig, target)
    assert target.read_bytes() == first
    save_figure(
        draw_mechanism(skeleton).figure, tmp_path / "again" / "fig01_mechanism.png"
    )  # same tag "Fig. 1"
    assert (tmp_path / "again" / "fig01_mechanism.png").read_bytes() == first


def test_save_figure_failure_leaves_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    target = tmp_path / "fig.png"
    target.write_bytes(b"old")
    fig, ax = new_figure()
    ax.plot([0, 1], [0, 1])

    def boom(*args, **kwargs):
        raise RuntimeError("disk full")

    monkeypatch.setattr(fig, "savefig", boom)
    with pytest.raises(RuntimeError, match="disk full"):
        save_figure(fig, target)
    assert target.read_bytes() == b"old"  # the previous file is untouched
    assert os.listdir(tmp_path) == ["fig.png"]


# ------------------------------------------------------------------------------------- regression
@pytest.mark.mpl_image_compare(
    tolerance=2,
    style=STYLE,
    savefig_kwargs={"dpi": DPI, "metadata": PNG_METADATA},
    filename="p3p4s_home.png",
)
def test_figure_p3p4s_home():
    """The 3-P(4S) at the paper's home pose, as Fig. 2 of zhao2017_3p4s is redrawn."""
    mech = P3P4S()
    return draw_mechanism(mech, mech.home()).figure


def test_figures_carry_their_paper_figure_number(tmp_path: Path) -> None:
    """save_figure puts 'Fig. N' (from a fig<N>_ file name) or 'Beyond the paper' (extra_) in the
    title unless a title already says it (issue 18: every figure titled with its number)."""
    from parakin.plot import figure_tag, new_figure

    assert (
        figure_tag("fig05_cm_velocity.png") == "Fig. 5"
        and figure_tag("extra_basin.png") == "Beyond the paper"
    )
    assert figure_tag("sketch.png") is None
    # the temporary file an atomic write draws into tags as its target would
    assert figure_tag(".extra_census.abc123.tmp.png") == "Beyond the paper"
    fig, ax = new_figure()
    ax.set_title("CM velocity")
    save_figure(fig, tmp_path / "fig05_cm_velocity.png", close=False)
    assert ax.get_title() == "Fig. 5: CM velocity"
    fig, ax = new_figure()
    ax.set_title("Fig. 5, surrogate")
    save_figure(fig, tmp_path / "fig05_x.png", close=False)
    assert ax.get_title() == "Fig. 5, surrogate"
    fig, ax = new_figure()
    save_figure(fig, tmp_path / "extra_thing.png", close=False)
    assert fig._suptitle is not None and fig._suptitle.get_text() == "Beyond the paper"
