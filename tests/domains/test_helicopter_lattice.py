"""Tests of the helicopter lattice: its Dubins primitives and the lattice invariants (Dubins itself: test_dubins)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.sparse import csr_array
from scipy.sparse.csgraph import breadth_first_order

from drd_planner.domains.dubins import wrap_angle
from drd_planner.domains.helicopter_lattice import HelicopterLattice, LatticeParams, build_lattice
from drd_planner.exceptions import ProblemError

R = 100.0


@pytest.fixture(scope="module")
def lattice() -> HelicopterLattice:
    return build_lattice()


# --------------------------------------------------------------------------------------------------
# Lattice invariants


def test_default_size_and_endpoints(lattice: HelicopterLattice) -> None:
    g = lattice.graph
    assert g.directed
    assert 1000 <= g.num_edges <= 3100
    assert g.vertex_states is not None
    assert g.vertex_states.shape == (g.num_vertices, 4)
    assert g.vertex_states[lattice.start].tolist() == [0.0, 0.0, 65.0, 0.0]
    assert g.vertex_states[lattice.goal].tolist() == [700.0, 0.0, 65.0, 0.0]


def test_vertices_lie_on_the_lattice(lattice: HelicopterLattice) -> None:
    states = lattice.graph.vertex_states
    assert states is not None
    assert np.allclose(np.round(states[:, :2] / 50.0) * 50.0, states[:, :2], atol=1e-9)
    assert np.all((states[:, 0] >= 0) & (states[:, 0] <= 700) & (np.abs(states[:, 1]) <= 250))
    assert set(np.round(states[:, 2], 9).tolist()) <= {40.0, 65.0, 90.0}
    steps = states[:, 3] / (math.pi / 4)
    assert np.allclose(steps, np.round(steps), atol=1e-9)
    assert np.all(np.abs(states[:, 3]) <= math.pi / 2 + 1e-9)
    assert np.unique(states, axis=0).shape[0] == states.shape[0]  # one vertex per state


def test_primitive_endpoints_land_on_lattice_states(lattice: HelicopterLattice) -> None:
    p = lattice.params
    prims = [(0, q) for q in p.axis_primitives] + [(1, q) for q in p.diagonal_primitives]
    assert len(prims) == len(lattice.primitive_paths)
    for (cls, (dx, dy, dh)), path in zip(prims, lattice.primitive_paths, strict=True):
        ex, ey, eh = path.end()  # the unsnapped Dubins end pose
        assert (ex, ey) == pytest.approx((dx * 50.0, dy * 50.0), abs=1e-9)
        assert float(wrap_angle(eh - (cls + dh) * math.pi / 4)) == pytest.approx(0.0, abs=1e-9)


def test_trajectories_join_their_end_states(lattice: HelicopterLattice) -> None:
    states = lattice.graph.vertex_states
    assert states is not None
    for e, (u, v) in enumerate(lattice.graph.edges.tolist()):
        traj = lattice.trajectory(e)
        assert traj.shape[1] == 4
        assert traj[0] == pytest.approx(states[u], abs=1e-9)
        assert traj[-1] == pytest.approx(states[v], abs=1e-9)
        # the sample before the snapped end is one step away along the unsnapped curve
        assert np.linalg.norm(traj[-1, :3] - traj[-2, :3]) <= lattice.params.sample_spacing + 1e-6


def test_sample_spacing_and_lengths(lattice: HelicopterLattice) -> None:
    spacing = lattice.params.sample_spacing
    for e in range(lattice.graph.num_edges):
        traj = lattice.trajectory(e)
        step = np.linalg.norm(np.diff(traj[:, :3], axis=0), axis=1)
        assert step.max() <= spacing + 1e-6
        polyline = step.sum()
        length = lattice.graph.lengths[e]
        # chords of arcs are slightly shorter than the arcs (relative error ~ (step / R)^2 / 24)
        assert polyline <= length + 1e-6
        assert polyline >= length * (1.0 - 1e-3)


def test_straight_edge_lengths(lattice: HelicopterLattice) -> None:
    names = lattice.primitive_names
    axis = names.index("axis(1,0,0)")
    diag = names.index("diagonal(1,1,0)")
    flat = lattice.climb == 0
    assert np.allclose(lattice.graph.lengths[(lattice.primitive == axis) & flat], 50.0)
    assert np.allclose(lattice.graph.lengths[(lattice.primitive == diag) & flat], 50.0 * math.sqrt(2))
    climbing = (lattice.primitive == diag) & ~flat
    assert climbing.any()
    assert np.allclose(lattice.graph.lengths[climbing], math.hypot(50.0 * math.sqrt(2), 25.0))


def _circumradius(p: np.ndarray) -> np.ndarray:
    a = np.linalg.norm(p[1:-1] - p[:-2], axis=1)
    b = np.linalg.norm(p[2:] - p[1:-1], axis=1)
    c = np.linalg.norm(p[2:] - p[:-2], axis=1)
    d1, d2 = p[1:-1] - p[:-2], p[2:] - p[:-2]
    cross = np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
    with np.errstate(divide="ignore"):
        return np.where(cross > 1e-12, a * b * c / (2.0 * cross), np.inf)


def test_no_turn_is_tighter_than_the_turning_radius(lattice: HelicopterLattice) -> None:
    for e in range(lattice.graph.num_edges):
        xy = lattice.trajectory(e)[:-1, :2]  # without the snapped end sample
        if xy.shape[0] >= 3:
            assert _circumradius(xy).min() >= R * (1.0 - 1e-6)


def test_quarter_turn_is_an_exact_arc_of_the_turning_radius(lattice: HelicopterLattice) -> None:
    left = lattice.primitive_names.index("axis(2,2,2)")
    states = lattice.graph.vertex_states
    assert states is not None
    edges = np.flatnonzero((lattice.primitive == left) & (lattice.climb == 0))
    assert edges.size
    for e in edges.tolist():
        u = int(lattice.graph.edges[e, 0])
        x, y, _z, h = states[u]
        centre = np.array([x - R * math.sin(h), y + R * math.cos(h)])  # left of the start heading
        traj = lattice.trajectory(e)
        assert np.linalg.norm(traj[:, :2] - centre, axis=1) == pytest.approx(np.full(traj.shape[0], R), abs=1e-6)
        assert lattice.graph.lengths[e] == pytest.approx(math.pi * R / 2, abs=1e-9)


def test_climbs_change_one_level_monotonically(lattice: HelicopterLattice) -> None:
    states = lattice.graph.vertex_states
    assert states is not None
    u, v = lattice.graph.edges[:, 0], lattice.graph.edges[:, 1]
    dz = states[v, 2] - states[u, 2]
    assert np.allclose(dz, 25.0 * lattice.climb)
    for e in np.flatnonzero(lattice.climb != 0).tolist():
        z = lattice.trajectory(e)[:, 2]
        assert np.all(np.diff(z) * lattice.climb[e] > 0)
        horizontal = np.linalg.norm(np.diff(lattice.trajectory(e)[:, :2], axis=0), axis=1).sum()
        assert 25.0 / horizontal <= lattice.params.max_climb_gradient + 1e-3


def test_directed_and_pruned_to_start_goal_paths(lattice: HelicopterLattice) -> None:
    g = lattice.graph
    lookup = {tuple(e) for e in g.edges.tolist()}
    states = g.vertex_states
    assert states is not None
    # headings only go forward: no edge has its reverse in the graph
    assert not any((v, u) in lookup for u, v in lookup)
    adjacency = csr_array((np.ones(g.num_edges), (g.edges[:, 0], g.edges[:, 1])), shape=(g.num_vertices,) * 2)
    forward = breadth_first_order(adjacency, lattice.start, directed=True, return_predecessors=False)
    backward = breadth_first_order(adjacency.T.tocsr(), lattice.goal, directed=True, return_predecessors=False)
    assert set(forward.tolist()) == set(range(g.num_vertices))
    assert set(backward.tolist()) == set(range(g.num_vertices))


def test_build_is_deterministic(lattice: HelicopterLattice) -> None:
    again = build_lattice(LatticeParams())
    assert np.array_equal(again.graph.edges, lattice.graph.edges)
    assert np.array_equal(again.points, lattice.points)
    assert np.array_equal(again.offsets, lattice.offsets)


def test_custom_small_lattice() -> None:
    small = build_lattice(LatticeParams(x_range=(0.0, 300.0), goal=(300.0, 0.0), z_levels=(50.0,), climb="none"))
    assert small.graph.num_edges > 0
    states = small.graph.vertex_states
    assert states is not None
    assert np.all(states[:, 2] == 50.0)
    assert states[small.goal].tolist() == [300.0, 0.0, 50.0, 0.0]


def test_params_round_trip_and_errors() -> None:
    params = LatticeParams(z_levels=(30.0, 60.0), max_heading_deg=180.0)
    assert LatticeParams.from_dict(params.to_dict()) == params
    with pytest.raises(ProblemError, match="unknown lattice parameters"):
        LatticeParams.from_dict({"spacing": 3})
    with pytest.raises(ProblemError, match="not on the lattice grid"):
        build_lattice(LatticeParams(start=(10.0, 0.0)))
    with pytest.raises(ProblemError, match="needs a loop"):
        build_lattice(LatticeParams(axis_primitives=((1, 0, 0), (1, 1, 2))))  # 50 m offset, 100 m radius
    with pytest.raises(ProblemError, match="climb"):
        LatticeParams(climb="sometimes")
    with pytest.raises(ProblemError, match="equally spaced"):
        LatticeParams(z_levels=(10.0, 20.0, 40.0))
    with pytest.raises(ProblemError, match="xy_spacing"):
        LatticeParams(xy_spacing=-1.0)
    with pytest.raises(ProblemError, match="not reachable"):
        build_lattice(LatticeParams(goal=(0.0, 250.0)))  # straight sideways: no forward path ends there
    with pytest.raises(ProblemError, match="out of range"):
        build_lattice().trajectory(10**6)
