"""A query's graph while roadmap growth adds to it: states, edges, check costs, training columns, motions.

New vertices get ids from the query's V on, new edges from its E on. Every new vertex also gets a **vertex
edge**: a self-loop whose motion is the vertex's one state, so that the check of the vertex itself (growth
checks each new state before joining it, as a PRM samples free configurations) is a check of an edge in the
plan's log like every other (a path never uses one: it has no length to offer). Only free vertices are joined
to others (:attr:`GrownGraph.usable`).

Each new edge's column of training outcomes is imputed like any motion's off the graph
(:func:`~drd_planner.planner.connect.imputed_columns`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.planner.connect import EdgeSampleIndex, imputed_columns
from drd_planner.planner.query_graph import QueryGraph

__all__ = ["GrownGraph", "new_pairs"]


def new_pairs(candidates: IntArray, edges: IntArray) -> IntArray:
    """The (M, 2) candidate pairs (u < v) that are not edges yet (in either orientation), each once, sorted."""
    unique: IntArray = np.unique(np.sort(candidates.reshape(-1, 2), axis=1), axis=0).astype(np.int64)
    unique = unique[unique[:, 0] != unique[:, 1]]
    if unique.shape[0] == 0 or edges.shape[0] == 0:
        return unique
    existing = {(int(u), int(v)) for u, v in np.sort(edges, axis=1).tolist()}
    keep = np.array([(u, v) not in existing for u, v in unique.tolist()], dtype=bool)
    return np.asarray(unique[keep], dtype=np.int64)


class GrownGraph:
    """The query's graph as it grows (see the module docstring).

    Args:
        query: the query's graph when growth begins.
        index: points along the prior's graph edges (imputation).
        worlds: (n, E) the prior's training worlds (None: no columns are kept).
    """

    def __init__(self, query: QueryGraph, index: EdgeSampleIndex, worlds: BoolArray | None) -> None:
        assert query.graph.vertex_states is not None
        self.base = query
        self.index = index
        self.prior_worlds = worlds if query.worlds is not None else None
        self.states = query.graph.vertex_states
        self.edges = query.graph.edges
        self.lengths = query.graph.lengths
        self.costs = query.edge_costs
        self.worlds = query.worlds
        self.motions = dict(query.motions)
        self.usable = np.ones(query.graph.num_vertices, dtype=bool)
        self.vertices_added = 0
        self.edges_added = 0
        self.vertex_edges = 0
        self._cost = float(np.median(query.edge_costs)) if query.edge_costs.size else 1.0

    @property
    def num_vertices(self) -> int:
        """V, the vertices so far."""
        return int(self.states.shape[0])

    def add_vertices(self, states: FloatArray) -> tuple[IntArray, IntArray]:
        """Add (N, D) states as vertices, each with its vertex edge; ``(vertex ids, vertex edge ids)``.

        They are not usable (joined to others) until :meth:`mark_free` says so.
        """
        first = self.num_vertices
        ids = np.arange(first, first + states.shape[0], dtype=np.int64)
        self.states = np.vstack([self.states, states])
        self.usable = np.concatenate([self.usable, np.zeros(ids.size, dtype=bool)])
        self.vertices_added += ids.size
        self.vertex_edges += ids.size
        loops = np.stack([ids, ids], axis=1)
        edge_ids = self._add_edges(loops, [np.asarray(q, dtype=np.float64)[None] for q in states])
        return ids, edge_ids

    def add_vertex_edge(self, vertex: int) -> int:
        """The vertex edge (self-loop) of an existing vertex, added now; its edge id."""
        self.vertex_edges += 1
        state = np.asarray(self.states[vertex], dtype=np.float64)[None]
        return int(self._add_edges(np.array([[vertex, vertex]], dtype=np.int64), [state])[0])

    def mark_free(self, vertices: IntArray) -> None:
        """Let these vertices (checked free) be joined to others."""
        self.usable[vertices] = True

    def add_edges(self, pairs: IntArray, motions: list[FloatArray], lengths: FloatArray | None = None) -> IntArray:
        """Add (M, 2) edges with their (K, D) motions (tail ``pairs[:, 0]`` first); their edge ids.

        ``lengths``: (M,) the motions' lengths in the graph's unit; None: the straight distance between the
        end states (joint space).
        """
        self.edges_added += pairs.shape[0]
        return self._add_edges(pairs, motions, lengths)

    def _add_edges(self, pairs: IntArray, motions: list[FloatArray], lengths: FloatArray | None = None) -> IntArray:
        first = self.edges.shape[0]
        ids = np.arange(first, first + pairs.shape[0], dtype=np.int64)
        self.edges = np.vstack([self.edges, pairs.reshape(-1, 2)])
        if lengths is None:  # a self-loop (vertex edge) has no length, even with a NaN heading
            loops = pairs[:, 0] == pairs[:, 1]
            lengths = np.zeros(pairs.shape[0])
            lengths[~loops] = np.linalg.norm(self.states[pairs[~loops, 1]] - self.states[pairs[~loops, 0]], axis=1)
        self.lengths = np.concatenate([self.lengths, np.asarray(lengths, dtype=np.float64)])
        self.costs = np.concatenate([self.costs, np.full(pairs.shape[0], self._cost)])
        if self.worlds is not None and self.prior_worlds is not None:
            self.worlds = self.worlds.with_columns(imputed_columns(self.index, self.prior_worlds, motions))
        self.motions.update({int(e): m for e, m in zip(ids.tolist(), motions, strict=True)})
        return ids

    def query(self) -> QueryGraph:
        """The grown graph as a query (the base query's start, goal and new states kept)."""
        graph = ExplicitGraph(self.edges, self.lengths, self.num_vertices, self.base.graph.directed, self.states)
        return dataclasses.replace(
            self.base, graph=graph, worlds=self.worlds, edge_costs=self.costs, motions=dict(self.motions)
        )
