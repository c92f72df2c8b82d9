"""Shapes: validation, FCL geometries, and the trap that cylinders and capsules lie along local +z."""

from __future__ import annotations

import math

import fcl
import numpy as np
import pytest
import trimesh

from drd_planner.exceptions import GeometryError
from drd_planner.geometry.aabb import shape_aabb
from drd_planner.geometry.fcl_queries import pair_collides
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import (
    Box,
    Capsule,
    Cylinder,
    Sphere,
    TriangleMesh,
    make_fcl_geometry,
    shape_point,
)

EPS = 1e-3


def probe_hits(shape: Box | Sphere | Cylinder | Capsule | TriangleMesh, point: tuple[float, float, float]) -> bool:
    """Whether a 1 mm sphere at ``point`` touches ``shape`` placed at the origin (plain FCL)."""
    body = fcl.CollisionObject(make_fcl_geometry(shape), Pose.identity().to_fcl())
    probe = fcl.CollisionObject(fcl.Sphere(1e-3), fcl.Transform(np.array(point, dtype=float)))
    return pair_collides(body, probe)


@pytest.mark.parametrize("shape", [Cylinder(0.05, 2.0), Capsule(0.05, 2.0)])
def test_cylinders_and_capsules_lie_along_local_z(shape: Cylinder | Capsule) -> None:
    half = shape.length / 2.0
    assert probe_hits(shape, (0.0, 0.0, half - EPS))
    assert probe_hits(shape, (0.0, 0.0, -half + EPS))
    assert not probe_hits(shape, (half - EPS, 0.0, 0.0))
    assert not probe_hits(shape, (0.0, half - EPS, 0.0))


def test_capsule_caps_extend_beyond_length_cylinder_does_not() -> None:
    z = 1.0 + 0.03  # beyond the straight part, inside the capsule's cap
    assert probe_hits(Capsule(0.05, 2.0), (0.0, 0.0, z))
    assert not probe_hits(Cylinder(0.05, 2.0), (0.0, 0.0, z))


def test_box_size_is_full_edge_length() -> None:
    box = Box((2.0, 4.0, 6.0))
    assert probe_hits(box, (1.0 - EPS, 2.0 - EPS, 3.0 - EPS))
    assert not probe_hits(box, (1.0 + 0.01, 0.0, 0.0))


def test_shapes_are_values() -> None:
    assert Box((1, 2, 3)) == Box([1.0, 2.0, 3.0])
    assert len({Box((1, 2, 3)), Box((1, 2, 3)), Sphere(1.0), Sphere(1)}) == 2
    mesh = TriangleMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    assert mesh == TriangleMesh(np.array(mesh.vertices), np.array(mesh.faces))
    assert hash(mesh) == hash(TriangleMesh(np.array(mesh.vertices), np.array(mesh.faces)))


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: Box((1, 0, 1)), "box size"),
        (lambda: Box((1, 1)), "shape"),
        (lambda: Sphere(0.0), "sphere radius"),
        (lambda: Sphere(math.inf), "sphere radius"),
        (lambda: Cylinder(1.0, -1.0), "cylinder length"),
        (lambda: Capsule(math.nan, 1.0), "capsule radius"),
        (lambda: Sphere("a"), "number"),  # type: ignore[arg-type]
        (lambda: TriangleMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 3]]), "indices"),
        (lambda: TriangleMesh([[0, 0, 0], [1, 0, 0]], [[0, 1, 1]]), "vertices"),
        (lambda: TriangleMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0.0, 1.0, 2.0]]), "integer"),
        (lambda: TriangleMesh([[0, 0, 0], [1, 0, 0], [0, 1, math.nan]], [[0, 1, 2]]), "finite"),
    ],
)
def test_invalid_shapes_raise(build: object, message: str) -> None:
    with pytest.raises(GeometryError, match=message):
        build()  # type: ignore[operator]


def test_make_fcl_geometry_types() -> None:
    assert isinstance(make_fcl_geometry(Box((1, 1, 1))), fcl.Box)
    assert isinstance(make_fcl_geometry(Sphere(1)), fcl.Sphere)
    assert isinstance(make_fcl_geometry(Cylinder(1, 1)), fcl.Cylinder)
    assert isinstance(make_fcl_geometry(Capsule(1, 1)), fcl.Capsule)
    box = trimesh.creation.box()
    assert isinstance(make_fcl_geometry(TriangleMesh(box.vertices, box.faces)), fcl.BVHModel)
    with pytest.raises(GeometryError, match="not a collision shape"):
        make_fcl_geometry("box")  # type: ignore[arg-type]


def test_shape_point_is_inside_the_shape() -> None:
    pose = Pose((1.0, 2.0, 3.0), (0.2, 0.1, 0.3, 0.9))
    np.testing.assert_allclose(shape_point(Box((1, 1, 1)), pose), [1, 2, 3])
    mesh = TriangleMesh([[9, 9, 9], [0, 0, 0], [1, 0, 0], [0, 1, 0]], [[1, 2, 3]])
    np.testing.assert_allclose(shape_point(mesh, Pose((5.0, 0.0, 0.0))), [5, 0, 0])


def sampled_aabb(mesh: trimesh.Trimesh, pose: Pose) -> tuple[np.ndarray, np.ndarray]:
    world = pose.transform_points(mesh.vertices)
    return world.min(axis=0), world.max(axis=0)


POSES = [Pose((0.3, -0.2, 1.0), q) for q in [(0, 0, 0, 1), (0.3, 0.5, -0.2, 0.8), (1, 0, 0, 0), (0, 0.7, 0, 0.7)]]


@pytest.mark.parametrize("pose", POSES)
def test_shape_aabb_matches_dense_tessellations(pose: Pose) -> None:
    cases = [
        (Box((0.4, 1.0, 2.0)), trimesh.creation.box(extents=(0.4, 1.0, 2.0)), 1e-9),
        (Sphere(0.5), trimesh.creation.icosphere(subdivisions=4, radius=0.5), 5e-3),
        (Cylinder(0.3, 1.5), trimesh.creation.cylinder(radius=0.3, height=1.5, sections=256), 5e-3),
        (Capsule(0.3, 1.5), trimesh.creation.capsule(radius=0.3, height=1.5, count=(256, 256)), 5e-3),
    ]
    for shape, mesh, tol in cases:
        lo, hi = shape_aabb(shape, pose)
        ref_lo, ref_hi = sampled_aabb(mesh, pose)
        assert np.all(lo <= ref_lo + 1e-9), shape
        assert np.all(hi >= ref_hi - 1e-9), shape
        np.testing.assert_allclose(lo, ref_lo, atol=tol)
        np.testing.assert_allclose(hi, ref_hi, atol=tol)
