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
        assert np.allclose(m.states[0], state) and np.allclose(m.states[-1], states[m.vertex])
        assert np.abs(np.diff(m.states, axis=0)).max() <= 0.1 + 1e-12
        assert np.isclose(m.length, np.linalg.norm(states[m.vertex] - state))
    into = connector.connect(state, graph, outgoing=False)
    assert all(np.allclose(m.states[-1], state) for m in into)
    assert connector.connect(np.array([20.0, 20.0]), graph, outgoing=True) == []
