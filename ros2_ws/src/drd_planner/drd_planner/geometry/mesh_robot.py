"""A robot's collision meshes: read once from the URDF's ``<collision>`` elements, placed by batched FK.

:func:`parse_link_meshes` reads every ``<collision>`` of a URDF text: meshes (``.obj``/``.stl``/``.dae`` through
trimesh, ``scale`` applied, duplicate vertices merged so that closed meshes are recognised as solids), boxes,
cylinders and spheres. Each becomes one :class:`LinkMesh` holding its FCL geometry: a ``BVHModel`` for meshes
(the MoveIt way), the FCL primitive for the others. Mesh file names are resolved against the folder of the
URDF: ``package://PKG/path`` is tried as ``<folder>/PKG/path`` and ``<folder>/path``, ``file://`` and absolute
paths are taken as they are, relative ones under the folder.

:data:`LINK_MESHES` (a :class:`LinkMeshLoader`) keeps what it parsed per (URDF text, folder), so every checker
of one robot shares one set of BVH models; a checker only makes its own light ``CollisionObject`` wrappers.

:class:`MeshPlacement` ties the parts to a :class:`~drd_planner.geometry.robot.RobotModel`'s kinematic chain by
link name: for (N, D) configurations it gives the (N, P, 4, 4) world pose of every part and its (N, P, 3)
world AABB, both from one batched forward-kinematics call.

Units: metres and radians.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path

import fcl
import numpy as np
import numpy.typing as npt
import trimesh
from scipy.spatial.transform import Rotation

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.exceptions import GeometryError
from drd_planner.geometry.robot import RobotModel
from drd_planner.geometry.shapes import Box, Cylinder, Sphere, bvh_model, make_fcl_geometry

__all__ = [
    "LINK_MESHES",
    "LinkMesh",
    "LinkMeshLoader",
    "LinkMeshes",
    "MeshPlacement",
    "parse_link_meshes",
]

#: Parsed mesh sets a loader keeps (the least recently used is dropped first).
MESH_SETS_KEPT = 4
#: Facets of the triangle mesh standing in for a cylinder collision in inside tests (FCL checks the exact
#: primitive).
PRIMITIVE_SECTIONS = 32


@dataclass(frozen=True, eq=False)
class LinkMesh:
    """One collision element of one link.

    Attributes:
        link: the URDF link name.
        origin: (4, 4) pose of the element in the link frame (``<collision><origin>``).
        vertices: (V, 3) vertices in the element's frame (m, scale applied, duplicates merged).
        faces: (F, 3) int64 triangles (for a primitive: a triangulation used for inside tests only).
        bounds: (2, 3) the element's AABB in its own frame (m): exact, primitives included.
        geometry: the FCL geometry (``BVHModel`` of the triangles, or the exact primitive), shared by every
            checker of the robot.
        solid: the closed mesh for inside tests, None when the mesh is not watertight (a surface only).
        kind: ``"mesh"``, ``"box"``, ``"cylinder"`` or ``"sphere"``.
        source: the file (meshes) or the primitive's size, for messages.
    """

    link: str
    origin: FloatArray
    vertices: FloatArray
    faces: IntArray
    bounds: FloatArray
    geometry: fcl.CollisionGeometry
    solid: trimesh.Trimesh | None
    kind: str
    source: str

    @property
    def box_centre(self) -> FloatArray:
        """(3,) centre of the element's AABB in its own frame (m)."""
        out: FloatArray = (self.bounds[0] + self.bounds[1]) / 2.0
        return out

    @property
    def box_half(self) -> FloatArray:
        """(3,) half extents of the element's AABB in its own frame (m)."""
        out: FloatArray = (self.bounds[1] - self.bounds[0]) / 2.0
        return out


@dataclass(frozen=True, eq=False)
class LinkMeshes:
    """Every collision element of a robot description.

    Attributes:
        parts: the elements, in URDF order (links, then their ``<collision>`` elements).
        folder: the folder mesh file names were resolved against.
    """

    parts: tuple[LinkMesh, ...]
    folder: Path

    @property
    def count(self) -> int:
        """P, the number of elements."""
        return len(self.parts)

    @property
    def triangles(self) -> int:
        """Triangles of all mesh elements together."""
        return sum(int(p.faces.shape[0]) for p in self.parts if p.kind == "mesh")

    @property
    def links(self) -> tuple[str, ...]:
        """(P,) link name of each element."""
        return tuple(p.link for p in self.parts)


# --------------------------------------------------------------------------------------------------
# Parsing


def _floats(text: str | None, count: int, what: str) -> FloatArray:
    """``count`` finite floats from a URDF attribute (zeros when absent)."""
    if text is None:
        return np.zeros(count)
    try:
        values = np.array([float(x) for x in text.split()], dtype=np.float64)
    except ValueError as exc:
        raise GeometryError(f"URDF {what} {text!r} is not {count} numbers") from exc
    if values.shape != (count,) or not np.all(np.isfinite(values)):
        raise GeometryError(f"URDF {what} {text!r} is not {count} finite numbers")
    return values


def _origin(element: ET.Element) -> FloatArray:
    """(4, 4) pose of a ``<collision>`` from its ``<origin xyz rpy>`` (identity when absent)."""
    origin = element.find("origin")
    out = np.eye(4)
    if origin is None:
        return out
    xyz = _floats(origin.get("xyz"), 3, "origin xyz")
    rpy = _floats(origin.get("rpy"), 3, "origin rpy")
    out[:3, :3] = Rotation.from_euler("xyz", rpy).as_matrix()  # URDF: fixed axes, roll first
    out[:3, 3] = xyz
    return out


def _mesh_path(filename: str, folder: Path) -> Path:
    """The file of a URDF mesh ``filename`` (see the module docstring); GeometryError when none exists."""
    tried: list[Path] = []
    if filename.startswith("package://"):
        rest = Path(filename[len("package://") :])
        tried = [folder / rest, folder / Path(*rest.parts[1:])] if len(rest.parts) > 1 else [folder / rest]
    elif filename.startswith("file://"):
        tried = [Path(filename[len("file://") :])]
    else:
        path = Path(filename)
        tried = [path if path.is_absolute() else folder / path]
    for path in tried:
        if path.is_file():
            return path
    raise GeometryError(
        f"collision mesh {filename!r} not found (tried {', '.join(str(p) for p in tried)}); give an "
        "urdf_path whose folder holds the meshes, or use collision_model 'spheres'"
    )


def _merged(vertices: FloatArray, faces: IntArray) -> trimesh.Trimesh:
    """A trimesh of the triangles with duplicate vertices merged (an OBJ repeats them per normal)."""
    mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=True)
    mesh.merge_vertices(merge_tex=True, merge_norm=True)
    return mesh


def _mesh_part(link: str, origin: FloatArray, element: ET.Element, folder: Path) -> LinkMesh:
    """The element of a ``<mesh filename scale>`` geometry."""
    filename = element.get("filename") or ""
    path = _mesh_path(filename, folder)
    try:
        loaded = trimesh.load(str(path), force="mesh", process=False)
    except (OSError, ValueError, KeyError, IndexError) as exc:
        raise GeometryError(f"collision mesh {path} of link {link!r} cannot be read: {exc}") from exc
    if not isinstance(loaded, trimesh.Trimesh) or loaded.faces.shape[0] == 0:
        raise GeometryError(f"collision mesh {path} of link {link!r} has no triangles")
    scale = _floats(element.get("scale") or "1 1 1", 3, "mesh scale")
    mesh = _merged(np.asarray(loaded.vertices, dtype=np.float64) * scale, np.asarray(loaded.faces))
    vertices = np.ascontiguousarray(mesh.vertices, dtype=np.float64)
    faces = np.ascontiguousarray(mesh.faces, dtype=np.int64)
    solid = mesh if mesh.is_watertight and mesh.is_volume else None
    bounds = np.stack([vertices.min(axis=0), vertices.max(axis=0)])
    return LinkMesh(link, origin, vertices, faces, bounds, bvh_model(vertices, faces), solid, "mesh", str(path))


def _primitive_part(link: str, origin: FloatArray, kind: str, element: ET.Element) -> LinkMesh:
    """The element of a ``<box size>``, ``<cylinder radius length>`` or ``<sphere radius>`` geometry."""
    if kind == "box":
        size = _floats(element.get("size"), 3, "box size")
        shape: Box | Cylinder | Sphere = Box(size)
        mesh = trimesh.creation.box(extents=size)
        half = size / 2.0
        source = f"box {size.tolist()}"
    elif kind == "cylinder":
        radius, length = (float(_floats(element.get(k), 1, f"cylinder {k}")[0]) for k in ("radius", "length"))
        shape = Cylinder(radius, length)
        mesh = trimesh.creation.cylinder(radius=radius, height=length, sections=PRIMITIVE_SECTIONS)
        half = np.array([radius, radius, length / 2.0])
        source = f"cylinder r={radius:g} l={length:g}"
    else:
        radius = float(_floats(element.get("radius"), 1, "sphere radius")[0])
        shape = Sphere(radius)
        mesh = trimesh.creation.icosphere(subdivisions=2, radius=radius)
        half = np.full(3, radius)
        source = f"sphere r={radius:g}"
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    bounds = np.stack([-half, half])
    return LinkMesh(link, origin, vertices, faces, bounds, make_fcl_geometry(shape), mesh, kind, source)


def parse_link_meshes(urdf: str, folder: str | Path) -> LinkMeshes:
    """Every ``<collision>`` element of a URDF text as a :class:`LinkMesh` (see the module docstring).

    Args:
        urdf: URDF XML text.
        folder: where relative and ``package://`` mesh file names are looked up (the URDF's folder).

    Raises:
        GeometryError: malformed XML, a collision without geometry, a mesh file that is missing or holds no
            triangles, invalid numbers, or no collision element at all.
    """
    base = Path(folder)
    try:
        root = ET.fromstring(urdf)
    except ET.ParseError as exc:
        raise GeometryError(f"URDF is not well-formed XML: {exc}") from exc
    parts: list[LinkMesh] = []
    for link in root.findall("link"):
        name = link.get("name") or ""
        for collision in link.findall("collision"):
            geometry = collision.find("geometry")
            element = None if geometry is None else next(iter(geometry), None)
            if element is None or element.tag not in ("mesh", "box", "cylinder", "sphere"):
                raise GeometryError(f"link {name!r} has a <collision> without mesh, box, cylinder or sphere")
            origin = _origin(collision)
            if element.tag == "mesh":
                parts.append(_mesh_part(name, origin, element, base))
            else:
                parts.append(_primitive_part(name, origin, element.tag, element))
    if not parts:
        raise GeometryError("the URDF has no <collision> elements: use collision_model 'spheres'")
    return LinkMeshes(tuple(parts), base)


class LinkMeshLoader:
    """Parses collision meshes once per (URDF text, folder) and keeps the last :data:`MESH_SETS_KEPT` sets.

    Args:
        capacity: sets kept.
    """

    def __init__(self, capacity: int = MESH_SETS_KEPT) -> None:
        self._capacity = int(capacity)
        self._sets: OrderedDict[tuple[str, str], LinkMeshes] = OrderedDict()

    def meshes(self, urdf: str, folder: str | Path) -> LinkMeshes:
        """The elements of ``urdf`` with meshes under ``folder`` (the kept set when seen before).

        Raises:
            GeometryError: see :func:`parse_link_meshes`.
        """
        key = (urdf, str(Path(folder).resolve()))
        known = self._sets.get(key)
        if known is not None:
            self._sets.move_to_end(key)
            return known
        parsed = parse_link_meshes(urdf, folder)
        self._sets[key] = parsed
        while len(self._sets) > self._capacity:
            self._sets.popitem(last=False)
        return parsed

    def __len__(self) -> int:
        return len(self._sets)


#: The loader every arm checker shares unless given its own.
LINK_MESHES = LinkMeshLoader()


# --------------------------------------------------------------------------------------------------
# Placement


class MeshPlacement:
    """The elements of :class:`LinkMeshes` carried by a robot's moving frames (matched by link name).

    Args:
        robot: the kinematic model (its chain must have every link that has an element).
        meshes: the elements.

    Attributes:
        frame_index: (P,) moving frame (0..D) of each element; 0 is the root, which never moves.
        offsets: (P, 4, 4) pose of each element in its moving frame.

    Raises:
        GeometryError: an element's link is not in the robot's chain.
    """

    def __init__(self, robot: RobotModel, meshes: LinkMeshes) -> None:
        chain = robot.chain
        index = np.array([chain.link_index(p.link) for p in meshes.parts], dtype=np.int64)
        self.robot = robot
        self.meshes = meshes
        self.frame_index: IntArray = chain.link_frames[index]
        self.offsets: FloatArray = chain.link_offsets[index] @ np.stack([p.origin for p in meshes.parts])
        self._centres = np.stack([p.box_centre for p in meshes.parts])
        self._halves = np.stack([p.box_half for p in meshes.parts])

    @property
    def count(self) -> int:
        """P, the number of elements."""
        return self.meshes.count

    def poses(self, q: npt.ArrayLike, parts: npt.ArrayLike | None = None) -> FloatArray:
        """(N, P', 4, 4) world poses of elements ``parts`` (all when None) for (N, D) configurations."""
        which = np.arange(self.count) if parts is None else np.asarray(parts, dtype=np.int64)
        frames = self.robot.fk.frames(q)
        out: FloatArray = frames[:, self.frame_index[which]] @ self.offsets[which]
        return out

    def boxes(self, poses: FloatArray, parts: npt.ArrayLike | None = None) -> tuple[FloatArray, FloatArray]:
        """``(lo, hi)``, each (N, P', 3) in metres: world AABBs of elements at (N, P', 4, 4) ``poses``.

        Each is the world AABB of the element's own-frame AABB (enclosing it, exact for boxes).
        """
        which = np.arange(self.count) if parts is None else np.asarray(parts, dtype=np.int64)
        rot = poses[..., :3, :3]
        centre = np.einsum("npij,pj->npi", rot, self._centres[which]) + poses[..., :3, 3]
        half = np.einsum("npij,pj->npi", np.abs(rot), self._halves[which])
        return centre - half, centre + half

    def world_vertices(self, pose: FloatArray, part: int) -> FloatArray:
        """(V, 3) world vertices (m) of element ``part`` at one (4, 4) ``pose``."""
        vertices = self.meshes.parts[part].vertices
        out: FloatArray = vertices @ pose[:3, :3].T + pose[:3, 3]
        return out
