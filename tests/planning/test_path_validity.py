"""Is a path still valid (planning/path_validity.py): only what the maps changed is re-checked."""

from __future__ import annotations

from typing import Any

import numpy as np
from test_nav2_codes import _ready, messages, prior  # noqa: F401 (fixtures)

from drd_msgs_py.bags import BagMessage, jazzy_typestore
from drd_msgs_py.factory import RosbagsMessages
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Box
from drd_planner.planning.path_validity import ServedPaths
from drd_planner.planning.world_messages import obstacle_markers


def _box_at(service: Any, xyz: Any, key: str = "blocking/1") -> None:
    box = [(key, Box((30.0, 30.0, 30.0)), Pose(position=tuple(float(v) for v in xyz)))]
    msg = obstacle_markers(box, frame_id="map", msgs=RosbagsMessages(jazzy_typestore()), delete_all_first=False)
    service.take_map("obstacles", msg)


def test_a_served_path_is_re_checked_only_where_the_maps_changed(
    prior: Any,  # noqa: F811
    messages: list[BagMessage],  # noqa: F811
) -> None:
    service, goal = _ready(prior, messages)
    outcome = service.serve_request(goal, None)
    assert outcome.ok
    assert outcome.result is not None
    assert outcome.session is not None
    served = ServedPaths(service.planning_lock)
    positions = outcome.result.states[:, :3]
    yaws = outcome.result.states[:, 3]
    assert outcome.snapshot is not None
    served.remember(outcome.session, outcome.result.path_edges, positions, outcome.snapshot)
    same = served.validity(positions, yaws, service.sessions, service.snapshot)
    assert same.valid
    assert same.served
    assert same.rechecked == 0
    assert same.invalid == ()
    _box_at(service, positions[len(positions) // 2], key="blocking/1")
    blocked = served.validity(positions, yaws, service.sessions, service.snapshot)
    assert not blocked.valid
    assert blocked.served
    assert blocked.rechecked >= 1
    assert len(positions) // 2 in blocked.invalid
    assert len(blocked.invalid) < len(positions)


def test_a_kept_path_is_then_known_free_on_the_new_maps(
    prior: Any,  # noqa: F811
    messages: list[BagMessage],  # noqa: F811
) -> None:
    service, goal = _ready(prior, messages)
    outcome = service.serve_request(goal, None)
    assert outcome.result is not None
    assert outcome.session is not None
    assert outcome.snapshot is not None
    served = ServedPaths()
    positions, yaws = outcome.result.states[:, :3], outcome.result.states[:, 3]
    served.remember(outcome.session, outcome.result.path_edges, positions, outcome.snapshot)
    _box_at(service, positions[len(positions) // 2] + np.array([0.0, 0.0, 60.0]), key="near/3")  # near, free
    first = served.validity(positions, yaws, service.sessions, service.snapshot)
    assert first.valid
    assert first.served
    again = served.validity(positions, yaws, service.sessions, service.snapshot)
    # verified on these maps already
    assert again.valid
    assert again.rechecked == 0


def test_a_path_it_did_not_serve_is_checked_pose_by_pose_and_an_empty_one_is_not_valid(
    prior: Any,  # noqa: F811
    messages: list[BagMessage],  # noqa: F811
) -> None:
    service, goal = _ready(prior, messages)
    outcome = service.serve_request(goal, None)
    assert outcome.result is not None
    positions = outcome.result.states[:, :3] + np.array([0.0, 0.0, 0.5])  # not the served poses
    yaws = outcome.result.states[:, 3]
    served = ServedPaths()
    free = served.validity(positions, yaws, service.sessions, service.snapshot)
    assert free.valid
    assert not free.served
    assert free.rechecked == len(positions)
    _box_at(service, positions[3])
    blocked = served.validity(positions, yaws, service.sessions, service.snapshot)
    assert not blocked.valid
    assert 3 in blocked.invalid
    empty = served.validity(np.zeros((0, 3)), np.zeros(0), service.sessions, service.snapshot)
    assert not empty.valid
    assert empty.invalid == ()
