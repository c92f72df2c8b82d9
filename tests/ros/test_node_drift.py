"""Odometry that drifts off the lattice still plans (issue 29): real rclpy, the shipped Wires prior, a real map.

A client flies the node's own plan with GPS noise and wind: it sends ``odom`` at poses of the plan moved 4 m
sideways and 2 m up and turned by up to 15 degrees, and asks ``get_plan`` to the prior's goal from there. Every
request must plan (each pose is checked free first by an independent FCL checker, so a pose that lies in a
wire's clearance would be a refusal, not a failure), and every path must start at the robot's pose, end at the
goal and be collision-free on the map.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

rclpy = pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")

from geometry_msgs.msg import PoseStamped  # noqa: E402
from harness import Peer, active_planner, private_context, spin_until, use_domain  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from nav_msgs.srv import GetPlan  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402

from drd_msgs_py.factory import RclpyMessages  # noqa: E402
from drd_planner.domains.helicopter import HelicopterDomain  # noqa: E402
from drd_planner.planning.world_messages import helicopter_world_messages  # noqa: E402
from drd_planner.ros.node import PlannerNode  # noqa: E402

PRIOR = Path(__file__).resolve().parents[2] / "trees" / "heli_wires.npz"
WORLD_SEED = 0  # a Wires world whose stored query has a free path (6 checks)
use_domain(60)


@pytest.fixture
def context() -> Iterator[Any]:
    with private_context() as ctx:
        yield ctx


def _pose(msg: Any, state: np.ndarray) -> Any:
    msg.header.frame_id = "map"
    pose = msg.pose.pose if isinstance(msg, Odometry) else msg.pose
    pose.position.x, pose.position.y, pose.position.z = (float(v) for v in state[:3])
    pose.orientation.z, pose.orientation.w = float(np.sin(state[3] / 2)), float(np.cos(state[3] / 2))
    return msg


def _states(path: Any) -> np.ndarray:
    """(K, 4) x, y, z, yaw of a nav_msgs/Path."""
    out = []
    for stamped in path.poses:
        p, q = stamped.pose.position, stamped.pose.orientation
        out.append([p.x, p.y, p.z, 2.0 * np.arctan2(q.z, q.w)])
    return np.array(out)


def _drifted(state: np.ndarray, rng: np.random.Generator, side: float) -> np.ndarray:
    """``state`` moved 4 m sideways (``side`` = +-1), 2 m up, turned by up to 15 degrees."""
    heading = state[3]
    lateral = side * 4.0 * np.array([-np.sin(heading), np.cos(heading)])
    turn = np.radians(rng.uniform(-15.0, 15.0))
    return np.array([state[0] + lateral[0], state[1] + lateral[1], state[2] + 2.0, heading + turn])


def test_odometry_drifting_off_the_lattice_replans_every_request(context: Any) -> None:
    node = PlannerNode(context=context, parameter_overrides=[Parameter("prior_paths", value=[str(PRIOR)])])
    peer = Peer(context)
    odom = peer.node.create_publisher(Odometry, "odom", 10)
    get_plan = peer.node.create_client(GetPlan, "get_plan")
    with active_planner(context, node, peer) as executor:
        session = node.sessions[0]
        domain = session.domain
        assert isinstance(domain, HelicopterDomain)
        world = domain.make_world("wires", WORLD_SEED)
        markers, cloud = helicopter_world_messages(world, wire_segments=8, frame_id="map", msgs=RclpyMessages())
        peer.terrain.publish(cloud)
        peer.obstacles.publish(markers)
        assert spin_until(executor, lambda: node.snapshot.version >= 2)
        checker = domain.checker(world)  # independent of the node's map: built from the world itself
        goal_state = session.vertex_state(int(domain.goal))

        def plan_from(state: np.ndarray) -> np.ndarray:
            odom.publish(_pose(Odometry(), state))

            def arrived() -> bool:
                known = None if node.service is None else node.service.robot_states.get("odom")
                return known is not None and bool(np.allclose(known, state))

            assert spin_until(executor, arrived)
            request = GetPlan.Request()
            request.goal = _pose(PoseStamped(), goal_state)
            future = get_plan.call_async(request)
            assert spin_until(executor, future.done)
            path = _states(future.result().plan)
            assert path.shape[0] > 0, node.errors[-1:]
            return path

        flown = plan_from(session.vertex_state(int(domain.start)))
        rng = np.random.default_rng(7)
        asked = planned = 0
        for k in range(10):
            on_plan = flown[int((k + 1) * flown.shape[0] / 11)]
            state = _drifted(on_plan, rng, side=1.0 if k % 2 else -1.0)
            if not checker.check_motion(state[None, :]):  # in a wire's clearance: not a plannable start
                continue
            asked += 1
            path = plan_from(state)
            planned += 1
            np.testing.assert_allclose(path[0, :3], state[:3], atol=1e-3)  # from where the robot is
            assert abs(np.angle(np.exp(1j * (path[0, 3] - state[3])))) < 1e-3  # with its heading
            np.testing.assert_allclose(path[-1, :3], goal_state[:3], atol=1e-3)
            assert checker.check_motion(path)  # the whole published path is free on the map
        assert asked >= 8
        assert planned == asked
