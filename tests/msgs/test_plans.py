"""Plan messages: checked-edge markers (DELETEALL first, a ready background), path poses, trajectory times."""

from __future__ import annotations

import numpy as np
import pytest

from drd_msgs_py.plans import (
    EDGE_COLOURS,
    checked_edges_markers,
    joint_trajectory_message,
    line_list_marker,
    path_poses,
    trajectory_times,
)


def test_checked_edge_markers_keep_every_segment_in_its_colour(msgs: object) -> None:
    rng = np.random.default_rng(0)
    segments = rng.normal(size=(7, 2, 3))
    outcome = np.array([1, 0, 1, -1, 0, 1, 1])
    background = line_list_marker(segments[:2], ns="library", rgba=EDGE_COLOURS[-1], frame_id="map", msgs=msgs)  # type: ignore[arg-type]
    array = checked_edges_markers(segments, outcome, frame_id="map", msgs=msgs, background=[background])  # type: ignore[arg-type]
    markers = list(array.markers)
    assert markers[0].action == 3
    assert markers[1] is background
    by_ns = {m.ns: m for m in markers[2:]}
    assert set(by_ns) == {"free", "blocked", "unchecked"}
    for value, name in ((1, "free"), (0, "blocked"), (-1, "unchecked")):
        pts = np.array([[p.x, p.y, p.z] for p in by_ns[name].points])
        np.testing.assert_allclose(pts, segments[outcome == value].reshape(-1, 3))
        assert by_ns[name].color.g == pytest.approx(EDGE_COLOURS[value][1])
    with pytest.raises(ValueError, match="one outcome per segment"):
        checked_edges_markers(segments, outcome[:3], frame_id="map", msgs=msgs)  # type: ignore[arg-type]


def test_path_poses_turn_headings_into_quaternions_about_z() -> None:
    poses = path_poses([[1.0, 2.0, 3.0, np.pi / 2], [4.0, 5.0, 6.0, 0.0]])
    np.testing.assert_allclose(poses[:, :3], [[1, 2, 3], [4, 5, 6]])
    np.testing.assert_allclose(poses[:, 3:], [[0, 0, np.sin(np.pi / 4), np.cos(np.pi / 4)], [0, 0, 0, 1]])
    np.testing.assert_array_equal(path_poses(np.zeros((2, 3)))[:, 3:], [[0, 0, 0, 1]] * 2)  # no heading
    with pytest.raises(ValueError, match=r"\(K, >= 3\)"):
        path_poses(np.zeros(3))


def test_trajectory_times_round_the_fraction_as_python_does() -> None:
    for seconds in (0.02, 0.1, 0.3, 1.0, 2.5, 0.0625):
        times = trajectory_times(40, seconds)
        expected = [[int(k * seconds), round((k * seconds - int(k * seconds)) * 1e9)] for k in range(40)]
        assert times.tolist() == expected
    assert trajectory_times(0, 1.0).shape == (0, 2)


def test_a_trajectory_point_owns_its_positions(msgs: object) -> None:
    q = np.zeros((2, 3))
    trajectory = joint_trajectory_message(["a", "b", "c"], q, frame_id="base", msgs=msgs)  # type: ignore[arg-type]
    q[:] = 1.0  # the caller's array changes after the message was built
    assert [list(p.positions) for p in trajectory.points] == [[0.0] * 3] * 2
    assert [(p.time_from_start.sec, p.time_from_start.nanosec) for p in trajectory.points] == [(0, 0), (1, 0)]
