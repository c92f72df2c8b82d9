"""Plan messages serialized in bulk: the bytes of rosbags' serializer, decoded by rclpy into the same message."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from drd_msgs_py.cdr import ENCAPSULATION, diagnostic_array_cdr, joint_trajectory_cdr, path_cdr
from drd_msgs_py.factory import MessageFactory, RclpyMessages, RosbagsMessages
from drd_msgs_py.plans import (
    CheckRecord,
    check_statuses,
    diagnostics_message,
    edge_checks_message,
    joint_trajectory_message,
    path_message,
    summary_fields,
    summary_status,
)

PATH = "nav_msgs/msg/Path"
TRAJECTORY = "trajectory_msgs/msg/JointTrajectory"
DIAGNOSTICS = "diagnostic_msgs/msg/DiagnosticArray"
#: Frames of every length modulo 8 (each shifts the padding before a pose's float64 values), and UTF-8.
FRAMES = ["", "m", "ma", "map", "odom", "world", "base_l", "panda_link0", "kärta"]
JOINTS = [[], ["j"], ["a", "bb", "ccc"], [f"panda_joint{i}" for i in range(1, 8)]]


@pytest.fixture(scope="module")
def typestore() -> Any:
    return get_typestore(Stores.ROS2_JAZZY)


def _rclpy() -> tuple[Any, Any]:
    """rclpy's decoder and message classes, or a skip when the wheels are absent."""
    pytest.importorskip("nav_msgs.msg", reason="rclpy message wheels not installed")
    from rclpy.serialization import deserialize_message

    return deserialize_message, RclpyMessages()


@pytest.mark.parametrize("frame", FRAMES)
@pytest.mark.parametrize("count", [0, 1, 2, 5])
@pytest.mark.parametrize("columns", [3, 4])
def test_path_bytes_are_rosbags_bytes_and_decode_to_path_message(
    typestore: Any, frame: str, count: int, columns: int
) -> None:
    states = np.random.default_rng(count).normal(scale=100.0, size=(count, columns))
    data = path_cdr(states, frame_id=frame, stamp=(12, 345))
    assert data.startswith(ENCAPSULATION)
    built = path_message(states, frame_id=frame, stamp=(12, 345), msgs=RosbagsMessages(typestore))
    assert bytes(typestore.serialize_cdr(built, PATH)) == data
    deserialize, msgs = _rclpy()
    from nav_msgs.msg import Path

    assert deserialize(data, Path) == path_message(states, frame_id=frame, stamp=(12, 345), msgs=msgs)


@pytest.mark.parametrize("names", JOINTS, ids=len)
@pytest.mark.parametrize("count", [0, 1, 2, 5])
@pytest.mark.parametrize("seconds", [0.02, 0.3, 1.0])
def test_trajectory_bytes_are_rosbags_bytes_and_decode_to_the_message(
    typestore: Any, names: list[str], count: int, seconds: float
) -> None:
    q = np.random.default_rng(count).normal(size=(count, len(names)))
    for frame in ("", "panda_link0", "abc"):
        data = joint_trajectory_cdr(names, q, frame_id=frame, stamp=(-3, 9), seconds_per_point=seconds)
        kwargs = {"frame_id": frame, "stamp": (-3, 9), "seconds_per_point": seconds}
        built = joint_trajectory_message(names, q, msgs=RosbagsMessages(typestore), **kwargs)  # type: ignore[arg-type]
        assert bytes(typestore.serialize_cdr(built, TRAJECTORY)) == data
        deserialize, msgs = _rclpy()
        from trajectory_msgs.msg import JointTrajectory

        assert deserialize(data, JointTrajectory) == joint_trajectory_message(names, q, msgs=msgs, **kwargs)  # type: ignore[arg-type]


def test_a_plan_of_heli_lines_size_is_one_block_of_equal_records(typestore: Any) -> None:
    states = np.column_stack([np.linspace(0, 2500, 679), np.zeros(679), np.full(679, 60.0), np.ones(679)])
    data = path_cdr(states, frame_id="map", stamp=(1, 2))
    decoded = typestore.deserialize_cdr(data, PATH)
    assert len(decoded.poses) == 679
    assert decoded.poses[-1].header.frame_id == "map"
    assert decoded.poses[-1].pose.position.x == 2500.0
    assert decoded.poses[3].pose.orientation.z == pytest.approx(np.sin(0.5))


def test_bad_shapes_are_refused_as_the_message_builders_refuse_them() -> None:
    with pytest.raises(ValueError, match=r"\(K, >= 3\)"):
        path_cdr(np.zeros((4, 2)), frame_id="map")
    with pytest.raises(ValueError, match=r"\(K, 2\)"):
        joint_trajectory_cdr(["a", "b"], np.zeros((4, 3)), frame_id="map")


def _checks(count: int) -> list[CheckRecord]:
    return [
        CheckRecord(
            k + 1,
            40 + k,
            k % 3 != 1,
            ("tree", "bisect", "improve")[k % 3],
            0.1234 * k,
            (k, k + 7),
            k % 2 == 0,
        )
        for k in range(count)
    ]


def _summary(msgs: MessageFactory | None) -> Any:
    values = {
        "tree": "heli_lines",
        "checks": 8,
        "total_s": "0.012345",
        "result": "found",
        "request": "goal_pose",
    }
    kwargs = {"ok": True, "message": "path of 7 edges", "values": values, "name": "drd_planner: plan"}
    if msgs is None:
        return summary_fields(**kwargs)  # type: ignore[arg-type]
    return diagnostics_message([summary_status(**kwargs, msgs=msgs)], stamp=(8, 9), msgs=msgs)  # type: ignore[arg-type]


@pytest.mark.parametrize("count", [0, 1, 2, 9])
def test_check_log_bytes_are_rosbags_bytes_and_decode_to_edge_checks_message(typestore: Any, count: int) -> None:
    data = diagnostic_array_cdr(check_statuses(_checks(count), hardware_id="node"), stamp=(8, 9))
    built = edge_checks_message(_checks(count), stamp=(8, 9), hardware_id="node", msgs=RosbagsMessages(typestore))
    assert bytes(typestore.serialize_cdr(built, DIAGNOSTICS)) == data
    deserialize, msgs = _rclpy()
    from diagnostic_msgs.msg import DiagnosticArray

    decoded = deserialize(data, DiagnosticArray)
    assert decoded == edge_checks_message(_checks(count), stamp=(8, 9), hardware_id="node", msgs=msgs)
    if count > 1:
        assert decoded.status[1].level == b"\x02"
        assert decoded.status[1].values[2].value == "0.123"


def test_summary_bytes_are_rosbags_bytes_and_decode_to_the_summary(typestore: Any) -> None:
    data = diagnostic_array_cdr([_summary(None)], stamp=(8, 9))
    assert bytes(typestore.serialize_cdr(_summary(RosbagsMessages(typestore)), DIAGNOSTICS)) == data
    deserialize, msgs = _rclpy()
    from diagnostic_msgs.msg import DiagnosticArray

    assert deserialize(data, DiagnosticArray) == _summary(msgs)
