"""A real site from GIS files: the site file (``format: drd-site/1``), read into corridors-model parameters.

A site file is YAML (read safely: :mod:`~drd_planner.data.site_yaml`); relative paths in it are resolved
against its folder. Its keys (every key is checked; an unknown one is refused with the valid ones named)::

    format: drd-site/1            # required
    name: front_range             # label (default: the file's folder name)
    dem:                          # the elevation model (required)
      path: dem.tif               #   GeoTIFF (.tif/.tiff) or ESRI ASCII grid
      crs: EPSG:4326              #   only for a grid without a CRS of its own (must match a GeoTIFF's)
      vertical_datum: EGM96       #   what its heights are above: EGM96 (SRTM) or WGS84 ellipsoid
    origin:                       # the lattice frame's origin (required)
      latitude: 40.1825           #   deg, WGS84
      longitude: -105.4617
      heading_deg: 0              #   compass bearing of the lattice's +x axis (deg clockwise from north)
      datum: DEM                  #   z = 0: DEM (the DEM's ground at the origin), EGM96 or WGS84 ellipsoid
      height_m: 0                 #   with EGM96 / WGS84 ellipsoid: z = 0 is this height above it
      geoid_separation_m: null    #   WGS84 ellipsoid minus EGM96 at the origin, when datum and DEM differ
    lattice: spec.json            # the helicopter spec (a JSON file, e.g. trees/heli_lines_spec.json), or a
                                  # mapping of its keys (lattice, terrain_cell, ...) with an optional `file`
    power_lines: power.osm        # OSM XML (.osm) or PBF (.pbf): power=line/minor_line ways, tower/pole nodes
    zones: zones.geojson          # GeoJSON FeatureCollection of Polygon/MultiPolygon no-fly zones
    uncertainty: {...}            # what is not known (see UNCERTAINTY_KEYS)
    dataset: {worlds: 200, seed: 0}   # defaults of drd build-dataset --site-file

:func:`load_site` gives a :class:`Site`: the ``"corridors"`` world model's parameters in the lattice frame
(``corridors``; z = 0 at the height datum, x along the heading) and the helicopter domain spec with them
(``domain_spec``, as a dataset or prior stores it). Every file is bounded before it is read whole and every
failure is one :class:`~drd_planner.exceptions.SiteFileError` naming the file and the key.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

from drd_planner.bounded_files import read_bounded_text
from drd_planner.data.geo_dem import SiteDem, check_covers, check_known_heights, open_dem
from drd_planner.data.geo_frame import SiteFrame
from drd_planner.data.geo_power import read_power
from drd_planner.data.geo_zones import read_zones
from drd_planner.data.site_convert import LineDefaults, Region, known_lines, known_zones, mast_zones
from drd_planner.data.site_yaml import (
    check_keys,
    get_number,
    get_probability,
    get_range,
    get_section,
    get_string,
    read_yaml_mapping,
)
from drd_planner.domains.helicopter_corridors_params import CorridorsParams
from drd_planner.domains.helicopter_params import params_to_dict
from drd_planner.domains.helicopter_spec import HelicopterParams
from drd_planner.domains.params import spec_keys
from drd_planner.exceptions import ProblemError, SiteFileError

__all__ = ["DATUMS", "SITE_FORMAT", "TOP_KEYS", "UNCERTAINTY_KEYS", "Site", "SiteOrigin", "load_site"]

#: The site file format this reader knows.
SITE_FORMAT = "drd-site/1"

#: Height datums: of the lattice's z = 0 (all three) and of the DEM's heights (the last two).
DATUMS: tuple[str, ...] = ("DEM", "EGM96", "WGS84 ellipsoid")

TOP_KEYS = ("format", "name", "dem", "origin", "lattice", "power_lines", "zones", "uncertainty", "dataset")
DEM_KEYS = ("path", "crs", "vertical_datum")
ORIGIN_KEYS = ("latitude", "longitude", "heading_deg", "datum", "height_m", "geoid_separation_m")
LAYER_KEYS = ("path",)
DATASET_KEYS = ("worlds", "seed")

#: Keys of ``uncertainty`` (defaults: a mapped line stands with 0.8, tower spacing 250-400 m where the towers
#: are not all mapped, heights 40-60 m, sag 4-15 m, 1-3 conductors; registration error 10 m per axis and
#: 15 m vertically (one sigma); a zone without ``p_active`` is active with 0.5; no random zones; no power lines
#: or lone towers missing from the map, ``unmapped_lines`` / ``unmapped_towers`` [lo, hi] per world, built
#: like the mapped lines).
UNCERTAINTY_KEYS = (
    "line_probability",
    "span_m",
    "tower_height_m",
    "sag_m",
    "conductors",
    "registration_error_m",
    "height_error_m",
    "zone_probability",
    "random_zones",
    "unmapped_lines",
    "unmapped_towers",
)

#: Worlds and seed of ``drd build-dataset --site-file`` when neither the flags nor ``dataset`` say.
DEFAULT_WORLDS = 200
DEFAULT_SEED = 0


class SiteOrigin(NamedTuple):
    """The lattice origin: latitude and longitude (deg, WGS84) and the height datum of z = 0 (one of DATUMS)."""

    latitude: float
    longitude: float
    datum: str


@dataclass(frozen=True)
class Site:
    """A site file, read and converted (see the module docstring).

    Attributes:
        path: the site file (absolute).
        name: its label.
        origin: latitude, longitude and height datum of the lattice origin.
        heading_deg: compass bearing of the lattice's +x axis (deg).
        frame: the lattice frame (lattice-frame metres to and from any CRS).
        dem: the DEM's header facts (path, CRS, extent).
        corridors: the ``"corridors"`` world model's parameters in the lattice frame.
        domain_spec: the full helicopter domain spec with ``models.corridors`` set to ``corridors``.
        world_model: ``"corridors"``.
        files: every file read (absolute): the site file, the DEM, the lattice spec, the OSM and GeoJSON files.
        worlds: default number of worlds of a dataset (count).
        seed: default base seed of a dataset.
        notes: what the conversion dropped or added (one line each).
    """

    path: str
    name: str
    origin: SiteOrigin
    heading_deg: float
    frame: SiteFrame
    dem: SiteDem
    corridors: CorridorsParams
    domain_spec: dict[str, Any]
    world_model: str
    files: tuple[str, ...]
    worlds: int
    seed: int
    notes: tuple[str, ...]


def _file(value: Any, base: Path, key: str) -> Path:
    """The existing file ``value`` names (relative to ``base``)."""
    if not isinstance(value, str) or not value:
        raise SiteFileError(f"{key} must be a file path (a string), got {value!r}")
    path = (base / value).resolve()
    if not path.is_file():
        raise SiteFileError(f"{key}: file {path} not found (relative paths are read from the site file's folder)")
    return path


def _layer(data: Mapping[str, Any], key: str, base: Path) -> Path | None:
    """The file of a vector layer given as a path or as ``{path: ...}`` (None when absent)."""
    value = data.get(key)
    if value is None:
        return None
    if isinstance(value, Mapping):
        check_keys(value, LAYER_KEYS, key)
        value = value.get("path")
        return _file(value, base, f"{key}.path")
    return _file(value, base, key)


def _spec(data: Mapping[str, Any], base: Path, files: list[str]) -> dict[str, Any]:
    """The helicopter spec of ``lattice`` (a JSON file, or inline keys over an optional ``file``)."""
    value = data.get("lattice")
    if value is None:
        raise SiteFileError("lattice is required: a helicopter spec JSON file (e.g. trees/heli_lines_spec.json)")
    inline: dict[str, Any] = {}
    if isinstance(value, Mapping):
        inline = {k: v for k, v in value.items() if k != "file"}
        check_keys(inline, (*spec_keys(HelicopterParams), "file"), "lattice")
        value = value.get("file")
    spec: dict[str, Any] = {}
    if value is not None:
        path = _file(value, base, "lattice" if not inline else "lattice.file")
        text = read_bounded_text(path, 1 << 20, f"lattice spec {path}", SiteFileError)
        try:
            spec = json.loads(text)
        except (json.JSONDecodeError, RecursionError) as exc:
            raise SiteFileError(f"lattice spec {path} is not readable JSON ({exc})") from None
        if not isinstance(spec, dict):
            raise SiteFileError(f"lattice spec {path} must hold a JSON object")
        files.append(str(path))
    if isinstance(spec.get("lattice"), Mapping) and isinstance(inline.get("lattice"), Mapping):
        inline["lattice"] = {**spec["lattice"], **inline["lattice"]}
    return {**spec, **inline}


def _origin(data: Mapping[str, Any], dem_datum: str) -> tuple[SiteOrigin, SiteFrame, float | None]:
    """The origin, the lattice frame and the corridors ``datum`` (DEM height of z = 0; None: ground there)."""
    section = get_section(data, "origin", "", ORIGIN_KEYS)
    if not section:
        raise SiteFileError(f"origin is required: a mapping with keys {', '.join(ORIGIN_KEYS)}")
    where = "origin."
    frame = SiteFrame(
        get_number(section, "latitude", where),
        get_number(section, "longitude", where),
        get_number(section, "heading_deg", where, 0.0),
    )
    datum = get_string(section, "datum", where, "DEM", choices=DATUMS)
    height = get_number(section, "height_m", where, 0.0)
    separation = section.get("geoid_separation_m")
    if datum == "DEM":
        if "height_m" in section:
            raise SiteFileError("origin.height_m goes with datum EGM96 or WGS84 ellipsoid, not DEM (the ground)")
        value = None
    elif datum == dem_datum:
        value = height
    else:
        if separation is None:
            raise SiteFileError(
                f"origin.datum {datum!r} differs from dem.vertical_datum {dem_datum!r}: give "
                "origin.geoid_separation_m (WGS84 ellipsoid minus EGM96 height at the origin, e.g. -16.9 m "
                "near Boulder, Colorado), or use the DEM's datum"
            )
        n = get_number(section, "geoid_separation_m", where)
        value = height - n if datum == "WGS84 ellipsoid" else height + n
    return SiteOrigin(frame.latitude, frame.longitude, datum), frame, value


def _region(params: HelicopterParams, grow: float) -> Region:
    """The lattice's extent grown by ``grow`` metres on every side."""
    (x0, x1), (y0, y1) = params.lattice.x_range, params.lattice.y_range
    return (x0 - grow, x1 + grow), (y0 - grow, y1 + grow)


def _helicopter(spec: Mapping[str, Any]) -> HelicopterParams:
    """The validated helicopter parameters of ``spec`` (its errors as SiteFileError)."""
    try:
        return HelicopterParams.from_spec(spec)
    except ProblemError as exc:
        raise SiteFileError(f"lattice: {exc}") from None


def load_site(path: str | Path) -> Site:
    """Read the site file at ``path`` and convert it (see the module docstring).

    Raises:
        SiteFileError: the site file or a file it names is missing, too large, malformed, of an unknown format
            or CRS, off the site, or a line or zone blocks the start or goal (one line naming file and key).
    """
    file = Path(path).resolve()
    data = read_yaml_mapping(file)
    check_keys(data, TOP_KEYS, f"site file {file}")
    fmt = data.get("format")
    if fmt != SITE_FORMAT:
        raise SiteFileError(
            f"site file {file}: format must be {SITE_FORMAT!r} (the versions this drd reads), got {fmt!r}"
        )
    try:
        return _load(file, data)
    except SiteFileError as exc:
        raise SiteFileError(f"site file {file}: {exc}") from None


def _dem(data: Mapping[str, Any], base: Path) -> tuple[SiteDem, str]:
    """The DEM's header facts and the vertical datum of its heights (the ``dem`` section)."""
    section = get_section(data, "dem", "", DEM_KEYS)
    if not section:
        raise SiteFileError(f"dem is required: a mapping with keys {', '.join(DEM_KEYS)}")
    path = _file(section.get("path"), base, "dem.path")
    crs = section.get("crs")
    if crs is not None and not isinstance(crs, str):
        raise SiteFileError(f"dem.crs must be a string such as 'EPSG:4326', got {crs!r}")
    vertical = get_string(section, "vertical_datum", "dem.", "EGM96", choices=DATUMS[1:])
    return open_dem(path, crs), vertical


def _line_defaults(unc: Mapping[str, Any]) -> LineDefaults:
    """What is not known of a mapped line (the ``uncertainty`` section's line keys)."""
    return LineDefaults(
        probability=get_probability(unc, "line_probability", "uncertainty.", 0.8),
        span=get_range(unc, "span_m", "uncertainty.", (250.0, 400.0), low=1.0),
        tower_height=get_range(unc, "tower_height_m", "uncertainty.", (40.0, 60.0)),
        sag=get_range(unc, "sag_m", "uncertainty.", (4.0, 15.0)),
        conductors=_count_range(unc, "conductors", (1, 3), low=1),
    )


def _load(file: Path, data: Mapping[str, Any]) -> Site:
    """The site of the checked top level ``data`` of ``file``."""
    base = file.parent
    files = [str(file)]
    dem, vertical = _dem(data, base)
    files.append(dem.path)
    origin, frame, datum = _origin(data, vertical)
    spec = _spec(data, base, files)
    params = _helicopter(spec)
    unc = get_section(data, "uncertainty", "", UNCERTAINTY_KEYS)
    shift = get_number(unc, "registration_error_m", "uncertainty.", 10.0, low=0.0)
    terrain_region = _region(params, params.world_margin + 3.0 * shift + params.terrain_cell)
    check_covers(dem, frame, terrain_region)
    check_known_heights(dem, frame, terrain_region)
    lattice = params.lattice
    starts = [tuple(lattice.start), tuple(lattice.goal)]
    given = params_to_dict(params.model("corridors"))
    keep = (
        [(float(p[0]), float(p[1])) for p in starts],
        float(given["nofly_keep_clear"]) + params.vehicle_radius + params.margin,
    )
    region = _region(params, params.world_margin)
    notes: list[str] = []
    lines: list[dict[str, object]] = []
    zones: list[dict[str, object]] = []
    defaults = _line_defaults(unc)
    power_path = _layer(data, "power_lines", base)
    if power_path is not None:
        power = read_power(power_path)
        files.append(power.path)
        lines = known_lines(power, frame, region, defaults, keep)
        zones += mast_zones(power, frame, region, keep)
        notes.append(f"{len(power.lines)} power way(s) in {power.path} gave {len(lines)} line(s) over the site")
    zone_path = _layer(data, "zones", base)
    if zone_path is not None:
        geo = read_zones(zone_path)
        files.append(geo.path)
        zone_p = get_probability(unc, "zone_probability", "uncertainty.", 0.5)
        found = known_zones(geo, frame, region, zone_p, keep)
        notes.append(f"{len(geo.zones)} zone(s) in {geo.path} gave {len(found)} prism(s) over the site")
        zones += found
    corridors = _corridors(given, dem, frame, datum, (unc, shift, defaults), lines, zones)
    models = dict(spec.get("models") or {})
    models["corridors"] = params_to_dict(corridors)
    full = _helicopter({**spec, "models": models}).to_spec()
    dataset = get_section(data, "dataset", "", DATASET_KEYS)
    name = get_string(data, "name", "", file.parent.name or "site")
    return Site(
        path=str(file),
        name=name,
        origin=origin,
        heading_deg=frame.heading_deg,
        frame=frame,
        dem=dem,
        corridors=corridors,
        domain_spec=full,
        world_model="corridors",
        files=tuple(files),
        worlds=int(_count(dataset, "worlds", DEFAULT_WORLDS, low=1)),
        seed=int(_count(dataset, "seed", DEFAULT_SEED, low=0)),
        notes=tuple(notes),
    )


def _count(data: Mapping[str, Any], key: str, default: int, *, low: int, where: str = "dataset.") -> int:
    """The integer ``data[key]`` >= ``low`` (``default`` when absent)."""
    value = data.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise SiteFileError(f"{where}{key} must be an integer >= {low}, got {value!r}")
    return value


def _count_range(data: Mapping[str, Any], key: str, default: tuple[int, int], *, low: int) -> tuple[int, int]:
    """The integer range ``data[key]`` = [lo, hi] with ``low`` <= lo <= hi."""
    lo, hi = get_range(data, key, "uncertainty.", (float(default[0]), float(default[1])), low=float(low))
    if lo != int(lo) or hi != int(hi):
        raise SiteFileError(f"uncertainty.{key} must be whole numbers, got {[lo, hi]}")
    return int(lo), int(hi)


def _corridors(
    given: Mapping[str, Any],
    dem: SiteDem,
    frame: SiteFrame,
    datum: float | None,
    uncertainty: tuple[Mapping[str, Any], float, LineDefaults],
    lines: list[dict[str, object]],
    zones: list[dict[str, object]],
) -> CorridorsParams:
    """The corridors parameters: the spec's own keys, then the site's (DEM, frame, datum, lines, zones).

    ``uncertainty``: the site file's section, its registration error (m) and the line defaults.
    """
    unc, shift, defaults = uncertainty
    template = {
        "name": "unmapped",
        "probability": 1.0,
        "span": list(defaults.span),
        "tower_height": list(defaults.tower_height),
        "sag": list(defaults.sag),
        "conductors": list(defaults.conductors),
    }
    site_keys: dict[str, Any] = {
        "path": dem.path,
        "grid_units": dem.units,
        "site_origin": list(frame.origin_in(dem.crs)),
        "site_heading_deg": frame.heading_in(dem.crs, geographic=dem.geographic),
        "datum": datum,
        "shift_sigma": shift,
        "bias_sigma": get_number(unc, "height_error_m", "uncertainty.", 15.0, low=0.0),
        "lines": lines,
        "zones": zones,
        "nofly": _count(unc, "random_zones", 0, low=0, where="uncertainty."),
        "unmapped_lines": list(_count_range(unc, "unmapped_lines", (0, 0), low=0)),
        "unmapped_towers": list(_count_range(unc, "unmapped_towers", (0, 0), low=0)),
        "unmapped_line": template,
    }
    try:
        return CorridorsParams(**{**given, **site_keys})
    except (ProblemError, TypeError) as exc:
        raise SiteFileError(f"the site's corridors parameters are invalid: {exc}") from None
