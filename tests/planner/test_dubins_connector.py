"""Helicopter motions joining off-lattice states: Dubins curves of the turning radius, altitude linear."""

from __future__ import annotations

import numpy as np

from drd_planner.planner.dubins_connector import DubinsConnector


def test_dubins_motions_join_state_and_vertex() -> None:
    from drd_planner.core.graph import ExplicitGraph

    states = np.array([[0.0, 0.0, 65.0, 0.0], [50.0, 0.0, 65.0, 0.0], [100.0, 0.0, 90.0, 0.0]])
    graph = ExplicitGraph(np.array([[0, 1], [1, 2]]), np.array([50.0, 56.0]), 3, True, states)
    connector = DubinsConnector(turning_radius=100.0, reach=120.0, spacing=5.0, max_climb_gradient=0.5)
    start = np.array([-40.0, 5.0, 60.0, 0.1])
    motions = connector.connect(start, graph, outgoing=True)
    assert motions
    for m in motions:
        assert np.allclose(m.states[0], start)
        assert np.allclose(m.states[-1, :3], states[m.vertex, :3], atol=1e-6)
        step = np.linalg.norm(np.diff(m.states[:, :2], axis=0), axis=1)
        assert step.max() <= 5.0 + 1e-9
        assert m.length >= np.linalg.norm(states[m.vertex, :3] - start[:3]) - 1e-9
    into = connector.connect(start, graph, outgoing=False)
    for m in into:
        assert np.allclose(m.states[-1], start) and np.allclose(m.states[0, :3], states[m.vertex, :3])
