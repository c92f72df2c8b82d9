"""Replay a rosbag2 MCAP bag through rclpy with its timing, and record the planner's outputs into a bag.

Library use (in-process, e.g. a test or the main job running a :class:`PlannerNode` in the same executor)::

    options = ReplayOptions(record=tmp / "out.mcap")
    summary = replay_bag("bags/heli_wires.mcap", context=ctx, nodes=[planner], options=options)

:func:`replay_bag` publishes every message of the bag as the raw CDR bytes stored in it (rclpy's
``Publisher.publish(bytes)``; nothing is re-encoded) on a publisher whose QoS is the one the bag offers
for that topic (map topics reliable + transient_local depth 1 in our bags; see
:mod:`drd_msgs_py.bags`), at the bag's times divided by ``rate``, while one executor spins the replay
node and the given ``nodes``. Before the first message it waits (up to ``wait`` seconds) until every
bag topic has a subscriber and every recorded topic a publisher, so a volatile request is not lost to
DDS discovery; after the last it keeps spinning for ``settle`` seconds. Meanwhile it records the
planner's outputs (``plan``, ``joint_trajectory``, ``edge_checks``, ``/diagnostics``,
``checked_edges``) with raw subscriptions, so the recorded bytes are exactly what the node sent. They
are stamped on the *bag's* timeline (bag start + elapsed wall time x ``rate``), so input and output
bags line up, and written with the QoS their publisher offers (from the ROS graph).

Command line (replays into an already running node; the node must be active; its flags are parsed in
:mod:`drd_planner.cli.replay`, which calls :func:`replay_command`)::

    drd_replay BAG [--record OUT.mcap] [--rate R] [--settle S] [--wait S]

A missing or corrupt bag, or no node subscribed to any of its topics after ``--wait`` seconds, exits
with status 2 and one line ``drd_replay: error: ...`` (no output bag is written).
"""

from __future__ import annotations

import math
import sys
import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.utilities import try_shutdown

from drd_msgs_py.bags import (
    BagContents,
    BagError,
    RawMessage,
    open_bag,
    topic_base,
    write_raw_bag,
)
from drd_msgs_py.exceptions import MessageError
from drd_msgs_py.factory import RclpyMessages
from drd_planner.exceptions import DrdError
from drd_planner.planning.shipped import resolve_bag_path
from drd_planner.ros.bag_qos import offered_qos, rclpy_qos

__all__ = [
    "OUTPUT_TOPICS",
    "Published",
    "ReplayError",
    "ReplayOptions",
    "ReplaySummary",
    "rclpy_qos",
    "replay_bag",
    "replay_command",
]

#: What the planner publishes (names relative to its namespace, as in docs/ros-node.md) -> type.
OUTPUT_TOPICS: dict[str, str] = {
    "plan": "nav_msgs/msg/Path",
    "joint_trajectory": "trajectory_msgs/msg/JointTrajectory",
    "edge_checks": "diagnostic_msgs/msg/DiagnosticArray",
    "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
    "checked_edges": "visualization_msgs/msg/MarkerArray",
}
#: Outputs the node publishes transient_local (used when the graph does not tell).
LATCHED_OUTPUTS = ("plan", "joint_trajectory")
#: Depth of the recording subscriptions (volatile: a plan latched before the replay is not recorded).
RECORD_DEPTH = 100
_SPIN_S = 0.02
#: Seconds spun after ``ReplayOptions.settle_until`` holds, so the outputs of the last answer arrive.
ANSWER_S = 0.5
#: Seconds spun after every subscriber matched, before the first message (discovery settles both ways).
_MATCH_GRACE_S = 0.3


class ReplayError(DrdError):
    """The replay cannot do its job: nobody listens to the bag's topics."""


@dataclass(frozen=True)
class Published:
    """One replayed message.

    Attributes:
        topic: the topic it was published on (resolved).
        msgtype: ``pkg/msg/Name``.
        time_ns: its time in the bag.
        sent_ns: when it went out, on the bag's timeline (the clock of the recorded outputs).
        late_s: how much later than its scheduled time it went out (wall s; the executor was busy).
    """

    topic: str
    msgtype: str
    time_ns: int
    sent_ns: int
    late_s: float


@dataclass(frozen=True)
class ReplaySummary:
    """What a replay did.

    Attributes:
        bag: the replayed bag.
        published: every message published, in order.
        recorded: every output received, in order, stamped on the bag's timeline (ns).
        record_path: the bag the outputs were written to (None: not recorded).
        unmatched: bag topics that still had no subscriber when the timeline started.
        seconds: wall time of the whole replay (waiting and settling included).
        interrupted: stopped early by Ctrl-C (what was recorded so far is still written).
    """

    bag: Path
    published: tuple[Published, ...]
    recorded: tuple[RawMessage, ...]
    record_path: Path | None
    unmatched: tuple[str, ...]
    seconds: float
    interrupted: bool = False

    @property
    def published_per_topic(self) -> dict[str, int]:
        """Topic -> messages published."""
        return dict(Counter(p.topic for p in self.published))

    @property
    def recorded_per_topic(self) -> dict[str, int]:
        """Topic -> messages recorded."""
        return dict(Counter(r.topic for r in self.recorded))

    def recorded_on(self, name: str) -> list[RawMessage]:
        """The recorded messages of one output (``plan``, ``edge_checks``, ``diagnostics``, ...), in order."""
        base = topic_base(name)
        return [r for r in self.recorded if topic_base(r.topic) == base]


class _Timeline:
    """Wall clock -> bag time: ``start_ns`` at :meth:`start`, then elapsed seconds x ``rate``."""

    def __init__(self, start_ns: int, rate: float) -> None:
        self.start_ns, self.rate = start_ns, rate
        self.t0: float | None = None

    def start(self) -> float:
        """Start now; the monotonic start time (s)."""
        self.t0 = time.monotonic()
        return self.t0

    def now_ns(self) -> int:
        """The bag time now (``start_ns`` before :meth:`start`)."""
        if self.t0 is None:
            return self.start_ns
        return self.start_ns + round((time.monotonic() - self.t0) * self.rate * 1e9)


def _resolve(topic: str, namespace: str | None) -> str:
    """A bag topic under ``namespace`` (None: as stored, made absolute)."""
    if namespace is None or namespace.strip("/") == "":
        return topic if topic.startswith("/") else f"/{topic}"
    return f"/{namespace.strip('/')}/{topic.lstrip('/')}"


# ----------------------------------------------------------------------------------------------------
# Replay


@dataclass(frozen=True)
class ReplayOptions:
    """How :func:`replay_bag` plays a bag.

    Attributes:
        record: the MCAP file for the outputs (None: do not record).
        overwrite: replace an existing ``record`` file.
        rate: playback speed factor (> 0; 2 plays twice as fast).
        settle: seconds to keep spinning after the last message.
        wait: at most this many seconds to wait for subscribers/publishers before the first message.
        namespace: publish the bag's topics and record the outputs under this namespace (the
            planner's); None: the topic names as stored, outputs at the root.
        log: called with one progress line at a time (None: silent).
        require_listener: refuse to replay (and to write ``record``) when after ``wait`` seconds no
            bag topic has a subscriber: no planner is running there.
        settle_until: after ``settle``, keep spinning until this returns True (e.g. the planner's
            ``planning_idle``: every request answered, however slow the machine), at most
            ``settle_limit`` seconds more; then spin :data:`ANSWER_S` so its last outputs are recorded.
        settle_limit: the most seconds spent waiting for ``settle_until``.
        ready: steps the bag by events: before each message after the first, spin until ``ready(n)`` holds,
            ``n`` the messages published so far (e.g. the planner took them all and answered: a request
            then always follows the maps before it and the previous answer, on any machine), at most
            ``settle_limit`` seconds per message; the bag's timing still spaces the messages. None: by the
            clock alone.

    Raises:
        ValueError: ``rate``, ``settle`` or ``wait`` out of range.
    """

    record: str | Path | None = None
    overwrite: bool = False
    rate: float = 1.0
    settle: float = 2.0
    wait: float = 5.0
    namespace: str | None = None
    log: Callable[[str], None] | None = None
    require_listener: bool = False
    settle_until: Callable[[], bool] | None = None
    settle_limit: float = 60.0
    ready: Callable[[int], bool] | None = None

    def __post_init__(self) -> None:
        rate, settle, wait = self.rate, self.settle, self.wait
        if not (math.isfinite(rate) and rate > 0):
            raise ValueError(f"rate must be a finite number > 0, got {rate}")
        if not (math.isfinite(settle) and settle >= 0 and math.isfinite(wait) and wait >= 0):
            raise ValueError(f"settle and wait must be finite and >= 0 s, got {settle}, {wait}")
        if not (math.isfinite(self.settle_limit) and self.settle_limit >= 0):
            raise ValueError(f"settle_limit must be finite and >= 0 s, got {self.settle_limit}")

    def say(self, line: str) -> None:
        """Pass one progress line to :attr:`log`."""
        if self.log is not None:
            self.log(line)


class _Replayer:
    """The replay node, its executor, publishers and recording subscriptions (one replay)."""

    def __init__(self, contents: BagContents, context: Any, nodes: Sequence[Any], options: ReplayOptions) -> None:
        self.contents, self.options, self.nodes = contents, options, nodes
        self.node = rclpy.create_node("drd_replay", context=context)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        for extra in nodes:
            self.executor.add_node(extra)
        self.start_ns = contents.messages[0].time_ns if contents.messages else 0
        self.timeline = _Timeline(self.start_ns, options.rate)
        self.recorded: list[RawMessage] = []
        self.publishers: dict[str, Any] = {}
        self.subscriptions: dict[str, Any] = {}

    def close(self) -> None:
        """Take the given nodes out of the executor (they are not destroyed) and destroy the replay node."""
        for extra in self.nodes:
            self.executor.remove_node(extra)
        self.executor.remove_node(self.node)
        self.executor.shutdown()
        self.node.destroy_node()

    def spin_until(self, done: Callable[[], bool], limit: float) -> None:
        """Spin until ``done()`` (at most ``limit`` s), then :data:`ANSWER_S` more for its outputs."""
        end = time.monotonic() + limit
        while not done() and time.monotonic() < end:
            self.executor.spin_once(timeout_sec=_SPIN_S)
        self.spin_for(ANSWER_S)

    def spin_for(self, seconds: float) -> None:
        """Spin the executor for ``seconds`` of wall time."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=_SPIN_S)

    def open_publishers(self, classes: RclpyMessages) -> None:
        """One publisher per bag topic, with the QoS the bag offers for it."""
        for name, info in self.contents.topics.items():
            try:
                cls = classes.message_class(info.msgtype)
            except MessageError as exc:
                raise BagError(f"{self.contents.path}: topic {name}: {exc}") from exc
            self.publishers[name] = self.node.create_publisher(
                cls, _resolve(name, self.options.namespace), rclpy_qos(next(iter(info.qos), None), name)
            )

    def open_recorders(self, classes: RclpyMessages) -> None:
        """Raw subscriptions to the planner's outputs, stamped on the bag's timeline."""
        for output, msgtype in OUTPUT_TOPICS.items():
            resolved = output if output.startswith("/") else _resolve(output, self.options.namespace or "/")

            def keep(data: bytes, topic: str = resolved, kind: str = msgtype) -> None:
                self.recorded.append(RawMessage(topic, kind, self.timeline.now_ns(), bytes(data)))

            profile = QoSProfile(depth=RECORD_DEPTH, reliability=ReliabilityPolicy.RELIABLE)
            self.subscriptions[resolved] = self.node.create_subscription(
                classes.message_class(msgtype), resolved, keep, profile, raw=True
            )

    def wait_for_peers(self) -> list[str]:
        """Spin until every bag topic has a subscriber and every output a publisher, or ``wait`` s passed.

        Returns the bag topics still without a subscriber.

        Raises:
            ReplayError: ``require_listener`` and no bag topic has a subscriber.
        """
        options = self.options
        deadline = time.monotonic() + options.wait
        while True:
            unmatched = [p.topic_name for p in self.publishers.values() if p.get_subscription_count() == 0]
            silent = [t for t, s in self.subscriptions.items() if s.get_publisher_count() == 0]
            if (not unmatched and not silent) or time.monotonic() >= deadline:
                break
            self.executor.spin_once(timeout_sec=_SPIN_S)
        if options.require_listener and self.publishers and len(unmatched) == len(self.publishers):
            raise ReplayError(
                f"no node subscribes to any of the bag's topics ({', '.join(sorted(unmatched))}) after "
                f"{options.wait:g} s: start the planner first (planner_node --ros-args -p autostart:=true ...) "
                "or check --namespace and ROS_DOMAIN_ID"
            )
        for topic in unmatched:
            options.say(f"  no subscriber on {topic} after {options.wait:g} s; publishing anyway")
        # A publisher counts a subscriber before that subscriber has matched the publisher in turn;
        # a volatile message sent in between is dropped (seen with the odometry at time 0).
        self.spin_for(_MATCH_GRACE_S)
        return unmatched

    def play(self) -> list[Published]:
        """Publish every message at its bag time divided by ``rate``, spinning in between."""
        published: list[Published] = []
        t0 = self.timeline.start()
        ready = self.options.ready
        for raw in self.contents.messages:
            if ready is not None and published:
                waited = time.monotonic()
                end = waited + self.options.settle_limit
                while not ready(len(published)) and time.monotonic() < end:
                    self.executor.spin_once(timeout_sec=_SPIN_S)
                t0 += time.monotonic() - waited  # the bag's spacing goes on from here
            due = t0 + (raw.time_ns - self.start_ns) / 1e9 / self.options.rate
            while (left := due - time.monotonic()) > 0:
                self.executor.spin_once(timeout_sec=min(left, 0.05))
            sent = self.timeline.now_ns()
            publisher = self.publishers[raw.topic]
            publisher.publish(raw.data)
            late = max(0.0, time.monotonic() - due)
            published.append(Published(publisher.topic_name, raw.msgtype, raw.time_ns, sent, late))
            self.options.say(f"  +{(raw.time_ns - self.start_ns) / 1e9:6.2f} s  {publisher.topic_name} ({raw.msgtype})")
        return published

    def write(self, out: Path) -> Path:
        """Write the recorded outputs with the QoS their publishers offer."""
        qos_out = {topic: offered_qos(self.node, topic, latched=LATCHED_OUTPUTS) for topic in self.subscriptions}
        return write_raw_bag(out, self.recorded, qos=qos_out, overwrite=self.options.overwrite)


def replay_bag(
    bag: str | Path | BagContents,
    *,
    context: Any = None,
    nodes: Sequence[Any] = (),
    options: ReplayOptions | None = None,
) -> ReplaySummary:
    """Publish a bag with its timing while spinning ``nodes``, record the planner's outputs (module docstring).

    Args:
        bag: a bag path, or one already read with :func:`~drd_msgs_py.bags.open_bag`.
        context: the rclpy context (initialized; None: the default one).
        nodes: nodes to spin in the same executor (e.g. a configured and active PlannerNode); they
            must not be spun elsewhere meanwhile. They are removed from the executor afterwards, not destroyed.
        options: how to play and record (:class:`ReplayOptions`; None: its defaults).

    Raises:
        ReplayError: ``require_listener`` and nobody subscribes to any of the bag's topics.
        BagError: an unreadable bag, or ``record`` exists and ``overwrite`` is False.
    """
    options = options or ReplayOptions()
    contents = bag if isinstance(bag, BagContents) else open_bag(bag)
    out = Path(options.record) if options.record is not None else None
    if out is not None and out.exists() and not options.overwrite:
        raise BagError(f"{out} exists already (not overwriting)")
    classes = RclpyMessages()
    started = time.monotonic()
    replayer = _Replayer(contents, context, nodes, options)
    try:
        replayer.open_publishers(classes)
        if out is not None:
            replayer.open_recorders(classes)
        options.say(
            f"replaying {contents.path}: {len(contents.messages)} messages on {len(contents.topics)} topics "
            f"over {contents.duration_ns / 1e9:.2f} s at rate {options.rate:g}"
        )
        published: list[Published] = []
        unmatched: list[str] = []
        interrupted = False
        try:
            unmatched = replayer.wait_for_peers()
            published = replayer.play()
            replayer.spin_for(options.settle)
            if options.settle_until is not None:
                replayer.spin_until(options.settle_until, options.settle_limit)
        except KeyboardInterrupt:
            interrupted = True
            options.say("  interrupted: writing what was recorded so far")
        written = replayer.write(out) if out is not None else None
        summary = ReplaySummary(
            contents.path,
            tuple(published),
            tuple(replayer.recorded),
            written,
            tuple(unmatched),
            time.monotonic() - started,
            interrupted,
        )
    finally:
        replayer.close()
    counts = ", ".join(f"{t} {n}" for t, n in sorted(summary.recorded_per_topic.items())) or "nothing"
    options.say(f"published {len(summary.published)} messages; recorded {counts}")
    if written is not None:
        options.say(f"wrote {written}")
    return summary


# ----------------------------------------------------------------------------------------------------
# Command line


def replay_command(bag: str, options: ReplayOptions) -> int:
    """``drd_replay``: replay ``bag`` (a path or a shipped bag's name) into a running node with ``options``.

    Errors (missing or corrupt bag, existing ``record`` file without ``overwrite``, nobody listening when
    ``options.require_listener``) print one line ``drd_replay: error: ...`` and return 2; an interrupted
    replay returns 130 (after writing what was recorded), else 0.
    """
    try:
        contents = open_bag(resolve_bag_path(bag))
        if not contents.messages:
            raise BagError(f"bag {bag} has no messages")
        if options.record and Path(options.record).exists() and not options.overwrite:
            raise BagError(f"{options.record} exists already (use --overwrite)")
    except (MessageError, DrdError) as exc:
        print(f"drd_replay: error: {exc}", file=sys.stderr)
        return 2
    rclpy.init()
    try:
        summary = replay_bag(contents, options=options)
    except (MessageError, DrdError) as exc:
        print(f"drd_replay: error: {exc}", file=sys.stderr)
        return 2
    finally:
        try_shutdown()
    return 130 if summary.interrupted else 0
