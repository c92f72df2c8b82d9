"""Scene: hand-placed shapes with known answers, margins, traps, editing and a brute-force cross-check."""

from __future__ import annotations

import math

import fcl
import numpy as np
import pytest
import trimesh

from drd_planner.exceptions import GeometryError
from drd_planner.geometry.fcl_queries import pair_collides
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Box, Capsule, Cylinder, Sphere, TriangleMesh, make_fcl_geometry
from drd_planner.geometry.terrain import Heightfield
from drd_planner.geometry.wires import Wire

YAW_90 = (0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4))  # ROS (x, y, z, w)


def unit_box_scene(margin: float = 0.0) -> Scene:
    scene = Scene(margin=margin)
    scene.add(Box((1.0, 1.0, 1.0)), Pose.identity(), name="box")
    return scene


def closed_box_mesh(size: float = 2.0) -> TriangleMesh:
    box = trimesh.creation.box(extents=(size, size, size))
    return TriangleMesh(box.vertices, box.faces)


# --------------------------------------------------------------------------------------------------
# Known answers and traps


def test_quaternion_order_box_rotated_90_about_z() -> None:
    scene = Scene()
    scene.add(Box((4.0, 1.0, 1.0)), Pose((0.0, 0.0, 0.0), YAW_90))  # long axis now along world y
    assert scene.spheres_collide([[0.0, 1.5, 0.0]], 0.1)
    assert not scene.spheres_collide([[1.5, 0.0, 0.0]], 0.1)
    assert scene.collides(Sphere(0.1), Pose((0.0, 1.5, 0.0)))
    assert not scene.collides(Sphere(0.1), Pose((1.5, 0.0, 0.0)))


@pytest.mark.parametrize("shape", [Cylinder(0.05, 2.0), Capsule(0.05, 2.0)])
def test_long_thin_obstacles_lie_along_z(shape: Cylinder | Capsule) -> None:
    scene = Scene()
    scene.add(shape, Pose.identity())
    half = shape.length / 2.0
    assert scene.spheres_collide([[0.0, 0.0, half - 1e-3]], 1e-3)
    assert not scene.spheres_collide([[half - 1e-3, 0.0, 0.0]], 1e-3)
    assert scene.collides(Sphere(1e-3), Pose((0.0, 0.0, -half + 1e-3)))
    assert not scene.collides(Sphere(1e-3), Pose((0.0, half - 1e-3, 0.0)))


def test_free_query_after_a_colliding_one_is_free() -> None:
    scene = unit_box_scene()
    answers = [scene.spheres_collide([[x, 0.0, 0.0]], 0.1) for x in (0.0, 5.0, 0.55, 0.65)]
    assert answers == [True, False, True, False]
    answers = [scene.collides(Sphere(0.1), Pose((x, 0.0, 0.0))) for x in (0.0, 5.0, 0.55, 0.65)]
    assert answers == [True, False, True, False]


def test_sphere_inside_closed_mesh_is_blocked() -> None:
    scene = Scene()
    scene.add(closed_box_mesh(), Pose((10.0, 0.0, 0.0)), name="crate")
    raw = fcl.CollisionObject(make_fcl_geometry(closed_box_mesh()), Pose((10.0, 0.0, 0.0)).to_fcl())
    probe = fcl.CollisionObject(fcl.Sphere(0.1), fcl.Transform(np.array([10.0, 0.0, 0.0])))
    assert not pair_collides(raw, probe)  # FCL alone: a surface, so "free"
    assert scene.spheres_collide([[10.0, 0.0, 0.0]], 0.1)
    assert scene.spheres_collide_mask([[10.0, 0.0, 0.0], [10.0, 0.0, 5.0]], 0.1).tolist() == [True, False]
    assert scene.collides(Sphere(0.1), Pose((10.0, 0.0, 0.0)))
    assert scene.collides(Box((0.2, 0.2, 0.2)), Pose((10.2, 0.1, -0.3)))
    assert not scene.sphere_sweep_free([[8.0, 0.0, 0.0], [10.0, 0.0, 0.0], [12.0, 0.0, 0.0]], 0.1)
    assert not scene.collides(Sphere(0.1), Pose((10.0, 0.0, 5.0)))


def test_triangle_soup_that_closes_up_is_a_solid() -> None:
    box = trimesh.creation.box(extents=(2.0, 2.0, 2.0))
    soup = box.vertices[box.faces].reshape(-1, 3)  # three fresh vertices per triangle, as a ROS TRIANGLE_LIST
    scene = Scene()
    scene.add(TriangleMesh(soup, np.arange(len(soup)).reshape(-1, 3)), Pose.identity())
    assert scene.spheres_collide([[0.0, 0.0, 0.0]], 0.1)


def test_open_mesh_is_only_a_surface() -> None:
    box = trimesh.creation.box(extents=(2.0, 2.0, 2.0))
    scene = Scene()
    scene.add(TriangleMesh(box.vertices, box.faces[:-1]), Pose.identity())  # one triangle missing: not closed
    assert not scene.spheres_collide([[0.0, 0.0, 0.0]], 0.1)
    assert scene.spheres_collide([[0.95, 0.0, 0.0]], 0.1)


def test_closed_mesh_query_swallowing_an_obstacle_is_blocked() -> None:
    scene = Scene()
    scene.add(Sphere(0.1), Pose((0.0, 0.0, 0.0)))
    assert scene.collides(closed_box_mesh(), Pose.identity())
    assert not scene.collides(closed_box_mesh(), Pose((5.0, 0.0, 0.0)))


def test_object_wholly_under_terrain_is_blocked() -> None:
    flat = Heightfield((0.0, 0.0), 10.0, np.full((11, 11), 10.0))
    scene = Scene()
    scene.add_terrain(flat)
    raw = fcl.CollisionObject(make_fcl_geometry(flat.to_mesh()), fcl.Transform())
    probe = fcl.CollisionObject(fcl.Sphere(1.0), fcl.Transform(np.array([50.0, 50.0, 5.0])))
    assert not pair_collides(raw, probe)  # FCL alone: under the surface is "free"
    assert scene.spheres_collide([[50.0, 50.0, 5.0]], 1.0)
    assert scene.collides(Sphere(1.0), Pose((50.0, 50.0, 5.0)))
    assert scene.collides(Box((1.0, 1.0, 1.0)), Pose((50.0, 50.0, 5.0)))
    assert not scene.sphere_sweep_free([[50.0, 50.0, 20.0], [50.0, 50.0, 5.0]], 1.0)
    assert not scene.spheres_collide([[50.0, 50.0, 12.0]], 1.0)
    assert scene.spheres_collide([[50.0, 50.0, 10.5]], 1.0)
    assert not scene.spheres_collide([[500.0, 500.0, 5.0]], 1.0)  # beyond the grid nothing is known


def test_moved_obstacle_is_seen_at_its_new_place() -> None:
    scene = unit_box_scene()
    version = scene.version
    assert scene.collides(Sphere(0.1), Pose((0.0, 0.0, 0.0)))
    scene.set_pose("box", Pose((5.0, 0.0, 0.0)))
    assert scene.version > version
    assert not scene.collides(Sphere(0.1), Pose((0.0, 0.0, 0.0)))
    assert scene.collides(Sphere(0.1), Pose((5.0, 0.0, 0.0)))
    assert not scene.spheres_collide([[0.0, 0.0, 0.0]], 0.1)
    assert scene.spheres_collide([[5.0, 0.0, 0.0]], 0.1)


def test_added_obstacle_is_seen_after_a_query() -> None:
    scene = Scene()
    assert not scene.collides(Sphere(0.1), Pose((3.0, 0.0, 0.0)))
    scene.add(Box((1.0, 1.0, 1.0)), Pose((3.0, 0.0, 0.0)))
    assert scene.collides(Sphere(0.1), Pose((3.0, 0.0, 0.0)))
    assert scene.spheres_collide([[3.0, 0.0, 0.0]], 0.1)


def test_removed_obstacle_is_gone() -> None:
    scene = unit_box_scene()
    scene.add(Sphere(0.5), Pose((3.0, 0.0, 0.0)), name="ball")
    scene.remove("box")
    assert not scene.collides(Sphere(0.1), Pose.identity())
    assert not scene.spheres_collide([[0.0, 0.0, 0.0]], 0.1)
    assert scene.collides(Sphere(0.1), Pose((3.0, 0.0, 0.0)))
    scene.clear()
    assert len(scene) == 0
    assert scene.bounds is None
    assert not scene.collides(Sphere(0.1), Pose((3.0, 0.0, 0.0)))


# --------------------------------------------------------------------------------------------------
# Margin: blocked iff distance < margin


@pytest.mark.parametrize(("gap", "blocked"), [(0.4, True), (0.6, False)])
def test_margin_for_spheres(gap: float, blocked: bool) -> None:
    scene = unit_box_scene(margin=0.5)
    centre = (0.5 + 0.2 + gap, 0.0, 0.0)  # sphere of radius 0.2 whose surface is ``gap`` from the box face
    assert scene.spheres_collide([centre], 0.2) is blocked
    assert bool(scene.spheres_collide_mask([centre], [0.2])[0]) is blocked
    assert scene.sphere_sweep_free([centre], 0.2) is not blocked
    assert scene.collides(Sphere(0.2), Pose(centre)) is blocked


@pytest.mark.parametrize(("gap", "blocked"), [(0.4, True), (0.6, False)])
def test_margin_for_boxes_capsules_and_cylinders(gap: float, blocked: bool) -> None:
    scene = unit_box_scene(margin=0.5)
    assert scene.collides(Box((0.2, 0.2, 0.2)), Pose((0.5 + 0.1 + gap, 0.0, 0.0))) is blocked
    assert scene.collides(Capsule(0.1, 1.0), Pose((0.5 + 0.1 + gap, 0.0, 0.0))) is blocked
    assert scene.collides(Cylinder(0.1, 1.0), Pose((0.0, 0.0, 0.5 + 0.5 + gap))) is blocked
    mesh = Scene(margin=0.5)
    mesh.add(closed_box_mesh(1.0), Pose.identity())
    assert mesh.collides(Box((0.2, 0.2, 0.2)), Pose((0.5 + 0.1 + gap, 0.0, 0.0))) is blocked
    terrain = Scene(margin=0.5)
    terrain.add_terrain(Heightfield((0.0, 0.0), 10.0, np.zeros((5, 5))))
    assert terrain.collides(Box((0.2, 0.2, 0.2)), Pose((20.0, 20.0, 0.1 + gap))) is blocked


@pytest.mark.parametrize(("gap", "blocked"), [(0.4, True), (0.6, False)])
def test_margin_over_terrain_and_wires(gap: float, blocked: bool) -> None:
    scene = Scene(margin=0.5)
    scene.add_terrain(Heightfield((0.0, 0.0), 10.0, np.zeros((5, 5))))
    scene.add_wire(Wire((0.0, 100.0, 30.0), (40.0, 100.0, 30.0), sag=0.0, diameter=0.02))
    assert scene.spheres_collide([[20.0, 20.0, 1.0 + gap]], 1.0) is blocked
    assert scene.spheres_collide([[20.0, 100.0, 30.0 + 0.01 + 1.0 + gap]], 1.0) is blocked


def test_mask_marks_each_sphere() -> None:
    scene = unit_box_scene()
    centres = [[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [0.6, 0.0, 0.0], [0.0, 0.0, 0.75]]
    assert scene.spheres_collide_mask(centres, [0.1, 0.1, 0.2, 0.2]).tolist() == [True, False, True, False]
    assert scene.spheres_collide_mask(np.zeros((0, 3)), 0.1).tolist() == []
    assert not scene.spheres_collide(np.zeros((0, 3)), 0.1)


def test_sweep_of_robot_spheres() -> None:
    scene = unit_box_scene()
    steps = np.linspace(-3.0, 3.0, 13)
    robot = np.stack([np.stack([steps, np.full(13, y), np.zeros(13)], axis=1) for y in (2.0, 2.5)], axis=1)
    assert robot.shape == (13, 2, 3)
    assert scene.sphere_sweep_free(robot, [0.1, 0.2])
    robot[:, 1, 1] = 0.0  # the second sphere now passes through the box
    assert not scene.sphere_sweep_free(robot, [0.1, 0.2])
    assert scene.sphere_sweep_free(robot[:3], 0.1)


# --------------------------------------------------------------------------------------------------
# Editing and validation


def test_names_versions_and_bounds() -> None:
    scene = Scene()
    assert scene.bounds is None
    first = scene.add(Sphere(1.0), Pose((1.0, 2.0, 3.0)))
    second = scene.add_wire(Wire((0, 0, 0), (10, 0, 0), sag=1.0, diameter=0.1), segments=4)
    assert first != second
    assert scene.names == (first, second)
    assert first in scene
    assert len(scene) == 2
    lo, hi = scene.bounds  # type: ignore[misc]
    capsule_radius = 0.05 + 1.0 / 4**2  # wire radius + sag / segments**2
    np.testing.assert_allclose(lo, [-capsule_radius, -capsule_radius, -1.0 - capsule_radius], atol=1e-9)
    np.testing.assert_allclose(hi, [10.0 + capsule_radius, 3.0, 4.0], atol=1e-9)
    version = scene.version
    scene.add(Box((1, 1, 1)), Pose.identity(), name=first, replace=True)
    assert scene.version > version
    assert scene.names == (second, first)


def test_terrain_is_replaced_and_removed() -> None:
    scene = Scene()
    name = scene.add_terrain(Heightfield((0.0, 0.0), 1.0, np.zeros((3, 3))))
    scene.add_terrain(Heightfield((0.0, 0.0), 1.0, np.full((3, 3), 5.0)))
    assert scene.names == (name,)
    assert scene.terrain is not None
    assert scene.terrain.heights[0, 0] == 5.0
    assert scene.spheres_collide([[1.0, 1.0, 5.0]], 0.1)
    scene.remove(name)
    assert scene.terrain is None
    assert not scene.spheres_collide([[1.0, 1.0, 1.0]], 0.1)


def test_editing_errors() -> None:
    scene = unit_box_scene()
    scene.add_wire(Wire((0, 0, 0), (10, 0, 0), sag=1.0, diameter=0.1), name="w")
    with pytest.raises(GeometryError, match="already"):
        scene.add(Sphere(1.0), Pose.identity(), name="box")
    with pytest.raises(GeometryError, match="no obstacle"):
        scene.remove("nothing")
    with pytest.raises(GeometryError, match="movable"):
        scene.set_pose("w", Pose.identity())
    with pytest.raises(GeometryError, match="pose must be a Pose"):
        scene.add(Sphere(1.0), (0, 0, 0))  # type: ignore[arg-type]
    with pytest.raises(GeometryError, match="margin"):
        Scene(margin=-1.0)
    with pytest.raises(GeometryError, match="pose must be a Pose"):
        scene.collides(Sphere(1.0), (0, 0, 0))  # type: ignore[arg-type]
    with pytest.raises(GeometryError, match="not a collision shape"):
        scene.collides("ball", Pose.identity())  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("centres", "radii", "message"),
    [
        ([[0.0, 0.0]], 0.1, "shape"),
        ([[0.0, 0.0, math.nan]], 0.1, "finite"),
        ([[0.0, 0.0, 0.0]], 0.0, "radius"),
        ([[0.0, 0.0, 0.0]], [-1.0], "radii"),
        ([[0.0, 0.0, 0.0]], [0.1, 0.2], "shape"),
    ],
)
def test_query_validation(centres: object, radii: object, message: str) -> None:
    scene = unit_box_scene()
    with pytest.raises(GeometryError, match=message):
        scene.spheres_collide(centres, radii)  # type: ignore[arg-type]


def test_sweep_validation() -> None:
    scene = unit_box_scene()
    with pytest.raises(GeometryError, match="sweep points"):
        scene.sphere_sweep_free(np.zeros((2, 2)), 0.1)
    with pytest.raises(GeometryError, match="broadcast"):
        scene.sphere_sweep_free(np.zeros((4, 3, 3)), [0.1, 0.2])


# --------------------------------------------------------------------------------------------------
# Cross-check of the prefilters against plain FCL on every obstacle


def brute_force_mask(
    scene: Scene, objects: list[fcl.CollisionObject], centres: np.ndarray, radius: float
) -> list[bool]:
    """Each sphere against every FCL object with no prefilter, plus the below-terrain test."""
    terrain = scene.terrain
    out = []
    for centre in centres:
        probe = fcl.CollisionObject(fcl.Sphere(radius + scene.margin), fcl.Transform(centre))
        hit = any(pair_collides(probe, obj) for obj in objects)
        if terrain is not None:
            hit |= bool(terrain.below(centre[None], interpolation="triangles")[0])
        out.append(hit)
    return out


def test_prefiltered_answers_equal_brute_force() -> None:
    rng = np.random.default_rng(7)
    heights = 5.0 * rng.random((9, 9))
    scene = Scene(margin=0.2)
    scene.add_terrain(Heightfield((0.0, 0.0), 5.0, heights), tile_cells=3)
    objects = [fcl.CollisionObject(make_fcl_geometry(Heightfield((0.0, 0.0), 5.0, heights).to_mesh()), fcl.Transform())]
    shapes = [Box((4.0, 1.0, 2.0)), Cylinder(1.0, 6.0), Capsule(0.5, 5.0), Sphere(1.5)]
    for k in range(12):
        shape = shapes[k % 4]
        pose = Pose(rng.uniform((0, 0, 3), (40, 40, 12)), rng.normal(size=4))
        scene.add(shape, pose)
        objects.append(fcl.CollisionObject(make_fcl_geometry(shape), pose.to_fcl()))
    wire = Wire((0.0, 20.0, 9.0), (40.0, 25.0, 11.0), sag=3.0, diameter=0.05)
    scene.add_wire(wire, segments=8)
    objects += [fcl.CollisionObject(make_fcl_geometry(c), p.to_fcl()) for c, p in wire.capsule_chain(8)]
    centres = rng.uniform((-5, -5, 0), (45, 45, 14), size=(400, 3))
    expected = brute_force_mask(scene, objects, centres, 0.7)
    assert 40 < sum(expected) < 360  # a mix of both answers
    assert scene.spheres_collide_mask(centres, 0.7).tolist() == expected
    assert scene.spheres_collide(centres, 0.7) == any(expected)
    for k in range(0, 400, 40):
        assert scene.spheres_collide(centres[k : k + 40], 0.7) == any(expected[k : k + 40])
        assert scene.sphere_sweep_free(centres[k : k + 40], 0.7) == (not any(expected[k : k + 40]))


def test_each_obstacle_alone_says_which_one_blocks() -> None:
    scene = Scene(margin=0.5)
    scene.add(Box((1.0, 1.0, 1.0)), Pose.identity(), name="box")
    scene.add(Sphere(1.0), Pose((10.0, 0.0, 0.0)), name="ball")
    scene.add_terrain(Heightfield((-10.0, -10.0), 10.0, np.zeros((3, 3))), name="ground")
    probe = np.array([[10.0, 0.0, 1.8]])  # 0.3 m above the ball's top: within the margin
    blocked = [name for name in scene.names if scene.alone(name).spheres_collide(probe, 0.5)]
    assert blocked == ["ball"]
    assert scene.spheres_collide(probe, 0.5)
    below = np.array([[5.0, 5.0, -3.0]])
    assert [n for n in scene.names if scene.alone(n).spheres_collide(below, 0.1)] == ["ground"]
    assert scene.alone("ground").terrain is not None
    assert scene.alone("box").terrain is None
    version = scene.version
    alone = scene.alone("box")
    alone.set_pose("box", Pose((50.0, 0.0, 0.0)))  # moving it there never moves it here
    assert scene.spheres_collide(np.zeros((1, 3)), 0.1)
    assert scene.version == version
    with pytest.raises(GeometryError, match="no obstacle named 'nothing'"):
        scene.alone("nothing")
