"""The graph while growth adds to it: vertex edges, usable vertices, edges, imputed columns, the query."""

from __future__ import annotations

import numpy as np

from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.world_columns import WorldColumns
from drd_planner.planner.connect import EdgeSampleIndex
from drd_planner.planner.grown_graph import GrownGraph, new_pairs
from drd_planner.planner.query_graph import QueryGraph
from drd_planner.planner.query_worlds import QueryWorlds


def _query() -> tuple[QueryGraph, np.ndarray]:
    states = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    edges = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
    graph = ExplicitGraph(edges, np.ones(4), 4, vertex_states=states)
    worlds = np.array([[True, False, True, True], [True, True, False, False], [False, True, True, True]])
    return QueryGraph(graph, QueryWorlds(worlds, WorldColumns(worlds)), np.ones(4), 0, 2), worlds


def test_new_pairs_are_sorted_unique_and_not_yet_edges() -> None:
    edges = np.array([[0, 1], [2, 1]])
    candidates = np.array([[1, 0], [3, 2], [2, 3], [1, 2], [4, 4]])
    assert new_pairs(candidates, edges).tolist() == [[2, 3]]


def test_vertices_get_a_vertex_edge_and_are_joined_only_when_free() -> None:
    query, worlds = _query()
    index = EdgeSampleIndex(query.graph, None, position_dims=2)
    grown = GrownGraph(query, index, worlds)
    ids, loops = grown.add_vertices(np.array([[0.5, 0.1], [0.5, 0.9]]))
    assert ids.tolist() == [4, 5]
    assert loops.tolist() == [4, 5]
    assert not grown.usable[ids].any()
    assert grown.usable[:4].all()
    grown.mark_free(ids[:1])
    assert grown.usable[4]
    assert not grown.usable[5]
    edge_ids = grown.add_edges(np.array([[0, 4]]), [np.linspace([0.0, 0.0], [0.5, 0.1], 4)])
    start_loop = grown.add_vertex_edge(0)
    q = grown.query()
    assert edge_ids.tolist() == [6]
    assert start_loop == 7
    assert q.graph.num_vertices == 6
    assert q.graph.num_edges == 8
    assert q.worlds is not None
    assert q.worlds.shape == (3, 8)
    assert q.graph.edges[4].tolist() == [4, 4]
    assert q.motions[4].shape == (1, 2)  # the vertex edge: its one state
    assert q.graph.lengths[4] == 0.0
    assert np.isclose(q.graph.lengths[6], np.hypot(0.5, 0.1))
    assert (q.start, q.goal) == (0, 2)
    assert grown.vertices_added == 2
    assert grown.edges_added == 1
    assert grown.vertex_edges == 3
