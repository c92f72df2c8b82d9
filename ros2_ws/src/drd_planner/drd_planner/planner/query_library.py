"""The path library of any query, built online from the prior's training worlds.

The authors' library (docs/algorithms.md, "Worlds, the path library and the split") is the union over
worlds of each world's k shortest free paths, subsampled to m. Yen's k shortest paths over a thousand worlds take
seconds; a planner asked for a new goal has milliseconds. The online library keeps the idea with k = 1:

1. a seeded sample of W distinct training worlds (:data:`~drd_planner.planner.goal_trees.SEARCH_WORLDS`,
   the same for every query of a prior) is searched;
2. each contributes its shortest free start-goal path, read off its reverse shortest-path tree of the goal
   (:mod:`~drd_planner.planner.goal_trees`: all W trees in one batched search, kept per goal, so a replan to
   the same goal from a new start only walks the trees);
3. the first m distinct paths in the sample's order are the library.

A start or goal off the graph is joined by motions (:mod:`~drd_planner.planner.connect`); in each world the
start takes the join with the shortest free path behind it (its imputed outcome counts), and a goal's joins
are arcs into an extra vertex of the search. R follows from X (a path is valid in a world iff all its edges
are free there).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from drd_planner.arrays import BoolArray, IntArray, first_distinct_rows
from drd_planner.core.lazysp import GraphArcs
from drd_planner.core.library import PathLibrary
from drd_planner.exceptions import ProblemError
from drd_planner.planner.goal_trees import JoinMotions, SearchWorlds
from drd_planner.planner.query_graph import Joins


class ShortestPaths:
    """Single-source shortest paths over one graph with per-call edge subsets (the arcs built once).

    Args:
        arcs: the graph's arcs (two per undirected edge).
        lengths: (E,) non-negative edge lengths.
    """

    def __init__(self, arcs: GraphArcs, lengths: npt.ArrayLike) -> None:
        self._arcs = arcs
        length = np.asarray(lengths, dtype=np.float64)[arcs.edge]
        # Zero-length arcs must stay arcs: csgraph may read an explicit 0 as "no arc", so nudge them.
        self._arc_length = np.where(length > 0, length, np.finfo(np.float64).tiny)
        n = arcs.num_vertices
        # One CSR structure for every call; a blocked arc gets weight inf, which Dijkstra never relaxes.
        self._csr = sp.csr_array((self._arc_length.copy(), arcs.v, arcs.indptr), shape=(n, n))

    def path(self, start: int, goal: int, free: BoolArray | None, *, limit: float = np.inf) -> IntArray | None:
        """Edge ids (start to goal) of a shortest path over the edges ``free`` (all when None).

        Returns None when the goal is unreachable within ``limit``.
        """
        arcs = self._arcs
        if free is None:
            self._csr.data[:] = self._arc_length
        else:
            np.copyto(self._csr.data, np.where(free[arcs.edge], self._arc_length, np.inf))
        dist, pred = dijkstra(self._csr, directed=True, indices=start, return_predecessors=True, limit=limit)
        if not np.isfinite(dist[goal]):
            return None
        return arcs.walk_back(pred, start, goal)


def library_paths(search: SearchWorlds, start: int | Joins, goal: int | Joins, *, max_paths: int) -> list[IntArray]:
    """The first ``max_paths`` distinct shortest free paths of the search worlds, from ``start`` to ``goal``.

    Args:
        search: the prior's search worlds (trees kept per goal vertex).
        start: a graph vertex, or the joins of an off-graph start.
        goal: a graph vertex, or the joins of an off-graph goal.
        max_paths: m, the most paths kept.

    Returns:
        Distinct paths as query edge-id arrays in traversal order, sorted by edge-id tuple (deterministic);
        empty when no search world has a free path.
    """
    if max_paths < 1:
        raise ProblemError(f"max_paths must be at least 1, got {max_paths}")
    if isinstance(start, int) and isinstance(goal, int) and start == goal:
        raise ProblemError(f"start and goal are the same vertex ({start}); no path has an edge to check")
    origin = _motions(search, start)
    target, into_goal = _goal_target(search, goal)
    walks = search.walks_from(target, origin)
    choice, table, counts = walks.choice, walks.table, walks.counts
    # The distinct (join, walk) rows in the worlds' order: the first max_paths of them make the library.
    kept = counts > 0
    keyed = np.concatenate([choice[:, None].astype(np.int32), table], axis=1)[kept]
    if keyed.shape[0] == 0:
        return []
    lengths, chosen = counts[kept], choice[kept]
    found: dict[tuple[int, ...], IntArray] = {}
    for row in first_distinct_rows(keyed)[:max_paths]:
        walk = keyed[row, 1 : 1 + int(lengths[row])].astype(np.int64)
        path = _walk_edges(search, walk, start, int(chosen[row]), into_goal)
        if path.size:
            found.setdefault(tuple(path.tolist()), path)
    return [found[k] for k in sorted(found)]


def union_path(search: SearchWorlds, start: int | Joins, goal: int | Joins) -> IntArray:
    """The query's shortest path over the edges (and motions) free in any search world, as query edge ids.

    Start to goal; empty when no search world has a path. In every search world where all its edges are free it
    is that world's shortest free path (no shorter path exists over the edges free in some world).
    """
    target, into_goal = _goal_target(search, goal)
    walk, chosen = search.union_walk(target, _motions(search, start))
    if walk.size == 0:
        return np.zeros(0, dtype=np.int64)
    return _walk_edges(search, walk, start, chosen, into_goal)


def _walk_edges(
    search: SearchWorlds, walk: IntArray, start: int | Joins, chosen: int, into_goal: dict[int, int]
) -> IntArray:
    """A search's walk (vertices; a joined goal's ends at ``B - 1``) as query edge ids, the start's motion first."""
    hops = walk if not into_goal else walk[:-1]  # the last hop of a joined goal is its motion
    edges = [search.arcs.edge_of(hops[:-1], hops[1:])] if hops.size > 1 else []
    if into_goal:
        edges.append(np.array([into_goal[int(hops[-1])]], dtype=np.int64))
    if isinstance(start, Joins):
        edges.insert(0, np.array([int(start.edges[chosen])], dtype=np.int64))
    return np.concatenate(edges) if edges else np.zeros(0, dtype=np.int64)


def _motions(search: SearchWorlds, start: int | Joins) -> int | JoinMotions:
    """A start vertex as it is, or an off-graph start's joins with their outcomes in the search worlds."""
    if not isinstance(start, Joins):
        return int(start)
    assert start.free is not None  # a library needs training worlds
    return JoinMotions(start.vertices, start.lengths, start.free[search.worlds])


def _goal_target(search: SearchWorlds, goal: int | Joins) -> tuple[int | JoinMotions, dict[int, int]]:
    """A goal vertex as it is, or an off-graph goal's first (best) joins in the search worlds; its join edge per vertex.

    The joins carry their outcomes in the search worlds; the map gives the query edge of the join at each vertex.
    """
    if not isinstance(goal, Joins):
        return int(goal), {}
    assert goal.free is not None
    k = min(goal.vertices.size, search.slots)  # the first (best) joins; any others stay in the graph
    joins = JoinMotions(goal.vertices[:k], goal.lengths[:k], goal.free[search.worlds][:, :k])
    return joins, dict(zip(goal.vertices[:k].tolist(), goal.edges[:k].tolist(), strict=True))


def vertex_sequence(edges: npt.NDArray[np.int64], start: int, path: IntArray) -> IntArray:
    """The vertices (start first) along ``path``, edge ids whose endpoints are ``edges`` (E, 2)."""
    seq = [int(start)]
    for e in path.tolist():
        u, v = int(edges[e, 0]), int(edges[e, 1])
        if seq[-1] == u:
            seq.append(v)
        elif seq[-1] == v:
            seq.append(u)
        else:
            raise ProblemError(f"edge {e} ({u}, {v}) does not continue a path at vertex {seq[-1]}")
    return np.asarray(seq, dtype=np.int64)


def query_library(
    search: SearchWorlds,
    edges: npt.NDArray[np.int64],
    start: int | Joins,
    goal: int | Joins,
    *,
    start_vertex: int,
    max_paths: int,
) -> PathLibrary | None:
    """:func:`library_paths` as a :class:`PathLibrary` over the query's (E', 2) ``edges`` (None when empty).

    ``start_vertex`` is the start's vertex in the query's graph (its own new vertex when it is joined).
    """
    paths = library_paths(search, start, goal, max_paths=max_paths)
    if not paths:
        return None
    return PathLibrary(tuple(paths), int(edges.shape[0]), tuple(vertex_sequence(edges, start_vertex, p) for p in paths))
