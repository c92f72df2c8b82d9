"""Tests of the helicopter edge checker: hand-placed worlds with answers computed independently."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial import cKDTree

from drd_planner.domains.helicopter import HelicopterDomain
from drd_planner.domains.helicopter_checker import HelicopterChecker, helicopter_checker
from drd_planner.domains.helicopter_world_params import NoFlyZone, TerrainParams
from drd_planner.domains.helicopter_worlds import HelicopterWorld
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Box, Shape
from drd_planner.geometry.terrain import Heightfield
from drd_planner.geometry.terrain_collider import window_max
from drd_planner.geometry.wires import Wire

REACH = 7.0  # vehicle radius 5 m + margin 2 m


@pytest.fixture(scope="module")
def domain() -> HelicopterDomain:
    return HelicopterDomain()


def _world(
    domain: HelicopterDomain,
    *,
    heights: np.ndarray | float = -1000.0,
    wires: tuple[Wire, ...] = (),
    zones: tuple[NoFlyZone, ...] = (),
    solids: tuple[tuple[str, Shape, Pose], ...] = (),
) -> HelicopterWorld:
    xs, ys = domain.frame.grid()
    grid = np.broadcast_to(np.asarray(heights, dtype=np.float64), (ys.size, xs.size))
    all_solids = solids + tuple((f"nofly_{i}", *z.solid()) for i, z in enumerate(zones))
    return HelicopterWorld("custom", 0, domain.frame.heightfield(grid), wires, all_solids, zones)


def _all_free(domain: HelicopterDomain, world: HelicopterWorld) -> np.ndarray:
    return domain.checker(world).check_many(np.arange(domain.graph.num_edges))


def _edge_min(domain: HelicopterDomain, distance: np.ndarray) -> np.ndarray:
    """Per edge the minimum of a per-sample distance (P,)."""
    offsets = domain.lattice.offsets
    return np.minimum.reduceat(distance, offsets[:-1])


def _assert_matches(free: np.ndarray, min_distance: np.ndarray, threshold: float, band: float = 1e-3) -> None:
    """free == (min distance >= threshold), except for edges within ``band`` of the threshold."""
    clear = np.abs(min_distance - threshold) > band
    assert clear.mean() > 0.99
    assert np.array_equal(free[clear], min_distance[clear] >= threshold)


def test_flat_terrain_far_below_leaves_every_edge_free(domain: HelicopterDomain) -> None:
    assert _all_free(domain, _world(domain, heights=-1000.0)).all()


def test_terrain_above_everything_blocks_every_edge(domain: HelicopterDomain) -> None:
    assert not _all_free(domain, _world(domain, heights=500.0)).any()


def test_sloped_plane_terrain_matches_sphere_plane_distance(domain: HelicopterDomain) -> None:
    slope, offset = 0.1, 20.0
    xs, _ys = domain.frame.grid()
    world = _world(domain, heights=(slope * xs + offset)[None, :])
    free = _all_free(domain, world)
    pts = domain.lattice.points
    # signed distance from each sample to the plane z = slope x + offset (positive above)
    distance = (pts[:, 2] - slope * pts[:, 0] - offset) / math.sqrt(1.0 + slope**2)
    _assert_matches(free, _edge_min(domain, distance), REACH)
    assert 0.2 < free.mean() < 0.9


def test_wire_across_the_corridor_blocks_the_edges_it_crosses(domain: HelicopterDomain) -> None:
    a, b = np.array([325.0, -400.0, 65.0]), np.array([325.0, 400.0, 65.0])
    wire = Wire(a, b, sag=0.0, diameter=0.03)
    free = _all_free(domain, _world(domain, wires=(wire,)))
    pts = domain.lattice.points[:, :3]
    t = np.clip((pts - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
    distance = np.linalg.norm(pts - (a + t[:, None] * (b - a)), axis=1)
    _assert_matches(free, _edge_min(domain, distance), REACH + 0.015)
    # every flat edge at 65 m crossing x = 325 is blocked; flat edges at 40 m and 90 m all stay free
    states = domain.graph.vertex_states
    assert states is not None
    u, v = domain.graph.edges[:, 0], domain.graph.edges[:, 1]
    flat = states[u, 2] == states[v, 2]
    crosses = (states[u, 0] < 325.0) & (states[v, 0] > 325.0)
    at_65 = flat & crosses & (states[u, 2] == 65.0)
    assert at_65.any()
    assert not free[at_65].any()
    assert free[flat & (states[u, 2] != 65.0)].all()


def test_sagging_wire_is_checked_conservatively(domain: HelicopterDomain) -> None:
    wire = Wire((250.0, -300.0, 100.0), (420.0, 300.0, 95.0), sag=40.0, diameter=0.03)
    free = _all_free(domain, _world(domain, wires=(wire,)))
    curve = wire.points(8001)  # about 8 cm apart
    distance, _ = cKDTree(curve).query(domain.lattice.points[:, :3])
    # the domain's 8-capsule chain contains the wire: capsule radius 0.015 + sag / 64 around chords that are
    # themselves up to sag / 64 from the curve
    chord_gap = 2 * 40.0 / 8**2
    dmin = _edge_min(domain, distance)
    assert not free[dmin < REACH - 0.1].any()  # 0.1 m covers the sampling of the curve
    assert free[dmin > REACH + chord_gap + 0.1].all()
    assert (~free).any()
    assert free.any()


def test_nofly_cylinder_around_a_vertex_blocks_its_edges(domain: HelicopterDomain) -> None:
    states = domain.graph.vertex_states
    assert states is not None
    vertex = int(np.flatnonzero(np.all(states == [350.0, 0.0, 65.0, 0.0], axis=1))[0])
    zone = NoFlyZone("cylinder", (350.0, 0.0), radius=10.0)
    free = _all_free(domain, _world(domain, zones=(zone,)))
    incident = (domain.graph.edges[:, 0] == vertex) | (domain.graph.edges[:, 1] == vertex)
    assert incident.sum() >= 4
    assert not free[incident].any()
    pts = domain.lattice.points
    distance = np.hypot(pts[:, 0] - 350.0, pts[:, 1])
    _assert_matches(free, _edge_min(domain, distance), 10.0 + REACH)


def test_nofly_prism_matches_rectangle_distance(domain: HelicopterDomain) -> None:
    zone = NoFlyZone("prism", (200.0, 100.0), size=(40.0, 100.0), yaw_deg=30.0)
    free = _all_free(domain, _world(domain, zones=(zone,)))
    pts = domain.lattice.points
    c, s = math.cos(math.radians(30.0)), math.sin(math.radians(30.0))
    px, py = pts[:, 0] - 200.0, pts[:, 1] - 100.0
    lx, ly = c * px + s * py, -s * px + c * py
    distance = np.hypot(np.maximum(np.abs(lx) - 20.0, 0.0), np.maximum(np.abs(ly) - 50.0, 0.0))
    _assert_matches(free, _edge_min(domain, distance), REACH)
    assert (~free).any()


@pytest.mark.parametrize("model", ["wires", "canyon", "terrain"])
def test_check_many_agrees_with_check(domain: HelicopterDomain, model: str) -> None:
    terrain = domain.model_params("terrain")
    assert isinstance(terrain, TerrainParams)
    if model == "terrain" and not terrain.resolved_path().is_file():
        pytest.skip("shared elevation model not present (set DRD_SHARED_DATA)")
    world = domain.make_world(model, 3)
    checker = domain.checker(world)
    edges = np.random.default_rng(11).choice(domain.graph.num_edges, size=250, replace=False)
    many = checker.check_many(edges)
    single = np.array([checker.check(int(e)) for e in edges])
    assert np.array_equal(many, single)
    # the node-facing checker on the bare scene (no obstacle boxes, no prefilter) agrees too
    bare = helicopter_checker(checker.scene, domain)
    assert np.array_equal(bare.check_many(edges), many)
    # order, duplicates and subsets do not change answers
    again = checker.check_many(np.concatenate([edges[::-1], edges[:10]]))
    assert np.array_equal(again[:250], many[::-1])
    assert np.array_equal(again[250:], many[:10])


def test_checker_follows_scene_changes(domain: HelicopterDomain) -> None:
    checker = domain.checker(_world(domain))
    edges = np.arange(domain.graph.num_edges)
    assert checker.check_many(edges).all()
    checker.scene.add(Box((100.0, 600.0, 400.0)), Pose((350.0, 0.0, 0.0)), name="late")
    blocked = ~checker.check_many(edges)
    pts = domain.lattice.points
    inside = _edge_min(domain, np.abs(pts[:, 0] - 350.0)) < 50.0 + REACH - 1e-3
    assert np.array_equal(blocked, inside)
    assert not checker.check(int(np.flatnonzero(inside)[0]))


def test_checker_input_errors(domain: HelicopterDomain) -> None:
    checker = domain.checker(_world(domain))
    assert checker.check_many([]).shape == (0,)
    with pytest.raises(ProblemError):
        checker.check(domain.graph.num_edges)
    with pytest.raises(ProblemError):
        checker.check_many([-1])
    with pytest.raises(ProblemError):
        HelicopterChecker(Scene(), np.zeros((3, 4)), [0, 2], radius=1.0)  # offsets do not end at P
    with pytest.raises(ProblemError):
        HelicopterChecker(Scene(), np.zeros((3, 4)), [0, 3], radius=0.0)
    with pytest.raises(ProblemError):
        helicopter_checker(Scene(), object())


# --------------------------------------------------------------------------------------------------
# Terrain prefilter cost and unknown terrain (issue 19)


def test_tiny_terrain_cells_do_not_blow_up_the_prefilter() -> None:
    # 2 x 2 points 1e-5 m apart under a 6 m reach: the old window padding allocated (2 * 600_001)^2 floats.
    terrain = Heightfield((0.0, 0.0), 1e-5, [[0.0, 1.0], [2.0, 3.0]])
    scene = Scene(margin=1.0)
    scene.add_terrain(terrain)
    points = np.array([[0.0, 0.0, 100.0], [0.0, 0.0, 50.0], [0.0, 0.0, 8.0], [0.0, 0.0, 5.0]])
    checker = HelicopterChecker(scene, points, [0, 2, 4], radius=5.0)
    assert checker.check_many([0, 1]).tolist() == [True, False]  # 3 m top: 8 m centre is 5 m above it


def test_window_max_is_the_brute_force_window_maximum() -> None:
    rng = np.random.default_rng(5)
    values = rng.random((7, 11))
    values[2, 3] = -np.inf
    for half in (0, 1, 3, 12, 10**9):
        got = window_max(values, half)
        want = np.array(
            [
                [values[max(0, i - half) : i + half + 1, max(0, j - half) : j + half + 1].max() for j in range(11)]
                for i in range(7)
            ]
        )
        np.testing.assert_array_equal(got, want)


def test_a_nan_band_through_a_plateau_blocks_the_edge_across_it() -> None:
    # Issue 19 item 10: a 200 m plateau 100 m high with a 20 m unknown band across it; a plan flew along the
    # band at 50 m because unknown cells had no surface.
    heights = np.full((21, 21), 100.0)
    heights[:, 9:12] = np.nan
    ys = np.linspace(-90.0, 90.0, 41)
    low = np.stack([np.zeros(41), ys, np.full(41, 50.0)], axis=1)
    scene = Scene(margin=1.0)
    scene.add_terrain(Heightfield((-100.0, -100.0), 10.0, heights))  # the default: unknown = blocked
    checker = HelicopterChecker(scene, low, [0, 41], radius=2.0)
    assert checker.check_many([0]).tolist() == [False]
    assert checker.check(0) is False
    high = np.stack([np.zeros(41), ys, np.full(41, 120.0)], axis=1)  # above the plateau
    for unknown, free_low, free_high in (("blocked", False, False), ("highest_neighbour", False, True)):
        scene = Scene(margin=1.0)
        scene.add_terrain(Heightfield((-100.0, -100.0), 10.0, heights, unknown=unknown))  # type: ignore[arg-type]
        checker = HelicopterChecker(scene, np.concatenate([low, high]), [0, 41, 82], radius=2.0)
        assert checker.check_many([0, 1]).tolist() == [free_low, free_high]
        assert [checker.check(0), checker.check(1)] == [free_low, free_high]


def test_the_explanation_names_the_terrain_or_the_obstacle_that_blocks(domain: HelicopterDomain) -> None:
    box = ("tower_7", Box((10.0, 10.0, 100.0)), Pose((300.0, 0.0, 50.0)))
    checker = domain.checker(_world(domain, heights=20.0, solids=(box,)))
    assert checker.explain_motion(np.array([[100.0, 0.0, 65.0, 0.0]])) == ""  # free
    below = checker.explain_motion(np.array([[100.0, 0.0, 15.0, 0.0]]))
    assert below == "the terrain (below it, ground at 20.0 m) (100.0, 0.0, 15.0 m)"
    near = checker.explain_motion(np.array([[100.0, 0.0, 24.0, 0.0]]))
    assert near.startswith("the terrain (within 7 m of it, ground at 20.0 m)")
    motion = np.array([[250.0, 0.0, 65.0, 0.0], [292.0, 0.0, 65.0, 0.0], [300.0, 0.0, 65.0, 0.0]])
    assert not checker.check_motion(motion)
    assert checker.explain_motion(motion) == "obstacle 'tower_7' at sample 2 of 3 (292.0, 0.0, 65.0 m)"
