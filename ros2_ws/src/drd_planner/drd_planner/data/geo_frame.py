"""The lattice frame of a real site: a local east-north-up origin on the globe and the lattice's heading.

The lattice frame has its origin at (``latitude``, ``longitude``), +x along ``heading_deg`` (a compass bearing:
degrees clockwise from true north, 0 = north, 90 = east), +y 90 degrees to the left of +x, z up. Horizontal
coordinates come from pyproj: a transverse Mercator projection on the WGS84 ellipsoid centred on the origin
(scale 1; within a few kilometres of the origin its scale error is below 1e-6), then turned by the heading.

:class:`SiteFrame` converts points of any CRS pyproj knows (EPSG codes, WKT, PROJ strings) to and from the
lattice frame, and gives the origin and the lattice's heading in a grid's own CRS (what the ``"corridors"``
world model's ``site_origin`` and ``site_heading_deg`` want).

Units: metres in the lattice frame; degrees for latitude, longitude and headings.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.domains.helicopter_corridors_model import metres_per_degree
from drd_planner.exceptions import SiteFileError

__all__ = ["WGS84", "SiteFrame", "crs_of"]

#: Longitude/latitude on WGS84 (x = longitude), the CRS of OSM and GeoJSON coordinates.
WGS84 = "OGC:CRS84"


def crs_of(value: Any, what: str) -> Any:
    """The pyproj CRS of ``value`` (an EPSG code such as "EPSG:4326", WKT or a PROJ string).

    Raises:
        SiteFileError: pyproj does not know it (``what`` names where it came from).
    """
    from pyproj import CRS
    from pyproj.exceptions import CRSError

    try:
        return CRS.from_user_input(value)
    except (CRSError, TypeError, ValueError) as exc:
        raise SiteFileError(f"{what}: {value!r} is not a coordinate reference system pyproj knows ({exc})") from None


@dataclass(frozen=True)
class SiteFrame:
    """The lattice frame at (``latitude``, ``longitude``) with +x along the bearing ``heading_deg``.

    Attributes:
        latitude: origin latitude (deg, WGS84), in (-85, 85).
        longitude: origin longitude (deg, WGS84), in [-180, 180].
        heading_deg: compass bearing of the lattice's +x axis (deg clockwise from true north).
    """

    latitude: float
    longitude: float
    heading_deg: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.latitude) and -85.0 < self.latitude < 85.0):
            raise SiteFileError(f"origin latitude must be in (-85, 85) degrees, got {self.latitude!r}")
        if not (math.isfinite(self.longitude) and -180.0 <= self.longitude <= 180.0):
            raise SiteFileError(f"origin longitude must be in [-180, 180] degrees, got {self.longitude!r}")
        if not math.isfinite(self.heading_deg):
            raise SiteFileError(f"origin heading_deg must be a finite bearing in degrees, got {self.heading_deg!r}")

    def _local(self) -> str:
        """The PROJ string of the local transverse Mercator projection (east, north metres from the origin)."""
        return (
            f"+proj=tmerc +lat_0={self.latitude!r} +lon_0={self.longitude!r} +k=1 +x_0=0 +y_0=0 "
            "+ellps=WGS84 +units=m +no_defs"
        )

    def _turn(self) -> tuple[float, float]:
        """(cos, sin) of the lattice +x axis's angle counter-clockwise from east."""
        theta = math.radians(90.0 - self.heading_deg)
        return math.cos(theta), math.sin(theta)

    def to_lattice(self, x: npt.ArrayLike, y: npt.ArrayLike, crs: Any = WGS84) -> tuple[FloatArray, FloatArray]:
        """Lattice-frame (x, y) metres of points given in ``crs`` (x = longitude for geographic CRSs).

        Raises:
            SiteFileError: an unknown CRS, or points pyproj cannot project (non-finite results).
        """
        from pyproj import Transformer

        source = crs_of(crs, "points' CRS")
        to_local = Transformer.from_crs(source, self._local(), always_xy=True)
        east, north = to_local.transform(np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64))
        east, north = np.asarray(east, dtype=np.float64), np.asarray(north, dtype=np.float64)
        if not (np.isfinite(east).all() and np.isfinite(north).all()):
            raise SiteFileError(f"points in {source.name} could not be projected around the site origin")
        c, s = self._turn()
        return c * east + s * north, -s * east + c * north

    def from_lattice(self, x: npt.ArrayLike, y: npt.ArrayLike, crs: Any = WGS84) -> tuple[FloatArray, FloatArray]:
        """Points of ``crs`` (x = longitude for geographic CRSs) of lattice-frame (x, y) metres."""
        from pyproj import Transformer

        c, s = self._turn()
        lx, ly = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        east, north = c * lx - s * ly, s * lx + c * ly
        target = crs_of(crs, "target CRS")
        to_crs = Transformer.from_crs(self._local(), target, always_xy=True)
        gx, gy = to_crs.transform(east, north)
        return np.asarray(gx, dtype=np.float64), np.asarray(gy, dtype=np.float64)

    def origin_in(self, crs: Any) -> tuple[float, float]:
        """The origin's (x, y) in ``crs``."""
        gx, gy = self.from_lattice([0.0], [0.0], crs)
        return float(gx[0]), float(gy[0])

    def heading_in(self, crs: Any, *, geographic: bool, length: float = 1000.0) -> float:
        """The lattice +x axis's direction in ``crs`` (deg counter-clockwise from the grid's +x, "east").

        Measured between the origin and the point ``length`` metres along +x; a geographic grid's degrees are
        scaled by the metres per degree of longitude and latitude at the origin, as the corridors model reads
        such a grid (:func:`~drd_planner.domains.helicopter_corridors_model.metres_per_degree`).
        """
        gx, gy = self.from_lattice([0.0, length], [0.0, 0.0], crs)
        dx, dy = float(gx[1] - gx[0]), float(gy[1] - gy[0])
        if geographic:
            east, north = metres_per_degree(self.latitude)
            dx, dy = dx * east, dy * north
        return math.degrees(math.atan2(dy, dx))
