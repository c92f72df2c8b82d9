#!/usr/bin/env python3
# mypy: allow-untyped-calls
"""Big obstacle maps through the real node: publish -> "obstacles accepted", wall seconds and node CPU per update.

The node runs as its own process (``python -m drd_planner.ros.planner_node``, autostart, the ``--tree``
prior, ``max_markers`` raised to fit), so its CPU time is read apart from this peer's (``/proc/<pid>/stat``,
user + system). The peer publishes on the latched ``obstacles`` topic (depth 1: every message is the whole
map) a MarkerArray of N cubes (a DELETEALL first), serialized once beforehand (its cost is not measured),
then, one after the other:

- ``full map``: the N cubes, the first obstacle map the node gets;
- ``one marker moved``: the same array with one cube 0.5 m further along x;
- ``same map again``: that array published again unchanged;
- ``moved back``: the first array again (the cube back in its place).

Each row is the wall time from ``publish`` to the node's ``<node>: maps`` status ``obstacles accepted`` of
the next map version arriving here (on ``/diagnostics``), the node's CPU seconds over that interval, and the
node's RSS after it. The node's map callback converts the array, builds the new snapshot's FCL scene and
each prior's checker before it reports the version accepted. The load average is printed: the CPU seconds
are the node's own, the wall seconds include waiting for a shared core.

Usage: python scripts/experiments/bench_node_maps.py [--markers 100000] [--tree heli_wires] [--domain-id 171]
    [--timeout 600]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import threading
import time
from typing import Any

import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile, ReliabilityPolicy
from visualization_msgs.msg import MarkerArray

from drd_msgs_py.bags import jazzy_typestore
from drd_msgs_py.factory import RosbagsMessages
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Box
from drd_planner.planning.world_messages import obstacle_markers
from drd_planner.ros.outputs import LATCHED

HEADER = f"{'update':<20} {'markers':>8} {'version':>8} {'wall s':>8} {'node CPU s':>11} {'node RSS MiB':>13}"
#: The peer's ``/diagnostics`` subscription (keeps every status).
RECORD = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
#: The cube that moves (index in the array after the DELETEALL).
MOVED = 7


def serialized_cubes(count: int, *, moved: float) -> bytes:
    """A serialized MarkerArray: DELETEALL then ``count`` 1 m cubes on a 3 m grid, cube MOVED shifted ``moved`` m."""
    typestore = jazzy_typestore()
    obstacles = [
        (
            f"box/{k}",
            Box((1.0, 1.0, 1.0)),
            Pose((3.0 * (k % 300) + (moved if k == MOVED else 0.0), 3.0 * (k // 300), 400.0)),
        )
        for k in range(count)
    ]
    msg = obstacle_markers(obstacles, frame_id="map", msgs=RosbagsMessages(typestore), delete_all_first=True)
    return bytes(typestore.serialize_cdr(msg, "visualization_msgs/msg/MarkerArray"))


def proc_cpu_s(pid: int) -> float:
    """User + system CPU seconds of process ``pid`` (its threads included)."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rpartition(")")[2].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def proc_rss_mib(pid: int) -> float:
    """Resident set size of process ``pid``, MiB."""
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


class Peer:
    """Publishes the obstacle maps and hears the node's ``maps`` statuses (versions accepted, refusals)."""

    def __init__(self, domain_id: int, node_name: str) -> None:
        self.context = rclpy.context.Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node("maps_bench_peer", context=self.context)
        self.publisher = self.node.create_publisher(MarkerArray, "obstacles", LATCHED)
        self.node.create_subscription(DiagnosticArray, "/diagnostics", self._on_diagnostics, RECORD)
        self._name = f"{node_name}: maps"
        self._lock = threading.Lock()
        self.accepted: dict[int, float] = {}  # map version -> perf_counter() when its status arrived
        self.refused: list[str] = []
        self._executor = SingleThreadedExecutor(context=self.context)
        self._executor.add_node(self.node)
        threading.Thread(target=self._executor.spin, daemon=True).start()

    def _on_diagnostics(self, msg: Any) -> None:
        now = time.perf_counter()
        for status in msg.status:
            if status.name != self._name:
                continue
            values = {kv.key: kv.value for kv in status.values}
            with self._lock:
                if status.message == "obstacles accepted" and "map_version" in values:
                    self.accepted[int(values["map_version"])] = now
                elif "obstacles" in status.message:
                    self.refused.append(status.message)

    def wait_accepted(self, version: int, timeout: float) -> float | None:
        """When version ``version`` was reported accepted (perf_counter), or None after ``timeout`` s."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            with self._lock:
                if version in self.accepted:
                    return self.accepted[version]
                if self.refused:
                    raise RuntimeError(f"the node refused the map: {self.refused[-1][:300]}")
            time.sleep(0.005)
        return None

    def close(self) -> None:
        self._executor.shutdown()
        self.node.destroy_node()
        rclpy.shutdown(context=self.context)


def start_node(tree: str, markers: int, domain_id: int, name: str) -> subprocess.Popen[bytes]:
    """The planner node process (autostart), its output to stderr-less quiet."""
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain_id), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    args = [sys.executable, "-m", "drd_planner.ros.planner_node", "--ros-args", "-r", f"__node:={name}"]
    for param in (
        f"prior_paths:=[{tree}]",
        "autostart:=true",
        "start_without_robot_state:=prior_start",
        f"max_markers:={markers}",
    ):
        args += ["-p", param]
    return subprocess.Popen(args, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--markers", type=int, default=100_000, help="cubes in the map (plus a DELETEALL)")
    parser.add_argument("--tree", default="heli_wires", help="the prior the node loads (prior_paths)")
    parser.add_argument("--domain-id", type=int, default=171, help="ROS_DOMAIN_ID of the node and the peer")
    parser.add_argument("--timeout", type=float, default=600.0, help="seconds to wait for one update")
    args = parser.parse_args()
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    name = "drd_planner_maps_bench"
    t0 = time.perf_counter()
    full = serialized_cubes(args.markers, moved=0.0)
    moved = serialized_cubes(args.markers, moved=0.5)
    print(f"messages: {len(full) / 2**20:.1f} MiB each, serialized in {time.perf_counter() - t0:.1f} s")
    node = start_node(args.tree, args.markers + 1, args.domain_id, name)
    peer = Peer(args.domain_id, name)
    try:
        end = time.monotonic() + 120.0
        while peer.publisher.get_subscription_count() == 0:
            if node.poll() is not None or time.monotonic() > end:
                raise SystemExit(f"the node did not subscribe to obstacles (exit {node.poll()})")
            time.sleep(0.1)
        time.sleep(1.0)  # the node's executor settles after activation
        print(f"node pid {node.pid}, RSS {proc_rss_mib(node.pid):.0f} MiB; load average {os.getloadavg()}")
        print(HEADER)
        updates = [("full map", full), ("one marker moved", moved), ("same map again", moved)]
        updates.append(("moved back", full))
        for version, (label, data) in enumerate(updates, start=1):
            cpu0, wall0 = proc_cpu_s(node.pid), time.perf_counter()
            peer.publisher.publish(data)
            done = peer.wait_accepted(version, args.timeout)
            cpu = proc_cpu_s(node.pid) - cpu0
            if done is None:
                print(f"{label:<20} {args.markers + 1:>8} {version:>8} timed out after {args.timeout:.0f} s")
                break
            print(
                f"{label:<20} {args.markers + 1:>8} {version:>8} {done - wall0:>8.2f} {cpu:>11.2f} "
                f"{proc_rss_mib(node.pid):>13.0f}"
            )
            time.sleep(0.5)
        print(f"load average after: {os.getloadavg()}")
    finally:
        peer.close()
        node.terminate()
        try:
            node.wait(timeout=30)
        except subprocess.TimeoutExpired:
            node.kill()


if __name__ == "__main__":
    main()
