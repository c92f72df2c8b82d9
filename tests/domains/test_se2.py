"""Tests of the SE(2) domain: the state lattice against the authors' graph, the checker."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import scipy.io as sio
from conftest import gccd_folder

from drd_planner.data.gccd import load_gccd_folder
from drd_planner.domains.base import Domain, EdgeChecker, domain_from_spec
from drd_planner.domains.dubins import DubinsPath, dubins_path
from drd_planner.domains.planar_worlds import WORLD_MODELS
from drd_planner.domains.se2 import HEADING_STEP, Se2Domain, build_lattice, points_in_boxes
from drd_planner.exceptions import ProblemError

AUTHORS_V, AUTHORS_E = 3049, 7981


@pytest.fixture(scope="module")
def dom() -> Se2Domain:
    """The default SE(2) domain (built once: about 0.2 s)."""
    return Se2Domain()


def grid_key(state: np.ndarray) -> tuple[int, int, int]:
    """(ix, iy, heading index) of a lattice state."""
    return round(state[0] / 0.05), round(state[1] / 0.05), round(state[2] / HEADING_STEP) % 8


# --------------------------------------------------------------------------------------------------
# Lattice


def test_lattice_counts_against_the_authors(dom: Se2Domain) -> None:
    g = dom.graph
    # ours keeps one boundary state and its one arc that the authors' graph drops (module docstring)
    assert (g.num_vertices, g.num_edges) == (AUTHORS_V + 1, AUTHORS_E + 1)
    assert g.directed
    assert g.vertex_states is not None
    assert g.vertex_states.shape == (g.num_vertices, 3)
    assert dom.start == 0
    assert g.vertex_states[dom.start] == pytest.approx([0.05, 0.5, 0.0])
    assert g.vertex_states[dom.goal] == pytest.approx([0.95, 0.5, 0.0])
    xy = g.vertex_states[:, :2]
    assert xy.min() >= 0.0
    assert xy.max() <= 1.0
    assert np.allclose(xy / 0.05, np.round(xy / 0.05))
    assert np.allclose(g.vertex_states[:, 2] / HEADING_STEP, np.round(g.vertex_states[:, 2] / HEADING_STEP))


def test_primitives_end_on_lattice_points_and_turn_by_45_degrees(dom: Se2Domain) -> None:
    prims = dom.lattice.primitives
    assert len(prims) == 24
    for i, p in enumerate(prims):
        assert p.heading == i // 3
        turn = (p.end_heading - p.heading) % 8
        assert turn == (0, 1, 7)[i % 3]  # straight, +45 deg, -45 deg
        wp = p.waypoints
        assert wp[0] == pytest.approx([0.0, 0.0, p.heading * HEADING_STEP])
        assert wp[-1] == pytest.approx([p.offset[0] * 0.05, p.offset[1] * 0.05, p.end_heading * HEADING_STEP])
        dx, dy = p.offset
        if i % 3 == 0:
            assert (abs(dx), abs(dy)) in {(1, 0), (0, 1), (1, 1)}
            assert p.length == pytest.approx(0.05 * math.hypot(dx, dy))
        else:
            assert sorted((abs(dx), abs(dy))) == [1, 2]
            assert p.length == pytest.approx(0.1143732, abs=1e-6)
        step = np.linalg.norm(np.diff(wp[:, :2], axis=0), axis=1)
        # evenly spaced, at most 0.01
        assert step.max() <= 0.01 + 1e-12
        assert step.min() >= 0.0075
        assert wp.shape[0] == math.ceil(p.length / 0.01 - 1e-9) + 1
        heading_steps = np.abs(np.remainder(np.diff(wp[:, 2]) + math.pi, 2 * math.pi) - math.pi)
        assert heading_steps.sum() == pytest.approx(math.pi / 4 if i % 3 else 0.0, abs=1e-9)


def test_every_edge_joins_its_vertices(dom: Se2Domain) -> None:
    g = dom.graph
    states = g.vertex_states
    assert states is not None
    trajs = dom.edge_trajectories()
    assert len(trajs) == g.num_edges
    for e in range(0, g.num_edges, 13):
        u, v = g.edges[e]
        t = trajs[e]
        assert t.shape[1] == 3
        assert t[0] == pytest.approx(states[u], abs=1e-12)
        assert t[-1] == pytest.approx(states[v], abs=1e-12)
        polyline = np.linalg.norm(np.diff(t[:, :2], axis=0), axis=1).sum()
        assert polyline <= g.lengths[e] + 1e-12
        assert polyline == pytest.approx(g.lengths[e], rel=2e-3)


def test_lattice_equals_the_authors_graph_plus_one_boundary_arc(dom: Se2Domain) -> None:
    folder = gccd_folder("dataset_xyh_1")
    raw = sio.loadmat(folder / "edge_traj_list.mat")["edge_traj_list"][:, 0]
    theirs = {}
    paths: dict[tuple[int, ...], tuple[DubinsPath, np.ndarray]] = {}
    worst = 0.0
    for item in raw:
        traj = np.asarray(item["traj"], dtype=np.float64)
        key = (grid_key(traj[0]), grid_key(traj[-1]))
        theirs[key] = traj
        # our Dubins path, evaluated at their (evenly spaced) arc lengths, reproduces their waypoints
        rel = (key[0][2], key[1][0] - key[0][0], key[1][1] - key[0][1], key[1][2], traj.shape[0])
        if rel not in paths:
            h0, dx, dy, h1, count = rel
            end = (dx * 0.05, dy * 0.05, h1 * HEADING_STEP)
            path = dubins_path((0.0, 0.0, h0 * HEADING_STEP), end, radius=dom.turning_radius, headings="unsigned")
            paths[rel] = (path, path.sample(np.linspace(0.0, path.length, count)))
        path, ours_at = paths[rel]
        worst = max(worst, float(np.abs(ours_at[:, :2] + traj[0, :2] - traj[:, :2]).max()))
        assert float(item["cost"][0, 0]) == pytest.approx(path.length, abs=1e-4)  # theirs: polyline length
    assert len(theirs) == AUTHORS_E
    assert len(paths) == 24
    assert worst < 1e-9
    states = dom.graph.vertex_states
    assert states is not None
    ours = {(grid_key(states[u]), grid_key(states[v])) for u, v in dom.graph.edges}
    assert set(theirs) <= ours
    assert ours - set(theirs) == {((20, 18, 2), (19, 20, 3))}  # (1.0, 0.9, 90 deg) -> (0.95, 1.0, 135 deg)
    problem = load_gccd_folder(folder)
    assert problem.graph is not None
    assert problem.graph.num_edges == AUTHORS_E


def test_lattice_errors() -> None:
    with pytest.raises(ProblemError, match="not a lattice state"):
        build_lattice(start=(0.051, 0.5, 0.0))
    with pytest.raises(ProblemError, match="not a lattice state"):
        build_lattice(goal=(0.95, 0.5, 0.3))
    with pytest.raises(ProblemError, match="outside the bounds"):
        build_lattice(goal=(1.05, 0.5, 0.0))
    with pytest.raises(ProblemError, match="whole number"):
        build_lattice(bounds=(0.0, 0.0, 1.02, 1.0))
    with pytest.raises(ProblemError, match="not reachable"):
        build_lattice(bounds=(0.0, 0.0, 0.2, 0.2), start=(0.0, 0.0, math.pi), goal=(0.2, 0.2, 0.0))
    small = build_lattice(bounds=(0.0, 0.0, 0.5, 0.5), start=(0.1, 0.25, 0.0), goal=(0.4, 0.25, 0.0))
    assert small.graph.num_vertices < 3050
    assert small.goal > 0


# --------------------------------------------------------------------------------------------------
# Checker


def test_points_in_closed_boxes() -> None:
    boxes = np.array([[0.2, 0.2, 0.4, 0.4], [0.6, 0.0, 0.7, 1.0]])
    pts = np.array([[0.3, 0.3], [0.2, 0.4], [0.4 + 1e-9, 0.3], [0.65, 0.99], [0.5, 0.5], [0.7, 0.0]])
    assert points_in_boxes(pts, boxes).tolist() == [True, True, False, True, False, True]
    assert points_in_boxes(pts, np.zeros((0, 4))).tolist() == [False] * 6
    many = np.random.default_rng(0).random((50000, 2))
    expected = ((many[:, None, :] >= boxes[:, :2]) & (many[:, None, :] <= boxes[:, 2:])).all(axis=2).any(axis=1)
    assert np.array_equal(points_in_boxes(many, boxes), expected)


def test_checker_hand_placed_boxes(dom: Se2Domain) -> None:
    g = dom.graph
    straight = g.edge_id(dom.start, 1)  # (0.05, 0.5, 0) -> (0.10, 0.5, 0), waypoints every 0.01 in x
    assert g.vertex_states is not None
    assert g.vertex_states[1] == pytest.approx([0.1, 0.5, 0.0])
    out_of_start = [g.edge_id(dom.start, v) for v in g.edges[g.edges[:, 0] == dom.start][:, 1]]
    assert len(out_of_start) == 3
    # a box around the waypoint (0.07, 0.5) of the straight edge only
    checker = dom.checker(np.array([[0.069, 0.499, 0.071, 0.501]]))
    assert isinstance(checker, EdgeChecker)
    free = checker.check_many(np.arange(g.num_edges))
    assert not free[straight]
    assert not checker.check(straight)
    trajs = dom.edge_trajectories()
    expected = np.array(
        [not ((np.abs(t[:, 0] - 0.07) <= 0.001) & (np.abs(t[:, 1] - 0.5) <= 0.001)).any() for t in trajs]
    )
    assert np.array_equal(free, expected)
    # a thin box strictly between two waypoints of the straight edge is missed: checks are sampled
    between = dom.checker(np.array([[0.0751, 0.4, 0.0799, 0.6]]))
    assert between.check(straight)
    # a box touching a waypoint only with its boundary counts (closed boxes)
    touching = dom.checker(np.array([[0.08, 0.5, 0.2, 0.6]]))
    assert not touching.check(straight)
    # a box far from everything blocks nothing; a box over the start blocks every edge out of it
    assert dom.checker(np.array([[2.0, 2.0, 3.0, 3.0]])).check_many(np.arange(g.num_edges)).all()
    over_start = dom.checker(np.array([[0.04, 0.49, 0.06, 0.51]]))
    assert not over_start.check_many(out_of_start).any()
    with pytest.raises(ProblemError, match="edge ids"):
        checker.check_many([g.num_edges])


@pytest.mark.parametrize("model", WORLD_MODELS)
def test_checker_matches_brute_force_over_trajectories(dom: Se2Domain, model: str) -> None:
    trajs = dom.edge_trajectories()
    lengths = np.array([t.shape[0] for t in trajs])
    pts = np.concatenate(trajs)[:, :2]
    owner = np.repeat(np.arange(len(trajs)), lengths)
    edges = np.random.default_rng(3).choice(dom.graph.num_edges, size=400, replace=False)
    for seed in range(2):
        world = dom.make_world(model, seed)
        inside = ((pts[:, None, :] >= world[:, :2]) & (pts[:, None, :] <= world[:, 2:])).all(axis=2).any(axis=1)
        blocked = np.zeros(len(trajs), dtype=bool)
        np.logical_or.at(blocked, owner, inside)
        checker = dom.checker(world)
        assert np.array_equal(checker.check_many(np.arange(len(trajs))), ~blocked)
        assert np.array_equal(checker.check_many(edges), ~blocked[edges])
        assert [checker.check(int(e)) for e in edges[:20]] == (~blocked[edges[:20]]).tolist()


# --------------------------------------------------------------------------------------------------
# Domain


def test_se2_domain_protocol_and_spec_round_trip(dom: Se2Domain) -> None:
    assert isinstance(dom, Domain)
    assert dom.name == "se2"
    assert dom.world_models == WORLD_MODELS
    spec = json.loads(json.dumps(dom.spec()))
    assert spec["start_state"] == [0.05, 0.5, 0.0]
    assert spec["turning_radius"] == 0.099
    again = domain_from_spec("se2", spec)
    assert isinstance(again, Se2Domain)
    assert again == dom
    assert again.spec() == dom.spec()
    assert np.array_equal(again.graph.edges, dom.graph.edges)
    assert np.array_equal(again.make_world("bugtrap", 5), dom.make_world("bugtrap", 5))
    assert not np.array_equal(dom.make_world("bugtrap", 5), dom.make_world("bugtrap", 6))
    meta = json.loads(json.dumps(dom.check_metadata()))
    assert meta["waypoint_spacing"] == 0.01
    assert meta["vehicle"] == "point"
    with pytest.raises(ProblemError, match=r"unknown .* spec keys"):
        domain_from_spec("se2", {"radius": 0.1})
    for bad in ({"start_state": [0.05, 0.5]}, {"spacing": "x"}, {"pattern_seed": -2}, {"keep_clear": "no"}):
        with pytest.raises(ProblemError):
            domain_from_spec("se2", bad)


def test_se2_keep_clear(dom: Se2Domain) -> None:
    clear = Se2Domain(keep_clear=True)
    for s in range(60):
        w = clear.make_world("bugtrap", s)
        for x, y in ((0.05, 0.5), (0.95, 0.5)):
            assert not ((w[:, 0] <= x) & (x <= w[:, 2]) & (w[:, 1] <= y) & (y <= w[:, 3])).any()


@pytest.mark.parametrize(
    ("model", "folder"),
    [
        ("one_wall", "dataset_xyh_1"),
        ("moving_wall", "dataset_xyh_3"),
        ("baffle", "dataset_xyh_4"),
        ("bugtrap", "dataset_xyh_5"),
    ],
)
def test_free_edge_fraction_matches_the_authors(dom: Se2Domain, model: str, folder: str) -> None:
    theirs = load_gccd_folder(gccd_folder(folder)).require_worlds().X.mean()
    all_edges = np.arange(dom.graph.num_edges)
    ours = np.mean([dom.checker(dom.make_world(model, s)).check_many(all_edges).mean() for s in range(30)])
    # measured with 100 worlds: 0.645 / 0.642, 0.781 / 0.775, 0.784 / 0.778, 0.820 / 0.808
    assert ours == pytest.approx(theirs, abs=0.04)
