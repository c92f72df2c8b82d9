"""Tests of the helicopter world models: determinism, parameters, keep-clear rules and the terrain reader."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import SHARED_DATA
from scipy.sparse import csr_array
from scipy.sparse.csgraph import breadth_first_order

from drd_planner.domains.helicopter import HelicopterDomain
from drd_planner.domains.helicopter_params import params_to_dict
from drd_planner.domains.helicopter_world_params import (
    CanyonParams,
    NoFlyZone,
    TerrainParams,
    WiresParams,
    default_terrain_path,
)
from drd_planner.domains.helicopter_worlds import WORLD_MODELS, HelicopterWorld, model_params_from_dict
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.shapes import Cylinder

TERRAIN_FILE = SHARED_DATA / "terrain" / "srtm_front_range_144.asc"


def _needs_models(model: str) -> None:
    if model in ("terrain", "corridors") and not TERRAIN_FILE.is_file():
        pytest.skip(f"shared elevation model {TERRAIN_FILE} not present (set DRD_SHARED_DATA)")


@pytest.fixture(scope="module")
def domain() -> HelicopterDomain:
    return HelicopterDomain(models={"terrain": {"path": str(TERRAIN_FILE)}})


def _same_world(a: HelicopterWorld, b: HelicopterWorld) -> bool:
    return (
        np.array_equal(a.terrain.heights, b.terrain.heights)
        and np.array_equal(a.terrain.origin, b.terrain.origin)
        and a.wires == b.wires
        and [(n, s, p) for n, s, p in a.solids] == [(n, s, p) for n, s, p in b.solids]
        and a.nofly == b.nofly
    )


@pytest.mark.parametrize("model", WORLD_MODELS)
def test_same_seed_same_world_different_seed_different_world(domain: HelicopterDomain, model: str) -> None:
    _needs_models(model)
    a, b, c = domain.make_world(model, 5), domain.make_world(model, 5), domain.make_world(model, 6)
    assert _same_world(a, b)
    assert not _same_world(a, c)
    edges = np.arange(domain.graph.num_edges)
    free_a = domain.checker(a).check_many(edges)
    assert np.array_equal(free_a, domain.checker(b).check_many(edges))
    assert not np.array_equal(free_a, domain.checker(c).check_many(edges))
    assert a.model == model
    assert a.seed == 5


@pytest.mark.parametrize("model", WORLD_MODELS)
def test_start_and_goal_are_clear_and_worlds_are_mixed(domain: HelicopterDomain, model: str) -> None:
    _needs_models(model)
    states = domain.graph.vertex_states
    assert states is not None
    ends = states[[domain.start, domain.goal], :3]
    g = domain.graph
    fractions, feasible = [], 0
    for seed in range(4):
        world = domain.make_world(model, seed)
        checker = domain.checker(world)
        assert not checker.scene.spheres_collide(ends, domain.vehicle_radius)
        free = checker.check_many(np.arange(g.num_edges))
        fractions.append(free.mean())
        kept = g.edges[free]
        adjacency = csr_array((np.ones(len(kept)), (kept[:, 0], kept[:, 1])), shape=(g.num_vertices,) * 2)
        reached = breadth_first_order(adjacency, domain.start, directed=True, return_predecessors=False)
        feasible += int(domain.goal in set(reached.tolist()))
    assert 0.15 < float(np.mean(fractions)) < 0.9
    assert feasible >= 3


def test_wires_hang_from_tower_tops(domain: HelicopterDomain) -> None:
    world = domain.make_world("wires", 2)
    towers = [(shape, pose) for name, shape, pose in world.solids if name.startswith("tower_")]
    assert towers
    assert world.wires
    tops = np.array(
        [
            pose.position + np.array([0.0, 0.0, shape.length / 2])
            for shape, pose in towers
            if isinstance(shape, Cylinder)
        ]
    )
    params = domain.model_params("wires")
    assert isinstance(params, WiresParams)
    gap = params.conductor_gap
    for wire in world.wires:
        for end in (wire.start, wire.end):
            d = np.linalg.norm(tops[:, :2] - end[:2], axis=1)
            k = int(np.argmin(d))
            assert d[k] < 1e-9
            drop = tops[k, 2] - end[2]
            assert drop == pytest.approx(round(drop / gap) * gap, abs=1e-9)
            assert drop >= -1e-9
    # every tower stands on the terrain (its base is below the ground)
    for shape, pose in towers:
        assert isinstance(shape, Cylinder)
        ground = world.terrain.height_at(pose.position[:2])[0]
        assert np.isnan(ground) or pose.position[2] - shape.length / 2 < ground


def test_canyon_valley_holds_start_and_goal(domain: HelicopterDomain) -> None:
    params = domain.model_params("canyon")
    assert isinstance(params, CanyonParams)
    for seed in range(3):
        world = domain.make_world("canyon", seed)
        floor, wall = world.info["floor"], world.info["wall"]
        assert params.floor_height[0] <= floor <= params.floor_height[1]
        h = world.terrain.height_at(np.array([[0.0, 0.0], [700.0, 0.0]]))
        assert np.all(h <= floor + 5.0)  # on the valley floor (spurs are kept away from the ends)
        assert world.terrain.heights.max() >= wall - 1e-9  # the plateau exists


def test_nofly_count_and_explicit_zones(domain: HelicopterDomain) -> None:
    states = domain.graph.vertex_states
    assert states is not None
    world = domain.make_world("wires", 1)
    assert len(world.nofly) == 2
    keep = domain.model_params("wires").nofly_keep_clear + domain.vehicle_radius + domain.margin
    for zone in world.nofly:
        for vertex in (domain.start, domain.goal):
            distance = np.hypot(*(states[vertex, :2] - np.array(zone.center)))
            assert distance - zone.footprint_radius >= keep - 1e-9
    zones = [{"shape": "prism", "center": [300, 50], "size": [60, 30], "yaw_deg": 45}, {"radius": 20.0}]
    custom = HelicopterDomain(models={"canyon": {"nofly": zones}})
    world = custom.make_world("canyon", 0)
    assert world.nofly == (
        NoFlyZone("prism", (300.0, 50.0), size=(60.0, 30.0), yaw_deg=45.0),
        NoFlyZone("cylinder", (350.0, 0.0), radius=20.0),
    )
    assert [name for name, _s, _p in world.solids] == ["nofly_0", "nofly_1"]
    inside = world.nofly[0].contains_xy(np.array([[300.0, 50.0], [300.0, 90.0]]))
    assert inside.tolist() == [True, False]


def test_model_params_round_trip_and_errors() -> None:
    for cls in (WiresParams, CanyonParams, TerrainParams):
        params = cls()
        model = {WiresParams: "wires", CanyonParams: "canyon", TerrainParams: "terrain"}[cls]
        assert model_params_from_dict(model, params_to_dict(params)) == params
    custom = WiresParams(lines=(1, 1), nofly=(NoFlyZone(radius=30.0),))
    assert model_params_from_dict("wires", params_to_dict(custom)) == custom
    with pytest.raises(ProblemError, match="unknown"):
        model_params_from_dict("wires", {"pylons": 3})
    with pytest.raises(ProblemError, match="unknown helicopter world model"):
        model_params_from_dict("ocean", {})
    with pytest.raises(ProblemError, match="lines"):
        model_params_from_dict("wires", {"lines": [3, 1]})
    with pytest.raises(ProblemError, match="nofly"):
        model_params_from_dict("canyon", {"nofly": -1})
    with pytest.raises(ProblemError, match="no-fly zone shape"):
        model_params_from_dict("canyon", {"nofly": [{"shape": "sphere"}]})
    with pytest.raises(ProblemError, match="open_fraction"):
        model_params_from_dict("terrain", {"open_fraction": [0.5, 1.5]})
    with pytest.raises(ProblemError, match="seed"):
        HelicopterDomain().make_world("wires", -1)


def _write_grid(path: Path, heights: np.ndarray, header: str) -> None:
    rows = "\n".join(" ".join(f"{v:g}" for v in row) for row in heights[::-1])  # files list rows north first
    path.write_text(header + rows + "\n", encoding="ascii")


def test_terrain_model_reads_any_esri_grid(tmp_path: Path) -> None:
    rows, cols = 120, 150
    yy, xx = np.mgrid[0:rows, 0:cols]
    heights = 300.0 + 40.0 * np.sin(xx / 9.0) * np.cos(yy / 13.0)
    heights[:5, :5] = -9999.0  # a NODATA corner
    path = tmp_path / "hills.asc"
    header = f"NCOLS {cols}\nNROWS {rows}\nXLLCENTER 5000\nYLLCENTER -2000\nCELLSIZE 30\nNODATA_value -9999\n"
    _write_grid(path, heights, header)
    domain = HelicopterDomain(models={"terrain": {"path": str(path)}})
    world = domain.make_world("terrain", 0)
    assert np.isfinite(world.terrain.heights).all()  # windows with unknown heights are redrawn
    assert world.info["path"] == str(path)
    assert np.array_equal(world.terrain.heights, domain.make_world("terrain", 0).terrain.heights)
    free = domain.checker(world).check_many(np.arange(domain.graph.num_edges))
    assert free.any()
    assert (~free).any()


def test_terrain_model_errors(tmp_path: Path) -> None:
    missing = HelicopterDomain(models={"terrain": {"path": str(tmp_path / "nope.asc")}})
    with pytest.raises(ProblemError, match=r"nope\.asc not found"):
        missing.make_world("terrain", 0)
    tiny = tmp_path / "tiny.asc"
    _write_grid(tiny, np.ones((4, 4)), "ncols 4\nnrows 4\nxllcorner 0\nyllcorner 0\ncellsize 1\n")
    with pytest.raises(ProblemError, match="no NaN-free window"):
        HelicopterDomain(models={"terrain": {"path": str(tiny)}}).make_world("terrain", 0)
    broken = tmp_path / "broken.asc"
    broken.write_text("ncols 4\nnrows 4\ncellsize 1\n1 2 3\n", encoding="ascii")
    with pytest.raises(ProblemError, match="cannot use terrain grid"):
        HelicopterDomain(models={"terrain": {"path": str(broken)}}).make_world("terrain", 0)


def test_default_terrain_path_follows_drd_shared_data(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("DRD_SHARED_DATA", str(tmp_path))
    assert default_terrain_path() == tmp_path / "terrain" / "srtm_front_range_144.asc"
    with pytest.raises(ProblemError, match="DRD_SHARED_DATA"):
        HelicopterDomain().make_world("terrain", 0)


def test_wires_on_known_line_sites_pick_a_subset_of_them() -> None:
    from drd_planner.domains.helicopter_world_params import WiresParams as _Wires

    sites = (200.0, 350.0, 500.0)
    params = _Wires(line_sites=sites, lines=(1, 3))
    domain = HelicopterDomain.from_spec({"models": {"wires": params_to_dict(params)}})
    seen: set[float] = set()
    for seed in range(12):
        lines = domain.make_world("wires", seed).info["lines"]
        xs = [line["x"] for line in lines]
        assert 1 <= len(xs) <= 3
        assert set(xs) <= set(sites)
        assert len(set(xs)) == len(xs)
        seen |= set(xs)
    assert seen == set(sites)
    with pytest.raises(ProblemError, match="line_sites"):
        _Wires(line_sites=(1.0, float("nan")))


def test_terrain_site_keeps_every_world_on_one_operating_area(tmp_path: Path) -> None:
    rows, cols = 160, 160
    yy, xx = np.mgrid[0:rows, 0:cols]
    heights = 300.0 + 40.0 * np.sin(xx / 9.0) * np.cos(yy / 13.0) + 0.5 * xx
    path = tmp_path / "hills.asc"
    _write_grid(path, heights, f"NCOLS {cols}\nNROWS {rows}\nXLLCORNER 0\nYLLCORNER 0\nCELLSIZE 30\n")
    site = {
        "path": str(path),
        "site": [0.5, 0.4],
        "site_jitter": 50.0,
        "rotation_deg": [-10, 10],
        "mirror": 0,
        "metres_per_cell": [20, 30],
    }
    domain = HelicopterDomain(models={"terrain": site})
    infos = [domain.make_world("terrain", seed).info for seed in range(12)]
    for info in infos:
        mpc = info["metres_per_cell"]
        ci, cj = info["centre_cell"]
        assert abs(ci - 0.5 * (rows - 1)) <= 50.0 / mpc + 1e-9
        assert abs(cj - 0.4 * (cols - 1)) <= 50.0 / mpc + 1e-9
        assert -10.0 <= info["rotation_deg"] <= 10.0
        assert info["flipped"] is False
        assert 20.0 <= mpc <= 30.0
    anywhere = HelicopterDomain(models={"terrain": {"path": str(path)}})
    centres = np.array([anywhere.make_world("terrain", seed).info["centre_cell"] for seed in range(12)])
    assert np.ptp(centres[:, 0]) > 20.0  # without a site the crops spread over the grid


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ({"site": [0.5]}, "site must be"),
        ({"site": [0.5, 1.5]}, "fractions must lie"),
        ({"site_jitter": -1.0}, "site_jitter"),
        ({"site_jitter": float("nan")}, "site_jitter"),
        ({"mirror": 2.0}, "mirror"),
        ({"rotation_deg": [10, -10]}, "rotation_deg"),
    ],
)
def test_terrain_site_parameters_are_validated(values: dict[str, object], message: str) -> None:
    with pytest.raises(ProblemError, match=message):
        TerrainParams(**values)  # type: ignore[arg-type]
