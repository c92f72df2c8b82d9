"""The arm's mesh collision model (spec ``collision_model: meshes``): the URDF's collision meshes, as MoveIt.

:func:`mesh_edge_checker` gives an :class:`~drd_planner.domains.arm_checker.ArmEdgeChecker` whose collision
model is a :class:`~drd_planner.geometry.mesh_collider.MeshCollider`: the ``<collision>`` meshes named by the
domain's URDF (``panda.urdf``: ``meshes/collision/*.obj``) as FCL BVH models, placed by the batched forward
kinematics of the checker's robot, against the scene's objects through an FCL broadphase manager. Sample
order, early exit, caching, ``check``/``check_many``/``check_motion`` and the self-collision test (the
sphere model's, only for another robot model) are those of the sphere checker.

- **Meshes are loaded once** per (URDF text, folder) by :data:`~drd_planner.geometry.mesh_robot.LINK_MESHES`
  and shared by every checker (each checker only wraps them in its own FCL objects).
- **Another robot model** (a ``robot_description`` on the node): its kinematics place the domain's meshes,
  matched by link name.
- **Margin**: a configuration is blocked when an element is closer than the scene margin to an obstacle part
  (FCL distance); exact but slow (about a millisecond per BVH-primitive distance), see
  :mod:`drd_planner.geometry.mesh_collider`.
- **Re-checks after a map update** (:mod:`drd_planner.planning.replan`) choose the plan edges to re-check
  from the sphere sweep model and re-check them with this checker. That choice is safe only if every mesh
  point lies inside the swept spheres; the Panda's collision meshes stick out of its spheres by up to a few
  centimetres (:func:`~drd_planner.geometry.mesh_cover.sphere_cover` measures by how much, per element).
  :meth:`ArmDomain.sweep_spheres <drd_planner.domains.arm.ArmDomain.sweep_spheres>` grows each sphere's
  sweep reach by :func:`mesh_sweep_growth` (the :attr:`~drd_planner.geometry.mesh_cover.SphereCover.growth`
  that makes the spheres contain the meshes) under this model, so the choice stays conservative.
- **The scene's obstacles** are read from its packed arrays
  (:meth:`~drd_planner.geometry.mesh_collider.SceneObstacles.of_scene`, ``Scene.packed_obstacles``).
"""

from __future__ import annotations

import weakref
from pathlib import Path
from typing import Any

from drd_planner.arrays import FloatArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.domains.arm_checker import ArmEdgeChecker
from drd_planner.domains.arm_params import ArmParams
from drd_planner.domains.arm_roadmap import EdgeSamples
from drd_planner.domains.arm_robot import default_panda_dir
from drd_planner.exceptions import GeometryError, ProblemError
from drd_planner.geometry.mesh_collider import MeshCollider, SceneObstacles
from drd_planner.geometry.mesh_cover import sphere_cover
from drd_planner.geometry.mesh_robot import LINK_MESHES, LinkMeshes, LinkMeshLoader, MeshPlacement
from drd_planner.geometry.robot import RobotModel
from drd_planner.geometry.scene import Scene

__all__ = [
    "SWEEP_COVER_SPACING",
    "arm_link_meshes",
    "mesh_edge_checker",
    "mesh_metadata",
    "mesh_model",
    "mesh_sweep_growth",
]

#: Subdivision (m) of the mesh surfaces when measuring the sweep growth (its bound, 5.8 mm, is included).
SWEEP_COVER_SPACING = 0.01

_GROWTH: weakref.WeakKeyDictionary[RobotModel, dict[int, FloatArray]] = weakref.WeakKeyDictionary()


def arm_link_meshes(params: ArmParams, urdf: str, *, loader: LinkMeshLoader = LINK_MESHES) -> LinkMeshes:
    """The collision meshes of the domain's URDF text ``urdf`` (from ``params.urdf_path``'s folder, or the Panda's).

    Raises:
        ProblemError: a mesh is missing or unreadable (the message names the file and ``urdf_path``).
    """
    folder = Path(params.urdf_path).parent if params.urdf_path is not None else default_panda_dir()
    try:
        return loader.meshes(urdf, folder)
    except GeometryError as exc:
        raise ProblemError(f"arm collision meshes: {exc}") from exc


def mesh_model(robot: RobotModel, scene: Scene, meshes: LinkMeshes) -> MeshCollider:
    """The mesh collision model of ``robot`` (its kinematics) with ``meshes`` against ``scene``.

    Raises:
        ProblemError: a link with meshes is not in the robot's chain.
    """
    try:
        placement = MeshPlacement(robot, meshes)
    except GeometryError as exc:
        raise ProblemError(f"arm collision meshes do not fit the robot model: {exc}") from exc
    return MeshCollider(placement, SceneObstacles.of_scene(scene))


def mesh_edge_checker(
    *,
    robot: RobotModel,
    graph: ExplicitGraph,
    scene: Scene,
    samples: EdgeSamples,
    meshes: LinkMeshes,
    self_collision: bool = False,
) -> ArmEdgeChecker:
    """An edge checker of ``graph`` in ``scene`` with the mesh collision model (see the module docstring).

    Args:
        robot: the arm's kinematics (and spheres for self-collision).
        graph: the roadmap; ``vertex_states`` (V, D) in radians.
        scene: the obstacles and margin.
        samples: the roadmap's edge samples (bisection order).
        meshes: the collision meshes (:func:`arm_link_meshes`).
        self_collision: also test self-collision (sphere model) of every sample.
    """
    return ArmEdgeChecker(
        robot=robot,
        graph=graph,
        scene=scene,
        samples=samples,
        self_collision=self_collision,
        model_for=lambda other: mesh_model(robot, other, meshes),
    )


def mesh_metadata(meshes: LinkMeshes) -> dict[str, Any]:
    """What a dataset records about the mesh model: elements, links, triangles, margin rule."""
    return {
        "mesh_elements": meshes.count,
        "mesh_links": sorted(set(meshes.links)),
        "mesh_triangles": meshes.triangles,
        "mesh_margin": "blocked when an element is closer than margin_m to an obstacle (FCL distance)",
        "mesh_self_collision": "sphere model (the roadmap is pruned with it)",
    }


def mesh_sweep_growth(robot: RobotModel, meshes: LinkMeshes) -> FloatArray:
    """(S,) growth (m) of each of ``robot``'s spheres so that the grown spheres contain ``meshes``.

    For the sweep model under ``collision_model: meshes``: add it to every sphere radius of the swept spheres.
    Computed once per (robot model, mesh set) (about a second for the Panda).

    Raises:
        ProblemError: a mesh whose moving frame carries no sphere.
    """
    per_robot = _GROWTH.setdefault(robot, {})
    growth = per_robot.get(id(meshes))
    if growth is None:
        try:
            growth = sphere_cover(robot, meshes, spacing=SWEEP_COVER_SPACING).growth
        except GeometryError as exc:
            raise ProblemError(f"the sweep model cannot cover the collision meshes: {exc}") from exc
        per_robot[id(meshes)] = growth
    return growth
