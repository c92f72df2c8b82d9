"""drd_map_server with real rclpy: its latched maps reach a planner node, which refuses a foreign terrain."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

rclpy = pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")

from harness import Peer, active_planner, private_context, spin_until  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from sensor_msgs.msg import PointCloud2  # noqa: E402
from visualization_msgs.msg import MarkerArray  # noqa: E402

from drd_msgs_py.factory import RclpyMessages  # noqa: E402
from drd_msgs_py.terrain import cloud_from_heightfield  # noqa: E402
from drd_planner.geometry.terrain import Heightfield  # noqa: E402
from drd_planner.ros.map_server import MapServer, MapServerError  # noqa: E402
from drd_planner.ros.node import LATCHED, PlannerNode  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
# This file's own domains (160-169): no other test file uses them.
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
os.environ["ROS_DOMAIN_ID"] = str(160 + os.getpid() % 10)


@pytest.fixture
def context() -> Iterator[Any]:
    with private_context() as ctx:
        yield ctx


def _server(ctx: Any, **values: Any) -> MapServer:
    return MapServer(context=ctx, parameter_overrides=[Parameter(k, value=v) for k, v in values.items()])


def test_each_bad_parameter_is_named_and_a_prior_of_no_site_is_refused(context: Any) -> None:
    with pytest.raises(MapServerError) as bad:
        _server(context, frame_id="two words", terrain_topic="bad topic!")
    text = str(bad.value)
    assert "frame_id must be a frame name" in text
    assert "terrain_topic must be a topic name" in text
    assert "prior or site_file must name the site to publish" in text
    with pytest.raises(
        MapServerError, match=r"heli_wires.npz is not a prior of a real site .*such as the shipped heli_lines"
    ):
        _server(context, prior="heli_wires")
    with pytest.raises(MapServerError, match=r"neither a file nor no_such_prior\.npz"):
        _server(context, prior="no_such_prior")


def test_a_late_planner_gets_the_latched_site_and_refuses_a_foreign_terrain(context: Any) -> None:
    server = _server(context, prior="heli_lines")
    got: dict[str, list[Any]] = {"terrain": [], "obstacles": []}
    listener = rclpy.create_node("listener", context=context)
    listener.create_subscription(PointCloud2, "terrain", got["terrain"].append, LATCHED)
    listener.create_subscription(MarkerArray, "obstacles", got["obstacles"].append, LATCHED)
    node = PlannerNode(
        context=context,
        parameter_overrides=[
            Parameter("prior_paths", value=["heli_lines"]),
            Parameter("start_without_robot_state", value="prior_start"),
        ],
    )
    peer = Peer(context)
    with active_planner(context, node, peer) as executor:
        executor.add_node(server)
        executor.add_node(listener)
        # Published once, before anyone listened: the latched QoS delivers both maps to the late subscribers.
        assert spin_until(executor, lambda: bool(got["terrain"] and got["obstacles"]), timeout=30.0)
        cloud = got["terrain"][0]
        assert cloud.header.frame_id == "map"
        assert (cloud.height, cloud.width) == server.world.terrain.shape
        assert len(got["obstacles"][0].markers) == 1 + len(server.world.wires) + len(server.world.solids)

        def snapshot() -> Any:
            return None if node.service is None else node.service.snapshot

        assert spin_until(
            executor, lambda: snapshot() is not None and snapshot().terrain is not None and snapshot().obstacles
        )
        accepted = snapshot()
        assert np.allclose(accepted.terrain.heights, server.world.terrain.heights, atol=1e-3)
        assert len(accepted.obstacles) == len(server.world.wires) + len(server.world.solids)
        assert not node.errors
        # The same grid 150 m higher: under some lattice vertices still, but not this prior's site.
        t = server.world.terrain
        raised = Heightfield(t.origin, t.cell_size, t.heights + 150.0)
        peer.terrain.publish(cloud_from_heightfield(raised, frame_id="map", stamp=(1, 0), msgs=RclpyMessages()))
        assert spin_until(executor, lambda: bool(node.errors))
        (error,) = node.errors
        assert error.startswith("terrain refused, map unchanged: not the prior's terrain: terrain is not the site")
        assert "median height differs by +150 m from its DEM (allowed 60 m" in error
        assert snapshot() is accepted  # the previous maps stay
        assert node.service is not None  # and the node stays up
    listener.destroy_node()
    server.destroy_node()


def test_the_console_script_refuses_a_missing_site_with_one_line() -> None:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    done = subprocess.run(
        [sys.executable, "-m", "drd_planner.cli.map_server", "--frame-id", "map"],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        check=False,
    )
    assert done.returncode == 2
    assert done.stderr.strip().splitlines()[-1] == (
        "drd_map_server: error: prior or site_file must name the site to publish (e.g. prior:=heli_lines)"
    )
