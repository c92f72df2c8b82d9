"""Rosbag2 MCAP bags of maps and requests (rosbags): reading, writing, and finding the requests.

A bag here is one self-contained ``.mcap`` file as rosbag2's MCAP storage writes it (``ros2 bag play
FILE.mcap`` and :class:`rosbags.rosbag2.Reader` open it directly): every channel carries its topic, type,
message definition and the **offered QoS** of its publisher in its metadata. rosbags writes empty QoS
unless told, and an empty QoS replays as volatile, so :func:`write_bag` always gives one explicitly:

- map topics (``obstacles``, ``terrain``, ``robot_description``): reliable, transient_local, depth 1
  (a late subscriber still gets the latest map; so every ``obstacles`` message should be a whole map);
- every other topic: reliable, volatile, depth 10.

:func:`bag_requests` lists a bag's planning requests and :func:`request_at` finds one; applying the map
messages before a request as a planner does is the planner's part (drd_planner's ``planning.bag_plan``).
Times are integer nanoseconds.
"""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.store import Typestore

from drd_msgs_py.exceptions import MessageError
from drd_msgs_py.topics import MAP_TOPICS, REQUEST_TOPICS, topic_base

__all__ = [
    "MAP_TOPICS",
    "REQUEST_TOPICS",
    "BagContents",
    "BagError",
    "BagMessage",
    "BagRequest",
    "BagTopic",
    "RawMessage",
    "bag_frame",
    "bag_requests",
    "default_qos",
    "jazzy_typestore",
    "latched_qos",
    "open_bag",
    "read_bag",
    "request_at",
    "topic_base",
    "volatile_qos",
    "write_bag",
    "write_raw_bag",
]


_UNSET = QosTime(0, 0)  # "unspecified": the middleware default (infinite deadline, lifespan, lease)


class BagError(MessageError):
    """A bag that cannot be written or read: missing, not a rosbag2 MCAP file, corrupt, inconsistent."""


def latched_qos(depth: int = 1) -> Qos:
    """Reliable, transient_local, keep-last ``depth``: what a map server offers."""
    return Qos(
        QosHistory.KEEP_LAST,
        depth,
        QosReliability.RELIABLE,
        QosDurability.TRANSIENT_LOCAL,
        _UNSET,
        _UNSET,
        QosLiveliness.AUTOMATIC,
        _UNSET,
        False,
    )


def volatile_qos(depth: int = 10) -> Qos:
    """Reliable, volatile, keep-last ``depth``: requests and ordinary streams."""
    return latched_qos(depth)._replace(durability=QosDurability.VOLATILE)


def default_qos(topic: str, *, latched: Iterable[str] = MAP_TOPICS) -> Qos:
    """The offered QoS of ``topic`` under the rules of the module docstring (``latched``: base names)."""
    return latched_qos() if topic_base(topic) in set(latched) else volatile_qos()


@lru_cache(maxsize=1)
def jazzy_typestore() -> Typestore:
    """The rosbags typestore of ROS 2 Jazzy's message definitions (built once).

    The cache holds a constant: the typestore depends on nothing but the fixed Jazzy definitions.
    """
    return get_typestore(Stores.ROS2_JAZZY)


@dataclass(frozen=True)
class RawMessage:
    """One serialized message of a bag.

    Attributes:
        topic: topic name as stored (``/obstacles``).
        msgtype: ``pkg/msg/Name``.
        time_ns: receive/log time, integer ns.
        data: the CDR bytes (with the 4-byte encapsulation header), as rclpy publishes them.
    """

    topic: str
    msgtype: str
    time_ns: int
    data: bytes


@dataclass(frozen=True)
class BagMessage:
    """One decoded message of a bag (a rosbags dataclass in ``message``); fields as :class:`RawMessage`."""

    topic: str
    msgtype: str
    time_ns: int
    message: Any


@dataclass(frozen=True)
class BagTopic:
    """A topic of a bag: its type, the QoS profiles its publishers offered, its message count."""

    name: str
    msgtype: str
    qos: tuple[Qos, ...]
    count: int


@dataclass(frozen=True)
class BagContents:
    """A whole bag in memory.

    Attributes:
        path: where it was read from.
        topics: topic name -> :class:`BagTopic`.
        messages: every message in time order (ties keep the file's order).
    """

    path: Path
    topics: Mapping[str, BagTopic]
    messages: tuple[RawMessage, ...]

    @property
    def duration_ns(self) -> int:
        """Time from the first to the last message (0 for an empty bag)."""
        return self.messages[-1].time_ns - self.messages[0].time_ns if self.messages else 0

    def decoded(self, typestore: Typestore | None = None) -> list[BagMessage]:
        """Every message deserialized with ``typestore`` (default: :func:`jazzy_typestore`).

        Raises:
            BagError: a message that does not deserialize as its declared type.
        """
        store = typestore or jazzy_typestore()
        out = []
        for raw in self.messages:
            try:
                message = store.deserialize_cdr(raw.data, raw.msgtype)
            except Exception as exc:  # rosbags raises assorted errors on bad CDR or unknown types
                raise BagError(
                    f"{self.path}: message on {raw.topic} at {raw.time_ns} ns is not a valid {raw.msgtype}: {exc}"
                ) from exc
            out.append(BagMessage(raw.topic, raw.msgtype, raw.time_ns, message))
        return out


# --------------------------------------------------------------------------------------------------
# Writing


def _validate(messages: Sequence[RawMessage]) -> None:
    types: dict[str, str] = {}
    for m in messages:
        if isinstance(m.time_ns, bool) or not isinstance(m.time_ns, (int, np.integer)) or m.time_ns < 0:
            raise BagError(f"message on {m.topic}: time must be an integer >= 0 ns, got {m.time_ns!r}")
        if not m.topic:
            raise BagError("a message has an empty topic name")
        if types.setdefault(m.topic, m.msgtype) != m.msgtype:
            raise BagError(f"topic {m.topic} has messages of two types: {types[m.topic]} and {m.msgtype}")


def write_raw_bag(
    path: str | Path,
    messages: Iterable[RawMessage],
    *,
    qos: Mapping[str, Qos] | None = None,
    typestore: Typestore | None = None,
    overwrite: bool = False,
) -> Path:
    """Write serialized messages as one rosbag2 MCAP file (topics in first-appearance order).

    Args:
        path: the ``.mcap`` file to write.
        messages: the messages; written in time order.
        qos: topic -> offered QoS; topics not in it get :func:`default_qos`.
        typestore: where message definitions come from (default: :func:`jazzy_typestore`).
        overwrite: replace an existing file (otherwise an existing file is an error).

    Returns:
        ``path``.

    Raises:
        BagError: the file exists, a type unknown to the typestore, bad times, or a write error.
    """
    out = Path(path)
    if out.exists() and not overwrite:
        raise BagError(f"{out} exists already (not overwriting)")
    ordered = sorted(messages, key=lambda m: m.time_ns)
    _validate(ordered)
    store = typestore or jazzy_typestore()
    offered = dict(qos or {})
    out.parent.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix=f".{out.stem}-", dir=out.parent))
    try:
        writer = Writer(work / "bag", version=Writer.VERSION_LATEST, storage_plugin=StoragePlugin.MCAP)
        with writer:
            connections: dict[str, Any] = {}
            for m in ordered:
                if m.topic not in connections:
                    if m.msgtype not in store.types:
                        raise BagError(f"topic {m.topic}: message type {m.msgtype} is unknown to the typestore")
                    profile = offered.get(m.topic, default_qos(m.topic))
                    connections[m.topic] = writer.add_connection(
                        m.topic, m.msgtype, typestore=store, offered_qos_profiles=[profile]
                    )
                writer.write(connections[m.topic], int(m.time_ns), bytes(m.data))
        files = sorted((work / "bag").glob("*.mcap"))
        if len(files) != 1:
            raise BagError(f"rosbags wrote {len(files)} MCAP files for {out}, expected 1")
        files[0].replace(out)
    except BagError:
        raise
    except Exception as exc:  # rosbags WriterError, OSError, ...
        raise BagError(f"cannot write {out}: {exc}") from exc
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return out


def write_bag(
    path: str | Path,
    messages: Iterable[BagMessage],
    *,
    qos: Mapping[str, Qos] | None = None,
    typestore: Typestore | None = None,
    overwrite: bool = False,
) -> Path:
    """Serialize decoded messages (rosbags dataclasses) with the typestore and write them (:func:`write_raw_bag`).

    Raises:
        BagError: a message that does not serialize as its declared type, or any error of
            :func:`write_raw_bag`.
    """
    store = typestore or jazzy_typestore()
    raw = []
    for m in messages:
        try:
            data = bytes(store.serialize_cdr(m.message, m.msgtype))
        except Exception as exc:  # rosbags raises assorted errors on mismatched dataclasses
            raise BagError(f"message on {m.topic} at {m.time_ns} ns is not a valid {m.msgtype}: {exc}") from exc
        raw.append(RawMessage(m.topic, m.msgtype, m.time_ns, data))
    return write_raw_bag(path, raw, qos=qos, typestore=store, overwrite=overwrite)


# --------------------------------------------------------------------------------------------------
# Reading


def open_bag(path: str | Path) -> BagContents:
    """Read a whole bag: a ``.mcap`` file, or a rosbag2 folder (``metadata.yaml`` + storage files).

    Raises:
        BagError: missing, unreadable, not a rosbag2 bag, or corrupt (the text names the file).
    """
    where = Path(path)
    if not where.exists():
        raise BagError(f"bag {where} does not exist")
    try:
        with Reader(where) as reader:
            topics: dict[str, BagTopic] = {}
            for conn in reader.connections:
                profiles = tuple(getattr(conn.ext, "offered_qos_profiles", ()) or ())
                known = topics.get(conn.topic)
                if known is not None and known.msgtype != conn.msgtype:
                    raise BagError(f"bag {where}: topic {conn.topic} has two types {known.msgtype}, {conn.msgtype}")
                topics[conn.topic] = BagTopic(
                    conn.topic,
                    conn.msgtype,
                    (known.qos if known else ()) + profiles,
                    (known.count if known else 0) + int(conn.msgcount),
                )
            raw = [RawMessage(c.topic, c.msgtype, int(t), bytes(d)) for c, t, d in reader.messages()]
    except BagError:
        raise
    except Exception as exc:  # rosbags ReaderError, struct/zstd/yaml errors on corrupt files, OSError
        raise BagError(f"bag {where} is not a readable rosbag2 MCAP bag: {type(exc).__name__}: {exc}") from exc
    raw.sort(key=lambda m: m.time_ns)
    return BagContents(where, topics, tuple(raw))


def read_bag(path: str | Path, *, typestore: Typestore | None = None) -> list[BagMessage]:
    """Every message of a bag, decoded, in time order (see :func:`open_bag`, :meth:`BagContents.decoded`)."""
    return open_bag(path).decoded(typestore)


# --------------------------------------------------------------------------------------------------
# Requests and maps


@dataclass(frozen=True)
class BagRequest:
    """A planning request of a bag.

    Attributes:
        index: 0-based among the bag's requests.
        position: index of the message in the bag's time-ordered message list.
        time_ns: its bag time.
        topic: ``goal_pose`` or ``goal_joints`` (as stored, possibly with a namespace).
        message: the decoded PoseStamped or JointState.
    """

    index: int
    position: int
    time_ns: int
    topic: str
    message: Any

    @property
    def kind(self) -> str:
        """``goal_pose`` or ``goal_joints``."""
        return topic_base(self.topic)


def bag_requests(messages: Sequence[BagMessage]) -> list[BagRequest]:
    """The requests (``goal_pose``, ``goal_joints``) among time-ordered ``messages``."""
    out: list[BagRequest] = []
    for position, m in enumerate(messages):
        if topic_base(m.topic) in REQUEST_TOPICS:
            out.append(BagRequest(len(out), position, m.time_ns, m.topic, m.message))
    return out


def bag_frame(messages: Sequence[BagMessage]) -> str | None:
    """The frame of the first map message with a non-empty frame (marker or cloud header), or None."""
    for m in messages:
        base = topic_base(m.topic)
        if base == "terrain" and str(m.message.header.frame_id):
            return str(m.message.header.frame_id)
        if base == "obstacles":
            for marker in m.message.markers:
                if str(marker.header.frame_id):
                    return str(marker.header.frame_id)
    return None


def request_at(messages: Sequence[BagMessage], index: int) -> BagRequest:
    """The ``index``-th (0-based) request of time-ordered ``messages``.

    Raises:
        BagError: the bag has no request ``index`` (the text says how many it has).
    """
    requests = bag_requests(messages)
    if not 0 <= index < len(requests):
        raise BagError(
            f"request {index} is not in the bag: it has {len(requests)} request(s) (goal_pose / goal_joints)"
        )
    return requests[index]
