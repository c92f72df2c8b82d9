"""Robot collision meshes against scenes: contact, margin, inside and terrain rules, early exit by group."""

from __future__ import annotations

import fcl
import numpy as np
import pytest
import trimesh
from conftest import SHARED_DATA

from drd_planner.domains.arm_params import DEFAULT_START
from drd_planner.domains.arm_robot import load_robot
from drd_planner.geometry.fcl_queries import pair_collides
from drd_planner.geometry.mesh_collider import MeshCollider, SceneObstacles
from drd_planner.geometry.mesh_robot import LinkMeshes, MeshPlacement, parse_link_meshes
from drd_planner.geometry.robot import RobotModel
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Box, Pose, TriangleMesh
from drd_planner.geometry.terrain import Heightfield

PANDA = SHARED_DATA / "panda"
Q = np.array([DEFAULT_START])


@pytest.fixture(scope="module")
def robot() -> RobotModel:
    if not (PANDA / "meshes" / "collision").is_dir():
        pytest.skip(f"shared Panda model {PANDA} not present (set DRD_SHARED_DATA)")
    return load_robot()


@pytest.fixture(scope="module")
def panda(robot: RobotModel) -> LinkMeshes:
    return parse_link_meshes((PANDA / "panda.urdf").read_text(), PANDA)


def only(meshes: LinkMeshes, link: str) -> LinkMeshes:
    """The elements of one link (so a hit can only be that link's)."""
    return LinkMeshes(tuple(p for p in meshes.parts if p.link == link), meshes.folder)


def collider(robot: RobotModel, meshes: LinkMeshes, scene: Scene) -> MeshCollider:
    return MeshCollider(MeshPlacement(robot, meshes), SceneObstacles.of_scene(scene))


def placed(robot: RobotModel, meshes: LinkMeshes) -> fcl.CollisionObject:
    """A fresh FCL object of the first element at its pose at Q."""
    pose = MeshPlacement(robot, meshes).poses(Q)[0, 0]
    return fcl.CollisionObject(meshes.parts[0].geometry, fcl.Transform(pose[:3, :3], pose[:3, 3]))


def hand_vertex(robot: RobotModel, hand: LinkMeshes) -> tuple[np.ndarray, np.ndarray]:
    """A hand vertex in the world at Q and the outward direction from the hand's box centre to it."""
    placement = MeshPlacement(robot, hand)
    world = placement.world_vertices(placement.poses(Q)[0, 0], 0)
    centre = (world.min(axis=0) + world.max(axis=0)) / 2.0
    far = int(np.argmax(np.linalg.norm(world - centre, axis=1)))
    out = world[far] - centre
    return world[far], out / np.linalg.norm(out)


def test_a_link_mesh_at_its_fk_pose_meets_a_box_on_it_and_not_one_moved_away(
    robot: RobotModel, panda: LinkMeshes
) -> None:
    hand = only(panda, "panda_hand")
    vertex, out = hand_vertex(robot, hand)
    on = Scene()
    on.add(Box([0.02, 0.02, 0.02]), Pose(vertex), name="on")
    hit = collider(robot, hand, on)
    assert hit.groups_blocked(Q, np.array([0]), 1).tolist() == [True]
    contact = hit.first_contact(Q)
    assert contact is not None
    assert (contact.link, contact.reason, contact.obstacle) == (
        "panda_hand",
        "contact",
        0,
    )
    assert 0.0 < contact.depth <= 0.02 * np.sqrt(3)
    part = hand.parts[0]  # its collision origin is the identity: the link frame is the mesh's
    assert np.all(contact.point >= part.bounds[0] - 0.021)
    assert np.all(contact.point <= part.bounds[1] + 0.021)
    world = MeshPlacement(robot, hand).poses(Q)[0, 0] @ np.append(contact.point, 1.0)
    assert np.linalg.norm(world[:3] - vertex) < 0.02 * np.sqrt(3)  # at the box
    away = Scene()
    away.add(Box([0.02, 0.02, 0.02]), Pose(vertex + 0.05 * out), name="away")
    free = collider(robot, hand, away)
    assert free.groups_blocked(Q, np.array([0]), 1).tolist() == [False]
    assert free.first_contact(Q) is None
    alone = placed(robot, hand)  # the same pairs, FCL alone
    assert not pair_collides(alone, SceneObstacles.of_scene(away).objects[0])
    assert pair_collides(alone, SceneObstacles.of_scene(on).objects[0])


def test_margin_blocks_what_lies_closer_than_it(robot: RobotModel, panda: LinkMeshes) -> None:
    hand = only(panda, "panda_hand")
    vertex, out = hand_vertex(robot, hand)
    outcomes = {}
    for margin in (0.0, 0.02, 0.06):
        scene = Scene(margin=margin)
        scene.add(Box([0.02, 0.02, 0.02]), Pose(vertex + 0.05 * out), name="near")
        model = collider(robot, hand, scene)
        contact = model.first_contact(Q)
        outcomes[margin] = None if contact is None else contact.reason
    # The box's nearest face is 0.04 m from the vertex along `out` (less sideways): free at 2 cm, not at 6 cm.
    assert outcomes == {0.0: None, 0.02: None, 0.06: "margin"}


def test_what_fcl_cannot_see_inside_meshes_still_blocks(robot: RobotModel, panda: LinkMeshes) -> None:
    link7 = only(panda, "panda_link7")
    assert link7.parts[0].solid is not None
    placement = MeshPlacement(robot, link7)
    pose = placement.poses(Q)[0, 0]
    inner = np.asarray(link7.parts[0].solid.center_mass)
    assert bool(link7.parts[0].solid.contains(inner[None])[0])
    tiny = Scene()
    tiny.add(Box([0.004, 0.004, 0.004]), Pose(pose[:3, :3] @ inner + pose[:3, 3]), name="tiny")
    assert not pair_collides(placed(robot, link7), SceneObstacles.of_scene(tiny).objects[0])  # hollow to FCL
    contact = collider(robot, link7, tiny).first_contact(Q)
    assert contact is not None
    assert (contact.reason, contact.obstacle) == ("inside", 0)
    shell = trimesh.creation.box(extents=[3.0, 3.0, 3.0])
    boxed = Scene()
    boxed.add(TriangleMesh(shell.vertices, shell.faces), Pose(), name="room")
    inside = collider(robot, link7, boxed).first_contact(Q)
    assert inside is not None
    assert inside.reason == "inside"
    buried = Scene()
    buried.add_terrain(Heightfield((-5.0, -5.0), 1.0, np.full((11, 11), 5.0)))
    under = collider(robot, link7, buried).first_contact(Q)
    assert under is not None
    assert under.reason == "terrain"
    assert collider(robot, link7, Scene()).first_contact(Q) is None


def test_groups_stop_at_their_first_blocked_configuration(robot: RobotModel, panda: LinkMeshes) -> None:
    hand = only(panda, "panda_hand")
    vertex, _ = hand_vertex(robot, hand)
    scene = Scene()
    scene.add(Box([0.3, 0.3, 0.3]), Pose(vertex), name="block")
    far = np.array(DEFAULT_START) + np.array([1.5, 0, 0, 0, 0, 0, 0])  # the hand swung away from the box
    rows = np.stack([far, Q[0], Q[0], Q[0], far, far])
    owner = np.array([0, 0, 0, 0, 1, 1])
    grouped = collider(robot, hand, scene)
    assert grouped.groups_blocked(rows, owner, 2).tolist() == [True, False]
    one_by_one = collider(robot, hand, scene)
    per_row = one_by_one.groups_blocked(rows, np.arange(6), 6)
    assert per_row.tolist() == [False, True, True, True, False, False]
    assert grouped.queries < one_by_one.queries  # rows 2 and 3 were never decided
    again = collider(robot, hand, scene)
    assert again.groups_blocked(rows, owner, 2).tolist() == [True, False]
    assert again.queries == grouped.queries
