"""How the sphere model covers the collision meshes, and the growth that makes it contain them."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import SHARED_DATA

from drd_planner.domains.arm_robot import load_robot
from drd_planner.exceptions import GeometryError
from drd_planner.geometry.mesh_cover import sphere_cover
from drd_planner.geometry.mesh_robot import LinkMeshes, MeshPlacement, parse_link_meshes
from drd_planner.geometry.robot import RobotModel

PANDA = SHARED_DATA / "panda"

ONE_LINK = """<robot name="r">
  <link name="base"><collision><geometry>{base}</geometry></collision></link>
  <link name="arm"><collision><origin xyz="0.3 0 0"/><geometry>{arm}</geometry></collision></link>
  <joint name="j" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>"""


def robot_and_meshes(arm_box: str, arm_sphere: str) -> tuple[RobotModel, LinkMeshes]:
    spheres = ONE_LINK.format(base='<sphere radius="0.1"/>', arm=arm_sphere)
    meshes = ONE_LINK.format(base='<box size="0.1 0.1 0.1"/>', arm=arm_box)
    return RobotModel.from_urdf(meshes, sphere_urdf=spheres), parse_link_meshes(meshes, ".")


def test_a_box_inside_its_sphere_needs_no_growth_beyond_the_bound() -> None:
    robot, meshes = robot_and_meshes('<box size="0.1 0.1 0.1"/>', '<sphere radius="0.1"/>')
    cover = sphere_cover(robot, meshes, spacing=0.01)
    # Corners are sqrt(3) * 0.05 = 0.0866 m from the centre: 0.0134 m inside the 0.1 m spheres.
    assert [e.max_excess for e in cover.elements] == pytest.approx([-0.1 + 0.05 * np.sqrt(3)] * 2, abs=1e-9)
    assert all(e.outside_share == 0.0 for e in cover.elements)
    assert cover.bound <= 0.01 / np.sqrt(3) + 1e-12
    assert np.all(cover.growth <= cover.bound)


def test_a_box_sticking_out_is_measured_and_the_growth_contains_it() -> None:
    robot, meshes = robot_and_meshes('<box size="0.4 0.04 0.04"/>', '<sphere radius="0.05"/>')
    cover = sphere_cover(robot, meshes, spacing=0.01)
    tip = np.sqrt(0.2**2 + 0.02**2 + 0.02**2) - 0.05  # the box's far corners
    arm = cover.elements[1]
    assert arm.max_excess == pytest.approx(tip, abs=1e-9)
    assert abs(abs(arm.worst_point[0] - 0.3) - 0.2) < 1e-9  # at an end of the box
    assert 0.5 < arm.outside_share < 1.0
    assert tip < cover.growth[1] <= tip + cover.bound + 1e-12  # the excess plus this element's bound


def test_panda_spheres_grown_by_the_growth_contain_every_mesh_vertex() -> None:
    if not (PANDA / "meshes" / "collision").is_dir():
        pytest.skip(f"shared Panda model {PANDA} not present (set DRD_SHARED_DATA)")
    robot = load_robot()
    meshes = parse_link_meshes((PANDA / "panda.urdf").read_text(), PANDA)
    cover = sphere_cover(robot, meshes, spacing=0.02)
    assert cover.max_excess > 0.0  # the spheres do not contain the meshes as they are
    placement = MeshPlacement(robot, meshes)
    spheres = robot.spheres
    for p, part in enumerate(meshes.parts):
        offset = placement.offsets[p]
        points = part.vertices @ offset[:3, :3].T + offset[:3, 3]
        own = np.nonzero(spheres.frame_index == placement.frame_index[p])[0]
        reach = spheres.radii[own] + cover.growth[own]
        gaps = np.linalg.norm(points[:, None] - spheres.centres[own], axis=2) - reach
        assert gaps.min(axis=1).max() <= 1e-12, part.link
        without = np.linalg.norm(points[:, None] - spheres.centres[own], axis=2) - spheres.radii[own]
        assert without.min(axis=1).max() <= cover.elements[p].max_excess + 1e-12


def test_an_element_without_spheres_on_its_frame_cannot_be_covered() -> None:
    spheres = ONE_LINK.format(base='<sphere radius="0.1"/>', arm="<sphere radius='0.1'/>").replace(
        '<link name="arm"><collision><origin xyz="0.3 0 0"/><geometry><sphere '
        "radius='0.1'/></geometry></collision></link>",
        '<link name="arm"/>',
    )
    meshes = ONE_LINK.format(base='<box size="0.1 0.1 0.1"/>', arm='<box size="0.1 0.1 0.1"/>')
    robot = RobotModel.from_urdf(meshes, sphere_urdf=spheres)
    with pytest.raises(GeometryError, match="no sphere moves with link 'arm'"):
        sphere_cover(robot, parse_link_meshes(meshes, "."))
    with pytest.raises(GeometryError, match="spacing"):
        sphere_cover(robot, parse_link_meshes(meshes, "."), spacing=0.0)
