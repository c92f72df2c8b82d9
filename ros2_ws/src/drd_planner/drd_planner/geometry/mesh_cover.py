"""How well a robot's sphere model covers its collision meshes, and how much to grow the spheres so it does.

:func:`sphere_cover` samples the surface of every collision element densely (its triangles subdivided until no
edge is longer than ``spacing``) and measures, per surface point, how far it lies outside the spheres carried
by the same moving frame: ``excess = min_s(|p - c_s| - r_s)`` (m; negative inside). From that:

- per element: the largest excess (how far the mesh sticks out of the sphere model), the share of its sample
  points outside every sphere, and where the worst point is;
- per sphere: a **growth** (m) such that every point of every element lies inside some sphere of its frame
  grown by its growth. Each sample point is given to the sphere it is least outside of; a sphere's growth is
  the largest excess among its points plus ``bound`` (the longest subdivided edge / sqrt(3): no point of a
  triangle lies farther than that from its nearest corner; ``excess`` changes at most as much as the point
  moves, so this bounds the points between the samples too).

Spheres grown by their growth contain the meshes: a check (or a sweep model) that sees what the grown spheres
see sees everything the meshes can touch.

Units: metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.exceptions import GeometryError
from drd_planner.geometry.mesh_robot import LinkMeshes, MeshPlacement
from drd_planner.geometry.robot import RobotModel

__all__ = ["ElementCover", "SphereCover", "sphere_cover"]

#: Default longest edge (m) of the subdivided surface triangles.
DEFAULT_SPACING = 0.006


@dataclass(frozen=True)
class ElementCover:
    """How one collision element sits in the sphere model.

    Attributes:
        link: the element's link.
        triangles: surface triangles tested (after subdivision; their corners are the sample points).
        outside_share: share of the element's surface area outside every sphere of the frame (by the
            triangles' centres).
        max_excess: the largest distance (m) of a sample point outside the spheres (<= 0: all inside).
        worst_point: (3,) that point in the element's moving frame (m).
    """

    link: str
    triangles: int
    outside_share: float
    max_excess: float
    worst_point: FloatArray


@dataclass(frozen=True)
class SphereCover:
    """The cover of a robot's meshes by its spheres (see the module docstring).

    Attributes:
        elements: per collision element, in the order of :attr:`LinkMeshes.parts`.
        growth: (S,) growth of each sphere (m, >= 0) that makes the spheres contain the meshes.
        bound: how far a surface point may lie from its nearest sample point (m), included in ``growth``.
    """

    elements: tuple[ElementCover, ...]
    growth: FloatArray
    bound: float

    @property
    def max_excess(self) -> float:
        """The largest excess over all elements (m)."""
        return max((e.max_excess for e in self.elements), default=0.0)


def _surface(vertices: FloatArray, faces: IntArray, spacing: float) -> tuple[FloatArray, float]:
    """(K, 3, 3) the triangles split in four until no edge exceeds ``spacing``, and their longest edge (m)."""
    tris = vertices[faces]
    done: list[FloatArray] = []
    while tris.shape[0]:
        longest = np.linalg.norm(tris - np.roll(tris, 1, axis=1), axis=2).max(axis=1)
        done.append(tris[longest <= spacing])
        big = tris[longest > spacing]
        a, b, c = big[:, 0], big[:, 1], big[:, 2]
        ab, bc, ca = (a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0
        tris = np.concatenate([np.stack(t, axis=1) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])
    kept = np.concatenate(done)
    return kept, float(np.linalg.norm(kept - np.roll(kept, 1, axis=1), axis=2).max())


def _excess(points: FloatArray, centres: FloatArray, radii: FloatArray) -> tuple[FloatArray, IntArray]:
    """(K,) how far each point lies outside the nearest-surface sphere (m), and (K,) which sphere that is."""
    gaps = np.linalg.norm(points[:, None, :] - centres, axis=2) - radii
    nearest = np.argmin(gaps, axis=1)
    return gaps[np.arange(points.shape[0]), nearest], nearest


def sphere_cover(robot: RobotModel, meshes: LinkMeshes, *, spacing: float = DEFAULT_SPACING) -> SphereCover:
    """Measure how the spheres of ``robot`` cover ``meshes`` and the growth that makes them cover it.

    Args:
        robot: the sphere model (and the chain carrying the elements).
        meshes: the collision elements.
        spacing: longest edge (m) of the subdivided triangles; smaller is tighter and slower.

    Raises:
        GeometryError: an element's moving frame carries no sphere (nothing can cover it), or a bad spacing.
    """
    if not (math.isfinite(spacing) and spacing > 0):
        raise GeometryError(f"cover spacing must be finite and > 0 m, got {spacing}")
    placement = MeshPlacement(robot, meshes)
    spheres = robot.spheres
    growth = np.zeros(spheres.count)
    elements: list[ElementCover] = []
    bound = 0.0
    for p, part in enumerate(meshes.parts):
        own = np.nonzero(spheres.frame_index == placement.frame_index[p])[0]
        if own.size == 0:
            raise GeometryError(f"no sphere moves with link {part.link!r}: the spheres cannot cover its mesh")
        tris, longest = _surface(part.vertices, part.faces, spacing)
        offset = placement.offsets[p]
        tris = tris @ offset[:3, :3].T + offset[:3, 3]  # in the moving frame, like the sphere centres
        points = tris.reshape(-1, 3)
        least, nearest = _excess(points, spheres.centres[own], spheres.radii[own])
        bound = max(bound, longest / math.sqrt(3.0))
        np.maximum.at(growth, own[nearest], np.maximum(least + longest / math.sqrt(3.0), 0.0))
        middle, _ = _excess(tris.mean(axis=1), spheres.centres[own], spheres.radii[own])
        areas = np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1) / 2.0
        worst = int(np.argmax(least))
        elements.append(
            ElementCover(
                part.link,
                int(tris.shape[0]),
                float(areas[middle > 0].sum() / areas.sum()),
                float(least[worst]),
                points[worst],
            )
        )
    return SphereCover(tuple(elements), growth, bound)
