"""Path-library construction and the train/test split, as in the authors' dataset scripts.

Library (docs/algorithms.md, "Worlds, the path library and the split"; [CODE] ``create_regions_from_graphs.m``
option 4): for every world, keep only its collision-free edges and take Yen's k shortest loopless start-goal
paths by edge length; the library is the union over all worlds, deduplicated, then subsampled uniformly at
random to at most ``max_paths`` paths.

Split (docs/algorithms.md, "Evaluation protocol (Table 1)"; [CODE] ``create_train_test.m`` type 3): the test
worlds are drawn uniformly among the worlds in which at least one library path is valid; every other world is
a training world.
"""

from __future__ import annotations

from itertools import islice

import networkx as nx
import numpy as np
import numpy.typing as npt
from tqdm import tqdm

from drd_planner.arrays import BoolArray, IntArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.library import PathLibrary
from drd_planner.exceptions import ProblemError

EdgeTuple = tuple[int, ...]
VertexTuple = tuple[int, ...]

__all__ = ["build_path_library", "k_shortest_paths_union", "split_worlds"]


def _check_inputs(graph: ExplicitGraph, x: npt.ArrayLike, start: int, goal: int, k: int) -> BoolArray:
    """Validate the builder inputs and return X as an (n, E) bool array."""
    xb = np.asarray(x)
    if xb.ndim != 2 or xb.shape[1] != graph.num_edges:
        raise ProblemError(f"X must have shape (worlds, {graph.num_edges}), got {xb.shape}")
    if xb.dtype != np.bool_:
        if not np.isin(xb, (0, 1)).all():
            raise ProblemError("X entries must be boolean (0 or 1)")
        xb = xb.astype(bool)
    for name, v in (("start", start), ("goal", goal)):
        if not 0 <= int(v) < graph.num_vertices:
            raise ProblemError(f"{name} vertex {v} outside [0, {graph.num_vertices})")
    if int(start) == int(goal):
        raise ProblemError(f"start and goal are the same vertex ({start}); no path has an edge to check")
    if k < 1:
        raise ProblemError(f"k must be at least 1, got {k}")
    return xb


def k_shortest_paths_union(
    graph: ExplicitGraph,
    X: npt.ArrayLike,
    start: int,
    goal: int,
    *,
    k: int = 5,
    progress: bool | None = None,
) -> list[tuple[EdgeTuple, VertexTuple]]:
    """The union over worlds of each world's k shortest loopless start-goal paths, before subsampling.

    For world h the search runs on the subgraph of the edges with ``X[h, e]`` True (all vertices kept),
    weighted by ``graph.lengths``, with networkx's Yen implementation (``shortest_simple_paths``);
    directed graphs are searched along edge orientation only. Worlds without a start-goal path add
    nothing. Worlds with identical free-edge rows are searched once.

    Args:
        graph: the explicit graph (E edges).
        X: (n, E) bool, True where the edge is collision-free in the world.
        start: start vertex id.
        goal: goal vertex id.
        k: paths per world (fewer when the world has fewer loopless paths).
        progress: show a tqdm bar over worlds; None shows it only on a terminal.

    Returns:
        Distinct paths as ``(edge ids, vertex ids)`` tuples in traversal order, sorted by edge-id tuple.
    """
    xb = _check_inputs(graph, X, start, goal, k)
    edges = graph.edges.tolist()
    lengths = graph.lengths.tolist()
    union: dict[EdgeTuple, VertexTuple] = {}
    seen_rows: set[bytes] = set()
    disable = None if progress is None else not progress
    for h in tqdm(range(xb.shape[0]), desc="k-shortest paths", unit="world", disable=disable):
        row = xb[h]
        key = np.packbits(row).tobytes()
        if key in seen_rows:
            continue
        seen_rows.add(key)
        g = nx.DiGraph() if graph.directed else nx.Graph()
        g.add_nodes_from(range(graph.num_vertices))
        free = np.flatnonzero(row).tolist()
        g.add_weighted_edges_from((edges[e][0], edges[e][1], lengths[e]) for e in free)
        try:
            for vpath in islice(nx.shortest_simple_paths(g, int(start), int(goal), weight="weight"), k):
                etuple = tuple(int(e) for e in graph.vertex_path_to_edges(vpath))
                union.setdefault(etuple, tuple(int(v) for v in vpath))
        except nx.NetworkXNoPath:
            continue
    return sorted(union.items())


def build_path_library(
    graph: ExplicitGraph,
    X: npt.ArrayLike,
    start: int,
    goal: int,
    *,
    k: int = 5,
    max_paths: int = 500,
    seed: int,
) -> PathLibrary:
    """Build the path library: per-world k shortest paths, union, deduplicate, seeded subsample.

    Args:
        graph: the explicit graph (E edges, lengths in the domain's length unit).
        X: (n, E) bool, True where edge e is collision-free in world h.
        start: start vertex id.
        goal: goal vertex id.
        k: Yen's k per world (5 in the authors' datasets).
        max_paths: the library keeps min(max_paths, union size) paths (500 in the authors' datasets).
        seed: seed of ``numpy.random.default_rng`` for the uniform subsample.

    Returns:
        A :class:`PathLibrary` of m paths (edge ids and vertex sequences, start first, goal last). The
        kept paths stay in the union's order (sorted by edge-id tuple), so equal inputs give equal
        libraries.

    Raises:
        ProblemError: bad inputs, or no world has a start-goal path on its free edges.
    """
    if max_paths < 1:
        raise ProblemError(f"max_paths must be at least 1, got {max_paths}")
    union = k_shortest_paths_union(graph, X, start, goal, k=k)
    if not union:
        raise ProblemError(
            f"no world has a collision-free path from vertex {start} to vertex {goal}; the path library "
            "would be empty (check the world model, the graph's connectivity, or X)"
        )
    keep = np.arange(len(union))
    if len(union) > max_paths:
        rng = np.random.default_rng(seed)
        keep = np.sort(rng.choice(len(union), size=max_paths, replace=False))
    chosen = [union[i] for i in keep.tolist()]
    return PathLibrary(
        tuple(np.array(e, dtype=np.int64) for e, _ in chosen),
        graph.num_edges,
        tuple(np.array(v, dtype=np.int64) for _, v in chosen),
    )


def split_worlds(R: npt.ArrayLike, *, test_fraction: float = 0.1, seed: int) -> tuple[IntArray, IntArray]:
    """The authors' train/test split (type 3).

    Args:
        R: (n, m) bool, R[h, i] True when library path i is valid in world h.
        test_fraction: share of all n worlds held out for testing, in [0, 1].
        seed: seed of ``numpy.random.default_rng`` for drawing the test worlds.

    Returns:
        ``(train_ids, test_ids)``, sorted int64 world indices. ``test_ids`` holds round(test_fraction * n)
        worlds drawn uniformly without replacement among the worlds with at least one valid path (all of
        them when there are fewer); ``train_ids`` holds every other world, unsolvable ones included.

    Raises:
        ProblemError: R is not 2-D or test_fraction lies outside [0, 1].
    """
    r = np.asarray(R, dtype=bool)
    if r.ndim != 2:
        raise ProblemError(f"R must have shape (worlds, paths), got {r.shape}")
    if not 0.0 <= test_fraction <= 1.0:
        raise ProblemError(f"test_fraction must lie in [0, 1], got {test_fraction}")
    n = r.shape[0]
    eligible = np.flatnonzero(r.any(axis=1)).astype(np.int64)
    n_test = min(round(test_fraction * n), int(eligible.size))
    rng = np.random.default_rng(seed)
    test = np.sort(rng.choice(eligible, size=n_test, replace=False)).astype(np.int64)
    train = np.setdiff1d(np.arange(n, dtype=np.int64), test).astype(np.int64)
    return train, test
