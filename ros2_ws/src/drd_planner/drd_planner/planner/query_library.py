"""The path library of any query, built online from the prior's training worlds.

The authors' library (ALGORITHMS.md 6.1, item 3) is the union over worlds of each world's k shortest
free paths, subsampled to m. Yen's k shortest paths over a thousand worlds take seconds; a planner
asked for a new goal has a fraction of that. The online library keeps the idea with k = 1:

1. the distinct training worlds are visited in a seeded random order;
2. each world contributes its shortest free start-goal path (one Dijkstra over its free edges);
3. until m distinct paths are found (a seeded uniform subsample of the worlds, as the authors subsample
   paths).

One Dijkstra costs about 0.25 ms on the 3 049-vertex SE(2) lattice, so a search in each of 900 worlds
would take a quarter of a second. Three rules keep the searches few:

- a world in which a path already found is free and as short as the shortest path of the whole graph
  needs no search (no free path can be shorter: exact);
- otherwise the shortest known path free in the world bounds the search radius (scipy's ``limit``:
  exact);
- at most ``max_searches`` Dijkstra calls are made: the library holds the shortest free paths of a seeded
  subsample of the training worlds (worlds in which no start-goal path is free cost a full search and
  give nothing, so an unbounded pass over them would dominate). A world left out is still served: some
  library path is often free in it, and the planner's graph stage covers the rest.

R follows from X (a path is valid in a world iff all its edges are free there).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from drd_planner.arrays import BoolArray, IntArray
from drd_planner.core.lazysp import GraphArcs
from drd_planner.core.library import PathLibrary
from drd_planner.exceptions import ProblemError

#: The most Dijkstra calls for one library (about 0.2 ms each on the SE(2) lattice; see the module doc).
DEFAULT_MAX_SEARCHES = 256
#: Relative slack on the search radius so that a path exactly as long as the bound is still found.
_LIMIT_RTOL = 1e-9


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

    def path(
        self, start: int, goal: int, free: BoolArray | None, *, limit: float = np.inf
    ) -> IntArray | None:
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


def build_query_library(
    arcs: GraphArcs,
    lengths: npt.ArrayLike,
    worlds: npt.ArrayLike,
    start: int,
    goal: int,
    *,
    max_paths: int,
    seed: int,
    max_searches: int = DEFAULT_MAX_SEARCHES,
) -> list[IntArray]:
    """Each visited training world's shortest free path, until ``max_paths`` distinct paths.

    Args:
        arcs: the graph's arcs.
        lengths: (E,) edge lengths (the path length the library minimises).
        worlds: (n, E) bool training worlds' outcomes (True = free).
        start: start vertex id.
        goal: goal vertex id (different from ``start``).
        max_paths: m, the most paths kept.
        seed: seed of the world order.
        max_searches: the most Dijkstra calls (worlds searched).

    Returns:
        Distinct paths as edge-id arrays in traversal order, sorted by edge-id tuple (deterministic);
        empty when no training world has a free start-goal path.
    """
    x = np.asarray(worlds, dtype=bool)
    length = np.asarray(lengths, dtype=np.float64)
    if start == goal:
        raise ProblemError(f"start and goal are the same vertex ({start}); no path has an edge to check")
    if max_paths < 1:
        raise ProblemError(f"max_paths must be at least 1, got {max_paths}")
    search = ShortestPaths(arcs, length)
    packed = np.packbits(x, axis=1)
    _, first = np.unique(packed, axis=0, return_index=True)
    order = first[np.random.default_rng(seed).permutation(first.size)]
    found: dict[tuple[int, ...], IntArray] = {}
    valid_in = np.zeros((x.shape[0], max_paths), dtype=bool)  # (n, m): found path k free in world h
    found_length = np.full(max_paths, np.inf)
    p0 = search.path(start, goal, None)
    if p0 is None:
        return []
    lower = float(length[p0].sum())
    searches = 0
    for h in order.tolist():
        if len(found) >= max_paths:
            break
        bound = float(found_length[valid_in[h]].min(initial=np.inf))
        if bound <= lower * (1 + _LIMIT_RTOL):
            continue  # a known free path is as short as any path can be
        if searches >= max_searches:
            break
        limit = bound * (1 + _LIMIT_RTOL) if np.isfinite(bound) else np.inf
        searches += 1
        path = search.path(start, goal, x[h], limit=limit)
        if path is None:
            continue
        key = tuple(path.tolist())
        if key in found:
            continue
        k = len(found)
        found[key] = path
        valid_in[:, k] = x[:, path].all(axis=1)
        found_length[k] = float(length[path].sum())
    return [found[k] for k in sorted(found)]


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
    arcs: GraphArcs,
    edges: npt.NDArray[np.int64],
    lengths: npt.ArrayLike,
    worlds: npt.ArrayLike,
    start: int,
    goal: int,
    *,
    max_paths: int,
    seed: int,
) -> PathLibrary | None:
    """:func:`build_query_library` as a :class:`PathLibrary` with vertex sequences (None when empty)."""
    paths = build_query_library(arcs, lengths, worlds, start, goal, max_paths=max_paths, seed=seed)
    if not paths:
        return None
    return PathLibrary(
        tuple(paths), int(np.asarray(lengths).size), tuple(vertex_sequence(edges, start, p) for p in paths)
    )
