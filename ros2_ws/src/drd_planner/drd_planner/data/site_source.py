"""World source ``--site-file FILE``: the ``corridors`` world model over a real site from GIS files.

The site file (:mod:`drd_planner.data.site_file`) gives the helicopter spec with ``models.corridors`` set: the
DEM, the mapped lines and zones in the lattice frame, and the uncertainty. That spec is the default under the
user's ``--domain-spec`` (top-level keys of ``--domain-spec`` replace the site's); worlds are drawn from seeds
as with ``--world-model corridors``. The site file and every file it names are hashed (SHA-256) into the
dataset's provenance; workers check the DEM, which they read, against its hash before drawing a world.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from drd_planner.data.site_file import load_site
from drd_planner.data.terrain_source import TerrainWorlds
from drd_planner.data.world_sources import FileRecord, ResolvedSource, SiteFile, records_from_json
from drd_planner.domains.base import Domain
from drd_planner.exceptions import DatasetError

__all__ = ["WORLD_MODEL", "open_worlds", "resolve", "spec_defaults"]

#: The world model a site file feeds.
WORLD_MODEL = SiteFile.world_model

#: The domain whose spec a site file gives.
SITE_DOMAIN = "helicopter"


def spec_defaults(request: SiteFile, domain_name: str) -> Mapping[str, Any]:
    """The site's helicopter spec (``{}`` for another domain: :func:`resolve` then refuses it)."""
    return load_site(request.path).domain_spec if domain_name == SITE_DOMAIN else {}


def resolve(request: SiteFile, domain: Domain, user_spec: Mapping[str, Any], num_worlds: int | None) -> ResolvedSource:
    """Check the domain and list the site's files; the spec is the user's (already over the site's).

    Raises:
        SiteFileError: the site file or a file it names cannot be used.
        DatasetError: a domain other than the helicopter (without the ``corridors`` model).
    """
    if domain.name != SITE_DOMAIN or WORLD_MODEL not in domain.world_models:
        raise DatasetError(
            f"--site-file describes a helicopter site: use --domain {SITE_DOMAIN} (got {domain.name!r}, world "
            f"models {', '.join(domain.world_models)})"
        )
    site = load_site(request.path)
    records = [FileRecord.of(path, what="site file input") for path in site.files]
    dem = next(r for r in records if r.path == site.dem.path)
    provenance = {
        "kind": request.kind,
        "site": site.name,
        "files": [r.to_json() for r in records],
        "origin": {"latitude": site.origin.latitude, "longitude": site.origin.longitude, "datum": site.origin.datum},
        "heading_deg": site.heading_deg,
        "dem": {"path": site.dem.path, "crs": site.dem.crs, "shape": list(site.dem.shape)},
        "lines": [line.name for line in site.corridors.lines],
        "zones": [zone.name for zone in site.corridors.zones],
        "notes": list(site.notes),
    }
    return ResolvedSource(
        kind=request.kind,
        world_model=WORLD_MODEL,
        num_worlds=site.worlds if num_worlds is None else num_worlds,
        seeded=True,
        spec=dict(user_spec),
        worker_data={"kind": request.kind, "world_model": WORLD_MODEL, "files": [dem.to_json()]},
        provenance=provenance,
    )


def open_worlds(data: Mapping[str, Any]) -> TerrainWorlds:
    """The site's worlds of a resolved source's ``worker_data`` (the DEM checked against its SHA-256)."""
    return TerrainWorlds(str(data.get("world_model", WORLD_MODEL)), records_from_json(data))
