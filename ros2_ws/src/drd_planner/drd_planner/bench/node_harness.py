# mypy: allow-untyped-calls
"""The planner node and a peer node in threads of one process: the harness of the node benchmarks.

:class:`Harness` runs the real :class:`~drd_planner.ros.node.PlannerNode` as ``planner_node`` runs it (a
``SingleThreadedExecutor`` for maps and requests, the node's own planning thread for plans) beside a peer
that publishes maps and requests and listens to ``/diagnostics`` and ``plan``; :func:`default_maps` gives the
maps it publishes, :func:`path_pose_count` reads a serialized Path's length without decoding it, and
:func:`wait_for` polls. ``scripts/experiments/bench_node_burst.py`` and ``bench_node_latency.py`` (and
``tests/ros/test_node_burst.py``) use them. rclpy is needed (a ROS install or the PyPI wheels).
"""

from __future__ import annotations

import struct
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Path as PathMsg
from nav_msgs.srv import GetPlan
from rclpy.executors import SingleThreadedExecutor
from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import PointCloud2
from visualization_msgs.msg import MarkerArray

from drd_msgs_py.factory import RclpyMessages
from drd_planner.planning.world_messages import helicopter_world_messages
from drd_planner.ros.node import LATCHED, REQUESTS, PlannerNode

__all__ = ["RECORD", "RECORD_LATCHED", "Harness", "default_maps", "path_pose_count", "wait_for"]

#: /diagnostics on the peer: deep enough to hold a whole burst of summaries.
RECORD = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
RECORD_LATCHED = QoSProfile(
    depth=1000, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)


class Harness:
    """The node and a peer, each on its own executor spinning in a thread of this process.

    Args:
        tree: the tree file the node loads.
        frame_id: the planning frame.
        domain_id: ROS domain id (None: ``ROS_DOMAIN_ID``).
        parameters: more node parameters (``replan_on_map_update``, ``seed``, ...).
    """

    def __init__(
        self,
        *,
        tree: Path,
        frame_id: str = "map",
        domain_id: int | None = None,
        parameters: Sequence[Parameter] = (),
    ) -> None:
        self.context = rclpy.context.Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = PlannerNode(
            context=self.context,
            parameter_overrides=[
                Parameter("prior_paths", value=[str(tree)]),
                Parameter("start_without_robot_state", value="prior_start"),
                Parameter("frame_id", value=frame_id),
                *parameters,
            ],
        )
        if self.node.trigger_configure() != TransitionCallbackReturn.SUCCESS:
            raise RuntimeError(f"configure failed: {self.node.errors[-1:]}")
        if self.node.trigger_activate() != TransitionCallbackReturn.SUCCESS:
            raise RuntimeError("activate failed")
        self.frame_id = frame_id
        self.peer = rclpy.create_node("burst_peer", context=self.context)
        self.obstacles = self.peer.create_publisher(MarkerArray, "obstacles", LATCHED)
        self.terrain = self.peer.create_publisher(PointCloud2, "terrain", LATCHED)
        self.goals = self.peer.create_publisher(PoseStamped, "goal_pose", REQUESTS)
        self.client = self.peer.create_client(GetPlan, "get_plan")
        self._lock = threading.Lock()
        self._listeners: list[Callable[[Any], None]] = []
        self._plan_listeners: list[Callable[[Any], None]] = []
        self.plans = 0  # Path messages received on plan (only counted: a kept message would look like a leak)
        self.peer.create_subscription(DiagnosticArray, "/diagnostics", self._on_diagnostics, RECORD)
        # Raw: a Path arrives as its serialized bytes, timed as it arrives (rclpy's Python decoding of
        # a Path costs 35 to 75 us a pose, a subscriber's own cost; path_pose_count reads its length).
        self.peer.create_subscription(PathMsg, "plan", self._on_plan, RECORD_LATCHED, raw=True)
        self._node_exec = SingleThreadedExecutor(context=self.context)
        self._node_exec.add_node(self.node)
        self._nudge = self.peer.create_guard_condition(lambda: None)
        self._peer_exec = SingleThreadedExecutor(context=self.context)
        self._peer_exec.add_node(self.peer)
        self._threads = [
            threading.Thread(target=self._node_exec.spin, daemon=True),
            threading.Thread(target=self._peer_exec.spin, daemon=True),
        ]
        for thread in self._threads:
            thread.start()

    def _on_plan(self, msg: Any) -> None:
        now = time.perf_counter()
        with self._lock:
            self.plans += 1
            listeners = list(self._plan_listeners)
        for listener in listeners:
            listener((now, msg))

    def _on_diagnostics(self, msg: Any) -> None:
        now = time.perf_counter()
        with self._lock:
            listeners = list(self._listeners)
        for status in msg.status:
            for listener in listeners:
                listener((now, status))

    def listen_plans(self, listener: Callable[[Any], None]) -> Callable[[], None]:
        """Call ``listener((receive_time, data))`` for each Path on ``plan`` (serialized bytes); returns the remover."""
        with self._lock:
            self._plan_listeners.append(listener)

        def remove() -> None:
            with self._lock:
                self._plan_listeners.remove(listener)

        return remove

    def settle(self) -> None:
        """Let the peer's executor run one more round.

        An executor drops the tasks it ran (service responses' done callbacks, with the responses) only
        when it next wakes up; without this the last responses of a burst would look like a leak.
        """
        for _ in range(2):
            self._nudge.trigger()
            time.sleep(0.02)

    def listen(self, listener: Callable[[Any], None]) -> Callable[[], None]:
        """Call ``listener((receive_time, status))`` for each /diagnostics status; returns the remover."""
        with self._lock:
            self._listeners.append(listener)

        def remove() -> None:
            with self._lock:
                self._listeners.remove(listener)

        return remove

    def goal(self, stamp: tuple[int, int] = (0, 0)) -> PoseStamped:
        """A valid request at the first tree's goal position, stamped ``stamp``."""
        goal = PoseStamped()
        goal.header.frame_id = self.frame_id
        goal.header.stamp.sec, goal.header.stamp.nanosec = stamp
        x, y, z = (float(v) for v in self.node.sessions[0].goal_position)
        goal.pose.position.x, goal.pose.position.y, goal.pose.position.z = x, y, z
        goal.pose.orientation.w = 1.0
        return goal

    def publish_maps(self, markers: Any, cloud: Any | None, *, timeout: float = 10.0) -> None:
        """Publish the maps and wait until the node holds a snapshot with them."""
        version = self.node.snapshot.version
        want = version + (2 if cloud is not None else 1)
        if cloud is not None:
            self.terrain.publish(cloud)
        self.obstacles.publish(markers)
        if not wait_for(lambda: self.node.snapshot.version >= want, timeout):
            raise RuntimeError(f"the node did not take the maps: {self.node.errors[-3:]}")

    def close(self) -> None:
        """Stop both executors and the context."""
        self._node_exec.shutdown()
        self._peer_exec.shutdown()
        for thread in self._threads:
            thread.join(timeout=5.0)
        self.node.destroy_node()
        self.peer.destroy_node()
        self.context.try_shutdown()


def path_pose_count(data: bytes) -> int:
    """Poses in a serialized ``nav_msgs/Path`` (CDR: header stamp, frame_id string, then the pose count)."""
    (length,) = struct.unpack_from("<I", data, 4 + 8)  # after the encapsulation header and the stamp
    offset = 8 + 4 + length
    offset += -offset % 4
    return int(struct.unpack_from("<I", data, 4 + offset)[0])


def wait_for(done: Callable[[], bool], timeout: float) -> bool:
    """Poll ``done`` every millisecond for up to ``timeout`` seconds."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if done():
            return True
        time.sleep(0.001)
    return done()


def default_maps(harness: Harness, *, world_seed: int, bag: Path | None) -> tuple[Any, Any | None]:
    """(MarkerArray, PointCloud2 or None): the first maps of ``bag``, else the tree's "wires" world."""
    if bag is not None and bag.is_file():
        from drd_msgs_py.bags import open_bag  # rosbags: only needed with a bag

        first: dict[str, Any] = {}
        for raw in open_bag(bag).messages:
            name = raw.topic.lstrip("/")
            if name in ("obstacles", "terrain") and name not in first:
                cls = MarkerArray if name == "obstacles" else PointCloud2
                first[name] = deserialize_message(raw.data, cls)
        if "obstacles" not in first:
            raise RuntimeError(f"{bag} has no /obstacles message")
        return first["obstacles"], first.get("terrain")
    domain: Any = harness.node.sessions[0].domain
    world = domain.make_world("wires", world_seed)
    segments = int(domain.spec().get("wire_segments", 8))
    return helicopter_world_messages(world, wire_segments=segments, frame_id=harness.frame_id, msgs=RclpyMessages())
