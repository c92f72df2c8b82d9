"""Helicopter motions joining off-lattice states: flyable Dubins curves ahead of the state, altitude linear."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drd_planner.core.graph import ExplicitGraph
from drd_planner.domains.dubins import dubins_lengths, dubins_path, path_to_point, point_lengths
from drd_planner.domains.helicopter_lattice import LatticeParams, build_lattice
from drd_planner.planner.dubins_connector import DubinsConnector, LatticeExtent
from drd_planner.planner.endpoints import QueryError

RADIUS = 100.0


@pytest.fixture(scope="module")
def lattice_graph() -> ExplicitGraph:
    return build_lattice(LatticeParams()).graph


def _connector(graph: ExplicitGraph, k: int = 8) -> DubinsConnector:
    return DubinsConnector(
        turning_radius=RADIUS,
        spacing=5.0,
        max_climb_gradient=0.5,
        neighbours=k,
        extent=LatticeExtent.of_graph(graph),
    )


def test_vectorised_lengths_equal_the_verified_paths() -> None:
    rng = np.random.default_rng(0)
    starts = rng.uniform([-300, -300, -math.pi], [300, 300, math.pi], (300, 3))
    ends = rng.uniform([-300, -300, -math.pi], [300, 300, math.pi], (300, 3))
    fast = dubins_lengths(starts, ends, radius=RADIUS)
    slow = [dubins_path(tuple(s), tuple(e), radius=RADIUS).length for s, e in zip(starts, ends, strict=True)]
    assert np.allclose(fast, slow, atol=1e-9)


def test_paths_to_a_point_end_there_and_are_never_longer_than_with_a_fixed_heading() -> None:
    rng = np.random.default_rng(1)
    reached = 0
    for start, point in zip(rng.uniform(-300, 300, (200, 3)), rng.uniform(-300, 300, (200, 2)), strict=True):
        path = path_to_point((start[0], start[1], start[2]), (point[0], point[1]), radius=RADIUS)
        length = point_lengths(start, point, radius=RADIUS)[0]
        if path is None:  # inside both turning circles
            assert math.isinf(length)
            continue
        reached += 1
        x, y, heading = path.end()
        assert math.hypot(x - point[0], y - point[1]) < 1e-6
        assert path.length == pytest.approx(length)
        fixed = dubins_path((start[0], start[1], start[2]), (point[0], point[1], heading), radius=RADIUS)
        assert path.length <= fixed.length + 1e-6
    assert reached > 150


def test_an_off_lattice_start_joins_vertices_ahead_by_flyable_motions(lattice_graph: ExplicitGraph) -> None:
    states = lattice_graph.vertex_states
    assert states is not None
    connector = _connector(lattice_graph)
    start = np.array([213.0, 37.0, 71.0, 0.3])  # between lattice points, levels and headings
    motions = connector.connect(start, lattice_graph, outgoing=True)
    assert len(motions) == 8
    for m in motions:
        end = states[m.vertex]
        assert np.allclose(m.states[0], start)
        assert np.allclose(m.states[-1], end)
        assert np.linalg.norm(np.diff(m.states[:, :2], axis=0), axis=1).max() <= 5.0 + 1e-9
        horizontal = dubins_path((start[0], start[1], start[3]), (end[0], end[1], end[3]), radius=RADIUS).length
        assert abs(end[2] - start[2]) <= 0.5 * horizontal + 1e-9  # the climb limit
        assert m.length == pytest.approx(math.hypot(horizontal, end[2] - start[2]))
        assert end[0] > start[0]  # ahead of a state flying east-north-east
    lengths = [m.length for m in motions]
    assert lengths == sorted(lengths)
    # the shortest motions of all vertices: no vertex outside the set has a shorter flyable motion
    poses = states[:, [0, 1, 3]]
    all_lengths = dubins_lengths(start[[0, 1, 3]], poses, radius=RADIUS)
    climbable = np.abs(states[:, 2] - start[2]) <= 0.5 * all_lengths
    best = np.sort(np.hypot(all_lengths, states[:, 2] - start[2])[climbable])[:8]
    assert np.allclose(lengths, best)


def test_a_goal_joins_from_vertices_behind_it_with_or_without_a_heading(lattice_graph: ExplicitGraph) -> None:
    states = lattice_graph.vertex_states
    assert states is not None
    connector = _connector(lattice_graph, k=6)
    goal = np.array([480.0, -30.0, 60.0, math.pi / 2])
    into = connector.connect(goal, lattice_graph, outgoing=False)
    assert len(into) == 6
    for m in into:
        assert np.allclose(m.states[-1], goal)
        assert np.allclose(m.states[0], states[m.vertex])
    free = np.array([480.0, -30.0, 60.0, np.nan])
    any_heading = connector.connect(free, lattice_graph, outgoing=False)
    assert len(any_heading) == 6
    for m in any_heading:
        assert np.allclose(m.states[-1, :3], free[:3])
        assert np.isfinite(m.states).all()
    assert min(m.length for m in any_heading) <= min(m.length for m in into) + 1e-9
    with pytest.raises(QueryError, match="needs a heading"):
        connector.connect(free, lattice_graph, outgoing=True)


def test_states_outside_the_extent_are_refused_with_the_extent(lattice_graph: ExplicitGraph) -> None:
    connector = _connector(lattice_graph)
    with pytest.raises(QueryError, match=r"horizontal extent x \[0, 700\] m, y \[-250, 250\] m"):
        connector.connect(np.array([4000.0, 0.0, 65.0, 0.0]), lattice_graph, outgoing=True)
    with pytest.raises(QueryError, match=r"altitude 300.0 m is outside the lattice's altitude band \[40, 90\] m"):
        connector.connect(np.array([100.0, 0.0, 300.0, 0.0]), lattice_graph, outgoing=False)
    inside = connector.connect(np.array([-20.0, 0.0, 35.0, 0.0]), lattice_graph, outgoing=True)  # within margins
    assert inside


def test_motions_to_any_ranked_vertices_follow_the_ranking(lattice_graph: ExplicitGraph) -> None:
    connector = _connector(lattice_graph, k=6)
    start = np.array([150.0, -40.0, 50.0, 2.8])  # flying west in an east-going lattice: joins need turns
    ranked = connector.ranked(start, lattice_graph, outgoing=True)
    first = connector.connect(start, lattice_graph, outgoing=True)
    then = connector.motions_to(start, lattice_graph, ranked[6:16], outgoing=True)
    assert [m.vertex for m in first + then] == ranked[:16].tolist()
    assert [m.length for m in first + then] == sorted(m.length for m in first + then)
    assert len(set(ranked.tolist())) == ranked.size  # every vertex once
    assert connector.motions_to(start, lattice_graph, ranked[:0], outgoing=True) == []


@pytest.mark.parametrize(
    ("state", "outgoing"),
    [
        (np.array([212.0, 33.0, 60.0, 2.9]), True),
        (np.array([212.0, 33.0, 60.0, -0.7]), False),
        (np.array([212.0, 33.0, 60.0, np.nan]), False),
    ],
)
def test_sketches_lie_on_the_motions_they_stand_for(
    lattice_graph: ExplicitGraph, state: np.ndarray, outgoing: bool
) -> None:
    connector = _connector(lattice_graph)
    vertices = connector.ranked(state, lattice_graph, outgoing=outgoing)[:40]
    fractions = np.linspace(0.0, 1.0, 5)
    lengths, points = connector.sketches(state, lattice_graph, vertices, outgoing=outgoing, fractions=fractions)
    motions = connector.motions_to(state, lattice_graph, vertices, outgoing=outgoing)
    assert points.shape == (vertices.size, 5, 3)
    assert len(motions) == vertices.size
    assert np.allclose(lengths, [m.length for m in motions], atol=1e-6)
    for motion, sketch in zip(motions, points, strict=True):
        assert np.allclose(sketch[[0, -1]], motion.states[[0, -1], :3], atol=1e-6)
        if math.isfinite(state[3]):  # the sketch is on the flown curve (a free heading's is the chord)
            gaps = np.linalg.norm(motion.states[:, None, :3] - sketch[None, :, :], axis=2).min(axis=0)
            assert gaps.max() < 5.0  # within one sample spacing of the motion's samples
