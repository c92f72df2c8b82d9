"""Random (start, goal) queries of a dataset's graph, for the query benchmark and the leaf validation.

The dataset's own query comes first; then a start uniformly among the vertices and a goal uniformly
among the vertices the start reaches in at least ``min_fraction`` of a sample of the training worlds (so
most queries have a free path, but not all). Seeded: same problem and seed, same queries.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order

from drd_planner.arrays import BoolArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.lazysp import GraphArcs
from drd_planner.core.problem import Problem
from drd_planner.exceptions import DrdError

#: Training worlds sampled to judge whether a start reaches a goal "in most worlds".
REACH_SAMPLE = 200


def reachable_fraction(graph: ExplicitGraph, worlds: BoolArray, start: int) -> npt.NDArray[np.float64]:
    """(V,) fraction of ``worlds`` (n, E) in which each vertex is reachable from ``start`` over free edges."""
    arcs = GraphArcs(graph)
    n = graph.num_vertices
    counts = np.zeros(n)
    for row in worlds:
        keep = row[arcs.edge]
        adj = sp.csr_array((np.ones(int(keep.sum())), (arcs.u[keep], arcs.v[keep])), shape=(n, n))
        counts[breadth_first_order(adj, start, directed=True, return_predecessors=False)] += 1
    return counts / max(len(worlds), 1)


def draw_queries(problem: Problem, count: int, *, seed: int, min_fraction: float = 0.5) -> list[tuple[int, int]]:
    """``count`` (start, goal) pairs: the problem's own query first, then seeded random connected pairs."""
    graph = problem.graph
    worlds = problem.require_worlds()
    if graph is None:
        raise DrdError(f"{problem.name}: --queries needs the dataset's graph")
    rng = np.random.default_rng(seed)
    train = worlds.X[worlds.train_ids]
    sample = train[np.sort(rng.choice(train.shape[0], size=min(REACH_SAMPLE, train.shape[0]), replace=False))]
    queries: list[tuple[int, int]] = []
    if problem.start is not None and problem.goal is not None:
        queries.append((int(problem.start), int(problem.goal)))
    attempts = 0
    while len(queries) < count:
        attempts += 1
        if attempts > 50 * count:
            raise DrdError(f"{problem.name}: could not draw {count} queries connected in most training worlds")
        start = int(rng.integers(graph.num_vertices))
        fraction = reachable_fraction(graph, sample, start)
        fraction[start] = 0.0
        goals = np.flatnonzero(fraction >= min_fraction)
        if goals.size:
            queries.append((start, int(rng.choice(goals))))
    return queries[:count]
