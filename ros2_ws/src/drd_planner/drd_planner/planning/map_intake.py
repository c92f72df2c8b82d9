"""Map messages' plain data (:mod:`drd_msgs_py.shapes`) <-> the planner's geometry.

drd_msgs_py reads a MarkerArray into marker shapes with poses and a terrain cloud into a height grid; this
module turns those into collision parts (shapes with world poses, metres) and a
:class:`~drd_planner.geometry.terrain.Heightfield`, and back (for writing worlds as messages):

- CUBE, SPHERE, CYLINDER, TRIANGLE_LIST: one part each, at the marker's pose;
- LINE_STRIP: the polyline's points go to the world frame, then one capsule of the strip's diameter per
  segment between distinct points (a wire with sag arrives as its polyline).

A shape the geometry refuses raises :class:`~drd_planner.exceptions.GeometryError` naming the marker.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from typing import Any

import numpy as np

from drd_msgs_py.obstacles import SAME_POINT_M, Obstacle, obstacle_update
from drd_msgs_py.shapes import (
    BoxData,
    CylinderData,
    HeightGrid,
    LineStripData,
    MeshData,
    PoseData,
    ShapeData,
    SphereData,
)
from drd_msgs_py.terrain import heightfield_from_cloud
from drd_planner.arrays import FloatArray
from drd_planner.exceptions import GeometryError
from drd_planner.geometry.map_limits import MapLimits
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Box, Cylinder, Shape, Sphere, TriangleMesh
from drd_planner.geometry.terrain import Heightfield, Unknown
from drd_planner.geometry.wires import capsule_between
from drd_planner.planning.map_state import Parts

__all__ = [
    "heightfield_of",
    "obstacle_data",
    "obstacle_map",
    "obstacle_parts",
    "obstacles_data",
    "pose_data",
    "pose_of",
    "terrain_from_cloud",
]


def pose_of(pose: PoseData) -> Pose:
    """The :class:`Pose` of a message pose (its quaternion normalised)."""
    return Pose(pose.position, pose.quaternion_xyzw)


def pose_data(pose: Pose) -> PoseData:
    """The message pose of a :class:`Pose`."""
    p, q = (float(v) for v in pose.position), (float(v) for v in pose.quaternion_xyzw)
    x, y, z = p
    qx, qy, qz, qw = q
    return PoseData((x, y, z), (qx, qy, qz, qw))


def _wire(strip: LineStripData, pose: Pose) -> Parts:
    """One capsule per segment of a LINE_STRIP between distinct world points."""
    world = pose.transform_points(strip.points)
    return tuple(
        capsule_between(a, b, strip.diameter / 2.0)
        for a, b in itertools.pairwise(world)
        if np.linalg.norm(b - a) > SAME_POINT_M  # a repeated point: nothing between them
    )


def _solid(shape: ShapeData) -> Shape:
    """The collision shape of a CUBE, SPHERE, CYLINDER or TRIANGLE_LIST marker."""
    if isinstance(shape, BoxData):
        return Box(shape.size)
    if isinstance(shape, SphereData):
        return Sphere(shape.radius)
    if isinstance(shape, CylinderData):
        return Cylinder(shape.radius, shape.length)
    if isinstance(shape, MeshData):
        return TriangleMesh(shape.vertices, shape.faces)
    raise GeometryError(f"not a solid marker shape: {type(shape).__name__}")


def obstacle_parts(obstacle: Obstacle) -> Parts:
    """The collision parts (shape, world pose) of one marker's obstacle.

    Raises:
        GeometryError: a shape the geometry refuses (the text names the marker).
    """
    pose = pose_of(obstacle.pose)
    try:
        if isinstance(obstacle.shape, LineStripData):
            parts = _wire(obstacle.shape, pose)
            if not parts:
                raise GeometryError("every LINE_STRIP point is the same (zero-length wire)")
            return parts
        return ((_solid(obstacle.shape), pose),)
    except GeometryError as exc:
        raise GeometryError(f"{obstacle.label or obstacle.key}: {exc}") from exc


def heightfield_of(grid: HeightGrid, unknown: Unknown = "blocked") -> Heightfield:
    """The :class:`Heightfield` of a terrain cloud's grid (``unknown``: how NaN heights count in checks).

    Raises:
        GeometryError: a grid the heightfield refuses (text prefixed ``terrain cloud:``).
    """
    try:
        return Heightfield(grid.origin, grid.cell_size, grid.heights, unknown=unknown)
    except GeometryError as exc:
        raise GeometryError(f"terrain cloud: {exc}") from exc


def terrain_from_cloud(msg: Any, *, frame_id: str, limits: MapLimits = MapLimits.DEFAULT) -> Heightfield:
    """The heightfield of a ``PointCloud2`` terrain (MessageError: a bad cloud; GeometryError: a bad grid)."""
    return heightfield_of(heightfield_from_cloud(msg, frame_id=frame_id, limits=limits), limits.unknown)


def obstacle_map(msg: Any, *, frame_id: str, limits: MapLimits = MapLimits.DEFAULT) -> dict[str, Parts]:
    """Key -> collision parts of a whole obstacle map (a MarkerArray applied to an empty map)."""
    obstacles = obstacle_update(msg, frame_id=frame_id, limits=limits).apply({})
    return {key: obstacle_parts(o) for key, o in obstacles.items()}


def obstacle_data(shape: Shape | FloatArray, pose: Pose | float) -> tuple[ShapeData, PoseData]:
    """The marker data of a collision shape at ``pose``, or of a wire (``shape`` points, ``pose`` diameter).

    A wire is given as (K >= 2, 3) world points and its diameter in metres: a LINE_STRIP with the identity pose.

    Raises:
        GeometryError: a shape with no marker form (a bare Capsule: send it as a two-point LINE_STRIP).
    """
    if isinstance(shape, np.ndarray):
        points = np.asarray(shape, dtype=np.float64).reshape(-1, 3)
        return LineStripData(points, float(pose)), PoseData()  # type: ignore[arg-type]
    if not isinstance(pose, Pose):
        raise GeometryError(f"a {type(shape).__name__} needs a Pose, got {type(pose).__name__}")
    data: ShapeData
    if isinstance(shape, Box):
        x, y, z = (float(v) for v in shape.size)
        data = BoxData((x, y, z))
    elif isinstance(shape, Sphere):
        data = SphereData(float(shape.radius))
    elif isinstance(shape, Cylinder):
        data = CylinderData(float(shape.radius), float(shape.length))
    elif isinstance(shape, TriangleMesh):
        data = MeshData(shape.vertices, shape.faces)
    else:
        raise GeometryError(f"{type(shape).__name__} has no marker form; send a LINE_STRIP")
    return data, pose_data(pose)


def obstacles_data(
    obstacles: Sequence[tuple[str, Shape | FloatArray, Pose | float]],
) -> list[tuple[str, ShapeData, PoseData]]:
    """``(key, shape, pose)`` items (see :func:`obstacle_data`) as marker data, keys kept.

    Raises:
        GeometryError: a shape with no marker form; the text names its key.
    """
    out = []
    for key, shape, pose in obstacles:
        try:
            data, where = obstacle_data(shape, pose)
        except GeometryError as exc:
            raise GeometryError(f"{key}: {exc}") from exc
        out.append((key, data, where))
    return out
