"""Collision shapes as frozen, validated values, and their FCL geometries.

Every shape is centred on its local origin. Cylinders and capsules lie along their local +z axis (as in FCL
and in ROS markers): ``length`` is the length of the straight part, from z = -length/2 to z = +length/2; a
capsule adds hemispherical caps of ``radius`` beyond that. All sizes are in metres.

:class:`Pose` lives in :mod:`drd_planner.geometry.pose` and is re-exported here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, TypeAlias

import fcl
import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.exceptions import GeometryError
from drd_planner.geometry.pose import Pose, frozen_array

__all__ = [
    "Box",
    "Capsule",
    "Cylinder",
    "Pose",
    "Shape",
    "Sphere",
    "TriangleMesh",
    "bvh_model",
    "make_fcl_geometry",
    "shape_point",
]


def _positive(value: float, what: str) -> float:
    """``value`` as a float, or GeometryError when it is not finite and > 0."""
    try:
        number = float(value)
    except (TypeError, ValueError) as exc:
        raise GeometryError(f"{what} must be a number, got {value!r}") from exc
    if not math.isfinite(number) or number <= 0.0:
        raise GeometryError(f"{what} must be finite and > 0, got {value!r}")
    return number


@dataclass(frozen=True, eq=False, init=False, repr=False)
class Box:
    """A solid box centred on its origin.

    Attributes:
        size: (3,) full edge lengths along local x, y, z in metres (each finite and > 0).
    """

    size: FloatArray

    def __init__(self, size: npt.ArrayLike) -> None:
        array = frozen_array(size, shape=(3,), what="box size")
        if np.any(array <= 0.0):
            raise GeometryError(f"box size must be > 0 along every axis, got {array.tolist()}")
        object.__setattr__(self, "size", array)

    def __eq__(self, other: Any) -> bool:
        return isinstance(other, Box) and bool(np.array_equal(self.size, other.size))

    def __hash__(self) -> int:
        return hash(("box", self.size.tobytes()))

    def __repr__(self) -> str:
        return f"Box(size={self.size.tolist()})"


@dataclass(frozen=True)
class Sphere:
    """A solid sphere centred on its origin.

    Attributes:
        radius: metres, finite and > 0.
    """

    radius: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", _positive(self.radius, "sphere radius"))


@dataclass(frozen=True)
class Cylinder:
    """A solid cylinder along local +z, centred on its origin.

    Attributes:
        radius: metres, finite and > 0.
        length: full height along local z in metres, finite and > 0.
    """

    radius: float
    length: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", _positive(self.radius, "cylinder radius"))
        object.__setattr__(self, "length", _positive(self.length, "cylinder length"))


@dataclass(frozen=True)
class Capsule:
    """A solid capsule along local +z, centred on its origin: a segment swept by a sphere.

    Attributes:
        radius: metres, finite and > 0.
        length: length of the segment (the straight part) along local z in metres, finite and > 0; the capsule
            spans z in [-length/2 - radius, length/2 + radius].
    """

    radius: float
    length: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", _positive(self.radius, "capsule radius"))
        object.__setattr__(self, "length", _positive(self.length, "capsule length"))


@dataclass(frozen=True, eq=False, init=False, repr=False)
class TriangleMesh:
    """A triangle mesh in its local frame. FCL treats it as a *surface*, not a solid.

    Attributes:
        vertices: (V, 3) float64 vertex coordinates in metres (finite).
        faces: (F, 3) int64 vertex indices (0-based) of each triangle, F >= 1.
    """

    vertices: FloatArray
    faces: IntArray

    def __init__(self, vertices: npt.ArrayLike, faces: npt.ArrayLike) -> None:
        try:
            verts = np.array(vertices, dtype=np.float64)
            tris = np.array(faces)
        except (TypeError, ValueError) as exc:
            raise GeometryError(f"mesh vertices and faces must be numeric arrays: {exc}") from exc
        if verts.ndim != 2 or verts.shape[1] != 3 or verts.shape[0] < 3:
            raise GeometryError(f"mesh vertices must have shape (V >= 3, 3), got {verts.shape}")
        if not np.all(np.isfinite(verts)):
            raise GeometryError("mesh vertices must be finite")
        if tris.ndim != 2 or tris.shape[1] != 3 or tris.shape[0] < 1:
            raise GeometryError(f"mesh faces must have shape (F >= 1, 3), got {tris.shape}")
        if not np.issubdtype(tris.dtype, np.integer):
            raise GeometryError(f"mesh faces must be integer vertex indices, got dtype {tris.dtype}")
        tris = tris.astype(np.int64)
        if tris.min() < 0 or tris.max() >= verts.shape[0]:
            raise GeometryError(f"mesh face indices must lie in [0, {verts.shape[0]})")
        verts.flags.writeable = False
        tris.flags.writeable = False
        object.__setattr__(self, "vertices", verts)
        object.__setattr__(self, "faces", tris)

    def __eq__(self, other: Any) -> bool:
        return (
            isinstance(other, TriangleMesh)
            and bool(np.array_equal(self.vertices, other.vertices))
            and bool(np.array_equal(self.faces, other.faces))
        )

    def __hash__(self) -> int:
        return hash(("mesh", self.vertices.tobytes(), self.faces.tobytes()))

    def __repr__(self) -> str:
        return f"TriangleMesh({self.vertices.shape[0]} vertices, {self.faces.shape[0]} faces)"


Shape: TypeAlias = Box | Sphere | Cylinder | Capsule | TriangleMesh


def make_fcl_geometry(shape: Shape) -> fcl.CollisionGeometry:
    """A new FCL collision geometry for ``shape`` (a ``BVHModel`` for meshes).

    Raises:
        GeometryError: ``shape`` is not one of the shape types, or FCL refuses the mesh.
    """
    if isinstance(shape, Box):
        return fcl.Box(*shape.size.tolist())
    if isinstance(shape, Sphere):
        return fcl.Sphere(shape.radius)
    if isinstance(shape, Cylinder):
        return fcl.Cylinder(shape.radius, shape.length)
    if isinstance(shape, Capsule):
        return fcl.Capsule(shape.radius, shape.length)
    if isinstance(shape, TriangleMesh):
        return bvh_model(shape.vertices, shape.faces)
    raise GeometryError(f"not a collision shape: {type(shape).__name__}")


def bvh_model(vertices: FloatArray, faces: IntArray) -> fcl.BVHModel:
    """An FCL ``BVHModel`` of (V, 3) ``vertices`` (metres) and (F, 3) ``faces`` (vertex indices).

    Raises:
        GeometryError: FCL refuses the data.
    """
    model = fcl.BVHModel()
    try:
        model.beginModel(int(faces.shape[0]), int(vertices.shape[0]))
        model.addSubModel(vertices, faces)
        model.endModel()
    except (ValueError, MemoryError) as exc:
        raise GeometryError(f"FCL cannot build a mesh of {faces.shape[0]} triangles: {exc}") from exc
    return model


def shape_point(shape: Shape, pose: Pose) -> FloatArray:
    """(3,) world coordinates of one point of ``shape`` (its centre; a mesh's first face's first vertex), in metres.

    Used for inside tests: a shape that touches no surface of a closed solid is wholly inside it or wholly
    outside, and testing any one of its points tells which.
    """
    if isinstance(shape, TriangleMesh):
        first: FloatArray = pose.transform_points(shape.vertices[shape.faces[0, :1]])[0]
        return first
    return np.array(pose.position)
