"""Mapped power lines and towers of an OpenStreetMap extract (XML ``.osm`` or ``.pbf``), read with pyosmium.

A power line is a way tagged ``power=line`` or ``power=minor_line``; its nodes, in order, are its route (WGS84
longitude/latitude). A node tagged ``power=tower`` or ``power=pole`` is a mapped tower. Everything else in the
file is skipped. Limits, checked before or while reading: the file's bytes (:data:`MAX_OSM_BYTES`, looked at
before it is opened) and the objects read (:data:`MAX_OSM_OBJECTS`); a file without power ways is refused, and so
is a power way whose nodes are not in the file.

Units: degrees (longitude, latitude).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from drd_planner.exceptions import SiteFileError

__all__ = ["LINE_TAGS", "MAX_OSM_BYTES", "MAX_OSM_OBJECTS", "OSM_SUFFIXES", "OsmPower", "PowerWay", "read_power"]

#: ``power=`` values of a way that is a power line.
LINE_TAGS: tuple[str, ...] = ("line", "minor_line")

#: ``power=`` values of a node that is a tower.
TOWER_TAGS: tuple[str, ...] = ("tower", "pole")

#: File endings pyosmium reads here, and the format each is read as.
OSM_SUFFIXES: dict[str, str] = {".osm": "osm", ".xml": "osm", ".pbf": "pbf"}

#: Largest OSM file read, bytes.
MAX_OSM_BYTES = 64 << 20

#: Most OSM objects (nodes, ways, relations) read from one file.
MAX_OSM_OBJECTS = 2_000_000


@dataclass(frozen=True)
class PowerWay:
    """One mapped power line.

    Attributes:
        osm_id: the way's id.
        name: its ``name`` tag, else its ``ref``, else ``way_<id>``.
        power: its ``power`` tag (one of :data:`LINE_TAGS`).
        points: (longitude, latitude) of its nodes in order, at least 2 (deg).
        towers: per point whether that node is a mapped tower or pole.
    """

    osm_id: int
    name: str
    power: str
    points: tuple[tuple[float, float], ...]
    towers: tuple[bool, ...]


@dataclass(frozen=True)
class OsmPower:
    """The power lines and towers of one OSM file.

    Attributes:
        path: the file (absolute).
        lines: the power ways in file order.
        towers: (longitude, latitude) of every tower or pole node (deg), on a line or not.
    """

    path: str
    lines: tuple[PowerWay, ...]
    towers: tuple[tuple[float, float], ...]


def _checked_file(path: Path) -> tuple[Path, str]:
    """``path`` resolved and its pyosmium format, after the size check.

    Raises:
        SiteFileError: missing, not a regular file, too large, or an ending pyosmium is not asked to read.
    """
    file = path.resolve()
    fmt = OSM_SUFFIXES.get(file.suffix.lower())
    if fmt is None:
        raise SiteFileError(f"OSM file {file}: its name must end in one of {', '.join(OSM_SUFFIXES)}")
    try:
        info = os.stat(file)
    except OSError as exc:
        raise SiteFileError(f"cannot read OSM file {file}: {exc.strerror or exc}") from None
    if not file.is_file():
        raise SiteFileError(f"OSM file {file} is not a regular file")
    if info.st_size > MAX_OSM_BYTES:
        raise SiteFileError(
            f"OSM file {file} has {info.st_size} bytes; at most {MAX_OSM_BYTES} are read (extract the site's "
            "power features first, e.g. with osmium tags-filter)"
        )
    return file, fmt


def _way_name(osm_id: int, tags: dict[str, str]) -> str:
    """The label of a power way (see :class:`PowerWay`)."""
    return tags.get("name") or tags.get("ref") or f"way_{osm_id}"


def read_power(path: str | Path) -> OsmPower:
    """The power lines and towers of the OSM file at ``path`` (see the module docstring).

    Raises:
        SiteFileError: a file too large or of another ending, one pyosmium cannot parse, too many objects,
            no power ways, or a power way with fewer than 2 nodes or nodes missing from the file.
    """
    import osmium

    file, fmt = _checked_file(Path(path))
    towers: dict[int, tuple[float, float]] = {}
    ways: list[tuple[int, dict[str, str], list[tuple[int, float, float] | int]]] = []
    count = 0
    try:
        for obj in osmium.FileProcessor(osmium.io.File(str(file), fmt)).with_locations():
            count += 1
            if count > MAX_OSM_OBJECTS:
                raise SiteFileError(f"OSM file {file} has more than {MAX_OSM_OBJECTS} objects; extract the site first")
            power = obj.tags.get("power")
            if isinstance(obj, osmium.osm.Node) and power in TOWER_TAGS and obj.location.valid():
                towers[obj.id] = (float(obj.location.lon), float(obj.location.lat))
            elif isinstance(obj, osmium.osm.Way) and power in LINE_TAGS:
                nodes: list[tuple[int, float, float] | int] = [
                    (n.ref, float(n.location.lon), float(n.location.lat)) if n.location.valid() else n.ref
                    for n in obj.nodes
                ]
                ways.append((obj.id, dict(obj.tags), nodes))
    except RuntimeError as exc:
        raise SiteFileError(f"OSM file {file} cannot be read as {fmt.upper()}: {exc}") from None
    if not ways:
        raise SiteFileError(
            f"OSM file {file} has no power lines: no way tagged power={' or power='.join(LINE_TAGS)} among its "
            f"{count} objects"
        )
    lines: list[PowerWay] = []
    for osm_id, tags, nodes in ways:
        missing = [n for n in nodes if isinstance(n, int)]
        if missing:
            raise SiteFileError(
                f"OSM file {file}: power way {osm_id} ({_way_name(osm_id, tags)}) refers to nodes not in the file "
                f"({missing[:5]}); extract with complete ways"
            )
        located = [n for n in nodes if not isinstance(n, int)]
        if len(located) < 2:
            raise SiteFileError(f"OSM file {file}: power way {osm_id} has {len(located)} node(s); a line needs 2")
        points = tuple((lon, lat) for _ref, lon, lat in located)
        lines.append(
            PowerWay(osm_id, _way_name(osm_id, tags), tags["power"], points, tuple(r in towers for r, _, _ in located))
        )
    return OsmPower(str(file), tuple(lines), tuple(towers.values()))
