"""The nominal world of a site prior's site and its map messages: what the map server publishes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from drd_msgs_py.bags import jazzy_typestore
from drd_msgs_py.factory import RosbagsMessages
from drd_planner.domains.helicopter_site import OperatingSite
from drd_planner.planner import load_prior
from drd_planner.planning.map_intake import obstacle_map, terrain_from_cloud
from drd_planner.planning.prior_domain import rebuild_domain
from drd_planner.planning.prior_site import prior_site
from drd_planner.planning.site_match import site_mismatch
from drd_planner.planning.site_world import TOWER_FOOTING_M, site_messages, site_world, tower_positions

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def site() -> OperatingSite:
    prior = load_prior(ROOT / "trees" / "heli_lines.npz")
    found = prior_site(prior, rebuild_domain(prior, "heli_lines"))
    assert found is not None
    return found


def test_towers_stand_on_every_route_point_and_evenly_between() -> None:
    route = np.array([[0.0, 0.0], [1000.0, 0.0], [1000.0, 300.0]])
    towers = tower_positions(route, 325.0)
    # 1000 m in 4 spans of 250 m, then 300 m in one span
    assert np.allclose(towers[:, 0], [0.0, 250.0, 500.0, 750.0, 1000.0, 1000.0])
    assert np.allclose(towers[:, 1], [0.0, 0.0, 0.0, 0.0, 0.0, 300.0])
    steps = np.linalg.norm(np.diff(towers, axis=0), axis=1)
    assert steps.max() <= 325.0


def test_the_nominal_world_holds_every_known_line_and_zone_on_the_sites_terrain(site: OperatingSite) -> None:
    world = site_world(site)
    p = site.params
    expected_towers = sum(tower_positions(np.asarray(line.route), 325.0).shape[0] for line in p.lines)
    towers = [(name, shape, pose) for name, shape, pose in world.solids if name.startswith("tower_")]
    assert len(towers) == expected_towers
    assert len(world.nofly) == len(p.zones)  # active or not, every published zone
    assert {f"nofly_{i}" for i in range(len(p.zones))} <= {name for name, _, _ in world.solids}
    # Tower tops at the middle of the height range above the DEM (no registration error).
    for _name, shape, pose in towers:
        x, y, z = (float(v) for v in pose.position)
        ground = float(site.heights(np.array([x]), np.array([y]))[0])
        top = z + shape.length / 2.0  # type: ignore[attr-defined]
        assert top - ground == pytest.approx(50.0)  # tower_height (40, 60)
        assert z - shape.length / 2.0 == pytest.approx(ground - TOWER_FOOTING_M)  # type: ignore[attr-defined]
    # Two conductors (the middle of 1-3) per span, 5 m apart.
    spans = sum(tower_positions(np.asarray(line.route), 325.0).shape[0] - 1 for line in p.lines)
    assert len(world.wires) == 2 * spans
    # The terrain is the DEM above the datum away from the start and goal pads.
    xs = world.terrain.origin[0] + world.terrain.cell_size * np.arange(world.terrain.shape[1])
    ys = world.terrain.origin[1] + world.terrain.cell_size * np.arange(world.terrain.shape[0])
    gx, gy = np.meshgrid(xs, ys)
    away = np.hypot(gx - 1250.0, gy - 1000.0) < 200.0  # the north-east ridge, far from both pads
    assert np.allclose(world.terrain.heights[away], site.heights(gx, gy)[away])
    assert site_mismatch(site, world.terrain) is None


def test_the_messages_read_back_as_the_planner_reads_maps(site: OperatingSite) -> None:
    msgs = RosbagsMessages(jazzy_typestore())
    world = site_world(site)
    markers, cloud = site_messages(site, frame_id="map", stamp=(5, 6), msgs=msgs, world=world)
    assert cloud.header.frame_id == "map"
    assert (cloud.header.stamp.sec, cloud.header.stamp.nanosec) == (5, 6)
    assert (cloud.height, cloud.width) == world.terrain.shape  # organized: one point per grid cell
    terrain = terrain_from_cloud(cloud, frame_id="map")
    assert np.allclose(terrain.heights, world.terrain.heights, atol=1e-3)  # float32 in the cloud
    assert markers.markers[0].action == 3  # DELETEALL: the whole map each time
    obstacles = obstacle_map(markers, frame_id="map")
    assert len(obstacles) == len(world.wires) + len(world.solids)
    strips = [m for m in markers.markers if m.type == 4]  # LINE_STRIP
    assert len(strips) == len(world.wires)
    assert all(len(m.points) == (site.wire_segments or 0) + 1 for m in strips)
