"""Map message data -> the planner's geometry: exact shapes, wires as capsule chains, terrain options."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from drd_msgs_py.obstacles import Obstacle
from drd_msgs_py.shapes import HeightGrid, LineStripData, MeshData, PoseData
from drd_msgs_py.terrain import cloud_from_heightfield
from drd_planner.exceptions import GeometryError
from drd_planner.geometry.map_limits import MapLimits
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Box, Capsule, Cylinder, Sphere, TriangleMesh
from drd_planner.geometry.terrain import Heightfield
from drd_planner.geometry.wires import Wire
from drd_planner.planning.map_intake import (
    heightfield_of,
    obstacle_data,
    obstacle_map,
    obstacle_parts,
    pose_data,
    pose_of,
    terrain_from_cloud,
)
from drd_planner.planning.world_messages import obstacle_markers

FRAME = "map"


def _world(msgs: Any) -> Any:
    yaw = math.radians(30)
    tet = TriangleMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]])
    wire = Wire([0, 0, 30], [100, 0, 30], sag=4.0, diameter=0.05)
    return obstacle_markers(
        [
            ("box/1", Box((2, 3, 4)), Pose((1, 2, 3), (0, 0, math.sin(yaw / 2), math.cos(yaw / 2)))),
            ("ball/2", Sphere(1.5), Pose((5, 5, 5))),
            ("nofly/3", Cylinder(50.0, 200.0), Pose((300, 0, 100))),
            ("mesh/4", tet, Pose((-5, 0, 0))),
            ("wire/5", wire.points(5), 0.05),
        ],
        frame_id=FRAME,
        msgs=msgs,
    )


def test_round_trip_gives_the_same_shapes(msgs: Any) -> None:
    parts = obstacle_map(_world(msgs), frame_id=FRAME)
    ((box, pose),) = parts["box/1"]
    assert box == Box((2, 3, 4))
    np.testing.assert_allclose(pose.position, (1, 2, 3))
    assert parts["ball/2"][0][0] == Sphere(1.5)
    assert parts["nofly/3"][0][0] == Cylinder(50.0, 200.0)
    mesh = parts["mesh/4"][0][0]
    assert isinstance(mesh, TriangleMesh)
    assert mesh.faces.shape == (4, 3)
    chain = parts["wire/5"]
    assert len(chain) == 4
    assert all(isinstance(s, Capsule) and s.radius == pytest.approx(0.025) for s, _ in chain)


def test_wire_capsules_touch_what_the_wire_touches(msgs: Any) -> None:
    scene = Scene()
    for key, parts in obstacle_map(_world(msgs), frame_id=FRAME).items():
        for k, (shape, pose) in enumerate(parts):
            scene.add(shape, pose, name=f"{key}#{k}")
    # The polyline's third knot is at x = 50, z = 30 - 4 (full sag): a small sphere there hits.
    assert scene.spheres_collide([[50.0, 0.0, 26.0]], 0.1)
    assert not scene.spheres_collide([[50.0, 0.0, 28.0]], 0.1)  # above the sagging middle
    assert scene.spheres_collide([[300.0, 0.0, 100.0]], 1.0)  # inside the no-fly cylinder (a solid)


def test_a_rotated_line_strip_goes_to_the_world_frame() -> None:
    strip = LineStripData(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 2.0, 0.0]]), 0.2)
    quarter = PoseData((10.0, 0.0, 0.0), (0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4)))
    parts = obstacle_parts(Obstacle("w/0", strip, quarter, "LINE_STRIP", 4))
    assert len(parts) == 2  # the repeated point makes no capsule
    np.testing.assert_allclose(parts[0][1].position, (10.0, 0.5, 0.0), atol=1e-12)
    assert [s.length for s, _ in parts] == pytest.approx([1.0, 2.0])


def test_shapes_the_geometry_refuses_name_their_marker() -> None:
    bad = MeshData(np.zeros((3, 3)), np.array([[0, 1, 5]]))
    with pytest.raises(GeometryError, match=r"marker 2 \(m/1\): mesh face indices"):
        obstacle_parts(Obstacle("m/1", bad, PoseData(), "TRIANGLE_LIST", 3, label="marker 2 (m/1)"))


def test_poses_and_shapes_convert_both_ways() -> None:
    pose = Pose((1.0, 2.0, 3.0), (0.0, 0.0, 0.6, 0.8))
    back = pose_of(pose_data(pose))
    np.testing.assert_array_equal(back.position, pose.position)
    np.testing.assert_array_equal(back.quaternion_xyzw, pose.quaternion_xyzw)
    data, where = obstacle_data(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]), 0.3)
    assert isinstance(data, LineStripData)
    assert data.diameter == 0.3
    assert where == PoseData()
    with pytest.raises(GeometryError, match="needs a Pose"):
        obstacle_data(Sphere(1.0), 0.5)


def test_the_unknown_terrain_option_reaches_the_heightfield(msgs: Any) -> None:
    rng = np.random.default_rng(0)
    heights = rng.uniform(0, 40, (7, 9))
    heights[2, 3] = np.nan
    cloud = cloud_from_heightfield(Heightfield((-100.0, 250.0), 25.0, heights), frame_id=FRAME, msgs=msgs)
    assert terrain_from_cloud(cloud, frame_id=FRAME).unknown == "blocked"
    terrain = terrain_from_cloud(cloud, frame_id=FRAME, limits=MapLimits(unknown_terrain="highest_neighbour"))
    assert terrain.unknown == "highest_neighbour"
    assert terrain.surface_heights[2, 3] == np.nanmax(terrain.heights[1:4, 2:5])
    with pytest.raises(GeometryError, match="terrain cloud: "):
        heightfield_of(HeightGrid((0.0, 0.0), -1.0, np.zeros((2, 2))))
