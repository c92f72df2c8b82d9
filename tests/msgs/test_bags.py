"""MCAP bags (rosbags): round trips, offered QoS, requests, refusals, the bundled bags."""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from bag_messages import SEC, T0, goal_message, obstacles_message, stamp, terrain_message
from conftest import REPO_ROOT, SHARED_DATA
from rosbags.interfaces import QosDurability, QosReliability

from drd_msgs_py.bags import (
    BagError,
    BagMessage,
    bag_frame,
    bag_requests,
    default_qos,
    jazzy_typestore,
    open_bag,
    read_bag,
    request_at,
    write_bag,
)
from drd_msgs_py.factory import RosbagsMessages, header

JOINTS = [f"panda_joint{i}" for i in range(1, 8)]


@pytest.fixture
def rb() -> RosbagsMessages:
    return RosbagsMessages(jazzy_typestore())


def _joints(rb: RosbagsMessages, t: int, names: list[str], q: list[float]) -> BagMessage:
    msg = rb(
        "sensor_msgs/msg/JointState",
        header=header(rb, "", stamp(t)),
        name=names,
        position=np.asarray(q, dtype=np.float64),
    )
    return BagMessage("/goal_joints", "sensor_msgs/msg/JointState", t, msg)


def _scenario(rb: RosbagsMessages) -> list[BagMessage]:
    """Maps at 0, a request at 0.5 s, a refused map (wrong frame) at 1 s, an update at 1.5 s, a request at 2.5 s."""
    return [
        terrain_message(rb, T0),
        obstacles_message(rb, T0),
        goal_message(rb, T0 + SEC // 2, (100.0, 0.0, 40.0)),
        obstacles_message(rb, T0 + SEC, extra=True, frame="odom"),
        obstacles_message(rb, T0 + 3 * SEC // 2, extra=True),
        goal_message(rb, T0 + 5 * SEC // 2, (100.0, 0.0, 40.0)),
    ]


def _cdr(m: BagMessage) -> bytes:
    return bytes(jazzy_typestore().serialize_cdr(m.message, m.msgtype))


def test_round_trip_gives_equal_messages_in_time_order(rb: RosbagsMessages, tmp_path: Path) -> None:
    messages = [
        *_scenario(rb),
        _joints(rb, T0 + 3 * SEC, JOINTS, [0.1 * i for i in range(7)]),
        BagMessage("/robot_description", "std_msgs/msg/String", T0, rb("std_msgs/msg/String", data="<robot/>")),
    ]
    shuffled = [messages[i] for i in np.random.default_rng(0).permutation(len(messages))]
    path = write_bag(tmp_path / "s.mcap", shuffled)
    assert path.is_file(), "no temporary folder is left behind"
    assert not list(tmp_path.glob(".s-*")), "no temporary folder is left behind"
    back = read_bag(path)
    want = sorted(messages, key=lambda m: m.time_ns)
    assert [(m.topic, m.msgtype, m.time_ns) for m in back] == [(m.topic, m.msgtype, m.time_ns) for m in want]
    assert [_cdr(m) for m in back] == [_cdr(m) for m in want]  # field-for-field equal
    assert back[-1].message.name == JOINTS
    assert back[-1].message.position[3] == pytest.approx(0.3)
    raw = open_bag(path)
    assert raw.duration_ns == 3 * SEC
    assert {t.name: t.count for t in raw.topics.values()}["/obstacles"] == 3


def test_offered_qos_is_latched_on_map_topics_only(rb: RosbagsMessages, tmp_path: Path) -> None:
    messages = [
        *_scenario(rb),
        BagMessage("/robot_description", "std_msgs/msg/String", T0, rb("std_msgs/msg/String", data="x")),
        _joints(rb, T0 + 3 * SEC, JOINTS, [0.0] * 7),
    ]
    topics = open_bag(write_bag(tmp_path / "q.mcap", messages)).topics
    for name in ("/obstacles", "/terrain", "/robot_description"):
        (qos,) = topics[name].qos
        assert (qos.durability, qos.reliability, qos.depth) == (
            QosDurability.TRANSIENT_LOCAL,
            QosReliability.RELIABLE,
            1,
        ), name
    for name in ("/goal_pose", "/goal_joints"):
        (qos,) = topics[name].qos
        assert (qos.durability, qos.reliability, qos.depth) == (
            QosDurability.VOLATILE,
            QosReliability.RELIABLE,
            10,
        )
    # An explicit profile wins over the rule.
    custom = {"/goal_pose": default_qos("obstacles")}
    topics = open_bag(write_bag(tmp_path / "c.mcap", messages, qos=custom)).topics
    assert topics["/goal_pose"].qos[0].durability == QosDurability.TRANSIENT_LOCAL


def test_requests_and_frame_of_a_bag(rb: RosbagsMessages, tmp_path: Path) -> None:
    messages = read_bag(write_bag(tmp_path / "m.mcap", _scenario(rb)))
    assert [(r.index, r.kind, r.time_ns, r.position) for r in bag_requests(messages)] == [
        (0, "goal_pose", T0 + SEC // 2, 2),
        (1, "goal_pose", T0 + 5 * SEC // 2, 5),
    ]
    assert request_at(messages, 1).time_ns == T0 + 5 * SEC // 2
    assert bag_frame(messages) == "map"
    assert bag_frame(messages[2:3]) is None


def test_missing_corrupt_and_foreign_bags_give_one_clear_error(rb: RosbagsMessages, tmp_path: Path) -> None:
    with pytest.raises(BagError, match="does not exist"):
        open_bag(tmp_path / "nope.mcap")
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(np.random.default_rng(1).bytes(3000))
    with pytest.raises(BagError, match="not a readable rosbag2 MCAP bag"):
        open_bag(junk)
    good = write_bag(tmp_path / "good.mcap", _scenario(rb))
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    with pytest.raises(BagError, match=r"cut\.mcap"):
        open_bag(cut)
    text = tmp_path / "bag.txt"
    text.write_text("hello")
    with pytest.raises(BagError, match=r"bag\.txt"):
        open_bag(text)
    with pytest.raises(BagError, match="exists already"):
        write_bag(good, _scenario(rb))
    with pytest.raises(BagError, match="has 2 request"):
        request_at(read_bag(good), 2)
    bad_type = BagMessage("/x", "nosuch_msgs/msg/Thing", T0, None)
    with pytest.raises(BagError, match="nosuch_msgs"):
        write_bag(tmp_path / "t.mcap", [bad_type])
    assert not (tmp_path / "t.mcap").exists()


@pytest.mark.slow
@pytest.mark.parametrize("name", ["heli_wires", "heli_lines", "arm_table_clutter"])
def test_bundled_bags_are_small_latched_and_reproducible(name: str, tmp_path: Path) -> None:
    bundled = REPO_ROOT / "bags" / f"{name}.mcap"
    if not bundled.is_file():
        pytest.skip(f"{bundled} not generated (python scripts/tools/make_bags.py)")
    if name.startswith("arm") and not (SHARED_DATA / "panda" / "panda.urdf").is_file():
        pytest.skip("the shared Panda files are needed to plan on the arm bag")
    if name == "heli_lines" and not (SHARED_DATA / "terrain" / "srtm_front_range_144.asc").is_file():
        pytest.skip("the shared elevation model is needed to draw the heli_lines world")
    contents = open_bag(bundled)
    assert bundled.stat().st_size < 2 * 1024 * 1024
    assert contents.topics["/obstacles"].qos[0].durability == QosDurability.TRANSIENT_LOCAL
    assert [r.kind for r in bag_requests(contents.decoded())] == ["goal_pose" if "heli" in name else "goal_joints"] * 4
    only = name if name.startswith("heli") else "arm"
    run = subprocess.run(
        [
            sys.executable,
            str(REPO_ROOT / "scripts" / "tools" / "make_bags.py"),
            "--only",
            only,
            "--out-dir",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    assert "world seed" in run.stdout
    assert "blocked" in run.stdout
    regenerated = open_bag(tmp_path / f"{name}.mcap")
    # Byte-equal on the machine that wrote it; elsewhere a float may differ in its last bits (another BLAS
    # kernel on another CPU: seen as 1 ULP in an arm obstacle pose), so floats are compared to 1e-12.
    assert _same_messages(regenerated.decoded(), contents.decoded()), (
        "the bundled bag is stale: run python scripts/tools/make_bags.py"
    )


def _same_messages(a: list[BagMessage], b: list[BagMessage]) -> bool:
    """Same topics, types, times and fields, floats equal to a relative 1e-12."""
    return len(a) == len(b) and all(
        (x.topic, x.msgtype, x.time_ns) == (y.topic, y.msgtype, y.time_ns) and _same_field(x.message, y.message)
        for x, y in zip(a, b, strict=True)
    )


def _same_field(a: object, b: object) -> bool:
    """Recursive equality of deserialized message fields with a 1e-12 tolerance on floats."""
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        return type(a) is type(b) and all(
            _same_field(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a)
        )
    if isinstance(a, np.ndarray) and isinstance(b, np.ndarray):
        if a.dtype.kind == "f":
            return a.shape == b.shape and bool(np.allclose(a, b, rtol=1e-12, atol=1e-12))
        return bool(np.array_equal(a, b))
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return len(a) == len(b) and all(_same_field(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) and isinstance(b, float):
        return math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-12)
    return a == b


def test_bag_comparison_tolerates_last_bits_of_floats_only(rb: RosbagsMessages) -> None:
    base = [_joints(rb, T0, JOINTS[:2], [0.5, 0.25])]
    assert _same_messages(base, [_joints(rb, T0, JOINTS[:2], [np.nextafter(0.5, 1.0), 0.25])])
    assert not _same_messages(base, [_joints(rb, T0, JOINTS[:2], [0.5 + 1e-6, 0.25])])
    assert not _same_messages(base, [_joints(rb, T0, JOINTS[:2][::-1], [0.5, 0.25])])
    assert not _same_messages(base, [_joints(rb, T0 + 1, JOINTS[:2], [0.5, 0.25])])
    assert not _same_messages(base, [])
