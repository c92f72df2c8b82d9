"""Where a dataset's worlds come from: a seeded world model, or the user's own files (the world-source seam).

Without a source a build draws world i of ``--world-model`` from seed i (:mod:`drd_planner.data.seeding`),
exactly as before sources existed. A *source request* names files instead:

- :class:`SceneFolder` (``--scenes DIR``): one world per MoveIt PlanningScene ``scene*.yaml``, sorted by name;
  the start and goal states of the folder's ``request*.yaml`` become graph vertices
  (:mod:`drd_planner.data.scene_source`);
- :class:`TerrainFile` (``--terrain FILE``): the ``terrain`` world model cropping the user's ESRI ASCII grid,
  with the operating site, crop and jitter as flags (:mod:`drd_planner.data.terrain_source`);
- :class:`SiteFile` (``--site-file FILE``): the ``corridors`` world model over a real site described by a site
  file (DEM, mapped power lines, no-fly zones; :mod:`drd_planner.data.site_source`);
- :class:`MapBags` (``--bags FILE...``): one world per map snapshot of recorded bags
  (:mod:`drd_planner.planning.bag_worlds`: it applies the map messages with the planner's one map store, and
  ``planning/`` may import ``data/`` but not the reverse, so it lives there).

Each kind has a module with these functions, found through :data:`SOURCE_MODULES` by name on first use (so
that this module imports none of them)::

    spec_defaults(request, domain_name) -> Mapping                     # optional: spec values under the user's
    resolve(request, domain, user_spec, num_worlds) -> ResolvedSource   # the building process
    open_worlds(data) -> WorldSet                                      # a worker, from worker_data

A :class:`ResolvedSource` names every file with its SHA-256 (:class:`FileRecord`); workers (local processes
or Dask) rebuild the world set from that JSON and refuse a file whose bytes changed, naming it.
"""

from __future__ import annotations

import hashlib
import importlib
import json
import os
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

from drd_planner.bounded_files import read_bounded
from drd_planner.domains.base import Domain, EdgeChecker
from drd_planner.exceptions import DatasetError

if TYPE_CHECKING:  # the online seam pulls in FCL; a CLI that only parses flags should not
    from drd_planner.domains.online import OnlineDomain

__all__ = [
    "CROP_CHOICES",
    "PROCESS_SOURCES",
    "SOURCE_MODULES",
    "FileRecord",
    "MapBags",
    "ResolvedSource",
    "SceneFolder",
    "SiteFile",
    "SourceCache",
    "TerrainFile",
    "WorldSet",
    "WorldSourceRequest",
    "online_domain",
    "open_world_set",
    "records_from_json",
    "resolve_source",
    "source_spec_defaults",
]

#: Source kind -> the module that resolves and opens it (imported on first use).
SOURCE_MODULES: Mapping[str, str] = {
    "scenes": "drd_planner.data.scene_source",
    "terrain": "drd_planner.data.terrain_source",
    "site": "drd_planner.data.site_source",
    "bags": "drd_planner.planning.bag_worlds",
}


#: Largest source file (scene, request, terrain grid, bag) read whole, bytes; each kind may ask for less.
MAX_SOURCE_BYTES = 1 << 30


def _bounded_bytes(where: str, what: str, max_bytes: int) -> bytes:
    """The bytes of the regular file ``where`` when it has at most ``max_bytes`` (its size looked at first).

    Raises:
        DatasetError: unreadable, not a regular file, or larger than ``max_bytes``.
    """
    return read_bounded(where, max_bytes, f"{what} {where}" if what else where, DatasetError)


def _absolute(path: str | os.PathLike[str]) -> str:
    """``path`` made absolute and normalised (so a recorded command works from any folder)."""
    return os.path.abspath(os.fspath(path))


@dataclass(frozen=True)
class FileRecord:
    """A file a dataset is built from, and the SHA-256 of its bytes when the build was planned.

    Attributes:
        path: absolute path.
        sha256: hex digest of the file's bytes.
    """

    path: str
    sha256: str

    @classmethod
    def of(cls, path: str | os.PathLike[str], *, what: str = "file", max_bytes: int = MAX_SOURCE_BYTES) -> FileRecord:
        """The record of ``path`` as it is now.

        Raises:
            DatasetError: the file cannot be read, is not a regular file or has more than ``max_bytes``
                (looked at before reading; the message names it and ``what`` it is).
        """
        where = _absolute(path)
        data = _bounded_bytes(where, what, max_bytes)
        return cls(where, hashlib.sha256(data).hexdigest())

    def read(self, *, max_bytes: int = MAX_SOURCE_BYTES) -> bytes:
        """The file's bytes, checked against the recorded SHA-256.

        Raises:
            DatasetError: the file is gone, unreadable, larger than ``max_bytes``, or its bytes changed
                since the build was planned.
        """
        data = _bounded_bytes(self.path, "", max_bytes)
        digest = hashlib.sha256(data).hexdigest()
        if digest != self.sha256:
            raise DatasetError(
                f"{self.path} changed since the build was planned (SHA-256 {digest[:16]}..., recorded "
                f"{self.sha256[:16]}...); restore it, or start the build again (delete the OUT.parts folder)"
            )
        return data

    def to_json(self) -> dict[str, str]:
        """``{"path": ..., "sha256": ...}``."""
        return {"path": self.path, "sha256": self.sha256}

    @classmethod
    def from_json(cls, data: Any) -> FileRecord:
        """The record of :meth:`to_json`'s dict.

        Raises:
            DatasetError: not such a dict.
        """
        if not isinstance(data, Mapping) or not isinstance(data.get("path"), str):
            raise DatasetError(f"a file record needs 'path' and 'sha256' strings, got {data!r}")
        digest = data.get("sha256")
        if not isinstance(digest, str) or len(digest) != 64:
            raise DatasetError(f"a file record needs a 64-digit 'sha256', got {digest!r}")
        return cls(data["path"], digest)


def records_from_json(data: Mapping[str, Any], key: str = "files") -> tuple[FileRecord, ...]:
    """The file records listed under ``data[key]``.

    Raises:
        DatasetError: no such list, or a malformed record.
    """
    items = data.get(key)
    if not isinstance(items, list):
        raise DatasetError(f"world source data needs a list {key!r}, got {items!r}")
    return tuple(FileRecord.from_json(item) for item in items)


# --------------------------------------------------------------------------------------------------
# Source requests: what the user asked for (recipe fields; they give the command-line flags back)


@dataclass(frozen=True)
class SceneFolder:
    """``--scenes DIR``: a folder of MoveIt PlanningScene ``scene*.yaml`` files (and ``request*.yaml``).

    Attributes:
        folder: the folder (made absolute).
        requests: add the requests' start and goal states as graph vertices (``--no-requests``: False).
    """

    kind: ClassVar[str] = "scenes"
    world_model: ClassVar[str] = "moveit_scenes"
    folder: str
    requests: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "folder", _absolute(self.folder))

    def argv(self) -> list[str]:
        """The ``drd build-dataset`` flags that ask for this source."""
        return ["--scenes", self.folder] + ([] if self.requests else ["--no-requests"])


@dataclass(frozen=True)
class MapBags:
    """``--bags FILE...``: rosbag2 MCAP bags whose map snapshots are the worlds.

    Attributes:
        files: the bags (made absolute), in the order their snapshots are taken.
        frame: the planning frame maps must be in (None: the frame of the first bag's first map message).
    """

    kind: ClassVar[str] = "bags"
    world_model: ClassVar[str] = "map_bags"
    files: tuple[str, ...]
    frame: str | None = None

    def __post_init__(self) -> None:
        if isinstance(self.files, str) or not self.files:
            raise DatasetError("--bags needs at least one bag file")
        object.__setattr__(self, "files", tuple(_absolute(f) for f in self.files))

    def argv(self) -> list[str]:
        """The ``drd build-dataset`` flags that ask for this source."""
        return ["--bags", *self.files] + ([] if self.frame is None else ["--frame", self.frame])


#: Crop presets of ``--crop``: ``random`` keeps the model's random rotation, mirror, scale and relief; ``as-is``
#: crops north up, unmirrored, at the grid's own cell size (one source cell = cell size metres) and heights.
CROP_CHOICES: tuple[str, ...] = ("random", "as-is")


@dataclass(frozen=True)
class TerrainFile:
    """``--terrain FILE``: the ``terrain`` world model on the user's ESRI ASCII grid.

    Attributes:
        path: the grid (made absolute).
        site: (x, y) centre of the operating area in the grid's own coordinates (its x/y unit, as its
            ``xllcorner``); None: crops anywhere on the grid.
        site_jitter: metres (world units) by which a crop's centre may move from the site per axis.
        crop: one of :data:`CROP_CHOICES`.
        crop_scale: (lo, hi) metres per source cell (drawn per world); None: the preset's.
    """

    kind: ClassVar[str] = "terrain"
    world_model: ClassVar[str] = "terrain"
    path: str
    site: tuple[float, float] | None = None
    site_jitter: float | None = None
    crop: str = "random"
    crop_scale: tuple[float, float] | None = field(default=None)

    def __post_init__(self) -> None:
        object.__setattr__(self, "path", _absolute(self.path))
        if self.crop not in CROP_CHOICES:
            raise DatasetError(f"--crop must be one of {', '.join(CROP_CHOICES)}, got {self.crop!r}")

    def argv(self) -> list[str]:
        """The ``drd build-dataset`` flags that ask for this source."""
        out = ["--terrain", self.path]
        if self.site is not None:  # one token: a negative X would otherwise read as an option
            out += [f"--site={self.site[0]!r},{self.site[1]!r}"]
        if self.site_jitter is not None:
            out += ["--site-jitter", repr(float(self.site_jitter))]
        if self.crop != "random":
            out += ["--crop", self.crop]
        if self.crop_scale is not None:
            out += ["--crop-scale", f"{self.crop_scale[0]!r},{self.crop_scale[1]!r}"]
        return out


@dataclass(frozen=True)
class SiteFile:
    """``--site-file FILE``: the ``corridors`` world model over the site a site file describes.

    Attributes:
        path: the site file (made absolute); see :mod:`drd_planner.data.site_file`.
    """

    kind: ClassVar[str] = "site"
    world_model: ClassVar[str] = "corridors"
    path: str

    def __post_init__(self) -> None:
        object.__setattr__(self, "path", _absolute(self.path))

    def argv(self) -> list[str]:
        """The ``drd build-dataset`` flags that ask for this source."""
        return ["--site-file", self.path]


WorldSourceRequest = SceneFolder | MapBags | TerrainFile | SiteFile


# --------------------------------------------------------------------------------------------------
# Resolved sources and world sets


@dataclass(frozen=True)
class ResolvedSource:
    """A source request checked against its domain in the building process.

    Attributes:
        kind: the source kind (a key of :data:`SOURCE_MODULES`).
        world_model: what the dataset's ``world_model`` field says (``moveit_scenes``, ``map_bags``, ``terrain``).
        num_worlds: n.
        seeded: True: world i is drawn from ``world_seeds(seed, n)[i]``; False: world i is the source's i-th
            world in file order (the dataset's ``world_seeds`` are then 0..n-1).
        spec: the domain spec to build with (the user's, with what the source adds), or None: the user's.
        worker_data: JSON-able data workers rebuild the world set from (kind, files with SHA-256, options).
        provenance: JSON-able account of the source for the dataset file (files with SHA-256, what was read).
    """

    kind: str
    world_model: str
    num_worlds: int
    seeded: bool
    spec: Mapping[str, Any] | None
    worker_data: Mapping[str, Any]
    provenance: Mapping[str, Any]


class WorldSet(Protocol):
    """The worlds of a resolved source, in a worker."""

    def checkers(self, domain: Domain, ids: Sequence[int]) -> Iterator[EdgeChecker]:
        """One edge checker per world id (a seed when the source is seeded, else a 0-based world index)."""
        ...


def _module(kind: str) -> Any:
    name = SOURCE_MODULES.get(kind)
    if name is None:
        raise DatasetError(f"unknown world source {kind!r}; known: {', '.join(SOURCE_MODULES)}")
    return importlib.import_module(name)


def source_spec_defaults(request: WorldSourceRequest, domain_name: str) -> dict[str, Any]:
    """Spec values the source kind sets for ``domain_name`` where the user's spec does not (``{}``: none)."""
    defaults = getattr(_module(request.kind), "spec_defaults", None)
    return {} if defaults is None else dict(defaults(request, domain_name))


def resolve_source(
    request: WorldSourceRequest, domain: Domain, user_spec: Mapping[str, Any], num_worlds: int | None
) -> ResolvedSource:
    """Check ``request`` against ``domain`` (built from ``user_spec``) and list its files and worlds.

    Args:
        request: the source request.
        domain: the domain built from the user's spec (its joint names, world models, margin).
        user_spec: the spec the user gave (``--domain-spec``; ``{}`` when none).
        num_worlds: use the first n worlds (None: all of a file source; required for a seeded one).

    Raises:
        DatasetError: the files cannot be used; the message names the file, the check and the parameter.
    """
    resolved: ResolvedSource = _module(request.kind).resolve(request, domain, user_spec, num_worlds)
    return resolved


def open_world_set(data: Mapping[str, Any]) -> WorldSet:
    """The world set of a resolved source's ``worker_data`` (files checked against their SHA-256).

    Raises:
        DatasetError: unknown kind, malformed data, or a file that changed.
    """
    world_set: WorldSet = _module(str(data.get("kind"))).open_worlds(data)
    return world_set


class SourceCache:
    """Opens world sets from their JSON and keeps the last one (one build at a time per process)."""

    def __init__(self) -> None:
        self._key: str | None = None
        self._worlds: WorldSet | None = None

    def worlds(self, source_json: str) -> WorldSet:
        """The world set of ``source_json`` (canonical JSON of ``worker_data``): the kept one, or a new one."""
        if self._worlds is None or self._key != source_json:
            self._worlds = open_world_set(json.loads(source_json))
            self._key = source_json
        return self._worlds


#: This process's world set (a worker opens it once per build).
PROCESS_SOURCES = SourceCache()


def online_domain(domain: Domain, what: str) -> OnlineDomain[Any]:
    """``domain`` as an :class:`OnlineDomain` (scene checks, margin, joint names).

    Raises:
        DatasetError: the domain lacks the online members ``what`` needs.
    """
    from drd_planner.domains.online import OnlineDomain

    if not isinstance(domain, OnlineDomain):
        raise DatasetError(
            f"{what} needs a domain with scene checks (the OnlineDomain members margin, joint_names, "
            f"scene_checker); domain {domain.name!r} ({type(domain).__name__}) has none: use --world-model"
        )
    return domain
