"""The operating site of a helicopter domain: its DEM from the lattice, the datum, the registration bounds."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from drd_planner.domains.helicopter import HelicopterDomain
from drd_planner.domains.helicopter_corridors_params import CorridorsParams
from drd_planner.domains.helicopter_site import operating_site
from drd_planner.domains.planar import PlanarDomain
from drd_planner.exceptions import ProblemError


@pytest.fixture(scope="module")
def plane(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A projected 60 x 60 grid of 50 m cells: 800 m + 0.1 per metre east (metres)."""
    path = tmp_path_factory.mktemp("dem") / "plane.asc"
    _north, east = np.mgrid[0:60, 0:60] * 50.0
    rows = "\n".join(" ".join(f"{v:.4f}" for v in row) for row in (800.0 + 0.1 * east)[::-1])
    path.write_text(f"ncols 60\nnrows 60\nxllcenter 0\nyllcenter 0\ncellsize 50\n{rows}\n", encoding="ascii")
    return path


def _params(plane: Path, **values: object) -> CorridorsParams:
    base: dict[str, object] = {"path": str(plane), "grid_units": "metres", "site_origin": (1000.0, 1500.0)}
    return CorridorsParams(**{**base, "site_heading_deg": 0.0, "lines": (), "zones": (), **values})  # type: ignore[arg-type]


def test_the_site_sees_the_dem_from_the_lattice_with_z_zero_at_the_datum(plane: Path) -> None:
    domain = HelicopterDomain()
    site = operating_site(domain, name="plane", params=_params(plane))
    assert site is not None
    assert site.datum == pytest.approx(900.0)  # the DEM at the lattice origin: 800 + 0.1 * 1000
    assert site.heights(np.array([100.0]), np.array([0.0]))[0] == pytest.approx(10.0)  # x is east here
    assert site.frame == domain.frame
    assert site.registration_bound == pytest.approx((30.0 * math.sqrt(2.0), 45.0))
    north = operating_site(domain, name="plane", params=_params(plane, site_heading_deg=90.0, datum=850.0))
    assert north is not None
    assert north.datum == 850.0
    assert north.heights(np.array([0.0]), np.array([100.0]))[0] == pytest.approx(40.0)  # y points west: 0.1 down


def test_other_domains_have_no_site_and_an_origin_off_the_dem_is_refused(plane: Path) -> None:
    assert operating_site(PlanarDomain(), name="planar") is None
    with pytest.raises(ProblemError, match="lies outside the elevation grid"):
        operating_site(HelicopterDomain(), name="off", params=_params(plane, site_origin=(1e6, 0.0)))
