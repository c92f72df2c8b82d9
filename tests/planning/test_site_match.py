"""Terrain maps against a site prior's DEM: the site's own worlds pass, another place, datum or extent fails."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from drd_msgs_py.bags import jazzy_typestore, read_bag
from drd_msgs_py.factory import RosbagsMessages
from drd_msgs_py.terrain import cloud_from_heightfield
from drd_planner.domains.helicopter_corridors_model import CorridorsModel
from drd_planner.domains.helicopter_corridors_params import CorridorsParams
from drd_planner.domains.helicopter_site import OperatingSite
from drd_planner.domains.helicopter_world_frame import WorldFrame
from drd_planner.exceptions import DrdError
from drd_planner.geometry.terrain import Heightfield
from drd_planner.planner import load_prior
from drd_planner.planning.map_intake import terrain_from_cloud
from drd_planner.planning.map_store import MapStore, terrain_fit_of
from drd_planner.planning.prior_domain import rebuild_domain
from drd_planner.planning.prior_site import prior_site
from drd_planner.planning.site_match import HEIGHT_TOLERANCE_M, OUTLIER_FRACTION, site_mismatch

ROOT = Path(__file__).resolve().parents[2]
FRAME = WorldFrame((0.0, 600.0), (-300.0, 300.0), 60.0, 20.0, ((0.0, 0.0, 60.0), (600.0, 0.0, 60.0)), 7.0, 20.0)


@pytest.fixture(scope="module")
def hills(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A projected 100 x 100 grid of 20 m cells: 1500 m plus hills of 60 m (sines of 400 m and 700 m)."""
    path = tmp_path_factory.mktemp("dem") / "hills.asc"
    north, east = np.mgrid[0:100, 0:100] * 20.0
    heights = 1500.0 + 40.0 * np.sin(east / 400.0 * 2 * math.pi) + 20.0 * np.cos(north / 700.0 * 2 * math.pi)
    rows = "\n".join(" ".join(f"{v:.4f}" for v in row) for row in heights[::-1])  # the file lists north first
    path.write_text(f"ncols 100\nnrows 100\nxllcenter 0\nyllcenter 0\ncellsize 20\n{rows}\n", encoding="ascii")
    return path


@pytest.fixture(scope="module")
def site(hills: Path) -> OperatingSite:
    params = CorridorsParams(
        path=str(hills), grid_units="metres", site_origin=(600.0, 1000.0), site_heading_deg=30.0, lines=(), zones=()
    )
    grid = CorridorsModel().site(params)
    return OperatingSite("hills", params, grid, 1500.0, FRAME, None)


def _terrain(site: OperatingSite, dx: float = 0.0, dy: float = 0.0, bias: float = 0.0) -> Heightfield:
    """The site's DEM on the frame's grid, shifted by (dx, dy) and raised by ``bias`` metres (a world of it)."""
    xs, ys = FRAME.grid()
    gx, gy = np.meshgrid(xs, ys)
    return FRAME.heightfield(site.heights(gx + dx, gy + dy) + bias)


def test_the_sites_worlds_at_the_registration_bounds_are_the_site(site: OperatingSite) -> None:
    shift, bias = site.registration_bound
    assert (shift, bias) == pytest.approx((30.0 * math.sqrt(2.0), 45.0))  # 3 sigma of 10 m and 15 m
    assert site_mismatch(site, _terrain(site)) is None
    for sx, sy, sb in ((1, 1, 1), (1, -1, -1), (-1, 1, 1), (-1, -1, -1)):
        world = _terrain(site, sx * 30.0, sy * 30.0, sb * bias)
        assert site_mismatch(site, world) is None, (sx, sy, sb)


def test_heights_in_another_datum_are_refused_with_the_offset_and_the_allowance(site: OperatingSite) -> None:
    allowed = site.registration_bound[1] + HEIGHT_TOLERANCE_M
    assert site_mismatch(site, _terrain(site, bias=allowed - 1.0)) is None
    reason = site_mismatch(site, _terrain(site, bias=1500.0))  # above sea level, not the datum
    assert reason is not None
    assert reason.startswith("terrain is not the site of prior 'hills': median height differs by +1500 m")
    assert f"allowed {allowed:.0f} m" in reason
    assert "datum (1500.0 m of the DEM)" in reason
    low = site_mismatch(site, _terrain(site, bias=-allowed - 5.0))
    assert low is not None
    assert f"differs by {-allowed - 5.0:+.0f} m" in low


def test_another_place_at_the_same_height_is_refused_by_its_shape(site: OperatingSite) -> None:
    here = _terrain(site)
    mirrored = Heightfield(here.origin, here.cell_size, here.heights[:, ::-1].copy())
    elsewhere = _terrain(site, dx=200.0)  # 200 m off: beyond the horizontal bound
    for other in (mirrored, elsewhere):
        reason = site_mismatch(site, other)
        assert reason is not None
        assert "its shape differs from the DEM" in reason
        assert f"allowed {100 * OUTLIER_FRACTION:.0f} %" in reason


def test_a_grid_that_does_not_cover_the_lattice_is_refused_naming_both_extents(site: OperatingSite) -> None:
    here = _terrain(site)
    half = Heightfield(here.origin, here.cell_size, here.heights[:, : here.shape[1] // 2].copy())
    reason = site_mismatch(site, half)
    assert reason is not None
    assert "does not cover the lattice x [0, 600] m, y [-300, 300] m" in reason
    unknown = Heightfield(here.origin, here.cell_size, np.full(here.shape, np.nan))
    blank = site_mismatch(site, unknown)
    assert blank is not None
    assert "no height of its grid over the lattice can be compared" in blank


@pytest.fixture(scope="module")
def heli_lines() -> tuple[object, OperatingSite]:
    prior = load_prior(ROOT / "trees" / "heli_lines.npz")
    domain = rebuild_domain(prior, "heli_lines")
    found = prior_site(prior, domain)
    assert found is not None
    return domain, found


def test_the_shipped_bags_terrain_is_the_shipped_priors_site_and_a_raised_copy_is_not(
    heli_lines: tuple[object, OperatingSite],
) -> None:
    domain, site = heli_lines
    (cloud,) = [m.message for m in read_bag(ROOT / "bags" / "heli_lines.mcap") if m.topic.endswith("terrain")]
    terrain = terrain_from_cloud(cloud, frame_id="map")
    assert site_mismatch(site, terrain) is None
    raised = Heightfield(terrain.origin, terrain.cell_size, terrain.heights + 150.0)  # still under some vertices
    reason = site_mismatch(site, raised)
    assert reason is not None
    assert "median height differs by +" in reason
    # Through the map store, as the node and `drd plan --bag` apply maps: refused, the maps kept.
    rb = RosbagsMessages(jazzy_typestore())
    store = MapStore(frame_id="map", terrain_fit=terrain_fit_of([domain], [site]))  # type: ignore[list-item]
    kept = store.apply("terrain", cloud)
    assert kept is not None
    with pytest.raises(DrdError, match="not the prior's terrain: terrain is not the site of prior 'heli_lines'"):
        store.apply("terrain", cloud_from_heightfield(raised, frame_id="map", stamp=(1, 0), msgs=rb))
    assert store.snapshot is kept
    # Without the site (any other prior) the raised copy is taken: it still lies under the lattice.
    plain = MapStore(frame_id="map", terrain_fit=terrain_fit_of([domain]))  # type: ignore[list-item]
    assert plain.apply("terrain", cloud_from_heightfield(raised, frame_id="map", stamp=(1, 0), msgs=rb)) is not None
