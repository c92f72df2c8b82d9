"""Inside tests for closed (watertight) meshes, which FCL treats as hollow surfaces.

FCL reports no collision for an object wholly inside a mesh, because a mesh is only its triangles. The scene
adds this test for meshes that enclose a volume: if an object touches none of the mesh's triangles, it is
either wholly inside or wholly outside, and one of its points decides which (trimesh's ``contains``, a ray
parity test, on the mesh in its own frame).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import trimesh

from drd_planner.arrays import BoolArray
from drd_planner.geometry.pose import Pose, as_points
from drd_planner.geometry.shapes import TriangleMesh

__all__ = ["ClosedMesh", "closed_mesh"]


class ClosedMesh:
    """A watertight mesh placed at a pose, answering point-inside queries. Build with :func:`closed_mesh`."""

    def __init__(self, mesh: trimesh.Trimesh, pose: Pose) -> None:
        self._mesh = mesh
        self._to_local = pose.inverse()

    def contains(self, points: npt.ArrayLike) -> BoolArray:
        """(K,) bool: whether each of the (K, 3) world ``points`` (metres) lies inside the closed mesh."""
        local = self._to_local.transform_points(as_points(points))
        inside: BoolArray = np.asarray(self._mesh.contains(local), dtype=bool)
        return inside


def closed_mesh(mesh: TriangleMesh, pose: Pose) -> ClosedMesh | None:
    """The inside test of ``mesh`` at ``pose`` when the mesh is watertight, else None (a surface only).

    Duplicate vertices are merged first, so triangle soups (e.g. ROS ``TRIANGLE_LIST`` markers, three fresh
    vertices per triangle) that close up are recognised as solids.
    """
    tm = trimesh.Trimesh(vertices=np.array(mesh.vertices), faces=np.array(mesh.faces), process=True)
    if not tm.is_watertight or tm.is_empty:
        return None
    return ClosedMesh(tm, pose)
