"""World source ``--terrain FILE``: the ``terrain`` world model cropping the user's ESRI ASCII grid.

Worlds are drawn from seeds as with ``--world-model terrain``; the flags become keys of the spec's
``models.terrain`` record (:class:`~drd_planner.domains.helicopter_world_params.TerrainParams`):

===================== ===================================================================================
flag                  spec key (``models.terrain``)
===================== ===================================================================================
``--terrain FILE``    ``path``: the grid (absolute)
``--site X,Y``        ``site``: [row, col] fractions of the grid, from (x, y) in the grid's own coordinates
                      (``row = (y - y0) / ((rows - 1) cell)``, ``col = (x - x0) / ((cols - 1) cell)``, with
                      (x0, y0) the centre of its lower-left cell)
``--site-jitter M``   ``site_jitter``: metres per axis a crop's centre may move from the site
``--crop as-is``      ``rotation_deg`` [0, 0], ``mirror`` 0, ``metres_per_cell`` [cell, cell] and ``relief``
                      null: north up, not mirrored, one source cell = the grid's own cell size (a geographic
                      grid's: its east-west metres at the site's latitude), the grid's own heights (only shifted
                      to the drawn open fraction; the default ``random`` keeps the model's random rotation,
                      mirror, scale and relief)
``--crop-scale LO,HI`` ``metres_per_cell``: metres per source cell east-west, drawn per world
===================== ===================================================================================

A geographic grid (cell size below 0.01: degrees of longitude and latitude) also sets ``cell_aspect``, how
many times longer its cells are north-south than east-west at the site's latitude (the grid's middle without
``--site``): at 40 degrees a 3-arc-second cell spans about 71 m east-west and 93 m north-south.

The flags win over the same keys in ``--domain-spec``. The grid is hashed in the building process and checked
again in every worker before it draws a world.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from typing import Any

from drd_planner.data.world_sources import (
    FileRecord,
    ResolvedSource,
    TerrainFile,
    records_from_json,
)
from drd_planner.domains.base import Domain, EdgeChecker
from drd_planner.domains.helicopter_corridors_model import metres_per_degree
from drd_planner.exceptions import DatasetError, GeometryError
from drd_planner.geometry.terrain import Heightfield, read_esri_ascii

__all__ = [
    "WORLD_MODEL",
    "TerrainWorlds",
    "geographic_cell",
    "open_worlds",
    "resolve",
    "site_fractions",
    "terrain_keys",
]

#: The world model a terrain file feeds (and the dataset's ``world_model`` field).
WORLD_MODEL = TerrainFile.world_model

#: Below this cell size a grid is taken to be geographic (degrees of longitude and latitude).
_GEOGRAPHIC_CELL = 0.01


def geographic_cell(grid: Heightfield, latitude_deg: float) -> tuple[float, float] | None:
    """(east-west metres, north-south over east-west) of a geographic grid's cell at ``latitude_deg``.

    None for a projected grid (cell size 0.01 or more: metres) or a latitude outside (-90, 90) degrees.
    """
    if float(grid.cell_size) >= _GEOGRAPHIC_CELL or not -90.0 < latitude_deg < 90.0:
        return None
    east, north = metres_per_degree(latitude_deg)
    return float(grid.cell_size) * east, north / east


def site_fractions(grid: Heightfield, site: tuple[float, float], path: str) -> list[float]:
    """[row, col] fractions of the grid at ``site`` = (x, y) in the grid's coordinates.

    Raises:
        DatasetError: the site lies outside the grid (its extent named).
    """
    rows, cols = grid.heights.shape
    x0, y0 = (float(v) for v in grid.origin)
    x1, y1 = x0 + (cols - 1) * grid.cell_size, y0 + (rows - 1) * grid.cell_size
    x, y = site
    if not (x0 <= x <= x1 and y0 <= y <= y1):
        raise DatasetError(
            f"--site {x:g},{y:g} lies outside the grid {path}: x in [{x0:g}, {x1:g}], y in [{y0:g}, {y1:g}] "
            "(cell centres, in the grid's own coordinates)"
        )
    return [(y - y0) / (y1 - y0), (x - x0) / (x1 - x0)]


def terrain_keys(request: TerrainFile, grid: Heightfield) -> dict[str, Any]:
    """The ``models.terrain`` keys the flags of ``request`` set (see the module docstring).

    Raises:
        DatasetError: a site outside the grid, or a geographic grid whose latitudes are not latitudes.
    """
    keys: dict[str, Any] = {"path": request.path}
    if request.site is not None:
        keys["site"] = site_fractions(grid, request.site, request.path)
    if request.site_jitter is not None:
        keys["site_jitter"] = float(request.site_jitter)
    _x0, _x1, y0, y1 = grid.extent
    latitude = request.site[1] if request.site is not None else 0.5 * (y0 + y1)
    geographic = geographic_cell(grid, latitude)
    if float(grid.cell_size) < _GEOGRAPHIC_CELL:
        if geographic is None:
            raise DatasetError(
                f"--terrain: {request.path} has cell size {grid.cell_size:g} (degrees?) but its y values "
                f"[{y0:g}, {y1:g}] are not latitudes in (-90, 90)"
            )
        keys["cell_aspect"] = geographic[1]
    if request.crop == "as-is":
        cell = float(grid.cell_size) if geographic is None else geographic[0]
        keys.update({"rotation_deg": [0.0, 0.0], "mirror": 0.0, "metres_per_cell": [cell, cell], "relief": None})
    if request.crop_scale is not None:
        keys["metres_per_cell"] = [float(request.crop_scale[0]), float(request.crop_scale[1])]
    return keys


def _merged(user_spec: Mapping[str, Any], keys: Mapping[str, Any]) -> dict[str, Any]:
    """``user_spec`` with ``models.terrain`` updated by ``keys``."""
    models = user_spec.get("models") or {}
    if not isinstance(models, Mapping):
        raise DatasetError(f"--domain-spec 'models' must be a JSON object, got {type(models).__name__}")
    terrain = models.get(WORLD_MODEL) or {}
    if not isinstance(terrain, Mapping):
        raise DatasetError(f"--domain-spec models.{WORLD_MODEL} must be a JSON object")
    return {**user_spec, "models": {**models, WORLD_MODEL: {**terrain, **keys}}}


def resolve(
    request: TerrainFile, domain: Domain, user_spec: Mapping[str, Any], num_worlds: int | None
) -> ResolvedSource:
    """Check the grid and the domain, and give the spec with the terrain keys.

    Raises:
        DatasetError: no ``terrain`` world model in the domain, no ``num_worlds``, an unreadable grid, a site
            outside it, or a grid in degrees whose y values are not latitudes.
    """
    if WORLD_MODEL not in domain.world_models:
        raise DatasetError(
            f"--terrain needs a domain with a {WORLD_MODEL!r} world model; domain {domain.name!r} has: "
            f"{', '.join(domain.world_models)}"
        )
    if num_worlds is None:
        raise DatasetError("--terrain draws its worlds from seeds: give their number with --worlds N")
    record = FileRecord.of(request.path, what="terrain grid")
    try:
        grid = read_esri_ascii(record.path)
    except GeometryError as exc:
        raise DatasetError(f"--terrain: {exc}") from exc
    keys = terrain_keys(request, grid)
    rows, cols = grid.heights.shape
    provenance = {
        "kind": request.kind,
        "file": record.to_json(),
        "grid": {
            "rows": rows,
            "cols": cols,
            "cell_size": float(grid.cell_size),
            "origin": grid.origin.tolist(),
        },
        "site_xy": None if request.site is None else list(request.site),
        "spec_keys": {f"models.{WORLD_MODEL}.{k}": v for k, v in keys.items()},
    }
    return ResolvedSource(
        kind=request.kind,
        world_model=WORLD_MODEL,
        num_worlds=num_worlds,
        seeded=True,
        spec=_merged(user_spec, keys),
        worker_data={"kind": request.kind, "world_model": WORLD_MODEL, "files": [record.to_json()]},
        provenance=provenance,
    )


class TerrainWorlds:
    """Seeded worlds of a model whose input files were checked against their SHA-256 when opened."""

    def __init__(self, world_model: str, records: Sequence[FileRecord]) -> None:
        for record in records:
            record.read()
        self.world_model = world_model
        self.records = tuple(records)

    def checkers(self, domain: Domain, ids: Sequence[int]) -> Iterator[EdgeChecker]:
        """The domain's checker of the world drawn with each seed in ``ids``."""
        for seed in ids:
            yield domain.checker(domain.make_world(self.world_model, int(seed)))


def open_worlds(data: Mapping[str, Any]) -> TerrainWorlds:
    """The terrain worlds of a resolved source's ``worker_data`` (the grid checked against its SHA-256)."""
    model = data.get("world_model", WORLD_MODEL)
    return TerrainWorlds(str(model), records_from_json(data))
