"""Straight segments joining an off-graph state to its nearest vertices."""

from __future__ import annotations

import numpy as np

from drd_planner.core.graph import ExplicitGraph
from drd_planner.planner.straight_connector import StraightConnector


def test_segments_join_the_nearest_vertices_within_reach_at_the_resolution() -> None:
    states = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [5.0, 5.0]])
    graph = ExplicitGraph(np.array([[0, 1], [0, 2], [2, 3]]), np.array([1.0, 1.0, 6.4]), 4, False, states)
    connector = StraightConnector(neighbours=2, reach=2.0, resolution=0.1)
    state = np.array([0.4, 0.1])
    out = connector.connect(state, graph, outgoing=True)
    assert sorted(m.vertex for m in out) == [0, 1]
    for m in out:
        assert np.allclose(m.states[0], state)
        assert np.allclose(m.states[-1], states[m.vertex])
        assert np.abs(np.diff(m.states, axis=0)).max() <= 0.1 + 1e-12
        assert np.isclose(m.length, np.linalg.norm(states[m.vertex] - state))
    into = connector.connect(state, graph, outgoing=False)
    assert all(np.allclose(m.states[-1], state) for m in into)
    assert connector.connect(np.array([20.0, 20.0]), graph, outgoing=True) == []


def test_a_segment_is_sampled_at_the_resolution_both_ends_included() -> None:
    connector = StraightConnector(reach=2.0, resolution=0.1)
    line = connector.segment(np.array([0.0, 0.0]), np.array([0.35, 0.0]))
    assert connector.resolution == 0.1
    assert line.shape == (5, 2)
    assert np.allclose(line[0], 0.0)
    assert np.allclose(line[-1], [0.35, 0.0])
    assert np.linalg.norm(np.diff(line, axis=0), axis=1).max() <= 0.1
    assert connector.segment(np.zeros(2), np.zeros(2)).shape == (2, 2)
    assert connector.sampler is None


def test_the_arm_connector_carries_the_arm_sampler(small_arm: object) -> None:
    from drd_planner.domains.arm_sampler import ArmStateSampler
    from drd_planner.planner import WorldPrior
    from drd_planner.planner.connect import connector_for

    graph = small_arm.graph  # type: ignore[attr-defined]
    prior = WorldPrior(
        name="small",
        domain="arm",
        graph=graph,
        edge_costs=np.ones(graph.num_edges),
        worlds=np.ones((2, graph.num_edges), dtype=bool),
        domain_spec=small_arm.spec(),  # type: ignore[attr-defined]
    )
    connector = connector_for(prior)
    assert isinstance(connector, StraightConnector)
    assert isinstance(connector.sampler, ArmStateSampler)
    assert connector.resolution == small_arm.params.resolution  # type: ignore[attr-defined]
    broken = WorldPrior(**{**prior.__dict__, "domain_spec": {"urdf_path": "/nowhere/robot.urdf"}})
    without = connector_for(broken)  # robot files missing: states still join, the roadmap does not grow
    assert isinstance(without, StraightConnector)
    assert without.sampler is None
