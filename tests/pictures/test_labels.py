"""Check numbers placed off obstacles: anchors, box-segment tests and the placer on small figures."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("matplotlib", reason="the plots extra (matplotlib) is not installed")

from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.patches import Polygon
from matplotlib.text import Text

from drd_planner.pictures.geometry import PictureError
from drd_planner.pictures.labels import (
    LabelPlacer,
    PendingLabel,
    boxes_hit_segments,
    boxes_overlap,
    line_anchors,
)


def test_line_anchors_follow_the_arc_length() -> None:
    line = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]])
    assert line_anchors(line, (0.5, 0.25, 0.75, 1.0)) == pytest.approx(
        np.array([[10.0, 0.0], [5.0, 0.0], [10.0, 5.0], [10.0, 10.0]])
    )
    assert line_anchors(np.array([[3.0, 4.0]]), (0.5, 0.1)).tolist() == [[3.0, 4.0], [3.0, 4.0]]
    assert line_anchors(np.array([[1.0, 1.0], [1.0, 1.0]]), (0.5,)).tolist() == [[1.0, 1.0]]


def test_boxes_hit_segments_matches_dense_sampling() -> None:
    rng = np.random.default_rng(7)
    corners = rng.uniform(0.0, 100.0, (300, 2))
    boxes = np.concatenate([corners, corners + rng.uniform(2.0, 20.0, (300, 2))], axis=1)
    segments = rng.uniform(0.0, 120.0, (40, 2, 2))
    segments[:5, 1] = segments[:5, 0]  # dots
    half = rng.uniform(0.0, 3.0, 40)
    hit = boxes_hit_segments(boxes, segments, half)
    t = np.linspace(0.0, 1.0, 20_001)[:, None]
    expected = np.zeros(len(boxes), dtype=bool)
    for (a, b), w in zip(segments, half, strict=True):
        points = a + t * (b - a)  # (S, 2)
        inside = (
            (points[None, :, 0] >= boxes[:, None, 0] - w)
            & (points[None, :, 0] <= boxes[:, None, 2] + w)
            & (points[None, :, 1] >= boxes[:, None, 1] - w)
            & (points[None, :, 1] <= boxes[:, None, 3] + w)
        )
        expected |= inside.any(axis=1)
    assert 30 < expected.sum() < 290  # both outcomes occur
    assert hit.tolist() == expected.tolist()
    assert boxes_hit_segments(boxes, np.zeros((0, 2, 2)), np.zeros(0)).sum() == 0


def test_boxes_overlap() -> None:
    boxes = np.array([[0.0, 0.0, 2.0, 2.0], [5.0, 5.0, 6.0, 6.0], [2.0, 0.0, 3.0, 1.5], [2.0, 0.0, 3.0, 1.0]])
    others = np.array([[1.0, 1.0, 4.0, 4.0]])
    assert boxes_overlap(boxes, others).tolist() == [True, False, True, False]  # touching is apart
    assert boxes_overlap(boxes, np.zeros((0, 4))).tolist() == [False] * 4


def _panel() -> tuple[Figure, Axes]:
    fig = Figure(figsize=(4.0, 4.0), dpi=150)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.1, 0.1, 0.8, 0.8))
    ax.set_xlim(0.0, 100.0)
    ax.set_ylim(0.0, 100.0)
    return fig, ax


def _box(fig: Figure, text: Text) -> np.ndarray:
    fig.canvas.draw()
    extent = text.get_bbox_patch().get_window_extent(fig.canvas.get_renderer())
    return np.array([extent.x0, extent.y0, extent.x1, extent.y1])


def _pixels(ax: Axes, points: np.ndarray) -> np.ndarray:
    return np.asarray(ax.transData.transform(points))


def test_a_label_moves_off_a_wire_along_its_edge_with_a_leader() -> None:
    fig, ax = _panel()
    wire = LineCollection([[[0.0, 50.0], [100.0, 50.0]]], linewidths=1.4)
    ax.add_collection(wire)
    placer = LabelPlacer(ax, [wire], [])
    edge = np.array([[20.0, 50.0], [80.0, 50.0]])  # right under the wire
    (text,), counts = placer.place([PendingLabel("7", "#2ca02c", edge)])
    assert counts == {"moved": 1, "hidden": 0}
    assert text.get_visible()
    assert text.get_text() == "7"
    box = _box(fig, text)
    pixels = _pixels(ax, np.array([[0.0, 50.0], [100.0, 50.0]]))[None]
    assert not boxes_hit_segments(box[None], pixels, np.array([1.4 * 150 / 72 / 2]))[0]
    (leader,) = ax.get_lines()
    start = leader.get_xydata()[0]
    # from the edge to the label
    assert start[1] == pytest.approx(50.0)
    assert 20.0 <= start[0] <= 80.0
    assert leader.get_color() == "#2ca02c"


def test_labels_keep_apart_and_clear_of_the_start() -> None:
    fig, ax = _panel()
    (start,) = ax.plot(50.0, 50.0, "o", markersize=8)
    placer = LabelPlacer(ax, [], [start])
    edge = np.array([[40.0, 50.0], [60.0, 50.0]])  # its middle is the start marker
    texts, counts = placer.place([PendingLabel(str(k), "black", edge) for k in range(3)])
    boxes = np.stack([_box(fig, t) for t in texts])
    marker = start.get_window_extent(fig.canvas.get_renderer())
    assert not boxes_overlap(boxes, np.array([[marker.x0, marker.y0, marker.x1, marker.y1]])).any()
    for k in range(3):
        others = np.delete(boxes, k, axis=0)
        assert not boxes_overlap(boxes[k : k + 1], others)[0]
    assert counts["hidden"] == 0


def test_a_background_surface_takes_labels_but_not_across_its_outline() -> None:
    fig, ax = _panel()
    table = Polygon([[5.0, 5.0], [95.0, 5.0], [95.0, 95.0], [5.0, 95.0]], closed=True, alpha=0.3)
    block = Polygon([[60.0, 20.0], [90.0, 20.0], [90.0, 40.0], [60.0, 40.0]], closed=True, alpha=0.3)
    for patch in (table, block):
        ax.add_patch(patch)
    placer = LabelPlacer(ax, [table, block], [])
    on_table = np.array([[20.0, 60.0], [40.0, 60.0]])
    on_block = np.array([[65.0, 30.0], [85.0, 30.0]])
    texts, counts = placer.place([PendingLabel("1", "red", on_table), PendingLabel("2", "red", on_block)])
    assert texts[0].get_position() == pytest.approx((30.0, 60.0))  # on the table, on its edge
    x, y = texts[1].get_position()
    assert not (60.0 <= x <= 90.0 and 20.0 <= y <= 40.0)  # off the block
    assert counts == {"moved": 1, "hidden": 0}
    block_path = block.get_path().transformed(block.get_transform())
    fig.canvas.draw()
    extent = texts[1].get_bbox_patch().get_window_extent(fig.canvas.get_renderer())
    assert not block_path.intersects_bbox(extent, filled=True)


def test_a_label_with_no_free_spot_is_thinned() -> None:
    _, ax = _panel()
    hatch = LineCollection([[[0.0, y], [100.0, y]] for y in np.arange(0.0, 101.0, 1.5)], linewidths=0.5)
    ax.add_collection(hatch)
    placer = LabelPlacer(ax, [hatch], [])
    (text,), counts = placer.place([PendingLabel("3", "red", np.array([[40.0, 40.0], [60.0, 60.0]]))])
    assert counts == {"moved": 0, "hidden": 1}
    assert not text.get_visible()


def test_unknown_obstacle_artists_are_refused() -> None:
    _, ax = _panel()
    note = ax.text(1.0, 1.0, "x")
    with pytest.raises(PictureError, match="LineCollection, Patch or Line2D"):
        LabelPlacer(ax, [note], [])
