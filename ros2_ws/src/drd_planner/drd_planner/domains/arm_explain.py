"""What blocks an arm configuration, in words: joint limits, self-collision, the floor, or which scene object.

:meth:`ArmEdgeChecker.explain_motion <drd_planner.domains.arm_checker.ArmEdgeChecker.explain_motion>` (the
planner's optional ``explain_motion`` protocol, :class:`drd_planner.planner.connect.MotionExplainer`) finds the
first blocked sample of a motion and asks :func:`explain_configuration` why it is blocked. The static rules
come first (the ones the roadmap was built with): joint limits, self-collision (the sphere model's pairs), the
floor (``floor_z``); then the scene, **one object at a time**: each object alone in a copy of the scene
(:func:`objects_alone`, FCL objects shared, no geometry rebuilt) is tested with the checker's own collision
model (spheres or meshes, through its ``model_for`` factory), so the objects named are exactly those that
block the configuration by themselves, with the link that meets each (the sphere model: the first moving
sphere that hits it; the mesh model: FCL's first contact).

Slow by design (a scene copy and a model per object) and only run after a plan failed.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.domains.arm_static import limits_text, lowest_link, touching_links
from drd_planner.geometry.mesh_collider import MeshCollider
from drd_planner.geometry.robot import RobotModel
from drd_planner.geometry.scene import Scene

if TYPE_CHECKING:
    from drd_planner.domains.arm_checker import ConfigurationTest

__all__ = ["MAX_NAMED", "explain_base", "explain_configuration", "objects_alone", "static_reason"]

#: Scene objects named in one explanation at most (the rest are counted).
MAX_NAMED = 4


def objects_alone(scene: Scene) -> Iterator[tuple[str, Scene]]:
    """``(name, scene with only that object)`` for every object of ``scene`` (terrain included), in order.

    Each scene is a copy (:meth:`Scene.copy`: the FCL objects are shared, nothing is rebuilt) with every
    other object removed; ``scene`` itself is not changed.
    """
    names = scene.names
    for name in names:
        alone = scene.copy()
        for other in names:
            if other != name:
                alone.remove(other)
        yield name, alone


def static_reason(robot: RobotModel, q: npt.ArrayLike, *, floor_z: float | None) -> str:
    """Why the (D,) configuration ``q`` (rad) fails the static rules, or "" when it passes them.

    The joint limits (joint, value and range in rad), self-collision (which two links touch) and the floor
    (which link reaches how low below ``floor_z``, m; None: no floor rule).
    """
    config = np.asarray(q, dtype=np.float64).reshape(1, -1)
    outside = limits_text(robot, config[0])
    if outside:
        return f"outside the joint limits ({outside} rad)"
    if bool(robot.self_collision(config)[0]):
        return f"self-collision ({touching_links(robot, config)})"
    if floor_z is not None:
        link, bottom = lowest_link(robot, config)
        if bottom < floor_z:
            return f"below the floor ({link} reaches down to z = {bottom:.3f} m, floor_z = {floor_z:g} m)"
    return ""


def _link_meeting(model: object, robot: RobotModel, q: FloatArray) -> str:
    """The robot link that meets the only object of ``model``'s scene at the (D,) configuration ``q``."""
    if isinstance(model, MeshCollider):
        contact = model.first_contact(q[None])
        return "" if contact is None else contact.link
    scene = getattr(model, "scene", None)
    if not isinstance(scene, Scene):
        return ""
    moving = np.flatnonzero(robot.spheres.frame_index > 0)
    centres = robot.sphere_centres(q[None])[0, moving]
    hits = scene.spheres_collide_mask(centres, robot.spheres.radii[moving])
    if not hits.any():
        return ""
    return robot.chain.link_names[int(robot.spheres.link_index[moving[int(np.argmax(hits))]])]


def _named(found: list[str], what: str) -> str:
    """``scene object 'a' (link)`` or ``scene objects 'a' (link), 'b' (link) and 2 more``."""
    shown = ", ".join(found[:MAX_NAMED])
    more = f" and {len(found) - MAX_NAMED} more" if len(found) > MAX_NAMED else ""
    return f"{what}{'s' if len(found) > 1 else ''} {shown}{more}"


def explain_configuration(
    robot: RobotModel,
    scene: Scene,
    q: npt.ArrayLike,
    *,
    model_for: Callable[[Scene], ConfigurationTest],
    floor_z: float | None,
) -> str:
    """What blocks the (D,) configuration ``q`` (rad), or "" when nothing does (see the module docstring).

    Args:
        robot: the arm model (limits, spheres, kinematics).
        scene: the obstacles (its margin applies).
        q: the configuration.
        model_for: the collision model of a scene (``groups_blocked``; a ``ConfigurationTest``).
        floor_z: the floor height (m) of the static rules; None: no floor.

    Returns:
        e.g. ``scene object 'Can1' (panda_hand)``, ``self-collision (panda_link1 touches panda_link7)``.
    """
    config = np.asarray(q, dtype=np.float64).reshape(-1)
    static = static_reason(robot, config, floor_z=floor_z)
    if static:
        return static
    found = []
    one = np.zeros(1, dtype=np.int64)
    for name, alone in objects_alone(scene):
        model = model_for(alone)
        if bool(model.groups_blocked(config[None], one, 1)[0]):
            link = _link_meeting(model, robot, config)
            found.append(f"'{name}'" + (f" ({link})" if link else ""))
    return _named(found, "scene object") if found else ""


def explain_base(scene: Scene, *, model_for: Callable[[Scene], ConfigurationTest]) -> str:
    """Which scene objects the robot's fixed base (the parts on its root link) meets; "" when none."""
    found = [f"'{name}'" for name, alone in objects_alone(scene) if not model_for(alone).base_free()]
    return f"the robot's fixed base meets {_named(found, 'scene object')}" if found else ""
