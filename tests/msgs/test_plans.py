"""Checked-edge markers: DELETEALL first, a ready background, one LINE_LIST per outcome."""

from __future__ import annotations

import numpy as np
import pytest

from drd_msgs_py.plans import EDGE_COLOURS, checked_edges_markers, line_list_marker


def test_checked_edge_markers_keep_every_segment_in_its_colour(msgs: object) -> None:
    rng = np.random.default_rng(0)
    segments = rng.normal(size=(7, 2, 3))
    outcome = np.array([1, 0, 1, -1, 0, 1, 1])
    background = line_list_marker(
        segments[:2], ns="library", rgba=EDGE_COLOURS[-1], frame_id="map", msgs=msgs
    )  # type: ignore[arg-type]
    array = checked_edges_markers(segments, outcome, frame_id="map", msgs=msgs, background=[background])  # type: ignore[arg-type]
    markers = list(array.markers)
    assert markers[0].action == 3 and markers[1] is background
    by_ns = {m.ns: m for m in markers[2:]}
    assert set(by_ns) == {"free", "blocked", "unchecked"}
    for value, name in ((1, "free"), (0, "blocked"), (-1, "unchecked")):
        pts = np.array([[p.x, p.y, p.z] for p in by_ns[name].points])
        np.testing.assert_allclose(pts, segments[outcome == value].reshape(-1, 3))
        assert by_ns[name].color.g == pytest.approx(EDGE_COLOURS[value][1])
    with pytest.raises(ValueError, match="one outcome per segment"):
        checked_edges_markers(segments, outcome[:3], frame_id="map", msgs=msgs)  # type: ignore[arg-type]
