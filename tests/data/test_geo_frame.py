"""The lattice frame of a real site: headings, round trips through pyproj, and refused origins."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.data.geo_frame import SiteFrame, crs_of
from drd_planner.domains.helicopter_corridors_model import metres_per_degree
from drd_planner.exceptions import SiteFileError

pytest.importorskip("pyproj")


def test_heading_zero_puts_x_north_and_y_west() -> None:
    frame = SiteFrame(40.1825, -105.4617, 0.0)
    east, north = metres_per_degree(40.1825)
    x, y = frame.to_lattice(
        [-105.4617, -105.4617, -105.4617 - 1000.0 / east], [40.1825 + 1000.0 / north, 40.1825, 40.1825]
    )
    np.testing.assert_allclose(x, [1000.0, 0.0, 0.0], atol=2.0)
    np.testing.assert_allclose(y, [0.0, 0.0, 1000.0], atol=2.0)


@pytest.mark.parametrize("heading", [0.0, 37.5, 90.0, 200.0])
def test_points_go_there_and_back_in_geographic_and_projected_crs(heading: float) -> None:
    frame = SiteFrame(40.1825, -105.4617, heading)
    x = np.array([0.0, 2500.0, -300.0, 1200.0])
    y = np.array([0.0, -1000.0, 800.0, 1250.0])
    for crs in ("EPSG:4326", "EPSG:32613"):
        gx, gy = frame.from_lattice(x, y, crs)
        bx, by = frame.to_lattice(gx, gy, crs)
        np.testing.assert_allclose(bx, x, atol=1e-3)
        np.testing.assert_allclose(by, y, atol=1e-3)


def test_heading_in_a_grid_turns_with_the_bearing() -> None:
    frame = SiteFrame(40.1825, -105.4617, 0.0)
    assert frame.heading_in("EPSG:4326", geographic=True) == pytest.approx(90.0, abs=1e-6)
    east = SiteFrame(40.1825, -105.4617, 90.0)
    assert east.heading_in("EPSG:4326", geographic=True) == pytest.approx(0.0, abs=0.05)
    # UTM 13N (central meridian -105): west of it, true north leans towards grid east by the convergence,
    # about (longitude + 105) sin(latitude) degrees
    utm = frame.heading_in("EPSG:32613", geographic=False)
    assert utm == pytest.approx(90.0 + (-105.4617 + 105.0) * np.sin(np.radians(40.1825)), abs=0.01)
    ox, oy = frame.origin_in("EPSG:32613")
    assert 400_000 < ox < 500_000
    assert 4_400_000 < oy < 4_500_000


def test_bad_origins_and_crs_are_refused() -> None:
    with pytest.raises(SiteFileError, match="latitude must be in"):
        SiteFrame(91.0, 0.0)
    with pytest.raises(SiteFileError, match="longitude must be in"):
        SiteFrame(40.0, 200.0)
    with pytest.raises(SiteFileError, match="heading_deg must be a finite"):
        SiteFrame(40.0, 0.0, float("nan"))
    with pytest.raises(SiteFileError, match="not a coordinate reference system pyproj knows"):
        crs_of("EPSG:99999999", "dem.crs")
