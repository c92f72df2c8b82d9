"""domain_view: straight edges at the check resolution, positions, one checker per latest snapshot."""

from __future__ import annotations

import numpy as np

from drd_planner.domains.base import domain_from_spec
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Box
from drd_planner.planning.domain_view import SnapshotCheckers, state_positions, straight_edge_states
from drd_planner.planning.map_state import MapSnapshot

SPEC = {"lattice": {"x_range": [0.0, 300.0], "y_range": [-100.0, 100.0], "goal": [300.0, 0.0]}}


def test_straight_edges_move_at_most_the_resolution_per_step_and_end_on_the_vertices() -> None:
    class Fine:
        resolution = 0.1

    states = straight_edge_states(Fine(), [0.0, 0.0], [0.35, -0.05])  # type: ignore[arg-type]
    assert np.allclose(states[0], [0.0, 0.0])
    assert np.allclose(states[-1], [0.35, -0.05])
    assert len(states) == 5
    assert np.max(np.abs(np.diff(states, axis=0))) <= 0.1 + 1e-12

    class Stored:
        resolution = 0.0  # edges are stored trajectories: no straight-edge sampling

    assert len(straight_edge_states(Stored(), [0.0], [5.0])) == 2  # type: ignore[arg-type]


def test_helicopter_positions_are_the_state_xyz() -> None:
    domain = domain_from_spec("helicopter", SPEC)
    states = np.array([[1.0, 2.0, 3.0, 0.5], [4.0, 5.0, 6.0, -0.5]])
    assert np.array_equal(state_positions(domain, states, 4, None), states[:, :3])


def test_one_checker_is_kept_for_the_latest_snapshot_and_answers_on_its_map() -> None:
    domain = domain_from_spec("helicopter", SPEC)
    checkers = SnapshotCheckers(domain)
    empty = MapSnapshot(0)
    assert checkers.prepare(empty) == 0.0  # nothing to prepare without maps
    edge = 0
    u = domain.graph.vertex_states[domain.graph.edges[edge, 0]]  # type: ignore[index]
    first = MapSnapshot(1, {}, None, 0.0, obstacle_map=True)
    assert checkers.prepare(first) > 0.0
    checker = checkers.checker(first)
    assert checkers.checker(first) is checker
    assert checker.check(edge)
    blocked = first.with_obstacles({"box": ((Box((40.0, 40.0, 40.0)), Pose(position=tuple(u[:3]))),)})
    assert checkers.checker(blocked) is not checker
    assert not checkers.checker(blocked).check(edge)
