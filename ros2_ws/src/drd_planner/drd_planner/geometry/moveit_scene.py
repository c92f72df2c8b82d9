"""MoveIt PlanningScene YAML (as written by MotionBenchMaker) -> box, cylinder and sphere primitives.

Reads ``world.collision_objects`` of a ``moveit_msgs/PlanningScene`` (or ``collision_objects`` of a
``PlanningSceneWorld``) with the bounded safe loader of :mod:`~drd_planner.geometry.moveit_yaml`. Each object's
primitives become :class:`ScenePrimitive` values whose pose is the object pose (``pose``, identity when absent, as in
older MoveIt messages) composed with the primitive pose; an all-zero (unset) quaternion means no rotation,
as in MoveIt. Poses may be written as lists
(``position: [x, y, z]``, ``orientation: [x, y, z, w]``) or as mappings with keys x, y, z(, w).
Primitive types may be names (``box``) or ``shape_msgs/SolidPrimitive`` constants (1 box, 2 sphere,
3 cylinder); dimensions follow SolidPrimitive: box (x, y, z), sphere (radius), cylinder (height,
radius), in metres.

Anything that cannot be represented exactly is refused with a :class:`GeometryError` naming the
object: meshes, planes, cones and other types, missing or extra dimensions, non-finite numbers,
objects in another frame, REMOVE/MOVE operations, attached objects, octomaps and a robot whose
virtual joint is not at the origin.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from drd_planner.exceptions import GeometryError
from drd_planner.geometry.moveit_yaml import load_yaml, quoted, read_yaml_text
from drd_planner.geometry.shapes import Box, Cylinder, Pose, Sphere

#: SolidPrimitive type constants (shape_msgs) and their names.
PRIMITIVE_TYPES: Mapping[int, str] = {1: "box", 2: "sphere", 3: "cylinder", 4: "cone", 5: "prism"}
#: Frames that mean "the planning frame" (the robot's root at the world origin).
DEFAULT_WORLD_FRAMES: tuple[str, ...] = ("", "world")

__all__ = [
    "DEFAULT_WORLD_FRAMES",
    "ScenePrimitive",
    "parse_planning_scene",
    "read_planning_scene",
]


@dataclass(frozen=True)
class ScenePrimitive:
    """One solid primitive of a planning scene.

    Attributes:
        name: the object id, with ``/<k>`` appended for the k-th primitive when an object has several.
        shape: a :class:`Box`, :class:`Cylinder` (along local +z) or :class:`Sphere`, sizes in metres.
        pose: the primitive's pose in the planning frame (object pose composed with primitive pose).
    """

    name: str
    shape: Box | Cylinder | Sphere
    pose: Pose


def _numbers(value: Any, count: int, what: str, where: str) -> list[float]:
    """``count`` finite floats from a list, or GeometryError naming ``where``."""
    if not isinstance(value, Sequence) or isinstance(value, str) or len(value) != count:
        raise GeometryError(f"{where}: {what} must be a list of {count} numbers, got {quoted(value)}")
    out: list[float] = []
    for item in value:
        if isinstance(item, bool) or not isinstance(item, int | float):
            raise GeometryError(f"{where}: {what} must contain numbers, got {quoted(item)}")
        if not math.isfinite(float(item)):
            raise GeometryError(f"{where}: {what} must be finite, got {quoted(value)}")
        out.append(float(item))
    return out


def _vector(value: Any, keys: str, what: str, where: str) -> list[float]:
    """A list ``[a, b, ...]`` or mapping ``{x: a, y: b, ...}`` as floats."""
    if isinstance(value, Mapping):
        missing = [k for k in keys if k not in value]
        if missing:
            raise GeometryError(f"{where}: {what} lacks {', '.join(missing)}")
        value = [value[k] for k in keys]
    return _numbers(value, len(keys), what, where)


def _pose(value: Any, where: str) -> Pose:
    """A ``geometry_msgs/Pose`` mapping as a :class:`Pose`."""
    if not isinstance(value, Mapping) or "position" not in value or "orientation" not in value:
        raise GeometryError(f"{where}: a pose needs 'position' and 'orientation', got {quoted(value)}")
    position = _vector(value["position"], "xyz", "position", where)
    orientation = _vector(value["orientation"], "xyzw", "orientation (x, y, z, w)", where)
    if not any(orientation):
        orientation = [0.0, 0.0, 0.0, 1.0]  # MoveIt reads an all-zero (unset) quaternion as no rotation
    try:
        return Pose(position, orientation)
    except GeometryError as exc:
        raise GeometryError(f"{where}: {exc}") from exc


def _shape(primitive: Any, where: str) -> Box | Cylinder | Sphere:
    """A SolidPrimitive mapping as a shape."""
    if not isinstance(primitive, Mapping):
        raise GeometryError(f"{where}: a primitive must be a mapping, got {quoted(primitive)}")
    kind = primitive.get("type")
    if isinstance(kind, int) and not isinstance(kind, bool):
        kind = PRIMITIVE_TYPES.get(kind, f"type {kind}")
    if kind not in ("box", "sphere", "cylinder"):
        raise GeometryError(f"{where}: primitive type {quoted(kind)} is not supported (box, sphere, cylinder)")
    if "dimensions" not in primitive:
        raise GeometryError(f"{where}: {kind} has no dimensions")
    dims = primitive["dimensions"]
    try:
        if kind == "box":
            return Box(_numbers(dims, 3, "box dimensions (x, y, z)", where))
        if kind == "sphere":
            return Sphere(_numbers(dims, 1, "sphere dimensions (radius)", where)[0])
        height, radius = _numbers(dims, 2, "cylinder dimensions (height, radius)", where)
        return Cylinder(radius=radius, length=height)
    except GeometryError as exc:
        if str(exc).startswith(where):
            raise
        raise GeometryError(f"{where}: {exc}") from exc


def _nonempty(obj: Mapping[str, Any], key: str) -> bool:
    """Whether ``obj[key]`` is present and not an empty list/mapping/None."""
    value = obj.get(key)
    return value is not None and value not in ([], {})


def _object_primitives(obj: Any, index: int, frames: Sequence[str]) -> list[ScenePrimitive]:
    """The primitives of one CollisionObject mapping."""
    if not isinstance(obj, Mapping):
        raise GeometryError(f"collision object #{index} must be a mapping, got {quoted(obj)}")
    name = str(obj.get("id") or f"#{index}")
    where = f"collision object {quoted(name)}"
    for key in ("meshes", "mesh_poses", "planes", "plane_poses"):
        if _nonempty(obj, key):
            raise GeometryError(f"{where} has {key}; only box, sphere and cylinder primitives are supported")
    operation = obj.get("operation", 0)
    if operation not in (0, "ADD", "add", b"\x00"):
        raise GeometryError(f"{where} has operation {quoted(operation)}; only ADD is supported")
    header = obj.get("header")
    frame = str(header.get("frame_id", "")) if isinstance(header, Mapping) else ""
    if frame not in frames:
        raise GeometryError(f"{where} is in frame {quoted(frame)}; supported frames: {list(frames)}")
    object_pose = _pose(obj["pose"], where) if "pose" in obj else Pose.identity()
    primitives = obj.get("primitives") or []
    poses = obj.get("primitive_poses") or []
    if not isinstance(primitives, list) or not isinstance(poses, list) or len(primitives) != len(poses):
        raise GeometryError(f"{where} needs one primitive_pose per primitive")
    if not primitives:
        raise GeometryError(f"{where} has no primitives")
    out = []
    for k, (primitive, pose) in enumerate(zip(primitives, poses, strict=True)):
        label = name if len(primitives) == 1 else f"{name}/{k}"
        shape = _shape(primitive, f"{where} primitive {k}")
        out.append(ScenePrimitive(label, shape, object_pose.compose(_pose(pose, f"{where} primitive {k}"))))
    return out


def _check_robot_state(scene: Mapping[str, Any]) -> None:
    """Refuse attached objects and a moved robot base (the planner assumes the base at the origin)."""
    state = scene.get("robot_state")
    if not isinstance(state, Mapping):
        return
    if _nonempty(state, "attached_collision_objects"):
        raise GeometryError("planning scene has attached collision objects; they are not supported")
    multi = state.get("multi_dof_joint_state")
    transforms = multi.get("transforms") if isinstance(multi, Mapping) else None
    for t in transforms or []:
        translation = _vector(t.get("translation"), "xyz", "virtual joint translation", "robot_state")
        rotation = _vector(t.get("rotation"), "xyzw", "virtual joint rotation", "robot_state")
        q = np.array(rotation) / max(float(np.linalg.norm(rotation)), 1e-300)
        if np.linalg.norm(translation) > 1e-9 or abs(abs(q[3]) - 1.0) > 1e-9:
            raise GeometryError("planning scene places the robot's virtual joint away from the origin; not supported")


def parse_planning_scene(
    text: str, *, source: str = "<string>", frames: Sequence[str] = DEFAULT_WORLD_FRAMES
) -> tuple[ScenePrimitive, ...]:
    """The primitives of a PlanningScene (or PlanningSceneWorld) YAML document.

    Args:
        text: YAML text.
        source: name used in error messages (a file name).
        frames: ``header.frame_id`` values accepted as the planning frame.

    Returns:
        The primitives, in file order.

    Raises:
        GeometryError: invalid YAML, no collision objects section, or anything listed in the module
            docstring; the message names the source and the object.
    """
    doc = load_yaml(text, source=source)
    if not isinstance(doc, Mapping):
        raise GeometryError(f"{source}: a planning scene must be a YAML mapping")
    world = doc.get("world", doc)
    if not isinstance(world, Mapping) or "collision_objects" not in world:
        raise GeometryError(f"{source}: no world.collision_objects section")
    try:
        _check_robot_state(doc)
        if isinstance(world.get("octomap"), Mapping) and _nonempty(world["octomap"], "octomap"):
            raise GeometryError("planning scene has an octomap; it is not supported")
        objects = world["collision_objects"] or []
        if not isinstance(objects, list):
            raise GeometryError("world.collision_objects must be a list")
        return tuple(p for i, obj in enumerate(objects) for p in _object_primitives(obj, i, frames))
    except GeometryError as exc:
        raise GeometryError(f"{source}: {exc}") from exc


def read_planning_scene(
    path: str | Path, *, frames: Sequence[str] = DEFAULT_WORLD_FRAMES
) -> tuple[ScenePrimitive, ...]:
    """The primitives of a PlanningScene YAML file (see :func:`parse_planning_scene`).

    Raises:
        GeometryError: unreadable file or invalid content.
    """
    return parse_planning_scene(read_yaml_text(path, "planning scene"), source=str(path), frames=frames)
