"""The main job's site mode (``planner_demo --prior P --site-file S``): a prior of your site, served live.

The third of the three commands from GIS files to a running node (``drd build-dataset --site-file S``,
``drd build-tree``, then this). Instead of replaying a bag's maps, it starts the map server
(:class:`~drd_planner.ros.map_server.MapServer`) for the site file in the same process and private ROS domain
as the planner node (:class:`~drd_planner.ros.node.PlannerNode`, on the prior ``P``): the site's terrain and
its mapped lines, towers and no-fly zones reach the node as they would from ``drd_map_server``. Then it
sends the node what a bag replay sends (:func:`site_requests`): the robot's state at the prior's stored start
on ``odom``, then on ``goal_pose`` the stored query's goal and :data:`EXTRA_GOALS` more lattice vertices far
from the start that the site's known map leaves reachable (drawn with the seed). The map server publishes
every mapped line as energised and every zone as active, so the stored query's goal may be cut off there;
the node then says so ("no free path"), as it would on a robot.

The requests go through :func:`~drd_planner.ros.replay.replay_bag`, stepped by events like a bag (each one
after the node took the maps and answered the one before), which also records the node's outputs into
``OUT/outputs.mcap``. Each plan's check log is printed and drawn (``OUT/plan_<k>.png``: the site's terrain,
the map server's lines and zones as the node's snapshot holds them, the checked edges, the plan) by
:func:`~drd_planner.ros.demo.report_served`.
"""

from __future__ import annotations

import os
import sys
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import rclpy
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.serialization import serialize_message

from drd_msgs_py.bags import BagContents, BagTopic, RawMessage
from drd_msgs_py.exceptions import MessageError
from drd_planner.arrays import FloatArray
from drd_planner.exceptions import DrdError
from drd_planner.planning.session import QuerySession
from drd_planner.ros.demo import ReplayReport, active_planner_node, demo_domain, replay_and_report
from drd_planner.ros.map_server import MapServer
from drd_planner.ros.node import PlannerNode

__all__ = ["EXTRA_GOALS", "SiteDemoOptions", "far_goals", "reachable", "run_site_demo", "site_requests"]

#: Goals sent after the stored query's: lattice vertices far from the start.
EXTRA_GOALS = 2
#: Seconds between two requests on the requests' timeline (before the playback rate).
_SPACING_S = 1.0
#: Seconds the node is given to take the map server's two latched maps.
_MAPS_S = 60.0
_FRAME = "map"


@dataclass(frozen=True)
class SiteDemoOptions:
    """One site-mode run of ``planner_demo``.

    Attributes:
        prior: the prior file of the site (``drd build-tree``'s output), or a shipped prior's name.
        site_file: the GIS site file whose maps the map server publishes.
        out: the output folder (``outputs.mcap`` and ``plan_<k>.png``; made if missing).
        rate: playback speed factor of the requests (> 0).
        seed: the policy's seed, and the draw of the extra goals.
        pictures: draw a picture of each plan (needs matplotlib).
        domain_id: the ROS domain, in [0, 232] (None: a private one where no other node is seen).
    """

    prior: str
    site_file: str
    out: Path = Path("out")
    rate: float = 2.0
    seed: int = 0
    pictures: bool = True
    domain_id: int | None = None


def reachable(session: QuerySession, start: int, free: Callable[[int], bool]) -> list[int]:
    """The lattice vertices joined to ``start`` by edges ``free`` passes (the site's known map), in search order.

    A breadth-first search that checks only the edges leaving the vertices it reaches (a helicopter lattice's
    edges are one-way motions), so a start fenced in by a mapped line costs few checks.
    """
    directed = session.prior.graph.directed
    edges = np.asarray(session.prior.graph.edges)
    leaving: dict[int, list[int]] = {}
    for e, (u, v) in enumerate(edges.tolist()):
        leaving.setdefault(int(u), []).append(e)
        if not directed:
            leaving.setdefault(int(v), []).append(e)
    seen, queue = {start}, deque([start])
    order = [start]
    while queue:
        vertex = queue.popleft()
        for e in leaving.get(vertex, []):
            other = int(edges[e, 1] if edges[e, 0] == vertex else edges[e, 0])
            if other not in seen and free(e):
                seen.add(other)
                queue.append(other)
                order.append(other)
    return order


def far_goals(session: QuerySession, start: int, count: int, seed: int, free: Callable[[int], bool]) -> list[int]:
    """``count`` vertices the site's known map leaves reachable from ``start``, far from it, drawn with ``seed``.

    The candidates are the vertices :func:`reachable` finds (``free``: an edge check on the maps the node holds),
    other than the start and the stored goal, in the farther half from the start's position (x, y, z, m);
    ``count`` of them are drawn without replacement (fewer when fewer are reachable). The same seed and map give
    the same goals; a goal asked for this way has a plan on the served maps.
    """
    states = session.prior.graph.vertex_states
    if states is None:
        raise DrdError(f"{session.name}: the prior's graph has no vertex states: its goals cannot be posed")
    xyz = np.asarray(states, dtype=np.float64)[:, :3]
    found = np.array([v for v in reachable(session, start, free) if v not in (start, int(session.domain.goal))])
    if found.size == 0:
        return []
    distance = np.linalg.norm(xyz[found] - xyz[start], axis=1)
    candidates = found[distance >= np.median(distance)]
    chosen = np.random.default_rng(seed).choice(candidates, size=min(count, candidates.size), replace=False)
    return [int(v) for v in chosen]


def _pose(msg: PoseStamped | Odometry, state: FloatArray) -> None:
    """Set the pose of ``msg`` (a PoseStamped, or an Odometry's pose) to a helicopter state (x, y, z m, yaw)."""
    pose = msg.pose if isinstance(msg, PoseStamped) else msg.pose.pose
    pose.position.x, pose.position.y, pose.position.z = (float(v) for v in state[:3])
    yaw = float(state[3]) if state.size > 3 else 0.0
    pose.orientation.z, pose.orientation.w = float(np.sin(yaw / 2.0)), float(np.cos(yaw / 2.0))


def site_requests(session: QuerySession, *, seed: int, free: Callable[[int], bool], frame: str = _FRAME) -> BagContents:
    """What a bag would send the node, in memory: ``/odom`` at the stored start, then the ``/goal_pose`` requests.

    The goals are the stored query's goal and :data:`EXTRA_GOALS` vertices of :func:`far_goals` (``free``:
    the edge check on the site's known map), all from the stored start, :data:`_SPACING_S` apart.

    Raises:
        DrdError: the prior plans no helicopter (its goals are joint states, not poses).
    """
    if session.domain.plans_joint_goals:
        raise DrdError(f"prior {session.name} plans an arm: site mode needs a helicopter prior of the site")
    start = int(session.domain.start)
    goals = [int(session.domain.goal), *far_goals(session, start, EXTRA_GOALS, seed, free)]
    messages = []
    odom = Odometry()
    odom.header.frame_id, odom.child_frame_id = frame, "base_link"
    _pose(odom, session.vertex_state(start))
    messages.append(RawMessage("/odom", "nav_msgs/msg/Odometry", 0, bytes(serialize_message(odom))))
    for k, vertex in enumerate(goals, start=1):
        goal = PoseStamped()
        goal.header.frame_id = frame
        time_ns = int(k * _SPACING_S * 1e9)
        goal.header.stamp.sec, goal.header.stamp.nanosec = divmod(time_ns, 10**9)
        _pose(goal, session.vertex_state(vertex))
        messages.append(RawMessage("/goal_pose", "geometry_msgs/msg/PoseStamped", time_ns, serialize_message(goal)))
    topics = {
        "/odom": BagTopic("/odom", "nav_msgs/msg/Odometry", (), 1),
        "/goal_pose": BagTopic("/goal_pose", "geometry_msgs/msg/PoseStamped", (), len(goals)),
    }
    return BagContents(Path(f"site requests of {session.name}"), topics, tuple(messages))


def _spin_until_maps(context: rclpy.context.Context, nodes: list[Node], node: PlannerNode) -> bool:
    """Spin the nodes until the planner took both maps (terrain and obstacles) or :data:`_MAPS_S` passed."""
    executor = SingleThreadedExecutor(context=context)
    for each in nodes:
        executor.add_node(each)
    end = time.monotonic() + _MAPS_S
    try:
        while node.snapshot.version < 2 and time.monotonic() < end:
            executor.spin_once(timeout_sec=0.05)
    finally:
        for each in nodes:
            executor.remove_node(each)
        executor.shutdown()
    return node.snapshot.version >= 2


def run_site_demo(options: SiteDemoOptions) -> int:
    """Run the site mode; 0 when every request got a verified plan, 1 if one did not, 2 on bad input."""
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    try:
        domain_id = demo_domain(options.domain_id)
    except DrdError as exc:
        print(f"planner_demo: error: {exc}", file=sys.stderr)
        return 2
    print(f"ROS domain {domain_id}" + (" (private)" if options.domain_id is None else ""))
    context = rclpy.context.Context()
    rclpy.init(context=context, domain_id=domain_id)
    nodes: list[Node] = []
    try:
        server = MapServer(
            context=context,
            parameter_overrides=[Parameter("site_file", value=options.site_file), Parameter("frame_id", value=_FRAME)],
        )
        nodes.append(server)
        node = active_planner_node(context, prior=options.prior, frame=_FRAME, seed=options.seed)
        if node is None:
            return 2
        nodes.append(node)
        session = node.sessions[0]
        print(f"map server: site {server.site.name} from {options.site_file}; planner node: prior {session.name}")
        if not _spin_until_maps(context, nodes, node):
            print(f"planner_demo: error: the node did not take the site's maps in {_MAPS_S:g} s", file=sys.stderr)
            return 2
        # The goals are chosen on the maps the node holds, with its own checker (the node is idle until asked).
        requests = site_requests(session, seed=options.seed, free=session.checker(node.snapshot).check)
        print(f"sending {len(requests.messages)} messages (odometry at the stored start, goals) to the planner node")
        report = ReplayReport(options.out, options.rate, options.pictures, "messages")
        return replay_and_report(requests, context=context, nodes=nodes, node=node, options=report)
    except (DrdError, MessageError) as exc:
        print(f"planner_demo: error: {exc}", file=sys.stderr)
        return 2
    finally:
        for each in reversed(nodes):
            each.destroy_node()
        context.try_shutdown()
