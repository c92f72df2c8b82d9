"""URDF and SRDF text -> a serial kinematic chain, collision spheres and self-collision exclusions.

The URDF is parsed by yourdfpy (after a well-formedness check with the standard XML parser, because
yourdfpy silently "recovers" broken XML); the SRDF, which yourdfpy does not read, with the standard
XML parser. Everything works from *strings*: a robot description arrives as text on the ROS topic
``robot_description``.

The chain: the movable joints on the path from the URDF's root link to the tip form the chain (D
joints). Fixed joints are folded into constant offsets. Movable joints off the chain (a gripper's
fingers) are frozen at 0 clipped into their limits and folded in as well. Moving frame 0 is the root
link; moving frame i (1..D) is the child link of chain joint i. Every URDF link is carried by one
moving frame with a constant offset.

Units: metres and radians throughout.
"""

from __future__ import annotations

import io
import logging
import math
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
import yourdfpy

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.exceptions import GeometryError

#: Joint types the chain may contain (continuous joints are revolute joints with limits [-pi, pi]).
MOVABLE_TYPES: frozenset[str] = frozenset({"revolute", "continuous", "prismatic"})
SUPPORTED_TYPES: frozenset[str] = MOVABLE_TYPES | {"fixed"}

__all__ = [
    "CollisionSpheres",
    "KinematicChain",
    "SrdfInfo",
    "description_summary",
    "joint_motion",
    "parse_collision_spheres",
    "parse_srdf",
    "parse_urdf_chain",
]


@dataclass(frozen=True)
class KinematicChain:
    """A serial chain of D movable joints with every URDF link attached to one of its D + 1 frames.

    Attributes:
        robot_name: the URDF ``<robot name>``.
        root_link: the URDF root link (moving frame 0; all poses are expressed in it).
        tip_link: the child link of the last chain joint.
        joint_names: (D,) chain joint names, root to tip.
        joint_types: (D,) ``"revolute"`` or ``"prismatic"`` (continuous joints appear as revolute).
        joint_origins: (D, 4, 4) pose of joint i's frame (before its motion) in moving frame i - 1.
        axes: (D, 3) unit joint axes in the joint frames.
        lower: (D,) lower joint limits (rad or m).
        upper: (D,) upper joint limits (rad or m).
        link_names: (L,) every URDF link, in URDF order.
        link_frames: (L,) int64 moving frame (0..D) that carries each link.
        link_offsets: (L, 4, 4) pose of each link in its moving frame.
        parent_child: the (parent link, child link) pairs of every URDF joint.
    """

    robot_name: str
    root_link: str
    tip_link: str
    joint_names: tuple[str, ...]
    joint_types: tuple[str, ...]
    joint_origins: FloatArray
    axes: FloatArray
    lower: FloatArray
    upper: FloatArray
    link_names: tuple[str, ...]
    link_frames: IntArray
    link_offsets: FloatArray
    parent_child: tuple[tuple[str, str], ...]

    @property
    def dof(self) -> int:
        """D, the number of chain joints."""
        return len(self.joint_names)

    def link_index(self, name: str) -> int:
        """Index of link ``name`` into :attr:`link_names`.

        Raises:
            GeometryError: no such link.
        """
        index = self._link_indices.get(name)
        if index is None:
            raise GeometryError(f"robot {self.robot_name!r} has no link {name!r}")
        return index

    @cached_property
    def _link_indices(self) -> dict[str, int]:
        """Link name -> its first index in :attr:`link_names` (a lookup per name, not a scan: L links, L lookups)."""
        return {name: i for i, name in reversed(list(enumerate(self.link_names)))}


@dataclass(frozen=True)
class CollisionSpheres:
    """Collision spheres read from ``<collision><geometry><sphere>`` elements.

    Attributes:
        link_names: (S,) link of each sphere.
        centres: (S, 3) sphere centres in their link's frame (m).
        radii: (S,) radii (m).
    """

    link_names: tuple[str, ...]
    centres: FloatArray
    radii: FloatArray

    @property
    def count(self) -> int:
        """S, the number of spheres."""
        return len(self.link_names)


@dataclass(frozen=True)
class SrdfInfo:
    """What the planner needs from an SRDF.

    Attributes:
        robot_name: the SRDF ``<robot name>``.
        disabled_pairs: link pairs (sorted names) whose collisions are never checked.
        chains: group name -> (base_link, tip_link) of the group's ``<chain>``.
        group_states: (group, state name) -> {joint name: value}.
    """

    robot_name: str
    disabled_pairs: frozenset[tuple[str, str]]
    chains: dict[str, tuple[str, str]]
    group_states: dict[tuple[str, str], dict[str, float]]


# --------------------------------------------------------------------------------------------------
# XML helpers


def _parse_xml(text: str, what: str) -> ET.Element:
    """The root element of an XML document, or GeometryError naming ``what`` and the parser's complaint."""
    if not isinstance(text, str) or not text.strip():
        raise GeometryError(f"{what} is empty")
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise GeometryError(f"{what} is not well-formed XML: {exc}") from exc
    if root.tag != "robot":
        raise GeometryError(f"{what} must have a <robot> root element, found <{root.tag}>")
    return root


def description_summary(urdf: str) -> tuple[int, int, float]:
    """(links, collision spheres, largest |number|) of a URDF string, read by the standard XML parser.

    The largest number is over every ``<origin xyz>`` coordinate and ``<sphere radius>`` (metres); inf when one
    is not finite. Nothing is built, so this is linear in the text and safe before a full parse.

    Raises:
        GeometryError: empty or malformed XML, or no ``<robot>`` root.
    """
    root = _parse_xml(urdf, "URDF")
    texts = [(e.get("xyz") or "").split() for e in root.iter("origin")]
    texts.append([e.get("radius") or "" for e in root.iter("sphere")])
    largest = 0.0
    for words in texts:
        for word in words:
            try:
                value = abs(float(word))
            except ValueError:
                continue  # the full parse says what is wrong with it
            largest = max(largest, value if math.isfinite(value) else math.inf)
    return len(root.findall("link")), len(root.findall("link/collision/geometry/sphere")), largest


@contextmanager
def _quiet_yourdfpy() -> Iterator[None]:
    """Silence yourdfpy's logger (it logs, then recovers, instead of raising) while parsing."""
    logger = logging.getLogger("yourdfpy.urdf")
    old = logger.level
    logger.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        logger.setLevel(old)


def _load_yourdfpy(urdf: str) -> Any:
    """A ``yourdfpy.URDF`` (no scene graph, no meshes) from a well-formed URDF string."""
    _parse_xml(urdf, "URDF")
    try:
        with _quiet_yourdfpy():
            return yourdfpy.URDF.load(
                io.BytesIO(urdf.encode("utf-8")),
                build_scene_graph=False,
                load_meshes=False,
                build_collision_scene_graph=False,
                load_collision_meshes=False,
            )
    except Exception as exc:  # yourdfpy raises bare KeyError/TypeError/ValueError on bad input
        raise GeometryError(f"URDF could not be parsed: {type(exc).__name__}: {exc}") from exc


def _matrix(origin: Any) -> FloatArray:
    """A (4, 4) float64 transform from yourdfpy's origin (None = identity), validated finite."""
    if origin is None:
        return np.eye(4)
    m = np.asarray(origin, dtype=np.float64)
    if m.shape != (4, 4) or not np.all(np.isfinite(m)):
        raise GeometryError(f"URDF origin must be a finite transform, got {m!r}")
    return m


# --------------------------------------------------------------------------------------------------
# Chain


def joint_motion(joint_type: str, axis: FloatArray, value: float) -> FloatArray:
    """(4, 4) motion of one joint at ``value`` (rad for revolute, m for prismatic) about/along ``axis``."""
    m = np.eye(4)
    if joint_type == "prismatic":
        m[:3, 3] = axis * value
    elif joint_type in ("revolute", "continuous"):
        k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
        m[:3, :3] = np.eye(3) + math.sin(value) * k + (1.0 - math.cos(value)) * (k @ k)
    return m


def _unit_axis(joint: Any) -> FloatArray:
    """The joint's axis normalised, or GeometryError when it is zero or not finite."""
    axis = np.asarray(joint.axis if joint.axis is not None else (1.0, 0.0, 0.0), dtype=np.float64)
    norm = float(np.linalg.norm(axis)) if axis.shape == (3,) else 0.0
    if not math.isfinite(norm) or norm < 1e-12:
        raise GeometryError(f"joint {joint.name!r} has an invalid axis {axis.tolist()}")
    return axis / norm


def _limits(joint: Any) -> tuple[float, float]:
    """(lower, upper) of a movable joint; continuous joints get [-pi, pi]."""
    if joint.type == "continuous":
        return -math.pi, math.pi
    limit = joint.limit
    if limit is None or limit.lower is None or limit.upper is None:
        raise GeometryError(f"joint {joint.name!r} ({joint.type}) has no <limit lower=... upper=...>")
    lower, upper = float(limit.lower), float(limit.upper)
    if not (math.isfinite(lower) and math.isfinite(upper)) or lower > upper:
        raise GeometryError(f"joint {joint.name!r} has invalid limits [{lower}, {upper}]")
    return lower, upper


def _tree(robot: Any) -> tuple[str, dict[str, list[Any]], dict[str, Any]]:
    """(root link, parent link -> joints, child link -> joint), validating the link tree."""
    links = [link.name for link in robot.links]
    if not links:
        raise GeometryError("URDF has no <link>")
    if len(set(links)) != len(links):
        raise GeometryError("URDF has duplicate link names")
    known = set(links)
    children: dict[str, list[Any]] = {name: [] for name in links}
    parent_joint: dict[str, Any] = {}
    for joint in robot.joints:
        if joint.type not in SUPPORTED_TYPES:
            raise GeometryError(
                f"joint {joint.name!r} has unsupported type {joint.type!r}; "
                f"supported: {', '.join(sorted(SUPPORTED_TYPES))}"
            )
        for role, name in (("parent", joint.parent), ("child", joint.child)):
            if name not in known:
                raise GeometryError(f"joint {joint.name!r} names unknown {role} link {name!r}")
        if joint.child in parent_joint:
            raise GeometryError(f"link {joint.child!r} is the child of two joints")
        parent_joint[joint.child] = joint
        children[joint.parent].append(joint)
    roots = [name for name in links if name not in parent_joint]
    if len(roots) != 1:
        raise GeometryError(f"URDF links must form one tree; root links: {roots or 'none (a cycle)'}")
    return roots[0], children, parent_joint


def _movable_path(link: str, parent_joint: dict[str, Any]) -> list[Any]:
    """Movable joints from the root to ``link`` (root first)."""
    path: list[Any] = []
    while link in parent_joint:
        joint = parent_joint[link]
        if joint.type in MOVABLE_TYPES:
            path.append(joint)
        link = joint.parent
    return path[::-1]


def _default_chain(robot: Any, parent_joint: dict[str, Any]) -> list[Any]:
    """The longest movable-joint path from the root; the common prefix when several tie (gripper fingers)."""
    paths = [_movable_path(link.name, parent_joint) for link in robot.links]
    longest = max(len(p) for p in paths)
    tied = {tuple(j.name for j in p): p for p in paths if len(p) == longest}
    if len(tied) == 1:
        return next(iter(tied.values()))
    names = list(tied)
    prefix = 0
    while all(n[prefix] == names[0][prefix] for n in names):
        prefix += 1
    if prefix == 0:
        raise GeometryError(
            f"URDF has several movable chains of {longest} joints from the root "
            f"(ending in {', '.join(n[-1] for n in names)}); give tip_link"
        )
    return next(iter(tied.values()))[:prefix]


def _chain_joints(
    robot: Any, children: dict[str, list[Any]], parent_joint: dict[str, Any], tip_link: str | None
) -> list[Any]:
    """The chain's movable joints, root first: up to ``tip_link``, or the default chain when it is None.

    Raises:
        GeometryError: an unknown tip link, no movable joint, or a mimic joint on the chain.
    """
    if tip_link is None:
        chain_joints = _default_chain(robot, parent_joint)
    else:
        if tip_link not in children:
            raise GeometryError(f"tip link {tip_link!r} is not a link of the URDF")
        chain_joints = _movable_path(tip_link, parent_joint)
    if not chain_joints:
        raise GeometryError(f"URDF {robot.name!r} has no movable (revolute/continuous/prismatic) joint")
    for joint in chain_joints:
        if joint.mimic is not None:
            raise GeometryError(f"chain joint {joint.name!r} mimics another joint; not supported")
    return chain_joints


def _place_links(
    root: str, children: dict[str, list[Any]], index: dict[str, int], origins: FloatArray
) -> tuple[dict[str, int], dict[str, FloatArray]]:
    """Walk the link tree from ``root``: each link's chain frame and its (4, 4) offset in that frame.

    Chain joints (``index``: joint name -> 1-based frame) start a new frame and write their placement into
    ``origins`` ((dof, 4, 4), filled in place); other movable joints are fixed at the value nearest 0 within
    their limits.

    Raises:
        GeometryError: a chain joint does not follow the previous one.
    """
    frame_of: dict[str, int] = {root: 0}
    offset_of: dict[str, FloatArray] = {root: np.eye(4)}
    stack = [root]
    while stack:
        parent = stack.pop()
        for joint in children[parent]:
            placed = offset_of[parent] @ _matrix(joint.origin)
            if joint.name in index:
                i = index[joint.name]
                if frame_of[parent] != i - 1:
                    raise GeometryError(f"chain joint {joint.name!r} does not follow the previous one")
                origins[i - 1] = placed
                frame_of[joint.child] = i
                offset_of[joint.child] = np.eye(4)
            else:
                value = 0.0
                if joint.type in MOVABLE_TYPES:
                    lo, hi = _limits(joint)
                    value = min(max(0.0, lo), hi)
                    placed = placed @ joint_motion(joint.type, _unit_axis(joint), value)
                frame_of[joint.child] = frame_of[parent]
                offset_of[joint.child] = placed
            stack.append(joint.child)
    return frame_of, offset_of


def parse_urdf_chain(urdf: str, *, tip_link: str | None = None) -> KinematicChain:
    """The serial chain of a URDF given as a string.

    Args:
        urdf: URDF XML text.
        tip_link: the chain's tip; by default the end of the longest movable-joint path from the root
            (the common part when several tie, so that gripper fingers are not part of the chain).

    Raises:
        GeometryError: malformed XML, not a URDF, broken link tree, unsupported joint types, missing
            limits, no movable joint, an unknown tip link, or a mimic joint on the chain.
    """
    model = _load_yourdfpy(urdf)
    robot = model.robot
    root, children, parent_joint = _tree(robot)
    chain_joints = _chain_joints(robot, children, parent_joint, tip_link)
    index = {joint.name: i + 1 for i, joint in enumerate(chain_joints)}
    dof = len(chain_joints)
    origins = np.zeros((dof, 4, 4))
    axes = np.zeros((dof, 3))
    lower = np.zeros(dof)
    upper = np.zeros(dof)
    types: list[str] = []
    for i, joint in enumerate(chain_joints):
        axes[i] = _unit_axis(joint)
        lower[i], upper[i] = _limits(joint)
        types.append("prismatic" if joint.type == "prismatic" else "revolute")
    frame_of, offset_of = _place_links(root, children, index, origins)
    link_names = tuple(link.name for link in robot.links)
    return KinematicChain(
        robot_name=str(robot.name),
        root_link=root,
        tip_link=str(chain_joints[-1].child),
        joint_names=tuple(str(j.name) for j in chain_joints),
        joint_types=tuple(types),
        joint_origins=origins,
        axes=axes,
        lower=lower,
        upper=upper,
        link_names=link_names,
        link_frames=np.array([frame_of[name] for name in link_names], dtype=np.int64),
        link_offsets=np.stack([offset_of[name] for name in link_names]),
        parent_child=tuple((str(j.parent), str(j.child)) for j in robot.joints),
    )


# --------------------------------------------------------------------------------------------------
# Spheres


def parse_collision_spheres(urdf: str) -> CollisionSpheres:
    """Every ``<collision>`` sphere of a (spherized) URDF string, in link frames.

    Raises:
        GeometryError: malformed URDF, a collision element that is not a sphere (it would be silently
            ignored otherwise), a non-positive or non-finite radius, or no sphere at all.
    """
    robot = _load_yourdfpy(urdf).robot
    names: list[str] = []
    centres: list[FloatArray] = []
    radii: list[float] = []
    for link in robot.links:
        for collision in link.collisions:
            geometry = collision.geometry
            if geometry is None or geometry.sphere is None:
                kind = next(
                    (k for k in ("box", "cylinder", "mesh") if getattr(geometry, k, None) is not None),
                    "no geometry",
                )
                raise GeometryError(
                    f"link {link.name!r} has a non-sphere collision element ({kind}); "
                    "the sphere model needs a spherized URDF with only <sphere> collisions"
                )
            radius = float(geometry.sphere.radius)
            if not (math.isfinite(radius) and radius > 0):
                raise GeometryError(f"link {link.name!r} has a collision sphere of radius {radius}")
            names.append(str(link.name))
            centres.append(_matrix(collision.origin)[:3, 3])
            radii.append(radius)
    if not names:
        raise GeometryError(f"URDF {robot.name!r} has no <collision><sphere> elements")
    return CollisionSpheres(tuple(names), np.array(centres, dtype=np.float64), np.array(radii))


# --------------------------------------------------------------------------------------------------
# SRDF


def _attr(element: ET.Element, name: str) -> str:
    """A required attribute, or GeometryError naming the element."""
    value = element.get(name)
    if value is None or not value:
        raise GeometryError(f"SRDF <{element.tag}> lacks the attribute {name!r}")
    return value


def parse_srdf(srdf: str) -> SrdfInfo:
    """Disabled collision pairs, group chains and group states of an SRDF string.

    Raises:
        GeometryError: malformed XML, no ``<robot>`` root, missing attributes, non-numeric joint values.
    """
    root = _parse_xml(srdf, "SRDF")
    disabled: set[tuple[str, str]] = set()
    for element in root.iter("disable_collisions"):
        a, b = _attr(element, "link1"), _attr(element, "link2")
        disabled.add((min(a, b), max(a, b)))
    chains: dict[str, tuple[str, str]] = {}
    for group in root.iter("group"):
        for chain in group.findall("chain"):
            chains[_attr(group, "name")] = (_attr(chain, "base_link"), _attr(chain, "tip_link"))
    states: dict[tuple[str, str], dict[str, float]] = {}
    for state in root.iter("group_state"):
        values: dict[str, float] = {}
        for joint in state.findall("joint"):
            text = _attr(joint, "value")
            try:
                values[_attr(joint, "name")] = float(text.split()[0])
            except (ValueError, IndexError):
                raise GeometryError(f"SRDF group_state joint value {text!r} is not a number") from None
        states[(_attr(state, "group"), _attr(state, "name"))] = values
    return SrdfInfo(str(root.get("name", "")), frozenset(disabled), chains, states)
