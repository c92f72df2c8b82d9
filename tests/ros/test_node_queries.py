"""The node plans from where the robot is to any goal (issue 15 items 1-3), with real rclpy and a real prior.

The prior is built in the test from a small generated dataset (a 300 m x 200 m helicopter lattice over 40
Wires worlds), so a goal that no precomputed tree was built for is planned by DiRECt online.
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
from std_srvs.srv import Trigger  # noqa: E402

from drd_msgs_py.factory import RclpyMessages  # noqa: E402
from drd_planner.cli.main import main as drd  # noqa: E402
from drd_planner.domains.helicopter import HelicopterDomain  # noqa: E402
from drd_planner.planning.world_messages import helicopter_world_messages  # noqa: E402
from drd_planner.ros.node import PlannerNode  # noqa: E402

SPEC = '{"lattice": {"x_range": [0.0, 300.0], "y_range": [-100.0, 100.0], "goal": [300.0, 0.0]}}'
GOAL = 16  # (250, 0, 65): not the goal the prior's tree was built for (300, 0, 65)
use_domain(40)


@pytest.fixture(scope="module")
def prior_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("prior")
    dataset, prior = folder / "data.npz", folder / "heli.npz"
    argv = [
        "build-dataset",
        "--domain",
        "helicopter",
        "--world-model",
        "wires",
        "--worlds",
        "40",
        "--seed",
        "3",
    ]
    assert drd([*argv, "--out", str(dataset), "--workers", "1", "--domain-spec", SPEC]) == 0
    assert drd(["build-tree", "--dataset", str(dataset), "--out", str(prior), "--eta", "0.2", "--kappa", "10"]) == 0
    return prior


@pytest.fixture
def context() -> Iterator[Any]:
    with private_context() as ctx:
        yield ctx


def _pose(msg: Any, state: np.ndarray, frame: str = "map") -> Any:
    msg.header.frame_id = frame
    pose = msg.pose.pose if isinstance(msg, Odometry) else msg.pose
    pose.position.x, pose.position.y, pose.position.z = (float(v) for v in state[:3])
    pose.orientation.z, pose.orientation.w = float(np.sin(state[3] / 2)), float(np.cos(state[3] / 2))
    return msg


def _xyz(path: Any, k: int) -> np.ndarray:
    p = path.poses[k].pose.position
    return np.array([p.x, p.y, p.z])


def _publish_world(executor: Any, node: PlannerNode, peer: Peer, seed: int) -> None:
    domain = node.sessions[0].domain
    assert isinstance(domain, HelicopterDomain)
    markers, cloud = helicopter_world_messages(
        domain.make_world("wires", seed), wire_segments=8, frame_id="map", msgs=RclpyMessages()
    )
    version = node.snapshot.version
    peer.terrain.publish(cloud)
    peer.obstacles.publish(markers)
    assert spin_until(executor, lambda: node.snapshot.version >= version + 2)


def _checked_free(peer: Peer) -> set[int]:
    return {int(s.name.split("/")[1]) for s in peer.checks[-1].status if s.level == b"\x00"}


def test_plans_start_at_the_robot_state_reach_any_goal_and_follow_the_robot(context: Any, prior_file: Path) -> None:
    node = PlannerNode(context=context, parameter_overrides=[Parameter("prior_paths", value=[str(prior_file)])])
    peer = Peer(context)
    odom = peer.node.create_publisher(Odometry, "odom", 10)
    get_plan = peer.node.create_client(GetPlan, "get_plan")
    replan = peer.node.create_client(Trigger, "replan")
    with active_planner(context, node, peer) as executor:
        session = node.sessions[0]
        goal_state = session.vertex_state(GOAL)
        goal = _pose(PoseStamped(), goal_state)
        _publish_world(executor, node, peer, 100)
        peer.goals.publish(goal)  # no robot state yet: a clear refusal, nothing planned
        assert spin_until(executor, lambda: bool(node.errors))
        assert "no robot state known yet" in node.errors[-1]
        assert "'odom'" in node.errors[-1]
        start = session.vertex_state(0) + np.array([-30.0, 0.0, 0.0, 0.0])  # off the graph
        odom.publish(_pose(Odometry(), start))
        assert spin_until(
            executor, lambda: node.service is not None and node.service.robot_states.get("odom") is not None
        )
        for seed in range(100, 130):  # the first world with a free path from there
            if seed > 100:
                _publish_world(executor, node, peer, seed)
            count = len(peer.summaries())
            peer.goals.publish(goal)
            assert spin_until(executor, lambda count=count: len(peer.summaries()) > count)
            if peer.summaries()[-1]["result"] == "found":
                break
        else:
            pytest.fail("no world with a free path")
        # Each plan summary comes with one check log; wait for this plan's (the topics race each other).
        assert spin_until(executor, lambda: bool(peer.plans) and len(peer.checks) >= len(peer.summaries()))
        path = peer.plans[-1]
        np.testing.assert_allclose(_xyz(path, 0), start[:3], atol=1e-4)  # from where the robot is ...
        np.testing.assert_allclose(_xyz(path, -1), goal_state[:3], atol=1e-4)  # ... to a goal no tree was for
        published = node.published
        assert published is not None
        assert set(published.path_edges) <= _checked_free(peer)
        assert any(e >= session.prior.graph.num_edges for e in published.path_edges)  # a checked new motion
        # get_plan with an explicit start plans from there.
        other = session.vertex_state(1) + np.array([-20.0, 0.0, 0.0, 0.0])
        request = GetPlan.Request()
        request.goal = goal
        _pose(request.start, other)
        future = get_plan.call_async(request)
        assert spin_until(executor, future.done)
        answer = future.result().plan
        assert answer.poses, node.errors[-1:]
        np.testing.assert_allclose(_xyz(answer, 0), other[:3], atol=1e-4)
        # The robot moved along its plan; `replan` plans again from where it is now.
        moved = np.array(published.states[len(published.states) // 3], dtype=float)
        odom.publish(_pose(Odometry(), moved))
        assert spin_until(
            executor,
            lambda: node.service is not None and np.allclose(node.service.robot_states["odom"], moved),
        )
        future = replan.call_async(Trigger.Request())
        assert spin_until(executor, future.done), future.result().message
        assert future.result().success, future.result().message
        # The plan topic may trail the response: wait until the newest plan on it starts where the robot is.
        assert spin_until(
            executor,
            lambda: bool(peer.plans[-1].poses) and np.allclose(_xyz(peer.plans[-1], 0), moved[:3], atol=1e-4),
        )
        # A box on the plan ahead of the robot: the node replans from the robot's state, not the old start.
        again = node.published
        assert again is not None
        edge = again.path_edges[len(again.path_edges) // 2]
        count = len(peer.plans)
        peer.block_edge(session, edge)

        def replans() -> list[dict[str, str]]:
            return [v for v in peer.summaries() if v["request"] == "map_update"]

        # The new plan (or the empty one) and the replan's summary travel on two topics: wait for both.
        assert spin_until(executor, lambda: len(peer.plans) > count and bool(replans()))
        last = peer.plans[-1]
        assert f"plan edge {edge} blocked" in replans()[-1]["replan_reason"]
        if last.poses:  # replanned from where the robot is
            np.testing.assert_allclose(_xyz(last, 0), moved[:3], atol=1e-4)
            assert node.published is not None
            assert edge not in node.published.path_edges
        else:  # no free path from where the robot is: the blocked plan was withdrawn
            message = replans()[-1]["message"]  # the robot's own state (off the graph) to the goal vertex
            assert node.published is None
            assert "from the start [" in message
            assert f"to the goal (vertex {GOAL}:" in message
