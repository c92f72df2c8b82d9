"""Tests of the corridors world model: registered terrain, known lines and zones, keep-clear refusals."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from drd_planner.domains.helicopter_corridors_model import CorridorsModel, metres_per_degree
from drd_planner.domains.helicopter_corridors_params import CorridorsParams, KnownLine, KnownZone
from drd_planner.domains.helicopter_world_frame import WorldFrame
from drd_planner.exceptions import ProblemError

#: Slopes (metres per metre east, north) of the synthetic planar DEM.
SLOPE = (0.1, 0.05)
FRAME = WorldFrame((0.0, 300.0), (-150.0, 150.0), 50.0, 25.0, ((0.0, 0.0, 65.0), (300.0, 0.0, 65.0)), 7.0, 40.0)


@pytest.fixture(scope="module")
def plane(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A projected 80 x 80 grid of 50 m cells: 1000 m + 0.1 east + 0.05 north (metres)."""
    path = tmp_path_factory.mktemp("dem") / "plane.asc"
    north, east = np.mgrid[0:80, 0:80] * 50.0
    heights = 1000.0 + SLOPE[0] * east + SLOPE[1] * north
    rows = "\n".join(" ".join(f"{v:.4f}" for v in row) for row in heights[::-1])  # the file lists north first
    path.write_text(f"ncols 80\nnrows 80\nxllcenter 0\nyllcenter 0\ncellsize 50\n{rows}\n", encoding="ascii")
    return path


def _params(plane: Path, **values: Any) -> CorridorsParams:
    base: dict[str, Any] = {
        "path": str(plane),
        "grid_units": "metres",
        "site_origin": (2000.0, 2000.0),
        "site_heading_deg": 0.0,
        "lines": (),
        "zones": (),
    }
    return CorridorsParams(**{**base, **values})


def _grid() -> tuple[np.ndarray, np.ndarray]:
    xs, ys = FRAME.grid()
    return np.meshgrid(xs, ys)


def test_terrain_is_the_dem_at_its_true_scale_seen_from_the_site(plane: Path) -> None:
    gx, gy = _grid()
    exact = _params(plane, shift_sigma=0.0, bias_sigma=0.0)
    draw = CorridorsModel().draw(np.random.default_rng(0), exact, FRAME)
    assert np.allclose(draw.terrain.heights, SLOPE[0] * gx + SLOPE[1] * gy, atol=1e-6)
    assert draw.info["datum"] == pytest.approx(1000.0 + 2000.0 * (SLOPE[0] + SLOPE[1]))
    north = _params(plane, shift_sigma=0.0, bias_sigma=0.0, site_heading_deg=90.0, datum=1290.0)
    turned = CorridorsModel().draw(np.random.default_rng(0), north, FRAME)
    # x points north and y west: the ground rises 0.05 per metre of x and falls 0.1 per metre of y
    expected = 10.0 + SLOPE[1] * gx - SLOPE[0] * gy
    assert np.allclose(turned.terrain.heights, expected, atol=1e-6)


def test_registration_error_shifts_and_lifts_the_dem(plane: Path) -> None:
    gx, gy = _grid()
    params = _params(plane, shift_sigma=20.0, bias_sigma=6.0, keep_clear_radius=1.0, ground_gap=0.0)
    seen = []
    for seed in range(30):
        draw = CorridorsModel().draw(np.random.default_rng(seed), params, FRAME)
        reg = draw.info["registration"]
        far = np.hypot(gx, gy) > 2.0
        far &= np.hypot(gx - 300.0, gy) > 2.0
        moved = SLOPE[0] * (gx + reg["dx"]) + SLOPE[1] * (gy + reg["dy"]) + reg["bias"]
        assert np.allclose(draw.terrain.heights[far], moved[far], atol=1e-6)
        assert abs(reg["dx"]) <= 60.0
        assert abs(reg["dy"]) <= 60.0
        assert abs(reg["bias"]) <= 18.0
        seen.append((reg["dx"], reg["bias"]))
    spread = np.std(np.asarray(seen), axis=0)
    assert 10.0 < spread[0] < 30.0
    assert 3.0 < spread[1] < 9.0


def test_a_present_line_stands_on_the_true_ground_along_its_route(plane: Path) -> None:
    line = KnownLine(
        name="l", route=((150.0, -150.0), (150.0, 150.0)), probability=1.0, span=(100.0, 100.0),
        tower_height=(30.0, 30.0), sag=(5.0, 5.0), conductors=(2, 2),
    )  # fmt: skip
    params = _params(plane, shift_sigma=0.0, bias_sigma=0.0, tower_jitter=0.0, lines=(line,))
    draw = CorridorsModel().draw(np.random.default_rng(1), params, FRAME)
    towers = [(name, pose) for name, _shape, pose in draw.solids if name.startswith("tower_l_")]
    assert len(towers) == 4  # 300 m of route, towers at most 100 m apart
    assert len(draw.wires) == 3 * 2
    assert {w.sag for w in draw.wires} == {5.0}
    tops = sorted(max(w.start[2], w.end[2]) for w in draw.wires)
    ground_top = SLOPE[0] * 150.0 + SLOPE[1] * 150.0 + 30.0  # the northern tower
    assert tops[-1] == pytest.approx(ground_top)
    assert draw.info["lines"][0]["present"] is True


def test_presence_and_activity_follow_their_probabilities_independently(plane: Path) -> None:
    lines = (
        KnownLine(name="half", route=((150.0, -150.0), (150.0, 150.0)), probability=0.5),
        KnownLine(name="never", route=((220.0, -150.0), (220.0, 150.0)), probability=0.0),
    )
    zones = (
        KnownZone(name="always", center=(150.0, 100.0), radius=20.0, probability=1.0),
        KnownZone(name="coin", center=(150.0, -100.0), radius=20.0, probability=0.5),
    )
    params = _params(plane, lines=lines, zones=zones)
    model = CorridorsModel()
    present, active = [], []
    for seed in range(200):
        draw = model.draw(np.random.default_rng(seed), params, FRAME)
        present.append([line["present"] for line in draw.info["lines"]])
        active.append([zone["active"] for zone in draw.info["zones"]])
        assert not any(name.startswith("tower_never") for name, _s, _p in draw.solids)
        assert draw.nofly[0].center == (150.0, 100.0)
        assert type(draw.nofly[0]).__name__ == "NoFlyZone"
        assert len(draw.nofly) == 1 + int(active[-1][1])
    rate = np.mean(np.asarray(present, dtype=float), axis=0)
    assert 0.38 < rate[0] < 0.62
    assert rate[1] == 0.0
    assert 0.38 < np.mean([a[1] for a in active]) < 0.62
    # the second line's draws do not depend on whether the first one is present
    flipped = _params(plane, lines=(KnownLine(**{**vars(lines[0]), "probability": 1.0}), lines[1]), zones=zones)
    a = model.draw(np.random.default_rng(7), params, FRAME).info["lines"][1]
    b = model.draw(np.random.default_rng(7), flipped, FRAME).info["lines"][1]
    assert a == b


def test_taps_need_their_line_and_grouped_zones_switch_together(plane: Path) -> None:
    lines = (
        KnownLine(name="trunk", route=((150.0, -150.0), (150.0, 150.0)), probability=0.5),
        KnownLine(name="tap", route=((220.0, -150.0), (220.0, -80.0)), probability=0.9, requires="trunk"),
    )
    zones = (
        KnownZone(name="a", center=(150.0, 100.0), radius=20.0, probability=0.5, group="exercise"),
        KnownZone(name="b", center=(150.0, -100.0), radius=20.0, probability=0.5, group="exercise"),
    )
    params = _params(plane, lines=lines, zones=zones)
    model = CorridorsModel()
    taps, states = [], []
    for seed in range(200):
        info = model.draw(np.random.default_rng(seed), params, FRAME).info
        trunk, tap = (line["present"] for line in info["lines"])
        assert trunk or not tap
        taps.append(tap)
        a, b = (zone["active"] for zone in info["zones"])
        assert a == b
        states.append(a)
    assert 0.3 < np.mean(taps) < 0.6
    assert 0.38 < np.mean(states) < 0.62


def test_same_seed_same_draw(plane: Path) -> None:
    params = _params(plane, lines=(KnownLine(name="l", route=((150.0, -150.0), (160.0, 150.0))),))
    one = CorridorsModel().draw(np.random.default_rng(4), params, FRAME)
    two = CorridorsModel().draw(np.random.default_rng(4), params, FRAME)
    assert np.array_equal(one.terrain.heights, two.terrain.heights)
    assert one.info == two.info
    assert one.wires == two.wires


@pytest.mark.parametrize(
    ("values", "match"),
    [
        ({"lines": (KnownLine(name="pad", route=((-50.0, -50.0), (50.0, 50.0))),)}, "known line 'pad'"),
        ({"zones": (KnownZone(name="z", center=(300.0, 60.0), radius=30.0),)}, "known no-fly zone 'z'"),
        ({"site_origin": (100.0, 100.0)}, "leaves the elevation grid"),
        ({"site_origin": (-500.0, 100.0)}, "outside the elevation grid"),
        (
            {"lines": (KnownLine(name="far", route=((150.0, 0.0), (150.0, 9000.0)), probability=1.0),)},
            "outside the elevation",
        ),
    ],
)
def test_refusals_name_what_to_change(plane: Path, values: dict[str, Any], match: str) -> None:
    params = _params(plane, **values)
    with pytest.raises(ProblemError, match=match):
        CorridorsModel().draw(np.random.default_rng(0), params, FRAME)


def test_metres_per_degree() -> None:
    east, north = metres_per_degree(40.0)
    assert east == pytest.approx(85_394.0, rel=1e-3)
    assert north == pytest.approx(111_035.0, rel=1e-3)
    assert metres_per_degree(0.0)[0] == pytest.approx(111_320.0, rel=1e-3)
    assert math.isclose(metres_per_degree(90.0)[0], 0.0, abs_tol=1.0)


def test_the_real_scale_preset_is_big_and_keeps_its_start_and_goal_clear() -> None:
    from conftest import REPO_ROOT, SHARED_DATA

    from drd_planner.domains.helicopter import HelicopterDomain
    from drd_planner.domains.helicopter_lattice import LatticeParams

    if not (SHARED_DATA / "terrain" / "srtm_front_range_144.asc").is_file():
        pytest.skip(f"shared elevation model not present under {SHARED_DATA} (set DRD_SHARED_DATA)")
    spec = json.loads((REPO_ROOT / "trees" / "heli_lines_spec.json").read_text(encoding="utf-8"))
    domain = HelicopterDomain.from_spec(spec)
    lattice, default = domain.params.lattice, LatticeParams()
    assert domain.graph.num_edges >= 10_000
    assert np.ptp(lattice.x_range) >= 2000.0
    assert np.ptp(lattice.y_range) >= 2000.0
    assert len(lattice.z_levels) > len(default.z_levels)
    assert lattice.max_heading_deg > default.max_heading_deg
    states = domain.graph.vertex_states
    assert states is not None
    assert np.unique(np.round(states[:, 3], 6)).size == 8  # every heading
    ends = states[[domain.start, domain.goal], :3]
    for seed in range(3):
        world = domain.make_world("corridors", seed)
        assert not domain.checker(world).scene.spheres_collide(ends, domain.vehicle_radius)
        assert world.info["datum"] > 2000.0  # metres above sea level: the real grid at its true heights


def test_the_shipped_lines_prior_walks_its_tree_on_a_corridors_world() -> None:
    from conftest import REPO_ROOT, SHARED_DATA

    from drd_planner.domains.base import domain_from_spec
    from drd_planner.planner import Planner, load_prior

    if not (SHARED_DATA / "terrain" / "srtm_front_range_144.asc").is_file():
        pytest.skip(f"shared elevation model not present under {SHARED_DATA} (set DRD_SHARED_DATA)")
    path = REPO_ROOT / "trees" / "heli_lines.npz"
    prior = load_prior(path)
    spec = json.loads((REPO_ROOT / "trees" / "heli_lines_spec.json").read_text(encoding="utf-8"))
    assert prior.domain == "helicopter"
    assert prior.domain_spec["lattice"]["z_levels"] == spec["lattice"]["z_levels"]
    domain = domain_from_spec(prior.domain, prior.domain_spec)
    assert np.array_equal(domain.graph.edges, prior.graph.edges)
    own = prior.trees[0]
    assert (own.start, own.goal) == (domain.start, domain.goal)
    # the tree does not hand over at its root
    assert own.leaf is not None
    assert own.leaf.eta < 1.0
    result = Planner(prior).plan(domain.start, domain.goal, domain.checker(domain.make_world("corridors", 6)))
    assert result.found
    stages = [check.stage for check in result.checks]
    assert stages[0] == "tree"
    assert "bisect" in stages


def test_a_geotiff_dem_gives_the_same_worlds_as_its_ascii_grid_and_its_crs_must_match_grid_units(
    plane: Path, tmp_path: Path
) -> None:
    pytest.importorskip("rasterio")
    from drd_planner.geometry.geotiff import write_geotiff
    from drd_planner.geometry.terrain import read_esri_ascii

    tif = tmp_path / "plane.tif"
    write_geotiff(tif, read_esri_ascii(plane), "EPSG:32613")
    from_asc = CorridorsModel().draw(np.random.default_rng(4), _params(plane), FRAME)
    from_tif = CorridorsModel().draw(np.random.default_rng(4), _params(tif), FRAME)
    np.testing.assert_allclose(from_tif.terrain.heights, from_asc.terrain.heights, atol=1e-3)  # float32 pixels
    with pytest.raises(ProblemError, match=r"is measured in metres \(its CRS\) but models\.corridors\.grid_units"):
        CorridorsModel().site(_params(tif, grid_units="degrees", site_origin=(-105.0, 40.0)))


def test_unmapped_lines_and_towers_cross_the_lattice_clear_of_the_start_and_goal(plane: Path) -> None:
    template = {
        "name": "u",
        "span": [60.0, 60.0],
        "tower_height": [25.0, 25.0],
        "sag": [3.0, 3.0],
        "conductors": [1, 1],
    }
    params = _params(plane, unmapped_lines=(1, 2), unmapped_towers=(2, 2), unmapped_line=template, tower_jitter=0.0)
    assert params.unmapped_line.tower_height == (25.0, 25.0)
    need = params.nofly_keep_clear + FRAME.clearance
    counts = set()
    for seed in range(25):
        draw = CorridorsModel().draw(np.random.default_rng(seed), params, FRAME)
        unmapped = draw.info["unmapped"]
        counts.add(len(unmapped["lines"]))
        assert len(unmapped["towers"]) == 2
        for route in unmapped["lines"]:
            ends = np.asarray(route)
            assert np.all((ends[:, 0] >= -1e-6) & (ends[:, 0] <= 300.0 + 1e-6))
            assert np.all((ends[:, 1] >= -150.0 - 1e-6) & (ends[:, 1] <= 150.0 + 1e-6))
            a, b = ends
            for point in ((0.0, 0.0), (300.0, 0.0)):
                t = np.clip(np.dot(np.asarray(point) - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0)
                assert np.hypot(*(a + t * (b - a) - point)) >= need
        for x, y, height in unmapped["towers"]:
            assert min(np.hypot(x, y), np.hypot(x - 300.0, y)) >= need
            assert height == 25.0
        names = [name for name, _s, _p in draw.solids]
        assert sum(n.startswith("tower_lone_") for n in names) == 2
        assert len(draw.wires) == sum(
            sum(n.startswith(f"tower_unmapped_line_{k}_") for n in names) - 1 for k in range(len(unmapped["lines"]))
        )
    assert counts == {1, 2}


def test_without_unmapped_obstacles_a_seed_draws_what_it_drew_before(plane: Path) -> None:
    line = KnownLine(name="l", route=((150.0, -150.0), (150.0, 150.0)), probability=0.5)
    plain = CorridorsModel().draw(np.random.default_rng(9), _params(plane, lines=(line,)), FRAME)
    assert "unmapped" not in plain.info
    more = CorridorsModel().draw(np.random.default_rng(9), _params(plane, lines=(line,), unmapped_towers=(1, 1)), FRAME)
    assert more.info["lines"] == plain.info["lines"]
    assert more.info["registration"] == plain.info["registration"]
    assert len(more.solids) == len(plain.solids) + 1
