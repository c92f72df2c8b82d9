"""Collision meshes from URDF text: parsing, primitives, file lookup, one shared load, placement by FK."""

from __future__ import annotations

from pathlib import Path

import fcl
import numpy as np
import pytest
from conftest import SHARED_DATA

from drd_planner.exceptions import GeometryError
from drd_planner.geometry.mesh_robot import LinkMeshLoader, MeshPlacement, parse_link_meshes
from drd_planner.geometry.robot import RobotModel

PANDA = SHARED_DATA / "panda"

BOX_ARM = """<robot name="boxy">
  <link name="base"><collision><geometry><box size="0.2 0.2 0.1"/></geometry></collision></link>
  <link name="arm">
    <collision><origin xyz="0.25 0 0" rpy="0 0 1.5707963267948966"/>
      <geometry><box size="0.1 0.5 0.04"/></geometry></collision>
    <collision><origin xyz="0.5 0 0"/><geometry><sphere radius="0.05"/></geometry></collision>
    <collision><geometry><cylinder radius="0.03" length="0.2"/></geometry></collision>
  </link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="0 0 0.1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>"""
BOX_ARM_SPHERES = """<robot name="boxy">
  <link name="base"><collision><geometry><sphere radius="0.1"/></geometry></collision></link>
  <link name="arm"><collision><origin xyz="0.25 0 0"/><geometry><sphere radius="0.1"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="0 0 0.1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>"""


@pytest.fixture(scope="module")
def panda_text() -> str:
    if not (PANDA / "meshes" / "collision").is_dir():
        pytest.skip(f"shared Panda meshes {PANDA} not present (set DRD_SHARED_DATA)")
    return (PANDA / "panda.urdf").read_text()


def test_panda_meshes_are_read_once_per_text_and_folder(panda_text: str) -> None:
    loader = LinkMeshLoader(capacity=1)
    meshes = loader.meshes(panda_text, PANDA)
    assert meshes.links == (
        "panda_link0",
        "panda_link1",
        "panda_link2",
        "panda_link3",
        "panda_link4",
        "panda_link5",
        "panda_link6",
        "panda_link7",
        "panda_hand",
        "panda_leftfinger",
        "panda_rightfinger",
    )
    assert all(p.kind == "mesh" and isinstance(p.geometry, fcl.BVHModel) for p in meshes.parts)
    # Merged OBJ vertices: most links close up into solids; link6 is 29 separate bodies (a surface).
    assert {p.link for p in meshes.parts if p.solid is None} == {"panda_link6"}
    assert meshes.triangles == sum(p.faces.shape[0] for p in meshes.parts) > 3000
    assert loader.meshes(panda_text, PANDA) is meshes
    assert len(loader) == 1
    assert loader.meshes(panda_text, PANDA / "meshes" / "..") is meshes  # the same folder spelled differently
    loader.meshes(BOX_ARM, PANDA)  # capacity 1: the Panda set is dropped
    assert loader.meshes(panda_text, PANDA) is not meshes
    # The right finger's collision is turned by pi about z: its mesh is the left one's, mirrored.
    left, right = meshes.parts[-2], meshes.parts[-1]
    np.testing.assert_allclose(right.origin[:2, :2], -np.eye(2), atol=1e-9)
    np.testing.assert_array_equal(left.vertices, right.vertices)


def test_primitives_and_origins_are_read_exactly() -> None:
    meshes = parse_link_meshes(BOX_ARM, ".")
    assert [p.kind for p in meshes.parts] == ["box", "box", "sphere", "cylinder"]
    box = meshes.parts[1]
    np.testing.assert_allclose(box.bounds, [[-0.05, -0.25, -0.02], [0.05, 0.25, 0.02]])
    np.testing.assert_allclose(box.origin[:3, 3], [0.25, 0, 0])
    np.testing.assert_allclose(box.origin[:3, :3] @ [1.0, 0, 0], [0, 1.0, 0], atol=1e-12)  # yaw pi/2
    np.testing.assert_allclose(meshes.parts[2].bounds, [[-0.05] * 3, [0.05] * 3])
    np.testing.assert_allclose(meshes.parts[3].bounds, [[-0.03, -0.03, -0.1], [0.03, 0.03, 0.1]])
    assert meshes.triangles == 0  # primitives only


def test_missing_or_bad_collisions_are_refused(tmp_path: Path) -> None:
    urdf = '<robot name="r"><link name="a"><collision><geometry><mesh filename="package://pkg/m/x.obj"/></geometry></collision></link></robot>'
    with pytest.raises(GeometryError, match=r"collision mesh 'package://pkg/m/x.obj' not found.*urdf_path"):
        parse_link_meshes(urdf, tmp_path)
    (tmp_path / "m").mkdir()
    (tmp_path / "m" / "x.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    found = parse_link_meshes(urdf, tmp_path)  # package name dropped: <folder>/m/x.obj
    assert found.parts[0].faces.shape == (1, 3)
    assert found.parts[0].solid is None
    with pytest.raises(GeometryError, match="no <collision> elements"):
        parse_link_meshes('<robot name="r"><link name="a"/></robot>', tmp_path)
    with pytest.raises(GeometryError, match="without mesh, box, cylinder or sphere"):
        parse_link_meshes('<robot name="r"><link name="a"><collision/></link></robot>', tmp_path)
    with pytest.raises(GeometryError, match="not 3 finite numbers"):
        parse_link_meshes(BOX_ARM.replace('size="0.2 0.2 0.1"', 'size="0.2 nan 0.1"'), tmp_path)
    with pytest.raises(GeometryError, match="well-formed"):
        parse_link_meshes("<robot", tmp_path)


def test_placement_follows_forward_kinematics() -> None:
    robot = RobotModel.from_urdf(BOX_ARM, sphere_urdf=BOX_ARM_SPHERES)
    meshes = parse_link_meshes(BOX_ARM, ".")
    placement = MeshPlacement(robot, meshes)
    assert placement.frame_index.tolist() == [0, 1, 1, 1]
    q = np.array([[0.0], [np.pi / 2]])
    poses = placement.poses(q)
    assert poses.shape == (2, 4, 4, 4)
    # The sphere element sits 0.5 m out along the arm, 0.1 m up: along x at q = 0, along y at q = pi/2.
    np.testing.assert_allclose(poses[0, 2, :3, 3], [0.5, 0, 0.1], atol=1e-12)
    np.testing.assert_allclose(poses[1, 2, :3, 3], [0, 0.5, 0.1], atol=1e-12)
    np.testing.assert_allclose(poses, robot.link_poses(q)[:, [0, 1, 1, 1]] @ np.stack([p.origin for p in meshes.parts]))
    lo, hi = placement.boxes(poses)
    # The box (0.1 x 0.5 x 0.04, turned by pi/2 in the link, the link by pi/2) lies along world y: exact box.
    np.testing.assert_allclose(lo[1, 1], [-0.05, 0.0, 0.08], atol=1e-12)
    np.testing.assert_allclose(hi[1, 1], [0.05, 0.5, 0.12], atol=1e-12)
    for n in range(2):
        for p in range(4):
            world = placement.world_vertices(poses[n, p], p)
            assert np.all(world >= lo[n, p] - 1e-12)
            assert np.all(world <= hi[n, p] + 1e-12)
    with pytest.raises(GeometryError, match="no link 'elbow'"):
        MeshPlacement(robot, parse_link_meshes(BOX_ARM.replace('"arm"', '"elbow"', 1), "."))
