"""MoveIt planning scenes (``moveit_msgs/msg/PlanningScene`` message objects) -> the planner's collision parts.

ROS-free: any object with the message's fields works (rclpy messages, or plain stand-ins in tests).
:class:`MoveItWorld` holds the collision objects of the scenes applied so far, the way MoveIt's planning
scene monitor does:

- a full scene (``is_diff`` false) replaces the world by its objects; a diff changes it object by object;
- each ``CollisionObject`` has an ``operation``: ADD (a new object, replacing one of the same id), REMOVE (an
  empty id removes every object), APPEND (shapes added to an object, relative to its pose as it is, the
  message's pose unread, as in MoveIt; or a new object), MOVE (the object to a new ``pose``, its shapes keeping
  their places relative to it);
- shapes: ``shape_msgs/SolidPrimitive`` BOX (x, y, z), SPHERE (radius), CYLINDER (**height, radius**, along
  local z), and ``shape_msgs/Mesh`` (triangles); each shape's pose (and each subframe's) is relative to the
  object's ``pose``, in metres; an all-zero (unset) quaternion means no rotation, as in MoveIt.

Refused with a :class:`~drd_planner.exceptions.GeometryError` that says why, leaving the world unchanged: an
octomap (the planner's world is made of solid shapes: send occupied space as collision objects), CONE, PRISM
and other primitive types, planes (unbounded), objects attached to the robot, an object in another frame than
the planning frame (an empty frame means the planning frame; the planner does no transforms), REMOVE or MOVE
of an unknown object, wrong dimension counts, non-finite or non-positive sizes, a non-unit quaternion, and
more objects or mesh triangles than the map limits allow.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from drd_planner.exceptions import GeometryError
from drd_planner.geometry.map_limits import MapLimits
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Box, Cylinder, Shape, Sphere, TriangleMesh
from drd_planner.planning.map_state import Parts

__all__ = ["ADD", "APPEND", "MOVE", "REMOVE", "MoveItObject", "MoveItWorld", "object_key", "pose_of_msg"]

#: CollisionObject operations (moveit_msgs constants).
ADD, REMOVE, APPEND, MOVE = 0, 1, 2, 3
#: SolidPrimitive types (shape_msgs constants) and their dimension counts; the ones the planner takes.
BOX, SPHERE, CYLINDER, CONE, PRISM = 1, 2, 3, 4, 5
_PRIMITIVE_NAMES = {BOX: "BOX", SPHERE: "SPHERE", CYLINDER: "CYLINDER", CONE: "CONE", PRISM: "PRISM"}
#: Unit quaternions are accepted within this tolerance of norm 1.
QUATERNION_TOL = 1e-3
#: Key prefix of a MoveIt object's parts in the map store (MarkerArray obstacles are ``ns/id``).
KEY_PREFIX = "moveit:"


def object_key(object_id: str) -> str:
    """The map store's key of the MoveIt collision object ``object_id``."""
    return f"{KEY_PREFIX}{object_id}"


def _finite(values: Sequence[float], what: str) -> list[float]:
    out = [float(v) for v in values]
    if not all(math.isfinite(v) for v in out):
        raise GeometryError(f"{what} must be finite, got {out}")
    return out


def pose_of_msg(msg: Any, what: str) -> Pose:
    """A ``geometry_msgs/Pose`` as a :class:`Pose` (metres); the all-zero quaternion is the identity rotation."""
    p, q = msg.position, msg.orientation
    position = _finite((p.x, p.y, p.z), f"{what} position")
    quat = _finite((q.x, q.y, q.z, q.w), f"{what} orientation")
    if not any(quat):
        quat = [0.0, 0.0, 0.0, 1.0]  # MoveIt reads an unset quaternion as no rotation
    norm = math.sqrt(sum(v * v for v in quat))
    if abs(norm - 1.0) > QUATERNION_TOL:
        raise GeometryError(f"{what} orientation is not a unit quaternion (norm {norm:.6g})")
    return Pose(position, quat)


def _primitive(msg: Any, what: str) -> Shape:
    """A ``shape_msgs/SolidPrimitive`` as a shape (sizes in metres)."""
    kind = int(msg.type)
    dims = _finite(list(msg.dimensions), f"{what} dimensions")
    expected = {BOX: 3, SPHERE: 1, CYLINDER: 2}
    if kind not in expected:
        name = _PRIMITIVE_NAMES.get(kind, f"type {kind}")
        raise GeometryError(f"{what} is a {name}; only BOX, SPHERE, CYLINDER primitives and meshes are supported")
    if len(dims) != expected[kind]:
        layout = {BOX: "(x, y, z)", SPHERE: "(radius)", CYLINDER: "(height, radius)"}[kind]
        raise GeometryError(f"{what}: {_PRIMITIVE_NAMES[kind]} needs dimensions {layout}, got {dims}")
    if any(d <= 0.0 for d in dims):
        raise GeometryError(f"{what}: dimensions must be > 0, got {dims}")
    if kind == BOX:
        return Box(dims)
    if kind == SPHERE:
        return Sphere(dims[0])
    height, radius = dims  # MoveIt's order: height first
    return Cylinder(radius, height)


def _mesh(msg: Any, what: str, limits: MapLimits) -> TriangleMesh:
    """A ``shape_msgs/Mesh`` as a triangle mesh."""
    count = len(msg.triangles)
    if count > limits.max_mesh_triangles:
        raise GeometryError(
            f"{what} has {count} triangles, over the limit max_mesh_triangles = {limits.max_mesh_triangles}"
        )
    vertices = [(v.x, v.y, v.z) for v in msg.vertices]
    faces = [[int(i) for i in t.vertex_indices] for t in msg.triangles]
    try:
        return TriangleMesh(vertices, faces)
    except GeometryError as exc:
        raise GeometryError(f"{what}: {exc}") from exc


@dataclass(frozen=True)
class MoveItObject:
    """One collision object of the world.

    Attributes:
        pose: the object's pose in the planning frame.
        shapes: (shape, pose relative to the object's pose) of each primitive and mesh.
        subframes: name -> pose relative to the object's pose (kept; they do not collide).
    """

    pose: Pose
    shapes: tuple[tuple[Shape, Pose], ...]
    subframes: Mapping[str, Pose]

    def parts(self) -> Parts:
        """The object's collision parts with their poses in the planning frame."""
        return tuple((shape, self.pose.compose(relative)) for shape, relative in self.shapes)


def _paired(items: Sequence[Any], poses: Sequence[Any], what: str, where: str) -> None:
    if len(items) != len(poses):
        raise GeometryError(f"{where} has {len(items)} {what} and {len(poses)} {what[:-1]}_poses")


def _shapes(msg: Any, where: str, limits: MapLimits) -> tuple[tuple[Shape, Pose], ...]:
    """The primitives and meshes of a CollisionObject, with poses relative to the object's pose."""
    if len(msg.planes) or len(msg.plane_poses):
        raise GeometryError(f"{where} has planes; an unbounded plane cannot be a collision part here")
    _paired(msg.primitives, msg.primitive_poses, "primitives", where)
    _paired(msg.meshes, msg.mesh_poses, "meshes", where)
    shapes: list[tuple[Shape, Pose]] = []
    for k, (primitive, pose) in enumerate(zip(msg.primitives, msg.primitive_poses, strict=True)):
        shapes.append((_primitive(primitive, f"{where} primitive {k}"), pose_of_msg(pose, f"{where} primitive {k}")))
    for k, (mesh, pose) in enumerate(zip(msg.meshes, msg.mesh_poses, strict=True)):
        shapes.append((_mesh(mesh, f"{where} mesh {k}", limits), pose_of_msg(pose, f"{where} mesh {k}")))
    return tuple(shapes)


def _subframes(msg: Any, where: str) -> dict[str, Pose]:
    _paired(msg.subframe_names, msg.subframe_poses, "subframe_names", where)
    return {
        str(name): pose_of_msg(pose, f"{where} subframe {name!r}")
        for name, pose in zip(msg.subframe_names, msg.subframe_poses, strict=True)
    }


def _operation(msg: Any) -> int:
    op = msg.operation
    return op[0] if isinstance(op, bytes | bytearray) else int(op)


class MoveItWorld:
    """The collision objects of the planning scenes applied so far (see the module docstring).

    Args:
        frame_id: the planning frame (objects in another frame are refused; "" means this frame).
        limits: the map limits (``max_markers`` caps the objects, ``max_mesh_triangles`` each mesh).
    """

    def __init__(self, *, frame_id: str, limits: MapLimits = MapLimits.DEFAULT) -> None:
        self.frame_id = frame_id
        self.limits = limits
        self._objects: dict[str, MoveItObject] = {}

    @property
    def objects(self) -> dict[str, MoveItObject]:
        """Object id -> object (a copy)."""
        return dict(self._objects)

    def parts(self) -> dict[str, Parts]:
        """The map store's key (:func:`object_key`) -> collision parts of every object."""
        return {object_key(name): obj.parts() for name, obj in self._objects.items()}

    def apply(self, scene: Any) -> dict[str, MoveItObject]:
        """Apply a ``PlanningScene`` (full or diff); the objects after it.

        Raises:
            GeometryError: anything the module docstring lists; the world is unchanged.
        """
        octomap = scene.world.octomap.octomap
        if len(octomap.data):
            raise GeometryError(
                f"planning scene has an octomap ({len(octomap.data)} bytes, resolution {octomap.resolution} m); "
                "octomaps are not supported: the planner's world is made of solid shapes, send the occupied "
                "space as collision objects"
            )
        attached = scene.robot_state.attached_collision_objects
        if len(attached):
            names = ", ".join(repr(str(a.object.id)) for a in attached)
            raise GeometryError(
                f"planning scene attaches objects to the robot ({names}); the planner's arm carries no objects"
            )
        objects = dict(self._objects) if scene.is_diff else {}
        for msg in scene.world.collision_objects:
            self._apply_object(objects, msg)
        if len(objects) > self.limits.max_markers:
            raise GeometryError(
                f"planning scene has {len(objects)} collision objects, over the limit max_markers = "
                f"{self.limits.max_markers}"
            )
        self._objects = objects
        return dict(objects)

    def apply_object(self, msg: Any) -> dict[str, MoveItObject]:
        """Apply one ``CollisionObject`` (as in a diff); the objects after it (GeometryError: unchanged)."""
        objects = dict(self._objects)
        self._apply_object(objects, msg)
        self._objects = objects
        return dict(objects)

    def _apply_object(self, objects: dict[str, MoveItObject], msg: Any) -> None:
        name = str(msg.id)
        where = f"collision object {name[:80]!r}"
        op = _operation(msg)
        if op == REMOVE:
            if name == "":
                objects.clear()
            elif objects.pop(name, None) is None:
                raise GeometryError(f"{where}: REMOVE of an object the scene does not have")
            return
        if op not in (ADD, APPEND, MOVE):
            raise GeometryError(f"{where} has operation {op}; MoveIt's are ADD 0, REMOVE 1, APPEND 2, MOVE 3")
        frame = str(msg.header.frame_id)
        if frame not in ("", self.frame_id):
            raise GeometryError(
                f"{where} is in frame {frame[:80]!r}; the planner works in {self.frame_id!r} and does no transforms"
            )
        if name == "":
            raise GeometryError("a collision object to add or move needs an id")
        pose = pose_of_msg(msg.pose, f"{where} pose")
        if op == MOVE:
            old = objects.get(name)
            if old is None:
                raise GeometryError(f"{where}: MOVE of an object the scene does not have")
            if len(msg.primitives) or len(msg.meshes) or len(msg.planes):
                raise GeometryError(f"{where}: MOVE takes a new pose only, not shapes")
            objects[name] = MoveItObject(pose, old.shapes, old.subframes)
            return
        shapes = _shapes(msg, where, self.limits)
        subframes = _subframes(msg, where)
        old = objects.get(name) if op == APPEND else None
        if old is None:
            if not shapes:
                raise GeometryError(f"{where} has no primitives or meshes")
            objects[name] = MoveItObject(pose, shapes, subframes)
            return
        # APPEND to an existing object: as MoveIt's World::addToObject, the new shapes (and subframes) are
        # relative to the object's own pose; the message's pose is not read
        objects[name] = MoveItObject(old.pose, old.shapes + shapes, {**old.subframes, **subframes})
